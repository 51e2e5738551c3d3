//! Radial basis kernels φ(r) of the variational interpolant (paper §3, eq. 2),
//! in f64 for the solver and in a vectorizable f32 form for batch evaluation.

/// The radial basis function of the interpolant.
///
/// Both kernels are written as functions of `r²` so no square root is needed
/// for the thin-plate kernel: `r² log r = ½ r² ln r²`.
///
/// Both are conditionally positive definite of order 2: on coefficient
/// vectors orthogonal to the degree-one polynomials their quadratic form is
/// positive, which is what makes the projected system symmetric positive
/// definite ([`crate::Interpolant`]).
///
/// How the kernel shapes the in-between shapes: `r² log r` (the paper's
/// kernel, eq. 2; the thin-plate spline, which is the variational `m = 3`
/// kernel in 4D) grows slowly, so far-away constraints matter less and the
/// in-between shapes stay slim; `r³` (the usual 3D variational kernel, the
/// biharmonic spline of 3D) grows faster, giving rounder, more bloated
/// intermediate shapes, and its system is worse conditioned (about 100× at
/// 8000 constraints on the reference case, per the measurement; see
/// [`FitReport::rcond`](crate::FitReport::rcond)). `r³` evaluates about 3×
/// faster (no logarithm).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum Kernel {
    /// `φ(r) = r² log r` (thin-plate spline, the paper's eq. 2 kernel). The default.
    #[default]
    ThinPlate,
    /// `φ(r) = r³` (triharmonic in 1D, biharmonic spline in 3D).
    Cubic,
}

impl Kernel {
    /// `φ` as a function of the squared distance, in f64.
    #[inline]
    pub fn eval_r2(self, r2: f64) -> f64 {
        match self {
            Kernel::ThinPlate => {
                if r2 > 0.0 {
                    0.5 * r2 * r2.ln()
                } else {
                    0.0
                }
            }
            Kernel::Cubic => r2 * r2.sqrt(),
        }
    }

    /// `φ'(r) / r` as a function of the squared distance, so that
    /// `∇_x φ(|x − c|) = (φ'(r)/r) (x − c)`.
    #[inline]
    pub fn gradient_factor_r2(self, r2: f64) -> f64 {
        match self {
            // d/dr (r² ln r) = 2 r ln r + r  →  /r = ln r² + 1
            Kernel::ThinPlate => {
                if r2 > 0.0 {
                    r2.ln() + 1.0
                } else {
                    0.0
                }
            }
            // d/dr r³ = 3 r²  →  /r = 3 r
            Kernel::Cubic => 3.0 * r2.sqrt(),
        }
    }

    /// A short name: `"tps"` or `"r3"` (the CLI's `--kernel` values).
    pub fn name(self) -> &'static str {
        match self {
            Kernel::ThinPlate => "tps",
            Kernel::Cubic => "r3",
        }
    }

    /// The kernel called `name` (`"tps"`, `"thin-plate"`, `"r2logr"`, `"r3"`, `"cubic"`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "tps" | "thin-plate" | "r2logr" => Some(Kernel::ThinPlate),
            "r3" | "cubic" => Some(Kernel::Cubic),
            _ => None,
        }
    }
}

impl Kernel {
    /// `φ` at every squared distance of `r2`, in place: the same values as
    /// [`Kernel::eval_r2`] to about one unit of round-off, in a loop that
    /// vectorizes (the fit's matrix and residual check evaluate `n²/2`
    /// kernels this way).
    pub(crate) fn eval_r2_in_place(self, r2: &mut [f64]) {
        match self {
            Kernel::ThinPlate => r2.iter_mut().for_each(|v| {
                let phi = 0.5 * *v * ln_f64(*v);
                *v = if *v > 0.0 { phi } else { 0.0 };
            }),
            Kernel::Cubic => r2.iter_mut().for_each(|v| *v *= v.sqrt()),
        }
    }
}

/// Natural logarithm of a positive normal `f64` to about one unit of
/// round-off, branch-free so that loops calling it vectorize: `x = m · 2^e`
/// with `m ∈ [√½, √2)`, `ln m = 2 atanh s` with `s = (m − 1)/(m + 1)`
/// (`|s| < 0.172`, series to `s²³`), `ln 2` split in two parts.
///
/// Zero, negative, subnormal or non-finite input gives a meaningless
/// result (callers select it away), never a panic.
#[inline(always)]
pub(crate) fn ln_f64(x: f64) -> f64 {
    // fdlibm's split of ln 2: the high part has 32 trailing zero bits, so
    // `e · LN2_HI` is exact.
    let ln2_hi = f64::from_bits(0x3fe6_2e42_fee0_0000);
    let ln2_lo = f64::from_bits(0x3dea_39ef_3579_3c76);
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    let bits = x.to_bits();
    let m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    let big = m > std::f64::consts::SQRT_2;
    let m = if big { 0.5 * m } else { m };
    // The biased exponent as f64 without an integer conversion (2^52 trick).
    let biased = f64::from_bits(0x4330_0000_0000_0000 | (bits >> 52)) - TWO_52;
    let e = biased - 1023.0 + if big { 1.0 } else { 0.0 };
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let mut q = 1.0 / 23.0;
    for c in [21.0, 19.0, 17.0, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0] {
        q = q * z + 1.0 / c;
    }
    let two_s = s + s;
    e * ln2_hi + (two_s + (two_s * z * q + e * ln2_lo))
}

