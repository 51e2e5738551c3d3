//! Greedy centre selection, FastRBF's "fit to an accuracy" (Carr et al.,
//! SIGGRAPH 2001, §3): interpolate a subset of the constraints, evaluate the
//! fit at all of them, add the worst-fitted ones as centres, and repeat
//! until every constraint is within a tolerance. The interpolant is still
//! the paper's global variational one, through fewer centres.
//!
//! Details: the first subset is spread over the positions (a median split
//! into cells); each round adds, worst residual first, constraints off by
//! more than half the tolerance, each at least half its distance to the
//! nearest centre away from those added before it in the round (so one
//! per poorly fitted patch, not whole clumps of neighbours), at most
//! doubling the subset; once it holds half of the constraints, the next
//! round interpolates all of them (cheaper than the rounds that would
//! follow, each adding a few centres). Each subset is solved by the
//! default solver (the hierarchical one from [`crate::HIERARCHICAL_MIN`]
//! centres) with GMRES stopped at `tolerance / (100 √n)` of the
//! right-hand side, which fits every centre to within a hundredth of the
//! tolerance. The residuals over all constraints are evaluated by the
//! treecode, and those that decide the round are recomputed by the exact
//! `f64` sum: at the large, cancelling weights of real meshes the fast
//! values err by more than the tolerance. On 1,000,000 constraints of two
//! shapes (sphere and torus in 4D) a tolerance of 2e-2 is reached with
//! 21173 centres in 6 rounds (96 s of CPU, 0.42 GB; the crate docs); 1e-2
//! is not reached within 64000 centres (largest exact residual 1.06e-2).
//!
//! The tolerance is a residual of the field, whose normal constraints are
//! 1 at `k` (the normal offset) inside the surface: a residual `ε` moves
//! the surface by about `ε k`. Samples of a real mesh at its own
//! resolution carry detail at every point, and a tight tolerance keeps
//! nearly all of them (bunny → dragon, 11678 constraints: 1e-2 and 1e-1
//! keep all, 0.5 keeps 5210).

use crate::error::RbfError;
use crate::hierarchical;
use crate::hmatrix::ClusterTree;
use crate::interpolant::{Constraint, Interpolant};
use isomorph_common::MorphError;
use rayon::prelude::*;

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
    /// still off by more than the tolerance (default 64000: the
    /// hierarchical solver fits that many in about 1 GB; 1,000,000
    /// constraints of two shapes reach a tolerance of 2e-2 with 21173).
    pub max_centres: usize,
}

