//! Automatic coplanar frames (§3.4, Figs. 10–11): local frames for a
//! matched pair of flat skeletons that put both in the local plane `z = 0`,
//! so that their Minkowski interpolation stays flat.

use crate::node::Primitive;
use crate::skeleton::Skeleton;
use glam::{Affine3A, Mat3, Quat, Vec3};
use isomorph_common::AffineParts;

/// A skeleton's vertices in world space, with the frame's uniform scale.
struct Placed {
    /// World vertices.
    vertices: Vec<Vec3>,
    /// The frame's scale (kept, so that radii keep their meaning).
    scale: f32,
}

impl Placed {
    /// `None` unless the frame is a similarity (then distances map exactly).
    fn of(p: &Primitive) -> Option<Self> {
        let parts = AffineParts::from_affine(&p.frame).ok()?;
        let scale = parts.stretch.x_axis.x;
        let uniform = Mat3::from_diagonal(Vec3::splat(scale));
        if !parts.stretch.abs_diff_eq(uniform, 1e-6 * scale.abs().max(1.0)) {
            return None;
        }
        let vertices = p.skeleton.vertices().iter().map(|&v| p.frame.transform_point3(v)).collect();
        Some(Self { vertices, scale })
    }

    fn centre(&self) -> Vec3 {
        self.vertices.iter().copied().sum::<Vec3>() / self.vertices.len() as f32
    }

    /// The unit direction of a segment, or of a polygon's principal axis.
    fn axis(&self) -> Vec3 {
        let c = self.centre();
        let mut cov = Mat3::ZERO;
        for v in &self.vertices {
            let d = *v - c;
            cov += Mat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        // Power iteration from the longest offset: the principal axis.
        let longest = self
            .vertices
            .iter()
            .map(|v| *v - c)
            .fold(Vec3::ZERO, |a, d| if d.length_squared() > a.length_squared() { d } else { a });
        let mut x = longest.try_normalize().unwrap_or(Vec3::X);
        for _ in 0..64 {
            x = (cov * x).try_normalize().unwrap_or(x);
        }
        x
    }

    /// A polygon's unit normal (`None` for lower dimensions).
    fn normal(&self, dimension: usize) -> Option<Vec3> {
        if dimension != 2 {
            return None;
        }
        let c = self.centre();
        let mut n = Vec3::ZERO;
        for (i, v) in self.vertices.iter().enumerate() {
            let w = self.vertices[(i + 1) % self.vertices.len()];
            n += (*v - c).cross(w - c);
        }
        n.try_normalize()
    }
}

/// The rotation whose local x axis is `x` and local z axis is (nearly) `z`.
fn basis(x: Vec3, z: Vec3) -> Quat {
    let z = (z - x * x.dot(z)).try_normalize().unwrap_or_else(|| x.any_orthonormal_vector());
    Quat::from_mat3(&Mat3::from_cols(x, z.cross(x), z)).normalize()
}

/// `p` re-expressed in the frame `T(centre) · rotation · scale` (the same field).
fn reframed(p: &Primitive, placed: &Placed, rotation: Quat) -> Primitive {
    let frame =
        Affine3A::from_scale_rotation_translation(Vec3::splat(placed.scale), rotation, placed.centre());
    let to_local = frame.inverse();
    let local: Vec<Vec3> = placed.vertices.iter().map(|&v| to_local.transform_point3(v)).collect();
    let skeleton = match local.as_slice() {
        [v] => Skeleton::Point(*v),
        [a, b] => Skeleton::Segment(*a, *b),
        _ => Skeleton::Polygon(local),
    };
    Primitive { skeleton, kernel: p.kernel, p: p.p, frame }
}

/// Frames for the matched primitives `a` and `b` in which both skeletons
/// lie in the local plane `z = 0`, centred on their centroids, x along a
/// segment or a polygon's principal axis, signs chosen for the least
/// rotation from `a` to `b`: two segments then stay a segment (turning in
/// the plane they span), a segment and a polygon, or two polygons, a
/// polygon — never a "deforming polyhedron" (Fig. 11). A point takes its
/// partner's orientation, so it does not spin.
///
/// `None` (keep the given frames) unless both skeletons have dimension ≤ 2,
/// at least one has dimension ≥ 1, both use the Euclidean metric (an L^p
/// distance depends on the axes) and both frames are similarities (so the
/// re-expressed primitives have exactly the same fields up to rounding).
pub(crate) fn coplanar_frames(a: &Primitive, b: &Primitive) -> Option<(Primitive, Primitive)> {
    let (da, db) = (a.skeleton.polytope().ok()?.dimension(), b.skeleton.polytope().ok()?.dimension());
    if da > 2 || db > 2 || da.max(db) == 0 || a.p != 2.0 || b.p != 2.0 {
        return None;
    }
    let (pa, pb) = (Placed::of(a)?, Placed::of(b)?);
    let (na, nb) = (pa.normal(da), pb.normal(db));
    let (xa, xb) = (pa.axis(), pb.axis());
    // A common plane normal where a side has none (a segment's is free).
    let cross = xa.cross(xb).try_normalize();
    let za = na.or(nb).or(cross).unwrap_or_else(|| xa.any_orthonormal_vector());
    let mut zb = nb.or(na).or(cross).unwrap_or(za);
    if zb.dot(za) < 0.0 {
        zb = -zb;
    }
    let mut xb = xb;
    if xb.dot(xa) < 0.0 {
        xb = -xb;
    }
    let (ra, rb) = match (da, db) {
        (0, _) => (basis(xb, zb), basis(xb, zb)),
        (_, 0) => (basis(xa, za), basis(xa, za)),
        _ => (basis(xa, za), basis(xb, zb)),
    };
    Some((reframed(a, &pa, ra), reframed(b, &pb, rb)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Kernel;

    fn prim(skeleton: Skeleton, frame: Affine3A) -> Primitive {
        Primitive::new(skeleton, Kernel::new(1.0, 0.5, 1.0)).with_frame(frame)
    }

    /// Re-expressed primitives have the same field, in the local plane z = 0.
    #[test]
    fn reframed_primitives_keep_their_fields_and_lie_flat() {
        let frame = Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.5),
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
            Vec3::new(0.2, -0.1, 0.4),
        );
        let seg = prim(Skeleton::Segment(Vec3::ZERO, Vec3::new(0.3, 0.2, 0.1)), frame);
        let tri = prim(
            Skeleton::Polygon(vec![Vec3::ZERO, Vec3::new(0.4, 0.0, 0.1), Vec3::new(0.0, 0.3, -0.2)]),
            Affine3A::from_rotation_x(0.8),
        );
        let (a, b) = coplanar_frames(&seg, &tri).unwrap();
        for (before, after) in [(&seg, &a), (&tri, &b)] {
            assert!(after.skeleton.vertices().iter().all(|v| v.z.abs() < 1e-5), "{after:?}");
            let t0 = crate::BlobTree::new(crate::Node::Primitive(before.clone()), 0.5).unwrap();
            let t1 = crate::BlobTree::new(crate::Node::Primitive(after.clone()), 0.5).unwrap();
            for i in 0..300 {
                let p = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
                assert!((t0.potential(p) - t1.potential(p)).abs() < 1e-5, "at {p}");
            }
        }
        // Not for an L^∞ metric or a polyhedron.
        assert!(coplanar_frames(&seg.clone().with_p(f32::INFINITY), &tri).is_none());
        assert!(
            coplanar_frames(&prim(Skeleton::cuboid(Vec3::splat(0.2)), Affine3A::IDENTITY), &tri).is_none()
        );
    }
}
