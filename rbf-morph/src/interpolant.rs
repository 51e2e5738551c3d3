//! Variational (polyharmonic) scattered-data interpolation in `D` dimensions,
//! paper §3: `f(x) = Σ_j d_j φ(|x − c_j|) + P(x)` with a degree-one `P`.

use crate::duplicates::{DuplicatePolicy, dedup};
use crate::error::RbfError;
use crate::greedy::{Centres, GreedyReport, fit_greedy};
use crate::hierarchical::IterativeFailure;
use crate::kernel::Kernel;
use crate::slice::{Slice2, Slice3, SliceEval};
pub use crate::solve::{Factorization, Solver};
use crate::treecode::Evaluation;
use isomorph_common::MorphError;
use rayon::prelude::*;

/// One interpolation constraint: `f(position) = value`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constraint<const D: usize> {
    /// Where the value is prescribed.
    pub position: [f32; D],
    /// The prescribed value (0 on a boundary, 1 for a normal constraint).
    pub value: f32,
}

impl<const D: usize> Constraint<D> {
    /// A constraint `f(position) = value`.
    pub fn new(position: [f32; D], value: f32) -> Self {
        Self { position, value }
    }
}

/// Settings of [`Interpolant::fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// The radial basis function (default `r² log r`).
    pub kernel: Kernel,
    /// Smoothing parameter `λ ≥ 0` added to the diagonal of `Φ` (in the
    /// normalized coordinates where the constraints' bounding box has unit
    /// diagonal): `0` interpolates exactly, larger values trade exactness for
    /// smoothness on noisy data (a smoothing spline). Default 0.
    pub smoothing: f64,
    /// Constraints closer than this fraction of their bounding-box diagonal
    /// are near-duplicates (default `1e-6`); see [`FitSettings::duplicates`].
    pub duplicate_tolerance: f64,
    /// What to do with near-duplicates (default [`DuplicatePolicy::MergeEqual`]).
    pub duplicates: DuplicatePolicy,
    /// Evaluate the fitted function at every constraint and report the
    /// largest residual (`O(n²)`, cheap next to the `O(n³)` solve). Default on.
    pub check_residual: bool,
    /// How the system is solved (default [`Solver::Auto`]: the hierarchical
    /// solver from 4000 constraints, below that the slab solver for two
    /// separated groups of constraints, the dense Cholesky otherwise).
    pub solver: Solver,
    /// Which constraints become centres (default [`Centres::All`]: exact
    /// interpolation; [`Centres::Greedy`] fits to a tolerance through fewer
    /// centres).
    pub centres: Centres,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            kernel: Kernel::ThinPlate,
            smoothing: 0.0,
            duplicate_tolerance: 1e-6,
            duplicates: DuplicatePolicy::MergeEqual,
            check_residual: true,
            solver: Solver::Auto,
            centres: Centres::All,
        }
    }
}

impl FitSettings {
    /// These settings with `kernel`.
    pub fn with_kernel(mut self, kernel: Kernel) -> Self {
        self.kernel = kernel;
        self
    }
}

/// What a user needs to trust a fit.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct FitReport {
    /// Constraints in the solved system (after merging near-duplicates).
    pub constraints: usize,
    /// Input constraints merged into others.
    pub merged: usize,
    /// The factorization that solved the projected system.
    pub factorization: Factorization,
    /// Estimated reciprocal condition number (1-norm) of the projected
    /// system; values near machine epsilon (`2e-16`) mean digits are lost.
    pub rcond: f64,
    /// Largest `|f(c_i) − h_i|` over the constraints, relative to the largest
    /// `|h_i|` (`None` when [`FitSettings::check_residual`] is off). With
    /// [`Centres::Greedy`], over every input constraint, not only the
    /// centres (evaluated in f32, to about `1e-4`).
    pub max_residual: Option<f64>,
    /// The greedy selection's rounds ([`Centres::Greedy`] with more
    /// constraints than its initial subset).
    pub greedy: Option<GreedyReport>,
    /// Set when the hierarchical solver did not converge and the dense
    /// solver solved the system instead: its iterations and last residual.
    /// The fit is then exact but took the dense solver's `O(n²)` memory and
    /// `O(n³)` time on top of the failed iteration.
    pub fallback: Option<IterativeFailure>,
}

