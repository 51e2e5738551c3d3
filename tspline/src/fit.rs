//! The initial T-spline level set (paper §3.2): weighted least squares of
//! eq. 3–4 to the source's signed distance `d_A` with weight
//! `ω = exp(−d_A²)`.
//!
//! Eq. 4 replaces the integral of eq. 3 by `N₀ ≫ n` uniformly distributed
//! points with equal weights `V(D)/N₀`. Here the integral is discretized leaf
//! by leaf instead: `q³` midpoint-rule points per leaf with weight
//! `vol(leaf)/q³`. It is the same quadrature of eq. 3, but the points are
//! dense where the T-mesh is fine (near the surfaces), so every blending
//! function sees many samples without millions of points in empty space.
//! A small Tikhonov term towards `d_A` at each anchor keeps the system
//! positive definite even where blending functions are linearly dependent
//! (note §3.4).
//!
//! # Final refinement
//! "If the accuracy of the approximation is not sufficient, a better `L₀`
//! can be found by using more degrees of freedom … and applying the 'final
//! refinement' step" (§3.2). With [`FitSettings::refinement`] set, every
//! leaf of the T-mesh that contains a source surface sample whose
//! first-order distance `|f|/|∇f|` exceeds the tolerance is split into
//! eight (the tree is 2:1 balanced again), and the fit is repeated on the
//! finer T-mesh, for at most the given number of rounds. Leaves at the
//! T-mesh's maximum depth cannot be split: refinement adds degrees of
//! freedom where the octree stopped early (few samples per cell, large
//! `n_T`), not beyond the depth limit.

use crate::error::{TsplineError, check_range};
use crate::lsq::{self, LeafRows};
use crate::tmesh::TMesh;
use crate::tspline::TSpline;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Arc;

/// Settings of the initial fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// Quadrature points per axis and leaf (`q`; `q³` per leaf).
    pub quadrature: u32,
    /// Tikhonov weight relative to the mean diagonal of the data term.
    pub tikhonov: f64,
    /// The "final refinement" (§3.2, module docs); `None` fits once on the
    /// given T-mesh.
    pub refinement: Option<Refinement>,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self { quadrature: 2, tikhonov: 1e-6, refinement: None }
    }
}

/// When and how often the fit refines its T-mesh (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refinement {
    /// Split the leaves holding a source surface sample whose first-order
    /// distance `|f|/|∇f|` to the zero set exceeds this (domain units, in
    /// `(0, 2]`; e.g. a tenth of the finest cell).
    pub tolerance: f64,
    /// At most this many refine-and-refit rounds (0–7: each round halves
    /// the leaves it splits, and the octree is at most
    /// [`crate::MAX_DEPTH`] deep). Stops early when no leaf can be split.
    pub max_rounds: usize,
}

impl FitSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting).
    pub fn validate(&self) -> Result<(), TsplineError> {
        check_range("quadrature", f64::from(self.quadrature), 1.0, 8.0, "1..=8")?;
        check_range("tikhonov", self.tikhonov, 1e-14, 1.0, "1e-14..=1")?;
        if let Some(r) = self.refinement {
            check_range("refinement tolerance", r.tolerance, 1e-12, 2.0, "(0, 2]")?;
            check_range("refinement rounds", r.max_rounds as f64, 0.0, f64::from(crate::MAX_DEPTH), "0..=7")?;
        }
        Ok(())
    }
}

/// The accuracy of one fit on one T-mesh: the initial fit, or the fit after
/// one refinement round.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FitRound {
    /// Coefficients (`n`) of this round's T-mesh.
    pub coefficients: usize,
    /// Leaves split before this round's fit, including the splits that
    /// restore the 2:1 balance (0 for the initial fit).
    pub leaves_split: usize,
    /// Largest `|f| / |∇f|` over the source surface samples, domain units.
    pub max_surface_error: f64,
    /// Mean of the same.
    pub mean_surface_error: f64,
}

