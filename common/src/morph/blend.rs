//! The naive baseline: linear interpolation of two signed distance volumes
//! ([`DistanceBlend`]), the comparison every method should beat (Breen &
//! Whitaker Fig. 6, Turk & O'Brien Fig. 3 top row).

use super::{Frame, Morph, MorphError, MorphReport, Outcome, Side, Stages, check, check_time};
use crate::control::Control;
use crate::marching_cubes::marching_cubes;
use crate::{Aabb, Grid3, Solid, TriMesh};
use glam::Affine3A;
use rayon::prelude::*;

/// Settings of [`DistanceBlend::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendSettings {
    /// Grid nodes along the longest edge of the box (8–2048; default 64).
    pub resolution: u32,
    /// Empty margin around both inputs' boxes, as a fraction of the union
    /// box's size per side (0–2; default 0.1).
    pub padding: f32,
}

impl Default for BlendSettings {
    fn default() -> Self {
        Self { resolution: 64, padding: 0.1 }
    }
}

impl BlendSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] naming the field.
    pub fn validate(&self) -> Result<(), MorphError> {
        check::count("resolution", u64::from(self.resolution), 8, 2048)?;
        check::range("padding", f64::from(self.padding), 0.0, 2.0)
    }
}

/// The naive baseline: `d(t) = (1 − t) d_A + t d_B` for two signed distance
/// volumes on one lattice. Cheap, but pieces of the target "pop out of thin
/// air" wherever the shapes do not overlap (Breen & Whitaker Fig. 6).
#[derive(Debug, Clone)]
pub struct DistanceBlend {
    source: Grid3<f32>,
    target: Grid3<f32>,
    report: MorphReport,
}

impl DistanceBlend {
    /// Samples the true signed distances of both solids over their union
    /// box (padded) and blends them.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`], the solids' conversion errors, and as
    /// [`DistanceBlend::from_grids`].
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &BlendSettings,
        control: &Control,
    ) -> Result<Self, MorphError> {
        settings.validate()?;
        let warnings = crate::validate_inputs(source, target, control)?;
        let mut stages = Stages::start();
        let bounds = source.bounds().union(&target.bounds()).padded(settings.padding);
        control.progress("distance volumes", Some(0.0), String::new);
        let a = source.distance_volume(&bounds, settings.resolution, control)?;
        control.progress("distance volumes", Some(0.5), String::new);
        let b = target.distance_volume(&bounds, settings.resolution, control)?;
        stages.lap("distance volumes");
        let mut blend = Self::from_grids(a, b)?;
        blend.report.stages.clear();
        blend.report = blend.report.with_stages(stages).with_warnings(warnings);
        Ok(blend)
    }

    /// The blend of two signed distance grids (positive inside) on one lattice.
    ///
    /// # Errors
    /// [`MorphError::Grid`] when the lattices differ, [`MorphError::NonFinite`]
    /// for NaN or infinite values, [`MorphError::EmptyShape`] when a grid has
    /// no positive node.
    pub fn from_grids(source: Grid3<f32>, target: Grid3<f32>) -> Result<Self, MorphError> {
        source.check_same_lattice(&target)?;
        for (side, g) in [(Side::Source, &source), (Side::Target, &target)] {
            if g.data().iter().any(|v| !v.is_finite()) {
                return Err(MorphError::NonFinite { side, what: "distance volume" });
            }
            if !g.data().iter().any(|&v| v > 0.0) {
                return Err(MorphError::EmptyShape { side, detail: "no grid node is inside it".into() });
            }
        }
        let bytes = 2 * source.len() * size_of::<f32>();
        let report = MorphReport::new("baseline", Outcome::Direct)
            .with_memory(bytes, Some(bytes + source.len() * size_of::<f32>()))
            .with_detail("nodes", source.len());
        Ok(Self { source, target, report })
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

    fn method(&self) -> &'static str {
        "baseline"
    }

    fn frame(&self, t: f32) -> Result<Frame<Grid3<f32>>, MorphError> {
        let t = check_time(t)?;
        Ok(Frame { field: self.blend(t)?, iso: 0.0, transform: Affine3A::IDENTITY })
    }

    fn field_bounds(&self) -> Aabb {
        self.source.bounds()
    }

    fn world_bounds(&self) -> Aabb {
        self.source.bounds()
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }

    /// Marching cubes directly on the blended grid (its own lattice, chosen
    /// by [`BlendSettings::resolution`]; `res` is ignored because resampling
    /// could only lose detail).
    fn frame_mesh(&self, t: f32, _res: u32) -> Result<TriMesh, MorphError> {
        let frame = self.frame(t)?;
        Ok(marching_cubes(&frame.field, frame.iso))
    }

    /// The identity: the blend is not placed.
    fn world_transform(&self, t: f32) -> Result<Affine3A, MorphError> {
        check_time(t)?;
        Ok(Affine3A::IDENTITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Shape;
    use glam::{UVec3, Vec3};

    fn blend() -> DistanceBlend {
        let a = Solid::shape(Shape::sphere(0.3).translated(Vec3::new(-0.15, 0.0, 0.0)));
        let b = Solid::shape(Shape::sphere(0.2).translated(Vec3::new(0.2, 0.0, 0.0)));
        DistanceBlend::new(&a, &b, &BlendSettings { resolution: 17, padding: 0.1 }, &Control::new()).unwrap()
    }

    #[test]
    fn endpoints_are_the_inputs() {
        let m = blend();
        assert_eq!(m.frame(0.0).unwrap().field.data(), m.source().data());
        assert_eq!(m.frame(1.0).unwrap().field.data(), m.target().data());
        let mid = m.frame(0.5).unwrap().field;
        let i = 100;
        assert!((mid.data()[i] - 0.5 * (m.source().data()[i] + m.target().data()[i])).abs() < 1e-6);
        assert_eq!(m.report().stages.len(), 1);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let m = blend();
        assert!(matches!(m.frame(1.5), Err(MorphError::InvalidTime(_))));
        assert!(matches!(m.frame(f32::NAN), Err(MorphError::InvalidTime(_))));
        let g = m.source().clone();
        let other = Grid3::new(UVec3::splat(9), Vec3::ZERO, 0.1, 1.0f32).unwrap();
        assert!(matches!(DistanceBlend::from_grids(g.clone(), other), Err(MorphError::Grid(_))));
        let mut nan = g.clone();
        nan.data_mut()[5] = f32::NAN;
        assert!(matches!(
            DistanceBlend::from_grids(g.clone(), nan),
            Err(MorphError::NonFinite { side: Side::Target, .. })
        ));
        let empty = g.map(|_| -1.0f32).unwrap();
        assert!(matches!(
            DistanceBlend::from_grids(empty, g),
            Err(MorphError::EmptyShape { side: Side::Source, .. })
        ));
        let bad = BlendSettings { resolution: 3, ..Default::default() };
        let s = Solid::shape(Shape::sphere(0.3));
        let e = DistanceBlend::new(&s, &s, &bad, &Control::new()).unwrap_err();
        assert!(e.to_string().contains("resolution = 3"), "{e}");
    }
}
