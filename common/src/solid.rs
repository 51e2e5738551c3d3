//! Input solids: one type for "a shape to morph" ([`Solid`]), converted on
//! demand to what a method needs: a true signed distance volume, a
//! pointwise signed distance, a mesh, moments.
//!
//! | kind | signed distance | mesh |
//! |---|---|---|
//! | closed mesh ([`Solid::mesh`]) | exact (BVH, winding-number sign; [`crate::sdf`]) | the mesh itself |
//! | distance volume ([`Solid::volume`]) | the volume, resampled trilinearly when the lattice differs | marching cubes of the volume |
//! | analytic shape or CSG model ([`Solid::shape`]) | the shape's own distance where it is exact ([`Shape::is_exact_distance`]: spheres, boxes, tori, cylinders), else scan conversion (Breen & Whitaker §6.1; [`crate::scan_conversion`]), never the raw CSG field | marching cubes of the distance volume |
//! | any implicit ([`Solid::implicit`], e.g. a BlobTree) | sampled, then redistanced by fast marching ([`crate::fast_marching::redistance`]) | marching cubes |
//!
//! Everything is positive inside, in world units. A `Solid` is cheap to
//! clone (shared).
//!
//! ```
//! use isomorph_common::{Aabb, Control, Field3, Solid, models};
//!
//! // Breen's "C" is CSG of superellipsoids: its raw field is not a distance,
//! // its scan-converted volume is.
//! let c = Solid::shape(models::c_shape());
//! let volume = c.distance_volume(&Aabb::cube(0.5), 48, &Control::new())?;
//! let h = volume.spacing();
//! let d = volume.value(glam::Vec3::new(-0.3, 0.0, 0.0)); // middle of the ring's left side
//! assert!(d > 0.0 && d < 0.1 + h);
//! # Ok::<(), isomorph_common::MorphError>(())
//! ```

use crate::alignment::{AlignError, Moments};
use crate::control::Control;
use crate::fast_marching::{FastMarchingSettings, redistance};
use crate::grid::lattice_for_box;
use crate::marching_cubes::marching_cubes;
use crate::mesh::bvh::Lattice;
use crate::morph::{MorphError, Side};
use crate::scan_conversion::scan_convert;
use crate::sdf::MeshSdf;
use crate::{Aabb, Field3, Grid3, Shape, TriMesh};
use glam::{Affine3A, UVec3, Vec3};
use rayon::prelude::*;
use std::any::Any;
use std::borrow::Cow;
use std::fmt;
use std::sync::Arc;

/// An implicit shape a method may want to see as itself (e.g. a BlobTree for
/// the BlobTree morph), and any other method samples as a field. Its
/// [`Field3`] is positive inside with the surface at 0, and
/// [`Field3::bounds`] must return a box containing the surface.
pub trait Implicit: Field3 + fmt::Debug + Send + Sync + 'static {
    /// The implicit as [`Any`], so a method can recover its concrete type.
    fn as_any(&self) -> &dyn Any;
}

#[derive(Debug)]
enum Repr {
    // The distance structure boxed: it is most of the variant's size.
    Mesh { mesh: TriMesh, sdf: Box<MeshSdf> },
    Volume(Grid3<f32>),
    Shape(Shape),
    Implicit { field: Arc<dyn Implicit>, bounds: Aabb },
}

/// A shape to morph (see the [crate docs](crate)).
#[derive(Debug, Clone)]
pub struct Solid(Arc<Repr>);

/// A pointwise true signed distance of a [`Solid`] ([`Solid::distance_field`]):
/// exact for meshes, trilinear in a distance volume for the other kinds.
#[derive(Debug, Clone)]
pub enum DistanceField<'a> {
    /// The exact distance to a mesh.
    Exact(&'a MeshSdf),
    /// A distance volume, continued outside its box by the distance to the
    /// box (a lower bound of the true negative distance there).
    Volume(Cow<'a, Grid3<f32>>),
}

impl Field3 for DistanceField<'_> {
    fn value(&self, p: Vec3) -> f32 {
        match self {
            DistanceField::Exact(sdf) => sdf.value(p),
            DistanceField::Volume(grid) => extrapolated(grid, p),
        }
    }

    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        match self {
            DistanceField::Exact(sdf) => sdf.values(points, out),
            DistanceField::Volume(grid) => {
                for (o, &p) in out.iter_mut().zip(points) {
                    *o = extrapolated(grid, p);
                }
            }
        }
    }

    fn bounds(&self) -> Option<Aabb> {
        match self {
            DistanceField::Exact(sdf) => sdf.bounds(),
            DistanceField::Volume(grid) => Some(grid.bounds()),
        }
    }
}

