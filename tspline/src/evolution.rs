//! Evolution of the T-spline level set towards the target (paper §3.3,
//! note §5): each step samples the zero set, evaluates the speed, solves a
//! sparse least-squares problem for the coefficient velocities `ċ` and takes
//! an explicit Euler step (eq. 9).
//!
//! # Sign convention
//! Fields are positive inside. A zero set moving outward with normal speed
//! `v` satisfies `∂f/∂τ = v |∇f|`, so `v = d_B > 0` inside the target grows
//! the shape there and shrinks it where `d_B < 0` (paper eq. 7). The mean
//! curvature `κ = div(∇f/|∇f|)/2` is negative on convex parts for a
//! positive-inside field, so `v = κ` is mean-curvature flow (convex bumps
//! shrink) and the paper's eq. 8, `v = λ d_B + (1 − λ) κ`, is used verbatim.
//!
//! # Least squares for `ċ` (note §5.3)
//! With samples `p_k` on the zero set (M of them) and band points
//! `q ∈ {p, p ± h n}` (K of them),
//!
//! ```text
//! F(ċ) = 1/M Σ_k (Σ_i ċ_i R_i(p_k) − v_k |∇f(p_k)|)²                      velocity
//!      + ω_D/K Σ_j (2 ∇f(q_j)·Σ_i ċ_i ∇R_i(q_j) + (|∇f(q_j)|² − 1)/τ)²    distance field
//!      + ω_F/L Σ_l (Σ_i ċ_i R_i(x_l))²                                      far field
//!      + ω_T ‖ċ‖²                                                          Tikhonov
//! ```
//!
//! The far-field rows (`x_l` the centres of the `L` leaves whose
//! coefficients have one sign, so that contain no zero, and that are out of
//! the front's reach) are our addition, a regularization of the paper's
//! velocity least squares: the velocity rows live on the zero set only, so
//! elsewhere `ḟ` is what the least-squares fit of the nearby rows spreads
//! over each blending function's support (four cells wide). Where `f` is a
//! shallow negative plateau a little away from a moving surface, that
//! spread lifts it through zero and a new piece of surface appears away
//! from the front (a *birth*, not a pinch-off). The far-field rows hold `ḟ`
//! at zero there, and they must dominate (default weight 100 against the
//! velocity rows' total of 1). Two rules keep them from also holding the
//! front back:
//!
//! - **Out of reach.** A leaf within the front's reach, the step `h`
//!   rounded up to whole finest cells (one at the default step) from a
//!   zero-set sample, gets no row: the next step may enter it. Without this
//!   rule a thin feature growing into empty space (the teapot's handle in
//!   Example 3), whose tip has a few velocity rows against strong rows just
//!   ahead of it, is stopped.
//! - **Constraints, not data.** `ω_T` is relative to the mean diagonal of
//!   the velocity and distance-field rows only. Counted in, the far rows
//!   made up about 99 % of that diagonal at the weight 100 and raised the
//!   Tikhonov damping of the velocity about seventy-fold.
//!
//! **Held cells.** The out-of-reach rule and the one-sign rule leave `ḟ`
//! free in leaves whose coefficients change sign, and there a shallow
//! plateau of `f` can still be lifted through zero away from the front
//! when the front has nearly stopped and the step `Δτ = min(1, h / max|v|)`
//! is long (Example 3: 18 of 22 births followed a step with `Δτ ≥ 0.59`).
//! With [`EvolveSettings::hold_fraction`] `= c > 0`, after the solve every
//! finest cell farther than `h / c` from the front whose centre `x` the
//! step would move towards zero by more than a fraction `c` of its value,
//!
//! ```text
//! f(x) ḟ(x) < 0   and   Δτ |ḟ(x)| > c |f(x)|,      ḟ = Σ_i ċ_i R_i,
//! ```
//!
//! gets a far-field row `ḟ(x) = 0` (same weight per row) and `ċ` is solved
//! again, up to three times. For a distance-like `f` with `ḟ` the extended
//! speed no cell qualifies (at a distance `d > h / c` from the front
//! `|f| ≈ d` and `Δτ |ḟ| ≤ h`), so the rows appear only where the least
//! squares changes `f` off the front faster than the front moves. Unlike a
//! shorter step (tried in the sixth session: Example 3 then stalled), the
//! step stays the front's.
//!
//! The distance-field term asks `G = |∇f|² − 1` to relax as `Ġ = −G/τ`, which
//! keeps `f` close to a signed distance function without re-initialization
//! (the constraint of the paper's reference [29]). `ω_T` is relative to the
//! mean diagonal of the data terms.

