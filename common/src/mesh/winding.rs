//! Generalized winding numbers of triangle meshes and soups
//! ([`WindingNumber`]): an inside test that stays sensible on open,
//! unwelded, self-intersecting or inconsistently tessellated meshes.
//!
//! The winding number of a point `q` is the signed solid angle the mesh
//! subtends at `q`, divided by `4π` (Jacobson, Kavan & Sorkine-Hornung,
//! *Robust inside-outside segmentation using generalized winding numbers*,
//! SIGGRAPH 2013). For a closed, consistently oriented mesh it is the integer
//! number of times the surface wraps around `q`: 1 inside, 0 outside (with
//! counter-clockwise-from-outside triangles, the convention of
//! [`TriMesh`]). For a mesh with holes it varies smoothly across the holes
//! and remains near 1 deep inside and near 0 far outside, so thresholding at
//! ½ gives a plausible inside.
//!
//! # Evaluation
//! One triangle's solid angle is exact by Van Oosterom & Strackee's formula
//! (IEEE TBME 1983). Summing all of them costs one `atan2` per triangle per
//! query, so [`WindingNumber`] uses the hierarchical approximation of Barill,
//! Dickson, Schmidt, Levin & Jacobson, *Fast winding numbers for soups and
//! clouds* (SIGGRAPH 2018): a tree over the triangles stores, per node, the
//! Taylor expansion of the node's solid-angle integrand about its
//! area-weighted centroid up to second order (a dipole, a 3×3 and a 3×3×3
//! moment). A node whose bounding sphere of radius `r` is farther than
//! `β · r` from the query ([`WindingNumber::with_accuracy`], default
//! [`DEFAULT_BETA`] = 2) is evaluated by its expansion, whose error decays
//! like `β⁻⁴`; nearer nodes are opened, and leaves are summed exactly. The
//! result is exact up to rounding near the surface, where it matters for the
//! inside test, and within a few 10⁻³ of the exact sum elsewhere at the
//! default β (measured: 1.7·10⁻³ on the bunny, 3·10⁻⁴ at β = 3, 6·10⁻⁵ at β = 4).
//!
//! # Scale
//! The winding number does not depend on the mesh's size, and neither does
//! its evaluation: [`WindingNumber::new`] multiplies the corners by a power
//! of two that brings the largest coordinate near 1 (exact: only the
//! exponent changes), and every query by the same factor. The exact solid
//! angle is computed in `f64`, whose range holds the cubes of any `f32`
//! lengths. So a mesh at 10³⁰ or 10⁻⁴⁰ has the same winding numbers as its
//! unit-size copy. A query too far away to express in that frame (farther
//! from the origin than 2⁶⁰ times the mesh's largest coordinate) has winding
//! number 0, as the sum would be far below `f32` resolution there.
//!
//! # Example
//! ```
//! use isomorph_common::mesh::winding::WindingNumber;
//! use isomorph_common::{TriMesh, glam::Vec3};
//!
//! // A tetrahedron, counter-clockwise seen from outside.
//! let mesh = TriMesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//! )?;
//! let wn = WindingNumber::new(&mesh);
//! assert!((wn.winding_number(Vec3::splat(0.2)) - 1.0).abs() < 1e-5);
//! assert!(wn.winding_number(Vec3::splat(2.0)).abs() < 1e-5);
//! assert!(wn.is_inside(Vec3::splat(0.1)) && !wn.is_inside(Vec3::new(-0.1, 0.2, 0.2)));
//! # Ok::<(), isomorph_common::MeshError>(())
//! ```

