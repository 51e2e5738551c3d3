//! Level-set shape metamorphosis after Breen & Whitaker, *A Level-Set Approach
//! for the Metamorphosis of Solid Models*, IEEE TVCG 7(2), 2001.
//!
//! The source surface is the zero set of an embedding `φ` (positive inside)
//! that evolves under `∂φ/∂t = |∇φ| γ_B` (eq. 17), where the speed
//! `γ_B(x) = f(D_B(T(x)))` is the target's signed distance seen through a
//! transform `T` ([`SpeedGrid`]): the surface grows where it is inside the
//! target and shrinks where it is outside, and stops on the target's surface.
//! Unlike blending distance volumes, no piece of the target appears out of
//! thin air: the surface moves continuously (Fig. 5 vs Fig. 6).
//!
//! Two solvers share the [`Solver`] interface:
//! - [`DenseSolver`]: the up-wind scheme over the whole grid (eq. 18–24);
//! - [`SparseFieldSolver`]: Whitaker's sparse field (§5.2.2) with the speed
//!   sampled at the subvoxel zero crossing; cost per iteration ∝ surface.
//!   Its embedding and status live in 8³ bricks allocated where the band is
//!   or has been ([`isomorph_common::Bricks`]), the far side elsewhere;
//!   [`SparseFieldSolver::from_field`] builds it from a narrow band of the
//!   source's distance and [`SpeedGrid::lazy`] computes the target speed
//!   per brick where the band goes (a brick at a time from a
//!   [`TargetSpeed`]: for a mesh, one batch query with its signs found once
//!   per region), so no dense grid is needed at all.
//!
//! [`evolve`] runs either to convergence and keeps frames in memory
//! proportional to the surface ([`BandFrame`]), as many as its
//! [`FrameSchedule`] says ([`LevelSetMorph::new`] keeps at most
//! `2 × FRAME_BUDGET + 2`, [`FRAME_BUDGET`], whatever the iteration count);
//! the result is a [`LevelSetMorph`], an [`isomorph_common::Morph`], whose
//! frame at time `t` is where the surface has made the share `t` of its
//! whole motion ([`LevelSetMorph::travel`]), interpolated between the two
//! kept frames around it when it was not kept, and polygonized plane by
//! plane (no dense grid).
//!
//! [`LevelSetMorph::new`] stores sparsely from [`SPARSE_FROM`] nodes up
//! ([`Storage`]): the source's distance in a narrow band of bricks and its
//! side elsewhere, the speed per brick where the surface goes, the overlap
//! judged near the target's surface ([`check_overlap_sparse`]), bricks the
//! band has left released ([`evolve_sparse`]); the kept frames are the
//! dense storage's.
//!
//! Units: grids are world units; solver values and speeds are in voxels.
//!
//! # Paper sections → modules
//! | paper | where |
//! |---|---|
//! | §3 the goal-driven motion along `γ_B N`; §4 steady state and overlap | [`evolve`], [`evolve_sparse`], [`SpeedGrid`], [`Response`], [`check_overlap`], [`check_overlap_sparse`] |
//! | §5.1–5.2.1 the level-set equation, up-wind differences and the time-step bound | [`DenseSolver`], [`StepParams`] |
//! | §5.2.2 Whitaker's sparse field: active layer, ±1 and ±2 layers, status changes | [`SparseFieldSolver`] |
//! | §6.1 scan conversion of CSG models into signed distances | `isomorph_common::scan_conversion`, through [`isomorph_common::Solid`] |
//! | §6.2 coordinate transforms `T` and their interpolation (eq. 25); the Appendix's moment alignment | [`Placement`], [`Align`], `isomorph_common::alignment` |
//! | §6.3 level-set deformation, frames kept near the surface; §6.4 polygonization | [`LevelSetMorph`], [`BandFrame`] |
//! | beyond the paper: a weighted mean-curvature term | [`Curvature`] |
//! | the whole pipeline from two solids | [`LevelSetMorph::new`], [`LevelSetSettings`] |
//!
//! # Guarantees
//! - Frame 0 is the source's distance volume and the last frame the
//!   converged evolution; every frame mesh is closed and outward, and the
//!   same for any thread count.
//! - Parts of the target the source does not overlap (judged on the target:
//!   a thin feature its sampling splits stays one part) are never silently
//!   dropped: up to [`LevelSetSettings::max_unreached_share`] of the target
//!   they are named in the report's warnings, above it they are a
//!   [`MorphError::NoOverlap`](isomorph_common::MorphError::NoOverlap)
//!   error naming each part and its share.
//! - Cost per sparse-field iteration grows with the surface, not the volume
//!   (measurements in `docs/EXPERIMENTS.md`).
//!
//! # Example
//! ```
//! use isomorph_common::{Control, Morph, Shape, Solid, models};
//! use isomorph_levelset::{LevelSetMorph, LevelSetSettings};
//!
//! let (sphere, torus) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(models::torus()));
//! let settings = LevelSetSettings { resolution: 48, ..Default::default() };
//! let morph = LevelSetMorph::new(&sphere, &torus, &settings, &Control::new())?;
//! assert!(morph.report().converged);
//! assert_eq!(morph.frame_mesh(1.0, 0)?.genus(), Some(1)); // the sphere became a torus
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The paper-level pieces stay public: sample a speed and evolve a grid
//! yourself.
//!
//! ```
//! use isomorph_common::{Aabb, Control, Grid3, Shape};
//! use isomorph_levelset::{EvolveSettings, Placement, Response, SpeedGrid, evolve};
//!
//! let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 32)?;
//! let speed = SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, Response::Identity)?;
//! let morph = evolve(&source, &speed, Placement::Identity, &EvolveSettings::default(), &Control::new())?;
//! assert!(morph.converged());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod band;
mod contract;
mod dense;
mod error;
mod evolution;
mod overlap;
mod placement;
mod solver;
mod sparse_field;
mod speed;
mod stencil;

