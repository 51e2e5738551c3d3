//! The morph contract for the volume warp: [`WarpMorph`] morphs one solid
//! into another by warping both densities towards each other with
//! trivariate B-spline maps (True's warp, thesis §5) and cross-dissolving
//! them — the classic "warp and dissolve" volume morph.

use crate::{BSplineMap, Filter, Handle, VolumeWarp, WarpError, WarpSettings, WorldMap, solve_drag};
use glam::{Affine3A, UVec3, Vec3};
use isomorph_common::alignment::{AlignMode, Alignment, align};
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::{
    Aabb, Control, Frame, Grid3, Landmarks, Morph, MorphError, MorphReport, Outcome, Solid, Stages,
    lattice_for_box,
};
use isomorph_common::{check, check_time};
use rayon::prelude::*;

/// Which points of the source go to which points of the target.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum WarpSpec {
    /// No warp: a plain cross-dissolve of the two densities.
    Identity,
    /// The moment alignment of the two solids (rotation, translation and a
    /// scale per principal axis; Breen & Whitaker's appendix): the source
    /// turns, moves and stretches onto the target while the two dissolve.
    #[default]
    Align,
    /// Landmark pairs `(point on the source, point on the target)` in world
    /// units: the B-spline maps that carry each landmark onto its partner
    /// with the least control-point motion (True §6 direct manipulation).
    Landmarks(Vec<(Vec3, Vec3)>),
}

impl WarpSpec {
    /// `"identity"`, `"align"` or `"landmarks"`.
    pub fn name(&self) -> &'static str {
        match self {
            WarpSpec::Identity => "identity",
            WarpSpec::Align => "align",
            WarpSpec::Landmarks(_) => "landmarks",
        }
    }
}

/// Settings of [`WarpMorph::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct WarpMorphSettings {
    /// Grid nodes along the longest edge of the common lattice (8–1024;
    /// default 64).
    pub resolution: u32,
    /// Empty margin around the box the shapes sweep during the morph, as a
    /// fraction of its longest edge per side (0–2; default 0.1): warped
    /// shapes need room.
    pub padding: f32,
    /// Voxels per B-spline region along each axis (the thesis' `G`; 2–256;
    /// default 8): smaller follows landmarks more locally.
    pub control_spacing: u32,
    /// The correspondence (default [`WarpSpec::Align`]).
    pub spec: WarpSpec,
    /// How densities are pushed through the maps (default
    /// [`Filter::Backward`]: exact for the affine alignment; the thesis'
    /// box filter over-covers rotated voxels and its thresholded densities
    /// break into pieces under large rotations).
    pub filter: Filter,
}

impl Default for WarpMorphSettings {
    fn default() -> Self {
        Self {
            resolution: 64,
            padding: 0.1,
            control_spacing: 8,
            spec: WarpSpec::Align,
            filter: Filter::Backward,
        }
    }
}

impl WarpMorphSettings {
    /// Checks the ranges and the landmarks.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] naming the field, its value and the range.
    pub fn validate(&self) -> Result<(), MorphError> {
        check::count("resolution", u64::from(self.resolution), 8, 1024)?;
        check::range("padding", f64::from(self.padding), 0.0, 2.0)?;
        check::count("control_spacing", u64::from(self.control_spacing), 2, 256)?;
        if let WarpSpec::Landmarks(pairs) = &self.spec {
            if pairs.is_empty() {
                return Err(MorphError::bad_setting("spec", "no landmarks", "at least one landmark pair"));
            }
            if let Some((a, b)) = pairs.iter().find(|(a, b)| !(a.is_finite() && b.is_finite())) {
                return Err(MorphError::bad_setting("spec", format!("landmark {a} → {b}"), "finite points"));
            }
        }
        Ok(())
    }
}

/// Half-width of the density ramp around the surface, in voxels: density
/// `0.5 + d / (2 w h)` clamped to `[0, 1]` for a signed distance `d` and
/// spacing `h`. Adjacent nodes of a true distance differ by at most `h`, so
/// every edge the surface crosses lies inside the ramp and marching cubes of
/// the density at 0.5 gives the distance's zero set.
const RAMP_VOXELS: f32 = 1.5;

/// The maps of both sides, in the voxel coordinates of the common lattice.
#[derive(Debug, Clone)]
enum Correspondence {
    /// No warp.
    Identity,
    /// The moment alignment (world units) and its inverse.
    Affine { alignment: Box<Alignment>, inverse: Affine3A },
    /// The full source-to-target and target-to-source maps, scaled per frame.
    Landmarks { forward: BSplineMap, backward: BSplineMap },
}

