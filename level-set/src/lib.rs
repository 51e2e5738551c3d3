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
//!
//! [`evolve`] runs either to convergence and keeps frames in memory
//! proportional to the surface ([`BandFrame`]); the result is a
//! [`LevelSetMorph`], an [`isomorph_common::Morph`].
//!
//! Units: grids are world units; solver values and speeds are in voxels.
//!
//! # Performance
//! The reference case (sphere r = 0.3 → torus R = 0.3, r = 0.12 in
//! `[-0.5, 0.5]³`, N³ nodes, speed = target distance), measured on a quiet
//! 2-core machine with `cargo bench -p isomorph-benches --bench levelset`:
//!
//! | N | sparse field, per iteration | dense, per iteration | sparse, whole morph |
//! |---|---|---|---|
//! | 64 | 0.77 ms | 5.0 ms | 79 ms |
//! | 128 | 3.6 ms (×4.7) | 39 ms (×7.8) | 683 ms |
//! | 256 | 17.9 ms (×4.9) | 312 ms (×8.0) | |
//!
//! The sparse field's cost grows like the surface (×4 per doubling), the
//! dense solver's like the volume (×8). Two things keep the sparse field's
//! cost per point flat once the grids outgrow the caches: its layer lists
//! are kept sorted by node index (so each iteration sweeps memory in order),
//! and the solver state is stepped in place. The whole dense morph at 64³
//! (to the sparse field's evolution time) needs about 600 iterations, as
//! eq. 24 bounds its step by the largest target distance anywhere.
//!
//! # Example
//! ```
//! use isomorph_common::{Aabb, Grid3, Morph, Shape};
//! use isomorph_levelset::{EvolveSettings, Placement, Response, SpeedGrid, evolve};
//!
//! let bounds = Aabb::cube(0.5);
//! let source = Grid3::sample_box(&Shape::sphere(0.3), &bounds, 32)?;
//! let torus = Shape::torus(0.3, 0.12);
//! let speed = SpeedGrid::sample(&source, &torus, |x| x, Response::Identity)?;
//! let morph = evolve(&source, &speed, Placement::Identity, &EvolveSettings::default(), &|_| {})?;
//! assert!(morph.converged());
//! let last = morph.frame_mesh(1.0, 0)?;
//! assert_eq!(last.genus(), Some(1)); // the sphere became a torus
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod band;
mod dense;
mod error;
mod evolution;
mod placement;
mod solver;
mod sparse_field;
mod speed;
mod stencil;

pub use band::BandFrame;
pub use dense::DenseSolver;
pub use error::LevelSetError;
pub use evolution::{
    EvolveSettings, FrameSchedule, LevelSetMorph, Progress, SolverKind, check_overlap, evolve,
};
pub use placement::{Placement, Warp};
pub use solver::{Curvature, Solver, StepParams, StepStats};
pub use sparse_field::SparseFieldSolver;
pub use speed::{Response, SpeedGrid};

use isomorph_common::{Grid3, GridError};
use stencil::Lattice;

/// Checks a source distance grid and converts it to voxel units; a solver
/// needing `bytes_per_node` of state per node is refused with
/// [`GridError::TooLarge`] over the process-wide grid memory limit.
fn initial_embedding(
    source: &Grid3<f32>,
    bytes_per_node: usize,
) -> Result<(Lattice, Vec<f32>), LevelSetError> {
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
    let u: Vec<f32> = source.data().iter().map(|&d| d * inv_h).collect();
    let lattice = Lattice::new(dims);
    if !u.iter().any(|&v| v > 0.0) || u.iter().all(|&v| v > 0.0) {
        return Err(LevelSetError::NoSurface("source"));
    }
    Ok((lattice, u))
}
