//! Convex hulls of small point sets of any affine dimension (0–3), in `f64`.
//!
//! Used to build convex skeletons from vertex lists and the *generic
//! topology* of Minkowski sums (§3.4.1): the hull of the candidate vertices
//! `a_i + b_j`, built once. Point sets are tens of points, so a simple
//! incremental hull (O(n²)) with a relative tolerance is the robust choice.

use glam::{DVec2, DVec3};

/// The combinatorial structure of a convex hull, as indices into the input.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum HullShape {
    /// All points coincide.
    Point(usize),
    /// All points on a line: the two extreme points.
    Segment(usize, usize),
    /// All points in a plane: the boundary ring, counter-clockwise about `normal`.
    Polygon {
        /// Vertex indices in order.
        ring: Vec<usize>,
        /// Unit normal of the plane.
        normal: DVec3,
    },
    /// A solid: outward-oriented boundary triangles.
    Polyhedron {
        /// Triangles (counter-clockwise seen from outside).
        triangles: Vec<[usize; 3]>,
    },
}

impl HullShape {
    /// The indices of the hull's vertices (sorted, unique).
    pub(crate) fn vertices(&self) -> Vec<usize> {
        let mut v: Vec<usize> = match self {
            HullShape::Point(i) => vec![*i],
            HullShape::Segment(i, j) => vec![*i, *j],
            HullShape::Polygon { ring, .. } => ring.clone(),
            HullShape::Polyhedron { triangles } => triangles.iter().flatten().copied().collect(),
        };
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The affine dimension (0 to 3).
    #[cfg(test)]
    fn dimension(&self) -> usize {
        match self {
            HullShape::Point(_) => 0,
            HullShape::Segment(..) => 1,
            HullShape::Polygon { .. } => 2,
            HullShape::Polyhedron { .. } => 3,
        }
    }
}

/// The convex hull of `points` (must be non-empty and finite). Points within
/// `1e-6 ×` (about ten f32 roundings) the set's diameter of a lower-dimensional flat are treated as lying on it.
pub(crate) fn convex_hull(points: &[DVec3]) -> HullShape {
    let far_from = |q: DVec3| -> (usize, f64) {
        points
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (*p - q).length()))
            .fold((0, -1.0), |best, c| if c.1 > best.1 { c } else { best })
    };
    let (i1, diam) = far_from(points[0]);
    let eps = 1e-6 * diam.max(1e-30);
    if diam <= 1e-12 {
        return HullShape::Point(0);
    }
    let (i0, _) = far_from(points[i1]);
    let (p0, p1) = (points[i0], points[i1]);
    let dir = (p1 - p0).normalize();
    let off_line = |p: DVec3| {
        let v = p - p0;
        (v - dir * v.dot(dir)).length()
    };
    let (i2, d2) = points
        .iter()
        .enumerate()
        .map(|(i, p)| (i, off_line(*p)))
        .fold((0, -1.0), |b, c| if c.1 > b.1 { c } else { b });
    if d2 <= eps {
        return HullShape::Segment(i0, i1);
    }
    let normal = (p1 - p0).cross(points[i2] - p0).normalize();
    let (i3, d3) = points
        .iter()
        .enumerate()
        .map(|(i, p)| (i, (*p - p0).dot(normal).abs()))
        .fold((0, -1.0), |b, c| if c.1 > b.1 { c } else { b });
    if d3 <= eps {
        return polygon_hull(points, p0, dir, normal, eps);
    }
    HullShape::Polyhedron { triangles: solid_hull(points, [i0, i1, i2, i3], eps) }
}

