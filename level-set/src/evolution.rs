//! Running a solver to convergence and keeping frames: [`evolve`] and the
//! resulting [`LevelSetMorph`].

use crate::band::BandFrame;
use crate::solver::{Curvature, Solver, StepParams, StepStats};
use crate::{
    DenseSolver, LevelSetError, Overlap, Placement, SparseFieldSolver, SpeedGrid, SpeedSampler,
    check_overlap, check_overlap_sparse,
};
use isomorph_common::glam::{Affine3A, UVec3, Vec3};
use isomorph_common::marching_cubes::marching_cubes_planes;
use isomorph_common::{Aabb, Bricks, Grid3, GridError, TriMesh};
use isomorph_common::{
    Control, Frame, Morph, MorphError, MorphReport, Outcome, Residual, Stages, check, check_time,
};
use rayon::prelude::*;
use std::borrow::Cow;
use std::fmt;
use std::sync::Arc;

/// Which solver integrates the level-set equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum SolverKind {
    /// Whitaker's sparse field (cost per iteration ∝ surface area).
    #[default]
    SparseField,
    /// Up-wind scheme over the whole grid (cost ∝ volume); the reference.
    Dense,
}

/// When frames of the evolution are kept (the first and the last always
/// are).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameSchedule {
    /// After every `k`-th iteration.
    EveryIterations(usize),
    /// Whenever the evolution time has advanced by this much (eq. 17's `t`).
    EveryTime(f64),
    /// Evenly in iterations within a memory budget, however many iterations
    /// the evolution takes: every `stride`-th iteration, the stride starting
    /// at 1 and doubling (every other kept frame dropped) whenever more than
    /// `2 × budget + 1` frames are kept. At most `2 × budget + 2` frames are
    /// kept; at least `budget + 1` once the stride has grown.
    Budget(usize),
}

impl FrameSchedule {
    /// Checks the interval, time or budget.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] named `frames`.
    pub fn validate(&self) -> Result<(), MorphError> {
        match *self {
            FrameSchedule::EveryIterations(k) => check::count("frames", k as u64, 1, u64::MAX),
            FrameSchedule::EveryTime(t) => check::positive("frames", t),
            FrameSchedule::Budget(b) => check::count("frames", b as u64, 1, u64::MAX),
        }
    }
}

/// Settings of [`evolve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvolveSettings {
    /// The solver.
    pub solver: SolverKind,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stop when the RMS target distance at the surface falls below this
    /// (voxels). The default, 0.003, lets the last iterations settle the
    /// points that joined the active set on the way in: the converged
    /// surface then lies within the grid's own polygonization floor of the
    /// target (figures in `docs/EXPERIMENTS.md`).
    pub rms_distance: f32,
    /// Stop when the RMS change per iteration falls below this (voxels).
    pub rms_change: f32,
    /// Upper bound on the time step (besides eq. 24's). Eq. 24 alone lets
    /// the step grow without bound as the surface nears the target, but the
    /// speed is a distance, which changes by one voxel per voxel moved along
    /// the normal: explicit Euler on that relaxation overshoots for steps
    /// above 1 and oscillates for steps above 2. The default, 1, converges
    /// monotonically (an unbounded step left the reference case's surface
    /// 0.29 voxel off the torus; see `docs/EXPERIMENTS.md`).
    pub max_time_step: f32,
    /// How far (voxels) the fastest front moves per iteration, which sets
    /// the time step far from the target (in `(0, ½]`; default
    /// [`FRONT_STEP`](crate::FRONT_STEP), ½; eq. 24 has ⅓).
    pub front_step: f32,
    /// Which intermediate frames to keep (the first and last always are).
    pub frames: FrameSchedule,
    /// Optional mean-curvature regularization of the speed.
    pub curvature: Option<Curvature>,
    /// Stop once the evolution time (eq. 17's `t`) reaches this; infinite by
    /// default. Lets two solvers be compared over the same evolution time.
    pub end_time: f64,
    /// Converged also when the RMS target distance (voxels) is at most this
    /// and has not fallen below 99 % of its best value for
    /// `settle_iterations`: the surface has reached what the grid resolves
    /// and oscillates by thousandths of a voxel above `rms_distance` (an open
    /// target's inner sheets, thin parts). Default 0.01 voxel; 0 turns it
    /// off.
    pub settled_rms_distance: f32,
    /// Iterations without improvement that make a run under
    /// `settled_rms_distance` converged. Default 50.
    pub settle_iterations: usize,
    /// Stop (as stalled) when the RMS target distance has not fallen below
    /// 99 % of its best value for this many iterations: a speed that is not
    /// a distance (seen through an anisotropic map, or a target the grid
    /// cannot resolve) can leave the surface oscillating a hundredth of a
    /// voxel above the thresholds forever. Default 500.
    pub stall_iterations: usize,
    /// Largest share of the target's inside (`[0, 1]`) that may lie in parts
    /// the source does not overlap: such parts are never reached, and the
    /// evolution runs with a warning in its report while their share is at
    /// most this, or is refused with [`MorphError::NoOverlap`] (see
    /// [`check_overlap`]). Default 0.05.
    pub max_unreached_share: f32,
}

