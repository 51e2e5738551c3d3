//! A bounding-volume hierarchy over a mesh's triangles for exact
//! nearest-point queries ([`TriangleBvh`]).
//!
//! The tree is a flat array of binary nodes built with a binned surface-area
//! heuristic; siblings are adjacent, so a parent visits both child boxes in
//! one cache line. Leaves hold up to [`MAX_LEAF`] triangles, stored in leaf
//! order with precomputed query data. A query descends nearer child first and
//! prunes every box farther (squared distance) than the best triangle so far.
//!
//! # The point–triangle step
//! Each triangle stores its unit normal and the gradients of its barycentric
//! coordinates `v`, `w` (of corners `b`, `c`), set up in `f64`. A query point
//! whose projection has `v, w > 0, v + w < 1` is nearest to the interior at
//! the plane distance; otherwise the nearest point lies on an edge whose
//! barycentric coordinate is violated, found by clamped projection. Every
//! classification error is confined to a band of width ≈ `f32::EPSILON · |p − a|`
//! around the region borders, where both answers agree to that width, so the
//! distance is accurate to a few ulps of the query's offset for *any* triangle
//! shape: slivers, needles, and exactly degenerate triangles (zero area;
//! handled as their edges). Ericson's region test (*Real-Time Collision
//! Detection* §5.1.5) in `f32` was measured to err by up to 4·10⁻³ on
//! unit-size slivers and so is not used.
//!
//! # Scale
//! The tree works in world units with `f32` squared distances, which
//! overflow for distances beyond about 10¹⁹ and underflow below about
//! 10⁻¹⁹. Callers that must handle any mesh scale build it over a copy
//! multiplied by a power of two (exact) that brings the coordinates near 1,
//! as [`MeshSdf`](crate::sdf::MeshSdf) and
//! [`surface_distance`](crate::mesh::distance::surface_distance) do.

mod lattice;

pub use lattice::{BlockNearest, BlockScratch, LATTICE_BLOCK, Lattice, LatticeHit};

use crate::TriMesh;
use glam::Vec3;
use rayon::prelude::*;

/// Most triangles in one leaf.
pub const MAX_LEAF: usize = 4;
/// Centroid bins per axis of the SAH build.
const BINS: usize = 16;
/// Depth below which splits fall back from SAH to centroid medians, which
/// halve the range and so bound the total depth by `SAH_DEPTH + 32`.
const SAH_DEPTH: usize = 28;
/// Traversal stack size: one entry per level is enough for the bounded depth.
const STACK: usize = 64;
/// Queries per work item of [`TriangleBvh::closest_many`]; fixed so that the
/// results (including tie-breaking between equidistant triangles) do not
/// depend on the thread count.
const CHUNK: usize = 256;

/// How a [`TriangleBvh`] is built: a trade between build and query cost.
/// Both answer every query exactly, with the same distances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhBuild {
    /// Top-down binned surface-area heuristic over all three axes: the
    /// fewest box and triangle tests per query, for a tree queried many
    /// more times than it has triangles (distance volumes, lattices).
    #[default]
    Sah,
    /// Morton order (a linear BVH, Lauterbach et al. 2009): the triangles
    /// sorted by the 30-bit Morton code of their box centres in the box of
    /// all centres, each node split where the highest bit in which its
    /// first and last codes differ changes (equal codes: halved). One sort
    /// and one pass, several times cheaper than [`BvhBuild::Sah`], at some
    /// more tests per query: for a tree queried about as many times as it
    /// has triangles or fewer (sampled distances between surfaces).
    Morton,
}

/// The nearest point of a mesh to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// The nearest surface point, in world units.
    pub point: Vec3,
    /// Index of the triangle it lies on (into [`TriMesh::triangles`]). Among
    /// equidistant triangles one is chosen deterministically.
    pub triangle: u32,
    /// Squared distance from the query to [`ClosestPoint::point`].
    pub distance_squared: f32,
    /// Weights of the triangle's corners `(a, b, c)` giving `point`
    /// (non-negative, sum 1 up to rounding).
    pub barycentric: Vec3,
}

/// A triangle in leaf order with its precomputed query data.
#[derive(Debug, Clone, Copy)]
struct Tri {
    /// Corner `a` and the edges `b − a`, `c − a`.
    a: Vec3,
    ab: Vec3,
    ac: Vec3,
    /// Unit normal (zero for a degenerate triangle).
    normal: Vec3,
    /// Gradients of the barycentric coordinates `v` (of `b`) and `w` (of `c`)
    /// of the projection onto the plane: `v = (p − a)·grad_v` (zero for a
    /// degenerate triangle).
    grad_v: Vec3,
    grad_w: Vec3,
    /// Reciprocal squared lengths of `ab`, `ac`, `bc` (zero for a zero-length edge).
    inv_ab: f32,
    inv_ac: f32,
    inv_bc: f32,
}

