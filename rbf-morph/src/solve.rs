//! The bordered system of §3 solved exactly in f64 (faer inside).
//!
//! ```text
//! [ Φ + λI  P ] [d]   [h]
//! [ Pᵀ      0 ] [c] = [0]        Φ_ij = φ(|c_i − c_j|),  P = [1 | positions]
//! ```
//!
//! A general LU loses 4–6 digits on this saddle-point matrix. Instead the
//! polynomial part is projected out: a Householder QR of `P = Q [R; 0]`
//! (`m = D + 1` reflectors, `Q = I − V T Vᵀ` in compact WY form) is applied
//! to `Φ` from both sides in two GEMM passes, `QᵀΦQ = Φ − X Vᵀ − V Xᵀ`. Only
//! the lower triangle of `Φ` is built (in parallel, `n²/2` kernels) and
//! updated; the products read it as a symmetric matrix. With
//! `d = Z y` (`Z` the last `n − m` columns of `Q`, so `Pᵀ d = 0` holds by
//! construction), the trailing block `B = Zᵀ(Φ + λI)Z` is symmetric positive
//! definite for a conditionally positive definite kernel of order 2 and
//! unisolvent points; it is factored in place by Cholesky. If that fails
//! (round-off with near-duplicate constraints, or an indefinite block) the
//! block is rebuilt and factored by Bunch–Kaufman `LBLᵀ`. Then
//! `R c = Q₁ᵀ h − Q₁ᵀ Φ Z y`, read off the transformed matrix.
//!
//! When the constraints form two groups well apart (the two shapes of a
//! shape transformation), `B` is instead solved by the slab solver
//! (`slab.rs`): Cholesky of each group's diagonal block, a low-rank
//! coupling, and conjugate gradients to the backward error of the direct
//! solve, at about a quarter of the flops; the dense Cholesky remains the
//! fallback ([`Solver`]).
//!
//! The reciprocal condition number of `B` is estimated in the 1-norm with
//! Hager's method (a handful of extra solves; with the slab solver, solves
//! with its preconditioner: on the reference case at 8000 constraints the
//! estimate is within 10 % of the dense one).

use crate::error::RbfError;
use crate::hierarchical::{self, IterativeFailure};
use crate::kernel::Kernel;
use crate::slab::{self, SlabPreconditioner};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::{lblt as bunch_kaufman, llt};
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Which factorization solved the projected system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Factorization {
    /// Cholesky `LLᵀ` of the projected block (the normal case).
    Cholesky,
    /// Bunch–Kaufman `LBLᵀ` (symmetric indefinite), the fallback when
    /// Cholesky failed.
    Lblt,
    /// The slab solver (see [`Solver::Auto`]): Cholesky of each slab's
    /// diagonal block and a low-rank coupling as the preconditioner of
    /// conjugate gradients, run to a relative residual of 1e-13 in f64.
    SlabCg {
        /// Conjugate-gradient iterations taken.
        iterations: usize,
    },
    /// The hierarchical solver ([`Solver::Hierarchical`]): an H-matrix of
    /// the kernel matrix (ACA-compressed far blocks) inside GMRES with a
    /// two-level overlapping domain-decomposition preconditioner, run to a
    /// relative residual of 1e-11 (see the crate docs).
    Hierarchical {
        /// GMRES iterations taken.
        iterations: usize,
        /// Bytes of the solver's data: the H-matrix's blocks, the
        /// preconditioner's factors and the GMRES basis (what is checked
        /// against the memory limit, `isomorph_common::set_memory_limit`;
        /// the process's peak is this plus the inputs and allocator
        /// overhead).
        bytes: usize,
    },
}

