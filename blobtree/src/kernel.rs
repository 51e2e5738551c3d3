//! The Blanc–Schlick field function (§2): piecewise rational in `r²`, with
//! maximum intensity `I`, radius of influence `R` and stiffness `k`.

use serde::{Deserialize, Serialize};

/// Field-function parameters of one skeletal primitive.
///
/// With `x = (d / R)²` the normalized squared distance,
///
/// ```text
/// g(x) = 1 − 9x² / (k + (9/2 − 4k) x)          0 ≤ x ≤ 1/4
/// g(x) = (1 − x)² / (3/4 − k + (3/2 + 4k) x)    1/4 ≤ x ≤ 1
/// g(x) = 0                                     x ≥ 1
/// f(d) = I · g((d / R)²)
/// ```
///
/// The pieces meet at `x = 1/4` with value 1/2 and equal slope `−2 − 16k/9`;
/// `g(0) = 1`, `g(1) = 0`, `g'(0) = g'(1) = 0` in `d`, and `g` decreases
/// monotonically for every `k ≥ 0` (denominators stay positive). Negative `k`
/// puts a pole in the first piece, so scenes reject it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kernel {
    /// Maximum intensity `I` (the value on the skeleton); `0` makes a phantom.
    pub intensity: f32,
    /// Radius of influence `R`: the field is exactly zero at distance ≥ `R`.
    pub radius: f32,
    /// Stiffness `k ≥ 0` of the Blanc–Schlick function.
    pub stiffness: f32,
}

impl Default for Kernel {
    /// `I = 1`, `R = 1`, `k = 1`.
    fn default() -> Self {
        Self { intensity: 1.0, radius: 1.0, stiffness: 1.0 }
    }
}

impl Kernel {
    /// A kernel with the given intensity, radius and stiffness.
    pub fn new(intensity: f32, radius: f32, stiffness: f32) -> Self {
        Self { intensity, radius, stiffness }
    }

    /// The field value at distance `d ≥ 0` from the skeleton.
    #[inline]
    pub fn value(&self, d: f32) -> f32 {
        let x = (d / self.radius) * (d / self.radius);
        self.intensity * profile(x, self.stiffness).0
    }

    /// The field value and its derivative with respect to `d`.
    #[inline]
    pub fn value_derivative(&self, d: f32) -> (f32, f32) {
        let r = d / self.radius;
        let (g, dg_dx) = profile(r * r, self.stiffness);
        // dx/dd = 2 r / R.
        (self.intensity * g, self.intensity * dg_dx * 2.0 * r / self.radius)
    }

    /// The distance at which an isolated primitive's field equals `level`
    /// (`None` when `level ≥ I` or `level ≤ 0`: no such distance inside the
    /// support). Solved by bisection on the monotone profile.
    pub fn iso_distance(&self, level: f32) -> Option<f32> {
        if !(level > 0.0 && level < self.intensity) {
            return None;
        }
        let (mut lo, mut hi) = (0.0f32, self.radius);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.value(mid) > level {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }

    /// Linear interpolation of the parameters (the field-function *class*
    /// interpolation of §3.4.2).
    pub fn lerp(&self, other: &Kernel, s: f32) -> Kernel {
        Kernel {
            intensity: self.intensity + (other.intensity - self.intensity) * s,
            radius: self.radius + (other.radius - self.radius) * s,
            stiffness: self.stiffness + (other.stiffness - self.stiffness) * s,
        }
    }
}

/// The normalized profile `g(x)` and `dg/dx` for `x = (d/R)²`.
#[inline]
fn profile(x: f32, k: f32) -> (f32, f32) {
    if x >= 1.0 {
        (0.0, 0.0)
    } else if x <= 0.25 {
        if x <= 0.0 {
            return (1.0, 0.0);
        }
        let den = k + (4.5 - 4.0 * k) * x;
        let g = 1.0 - 9.0 * x * x / den;
        // d/dx [9x²/den] = 9x (2 den − x (9/2 − 4k)) / den² = 9x (2k + (9/2 − 4k) x) / den².
        let dg = -9.0 * x * (2.0 * k + (4.5 - 4.0 * k) * x) / (den * den);
        (g, dg)
    } else {
        let a = 0.75 - k;
        let c = 1.5 + 4.0 * k;
        let den = a + c * x;
        let u = 1.0 - x;
        let g = u * u / den;
        let dg = -u * (2.0 * den + c * u) / (den * den);
        (g, dg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's printed formula, written out independently in f64.
    fn closed_form(r: f64, k: f64) -> f64 {
        let r2 = r * r;
        if r2 <= 0.25 {
            if r2 == 0.0 { 1.0 } else { 1.0 - 9.0 * r2 * r2 / (k + (4.5 - 4.0 * k) * r2) }
        } else if r2 <= 1.0 {
            (1.0 - r2).powi(2) / (0.75 - k + (1.5 + 4.0 * k) * r2)
        } else {
            0.0
        }
    }

    #[test]
    fn matches_the_printed_formula_and_its_properties() {
        for &k in &[0.0f32, 0.25, 1.0, 3.0] {
            let kern = Kernel::new(2.0, 1.5, k);
            assert_eq!(kern.value(0.0), 2.0);
            assert_eq!(kern.value(1.5), 0.0);
            assert_eq!(kern.value(7.0), 0.0);
            // Pieces meet at r² = 1/4 with value I/2.
            assert!((kern.value(0.75) - 1.0).abs() < 1e-6, "{}", kern.value(0.75));
            let mut prev = f32::INFINITY;
            for i in 0..=300 {
                let d = 1.6 * i as f32 / 300.0;
                let v = kern.value(d);
                let expect = 2.0 * closed_form(d as f64 / 1.5, k as f64);
                assert!((v as f64 - expect).abs() < 1e-5, "k={k} d={d}: {v} vs {expect}");
                assert!(v <= prev + 1e-7, "not monotone at d={d}");
                prev = v;
                // Analytic derivative vs central differences.
                let h = 1e-3;
                if d > h {
                    let fd = (kern.value(d + h) - kern.value(d - h)) / (2.0 * h);
                    let (_, an) = kern.value_derivative(d);
                    assert!((fd - an).abs() < 2e-3 * (1.0 + an.abs()), "k={k} d={d}: {an} vs {fd}");
                }
            }
            assert_eq!(kern.value_derivative(0.0).1, 0.0);
            assert!(kern.value_derivative(1.5 - 1e-4).1.abs() < 1e-3);
        }
    }

    #[test]
    fn iso_distance_inverts_the_kernel() {
        let kern = Kernel::new(1.0, 2.0, 0.5);
        let r = kern.iso_distance(0.5).unwrap();
        assert!((r - 1.0).abs() < 1e-4, "the midpoint r² = 1/4 gives d = R/2, got {r}");
        let r = kern.iso_distance(0.2).unwrap();
        assert!((kern.value(r) - 0.2).abs() < 1e-5);
        assert!(kern.iso_distance(1.0).is_none());
    }
}