impl Tri {
    /// Query data of the triangle `abc`, set up in `f64`.
    fn new([a, b, c]: [Vec3; 3]) -> Self {
        let (ab, ac) = (b.as_dvec3() - a.as_dvec3(), c.as_dvec3() - a.as_dvec3());
        let n = ab.cross(ac);
        let n2 = n.length_squared();
        let grad_v = (ac.cross(n) / n2).as_vec3();
        let grad_w = (n.cross(ab) / n2).as_vec3();
        // A triangle whose gradients do not fit in f32 is treated as its edges.
        let flat = !(n2 > 0.0 && grad_v.is_finite() && grad_w.is_finite());
        let inverse =
            |len2: f64| if len2 > 0.0 && (1.0 / len2) < f32::MAX as f64 { (1.0 / len2) as f32 } else { 0.0 };
        Self {
            a,
            ab: ab.as_vec3(),
            ac: ac.as_vec3(),
            normal: if flat { Vec3::ZERO } else { (n / n2.sqrt()).as_vec3() },
            grad_v: if flat { Vec3::ZERO } else { grad_v },
            grad_w: if flat { Vec3::ZERO } else { grad_w },
            inv_ab: inverse(ab.length_squared()),
            inv_ac: inverse(ac.length_squared()),
            inv_bc: inverse((ac - ab).length_squared()),
        }
    }
}

/// The nearest point of one triangle: squared distance, the point, and the
/// barycentric coordinates `(v, w)` of corners `b` and `c`.
#[derive(Debug, Clone, Copy)]
struct OnTriangle {
    d2: f32,
    point: Vec3,
    v: f32,
    w: f32,
}

/// A tree node: its box, and either its children `first, first + 1`
/// (`count == 0`) or its triangles `first .. first + count`.
#[derive(Debug, Clone, Copy)]
struct Node {
    min: Vec3,
    first: u32,
    max: Vec3,
    count: u32,
}

impl Node {
    /// Squared distance from `p` to the node's box (0 inside).
    #[inline(always)]
    fn distance_squared(&self, p: Vec3) -> f32 {
        (self.min - p).max(p - self.max).max(Vec3::ZERO).length_squared()
    }
}

/// The best candidate of a query: squared distance and, once found, the leaf
/// slot of the triangle.
#[derive(Debug, Clone, Copy)]
struct Best {
    d2: f32,
    slot: u32,
}

impl Best {
    const NONE: u32 = u32::MAX;

    fn bound(d2: f32) -> Self {
        Self { d2, slot: Self::NONE }
    }
}

/// Bounding-volume hierarchy over a [`TriMesh`]'s triangles answering exact
/// closest-point queries.
///
/// The tree keeps its own copy of the geometry; the mesh can be dropped.
#[derive(Debug, Clone, Default)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    /// Triangles in leaf order.
    tris: Vec<Tri>,
    /// Original triangle index of each leaf slot.
    ids: Vec<u32>,
}

impl TriangleBvh {
    /// Builds the tree over all triangles of `mesh` (degenerate ones
    /// included) with the surface-area heuristic ([`BvhBuild::Sah`]).
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn new(mesh: &TriMesh) -> Self {
        Self::with_build(mesh, BvhBuild::Sah)
    }