use crate::TriMesh;
use glam::{Mat3, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// Default accuracy parameter β: a node is expanded when the query is
/// farther than `β` times its bounding radius (Barill et al. use 2).
pub const DEFAULT_BETA: f32 = 2.0;
/// Most triangles in one leaf of the tree.
const LEAF_SIZE: usize = 8;
/// Traversal stack size; the median-split tree has depth ≤ log2(n) + 1.
const STACK: usize = 64;
/// Queries per work item of the batch evaluation.
const CHUNK: usize = 256;
/// Queries farther than this from the origin of the normalized frame (where
/// the mesh lies within 4 units of the origin) have winding number 0: the
/// true value is below `n_triangles · 2⁻¹¹⁰` there, and squared distances
/// would overflow `f32` beyond 2⁶³.
const FAR: f32 = 1_152_921_504_606_846_976.0; // 2⁶⁰

/// Signed solid angle of the triangle `abc` seen from the origin (corners
/// given relative to the query), by Van Oosterom & Strackee; positive when
/// the query is on the side opposite the right-hand normal. In `(-2π, 2π)`;
/// zero for a query in the triangle's plane (so a point on a smooth surface
/// gets winding number ½).
///
/// Computed in `f64`, which holds the cubic products of any finite `f32`
/// corners without overflow or underflow, so the result depends only on the
/// directions of `a`, `b`, `c`, whatever their magnitude.
#[inline]
pub fn solid_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let det = a.dot(b.cross(c));
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    // Within the rounding of the f32 offsets from the plane, the sign of
    // `det` is noise.
    if det.abs() <= 8.0 * f64::from(f32::EPSILON) * la * lb * lc {
        return 0.0;
    }
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    (2.0 * det.atan2(den)) as f32
}

/// A node of the expansion tree: bounding sphere, Taylor coefficients and
/// either children `first, first + 1` (`count == 0`) or the triangles
/// `first .. first + count` (in tree order).
#[derive(Debug, Clone, Copy)]
struct Node {
    /// Expansion centre: the area-weighted centroid of the node's triangles.
    center: Vec3,
    /// Largest distance from `center` to a corner of the node's triangles,
    /// times β (so the far test is one comparison).
    far_radius: f32,
    /// Order 0 of the integrand's expansion: `Σ aₜ nₜ` (half the sum of the
    /// triangles' cross products).
    dipole: Vec3,
    /// Order 1: `M[i][j] = Σ aₜ nₜᵢ (cₜ − center)ⱼ` (`Mat3` columns are `j`).
    first_moment: Mat3,
    /// Order 2: `S_i = Σ nₜᵢ ∫ₜ (x − center)(x − center)ᵀ dA`, one symmetric
    /// matrix per normal component `i`.
    second_moment: [Mat3; 3],
    first: u32,
    count: u32,
}

/// Generalized winding number of a triangle mesh or soup, with a
/// precomputed hierarchy for fast queries (see the [module docs](self)).
///
/// The structure keeps its own copy of the geometry, in a normalized frame
/// (see [Scale](self#scale)); the mesh can be dropped.
#[derive(Debug, Clone)]
pub struct WindingNumber {
    nodes: Vec<Node>,
    /// Triangle corners in tree order, times `scale`.
    tris: Vec<[Vec3; 3]>,
    beta: f32,
    /// The power of two taking world coordinates to the normalized frame.
    scale: f32,
}