/// The solution of the bordered system.
pub(crate) struct Solution {
    /// RBF weights `d_j`.
    pub weights: Vec<f64>,
    /// Polynomial coefficients: constant first, then one per coordinate.
    pub poly: Vec<f64>,
    /// Which factorization was used.
    pub factorization: Factorization,
    /// Reciprocal 1-norm condition estimate of the projected block.
    pub rcond: f64,
    /// The fitted function at the centres, when the solver computed it
    /// (the hierarchical solver, with its H-matrix).
    pub centre_values: Option<Vec<f64>>,
    /// Why the hierarchical solver gave way to this dense solution, if it did.
    pub fallback: Option<IterativeFailure>,
}

/// Householder QR of the `n × m` polynomial matrix `P = [1 | x]`.
pub(crate) struct PolyQr {
    n: usize,
    pub m: usize,
    /// Householder vectors, column-major `n × m` (`v_k[k] = 1`, zeros above).
    v: Mat<f64>,
    tau: Vec<f64>,
    /// Upper-triangular `m × m` factor.
    pub r: Mat<f64>,
}

impl PolyQr {
    /// QR of `[1 | positions]`; `NotUnisolvent` when the positions span
    /// fewer than `dim` dimensions.
    pub fn new(positions: &[f64], dim: usize) -> Result<Self, RbfError> {
        let n = positions.len() / dim;
        let m = dim + 1;
        let mut a = Mat::<f64>::from_fn(n, m, |i, k| if k == 0 { 1.0 } else { positions[i * dim + k - 1] });
        let mut v = Mat::<f64>::zeros(n, m);
        let mut tau = vec![0.0; m];
        for k in 0..m {
            let norm = (k..n).map(|i| a[(i, k)] * a[(i, k)]).sum::<f64>().sqrt();
            let x0 = a[(k, k)];
            let alpha = if x0 >= 0.0 { -norm } else { norm };
            let v0 = x0 - alpha;
            if norm == 0.0 || v0 == 0.0 {
                // Column already zero below the diagonal: identity reflector.
                v[(k, k)] = 1.0;
                tau[k] = 0.0;
                continue;
            }
            v[(k, k)] = 1.0;
            for i in k + 1..n {
                v[(i, k)] = a[(i, k)] / v0;
            }
            let vv: f64 = (k..n).map(|i| v[(i, k)] * v[(i, k)]).sum();
            tau[k] = 2.0 / vv;
            for j in k..m {
                let s: f64 = (k..n).map(|i| v[(i, k)] * a[(i, j)]).sum::<f64>() * tau[k];
                for i in k..n {
                    a[(i, j)] -= s * v[(i, k)];
                }
            }
        }
        let r = Mat::<f64>::from_fn(m, m, |i, j| if i <= j { a[(i, j)] } else { 0.0 });
        let diag_max = (0..m).map(|k| r[(k, k)].abs()).fold(0.0, f64::max);
        let rank = (0..m).filter(|&k| r[(k, k)].abs() > 1e-9 * diag_max).count();
        if rank < m {
            return Err(RbfError::NotUnisolvent { rank: rank.saturating_sub(1), dim });
        }
        Ok(Self { n, m, v, tau, r })
    }

    /// An upper bound of the bytes of the QR of `n` points with `m`
    /// polynomial terms (the reflectors, their column padding, `R`, `τ`).
    pub fn bytes_bound(n: usize, m: usize) -> usize {
        ((n + 16) * m + m * m + m) * size_of::<f64>()
    }

    /// `x ← Qᵀ x` (reflectors in order).
    pub fn apply_qt(&self, x: &mut [f64]) {
        for k in 0..self.m {
            self.reflect(k, x);
        }
    }

    /// `x ← Q x` (reflectors in reverse order).
    pub fn apply_q(&self, x: &mut [f64]) {
        for k in (0..self.m).rev() {
            self.reflect(k, x);
        }
    }

    fn reflect(&self, k: usize, x: &mut [f64]) {
        let s: f64 = (k..self.n).map(|i| self.v[(i, k)] * x[i]).sum::<f64>() * self.tau[k];
        for i in k..self.n {
            x[i] -= s * self.v[(i, k)];
        }
    }

