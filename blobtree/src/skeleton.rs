//! Convex skeletons (§2): points, segments, convex polygons and convex
//! polyhedra, and the L^p distance to them.
//!
//! A [`Skeleton`] is the user's description (vertex lists); a [`Polytope`]
//! is its evaluable form: the convex hull with its structure. Minkowski
//! interpolation (§3.4.1) produces polytopes of any dimension directly.
//!
//! **Distance.** The Euclidean distance (`p = 2`) is exact for every kind.
//! For `p ≠ 2` the L^p distance `min_{q∈S} ‖x − q‖_p` is computed exactly for
//! points and segments (a one-dimensional convex minimization); for polygons
//! and polyhedra it is `‖x − q₂(x)‖_p` with `q₂` the Euclidean closest point,
//! which is exact for axis-aligned boxes and rectangles (the closest points
//! coincide coordinate-wise) and an upper bound otherwise.

use crate::hull::{HullShape, convex_hull};
use glam::{DVec3, Vec3};

/// A convex skeleton in its primitive's local frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Skeleton {
    /// A point.
    Point(Vec3),
    /// A line segment between two distinct points.
    Segment(Vec3, Vec3),
    /// A convex polygon: the convex hull of coplanar vertices (≥ 3).
    Polygon(Vec<Vec3>),
    /// A convex polyhedron: the convex hull of vertices spanning 3D (≥ 4).
    Polyhedron(Vec<Vec3>),
    /// A polytope whose structure is already known (an instant of a
    /// Minkowski interpolation, §3.4.1): used as is, no hull is rebuilt.
    Generic(Polytope),
}

impl Skeleton {
    /// The axis-aligned box `[-half, half]` as a polyhedron.
    pub fn cuboid(half: Vec3) -> Self {
        let mut v = Vec::with_capacity(8);
        for i in 0..8 {
            v.push(Vec3::new(
                if i & 1 == 0 { -half.x } else { half.x },
                if i & 2 == 0 { -half.y } else { half.y },
                if i & 4 == 0 { -half.z } else { half.z },
            ));
        }
        Skeleton::Polyhedron(v)
    }

    /// The kind's name (`"point"`, `"segment"`, `"polygon"`, `"polyhedron"`).
    pub fn kind(&self) -> &'static str {
        match self {
            Skeleton::Point(_) => "point",
            Skeleton::Segment(..) => "segment",
            Skeleton::Polygon(_) => "polygon",
            Skeleton::Polyhedron(_) => "polyhedron",
            Skeleton::Generic(p) => ["point", "segment", "polygon", "polyhedron"][p.dimension()],
        }
    }

    /// The vertices as given.
    pub fn vertices(&self) -> Vec<Vec3> {
        match self {
            Skeleton::Point(p) => vec![*p],
            Skeleton::Segment(a, b) => vec![*a, *b],
            Skeleton::Polygon(v) | Skeleton::Polyhedron(v) => v.clone(),
            Skeleton::Generic(p) => p.vertices().to_vec(),
        }
    }

    /// The mean of the vertices.
    pub fn centre(&self) -> Vec3 {
        let v = self.vertices();
        v.iter().copied().sum::<Vec3>() / v.len().max(1) as f32
    }

    /// The evaluable polytope, checking the vertex count and dimension.
    ///
    /// # Errors
    /// A [`crate::NodeProblem`] for a wrong vertex count, non-finite
    /// coordinates, or a dimension that does not match the kind.
    pub fn polytope(&self) -> Result<Polytope, crate::NodeProblem> {
        use crate::NodeProblem as P;
        if let Skeleton::Generic(p) = self {
            return if p.vertices().iter().all(|v| v.is_finite()) {
                Ok(p.clone())
            } else {
                Err(P::NotFinite("vertices"))
            };
        }
        let v = self.vertices();
        if v.iter().any(|p| !p.is_finite()) {
            return Err(P::NotFinite("vertices"));
        }
        let (need, min) = match self {
            Skeleton::Point(_) => (0, 1),
            Skeleton::Segment(..) => (1, 2),
            Skeleton::Polygon(_) => (2, 3),
            Skeleton::Polyhedron(_) | Skeleton::Generic(_) => (3, 4),
        };
        if v.len() < min {
            let expected = if min == 3 { "≥ 3" } else { "≥ 4" };
            return Err(P::WrongVertexCount { kind: self.kind(), expected, got: v.len() });
        }
        let poly = Polytope::hull(&v);
        if poly.dimension() != need {
            return Err(P::WrongDimension(self.kind()));
        }
        Ok(poly)
    }
}

