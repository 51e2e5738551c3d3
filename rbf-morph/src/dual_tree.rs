//! Fast evaluation of a 3D slice on a whole lattice: a dual tree traversal
//! with barycentric Lagrange interpolation on both sides (BLDTT, Wilson,
//! Vaughn & Krasny, "A GPU-accelerated fast multipole method based on
//! barycentric Lagrange interpolation and dual tree traversal", 2021),
//! specialised to a regular lattice of targets.
//!
//! The sources are the [`treecode`](crate::treecode)'s: the slice's centres
//! in `S + 1 = 4` dimensions (`(c_j, √w_j)`), a k-d tree with Chebyshev
//! proxies per cluster. The targets are the lattice's nodes `(p, 0)`,
//! split as a binary tree of index boxes (the axis with the most nodes
//! halved until a box has at most [`LEAF_NODES`] nodes; binary rather than
//! octree splits give more box sizes, so fewer sources wait for the leaves,
//! where far sums reach fewest nodes per Chebyshev point). Every target box
//! carries the tensor-product Chebyshev points ([`ORDER`] per axis) of its
//! bounding box.
//!
//! [`ORDER`]: crate::treecode::ORDER
//!
//! The traversal starts with the whole lattice and the source root as the
//! only candidate. At a target box each candidate cluster is
//! - **separated** (`r_cluster + r_box ≤ θ R`, `R` the distance of the
//!   boxes' centres, θ = [`THETA`]): its proxies (or its sources, when it
//!   has fewer sources than proxies) are summed at the box's Chebyshev
//!   points — a cluster–cluster interaction;
//! - **opened** when it is wider than the box (or the box is a leaf) and has
//!   children: its children are examined instead;
//! - **passed down** to the box's children otherwise; at a leaf box, each
//!   source of a leaf cluster that is not separated is taken on its own: a
//!   source separated from the box as a point (`r_box ≤ θ R`) is summed at
//!   the box's Chebyshev points, the others exactly at every node (the near
//!   field). At the end slices of a morph (t = 0, 1), where one shape's
//!   centres lie in the slice, this halves the work of the near field.
//!
//! A box's far field (its own interactions plus its parent's far field,
//! interpolated to its Chebyshev points) is interpolated to its children's
//! points, and at a leaf to its nodes. Every interpolation is separable
//! (three small matrix products per box).
//!
//! # Error bound
//! The same as the treecode's, `|f_fast(x) − f_direct(x)| ≤ ε Σ_j |λ_j|
//! R_max^k` in normalized coordinates (`ε` = [`PAIR_ERROR_TPS`] for
//! `r² log r` with `k = 2`, [`PAIR_ERROR_CUBIC`] for `r³` with `k = 3`),
//! plus the `f32` round-off both paths share: every far source reaches a
//! node through one two-sided (or, for clusters without proxies,
//! target-sided) Chebyshev interpolation of a separated pair at some box,
//! whose error the constant bounds (`pair_error_stays_within_the_stated_constant`
//! in the treecode tests measures both, point sources included); the box's interpolant, carried
//! down to its children's points and re-interpolated there, is a tensor
//! polynomial of degree `ORDER − 1` per axis, which the children's
//! interpolation of the same degree reproduces exactly, so carrying it down
//! adds only round-off.
//!
//! Every box is evaluated from its parent's data alone, in a fixed order,
//! so the result does not depend on the number of threads.
//!
//! [`PAIR_ERROR_TPS`]: crate::treecode::PAIR_ERROR_TPS
//! [`PAIR_ERROR_CUBIC`]: crate::treecode::PAIR_ERROR_CUBIC

use crate::slice::Sources;
use crate::treecode::{Axis, Bbox, MAX_DIMS, THETA, Treecode};
use rayon::prelude::*;

/// Most lattice nodes in a leaf box of the target tree (8³; measured
/// against 256 and 1024 in `docs/EXPERIMENTS.md`).
pub const LEAF_NODES: usize = 512;

/// A lattice of targets in normalized coordinates: node `(i, j, k)` is at
/// `(axes[0][i], axes[1][j], axes[2][k])`, `i` fastest in the output.
#[derive(Debug, Clone)]
pub(crate) struct Lattice {
    pub axes: [Vec<f32>; 3],
}

/// A box of the lattice: node index ranges `lo[d]..hi[d]` per axis.
#[derive(Debug, Clone, Copy)]
struct IndexBox {
    lo: [usize; 3],
    hi: [usize; 3],
}