impl WindingNumber {
    /// Builds the hierarchy over all triangles of `mesh` with the default
    /// accuracy [`DEFAULT_BETA`]. Degenerate triangles contribute nothing.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn new(mesh: &TriMesh) -> Self {
        let scale = mesh.unit_scale();
        let mut tris: Vec<[Vec3; 3]> =
            (0..mesh.triangles.len()).map(|t| mesh.corners(t).map(|p| p * scale)).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len().div_ceil(LEAF_SIZE));
        if !tris.is_empty() {
            nodes.push(Node::leaf(&tris, 0, tris.len(), DEFAULT_BETA));
            build(&mut nodes, &mut tris, 0, DEFAULT_BETA);
        }
        Self { nodes, tris, beta: DEFAULT_BETA, scale }
    }

    /// The same hierarchy with accuracy parameter `beta` (clamped to at
    /// least 1): larger is more accurate and slower. Error of the far-field
    /// expansion falls like `β⁻⁴`.
    pub fn with_accuracy(mut self, beta: f32) -> Self {
        let beta = if beta.is_finite() { beta.max(1.0) } else { DEFAULT_BETA };
        for node in &mut self.nodes {
            node.far_radius *= beta / self.beta;
        }
        self.beta = beta;
        self
    }

    /// The accuracy parameter β in use.
    pub fn accuracy(&self) -> f32 {
        self.beta
    }

    /// Number of triangles indexed.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when the mesh has no triangle (the winding number is then 0).
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The winding number at `p`: about 1 inside and 0 outside a closed
    /// outward-oriented mesh, ½ on a smooth part of the surface, fractional
    /// near holes. NaN for a non-finite `p`.
    pub fn winding_number(&self, p: Vec3) -> f32 {
        if !p.is_finite() {
            return f32::NAN;
        }
        let p = p * self.scale;
        if self.nodes.is_empty() || p.abs().max_element() > FAR {
            return 0.0;
        }
        let mut stack = [0u32; STACK];
        let mut top = 1;
        let mut angle = 0.0f32; // 4π × winding number
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let r = node.center - p;
            let r2 = r.length_squared();
            if r2 > node.far_radius * node.far_radius {
                angle += node.expansion(r, r2);
            } else if node.count > 0 {
                let first = node.first as usize;
                for [a, b, c] in &self.tris[first..first + node.count as usize] {
                    angle += solid_angle(*a - p, *b - p, *c - p);
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
        angle / (4.0 * PI)
    }

    /// True when the winding number at `p` exceeds ½.
    pub fn is_inside(&self, p: Vec3) -> bool {
        self.winding_number(p) > 0.5
    }

    /// [`WindingNumber::winding_number`] of every point, written to the same
    /// position of `out`; parallel over fixed chunks.
    ///
    /// # Panics
    /// If `out` and `points` differ in length.
    pub fn winding_numbers(&self, points: &[Vec3], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "winding_numbers: one output slot per point");
        points.par_chunks(CHUNK).zip(out.par_chunks_mut(CHUNK)).for_each(|(ps, os)| {
            for (&p, o) in ps.iter().zip(os) {
                *o = self.winding_number(p);
            }
        });
    }

    /// Exact winding number at `p`: the plain sum of every triangle's solid
    /// angle, with no approximation (slow: linear in the triangle count).
    /// NaN for a non-finite `p`, 0 beyond the normalized frame's reach (as
    /// [`WindingNumber::winding_number`]).
    pub fn exact_winding_number(&self, p: Vec3) -> f32 {
        if !p.is_finite() {
            return f32::NAN;
        }
        let p = p * self.scale;
        if p.abs().max_element() > FAR {
            return 0.0;
        }
        let sum: f64 = self.tris.iter().map(|&[a, b, c]| f64::from(solid_angle(a - p, b - p, c - p))).sum();
        (sum / (4.0 * std::f64::consts::PI)) as f32
    }
}

impl Node {
    /// A node about `center` with zero moments, to be accumulated.
    fn zero(center: Vec3, first: u32, count: u32) -> Self {
        Node {
            center,
            far_radius: 0.0,
            dipole: Vec3::ZERO,
            first_moment: Mat3::ZERO,
            second_moment: [Mat3::ZERO; 3],
            first,
            count,
        }
    }

