//! The projected system of a shape transformation solved slab by slab.
//!
//! A shape transformation puts the constraints of each shape in its own
//! slab (`t = 0` and `t = t_max`, §6), well apart in the extra dimension.
//! Ordered slab by slab, the projected block is
//!
//! ```text
//! B = [ A  Gᵀ ]  =  L [ I  X ] Lᵀ,    L = [ L_A   0  ],    X = L_A⁻¹ Gᵀ L_D⁻ᵀ,
//!     [ G  D  ]       [ Xᵀ I ]            [  0   L_D ]
//! ```
//!
//! and the coupling `X` between slabs is smooth: its singular values fall
//! from ≈ 1 to below 1e-5 within a few dozen (measured on the reference
//! case). So `B` is solved by conjugate gradients in f64 with the
//! preconditioner `M = L [I X̃; X̃ᵀ I] Lᵀ`, where `L_A`, `L_D` are exact
//! Cholesky factors of the two diagonal blocks (a quarter of the full
//! factorization's flops) and `X̃ = U Σ Vᵀ` is a rank-`p` approximation of
//! `X` from a randomized range finder. `M⁻¹` is
//! exact and cheap (block triangular solves and a `2 × 2` solve per singular
//! pair), and `M⁻¹B` differs from the identity by about `σ_{p+1}`, so CG
//! reaches the backward error of a direct solver in a handful of iterations. When
//! the constraints do not form two separated groups, a block factorization
//! fails or CG does not converge, the caller falls back to the dense
//! Cholesky.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Fewest constraints for which the slab solver is tried: below this the
/// dense Cholesky takes well under a second anyway.
const MIN_CONSTRAINTS: usize = 1500;
/// Smallest share of the constraints in the smaller slab.
const MIN_SHARE: f64 = 0.2;
/// Smallest empty gap between the slabs along an axis, as a fraction of the
/// constraints' bounding-box diagonal (the normalized coordinates have unit
/// diagonal).
const MIN_GAP: f64 = 0.15;
/// Rank of the coupling approximation (with oversampling).
const RANK: usize = 64;
/// Give up on the slab solver when the smallest captured singular value of
/// the coupling is above this (the coupling is not smooth enough).
const MAX_TAIL: f64 = 1e-3;
/// Normwise backward error `‖g − B y‖₂ / (‖B‖ ‖y‖₂ + ‖g‖₂)` at which CG
/// stops (`‖B‖` estimated by the 1-norm): about five units of round-off,
/// what a backward stable direct solver attains.
const BACKWARD_ERROR: f64 = 1e-15;
/// CG iterations before giving up (a handful are needed when the coupling
/// is captured).
const MAX_ITERATIONS: usize = 30;

/// A split of the constraints into two slabs: `order` lists the constraint
/// indices slab by slab, the first `first` of them in the first slab.
pub(crate) struct Split {
    pub order: Vec<usize>,
    pub first: usize,
}

/// Finds the widest empty gap along any axis between two groups of
/// constraints (`positions` row-major `n × dim`, normalized to a unit
/// bounding-box diagonal); `None` unless the system is large, the gap at
/// least [`MIN_GAP`] and both sides at least [`MIN_SHARE`] of the constraints.
pub(crate) fn find_split(positions: &[f64], dim: usize) -> Option<Split> {
    let n = positions.len() / dim;
    if n < MIN_CONSTRAINTS {
        return None;
    }
    let mut best: Option<(f64, usize, f64)> = None;
    for axis in 0..dim {
        let mut coords: Vec<f64> = (0..n).map(|i| positions[i * dim + axis]).collect();
        coords.sort_by(f64::total_cmp);
        let min_side = (MIN_SHARE * n as f64).ceil() as usize;
        for i in min_side.max(1)..=n.saturating_sub(min_side) {
            let gap = coords[i] - coords[i - 1];
            if gap >= MIN_GAP && best.is_none_or(|(g, _, _)| gap > g) {
                best = Some((gap, axis, 0.5 * (coords[i] + coords[i - 1])));
            }
        }
    }
    let (_, axis, cut) = best?;
    let (mut order, second): (Vec<usize>, Vec<usize>) =
        (0..n).partition(|&i| positions[i * dim + axis] < cut);
    let first = order.len();
    order.extend(second);
    Some(Split { order, first })
}