    /// The compact-WY factor `T` (upper triangular) with `Q = I − V T Vᵀ`.
    fn wy_t(&self) -> Mat<f64> {
        let m = self.m;
        let mut t = Mat::<f64>::zeros(m, m);
        for k in 0..m {
            t[(k, k)] = self.tau[k];
            // t[0..k, k] = −τ_k T[0..k, 0..k] (V[:, 0..k]ᵀ v_k)
            let w: Vec<f64> =
                (0..k).map(|j| (k..self.n).map(|i| self.v[(i, j)] * self.v[(i, k)]).sum::<f64>()).collect();
            for i in 0..k {
                let s: f64 = (i..k).map(|j| t[(i, j)] * w[j]).sum();
                t[(i, k)] = -self.tau[k] * s;
            }
        }
        t
    }
}

/// Fills the lower triangle of `a` (column-major `n × n`) with `Φ + λI` and
/// transforms it to the lower triangle of `QᵀΦQ` in place. The strict upper
/// triangle is neither read nor written: the kernel is evaluated `n²/2`
/// times and the rank-`2m` update touches half the matrix.
pub(crate) fn build_projected(
    a: &mut [f64],
    positions: &[f64],
    dim: usize,
    kernel: Kernel,
    smoothing: f64,
    qr: &PolyQr,
) {
    let n = qr.n;
    // One coordinate per vector, so that each column's r² and kernels are
    // vectorized loops.
    let coords: Vec<Vec<f64>> = (0..dim).map(|k| (0..n).map(|i| positions[i * dim + k]).collect()).collect();
    a.par_chunks_mut(n).enumerate().for_each(|(j, col)| {
        let col = &mut col[j..];
        col.fill(0.0);
        for xs in &coords {
            let (xs, xj) = (&xs[j..], xs[j]);
            col.iter_mut().zip(xs).for_each(|(r2, x)| *r2 += (x - xj) * (x - xj));
        }
        kernel.eval_r2_in_place(col);
        col[0] += smoothing;
    });
    let mut am = MatMut::from_column_major_slice_mut(a, n, n);
    // Y = A V (A symmetric from its lower triangle L: Y = L V + L_strictᵀ V),
    // M = Vᵀ Y,  X = Y T − ½ V Tᵀ M T,  QᵀAQ = A − X Vᵀ − V Xᵀ.
    let t = qr.wy_t();
    let par = crate::solve::PARALLELISM;
    let mut y = Mat::<f64>::zeros(n, qr.m);
    symmetric_lower_mul(y.as_mut(), Accum::Replace, am.as_ref(), qr.v.as_ref(), par);
    let mm = qr.v.transpose() * &y;
    let x = &y * &t - (&qr.v * (t.transpose() * &mm * &t)) * 0.5;
    let rect = BlockStructure::Rectangular;
    for (l, r) in [(x.as_ref(), qr.v.transpose()), (qr.v.as_ref(), x.transpose())] {
        triangular::matmul(
            am.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            l,
            rect,
            r,
            rect,
            -1.0,
            par,
        );
    }
}

/// `y ← S x + y` (or `y ← S x` with [`Accum::Replace`]) for the symmetric
/// `S` given by its lower triangle.
fn symmetric_lower_mul(y: MatMut<'_, f64>, accum: Accum, s: MatRef<'_, f64>, x: MatRef<'_, f64>, par: Par) {
    let rect = BlockStructure::Rectangular;
    let mut y = y;
    triangular::matmul(y.as_mut(), rect, accum, s, BlockStructure::TriangularLower, x, rect, 1.0, par);
    triangular::matmul(
        y,
        rect,
        Accum::Add,
        s.transpose(),
        BlockStructure::StrictTriangularUpper,
        x,
        rect,
        1.0,
        par,
    );
}

/// Copies the strict lower triangle of `b` onto the strict upper one.
fn mirror_lower(mut b: MatMut<'_, f64>) {
    for j in 0..b.ncols() {
        for i in 0..j {
            b[(i, j)] = b[(j, i)];
        }
    }
}