impl Default for EvolveSettings {
    fn default() -> Self {
        Self {
            solver: SolverKind::SparseField,
            max_iterations: 5000,
            rms_distance: 0.003,
            rms_change: 1e-4,
            max_time_step: 1.0,
            front_step: crate::FRONT_STEP,
            frames: FrameSchedule::EveryIterations(10),
            curvature: None,
            end_time: f64::INFINITY,
            stall_iterations: 500,
            settled_rms_distance: 0.01,
            settle_iterations: 50,
            max_unreached_share: 0.05,
        }
    }
}

/// A finished level-set evolution: the kept frames and how it went. As a
/// [`Morph`], `frame(t)` is the embedding where the surface has made the
/// share `t` of its whole motion ([`LevelSetMorph::travel`]: the
/// cumulative RMS change per iteration at the surface, in voxels): the
/// kept frame at that travel when there is one (always for `t = 0` and
/// `t = 1`), otherwise the values of the two kept frames bracketing it
/// interpolated linearly in travel (each frame's band values, `±1.5`
/// voxels elsewhere; the interpolated zero set lies between the two
/// frames' surfaces). It is placed by the interpolated transform `T(x, t)`
/// (Breen eq. 25–26; see [`Placement`]).
///
/// Frames are placed by travel, not by iteration or by evolution time
/// (eq. 17's `t`), because both of those are dominated by the run's tail:
/// the last iterations move the surface by thousandths of a voxel each,
/// at the time-step cap of 1, and how many of them run depends on when
/// the stopping test fires, which shifted every in-between frame of two
/// runs converging to the same surface (a sphere as a mesh and as a
/// `.npy` volume, `tests/tests/volumes.rs`). The travel of the tail is
/// negligible, so a frame's place depends on how far the surface has come,
/// as an animator expects: frames evenly spaced in `t` are about evenly
/// spaced in motion.
#[derive(Debug, Clone)]
pub struct LevelSetMorph {
    frames: Vec<BandFrame>,
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
    placement: Placement,
    stats: Vec<StepStats>,
    /// [`LevelSetMorph::travel`]: one entry per iteration and the start.
    travel: Vec<f64>,
    converged: bool,
    world: Aabb,
    report: MorphReport,
}

/// Evolves the source surface (a signed distance grid, world units,
/// positive inside) under the target `speed` until it matches the target
/// (RMS distance or RMS change below the settings' thresholds) or the
/// iteration cap, keeping frames as scheduled. `placement` is Breen's
/// `T(x, α)`: kept frames are placed by it when polygonized (use
/// [`Placement::Identity`] when the speed was sampled without a map).
///
/// Progress is reported to `control` after every iteration (stage
/// `"evolution"`, with the RMS target distance), which is also checked for
/// cancellation; the solvers run on its threads.
///
/// # Errors
/// Input errors of the solvers, [`MorphError::NoOverlap`] when target parts
/// the source does not overlap hold more than
/// [`EvolveSettings::max_unreached_share`] of the target, [`MorphError::BadSetting`],
/// [`MorphError::Grid`] when `speed` lies on another lattice,
/// [`MorphError::Cancelled`].
pub fn evolve(
    source: &Grid3<f32>,
    speed: &SpeedGrid,
    placement: Placement,
    settings: &EvolveSettings,
    control: &Control,
) -> Result<LevelSetMorph, LevelSetError> {
    control.install(|| evolve_on_pool(source, speed, placement, settings, control))
}

