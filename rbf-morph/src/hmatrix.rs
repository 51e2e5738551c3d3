//! The kernel matrix `Φ` as a hierarchical matrix (H-matrix).
//!
//! A cluster tree splits the constraints recursively at the median of the
//! longest side of their bounding box, down to leaves of at most
//! [`LEAF`] points; the constraints are renumbered so that every cluster is
//! a contiguous range. A pair of clusters `(s, t)` is *admissible* when
//! `max(diam s, diam t) ≤ η dist(s, t)` (strong admissibility, bounding
//! boxes, η = [`ETA`]); on such a pair the kernel is smooth and the block
//! `Φ[s, t]` is numerically low-rank. The block tree covers the lower
//! triangle of `Φ` (the matrix is symmetric) with admissible blocks,
//! compressed by adaptive cross approximation with partial pivoting (ACA,
//! Bebendorf 2000) to a relative Frobenius tolerance, and dense blocks of
//! leaf pairs. For constraints on surfaces (two 2D manifolds in 4D for a
//! shape transformation) there are `O(n)` blocks of bounded rank, so storage
//! and a product `Φx` cost `O(n log n)`.
//!
//! Storage: the terms of each low-rank block are kept in f64, or as 32-
//! or 16-bit integers (with a scale per term), each term in the most compact
//! form whose rounding error fits the block's tolerance (see [`aca`]):
//! most of ACA's terms are many orders of magnitude below the block's
//! norm and need few digits.
//!
//! Error bound: each admissible `m × n` block `Φ[s, t]` is replaced by
//! `U Vᵀ` with `‖Φ[s, t] − U Vᵀ‖_F ≤ ε max(‖Φ[s, t]‖_F, ρ √(m n))` as
//! estimated by ACA's stopping rule (the norm of the last cross against the
//! running norm of the approximation), `ρ` the root mean square entry of
//! `Φ`; storing the terms in reduced precision adds at most as much again.
//! Dense blocks are exact. Summed over blocks,
//! `‖Φ − Φ_H‖_F ≲ 2 √2 ε ‖Φ‖_F`, so a product is accurate to about
//! `ε ‖Φ‖_F ‖x‖₂` (tested against the dense product).

use crate::kernel::Kernel;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Most points in a leaf cluster.
pub(crate) const LEAF: usize = 48;
/// The admissibility parameter η.
const ETA: f64 = 3.0;
/// Product accumulators of [`HMatrix::matvec`]: a fixed count, so that the
/// summation order does not depend on the number of threads.
pub(crate) const PARTS: usize = 16;

/// One cluster: a contiguous range of the renumbered points and its
/// bounding box.
pub(crate) struct Node {
    /// The points of the cluster (in tree order).
    pub range: Range<usize>,
    /// The two sub-clusters, or `None` for a leaf.
    pub children: Option<(usize, usize)>,
    /// Lower corner of the bounding box.
    pub lo: Vec<f64>,
    /// Upper corner of the bounding box.
    pub hi: Vec<f64>,
}

impl Node {
    /// The diagonal of the bounding box.
    pub fn diameter(&self) -> f64 {
        self.lo.iter().zip(&self.hi).map(|(a, b)| (b - a) * (b - a)).sum::<f64>().sqrt()
    }

    /// The distance between two bounding boxes.
    fn distance(&self, other: &Node) -> f64 {
        (0..self.lo.len())
            .map(|k| {
                let gap = (other.lo[k] - self.hi[k]).max(self.lo[k] - other.hi[k]).max(0.0);
                gap * gap
            })
            .sum::<f64>()
            .sqrt()
    }
}

/// A binary cluster tree over points in `dim` dimensions.
pub(crate) struct ClusterTree {
    /// The clusters; the root is node 0.
    pub nodes: Vec<Node>,
    /// `order[i]` is the input index of the `i`-th point in tree order.
    pub order: Vec<usize>,
    /// The points in tree order, row-major `n × dim`.
    pub points: Vec<f64>,
    /// The dimension.
    pub dim: usize,
}

impl ClusterTree {
    /// The tree of `positions` (row-major `n × dim`, `n ≥ 1`), with leaves
    /// of at most `leaf` points.
    pub fn new(positions: &[f64], dim: usize, leaf: usize) -> Self {
        let n = positions.len() / dim;
        let mut order: Vec<usize> = (0..n).collect();
        let mut nodes = Vec::new();
        split(&mut nodes, &mut order, 0, positions, dim, leaf.max(1));
        let points = order.iter().flat_map(|&i| positions[i * dim..(i + 1) * dim].iter().copied()).collect();
        Self { nodes, order, points, dim }
    }

