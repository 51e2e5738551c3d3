//! Surface reconstruction from planar contours (paper §6, §6.1, §6.2).

use crate::constraints::NormalOffset;
use crate::error::RbfError;
use crate::image::image_constraints;
use crate::interpolant::{Constraint, FitSettings, Interpolant};
use crate::slice::Slice3;
use glam::{Vec2, Vec3};
use isomorph_common::MorphError;
use isomorph_common::marching_cubes::level_set_mesh;
use isomorph_common::{Aabb, Field3, Grid2, TriMesh};

/// A plane in 3D carrying 2D contour coordinates: the 2D point `(x, y)` sits
/// at `origin + x·u + y·v`. The axes need not be unit length or orthogonal
/// (e.g. `u`, `v` = the pixel spacing of a scanner slice), only independent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    origin: Vec3,
    u: Vec3,
    v: Vec3,
}

impl Plane {
    /// The plane through `origin` spanned by the axes `u` and `v`.
    ///
    /// # Errors
    /// [`RbfError::DegeneratePlane`] for a non-finite origin or axis, a zero
    /// axis, or (nearly) parallel axes.
    pub fn new(origin: Vec3, u: Vec3, v: Vec3) -> Result<Self, RbfError> {
        if !(origin.is_finite() && u.is_finite() && v.is_finite()) {
            return Err(RbfError::DegeneratePlane("non-finite origin or axis"));
        }
        if u == Vec3::ZERO || v == Vec3::ZERO {
            return Err(RbfError::DegeneratePlane("zero axis"));
        }
        if u.cross(v).length() <= 1e-6 * u.length() * v.length() {
            return Err(RbfError::DegeneratePlane("parallel axes"));
        }
        Ok(Self { origin, u, v })
    }

    /// The horizontal plane at height `z` with the 2D coordinates being world
    /// `x` and `y` (a slice of a parallel stack).
    ///
    /// # Errors
    /// [`RbfError::DegeneratePlane`] for a non-finite `z`.
    pub fn at_z(z: f32) -> Result<Self, RbfError> {
        Self::new(Vec3::Z * z, Vec3::X, Vec3::Y)
    }

    /// The 3D position of the 2D point `p`.
    pub fn point(&self, p: Vec2) -> Vec3 {
        self.origin + p.x * self.u + p.y * self.v
    }

    /// The 3D direction of the 2D direction `d` (not normalized).
    pub fn direction(&self, d: Vec2) -> Vec3 {
        d.x * self.u + d.y * self.v
    }

    /// The unit normal `u × v / |u × v|`.
    pub fn normal(&self) -> Vec3 {
        self.u.cross(self.v).normalize()
    }
}

/// Settings of [`ContourSet::fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct ReconstructSettings {
    /// The fit (kernel, smoothing, duplicates). With the default `r² log r`
    /// the surface is the smoothest (thin-plate) one through the contours;
    /// `r³` is the 3D variational (triharmonic) choice.
    pub fit: FitSettings,
    /// Inward offset of the normal constraints made from polylines (default
    /// `k = 0.01` of the diagonal of all contour points' bounding box). It
    /// must be below half the thinnest part of a contour. Constraints added
    /// by [`ContourSet::add_constraints`] or [`ContourSet::add_image`] keep
    /// their own offsets.
    pub offset: NormalOffset,
    /// Margin around the contours' bounding box for the surface's bounds, as
    /// a fraction of its diagonal (default 0.15): the surface rounds off
    /// beyond the outermost slices.
    pub margin: f32,
}

impl Default for ReconstructSettings {
    fn default() -> Self {
        Self { fit: FitSettings::default(), offset: NormalOffset::RelativeToDiagonal(0.01), margin: 0.15 }
    }
}

