//! The warp as a plain map of world space (for other methods, e.g. as
//! Breen & Whitaker's generalized warp `T`) and as a [`Morph`] that animates
//! the control points of one volume from the identity to the user's
//! configuration ([`WarpAnimation`]; the two-solid morph is
//! [`crate::WarpAnimation`]).

use crate::pushforward::Density;
use crate::{BSplineMap, VolumeWarp, WarpError, WarpSettings};
use glam::{Affine3A, Vec3};
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::{Aabb, Frame, Grid3, Morph, MorphReport, Outcome, TriMesh, check_time};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// A [`BSplineMap`] placed in world space by a source grid's origin and
/// spacing: `apply(p) = origin + spacing · B((p − origin)/spacing)`.
/// Borrowed from a [`VolumeWarp`] ([`VolumeWarp::world_map`]) or owned
/// (`WorldMap<'static>`, e.g. [`WorldMap::from_landmarks`], to be moved into
/// a closure).
#[derive(Debug, Clone)]
pub struct WorldMap<'a> {
    map: Cow<'a, BSplineMap>,
    origin: Vec3,
    spacing: f32,
}

impl<'a> WorldMap<'a> {
    /// `map` placed like a grid with node 0 at `origin` and node `spacing`.
    pub fn new(map: &'a BSplineMap, origin: Vec3, spacing: f32) -> Self {
        Self { map: Cow::Borrowed(map), origin, spacing }
    }

    /// Like [`WorldMap::new`], owning `map`.
    pub fn owned(map: BSplineMap, origin: Vec3, spacing: f32) -> WorldMap<'static> {
        WorldMap { map: Cow::Owned(map), origin, spacing }
    }

    /// The underlying map (source voxel coordinates).
    pub fn map(&self) -> &BSplineMap {
        &self.map
    }

    /// The image of world point `p`.
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.origin + self.spacing * self.map.eval((p - self.origin) / self.spacing)
    }

    /// The approximate inverse: the world point mapped to `q` (Newton, to
    /// 1e-4 voxels), or `None` where the map folds or `q` is not in its image.
    pub fn inverse(&self, q: Vec3) -> Option<Vec3> {
        self.map.inverse((q - self.origin) / self.spacing, 1e-4, 30).map(|x| self.origin + self.spacing * x)
    }

    /// The map as a JSON file ([`WorldMap::from_json`] reads it back):
    /// `kind` `"bspline-map"`, the lattice placement `origin` and `spacing`
    /// (world units), `source_dims` and `controls` (per axis) and every
    /// control point's `displacements` (voxel units, x fastest).
    pub fn to_json(&self) -> String {
        let file = MapFile {
            kind: MAP_KIND.into(),
            origin: self.origin.to_array(),
            spacing: self.spacing,
            source_dims: self.map.source_dims().to_array(),
            controls: self.map.controls().to_array(),
            displacements: self.map.displacements().iter().map(|d| d.to_array()).collect(),
        };
        serde_json::to_string(&file).expect("finite numbers always serialize")
    }

    /// The map as a closure `Fn(Vec3) -> Vec3`.
    pub fn as_fn(&self) -> impl Fn(Vec3) -> Vec3 + '_ {
        move |p| self.apply(p)
    }
}

/// The `kind` of a map file.
const MAP_KIND: &str = "bspline-map";

/// A map file as [`WorldMap::to_json`] writes it.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    kind: String,
    origin: [f32; 3],
    spacing: f32,
    source_dims: [u32; 3],
    controls: [u32; 3],
    displacements: Vec<[f32; 3]>,
}