/// The structure of a polytope, as indices into its vertex list.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Structure {
    Point,
    Segment,
    /// Ring order counter-clockwise about `normal`.
    Polygon {
        normal: Vec3,
    },
    /// Outward triangles.
    Polyhedron {
        triangles: Vec<[u32; 3]>,
    },
}

/// A convex polytope of dimension 0–3 ready for distance queries.
#[derive(Debug, Clone, PartialEq)]
pub struct Polytope {
    vertices: Vec<Vec3>,
    structure: Structure,
    /// Outward unit normals and offsets of the solid's triangle planes
    /// (`n·x ≤ e` inside), one per triangle; zero normal for a degenerate one.
    planes: Vec<(Vec3, f32)>,
    /// Polygon: in-plane inward edge normals and offsets.
    edge_planes: Vec<(Vec3, f32)>,
    /// Set when the polyhedron is an axis-aligned box: closest points by clamping.
    aabb: Option<(Vec3, Vec3)>,
}

impl Polytope {
    /// The convex hull of `points` (non-empty, finite).
    pub fn hull(points: &[Vec3]) -> Self {
        let dp: Vec<DVec3> = points.iter().map(|p| p.as_dvec3()).collect();
        let h = convex_hull(&dp);
        Self::from_hull(&h, |i| points[i]).0
    }

    /// A polytope from a hull structure over vertices given by `vertex(i)`
    /// (the hull's indices are renumbered to the vertex list).
    /// Also returns, for each polytope vertex, the hull input index it came from.
    pub(crate) fn from_hull(h: &HullShape, vertex: impl Fn(usize) -> Vec3) -> (Self, Vec<usize>) {
        let used = h.vertices();
        let map = |i: usize| used.binary_search(&i).expect("hull vertex") as u32;
        let structure = match h {
            HullShape::Point(_) => (Structure::Point, Vec::new()),
            HullShape::Segment(i, j) => (Structure::Segment, vec![*i, *j]),
            HullShape::Polygon { ring, normal } => {
                (Structure::Polygon { normal: normal.as_vec3() }, ring.clone())
            }
            HullShape::Polyhedron { triangles } => (
                Structure::Polyhedron { triangles: triangles.iter().map(|t| t.map(map)).collect() },
                Vec::new(),
            ),
        };
        // Segment and polygon keep their hull order.
        let order: Vec<usize> = if structure.1.is_empty() { used.clone() } else { structure.1 };
        let structure = match structure.0 {
            Structure::Polyhedron { triangles } => {
                // Triangles index `used`; vertices are listed in `used` order.
                Structure::Polyhedron { triangles }
            }
            s => s,
        };
        let vertices = order.iter().map(|&i| vertex(i)).collect();
        (Self::with_structure(vertices, structure), order)
    }

    /// Rebuilds the derived planes for the given vertex positions.
    pub(crate) fn with_structure(vertices: Vec<Vec3>, structure: Structure) -> Self {
        let mut p = Self { vertices, structure, planes: Vec::new(), edge_planes: Vec::new(), aabb: None };
        match &p.structure {
            Structure::Polyhedron { triangles } => {
                for t in triangles {
                    let [a, b, c] = t.map(|i| p.vertices[i as usize]);
                    let n = (b - a).cross(c - a);
                    let len = n.length();
                    if len > 1e-12 {
                        let n = n / len;
                        p.planes.push((n, n.dot(a)));
                    } else {
                        p.planes.push((Vec3::ZERO, 0.0));
                    }
                }
                let (lo, hi) = (p.bounds().min, p.bounds().max);
                let on_corner = |v: &Vec3| (0..3).all(|k| v[k] == lo[k] || v[k] == hi[k]);
                if p.vertices.len() == 8 && p.vertices.iter().all(on_corner) {
                    p.aabb = Some((lo, hi));
                }
            }
            Structure::Polygon { normal } => {
                let m = p.vertices.len();
                for i in 0..m {
                    let (a, b) = (p.vertices[i], p.vertices[(i + 1) % m]);
                    let inward = normal.cross(b - a).normalize_or_zero();
                    p.edge_planes.push((inward, inward.dot(a)));
                }
            }
            _ => {}
        }
        p
    }

    /// The vertices (hull vertices only; segment and polygon in boundary order).
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// The same structure with moved vertices (same count and order).
    pub(crate) fn moved(&self, vertices: Vec<Vec3>) -> Self {
        Self::with_structure(vertices, self.structure.clone())
    }

    /// The affine dimension: 0 point, 1 segment, 2 polygon, 3 polyhedron.
    pub fn dimension(&self) -> usize {
        match self.structure {
            Structure::Point => 0,
            Structure::Segment => 1,
            Structure::Polygon { .. } => 2,
            Structure::Polyhedron { .. } => 3,
        }
    }

