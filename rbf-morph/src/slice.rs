//! Fast batch evaluation of 2D and 3D slices of an interpolant.

use crate::dual_tree::Lattice;
use crate::islands::{BAND_SAFETY, EXACT_TERMS, ISLAND_NODES, PROBES, doubtful_nodes, surface_probes};
use crate::kernel::{Kernel, eval_r2_f32};
use crate::treecode::{AUTO_MIN_CENTRES, AUTO_MIN_NODES, AUTO_MIN_POINTS, Evaluation, Treecode};
use glam::{UVec3, Vec2, Vec3};
use isomorph_common::marching_cubes::{SparseSettings, marching_cubes, polygonize_near_surface};
use isomorph_common::{Aabb, Field3, Grid2, Grid3, GridError, MorphError, TriMesh, lattice_for_box};
use pulp::{Arch, Simd, WithSimd};
use rayon::prelude::*;
use std::sync::OnceLock;

/// Points evaluated together in the inner loop, per kernel: `r² log r`,
/// whose long logarithm chain wants many independent lanes in flight, and
/// `r³`, which wants few (measured on `eval_grid…/8000/64` with AVX2: 8, 16
/// and 32 lanes take 1.77, 1.50 and 1.38 s for `r² log r`, 0.37, 0.50 and
/// 0.58 s (24 lanes) for `r³`).
const LANES_TPS: usize = 32;
const LANES_CUBIC: usize = 8;
/// Centres summed in f32 before adding into the f64 totals.
const CHUNK: usize = 256;
/// Points per rayon task.
const TASK: usize = 256;

/// A point type the evaluator reads coordinates from.
pub(crate) trait AsPoint<const S: usize>: Copy + Sync {
    fn coords(self) -> [f32; S];
}

impl<const S: usize> AsPoint<S> for [f32; S] {
    #[inline(always)]
    fn coords(self) -> [f32; S] {
        self
    }
}

impl AsPoint<3> for Vec3 {
    #[inline(always)]
    fn coords(self) -> [f32; 3] {
        self.to_array()
    }
}

impl AsPoint<2> for Vec2 {
    #[inline(always)]
    fn coords(self) -> [f32; 2] {
        self.to_array()
    }
}

/// Weighted kernel sources of a slice's sum, structure-of-arrays `f32`:
/// source `j` contributes `weights[j] · φ(√(|p − c_j|² + offset[j]))` at a
/// normalized point `p`. Both the centres of a slice and the proxies of the
/// [`treecode`](crate::treecode) are sources of this form.
#[derive(Debug, Clone)]
pub(crate) struct Sources<const S: usize> {
    /// Normalized coordinates, one array per axis.
    pub coords: [Vec<f32>; S],
    /// Squared distance in the coordinates the slice fixes (≥ 0).
    pub offset: Vec<f32>,
    pub weights: Vec<f32>,
}

impl<const S: usize> Default for Sources<S> {
    fn default() -> Self {
        Self { coords: std::array::from_fn(|_| Vec::new()), offset: Vec::new(), weights: Vec::new() }
    }
}

impl<const S: usize> Sources<S> {
    /// Number of sources.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Removes every source, keeping the allocations.
    pub fn clear(&mut self) {
        self.coords.iter_mut().for_each(Vec::clear);
        self.offset.clear();
        self.weights.clear();
    }

    /// Appends sources `range` of `other`.
    pub fn extend_from(&mut self, other: &Self, range: std::ops::Range<usize>) {
        for k in 0..S {
            self.coords[k].extend_from_slice(&other.coords[k][range.clone()]);
        }
        self.offset.extend_from_slice(&other.offset[range.clone()]);
        self.weights.extend_from_slice(&other.weights[range]);
    }

    /// Appends one source.
    pub fn push(&mut self, coords: [f32; S], offset: f32, weight: f32) {
        for k in 0..S {
            self.coords[k].push(coords[k]);
        }
        self.offset.push(offset);
        self.weights.push(weight);
    }