    /// Builds the tree over all triangles of `mesh` (degenerate ones
    /// included) the way `build` says. Every build answers every query
    /// exactly (the same distances); they differ in build and query cost.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn with_build(mesh: &TriMesh, build: BvhBuild) -> Self {
        let n = mesh.triangles.len();
        if n == 0 {
            return Self::default();
        }
        let corners: Vec<[Vec3; 3]> = (0..n).map(|t| mesh.corners(t)).collect();
        let builder = Builder::new(&corners, build);
        let ids: Vec<u32> = builder.order().collect();
        let tris = ids.iter().map(|&t| Tri::new(corners[t as usize])).collect();
        Self { nodes: builder.nodes, tris, ids }
    }

    /// Number of triangles indexed.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when the tree holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The nearest point of the mesh to `p`; `None` for an empty mesh or a
    /// non-finite `p`.
    pub fn closest(&self, p: Vec3) -> Option<ClosestPoint> {
        self.closest_point_within(p, f32::INFINITY)
    }

    /// The nearest point of the mesh to `p` if it lies within `max_dist`
    /// (inclusive) of `p`, else `None`. A tight bound makes the query faster.
    pub fn closest_point_within(&self, p: Vec3, max_dist: f32) -> Option<ClosestPoint> {
        // A negative or NaN `max_dist` admits nothing.
        let bound = if max_dist >= 0.0 { max_dist * max_dist } else { -1.0 };
        let best = self.search(p, Best::bound(bound));
        self.result(p, best)
    }

    /// [`TriangleBvh::closest`] for every point of `points`, written to the
    /// same position of `out`; parallel over fixed chunks. Consecutive points
    /// start from the distance to their predecessor's triangle as an upper
    /// bound, so coherent orders (grid rows) run fastest.
    ///
    /// # Panics
    /// If `out` and `points` differ in length.
    pub fn closest_many(&self, points: &[Vec3], out: &mut [Option<ClosestPoint>]) {
        assert_eq!(points.len(), out.len(), "closest_many: one output slot per point");
        points.par_chunks(CHUNK).zip(out.par_chunks_mut(CHUNK)).for_each(|(ps, os)| {
            let mut previous = Best::NONE;
            for (&p, o) in ps.iter().zip(os) {
                let start = if previous == Best::NONE {
                    Best::bound(f32::INFINITY)
                } else {
                    Best { d2: closest_on_triangle(p, &self.tris[previous as usize]).d2, slot: previous }
                };
                let best = self.search(p, start);
                previous = best.slot;
                *o = self.result(p, best);
            }
        });
    }

    /// The largest squared distance from any point of `points` to the mesh
    /// (the directed sampled Hausdorff distance, squared): the same figure
    /// as the largest [`ClosestPoint::distance_squared`] of
    /// [`TriangleBvh::closest_many`], for a fraction of its work. A point
    /// only needs its exact distance when it may raise the maximum: its
    /// search stops at the first triangle nearer than the largest distance
    /// found so far (Taha & Hanbury's early break), and starts from its
    /// predecessor's triangle, which in a coherent order (a mesh's vertices,
    /// [`surface_samples`](crate::mesh::distance::surface_samples)) is
    /// usually near enough already. Parallel over fixed chunks sharing the
    /// running maximum; the result does not depend on the thread count or
    /// the order. Non-finite points are skipped; `None` for an empty tree or
    /// no finite point.
    pub fn farthest_distance_squared(&self, points: &[Vec3]) -> Option<f32> {
        use std::sync::atomic::{AtomicU32, Ordering};
        if self.is_empty() {
            return None;
        }
        // Non-negative f32s order as their bit patterns.
        let running = AtomicU32::new(0);
        let any = std::sync::atomic::AtomicBool::new(false);
        points.par_chunks(CHUNK).for_each(|ps| {
            let mut previous = Best::NONE;
            for &p in ps {
                if !p.is_finite() {
                    continue;
                }
                let floor = f32::from_bits(running.load(Ordering::Relaxed));
                let start = if previous == Best::NONE {
                    Best::bound(f32::INFINITY)
                } else {
                    Best { d2: closest_on_triangle(p, &self.tris[previous as usize]).d2, slot: previous }
                };
                let best = if start.d2 < floor { start } else { self.search_until(p, start, floor) };
                previous = best.slot;
                any.store(true, Ordering::Relaxed);
                if best.d2 >= floor {
                    // The search ran to the end: `best.d2` is the exact distance.
                    running.fetch_max(best.d2.to_bits(), Ordering::Relaxed);
                }
            }
        });
        any.into_inner().then(|| f32::from_bits(running.into_inner()))
    }

    fn result(&self, p: Vec3, best: Best) -> Option<ClosestPoint> {
        if best.slot == Best::NONE {
            return None;
        }
        let on = closest_on_triangle(p, &self.tris[best.slot as usize]);
        Some(ClosestPoint {
            point: on.point,
            triangle: self.ids[best.slot as usize],
            distance_squared: on.d2,
            barycentric: Vec3::new((1.0 - on.v - on.w).max(0.0), on.v, on.w),
        })
    }

    /// Ordered descent from the root, improving on `best`; nothing for a
    /// non-finite `p`.
    fn search(&self, p: Vec3, best: Best) -> Best {
        self.search_until(p, best, f32::NEG_INFINITY)
    }

    /// [`Self::search`] that returns as soon as it finds a triangle at a
    /// squared distance below `enough` (then the result is an upper bound
    /// under `enough`, not the nearest); exact otherwise.
    #[inline(always)]
    fn search_until(&self, p: Vec3, mut best: Best, enough: f32) -> Best {
        if !p.is_finite() {
            return Best::bound(-1.0);
        }
        let Some(root) = self.nodes.first() else { return best };
        let d2 = root.distance_squared(p);
        if d2.is_nan() || d2 > best.d2 {
            return best;
        }
        let mut stack = [(0u32, 0f32); STACK];
        let mut top = 0;
        let mut node = root;
        loop {
            if node.count > 0 {
                let first = node.first as usize;
                for slot in first..first + node.count as usize {
                    let t = &self.tris[slot];
                    let h = (p - t.a).dot(t.normal);
                    if h * h > best.d2 {
                        continue;
                    }
                    let d2 = closest_on_triangle(p, t).d2;
                    if d2 <= best.d2 {
                        best = Best { d2, slot: slot as u32 };
                        if d2 < enough {
                            return best;
                        }
                    }
                }
            } else {
                let left = node.first as usize;
                let (l, r) = (&self.nodes[left], &self.nodes[left + 1]);
                let (dl, dr) = (l.distance_squared(p), r.distance_squared(p));
                let (near, d_near, far, d_far) =
                    if dl <= dr { (l, dl, left + 1, dr) } else { (r, dr, left, dl) };
                if d_near <= best.d2 {
                    if d_far <= best.d2 {
                        stack[top] = (far as u32, d_far);
                        top += 1;
                    }
                    node = near;
                    continue;
                }
            }
            // Pop the nearest pending subtree still within the bound.
            loop {
                if top == 0 {
                    return best;
                }
                top -= 1;
                let (index, d2) = stack[top];
                if d2 <= best.d2 {
                    node = &self.nodes[index as usize];
                    break;
                }
            }
        }
    }
}

/// The point of triangle `corners` nearest to `p` (any triangle, degenerate
/// ones included: then the nearest point of its edges). The BVH's own
/// query, for callers with a single triangle.
pub fn closest_point_on_triangle(p: Vec3, corners: [Vec3; 3]) -> Vec3 {
    closest_on_triangle(p, &Tri::new(corners)).point
}