/// A factored projected block `B` (stored in the trailing block of the
/// transformed matrix).
enum Factor {
    Llt,
    Lblt { subdiag: faer::diag::Diag<f64>, perm: Vec<usize>, perm_inv: Vec<usize> },
}

/// How [`Interpolant::fit`](crate::Interpolant::fit) solves the projected
/// system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Solver {
    /// The hierarchical solver from [`HIERARCHICAL_MIN`] (4000)
    /// constraints, both kernels (the default); below that the slab solver
    /// ([`Factorization::SlabCg`]) when the constraints form two groups
    /// well apart along some axis (the two shapes of a shape
    /// transformation), with at least 1500 constraints; the dense Cholesky
    /// otherwise, and whenever an iterative solver does not converge.
    #[default]
    Auto,
    /// Always the dense Cholesky (with its `LBLᵀ` fallback).
    Dense,
    /// The hierarchical solver ([`Factorization::Hierarchical`]), `O(n log n)`
    /// memory and near-linear time; the default ([`Solver::Auto`]) from
    /// [`HIERARCHICAL_MIN`] constraints. Falls back to the dense Cholesky when GMRES does
    /// not converge, or fails with [`RbfError::NotConverged`] when the dense
    /// system would not fit in memory.
    Hierarchical,
}

/// Fewest constraints for which [`Solver::Auto`] uses the hierarchical
/// solver (both kernels), where it wins in time and memory over the slab
/// solver: on the sphere → torus reference case it takes as much CPU at
/// 3000 constraints (0.38 s against 0.39 s of process user time, 67 MB
/// against 110 MB), 1.7× less at 4000 (0.44 s against 0.73 s, 80 MB
/// against 174 MB) and 3× less at 8000 (1.00 s against 3.14 s, 128 MB
/// against 593 MB); at 2000 the slab solver is faster (0.17 s against
/// 0.22 s). `docs/EXPERIMENTS.md` (issue 21, fourth session).
pub const HIERARCHICAL_MIN: usize = 4000;

/// The parallelism of the dense kernels (faer): a fixed task count rather
/// than the pool's thread count, because faer's blocking, and with it the
/// rounding, follows the task count; rayon runs the tasks on however many
/// threads the [`Control`](isomorph_common::Control) gives, so the solution
/// is bit-identical for any thread count.
pub(crate) const PARALLELISM: Par = Par::Rayon(std::num::NonZeroUsize::new(4).expect("4 > 0"));

/// Solves the interpolation system for `positions` (row-major `n × dim`,
/// already normalized) and `values`, with the hierarchical solver's
/// `settings` when `solver` picks it.
pub(crate) fn solve_with(
    positions: &[f64],
    dim: usize,
    values: &[f64],
    kernel: Kernel,
    smoothing: f64,
    solver: Solver,
    settings: &hierarchical::Settings,
) -> Result<Solution, RbfError> {
    let n = values.len();
    let iterative = match solver {
        Solver::Auto => n >= HIERARCHICAL_MIN,
        Solver::Dense => false,
        Solver::Hierarchical => n > dim + 1,
    };
    let mut fallback = None;
    if iterative {
        match hierarchical::solve(positions, dim, values, kernel, smoothing, settings)? {
            Ok(solution) => return Ok(solution),
            Err(failure) => {
                if !settings.dense_fallback || reserve_system(n, false).is_err() {
                    return Err(RbfError::NotConverged {
                        iterations: failure.iterations,
                        residual: failure.residual,
                    });
                }
                fallback = Some(failure);
            }
        }
    }
    let mut solution = solve_direct(positions, dim, values, kernel, smoothing, solver)?;
    solution.fallback = fallback;
    Ok(solution)
}