    /// Point `i` (tree order).
    pub fn point(&self, i: usize) -> &[f64] {
        &self.points[i * self.dim..(i + 1) * self.dim]
    }
}

/// Appends the cluster of `idx` (the points `start..start + idx.len()` in
/// tree order) and its descendants; returns its node index.
fn split(
    nodes: &mut Vec<Node>,
    idx: &mut [usize],
    start: usize,
    positions: &[f64],
    dim: usize,
    leaf: usize,
) -> usize {
    let mut lo = vec![f64::INFINITY; dim];
    let mut hi = vec![f64::NEG_INFINITY; dim];
    for &i in idx.iter() {
        for k in 0..dim {
            lo[k] = lo[k].min(positions[i * dim + k]);
            hi[k] = hi[k].max(positions[i * dim + k]);
        }
    }
    let id = nodes.len();
    let range = start..start + idx.len();
    nodes.push(Node { range, children: None, lo, hi });
    if idx.len() > leaf {
        let node = &nodes[id];
        let axis = (0..dim).max_by(|&a, &b| (node.hi[a] - node.lo[a]).total_cmp(&(node.hi[b] - node.lo[b])));
        let axis = axis.expect("dim ≥ 1");
        let half = split_index(idx, positions, dim, axis);
        let (left, right) = idx.split_at_mut(half);
        let l = split(nodes, left, start, positions, dim, leaf);
        let r = split(nodes, right, start + half, positions, dim, leaf);
        nodes[id].children = Some((l, r));
    }
    id
}

/// Sorts `idx` along `axis` and returns where to split it: the position
/// nearest the median at which the coordinate changes, so that points with
/// equal coordinates (a layer such as a shape transformation's `t = 0`)
/// are never cut apart. Cutting a layer at the median would put an
/// arbitrary subset of its points, spread over the whole layer, into a
/// cluster of the other one: a subdomain scattered over a whole shape,
/// whose local solve is no approximation of the global one.
fn split_index(idx: &mut [usize], positions: &[f64], dim: usize, axis: usize) -> usize {
    let x = |i: usize| positions[i * dim + axis];
    idx.sort_unstable_by(|&a, &b| x(a).total_cmp(&x(b)).then(a.cmp(&b)));
    let half = idx.len() / 2;
    let changes = |i: &usize| x(idx[*i - 1]) < x(idx[*i]);
    let above = (half..idx.len()).find(changes);
    let below = (1..=half).rev().find(changes);
    match (below, above) {
        (Some(b), Some(a)) => {
            if half - b <= a - half {
                b
            } else {
                a
            }
        }
        (Some(b), None) => b,
        (None, Some(a)) => a,
        // Every point has the same coordinate (only when all coincide).
        (None, None) => half,
    }
}

/// A block of the lower triangle of `Φ`.
enum Block {
    /// Dense, row-major `rows × cols`.
    Dense { rows: Range<usize>, cols: Range<usize>, a: Vec<f64> },
    /// `U Vᵀ` (see [`LowRank`]; boxed: most blocks are dense, and the
    /// enum is as large as its largest variant).
    LowRank { rows: Range<usize>, cols: Range<usize>, f: Box<LowRank> },
}

/// The factors of a low-rank block `U Vᵀ`, term by term (`U` is
/// `rank × rows`, `V` likewise): the leading terms in f64, then smaller
/// ones as 32-bit integers, the smallest as 16-bit integers, each integer
/// term times a scale — each as compact as its share of the block's
/// tolerance allows (see [`aca`]).
struct LowRank {
    u: Vec<f64>,
    v: Vec<f64>,
    i32: Quantized<i32>,
    i16: Quantized<i16>,
}

impl LowRank {
    /// Stored factor entries (all precisions).
    fn len(&self) -> usize {
        self.u.len() + self.v.len() + self.i32.len() + self.i16.len()
    }
}

/// Terms `u_k v_kᵀ ≈ scale_k q_u q_vᵀ` with `q_u`, `q_v` integers of type
/// `T` (`U` is `rank × rows`, `V` likewise).
struct Quantized<T> {
    u: Vec<T>,
    v: Vec<T>,
    scale: Vec<f64>,
}

impl<T> Quantized<T> {
    /// Stored integer entries.
    fn len(&self) -> usize {
        self.u.len() + self.v.len()
    }

    /// Bytes stored.
    fn bytes(&self) -> usize {
        self.len() * size_of::<T>() + self.scale.len() * size_of::<f64>()
    }
}

/// An integer type that terms are quantized to: `x ≈ s q`, the largest
/// entry of `x` at `±MAX`.
trait Level: Copy + Into<f64> {
    /// The largest magnitude.
    const MAX: f64;
    /// `v` (at most `MAX` in magnitude) rounded to the nearest integer.
    fn round(v: f64) -> Self;
}