/// The nearest point of triangle `t` to `p` (see the [module docs](self)).
///
/// Inlined so that callers needing only the distance skip the rest.
#[inline(always)]
fn closest_on_triangle(p: Vec3, t: &Tri) -> OnTriangle {
    let ap = p - t.a;
    let v = ap.dot(t.grad_v);
    let w = ap.dot(t.grad_w);
    if v > 0.0 && w > 0.0 && v + w < 1.0 {
        let h = ap.dot(t.normal);
        return OnTriangle { d2: h * h, point: p - h * t.normal, v, w };
    }
    // Outside (or degenerate, where v = w = 0): the nearest point is on an
    // edge whose opposite corner's coordinate is violated. For a degenerate
    // triangle the edges ab and ac cover it.
    let mut best = OnTriangle { d2: f32::INFINITY, point: t.a, v: 0.0, w: 0.0 };
    let mut consider = |d: Vec3, v: f32, w: f32| {
        let d2 = d.length_squared();
        if d2 < best.d2 {
            best = OnTriangle { d2, point: p - d, v, w };
        }
    };
    if w <= 0.0 {
        let s = (ap.dot(t.ab) * t.inv_ab).clamp(0.0, 1.0);
        consider(ap - s * t.ab, s, 0.0);
    }
    if v <= 0.0 {
        let s = (ap.dot(t.ac) * t.inv_ac).clamp(0.0, 1.0);
        consider(ap - s * t.ac, 0.0, s);
    }
    if v + w >= 1.0 {
        let (bp, bc) = (ap - t.ab, t.ac - t.ab);
        let s = (bp.dot(bc) * t.inv_bc).clamp(0.0, 1.0);
        consider(bp - s * bc, 1.0 - s, s);
    }
    best
}

/// A triangle during the build: its bounding box and index.
#[derive(Debug, Clone, Copy)]
struct Item {
    lo: Vec3,
    hi: Vec3,
    id: u32,
}

impl Item {
    /// Twice the centroid of the box (the factor 2 cancels in binning).
    #[inline(always)]
    fn centroid2(&self) -> Vec3 {
        self.lo + self.hi
    }
}

/// A box `(min, max)`; empty as `(+∞, −∞)`.
type Bounds = (Vec3, Vec3);

const EMPTY: Bounds = (Vec3::INFINITY, Vec3::NEG_INFINITY);

/// `b` grown by the box `[lo, hi]`.
#[inline(always)]
fn grow((min, max): Bounds, lo: Vec3, hi: Vec3) -> Bounds {
    (min.min(lo), max.max(hi))
}

/// A chosen split of a node: the position in `items`, the children's boxes
/// and the bounds of their (doubled) centroids.
struct Split {
    mid: usize,
    boxes: [Bounds; 2],
    centroids: [Bounds; 2],
}

/// Top-down binned-SAH construction state. The items are kept in the
/// order they are partitioned into (so that every pass reads memory in
/// sequence), and each split hands its children their boxes (from its
/// bins) and centroid bounds (from its partition pass): one binning pass
/// for all three axes and one partition pass per node.
struct Builder {
    /// Per-triangle boxes, partitioned into leaf order; non-finite ones
    /// (from non-finite vertices, which a validated mesh does not have) are
    /// replaced by the origin so that binning stays well defined.
    items: Vec<Item>,
    nodes: Vec<Node>,
}

