//! Greedy centre selection, FastRBF's "fit to an accuracy" (Carr et al.,
//! SIGGRAPH 2001, §3): interpolate a subset of the constraints, evaluate the
//! fit at all of them, add the worst-fitted ones as centres, and repeat
//! until every constraint is within a tolerance. The interpolant is still
//! the paper's global variational one, through fewer centres.

use crate::error::RbfError;
use crate::interpolant::{Constraint, Interpolant};
use isomorph_common::MorphError;

/// How [`crate::FitSettings::centres`] chooses the interpolant's centres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Centres {
    /// Every constraint is a centre (the paper's exact interpolation).
    #[default]
    All,
    /// Greedy selection to a tolerance (FastRBF).
    Greedy(GreedySettings),
}

/// Settings of the greedy centre selection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GreedySettings {
    /// Largest accepted `|f(x_i) − h_i|` at any constraint, relative to the
    /// largest `|h_i|` (1e-3 to 1; default 1e-2: a hundredth of the normal
    /// constraints' value).
    pub tolerance: f64,
    /// Centres of the first fit, spread over the constraints' positions
    /// (one per cell of a median split of the positions, whatever their
    /// order; at least `D + 1`; default 1000).
    pub initial: usize,
    /// Most centres; the selection stops there even if some constraint is
    /// still off by more than the tolerance (default 16000).
    pub max_centres: usize,
}

impl Default for GreedySettings {
    fn default() -> Self {
        Self { tolerance: 1e-2, initial: 1000, max_centres: 16_000 }
    }
}

impl GreedySettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] naming the field.
    pub fn validate(&self) -> Result<(), MorphError> {
        isomorph_common::check::range("tolerance", self.tolerance, 1e-3, 1.0)?;
        isomorph_common::check::count("initial", self.initial as u64, 8, 1 << 24)?;
        isomorph_common::check::count("max_centres", self.max_centres as u64, self.initial as u64, 1 << 24)
    }
}

/// One round of the selection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GreedyRound {
    /// Centres of this round's fit.
    pub centres: usize,
    /// Largest residual over all constraints, relative to the largest value.
    pub max_residual: f64,
}

/// What the selection did, in [`crate::FitReport::greedy`].
#[derive(Debug, Clone, PartialEq)]
pub struct GreedyReport {
    /// The rounds in order; the last is the returned fit.
    pub rounds: Vec<GreedyRound>,
    /// Every constraint is within the tolerance.
    pub converged: bool,
}

/// Fits through a growing subset of `constraints` (see the module docs);
/// `all_centres` fits one subset exactly.
pub(crate) fn fit_greedy<const D: usize>(
    constraints: &[Constraint<D>],
    greedy: &GreedySettings,
    all_centres: impl Fn(&[Constraint<D>]) -> Result<Interpolant<D>, RbfError>,
) -> Result<(Interpolant<D>, GreedyReport), RbfError> {
    greedy.validate()?;
    let n = constraints.len();
    let initial = greedy.initial.max(D + 1).min(n);
    let scale =
        constraints.iter().fold(0.0f64, |m, c| m.max(f64::from(c.value).abs())).max(f64::MIN_POSITIVE);
    let mut chosen = vec![false; n];
    for i in spread(constraints, initial) {
        chosen[i] = true;
    }
    let mut rounds = Vec::new();
    loop {
        let subset: Vec<Constraint<D>> =
            constraints.iter().zip(&chosen).filter(|(_, c)| **c).map(|(c, _)| *c).collect();
        let fit = all_centres(&subset)?;
        let values = fit.values_at(constraints)?;
        let residual: Vec<f64> =
            values.iter().zip(constraints).map(|(v, c)| f64::from(v - c.value).abs() / scale).collect();
        let max_residual = residual.iter().copied().fold(0.0, f64::max);
        rounds.push(GreedyRound { centres: subset.len(), max_residual });
        let room = greedy.max_centres.saturating_sub(subset.len());
        if max_residual <= greedy.tolerance || room == 0 || subset.len() == n {
            let converged = max_residual <= greedy.tolerance;
            return Ok((fit, GreedyReport { rounds, converged }));
        }
        // The worst-fitted constraints become centres: at most as many as
        // there are now (the subset at most doubles), ties by index.
        let mut worst: Vec<usize> =
            (0..n).filter(|&i| !chosen[i] && residual[i] > greedy.tolerance).collect();
        worst.sort_by(|&a, &b| residual[b].total_cmp(&residual[a]).then(a.cmp(&b)));
        for &i in worst.iter().take(room.min(subset.len())) {
            chosen[i] = true;
        }
    }
}