    /// The sums at up to `LANES` normalized points.
    #[inline(always)]
    fn block<const TPS: bool, const LANES: usize>(&self, points: &[[f32; S]]) -> [f64; LANES] {
        let mut p = [[0.0f32; LANES]; S];
        for l in 0..LANES {
            let q = points[l.min(points.len() - 1)];
            for k in 0..S {
                p[k][l] = q[k];
            }
        }
        let kernel = if TPS { Kernel::ThinPlate } else { Kernel::Cubic };
        let mut total = [0.0f64; LANES];
        let n = self.weights.len();
        let mut start = 0;
        while start < n {
            let end = (start + CHUNK).min(n);
            let mut acc = [0.0f32; LANES];
            for j in start..end {
                let w = self.offset[j];
                let d = self.weights[j];
                let mut r2 = [w; LANES];
                for k in 0..S {
                    let c = self.coords[k][j];
                    for l in 0..LANES {
                        let t = p[k][l] - c;
                        r2[l] += t * t;
                    }
                }
                for l in 0..LANES {
                    acc[l] += d * eval_r2_f32(kernel, r2[l]);
                }
            }
            for l in 0..LANES {
                total[l] += f64::from(acc[l]);
            }
            start = end;
        }
        total
    }

    /// The sums `Σ_j weights[j] φ(…)` at normalized `points` into `out`
    /// (sequential and vectorized; callers parallelize). Each point's sum
    /// runs over the sources in order, so it does not depend on how the
    /// points are split.
    pub fn sums(&self, kernel: Kernel, points: &[[f32; S]], out: &mut [f64]) {
        struct Op<'a, const S: usize> {
            sources: &'a Sources<S>,
            kernel: Kernel,
            points: &'a [[f32; S]],
            out: &'a mut [f64],
        }
        impl<const S: usize> WithSimd for Op<'_, S> {
            type Output = ();
            #[inline(always)]
            fn with_simd<Sm: Simd>(self, _simd: Sm) {
                fn lanes<const S: usize, const TPS: bool, const LANES: usize>(
                    sources: &Sources<S>,
                    points: &[[f32; S]],
                    out: &mut [f64],
                ) {
                    for (pts, out) in points.chunks(LANES).zip(out.chunks_mut(LANES)) {
                        let total = sources.block::<TPS, LANES>(pts);
                        out.copy_from_slice(&total[..out.len()]);
                    }
                }
                match self.kernel {
                    Kernel::ThinPlate => lanes::<S, true, LANES_TPS>(self.sources, self.points, self.out),
                    Kernel::Cubic => lanes::<S, false, LANES_CUBIC>(self.sources, self.points, self.out),
                }
            }
        }
        assert_eq!(points.len(), out.len(), "sums: points and out differ in length");
        if self.weights.is_empty() {
            out.fill(0.0);
            return;
        }
        Arch::new().dispatch(Op { sources: self, kernel, points, out });
    }
}

/// The reduced sum of an `S`-dimensional slice.
#[derive(Debug, Clone)]
pub(crate) struct SliceEval<const S: usize> {
    pub kernel: Kernel,
    /// The centres, with the fixed coordinates folded into the offsets.
    pub sources: Sources<S>,
    /// Polynomial constant (including the fixed coordinates' part).
    pub constant: f64,
    /// Polynomial linear part in normalized coordinates.
    pub linear: [f64; S],
    /// World → normalized: `(p − shift) · scale`.
    pub shift: [f64; S],
    pub scale: f64,
    /// How [`SliceEval::values`] evaluates.
    pub evaluation: Evaluation,
    /// The source tree, built at the first treecode evaluation.
    pub tree: OnceLock<Treecode<S>>,
}

impl<const S: usize> SliceEval<S> {
    fn normalize(&self, p: [f32; S]) -> [f32; S] {
        std::array::from_fn(|k| ((f64::from(p[k]) - self.shift[k]) * self.scale) as f32)
    }

