//! The [`Morph`] trait every method implements, and the naive baseline:
//! linear interpolation of two signed distance volumes ([`DistanceBlend`]),
//! the comparison every method should beat (Breen & Whitaker Fig. 6, Turk &
//! O'Brien Fig. 3 top row).

use crate::marching_cubes::marching_cubes;
use crate::{Aabb, Field3, Grid3, GridError, TriMesh};
use glam::Affine3A;
use rayon::prelude::*;

/// One in-between shape: a field (positive inside, surface at `iso`) in the
/// morph's field space, and the map that places it in the world.
#[derive(Debug, Clone)]
pub struct Frame<F> {
    /// The shape as a field.
    pub field: F,
    /// The surface is the level set `field == iso`.
    pub iso: f32,
    /// Field space → world space (Breen eq. 25's `T(x, t)`; identity when the
    /// method needs no placement).
    pub transform: Affine3A,
}

/// A time-parameterized shape: `frame(0)` is the source, `frame(1)` the target.
pub trait Morph: Sync {
    /// The field of one frame.
    type Field: Field3;
    /// What can go wrong when making a frame.
    type Error: std::error::Error + From<GridError> + Send + Sync + 'static;

    /// Short method name used in reports (`"baseline"`, `"level-set"`, ...).
    fn method(&self) -> &str;

    /// The shape at time `t ∈ [0, 1]`.
    ///
    /// # Errors
    /// Method specific; every method rejects `t` outside `[0, 1]` or NaN.
    fn frame(&self, t: f32) -> Result<Frame<Self::Field>, Self::Error>;

    /// A box in field space containing the surface of every frame.
    fn bounds(&self) -> Aabb;

    /// Method-specific facts a user needs to trust the result (iterations,
    /// residuals, convergence, memory), as JSON; the sequence exporter
    /// writes them into `report.json` under `details`. `None` by default.
    fn details(&self) -> Option<serde_json::Value> {
        None
    }

    /// The frame at `t` as a world-space mesh: the field sampled over
    /// [`Morph::bounds`] with `res` nodes along its longest edge, marching
    /// cubes at the frame's iso value, then placed by the frame's transform.
    /// Methods whose frames already are grids override this to skip the
    /// resampling.
    ///
    /// # Errors
    /// As [`Morph::frame`], plus grid allocation errors.
    fn frame_mesh(&self, t: f32, res: u32) -> Result<TriMesh, Self::Error> {
        let frame = self.frame(t)?;
        let grid = Grid3::sample_box(&frame.field, &self.bounds().expanded(1e-4), res)?;
        let mut mesh = marching_cubes(&grid, frame.iso);
        mesh.transform(&frame.transform);
        Ok(mesh)
    }
}