impl Level for i16 {
    const MAX: f64 = i16::MAX as f64;
    fn round(v: f64) -> Self {
        v.round() as i16
    }
}

impl Level for i32 {
    const MAX: f64 = i32::MAX as f64;
    fn round(v: f64) -> Self {
        v.round() as i32
    }
}

impl Block {
    /// Bytes stored.
    fn bytes(&self) -> usize {
        match self {
            Block::Dense { a, .. } => a.len() * size_of::<f64>(),
            Block::LowRank { f, .. } => {
                (f.u.len() + f.v.len()) * size_of::<f64>() + f.i32.bytes() + f.i16.bytes()
            }
        }
    }

    /// `y[rows] += B x[cols]` and, off the diagonal, `y[cols] += Bᵀ x[rows]`.
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Block::Dense { rows, cols, a } => {
                let (xc, w) = (&x[cols.clone()], cols.len());
                let diagonal = rows == cols;
                for (r, row) in a.chunks_exact(w).enumerate() {
                    let i = rows.start + r;
                    y[i] += dot(row, xc);
                    if !diagonal {
                        let xi = x[i];
                        y[cols.clone()].iter_mut().zip(row).for_each(|(y, a)| *y += a * xi);
                    }
                }
            }
            Block::LowRank { rows, cols, f } => {
                apply_terms(&f.u, &f.v, std::iter::repeat(1.0), rows, cols, x, y);
                apply_terms(&f.i32.u, &f.i32.v, f.i32.scale.iter().copied(), rows, cols, x, y);
                apply_terms(&f.i16.u, &f.i16.v, f.i16.scale.iter().copied(), rows, cols, x, y);
            }
        }
    }

    /// Multiply–adds of [`Block::apply`] (for balancing the work).
    fn cost(&self) -> usize {
        match self {
            Block::Dense { a, .. } => a.len() * 2,
            Block::LowRank { f, .. } => f.len() * 2,
        }
    }
}

/// `y[rows] += U S Vᵀ x[cols]` and `y[cols] += V S Uᵀ x[rows]` for the
/// terms `U`, `V` stored in any precision, `S` the diagonal of `scales`
/// (accumulated in f64).
fn apply_terms<T: Copy + Into<f64>>(
    u: &[T],
    v: &[T],
    scales: impl Iterator<Item = f64>,
    rows: &Range<usize>,
    cols: &Range<usize>,
    x: &[f64],
    y: &mut [f64],
) {
    for ((uk, vk), s) in u.chunks_exact(rows.len()).zip(v.chunks_exact(cols.len())).zip(scales) {
        let a = s * dot(vk, &x[cols.clone()]);
        let b = s * dot(uk, &x[rows.clone()]);
        y[rows.clone()].iter_mut().zip(uk).for_each(|(y, &u)| *y += a * u.into());
        y[cols.clone()].iter_mut().zip(vk).for_each(|(y, &v)| *y += b * v.into());
    }
}

/// The block structure of a cluster tree's H-matrix before any entry is
/// computed: the cluster pairs of the lower triangle and the bytes of the
/// near-field (dense) ones, so that the memory can be checked first.
pub(crate) struct BlockPlan {
    /// `(s, t, admissible)` for each block.
    pairs: Vec<(usize, usize, bool)>,
    /// Bytes of the inadmissible (dense, f64) blocks: exact.
    pub near_bytes: usize,
}

impl BlockPlan {
    /// The blocks of `tree`'s H-matrix.
    pub fn new(tree: &ClusterTree) -> Self {
        let mut pairs = Vec::new();
        block_pairs(tree, 0, 0, &mut pairs);
        let near_bytes = pairs
            .iter()
            .filter(|p| !p.2)
            .map(|&(s, t, _)| tree.nodes[s].range.len() * tree.nodes[t].range.len() * size_of::<f64>())
            .sum();
        Self { pairs, near_bytes }
    }
}

/// The symmetric matrix `Φ + λI` of a cluster tree's points as an H-matrix
/// (see the module docs).
pub(crate) struct HMatrix {
    blocks: Vec<Block>,
    /// Block ranges of the [`PARTS`] accumulators.
    parts: Vec<Range<usize>>,
    n: usize,
}