use crate::error::{TsplineError, check_range};
use crate::lsq::{self, LeafRows};
use crate::sampling::{Sample, Sampler, zero_set_samples};
use crate::tspline::TSpline;
use glam::DVec3;
use isomorph_common::Control;
use rayon::prelude::*;

/// The speed function of the evolution.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Speed {
    /// The paper's eq. 8: `v = λ d_B + (1 − λ) κ`, `λ = exp(−d_B²)`. Keeps
    /// thin features from splitting (Fig. 3), but far from the target the
    /// curvature term dominates and large growth can stall or collapse
    /// (note §5.2); stalls are detected and reported.
    Paper,
    /// `λ ≡ 1`: `v = d_B`, Breen & Whitaker's speed (the paper's Fig. 2).
    Distance,
    /// The note's robust alternative (§5.2):
    /// `v = clamp(d_B, ±v_max) + β (1 − λ) κ` with `κ` clamped to `±1/h`.
    /// The target stays a fixed point; curvature only regularizes.
    Robust {
        /// Largest distance speed (domain units per unit time), e.g. 0.2.
        v_max: f64,
        /// Curvature weight `β` in units of the T-mesh's finest cell size
        /// (so that it follows the depth), e.g. 1.
        beta_cells: f64,
    },
}

impl Speed {
    /// The robust speed's default largest distance speed `v_max` (domain
    /// units per unit time).
    pub const ROBUST_V_MAX: f64 = 0.2;
    /// The robust speed's default curvature weight `β`, in finest cells.
    pub const ROBUST_BETA_CELLS: f64 = 1.0;
    /// The largest valid `β` in finest cells: the clamped curvature term
    /// `β h κ` is then up to 10 domain units per unit time, fifty times
    /// [`Speed::ROBUST_V_MAX`], and the distance term no longer steers.
    pub const MAX_BETA_CELLS: f64 = 10.0;

    /// [`Speed::Robust`] with the default `v_max` and curvature weight
    /// `beta_cells` (finest cells, 0 to [`Speed::MAX_BETA_CELLS`]).
    pub fn robust(beta_cells: f64) -> Self {
        Speed::Robust { v_max: Self::ROBUST_V_MAX, beta_cells }
    }

    /// A short description for reports, e.g. `robust (v_max 0.2, beta 0.5
    /// finest cells)`.
    pub fn describe(&self) -> String {
        match self {
            Speed::Paper => "paper (eq. 8)".to_string(),
            Speed::Distance => "distance".to_string(),
            Speed::Robust { v_max, beta_cells } => {
                format!("robust (v_max {v_max}, beta {beta_cells} finest cells)")
            }
        }
    }
}

/// Settings of the evolution.
#[derive(Debug, Clone, PartialEq)]
pub struct EvolveSettings {
    /// The speed function.
    pub speed: Speed,
    /// Morph step size `h` of `Δτ = min(1, h / max |v|)` (domain units);
    /// `None` uses half the finest cell size.
    pub step: Option<f64>,
    /// Step cap (0–1 000 000; 0 keeps the initial fit only).
    pub max_steps: usize,
    /// Stop when the RMS distance between the zero set and the target
    /// (both ways) is below this (domain units) and no zero-set sample is
    /// farther than half the finest cell from the target (so that pinched-off
    /// pieces vanish before the morph stops); `None` uses a tenth of the
    /// finest cell size.
    pub tolerance: Option<f64>,
    /// Weight `ω_D` of the distance-field constraint.
    pub distance_weight: f64,
    /// Relaxation time `τ` of the distance-field constraint.
    pub relaxation: f64,
    /// Tikhonov weight `ω_T` (relative to the mean diagonal).
    pub tikhonov: f64,
    /// Weight `ω_F` of the far-field rows `ḟ = 0` at the centres of leaves
    /// without a zero (coefficients of one sign) and out of the front's
    /// reach in one step, against the velocity rows' total weight of 1
    /// (each group is normalized by its row count; 0 turns them off). They
    /// keep blending functions with large supports that barely touch the
    /// zero set from lifting `f` through zero away from the front, which
    /// creates new pieces of surface (module docs). Default 100: the
    /// paper's Examples 1 and 3 and the T → C test all pass with it (at 0.1
    /// Example 1 had such pieces in 11 of 39 level sets).
    pub far_field_weight: f64,
    /// Fraction `c` (0–1) of the held cells (module docs, "Held cells"):
    /// finest cells farther than `h / c` from the front where the step
    /// would move `f` towards zero by more than `c |f|` get far-field rows
    /// `ḟ = 0` and the step's least squares is solved again, so that no new
    /// piece of surface is born there. 0 turns it off; it also needs a
    /// positive [`Self::far_field_weight`], whose per-row weight it uses.
    pub hold_fraction: f64,
    /// Where the zero-set samples come from (paper §3.3).
    pub sampler: Sampler,
    /// Marching-cubes nodes per finest cell for the zero-set samples (1–4;
    /// [`Sampler::MarchingCubes`]).
    pub samples_per_cell: u32,
    /// Report a stall when the error has not dropped by 1 % over this many
    /// steps (and stop).
    pub stall_steps: usize,
}

