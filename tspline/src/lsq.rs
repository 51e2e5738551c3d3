//! Sparse weighted least squares over T-spline coefficients: rows grouped by
//! leaf (each row has one entry per blending function of its leaf), the
//! normal equations `(AᵀWA + ω I) x = AᵀW b + ω x_ref` assembled column by
//! column (deterministic, parallel, no triplet lists) and solved by faer's
//! sparse Cholesky factorization.

use crate::error::TsplineError;
use crate::tmesh::TMesh;
use faer::linalg::matmul::matmul;
use faer::prelude::*;
use faer::sparse::linalg::LltError;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, MatMut, MatRef, Par, Side};
use rayon::prelude::*;

/// The rows of one leaf: `rows` is row-major with one entry per anchor of
/// the leaf's list.
#[derive(Debug, Clone, Default)]
pub(crate) struct LeafRows {
    pub rows: Vec<f64>,
    pub weights: Vec<f64>,
    pub rhs: Vec<f64>,
    /// `Σ w ‖a‖²` of the rows pushed by [`LeafRows::push_constraint`]: their
    /// part of the normal matrix's trace, left out of the Tikhonov scale.
    pub constraint_trace: f64,
}

impl LeafRows {
    /// Appends one row (`entries.len()` = the leaf's anchor count, weight
    /// ≥ 0).
    pub fn push(&mut self, entries: &[f64], weight: f64, rhs: f64) {
        debug_assert!(
            weight >= 0.0 || weight.is_nan(),
            "least-squares weights are non-negative (NaN is reported later)"
        );
        self.rows.extend_from_slice(entries);
        self.weights.push(weight);
        self.rhs.push(rhs);
    }

    /// Appends a constraint row: as [`LeafRows::push`], but its weight is
    /// left out of the mean diagonal that scales the Tikhonov term, so that
    /// strong constraints do not also strengthen the regularization of the
    /// data rows.
    pub fn push_constraint(&mut self, entries: &[f64], weight: f64, rhs: f64) {
        self.push(entries, weight, rhs);
        self.constraint_trace += weight * entries.iter().map(|a| a * a).sum::<f64>();
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.weights.len()
    }
}

/// The symbolic Cholesky factorization (fill-reducing ordering and
/// supernodal structure) of the last normal matrix, reused while the
/// sparsity pattern stays the same, as it does from one evolution step to
/// the next.
#[derive(Debug, Default)]
pub(crate) struct SymbolicCache {
    last: Option<(Vec<usize>, Vec<usize>, SymbolicLlt<usize>)>,
}

impl SymbolicCache {
    /// The Cholesky factorization of the lower triangle `(col_ptr, row_idx,
    /// vals)`, with the symbolic part reused when the pattern is the last
    /// one's.
    fn factor(
        &mut self,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        vals: &[f64],
    ) -> Result<Llt<usize, f64>, LltError> {
        let n = col_ptr.len() - 1;
        let same = matches!(&self.last, Some((c, r, _)) if *c == col_ptr && *r == row_idx);
        if !same {
            let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
            let symbolic = SymbolicLlt::try_new(pattern, Side::Lower)?;
            self.last = Some((col_ptr, row_idx, symbolic));
        }
        let Some((col_ptr, row_idx, symbolic)) = &self.last else { unreachable!("set above") };
        let matrix =
            SparseColMatRef::new(SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx), vals);
        Llt::try_new_with_symbolic(symbolic.clone(), matrix, Side::Lower)
    }
}

/// How a solve went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SolveStats {
    /// Unknowns.
    pub unknowns: usize,
    /// Stored non-zeros of the lower triangle of the normal matrix.
    pub nonzeros: usize,
}