/// A fitted variational implicit function in `D` dimensions (`D = 2..=6`).
///
/// Constraint positions are centred on their bounding box and scaled to unit
/// diagonal before the solve (both kernels give the same interpolant under
/// this map, since the weights annihilate degree-one polynomials; it only
/// improves the conditioning of the polynomial block). The system is solved
/// in f64 by the projected Cholesky method described in the crate docs.
///
/// ```
/// use isomorph_rbf::{Constraint, FitSettings, Interpolant};
/// // A circle: zeros on the unit circle, 1 at the centre.
/// let mut cs: Vec<Constraint<2>> = (0..12)
///     .map(|i| {
///         let a = i as f32 * std::f32::consts::TAU / 12.0;
///         Constraint::new([a.cos(), a.sin()], 0.0)
///     })
///     .collect();
/// cs.push(Constraint::new([0.0, 0.0], 1.0));
/// let f = Interpolant::fit(&cs, &FitSettings::default()).unwrap();
/// assert!(f.value([0.0, 0.0]) > 0.99 && f.value([0.0, 2.0]) < 0.0);
/// assert!(f.report().max_residual.unwrap() < 1e-10);
/// ```
#[derive(Debug, Clone)]
pub struct Interpolant<const D: usize> {
    kernel: Kernel,
    /// Centres in normalized coordinates.
    centres: Vec<[f64; D]>,
    weights: Vec<f64>,
    constant: f64,
    linear: [f64; D],
    shift: [f64; D],
    scale: f64,
    report: FitReport,
}

impl<const D: usize> Interpolant<D> {
    /// Fits the interpolant through `constraints`.
    ///
    /// # Errors
    /// [`RbfError::NonFinite`] for NaN/infinite input,
    /// [`MorphError::BadSetting`] for a negative or NaN smoothing or
    /// tolerance, [`RbfError::NearDuplicate`] per [`FitSettings::duplicates`],
    /// [`RbfError::TooFewConstraints`] with fewer than `D + 1`,
    /// [`RbfError::NotUnisolvent`] when the positions are coplanar in `D`
    /// dimensions, [`RbfError::Singular`] when even the indefinite fallback
    /// finds the system singular.
    pub fn fit(constraints: &[Constraint<D>], settings: &FitSettings) -> Result<Self, RbfError> {
        match settings.centres {
            Centres::Greedy(greedy) if constraints.len() > greedy.initial => {
                Self::check_input(constraints, settings)?;
                let (mut fit, report) = fit_greedy(constraints, &greedy, |subset, iterative| {
                    Self::fit_solved(subset, settings, iterative)
                })?;
                fit.report.max_residual = report.rounds.last().map(|r| r.max_residual);
                fit.report.greedy = Some(report);
                Ok(fit)
            }
            _ => Self::fit_all(constraints, settings),
        }
    }

    /// The settings and constraints [`Interpolant::fit`] refuses.
    fn check_input(constraints: &[Constraint<D>], settings: &FitSettings) -> Result<(), RbfError> {
        const { assert!(D >= 2 && D <= 6, "Interpolant supports 2 to 6 dimensions") };
        if !(settings.smoothing >= 0.0 && settings.smoothing.is_finite()) {
            return Err(
                MorphError::bad_setting("smoothing", settings.smoothing, "a finite number ≥ 0").into()
            );
        }
        if !(settings.duplicate_tolerance >= 0.0 && settings.duplicate_tolerance.is_finite()) {
            return Err(MorphError::bad_setting(
                "duplicate_tolerance",
                settings.duplicate_tolerance,
                "a finite number ≥ 0",
            )
            .into());
        }
        for (index, c) in constraints.iter().enumerate() {
            if c.position.iter().any(|x| !x.is_finite()) {
                return Err(RbfError::NonFinite { index, what: "position" });
            }
            if !c.value.is_finite() {
                return Err(RbfError::NonFinite { index, what: "value" });
            }
        }
        if constraints.len() < D + 1 {
            return Err(RbfError::TooFewConstraints { got: constraints.len(), needed: D + 1, dim: D });
        }
        Ok(())
    }

    /// [`Interpolant::fit`] with every constraint a centre and the
    /// hierarchical solver's `iterative` settings (tests reach the fallback
    /// and the error paths through them).
    #[cfg(test)]
    pub(crate) fn fit_with(
        constraints: &[Constraint<D>],
        settings: &FitSettings,
        iterative: &crate::hierarchical::Settings,
    ) -> Result<Self, RbfError> {
        Self::fit_solved(constraints, settings, iterative)
    }

    /// Interpolates every constraint.
    fn fit_all(constraints: &[Constraint<D>], settings: &FitSettings) -> Result<Self, RbfError> {
        Self::fit_solved(constraints, settings, &crate::hierarchical::Settings::default())
    }