/// Andrew's monotone chain in the plane through `origin` spanned by `u` and `normal × u`.
fn polygon_hull(points: &[DVec3], origin: DVec3, u: DVec3, normal: DVec3, eps: f64) -> HullShape {
    let v = normal.cross(u);
    let mut pts: Vec<(DVec2, usize)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (DVec2::new((*p - origin).dot(u), (*p - origin).dot(v)), i))
        .collect();
    pts.sort_by(|a, b| a.0.x.total_cmp(&b.0.x).then(a.0.y.total_cmp(&b.0.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut ring: Vec<(DVec2, usize)> = Vec::new();
    for pass in 0..2 {
        let start = ring.len();
        let iter: Box<dyn Iterator<Item = &(DVec2, usize)>> =
            if pass == 0 { Box::new(pts.iter()) } else { Box::new(pts.iter().rev()) };
        for &p in iter {
            while ring.len() >= start + 2
                && cross(ring[ring.len() - 2].0, ring[ring.len() - 1].0, p.0) <= eps * eps * 1e6
            {
                ring.pop();
            }
            ring.push(p);
        }
        ring.pop();
    }
    HullShape::Polygon { ring: ring.into_iter().map(|(_, i)| i).collect(), normal }
}

/// Incremental 3D hull starting from a non-degenerate tetrahedron.
fn solid_hull(points: &[DVec3], seed: [usize; 4], eps: f64) -> Vec<[usize; 3]> {
    let [a, b, c, d] = seed;
    let centroid = (points[a] + points[b] + points[c] + points[d]) / 4.0;
    let orient = |t: [usize; 3]| -> [usize; 3] {
        let n = (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]);
        if n.dot(points[t[0]] - centroid) < 0.0 { [t[0], t[2], t[1]] } else { t }
    };
    let mut faces: Vec<[usize; 3]> =
        vec![orient([a, b, c]), orient([a, b, d]), orient([a, c, d]), orient([b, c, d])];
    let plane_distance = |f: &[usize; 3], p: DVec3| {
        let n = (points[f[1]] - points[f[0]]).cross(points[f[2]] - points[f[0]]);
        let len = n.length();
        if len <= 0.0 { 0.0 } else { (p - points[f[0]]).dot(n) / len }
    };
    for (i, &p) in points.iter().enumerate() {
        if seed.contains(&i) {
            continue;
        }
        let visible: Vec<bool> = faces.iter().map(|f| plane_distance(f, p) > eps).collect();
        if !visible.iter().any(|&v| v) {
            continue;
        }
        let mut edges = std::collections::HashSet::new();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, v)| **v) {
            for e in 0..3 {
                edges.insert((f[e], f[(e + 1) % 3]));
            }
        }
        let mut next: Vec<[usize; 3]> =
            faces.iter().zip(&visible).filter(|(_, v)| !**v).map(|(f, _)| *f).collect();
        for &(u, w) in &edges {
            if !edges.contains(&(w, u)) {
                next.push([u, w, i]);
            }
        }
        faces = next;
    }
    faces
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_hull_has_eight_vertices_and_twelve_triangles() {
        let mut pts = Vec::new();
        for i in 0..8 {
            pts.push(DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64));
        }
        pts.push(DVec3::splat(0.5)); // interior
        pts.push(DVec3::new(0.5, 0.5, 1.0)); // on a face
        let h = convex_hull(&pts);
        assert_eq!(h.vertices(), (0..8).collect::<Vec<_>>());
        let HullShape::Polyhedron { triangles } = h else { panic!("not solid") };
        assert_eq!(triangles.len(), 12);
        // Every triangle faces outward: the centre is behind every face.
        for t in &triangles {
            let n = (pts[t[1]] - pts[t[0]]).cross(pts[t[2]] - pts[t[0]]);
            assert!(n.dot(DVec3::splat(0.5) - pts[t[0]]) < 0.0);
        }
    }

    #[test]
    fn lower_dimensions_are_detected() {
        assert_eq!(convex_hull(&[DVec3::ONE, DVec3::ONE]).dimension(), 0);
        let seg = convex_hull(&[DVec3::ZERO, DVec3::X * 0.5, DVec3::X]);
        assert_eq!(seg.vertices(), vec![0, 2]);
        let square = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.5, 0.5, 0.0)];
        let h = convex_hull(&square);
        assert_eq!(h.dimension(), 2);
        assert_eq!(h.vertices(), vec![0, 1, 2, 3]);
    }
}