impl DistanceField<'_> {
    /// The distance (world units, positive inside) at the image under `map`
    /// of every node of `lattice` (x fastest): the values of
    /// [`Field3::value`] there, for a mesh by [`MeshSdf::sample_mapped`]
    /// (one batch query, signs found once per region).
    pub fn sample_mapped(&self, lattice: &Lattice, map: &Affine3A) -> Vec<f32> {
        match self {
            DistanceField::Exact(sdf) => sdf.sample_mapped(lattice, map),
            DistanceField::Volume(grid) => (0..lattice.len())
                .into_par_iter()
                .map(|n| extrapolated(grid, map.transform_point3(lattice.position_of(n))))
                .collect(),
        }
    }
}

/// `grid`'s trilinear value at `p`, minus the distance from `p` to the grid's box.
fn extrapolated(grid: &Grid3<f32>, p: Vec3) -> f32 {
    let b = grid.bounds();
    let q = p.clamp(b.min, b.max);
    grid.trilinear(q) - p.distance(q)
}

impl Solid {
    /// A closed, outward-oriented triangle mesh (world units). Open or
    /// unwelded meshes are accepted: their inside comes from the generalized
    /// winding number ([`crate::sdf::SignMode::WindingNumber`]).
    ///
    /// # Errors
    /// [`MorphError::Mesh`] for invalid indices or non-finite positions,
    /// [`MorphError::Distance`] for a mesh without triangles.
    pub fn mesh(mesh: TriMesh) -> Result<Self, MorphError> {
        mesh.validate()?;
        let sdf = MeshSdf::new(&mesh)?;
        Ok(Self(Arc::new(Repr::Mesh { mesh, sdf: Box::new(sdf) })))
    }

    /// A signed distance volume (positive inside, world units) on its grid.
    ///
    /// # Errors
    /// [`MorphError::InvalidInput`] for NaN or infinite values.
    pub fn volume(distance: Grid3<f32>) -> Result<Self, MorphError> {
        if let Some(node) = distance.data().iter().position(|v| !v.is_finite()) {
            return Err(MorphError::InvalidInput(format!(
                "the distance volume has a NaN or infinite value at node {}",
                distance.node_of(node)
            )));
        }
        Ok(Self(Arc::new(Repr::Volume(distance))))
    }

    /// A volume of any values whose surface is the level `iso`, positive
    /// inside above it (a density, a scaled field): turned into a signed
    /// distance volume by fast marching (values minus `iso`, redistanced).
    ///
    /// # Errors
    /// [`MorphError::InvalidInput`] for a non-finite value or `iso`,
    /// [`MorphError::FastMarching`] when the level does not cross the grid.
    pub fn level_volume(values: &Grid3<f32>, iso: f32) -> Result<Self, MorphError> {
        if !iso.is_finite() {
            return Err(MorphError::InvalidInput(format!("the iso value {iso} is not finite")));
        }
        let shifted = values.map(|v| v - iso)?;
        Self::volume(redistance(&shifted, &FastMarchingSettings::default())?)
    }

    /// An analytic shape or CSG model.
    pub fn shape(shape: Shape) -> Self {
        Self(Arc::new(Repr::Shape(shape)))
    }

    /// Any implicit shape (positive inside, surface at 0) with a box.
    ///
    /// # Errors
    /// [`MorphError::InvalidInput`] when the implicit reports no finite,
    /// non-empty bounds.
    pub fn implicit(field: Arc<dyn Implicit>) -> Result<Self, MorphError> {
        let bounds = field.bounds().filter(|b| !b.is_empty() && b.min.is_finite() && b.max.is_finite());
        let bounds = bounds.ok_or_else(|| {
            MorphError::InvalidInput("the implicit shape reports no finite bounding box".into())
        })?;
        Ok(Self(Arc::new(Repr::Implicit { field, bounds })))
    }