    /// [`Interpolant::fit_all`] with the hierarchical solver's settings.
    fn fit_solved(
        constraints: &[Constraint<D>],
        settings: &FitSettings,
        iterative: &crate::hierarchical::Settings,
    ) -> Result<Self, RbfError> {
        Self::check_input(constraints, settings)?;
        // Normalize: bounding-box centre to the origin, unit diagonal.
        let mut lo = [f64::INFINITY; D];
        let mut hi = [f64::NEG_INFINITY; D];
        for c in constraints {
            for k in 0..D {
                lo[k] = lo[k].min(f64::from(c.position[k]));
                hi[k] = hi[k].max(f64::from(c.position[k]));
            }
        }
        let shift: [f64; D] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
        let diag = (0..D).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        let scale = if diag > 0.0 { 1.0 / diag } else { 1.0 };
        let normalized: Vec<[f64; D]> = constraints
            .iter()
            .map(|c| std::array::from_fn(|k| (f64::from(c.position[k]) - shift[k]) * scale))
            .collect();
        let values: Vec<f64> = constraints.iter().map(|c| f64::from(c.value)).collect();
        let (kept, values) = dedup(&normalized, &values, settings.duplicate_tolerance, settings.duplicates)?;
        let centres: Vec<[f64; D]> = kept.iter().map(|&i| normalized[i]).collect();
        let flat: Vec<f64> = centres.iter().flatten().copied().collect();
        let sol = crate::solve::solve_with(
            &flat,
            D,
            &values,
            settings.kernel,
            settings.smoothing,
            settings.solver,
            iterative,
        )?;
        let centre_values = sol.centre_values;
        let mut interpolant = Self {
            kernel: settings.kernel,
            weights: sol.weights,
            constant: sol.poly[0],
            linear: std::array::from_fn(|k| sol.poly[k + 1]),
            centres,
            shift,
            scale,
            report: FitReport {
                constraints: kept.len(),
                merged: constraints.len() - kept.len(),
                factorization: sol.factorization,
                rcond: sol.rcond,
                max_residual: None,
                greedy: None,
                fallback: sol.fallback,
            },
        };
        if settings.check_residual {
            let hmax = values.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
            let worst = centre_values
                .unwrap_or_else(|| interpolant.values_at_centres())
                .iter()
                .zip(&values)
                .map(|(f, h)| (f - h).abs())
                .fold(0.0, f64::max);
            interpolant.report.max_residual = Some(worst / hmax);
        }
        Ok(interpolant)
    }

    /// `f` at every centre, using the symmetry `φ_ij = φ_ji`: each pair's
    /// kernel is evaluated once (`n²/2` kernels). Parallel over fixed blocks
    /// of rows, each with its own accumulator, summed in block order, so the
    /// result does not depend on the number of threads.
    fn values_at_centres(&self) -> Vec<f64> {
        const ROWS: usize = 256;
        let n = self.centres.len();
        let (c, d) = (&self.centres, &self.weights);
        let coords: [Vec<f64>; D] = std::array::from_fn(|k| c.iter().map(|x| x[k]).collect());
        let partial: Vec<Vec<f64>> = (0..n.div_ceil(ROWS))
            .into_par_iter()
            .map(|block| {
                let mut acc = vec![0.0f64; n];
                let mut phi = vec![0.0f64; n];
                for i in block * ROWS..((block + 1) * ROWS).min(n) {
                    // φ(|c_i − c_j|) for j ≤ i, vectorized.
                    let phi = &mut phi[..=i];
                    phi.fill(0.0);
                    for xs in &coords {
                        let xi = xs[i];
                        phi.iter_mut().zip(xs).for_each(|(r2, x)| *r2 += (x - xi) * (x - xi));
                    }
                    self.kernel.eval_r2_in_place(phi);
                    let (own_phi, others) = phi.split_last_mut().expect("j = i is included");
                    let mut own = d[i] * *own_phi;
                    for ((a, p), dj) in acc.iter_mut().zip(others.iter()).zip(d) {
                        own += dj * p;
                        *a += d[i] * p;
                    }
                    acc[i] += own;
                }
                acc
            })
            .collect();
        let mut sums: Vec<f64> =
            c.iter().map(|x| self.constant + (0..D).map(|k| self.linear[k] * x[k]).sum::<f64>()).collect();
        for acc in &partial {
            sums.iter_mut().zip(acc).for_each(|(s, a)| *s += a);
        }
        sums
    }