    /// A leaf over `tris[start..end]` with its expansion.
    fn leaf(tris: &[[Vec3; 3]], start: usize, end: usize, beta: f32) -> Self {
        let part = &tris[start..end];
        // Centre: area-weighted centroid (the plain vertex mean if all are degenerate).
        let (mut weighted, mut area) = (Vec3::ZERO, 0.0f32);
        for &[a, b, c] in part {
            let w = 0.5 * (b - a).cross(c - a).length();
            weighted += w * (a + b + c) / 3.0;
            area += w;
        }
        let center = if area > 0.0 {
            weighted / area
        } else {
            part.iter().map(|&[a, b, c]| a + b + c).sum::<Vec3>() / (3 * part.len()) as f32
        };
        let mut node = Node::zero(center, start as u32, (end - start) as u32);
        let mut radius2 = 0.0f32;
        for &[a, b, c] in part {
            let [a, b, c] = [a - center, b - center, c - center];
            radius2 = radius2.max(a.length_squared()).max(b.length_squared()).max(c.length_squared());
            let an = 0.5 * (b - a).cross(c - a); // area × unit normal
            let area = an.length();
            let centroid = (a + b + c) / 3.0;
            node.dipole += an;
            node.first_moment += outer(an, centroid);
            // ∫ x xᵀ dA over the triangle = area/12 (Σ vᵥ vᵥᵀ + 9 c cᵀ).
            let second =
                (outer(a, a) + outer(b, b) + outer(c, c) + 9.0 * outer(centroid, centroid)) * (area / 12.0);
            let unit = if area > 0.0 { an / area } else { Vec3::ZERO };
            for i in 0..3 {
                node.second_moment[i] += second * unit[i];
            }
        }
        node.far_radius = beta * radius2.sqrt();
        node
    }

    /// Interior node over `first, first + 1`, combining their expansions
    /// about a new centre.
    fn parent(children: [&Node; 2], first: u32, areas: [f32; 2], beta: f32) -> Self {
        let total = areas[0] + areas[1];
        let center = if total > 0.0 {
            (areas[0] * children[0].center + areas[1] * children[1].center) / total
        } else {
            0.5 * (children[0].center + children[1].center)
        };
        let mut node = Node::zero(center, first, 0);
        for child in children {
            // Shift the moments from the child's centre by s = c_child − center:
            // ∫ n (δ + s)ᵀ = M + d sᵀ, ∫ nᵢ (δ + s)(δ + s)ᵀ = Sᵢ + Mᵢ sᵀ + s Mᵢᵀ + dᵢ s sᵀ.
            let s = child.center - center;
            node.dipole += child.dipole;
            node.first_moment += child.first_moment + outer(child.dipole, s);
            for i in 0..3 {
                let row = child.first_moment.row(i);
                node.second_moment[i] +=
                    child.second_moment[i] + outer(row, s) + outer(s, row) + outer(s, s) * child.dipole[i];
            }
            let reach = child.far_radius / beta + s.length();
            node.far_radius = node.far_radius.max(reach);
        }
        node.far_radius *= beta;
        node
    }

    /// `4π ×` the expansion's winding number, for `r = center − query`
    /// with `r2 = |r|²`. Written in the direction `u = r / |r|` and powers
    /// of `1/|r|`, so that no term grows with the distance (no overflow for
    /// any finite `r2`).
    #[inline]
    fn expansion(&self, r: Vec3, r2: f32) -> f32 {
        let inv = 1.0 / r2.sqrt();
        let u = r * inv;
        let m = &self.first_moment;
        // Order 0: r·d / |r|³ = u·d / |r|².
        let order0 = u.dot(self.dipole);
        // Order 1: Σ J_ij M_ij with J = I/|r|³ − 3 r rᵀ/|r|⁵ = (I − 3 u uᵀ)/|r|³.
        let mu = *m * u; // (M u)_i = Σ_j M_ij u_j
        let order1 = trace(m) - 3.0 * u.dot(mu);
        // Order 2: ½ Σ H_ijk S_ijk with H_ijk = −3(δ_ij r_k + δ_ik r_j + δ_jk r_i)/|r|⁵
        // + 15 r_i r_j r_k/|r|⁷ = (−3(δ_ij u_k + δ_ik u_j + δ_jk u_i) + 15 u_i u_j u_k)/|r|⁴.
        let s = &self.second_moment;
        let su = [s[0] * u, s[1] * u, s[2] * u];
        let diag = su[0].x + su[1].y + su[2].z; // Σ_ij S_iij u_j
        let traces = Vec3::new(trace(&s[0]), trace(&s[1]), trace(&s[2]));
        let cubic = u.x * u.dot(su[0]) + u.y * u.dot(su[1]) + u.z * u.dot(su[2]);
        let order2 = 0.5 * (-3.0 * (2.0 * diag + u.dot(traces)) + 15.0 * cubic);
        inv * inv * (order0 + inv * (order1 + inv * order2))
    }
}

