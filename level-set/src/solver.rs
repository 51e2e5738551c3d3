//! What both solvers share: the [`Solver`] interface and per-iteration
//! statistics.

use crate::stencil::{Lattice, Values, upwind_norm};
use crate::{BandFrame, SpeedGrid};

/// Statistics of one solver iteration; distances in voxels.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct StepStats {
    /// Time step used ([`StepParams::front_step`] over the largest speed,
    /// eq. 24's bound for a front step of ⅓, and the sparse field's
    /// half-voxel limit).
    pub dt: f32,
    /// RMS change of the embedding at the surface nodes (voxels).
    pub rms_change: f32,
    /// RMS target distance at the surface (voxels): how far the evolving
    /// surface still is from the target.
    pub rms_distance: f32,
    /// Nodes next to the zero set that were updated (the sparse field's
    /// active set; the dense solver's sign-change nodes).
    pub surface_nodes: usize,
}

/// The mean-curvature term of the speed (Yang & Jüttler 2007, eq. 11):
/// `γ = λ D + (1 − λ) w κ` with `λ = exp(−(D / ℓ)²)`, where `D` is the
/// target distance and `κ = ∇·(∇φ/|∇φ|)` the mean curvature (sum of the
/// principal curvatures; negative on convex parts of a positive-inside
/// embedding, so the term shrinks bumps and fills dents). Far from the
/// target the surface is smoothed; on the target (`D → 0`, `λ → 1`) the
/// distance term alone fixes it. Mean-curvature motion smooths but does not
/// stop thin necks from pinching off (it drives them to): measured on the
/// aligned mug → chain at 40³, the most pieces in one frame went from 11
/// without the term to 12–16 with `w ∈ [2, 5]`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Curvature {
    /// Weight `w` of the curvature term (voxels² per unit time; the speed
    /// `w κ` is in voxels per unit time with `κ` in 1/voxel).
    pub weight: f32,
    /// Length `ℓ` (world units) over which `λ` falls from 1 to 1/e.
    pub length: f32,
}

/// Per-iteration parameters shared by both solvers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Upper bound on the time step besides the stability bounds.
    pub max_time_step: f32,
    /// How far (voxels) the fastest front may move in one iteration: the
    /// time step is at most `front_step / max |γ|` (see
    /// [`FRONT_STEP`]).
    pub front_step: f32,
    /// Optional mean-curvature regularization.
    pub curvature: Option<Curvature>,
}

impl Default for StepParams {
    fn default() -> Self {
        Self { max_time_step: 1.0, front_step: FRONT_STEP, curvature: None }
    }
}

/// The default distance (voxels) the fastest front moves per iteration:
/// half a voxel. Breen & Whitaker's eq. 24 bounds the step by
/// `Δt ≤ 1 / (3 max |γ|)`, a third of a voxel; the up-wind scheme's own
/// stability (CFL) bound is `Δt · max |γ| · (|n_x| + |n_y| + |n_z|) ≤ 1`,
/// at worst `1/√3 ≈ 0.58` voxel, and the sparse field moves no active
/// value by more than half a voxel per iteration anyway, so ½ is stable
/// and converges to the same surface as ⅓ in about a quarter fewer
/// iterations (the reference case: 121 instead of 166, surface error
/// unchanged; `docs/EXPERIMENTS.md`). Pass `1.0 / 3.0` as
/// [`StepParams::front_step`] for eq. 24's step.
pub const FRONT_STEP: f32 = 0.5;

/// The rate `∂φ/∂t` at node `n` for target distance `d` (voxels, already
/// sampled where the solver samples it) and the parts that bound the time
/// step: `(rate, distance term speed)`.
pub(crate) fn node_rate(
    lattice: &Lattice,
    u: &(impl Values + ?Sized),
    n: usize,
    d: f32,
    spacing: f32,
    curvature: Option<Curvature>,
) -> (f32, f32) {
    let (minus, plus) = lattice.one_sided(u, n);
    match curvature {
        None => (d * upwind_norm(minus, plus, d), d),
        Some(c) => {
            let lambda = (-(d * spacing / c.length).powi(2)).exp();
            let gamma = lambda * d;
            let (kappa, grad_norm) = lattice.mean_curvature(u, n);
            (gamma * upwind_norm(minus, plus, gamma) + (1.0 - lambda) * c.weight * kappa * grad_norm, gamma)
        }
    }
}

/// The largest stable time step: the fastest front moving
/// `params.front_step` voxels for the distance term (largest speed
/// `max_speed`; eq. 24 with `front_step = 1/3`), `1/(6w)` for the
/// curvature term, and `params.max_time_step`.
pub(crate) fn stable_time_step(max_speed: f32, params: &StepParams) -> f32 {
    let mut dt = params.max_time_step;
    if max_speed > 0.0 {
        dt = dt.min(params.front_step / max_speed);
    }
    if let Some(c) = params.curvature.filter(|c| c.weight > 0.0) {
        dt = dt.min(1.0 / (6.0 * c.weight));
    }
    dt
}

/// A level-set solver for `∂φ/∂t = |∇φ| γ` (Breen & Whitaker eq. 17) on a
/// fixed lattice; values in voxel units, positive inside.
pub trait Solver: Send {
    /// One explicit Euler iteration (eq. 18) with the largest stable time
    /// step within `params`.
    fn step(&mut self, speed: &SpeedGrid, params: &StepParams) -> StepStats;

    /// [`Solver::step`], with the state before it captured as a kept frame
    /// when `capture` gives the frame's `(iteration, time)`: the same frame
    /// as [`Solver::capture`] before the step, which a solver may capture
    /// while it computes the step (the sparse field does).
    fn step_after_capture(
        &mut self,
        speed: &SpeedGrid,
        params: &StepParams,
        capture: Option<(usize, f64)>,
    ) -> (StepStats, Option<BandFrame>) {
        let frame = capture.map(|(iteration, time)| self.capture(iteration, time));
        (self.step(speed, params), frame)
    }

    /// Heap bytes of the solver's state (embedding, status or change
    /// arrays, lists, buffers).
    fn heap_bytes(&self) -> usize;

    /// The current embedding as a kept frame, stamped with the `iteration`
    /// and evolution `time` reached (`O(surface)` work for the sparse
    /// field).
    fn capture(&self, iteration: usize, time: f64) -> BandFrame;

    /// Frees the storage of the regions the band has left, where the state
    /// reads as the far inside or outside anyway (no value changes; the
    /// sparse field's bricks, nothing for dense state). Returns the bricks
    /// released.
    fn release(&mut self) -> usize {
        0
    }
}