/// The contours of all slices, collected before one fit.
///
/// Every contour lies in a [`Plane`] (an origin and two in-plane axes); its
/// 2D boundary and normal constraints are lifted into 3D there, the normal
/// constraints stay in the plane and point inward. The constraints of *all*
/// slices are interpolated **once** by one variational implicit in 3D, so the
/// zero set passes through every contour and its normal is continuous across
/// the slice planes (no pairwise stacking), with rounded caps beyond the
/// outermost slices. Parallel slices with any (also varying) spacing are
/// planes [`Plane::at_z`]; slices in any other orientation, also crossing
/// each other (§6.1), are planes [`Plane::new`]. The spacing is the real
/// one: constraints sit where the slices were taken (§6.2).
///
/// Positive inside, zero on the surface, world units throughout.
///
/// ```
/// use glam::{Vec2, Vec3};
/// use isomorph_common::Field3;
/// use isomorph_rbf::{ContourSet, Plane, ReconstructSettings};
///
/// // Circles of a sphere (radius 0.3) at unevenly spaced heights.
/// let mut set = ContourSet::new();
/// for z in [-0.25f32, -0.1, 0.0, 0.05, 0.2] {
///     let r = (0.09 - z * z).sqrt();
///     let circle: Vec<Vec2> = (0..24)
///         .map(|i| Vec2::from_angle(i as f32 * std::f32::consts::TAU / 24.0) * r)
///         .collect();
///     set.add_polylines(&Plane::at_z(z)?, &[circle])?;
/// }
/// let surface = set.fit(&ReconstructSettings::default())?;
/// let field = surface.field();
/// assert!(field.value(Vec3::new(0.3, 0.0, 0.0)).abs() < 1e-3); // on a contour
/// assert!(field.value(Vec3::ZERO) > 0.0); // inside
/// let mesh = surface.mesh(32)?;
/// assert_eq!(mesh.connected_components(), 1);
/// # Ok::<(), isomorph_rbf::RbfError>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct ContourSet {
    /// Complete constraints (from 2D constraints and images).
    constraints: Vec<Constraint<3>>,
    /// Boundary points of polylines with their unit inward in-plane direction;
    /// their normal constraints are made at fit time, when the offset is known.
    oriented: Vec<(Vec3, Vec3)>,
}