    /// Checks that the solid has a surface to morph, the same way for every
    /// method (each method's constructor calls it through
    /// [`validate_inputs`]), and returns warnings about what is usable but
    /// unusual.
    ///
    /// - A closed mesh must enclose a positive volume: an inside-out mesh
    ///   (faces pointing inward) is [`MorphError::InsideOut`], a flat one
    ///   (a single polygon, all vertices coplanar) is
    ///   [`MorphError::EmptyShape`].
    /// - An open or non-manifold mesh is accepted with a warning (its inside
    ///   comes from the generalized winding number) when some node of a
    ///   [`PROBE_RESOLUTION`]-node probe grid over its box is inside it, and
    ///   is [`MorphError::EmptyShape`] otherwise (e.g. a single triangle).
    /// - A volume, analytic shape or implicit must be positive somewhere and
    ///   negative somewhere on its own grid (volumes) or on the probe grid.
    ///
    /// # Errors
    /// As above, and [`MorphError::Cancelled`].
    pub fn validate(&self, side: Side, control: &Control) -> Result<Vec<String>, MorphError> {
        control.check()?;
        let empty = |detail: String| MorphError::EmptyShape { side, detail };
        let probe = |field: &dyn Field3| -> Result<(bool, bool), MorphError> {
            let grid = control
                .install(|| Grid3::sample_box(field, &self.bounds().padded(0.05), PROBE_RESOLUTION))?;
            Ok((grid.data().iter().any(|&v| v > 0.0), grid.data().iter().any(|&v| v <= 0.0)))
        };
        // A field sampled on the probe grid must be inside and outside somewhere.
        let has_surface = |field: &dyn Field3| -> Result<(), MorphError> {
            match probe(field)? {
                (false, _) => Err(empty(format!("no node of a {PROBE_RESOLUTION}³ probe grid is inside it"))),
                (_, false) => Err(empty("it fills its whole box: no surface".into())),
                _ => Ok(()),
            }
        };
        let mut warnings = Vec::new();
        match &*self.0 {
            Repr::Mesh { mesh, sdf } => {
                let diagonal = mesh.bounds().size().as_dvec3().length();
                if diagonal <= 0.0 {
                    return Err(empty("all its vertices coincide".into()));
                }
                let edges = mesh.edge_stats();
                if edges.boundary_edges == 0 && edges.nonmanifold_edges == 0 {
                    let volume = mesh.signed_volume();
                    let negligible = 1e-9 * diagonal.powi(3);
                    if volume < -negligible {
                        return Err(MorphError::InsideOut { side, volume });
                    }
                    if volume <= negligible {
                        return Err(empty(format!(
                            "the closed mesh encloses no volume ({volume:.3e}; is it flat?)"
                        )));
                    }
                    if edges.misoriented_edges > 0 {
                        warnings.push(format!(
                            "the {side} mesh has {} inconsistently oriented edges; its inside comes \
                             from the generalized winding number",
                            edges.misoriented_edges
                        ));
                    }
                } else {
                    if !probe(&**sdf)?.0 {
                        return Err(empty(format!(
                            "the open mesh ({} boundary edges) encloses nothing: no node of a {PROBE_RESOLUTION}³ \
                             probe grid over its box has winding number above ½",
                            edges.boundary_edges
                        )));
                    }
                    warnings.push(format!(
                        "the {side} mesh is open or non-manifold ({} boundary, {} non-manifold edges); its \
                         inside comes from the generalized winding number",
                        edges.boundary_edges, edges.nonmanifold_edges
                    ));
                }
            }
            Repr::Volume(grid) => {
                if !grid.data().iter().any(|&v| v > 0.0) {
                    return Err(empty("no node of the distance volume is inside (positive)".into()));
                }
                if !grid.data().iter().any(|&v| v <= 0.0) {
                    return Err(empty("every node of the distance volume is inside: no surface".into()));
                }
            }
            Repr::Shape(shape) => has_surface(shape)?,
            Repr::Implicit { field, .. } => has_surface(field.as_ref())?,
        }
        Ok(warnings)
    }