    /// Adds the polynomial to the kernel sums at normalized `points`.
    fn finish(&self, points: &[[f32; S]], sums: &[f64], out: &mut [f32]) {
        for ((o, p), s) in out.iter_mut().zip(points).zip(sums) {
            let mut v = s + self.constant;
            for k in 0..S {
                v += self.linear[k] * f64::from(p[k]);
            }
            *o = v as f32;
        }
    }

    /// Direct values at `points` into `out` (sequential; callers parallelize).
    fn run<P: AsPoint<S>>(&self, points: &[P], out: &mut [f32]) {
        let normalized: Vec<[f32; S]> = points.iter().map(|p| self.normalize(p.coords())).collect();
        let mut sums = vec![0.0f64; points.len()];
        self.sources.sums(self.kernel, &normalized, &mut sums);
        self.finish(&normalized, &sums, out);
    }

    /// Values at `points` into `out`: direct (parallel over blocks of
    /// points) or by the treecode, per [`SliceEval::evaluation`] (`Auto`:
    /// the treecode for batches of at least [`AUTO_MIN_POINTS`] points with
    /// at least [`AUTO_MIN_CENTRES`] centres).
    pub(crate) fn values<P: AsPoint<S>>(&self, points: &[P], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "values: points and out differ in length");
        let by_tree = match self.evaluation {
            Evaluation::Direct => false,
            Evaluation::Treecode => true,
            Evaluation::Auto => self.sources.len() >= AUTO_MIN_CENTRES && points.len() >= AUTO_MIN_POINTS,
        };
        if by_tree {
            let tree = self.tree();
            let normalized: Vec<[f32; S]> = points.iter().map(|p| self.normalize(p.coords())).collect();
            let mut sums = vec![0.0f64; points.len()];
            tree.sums(&normalized, &mut sums);
            self.finish(&normalized, &sums, out);
        } else {
            self.values_direct(points, out);
        }
    }

    /// The source tree, built at its first use.
    fn tree(&self) -> &Treecode<S> {
        self.tree.get_or_init(|| Treecode::new(&self.sources, self.kernel))
    }

    /// Direct values at `points` into `out`, parallel over blocks of points.
    pub(crate) fn values_direct<P: AsPoint<S>>(&self, points: &[P], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "values: points and out differ in length");
        points.par_chunks(TASK).zip(out.par_chunks_mut(TASK)).for_each(|(p, o)| self.run(p, o));
    }

    /// Whether lattices of `nodes` nodes are evaluated by the dual tree.
    fn lattice_by_tree(&self, nodes: usize) -> bool {
        match self.evaluation {
            Evaluation::Direct => false,
            Evaluation::Treecode => true,
            Evaluation::Auto => self.sources.len() >= AUTO_MIN_CENTRES && nodes >= AUTO_MIN_NODES,
        }
    }

    fn value(&self, p: [f32; S]) -> f32 {
        let mut out = [0.0f32];
        self.run(&[p], &mut out);
        out[0]
    }

    /// Analytic gradient in world units (f64 accumulation).
    fn gradient(&self, p: [f32; S]) -> [f32; S] {
        let q = self.normalize(p).map(f64::from);
        let mut g = self.linear;
        let src = &self.sources;
        for j in 0..src.len() {
            let diff: [f64; S] = std::array::from_fn(|k| q[k] - f64::from(src.coords[k][j]));
            let r2 = f64::from(src.offset[j]) + diff.iter().map(|x| x * x).sum::<f64>();
            let s = f64::from(src.weights[j]) * self.kernel.gradient_factor_r2(r2);
            for k in 0..S {
                g[k] += s * diff[k];
            }
        }
        g.map(|v| (v * self.scale) as f32)
    }
}