impl ContourSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds closed contours of one slice, given as polylines of 2D points in
    /// `plane` (the last point joins the first; repeating the first point at
    /// the end is allowed). Inside is decided by nesting, whatever the
    /// orientation: a contour inside an even number of the others bounds
    /// material, inside an odd number it bounds a hole. Each vertex becomes a
    /// boundary constraint; its normal constraint goes inward in the plane,
    /// along the average of the two edge normals. Sample contours densely
    /// enough: the surface passes through the vertices, not the edges.
    ///
    /// # Errors
    /// [`RbfError::EmptyShape`] for no polylines,
    /// [`RbfError::NonFinite`] for a NaN or infinite point (its index counts
    /// over all polylines of the call), [`RbfError::InvalidContour`] for a
    /// polyline with fewer than three distinct points, zero area, or a
    /// vertex where the contour turns back on itself.
    pub fn add_polylines(&mut self, plane: &Plane, polylines: &[Vec<Vec2>]) -> Result<(), RbfError> {
        if polylines.iter().all(Vec::is_empty) {
            return Err(RbfError::EmptyShape("contour"));
        }
        if let Some(index) = polylines.iter().flatten().position(|p| !p.is_finite()) {
            return Err(RbfError::NonFinite { index, what: "position" });
        }
        let loops: Vec<Vec<Vec2>> = polylines.iter().map(|l| distinct_loop(l)).collect();
        let mut added = Vec::new();
        for (contour, ring) in loops.iter().enumerate() {
            if ring.len() < 3 {
                return Err(RbfError::InvalidContour { contour, reason: "fewer than three distinct points" });
            }
            let area = signed_area(ring);
            if area == 0.0 {
                return Err(RbfError::InvalidContour { contour, reason: "zero area" });
            }
            let depth = loops
                .iter()
                .enumerate()
                .filter(|&(other, l)| other != contour && l.len() >= 3 && contains(l, ring[0]))
                .count();
            // Material lies left of a counter-clockwise outer contour; flip
            // for clockwise contours and for holes.
            let left = (area > 0.0) != (depth % 2 == 1);
            let side = if left { 1.0 } else { -1.0 };
            let n = ring.len();
            for i in 0..n {
                let (prev, p, next) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
                let normal = (p - prev).normalize().perp() + (next - p).normalize().perp();
                let inward = plane.direction(side * normal).normalize_or_zero();
                if inward == Vec3::ZERO {
                    return Err(RbfError::InvalidContour {
                        contour,
                        reason: "the contour turns back on itself",
                    });
                }
                added.push((plane.point(p), inward));
            }
        }
        self.oriented.extend(added);
        Ok(())
    }

    /// Adds 2D constraints (boundary and normal constraints in the plane's
    /// coordinates, e.g. from [`image_constraints`]) lifted into `plane`.
    ///
    /// # Errors
    /// [`RbfError::EmptyShape`] for no constraints, [`RbfError::NonFinite`]
    /// for a NaN or infinite position or value.
    pub fn add_constraints(&mut self, plane: &Plane, constraints: &[Constraint<2>]) -> Result<(), RbfError> {
        if constraints.is_empty() {
            return Err(RbfError::EmptyShape("contour"));
        }
        for (index, c) in constraints.iter().enumerate() {
            if !(c.position[0].is_finite() && c.position[1].is_finite()) {
                return Err(RbfError::NonFinite { index, what: "position" });
            }
            if !c.value.is_finite() {
                return Err(RbfError::NonFinite { index, what: "value" });
            }
        }
        self.constraints.extend(
            constraints
                .iter()
                .map(|c| Constraint::new(plane.point(Vec2::from_array(c.position)).to_array(), c.value)),
        );
        Ok(())
    }

    /// Adds the shape of a grayscale slice image (bright inside, boundary at
    /// level `mid`) by [`image_constraints`] (§4.1: normal constraints one
    /// pixel inward), with the image's world coordinates as the plane's 2D
    /// coordinates.
    ///
    /// # Errors
    /// Those of [`image_constraints`] (blank image, NaN pixel).
    pub fn add_image(&mut self, plane: &Plane, image: &Grid2<f32>, mid: f32) -> Result<(), RbfError> {
        self.add_constraints(plane, &image_constraints(image, mid)?)
    }

    /// Number of constraints the fit will have (before merging duplicates).
    pub fn len(&self) -> usize {
        self.constraints.len() + 2 * self.oriented.len()
    }

    /// True when nothing was added.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Fits one variational implicit through the constraints of all slices.
    ///
    /// # Errors
    /// [`RbfError::EmptyShape`] for an empty set, [`MorphError::BadSetting`]
    /// for a bad offset or margin, [`RbfError::NotUnisolvent`] when all
    /// contours lie in one plane (a single slice does not determine a
    /// surface), and the other errors of [`Interpolant::fit`].
    pub fn fit(&self, settings: &ReconstructSettings) -> Result<ContourSurface, RbfError> {
        if self.is_empty() {
            return Err(RbfError::EmptyShape("contour set"));
        }
        if !(settings.margin >= 0.0 && settings.margin.is_finite()) {
            return Err(MorphError::bad_setting("margin", settings.margin, "a finite number ≥ 0").into());
        }
        let points: Vec<Vec3> = (self.constraints.iter().map(|c| Vec3::from_array(c.position)))
            .chain(self.oriented.iter().map(|&(p, _)| p))
            .collect();
        let bounds = Aabb::from_points(&points);
        let k = match settings.offset {
            NormalOffset::RelativeToDiagonal(k) => k * bounds.diagonal(),
            NormalOffset::Absolute(k) => k,
        };
        if !(k > 0.0 && k.is_finite()) {
            return Err(MorphError::bad_setting("offset", k, "a finite number > 0").into());
        }
        let mut all = self.constraints.clone();
        for &(p, inward) in &self.oriented {
            all.push(Constraint::new(p.to_array(), 0.0));
            all.push(Constraint::new((p + k * inward).to_array(), 1.0));
        }
        let interpolant = Interpolant::fit(&all, &settings.fit)?;
        let step = settings.margin.max(0.05) * bounds.diagonal();
        let mut surface =
            ContourSurface { interpolant, bounds: bounds.expanded(settings.margin * bounds.diagonal()) };
        // The caps beyond the outermost slices reach further for wide
        // contours far apart: grow the box until its faces are outside.
        for _ in 0..MAX_GROWTH {
            if !surface.positive_on_faces() {
                break;
            }
            surface.bounds = surface.bounds.expanded(step);
        }
        Ok(surface)
    }
}