impl Builder {
    fn new(corners: &[[Vec3; 3]], build: BvhBuild) -> Self {
        let items: Vec<Item> = corners
            .iter()
            .enumerate()
            .map(|(id, &[a, b, c])| {
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                let (lo, hi) =
                    if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (Vec3::ZERO, Vec3::ZERO) };
                Item { lo, hi, id: id as u32 }
            })
            .collect();
        let n = items.len();
        let mut builder = Self { items, nodes: Vec::with_capacity(2 * n.div_ceil(MAX_LEAF)) };
        let (boxes, centroids) = builder.bounds(0, n);
        builder.nodes.push(Node { min: boxes.0, first: 0, max: boxes.1, count: n as u32 });
        match build {
            BvhBuild::Sah => builder.split(0, 0, centroids),
            BvhBuild::Morton => {
                let codes = builder.morton_order(centroids);
                builder.morton_split(0, &codes);
            }
        }
        builder
    }

    /// Sorts the items by the Morton code of their (doubled) centroids,
    /// quantized to [`MORTON_BITS`] bits per axis over the centroids'
    /// bounds, ties by their index (so the order is deterministic); returns
    /// the sorted codes.
    fn morton_order(&mut self, (cmin, cmax): Bounds) -> Vec<u32> {
        let cells = ((1u32 << MORTON_BITS) - 1) as f32;
        let extent = cmax - cmin;
        let scale =
            Vec3::from_array([0, 1, 2].map(|a| if extent[a] > 0.0 { cells / extent[a] } else { 0.0 }));
        let mut keyed: Vec<(u32, u32)> = self
            .items
            .iter()
            .enumerate()
            .map(|(i, t)| {
                // `as` saturates: a rounding just past the box stays in it.
                let q = ((t.centroid2() - cmin) * scale).to_array().map(|x| (x as u32).min(cells as u32));
                (spread_bits(q[0]) | spread_bits(q[1]) << 1 | spread_bits(q[2]) << 2, i as u32)
            })
            .collect();
        keyed.sort_unstable();
        self.items = keyed.iter().map(|&(_, i)| self.items[i as usize]).collect();
        keyed.into_iter().map(|(code, _)| code).collect()
    }

    /// Splits the node `index` of Morton-ordered items (`codes` their
    /// sorted codes) where its codes' highest differing bit changes, or in
    /// half when they are equal, down to leaves of at most [`MAX_LEAF`]
    /// triangles; sets the boxes on the way back up. Each split either
    /// consumes a bit or halves equal codes, so the depth is at most
    /// `3 MORTON_BITS + 32 + 1` (within [`STACK`]).
    fn morton_split(&mut self, index: usize, codes: &[u32]) -> Bounds {
        let node = self.nodes[index];
        let (start, end) = (node.first as usize, (node.first + node.count) as usize);
        let bounds = if end - start <= MAX_LEAF {
            self.bounds(start, end).0
        } else {
            let (first, last) = (codes[start], codes[end - 1]);
            let mid = if first == last {
                (start + end) / 2
            } else {
                let bit = 1u32 << (31 - (first ^ last).leading_zeros());
                start + codes[start..end].partition_point(|&c| c & bit == 0)
            };
            let left = self.nodes.len();
            self.nodes.extend([
                Node { min: Vec3::ZERO, first: start as u32, max: Vec3::ZERO, count: (mid - start) as u32 },
                Node { min: Vec3::ZERO, first: mid as u32, max: Vec3::ZERO, count: (end - mid) as u32 },
            ]);
            self.nodes[index].first = left as u32;
            self.nodes[index].count = 0;
            let (l, r) = (self.morton_split(left, codes), self.morton_split(left + 1, codes));
            grow(l, r.0, r.1)
        };
        (self.nodes[index].min, self.nodes[index].max) = bounds;
        bounds
    }

    /// The triangles' original indices in leaf order.
    fn order(&self) -> impl Iterator<Item = u32> + '_ {
        self.items.iter().map(|i| i.id)
    }

    /// Bounds of `items[start..end]`: of the boxes and of the (doubled)
    /// centroids.
    fn bounds(&self, start: usize, end: usize) -> (Bounds, Bounds) {
        self.items[start..end].iter().fold((EMPTY, EMPTY), |(b, c), t| {
            let c2 = t.centroid2();
            (grow(b, t.lo, t.hi), grow(c, c2, c2))
        })
    }

    /// Splits the leaf `index`, whose centroids have the bounds
    /// `centroids`, recursively while that pays off.
    fn split(&mut self, index: usize, depth: usize, centroids: Bounds) {
        let node = self.nodes[index];
        let (start, end) = (node.first as usize, (node.first + node.count) as usize);
        if end - start <= 1 {
            return;
        }
        let split = match self.sah_split(start, end, depth, half_area(node.min, node.max), centroids) {
            Some(split) => split,
            None if end - start <= MAX_LEAF => return,
            None => {
                let mid = self.median_split(start, end, centroids);
                let ((lb, lc), (rb, rc)) = (self.bounds(start, mid), self.bounds(mid, end));
                Split { mid, boxes: [lb, rb], centroids: [lc, rc] }
            }
        };
        let Split { mid, boxes: [lb, rb], centroids: [lc, rc] } = split;
        let left = self.nodes.len();
        self.nodes.extend([
            Node { min: lb.0, first: start as u32, max: lb.1, count: (mid - start) as u32 },
            Node { min: rb.0, first: mid as u32, max: rb.1, count: (end - mid) as u32 },
        ]);
        self.nodes[index].first = left as u32;
        self.nodes[index].count = 0;
        self.split(left, depth + 1, lc);
        self.split(left + 1, depth + 1, rc);
    }

    /// Partitions `items[start..end]` (a node of half-area `area` whose
    /// centroids have the bounds `(cmin, cmax)`) at the cheapest binned SAH
    /// plane. `None` when a leaf is cheaper (only for at most [`MAX_LEAF`]
    /// triangles), no plane separates the centroids, or the tree is too
    /// deep for SAH.
    fn sah_split(
        &mut self,
        start: usize,
        end: usize,
        depth: usize,
        area: f32,
        (cmin, cmax): Bounds,
    ) -> Option<Split> {
        let n = end - start;
        if depth >= SAH_DEPTH {
            return None;
        }
        let extent = cmax - cmin;
        let usable = [0, 1, 2].map(|axis| extent[axis] > 0.0 && !extent[axis].is_nan());
        let scale = Vec3::from_array(
            [0, 1, 2].map(|axis| if usable[axis] { BINS as f32 / extent[axis] } else { 0.0 }),
        );
        // All three axes' bins in one pass.
        let mut bins = [[(EMPTY, 0usize); BINS]; 3];
        for t in &self.items[start..end] {
            let c2 = t.centroid2();
            for axis in 0..3 {
                let bin = &mut bins[axis][bin_of(c2[axis], cmin[axis], scale[axis])];
                *bin = (grow(bin.0, t.lo, t.hi), bin.1 + 1);
            }
        }
        // (cost, axis, last bin on the left, left box, right box)
        let mut best: Option<(f32, usize, usize, Bounds, Bounds)> = None;
        for axis in (0..3).filter(|&axis| usable[axis]) {
            let bins = &bins[axis];
            // Cost of "bins[..=i] | bins[i + 1..]" from a suffix and a prefix sweep.
            let mut right = [(0f32, EMPTY); BINS];
            let mut acc = (EMPTY, 0);
            for i in (1..BINS).rev() {
                acc = (grow(acc.0, bins[i].0.0, bins[i].0.1), acc.1 + bins[i].1);
                right[i - 1] = (half_area(acc.0.0, acc.0.1) * acc.1 as f32, acc.0);
            }
            let mut acc = (EMPTY, 0);
            for i in 0..BINS - 1 {
                acc = (grow(acc.0, bins[i].0.0, bins[i].0.1), acc.1 + bins[i].1);
                let cost = half_area(acc.0.0, acc.0.1) * acc.1 as f32 + right[i].0;
                if acc.1 > 0 && acc.1 < n && best.is_none_or(|(c, ..)| cost < c) {
                    best = Some((cost, axis, i, acc.0, right[i].1));
                }
            }
        }
        let (cost, axis, last, left_box, right_box) = best?;
        // Splitting costs one box test (≈ one triangle test) per visit.
        if n <= MAX_LEAF && area + cost >= area * n as f32 {
            return None;
        }
        let (mut mid, mut centroids) = (start, [EMPTY, EMPTY]);
        for i in start..end {
            let c2 = self.items[i].centroid2();
            if bin_of(c2[axis], cmin[axis], scale[axis]) <= last {
                self.items.swap(i, mid);
                mid += 1;
                centroids[0] = grow(centroids[0], c2, c2);
            } else {
                centroids[1] = grow(centroids[1], c2, c2);
            }
        }
        Some(Split { mid, boxes: [left_box, right_box], centroids })
    }

    /// Halves `items[start..end]` (centroid bounds `(cmin, cmax)`) at the
    /// centroid median of the widest axis.
    fn median_split(&mut self, start: usize, end: usize, (cmin, cmax): Bounds) -> usize {
        let axis = (cmax - cmin).max_position();
        let mid = (start + end) / 2;
        let key = |t: &Item| t.lo[axis] + t.hi[axis];
        self.items[start..end].select_nth_unstable_by(mid - start, |a, b| key(a).total_cmp(&key(b)));
        mid
    }
}

