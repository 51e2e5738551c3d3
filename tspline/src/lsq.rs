//! Sparse weighted least squares over T-spline coefficients: rows grouped by
//! leaf (each row has one entry per blending function of its leaf), the
//! normal equations `(AᵀWA + ω I) x = AᵀW b + ω x_ref` assembled column by
//! column (deterministic, parallel, no triplet lists) and solved by faer's
//! sparse Cholesky factorization.

use crate::error::TsplineError;
use crate::tmesh::TMesh;
use faer::Side;
use faer::prelude::*;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use rayon::prelude::*;

/// The rows of one leaf: `rows` is row-major with one entry per anchor of
/// the leaf's list.
#[derive(Debug, Clone, Default)]
pub(crate) struct LeafRows {
    pub rows: Vec<f64>,
    pub weights: Vec<f64>,
    pub rhs: Vec<f64>,
}

impl LeafRows {
    /// Appends one row (`entries.len()` = the leaf's anchor count).
    pub fn push(&mut self, entries: &[f64], weight: f64, rhs: f64) {
        self.rows.extend_from_slice(entries);
        self.weights.push(weight);
        self.rhs.push(rhs);
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.weights.len()
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
) -> Result<(Vec<f64>, SolveStats), TsplineError> {
    let n = mesh.anchor_count();
    // Per leaf, the dense Gram matrix `RᵀWR` (m × m, rank-one updates over
    // contiguous rows, vectorized) and `RᵀWb` of its rows, so that the
    // global assembly below touches each leaf's m² entries once instead of
    // once per row.
    let grams: Vec<(Vec<f64>, Vec<f64>)> = blocks
        .par_iter()
        .enumerate()
        .map(|(leaf, blk)| {
            if blk.weights.is_empty() {
                return (Vec::new(), Vec::new());
            }
            let m = mesh.leaf_anchors(leaf).len();
            let (mut gram, mut rhs) = (vec![0.0f64; m * m], vec![0.0f64; m]);
            for (r, row) in blk.rows.chunks_exact(m).enumerate() {
                let w = blk.weights[r];
                for (q, &x) in row.iter().enumerate() {
                    let wx = w * x;
                    if wx == 0.0 {
                        continue;
                    }
                    rhs[q] += wx * blk.rhs[r];
                    gram[q * m..(q + 1) * m].iter_mut().zip(row).for_each(|(g, y)| *g += wx * y);
                }
            }
            (gram, rhs)
        })
        .collect();
    // Column a of the lower triangle: the Gram rows of a in every leaf.
    let columns: Vec<(Vec<u32>, Vec<f64>, f64)> = (0..n)
        .into_par_iter()
        .map_init(
            || (vec![0.0f64; n], vec![false; n], Vec::<u32>::new()),
            |(acc, seen, touched), a| {
                let mut rhs = 0.0;
                for &(leaf, pos) in mesh.anchor_leaves(a) {
                    let (gram, leaf_rhs) = &grams[leaf as usize];
                    if gram.is_empty() {
                        continue;
                    }
                    let list = mesh.leaf_anchors(leaf as usize);
                    let m = list.len();
                    let pos = pos as usize;
                    rhs += leaf_rhs[pos];
                    for (&b, &g) in list.iter().zip(&gram[pos * m..(pos + 1) * m]) {
                        if (b as usize) < a {
                            continue;
                        }
                        acc[b as usize] += g;
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
    let mean_diag = columns.iter().map(|(_, v, _)| v[0]).sum::<f64>() / n.max(1) as f64;
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
    let symbolic = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
    let matrix = SparseColMatRef::new(symbolic, &vals);
    let llt = matrix.sp_cholesky(Side::Lower).map_err(|_| TsplineError::Singular(what))?;
    llt.solve_in_place(rhs.as_mat_mut());
    let x: Vec<f64> = (0..n).map(|i| rhs[i]).collect();
    if x.iter().any(|v| !v.is_finite()) {
        return Err(TsplineError::Singular(what));
    }
    Ok((x, SolveStats { unknowns: n, nonzeros }))
}