/// The sums of one leaf box, nodes `i` fastest.
struct LeafSums {
    cell: IndexBox,
    sums: Vec<f64>,
}

/// A box's far field: its values at the box's Chebyshev points.
struct FarField {
    axes: [Axis; 3],
    values: Vec<f64>,
}

impl IndexBox {
    fn side(&self, d: usize) -> usize {
        self.hi[d] - self.lo[d]
    }

    fn is_leaf(&self) -> bool {
        self.side(0) * self.side(1) * self.side(2) <= LEAF_NODES
    }

    fn bbox(&self, lattice: &Lattice) -> Bbox {
        let mut b = Bbox { lo: [0.0; MAX_DIMS], hi: [0.0; MAX_DIMS] };
        for d in 0..3 {
            let (a, z) = (f64::from(lattice.axes[d][self.lo[d]]), f64::from(lattice.axes[d][self.hi[d] - 1]));
            (b.lo[d], b.hi[d]) = (a.min(z), a.max(z));
        }
        b
    }

    /// The two boxes made by halving the axis with the most nodes (the
    /// first of equals).
    fn children(&self) -> [IndexBox; 2] {
        let axis = (0..3).fold(0, |a, d| if self.side(d) > self.side(a) { d } else { a });
        let mid = self.lo[axis] + self.side(axis) / 2;
        let (mut first, mut second) = (*self, *self);
        first.hi[axis] = mid;
        second.lo[axis] = mid;
        [first, second]
    }
}

/// `values` (a tensor over `from`'s points, axis 0 fastest) evaluated at the
/// tensor product of the coordinates `to` (axis 0 fastest).
fn interpolate(from: &[Axis; 3], values: &[f64], to: [&[f64]; 3]) -> Vec<f64> {
    let mut basis = Vec::new();
    // Per axis, the (targets × sources) Lagrange matrix.
    let matrices: Vec<Vec<f64>> = (0..3)
        .map(|d| {
            let mut m = Vec::with_capacity(to[d].len() * from[d].nodes.len());
            for &y in to[d] {
                if from[d].nodes.len() == 1 {
                    m.push(1.0);
                } else {
                    from[d].basis(y, &mut basis);
                    m.extend_from_slice(&basis);
                }
            }
            m
        })
        .collect();
    // Contract one axis at a time: the shape goes from (n0, n1, n2) sources
    // to (t0, t1, t2) targets.
    let mut shape = [from[0].nodes.len(), from[1].nodes.len(), from[2].nodes.len()];
    let mut current = values.to_vec();
    for d in 0..3 {
        let (n, t) = (shape[d], to[d].len());
        let inner: usize = shape[..d].iter().product();
        let outer: usize = shape[d + 1..].iter().product();
        let mut next = vec![0.0f64; inner * t * outer];
        for o in 0..outer {
            for (ti, row) in matrices[d].chunks_exact(n).enumerate() {
                let dst = &mut next[(o * t + ti) * inner..(o * t + ti + 1) * inner];
                for (si, &w) in row.iter().enumerate() {
                    let src = &current[(o * n + si) * inner..(o * n + si + 1) * inner];
                    dst.iter_mut().zip(src).for_each(|(a, b)| *a += w * b);
                }
            }
        }
        shape[d] = t;
        current = next;
    }
    current
}

impl Treecode<3> {
    /// The kernel sums at every node of `lattice` into `out` (`i` fastest),
    /// by the dual tree traversal of the module docs, in parallel.
    pub(crate) fn lattice_sums(&self, lattice: &Lattice, out: &mut [f64]) {
        let dims = [lattice.axes[0].len(), lattice.axes[1].len(), lattice.axes[2].len()];
        assert_eq!(out.len(), dims.iter().product::<usize>(), "lattice_sums: out does not match the lattice");
        if out.is_empty() {
            return;
        }
        let root = IndexBox { lo: [0; 3], hi: dims };
        for leaf in self.visit(lattice, root, vec![0], None) {
            let c = leaf.cell;
            let mut sums = leaf.sums.iter();
            for k in c.lo[2]..c.hi[2] {
                for j in c.lo[1]..c.hi[1] {
                    let row = (k * dims[1] + j) * dims[0];
                    out[row + c.lo[0]..row + c.hi[0]].iter_mut().zip(&mut sums).for_each(|(o, s)| *o = *s);
                }
            }
        }
    }