fn evolve_on_pool(
    source: &Grid3<f32>,
    speed: &SpeedGrid,
    placement: Placement,
    settings: &EvolveSettings,
    control: &Control,
) -> Result<LevelSetMorph, LevelSetError> {
    let stages = Stages::start();
    check_settings(settings)?;
    if !speed.on_lattice_of(source) {
        let dims = (source.dims(), speed.dims());
        let message =
            format!("the speed's lattice ({} nodes) is not the source's ({} nodes)", dims.1, dims.0);
        return Err(isomorph_common::GridError::Mismatch(message).into());
    }
    let solver: Box<dyn Solver> = match settings.solver {
        SolverKind::SparseField => sparse_field(source)?,
        SolverKind::Dense => Box::new(DenseSolver::new(source)?),
    };
    let overlap = check_overlap(source, speed, settings.max_unreached_share)?;
    let lattice = (source.dims(), source.origin(), source.spacing());
    let start = Start { solver, speed, overlap, lattice, source_bytes: source.len() * size_of::<f32>() };
    run(start, placement, settings, control, stages)
}

/// Lattices up to this many nodes (256³) keep [`evolve`]'s sparse-field
/// state in flat arrays (5 bytes per node, beside the caller's dense source
/// and speed, 8 bytes per node): every neighbour read is one index instead
/// of a brick table lookup, which makes the evolution markedly faster, with
/// bitwise the same results. Larger lattices keep it in bricks, whose
/// memory grows with the surface.
pub const FLAT_STATE_NODES: usize = 1 << 24;

/// The sparse-field solver of `source`, its state flat up to
/// [`FLAT_STATE_NODES`] nodes (and within the memory limit), in bricks
/// otherwise.
fn sparse_field(source: &Grid3<f32>) -> Result<Box<dyn Solver>, LevelSetError> {
    if source.len() <= FLAT_STATE_NODES {
        match SparseFieldSolver::<Vec<f32>, Vec<i8>>::with_storage(source) {
            Err(LevelSetError::Morph(MorphError::Grid(GridError::TooLarge { .. }))) => {}
            flat => return Ok(Box::new(flat?)),
        }
    }
    Ok(Box::new(SparseFieldSolver::new(source)?))
}

/// The inputs of [`evolve_sparse`]: the source and the target without a
/// dense grid.
#[derive(Clone)]
pub struct SparseInputs {
    /// The source's signed distance (world units, positive inside) in a
    /// narrow band of bricks at least [`SparseFieldSolver::band_width`]
    /// wide, its side elsewhere ([`Bricks::sample_band`]); its dims are the
    /// evolution lattice's.
    pub source: Bricks<f32>,
    /// World position of node `(0, 0, 0)`.
    pub origin: Vec3,
    /// World units per voxel.
    pub spacing: f32,
    /// The speed at a world point (voxel units: the target's signed
    /// distance there, seen through the map `T`, over `spacing`).
    pub target: SpeedSampler,
    /// A bound on how fast `target` changes, in voxels per voxel moved: 1
    /// for an exact distance, the norm of `T`'s linear part with a map.
    pub lipschitz: f32,
}

impl fmt::Debug for SparseInputs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SparseInputs")
            .field("dims", &self.source.dims())
            .field("origin", &self.origin)
            .field("spacing", &self.spacing)
            .field("lipschitz", &self.lipschitz)
            .finish_non_exhaustive()
    }
}

