//! One cubic B-spline on a local knot vector of five knots (Cox–de Boor),
//! with its first and second derivatives (note §2.1).

/// `1 / (b − a)`, or 0 for coincident knots (the 0/0 := 0 convention).
#[inline]
fn inv(a: f64, b: f64) -> f64 {
    if b > a { 1.0 / (b - a) } else { 0.0 }
}

/// Value, first and second derivative at `x` of the cubic B-spline on the
/// knots `k` (non-decreasing). Spans are half-open, `[k_j, k_{j+1})`; the
/// function and its first two derivatives vanish outside `[k0, k4)`.
#[inline]
pub(crate) fn cubic(k: &[f64; 5], x: f64) -> [f64; 3] {
    if !(x >= k[0] && x < k[4]) {
        return [0.0; 3];
    }
    // Degree 0.
    let mut n0 = [0.0; 4];
    for j in 0..4 {
        if x >= k[j] && x < k[j + 1] {
            n0[j] = 1.0;
        }
    }
    // Degree 1..3 with the inverse knot differences a_ij = 1/(k_j − k_i).
    let a = |i: usize, j: usize| inv(k[i], k[j]);
    let n1: [f64; 3] = std::array::from_fn(|j| {
        (x - k[j]) * a(j, j + 1) * n0[j] + (k[j + 2] - x) * a(j + 1, j + 2) * n0[j + 1]
    });
    let n2: [f64; 2] = std::array::from_fn(|j| {
        (x - k[j]) * a(j, j + 2) * n1[j] + (k[j + 3] - x) * a(j + 1, j + 3) * n1[j + 1]
    });
    let (a03, a14) = (a(0, 3), a(1, 4));
    let value = (x - k[0]) * a03 * n2[0] + (k[4] - x) * a14 * n2[1];
    let d1 = 3.0 * (a03 * n2[0] - a14 * n2[1]);
    let d2 = 6.0 * (a03 * (a(0, 2) * n1[0] - a(1, 3) * n1[1]) - a14 * (a(1, 3) * n1[1] - a(2, 4) * n1[2]));
    [value, d1, d2]
}

/// One cubic B-spline on five strictly increasing knots as its four
/// polynomial pieces, precomputed once per anchor: evaluation is a span
/// lookup and a Horner step, with no division (Cox–de Boor in [`cubic`]
/// costs ten divisions per call, and the blending functions are evaluated
/// millions of times per evolution step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CubicPieces {
    /// The knots `k0 < … < k4`.
    knots: [f64; 5],
    /// Per span `[k_j, k_{j+1})`: `c0 + c1 u + c2 u² + c3 u³` with `u = x − k_j`.
    coeffs: [[f64; 4]; 4],
}

impl CubicPieces {
    /// The pieces of the B-spline on `knots` (strictly increasing): on each
    /// span the value and the first two derivatives at its left knot from
    /// [`cubic`], and the constant third derivative from the second
    /// derivative's change across the span (it is continuous at simple knots
    /// and vanishes at `k4`).
    pub(crate) fn new(knots: &[f64; 5]) -> Self {
        let coeffs = std::array::from_fn(|j| {
            let [v, d1, d2] = cubic(knots, knots[j]);
            let d2_end = if j == 3 { 0.0 } else { cubic(knots, knots[j + 1])[2] };
            let h = knots[j + 1] - knots[j];
            [v, d1, 0.5 * d2, (d2_end - d2) / (6.0 * h)]
        });
        Self { knots: *knots, coeffs }
    }

    /// The value alone at `x` (zero outside `[k0, k4)`).
    #[inline]
    pub(crate) fn value(&self, x: f64) -> f64 {
        let k = &self.knots;
        if !(x >= k[0] && x < k[4]) {
            return 0.0;
        }
        let span = usize::from(x >= k[1]) + usize::from(x >= k[2]) + usize::from(x >= k[3]);
        let [c0, c1, c2, c3] = self.coeffs[span];
        let u = x - k[span];
        ((c3 * u + c2) * u + c1) * u + c0
    }