/// Column ranges of [`symmetric_matvec`]: a fixed count, so that the
/// summation order (and the result) does not depend on the thread count.
const MATVEC_PARTS: usize = 8;

/// `y ← S x` for the symmetric `S` given by its lower triangle (columns
/// contiguous): one pass over the triangle, each column contributing a dot
/// product and an axpy, in parallel over [`MATVEC_PARTS`] column ranges of
/// equal area with one accumulator each, summed in a fixed order.
fn symmetric_matvec(s: MatRef<'_, f64>, x: &[f64], y: &mut [f64]) {
    let k = x.len();
    let parts = MATVEC_PARTS;
    // Column j holds k − j entries: split the triangle into equal areas.
    let total = (k * (k + 1) / 2) as f64;
    let mut bounds = vec![0usize];
    let mut area = 0.0;
    for j in 0..k {
        area += (k - j) as f64;
        if area >= total * bounds.len() as f64 / parts as f64 && j + 1 < k {
            bounds.push(j + 1);
        }
    }
    bounds.push(k);
    let partial: Vec<Vec<f64>> = bounds
        .windows(2)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|w| {
            let mut acc = vec![0.0f64; k];
            for j in w[0]..w[1] {
                let col = &s.col(j).try_as_col_major().expect("column-major block").as_slice()[j..];
                let (xs, out) = (&x[j..], &mut acc[j..]);
                let xj = xs[0];
                let mut dots = [0.0f64; 4];
                let (col4, col_rest) = col.split_at(col.len() / 4 * 4);
                for ((c, xv), o) in col4.chunks_exact(4).zip(xs.chunks_exact(4)).zip(out.chunks_exact_mut(4))
                {
                    for l in 0..4 {
                        dots[l] += c[l] * xv[l];
                        o[l] += c[l] * xj;
                    }
                }
                let start = col4.len();
                let mut dot = dots.iter().sum::<f64>();
                for (i, c) in col_rest.iter().enumerate() {
                    dot += c * xs[start + i];
                    out[start + i] += c * xj;
                }
                // The diagonal entry was counted in both the dot and the axpy.
                out[0] += dot - col[0] * xj;
            }
            acc
        })
        .collect();
    y.iter_mut().for_each(|v| *v = 0.0);
    for acc in &partial {
        y.iter_mut().zip(acc).for_each(|(y, a)| *y += a);
    }
}

/// The slab preconditioner `M = L [I X̃; X̃ᵀ I] Lᵀ` (see the module docs).
pub(crate) struct SlabPreconditioner {
    /// Cholesky factor of the first diagonal block `A` (lower triangle).
    l_a: Mat<f64>,
    /// Cholesky factor of the second diagonal block `D`.
    l_d: Mat<f64>,
    /// Left singular vectors of `X̃` (`h × p`, orthonormal).
    u: Mat<f64>,
    /// Right singular vectors of `X̃` (`(k − h) × p`, orthonormal).
    v: Mat<f64>,
    /// Singular values of `X̃`, each below 1.
    sigma: Vec<f64>,
}