    /// The sums over the nodes of `cell`, given the source clusters
    /// `candidates` not yet taken by its ancestors and its parent's far
    /// field.
    fn visit(
        &self,
        lattice: &Lattice,
        cell: IndexBox,
        candidates: Vec<usize>,
        parent: Option<&FarField>,
    ) -> Vec<LeafSums> {
        let bbox = cell.bbox(lattice);
        let (centre, radius) = (bbox.centre(), bbox.radius());
        let leaf = cell.is_leaf();
        let (mut far, mut near) = (Sources::<3>::default(), Sources::<3>::default());
        let mut passed = Vec::new();
        let mut stack = candidates;
        stack.reverse();
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            let distance = (0..MAX_DIMS).map(|d| (node.centre[d] - centre[d]).powi(2)).sum::<f64>().sqrt();
            let (start, end) = node.sources;
            if node.radius + radius <= THETA * distance {
                if node.proxies.1 > node.proxies.0 {
                    far.extend_from(&self.proxies, node.proxies.0..node.proxies.1);
                } else {
                    far.extend_from(&self.sources, start..end);
                }
            } else if let Some(c) = node.children.filter(|_| leaf || node.radius > radius) {
                stack.push(c + 1);
                stack.push(c);
            } else if leaf {
                // Each source on its own: a point separated from the box
                // (`r_box ≤ θ R`) goes through the box's interpolation.
                let src = &self.sources;
                for j in start..end {
                    let r2 = f64::from(src.offset[j])
                        + (0..3).map(|d| (f64::from(src.coords[d][j]) - centre[d]).powi(2)).sum::<f64>();
                    let to = if radius * radius <= THETA * THETA * r2 { &mut far } else { &mut near };
                    to.extend_from(src, j..j + 1);
                }
            } else {
                passed.push(i);
            }
        }
        let axes: [Axis; 3] = std::array::from_fn(|d| Axis::new(bbox.lo[d], bbox.hi[d]));
        let points: [Vec<f64>; 3] = std::array::from_fn(|d| axes[d].nodes.clone());
        let mut field = parent.map(|p| FarField {
            values: interpolate(&p.axes, &p.values, [&points[0], &points[1], &points[2]]),
            axes: axes.clone(),
        });
        if far.len() > 0 {
            let mut nodes = Vec::new();
            for &z in &points[2] {
                for &y in &points[1] {
                    for &x in &points[0] {
                        nodes.push([x as f32, y as f32, z as f32]);
                    }
                }
            }
            let mut sums = vec![0.0f64; nodes.len()];
            far.sums(self.kernel, &nodes, &mut sums);
            match &mut field {
                Some(f) => f.values.iter_mut().zip(&sums).for_each(|(v, s)| *v += s),
                None => field = Some(FarField { axes, values: sums }),
            }
        }
        if leaf {
            let coords: [Vec<f64>; 3] = std::array::from_fn(|d| {
                lattice.axes[d][cell.lo[d]..cell.hi[d]].iter().map(|&x| f64::from(x)).collect()
            });
            let mut sums = match &field {
                Some(f) => interpolate(&f.axes, &f.values, [&coords[0], &coords[1], &coords[2]]),
                None => vec![0.0f64; coords.iter().map(Vec::len).product()],
            };
            if near.len() > 0 {
                let mut nodes = Vec::with_capacity(sums.len());
                for k in cell.lo[2]..cell.hi[2] {
                    for j in cell.lo[1]..cell.hi[1] {
                        for i in cell.lo[0]..cell.hi[0] {
                            nodes.push([lattice.axes[0][i], lattice.axes[1][j], lattice.axes[2][k]]);
                        }
                    }
                }
                let mut exact = vec![0.0f64; nodes.len()];
                near.sums(self.kernel, &nodes, &mut exact);
                sums.iter_mut().zip(&exact).for_each(|(s, e)| *s += e);
            }
            return vec![LeafSums { cell, sums }];
        }
        let children = cell.children();
        children
            .into_par_iter()
            .map(|child| self.visit(lattice, child, passed.clone(), field.as_ref()))
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::treecode::tests::{sphere_torus, stated_bound};
    use crate::{Evaluation, FitSettings, Interpolant, Kernel, Slice3};
    use glam::{UVec3, Vec3};
    use isomorph_common::Field3;