/// [`evolve`] with memory proportional to the surfaces: the sparse field
/// built from the source's narrow band ([`SparseFieldSolver::from_band`]),
/// the overlap judged near the target's surface only
/// ([`check_overlap_sparse`]), the speed computed per brick where the
/// surface goes ([`SpeedGrid::lazy_unchecked`]). Same results as [`evolve`]
/// of the dense samples of the same fields.
///
/// # Errors
/// As [`evolve`]; [`MorphError::BadSetting`] for the dense solver, which
/// needs a dense source.
pub fn evolve_sparse(
    inputs: &SparseInputs,
    placement: Placement,
    settings: &EvolveSettings,
    control: &Control,
) -> Result<LevelSetMorph, LevelSetError> {
    control.install(|| {
        let stages = Stages::start();
        check_settings(settings)?;
        if settings.solver == SolverKind::Dense {
            return Err(
                MorphError::bad_setting("solver", "Dense", "the sparse field for a sparse source").into()
            );
        }
        let SparseInputs { source, origin, spacing, target, lipschitz } = inputs;
        let solver = Box::new(SparseFieldSolver::from_band(source, *spacing)?);
        let lattice = (*origin, *spacing);
        let overlap =
            check_overlap_sparse(source, lattice, target, *lipschitz, settings.max_unreached_share)?;
        // A bound on the speed from the lattice's centre (only the dense solver reads it).
        let dims = source.dims();
        let half = 0.5 * (dims - UVec3::ONE).as_vec3();
        let bound = target.at(*origin + *spacing * half).abs() + lipschitz * half.length();
        let speed = SpeedGrid::lazy_unchecked(dims, *origin, *spacing, Arc::clone(target), bound)?;
        let start = Start {
            solver,
            speed: &speed,
            overlap,
            lattice: (dims, *origin, *spacing),
            source_bytes: source.heap_bytes(),
        };
        run(start, placement, settings, control, stages)
    })
}

/// Iterations between two releases of the storage the band has left
/// ([`Solver::release`]; a pass over the allocated bricks).
const RELEASE_EVERY: usize = 16;

/// An evolution ready to run.
struct Start<'a> {
    solver: Box<dyn Solver + 'a>,
    speed: &'a SpeedGrid,
    overlap: Overlap,
    /// Nodes per axis, world position of node `(0, 0, 0)`, spacing.
    lattice: (UVec3, Vec3, f32),
    /// Heap bytes of the source's storage.
    source_bytes: usize,
}