impl Default for EvolveSettings {
    fn default() -> Self {
        Self {
            speed: Speed::Paper,
            step: None,
            max_steps: 200,
            tolerance: None,
            distance_weight: 0.001,
            relaxation: 1.0,
            tikhonov: 1e-2,
            far_field_weight: 100.0,
            hold_fraction: 0.0,
            sampler: Sampler::MarchingCubes,
            samples_per_cell: 3,
            stall_steps: 8,
        }
    }
}

impl EvolveSettings {
    /// The morph step size `h` on a T-mesh whose finest cell is `finest`
    /// (domain units).
    pub fn step_size(&self, finest: f64) -> f64 {
        self.step.unwrap_or(0.5 * finest)
    }

    /// Checks the ranges.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting).
    pub fn validate(&self) -> Result<(), TsplineError> {
        if let Some(h) = self.step {
            check_range("step", h, 1e-6, 2.0, "(0, 2]")?;
        }
        if let Some(t) = self.tolerance {
            check_range("tolerance", t, 1e-9, 2.0, "(0, 2]")?;
        }
        check_range("max_steps", self.max_steps as f64, 0.0, 1e6, "0..=1000000")?;
        check_range("distance_weight", self.distance_weight, 0.0, 1e6, "0..=1e6")?;
        check_range("relaxation", self.relaxation, 1e-6, 1e6, "> 0")?;
        check_range("tikhonov", self.tikhonov, 1e-14, 1.0, "1e-14..=1")?;
        check_range("far_field_weight", self.far_field_weight, 0.0, 1e6, ">= 0")?;
        check_range("hold_fraction", self.hold_fraction, 0.0, 1.0, "0..=1")?;
        check_range("samples_per_cell", f64::from(self.samples_per_cell), 1.0, 4.0, "1..=4")?;
        check_range("stall_steps", self.stall_steps as f64, 1.0, 1e9, ">= 1")?;
        if let Sampler::MarchingTriangulation { edge_cells } = self.sampler {
            check_range("sampler edge_cells", edge_cells, 0.05, 4.0, "0.05..=4")?;
        }
        if let Speed::Robust { v_max, beta_cells: beta } = self.speed {
            check_range("v_max", v_max, 1e-9, 1e6, "> 0")?;
            check_range("beta_cells", beta, 0.0, Speed::MAX_BETA_CELLS, "0..=10 finest cells")?;
        }
        Ok(())
    }
}

/// Why the evolution stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Outcome {
    /// The zero set is within the tolerance of the target.
    Converged,
    /// No progress towards the target over `stall_steps` steps.
    Stalled,
    /// The step cap was reached.
    StepLimit,
    /// The zero set vanished (no sample left).
    Vanished,
}

/// Statistics of one evolution step.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct StepStats {
    /// Step number (1-based).
    pub step: usize,
    /// Zero-set samples used (`N₁`).
    pub samples: usize,
    /// Largest `|v|` over the samples.
    pub max_speed: f64,
    /// The Euler step `Δτ`.
    pub dt: f64,
    /// RMS of `d_B` over the zero-set samples before the step.
    pub rms_to_target: f64,
    /// Largest `|d_B|` over the zero-set samples before the step.
    pub max_to_target: f64,
    /// RMS first-order distance `|f|/|∇f|` of the target samples to the zero
    /// set before the step.
    pub rms_from_target: f64,
    /// Range of `|∇f|` over the samples.
    pub gradient_range: (f64, f64),
    /// Stored non-zeros of the normal matrix.
    pub nonzeros: usize,
    /// Far-field rows `ḟ = 0` of the step's least squares (module docs),
    /// the held cells' rows included.
    pub far_rows: usize,
    /// Held cells of the step (module docs, "Held cells"; 0 when
    /// [`EvolveSettings::hold_fraction`] is 0).
    pub held_cells: usize,
}