/// How often [`ContourSet::fit`] grows the box to enclose the caps.
const MAX_GROWTH: usize = 8;

/// The reconstructed surface: the zero set of a 3D variational implicit,
/// positive inside.
#[derive(Debug, Clone)]
pub struct ContourSurface {
    interpolant: Interpolant<3>,
    bounds: Aabb,
}

impl ContourSurface {
    /// The implicit (f64 evaluation, gradient, fit report).
    pub fn interpolant(&self) -> &Interpolant<3> {
        &self.interpolant
    }

    /// The contours' bounding box grown by the margin, and further (up to 8
    /// more steps of the margin, at least 5 % of the diagonal) until the
    /// field is negative on a 16 × 16 lattice on each face: it encloses the
    /// rounded caps beyond the outermost slices.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The implicit as a fast [`Field3`] (f32
    /// batch evaluation) reporting [`ContourSurface::bounds`].
    pub fn field(&self) -> Slice3 {
        // A 3D interpolant has no coordinate to fix: this cannot fail.
        self.interpolant.slice3(&[]).expect("a 3D interpolant slices to 3D").with_bounds(self.bounds)
    }

    /// The surface as a triangle mesh: [`ContourSurface::bounds`] sampled
    /// with `res` nodes along its longest edge, polygonized near the surface
    /// only.
    ///
    /// # Errors
    /// [`MorphError::Grid`] for `res < 2` or a lattice too large.
    pub fn mesh(&self, res: u32) -> Result<TriMesh, RbfError> {
        Ok(level_set_mesh(&self.field(), &self.bounds, res, 0.0)?)
    }
}

impl ContourSurface {
    /// True when the field is positive somewhere on a 16 × 16 lattice on the
    /// faces of the bounds.
    fn positive_on_faces(&self) -> bool {
        const N: usize = 16;
        let (lo, size) = (self.bounds.min, self.bounds.size());
        let mut points = Vec::with_capacity(6 * N * N);
        for axis in 0..3 {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in [0.0, 1.0] {
                for i in 0..N {
                    for j in 0..N {
                        let mut q = Vec3::ZERO;
                        q[axis] = side;
                        q[a] = i as f32 / (N - 1) as f32;
                        q[b] = j as f32 / (N - 1) as f32;
                        points.push(lo + q * size);
                    }
                }
            }
        }
        let mut values = vec![0.0f32; points.len()];
        self.field().values(&points, &mut values);
        values.iter().any(|&v| v > 0.0)
    }
}