/// Recursively splits the leaf `index` (holding `tris[first..first+count]`)
/// at the median centroid of its widest axis, down to [`LEAF_SIZE`].
/// Returns the node's total area.
fn build(nodes: &mut Vec<Node>, tris: &mut [[Vec3; 3]], index: usize, beta: f32) -> f32 {
    let (start, count) = (nodes[index].first as usize, nodes[index].count as usize);
    let end = start + count;
    if count <= LEAF_SIZE {
        return tris[start..end].iter().map(|&[a, b, c]| 0.5 * (b - a).cross(c - a).length()).sum();
    }
    let centroid = |t: &[Vec3; 3]| t[0] + t[1] + t[2];
    let (lo, hi) = tris[start..end]
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), t| (lo.min(centroid(t)), hi.max(centroid(t))));
    let axis = (hi - lo).max_position();
    let mid = count / 2;
    tris[start..end].select_nth_unstable_by(mid, |a, b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
    let first = nodes.len();
    nodes.push(Node::leaf(tris, start, start + mid, beta));
    nodes.push(Node::leaf(tris, start + mid, end, beta));
    let areas = [build(nodes, tris, first, beta), build(nodes, tris, first + 1, beta)];
    nodes[index] = Node::parent([&nodes[first], &nodes[first + 1]], first as u32, areas, beta);
    areas[0] + areas[1]
}

/// The outer product `u vᵀ`.
#[inline]
fn outer(u: Vec3, v: Vec3) -> Mat3 {
    Mat3::from_cols(u * v.x, u * v.y, u * v.z)
}