impl StepStats {
    /// The two-sided error `max(rms_to_target, rms_from_target)`.
    pub fn error(&self) -> f64 {
        self.rms_to_target.max(self.rms_from_target)
    }
}

/// The result of [`evolve`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Evolution {
    /// Coefficient vectors `c(τ_i)`, the initial one first.
    pub frames: Vec<Vec<f64>>,
    /// Per-step statistics.
    pub steps: Vec<StepStats>,
    /// Why it stopped.
    pub outcome: Outcome,
    /// The two-sided RMS error of the last frame (domain units).
    pub final_error: f64,
}

/// Evolves `initial` towards the target with signed distance `target`
/// (domain units, positive inside); `target_surface` are target surface
/// samples (for the two-sided stopping test). `progress` sees every step and
/// may break to cancel.
///
/// # Errors
/// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting),
/// [`TsplineError::Singular`] when a step's system cannot be solved,
/// [`MorphError::Cancelled`](isomorph_common::MorphError::Cancelled) (checked
/// after every step), [`MorphError::Grid`](isomorph_common::MorphError::Grid)
/// when the sampling lattice does not fit in memory.
pub fn evolve<D: Fn(DVec3) -> f64 + Sync + Send>(
    initial: &TSpline,
    target: D,
    target_surface: &[DVec3],
    settings: &EvolveSettings,
    control: &Control,
) -> Result<Evolution, TsplineError> {
    control.install(|| evolve_on_pool(initial, target, target_surface, settings, control))
}

fn evolve_on_pool<D: Fn(DVec3) -> f64 + Sync + Send>(
    initial: &TSpline,
    target: D,
    target_surface: &[DVec3],
    settings: &EvolveSettings,
    control: &Control,
) -> Result<Evolution, TsplineError> {
    settings.validate()?;
    let h_min = initial.mesh().finest_cell();
    let h = settings.step_size(h_min);
    let tol = settings.tolerance.unwrap_or(0.1 * h_min);
    let mut spline = initial.clone();
    let mut frames = vec![spline.coefficients().to_vec()];
    let mut steps: Vec<StepStats> = Vec::new();
    let mut best = f64::INFINITY;
    let mut best_step = 0;
    // The normal matrix keeps its sparsity pattern while the same leaves
    // hold rows, so its symbolic factorization is reused.
    let mut symbolic = lsq::SymbolicCache::default();
    let final_error;
    let outcome = loop {
        let samples = zero_set_samples(&spline, settings.sampler, settings.samples_per_cell)?;
        if samples.is_empty() {
            final_error = f64::INFINITY;
            break Outcome::Vanished;
        }
        let d_b: Vec<f64> = samples.par_iter().map(|s| target(s.p)).collect();
        let rms_to = (d_b.iter().map(|d| d * d).sum::<f64>() / d_b.len() as f64).sqrt();
        let max_to = d_b.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        let rms_from = rms_first_order(&spline, target_surface);
        let error = rms_to.max(rms_from);
        if error < tol && max_to < 0.5 * h_min {
            final_error = error;
            break Outcome::Converged;
        }
        if error < best * 0.99 {
            best = error;
            best_step = steps.len();
        } else if steps.len() - best_step >= settings.stall_steps {
            final_error = error;
            break Outcome::Stalled;
        }
        if steps.len() >= settings.max_steps {
            final_error = error;
            break Outcome::StepLimit;
        }
        let speeds: Vec<f64> =
            samples.iter().zip(&d_b).map(|(s, &d)| speed(settings.speed, d, s, h_min)).collect();
        let max_speed = speeds.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let dt = if max_speed > 0.0 { (h / max_speed).min(1.0) } else { 1.0 };
        let Velocity { cdot, nonzeros, far_rows, held_cells } =
            velocity(&spline, &samples, &speeds, h_min, dt, settings, &mut symbolic)?;
        let c: Vec<f64> = spline.coefficients().iter().zip(&cdot).map(|(c, d)| c + dt * d).collect();
        let grads = samples.iter().map(|s| s.eval.gradient.length());
        let gradient_range = grads.fold((f64::MAX, 0.0f64), |(lo, hi), g| (lo.min(g), hi.max(g)));
        spline = spline.with_coefficients(c)?;
        frames.push(spline.coefficients().to_vec());
        let stats = StepStats {
            step: steps.len() + 1,
            samples: samples.len(),
            max_speed,
            dt,
            rms_to_target: rms_to,
            max_to_target: max_to,
            rms_from_target: rms_from,
            gradient_range,
            nonzeros,
            far_rows,
            held_cells,
        };
        steps.push(stats);
        control.progress("evolution", Some(steps.len() as f32 / settings.max_steps as f32), || {
            format!(
                "step {}, RMS to target {:.4}, {} samples",
                stats.step, stats.rms_to_target, stats.samples
            )
        });
        control.check()?;
    };
    Ok(Evolution { frames, steps, outcome, final_error })
}

