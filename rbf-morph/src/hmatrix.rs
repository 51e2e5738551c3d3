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
//! Error bound: each admissible block `Φ[s, t]` is replaced by `U Vᵀ` with
//! `‖Φ[s, t] − U Vᵀ‖_F ≤ ε ‖U Vᵀ‖_F` as estimated by ACA's stopping rule
//! (the norm of the last cross against the running norm of the
//! approximation); dense blocks are exact. Summed over blocks,
//! `‖Φ − Φ_H‖_F ≲ ε ‖Φ‖_F`, so a product is accurate to about
//! `ε ‖Φ‖_F ‖x‖₂` (tested against the dense product).

use crate::kernel::Kernel;
use rayon::prelude::*;
use std::ops::Range;

/// Most points in a leaf cluster.
pub(crate) const LEAF: usize = 48;
/// The admissibility parameter η.
const ETA: f64 = 3.0;
/// Product accumulators of [`HMatrix::matvec`]: a fixed count, so that the
/// summation order does not depend on the number of threads.
const PARTS: usize = 16;

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
        let half = idx.len() / 2;
        idx.select_nth_unstable_by(half, |&a, &b| {
            positions[a * dim + axis].total_cmp(&positions[b * dim + axis]).then(a.cmp(&b))
        });
        let (left, right) = idx.split_at_mut(half);
        let l = split(nodes, left, start, positions, dim, leaf);
        let r = split(nodes, right, start + half, positions, dim, leaf);
        nodes[id].children = Some((l, r));
    }
    id
}

/// A block of the lower triangle of `Φ`.
enum Block {
    /// Dense, row-major `rows × cols`.
    Dense { rows: Range<usize>, cols: Range<usize>, a: Vec<f64> },
    /// `U Vᵀ`, `U` stored term by term (`rank × rows`), `V` likewise.
    LowRank { rows: Range<usize>, cols: Range<usize>, u: Vec<f64>, v: Vec<f64> },
}

impl Block {
    /// Stored f64 values.
    fn len(&self) -> usize {
        match self {
            Block::Dense { a, .. } => a.len(),
            Block::LowRank { u, v, .. } => u.len() + v.len(),
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
            Block::LowRank { rows, cols, u, v } => {
                for (uk, vk) in u.chunks_exact(rows.len()).zip(v.chunks_exact(cols.len())) {
                    let a = dot(vk, &x[cols.clone()]);
                    let b = dot(uk, &x[rows.clone()]);
                    y[rows.clone()].iter_mut().zip(uk).for_each(|(y, u)| *y += a * u);
                    y[cols.clone()].iter_mut().zip(vk).for_each(|(y, v)| *y += b * v);
                }
            }
        }
    }

    /// Multiply–adds of [`Block::apply`] (for balancing the work).
    fn cost(&self) -> usize {
        self.len() * 2
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
    /// Builds `Φ + λI` for the points of `tree`, compressing admissible
    /// blocks by ACA to the relative tolerance `eps`.
    pub fn new(tree: &ClusterTree, kernel: Kernel, smoothing: f64, eps: f64) -> Self {
        let mut pairs = Vec::new();
        block_pairs(tree, 0, 0, &mut pairs);
        let blocks: Vec<Block> = pairs
            .into_par_iter()
            .map(|(s, t, admissible)| {
                let (rows, cols) = (tree.nodes[s].range.clone(), tree.nodes[t].range.clone());
                let low_rank =
                    if admissible { aca(tree, kernel, rows.clone(), cols.clone(), eps) } else { None };
                match low_rank {
                    Some((u, v)) => Block::LowRank { rows, cols, u, v },
                    None => {
                        let mut a = dense_block(tree, kernel, rows.clone(), cols.clone());
                        if rows == cols {
                            for i in 0..rows.len() {
                                a[i * rows.len() + i] += smoothing;
                            }
                        }
                        Block::Dense { rows, cols, a }
                    }
                }
            })
            .collect();
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
        Self { blocks, parts, n: tree.order.len() }
    }

    /// Bytes stored in the blocks.
    #[cfg(test)]
    pub fn bytes(&self) -> usize {
        self.blocks.iter().map(Block::len).sum::<usize>() * size_of::<f64>()
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

/// Adaptive cross approximation with partial pivoting of the block
/// `Φ[rows, cols]` to the relative Frobenius tolerance `eps`: `(U, V)` term
/// by term, or `None` when its storage would reach the dense block's
/// (rank `k` with `k (m + n) ≥ m n`).
fn aca(
    tree: &ClusterTree,
    kernel: Kernel,
    rows: Range<usize>,
    cols: Range<usize>,
    eps: f64,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (m, n) = (rows.len(), cols.len());
    let max_rank = m * n / (m + n);
    let (mut u, mut v) = (Vec::<f64>::new(), Vec::<f64>::new());
    let mut used = vec![false; m];
    let mut norm2 = 0.0f64;
    let mut i = 0;
    let mut rank = 0;
    let mut row = vec![0.0; n];
    let mut col = vec![0.0; m];
    let mut col_point = vec![0.0; tree.dim];
    loop {
        used[i] = true;
        kernel_row(tree, kernel, tree.point(rows.start + i), cols.clone(), &mut row);
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
                None => return Some((u, v)),
            }
        }
        if rank >= max_rank {
            return None;
        }
        row.iter_mut().for_each(|r| *r /= pivot);
        col_point.copy_from_slice(tree.point(cols.start + j));
        kernel_row(tree, kernel, &col_point, rows.clone(), &mut col);
        for k in 0..rank {
            let vk = v[k * n + j];
            col.iter_mut().zip(&u[k * m..(k + 1) * m]).for_each(|(c, u)| *c -= vk * u);
        }
        let (nu, nv) = (dot(&col, &col), dot(&row, &row));
        let cross: f64 =
            (0..rank).map(|k| dot(&u[k * m..(k + 1) * m], &col) * dot(&v[k * n..(k + 1) * n], &row)).sum();
        norm2 += nu * nv + 2.0 * cross;
        u.extend_from_slice(&col);
        v.extend_from_slice(&row);
        rank += 1;
        if nu * nv <= eps * eps * norm2 {
            return Some((u, v));
        }
        let next = (0..m).filter(|&r| !used[r]).fold(None, |b: Option<(usize, f64)>, r| match b {
            Some((_, best)) if col[r].abs() <= best => b,
            _ => Some((r, col[r].abs())),
        });
        match next {
            Some((r, _)) => i = r,
            None => return Some((u, v)),
        }
    }
}

/// The dot product, in eight interleaved partial sums added in a fixed
/// order (so that it vectorizes and still does not depend on anything but
/// its inputs).
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut lanes = [0.0f64; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        lanes.iter_mut().zip(x.iter().zip(y)).for_each(|(lane, (x, y))| *lane += x * y);
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
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
    fn product_matches_the_dense_matrix_within_the_tolerance() {
        let n = 1500;
        let p = two_spheres(n);
        let tree = ClusterTree::new(&p, 4, LEAF);
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            for eps in [1e-4, 1e-9] {
                let h = HMatrix::new(&tree, kernel, 0.0, eps);
                assert!(h.blocks.iter().any(|b| matches!(b, Block::LowRank { .. })), "nothing compressed");
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