/// The warp-and-dissolve morph of two solids: both densities are warped
/// towards each other with trivariate B-spline maps (True's warp, thesis
/// §5) and cross-dissolved.
///
/// Frame `t`: the source density is pushed forward through the source map at
/// `t`, the target density through the target map at `t`, and the frame is
/// `(1 − t) · source_t + t · target_t` with its surface at density 0.5. The
/// correspondence ([`WarpSpec`]) decides the maps: none (a plain
/// cross-dissolve), the moment alignment (an affine map, which cubic
/// B-splines reproduce exactly), or landmark pairs solved by direct
/// manipulation (thesis §6).
///
/// Frames are `f32` densities on one lattice, positive inside, in world
/// space.
///
/// ```
/// use isomorph_common::{Control, Morph, Shape, Solid};
/// use isomorph_warp::{WarpMorph, WarpMorphSettings};
///
/// let sphere = Solid::shape(Shape::sphere(0.3));
/// let torus = Solid::shape(Shape::torus(0.3, 0.12));
/// let settings = WarpMorphSettings { resolution: 40, ..Default::default() };
/// let morph = WarpMorph::new(&sphere, &torus, &settings, &Control::new())?;
/// assert_eq!(morph.frame_mesh(1.0, 0)?.genus(), Some(1));
/// # Ok::<(), isomorph_warp::WarpError>(())
/// ```
#[derive(Debug, Clone)]
pub struct WarpMorph {
    source: Grid3<f32>,
    target: Grid3<f32>,
    correspondence: Correspondence,
    controls: UVec3,
    warp: WarpSettings,
    report: MorphReport,
}