/// `√½`, the split point of the mantissa range in [`fast_ln`].
const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Natural logarithm of a positive normal `f32`, branch-free so that loops
/// calling it vectorize (the Cephes `logf` reduction and polynomial: relative
/// error about 1e-7 over the normal range).
///
/// `x` must be positive and normal; callers clamp it (the kernels clamp `r²`
/// to at least [`TINY_R2`]). Zero, negative, subnormal or non-finite input
/// gives a meaningless finite or NaN result, never a panic.
#[inline(always)]
#[allow(clippy::excessive_precision)] // the Cephes coefficients as published
pub(crate) fn fast_ln(x: f32) -> f32 {
    let bits = x.to_bits();
    // x = m · 2^e with m in [0.5, 1).
    let mut e = ((bits >> 23) & 0xff) as i32 - 126;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
    let small = m < SQRT_HALF;
    e -= i32::from(small);
    let m = if small { m + m - 1.0 } else { m - 1.0 };
    let e = e as f32;
    let z = m * m;
    let mut y = 7.037_683_6e-2;
    y = y * m - 1.151_461e-1;
    y = y * m + 1.167_699_9e-1;
    y = y * m - 1.242_014_1e-1;
    y = y * m + 1.424_932_3e-1;
    y = y * m - 1.666_805_8e-1;
    y = y * m + 2.000_071_5e-1;
    y = y * m - 2.499_999_4e-1;
    y = y * m + 3.333_333_1e-1;
    y *= m * z;
    y += -2.121_944_4e-4 * e;
    y += -0.5 * z;
    m + y + 0.693_359_4 * e
}

/// Lower clamp of `r²` in the f32 thin-plate kernel: keeps [`fast_ln`] in its
/// normal range; `½ r² ln r²` is below 1e-28 there, i.e. zero for all purposes.
pub(crate) const TINY_R2: f32 = 1e-30;

/// `φ` of `kernel` as a function of `r²`, in f32, vectorizable.
#[inline(always)]
pub(crate) fn eval_r2_f32(kernel: Kernel, r2: f32) -> f32 {
    match kernel {
        Kernel::ThinPlate => {
            let r2 = r2.max(TINY_R2);
            0.5 * r2 * fast_ln(r2)
        }
        Kernel::Cubic => r2 * r2.sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_f64_is_accurate_to_round_off() {
        let mut worst = 0.0f64;
        let mut x = 1e-300f64;
        while x < 1e300 {
            let r = std::f64::consts::SQRT_2;
            for y in
                [x, x * r * (1.0 - 1e-15), x * r * (1.0 + 1e-15), x * 0.999_999_9, x * 1.000_000_1, x * 1.7]
            {
                let (got, want) = (ln_f64(y), y.ln());
                worst = worst.max((got - want).abs() / want.abs().max(1.0));
            }
            x *= 1.37;
        }
        assert!(worst < 4.0 * f64::EPSILON, "worst relative error {worst:e}");
        for v in [0.5, 1.0, 2.0, 0.1, 1e-12] {
            let mut r2 = [v, 0.0];
            Kernel::ThinPlate.eval_r2_in_place(&mut r2);
            assert!((r2[0] - Kernel::ThinPlate.eval_r2(v)).abs() <= 2.0 * f64::EPSILON * r2[0].abs());
            assert_eq!(r2[1], 0.0);
        }
    }

    #[test]
    fn fast_ln_matches_std() {
        let mut worst = 0.0f64;
        let mut x = 1e-30f32;
        while x < 1e30 {
            for f in [1.0f32, 1.37, 2.0 - 1e-6, SQRT_HALF, SQRT_HALF + 1e-7] {
                let v = x * f;
                let got = f64::from(fast_ln(v));
                let want = f64::from(v).ln();
                let err = (got - want).abs() / want.abs().max(1.0);
                worst = worst.max(err);
            }
            x *= 1.9;
        }
        assert!(worst < 3e-7, "worst relative error {worst:e}");
        assert_eq!(fast_ln(1.0), 0.0);
    }

    #[test]
    fn kernels_f32_match_f64() {
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            for r2 in [0.0f32, 1e-12, 1e-4, 0.3, 1.0, 2.5, 100.0] {
                let a = f64::from(eval_r2_f32(kernel, r2));
                let b = kernel.eval_r2(f64::from(r2));
                assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-6), "{kernel:?} r2={r2}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn gradient_factor_matches_difference() {
        for kernel in [Kernel::ThinPlate, Kernel::Cubic] {
            let r = 0.7f64;
            let h = 1e-6;
            let d = (kernel.eval_r2((r + h) * (r + h)) - kernel.eval_r2((r - h) * (r - h))) / (2.0 * h);
            assert!((d / r - kernel.gradient_factor_r2(r * r)).abs() < 1e-6);
        }
        assert_eq!(Kernel::from_name("r3"), Some(Kernel::Cubic));
        assert_eq!(Kernel::from_name(Kernel::ThinPlate.name()), Some(Kernel::ThinPlate));
        assert_eq!(Kernel::from_name("gauss"), None);
    }
}