/// How well the fit approximates the source (the last round's fit).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct FitReport {
    /// Quadrature points used (`N₀`).
    pub samples: usize,
    /// Coefficients (`n`).
    pub coefficients: usize,
    /// Non-zeros of the lower triangle of the normal matrix.
    pub nonzeros: usize,
    /// Largest `|f| / |∇f|` (first-order distance of the zero set) over the
    /// source surface samples, domain units.
    pub max_surface_error: f64,
    /// Mean of the same.
    pub mean_surface_error: f64,
    /// Smallest and largest `|∇f|` on the source surface samples (≈ 1 for a
    /// good distance fit).
    pub gradient_range: (f64, f64),
    /// Every fit made: the initial one first, then one per refinement round
    /// (just the initial one without [`FitSettings::refinement`]).
    pub rounds: Vec<FitRound>,
}

/// Fits `f ≈ d_A` (paper eq. 3–4), then applies the final refinement when
/// [`FitSettings::refinement`] asks for it (the returned spline's T-mesh is
/// then finer than `mesh`). `distance` is the source's signed distance in
/// domain units (positive inside); `surface` are samples of the source
/// surface, used to measure the error.
///
/// # Errors
/// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) for bad settings, [`TsplineError::NonFinite`]
/// when `distance` returns NaN, [`TsplineError::Singular`] when the system
/// cannot be factorized.
pub fn fit<D: Fn(DVec3) -> f64 + Sync>(
    mesh: Arc<TMesh>,
    distance: D,
    surface: &[DVec3],
    settings: &FitSettings,
) -> Result<(TSpline, FitReport), TsplineError> {
    settings.validate()?;
    let (mut spline, mut stats) = fit_once(mesh, &distance, settings)?;
    let mut errors = surface_errors(&spline, surface);
    let mut rounds = vec![round(&spline, &errors, 0)];
    if let Some(refinement) = settings.refinement {
        for _ in 0..refinement.max_rounds {
            let bad: Vec<DVec3> = surface
                .iter()
                .zip(&errors)
                .filter(|(_, e)| e.0 > refinement.tolerance)
                .map(|(p, _)| *p)
                .collect();
            let finer = spline.mesh().refined(&bad);
            let leaves_split = (finer.leaf_count() - spline.mesh().leaf_count()) / 7;
            if leaves_split == 0 {
                break;
            }
            (spline, stats) = fit_once(Arc::new(finer), &distance, settings)?;
            errors = surface_errors(&spline, surface);
            rounds.push(round(&spline, &errors, leaves_split));
        }
    }
    let last = rounds[rounds.len() - 1];
    Ok((
        spline,
        FitReport {
            samples: stats.samples,
            coefficients: last.coefficients,
            nonzeros: stats.nonzeros,
            max_surface_error: last.max_surface_error,
            mean_surface_error: last.mean_surface_error,
            gradient_range: gradient_range(&errors),
            rounds,
        },
    ))
}

/// Quadrature points and normal-matrix non-zeros of one fit.
struct FitStats {
    samples: usize,
    nonzeros: usize,
}

