//! The dense up-wind solver (Breen & Whitaker §5.2.1, eq. 18–24): every node
//! of the grid is updated at every iteration. The reference for the sparse
//! field solver; its cost grows with the volume.

use crate::solver::{Solver, StepParams, StepStats, node_rate, stable_time_step};
use crate::stencil::{Lattice, speed_at_zero_crossing};
use crate::{BandFrame, LevelSetError, SpeedGrid};
use isomorph_common::Grid3;
use rayon::prelude::*;

/// The whole-grid up-wind solver.
#[derive(Debug, Clone)]
pub struct DenseSolver {
    lattice: Lattice,
    u: Vec<f32>,
    change: Vec<f32>,
}

impl DenseSolver {
    /// Starts from the source's signed distance grid (world units, positive
    /// inside), converted to voxel units.
    ///
    /// # Errors
    /// [`LevelSetError::NonFinite`], [`MorphError::Grid`](isomorph_common::MorphError::Grid) (fewer than 3 nodes per axis, or over the memory limit),
    /// [`LevelSetError::NoSurface`] for a source without a sign change.
    pub fn new(source: &Grid3<f32>) -> Result<Self, LevelSetError> {
        // The embedding and the change volume.
        let (lattice, u) = crate::initial_embedding(source, 8)?;
        let change = vec![0.0; u.len()];
        Ok(Self { lattice, u, change })
    }
}

impl Solver for DenseSolver {
    fn heap_bytes(&self) -> usize {
        (self.u.capacity() + self.change.capacity()) * size_of::<f32>()
    }

    fn step(&mut self, speed: &SpeedGrid, params: &StepParams) -> StepStats {
        let (lattice, u, v) = (&self.lattice, &self.u, speed.reader());
        let h = speed.spacing();
        // Steps 4a–d: up-wind change per node into a separate volume.
        self.change.par_iter_mut().enumerate().for_each(|(n, c)| {
            *c = node_rate(lattice, u, n, v.node(n), h, params.curvature).0;
        });
        // Step 5: eq. 24 with the front step (λ ≤ 1, so the largest target speed bounds the
        // distance term with or without curvature).
        let dt = stable_time_step(speed.max_abs(), params);
        // Step 6: update, and the stopping statistics at the surface nodes
        // (target distance sampled at the subvoxel zero crossing, as the
        // sparse field does, so both solvers stop by the same measure).
        self.u.par_iter_mut().zip(self.change.par_iter()).for_each(|(un, &c)| *un += dt * c);
        let (u, change) = (&self.u, &self.change);
        let (sum_change, sum_dist, count) = (0..u.len())
            .into_par_iter()
            .filter(|&n| lattice.on_zero_set(u, n))
            .map(|n| {
                let gamma = speed_at_zero_crossing(lattice, u, speed, n);
                ((dt * change[n]).powi(2), gamma * gamma, 1usize)
            })
            .reduce(|| (0.0, 0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
        let denom = count.max(1) as f32;
        StepStats {
            dt,
            rms_change: (sum_change / denom).sqrt(),
            rms_distance: (sum_dist / denom).sqrt(),
            surface_nodes: count,
        }
    }

    fn capture(&self, iteration: usize, time: f64) -> BandFrame {
        BandFrame::capture(&self.u, &self.lattice, iteration, time)
    }
}