impl WorldMap<'static> {
    /// Reads a map written by [`WorldMap::to_json`] (`isomorph warp` writes
    /// one as `map.json`).
    ///
    /// # Errors
    /// [`WarpError::MapFile`] for other JSON, a wrong count of
    /// displacements or a placement that is not finite and positive; the
    /// lattice's errors ([`BSplineMap::with_controls`]); non-finite
    /// displacements.
    pub fn from_json(text: &str) -> Result<Self, WarpError> {
        let file: MapFile = serde_json::from_str(text).map_err(|e| WarpError::MapFile(e.to_string()))?;
        if file.kind != MAP_KIND {
            return Err(WarpError::MapFile(format!("kind {:?}, expected {MAP_KIND:?}", file.kind)));
        }
        let origin = Vec3::from_array(file.origin);
        if !(origin.is_finite() && file.spacing.is_finite() && file.spacing > 0.0) {
            return Err(WarpError::MapFile("origin and spacing must be finite, spacing > 0".into()));
        }
        let mut map = BSplineMap::with_controls(file.source_dims.into(), file.controls.into())?;
        if file.displacements.len() != map.displacements().len() {
            return Err(WarpError::MapFile(format!(
                "{} displacements for {} control points",
                file.displacements.len(),
                map.displacements().len()
            )));
        }
        for (c, d) in map.control_indices().zip(&file.displacements) {
            map.set_displacement(c, Vec3::from_array(*d))?;
        }
        Ok(WorldMap::owned(map, origin, file.spacing))
    }

    /// Reads a map file ([`WorldMap::from_json`]).
    ///
    /// # Errors
    /// [`WarpError::MapFile`] for an unreadable file, then
    /// [`WorldMap::from_json`]'s.
    pub fn load(path: &std::path::Path) -> Result<Self, WarpError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| WarpError::MapFile(format!("cannot read {}: {e}", path.display())))?;
        Self::from_json(&text)
    }
}

impl<T: Density> VolumeWarp<T> {
    /// The current map in the world coordinates of the source grid.
    pub fn world_map(&self) -> WorldMap<'_> {
        WorldMap::new(self.map(), self.source().origin(), self.source().spacing())
    }
}

/// A morph from a volume to its warp: frame `t` pushes the source forward
/// through the map whose control displacements are `t` times the final
/// ones (linear in t, so every frame is a B-spline warp and frame 0 is the
/// source exactly).
#[derive(Debug, Clone)]
pub struct WarpAnimation<T> {
    source: Grid3<T>,
    map: BSplineMap,
    settings: WarpSettings,
    iso: f32,
    report: MorphReport,
}

impl<T: Density> WarpAnimation<T> {
    /// The morph of `source` to its warp by `map`; `iso` is the surface level
    /// of the volume's values (127.5 for thesis-style u8 densities).
    ///
    /// # Errors
    /// [`WarpError::Mismatch`] when `map` was built for another size.
    pub fn new(
        source: Grid3<T>,
        map: BSplineMap,
        settings: WarpSettings,
        iso: f32,
    ) -> Result<Self, WarpError> {
        if map.source_dims() != source.dims() {
            return Err(WarpError::Mismatch(format!(
                "map built for {} voxels, source has {}",
                map.source_dims(),
                source.dims()
            )));
        }
        let bytes = source.len() * size_of::<T>() + size_of_val(map.displacements());
        let report = MorphReport::new("warp-animation", Outcome::Direct).with_memory(bytes, None);
        Ok(Self { source, map, settings, iso, report })
    }

    /// The warped volume at time `t` (values as `f32`).
    fn warped(&self, t: f32) -> Result<Grid3<f32>, WarpError> {
        let t = check_time(t)?;
        let map = self.map.scaled(t)?;
        let warp = VolumeWarp::with_map(self.source.clone(), map, self.settings)?;
        Ok(warp.target().map(|v| v.to_f32())?)
    }
}

impl<T: Density> Morph for WarpAnimation<T> {
    type Field = Grid3<f32>;
    type Error = WarpError;