/// Bits per axis of a [`BvhBuild::Morton`] code.
const MORTON_BITS: u32 = 10;

/// The low [`MORTON_BITS`] bits of `x` moved to every third bit (bit `i`
/// to bit `3i`).
#[inline]
fn spread_bits(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
}

/// Bin of coordinate `x` in `BINS` bins of width `1/scale` from `min`.
#[inline]
fn bin_of(x: f32, min: f32, scale: f32) -> usize {
    (((x - min) * scale) as usize).min(BINS - 1)
}

/// Half the surface area of the box `[lo, hi]` (0 when empty).
#[inline]
fn half_area(lo: Vec3, hi: Vec3) -> f32 {
    let d = (hi - lo).max(Vec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::metrics::test_meshes::{bunny, torus, uv_sphere};
    use proptest::prelude::*;

    /// Every way of building a tree.
    const BUILDS: [BvhBuild; 2] = [BvhBuild::Sah, BvhBuild::Morton];

    /// The nearest triangle by testing all of them: `(distance², index)`.
    fn brute_force(mesh: &TriMesh, p: Vec3) -> Option<(f32, u32)> {
        (0..mesh.triangles.len())
            .map(|t| (closest_on_triangle(p, &Tri::new(mesh.corners(t))).d2, t as u32))
            .min_by(|x, y| x.0.total_cmp(&y.0))
    }

    /// Depth of the subtree at `node` (a leaf has depth 1).
    fn depth(bvh: &TriangleBvh, node: usize) -> usize {
        let n = bvh.nodes[node];
        if n.count > 0 { 1 } else { 1 + depth(bvh, n.first as usize).max(depth(bvh, n.first as usize + 1)) }
    }

    /// Checks a query result against brute force and its own consistency.
    #[track_caller]
    fn check(mesh: &TriMesh, p: Vec3, got: Option<ClosestPoint>) {
        let (want, _) = brute_force(mesh, p).expect("non-empty mesh");
        let got = got.expect("a finite query on a non-empty mesh has an answer");
        let [a, b, c] = mesh.corners(got.triangle as usize);
        // Rounding of a distance is relative to the coordinates' magnitude,
        // not to the distance (a BVH and brute force may round differently).
        let scale = 1.0 + a.abs().max(b.abs()).max(c.abs()).max(p.abs()).max_element();
        let diff = (got.distance_squared.sqrt() - want.sqrt()).abs();
        assert!(
            diff <= 1e-6 * scale,
            "at {p}: expected d² {want}, got {}, distance difference {diff}",
            got.distance_squared
        );
        let w = got.barycentric;
        assert!(w.min_element() >= 0.0 && (w.element_sum() - 1.0).abs() < 1e-5, "barycentric {w}");
        let off_triangle = (w.x * a + w.y * b + w.z * c - got.point).length();
        assert!(off_triangle <= 1e-5 * scale, "point {} is {off_triangle} off its triangle", got.point);
        let (d, reported) = ((p - got.point).length(), got.distance_squared.sqrt());
        assert!((d - reported).abs() <= 1e-6 * scale, "point at distance {d}, distance reported {reported}");
    }

    /// Squared distance from `p` to the triangle `abc` in `f64`: the plane
    /// projection when it lies inside, else the nearest of the three edges.
    fn reference_distance_squared(p: Vec3, [a, b, c]: [Vec3; 3]) -> f64 {
        let [p, a, b, c] = [p, a, b, c].map(|x| x.as_dvec3());
        let segment = |s: glam::DVec3, e: glam::DVec3| {
            let d = e - s;
            let t = if d.length_squared() > 0.0 {
                ((p - s).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - s - t * d).length_squared()
        };
        let edges = segment(a, b).min(segment(a, c)).min(segment(b, c));
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let n = ab.cross(ac);
        if n.length_squared() == 0.0 {
            return edges;
        }
        let q = ap - n * (ap.dot(n) / n.length_squared());
        let (v, w) = (q.cross(ac).dot(n) / n.length_squared(), ab.cross(q).dot(n) / n.length_squared());
        if v >= 0.0 && w >= 0.0 && v + w <= 1.0 { (ap - q).length_squared().min(edges) } else { edges }
    }

    fn mesh_strategy() -> impl Strategy<Value = TriMesh> {
        let coord = -1.0f32..1.0;
        (prop::collection::vec([coord.clone(), coord.clone(), coord], 1..30), 1..80usize).prop_flat_map(
            |(pts, nt)| {
                let nv = pts.len() as u32;
                let positions: Vec<Vec3> = pts.into_iter().map(Vec3::from_array).collect();
                prop::collection::vec([0..nv, 0..nv, 0..nv], nt)
                    .prop_map(move |triangles| TriMesh::new(positions.clone(), triangles).unwrap())
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn matches_brute_force_on_random_meshes(
            mesh in mesh_strategy(),
            points in prop::collection::vec([-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0], 1..40),
        ) {
            let points: Vec<Vec3> = points.into_iter().map(Vec3::from_array).collect();
            for build in BUILDS {
                let bvh = TriangleBvh::with_build(&mesh, build);
                let mut many = vec![None; points.len()];
                bvh.closest_many(&points, &mut many);
                for (&p, &m) in points.iter().zip(&many) {
                    check(&mesh, p, bvh.closest(p));
                    check(&mesh, p, m);
                }
            }
        }

        /// No point of a dense barycentric sample of the triangle is nearer
        /// than the reported closest point.
        #[test]
        fn triangle_closest_point_is_nearest(
            corners in prop::array::uniform3(prop::array::uniform3(-1.0f32..1.0)),
            p in [-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0],
        ) {
            let [a, b, c] = corners.map(Vec3::from_array);
            let p = Vec3::from_array(p);
            let on = closest_on_triangle(p, &Tri::new([a, b, c]));
            prop_assert!(on.v >= 0.0 && on.w >= 0.0 && on.v + on.w <= 1.0 + 1e-6);
            let want = reference_distance_squared(p, [a, b, c]);
            prop_assert!((on.d2.sqrt() as f64 - want.sqrt()).abs() < 1e-6, "expected {want}, got {}", on.d2);
            let n = 60;
            for i in 0..=n {
                for j in 0..=n - i {
                    let q = a + (i as f32 / n as f32) * (b - a) + (j as f32 / n as f32) * (c - a);
                    prop_assert!((p - q).length_squared() >= on.d2 - 1e-5, "sample {q} nearer than {}", on.d2);
                }
            }
        }
    }

    /// Slivers and needles of every thinness down to exact degeneracy, in all
    /// three corner orders, against the `f64` reference: the distance error
    /// stays at `f32` rounding of the query offset (|p| ≤ 3 here).
    #[test]
    fn slivers_and_needles_are_accurate() {
        let mut state = 1u64;
        let mut rnd = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        for _ in 0..20000 {
            let [a, b, off, p] = [(); 4].map(|_| Vec3::new(rnd(), rnd(), rnd()));
            let p = 3.0 * p;
            for k in 0..16 {
                let eps = if k == 15 { 0.0 } else { 10f32.powi(-(k / 2)) };
                // Even k: a sliver (c near the line ab); odd k: a needle (c near a).
                let c = if k % 2 == 0 { a + rnd().abs() * (b - a) + eps * off } else { a + eps * off };
                for corners in [[a, b, c], [b, c, a], [c, a, b]] {
                    let got = closest_on_triangle(p, &Tri::new(corners)).d2 as f64;
                    let want = reference_distance_squared(p, corners);
                    let err = (got.sqrt() - want.sqrt()).abs();
                    assert!(err < 2e-6, "{corners:?} from {p}: expected {}, got {}", want.sqrt(), got.sqrt());
                }
            }
        }
    }

    #[test]
    fn degenerate_triangles_give_finite_exact_answers() {
        let (a, b) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0));
        let cases = [
            // (corners, query, expected distance²)
            ([a, a, a], Vec3::new(1.0, 1.0, 1.0), 3.0),
            ([a, b, b], Vec3::new(1.0, 1.0, 0.0), 1.0),
            ([a, a, b], Vec3::new(3.0, 0.0, 4.0), 17.0),
            ([a, b, 0.5 * b], Vec3::new(1.5, -2.0, 0.0), 4.0),
            ([0.5 * b, a, b], Vec3::new(-1.0, 0.0, 0.0), 1.0),
            ([b, a, 0.5 * b], Vec3::new(2.5, 0.0, 0.0), 0.25),
        ];
        for (corners, p, want) in cases {
            let on = closest_on_triangle(p, &Tri::new(corners));
            assert!((on.d2 - want).abs() < 1e-6, "{corners:?} from {p}: expected {want}, got {on:?}");
            let mesh = TriMesh::new(corners.to_vec(), vec![[0, 1, 2]]).unwrap();
            check(&mesh, p, TriangleBvh::new(&mesh).closest(p));
        }
    }

    #[test]
    fn empty_mesh_and_bad_queries_give_none() {
        let empty = TriangleBvh::new(&TriMesh::default());
        assert!(empty.is_empty());
        assert_eq!(empty.closest(Vec3::ZERO), None);
        let s = uv_sphere(Vec3::ZERO, 1.0, 8, 12);
        let bvh = TriangleBvh::new(&s);
        assert_eq!(bvh.len(), s.triangles.len());
        for bad in [Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
            assert_eq!(bvh.closest(bad), None);
        }
        let points = [Vec3::ZERO, Vec3::NAN, Vec3::X * 3.0];
        let mut out = [None; 3];
        bvh.closest_many(&points, &mut out);
        assert!(out[0].is_some() && out[1].is_none() && out[2].is_some());
    }

    #[test]
    fn closest_within_respects_the_bound() {
        let s = uv_sphere(Vec3::ZERO, 1.0, 16, 32);
        let bvh = TriangleBvh::new(&s);
        let p = Vec3::new(0.0, 0.0, 3.0); // the pole is exactly 2 away
        assert_eq!(bvh.closest(p).unwrap().distance_squared, 4.0);
        assert_eq!(bvh.closest_point_within(p, 1.99), None);
        assert_eq!(bvh.closest_point_within(p, 2.0).unwrap().point, Vec3::Z);
        assert_eq!(bvh.closest_point_within(p, -1.0), None);
        assert_eq!(bvh.closest_point_within(p, f32::NAN), None);
    }

    #[test]
    fn duplicated_triangles_build_a_shallow_tree() {
        // Identical centroids defeat SAH; the median fallback must still split.
        let mut positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        positions.extend((1..2000).map(|i| Vec3::splat(0.5 / i as f32)));
        let triangles = (0..3000).map(|i| if i % 2 == 0 { [0, 1, 2] } else { [0, 1, 3 + i / 2] }).collect();
        let mesh = TriMesh::new(positions, triangles).unwrap();
        for build in BUILDS {
            let bvh = TriangleBvh::with_build(&mesh, build);
            assert!(depth(&bvh, 0) <= STACK, "{build:?}: depth {}", depth(&bvh, 0));
            check(&mesh, Vec3::new(0.2, 0.2, 1.0), bvh.closest(Vec3::new(0.2, 0.2, 1.0)));
        }
    }

    #[test]
    fn bunny_and_torus_match_brute_force() {
        for (mesh, build) in
            [bunny(), torus(3.0, 1.0, 40, 20)].into_iter().flat_map(|m| BUILDS.map(|b| (m.clone(), b)))
        {
            let bvh = TriangleBvh::with_build(&mesh, build);
            assert!(depth(&bvh, 0) <= STACK);
            assert_eq!(bvh.len(), mesh.triangles.len());
            let bounds = mesh.bounds().padded(0.2);
            // A deterministic scatter of points over the padded box.
            let points: Vec<Vec3> = (0..2000u32)
                .map(|i| {
                    let f = |k: u32| {
                        ((i.wrapping_mul(2654435761).wrapping_add(k * 40503)) % 1009) as f32 / 1008.0
                    };
                    bounds.min + bounds.size() * Vec3::new(f(1), f(2), f(3))
                })
                .collect();
            let mut out = vec![None; points.len()];
            bvh.closest_many(&points, &mut out);
            for (&p, &o) in points.iter().zip(&out) {
                check(&mesh, p, o);
            }
        }
    }

    #[test]
    fn farthest_is_the_largest_closest_distance() {
        let mesh = torus(3.0, 1.0, 40, 20);
        let bvh = TriangleBvh::new(&mesh);
        let other = bunny();
        // The bunny's vertices (a coherent order) and a scatter, with a
        // non-finite point that must be skipped.
        let mut points: Vec<Vec3> = other.positions.iter().map(|&p| p * 4.0).collect();
        points.extend((0..500).map(|i| Vec3::new((i % 7) as f32, (i % 11) as f32 - 5.0, (i % 5) as f32)));
        points.insert(100, Vec3::NAN);
        let mut out = vec![None; points.len()];
        bvh.closest_many(&points, &mut out);
        let want = out.iter().flatten().map(|c| c.distance_squared).fold(0.0, f32::max);
        assert!(want > 1.0, "the scatter reaches away from the torus: {want}");
        assert_eq!(bvh.farthest_distance_squared(&points), Some(want));
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(one.install(|| bvh.farthest_distance_squared(&points)), Some(want));
        assert_eq!(bvh.farthest_distance_squared(&[Vec3::NAN]), None);
        assert_eq!(TriangleBvh::default().farthest_distance_squared(&points), None);
    }

    /// Times 128³ queries over the bunny's box padded by 10 % per side, in
    /// x-fastest lattice order. Run with
    /// `cargo test --release -p isomorph-common bvh_timing -- --ignored --nocapture`.
    #[test]
    #[ignore = "timing helper"]
    fn bvh_timing() {
        let mesh = bunny();
        for build in BUILDS {
            let start = std::time::Instant::now();
            let bvh = TriangleBvh::with_build(&mesh, build);
            let build_time = start.elapsed();
            let bounds = mesh.bounds().padded(0.1);
            let n = 128;
            let step = bounds.size() / (n - 1) as f32;
            let points: Vec<Vec3> = (0..n * n * n)
                .map(|i| {
                    bounds.min + step * Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32)
                })
                .collect();
            let mut out = vec![None; points.len()];
            let start = std::time::Instant::now();
            bvh.closest_many(&points, &mut out);
            let query = start.elapsed();
            let start = std::time::Instant::now();
            let hits =
                bvh.nearest_on_lattice(&Lattice::spanning(&bounds, glam::UVec3::splat(n as u32))).unwrap();
            println!("{build:?} lattice: {:?}", start.elapsed());
            assert!(
                hits.iter()
                    .zip(&out)
                    .all(|(h, o)| (h.distance - o.unwrap().distance_squared.sqrt()).abs() < 1e-5)
            );
            let mean =
                out.iter().map(|o| o.unwrap().distance_squared.sqrt() as f64).sum::<f64>() / out.len() as f64;
            println!(
                "{build:?} bunny BVH: {} nodes, depth {}, build {build_time:?}; {} queries in {query:?} ({} threads), mean distance {mean:.4}",
                bvh.nodes.len(),
                depth(&bvh, 0),
                points.len(),
                rayon::current_num_threads()
            );
            assert!(out.iter().all(Option::is_some));
        }
    }
}