    /// The lattice of the tests: 40³ nodes over [-0.5, 0.5]³ (leaf boxes of
    /// 10 × 10 × 5 nodes, seven levels above them).
    const DIMS: UVec3 = UVec3::splat(40);
    const ORIGIN: Vec3 = Vec3::splat(-0.5);
    const SPACING: f32 = 1.0 / 39.0;

    fn on_lattice(slice: &Slice3) -> Vec<f32> {
        let mut out = vec![0.0f32; (DIMS.x * DIMS.y * DIMS.z) as usize];
        slice.values_on_lattice(DIMS, ORIGIN, SPACING, &mut out);
        out
    }

    #[test]
    fn dual_tree_agrees_with_direct_evaluation_within_the_bound() {
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            for n in [300, 700] {
                let f =
                    Interpolant::fit(&sphere_torus(n), &FitSettings::default().with_kernel(kernel)).unwrap();
                for t in [0.0, 0.5] {
                    let slice = f.slice3(&[t]).unwrap();
                    let direct = on_lattice(&slice.clone().with_evaluation(Evaluation::Direct));
                    let fast = on_lattice(&slice.clone().with_evaluation(Evaluation::Treecode));
                    let eval = f.slice_eval::<3>(&[t]).unwrap();
                    // The largest node–centre distance is at most the
                    // diagonal of the union of the lattice's and the
                    // centres' boxes (4D, the lattice at offset 0).
                    let src = &eval.sources;
                    let extent = |values: &mut dyn Iterator<Item = f64>| {
                        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
                    };
                    let mut r2 = 0.0;
                    for d in 0..3 {
                        let ends = [ORIGIN[d], ORIGIN[d] + SPACING * (DIMS[d] - 1) as f32]
                            .map(|x| (f64::from(x) - eval.shift[d]) * eval.scale);
                        let (lo, hi) = extent(&mut src.coords[d].iter().map(|&c| f64::from(c)).chain(ends));
                        r2 += (hi - lo).powi(2);
                    }
                    let (_, hi) = extent(&mut src.offset.iter().map(|&w| f64::from(w).sqrt()));
                    let r_max = (r2 + hi * hi).sqrt();
                    let (bound, _) = stated_bound(kernel, src, r_max);
                    let worst =
                        fast.iter().zip(&direct).map(|(a, b)| f64::from((a - b).abs())).fold(0.0, f64::max);
                    let (lo, hi) = extent(&mut direct.iter().map(|&v| f64::from(v)));
                    let range = hi - lo;
                    println!(
                        "{kernel:?} {} centres, t = {t}: max |dual − direct| {worst:e}, {:e} of the range, bound {bound:e}",
                        src.len(),
                        worst / range
                    );
                    assert!(worst <= bound, "{worst:e} > {bound:e}");
                    // And far below the bound in practice: measured up to
                    // 1.1e-5 of the range for r² log r and 1.7e-4 for r³,
                    // whose weights (Σ|λ| ≈ 1e6 here) put the f32 round-off
                    // of the far sums near 1e-4 of the range.
                    let practical = if kernel == Kernel::Cubic { 3e-4 } else { 2e-5 };
                    assert!(worst <= practical * range, "{worst:e} vs range {range:e}");
                }
            }
        }
    }

    #[test]
    fn dual_tree_is_the_same_for_any_thread_count() {
        let f = Interpolant::fit(&sphere_torus(700), &FitSettings::default()).unwrap();
        let slice = f.slice3(&[0.25]).unwrap().with_evaluation(Evaluation::Treecode);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| on_lattice(&slice))
        };
        let one = run(1);
        assert_eq!(one, run(3));
        assert_ne!(one, on_lattice(&slice.clone().with_evaluation(Evaluation::Direct)));
    }

    #[test]
    fn auto_takes_the_direct_sum_for_few_centres() {
        let f = Interpolant::fit(&sphere_torus(100), &FitSettings::default()).unwrap();
        let slice = f.slice3(&[0.5]).unwrap();
        assert_eq!(on_lattice(&slice), on_lattice(&slice.clone().with_evaluation(Evaluation::Direct)));
        // And the rows are the pointwise batch values.
        let mut grid = isomorph_common::Grid3::new(DIMS, ORIGIN, SPACING, 0.0f32).unwrap();
        grid.fill_from(&slice);
        let p = grid.position(3, 17, 29);
        assert_eq!(grid.get(3, 17, 29).copied(), Some(slice.value(p)));
    }
}