impl HMatrix {
    /// Builds `Φ + λI` for the points of `tree` with the blocks of `plan`,
    /// compressing admissible blocks by ACA to the relative tolerance
    /// `eps`; `Err(bytes)` as soon as the blocks would take more than
    /// `budget` bytes (the admissible blocks' ranks are not known before
    /// ACA, so their bytes are counted as they are made; `bytes` is the
    /// count when it went over). Whether it fails depends only on the
    /// total, not on the order in which the threads make the blocks.
    pub fn new(
        tree: &ClusterTree,
        plan: BlockPlan,
        kernel: Kernel,
        smoothing: f64,
        eps: f64,
        budget: usize,
    ) -> Result<Self, usize> {
        if plan.near_bytes > budget {
            return Err(plan.near_bytes);
        }
        let rms = rms_entry(tree, kernel);
        let used = AtomicUsize::new(plan.near_bytes);
        let blocks: Option<Vec<Block>> = plan
            .pairs
            .into_par_iter()
            .map_init(AcaWork::default, |work, (s, t, admissible)| {
                if admissible && used.load(Ordering::Relaxed) > budget {
                    return None;
                }
                let (rows, cols) = (tree.nodes[s].range.clone(), tree.nodes[t].range.clone());
                let low_rank = if admissible {
                    aca(tree, kernel, rows.clone(), cols.clone(), eps, rms, work)
                } else {
                    None
                };
                let block = match low_rank {
                    Some(f) => Block::LowRank { rows, cols, f: Box::new(f) },
                    None => {
                        let mut a = dense_block(tree, kernel, rows.clone(), cols.clone());
                        if rows == cols {
                            for i in 0..rows.len() {
                                a[i * rows.len() + i] += smoothing;
                            }
                        }
                        Block::Dense { rows, cols, a }
                    }
                };
                let bytes = block.bytes();
                let over = admissible && used.fetch_add(bytes, Ordering::Relaxed) + bytes > budget;
                (!over).then_some(block)
            })
            .collect();
        let Some(blocks) = blocks else {
            return Err(used.into_inner());
        };
        let total: usize = blocks.iter().map(Block::cost).sum();
        let mut parts = Vec::with_capacity(PARTS);
        let (mut start, mut acc) = (0, 0);
        for (i, b) in blocks.iter().enumerate() {
            acc += b.cost();
            if acc * PARTS >= total * (parts.len() + 1) && parts.len() + 1 < PARTS {
                parts.push(start..i + 1);
                start = i + 1;
            }
        }
        parts.push(start..blocks.len());
        Ok(Self { blocks, parts, n: tree.order.len() })
    }

    /// Bytes stored in the blocks.
    pub fn bytes(&self) -> usize {
        self.blocks.iter().map(Block::bytes).sum::<usize>()
    }

    /// `y ← (Φ + λI) x` (tree order). Parallel over a fixed set of block
    /// ranges with one accumulator each, summed in a fixed order: the
    /// result does not depend on the thread count.
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        let partial: Vec<Vec<f64>> = self
            .parts
            .par_iter()
            .map(|range| {
                let mut acc = vec![0.0; self.n];
                self.blocks[range.clone()].iter().for_each(|b| b.apply(x, &mut acc));
                acc
            })
            .collect();
        y.iter_mut().for_each(|v| *v = 0.0);
        for acc in &partial {
            y.iter_mut().zip(acc).for_each(|(y, a)| *y += a);
        }
    }
}

/// The block pairs `(s, t, admissible)` of the lower triangle below the
/// pair `(s, t)` (`s` not before `t`).
fn block_pairs(tree: &ClusterTree, s: usize, t: usize, out: &mut Vec<(usize, usize, bool)>) {
    let (ns, nt) = (&tree.nodes[s], &tree.nodes[t]);
    if s == t {
        match ns.children {
            None => out.push((s, s, false)),
            Some((a, b)) => {
                block_pairs(tree, a, a, out);
                block_pairs(tree, b, a, out);
                block_pairs(tree, b, b, out);
            }
        }
        return;
    }
    if ns.diameter().max(nt.diameter()) <= ETA * ns.distance(nt) {
        out.push((s, t, true));
        return;
    }
    match (ns.children, nt.children) {
        (None, None) => out.push((s, t, false)),
        (Some((a, b)), None) => [a, b].into_iter().for_each(|c| block_pairs(tree, c, t, out)),
        (None, Some((a, b))) => [a, b].into_iter().for_each(|c| block_pairs(tree, s, c, out)),
        (Some((a, b)), Some((c, d))) => {
            if ns.range.len() >= nt.range.len() {
                [a, b].into_iter().for_each(|x| block_pairs(tree, x, t, out));
            } else {
                [c, d].into_iter().for_each(|x| block_pairs(tree, s, x, out));
            }
        }
    }
}

/// `φ(|x_i − x_j|)` for `i` in `rows`, `j` in `cols`, row-major.
pub(crate) fn dense_block(
    tree: &ClusterTree,
    kernel: Kernel,
    rows: Range<usize>,
    cols: Range<usize>,
) -> Vec<f64> {
    let w = cols.len();
    let mut a = vec![0.0; rows.len() * w];
    for (r, row) in a.chunks_exact_mut(w).enumerate() {
        kernel_row(tree, kernel, tree.point(rows.start + r), cols.clone(), row);
    }
    a
}