/// Runs `start` to convergence, keeping frames as `settings` schedule.
fn run(
    start: Start<'_>,
    placement: Placement,
    settings: &EvolveSettings,
    control: &Control,
    mut stages: Stages,
) -> Result<LevelSetMorph, LevelSetError> {
    let Start { mut solver, speed, overlap, lattice: (dims, origin, spacing), source_bytes } = start;
    let mut frames = vec![solver.capture(0, 0.0)];
    let mut stats = Vec::new();
    let (mut time, mut last_kept_time) = (0.0f64, 0.0f64);
    let mut converged = false;
    let (mut best, mut best_at, mut stalled) = (f32::INFINITY, 0, false);
    let params = StepParams {
        max_time_step: settings.max_time_step,
        front_step: settings.front_step,
        curvature: settings.curvature,
    };
    let mut released = 0;
    // Iterations between kept frames under a budget.
    let mut stride = 1;
    // A frame due after an iteration that is not the last is captured by
    // the next step, beside its own work.
    let mut pending = None;
    for iteration in 1..=settings.max_iterations {
        control.check()?;
        let (s, frame) = solver.step_after_capture(speed, &params, pending.take());
        if let Some(frame) = frame {
            frames.push(frame);
            if let FrameSchedule::Budget(budget) = settings.frames
                && frames.len() > 2 * budget + 1
            {
                stride *= 2;
                frames.retain(|f| f.iteration % stride == 0);
            }
        }
        if iteration % RELEASE_EVERY == 0 {
            released += solver.release();
        }
        time += f64::from(s.dt);
        stats.push(s);
        control.progress("evolution", Some(iteration as f32 / settings.max_iterations as f32), || {
            format!("iteration {iteration}, RMS distance {:.3} voxels", s.rms_distance)
        });
        if s.rms_distance < 0.99 * best {
            (best, best_at) = (s.rms_distance, iteration);
        }
        let settled =
            best <= settings.settled_rms_distance && iteration - best_at >= settings.settle_iterations;
        converged = s.rms_distance <= settings.rms_distance || s.rms_change <= settings.rms_change || settled;
        stalled = !converged && iteration - best_at >= settings.stall_iterations;
        let done = converged || stalled || time >= settings.end_time;
        let due = match settings.frames {
            FrameSchedule::EveryIterations(k) => iteration % k == 0,
            FrameSchedule::EveryTime(dt) => time - last_kept_time >= dt,
            FrameSchedule::Budget(_) => iteration % stride == 0,
        };
        let last = done || iteration == settings.max_iterations;
        if due || last {
            last_kept_time = time;
            if last {
                frames.push(solver.capture(iteration, time));
            } else {
                pending = Some((iteration, time));
            }
        }
        if done {
            break;
        }
    }
    stages.lap("evolution");
    let last = stats.last().copied().unwrap_or_default();
    let outcome = if converged {
        Outcome::Converged
    } else if stalled {
        Outcome::Stalled
    } else {
        // The iteration cap or the evolution time limit.
        Outcome::IterationCap
    };
    let stored: usize = frames.iter().map(BandFrame::stored_bytes).sum();
    // The solver's state at the end (bricks are kept once allocated), the
    // speed's stored values and the source grid.
    let working = solver.heap_bytes() + speed.heap_bytes() + source_bytes;
    let report = MorphReport::new("level-set", outcome)
        .with_iterations(stats.len())
        .with_residual(Residual {
            what: "RMS target distance at the surface",
            value: f64::from(last.rms_distance),
            unit: "voxels",
        })
        .with_stages(stages)
        .with_memory(stored, Some(stored + working))
        .with_detail("solver", format!("{:?}", settings.solver))
        .with_detail("nodes", dims.as_u64vec3().element_product() as usize)
        .with_detail("evolution_time", time)
        .with_detail("final_rms_change_voxels", f64::from(last.rms_change))
        .with_detail("final_surface_nodes", last.surface_nodes)
        .with_detail("kept_frames", frames.len())
        .with_detail("released_bricks", released)
        .with_detail("placement", placement.kind())
        .with_detail("target_parts", overlap.parts)
        .with_detail("unreached_share", f64::from(overlap.unreached_share()))
        .with_warnings(overlap.warning());
    let field = Aabb::new(origin, origin + (dims - UVec3::ONE).as_vec3() * spacing);
    let world = placed_box(&field, &placement);
    let travel = cumulative_travel(&stats);
    Ok(LevelSetMorph { frames, dims, origin, spacing, placement, stats, travel, converged, world, report })
}

/// The surface's cumulative motion after each iteration (entry 0 the
/// start): the running sum of [`StepStats::rms_change`] (voxels; a
/// non-finite change counts as none), non-decreasing.
fn cumulative_travel(stats: &[StepStats]) -> Vec<f64> {
    let mut travel = Vec::with_capacity(stats.len() + 1);
    let mut sum = 0.0;
    travel.push(sum);
    for s in stats {
        let change = f64::from(s.rms_change);
        if change.is_finite() && change > 0.0 {
            sum += change;
        }
        travel.push(sum);
    }
    travel
}

/// A world box containing `field` placed by `T(·, α)` for every `α`: for
/// an affine path the union over 33 times (padded by 1 % for the arcs of a
/// rotation between them), for a warp the union of the box and its image
/// sampled on a 9³ lattice (`T` blends the two linearly).
fn placed_box(field: &Aabb, placement: &Placement) -> Aabb {
    let samples = |n: u32| (0..=n).map(move |i| i as f32 / n as f32);
    match placement {
        Placement::Identity => *field,
        Placement::Affine(_) => {
            let maps = samples(32).map(|a| placement.affine_at(a));
            isomorph_common::placed_bounds(field, maps).padded(0.01)
        }
        Placement::Warp(_) => {
            let size = field.size();
            let mut b = *field;
            for x in samples(8) {
                for y in samples(8) {
                    for z in samples(8) {
                        let p = field.min + size * Vec3::new(x, y, z);
                        b = b.union(&Aabb::new(placement.point_at(p, 1.0), placement.point_at(p, 1.0)));
                    }
                }
            }
            b.padded(0.02)
        }
    }
}