/// The polyline without consecutive repeated points (also last = first).
fn distinct_loop(points: &[Vec2]) -> Vec<Vec2> {
    let mut out: Vec<Vec2> = Vec::with_capacity(points.len());
    for &p in points {
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

/// The signed area of a closed polygon (positive counter-clockwise).
fn signed_area(ring: &[Vec2]) -> f32 {
    let n = ring.len();
    0.5 * (0..n).map(|i| ring[i].perp_dot(ring[(i + 1) % n])).sum::<f32>()
}

/// Even-odd point-in-polygon test (crossing number).
fn contains(ring: &[Vec2], p: Vec2) -> bool {
    let n = ring.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::TAU;

    fn circle(r: f32, n: usize) -> Vec<Vec2> {
        (0..n).map(|i| Vec2::from_angle(i as f32 * TAU / n as f32) * r).collect()
    }

    /// Asserts that the surface passes through `points`: `|f| < 1e-6` there
    /// (exact f64 evaluation) and every point lies within one grid spacing of
    /// a vertex of the mesh at `res`, which is returned.
    fn assert_through(surface: &ContourSurface, points: &[Vec3], res: u32) -> TriMesh {
        let mesh = surface.mesh(res).unwrap();
        let h = surface.bounds().size().max_element() / (res - 1) as f32;
        let f = surface.interpolant();
        let value = points.iter().map(|p| f.value_f64(p.to_array().map(f64::from)).abs()).fold(0.0, f64::max);
        assert!(value < 1e-6, "|f| on the contours {value:e}");
        let distance = points
            .iter()
            .map(|p| mesh.positions.iter().map(|q| q.distance(*p)).fold(f32::INFINITY, f32::min))
            .fold(0.0, f32::max);
        assert!(distance < h, "contour point {distance} from the mesh (spacing {h})");
        assert_eq!(mesh.connected_components(), 1);
        mesh
    }

    #[test]
    fn three_orthogonal_circles_give_the_sphere() {
        let r = 0.3;
        let planes = [
            Plane::new(Vec3::ZERO, Vec3::X, Vec3::Y).unwrap(),
            Plane::new(Vec3::ZERO, Vec3::Y, Vec3::Z).unwrap(),
            // Tilted axes of other lengths: the lifting is affine.
            Plane::new(Vec3::ZERO, Vec3::Z * 2.0, Vec3::X * 0.5).unwrap(),
        ];
        let mut set = ContourSet::new();
        let mut points = Vec::new();
        for (k, plane) in planes.iter().enumerate() {
            // The same circle of radius r in world units on each plane.
            let ring: Vec<Vec2> = circle(r, 40)
                .into_iter()
                .map(|p| if k == 2 { Vec2::new(p.x / 2.0, p.y * 2.0) } else { p })
                .collect();
            points.extend(ring.iter().map(|&p| plane.point(p)));
            set.add_polylines(plane, &[ring]).unwrap();
        }
        assert_eq!(set.len(), 240);
        let surface = set.fit(&ReconstructSettings::default()).unwrap();
        let report = surface.interpolant().report();
        assert!(report.max_residual.unwrap() < 1e-8, "{report:?}");
        assert!(report.merged > 0, "the circles cross at the axes");
        let mesh = assert_through(&surface, &points, 40);
        assert_eq!(mesh.genus(), Some(0));
        // Between the circles the surface stays close to the sphere.
        let worst = mesh.positions.iter().map(|p| (p.length() - r).abs()).fold(0.0, f32::max);
        assert!(worst < 0.1 * r, "off the sphere by {worst}");
        assert!(surface.field().value(Vec3::ZERO) > 0.5);
    }

    #[test]
    fn parallel_slices_with_varying_spacing() {
        // Circles of a sphere of radius 0.3 at unevenly spaced heights.
        let r = 0.3f32;
        let heights = [-0.26f32, -0.2, -0.08, -0.03, 0.0, 0.12, 0.22, 0.27];
        let mut set = ContourSet::new();
        let mut points = Vec::new();
        for &z in &heights {
            let plane = Plane::at_z(z).unwrap();
            let ring = circle((r * r - z * z).sqrt(), 32);
            points.extend(ring.iter().map(|&p| plane.point(p)));
            set.add_polylines(&plane, &[ring]).unwrap();
        }
        let surface = set.fit(&ReconstructSettings::default()).unwrap();
        let mesh = assert_through(&surface, &points, 40);
        // Within the slices' z range the surface is the sphere, also in the
        // wide gaps (0.12 .. 0.22) and (-0.2 .. -0.08).
        let within: Vec<f32> =
            mesh.positions.iter().filter(|p| p.z.abs() < 0.2).map(|p| (p.length() - r).abs()).collect();
        let worst = within.iter().fold(0.0f32, |m, &d| m.max(d));
        assert!(worst < 0.02, "off the sphere by {worst} between slices");
        // The caps round off beyond the outermost slices, near the poles.
        let top = mesh.positions.iter().map(|p| p.z).fold(f32::NEG_INFINITY, f32::max);
        assert!(top > 0.27 && top < 0.34, "top at {top}");
    }

    #[test]
    fn image_slices_and_nested_contours() {
        // A tube: an annulus (outer 0.3, hole 0.15) as images at uneven z, and
        // the same annulus as two polylines given both clockwise.
        let ring_sd = |p: Vec2| 0.075 - (p.length() - 0.225).abs();
        let image = crate::figures::raster(32, ring_sd);
        let mut set = ContourSet::new();
        for z in [0.0f32, 0.1, 0.4] {
            set.add_image(&Plane::at_z(z).unwrap(), &image, 0.5).unwrap();
        }
        let cw = |r: f32| circle(r, 32).into_iter().rev().collect::<Vec<_>>();
        set.add_polylines(&Plane::at_z(0.3).unwrap(), &[cw(0.3), cw(0.15)]).unwrap();
        // Normal constraints one pixel inward on every slice.
        let settings =
            ReconstructSettings { offset: NormalOffset::Absolute(1.0 / 32.0), ..Default::default() };
        let surface = set.fit(&settings).unwrap();
        let f = surface.field();
        for z in [0.0f32, 0.2, 0.3, 0.4] {
            assert!(f.value(Vec3::new(0.225, 0.0, z)) > 0.0, "wall at z={z}");
            assert!(f.value(Vec3::new(0.0, 0.0, z)) < 0.0, "hole at z={z}");
            assert!(f.value(Vec3::new(0.0, 0.4, z)) < 0.0, "outside at z={z}");
        }
        let mesh = surface.mesh(40).unwrap();
        assert_eq!(mesh.connected_components(), 1);
        assert_eq!(mesh.genus(), Some(1), "a tube closed at both ends is a torus");
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let degenerate = |e: Result<Plane, RbfError>| matches!(e, Err(RbfError::DegeneratePlane(_)));
        assert!(degenerate(Plane::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0)));
        assert!(degenerate(Plane::new(Vec3::ZERO, Vec3::ZERO, Vec3::Y)));
        assert!(degenerate(Plane::new(Vec3::NAN, Vec3::X, Vec3::Y)));
        assert!(degenerate(Plane::at_z(f32::INFINITY)));
        let plane = Plane::at_z(0.0).unwrap();
        let mut set = ContourSet::new();
        assert!(matches!(set.fit(&ReconstructSettings::default()), Err(RbfError::EmptyShape(_))));
        assert!(matches!(set.add_polylines(&plane, &[]), Err(RbfError::EmptyShape(_))));
        assert!(matches!(set.add_polylines(&plane, &[vec![]]), Err(RbfError::EmptyShape(_))));
        assert!(matches!(set.add_constraints(&plane, &[]), Err(RbfError::EmptyShape(_))));
        let mut bad = circle(1.0, 8);
        bad[3].y = f32::NAN;
        assert!(matches!(
            set.add_polylines(&plane, &[circle(1.0, 8), bad]),
            Err(RbfError::NonFinite { index: 11, .. })
        ));
        let two = vec![Vec2::ZERO, Vec2::X, Vec2::ZERO];
        assert!(matches!(
            set.add_polylines(&plane, &[circle(1.0, 8), two]),
            Err(RbfError::InvalidContour { contour: 1, .. })
        ));
        let flat = vec![Vec2::ZERO, Vec2::X, Vec2::X * 2.0];
        assert!(matches!(
            set.add_polylines(&plane, &[flat]),
            Err(RbfError::InvalidContour { contour: 0, .. })
        ));
        assert!(set.is_empty(), "failed calls add nothing");
        let nan = [Constraint::new([0.0, f32::NAN], 0.0)];
        assert!(matches!(set.add_constraints(&plane, &nan), Err(RbfError::NonFinite { index: 0, .. })));
        // One slice alone is coplanar: no surface is determined.
        set.add_polylines(&plane, &[circle(1.0, 8)]).unwrap();
        assert!(matches!(set.fit(&ReconstructSettings::default()), Err(RbfError::NotUnisolvent { .. })));
        let s = ReconstructSettings { offset: NormalOffset::Absolute(-1.0), ..Default::default() };
        assert!(matches!(set.fit(&s), Err(RbfError::Morph(MorphError::BadSetting { .. }))));
    }
}