    /// `f` at a normalized position.
    fn value_normalized(&self, x: &[f64; D]) -> f64 {
        let mut sum = self.constant;
        for k in 0..D {
            sum += self.linear[k] * x[k];
        }
        for (c, d) in self.centres.iter().zip(&self.weights) {
            let r2: f64 = (0..D).map(|k| (x[k] - c[k]) * (x[k] - c[k])).sum();
            sum += d * self.kernel.eval_r2(r2);
        }
        sum
    }

    fn normalize(&self, x: &[f64; D]) -> [f64; D] {
        std::array::from_fn(|k| (x[k] - self.shift[k]) * self.scale)
    }

    /// `f` at the constraints' positions, in f32 batches (as slices
    /// evaluate: within about `1e-4` of the f64 value).
    pub(crate) fn values_at(&self, constraints: &[Constraint<D>]) -> Result<Vec<f32>, RbfError> {
        let points: Vec<[f32; D]> = constraints.iter().map(|c| c.position).collect();
        let mut out = vec![0.0; points.len()];
        self.slice_eval::<D>(&[])?.values(&points, &mut out);
        Ok(out)
    }

    /// `f(x)` in f64 (exact evaluation, `O(n)`; use slices for batches).
    pub fn value_f64(&self, x: [f64; D]) -> f64 {
        self.value_normalized(&self.normalize(&x))
    }

    /// `f(x)` (computed in f64, rounded).
    pub fn value(&self, x: [f32; D]) -> f32 {
        self.value_f64(x.map(f64::from)) as f32
    }

    /// The analytic gradient `∇f(x)` in f64 (points inward for shapes).
    pub fn gradient_f64(&self, x: [f64; D]) -> [f64; D] {
        let xn = self.normalize(&x);
        let mut g = self.linear;
        for (c, d) in self.centres.iter().zip(&self.weights) {
            let r2: f64 = (0..D).map(|k| (xn[k] - c[k]) * (xn[k] - c[k])).sum();
            let s = d * self.kernel.gradient_factor_r2(r2);
            for k in 0..D {
                g[k] += s * (xn[k] - c[k]);
            }
        }
        g.map(|v| v * self.scale)
    }

    /// The kernel weights `λ_j` (one per centre, in the order of the
    /// constraints after merging): their size tells the conditioning
    /// (cancelling weights of `1e6` need `f64` evaluation).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The fit report (conditioning, residual, merges).
    pub fn report(&self) -> &FitReport {
        &self.report
    }

    /// The kernel.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Number of centres (constraints after merging).
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// Always false: a fitted interpolant has at least `D + 1` centres.
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// The 3D slice with the last `D − 3` coordinates fixed to `fixed`
    /// (e.g. `[t]` for a 4D shape transformation): a fast [`Field3`](isomorph_common::Field3).
    ///
    /// # Errors
    /// [`RbfError::SliceArity`] unless `fixed.len() == D − 3`;
    /// [`RbfError::NonFinite`] for a NaN coordinate.
    pub fn slice3(&self, fixed: &[f32]) -> Result<Slice3, RbfError> {
        Ok(Slice3::new(self.slice_eval::<3>(fixed)?))
    }

    /// The 2D slice with the last `D − 2` coordinates fixed to `fixed`
    /// (e.g. `[t]` for a 3D transformation of 2D shapes).
    ///
    /// # Errors
    /// As [`Interpolant::slice3`], with `D − 2` fixed coordinates.
    pub fn slice2(&self, fixed: &[f32]) -> Result<Slice2, RbfError> {
        Ok(Slice2::new(self.slice_eval::<2>(fixed)?))
    }