/// One weighted least-squares fit of eq. 3–4 on `mesh`.
fn fit_once<D: Fn(DVec3) -> f64 + Sync>(
    mesh: Arc<TMesh>,
    distance: &D,
    settings: &FitSettings,
) -> Result<(TSpline, FitStats), TsplineError> {
    let q = settings.quadrature as usize;
    let blocks: Vec<LeafRows> = (0..mesh.leaf_count())
        .into_par_iter()
        .map_init(
            || (crate::basis::LocalBasis::default(), Vec::new(), Vec::new()),
            |(local, r, dr), leaf| {
                let (lo, hi) = mesh.leaf_box(leaf);
                let size = hi - lo;
                let w0 = size.x * size.y * size.z / (q * q * q) as f64;
                let mut blk = LeafRows::default();
                for k in 0..q * q * q {
                    let t = DVec3::new((k % q) as f64, (k / q % q) as f64, (k / (q * q)) as f64);
                    let p = lo + (t + DVec3::splat(0.5)) / q as f64 * size;
                    let d = distance(p);
                    local.at(&mesh, p);
                    if !local.rational(r, dr) {
                        continue;
                    }
                    blk.push(r, w0 * (-d * d).exp(), d);
                }
                blk
            },
        )
        .collect();
    if blocks.iter().any(|b| b.rhs.iter().any(|v| !v.is_finite())) {
        return Err(TsplineError::NonFinite("source distance"));
    }
    let samples = blocks.iter().map(LeafRows::len).sum();
    let reference: Vec<f64> = (0..mesh.anchor_count())
        .into_par_iter()
        .map(|i| {
            let d = distance(mesh.anchor_position(i));
            if d.is_finite() { d } else { 0.0 }
        })
        .collect();
    let (coeffs, stats) =
        lsq::solve(&mesh, &blocks, settings.tikhonov, &reference, "fit", &mut Default::default())?;
    Ok((TSpline::new(mesh, coeffs)?, FitStats { samples, nonzeros: stats.nonzeros }))
}

/// The error summary of one fit from its per-sample errors.
fn round(spline: &TSpline, errors: &[(f64, f64)], leaves_split: usize) -> FitRound {
    let (max_surface_error, mean_surface_error) = error_summary(errors);
    FitRound {
        coefficients: spline.coefficients().len(),
        leaves_split,
        max_surface_error,
        mean_surface_error,
    }
}

/// Per point: the first-order distance `|f|/|∇f|` and `|∇f|`.
fn surface_errors(spline: &TSpline, points: &[DVec3]) -> Vec<(f64, f64)> {
    points
        .par_iter()
        .map(|&p| {
            let e = spline.eval(p);
            let g = e.gradient.length();
            (e.value.abs() / g.max(1e-12), g)
        })
        .collect()
}

/// Max and mean of the first-order distances (0 for no points).
fn error_summary(errors: &[(f64, f64)]) -> (f64, f64) {
    if errors.is_empty() {
        return (0.0, 0.0);
    }
    let max = errors.iter().fold(0.0f64, |m, e| m.max(e.0));
    (max, errors.iter().map(|e| e.0).sum::<f64>() / errors.len() as f64)
}