/// `out[j] = φ(|x − x_j|)` for `j` in `cols` (vectorized kernel).
fn kernel_row(tree: &ClusterTree, kernel: Kernel, x: &[f64], cols: Range<usize>, out: &mut [f64]) {
    let d = tree.dim;
    for (o, p) in out.iter_mut().zip(tree.points[cols.start * d..cols.end * d].chunks_exact(d)) {
        *o = p.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
    }
    kernel.eval_r2_in_place(out);
}

/// ACA's factors grow by this many terms at a time.
const GROW: usize = 8;

/// ACA's working vectors, reused from block to block on a thread: the
/// factors in f64 and the term norms, the current row and column, the
/// rows used. Reusing them (rather than allocating and freeing factors of
/// tens of MB per block) keeps the allocator from scattering freed pieces
/// between the stored blocks, which had cost some 300 MB of resident
/// memory at 100000 constraints.
#[derive(Default)]
struct AcaWork {
    u: Vec<f64>,
    v: Vec<f64>,
    terms: Vec<f64>,
    row: Vec<f64>,
    col: Vec<f64>,
    used: Vec<bool>,
}

/// Pairs sampled by [`rms_entry`].
const SAMPLES: usize = 1 << 16;

/// The root mean square of the entries of `Φ`, estimated from [`SAMPLES`]
/// fixed (deterministic) pairs of distinct points: `rms · n ≈ ‖Φ‖_F`.
fn rms_entry(tree: &ClusterTree, kernel: Kernel) -> f64 {
    let n = tree.order.len();
    if n < 2 {
        return 0.0;
    }
    let mut r2: Vec<f64> = (0..SAMPLES)
        .map(|s| {
            let i = s.wrapping_mul(7919) % n;
            let j = (i + 1 + s.wrapping_mul(104_729) % (n - 1)) % n;
            tree.point(i).iter().zip(tree.point(j)).map(|(a, b)| (a - b) * (a - b)).sum()
        })
        .collect();
    kernel.eval_r2_in_place(&mut r2);
    (dot(&r2, &r2) / SAMPLES as f64).sqrt()
}

/// Adaptive cross approximation with partial pivoting of the block
/// `Φ[rows, cols]` (`m × n`) to the Frobenius tolerance
/// `eps · max(‖Φ[rows, cols]‖_F, rms √(m n))`, `rms` the root mean square
/// entry of the whole `Φ`: blocks whose entries are small against the
/// matrix's (near admissible pairs of the growing kernels) get the share
/// of the global error budget `ε ‖Φ‖_F` their size allows rather than a
/// relative tolerance of their own. Returns the factors, or `None` when
/// their storage would reach the dense block's (rank `k` with
/// `k (m + n) ≥ m n`).
///
/// The terms are then stored as compactly as the tolerance allows: from
/// the last (smallest) one backwards, as 16-bit integers times a scale
/// while the sum of their exact rounding errors stays within half the
/// tolerance, then as 32-bit integers times a scale while the total stays
/// within the tolerance, the rest in f64. So a block's error stays within
/// twice its tolerance. (32-bit integers scaled to the largest entry are
/// at least as accurate in norm as f32 for terms of up to 65536 entries,
/// and far more for ACA's smooth, flat terms, so more terms leave f64.) ACA's terms shrink roughly geometrically to `ε` of the
/// block's norm, and most of them are far below it.
#[allow(clippy::too_many_arguments)]
fn aca(
    tree: &ClusterTree,
    kernel: Kernel,
    rows: Range<usize>,
    cols: Range<usize>,
    eps: f64,
    rms: f64,
    work: &mut AcaWork,
) -> Option<LowRank> {
    let (m, n) = (rows.len(), cols.len());
    let floor2 = rms * rms * (m * n) as f64;
    let norm2 = aca_terms(tree, kernel, rows, cols, eps * eps * floor2, eps, work)?;
    let (u, v) = (&work.u[..], &work.v[..]);
    let budget = eps * norm2.max(floor2).sqrt();
    let mut spent = 0.0;
    let j16 = quantizable::<i16>(u, v, (m, n), work.terms.len(), &mut spent, 0.5 * budget);
    let j32 = quantizable::<i32>(u, v, (m, n), j16, &mut spent, budget);
    let rank = work.terms.len();
    Some(LowRank {
        i32: quantized(u, v, (m, n), j32..j16),
        i16: quantized(u, v, (m, n), j16..rank),
        u: u[..j32 * m].to_vec(),
        v: v[..j32 * n].to_vec(),
    })
}