/// RMS of `|f|/|∇f|` over `points` (0 for none).
fn rms_first_order(spline: &TSpline, points: &[DVec3]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let sum: f64 = points
        .par_iter()
        .map(|&p| {
            let e = spline.eval(p);
            let d = e.value / e.gradient.length().max(1e-3);
            d * d
        })
        .sum();
    (sum / points.len() as f64).sqrt()
}

/// The normal speed at a sample.
fn speed(kind: Speed, d_b: f64, s: &Sample, h_min: f64) -> f64 {
    let lambda = (-d_b * d_b).exp();
    match kind {
        Speed::Paper => lambda * d_b + (1.0 - lambda) * s.eval.mean_curvature(),
        Speed::Distance => d_b,
        Speed::Robust { v_max, beta_cells } => {
            let k = s.eval.mean_curvature().clamp(-1.0 / h_min, 1.0 / h_min);
            d_b.clamp(-v_max, v_max) + beta_cells * h_min * (1.0 - lambda) * k
        }
    }
}

/// One row: its leaf and entries in that leaf's anchor order.
struct Row {
    leaf: usize,
    entries: Vec<f64>,
    weight: f64,
    rhs: f64,
}

/// The coefficient velocities of a step and how they were found.
struct Velocity {
    /// `ċ`.
    cdot: Vec<f64>,
    /// Stored non-zeros of the normal matrix.
    nonzeros: usize,
    /// Far-field rows, the held cells' included.
    far_rows: usize,
    /// Held cells.
    held_cells: usize,
}

/// Largest number of times a step's least squares is solved again with
/// new held cells (module docs).
const HOLD_PASSES: usize = 3;