impl WarpMorph {
    /// Samples both solids' true signed distances on one lattice over the
    /// box they sweep during the morph, turns them into densities, and sets
    /// up the maps of `settings.spec`.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`], [`MorphError::Cancelled`], the solids'
    /// conversion and alignment errors, and [`WarpError`]s of the maps
    /// (e.g. a landmark outside the lattice, [`WarpError::Unreachable`]).
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &WarpMorphSettings,
        control: &Control,
    ) -> Result<Self, WarpError> {
        settings.validate()?;
        let warnings = isomorph_common::validate_inputs(source, target, control)?;
        control.install(|| {
            let mut stages = Stages::start();
            let res = settings.resolution;
            let alignment = match settings.spec {
                WarpSpec::Align => {
                    control.progress("alignment", None, String::new);
                    let (m, n) = (source.moments(res, control)?, target.moments(res, control)?);
                    let alignment = align(&m, &n, AlignMode::Affine).map_err(MorphError::from)?;
                    stages.lap("alignment");
                    Some(alignment)
                }
                _ => None,
            };
            let bounds = swept_bounds(source.bounds(), target.bounds(), &settings.spec, alignment.as_ref());
            let bounds = bounds.expanded(settings.padding * bounds.size().max_element());
            control.progress("distance volumes", Some(0.0), String::new);
            let a = density(source.distance_volume(&bounds, res, control)?)?;
            control.progress("distance volumes", Some(0.5), String::new);
            let b = density(target.distance_volume(&bounds, res, control)?)?;
            stages.lap("distance volumes");
            control.check()?;
            let controls = control_grid(a.dims(), settings.control_spacing);
            let identity = BSplineMap::with_controls(a.dims(), controls)?;
            let correspondence = match (&settings.spec, alignment) {
                (WarpSpec::Landmarks(pairs), _) => {
                    control.progress("landmarks", None, || format!("{} pairs", pairs.len()));
                    let swapped: Vec<_> = pairs.iter().map(|&(p, q)| (q, p)).collect();
                    let forward = landmark_map(&identity, a.origin(), a.spacing(), pairs)?;
                    let backward = landmark_map(&identity, a.origin(), a.spacing(), &swapped)?;
                    stages.lap("landmarks");
                    Correspondence::Landmarks { forward, backward }
                }
                (_, Some(alignment)) => {
                    let inverse = alignment.map.inverse();
                    Correspondence::Affine { alignment: Box::new(alignment), inverse }
                }
                (_, None) => Correspondence::Identity,
            };
            let warp = WarpSettings { csize: 4, pad: 0, filter: settings.filter, ..Default::default() };
            let mut morph = Self { source: a, target: b, correspondence, controls, warp, report: MorphReport::new("warp", Outcome::Direct) };
            control.progress("maps", None, String::new);
            let folded = morph.warped(&morph.source, morph.source_map(1.0)?)?.deformation().folded_cells();
            stages.lap("maps");
            let bytes = 2 * morph.source.len() * size_of::<f32>();
            let mut report = MorphReport::new("warp", Outcome::Direct)
                .with_stages(stages)
                .with_memory(bytes, Some(3 * bytes))
                .with_detail("spec", settings.spec.name())
                .with_detail("control points", (controls.x * controls.y * controls.z) as usize)
                .with_detail("folded cells", folded)
                .with_warnings(warnings);
            if folded > 0 {
                report = report.with_warnings([format!(
                    "the source map folds over itself in {folded} voxel cells: the warped shape overlaps itself there"
                )]);
            }
            morph.report = report;
            Ok(morph)
        })
    }

    /// The source density (`[0, 1]`, surface at 0.5) on the common lattice.
    pub fn source(&self) -> &Grid3<f32> {
        &self.source
    }

    /// The target density on the common lattice.
    pub fn target(&self) -> &Grid3<f32> {
        &self.target
    }

    /// The B-spline map that carries the source at time `t` (voxel
    /// coordinates of the common lattice).
    ///
    /// # Errors
    /// [`WarpError::NonFinite`] when a degenerate alignment gives a
    /// non-finite control point.
    pub fn source_map(&self, t: f32) -> Result<BSplineMap, WarpError> {
        match &self.correspondence {
            Correspondence::Identity => self.identity(),
            Correspondence::Affine { alignment, .. } => self.affine_map(alignment.at(t)),
            Correspondence::Landmarks { forward, .. } => forward.scaled(t),
        }
    }

    /// The B-spline map that carries the target at time `t` (the identity
    /// at `t = 1`).
    ///
    /// # Errors
    /// As [`WarpMorph::source_map`].
    pub fn target_map(&self, t: f32) -> Result<BSplineMap, WarpError> {
        match &self.correspondence {
            Correspondence::Identity => self.identity(),
            Correspondence::Affine { alignment, inverse } => self.affine_map(alignment.at(t) * *inverse),
            Correspondence::Landmarks { backward, .. } => backward.scaled(1.0 - t),
        }
    }

    fn identity(&self) -> Result<BSplineMap, WarpError> {
        BSplineMap::with_controls(self.source.dims(), self.controls)
    }

    /// The world map `world` as a B-spline map in lattice voxel coordinates
    /// (exact: cubic B-splines reproduce affine maps).
    fn affine_map(&self, world: Affine3A) -> Result<BSplineMap, WarpError> {
        let mut map = self.identity()?;
        let (o, h) = (self.source.origin(), self.source.spacing());
        for idx in map.control_indices() {
            let rest = map.rest_position(idx);
            let image = (world.transform_point3(o + h * rest) - o) / h;
            map.set_displacement(idx, image - rest)?;
        }
        Ok(map)
    }

    /// `density` pushed forward through `map` with the settings' filter.
    fn warped(&self, density: &Grid3<f32>, map: BSplineMap) -> Result<VolumeWarp<f32>, WarpError> {
        VolumeWarp::with_map(density.clone(), map, self.warp)
    }

    /// The dissolved density at `t` (not checked).
    fn blend(&self, t: f32) -> Result<Grid3<f32>, WarpError> {
        // The maps are the identity at the ends (exactly in the limit; the
        // inputs themselves are returned so the ends are exact).
        if t == 0.0 {
            return Ok(self.source.clone());
        }
        if t == 1.0 {
            return Ok(self.target.clone());
        }
        let mut out = self.warped(&self.source, self.source_map(t)?)?.into_target();
        let b = self.warped(&self.target, self.target_map(t)?)?.into_target();
        out.data_mut()
            .par_iter_mut()
            .zip(b.data().par_iter())
            .for_each(|(x, &y)| *x = (1.0 - t) * *x + t * y);
        Ok(out)
    }
}

/// Density `0.5 + d / (2 · RAMP_VOXELS · h)` clamped to `[0, 1]`.
fn density(distance: Grid3<f32>) -> Result<Grid3<f32>, MorphError> {
    let scale = 0.5 / (RAMP_VOXELS * distance.spacing());
    Ok(distance.map(|d| (0.5 + d * scale).clamp(0.0, 1.0))?)
}