/// The first of the terms of `U` (`rank × m`) and `V` (`rank × n`) before
/// `end` that can be quantized to integers `T`: from the last one
/// backwards while `spent` plus their exact errors stays within `limit`
/// (they are added to `spent`).
fn quantizable<T: Level>(
    u: &[f64],
    v: &[f64],
    (m, n): (usize, usize),
    end: usize,
    spent: &mut f64,
    limit: f64,
) -> usize {
    let mut first = end;
    while first > 0 {
        let k = first - 1;
        let (uk, vk) = (&u[k * m..(k + 1) * m], &v[k * n..(k + 1) * n]);
        let ((_, eu), (_, ev)) = (quantize::<T>(uk, |_| ()), quantize::<T>(vk, |_| ()));
        // ‖s q_u q_vᵀ − u vᵀ‖_F ≤ e_u ‖v‖ + ‖u‖ e_v + e_u e_v.
        let error = eu * dot(vk, vk).sqrt() + dot(uk, uk).sqrt() * ev + eu * ev;
        if *spent + error > limit {
            break;
        }
        *spent += error;
        first = k;
    }
    first
}

/// The terms `range` of `U` (`rank × m`) and `V` (`rank × n`) quantized
/// to integers `T`, each vector with its own scale.
fn quantized<T: Level>(u: &[f64], v: &[f64], (m, n): (usize, usize), range: Range<usize>) -> Quantized<T> {
    let mut q = Quantized {
        u: Vec::with_capacity(range.len() * m),
        v: Vec::with_capacity(range.len() * n),
        scale: Vec::with_capacity(range.len()),
    };
    for k in range {
        let (su, _) = quantize::<T>(&u[k * m..(k + 1) * m], |x| q.u.push(x));
        let (sv, _) = quantize::<T>(&v[k * n..(k + 1) * n], |x| q.v.push(x));
        q.scale.push(su * sv);
    }
    q
}

/// `x` as integers `q` (passed to `out` in order) and a scale `s`
/// (`x ≈ s q`, the largest entry at `±T::MAX`); returns `s` and the exact
/// error `‖s q − x‖₂`.
fn quantize<T: Level>(x: &[f64], mut out: impl FnMut(T)) -> (f64, f64) {
    let largest = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let s = if largest == 0.0 { 0.0 } else { largest / T::MAX };
    let mut error2 = 0.0;
    for &v in x {
        let q = if s == 0.0 { T::round(0.0) } else { T::round(v / s) };
        error2 += (s * q.into() - v).powi(2);
        out(q);
    }
    (s, error2.sqrt())
}

/// The terms of [`aca`] in f64 into `work` (`U` in `work.u`, `V` in
/// `work.v`, `‖u_k‖ ‖v_k‖` in `work.terms`), stopping when the last term's
/// squared norm is below `eps² ‖U Vᵀ‖_F²` or `floor2`; returns
/// `‖U Vᵀ‖_F²`, or `None` at the break-even rank.
fn aca_terms(
    tree: &ClusterTree,
    kernel: Kernel,
    rows: Range<usize>,
    cols: Range<usize>,
    floor2: f64,
    eps: f64,
    work: &mut AcaWork,
) -> Option<f64> {
    let (m, n) = (rows.len(), cols.len());
    let max_rank = m * n / (m + n);
    let AcaWork { u, v, terms, row, col, used } = work;
    for w in [&mut *u, &mut *v, &mut *terms] {
        w.clear();
    }
    used.clear();
    used.resize(m, false);
    row.resize(n, 0.0);
    col.resize(m, 0.0);
    let (row, col) = (&mut row[..n], &mut col[..m]);
    let mut norm2 = 0.0f64;
    let mut i = 0;
    let mut rank = 0;
    let mut col_point = [0.0; 8];
    let col_point = &mut col_point[..tree.dim];
    loop {
        used[i] = true;
        kernel_row(tree, kernel, tree.point(rows.start + i), cols.clone(), row);
        for k in 0..rank {
            let uk = u[k * m + i];
            row.iter_mut().zip(&v[k * n..(k + 1) * n]).for_each(|(r, v)| *r -= uk * v);
        }
        let (j, pivot) = row
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |b, (j, r)| if r.abs() > b.1.abs() { (j, *r) } else { b });
        if pivot.abs() <= f64::MIN_POSITIVE {
            // A zero residual row: try an unused row, or stop.
            match (0..m).find(|&r| !used[r]) {
                Some(next) => {
                    i = next;
                    continue;
                }
                None => return Some(norm2),
            }
        }
        if rank >= max_rank {
            return None;
        }
        row.iter_mut().for_each(|r| *r /= pivot);
        col_point.copy_from_slice(tree.point(cols.start + j));
        kernel_row(tree, kernel, col_point, rows.clone(), col);
        for k in 0..rank {
            let vk = v[k * n + j];
            col.iter_mut().zip(&u[k * m..(k + 1) * m]).for_each(|(c, u)| *c -= vk * u);
        }
        let (nu, nv) = (dot(col, col), dot(row, row));
        let cross: f64 =
            (0..rank).map(|k| dot(&u[k * m..(k + 1) * m], col) * dot(&v[k * n..(k + 1) * n], row)).sum();
        norm2 += nu * nv + 2.0 * cross;
        // Grow by a few terms at a time, not by doubling: the factors of
        // the largest blocks are tens of MB.
        if u.capacity() < u.len() + m {
            u.reserve_exact(GROW * m);
            v.reserve_exact(GROW * n);
        }
        u.extend_from_slice(col);
        v.extend_from_slice(row);
        rank += 1;
        terms.push((nu * nv).sqrt());
        if nu * nv <= (eps * eps * norm2).max(floor2) {
            return Some(norm2);
        }
        let next = (0..m).filter(|&r| !used[r]).fold(None, |b: Option<(usize, f64)>, r| match b {
            Some((_, best)) if col[r].abs() <= best => b,
            _ => Some((r, col[r].abs())),
        });
        match next {
            Some((r, _)) => i = r,
            None => return Some(norm2),
        }
    }
}