    fn method(&self) -> &'static str {
        "warp-animation"
    }

    fn frame(&self, t: f32) -> Result<Frame<Grid3<f32>>, WarpError> {
        Ok(Frame { field: self.warped(t)?, iso: self.iso, transform: Affine3A::IDENTITY })
    }

    /// The padded target box (every frame lives on it).
    fn field_bounds(&self) -> Aabb {
        let pad = Vec3::splat(self.settings.pad as f32 * self.source.spacing());
        let b = self.source.bounds();
        Aabb::new(b.min - pad, b.max + pad)
    }

    fn world_bounds(&self) -> Aabb {
        self.field_bounds()
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }

    /// Marching cubes directly on the warped grid (`res` is ignored).
    fn frame_mesh(&self, t: f32, _res: u32) -> Result<TriMesh, WarpError> {
        let frame = self.frame(t)?;
        Ok(marching_cubes(&frame.field, frame.iso))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Filter;
    use glam::UVec3;

    #[test]
    fn map_files_round_trip_and_bad_ones_are_errors() {
        let mut map = BSplineMap::identity(UVec3::new(16, 12, 10), 7).unwrap();
        map.set_displacement(UVec3::new(3, 2, 4), Vec3::new(1.5, -0.5, 0.25)).unwrap();
        let w = WorldMap::new(&map, Vec3::new(-1.0, 0.5, 2.0), 0.1);
        let back = WorldMap::from_json(&w.to_json()).unwrap();
        assert_eq!(back.map(), &map);
        let p = Vec3::new(-0.4, 1.0, 2.5);
        assert_eq!(back.apply(p), w.apply(p));
        let text = w.to_json();
        for (bad, why) in [
            (text.replace("bspline-map", "mesh"), "kind"),
            (text.replace("\"spacing\":0.1", "\"spacing\":-0.1"), "spacing"),
            (text.replace("\"controls\":[7,7,7]", "\"controls\":[7,7,8]"), "displacements for"),
            ("{}".to_string(), "missing field"),
        ] {
            let e = WorldMap::from_json(&bad).unwrap_err().to_string();
            assert!(e.contains(why), "{why}: {e}");
        }
    }

    #[test]
    fn world_map_and_inverse_round_trip() {
        let mut map = BSplineMap::identity(UVec3::splat(16), 7).unwrap();
        map.set_displacement(UVec3::new(3, 3, 3), Vec3::new(1.5, -0.5, 0.5)).unwrap();
        let (origin, spacing) = (Vec3::new(-1.0, 0.5, 2.0), 0.1);
        let w = WorldMap::new(&map, origin, spacing);
        let p = origin + spacing * Vec3::new(6.0, 7.0, 5.5);
        let q = w.as_fn()(p);
        assert!((q - (origin + spacing * map.eval(Vec3::new(6.0, 7.0, 5.5)))).length() < 1e-5);
        assert!(q.distance(p) > 0.01, "the point moves");
        let back = w.inverse(q).unwrap();
        assert!(back.distance(p) < 1e-4, "{back} vs {p}");
    }

    #[test]
    fn morph_starts_at_the_source_and_ends_at_the_warp() {
        let dims = UVec3::splat(16);
        let mut src = Grid3::new(dims, Vec3::ZERO, 0.5, 0u8).unwrap();
        for n in 0..src.len() {
            let d = 4.0 - (src.node_of(n).as_vec3() - Vec3::splat(7.5)).length();
            src.data_mut()[n] = (127.5 + 64.0 * d).clamp(0.0, 255.0) as u8;
        }
        let mut map = BSplineMap::identity(dims, 6).unwrap();
        map.set_displacement(UVec3::new(2, 2, 2), Vec3::new(3.0, 0.0, 0.0)).unwrap();
        let settings = WarpSettings { csize: 6, pad: 3, filter: Filter::Box, ..Default::default() };
        let morph = WarpAnimation::new(src.clone(), map.clone(), settings, 127.5).unwrap();
        let f0 = morph.frame(0.0).unwrap();
        let f1 = morph.frame(1.0).unwrap();
        let end = VolumeWarp::with_map(src.clone(), map, settings).unwrap();
        assert_eq!(*f0.field.get(3 + 7, 3 + 7, 3 + 7).unwrap(), f32::from(*src.get(7, 7, 7).unwrap()));
        assert!(f1.field.data().iter().zip(end.target().data()).all(|(a, b)| *a == f32::from(*b)));
        assert!(morph.frame_mesh(0.5, 0).unwrap().metrics().triangles > 0);
        assert!(matches!(
            morph.frame(1.5),
            Err(WarpError::Morph(isomorph_common::MorphError::InvalidTime(_)))
        ));
        assert!(morph.field_bounds().contains(f1.field.bounds().center()));
    }
}