    /// Value, first and second derivative at `x` (zero outside `[k0, k4)`),
    /// as [`cubic`] to round-off.
    #[inline]
    pub(crate) fn eval(&self, x: f64) -> [f64; 3] {
        let k = &self.knots;
        if !(x >= k[0] && x < k[4]) {
            return [0.0; 3];
        }
        let span = usize::from(x >= k[1]) + usize::from(x >= k[2]) + usize::from(x >= k[3]);
        let [c0, c1, c2, c3] = self.coeffs[span];
        let u = x - k[span];
        [((c3 * u + c2) * u + c1) * u + c0, (3.0 * c3 * u + 2.0 * c2) * u + c1, 6.0 * c3 * u + 2.0 * c2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_spline_values() {
        let k = [0.0, 1.0, 2.0, 3.0, 4.0];
        // The uniform cubic B-spline: 1/6, 2/3, 1/6 at the inner knots.
        assert!((cubic(&k, 1.0)[0] - 1.0 / 6.0).abs() < 1e-14);
        assert!((cubic(&k, 2.0)[0] - 2.0 / 3.0).abs() < 1e-14);
        assert!((cubic(&k, 3.0)[0] - 1.0 / 6.0).abs() < 1e-14);
        assert_eq!(cubic(&k, 2.0)[1], 0.0);
        assert!((cubic(&k, 2.0)[2] + 2.0).abs() < 1e-14);
        assert_eq!(cubic(&k, 4.0), [0.0; 3]);
        assert_eq!(cubic(&k, -0.1), [0.0; 3]);
    }

    #[test]
    fn derivatives_match_finite_differences_on_non_uniform_knots() {
        let k = [-0.3, 0.1, 0.25, 0.9, 1.0];
        let e = 1e-6;
        for i in 1..40 {
            let x = -0.3 + 1.3 * i as f64 / 40.0;
            if k.iter().any(|&t| (t - x).abs() < 1e-4) {
                continue;
            }
            let [_, d1, d2] = cubic(&k, x);
            let fd1 = (cubic(&k, x + e)[0] - cubic(&k, x - e)[0]) / (2.0 * e);
            let fd2 = (cubic(&k, x + e)[1] - cubic(&k, x - e)[1]) / (2.0 * e);
            assert!((d1 - fd1).abs() < 1e-6, "x {x}: d1 {d1} fd {fd1}");
            assert!((d2 - fd2).abs() < 1e-5, "x {x}: d2 {d2} fd {fd2}");
        }
    }

    #[test]
    fn pieces_match_cox_de_boor() {
        for k in [[0.0, 1.0, 2.0, 3.0, 4.0], [-0.3, 0.1, 0.25, 0.9, 1.0], [-1.0, -0.875, -0.75, -0.5, 0.0]] {
            let pieces = CubicPieces::new(&k);
            let scale = 1.0 / (k[4] - k[0]);
            for i in 0..=400 {
                let x = k[0] - 0.1 + (k[4] - k[0] + 0.2) * i as f64 / 400.0;
                let (got, want) = (pieces.eval(x), cubic(&k, x));
                for d in 0..3 {
                    let tol = 1e-12 * scale.powi(d as i32).max(1.0);
                    assert!(
                        (got[d] - want[d]).abs() < tol,
                        "knots {k:?} x {x} derivative {d}: {got:?} vs {want:?}"
                    );
                }
            }
            // Exactly at the knots (the half-open spans).
            for &x in &k {
                let (got, want) = (pieces.eval(x), cubic(&k, x));
                assert!((0..3).all(|d| (got[d] - want[d]).abs() < 1e-12 * scale.powi(d as i32).max(1.0)));
            }
        }
    }

    #[test]
    fn coincident_knots_do_not_divide_by_zero() {
        let k = [0.0, 0.0, 0.0, 1.0, 2.0];
        for i in 0..20 {
            let v = cubic(&k, i as f64 * 0.1);
            assert!(v.iter().all(|x| x.is_finite()));
        }
        assert!(cubic(&k, 0.0)[0] > 0.0 || cubic(&k, 0.5)[0] > 0.0);
    }
}
