//! What both solvers share: the [`Solver`] interface and per-iteration
//! statistics.

use crate::SpeedGrid;

/// Statistics of one solver iteration; distances in voxels.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct StepStats {
    /// Time step used (eq. 24, and the sparse field's half-voxel limit).
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

/// A level-set solver for `∂φ/∂t = |∇φ| γ` (Breen & Whitaker eq. 17) on a
/// fixed lattice; values in voxel units, positive inside.
pub trait Solver: Send {
    /// One explicit Euler iteration (eq. 18) with the largest stable time
    /// step, capped at `max_dt`.
    fn step(&mut self, speed: &SpeedGrid, max_dt: f32) -> StepStats;

    /// The embedding `φ` at every node (voxel units, positive inside). Only
    /// its sign and the values next to the zero set are meaningful for the
    /// sparse-field solver.
    fn embedding(&self) -> &[f32];
}