    /// `"mesh"`, `"distance volume"`, `"analytic shape"` or `"implicit"`.
    pub fn kind(&self) -> &'static str {
        match &*self.0 {
            Repr::Mesh { .. } => "mesh",
            Repr::Volume(_) => "distance volume",
            Repr::Shape(_) => "analytic shape",
            Repr::Implicit { .. } => "implicit",
        }
    }

    /// The mesh, for mesh solids.
    pub fn as_mesh(&self) -> Option<&TriMesh> {
        match &*self.0 {
            Repr::Mesh { mesh, .. } => Some(mesh),
            _ => None,
        }
    }

    /// The implicit, for implicit solids (downcast it with
    /// [`Implicit::as_any`]).
    pub fn as_implicit(&self) -> Option<&dyn Implicit> {
        match &*self.0 {
            Repr::Implicit { field, .. } => Some(field.as_ref()),
            _ => None,
        }
    }

    /// A box containing the surface (world units). For a distance volume,
    /// the box of its nodes.
    pub fn bounds(&self) -> Aabb {
        match &*self.0 {
            Repr::Mesh { mesh, .. } => mesh.bounds(),
            Repr::Volume(grid) => grid.bounds(),
            Repr::Shape(shape) => shape.aabb(),
            Repr::Implicit { bounds, .. } => *bounds,
        }
    }

    /// The exact unsigned distance from `p` to the surface, where the solid
    /// knows it without sampling a volume: meshes (their tree) and analytic
    /// shapes whose distance is exact ([`Shape::is_exact_distance`]).
    /// `None` for the other kinds, whose distance comes from a sampled
    /// volume ([`Solid::distance_field`]), and for a non-finite `p`.
    pub fn exact_distance(&self, p: Vec3) -> Option<f32> {
        if !self.has_exact_distance() {
            return None;
        }
        match &*self.0 {
            Repr::Mesh { sdf, .. } => sdf.closest(p).map(|c| c.distance_squared.max(0.0).sqrt()),
            Repr::Shape(shape) if p.is_finite() => Some(shape.distance(p).abs()),
            _ => None,
        }
    }

    /// The point of the surface nearest to `p`, where the solid knows its
    /// exact distance ([`Solid::exact_distance`]): the closest point of a
    /// mesh; for an analytic shape, Newton steps along the distance's
    /// gradient (exact for points near the surface, e.g. the vertices of a
    /// polygonization, to within rounding). `None` for the other kinds and
    /// for a non-finite `p`.
    pub fn nearest_surface_point(&self, p: Vec3) -> Option<Vec3> {
        if !p.is_finite() {
            return None;
        }
        match &*self.0 {
            Repr::Mesh { sdf, .. } => sdf.closest(p).map(|c| c.point),
            Repr::Shape(shape) if shape.is_exact_distance() => {
                let mut q = p;
                for _ in 0..NEWTON_STEPS {
                    let (f, g) = (shape.distance(q), shape.gradient(q));
                    let g2 = g.length_squared();
                    if f == 0.0 || g2.is_nan() || g2 <= f32::MIN_POSITIVE {
                        break;
                    }
                    q -= g * (f / g2);
                }
                q.is_finite().then_some(q)
            }
            _ => None,
        }
    }

    /// The exact signed distance (positive inside, world units) as a field
    /// evaluated point by point, for the solids that know it without a
    /// volume (as [`Solid::exact_distance`]): it changes by at most the
    /// distance moved, so a narrow band of it can be sampled brick by brick
    /// ([`crate::Bricks::sample_band`]). Its values equal those of
    /// [`Solid::distance_volume`] at the lattice's nodes up to rounding.
    /// `None` for the other kinds.
    pub fn exact_field(&self) -> Option<&dyn Field3> {
        match &*self.0 {
            Repr::Mesh { sdf, .. } => Some(sdf.as_ref()),
            Repr::Shape(shape) if shape.is_exact_distance() => Some(shape),
            _ => None,
        }
    }

    /// The exact signed distance (world units, positive inside) at the
    /// image under `map` of the nodes `first + (i, j, k)`, `(i, j, k) <
    /// dims` (x fastest), of `lattice`: [`Solid::exact_field`]'s value
    /// there (to the last bit but for near-ties; see
    /// [`MeshSdf::sample_mapped`]), a mesh's from one batch query with its
    /// signs found once per region ([`MeshSdf::sample_mapped_nodes`]).
    /// `None` where [`Solid::exact_field`] is.
    pub fn exact_mapped_nodes(
        &self,
        lattice: &Lattice,
        first: UVec3,
        dims: UVec3,
        map: &Affine3A,
    ) -> Option<Vec<f32>> {
        if let Repr::Mesh { sdf, .. } = &*self.0 {
            return Some(sdf.sample_mapped_nodes(lattice, first, dims, map));
        }
        let field = self.exact_field()?;
        let value = |n| field.value(map.transform_point3(lattice.position_in_box(first, dims, n)));
        Some((0..Lattice { dims, ..*lattice }.len()).into_par_iter().map(value).collect())
    }

    /// True when [`Solid::exact_distance`] answers (for finite points).
    pub fn has_exact_distance(&self) -> bool {
        match &*self.0 {
            Repr::Mesh { .. } => true,
            Repr::Shape(shape) => shape.is_exact_distance(),
            Repr::Volume(_) | Repr::Implicit { .. } => false,
        }
    }

    /// The true signed distance (positive inside, world units) on the
    /// lattice over `bounds` with `res` nodes along its longest edge (see
    /// [`lattice_for_box`]).
    ///
    /// # Errors
    /// Grid errors (memory limit, bad box), scan conversion and
    /// redistancing errors (e.g. a surface that does not cross the lattice),
    /// [`MorphError::Cancelled`].
    pub fn distance_volume(
        &self,
        bounds: &Aabb,
        res: u32,
        control: &Control,
    ) -> Result<Grid3<f32>, MorphError> {
        control.check()?;
        let volume = control.install(|| -> Result<_, MorphError> {
            Ok(match &*self.0 {
                Repr::Mesh { sdf, .. } => sdf.sample_grid(bounds, res)?,
                Repr::Shape(shape) if shape.is_exact_distance() => Grid3::sample_box(shape, bounds, res)?,
                Repr::Shape(shape) => scan_convert(shape, bounds, res, &FastMarchingSettings::default())?,
                Repr::Volume(grid) => {
                    let (dims, origin, spacing) = lattice_for_box(bounds, res)?;
                    if grid.dims() == dims && grid.origin() == origin && grid.spacing() == spacing {
                        grid.clone()
                    } else {
                        Grid3::sample(&|p| extrapolated(grid, p), dims, origin, spacing)?
                    }
                }
                Repr::Implicit { field, .. } => {
                    let sampled = Grid3::sample_box(field.as_ref(), bounds, res)?;
                    redistance(&sampled, &FastMarchingSettings::default())?
                }
            })
        })?;
        control.check()?;
        Ok(volume)
    }

    /// A pointwise true signed distance: exact for meshes, a distance volume
    /// with `res` nodes along the longest edge of the solid's box (padded by
    /// 10 % per side) for analytic shapes and implicits, the volume itself
    /// for volumes.
    ///
    /// # Errors
    /// As [`Solid::distance_volume`].
    pub fn distance_field(&self, res: u32, control: &Control) -> Result<DistanceField<'_>, MorphError> {
        Ok(match &*self.0 {
            Repr::Mesh { sdf, .. } => DistanceField::Exact(sdf),
            Repr::Volume(grid) => DistanceField::Volume(Cow::Borrowed(grid)),
            _ => DistanceField::Volume(Cow::Owned(self.distance_volume(
                &self.bounds().padded(0.1),
                res,
                control,
            )?)),
        })
    }

    /// The surface as a mesh: the mesh itself, or marching cubes of the
    /// distance volume over the solid's box (padded by 5 % per side) with
    /// `res` nodes along its longest edge.
    ///
    /// # Errors
    /// As [`Solid::distance_volume`].
    pub fn surface(&self, res: u32, control: &Control) -> Result<Cow<'_, TriMesh>, MorphError> {
        let bounds = self.bounds().padded(0.05);
        Ok(match &*self.0 {
            Repr::Mesh { mesh, .. } => Cow::Borrowed(mesh),
            _ => Cow::Owned(marching_cubes(&self.distance_volume(&bounds, res, control)?, 0.0)),
        })
    }

    /// The solid's moments (volume, centroid, covariance): exact for closed
    /// meshes, from the distance volume with `res` nodes along the longest
    /// edge otherwise — including open meshes, whose inside (as everywhere in
    /// the morphs) comes from the generalized winding number, so their
    /// triangles alone bound no volume.
    ///
    /// # Errors
    /// [`MorphError::Alignment`] for empty or degenerate shapes, and as
    /// [`Solid::distance_volume`].
    pub fn moments(&self, res: u32, control: &Control) -> Result<Moments, MorphError> {
        let sampled = || -> Result<Moments, MorphError> {
            Ok(Moments::from_grid(&self.distance_volume(&self.bounds().padded(0.05), res, control)?)?)
        };
        match &*self.0 {
            Repr::Mesh { mesh, .. } => match Moments::from_mesh(mesh) {
                Err(AlignError::OpenMesh { .. }) => sampled(),
                closed => Ok(closed?),
            },
            _ => sampled(),
        }
    }
}