/// A box containing both solids along the whole morph: for the alignment,
/// the source's box carried by the interpolated map and the target's by
/// its inverse, sampled at nine times; for landmarks, the landmarks too.
fn swept_bounds(source: Aabb, target: Aabb, spec: &WarpSpec, alignment: Option<&Alignment>) -> Aabb {
    let mut bounds = source.union(&target);
    if let Some(alignment) = alignment {
        let inverse = alignment.map.inverse();
        for k in 0..=8 {
            let at = alignment.at(k as f32 / 8.0);
            bounds = bounds.union(&source.transformed(&at)).union(&target.transformed(&(at * inverse)));
        }
    }
    if let WarpSpec::Landmarks(pairs) = spec {
        for &(p, q) in pairs {
            bounds = bounds.including(p).including(q);
        }
    }
    bounds
}

/// Control points per axis for a lattice of `dims` nodes with a B-spline
/// region every `spacing` voxels (a cubic spline's three extra controls).
fn control_grid(dims: UVec3, spacing: u32) -> UVec3 {
    (dims.as_vec3() / spacing as f32).ceil().as_uvec3().max(UVec3::ONE) + UVec3::splat(3)
}

/// The least-motion map carrying each world landmark `p` to its partner `q`
/// (thesis §6), in the voxel coordinates of the lattice with node 0 at `o`
/// and spacing `h`.
fn landmark_map(
    identity: &BSplineMap,
    o: Vec3,
    h: f32,
    pairs: &[(Vec3, Vec3)],
) -> Result<BSplineMap, WarpError> {
    let handles: Vec<Handle> =
        pairs.iter().map(|&(p, q)| Handle { point: (p - o) / h, goal: (q - o) / h }).collect();
    let drag = solve_drag(identity, &handles, None)?;
    let mut map = identity.clone();
    for (c, position) in drag.moves {
        map.set_control_point(c, position)?;
    }
    Ok(map)
}

impl WorldMap<'static> {
    /// True's B-spline warp through landmark pairs (`W(pᵢ) = qᵢ`), fitted by
    /// the minimum-norm direct manipulation of [`solve_drag`] from the
    /// identity, on a lattice of `resolution` nodes along the longest edge
    /// of `bounds` with a control point every `control_spacing` voxels: the
    /// alternative to the RBF displacement warp for Breen & Whitaker's
    /// generalized warp (§6.2). Outside `bounds` the map is the identity
    /// plus the nearest control displacements' fading tail.
    ///
    /// # Errors
    /// [`WarpError`] for a bad lattice or control spacing, and
    /// [`solve_drag`]'s.
    pub fn from_landmarks(
        bounds: &Aabb,
        resolution: u32,
        control_spacing: u32,
        landmarks: &Landmarks,
    ) -> Result<Self, WarpError> {
        check::count("control_spacing", u64::from(control_spacing), 2, 256)?;
        let bounds = landmarks.pairs().iter().fold(*bounds, |b, &(p, q)| b.including(p).including(q));
        let (dims, origin, spacing) = lattice_for_box(&bounds, resolution)?;
        let identity = BSplineMap::with_controls(dims, control_grid(dims, control_spacing))?;
        let map = landmark_map(&identity, origin, spacing, landmarks.pairs())?;
        Ok(WorldMap::owned(map, origin, spacing))
    }
}

/// Frames are densities on the common lattice in world space (identity
/// transform); [`Morph::frame_mesh`] runs marching cubes on that lattice.
impl Morph for WarpMorph {
    type Field = Grid3<f32>;
    type Error = WarpError;

    fn method(&self) -> &'static str {
        "warp"
    }

    fn frame(&self, t: f32) -> Result<Frame<Grid3<f32>>, WarpError> {
        let t = check_time(t)?;
        Ok(Frame { field: self.blend(t)?, iso: 0.5, transform: Affine3A::IDENTITY })
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

    /// Marching cubes directly on the frame's lattice (chosen by
    /// [`WarpMorphSettings::resolution`]; `res` is ignored because
    /// resampling could only lose detail).
    fn frame_mesh(&self, t: f32, _res: u32) -> Result<isomorph_common::TriMesh, WarpError> {
        let frame = self.frame(t)?;
        Ok(marching_cubes(&frame.field, frame.iso))
    }

    /// The identity: frames are not placed (without making the frame).
    fn world_transform(&self, t: f32) -> Result<Affine3A, WarpError> {
        check_time(t)?;
        Ok(Affine3A::IDENTITY)
    }
}