#[inline]
fn trace(m: &Mat3) -> f32 {
    m.x_axis.x + m.y_axis.y + m.z_axis.z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::metrics::test_meshes::{bunny, cube, read_obj, torus, uv_sphere};

    /// A deterministic scatter of `n` points over `bounds`.
    fn scatter(bounds: crate::Aabb, n: u32) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let f =
                    |k: u32| ((i.wrapping_mul(2654435761).wrapping_add(k * 40503)) % 1009) as f32 / 1008.0;
                bounds.min + bounds.size() * Vec3::new(f(1), f(2), f(3))
            })
            .collect()
    }

    #[test]
    fn solid_angle_of_an_octant_triangle() {
        // The triangle X, Y, Z cuts off one octant: 4π/8 from the origin,
        // negative seen from the side its right-hand normal points to.
        let w = solid_angle(Vec3::X, Vec3::Y, Vec3::Z);
        assert!((w - PI / 2.0).abs() < 1e-6, "{w}");
        assert!((solid_angle(Vec3::X, Vec3::Z, Vec3::Y) + PI / 2.0).abs() < 1e-6);
    }

    #[test]
    fn solid_angle_does_not_depend_on_magnitude() {
        for s in [1e-45f32, 1e-40, 1e-20, 1e13, 1e20, 1e30, 3e38] {
            let w = solid_angle(Vec3::X * s, Vec3::Y * s, Vec3::Z * s);
            assert!((w - PI / 2.0).abs() < 1e-6, "× {s:e}: {w}");
            // Unequal magnitudes: the corners' directions alone count.
            let w = solid_angle(Vec3::X * s, Vec3::Y * s.sqrt(), Vec3::Z * 3.0);
            assert!((w - PI / 2.0).abs() < 1e-6, "× {s:e}, mixed: {w}");
        }
    }

    /// A mesh scaled by `factor` has the unit mesh's winding numbers at the
    /// points scaled likewise, by the tree and by the exact sum; points too
    /// far to express relative to a tiny mesh have winding number 0.
    #[test]
    fn winding_numbers_do_not_depend_on_scale() {
        let points = [
            Vec3::ZERO,
            Vec3::new(0.4, -0.7, 0.1),
            Vec3::new(0.9, 0.2, -0.3),
            Vec3::new(1.1, 0.0, 0.0),
            Vec3::new(-0.6, 1.4, 0.2),
            Vec3::splat(3.0),
            Vec3::new(40.0, -2.0, 7.0),
        ];
        for mesh in [cube(1.0), uv_sphere(Vec3::ZERO, 1.0, 12, 24), torus(0.7, 0.3, 24, 12)] {
            let unit = WindingNumber::new(&mesh);
            for factor in [1e13f32, 1e20, 1e30, 1e-20, 1e-38, 1e-40] {
                let wn = WindingNumber::new(&mesh.scaled(factor));
                for p in points {
                    // The tree may split the rounded copy differently: equal to
                    // within its approximation error, and exact sums to rounding.
                    let (want, got) = (unit.winding_number(p), wn.winding_number(p * factor));
                    assert!((got - want).abs() < 2e-3, "× {factor:e} at {p}: {got} vs {want}");
                    let (want, got) = (unit.exact_winding_number(p), wn.exact_winding_number(p * factor));
                    assert!((got - want).abs() < 1e-5, "× {factor:e} at {p}, exact: {got} vs {want}");
                }
            }
        }
        let tiny = WindingNumber::new(&cube(1.0).scaled(1e-38));
        assert!((tiny.winding_number(Vec3::ZERO) - 1.0).abs() < 1e-5);
        for p in [Vec3::X, Vec3::new(-3e38, 1.0, 0.0)] {
            assert_eq!((tiny.winding_number(p), tiny.exact_winding_number(p)), (0.0, 0.0), "{p}");
        }
        let huge = WindingNumber::new(&cube(1.0).scaled(3e38));
        assert!((huge.winding_number(Vec3::new(1e38, -2e38, 0.0)) - 1.0).abs() < 1e-5);
        assert!(huge.winding_number(Vec3::new(1e38, -2e38, f32::MAX)).abs() < 1e-5);
    }

    #[test]
    fn expansion_matches_brute_force() {
        let mesh = bunny();
        let wn = WindingNumber::new(&mesh);
        let points = scatter(mesh.bounds().padded(0.3), 3000);
        let mut fast = vec![0.0; points.len()];
        wn.winding_numbers(&points, &mut fast);
        let mut worst = 0.0f32;
        for (&p, &f) in points.iter().zip(&fast) {
            worst = worst.max((f - wn.exact_winding_number(p)).abs());
        }
        assert!(worst < 2e-3, "largest error {worst}");
        // A larger β is more accurate.
        let precise = wn.clone().with_accuracy(4.0);
        let worst4 = points
            .iter()
            .map(|&p| (precise.winding_number(p) - wn.exact_winding_number(p)).abs())
            .fold(0.0f32, f32::max);
        assert!(worst4 < worst.max(1e-5) && worst4 < 2e-4, "β = 4: largest error {worst4}");
    }

    #[test]
    fn closed_meshes_are_one_inside_and_zero_outside() {
        for (mesh, inside, outside) in [
            (
                cube(1.0),
                vec![Vec3::ZERO, Vec3::splat(0.99)],
                vec![Vec3::splat(1.01), Vec3::new(5.0, 0.0, 0.0)],
            ),
            (
                uv_sphere(Vec3::ZERO, 1.0, 24, 48),
                vec![Vec3::ZERO, Vec3::new(0.0, 0.9, 0.3)],
                vec![Vec3::new(0.0, 1.1, 0.3), Vec3::splat(30.0)],
            ),
            (
                torus(3.0, 1.0, 48, 24),
                vec![Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, -3.5, 0.5)],
                vec![Vec3::ZERO, Vec3::new(3.0, 0.0, 1.2)],
            ),
        ] {
            let wn = WindingNumber::new(&mesh);
            for p in inside {
                assert!((wn.winding_number(p) - 1.0).abs() < 1e-2, "{p}: {}", wn.winding_number(p));
            }
            for p in outside {
                assert!(wn.winding_number(p).abs() < 1e-2, "{p}: {}", wn.winding_number(p));
            }
        }
    }

    #[test]
    fn fractions_on_the_surface() {
        // On the cube [-1, 1]³: ½ on a face, ¼ on an edge (a right dihedral
        // angle), ⅛ at a corner.
        let wn = WindingNumber::new(&cube(1.0));
        for (p, want) in [
            (Vec3::new(0.3, -0.6, 1.0), 0.5),
            (Vec3::new(-1.0, 0.25, 0.1), 0.5),
            (Vec3::new(1.0, 1.0, 0.2), 0.25),
            (Vec3::new(-1.0, 1.0, -1.0), 0.125),
        ] {
            let (w, exact) = (wn.winding_number(p), wn.exact_winding_number(p));
            assert!((w - want).abs() < 1e-5 && (exact - want).abs() < 1e-5, "{p}: {w}, exact {exact}");
        }
    }

    #[test]
    fn robust_to_duplicates_flips_and_holes() {
        let sphere = uv_sphere(Vec3::ZERO, 1.0, 16, 32);
        // Holes: drop a triangle near the equator and one at a pole.
        let mut holed = sphere.clone();
        holed.triangles.remove(200);
        holed.triangles.remove(0);
        // Duplicates: the same sphere twice counts twice; a duplicated and
        // flipped triangle cancels out.
        let mut doubled = sphere.clone();
        doubled.append(&sphere);
        let mut flipped = sphere.clone();
        let t = flipped.triangles[100];
        flipped.triangles.extend([t, [t[0], t[2], t[1]]]);
        // Flipping one triangle breaks the count only near it.
        let mut one_flipped = sphere.clone();
        one_flipped.triangles[300].swap(1, 2);
        for (name, mesh, inside_w) in [
            ("holed", holed, 1.0),
            ("doubled", doubled, 2.0),
            ("flipped", flipped, 1.0),
            ("one flipped", one_flipped, 1.0),
        ] {
            let wn = WindingNumber::new(&mesh);
            for p in [Vec3::ZERO, Vec3::new(0.3, -0.2, 0.4), Vec3::new(0.0, 0.0, -0.5)] {
                let w = wn.winding_number(p);
                assert!((w - inside_w).abs() < 0.1, "{name} at {p}: {w}");
                assert!(wn.is_inside(p), "{name} at {p}");
            }
            for p in [Vec3::new(1.5, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.3), Vec3::splat(3.0)] {
                assert!(wn.winding_number(p).abs() < 0.1 && !wn.is_inside(p), "{name} at {p}");
            }
        }
    }

    #[test]
    fn teapot_has_a_sensible_inside() {
        let teapot = read_obj(concat!(env!("CARGO_MANIFEST_DIR"), "/../data/teapot.obj"));
        let wn = WindingNumber::new(&teapot);
        // y is up: the open-bottomed body spans y ∈ [-7.9, 4.1] with radius
        // up to 10, the lid reaches y = 7.9, spout and handle stick out along x.
        let bounds = teapot.bounds();
        for p in [Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 5.0), Vec3::new(-4.0, -3.0, 3.0)]
        {
            assert!(wn.is_inside(p), "inside at {p}: {}", wn.winding_number(p));
        }
        for p in [
            Vec3::new(0.0, bounds.max.y + 1.0, 0.0),
            Vec3::new(0.0, bounds.min.y - 1.0, 0.0),
            Vec3::new(bounds.max.x + 1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, bounds.max.z + 1.0),
            Vec3::new(8.0, 5.0, 8.0),
            bounds.max + Vec3::ONE,
        ] {
            assert!(!wn.is_inside(p), "outside at {p}: {}", wn.winding_number(p));
        }
    }

    #[test]
    fn empty_and_non_finite() {
        let wn = WindingNumber::new(&TriMesh::default());
        assert!(wn.is_empty());
        assert_eq!(wn.winding_number(Vec3::ZERO), 0.0);
        let wn = WindingNumber::new(&cube(1.0));
        assert_eq!(wn.len(), 12);
        assert!(wn.winding_number(Vec3::NAN).is_nan());
        assert!(wn.exact_winding_number(Vec3::INFINITY).is_nan());
    }
}
