//! The uniform cubic B-spline basis of thesis §5.1.
//!
//! `B0(t) = (1 − t)³/6`, `B1(t) = (3t³ − 6t² + 4)/6`,
//! `B2(t) = (−3t³ + 3t² + 3t + 1)/6`, `B3(t) = t³/6` for `t ∈ [0, 1)`: the
//! four pieces of the cubic B-spline that blend the four control points
//! `P_a … P_{a+3}` of region `a`. They sum to one and reproduce linear
//! functions: `Σ_i B_i(t) · i = t + 1`.

/// Polynomial coefficients `b[i][p]` of `t^p` in basis function `B_i`
/// (thesis §5.2 notation), so that `B_i(t) = Σ_p b[i][p] t^p`.
pub const COEFFICIENTS: [[f64; 4]; 4] = [
    [1.0 / 6.0, -3.0 / 6.0, 3.0 / 6.0, -1.0 / 6.0],
    [4.0 / 6.0, 0.0, -6.0 / 6.0, 3.0 / 6.0],
    [1.0 / 6.0, 3.0 / 6.0, 3.0 / 6.0, -3.0 / 6.0],
    [0.0, 0.0, 0.0, 1.0 / 6.0],
];

/// The four basis values `[B0(t), B1(t), B2(t), B3(t)]`.
#[inline]
pub fn weights(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    [
        s * s * s / 6.0,
        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
        t3 / 6.0,
    ]
}

/// The derivatives `[B0'(t), …, B3'(t)]` (per unit of the parameter `t`).
#[inline]
pub fn derivatives(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    let t2 = t * t;
    [-0.5 * s * s, 1.5 * t2 - 2.0 * t, -1.5 * t2 + t + 0.5, 0.5 * t2]
}

/// `B_i(t)` evaluated from the polynomial coefficients in `f64` (the form
/// eq. 4 of the thesis sums over).
pub fn weight_poly(i: usize, t: f64) -> f64 {
    let b = &COEFFICIENTS[i];
    b[0] + t * (b[1] + t * (b[2] + t * b[3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_linear_precision() {
        for n in 0..=100 {
            let t = n as f32 / 100.0;
            let w = weights(t);
            let sum: f32 = w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-6, "t = {t}: sum {sum}");
            let first: f32 = w.iter().enumerate().map(|(i, w)| i as f32 * w).sum();
            assert!((first - (t + 1.0)).abs() < 1e-6, "t = {t}: Σ i B_i = {first}, expected {}", t + 1.0);
            let d = derivatives(t);
            assert!(d.iter().sum::<f32>().abs() < 1e-6);
            for (i, &wi) in w.iter().enumerate() {
                assert!((weight_poly(i, f64::from(t)) as f32 - wi).abs() < 1e-6);
                let h = 1e-3;
                let fd = (weight_poly(i, f64::from(t) + h) - weight_poly(i, f64::from(t) - h)) / (2.0 * h);
                assert!((fd as f32 - d[i]).abs() < 1e-5, "B{i}'({t}): {} vs {fd}", d[i]);
            }
        }
    }

    #[test]
    fn pieces_join_with_c2_continuity() {
        // B_{i+1}(0) = B_i(1) and the same for the first derivative: the
        // pieces form one C² cubic B-spline.
        let (w0, w1) = (weights(0.0), weights(1.0));
        let (d0, d1) = (derivatives(0.0), derivatives(1.0));
        for i in 0..3 {
            assert!((w0[i] - w1[i + 1]).abs() < 1e-7);
            assert!((d0[i] - d1[i + 1]).abs() < 1e-7);
        }
        assert_eq!(w0[3], 0.0);
        assert!(w1[0].abs() < 1e-7);
    }
}