/// `count` indices of `constraints` spread over their positions: the
/// positions are split at the median of the widest axis into `count` cells
/// (sizes differing by at most one) and the first constraint (lowest index)
/// of each cell is taken. Unlike every `n / count`-th constraint, this does
/// not alias with a periodic input order (e.g. boundary and normal
/// constraints of two shapes listed in turn).
fn spread<const D: usize>(constraints: &[Constraint<D>], count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..constraints.len()).collect();
    let mut picked = Vec::with_capacity(count);
    // (range of `order`, cells it is split into)
    let mut todo = vec![(0, order.len(), count.min(order.len()))];
    while let Some((start, end, cells)) = todo.pop() {
        if cells == 0 {
            continue;
        }
        let part = &mut order[start..end];
        if cells == 1 {
            picked.extend(part.iter().min().copied());
            continue;
        }
        let axis = (0..D)
            .map(|k| {
                let (lo, hi) = part.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &i| {
                    let x = constraints[i].position[k];
                    (lo.min(x), hi.max(x))
                });
                hi - lo
            })
            .enumerate()
            .fold((0, f32::NEG_INFINITY), |best, (k, w)| if w > best.1 { (k, w) } else { best })
            .0;
        // Split the cells in two and the points in the same proportion.
        let left_cells = cells / 2;
        let mid = part.len() * left_cells / cells;
        part.select_nth_unstable_by(mid, |&a, &b| {
            constraints[a].position[axis].total_cmp(&constraints[b].position[axis]).then(a.cmp(&b))
        });
        todo.push((start + mid, end, cells - left_cells));
        todo.push((start, start + mid, left_cells));
    }
    picked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FitSettings;

    /// Boundary (0) and inward normal (1) constraints of an ellipsoid with
    /// semi-axes 0.4, 0.3, 0.2, at `n` Fibonacci-sphere directions.
    fn ellipsoid(n: usize) -> Vec<Constraint<3>> {
        let axes = [0.4f32, 0.3, 0.2];
        let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
        (0..n)
            .flat_map(|i| {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let r = (1.0 - z * z).sqrt();
                let d = [r * (golden * i as f32).cos(), r * (golden * i as f32).sin(), z];
                let p: [f32; 3] = std::array::from_fn(|k| d[k] * axes[k]);
                let inward: [f32; 3] = std::array::from_fn(|k| p[k] - 0.01 * d[k] / axes[k]);
                [Constraint::new(p, 0.0), Constraint::new(inward, 1.0)]
            })
            .collect()
    }

    #[test]
    fn greedy_fit_reaches_its_tolerance_with_fewer_centres() {
        let constraints = ellipsoid(3000);
        let greedy = GreedySettings { tolerance: 1e-2, initial: 300, max_centres: 6000 };
        let settings = FitSettings { centres: Centres::Greedy(greedy), ..FitSettings::default() };
        let fit = Interpolant::fit(&constraints, &settings).unwrap();
        let report = fit.report().greedy.clone().expect("a greedy report");
        assert!(report.converged, "{report:?}");
        assert!(fit.len() < constraints.len() / 2, "{} centres for {}", fit.len(), constraints.len());
        assert_eq!(report.rounds.last().unwrap().centres, fit.len());
        // Checked exactly, in f64, at every constraint.
        let worst = constraints
            .iter()
            .map(|c| (fit.value_f64(c.position.map(f64::from)) - f64::from(c.value)).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-2 + 1e-4, "worst residual {worst}");
        // Fewer centres allowed than needed: stopped, not converged.
        let capped = GreedySettings { max_centres: 400, ..greedy };
        let settings = FitSettings { centres: Centres::Greedy(capped), ..FitSettings::default() };
        let fit = Interpolant::fit(&constraints, &settings).unwrap();
        let report = fit.report().greedy.clone().unwrap();
        assert!(!report.converged && fit.len() <= 400, "{report:?}");
        assert!(fit.report().max_residual.unwrap() > 1e-2);
    }

    #[test]
    fn initial_centres_cover_both_shapes_of_a_periodic_order() {
        // Four constraint kinds listed in turn (two shapes at t = 0 and 1,
        // boundary and normal), 1000 of each: every 4th constraint would
        // take one kind only, all at t = 0 (not unisolvent in 4D).
        let shape = ellipsoid(1000);
        let mut all = Vec::new();
        for pair in shape.chunks(2) {
            for t in [0.0, 1.0] {
                for c in pair {
                    let p = c.position;
                    all.push(Constraint::new([p[0], p[1], p[2], t], c.value));
                }
            }
        }
        let picked = spread(&all, 100);
        assert_eq!(picked.len(), 100);
        let mut kinds = [0usize; 4];
        for &i in &picked {
            kinds[i % 4] += 1;
        }
        // Both times in equal numbers (the 4th axis is the widest), both
        // values (boundary and normal points share cells, whose lowest
        // index is the boundary one, so fewer normal ones).
        assert_eq!((kinds[0] + kinds[1], kinds[2] + kinds[3]), (50, 50), "{kinds:?}");
        assert!(kinds[1] > 0 && kinds[3] > 0, "{kinds:?}");
        let mut unique = picked.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), 100);
        // The greedy fit of this order runs (the old every-n/count-th
        // choice failed with `NotUnisolvent`).
        let greedy = GreedySettings { tolerance: 5e-2, initial: 100, max_centres: 4000 };
        let settings = FitSettings { centres: Centres::Greedy(greedy), ..FitSettings::default() };
        let fit = Interpolant::fit(&all, &settings).unwrap();
        assert!(fit.report().greedy.as_ref().unwrap().converged);
    }

    #[test]
    fn bad_greedy_settings_are_errors() {
        let constraints = ellipsoid(200);
        for (greedy, field) in [
            (GreedySettings { tolerance: 0.0, initial: 20, ..GreedySettings::default() }, "tolerance"),
            (GreedySettings { initial: 20, max_centres: 10, ..GreedySettings::default() }, "max_centres"),
        ] {
            let settings = FitSettings { centres: Centres::Greedy(greedy), ..FitSettings::default() };
            let err = Interpolant::fit(&constraints, &settings).unwrap_err();
            assert!(err.to_string().contains(field), "{field}: {err}");
        }
    }
}
