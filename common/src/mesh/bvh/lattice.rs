//! Exact nearest-triangle queries for every node of a regular lattice
//! ([`TriangleBvh::nearest_on_lattice`]), much faster than one tree descent
//! per node.

use super::{Best, ClosestPoint, STACK, Tri, TriangleBvh, closest_on_triangle};
use crate::Aabb;
use glam::{UVec3, Vec3};
use rayon::prelude::*;

/// Nodes per block edge.
const BLOCK: u32 = 8;
/// Nodes per edge of the blocks [`TriangleBvh::nearest_on_lattice`] solves
/// one at a time (from node 0 along each axis); see
/// [`TriangleBvh::nearest_in_block`].
pub const LATTICE_BLOCK: u32 = BLOCK;
/// Relative slack on the pruning bounds, covering the rounding of the `f32`
/// distances they compare (far above it, far below any useful tolerance).
const SLACK: f32 = 1e-5;

/// Per-thread scratch space of the block solver.
#[derive(Debug, Default)]
struct Scratch {
    /// The block's candidates `(dist(T, c), slot)` and their packs.
    candidates: Vec<(f32, u32)>,
    packs: Vec<Pack>,
    /// The same for the current sub-block.
    sub_candidates: Vec<(f32, u32)>,
    sub_packs: Vec<Pack>,
    /// Nearest slot of the last block centre (a starting bound for the next).
    previous: u32,
}

/// Per-thread scratch space of [`TriangleBvh::nearest_in_block`] (candidate
/// lists reused from block to block).
#[derive(Debug)]
pub struct BlockScratch(Scratch);

impl Default for BlockScratch {
    fn default() -> Self {
        Self(Scratch { previous: Best::NONE, ..Scratch::default() })
    }
}

/// What [`TriangleBvh::nearest_in_block`] found about a block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockNearest {
    /// The block's centre (the lattice's units).
    pub center: Vec3,
    /// The exact distance from `center` to the surface: the ball of that
    /// radius about it holds no surface.
    pub distance: f32,
    /// False when every node of the block lies farther than the requested
    /// `max_distance` from the surface and no node was solved.
    pub solved: bool,
}

/// One of the up to eight parts of a block.
#[derive(Debug, Clone, Copy)]
struct SubBlock {
    lo: UVec3,
    n: UVec3,
    center: Vec3,
    /// Distance from `center` to the farthest node.
    radius: f32,
}

/// The block of `n` nodes from `lo` halved along each axis of more than one node.
fn sub_blocks(lattice: &Lattice, lo: UVec3, n: UVec3) -> [Option<SubBlock>; 8] {
    let mut out = [None; 8];
    for (c, slot) in out.iter_mut().enumerate() {
        let upper = UVec3::new(c as u32 & 1, (c as u32 >> 1) & 1, c as u32 >> 2);
        let first = (n + UVec3::ONE) / 2;
        let size = UVec3::select(upper.cmpeq(UVec3::ONE), n - first, first);
        if size.min_element() == 0 {
            continue;
        }
        let start = lo + upper * first;
        let half = (size - UVec3::ONE).as_vec3() * 0.5;
        *slot = Some(SubBlock {
            lo: start,
            n: size,
            center: lattice.origin + lattice.step * (start.as_vec3() + half),
            radius: (lattice.step * half).length(),
        });
    }
    out
}

/// Sorts candidates by distance, then slot (non-negative floats order like
/// their bit patterns).
fn sort_candidates(candidates: &mut [(f32, u32)]) {
    candidates.sort_unstable_by_key(|&(e, slot)| (u64::from(e.to_bits()) << 32) | u64::from(slot));
}

/// Triangles per [`Pack`].
const LANES: usize = 8;

/// Query data of [`LANES`] candidate triangles in structure-of-arrays form,
/// so that [`Pack::distances`] runs branch-free over the lanes (and
/// vectorizes). Short packs repeat their last triangle.
#[derive(Debug, Clone, Copy)]
struct Pack {
    /// Each lane's distance to the block centre (sorted ascending).
    reach: [f32; LANES],
    /// Corner `a`, edges `ab` and `ac`, normal, barycentric gradients: x, y,
    /// z rows of each.
    a: [[f32; LANES]; 3],
    ab: [[f32; LANES]; 3],
    ac: [[f32; LANES]; 3],
    normal: [[f32; LANES]; 3],
    grad_v: [[f32; LANES]; 3],
    grad_w: [[f32; LANES]; 3],
    /// Reciprocal squared lengths of `ab`, `ac`, `bc` (0 for a zero edge).
    inv: [[f32; LANES]; 3],
}