/// Errors of the baseline morph (and a convenient error type for simple morphs).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MorphError {
    /// `t` is NaN or outside `[0, 1]`.
    #[error("time {0} is outside [0, 1]")]
    InvalidTime(f32),
    /// A grid could not be made, or two grids do not share a lattice.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// An input field has a NaN or infinite value.
    #[error("the {0} field has a NaN or infinite value at node {1}")]
    NonFinite(&'static str, usize),
    /// An input shape is empty (no node inside) — nothing to morph.
    #[error("the {0} shape is empty: no grid node is inside it")]
    EmptyShape(&'static str),
}

/// Checks that `t` is a valid morph time.
///
/// # Errors
/// [`MorphError::InvalidTime`] for NaN or `t ∉ [0, 1]`.
pub fn check_time(t: f32) -> Result<f32, MorphError> {
    if (0.0..=1.0).contains(&t) { Ok(t) } else { Err(MorphError::InvalidTime(t)) }
}

/// The naive baseline: `d(t) = (1 − t) d_A + t d_B` for two signed distance
/// volumes on one lattice. Cheap, but pieces of the target "pop out of thin
/// air" wherever the shapes do not overlap (Breen & Whitaker Fig. 6).
#[derive(Debug, Clone)]
pub struct DistanceBlend {
    source: Grid3<f32>,
    target: Grid3<f32>,
}

impl DistanceBlend {
    /// The blend of two signed distance grids (positive inside) on one lattice.
    ///
    /// # Errors
    /// [`MorphError::Grid`] when the lattices differ, [`MorphError::NonFinite`]
    /// for NaN or infinite values, [`MorphError::EmptyShape`] when a grid has
    /// no positive node.
    pub fn new(source: Grid3<f32>, target: Grid3<f32>) -> Result<Self, MorphError> {
        source.check_same_lattice(&target)?;
        for (name, g) in [("source", &source), ("target", &target)] {
            if let Some(i) = g.data().iter().position(|v| !v.is_finite()) {
                return Err(MorphError::NonFinite(name, i));
            }
            if !g.data().iter().any(|&v| v > 0.0) {
                return Err(MorphError::EmptyShape(name));
            }
        }
        Ok(Self { source, target })
    }

    /// Samples two fields (signed distances, positive inside) over `bounds`
    /// with `res` nodes along its longest edge and blends them.
    ///
    /// # Errors
    /// As [`DistanceBlend::new`] and [`Grid3::sample_box`].
    pub fn from_fields<A: Field3 + ?Sized, B: Field3 + ?Sized>(
        source: &A,
        target: &B,
        bounds: &Aabb,
        res: u32,
    ) -> Result<Self, MorphError> {
        let a = Grid3::sample_box(source, bounds, res)?;
        let b = Grid3::sample_box(target, bounds, res)?;
        Self::new(a, b)
    }

    /// The source distance grid.
    pub fn source(&self) -> &Grid3<f32> {
        &self.source
    }

    /// The target distance grid.
    pub fn target(&self) -> &Grid3<f32> {
        &self.target
    }

    /// The blended grid at `t` (not checked; see [`Morph::frame`]).
    fn blend(&self, t: f32) -> Result<Grid3<f32>, MorphError> {
        let mut out = self.source.with_same_lattice(0.0f32)?;
        out.data_mut()
            .par_iter_mut()
            .zip(self.source.data().par_iter().zip(self.target.data().par_iter()))
            .for_each(|(o, (&a, &b))| *o = (1.0 - t) * a + t * b);
        Ok(out)
    }
}

impl Morph for DistanceBlend {
    type Field = Grid3<f32>;
    type Error = MorphError;

    fn method(&self) -> &str {
        "baseline"
    }

    fn frame(&self, t: f32) -> Result<Frame<Grid3<f32>>, MorphError> {
        let t = check_time(t)?;
        Ok(Frame { field: self.blend(t)?, iso: 0.0, transform: Affine3A::IDENTITY })
    }

    fn bounds(&self) -> Aabb {
        self.source.bounds()
    }

    /// Marching cubes directly on the blended grid (its own lattice; `res` is
    /// ignored because resampling could only lose detail).
    fn frame_mesh(&self, t: f32, _res: u32) -> Result<TriMesh, MorphError> {
        let frame = self.frame(t)?;
        Ok(marching_cubes(&frame.field, frame.iso))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Shape;
    use glam::{UVec3, Vec3};

    fn blend() -> DistanceBlend {
        let a = Shape::sphere(0.3).translated(Vec3::new(-0.15, 0.0, 0.0));
        let b = Shape::sphere(0.2).translated(Vec3::new(0.2, 0.0, 0.0));
        DistanceBlend::from_fields(&a, &b, &Aabb::cube(0.5), 17).unwrap()
    }

    #[test]
    fn endpoints_are_the_inputs() {
        let m = blend();
        assert_eq!(m.frame(0.0).unwrap().field.data(), m.source().data());
        assert_eq!(m.frame(1.0).unwrap().field.data(), m.target().data());
        let mid = m.frame(0.5).unwrap().field;
        let i = 100;
        assert!((mid.data()[i] - 0.5 * (m.source().data()[i] + m.target().data()[i])).abs() < 1e-6);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let m = blend();
        assert!(matches!(m.frame(1.5), Err(MorphError::InvalidTime(_))));
        assert!(matches!(m.frame(f32::NAN), Err(MorphError::InvalidTime(_))));
        let g = m.source().clone();
        let other = Grid3::new(UVec3::splat(9), Vec3::ZERO, 0.1, 1.0f32).unwrap();
        assert!(matches!(DistanceBlend::new(g.clone(), other), Err(MorphError::Grid(_))));
        let mut nan = g.clone();
        nan.data_mut()[5] = f32::NAN;
        assert!(matches!(DistanceBlend::new(g.clone(), nan), Err(MorphError::NonFinite("target", 5))));
        let empty = g.map(|_| -1.0f32).unwrap();
        assert!(matches!(DistanceBlend::new(empty, g), Err(MorphError::EmptyShape("source"))));
    }
}