pub use band::BandFrame;
pub use contract::{Align, FRAME_BUDGET, LevelSetSettings, SPARSE_FROM, Storage};
pub use dense::DenseSolver;
pub use error::LevelSetError;
pub use evolution::{
    EvolveSettings, FLAT_STATE_NODES, FrameSchedule, LevelSetMorph, SolverKind, SparseInputs, evolve,
    evolve_sparse,
};
pub use overlap::{Overlap, check_overlap, check_overlap_sparse};
pub use placement::{Placement, Warp};
pub use solver::{Curvature, FRONT_STEP, Solver, StepParams, StepStats};
pub use sparse_field::SparseFieldSolver;
pub use speed::{Response, SpeedGrid, SpeedSampler, TargetSpeed};

use isomorph_common::{Grid3, GridError};
use stencil::Lattice;

/// Checks a source distance grid and converts it to voxel units; a solver
/// needing `bytes_per_node` of state per node is refused with
/// [`GridError::TooLarge`] over the process-wide grid memory limit.
fn initial_embedding(
    source: &Grid3<f32>,
    bytes_per_node: usize,
) -> Result<(Lattice, Vec<f32>), LevelSetError> {
    let lattice = check_source(source, bytes_per_node)?;
    let inv_h = 1.0 / source.spacing();
    Ok((lattice, source.data().iter().map(|&d| d * inv_h).collect()))
}

/// Checks a source distance grid: at least 3 nodes per axis,
/// `bytes_per_node` of solver state per node within the memory limit,
/// finite values, and a sign change (in voxel units, as the solvers see it).
fn check_source(source: &Grid3<f32>, bytes_per_node: usize) -> Result<Lattice, LevelSetError> {
    let dims = source.dims();
    if dims.min_element() < 3 {
        return Err(GridError::TooSmall { dims, min: 3 }.into());
    }
    let requested = source.len().saturating_mul(bytes_per_node);
    let limit = isomorph_common::memory_limit();
    if requested > limit {
        return Err(GridError::TooLarge { dims, requested, limit }.into());
    }
    if let Some(node) = source.data().iter().position(|v| !v.is_finite()) {
        return Err(LevelSetError::NonFinite { what: "source", node });
    }
    let inv_h = 1.0 / source.spacing();
    let inside = |&d: &f32| d * inv_h > 0.0;
    if !source.data().iter().any(inside) || source.data().iter().all(inside) {
        return Err(LevelSetError::NoSurface("source"));
    }
    Ok(Lattice::new(dims))
}