    /// The support point in direction `u`: `argmax_{x∈S} u·x`.
    pub fn support(&self, u: Vec3) -> Vec3 {
        self.vertices.iter().copied().max_by(|a, b| a.dot(u).total_cmp(&b.dot(u))).unwrap_or(Vec3::ZERO)
    }

    /// The box of the vertices.
    pub fn bounds(&self) -> isomorph_common::Aabb {
        isomorph_common::Aabb::from_points(&self.vertices)
    }

    /// The Euclidean closest point of the polytope to `x`.
    pub fn closest_point(&self, x: Vec3) -> Vec3 {
        let v = &self.vertices;
        match &self.structure {
            Structure::Point => v[0],
            Structure::Segment => closest_on_segment(x, v[0], v[1]),
            Structure::Polygon { normal } => {
                let proj = x - *normal * (x - v[0]).dot(*normal);
                if self.edge_planes.iter().all(|(n, e)| n.dot(proj) >= *e - 1e-7) {
                    return proj;
                }
                // Outside: the closest point is on an edge whose half-plane
                // excludes the projection (same normal-cone argument as below).
                let m = v.len();
                let mut best = v[0];
                let mut best_d = f32::INFINITY;
                for (i, (n, e)) in self.edge_planes.iter().enumerate() {
                    if n.dot(proj) >= *e && *n != Vec3::ZERO {
                        continue;
                    }
                    let q = closest_on_segment(x, v[i], v[(i + 1) % m]);
                    let d = (q - x).length_squared();
                    if d < best_d {
                        best_d = d;
                        best = q;
                    }
                }
                best
            }
            Structure::Polyhedron { triangles } => {
                if let Some((lo, hi)) = self.aabb {
                    return x.clamp(lo, hi);
                }
                if self.planes.iter().all(|(n, e)| n.dot(x) <= *e) {
                    return x;
                }
                // The closest point lies on a triangle whose plane has `x` in
                // front (its normal cone contains x − q), and no triangle is
                // closer than its plane: skip the others.
                let mut best = v[0];
                let mut best_d = f32::INFINITY;
                for (t, (n, e)) in triangles.iter().zip(&self.planes) {
                    let front = n.dot(x) - e;
                    let degenerate = *n == Vec3::ZERO;
                    if !degenerate && (front <= 0.0 || front * front >= best_d) {
                        continue;
                    }
                    let [a, b, c] = t.map(|i| v[i as usize]);
                    let q = closest_on_triangle(x, a, b, c);
                    let d = (q - x).length_squared();
                    if d < best_d {
                        best_d = d;
                        best = q;
                    }
                }
                best
            }
        }
    }

    /// The L^p distance from `x` (see the module docs for exactness) and its
    /// gradient with respect to `x` (zero inside the skeleton).
    ///
    /// The gradient is analytic (`∇‖x − q‖_p` at the closest point `q`) for
    /// `p = 2` and for points; for other skeletons with `p ≠ 2` the L^p
    /// closest point need not be unique (flat optima of `p = ∞`), so the
    /// gradient is taken by central differences of the distance (step 1e-4).
    pub fn distance(&self, x: Vec3, p: f32) -> (f32, Vec3) {
        if p == 2.0 || matches!(self.structure, Structure::Point) {
            let r = x - self.closest_point(x);
            return (lp_norm(r, p), lp_norm_gradient(r, p));
        }
        let d = self.lp_distance(x, p);
        let h = 1e-4;
        let g = Vec3::new(
            self.lp_distance(x + Vec3::X * h, p) - self.lp_distance(x - Vec3::X * h, p),
            self.lp_distance(x + Vec3::Y * h, p) - self.lp_distance(x - Vec3::Y * h, p),
            self.lp_distance(x + Vec3::Z * h, p) - self.lp_distance(x - Vec3::Z * h, p),
        ) / (2.0 * h);
        (d, g)
    }

    /// The L^p distance alone (see the module docs for exactness).
    pub fn lp_distance(&self, x: Vec3, p: f32) -> f32 {
        let q = match self.structure {
            Structure::Segment if p != 2.0 => lp_closest_on_segment(x, self.vertices[0], self.vertices[1], p),
            _ => self.closest_point(x),
        };
        lp_norm(x - q, p)
    }
}