impl SliceEval<3> {
    /// Values at the lattice of `dims` nodes at `origin + spacing·(i, j, k)`
    /// into `out` (`i` fastest) by the [`dual_tree`](crate::dual_tree).
    fn lattice_values(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        // World coordinates as `values_by_rows` forms them, then normalized
        // as the direct path does, so that the near field is bit-identical.
        let axes: [Vec<f32>; 3] = std::array::from_fn(|d| {
            (0..dims[d])
                .map(|i| ((f64::from(origin[d] + spacing * i as f32) - self.shift[d]) * self.scale) as f32)
                .collect()
        });
        let lattice = Lattice { axes };
        let mut sums = vec![0.0f64; out.len()];
        self.tree().lattice_sums(&lattice, &mut sums);
        let (nx, ny) = (dims.x as usize, dims.y as usize);
        out.par_chunks_mut(nx).zip(sums.par_chunks(nx)).enumerate().for_each(|(row, (out, sums))| {
            let (j, k) = (row % ny, row / ny);
            for (i, (o, s)) in out.iter_mut().zip(sums).enumerate() {
                let q = [lattice.axes[0][i], lattice.axes[1][j], lattice.axes[2][k]];
                let mut v = s + self.constant;
                for d in 0..3 {
                    v += self.linear[d] * f64::from(q[d]);
                }
                *o = v as f32;
            }
        });
    }
}

/// A 3D slice of an interpolant (e.g. the shape at time `t` of a 4D shape
/// transformation): a [`Field3`], positive inside, surface at 0, with fast
/// parallel batch evaluation ([`Field3::values`]) and an analytic gradient.
///
/// A slice fixes the trailing coordinates of a `D`-dimensional interpolant;
/// each centre then contributes `d_j φ(√(|p − c_j|² + w_j))` with a constant
/// per-centre offset `w_j`, and the polynomial collapses to an affine
/// function of `p`. The centres are stored as structure-of-arrays `f32`.
///
/// The hot loop takes a block of points at a time (32 for `r² log r`, 8 for
/// `r³`) and walks over all centres: one independent accumulator per point,
/// the centre broadcast, the point block in registers, so the compiler
/// vectorizes across points (AVX2/FMA or
/// AVX-512 chosen at run time by `pulp`, SSE2 otherwise). `r² log r` uses the
/// branch-free `fast_ln`. Partial sums over 256
/// centres are added into `f64` totals. Weights and centres are rounded to
/// `f32`, so a slice agrees with the exact f64 [`Interpolant`](crate::Interpolant)
/// to about `1e-4` of the unit constraint value (tested); near the surface,
/// where `|∇f| ≈ 1/offset`, that is a positional error of about `1e-6` world units. Rayon splits the points
/// into blocks; the result does not depend on the thread count.
///
/// [`Slice3::with_evaluation`] with [`Evaluation::Treecode`] evaluates
/// batches through the [`treecode`](crate::treecode) instead: far clusters
/// of centres are replaced by Chebyshev proxies, within the bound stated
/// there. Whole lattices ([`Field3::values_on_lattice`], e.g.
/// `Grid3::fill_from`) go through the [`dual_tree`](crate::dual_tree) with
/// `Treecode`, and with the default [`Evaluation::Auto`] from
/// [`AUTO_MIN_CENTRES`](crate::treecode::AUTO_MIN_CENTRES) centres.
#[derive(Debug, Clone)]
pub struct Slice3 {
    eval: SliceEval<3>,
    bounds: Option<Aabb>,
}

impl Slice3 {
    pub(crate) fn new(eval: SliceEval<3>) -> Self {
        Self { eval, bounds: None }
    }

    /// A slice made directly from centres in world coordinates `centres`,
    /// per-centre squared offsets `offsets` (the squared distance in the
    /// fixed coordinates) and weights, with no polynomial part: for
    /// benchmarks and tests of evaluation at sizes the fit cannot reach
    /// quickly. Not a fitted function.
    ///
    /// # Panics
    /// If the three slices differ in length.
    #[doc(hidden)]
    pub fn from_sources(kernel: Kernel, centres: &[[f32; 3]], offsets: &[f32], weights: &[f32]) -> Self {
        assert!(centres.len() == offsets.len() && centres.len() == weights.len(), "lengths differ");
        let mut sources = Sources::default();
        for ((c, o), w) in centres.iter().zip(offsets).zip(weights) {
            sources.push(*c, *o, *w);
        }
        Self::new(SliceEval {
            kernel,
            sources,
            constant: 0.0,
            linear: [0.0; 3],
            shift: [0.0; 3],
            scale: 1.0,
            evaluation: Evaluation::default(),
            tree: OnceLock::new(),
        })
    }