/// Smallest and largest `|∇f|` ((0, 0) for no points).
fn gradient_range(errors: &[(f64, f64)]) -> (f64, f64) {
    if errors.is_empty() {
        return (0.0, 0.0);
    }
    errors.iter().fold((f64::MAX, 0.0f64), |(lo, hi), e| (lo.min(e.1), hi.max(e.1)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tmesh::TMeshSettings;

    #[test]
    fn fits_a_sphere_distance_closely() {
        let pts = crate::demo::sphere_samples(4000, 0.5, DVec3::ZERO);
        let s = TMeshSettings { max_depth: 5, max_samples_per_cell: 8, ..Default::default() };
        let mesh = Arc::new(TMesh::build(&pts, &s).unwrap());
        let settings = FitSettings { quadrature: 3, ..Default::default() };
        let (f, report) = fit(mesh.clone(), |p: DVec3| 0.5 - p.length(), &pts, &settings).unwrap();
        let h = mesh.finest_cell();
        assert!(report.max_surface_error < 0.1 * h, "{report:?} h {h}");
        // Near T-junctions the T-spline space is poorer than the tensor-product
        // one (a uniform depth-5 fit has |∇f| within 1e-3 of 1; measured 0.81 here).
        assert!(report.gradient_range.0 > 0.75 && report.gradient_range.1 < 1.25, "{report:?}");
        assert!(report.samples > 4 * report.coefficients, "N0 ≫ n: {report:?}");
        // Mean curvature of the sphere of radius 0.5 is −2 (convex, positive inside).
        let ks: Vec<f64> = pts.iter().map(|&p| f.eval(p).mean_curvature()).collect();
        let mean = ks.iter().sum::<f64>() / ks.len() as f64;
        assert!((mean + 2.0).abs() < 0.05, "mean κ = {mean}");
        let mean_abs = ks.iter().map(|k| (k + 2.0).abs()).sum::<f64>() / ks.len() as f64;
        // Second derivatives of the rational T-spline are much less accurate
        // near T-junctions (measured mean error 0.76 here, see the crate docs).
        assert!(mean_abs < 1.0, "mean |κ error| {mean_abs}");
    }

    #[test]
    fn uniform_mesh_fit_has_accurate_curvature() {
        let pts = crate::demo::sphere_samples(2000, 0.5, DVec3::ZERO);
        let mesh = Arc::new(TMesh::uniform(4).unwrap());
        let (f, report) = fit(mesh, |p: DVec3| 0.5 - p.length(), &pts, &FitSettings::default()).unwrap();
        assert!(report.max_surface_error < 1e-3, "{report:?}");
        assert!(report.gradient_range.0 > 0.99 && report.gradient_range.1 < 1.01, "{report:?}");
        let worst = pts.iter().fold(0.0f64, |m, &p| m.max((f.eval(p).mean_curvature() + 2.0).abs()));
        assert!(worst < 0.1, "worst κ error {worst}");
    }

    #[test]
    fn final_refinement_reduces_the_surface_error() {
        // A thin torus on an octree that stopped at depth 2 (every cell holds
        // fewer samples than n_T): the unrefined fit cannot resolve the tube.
        let (major, minor) = (0.5, 0.12);
        let torus = move |p: DVec3| minor - DVec3::new(p.truncate().length() - major, 0.0, p.z).length();
        let pts: Vec<DVec3> = (0..4000)
            .map(|i| {
                let (u, v) =
                    (i as f64 * 0.618_034 * std::f64::consts::TAU, i as f64 * 0.021 * std::f64::consts::TAU);
                let rho = major + minor * v.cos();
                DVec3::new(rho * u.cos(), rho * u.sin(), minor * v.sin())
            })
            .collect();
        assert!(pts.iter().all(|&p| torus(p).abs() < 1e-12));
        let s =
            TMeshSettings { max_depth: 5, min_depth: 2, max_samples_per_cell: 100_000, ..Default::default() };
        let mesh = Arc::new(TMesh::build(&pts, &s).unwrap());
        let refinement = Refinement { tolerance: 0.005, max_rounds: 3 };
        let settings = FitSettings { refinement: Some(refinement), ..Default::default() };
        let (f, report) = fit(mesh.clone(), torus, &pts, &settings).unwrap();
        let r = &report.rounds;
        eprintln!("{r:#?}");
        assert_eq!(r.len(), 4, "three refinement rounds");
        assert!(r[0].max_surface_error > 0.04, "the unrefined fit is poor: {r:?}");
        assert!(r.windows(2).all(|w| w[1].coefficients > w[0].coefficients && w[1].leaves_split > 0));
        assert!(report.max_surface_error < 0.2 * r[0].max_surface_error, "{r:?}");
        assert!(report.mean_surface_error < 0.1 * r[0].mean_surface_error, "{r:?}");
        assert_eq!(report.coefficients, f.coefficients().len());
        assert!(f.mesh().is_balanced() && f.mesh().leaf_count() > mesh.leaf_count());
        // Without refinement the report has the initial round only.
        let (_, plain) = fit(mesh, torus, &pts, &FitSettings::default()).unwrap();
        assert_eq!(plain.rounds, vec![r[0]]);
    }

    #[test]
    fn nan_distance_is_an_error() {
        let mesh = Arc::new(TMesh::uniform(2).unwrap());
        let r = fit(mesh, |_p: DVec3| f64::NAN, &[], &FitSettings::default());
        assert!(matches!(r, Err(TsplineError::NonFinite(_))));
    }
}