/// The direct solvers of [`solve_with`]: the slab solver when `solver` is
/// [`Solver::Auto`] and the constraints split into slabs, dense otherwise.
fn solve_direct(
    positions: &[f64],
    dim: usize,
    values: &[f64],
    kernel: Kernel,
    smoothing: f64,
    solver: Solver,
) -> Result<Solution, RbfError> {
    let split = match solver {
        Solver::Auto => slab::find_split(positions, dim),
        Solver::Dense | Solver::Hierarchical => None,
    };
    let Some(split) = split else {
        return solve_ordered(positions, dim, values, kernel, smoothing, None);
    };
    let ordered: Vec<f64> =
        split.order.iter().flat_map(|&i| positions[i * dim..(i + 1) * dim].iter().copied()).collect();
    let ordered_values: Vec<f64> = split.order.iter().map(|&i| values[i]).collect();
    let mut sol = solve_ordered(&ordered, dim, &ordered_values, kernel, smoothing, Some(split.first))?;
    let mut weights = vec![0.0; values.len()];
    for (w, &i) in sol.weights.iter().zip(&split.order) {
        weights[i] = *w;
    }
    sol.weights = weights;
    Ok(sol)
}

/// [`solve`] with the constraints in the given order; `slab_end` is where
/// the first slab ends when the slab solver should be tried.
fn solve_ordered(
    positions: &[f64],
    dim: usize,
    values: &[f64],
    kernel: Kernel,
    smoothing: f64,
    slab_end: Option<usize>,
) -> Result<Solution, RbfError> {
    let n = values.len();
    let m = dim + 1;
    if n < m {
        return Err(RbfError::TooFewConstraints { got: n, needed: m, dim });
    }
    reserve_system(n, slab_end.is_some())?;
    let qr = PolyQr::new(positions, dim)?;
    let k = n - m;
    let mut g = values.to_vec();
    qr.apply_qt(&mut g);
    let mut a = vec![0.0f64; n * n];
    let mut y2 = g[m..].to_vec();
    let (factorization, rcond) = if k == 0 {
        (Factorization::Cholesky, 1.0)
    } else {
        build_projected(&mut a, positions, dim, kernel, smoothing, &qr);
        let am = MatMut::from_column_major_slice_mut(&mut a, n, n);
        let mut b = am.submatrix_mut(m, m, k, k);
        // Both kernels are conditionally positive definite of order 2, so B
        // is positive definite; check the sign through its trace anyway and
        // negate an (inverted) negative definite block.
        let trace: f64 = (0..k).map(|i| b[(i, i)]).sum();
        let sign = if trace < 0.0 { -1.0 } else { 1.0 };
        if sign < 0.0 {
            b.rb_mut().col_iter_mut().for_each(|c| c.iter_mut().for_each(|x| *x = -*x));
        }
        for v in &mut y2 {
            *v *= sign;
        }
        let norm1 = one_norm(b.rb());
        // Slab rows of B start after the m constraints absorbed by the
        // polynomial part.
        let slab = slab_end.and_then(|end| end.checked_sub(m)).filter(|h| (1..k).contains(h)).and_then(|h| {
            let preconditioner = SlabPreconditioner::new(b.rb(), h)?;
            let (y, iterations) = slab::conjugate_gradients(b.rb(), norm1, &preconditioner, &y2)?;
            Some((y, iterations, hager_inverse_norm(k, &|x| preconditioner.apply(x))))
        });
        let (factorization, inv_norm) = match slab {
            Some((y, iterations, inv_norm)) => {
                y2 = y;
                (Factorization::SlabCg { iterations }, inv_norm)
            }
            None => dense_solve(&mut a, n, m, sign, &mut y2, &|a| {
                build_projected(a, positions, dim, kernel, smoothing, &qr)
            }),
        };
        let rcond = if norm1 > 0.0 && inv_norm.is_finite() && inv_norm > 0.0 {
            1.0 / (norm1 * inv_norm)
        } else {
            0.0
        };
        (factorization, rcond)
    };
    if rcond.is_nan() || rcond <= f64::EPSILON || y2.iter().any(|v| !v.is_finite()) {
        return Err(RbfError::Singular { rcond: if rcond.is_finite() { rcond } else { 0.0 } });
    }
    // d = Q [0; y2]
    let mut weights = vec![0.0; n];
    weights[m..].copy_from_slice(&y2);
    qr.apply_q(&mut weights);
    // R c = g[0..m] − (QᵀΦQ)[0..m, m..] y2, read from the lower block.
    let am = MatMut::from_column_major_slice_mut(&mut a, n, n);
    let mut rhs: Vec<f64> = (0..m)
        .map(|i| g[i] - if k == 0 { 0.0 } else { (0..k).map(|j| am[(m + j, i)] * y2[j]).sum::<f64>() })
        .collect();
    for i in (0..m).rev() {
        let s: f64 = (i + 1..m).map(|j| qr.r[(i, j)] * rhs[j]).sum();
        rhs[i] = (rhs[i] - s) / qr.r[(i, i)];
    }
    if rhs.iter().chain(&weights).any(|v| !v.is_finite()) {
        return Err(RbfError::Singular { rcond });
    }
    Ok(Solution { weights, poly: rhs, factorization, rcond, centre_values: None, fallback: None })
}