    /// This slice reporting `bounds` from [`Field3::bounds`] (e.g. a box
    /// known to contain the surface).
    pub fn with_bounds(mut self, bounds: Aabb) -> Self {
        self.bounds = Some(bounds);
        self
    }

    /// Number of centres summed per evaluation.
    pub fn centres(&self) -> usize {
        self.eval.sources.len()
    }

    /// This slice evaluating batches by `evaluation` (default
    /// [`Evaluation::Auto`]).
    pub fn with_evaluation(mut self, evaluation: Evaluation) -> Self {
        self.eval.evaluation = evaluation;
        self
    }

    /// The mesh of the zero level set on the lattice of
    /// [`Grid3::sample_box`](isomorph_common::Grid3::sample_box)`(bounds, res)`
    /// (outward oriented, positive inside).
    ///
    /// When the slice evaluates that lattice by the
    /// [`dual_tree`](crate::dual_tree) (many centres, see [`Evaluation`]),
    /// the whole lattice is evaluated and polygonized: the dual tree's cost
    /// is dominated by the far field, shared by all nodes, so the whole
    /// lattice costs less than the scattered near-surface nodes through the
    /// treecode, its error is smaller (see `docs/EXPERIMENTS.md`), and no
    /// sign is inferred. Otherwise the direct sum is taken only near the
    /// surface ([`level_set_mesh`](isomorph_common::marching_cubes::level_set_mesh)),
    /// which gives the same mesh as the whole lattice.
    ///
    /// # Errors
    /// As [`Grid3::sample_box`](isomorph_common::Grid3::sample_box) (bad box,
    /// `res < 2`, a lattice too large for memory).
    pub fn polygonize(&self, bounds: &Aabb, res: u32) -> Result<TriMesh, MorphError> {
        self.polygonize_confirmed(bounds, res, None)
    }

    /// [`Slice3::polygonize`], with the lattice's doubtful nodes (small
    /// sign islands, values near zero: [`islands`](crate::islands))
    /// re-evaluated by `exact` (the value at a world point) before marching
    /// cubes when the dual tree evaluated the lattice.
    pub(crate) fn polygonize_confirmed(
        &self,
        bounds: &Aabb,
        res: u32,
        exact: Option<&(dyn Fn(Vec3) -> f64 + Sync)>,
    ) -> Result<TriMesh, MorphError> {
        let (dims, _, _) = lattice_for_box(bounds, res)?;
        if self.eval.lattice_by_tree(dims.element_product() as usize) {
            let mut grid = Grid3::sample_box(self, bounds, res)?;
            if let Some(exact) = exact {
                let at = |grid: &Grid3<f32>, nodes: &[usize]| -> Vec<f32> {
                    nodes
                        .par_iter()
                        .map(|&n| {
                            let c = grid.node_of(n);
                            exact(grid.position(c.x, c.y, c.z)) as f32
                        })
                        .collect()
                };
                // The probes (sorted) measure the band and keep their exact
                // values; the doubtful nodes are then evaluated once each.
                let probes = surface_probes(&grid, 0.0, PROBES);
                let mut band = 0.0f32;
                for (&n, e) in probes.iter().zip(at(&grid, &probes)) {
                    band = band.max((e - grid.data()[n]).abs());
                    grid.data_mut()[n] = e;
                }
                let limit = EXACT_TERMS / self.centres().max(1);
                let nodes: Vec<usize> = doubtful_nodes(&grid, 0.0, band * BAND_SAFETY, ISLAND_NODES, limit)
                    .into_iter()
                    .filter(|n| probes.binary_search(n).is_err())
                    .collect();
                let values = at(&grid, &nodes);
                let data = grid.data_mut();
                nodes.iter().zip(values).for_each(|(&n, v)| data[n] = v);
            }
            Ok(marching_cubes(&grid, 0.0))
        } else {
            polygonize_near_surface(self, bounds, res, 0.0, &SparseSettings::default()).map(|(mesh, _)| mesh)
        }
    }
}