/// Solves the least-squares problem of the module docs for `ċ`, holding
/// the cells that a step of `dt` would lift through zero off the front.
fn velocity(
    spline: &TSpline,
    samples: &[Sample],
    speeds: &[f64],
    h_min: f64,
    dt: f64,
    settings: &EvolveSettings,
    symbolic: &mut lsq::SymbolicCache,
) -> Result<Velocity, TsplineError> {
    let mesh = spline.mesh();
    let h_step = settings.step_size(h_min);
    let m = samples.len() as f64;
    let k = 3.0 * m;
    let w_data = 1.0 / m;
    let w_dist = settings.distance_weight / k;
    let tau = settings.relaxation;
    let rows: Vec<Row> = samples
        .par_iter()
        .zip(speeds)
        .map_init(
            || (crate::basis::LocalBasis::default(), Vec::new(), Vec::new()),
            |(local, r, dr), (s, &v)| {
                let mut out = Vec::with_capacity(4);
                let g = s.eval.gradient;
                local.at(mesh, s.p);
                if local.rational(r, dr) {
                    out.push(Row {
                        leaf: local.leaf,
                        entries: r.clone(),
                        weight: w_data,
                        rhs: v * g.length(),
                    });
                }
                if settings.distance_weight > 0.0 {
                    let n = g.normalize_or_zero();
                    for q in [s.p, s.p + h_min * n, s.p - h_min * n] {
                        local.at(mesh, q);
                        if !local.rational(r, dr) {
                            continue;
                        }
                        let (_, gq) = local.value_gradient(mesh, spline.coefficients());
                        let entries = dr.iter().map(|d| 2.0 * gq.dot(*d)).collect();
                        let rhs = -(gq.length_squared() - 1.0) / tau;
                        out.push(Row { leaf: local.leaf, entries, weight: w_dist, rhs });
                    }
                }
                out
            },
        )
        .flatten()
        .collect();
    let mut blocks = vec![LeafRows::default(); mesh.leaf_count()];
    for row in &rows {
        blocks[row.leaf].push(&row.entries, row.weight, row.rhs);
    }
    let (mut far_rows, row_weight) = if settings.far_field_weight > 0.0 {
        far_field_rows(spline, samples, h_step, settings.far_field_weight, &mut blocks)
    } else {
        (0, 0.0)
    };
    let zero = vec![0.0; mesh.anchor_count()];
    let (mut cdot, mut stats) = lsq::solve(mesh, &blocks, settings.tikhonov, &zero, "evolution", symbolic)?;
    let fraction = settings.hold_fraction;
    let passes = if fraction > 0.0 && row_weight > 0.0 { HOLD_PASSES } else { 0 };
    let mut held = vec![false; if passes > 0 { mesh.finest_cells() } else { 0 }];
    let mut held_cells = 0;
    for _ in 0..passes {
        let lifted = lifted_cells(spline, &cdot, samples, h_step, fraction, dt);
        let new: Vec<usize> = lifted.into_iter().filter(|&cell| !held[cell]).collect();
        if new.is_empty() {
            break;
        }
        let mut local = crate::basis::LocalBasis::default();
        let (mut r, mut dr) = (Vec::new(), Vec::new());
        for cell in new {
            held[cell] = true;
            held_cells += 1;
            local.at(mesh, mesh.finest_cell_centre(cell));
            if local.rational(&mut r, &mut dr) {
                blocks[local.leaf].push_constraint(&r, row_weight, 0.0);
                far_rows += 1;
            }
        }
        (cdot, stats) = lsq::solve(mesh, &blocks, settings.tikhonov, &zero, "evolution", symbolic)?;
    }
    Ok(Velocity { cdot, nonzeros: stats.nonzeros, far_rows, held_cells })
}

/// The finest cells to hold (module docs, "Held cells"): those farther than
/// `h_step / fraction` from the zero-set samples (whole cells, Chebyshev
/// distance, at least one) at whose centre a step of `dt` along `cdot`
/// (`ċ`) moves `f` towards zero by more than `fraction |f|`. In ascending
/// order.
fn lifted_cells(
    spline: &TSpline,
    cdot: &[f64],
    samples: &[Sample],
    h_step: f64,
    fraction: f64,
    dt: f64,
) -> Vec<usize> {
    let mesh = spline.mesh();
    let c = spline.coefficients();
    let reach = (h_step / (fraction * mesh.finest_cell())).ceil().max(1.0) as i64;
    let near = front_cells(mesh, samples, reach);
    let range = |v: &[f64], list: &[u32]| {
        list.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &i| (lo.min(v[i as usize]), hi.max(v[i as usize])))
    };
    let mut cells: Vec<usize> = (0..mesh.leaf_count())
        .into_par_iter()
        .filter(|&l| {
            // f and ḟ are convex combinations of the leaf's coefficients,
            // so where `dt ḟ + c f` keeps the sign of f by their ranges, no
            // centre of the leaf qualifies.
            let list = mesh.leaf_anchors(l);
            let ((lo, hi), (dlo, dhi)) = (range(c, list), range(cdot, list));
            !(lo > 0.0 && dt * dlo + fraction * lo >= 0.0 || hi < 0.0 && dt * dhi + fraction * hi <= 0.0)
        })
        .flat_map_iter(|l| mesh.leaf_cells(l).filter(|&cell| !near[cell]).collect::<Vec<_>>())
        .map_init(crate::basis::LocalBasis::default, |local, cell| {
            local.at(mesh, mesh.finest_cell_centre(cell));
            let (mut f, mut fdot) = (0.0, 0.0);
            for (&i, b) in mesh.leaf_anchors(local.leaf).iter().zip(&local.b) {
                f += c[i as usize] * b;
                fdot += cdot[i as usize] * b;
            }
            // Both share the denominator D > 0, which cancels.
            (f * fdot < 0.0 && dt * fdot.abs() > fraction * f.abs()).then_some(cell)
        })
        .flatten()
        .collect();
    cells.sort_unstable();
    cells
}