/// `‖v‖_p` for `p ∈ [1, ∞]`.
#[inline]
pub fn lp_norm(v: Vec3, p: f32) -> f32 {
    let a = v.abs();
    if p == 2.0 {
        v.length()
    } else if p == 1.0 {
        a.x + a.y + a.z
    } else if p.is_infinite() {
        a.max_element()
    } else {
        let m = a.max_element();
        if m == 0.0 {
            return 0.0;
        }
        let s = a / m;
        // Integer exponents (common: interpolating 2 → ∞ passes p = 4) use powi.
        let sum = if p == p.round() && p <= 16.0 {
            let k = p as i32;
            s.x.powi(k) + s.y.powi(k) + s.z.powi(k)
        } else {
            s.x.powf(p) + s.y.powf(p) + s.z.powf(p)
        };
        m * sum.powf(1.0 / p)
    }
}

/// Gradient of `‖v‖_p` (zero at `v = 0`).
#[inline]
fn lp_norm_gradient(v: Vec3, p: f32) -> Vec3 {
    if v == Vec3::ZERO {
        return Vec3::ZERO;
    }
    if p == 2.0 {
        v / v.length()
    } else if p == 1.0 {
        v.signum() * v.abs().cmpgt(Vec3::ZERO).into_f32()
    } else if p.is_infinite() {
        let a = v.abs();
        let m = a.max_element();
        let k = if a.x == m {
            0
        } else if a.y == m {
            1
        } else {
            2
        };
        let mut g = Vec3::ZERO;
        g[k] = v[k].signum();
        g
    } else {
        let n = lp_norm(v, p);
        let s = v.abs() / n;
        v.signum() * Vec3::new(s.x.powf(p - 1.0), s.y.powf(p - 1.0), s.z.powf(p - 1.0))
    }
}

trait IntoF32 {
    fn into_f32(self) -> Vec3;
}
impl IntoF32 for glam::BVec3 {
    fn into_f32(self) -> Vec3 {
        Vec3::new(self.x as u8 as f32, self.y as u8 as f32, self.z as u8 as f32)
    }
}

fn closest_on_segment(x: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let e = b - a;
    let l2 = e.length_squared();
    if l2 <= 0.0 {
        return a;
    }
    a + e * ((x - a).dot(e) / l2).clamp(0.0, 1.0)
}

/// Exact L^p closest point on a segment: `‖x − a − t e‖_p` is convex in `t`,
/// minimized by golden-section search over `[0, 1]`.
fn lp_closest_on_segment(x: Vec3, a: Vec3, b: Vec3, p: f32) -> Vec3 {
    let e = b - a;
    let f = |t: f32| lp_norm(x - a - e * t, p);
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    const G: f32 = 0.618_034;
    let mut c = hi - G * (hi - lo);
    let mut d = lo + G * (hi - lo);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..40 {
        if fc <= fd {
            hi = d;
            d = c;
            fd = fc;
            c = hi - G * (hi - lo);
            fc = f(c);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + G * (hi - lo);
            fd = f(d);
        }
    }
    let mid = 0.5 * (lo + hi);
    // The ends may be better when the minimum sits on the boundary.
    let best = [0.0, mid, 1.0].into_iter().min_by(|s, t| f(*s).total_cmp(&f(*t))).unwrap_or(mid);
    a + e * best
}