/// Solves `min Σ w_r (a_r·x − b_r)² + ω Σ_i (x_i − x_ref,i)²` where `ω` is
/// `tikhonov` times the mean diagonal of `AᵀWA` (so the regularization is
/// relative to the data term).
pub(crate) fn solve(
    mesh: &TMesh,
    blocks: &[LeafRows],
    tikhonov: f64,
    reference: &[f64],
    what: &'static str,
    cache: &mut SymbolicCache,
) -> Result<(Vec<f64>, SolveStats), TsplineError> {
    let n = mesh.anchor_count();
    // Per leaf, the dense Gram matrix `RᵀWR` (m × m, one GEMM of the
    // weighted rows `W^½ R`) and `RᵀWb` of its rows, so that the global
    // assembly below touches each leaf's m² entries once instead of once
    // per row. The Gram matrix is symmetric, so its column-major storage
    // also holds its rows.
    let grams: Vec<(Vec<f64>, Vec<f64>)> = blocks
        .par_iter()
        .enumerate()
        .map(|(leaf, blk)| {
            if blk.weights.is_empty() {
                return (Vec::new(), Vec::new());
            }
            let m = mesh.leaf_anchors(leaf).len();
            let k = blk.len();
            let mut rhs = vec![0.0f64; m];
            let mut scaled = blk.rows.clone();
            for ((row, &w), &b) in scaled.chunks_exact_mut(m).zip(&blk.weights).zip(&blk.rhs) {
                for (r, x) in rhs.iter_mut().zip(row.iter()) {
                    *r += w * b * x;
                }
                let s = w.sqrt();
                row.iter_mut().for_each(|x| *x *= s);
            }
            let mut gram = vec![0.0f64; m * m];
            let rows = MatRef::from_row_major_slice(&scaled, k, m);
            matmul(
                MatMut::from_column_major_slice_mut(&mut gram, m, m),
                Accum::Replace,
                rows.transpose(),
                rows,
                1.0,
                Par::Seq,
            );
            (gram, rhs)
        })
        .collect();
    // Column a of the lower triangle: the Gram rows of a in every leaf.
    let columns: Vec<(Vec<u32>, Vec<f64>, f64)> = (0..n)
        .into_par_iter()
        .map_init(
            || (vec![0.0f64; n], vec![false; n], Vec::<u32>::new()),
            |(acc, seen, touched), a| {
                // Every leaf of `a` contributes to the pattern, with or
                // without rows, so that the pattern is the T-mesh's and the
                // symbolic factorization can be reused.
                let mut rhs = 0.0;
                for &(leaf, pos) in mesh.anchor_leaves(a) {
                    let (gram, leaf_rhs) = &grams[leaf as usize];
                    let list = mesh.leaf_anchors(leaf as usize);
                    let m = list.len();
                    let pos = pos as usize;
                    if !gram.is_empty() {
                        rhs += leaf_rhs[pos];
                    }
                    for (q, &b) in list.iter().enumerate() {
                        if (b as usize) < a {
                            continue;
                        }
                        if !gram.is_empty() {
                            acc[b as usize] += gram[pos * m + q];
                        }
                        if !seen[b as usize] {
                            seen[b as usize] = true;
                            touched.push(b);
                        }
                    }
                }
                if !seen[a] {
                    touched.push(a as u32);
                }
                touched.sort_unstable();
                let vals = touched.iter().map(|&b| acc[b as usize]).collect();
                let rows = touched.clone();
                for &b in touched.iter() {
                    acc[b as usize] = 0.0;
                    seen[b as usize] = false;
                }
                touched.clear();
                (rows, vals, rhs)
            },
        )
        .collect();
    let constraints: f64 = blocks.iter().map(|b| b.constraint_trace).sum();
    let trace = columns.iter().map(|(_, v, _)| v[0]).sum::<f64>();
    let mean_diag = (trace - constraints).max(0.0) / n.max(1) as f64;
    let omega = tikhonov * if mean_diag > 0.0 { mean_diag } else { 1.0 };
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    let mut vals = Vec::new();
    let mut rhs = Col::<f64>::zeros(n);
    col_ptr.push(0usize);
    for (a, (rows, v, b)) in columns.into_iter().enumerate() {
        for (r, x) in rows.into_iter().zip(v) {
            row_idx.push(r as usize);
            vals.push(if r as usize == a { x + omega } else { x });
        }
        rhs[a] = b + omega * reference[a];
        col_ptr.push(row_idx.len());
    }
    if vals.iter().any(|v| !v.is_finite()) || (0..n).any(|i| !rhs[i].is_finite()) {
        return Err(TsplineError::NonFinite(what));
    }
    let nonzeros = vals.len();
    let llt = cache.factor(col_ptr, row_idx, &vals).map_err(|_| TsplineError::Singular(what))?;
    llt.solve_in_place(rhs.as_mat_mut());
    let x: Vec<f64> = (0..n).map(|i| rhs[i]).collect();
    if x.iter().any(|v| !v.is_finite()) {
        return Err(TsplineError::Singular(what));
    }
    Ok((x, SolveStats { unknowns: n, nonzeros }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One row per leaf centre and corner with pseudo-random values.
    fn blocks(mesh: &TMesh, seed: f64) -> Vec<LeafRows> {
        let mut local = crate::basis::LocalBasis::default();
        let (mut r, mut dr) = (Vec::new(), Vec::new());
        (0..mesh.leaf_count())
            .map(|leaf| {
                let (lo, hi) = mesh.leaf_box(leaf);
                let mut blk = LeafRows::default();
                for t in [0.5, 0.2, 0.8] {
                    local.at(mesh, lo + t * (hi - lo));
                    if local.rational(&mut r, &mut dr) {
                        blk.push(&r, 1.0, ((leaf as f64 + seed) * 12.9898).sin());
                    }
                }
                blk
            })
            .collect()
    }

    #[test]
    fn a_reused_symbolic_factorization_solves_a_new_system() {
        let mesh = TMesh::uniform(2).unwrap();
        let reference = vec![0.0; mesh.anchor_count()];
        let mut warm = SymbolicCache::default();
        let (first, _) = solve(&mesh, &blocks(&mesh, 0.0), 1e-3, &reference, "test", &mut warm).unwrap();
        // Same pattern, other values: the cached symbolic part is reused and
        // the solution equals a cold solve's.
        let other = blocks(&mesh, 0.5);
        let (again, _) = solve(&mesh, &other, 1e-3, &reference, "test", &mut warm).unwrap();
        let (cold, _) = solve(&mesh, &other, 1e-3, &reference, "test", &mut Default::default()).unwrap();
        assert!(first.iter().zip(&again).any(|(a, b)| (a - b).abs() > 1e-3), "a different system");
        assert!(again.iter().zip(&cold).all(|(a, b)| (a - b).abs() < 1e-12));
        // Rows in only some leaves: the pattern is still the whole T-mesh's.
        let mut sparse = blocks(&mesh, 0.0);
        sparse.iter_mut().step_by(2).for_each(|b| *b = LeafRows::default());
        let (_, full) = solve(&mesh, &blocks(&mesh, 0.0), 1e-3, &reference, "test", &mut warm).unwrap();
        let (_, part) = solve(&mesh, &sparse, 1e-3, &reference, "test", &mut warm).unwrap();
        assert_eq!(full.nonzeros, part.nonzeros);
    }

    #[test]
    fn constraint_rows_do_not_scale_the_tikhonov_term() {
        let mesh = TMesh::uniform(2).unwrap();
        let reference = vec![0.0; mesh.anchor_count()];
        let data = blocks(&mesh, 0.0);
        let (x, _) = solve(&mesh, &data, 1e-2, &reference, "test", &mut Default::default()).unwrap();
        // Strong rows that the data solution already satisfies: as
        // constraints they leave the solution as it is; as data rows they
        // raise the mean diagonal, and with it the damping, a thousandfold.
        let (mut with_constraints, mut with_rows) = (data.clone(), data);
        let mut local = crate::basis::LocalBasis::default();
        let (mut r, mut dr) = (Vec::new(), Vec::new());
        for leaf in 0..mesh.leaf_count() {
            let (lo, hi) = mesh.leaf_box(leaf);
            local.at(&mesh, lo + 0.35 * (hi - lo));
            assert!(local.rational(&mut r, &mut dr));
            let value: f64 = mesh.leaf_anchors(leaf).iter().zip(&r).map(|(&i, a)| a * x[i as usize]).sum();
            with_constraints[leaf].push_constraint(&r, 1e3, value);
            with_rows[leaf].push(&r, 1e3, value);
        }
        let (y, _) =
            solve(&mesh, &with_constraints, 1e-2, &reference, "test", &mut Default::default()).unwrap();
        let (z, _) = solve(&mesh, &with_rows, 1e-2, &reference, "test", &mut Default::default()).unwrap();
        let diff = |a: &[f64]| a.iter().zip(&x).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(diff(&y) < 1e-6 * scale, "constraints moved the solution by {}", diff(&y));
        assert!(diff(&z) > 1e-2 * scale, "data rows changed it by only {}", diff(&z));
    }

    #[test]
    fn non_finite_systems_are_typed_errors() {
        let mesh = TMesh::uniform(2).unwrap();
        let reference = vec![0.0; mesh.anchor_count()];
        let mut nan = blocks(&mesh, 0.0);
        nan[0].rhs[0] = f64::NAN;
        let r = solve(&mesh, &nan, 1e-3, &reference, "test", &mut Default::default());
        assert!(matches!(r, Err(TsplineError::NonFinite("test"))), "{r:?}");
    }
}