/// Adds the far-field rows `ḟ = 0` (module docs) to `blocks` and returns
/// their number and the weight of each: one at the centre of every leaf
/// whose coefficients have one sign (no zero inside) and that lies farther
/// than the front's reach from every zero-set sample. The reach is the
/// step `h_step` rounded up to whole finest cells (at least one): a leaf
/// within it may be entered by the next step, and a row there would hold
/// the front back. The rows are constraints: their weight does not scale
/// the Tikhonov term.
fn far_field_rows(
    spline: &TSpline,
    samples: &[Sample],
    h_step: f64,
    weight: f64,
    blocks: &mut [LeafRows],
) -> (usize, f64) {
    let mesh = spline.mesh();
    let c = spline.coefficients();
    let reach = (h_step / mesh.finest_cell()).ceil().max(1.0) as i64;
    let near = front_cells(mesh, samples, reach);
    let far: Vec<usize> = (0..mesh.leaf_count())
        .filter(|&l| {
            let list = mesh.leaf_anchors(l);
            let one_sign =
                list.iter().all(|&i| c[i as usize] > 0.0) || list.iter().all(|&i| c[i as usize] < 0.0);
            one_sign && !mesh.leaf_cells(l).any(|cell| near[cell])
        })
        .collect();
    let w = weight / far.len().max(1) as f64;
    let mut local = crate::basis::LocalBasis::default();
    let (mut r, mut dr) = (Vec::new(), Vec::new());
    let mut count = 0;
    for l in far {
        let (lo, hi) = mesh.leaf_box(l);
        local.at(mesh, 0.5 * (lo + hi));
        if local.rational(&mut r, &mut dr) {
            blocks[l].push_constraint(&r, w, 0.0);
            count += 1;
        }
    }
    (count, w)
}