impl Default for GreedySettings {
    fn default() -> Self {
        Self { tolerance: 1e-2, initial: 1000, max_centres: 64_000 }
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
/// `fit` fits one subset exactly with the hierarchical solver's settings
/// it is given (a GMRES tolerance matched to the greedy tolerance).
pub(crate) fn fit_greedy<const D: usize>(
    constraints: &[Constraint<D>],
    greedy: &GreedySettings,
    fit: impl Fn(&[Constraint<D>], &hierarchical::Settings) -> Result<Interpolant<D>, RbfError>,
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
        let round_fit = fit(&subset, &iterative_settings(greedy.tolerance, subset.len()))?;
        let residual = residuals(&round_fit, constraints, &chosen, scale, 0.5 * greedy.tolerance)?;
        // At the centres the fit's own exact check, when it made one.
        let at_centres = round_fit
            .report()
            .max_residual
            .unwrap_or_else(|| (0..n).filter(|&i| chosen[i]).map(|i| residual[i]).fold(0.0, f64::max));
        let max_residual = (0..n).filter(|&i| !chosen[i]).map(|i| residual[i]).fold(at_centres, f64::max);
        rounds.push(GreedyRound { centres: subset.len(), max_residual });
        let room = greedy.max_centres.saturating_sub(subset.len());
        if max_residual <= greedy.tolerance || room == 0 || subset.len() == n {
            let converged = max_residual <= greedy.tolerance;
            return Ok((round_fit, GreedyReport { rounds, converged }));
        }
        // The worst-fitted constraints become centres, spread over space:
        // at most as many as there are now (the subset at most doubles).
        // Those within a factor two of the tolerance are candidates too
        // (taken only when the worse ones leave room), so that the last
        // rounds do not each add a handful of stragglers.
        let candidates: Vec<usize> =
            (0..n).filter(|&i| !chosen[i] && residual[i] > 0.5 * greedy.tolerance).collect();
        let picked = worst_spread(constraints, &chosen, &residual, candidates, room.min(subset.len()));
        if picked.is_empty() {
            // Only centres are off (a fit that is not exact): nothing to add.
            return Ok((round_fit, GreedyReport { rounds, converged: false }));
        }
        for i in picked {
            chosen[i] = true;
        }
        // Past half of the constraints every further round costs at least
        // half of the fit through all of them, and the rounds there add
        // ever fewer centres (each fixes a patch and disturbs another):
        // samples of a real mesh at its own resolution need nearly all of
        // them at a tight tolerance (bunny → dragon, 11678 constraints,
        // 1e-2: 11526 centres after five rounds past 8000). The exact
        // interpolation through all of them is cheaper and meets any
        // tolerance.
        let count = chosen.iter().filter(|&&c| c).count();
        if 2 * count > n && n <= greedy.max_centres {
            chosen.fill(true);
        }
    }
}

/// Most kernel terms (constraints × centres) a round spends on exact
/// residuals beyond [`PROBES`]: about 8 s of CPU (8 ns per term).
const EXACT_TERMS: usize = 1_000_000_000;
/// The worst fast residuals away from the centres recomputed exactly in
/// every round to measure the fast evaluation's error there.
const PROBES: usize = 256;

/// `|f(x_i) − h_i| / scale` at every constraint. The fast evaluation
/// (`Interpolant::values_at`, the `f32` treecode) errs by up to ~0.1–0.9
/// of the values at the large weights of real meshes (`Σ|λ|` ~1e7–1e8),
/// where the greedy would chase the evaluator's error, so the residuals
/// that decide the round are made exact: the [`PROBES`] worst ones away
/// from the centres are recomputed with the exact `f64` sum, and twice
/// their largest change is the `margin` of the fast values. When the
/// margin exceeds an eighth of `threshold`, every residual above
/// `threshold − margin` is recomputed too, worst first, within
/// [`EXACT_TERMS`]; the others keep their fast values.
fn residuals<const D: usize>(
    f: &Interpolant<D>,
    constraints: &[Constraint<D>],
    chosen: &[bool],
    scale: f64,
    threshold: f64,
) -> Result<Vec<f64>, RbfError> {
    let values = f.values_at(constraints)?;
    let mut residual: Vec<f64> =
        values.iter().zip(constraints).map(|(v, c)| f64::from(v - c.value).abs() / scale).collect();
    let exact = |idx: &[usize]| -> Vec<f64> {
        idx.par_iter()
            .map(|&i| {
                let c = &constraints[i];
                (f.value_f64(c.position.map(f64::from)) - f64::from(c.value)).abs() / scale
            })
            .collect()
    };
    let mut order: Vec<usize> = (0..residual.len()).filter(|&i| !chosen[i]).collect();
    order.sort_unstable_by(|&a, &b| residual[b].total_cmp(&residual[a]).then(a.cmp(&b)));
    let probes = &order[..order.len().min(PROBES)];
    let mut margin = 0.0f64;
    for (&i, r) in probes.iter().zip(exact(probes)) {
        margin = margin.max(2.0 * (r - residual[i]).abs());
        residual[i] = r;
    }
    if margin > threshold / 8.0 {
        let rest = &order[probes.len()..];
        let budget = (EXACT_TERMS / f.len().max(1)).saturating_sub(PROBES);
        let over = rest.iter().take_while(|&&i| residual[i] > threshold - margin).count().min(budget);
        for (&i, r) in rest[..over].iter().zip(exact(&rest[..over])) {
            residual[i] = r;
        }
    }
    Ok(residual)
}

/// The hierarchical solver's settings for a greedy round of `centres`
/// centres: GMRES stops at a relative residual of `tolerance / (100 √n)`.
/// The projected residual bounds the residual at the centres in the
/// 2-norm (`‖h − f‖₂ = ‖g − B y‖₂ ≤ τ ‖h‖₂ ≤ τ √n max |h|`), so every centre
/// is then fitted to a hundredth of the greedy tolerance — far tighter
/// than the check over all constraints needs, and far looser (fewer
/// iterations) than the exact fit's `1e-11`.
fn iterative_settings(tolerance: f64, centres: usize) -> hierarchical::Settings {
    let exact = hierarchical::Settings::default();
    let tau = (1e-2 * tolerance / (centres.max(1) as f64).sqrt()).max(exact.tolerance);
    hierarchical::Settings { tolerance: tau, ..exact }
}

/// Up to `quota` of `candidates` (indices of constraints), worst residual
/// first (ties by index), each at least half its distance to the nearest
/// chosen centre away from every one picked before it. Taking simply the
/// worst ones would add whole clumps of neighbouring constraints where the
/// fit is poor (their residuals are alike): redundant centres, fitted
/// exactly while their surroundings overshoot, and dense clusters next to
/// sparse regions that make the system harder. The exclusion radius
/// follows the local spacing of the centres, the scale on which the
/// residual varies, so each round adds about one centre per poorly fitted
/// patch of that size (FastRBF adds the worst points per region).
fn worst_spread<const D: usize>(
    constraints: &[Constraint<D>],
    chosen: &[bool],
    residual: &[f64],
    candidates: Vec<usize>,
    quota: usize,
) -> Vec<usize> {
    if candidates.is_empty() || quota == 0 {
        return Vec::new();
    }
    let flat = |idx: &mut dyn Iterator<Item = usize>| -> Vec<f64> {
        idx.flat_map(|i| constraints[i].position.map(f64::from)).collect()
    };
    let centres = ClusterTree::new(&flat(&mut (0..chosen.len()).filter(|&i| chosen[i])), D, SEARCH_LEAF);
    // Radius of exclusion around each candidate, in candidate order.
    let radius: Vec<f64> = candidates
        .par_iter()
        .map(|&i| 0.5 * nearest_distance(&centres, &constraints[i].position.map(f64::from)))
        .collect();
    let tree = ClusterTree::new(&flat(&mut candidates.iter().copied()), D, SEARCH_LEAF);
    // `excluded[k]`: candidate at tree position `k` is too near a pick.
    let mut excluded = vec![false; candidates.len()];
    let mut slot = vec![0; candidates.len()];
    for (k, &c) in tree.order.iter().enumerate() {
        slot[c] = k;
    }
    let mut by_residual: Vec<usize> = (0..candidates.len()).collect();
    by_residual.sort_by(|&a, &b| {
        residual[candidates[b]].total_cmp(&residual[candidates[a]]).then(candidates[a].cmp(&candidates[b]))
    });
    let mut picked = Vec::with_capacity(quota);
    for c in by_residual {
        if picked.len() == quota {
            break;
        }
        if excluded[slot[c]] {
            continue;
        }
        picked.push(candidates[c]);
        excluded[slot[c]] = true;
        within(&tree, tree.point(slot[c]), radius[c], &mut |k| excluded[k] = true);
    }
    picked
}

/// Leaf size of the search trees of [`worst_spread`].
const SEARCH_LEAF: usize = 16;

/// The squared distance from `x` to the bounding box of `node`.
fn box_distance2(node: &crate::hmatrix::Node, x: &[f64]) -> f64 {
    x.iter()
        .zip(node.lo.iter().zip(&node.hi))
        .map(|(&x, (&lo, &hi))| (lo - x).max(x - hi).max(0.0).powi(2))
        .sum()
}

/// The distance from `x` to the nearest point of `tree` (infinite for an
/// empty tree), by branch and bound over the bounding boxes.
fn nearest_distance(tree: &ClusterTree, x: &[f64]) -> f64 {
    let mut best = f64::INFINITY;
    let mut stack = vec![0usize];
    while let Some(s) = stack.pop() {
        let node = &tree.nodes[s];
        if node.range.is_empty() || box_distance2(node, x) >= best {
            continue;
        }
        match node.children {
            Some((a, b)) => {
                // The nearer child is searched first (pushed last).
                let (da, db) = (box_distance2(&tree.nodes[a], x), box_distance2(&tree.nodes[b], x));
                stack.extend(if da <= db { [b, a] } else { [a, b] });
            }
            None => {
                for i in node.range.clone() {
                    let d2: f64 = tree.point(i).iter().zip(x).map(|(p, x)| (p - x) * (p - x)).sum();
                    best = best.min(d2);
                }
            }
        }
    }
    best.sqrt()
}

/// Calls `hit` with the tree position of every point of `tree` within
/// `radius` of `x`.
fn within(tree: &ClusterTree, x: &[f64], radius: f64, hit: &mut dyn FnMut(usize)) {
    let r2 = radius * radius;
    let mut stack = vec![0usize];
    while let Some(s) = stack.pop() {
        let node = &tree.nodes[s];
        if node.range.is_empty() || box_distance2(node, x) > r2 {
            continue;
        }
        match node.children {
            Some((a, b)) => stack.extend([a, b]),
            None => {
                for i in node.range.clone() {
                    let d2: f64 = tree.point(i).iter().zip(x).map(|(p, x)| (p - x) * (p - x)).sum();
                    if d2 <= r2 {
                        hit(i);
                    }
                }
            }
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
    use crate::{FitSettings, Kernel};

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
    fn new_centres_are_spread_not_clumped() {
        // A 60 × 60 grid at spacing 0.01 with centres every 0.1; every
        // point within 0.15 of (0.3, 0.3) is badly fitted (worst at the
        // middle). The worst 100 would all be neighbours in that disc.
        let side = 60;
        let cs: Vec<Constraint<2>> = (0..side * side)
            .map(|i| Constraint::new([(i % side) as f32 * 0.01, (i / side) as f32 * 0.01], 0.0))
            .collect();
        let chosen: Vec<bool> = (0..cs.len()).map(|i| i % 10 == 0 && (i / side) % 10 == 0).collect();
        let distance = |a: [f32; 2], b: [f32; 2]| f64::from((a[0] - b[0]).hypot(a[1] - b[1]));
        let residual: Vec<f64> =
            cs.iter().map(|c| (1.0 - 5.0 * distance(c.position, [0.3, 0.3])).max(0.0) - 0.25).collect();
        let candidates: Vec<usize> = (0..cs.len()).filter(|&i| !chosen[i] && residual[i] > 0.0).collect();
        let in_disc = candidates.len();
        assert!(in_disc > 600, "{in_disc}");
        let picked = worst_spread(&cs, &chosen, &residual, candidates, 100);
        // The worst first (the middle is a centre: a neighbour of it);
        // then far fewer than the disc holds, none nearer to an earlier
        // pick than half its distance to the nearest centre.
        assert!(distance(cs[picked[0]].position, [0.3, 0.3]) < 0.0101, "{:?}", cs[picked[0]].position);
        assert!(picked.len() >= 10 && picked.len() < in_disc / 5, "{} of {in_disc}", picked.len());
        let centres: Vec<[f32; 2]> = (0..cs.len()).filter(|&i| chosen[i]).map(|i| cs[i].position).collect();
        for (k, &a) in picked.iter().enumerate() {
            assert!(residual[a] > 0.0 && !chosen[a]);
            let nearest = centres.iter().map(|&c| distance(cs[a].position, c)).fold(f64::INFINITY, f64::min);
            for &b in &picked[k + 1..] {
                assert!(distance(cs[a].position, cs[b].position) > 0.5 * nearest - 1e-6);
                assert!(residual[b] <= residual[a]);
            }
        }
        // Nothing to pick, or no room: nothing picked.
        assert!(worst_spread(&cs, &chosen, &residual, Vec::new(), 10).is_empty());
        assert!(worst_spread(&cs, &chosen, &residual, vec![5], 0).is_empty());
    }

    #[test]
    fn greedy_rounds_through_the_hierarchical_solver_reach_the_tolerance() {
        // Every subset goes through GMRES with the greedy's looser stopping
        // rule; the tolerance must still hold, exactly, at every constraint.
        let constraints = ellipsoid(1500);
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            let greedy = GreedySettings { tolerance: 1e-2, initial: 300, max_centres: 3000 };
            let settings = FitSettings {
                centres: Centres::Greedy(greedy),
                solver: crate::Solver::Hierarchical,
                ..FitSettings::default().with_kernel(kernel)
            };
            let fit = Interpolant::fit(&constraints, &settings).unwrap();
            let report = fit.report();
            assert!(
                matches!(report.factorization, crate::Factorization::Hierarchical { .. }),
                "{kernel:?}: {report:?}"
            );
            assert!(report.fallback.is_none() && report.greedy.as_ref().unwrap().converged, "{report:?}");
            let worst = constraints
                .iter()
                .map(|c| (fit.value_f64(c.position.map(f64::from)) - f64::from(c.value)).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 1e-2 + 1e-4, "{kernel:?}: worst residual {worst}");
        }
    }

    #[test]
    fn the_greedy_stopping_rule_fits_every_centre_well_within_the_tolerance() {
        // τ √n max|h| ≤ tolerance / 100, and never tighter than the exact fit.
        for (tolerance, n) in [(1e-2, 16_000usize), (1e-3, 1_000_000), (1.0, 100)] {
            let tau = iterative_settings(tolerance, n).tolerance;
            assert!(tau * (n as f64).sqrt() <= tolerance / 100.0 * (1.0 + 1e-12), "{tolerance} {n}");
            assert!(tau >= hierarchical::Settings::default().tolerance);
        }
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