/// Closest point on triangle `abc` (Ericson, *Real-Time Collision Detection* §5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        // Degenerate triangle: closest of its edges.
        return [closest_on_segment(p, a, b), closest_on_segment(p, b, c), closest_on_segment(p, a, c)]
            .into_iter()
            .min_by(|s, t| (*s - p).length_squared().total_cmp(&(*t - p).length_squared()))
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: distance to a dense sampling of the convex hull (convex
    /// combinations of the vertices on a lattice of barycentric weights).
    fn brute(verts: &[Vec3], x: Vec3, p: f32) -> f32 {
        let n = verts.len();
        let mut best = f32::INFINITY;
        let mut state = 12345u64;
        for _ in 0..60_000 {
            let mut w: Vec<f32> = (0..n)
                .map(|_| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    let u = ((state >> 33) as f32) / (1u64 << 31) as f32;
                    u.powi(4)
                })
                .collect();
            let s: f32 = w.iter().sum();
            w.iter_mut().for_each(|v| *v /= s);
            let q: Vec3 = verts.iter().zip(&w).map(|(v, w)| *v * *w).sum();
            best = best.min(lp_norm(x - q, p));
        }
        for v in verts {
            best = best.min(lp_norm(x - *v, p));
        }
        best
    }

    #[test]
    fn closed_forms() {
        let pt = Skeleton::Point(Vec3::new(1.0, 2.0, 3.0)).polytope().unwrap();
        assert!((pt.distance(Vec3::new(1.0, 2.0, 5.0), 2.0).0 - 2.0).abs() < 1e-6);
        assert!((pt.distance(Vec3::new(2.0, 3.0, 4.0), 1.0).0 - 3.0).abs() < 1e-6);
        assert!((pt.distance(Vec3::new(2.0, 4.0, 3.5), f32::INFINITY).0 - 2.0).abs() < 1e-6);
        let seg = Skeleton::Segment(Vec3::ZERO, Vec3::X * 2.0).polytope().unwrap();
        assert!((seg.distance(Vec3::new(1.0, 3.0, 4.0), 2.0).0 - 5.0).abs() < 1e-6);
        assert!((seg.distance(Vec3::new(-3.0, 0.0, 4.0), 2.0).0 - 5.0).abs() < 1e-6);
        let cube = Skeleton::cuboid(Vec3::ONE).polytope().unwrap();
        assert_eq!(cube.distance(Vec3::new(0.3, -0.2, 0.9), 2.0).0, 0.0);
        assert!((cube.distance(Vec3::new(2.0, 3.0, 0.0), 2.0).0 - 5f32.sqrt()).abs() < 1e-6);
        assert!((cube.distance(Vec3::new(2.0, 3.0, 0.0), f32::INFINITY).0 - 2.0).abs() < 1e-6);
        assert!((cube.distance(Vec3::new(2.0, 3.0, 0.0), 1.0).0 - 3.0).abs() < 1e-6);
        let tri = Skeleton::Polygon(vec![Vec3::ZERO, Vec3::X, Vec3::Y]).polytope().unwrap();
        assert!((tri.distance(Vec3::new(0.2, 0.2, -0.7), 2.0).0 - 0.7).abs() < 1e-6);
    }

    #[test]
    fn euclidean_distances_match_brute_force() {
        let tet =
            vec![Vec3::ZERO, Vec3::new(1.0, 0.2, 0.0), Vec3::new(0.3, 1.0, 0.1), Vec3::new(0.2, 0.3, 1.2)];
        let quad = vec![
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, -1.0, 0.2),
            Vec3::new(1.0, 0.0, 0.4),
            Vec3::new(0.0, 1.0, 0.2),
        ];
        let seg = vec![Vec3::new(-1.0, 0.5, 0.0), Vec3::new(1.0, -0.5, 0.3)];
        let xs = [
            Vec3::new(2.0, 0.5, 0.1),
            Vec3::new(-0.5, -0.6, 1.5),
            Vec3::new(0.3, 0.3, -1.0),
            Vec3::new(0.1, 0.1, 0.1),
        ];
        for verts in [&tet, &quad, &seg] {
            let poly = Polytope::hull(verts);
            for &x in &xs {
                let d = poly.distance(x, 2.0).0;
                let b = brute(verts, x, 2.0);
                assert!(d <= b + 1e-5 && b - d < 2e-2, "{verts:?} at {x}: {d} vs brute {b}");
            }
        }
        // Exact L^p on an oblique segment.
        let poly = Polytope::hull(&seg);
        for &p in &[1.0f32, 1.5, 3.0, f32::INFINITY] {
            for &x in &xs {
                let d = poly.distance(x, p).0;
                let b = brute(&seg, x, p);
                assert!(d <= b + 1e-4 && b - d < 2e-2, "p={p} at {x}: {d} vs brute {b}");
            }
        }
    }

    #[test]
    fn distance_gradients_match_differences() {
        let poly = Polytope::hull(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]);
        for &p in &[2.0f32, 3.0] {
            let x = Vec3::new(0.9, 0.8, -0.4);
            let (_, g) = poly.distance(x, p);
            let h = 1e-3;
            let fd = Vec3::new(
                poly.distance(x + Vec3::X * h, p).0 - poly.distance(x - Vec3::X * h, p).0,
                poly.distance(x + Vec3::Y * h, p).0 - poly.distance(x - Vec3::Y * h, p).0,
                poly.distance(x + Vec3::Z * h, p).0 - poly.distance(x - Vec3::Z * h, p).0,
            ) / (2.0 * h);
            assert!((g - fd).length() < 1e-2, "p={p}: {g} vs {fd}");
        }
    }

    #[test]
    fn wrong_skeletons_are_rejected() {
        assert!(Skeleton::Segment(Vec3::ONE, Vec3::ONE).polytope().is_err());
        assert!(Skeleton::Polygon(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]).polytope().is_err());
        assert!(
            Skeleton::Polyhedron(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE.with_z(0.0)])
                .polytope()
                .is_err()
        );
        assert!(Skeleton::Point(Vec3::NAN).polytope().is_err());
        assert!(Skeleton::Polygon(vec![Vec3::ZERO, Vec3::X]).polytope().is_err());
    }
}