fn check_settings(s: &EvolveSettings) -> Result<(), MorphError> {
    check::count("max_iterations", s.max_iterations as u64, 1, u64::MAX)?;
    check::positive("max_time_step", f64::from(s.max_time_step))?;
    check::positive("front_step", f64::from(s.front_step))?;
    check::range("front_step", f64::from(s.front_step), 0.0, 0.5)?;
    check::count("stall_iterations", s.stall_iterations as u64, 1, u64::MAX)?;
    check::count("settle_iterations", s.settle_iterations as u64, 1, u64::MAX)?;
    check::range("max_unreached_share", f64::from(s.max_unreached_share), 0.0, 1.0)?;
    for (name, v) in [
        ("rms_distance", f64::from(s.rms_distance)),
        ("rms_change", f64::from(s.rms_change)),
        ("settled_rms_distance", f64::from(s.settled_rms_distance)),
    ] {
        if v.is_nan() {
            return Err(MorphError::bad_setting(name, v, "a threshold (not NaN)"));
        }
    }
    if s.end_time.is_nan() || s.end_time <= 0.0 {
        return Err(MorphError::bad_setting("end_time", s.end_time, "a time > 0 (infinite by default)"));
    }
    if let Some(c) = s.curvature {
        check::range("curvature.weight", f64::from(c.weight), 0.0, f64::from(f32::MAX))?;
        check::positive("curvature.length", f64::from(c.length))?;
    }
    s.frames.validate()
}

impl LevelSetMorph {
    /// Number of kept frames (at least 2: the source and the last iterate).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Always false: a morph keeps at least its first and last frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The kept frames, in order.
    pub fn frames(&self) -> &[BandFrame] {
        &self.frames
    }

    /// Statistics of every iteration.
    pub fn stats(&self) -> &[StepStats] {
        &self.stats
    }

    /// Evolution time reached (eq. 17's `t`).
    pub fn end_time(&self) -> f64 {
        self.stats.iter().map(|s| f64::from(s.dt)).sum()
    }

    /// Whether a stopping threshold was met before the iteration cap.
    pub fn converged(&self) -> bool {
        self.converged
    }

    /// Heap bytes of all kept frames.
    pub fn stored_bytes(&self) -> usize {
        self.frames.iter().map(BandFrame::stored_bytes).sum()
    }

    /// Kept frame `n` as a signed distance-like grid (world units, positive
    /// inside; exact next to the zero set).
    ///
    /// # Errors
    /// [`MorphError::Grid`](isomorph_common::MorphError::Grid) if the grid cannot be allocated.
    pub fn frame_grid(&self, n: usize) -> Result<Grid3<f32>, LevelSetError> {
        let n = n.min(self.frames.len() - 1);
        self.grid_at((n, n, 0.0))
    }

    /// The embedding at the bracket `(a, b, w)` ([`Self::fill`]) as a grid.
    fn grid_at(&self, bracket: (usize, usize, f32)) -> Result<Grid3<f32>, LevelSetError> {
        let mut data = vec![0.0; self.dims.element_product() as usize];
        self.fill(bracket, 0, &mut data);
        Ok(Grid3::from_vec(self.dims, self.origin, self.spacing, data)?)
    }

    /// The surface's travel after each iteration (entry `i` after `i`
    /// iterations, entry 0 the start): the cumulative sum of
    /// [`StepStats::rms_change`], in voxels. Morph time `t` shows the
    /// embedding at travel `t × travel.last()` (see [`LevelSetMorph`]).
    pub fn travel(&self) -> &[f64] {
        &self.travel
    }

    /// The travel (voxels) at which kept frame `n` was captured.
    fn frame_travel(&self, n: usize) -> f64 {
        let i = self.frames[n].iteration;
        self.travel.get(i).or(self.travel.last()).copied().unwrap_or(0.0)
    }

    /// The kept frames `(a, b)` bracketing morph time `t` (in `[0, 1]`) and
    /// the weight of `b`: `(n, n, 0)` when frame `n` is at that travel.
    fn bracket(&self, t: f32) -> (usize, usize, f32) {
        let last = self.frames.len() - 1;
        if t >= 1.0 {
            return (last, last, 0.0);
        }
        let end = self.frame_travel(last);
        let at = f64::from(t) * end;
        // The first kept frame at or past `at` (the travel never decreases).
        let (mut b, mut hi) = (0, last);
        while b < hi {
            let mid = (b + hi) / 2;
            if self.frame_travel(mid) < at { b = mid + 1 } else { hi = mid }
        }
        let tb = self.frame_travel(b);
        if tb <= at || b == 0 {
            return (b, b, 0.0);
        }
        let ta = self.frame_travel(b - 1);
        (b - 1, b, ((at - ta) / (tb - ta)) as f32)
    }