impl Field3 for Slice3 {
    fn value(&self, p: Vec3) -> f32 {
        self.eval.value(p.to_array())
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        Vec3::from_array(self.eval.gradient(p.to_array()))
    }

    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        self.eval.values(points, out);
    }

    fn bounds(&self) -> Option<Aabb> {
        self.bounds
    }

    /// By the [`dual_tree`](crate::dual_tree) when the slice's
    /// [`Evaluation`] says so, else row by row.
    fn values_on_lattice(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        let nodes = dims.x as usize * dims.y as usize * dims.z as usize;
        assert_eq!(out.len(), nodes, "values_on_lattice: out does not match the lattice");
        if nodes > 0 && self.eval.lattice_by_tree(nodes) {
            self.eval.lattice_values(dims, origin, spacing, out);
        } else {
            isomorph_common::values_by_rows(self, dims, origin, spacing, out);
        }
    }
}

/// A 2D slice of an interpolant (the shape at time `t` of a transformation
/// between 2D shapes, or a single 2D variational implicit): positive inside,
/// curve at 0.
#[derive(Debug, Clone)]
pub struct Slice2 {
    eval: SliceEval<2>,
}

impl Slice2 {
    pub(crate) fn new(eval: SliceEval<2>) -> Self {
        Self { eval }
    }

    /// This slice evaluating batches by `evaluation` (default
    /// [`Evaluation::Auto`]).
    pub fn with_evaluation(mut self, evaluation: Evaluation) -> Self {
        self.eval.evaluation = evaluation;
        self
    }

    /// The value at `p`.
    pub fn value(&self, p: Vec2) -> f32 {
        self.eval.value(p.to_array())
    }

    /// The analytic gradient at `p` (points inward).
    pub fn gradient(&self, p: Vec2) -> Vec2 {
        Vec2::from_array(self.eval.gradient(p.to_array()))
    }

    /// Values at `points` into `out`, parallel and vectorized.
    ///
    /// # Panics
    /// If `points` and `out` differ in length.
    pub fn values(&self, points: &[Vec2], out: &mut [f32]) {
        self.eval.values(points, out);
    }

    /// The slice sampled on a `dims` lattice of nodes at `origin + spacing·(i, j)`
    /// (for [`marching_squares`](isomorph_common::marching_squares::marching_squares)
    /// or an image).
    ///
    /// # Errors
    /// As [`Grid2::from_vec`] (zero dimension, bad spacing).
    pub fn sample(&self, dims: glam::UVec2, origin: Vec2, spacing: f32) -> Result<Grid2<f32>, GridError> {
        sample_lattice(dims, origin, spacing, |points, out| self.values(points, out))
    }
}

/// A 2D field sampled by `values` on the `dims` lattice of nodes at
/// `origin + spacing·(i, j)`, `i` fastest.
pub(crate) fn sample_lattice(
    dims: glam::UVec2,
    origin: Vec2,
    spacing: f32,
    values: impl FnOnce(&[Vec2], &mut [f32]),
) -> Result<Grid2<f32>, GridError> {
    let points: Vec<Vec2> = (0..dims.y)
        .flat_map(|j| (0..dims.x).map(move |i| origin + spacing * Vec2::new(i as f32, j as f32)))
        .collect();
    let mut out = vec![0.0f32; points.len()];
    values(&points, &mut out);
    Grid2::from_vec(dims, origin, spacing, out)
}