impl Pack {
    fn new(tris: &[Tri], chunk: &[(f32, u32)]) -> Self {
        let mut pack = Pack {
            reach: [0.0; LANES],
            a: [[0.0; LANES]; 3],
            ab: [[0.0; LANES]; 3],
            ac: [[0.0; LANES]; 3],
            normal: [[0.0; LANES]; 3],
            grad_v: [[0.0; LANES]; 3],
            grad_w: [[0.0; LANES]; 3],
            inv: [[0.0; LANES]; 3],
        };
        for l in 0..LANES {
            let (reach, slot) = chunk[l.min(chunk.len() - 1)];
            let t = &tris[slot as usize];
            pack.reach[l] = reach;
            for c in 0..3 {
                pack.a[c][l] = t.a[c];
                pack.ab[c][l] = t.ab[c];
                pack.ac[c][l] = t.ac[c];
                pack.normal[c][l] = t.normal[c];
                pack.grad_v[c][l] = t.grad_v[c];
                pack.grad_w[c][l] = t.grad_w[c];
            }
            pack.inv[0][l] = t.inv_ab;
            pack.inv[1][l] = t.inv_ac;
            pack.inv[2][l] = t.inv_bc;
        }
        pack
    }

    /// Squared distances from `p` to the pack's triangles. Same geometry as the scalar
    /// point–triangle step: the plane distance when the projection is
    /// inside, else the nearest of the three clamped edge projections
    /// (which are never nearer than the true distance, so taking all three
    /// needs no region branch).
    #[inline]
    fn distances(&self, p: Vec3) -> [f32; LANES] {
        let mut d = [0.0f32; LANES];
        for l in 0..LANES {
            let ap = [p.x - self.a[0][l], p.y - self.a[1][l], p.z - self.a[2][l]];
            let dot = |u: &[[f32; LANES]; 3], x: [f32; 3]| u[0][l] * x[0] + u[1][l] * x[1] + u[2][l] * x[2];
            let v = dot(&self.grad_v, ap);
            let w = dot(&self.grad_w, ap);
            let h = dot(&self.normal, ap);
            let inside = v > 0.0 && w > 0.0 && v + w < 1.0;
            let plane = if inside { h * h } else { f32::INFINITY };
            let ab = [self.ab[0][l], self.ab[1][l], self.ab[2][l]];
            let ac = [self.ac[0][l], self.ac[1][l], self.ac[2][l]];
            let bp = [ap[0] - ab[0], ap[1] - ab[1], ap[2] - ab[2]];
            let bc = [ac[0] - ab[0], ac[1] - ab[1], ac[2] - ab[2]];
            let edge = |from: [f32; 3], e: [f32; 3], inv: f32| {
                let s = clamp01((from[0] * e[0] + from[1] * e[1] + from[2] * e[2]) * inv);
                let r = [from[0] - s * e[0], from[1] - s * e[1], from[2] - s * e[2]];
                r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
            };
            let e1 = edge(ap, ab, self.inv[0][l]);
            let e2 = edge(ap, ac, self.inv[1][l]);
            let e3 = edge(bp, bc, self.inv[2][l]);
            d[l] = min(min(plane, e1), min(e2, e3));
        }
        d
    }
}

/// The smallest value of `d` and its first lane.
#[inline(always)]
fn argmin(d: &[f32; LANES]) -> (f32, usize) {
    let m = d.iter().fold(f32::INFINITY, |m, &x| min(m, x));
    (m, d.iter().position(|&x| x == m).unwrap_or(0))
}

/// `x` clamped to `[0, 1]` (branch-free for vectorization).
#[inline(always)]
fn clamp01(x: f32) -> f32 {
    let x = if x > 0.0 { x } else { 0.0 };
    if x < 1.0 { x } else { 1.0 }
}

/// The smaller of `a` and `b` (branch-free for vectorization).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// A regular lattice of points: node `(i, j, k)` at `origin + step * (i, j,
/// k)`, stored x-fastest (linear index `i + nx · (j + ny · k)`, as
/// [`Grid3`](crate::Grid3)). Unlike a grid the step may differ per axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    /// Node counts along x, y, z.
    pub dims: UVec3,
    /// Position of node `(0, 0, 0)`, world units.
    pub origin: Vec3,
    /// Spacing of the nodes along each axis, world units.
    pub step: Vec3,
}

