//! The target speed `γ_B(x) = f(D_B(T(x)))` of Breen & Whitaker eq. 6,
//! sampled once on the evolution lattice.

use crate::LevelSetError;
use crate::stencil::Lattice;
use isomorph_common::glam::{UVec3, Vec3};
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

    /// Speed at voxel coordinates `g` (clamped to the grid): trilinear
    /// interpolation of the node speeds, corrected by its second-order
    /// error term.
    ///
    /// Trilinear interpolation in a cell is exact for `x`, `y`, `z` and
    /// their products but misses the pure second derivatives: its error is
    /// `½ Σᵢ tᵢ(1 − tᵢ) ∂ᵢᵢγ` (cell-local coordinates `t ∈ [0, 1]³`). A
    /// distance bends by the surface's curvature, so on a curved target the
    /// interpolated zero set is pulled inwards on convex parts and outwards
    /// on concave ones (by a hundredth of a voxel on the reference case;
    /// `docs/EXPERIMENTS.md`). The correction subtracts that term,
    /// with `∂ᵢᵢγ` the second difference at the cell edge's two ends nearest
    /// `g`, limited by min-mod: the smaller when both have the same sign,
    /// none across a kink of the distance (a medial axis, a CSG edge, a
    /// clamped response) where they differ. The result is third-order
    /// accurate where the speed is smooth and never corrects more than the
    /// smaller of the two curvatures would.
    pub(crate) fn at_voxel(&self, g: Vec3) -> f32 {
        let dims = self.grid.dims();
        let v = self.grid.data();
        let strides = [1usize, dims.x as usize, (dims.x * dims.y) as usize];
        let g = g.clamp(Vec3::ZERO, (dims - UVec3::ONE).as_vec3());
        // Solver lattices have at least 3 nodes per axis.
        let base = g.floor().min((dims - UVec3::splat(2)).as_vec3());
        let t = g - base;
        let b = base.as_uvec3();
        let at = |c: UVec3| c.x as usize + c.y as usize * strides[1] + c.z as usize * strides[2];
        let corner = at(b);
        let c = |i: usize, j: usize, k: usize| v[corner + i + j * strides[1] + k * strides[2]];
        let x00 = c(0, 0, 0) + t.x * (c(1, 0, 0) - c(0, 0, 0));
        let x10 = c(0, 1, 0) + t.x * (c(1, 1, 0) - c(0, 1, 0));
        let x01 = c(0, 0, 1) + t.x * (c(1, 0, 1) - c(0, 0, 1));
        let x11 = c(0, 1, 1) + t.x * (c(1, 1, 1) - c(0, 1, 1));
        let y0 = x00 + t.y * (x10 - x00);
        let y1 = x01 + t.y * (x11 - x01);
        let trilinear = y0 + t.z * (y1 - y0);
        // The cell corner nearest `g`.
        let near = b + UVec3::new(u32::from(t.x > 0.5), u32::from(t.y > 0.5), u32::from(t.z > 0.5));
        let mut correction = 0.0;
        for axis in 0..3 {
            if b[axis] == 0 || b[axis] + 2 >= dims[axis] {
                continue;
            }
            let mut lo = near;
            lo[axis] = b[axis];
            let (n, s) = (at(lo), strides[axis]);
            let (before, first, second, after) = (v[n - s], v[n], v[n + s], v[n + 2 * s]);
            let (d_first, d_second) = (before - 2.0 * first + second, first - 2.0 * second + after);
            let curvature = if d_first * d_second <= 0.0 {
                0.0
            } else if d_first.abs() < d_second.abs() {
                d_first
            } else {
                d_second
            };
            correction += t[axis] * (1.0 - t[axis]) * curvature;
        }
        trilinear - 0.5 * correction
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::{Aabb, Shape};

    /// On a sphere of radius 9.6 voxels, points on the surface read a speed
    /// within 0.003 voxel of zero, a fifth of trilinear interpolation's
    /// error at most (its zero set is pulled inwards).
    #[test]
    fn corrected_interpolation_puts_a_curved_zero_set_in_place() {
        let grid = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 33).unwrap();
        let speed = SpeedGrid::from_grid(&grid, Response::Identity).unwrap();
        let h = grid.spacing();
        let (mut corrected, mut trilinear) = (0.0f32, 0.0f32);
        for i in 0..40 {
            for j in 0..20 {
                let (a, b) = (i as f32 * 0.157, 0.05 + j as f32 * 0.155);
                let p = 0.3 * Vec3::new(b.sin() * a.cos(), b.sin() * a.sin(), b.cos());
                corrected = corrected.max(speed.at_voxel((p - grid.origin()) / h).abs());
                trilinear = trilinear.max(speed.grid().trilinear(p).abs());
            }
        }
        assert!(
            corrected < 0.003 && corrected < 0.2 * trilinear,
            "corrected {corrected}, trilinear {trilinear} voxel at the surface"
        );
    }

    /// Across a kink of the distance (a slab's middle plane), the limiter
    /// keeps the correction from overshooting: the corrected value is never
    /// further from the true distance than the trilinear one.
    #[test]
    fn the_correction_is_limited_across_a_kink() {
        let slab = Shape::cuboid(Vec3::new(0.5, 0.5, 0.1));
        let grid = Grid3::sample_box(&slab, &Aabb::cube(0.5), 33).unwrap();
        let speed = SpeedGrid::from_grid(&grid, Response::Identity).unwrap();
        let h = grid.spacing();
        // Along z through the slab's middle plane (a kink of the distance).
        for k in 0..=40 {
            let p = Vec3::new(0.013, -0.021, -0.05 + 0.1 * k as f32 / 40.0);
            let exact = slab.value(p) / h;
            let got = speed.at_voxel((p - grid.origin()) / h);
            let tri = speed.grid().trilinear(p);
            assert!((got - exact).abs() <= (tri - exact).abs() + 1e-5, "z {}: {got} vs {exact}", p.z);
        }
    }
}