impl SlabPreconditioner {
    /// Builds the preconditioner of `b` (lower triangle read) split after
    /// row `h`; `None` when a diagonal block is not numerically positive
    /// definite or the coupling is not smooth.
    pub(crate) fn new(b: MatRef<'_, f64>, h: usize) -> Option<Self> {
        let k = b.nrows();
        let par = crate::solve::PARALLELISM;
        let l_a = cholesky(b.submatrix(0, 0, h, h), par)?;
        let l_d = cholesky(b.submatrix(h, h, k - h, k - h), par)?;
        let g = b.submatrix(h, 0, k - h, h);
        let p = RANK.min(h).min(k - h);
        // X W = L_A⁻¹ (Gᵀ (L_D⁻ᵀ W)) and Xᵀ Y = L_D⁻¹ (G (L_A⁻ᵀ Y)).
        let apply_x = |mut w: Mat<f64>| {
            solve_upper_triangular_in_place(l_d.transpose(), w.as_mut(), par);
            let mut y = g.transpose() * &w;
            solve_lower_triangular_in_place(l_a.as_ref(), y.as_mut(), par);
            y
        };
        let apply_xt = |mut y: Mat<f64>| {
            solve_upper_triangular_in_place(l_a.transpose(), y.as_mut(), par);
            let mut w = g * &y;
            solve_lower_triangular_in_place(l_d.as_ref(), w.as_mut(), par);
            w
        };
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let omega = Mat::<f64>::from_fn(k - h, p, |_, _| uniform(&mut state));
        let range = orthonormal(&apply_x(omega));
        // X̃ = range rangeᵀ X = range Zᵀ with Z = Xᵀ range = V Σ Wᵀ.
        let z = apply_xt(range.clone());
        let svd = z.thin_svd().ok()?;
        let sigma: Vec<f64> = (0..p).map(|i| svd.S()[i]).collect();
        if sigma.iter().any(|s| !(s.is_finite() && *s < 1.0)) || sigma[p - 1] > MAX_TAIL {
            return None;
        }
        let u = &range * svd.V();
        Some(Self { l_a, l_d, u, v: svd.U().to_owned(), sigma })
    }

    /// `r ← M⁻¹ r`.
    pub(crate) fn apply(&self, r: &mut [f64]) {
        let h = self.l_a.nrows();
        let par = crate::solve::PARALLELISM;
        let (r1, r2) = r.split_at_mut(h);
        let mut w1 = MatMut::from_column_major_slice_mut(r1, h, 1);
        let mut w2 = MatMut::from_column_major_slice_mut(r2, self.l_d.nrows(), 1);
        solve_lower_triangular_in_place(self.l_a.as_ref(), w1.as_mut(), par);
        solve_lower_triangular_in_place(self.l_d.as_ref(), w2.as_mut(), par);
        // [I Σ; Σ I] [α; β] = [a; b] on the singular pairs, identity elsewhere.
        let a = self.u.transpose() * w1.as_ref();
        let b = self.v.transpose() * w2.as_ref();
        let p = self.sigma.len();
        let (mut da, mut db) = (Mat::<f64>::zeros(p, 1), Mat::<f64>::zeros(p, 1));
        for i in 0..p {
            let s = self.sigma[i];
            let det = (1.0 - s) * (1.0 + s);
            da[(i, 0)] = (a[(i, 0)] - s * b[(i, 0)]) / det - a[(i, 0)];
            db[(i, 0)] = (b[(i, 0)] - s * a[(i, 0)]) / det - b[(i, 0)];
        }
        w1 += &self.u * &da;
        w2 += &self.v * &db;
        solve_upper_triangular_in_place(self.l_a.transpose(), w1, par);
        solve_upper_triangular_in_place(self.l_d.transpose(), w2, par);
    }
}