/// Checks the dense system's memory (the `n × n` matrix of f64, and the
/// slab preconditioner's diagonal-block factors when it is tried) against the
/// memory limit before anything is allocated.
fn reserve_system(n: usize, slab: bool) -> Result<(), RbfError> {
    let matrices = if slab { 2 } else { 1 };
    let requested = n.saturating_mul(n).saturating_mul(size_of::<f64>()).saturating_mul(matrices);
    reserve(|| format!("the dense interpolation system of {n} constraints"), requested)
}

/// What a user can lower when a solver's system is over the memory limit.
const MEMORY_ADVICE: &str = "use fewer constraints (points per shape, or a coarser image)";

/// Checks `requested` bytes for `what` (a solver's system) against the
/// memory limit.
pub(crate) fn reserve(what: impl FnOnce() -> String, requested: usize) -> Result<(), RbfError> {
    isomorph_common::reserve_memory(what, requested, MEMORY_ADVICE).map_err(memory_error)
}

/// The memory-limit error for `what`, which needs (at least) `requested`
/// bytes, over `limit`.
pub(crate) fn over_limit(what: String, requested: usize, limit: usize) -> RbfError {
    memory_error(isomorph_common::MemoryLimitError { what, requested, limit, advice: MEMORY_ADVICE })
}

fn memory_error(e: isomorph_common::MemoryLimitError) -> RbfError {
    RbfError::from(isomorph_common::MorphError::from(e))
}