impl Lattice {
    /// `dims` nodes spanning `bounds` with a node on each face (per-axis
    /// step `size / (dims − 1)`; an axis with one node sits at the box's
    /// minimum).
    pub fn spanning(bounds: &Aabb, dims: UVec3) -> Self {
        let cells = dims.saturating_sub(UVec3::ONE).max(UVec3::ONE).as_vec3();
        Self { dims, origin: bounds.min, step: bounds.size() / cells }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.dims.x as usize * self.dims.y as usize * self.dims.z as usize
    }

    /// True when the lattice has no node.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Position of node `(i, j, k)`.
    #[inline]
    pub fn position(&self, i: u32, j: u32, k: u32) -> Vec3 {
        self.origin + self.step * Vec3::new(i as f32, j as f32, k as f32)
    }

    /// Position of node `n` in x-fastest order.
    #[inline]
    pub fn position_of(&self, n: usize) -> Vec3 {
        self.position_in_box(UVec3::ZERO, self.dims, n)
    }

    /// Position of node `n`, in x-fastest order, of the box of `dims`
    /// nodes from node `first` (placed as the whole lattice places it,
    /// bitwise).
    #[inline]
    pub fn position_in_box(&self, first: UVec3, dims: UVec3, n: usize) -> Vec3 {
        let (nx, ny) = (dims.x as usize, dims.y as usize);
        let c = first + UVec3::new((n % nx) as u32, ((n / nx) % ny) as u32, (n / (nx * ny)) as u32);
        self.position(c.x, c.y, c.z)
    }
}

/// The nearest triangle of one lattice node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeHit {
    /// Distance to the nearest surface point, world units (NaN when the
    /// lattice is not finite).
    pub distance: f32,
    /// Index of the nearest triangle (into [`TriMesh::triangles`](crate::TriMesh::triangles)).
    pub triangle: u32,
    /// Leaf slot of the triangle in the tree.
    slot: u32,
}

impl LatticeHit {
    /// No triangle (a node not solved), NaN distance.
    pub const NONE: Self = Self { distance: f32::NAN, triangle: u32::MAX, slot: u32::MAX };
}

impl TriangleBvh {
    /// The exact nearest triangle of every node of `lattice` (x-fastest
    /// order), computed block by block in parallel. `None` for an empty tree.
    ///
    /// The lattice is cut into blocks of 8³ nodes. For a block with centre
    /// `c`, one tree query gives the exact distance `d(c)`. Since the distance
    /// is 1-Lipschitz, every node `x` of the block has `d(x) ≤ d(c) + |x − c|`,
    /// and a triangle `T` nearest to `x` satisfies
    /// `dist(T, c) ≤ d(x) + |x − c| ≤ d(c) + 2r` where `r` bounds `|x − c|`. One
    /// range query collects those candidates with their exact distances
    /// `e_T = dist(T, c)`,
    /// sorted by `e_T`. Each half of the block along every axis (a sub-block
    /// with centre `c'` and radius `r'`) then narrows the list the same way to
    /// the triangles within `d(c') + 2r'` of `c'`, found among the block's
    /// candidates (the ball they lie in is inside the block's ball). Each node
    /// scans its sub-block's list in order of `e'_T` and stops at the first with
    /// `e'_T − |x − c'| >` its best distance so far (the triangle inequality
    /// makes that a lower bound for all the rest). The result is the exact
    /// minimum over all triangles, as a brute-force search would find it, at the
    /// cost of a few dozen point–triangle tests per node (eight at a time,
    /// branch-free, over structure-of-arrays packs that the compiler
    /// vectorizes) and one tree traversal per block.
    ///
    /// # Example
    /// ```
    /// use isomorph_common::mesh::bvh::{Lattice, TriangleBvh};
    /// use isomorph_common::{Aabb, TriMesh, glam::{UVec3, Vec3}};
    ///
    /// let mesh = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])?;
    /// let bvh = TriangleBvh::new(&mesh);
    /// // 3 × 3 × 2 nodes over [0, 1]² × [1, 2].
    /// let lattice = Lattice::spanning(&Aabb::new(Vec3::Z, Vec3::ONE + Vec3::Z), UVec3::new(3, 3, 2));
    /// let hits = bvh.nearest_on_lattice(&lattice).expect("non-empty mesh");
    /// assert_eq!(hits.len(), 18);
    /// assert_eq!(hits[0].distance, 1.0); // node (0, 0, 0) at z = 1 above the corner
    /// assert_eq!(hits[17].distance, Vec3::new(0.5, 0.5, 2.0).length()); // (1, 1, 2) to (½, ½, 0)
    /// # Ok::<(), isomorph_common::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If the lattice has more than `u32::MAX` nodes along an axis product
    /// that does not fit memory (allocation failure).
    pub fn nearest_on_lattice(&self, lattice: &Lattice) -> Option<Vec<LatticeHit>> {
        self.nearest_on_lattice_within(lattice, f32::INFINITY)
    }