/// The dot product, in eight interleaved partial sums added in a fixed
/// order (so that it vectorizes and still does not depend on anything but
/// its inputs).
pub(crate) fn dot<T: Copy + Into<f64>>(a: &[T], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut lanes = [0.0f64; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        lanes.iter_mut().zip(x.iter().zip(y)).for_each(|(lane, (&x, y))| *lane += x.into() * y);
    }
    let tail: f64 = ra.iter().zip(rb).map(|(&x, y)| x.into() * y).sum();
    lanes.iter().sum::<f64>() + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on two spheres (radius 0.3) at `t = ±0.5` in 4D.
    fn two_spheres(n: usize) -> Vec<f64> {
        let golden = std::f64::consts::PI * (3.0 - 5.0f64.sqrt());
        (0..n)
            .flat_map(|i| {
                let z = 1.0 - 2.0 * ((i / 2) as f64 + 0.5) / (n / 2) as f64;
                let r = (1.0 - z * z).sqrt();
                let a = golden * (i / 2) as f64;
                [0.3 * r * a.cos(), 0.3 * r * a.sin(), 0.3 * z, if i % 2 == 0 { -0.5 } else { 0.5 }]
            })
            .collect()
    }

    #[test]
    fn tree_is_a_permutation_with_small_leaves() {
        let p = two_spheres(1000);
        let tree = ClusterTree::new(&p, 4, LEAF);
        let mut sorted = tree.order.clone();
        sorted.sort_unstable();
        assert!(sorted.iter().enumerate().all(|(i, &j)| i == j));
        for node in &tree.nodes {
            match node.children {
                None => assert!(node.range.len() <= LEAF),
                Some((a, b)) => {
                    assert_eq!(tree.nodes[a].range.start, node.range.start);
                    assert_eq!(tree.nodes[a].range.end, tree.nodes[b].range.start);
                    assert_eq!(tree.nodes[b].range.end, node.range.end);
                }
            }
            for i in node.range.clone() {
                let x = tree.point(i);
                assert!((0..4).all(|k| node.lo[k] <= x[k] && x[k] <= node.hi[k]));
            }
        }
    }

    #[test]
    fn clusters_never_cut_a_layer_of_equal_coordinates() {
        // 700 points at t = −0.5 and 300 at t = +0.5: the median of t falls
        // inside the first layer.
        let p: Vec<f64> = two_spheres(1400)
            .chunks_exact(4)
            .enumerate()
            .filter(|(i, _)| i % 2 == 0 || i % 7 < 3)
            .flat_map(|(_, x)| x.iter().copied())
            .collect();
        let count = |t: f64| p.chunks_exact(4).filter(|x| x[3] == t).count();
        assert_eq!((count(-0.5), count(0.5)), (700, 300));
        let tree = ClusterTree::new(&p, 4, LEAF);
        let (a, b) = tree.nodes[0].children.unwrap();
        assert_eq!((tree.nodes[a].range.len(), tree.nodes[b].range.len()), (700, 300));
        for node in &tree.nodes[1..] {
            assert_eq!(node.lo[3], node.hi[3], "a cluster below the root spans both layers");
        }
        // Within a layer the split stays at the median.
        let (c, _) = tree.nodes[a].children.unwrap();
        assert_eq!(tree.nodes[c].range.len(), 350);
    }

    #[test]
    fn quantize_reports_its_exact_error() {
        let x: Vec<f64> = (0..200).map(|i| ((i * 37) % 101) as f64 / 7.0 - 5.0).collect();
        let mut q = Vec::new();
        let (s, error) = quantize::<i16>(&x, |v| q.push(v));
        let exact = q.iter().zip(&x).map(|(&q, &x)| (s * f64::from(q) - x).powi(2)).sum::<f64>().sqrt();
        assert_eq!(error, exact);
        // Half a step per entry at most, and not exact.
        let largest = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(q.iter().any(|&q| q.unsigned_abs() == i16::MAX as u16));
        assert!(error <= 0.5 * s * (x.len() as f64).sqrt() && error > 0.0, "{error:e}");
        assert!(s <= largest / 32000.0);
        let mut zeros = Vec::new();
        assert_eq!(quantize::<i16>(&[0.0; 4], |v| zeros.push(v)), (0.0, 0.0));
        assert_eq!(zeros, [0; 4]);
        // 32-bit: the same rule, 2¹⁶ times finer.
        let mut q32 = Vec::new();
        let (s32, error32) = quantize::<i32>(&x, |v| q32.push(v));
        assert!(q32.iter().any(|&q| q.unsigned_abs() == i32::MAX as u32));
        assert!(error32 <= 0.5 * s32 * (x.len() as f64).sqrt() && error32 < 1e-4 * error, "{error32:e}");
    }

    #[test]
    fn blocks_over_the_budget_stop_the_build() {
        let p = two_spheres(1500);
        let tree = ClusterTree::new(&p, 4, LEAF);
        let plan = BlockPlan::new(&tree);
        let near = plan.near_bytes;
        let full = HMatrix::new(&tree, plan, Kernel::ThinPlate, 0.0, 1e-9, usize::MAX).unwrap();
        let bytes = full.bytes();
        assert!(near > 0 && bytes > near, "near {near}, all {bytes}");
        // Exactly enough: built, the same blocks.
        let exact = HMatrix::new(&tree, BlockPlan::new(&tree), Kernel::ThinPlate, 0.0, 1e-9, bytes).unwrap();
        assert_eq!(exact.bytes(), bytes);
        // One byte short, or room for the near blocks only: refused, with
        // the count reached (over the budget, at most the full size).
        for budget in [bytes - 1, near] {
            let Err(reached) =
                HMatrix::new(&tree, BlockPlan::new(&tree), Kernel::ThinPlate, 0.0, 1e-9, budget)
            else {
                panic!("built within {budget} bytes");
            };
            assert!(reached > budget && reached <= bytes, "{reached} for budget {budget}");
        }
        // Not even the near blocks fit: refused before any is made.
        assert_eq!(
            HMatrix::new(&tree, BlockPlan::new(&tree), Kernel::ThinPlate, 0.0, 1e-9, near - 1).err(),
            Some(near)
        );
    }

    #[test]
    fn product_matches_the_dense_matrix_within_the_tolerance() {
        let n = 1500;
        let p = two_spheres(n);
        let tree = ClusterTree::new(&p, 4, LEAF);
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            for eps in [1e-4, 1e-9] {
                let h = HMatrix::new(&tree, BlockPlan::new(&tree), kernel, 0.0, eps, usize::MAX).unwrap();
                assert!(h.blocks.iter().any(|b| matches!(b, Block::LowRank { .. })), "nothing compressed");
                // The smallest terms are stored in reduced precision.
                let reduced =
                    |b: &Block| matches!(b, Block::LowRank { f, .. } if f.i32.len() + f.i16.len() > 0);
                assert!(h.blocks.iter().any(reduced), "{kernel:?} ε {eps:e}: all terms in f64");
                assert!(h.bytes() < n * n * 8 / 2, "{} bytes", h.bytes());
                let x: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0).collect();
                let mut y = vec![0.0; n];
                h.matvec(&x, &mut y);
                let a = dense_block(&tree, kernel, 0..n, 0..n);
                let frob = dot(&a, &a).sqrt();
                let err: f64 = a
                    .chunks_exact(n)
                    .zip(&y)
                    .map(|(row, yi)| (dot(row, &x) - yi).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let bound = eps * frob * dot(&x, &x).sqrt();
                assert!(err <= bound, "{kernel:?} ε {eps:e}: error {err:e} > bound {bound:e}");
                // Not trivially exact either: the coarse tolerance shows.
                if eps > 1e-5 {
                    assert!(err > 1e-3 * bound, "{kernel:?}: suspiciously exact {err:e}");
                }
            }
        }
    }
}
