//! The target speed `γ_B(x) = f(D_B(T(x)))` of Breen & Whitaker eq. 6,
//! sampled once on the evolution lattice.

use crate::LevelSetError;
use crate::stencil::Lattice;
use isomorph_common::glam::Vec3;
use isomorph_common::{Field3, Grid3};
use rayon::prelude::*;

/// The monotone map `f` with `f(0) = 0` turning the target's signed distance
/// (world units, positive inside) into a speed.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Response {
    /// `f(d) = d`: the paper's choice; far parts move fast, and the time step
    /// (eq. 24) shrinks accordingly.
    #[default]
    Identity,
    /// `f(d) = clamp(d, −max, max)` (world units): bounded speed, so the time
    /// step stays large while far parts approach at constant speed.
    Clamped {
        /// Largest speed magnitude, in world units of distance.
        max: f32,
    },
}

impl Response {
    /// `f(d)`.
    pub fn apply(self, d: f32) -> f32 {
        match self {
            Response::Identity => d,
            Response::Clamped { max } => d.clamp(-max, max),
        }
    }
}

/// The speed at every node of the evolution lattice, in voxel units (target
/// distance divided by the grid spacing), positive where the target is
/// inside (the surface expands there).
#[derive(Debug, Clone)]
pub struct SpeedGrid {
    /// Speeds in voxel units on the evolution lattice.
    grid: Grid3<f32>,
    max_abs: f32,
}

impl SpeedGrid {
    /// Samples `f(target(map(x)))` at every node `x` of `lattice`'s grid
    /// (its values are ignored; only its nodes are used). `map` is Breen's
    /// transform `T` from the evolving (source) space into the target's
    /// space (eq. 25); pass `|x| x` for none.
    ///
    /// # Errors
    /// [`LevelSetError::NonFinite`] if the target gives NaN or infinity at a
    /// node; [`LevelSetError::NoSurface`] if the target has no inside node.
    pub fn sample<F, M>(
        lattice: &Grid3<f32>,
        target: &F,
        map: M,
        response: Response,
    ) -> Result<Self, LevelSetError>
    where
        F: Field3 + ?Sized,
        M: Fn(Vec3) -> Vec3 + Sync,
    {
        let lat = Lattice::new(lattice.dims());
        let inv_h = 1.0 / lattice.spacing();
        let values: Vec<f32> = (0..lat.len())
            .into_par_iter()
            .map(|n| {
                let [i, j, k] = lat.coords(n);
                let x = lattice.position(i as u32, j as u32, k as u32);
                response.apply(target.value(map(x))) * inv_h
            })
            .collect();
        Self::from_voxel_values(lattice, values)
    }

    /// A target distance grid (world units, positive inside) that already
    /// lies on the evolution lattice, through `response`.
    ///
    /// # Errors
    /// As [`SpeedGrid::sample`].
    pub fn from_grid(target: &Grid3<f32>, response: Response) -> Result<Self, LevelSetError> {
        let inv_h = 1.0 / target.spacing();
        let values = target.data().par_iter().map(|&d| response.apply(d) * inv_h).collect();
        Self::from_voxel_values(target, values)
    }

    /// Wraps voxel-unit `values` on the lattice of `like`.
    fn from_voxel_values(like: &Grid3<f32>, values: Vec<f32>) -> Result<Self, LevelSetError> {
        if let Some(node) = values.iter().position(|v| !v.is_finite()) {
            return Err(LevelSetError::NonFinite { what: "target", node });
        }
        if !values.iter().any(|&v| v > 0.0) {
            return Err(LevelSetError::NoSurface("target"));
        }
        let max_abs = values.par_iter().map(|v| v.abs()).reduce(|| 0.0, f32::max);
        let grid = Grid3::from_vec(like.dims(), like.origin(), like.spacing(), values)?;
        Ok(Self { grid, max_abs })
    }

    /// Speeds per node (voxel units), x-fastest.
    pub fn values(&self) -> &[f32] {
        self.grid.data()
    }

    /// Largest speed magnitude (voxels per unit time).
    pub fn max_abs(&self) -> f32 {
        self.max_abs
    }

    /// Grid spacing (world units per voxel).
    pub fn spacing(&self) -> f32 {
        self.grid.spacing()
    }

    /// The speeds as a grid (voxel units) on the evolution lattice.
    pub fn grid(&self) -> &Grid3<f32> {
        &self.grid
    }

    /// Trilinear speed at voxel coordinates `g` (clamped to the grid).
    pub(crate) fn at_voxel(&self, g: Vec3) -> f32 {
        self.grid.trilinear(self.grid.origin() + g * self.grid.spacing())
    }
}