    /// As [`TriangleBvh::nearest_on_lattice`], but blocks of nodes all
    /// farther than `max_distance` from the surface are skipped: their
    /// nodes get a NaN distance (and no triangle). Every node within
    /// `max_distance` gets its exact nearest triangle; some farther nodes
    /// (in blocks that reach into the band) do too.
    ///
    /// # Panics
    /// As [`TriangleBvh::nearest_on_lattice`].
    pub fn nearest_on_lattice_within(&self, lattice: &Lattice, max_distance: f32) -> Option<Vec<LatticeHit>> {
        if self.is_empty() {
            return None;
        }
        let (nx, ny) = (lattice.dims.x as usize, lattice.dims.y as usize);
        let mut out = vec![LatticeHit::NONE; lattice.len()];
        if out.is_empty() || !lattice.origin.is_finite() || !lattice.step.is_finite() {
            return Some(out);
        }
        let slab = nx * ny * BLOCK as usize;
        out.par_chunks_mut(slab).enumerate().for_each_init(
            || Scratch { previous: Best::NONE, ..Scratch::default() },
            |scratch, (s, hits)| {
                let k0 = s as u32 * BLOCK;
                let kn = (lattice.dims.z - k0).min(BLOCK);
                for j0 in (0..lattice.dims.y).step_by(BLOCK as usize) {
                    for i0 in (0..lattice.dims.x).step_by(BLOCK as usize) {
                        let lo = UVec3::new(i0, j0, k0);
                        let n = (lattice.dims - lo).min(UVec3::new(BLOCK, BLOCK, kn));
                        self.block(lattice, lo, n, max_distance, scratch, |i, j, k, hit| {
                            hits[i as usize + nx * (j as usize + ny * (k - k0) as usize)] = hit;
                        });
                    }
                }
            },
        );
        Some(out)
    }

    /// The closest point of `hit`'s triangle to `p` (normally the lattice
    /// node `hit` was computed for), with barycentric coordinates.
    pub fn closest_point_of(&self, p: Vec3, hit: &LatticeHit) -> Option<ClosestPoint> {
        if hit.slot == Best::NONE || hit.slot as usize >= self.tris.len() {
            return None;
        }
        self.result(p, Best { d2: 0.0, slot: hit.slot })
    }

    /// The nearest triangle of every node of one block of `lattice` (the
    /// up to 8³ nodes from `lo`, a multiple of [`LATTICE_BLOCK`] per axis:
    /// one of the blocks [`TriangleBvh::nearest_on_lattice`] solves, with
    /// bitwise its results), handed to `emit(i, j, k, hit)`; a block whose
    /// nodes are all farther than `max_distance` is skipped (nothing
    /// emitted). Returns the block's centre and its exact distance to the
    /// surface (every node of a skipped block lies within that ball's
    /// radius minus `max_distance` of the centre), and whether the block
    /// was solved. Lets a caller solve only the blocks it stores (a brick
    /// grid), with `scratch` kept per thread. `None` for an empty tree.
    pub fn nearest_in_block(
        &self,
        lattice: &Lattice,
        lo: UVec3,
        max_distance: f32,
        scratch: &mut BlockScratch,
        emit: impl FnMut(u32, u32, u32, LatticeHit),
    ) -> Option<BlockNearest> {
        if self.is_empty() || lo.cmpge(lattice.dims).any() {
            return None;
        }
        let n = (lattice.dims - lo).min(UVec3::splat(BLOCK));
        Some(self.block(lattice, lo, n, max_distance, &mut scratch.0, emit))
    }