    /// Reduces `f` on an `S`-dimensional axis-aligned slice to an
    /// `S`-dimensional sum with a per-centre offset `w_j = |fixed − c_j,rest|²`.
    pub(crate) fn slice_eval<const S: usize>(&self, fixed: &[f32]) -> Result<SliceEval<S>, RbfError> {
        if D < S || fixed.len() != D - S {
            return Err(RbfError::SliceArity {
                dim: D,
                slice_dim: S,
                expected: D.saturating_sub(S),
                got: fixed.len(),
            });
        }
        if let Some(index) = fixed.iter().position(|v| !v.is_finite()) {
            return Err(RbfError::NonFinite { index, what: "position" });
        }
        let rest: Vec<f64> =
            fixed.iter().enumerate().map(|(i, &v)| (f64::from(v) - self.shift[S + i]) * self.scale).collect();
        let mut sources = crate::slice::Sources::<S>::default();
        for (c, d) in self.centres.iter().zip(&self.weights) {
            let offset = rest.iter().enumerate().map(|(i, r)| (r - c[S + i]).powi(2)).sum::<f64>();
            sources.push(std::array::from_fn(|k| c[k] as f32), offset as f32, *d as f32);
        }
        let constant =
            self.constant + rest.iter().enumerate().map(|(i, r)| self.linear[S + i] * r).sum::<f64>();
        Ok(SliceEval {
            kernel: self.kernel,
            sources,
            constant,
            linear: std::array::from_fn(|k| self.linear[k]),
            shift: std::array::from_fn(|k| self.shift[k]),
            scale: self.scale,
            evaluation: Evaluation::default(),
            tree: std::sync::OnceLock::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A seeded xorshift generator for reproducible random constraint sets.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    fn random_set<const D: usize>(n: usize, seed: u64) -> Vec<Constraint<D>> {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        (0..n)
            .map(|_| Constraint::new(std::array::from_fn(|_| rng.next() * 2.0 - 1.0), rng.next() * 4.0 - 2.0))
            .collect()
    }

    fn assert_interpolates<const D: usize>(cs: &[Constraint<D>], settings: &FitSettings) -> Interpolant<D> {
        let f = Interpolant::fit(cs, settings).unwrap();
        let hmax = cs.iter().fold(0.0f64, |m, c| m.max(f64::from(c.value).abs()));
        for c in cs {
            let got = f.value_f64(c.position.map(f64::from));
            let err = (got - f64::from(c.value)).abs();
            assert!(err <= 1e-8 * hmax, "at {:?}: expected {}, got {got}, diff {err:e}", c.position, c.value);
        }
        assert!(f.report().max_residual.unwrap() <= 1e-8);
        f
    }

    #[test]
    fn interpolates_in_every_dimension_with_both_kernels() {
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            let s = FitSettings::default().with_kernel(kernel);
            assert_interpolates(&random_set::<2>(60, 1), &s);
            assert_interpolates(&random_set::<3>(80, 2), &s);
            assert_interpolates(&random_set::<4>(100, 3), &s);
            assert_interpolates(&random_set::<5>(60, 4), &s);
            let f = assert_interpolates(&random_set::<6>(60, 5), &s);
            assert_eq!(f.report().factorization, Factorization::Cholesky);
            assert!(f.report().rcond > 1e-14 && f.report().rcond <= 1.0, "{}", f.report().rcond);
        }
    }

    #[test]
    fn reproduces_affine_functions_exactly() {
        // Values from a degree-one polynomial (rounded to f32, hence the
        // 1e-6 tolerance): the weights nearly vanish.
        let cs: Vec<Constraint<3>> = random_set::<3>(40, 9)
            .into_iter()
            .map(|c| Constraint::new(c.position, 0.5 + c.position[0] - 2.0 * c.position[2]))
            .collect();
        let f = Interpolant::fit(&cs, &FitSettings::default()).unwrap();
        let x = [0.3f64, -0.7, 0.25];
        assert!((f.value_f64(x) - (0.5 + 0.3 - 0.5)).abs() < 1e-6, "{}", f.value_f64(x));
        let g = f.gradient_f64(x);
        assert!((g[0] - 1.0).abs() < 1e-5 && g[1].abs() < 1e-5 && (g[2] + 2.0).abs() < 1e-5, "{g:?}");
    }

    #[test]
    fn minimal_set_is_the_affine_interpolant() {
        let cs = [
            Constraint::new([0.0, 0.0], 1.0),
            Constraint::new([1.0, 0.0], 2.0),
            Constraint::new([0.0, 1.0], 3.0),
        ];
        let f = Interpolant::fit(&cs, &FitSettings::default()).unwrap();
        assert!((f.value_f64([1.0, 1.0]) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn gradient_matches_differences() {
        let f = Interpolant::fit(&random_set::<3>(50, 11), &FitSettings::default()).unwrap();
        let x = [0.1f64, 0.2, -0.3];
        let g = f.gradient_f64(x);
        for k in 0..3 {
            let h = 1e-6;
            let mut a = x;
            let mut b = x;
            a[k] += h;
            b[k] -= h;
            let fd = (f.value_f64(a) - f.value_f64(b)) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-5 * (1.0 + g[k].abs()), "axis {k}: {fd} vs {}", g[k]);
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let s = FitSettings::default();
        let few = random_set::<3>(3, 1);
        assert!(matches!(
            Interpolant::fit(&few, &s),
            Err(RbfError::TooFewConstraints { got: 3, needed: 4, dim: 3 })
        ));
        let mut nan = random_set::<3>(10, 1);
        nan[4].position[1] = f32::NAN;
        assert!(matches!(
            Interpolant::fit(&nan, &s),
            Err(RbfError::NonFinite { index: 4, what: "position" })
        ));
        let mut nanv = random_set::<3>(10, 1);
        nanv[2].value = f32::INFINITY;
        assert!(matches!(Interpolant::fit(&nanv, &s), Err(RbfError::NonFinite { index: 2, what: "value" })));
        // All points on the plane z = 0.25 in 3D.
        let flat: Vec<Constraint<3>> = random_set::<3>(30, 3)
            .into_iter()
            .map(|c| Constraint::new([c.position[0], c.position[1], 0.25], c.value))
            .collect();
        assert!(matches!(Interpolant::fit(&flat, &s), Err(RbfError::NotUnisolvent { rank: 2, dim: 3 })));
        // Collinear in 2D.
        let line: Vec<Constraint<2>> =
            (0..10).map(|i| Constraint::new([i as f32, 2.0 * i as f32], 0.0)).collect();
        assert!(matches!(Interpolant::fit(&line, &s), Err(RbfError::NotUnisolvent { rank: 1, dim: 2 })));
        let bad = FitSettings { smoothing: -1.0, ..FitSettings::default() };
        assert!(matches!(
            Interpolant::fit(&random_set::<2>(10, 1), &bad),
            Err(RbfError::Morph(MorphError::BadSetting { .. }))
        ));
    }

    #[test]
    fn near_duplicates_are_merged_or_rejected() {
        let mut cs = random_set::<3>(30, 5);
        let mut dup = cs[7];
        dup.position[0] += 1e-7;
        cs.push(dup);
        let f = Interpolant::fit(&cs, &FitSettings::default()).unwrap();
        assert_eq!(f.report().merged, 1);
        assert_eq!(f.len(), 30);
        dup.value += 1.0;
        cs.push(dup);
        let err = Interpolant::fit(&cs, &FitSettings::default()).unwrap_err();
        assert!(matches!(err, RbfError::NearDuplicate { first: 7, .. }), "{err}");
        // Without merging, the duplicate pair is singular: the fit reports
        // it instead of returning garbage.
        let exact = FitSettings { duplicate_tolerance: 0.0, ..FitSettings::default() };
        let mut same = random_set::<3>(30, 5);
        same.push(same[3]);
        let err = Interpolant::fit(&same, &exact).unwrap_err();
        assert!(matches!(err, RbfError::Singular { .. }), "{err}");
    }

    #[test]
    fn smoothing_trades_exactness_for_smoothness() {
        let cs = random_set::<2>(80, 21);
        let exact = Interpolant::fit(&cs, &FitSettings::default()).unwrap();
        let smooth =
            Interpolant::fit(&cs, &FitSettings { smoothing: 1e-2, ..FitSettings::default() }).unwrap();
        assert!(exact.report().max_residual.unwrap() < 1e-9);
        let r = smooth.report().max_residual.unwrap();
        assert!(r > 1e-4, "smoothing should leave a residual, got {r:e}");
        assert!(smooth.report().rcond > exact.report().rcond);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
        #[test]
        fn interpolates_random_sets(
            pts in proptest::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, -5.0f32..5.0), 8..60),
            cubic in any::<bool>(),
        ) {
            let cs: Vec<Constraint<4>> = pts.iter().map(|&(a, b, c, d, v)| Constraint::new([a, b, c, d], v)).collect();
            let kernel = if cubic { Kernel::Cubic } else { Kernel::ThinPlate };
            let settings = FitSettings::default().with_kernel(kernel);
            match Interpolant::fit(&cs, &settings) {
                Ok(f) => {
                    let hmax = cs.iter().fold(1e-30f64, |m, c| m.max(f64::from(c.value).abs()));
                    for c in &cs {
                        let got = f.value_f64(c.position.map(f64::from));
                        prop_assert!((got - f64::from(c.value)).abs() <= 1e-8 * hmax,
                            "expected {}, got {got}", c.value);
                    }
                }
                // Random near-duplicates with different values are a valid refusal.
                Err(RbfError::NearDuplicate { .. }) => {}
                Err(e) => prop_assert!(false, "unexpected error {e}"),
            }
        }
    }
}