/// Factors the projected block `B` (the trailing `k × k` block of the
/// `n × n` matrix `a`, already multiplied by `sign`) by Cholesky, or by
/// Bunch–Kaufman after `rebuild` refills `a` when Cholesky fails, and solves
/// `B y = y2` in place. Returns the factorization and Hager's estimate of
/// `‖B⁻¹‖₁`.
fn dense_solve(
    a: &mut [f64],
    n: usize,
    m: usize,
    sign: f64,
    y2: &mut [f64],
    rebuild: &dyn Fn(&mut [f64]),
) -> (Factorization, f64) {
    let k = n - m;
    let par = crate::solve::PARALLELISM;
    let llt_ok = {
        let am = MatMut::from_column_major_slice_mut(a, n, n);
        let b = am.submatrix_mut(m, m, k, k);
        let mut mem =
            MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(k, par, Default::default()));
        llt::factor::cholesky_in_place(
            b,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .is_ok()
    };
    let factor = if llt_ok {
        Factor::Llt
    } else {
        // Rebuild the block (the failed factorization overwrote it) and use
        // the symmetric-indefinite factorization on the whole block.
        rebuild(a);
        let am = MatMut::from_column_major_slice_mut(a, n, n);
        let mut b = am.submatrix_mut(m, m, k, k);
        mirror_lower(b.rb_mut());
        if sign < 0.0 {
            b.rb_mut().col_iter_mut().for_each(|c| c.iter_mut().for_each(|x| *x = -*x));
        }
        let mut subdiag = faer::diag::Diag::<f64>::zeros(k);
        let mut perm = vec![0usize; k];
        let mut perm_inv = vec![0usize; k];
        let mut mem = MemBuffer::new(bunch_kaufman::factor::cholesky_in_place_scratch::<usize, f64>(
            k,
            par,
            Default::default(),
        ));
        bunch_kaufman::factor::cholesky_in_place(
            b.rb_mut(),
            subdiag.as_mut(),
            &mut perm,
            &mut perm_inv,
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        Factor::Lblt { subdiag, perm, perm_inv }
    };
    let am = MatRef::from_column_major_slice(a, n, n);
    let b = am.submatrix(m, m, k, k);
    let solve_in_place = |x: &mut [f64]| {
        let rhs = MatMut::from_column_major_slice_mut(x, k, 1);
        match &factor {
            Factor::Llt => {
                let mut mem = MemBuffer::new(llt::solve::solve_in_place_scratch::<f64>(k, 1, par));
                llt::solve::solve_in_place(b, rhs, par, MemStack::new(&mut mem));
            }
            Factor::Lblt { subdiag, perm, perm_inv } => {
                let perm = faer::perm::PermRef::new_checked(perm, perm_inv, k);
                let mut mem =
                    MemBuffer::new(bunch_kaufman::solve::solve_in_place_scratch::<usize, f64>(k, 1, par));
                bunch_kaufman::solve::solve_in_place(
                    b,
                    b.diagonal(),
                    subdiag.as_ref(),
                    perm,
                    rhs,
                    par,
                    MemStack::new(&mut mem),
                );
            }
        }
    };
    solve_in_place(y2);
    let inv_norm = hager_inverse_norm(k, &solve_in_place);
    let factorization = match factor {
        Factor::Llt => Factorization::Cholesky,
        Factor::Lblt { .. } => Factorization::Lblt,
    };
    (factorization, inv_norm)
}

/// The 1-norm (largest column sum of magnitudes) of a symmetric matrix
/// given by its lower triangle: column `j` sums its lower part and row `j`
/// of the strict lower part.
fn one_norm(b: MatRef<'_, f64>) -> f64 {
    let k = b.ncols();
    let sums = (0..k)
        .into_par_iter()
        .fold(
            || vec![0.0f64; k],
            |mut sums, j| {
                let col = b.col(j);
                sums[j] += col[j].abs();
                for i in j + 1..k {
                    let v = col[i].abs();
                    sums[j] += v;
                    sums[i] += v;
                }
                sums
            },
        )
        .reduce(
            || vec![0.0f64; k],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        );
    sums.into_iter().fold(0.0, f64::max)
}

/// Hager's (Higham's refinement) estimate of `‖B⁻¹‖₁` for symmetric `B`,
/// given a solver `x ← B⁻¹x`.
pub(crate) fn hager_inverse_norm(k: usize, solve: &dyn Fn(&mut [f64])) -> f64 {
    let mut x = vec![1.0 / k as f64; k];
    let mut est = 0.0;
    for iter in 0..5 {
        let mut y = x.clone();
        solve(&mut y);
        let norm: f64 = y.iter().map(|v| v.abs()).sum();
        if iter > 0 && norm <= est {
            break;
        }
        est = norm;
        let mut z: Vec<f64> = y.iter().map(|v| if *v >= 0.0 { 1.0 } else { -1.0 }).collect();
        solve(&mut z);
        let (jmax, zmax) = z
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |acc, (j, v)| if v.abs() > acc.1 { (j, v.abs()) } else { acc });
        let ztx: f64 = z.iter().zip(&x).map(|(a, b)| a * b).sum();
        if zmax <= ztx {
            break;
        }
        x.iter_mut().for_each(|v| *v = 0.0);
        x[jmax] = 1.0;
    }
    est
}