    /// Solves the block of `n` nodes starting at node `lo`, handing each
    /// node's hit to `emit`, using the thread's scratch space; a block whose
    /// nodes are all farther than `max_distance` is left as it is.
    fn block(
        &self,
        lattice: &Lattice,
        lo: UVec3,
        n: UVec3,
        max_distance: f32,
        scratch: &mut Scratch,
        mut emit: impl FnMut(u32, u32, u32, LatticeHit),
    ) -> BlockNearest {
        let center = lattice.origin + lattice.step * (lo.as_vec3() + (n - UVec3::ONE).as_vec3() * 0.5);
        // The block is split in two along each axis; `span` bounds the
        // distance from the centre to every node of a sub-block through the
        // sub-block's centre (`|c' − c| + r'`), and so also to every node.
        let subs = sub_blocks(lattice, lo, n);
        let span = subs.iter().flatten().map(|s| (s.center - center).length() + s.radius).fold(0.0, f32::max);
        let start = if scratch.previous == Best::NONE {
            Best::bound(f32::INFINITY)
        } else {
            let previous = scratch.previous;
            Best { d2: closest_on_triangle(center, &self.tris[previous as usize]).d2, slot: previous }
        };
        let nearest = self.search(center, start);
        scratch.previous = nearest.slot;
        // Every node is within `span` of the centre: d(x) ≥ d(c) − span.
        let distance = nearest.d2.sqrt();
        if distance - span > max_distance * (1.0 + SLACK) + SLACK * span {
            return BlockNearest { center, distance, solved: false };
        }
        let reach = (nearest.d2.sqrt() + 2.0 * span) * (1.0 + SLACK) + SLACK * span;
        self.gather(center, reach, &mut scratch.candidates);
        sort_candidates(&mut scratch.candidates);
        scratch.packs.clear();
        scratch.packs.extend(scratch.candidates.chunks(LANES).map(|chunk| Pack::new(&self.tris, chunk)));
        for sub in subs.iter().flatten() {
            // The sub-block's candidates: every triangle within d(c') + 2r'
            // of its centre c', found among the block's (which hold them all,
            // as the ball about c' of that radius lies in the block's).
            let offset = (sub.center - center).length() * (1.0 + SLACK) + SLACK * span;
            let own = &mut scratch.sub_candidates;
            own.clear();
            let mut nearest = f32::INFINITY;
            let widen = 2.0 * sub.radius * (1.0 + SLACK) + SLACK * span;
            for (q, pack) in scratch.packs.iter().enumerate() {
                if pack.reach[0] > nearest + widen + offset {
                    break;
                }
                let e = pack.distances(sub.center).map(f32::sqrt);
                nearest = e.iter().fold(nearest, |m, &x| min(m, x));
                let lanes = (scratch.candidates.len() - q * LANES).min(LANES);
                for (l, &e) in e.iter().enumerate().take(lanes) {
                    if e <= nearest + widen {
                        own.push((e, scratch.candidates[q * LANES + l].1));
                    }
                }
            }
            own.retain(|&(e, _)| e <= nearest + widen);
            sort_candidates(own);
            scratch.sub_packs.clear();
            scratch.sub_packs.extend(own.chunks(LANES).map(|chunk| Pack::new(&self.tris, chunk)));
            for k in sub.lo.z..sub.lo.z + sub.n.z {
                for j in sub.lo.y..sub.lo.y + sub.n.y {
                    for i in sub.lo.x..sub.lo.x + sub.n.x {
                        let p = lattice.position(i, j, k);
                        let offset = (p - sub.center).length() * (1.0 + SLACK) + SLACK * span;
                        let (mut best2, mut best, mut index) = (f32::INFINITY, f32::INFINITY, 0);
                        for (q, pack) in scratch.sub_packs.iter().enumerate() {
                            if pack.reach[0] > best + offset {
                                break;
                            }
                            let d = pack.distances(p);
                            if d.iter().any(|&x| x < best2) {
                                let (d2, lane) = argmin(&d);
                                (best2, best, index) = (d2, d2.sqrt(), q * LANES + lane);
                            }
                        }
                        let slot = own[index].1;
                        let triangle = self.ids[slot as usize];
                        emit(i, j, k, LatticeHit { distance: best, triangle, slot });
                    }
                }
            }
        }
        BlockNearest { center, distance, solved: true }
    }