/// Nodes along the longest edge of the probe grid [`Solid::validate`]
/// samples to find an inside.
pub const PROBE_RESOLUTION: u32 = 24;

/// Validates both inputs of a morph ([`Solid::validate`]) and returns their
/// warnings; every method's constructor calls it first.
///
/// # Errors
/// As [`Solid::validate`], for the source first.
pub fn validate_inputs(source: &Solid, target: &Solid, control: &Control) -> Result<Vec<String>, MorphError> {
    let mut warnings = source.validate(Side::Source, control)?;
    warnings.extend(target.validate(Side::Target, control)?);
    Ok(warnings)
}

/// Newton steps of [`Solid::nearest_surface_point`] on analytic shapes:
/// from a point `ε` off a surface of curvature `κ`, a step leaves an error
/// of order `κ ε²`, so two reach rounding from a polygonization's vertices.
const NEWTON_STEPS: usize = 2;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::primitives::uv_sphere;
    use crate::models;

    /// Boxes of a lattice's nodes seen through a map take each node's
    /// exact distance, for a mesh (batch query, signs propagated within the
    /// box) and an analytic shape; a sampled volume has none.
    #[test]
    fn exact_mapped_nodes_are_the_pointwise_distances() {
        let map = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.2, 0.9, 1.05),
            glam::Quat::from_rotation_y(0.5),
            Vec3::new(0.03, -0.02, 0.01),
        );
        let lattice = Lattice { dims: UVec3::splat(24), origin: Vec3::splat(-0.45), step: Vec3::splat(0.04) };
        let shape = Shape::torus(0.3, 0.12);
        let mesh =
            Solid::mesh(marching_cubes(&Grid3::sample_box(&shape, &Aabb::cube(0.5), 40).unwrap(), 0.0));
        for solid in [Solid::shape(shape), mesh.unwrap()] {
            let field = solid.exact_field().unwrap();
            let (mut inside, mut worst) = (0, 0.0f32);
            for first in [UVec3::ZERO, UVec3::new(8, 8, 8), UVec3::new(16, 4, 9)] {
                let d = solid.exact_mapped_nodes(&lattice, first, UVec3::splat(8), &map).unwrap();
                for (n, &v) in d.iter().enumerate() {
                    let c = first + UVec3::new(n as u32 % 8, (n as u32 / 8) % 8, n as u32 / 64);
                    let exact = field.value(map.transform_point3(lattice.position(c.x, c.y, c.z)));
                    assert_eq!(v > 0.0, exact > 0.0, "{} at {c}: {v} vs {exact}", solid.kind());
                    inside += usize::from(v > 0.0);
                    worst = worst.max((v - exact).abs());
                }
            }
            // Equal but for a near-tie between triangles resolved in another order.
            assert!(worst <= 1e-6, "{}: {worst}", solid.kind());
            assert!(inside > 50, "{}: {inside} inside nodes", solid.kind());
        }
        let volume = Solid::volume(Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 16).unwrap());
        assert!(volume.unwrap().exact_mapped_nodes(&lattice, UVec3::ZERO, UVec3::ONE, &map).is_none());
    }

    #[test]
    fn nearest_surface_points_lie_on_the_surface() {
        let control = Control::new();
        let torus = Solid::shape(Shape::torus(0.3, 0.12).translated(Vec3::new(0.1, -0.05, 0.2)));
        let mesh = torus.surface(48, &control).unwrap().into_owned();
        let mut worst_before = 0.0f32;
        for &p in &mesh.positions {
            let q = torus.nearest_surface_point(p).unwrap();
            worst_before = worst_before.max(torus.exact_distance(p).unwrap());
            assert!(torus.exact_distance(q).unwrap() < 2e-6, "{p} -> {q}");
            // The nearest point: no farther than the polygonization's error.
            assert!(p.distance(q) <= torus.exact_distance(p).unwrap() + 2e-6, "{p} -> {q}");
        }
        assert!(worst_before > 1e-4, "the vertices start off the surface ({worst_before})");
        let sphere = Solid::mesh(uv_sphere(Vec3::ZERO, 0.3, 12, 24)).unwrap();
        let q = sphere.nearest_surface_point(Vec3::new(0.0, 0.0, 0.5)).unwrap();
        assert!((q.z - 0.3).abs() < 1e-6 && q.x.abs() < 1e-6, "{q}");
        let csg = Solid::shape(models::c_shape());
        assert_eq!(csg.nearest_surface_point(Vec3::ZERO), None);
        assert_eq!(torus.nearest_surface_point(Vec3::NAN), None);
    }

    #[test]
    fn exact_distances_are_unsigned_and_only_where_known() {
        let mesh = Solid::mesh(uv_sphere(Vec3::ZERO, 0.3, 48, 96)).unwrap();
        let shape = Solid::shape(Shape::sphere(0.3));
        for p in [Vec3::ZERO, Vec3::new(0.1, 0.05, 0.0), Vec3::new(0.5, 0.2, -0.1)] {
            let want = (p.length() - 0.3).abs();
            assert!((shape.exact_distance(p).unwrap() - want).abs() < 1e-6, "{p}");
            // The mesh is a polyhedron: its faces lie up to 0.3 · (2 − cos(π/48)
            // − cos(π/96)) ≈ 8e-4 inside the sphere.
            assert!((mesh.exact_distance(p).unwrap() - want).abs() < 1e-3, "{p}");
        }
        assert_eq!(shape.exact_distance(Vec3::NAN), None);
        let volume =
            Solid::volume(Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 17).unwrap()).unwrap();
        let csg = Solid::shape(models::c_shape());
        assert_eq!((volume.exact_distance(Vec3::ZERO), csg.exact_distance(Vec3::ZERO)), (None, None));
        assert!(mesh.has_exact_distance() && shape.has_exact_distance() && !csg.has_exact_distance());
    }

    #[test]
    fn every_kind_gives_a_true_distance() {
        let control = Control::new();
        let bounds = Aabb::cube(0.5);
        let sphere = Shape::sphere(0.3);
        let mesh = Solid::mesh(uv_sphere(Vec3::ZERO, 0.3, 48, 96)).unwrap();
        let shape = Solid::shape(sphere.clone());
        let exact = Grid3::sample_box(&sphere, &bounds, 33).unwrap();
        let volume = Solid::volume(exact.clone()).unwrap();
        for solid in [&mesh, &shape, &volume] {
            let g = solid.distance_volume(&bounds, 33, &control).unwrap();
            let worst = g.data().iter().zip(exact.data()).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
            // The mesh is a polyhedron (chord error 0.3·(1 − cos(π/96)) ≈ 2e-4).
            assert!(worst < 0.3 * g.spacing(), "{}: {worst}", solid.kind());
        }
        // A resampled volume agrees off its lattice.
        let fine = volume.distance_volume(&bounds, 41, &control).unwrap();
        assert!(
            (fine.value(Vec3::new(0.1, 0.05, 0.0)) - sphere.value(Vec3::new(0.1, 0.05, 0.0))).abs() < 0.01
        );
        // Outside the volume's box the continuation stays negative.
        assert!(volume.distance_field(0, &control).unwrap().value(Vec3::splat(2.0)) < -1.0);
    }

    #[test]
    fn csg_is_scan_converted_not_its_raw_field() {
        let c = models::c_shape();
        let bounds = Aabb::cube(0.5);
        let d = Solid::shape(c.clone()).distance_volume(&bounds, 40, &Control::new()).unwrap();
        let scanned = scan_convert(&c, &bounds, 40, &FastMarchingSettings::default()).unwrap();
        assert_eq!(d.data(), scanned.data());
        let raw = Grid3::sample_box(&c, &bounds, 40).unwrap();
        let differ =
            raw.data().iter().zip(d.data()).filter(|(a, b)| (*a - *b).abs() > 0.1 * d.spacing()).count();
        assert!(differ > raw.len() / 10, "the raw CSG field is not a distance: {differ} nodes differ");
    }

    #[test]
    fn unusable_meshes_are_refused_the_same_way() {
        let control = Control::new();
        let check = |mesh: TriMesh| Solid::mesh(mesh).unwrap().validate(Side::Target, &control);
        let sphere = uv_sphere(Vec3::ZERO, 0.3, 16, 32);
        assert_eq!(check(sphere.clone()).unwrap(), Vec::<String>::new());
        // Inside out: every triangle reversed.
        let mut flipped = sphere.clone();
        flipped.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        assert!(
            matches!(check(flipped), Err(MorphError::InsideOut { side: Side::Target, volume }) if volume < 0.0)
        );
        // A single triangle, and a flat 200-gon (fan-triangulated): no inside.
        let triangle = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        assert!(matches!(check(triangle), Err(MorphError::EmptyShape { side: Side::Target, .. })));
        let ring: Vec<Vec3> =
            (0..200).map(|i| Vec3::new((i as f32 * 0.0314).cos(), (i as f32 * 0.0314).sin(), 0.0)).collect();
        let fan = (1..199).map(|i| [0, i, i + 1]).collect();
        assert!(matches!(check(TriMesh::new(ring, fan).unwrap()), Err(MorphError::EmptyShape { .. })));
        // An open sphere (a band of triangles removed) still has an inside: a warning.
        let mut open = sphere;
        open.triangles.truncate(open.triangles.len() - 32);
        let warnings = check(open).unwrap();
        assert!(warnings.len() == 1 && warnings[0].contains("open"), "{warnings:?}");
    }

    #[test]
    fn open_meshes_have_the_moments_of_their_winding_number_inside() {
        let control = Control::new();
        let sphere = uv_sphere(Vec3::new(0.05, -0.02, 0.01), 0.3, 32, 64);
        let closed = Solid::mesh(sphere.clone()).unwrap().moments(64, &control).unwrap();
        // A cap of triangles removed: the triangles bound no volume, but the
        // winding number still sees (nearly) the whole ball.
        let mut cut = sphere;
        cut.triangles.truncate(cut.triangles.len() - 64);
        assert!(matches!(Moments::from_mesh(&cut), Err(AlignError::OpenMesh { .. })));
        let open = Solid::mesh(cut).unwrap().moments(64, &control).unwrap();
        assert!((open.volume / closed.volume - 1.0).abs() < 0.05, "{} vs {}", open.volume, closed.volume);
        assert!(
            (open.centroid - closed.centroid).length() < 0.02,
            "{} vs {}",
            open.centroid,
            closed.centroid
        );
    }

    #[test]
    fn empty_volumes_and_implicits_are_refused() {
        let control = Control::new();
        let outside = Grid3::new(glam::UVec3::splat(8), Vec3::ZERO, 0.1, -1.0f32).unwrap();
        let inside = Grid3::new(glam::UVec3::splat(8), Vec3::ZERO, 0.1, 1.0f32).unwrap();
        for grid in [outside, inside] {
            let err = Solid::volume(grid).unwrap().validate(Side::Source, &control).unwrap_err();
            assert!(matches!(err, MorphError::EmptyShape { side: Side::Source, .. }), "{err}");
        }
        let sphere = Solid::shape(Shape::sphere(0.3));
        assert!(validate_inputs(&sphere, &sphere, &control).unwrap().is_empty());
    }

    #[test]
    fn bad_inputs_are_errors_and_cancel_is_honoured() {
        let mut g = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 9).unwrap();
        g.data_mut()[3] = f32::NAN;
        assert!(matches!(Solid::volume(g), Err(MorphError::InvalidInput(_))));
        assert!(Solid::mesh(TriMesh::default()).is_err());
        let control = Control::new();
        control.cancel_token().cancel();
        let s = Solid::shape(Shape::sphere(0.3));
        assert!(matches!(s.distance_volume(&Aabb::cube(0.5), 9, &control), Err(MorphError::Cancelled)));
    }
}