/// Solves `B y = g` by preconditioned conjugate gradients (`b` symmetric,
/// its lower triangle read, `norm_b` its 1-norm); returns `y` and the
/// iteration count, or `None` when the true residual does not reach the
/// backward error [`BACKWARD_ERROR`] within [`MAX_ITERATIONS`].
pub(crate) fn conjugate_gradients(
    b: MatRef<'_, f64>,
    norm_b: f64,
    m: &SlabPreconditioner,
    g: &[f64],
) -> Option<(Vec<f64>, usize)> {
    let k = g.len();
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let norm_g = dot(g, g).sqrt();
    if norm_g == 0.0 {
        return Some((vec![0.0; k], 0));
    }
    let converged =
        |r: &[f64], y: &[f64]| dot(r, r).sqrt() <= BACKWARD_ERROR * (norm_b * dot(y, y).sqrt() + norm_g);
    let matvec = |x: &[f64], out: &mut [f64]| symmetric_matvec(b, x, out);
    let mut y = vec![0.0; k];
    let mut r = g.to_vec();
    let mut q = vec![0.0; k];
    let mut iterations = 0;
    // Restarts recompute the true residual, so that drift of the recurrence
    // cannot fake convergence.
    while iterations < MAX_ITERATIONS {
        let mut z = r.clone();
        m.apply(&mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        while iterations < MAX_ITERATIONS {
            iterations += 1;
            matvec(&p, &mut q);
            let alpha = rz / dot(&p, &q);
            if !alpha.is_finite() {
                return None;
            }
            y.iter_mut().zip(&p).for_each(|(y, p)| *y += alpha * p);
            r.iter_mut().zip(&q).for_each(|(r, q)| *r -= alpha * q);
            if converged(&r, &y) {
                break;
            }
            z.copy_from_slice(&r);
            m.apply(&mut z);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
        }
        matvec(&y, &mut q);
        r.iter_mut().zip(g.iter().zip(&q)).for_each(|(r, (g, q))| *r = g - q);
        if converged(&r, &y) {
            return Some((y, iterations));
        }
    }
    None
}

/// The Cholesky factor of the symmetric block `s` (lower triangle read);
/// `None` if it is not numerically positive definite.
pub(crate) fn cholesky(s: MatRef<'_, f64>, par: Par) -> Option<Mat<f64>> {
    let mut l = s.to_owned();
    cholesky_in_place(l.as_mut(), par).then_some(l)
}

/// Overwrites the lower triangle of the symmetric `l` (lower triangle
/// read) with its Cholesky factor; `false` if it is not numerically
/// positive definite.
pub(crate) fn cholesky_in_place(l: MatMut<'_, f64>, par: Par) -> bool {
    let n = l.nrows();
    let mut mem = MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(n, par, Default::default()));
    llt::factor::cholesky_in_place(l, Default::default(), par, MemStack::new(&mut mem), Default::default())
        .is_ok()
}

/// An orthonormal basis of the columns of `y` (thin QR).
fn orthonormal(y: &Mat<f64>) -> Mat<f64> {
    y.qr().compute_thin_Q()
}