    /// Every triangle within `reach` of `p`, with its exact distance, into
    /// `out` (cleared first).
    fn gather(&self, p: Vec3, reach: f32, out: &mut Vec<(f32, u32)>) {
        out.clear();
        let reach2 = reach * reach;
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.distance_squared(p) > reach2 {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for slot in first..first + node.count as usize {
                    let t = &self.tris[slot];
                    let h = (p - t.a).dot(t.normal);
                    if h * h > reach2 {
                        continue;
                    }
                    let d2 = closest_on_triangle(p, t).d2;
                    if d2 <= reach2 {
                        out.push((d2.sqrt(), slot as u32));
                    }
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TriMesh;
    use crate::mesh::metrics::test_meshes::{bunny, torus};

    /// Checks every node of `lattice` against a single-point query.
    fn check(mesh: &TriMesh, lattice: &Lattice) {
        let bvh = TriangleBvh::new(mesh);
        let hits = bvh.nearest_on_lattice(lattice).unwrap();
        assert_eq!(hits.len(), lattice.len());
        let mut index = 0;
        for k in 0..lattice.dims.z {
            for j in 0..lattice.dims.y {
                for i in 0..lattice.dims.x {
                    let p = lattice.position(i, j, k);
                    let want = bvh.closest(p).unwrap();
                    let hit = hits[index];
                    let scale = 1e-6 * (1.0 + want.distance_squared.sqrt());
                    assert!(
                        (hit.distance - want.distance_squared.sqrt()).abs() <= scale,
                        "node ({i}, {j}, {k}) at {p}: {} vs {}",
                        hit.distance,
                        want.distance_squared.sqrt()
                    );
                    let on = bvh.closest_point_of(p, &hit).unwrap();
                    assert_eq!(on.triangle, hit.triangle);
                    assert!((on.distance_squared.sqrt() - hit.distance).abs() <= scale);
                    index += 1;
                }
            }
        }
    }

    #[test]
    fn matches_single_queries() {
        let mesh = bunny();
        // Anisotropic steps and sizes that do not divide into blocks.
        let lattice = Lattice::spanning(&mesh.bounds().padded(0.2), UVec3::new(23, 30, 17));
        check(&mesh, &lattice);
        // A lattice far from the surface, and one cutting through a torus.
        let far =
            Lattice { dims: UVec3::new(9, 5, 6), origin: Vec3::splat(20.0), step: Vec3::new(0.7, 1.3, 0.4) };
        check(&mesh, &far);
        let t = torus(3.0, 1.0, 40, 20);
        check(&t, &Lattice::spanning(&t.bounds().padded(0.1), UVec3::new(26, 26, 9)));
    }

    /// Far from the origin, node positions round to f32 by up to a few steps
    /// (steps of 0.01 and 0.3 at 10⁶, where positions are sixteenths); the
    /// block search still finds each node's nearest triangle.
    #[test]
    fn rounded_node_positions() {
        let offset = Vec3::new(1e6, -1e6, 1e6);
        let mesh = torus(1.0, 0.4, 24, 12).transformed(&glam::Affine3A::from_translation(offset));
        for step in [0.01, 0.3] {
            let origin = offset - Vec3::new(1.5, 0.5, 0.2);
            check(&mesh, &Lattice { dims: UVec3::new(20, 19, 17), origin, step: Vec3::splat(step) });
        }
    }

    #[test]
    fn degenerate_lattices() {
        let mesh = bunny();
        let bvh = TriangleBvh::new(&mesh);
        let single = Lattice { dims: UVec3::ONE, origin: Vec3::ZERO, step: Vec3::ZERO };
        let hit = bvh.nearest_on_lattice(&single).unwrap()[0];
        assert_eq!(hit.distance, bvh.closest(Vec3::ZERO).unwrap().distance_squared.sqrt());
        let empty = Lattice { dims: UVec3::new(4, 0, 2), ..single };
        assert!(bvh.nearest_on_lattice(&empty).unwrap().is_empty());
        let bad = Lattice { origin: Vec3::NAN, dims: UVec3::splat(2), ..single };
        let hits = bvh.nearest_on_lattice(&bad).unwrap();
        assert!(hits.iter().all(|h| h.distance.is_nan() && bvh.closest_point_of(Vec3::ZERO, h).is_none()));
        assert!(TriangleBvh::new(&TriMesh::default()).nearest_on_lattice(&single).is_none());
    }
}