/// Marks the finest lattice cells (indexed as
/// [`TMesh::leaf_cells`](crate::tmesh::TMesh::leaf_cells) does) within
/// `reach` cells (Chebyshev distance) of a cell holding a sample.
fn front_cells(mesh: &crate::tmesh::TMesh, samples: &[Sample], reach: i64) -> Vec<bool> {
    let res = mesh.resolution();
    let mut mark = vec![false; mesh.finest_cells()];
    for s in samples {
        let [x, y, z] = mesh.cell_of(s.p);
        for c in (z - reach).max(0)..=(z + reach).min(res - 1) {
            for b in (y - reach).max(0)..=(y + reach).min(res - 1) {
                for a in (x - reach).max(0)..=(x + reach).min(res - 1) {
                    mark[((c * res + b) * res + a) as usize] = true;
                }
            }
        }
    }
    mark
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{FitSettings, fit};
    use crate::tmesh::{TMesh, TMeshSettings};
    use std::sync::Arc;

    fn run(r0: f64, r1: f64, speed: Speed) -> Evolution {
        run_sampled(r0, r1, speed, Sampler::MarchingCubes)
    }

    fn run_sampled(r0: f64, r1: f64, speed: Speed, sampler: Sampler) -> Evolution {
        let (f0, b) = sphere_fit(r0, r1);
        let settings = EvolveSettings { speed, sampler, max_steps: 60, ..Default::default() };
        evolve(&f0, move |p: DVec3| r1 - p.length(), &b, &settings, &Control::new()).unwrap()
    }

    #[test]
    fn shrinking_sphere_converges_to_the_target() {
        let e = run(0.6, 0.4, Speed::Paper);
        assert_eq!(e.outcome, Outcome::Converged, "{:?}", e.steps.last());
        assert_eq!(e.frames.len(), e.steps.len() + 1);
        // Each step moves the surface at most about h; the error decreases.
        let first = e.steps[0].error();
        assert!(first > 0.15 && e.final_error < 0.5 * 0.125, "{first} → {}", e.final_error);
        let g = e.steps.last().unwrap().gradient_range;
        assert!(g.0 > 0.7 && g.1 < 1.3, "|∇f| in {g:?}");
    }

    #[test]
    fn growing_sphere_converges_with_the_robust_speed() {
        let e = run(0.3, 0.6, Speed::Robust { v_max: 0.2, beta_cells: 1.0 });
        assert_eq!(e.outcome, Outcome::Converged, "{:?}", e.steps.last());
    }

    /// A depth-4 T-mesh around spheres of radius `r0` and `r1` and the fit
    /// of the first's distance.
    fn sphere_fit(r0: f64, r1: f64) -> (TSpline, Vec<DVec3>) {
        let (a, b) = (
            crate::demo::sphere_samples(1500, r0, DVec3::ZERO),
            crate::demo::sphere_samples(1500, r1, DVec3::ZERO),
        );
        let all: Vec<DVec3> = a.iter().chain(&b).copied().collect();
        let s = TMeshSettings { max_depth: 4, min_depth: 3, sample_spacing: 0.05, ..Default::default() };
        let mesh = Arc::new(TMesh::build(&all, &s).unwrap());
        (fit(mesh, move |p: DVec3| r0 - p.length(), &a, &FitSettings::default()).unwrap().0, b)
    }

    #[test]
    fn lifted_cells_are_exactly_the_off_front_cells_the_step_moves_too_far() {
        let (f0, _) = sphere_fit(0.4, 0.4);
        let mesh = f0.mesh().clone();
        let samples = zero_set_samples(&f0, Sampler::MarchingCubes, 3).unwrap();
        // A uniform lift ḟ ≡ k (the R_i sum to one): every cell outside the
        // sphere (f < 0) with dt k > c |f| and off the front qualifies.
        let (k, dt, fraction, h) = (0.2, 1.0, 0.5, 0.5 * mesh.finest_cell());
        let cdot = vec![k; mesh.anchor_count()];
        let got = lifted_cells(&f0, &cdot, &samples, h, fraction, dt);
        let reach = (h / (fraction * mesh.finest_cell())).ceil().max(1.0) as i64;
        let near = front_cells(&mesh, &samples, reach);
        let expected: Vec<usize> = (0..mesh.finest_cells())
            .filter(|&cell| {
                let f = f0.value_at(mesh.finest_cell_centre(cell));
                !near[cell] && f < 0.0 && dt * k > fraction * f.abs()
            })
            .collect();
        assert!(!expected.is_empty() && expected.len() < near.len() / 2, "{}", expected.len());
        assert_eq!(got, expected);
        // Lowering f instead moves only cells inside the sphere towards zero.
        let down = vec![-k; mesh.anchor_count()];
        let inside = lifted_cells(&f0, &down, &samples, h, fraction, dt);
        assert!(inside.iter().all(|&cell| f0.value_at(mesh.finest_cell_centre(cell)) > 0.0));
        assert!(!inside.is_empty());
    }

    #[test]
    fn a_distance_like_front_holds_no_cell() {
        let (f0, b) = sphere_fit(0.3, 0.6);
        let target = |p: DVec3| 0.6 - p.length();
        let speed = Speed::robust(1.0);
        let held = EvolveSettings { speed, hold_fraction: 0.5, max_steps: 60, ..Default::default() };
        let e = evolve(&f0, target, &b, &held, &Control::new()).unwrap();
        assert_eq!(e.outcome, Outcome::Converged, "{:?}", e.steps.last());
        assert!(e.steps.iter().all(|s| s.held_cells == 0), "{:?}", e.steps);
        // Without holding, the same steps.
        let free = EvolveSettings { hold_fraction: 0.0, ..held };
        let plain = evolve(&f0, target, &b, &free, &Control::new()).unwrap();
        assert_eq!(plain.frames, e.frames);
        let bad = EvolveSettings { hold_fraction: 1.5, ..Default::default() };
        assert!(
            evolve(&f0, target, &b, &bad, &Control::new()).unwrap_err().to_string().contains("hold_fraction")
        );
    }

    #[test]
    fn marching_triangulation_samples_drive_the_same_evolution() {
        let speed = Speed::Robust { v_max: 0.2, beta_cells: 1.0 };
        let cubes = run(0.3, 0.6, speed);
        let tri = run_sampled(0.3, 0.6, speed, Sampler::MarchingTriangulation { edge_cells: 0.5 });
        assert_eq!(tri.outcome, Outcome::Converged, "{:?}", tri.steps.last());
        // Uniform points, about 2/√3 per (edge)² of area, fewer than the
        // marching-cubes vertices at 3 nodes per cell.
        let (a, b) = (tri.steps[0].samples, cubes.steps[0].samples);
        assert!(a < b, "{a} triangulation samples vs {b}");
        assert!(
            tri.steps.len().abs_diff(cubes.steps.len()) <= 3,
            "{} vs {} steps",
            tri.steps.len(),
            cubes.steps.len()
        );
    }
}