    /// The embedding (world units) of nodes `start .. start + out.len()` at
    /// the bracket `(a, b, w)`: `(1 − w)` frame `a` plus `w` frame `b`.
    fn fill(&self, (a, b, w): (usize, usize, f32), start: usize, out: &mut [f32]) {
        self.frames[a].fill(start, out);
        if w > 0.0 {
            let mut later = vec![0.0; out.len()];
            self.frames[b].fill(start, &mut later);
            out.iter_mut().zip(&later).for_each(|(v, l)| *v = (1.0 - w) * *v + w * l);
        }
        out.iter_mut().for_each(|v| *v *= self.spacing);
    }

    /// Breen's `T(x, α)` placing the kept frames.
    pub fn placement(&self) -> &Placement {
        &self.placement
    }

    /// The report, for the constructor that adds its stages.
    pub(crate) fn report_mut(&mut self) -> &mut MorphReport {
        &mut self.report
    }
}

impl Morph for LevelSetMorph {
    type Field = Grid3<f32>;
    type Error = LevelSetError;

    fn method(&self) -> &'static str {
        "level-set"
    }

    fn frame(&self, t: f32) -> Result<Frame<Grid3<f32>>, LevelSetError> {
        let t = check_time(t)?;
        let field = self.grid_at(self.bracket(t))?;
        Ok(Frame { field, iso: 0.0, transform: self.placement.affine_at(t) })
    }

    /// The evolution lattice's box (source space).
    fn field_bounds(&self) -> Aabb {
        Aabb::new(self.origin, self.origin + (self.dims - UVec3::ONE).as_vec3() * self.spacing)
    }

    fn world_bounds(&self) -> Aabb {
        self.world
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }

    /// Marching cubes directly on the frame's lattice (`res` ignored: the
    /// resolution is the evolution's), placed by `T(x, t)`.
    fn frame_mesh(&self, t: f32, _res: u32) -> Result<TriMesh, LevelSetError> {
        let t = check_time(t)?;
        let bracket = self.bracket(t);
        // Rebuilt plane by plane: the same mesh as marching cubes of
        // `frame(t)`'s grid, without the dense grid.
        let plane_len = (self.dims.x * self.dims.y) as usize;
        let mut mesh = marching_cubes_planes(self.dims, self.origin, self.spacing, 0.0, |k| {
            let mut values = vec![0.0; plane_len];
            self.fill(bracket, k * plane_len, &mut values);
            Cow::Owned(values)
        });
        self.placement.apply(&mut mesh, t);
        Ok(mesh)
    }

    /// `T(·, t)`'s affine part, without making the frame.
    fn world_transform(&self, t: f32) -> Result<Affine3A, LevelSetError> {
        Ok(self.placement.affine_at(check_time(t)?))
    }

    /// Each point's field point `x` (`T(x, α) = p`, [`Placement::unplace`])
    /// placed at `α = 0` and `α = 1`: exact for a warp too, where the default
    /// (affine parts only) would read the inputs' colours where the frame
    /// lies, not where its surface came from.
    fn ends_of(&self, t: f32, points: &[Vec3]) -> Result<[Vec<Vec3>; 2], LevelSetError> {
        let alpha = check_time(t)?;
        let Placement::Warp(warp) = &self.placement else {
            // An affine placement: two maps, computed once.
            let back = self.placement.affine_at(alpha).inverse();
            let to = |end: f32| {
                let map = self.placement.affine_at(end) * back;
                points.iter().map(|&p| map.transform_point3(p)).collect()
            };
            return Ok([to(0.0), to(1.0)]);
        };
        let scale = self.field_bounds().size().max_element();
        let field: Vec<Vec3> = points.par_iter().map(|&p| self.placement.unplace(p, alpha, scale)).collect();
        let on_target = field.par_iter().map(|&x| warp(x)).collect();
        Ok([field, on_target])
    }
}