/// A deterministic uniform number in `[−1, 1)` (SplitMix64), for the range
/// finder's test matrix.
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::constraints::{NormalOffset, Subsample, SurfaceSettings, field_constraints};
    use crate::transform::lift;
    use crate::{Factorization, FitSettings, Interpolant, Kernel, Solver};
    use isomorph_common::{Aabb, Shape};

    /// The reference case's constraints (sphere at t = 0, torus at t = 1)
    /// with `total` constraints, from 32³ polygonizations.
    pub(crate) fn sphere_torus(total: usize) -> Vec<crate::Constraint<4>> {
        sphere_torus_at(total, 32)
    }

    /// [`sphere_torus`] from polygonizations at `resolution`³ (enough
    /// vertices for larger `total`).
    pub(crate) fn sphere_torus_at(total: usize, resolution: u32) -> Vec<crate::Constraint<4>> {
        let s = SurfaceSettings {
            offset: NormalOffset::Absolute(0.01),
            subsample: Subsample::FarthestPoint(total / 4),
        };
        let a = field_constraints(&Shape::sphere(0.3), &Aabb::cube(0.5), resolution, &s).unwrap();
        let b = field_constraints(&Shape::torus(0.3, 0.12), &Aabb::cube(0.5), resolution, &s).unwrap();
        let mut all = lift::<3, 4>(&a, &[0.0]);
        all.extend(lift::<3, 4>(&b, &[1.0]));
        all
    }

    #[test]
    fn slab_solver_agrees_with_the_dense_cholesky() {
        let cs = sphere_torus(2000);
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            let auto = Interpolant::fit(&cs, &FitSettings::default().with_kernel(kernel)).unwrap();
            let dense = FitSettings { solver: Solver::Dense, ..FitSettings::default().with_kernel(kernel) };
            let dense = Interpolant::fit(&cs, &dense).unwrap();
            let Factorization::SlabCg { iterations } = auto.report().factorization else {
                panic!("{kernel:?}: the slab solver was not used: {:?}", auto.report().factorization);
            };
            assert!(iterations <= 8, "{kernel:?}: {iterations} iterations");
            assert_eq!(dense.report().factorization, Factorization::Cholesky);
            assert!(auto.report().max_residual.unwrap() < 1e-8, "{:?}", auto.report());
            // Same function: compare at points between and beyond the slabs.
            for i in 0..200 {
                let u = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0 - 0.5;
                let x = [u(1), u(2), u(3), 1.5 * u(4) + 0.5];
                let (fa, fd) = (auto.value_f64(x), dense.value_f64(x));
                assert!((fa - fd).abs() < 1e-7 * (1.0 + fd.abs()), "{kernel:?} at {x:?}: {fa} vs {fd}");
            }
            let ratio = auto.report().rcond / dense.report().rcond;
            assert!((0.1..10.0).contains(&ratio), "{kernel:?}: rcond {ratio}× the dense estimate");
        }
    }

    #[test]
    fn split_needs_two_separated_groups() {
        let mut state = 7u64;
        let cloud: Vec<f64> = (0..4 * 2000).map(|_| 0.3 * uniform(&mut state)).collect();
        assert!(find_split(&cloud, 4).is_none(), "one cloud has no slabs");
        // Two slabs along axis 2, a quarter of the points in the first.
        let mut slabs = cloud.clone();
        for i in 0..2000 {
            slabs[i * 4 + 2] = if i % 4 == 1 { -0.3 } else { 0.2 } + 0.01 * uniform(&mut state);
        }
        let split = find_split(&slabs, 4).expect("two slabs");
        assert_eq!(split.first, 500);
        assert!(split.order[..500].iter().all(|&i| i % 4 == 1));
        let mut sorted = split.order.clone();
        sorted.sort_unstable();
        assert!(sorted.iter().enumerate().all(|(i, &j)| i == j), "order is a permutation");
        assert!(find_split(&slabs[..4 * 1000], 4).is_none(), "too few constraints");
    }

    #[test]
    fn preconditioner_is_exact_for_a_low_rank_coupling() {
        // B = [A Gᵀ; G D] with A, D diagonally dominant and G of rank 3, so
        // the rank-p coupling approximation is exact and M = B.
        let mut state = 11u64;
        let (h, k) = (150, 320);
        let (w, z): (Vec<[f64; 3]>, Vec<[f64; 3]>) = (
            (0..k - h).map(|_| std::array::from_fn(|_| uniform(&mut state))).collect(),
            (0..h).map(|_| std::array::from_fn(|_| uniform(&mut state))).collect(),
        );
        let noise = Mat::<f64>::from_fn(k, k, |_, _| 0.01 * uniform(&mut state));
        let b = Mat::<f64>::from_fn(k, k, |i, j| {
            let (i, j) = (i.max(j), i.min(j));
            if i >= h && j < h {
                0.01 * (0..3).map(|d| w[i - h][d] * z[j][d]).sum::<f64>()
            } else if i == j {
                4.0
            } else if (i < h) == (j < h) {
                noise[(i, j)]
            } else {
                0.0
            }
        });
        let m = SlabPreconditioner::new(b.as_ref(), h).expect("exact low-rank coupling");
        let x: Vec<f64> = (0..k).map(|_| uniform(&mut state)).collect();
        let mut bx = vec![0.0; k];
        symmetric_matvec(b.as_ref(), &x, &mut bx);
        let dense = &b * MatRef::from_column_major_slice(&x, k, 1);
        assert!((0..k).all(|i| (bx[i] - dense[(i, 0)]).abs() < 1e-12 * (1.0 + dense[(i, 0)].abs())));
        m.apply(&mut bx);
        assert!(x.iter().zip(&bx).all(|(a, b)| (a - b).abs() < 1e-10), "M⁻¹B ≠ I");
        let (y, iterations) = conjugate_gradients(b.as_ref(), 5.0, &m, &x).expect("converges");
        assert!(iterations <= 2, "{iterations} iterations");
        let mut by = vec![0.0; k];
        symmetric_matvec(b.as_ref(), &y, &mut by);
        assert!(x.iter().zip(&by).all(|(a, b)| (a - b).abs() < 1e-12));
    }
}
