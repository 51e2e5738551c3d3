//! The T-spline level-set function `f(x) = Σ c_i B_i(x) / Σ B_i(x)` (paper
//! eq. 1) over a fixed [`TMesh`], as a [`Field3`].

use crate::basis::{Eval, LocalBasis, blend};
use crate::error::TsplineError;
use crate::tmesh::TMesh;
use glam::{DVec3, Vec3};
use isomorph_common::{Aabb, Field3};
use std::cell::RefCell;
use std::sync::Arc;

thread_local! {
    static SCRATCH: RefCell<LocalBasis> = RefCell::new(LocalBasis::default());
}

/// A trivariate cubic T-spline function on the domain `D = [−1, 1]³`: the
/// shared [`TMesh`] plus one coefficient per anchor. Cheap to clone (the mesh
/// is shared).
///
/// As a [`Field3`] it is evaluated in domain coordinates; outside `D` it is
/// continued by `f(q) − |p − q|` with `q` the nearest domain point, so it
/// stays continuous and becomes negative (outside) far away.
#[derive(Debug, Clone)]
pub struct TSpline {
    mesh: Arc<TMesh>,
    coeffs: Arc<Vec<f64>>,
}

impl TSpline {
    /// The function with `coeffs` (one per anchor of `mesh`).
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) when the lengths differ,
    /// [`TsplineError::NonFinite`] for NaN or infinite coefficients.
    pub fn new(mesh: Arc<TMesh>, coeffs: Vec<f64>) -> Result<Self, TsplineError> {
        if coeffs.len() != mesh.anchor_count() {
            return Err(isomorph_common::MorphError::bad_setting(
                "coefficients",
                coeffs.len(),
                "one coefficient per anchor",
            )
            .into());
        }
        if coeffs.iter().any(|c| !c.is_finite()) {
            return Err(TsplineError::NonFinite("coefficients"));
        }
        Ok(Self { mesh, coeffs: Arc::new(coeffs) })
    }

    /// The constant function `c` (every coefficient `c`).
    pub fn constant(mesh: Arc<TMesh>, c: f64) -> Self {
        let n = mesh.anchor_count();
        Self { mesh, coeffs: Arc::new(vec![c; n]) }
    }

    /// The shared T-mesh.
    pub fn mesh(&self) -> &Arc<TMesh> {
        &self.mesh
    }

    /// The coefficients, in anchor order.
    pub fn coefficients(&self) -> &[f64] {
        &self.coeffs
    }

    /// Value, gradient and Hessian at a point of the domain (points outside
    /// are clamped into it), from the blending functions of the leaf only.
    pub fn eval(&self, p: DVec3) -> Eval {
        let p = p.clamp(DVec3::splat(-1.0), DVec3::ONE);
        SCRATCH.with(|s| {
            let mut s = s.borrow_mut();
            s.at_with_hessians(&self.mesh, p);
            s.combine(&self.mesh, &self.coeffs)
        })
    }

    /// Value and gradient alone at a point of the domain (clamped).
    pub(crate) fn value_gradient(&self, p: DVec3) -> (f64, DVec3) {
        let p = p.clamp(DVec3::splat(-1.0), DVec3::ONE);
        SCRATCH.with(|s| {
            let mut s = s.borrow_mut();
            s.at(&self.mesh, p);
            s.value_gradient(&self.mesh, &self.coeffs)
        })
    }

    /// The value at a point of the domain (clamped), without derivatives.
    pub fn value_at(&self, p: DVec3) -> f64 {
        let p = p.clamp(DVec3::splat(-1.0), DVec3::ONE);
        SCRATCH.with(|s| s.borrow_mut().value(&self.mesh, &self.coeffs, p))
    }

    /// Reference evaluation: the sums over **all** anchors (O(n) per point),
    /// for the tests that check [`TSpline::eval`].
    #[cfg(test)]
    fn eval_brute_force(&self, p: DVec3) -> Eval {
        let p = p.clamp(DVec3::splat(-1.0), DVec3::ONE);
        let (mut n, mut dn, mut hn) = (0.0, DVec3::ZERO, [0.0; 6]);
        let (mut d, mut dd, mut hd) = (0.0, DVec3::ZERO, [0.0; 6]);
        for (a, &c) in self.mesh.anchors().iter().zip(self.coeffs.iter()) {
            let (b, g, h) = blend(a, p);
            n += c * b;
            dn += c * g;
            d += b;
            dd += g;
            for k in 0..6 {
                hn[k] += c * h[k];
                hd[k] += h[k];
            }
        }
        if d <= 0.0 {
            return Eval::default();
        }
        crate::basis::rational_derivatives(n, dn, &hn, d, dd, &hd)
    }

    /// `Σ B_i(p)` over all anchors (the normalization denominator; > 0 on `D`).
    pub fn denominator(&self, p: DVec3) -> f64 {
        self.mesh.anchors().iter().map(|a| blend(a, p).0).sum()
    }

    /// A copy with other coefficients on the same mesh.
    ///
    /// # Errors
    /// As [`TSpline::new`].
    pub fn with_coefficients(&self, coeffs: Vec<f64>) -> Result<Self, TsplineError> {
        Self::new(self.mesh.clone(), coeffs)
    }
}

fn clamp_outside(p: Vec3) -> (DVec3, f64) {
    let p = p.as_dvec3();
    let q = p.clamp(DVec3::splat(-1.0), DVec3::ONE);
    (q, (p - q).length())
}

impl Field3 for TSpline {
    fn value(&self, p: Vec3) -> f32 {
        let (q, out) = clamp_outside(p);
        (self.value_at(q) - out) as f32
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        let (q, out) = clamp_outside(p);
        let g = self.eval(q).gradient;
        if out > 0.0 { (g + (q - p.as_dvec3()) / out).as_vec3() } else { g.as_vec3() }
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(Aabb::cube(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tmesh::TMeshSettings;

    /// An adapted, unbalanced-looking (but balanced) mesh with hanging anchors.
    fn adapted() -> Arc<TMesh> {
        let pts = crate::demo::sphere_samples(3000, 0.45, DVec3::new(0.1, -0.05, 0.02));
        let s = TMeshSettings { max_depth: 5, min_depth: 1, ..Default::default() };
        Arc::new(TMesh::build(&pts, &s).unwrap())
    }

    fn pseudo_random(i: usize) -> f64 {
        ((i as f64 * 12.9898).sin() * 43758.5453).fract().abs()
    }

    fn random_spline(mesh: Arc<TMesh>) -> TSpline {
        let c = (0..mesh.anchor_count()).map(|i| pseudo_random(i) * 2.0 - 1.0).collect();
        TSpline::new(mesh, c).unwrap()
    }

    fn random_points(n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                DVec3::new(pseudo_random(3 * i + 1), pseudo_random(3 * i + 2), pseudo_random(3 * i + 3)) * 2.0
                    - DVec3::ONE
            })
            .collect()
    }

    #[test]
    fn uniform_interior_is_a_partition_of_unity_before_normalization() {
        let m = Arc::new(TMesh::uniform(3).unwrap());
        let f = TSpline::constant(m, 1.0);
        // Interior points: at least two cells (of 0.25) from the border,
        // where the outer anchors are missing and D < 1.
        for p in random_points(50).into_iter().map(|p| p * 0.5) {
            assert!((f.denominator(p) - 1.0).abs() < 1e-12, "D({p}) = {}", f.denominator(p));
        }
    }

    #[test]
    fn normalized_basis_is_a_partition_of_unity() {
        let m = adapted();
        assert!(m.mean_support() > 64.0, "the mesh is refined: {}", m.mean_support());
        let f = TSpline::constant(m.clone(), 7.0);
        let mut local = LocalBasis::default();
        let (mut r, mut dr) = (Vec::new(), Vec::new());
        let (mut dmin, mut dmax) = (f64::MAX, 0.0f64);
        for p in random_points(300) {
            let e = f.eval(p);
            assert!((e.value - 7.0).abs() < 1e-12 && e.gradient.length() < 1e-10, "{e:?}");
            local.at(&m, p);
            assert!(local.rational(&mut r, &mut dr));
            assert!((r.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(dr.iter().sum::<DVec3>().length() < 1e-10);
            let d = f.denominator(p);
            dmin = dmin.min(d);
            dmax = dmax.max(d);
        }
        // On a T-mesh the sum of blending functions is not 1: the
        // normalization of eq. 1 matters.
        assert!(dmin > 0.0 && dmax > dmin, "D in [{dmin}, {dmax}]");
    }

    #[test]
    fn leaf_lookup_agrees_with_the_sum_over_all_anchors() {
        let f = random_spline(adapted());
        for p in random_points(300).into_iter().chain([DVec3::ONE, -DVec3::ONE, DVec3::new(1.0, 0.0, -1.0)]) {
            let (a, b) = (f.eval(p), f.eval_brute_force(p));
            assert!((a.value - b.value).abs() < 1e-12, "{p}: {} vs {}", a.value, b.value);
            assert!((a.gradient - b.gradient).length() < 1e-9);
            assert!((a.hessian - b.hessian).abs_diff_eq(glam::DMat3::ZERO, 1e-7));
            assert!((f.value_at(p) - a.value).abs() < 1e-12);
            let (v, g) = f.value_gradient(p);
            assert!((v - a.value).abs() < 1e-12 && (g - a.gradient).length() < 1e-9);
        }
    }

    #[test]
    fn row_values_agree_with_the_sum_over_all_anchors() {
        // Rows along x through every leaf, including points on the leaf's
        // faces (closed leaves) and reuse of the sums along a row.
        let f = random_spline(adapted());
        let m = f.mesh().clone();
        let mut row = crate::basis::RowValues::default();
        for leaf in (0..m.leaf_count()).step_by(7) {
            let (lo, hi) = m.leaf_box(leaf);
            for (j, k) in [(0.0, 0.0), (0.3, 0.8), (1.0, 1.0)] {
                for i in 0..=4 {
                    let t = DVec3::new(f64::from(i) / 4.0, j, k);
                    let p = lo + t * (hi - lo);
                    let want = f.eval_brute_force(p).value;
                    let got = row.value(&m, f.coefficients(), leaf, p);
                    assert!((got - want).abs() < 1e-12, "leaf {leaf} at {p}: {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let f = random_spline(adapted());
        let e = 1e-6;
        for p in random_points(60) {
            let p = p * 0.95;
            let x = f.eval(p);
            for a in 0..3 {
                let mut d = DVec3::ZERO;
                d[a] = e;
                let (fp, fm) = (f.eval(p + d), f.eval(p - d));
                let g = (fp.value - fm.value) / (2.0 * e);
                assert!(
                    (g - x.gradient[a]).abs() < 1e-5 * (1.0 + g.abs()),
                    "grad {a} at {p}: {g} vs {}",
                    x.gradient[a]
                );
                let h = (fp.gradient - fm.gradient) / (2.0 * e);
                let col = x.hessian.col(a);
                assert!((h - col).length() < 1e-4 * (1.0 + h.length()), "hess {a} at {p}: {h} vs {col}");
            }
        }
    }

    #[test]
    fn second_derivatives_are_continuous_across_cell_faces() {
        let m = adapted();
        let f = random_spline(m.clone());
        let e = 1e-9;
        let mut checked = 0;
        for leaf in 0..m.leaf_count() {
            let (lo, hi) = m.leaf_box(leaf);
            if hi.x >= 1.0 {
                continue;
            }
            // A point on the +x face of the leaf, evaluated from both sides.
            let c = 0.5 * (lo + hi);
            let face = DVec3::new(hi.x, c.y + 0.13 * (hi.y - lo.y), c.z - 0.21 * (hi.z - lo.z));
            let (a, b) = (f.eval(face - DVec3::X * e), f.eval(face + DVec3::X * e));
            assert!((a.value - b.value).abs() < 1e-7);
            assert!(
                (a.gradient - b.gradient).length() < 1e-5,
                "leaf {leaf} {:?} at {face}: {} vs {} (leaves {} {})",
                m.leaf_box(leaf),
                a.gradient,
                b.gradient,
                m.locate(face - DVec3::X * e),
                m.locate(face + DVec3::X * e)
            );
            let jump = (a.hessian - b.hessian).to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let scale = a.hessian.to_cols_array().iter().fold(1.0f64, |m, v| m.max(v.abs()));
            assert!(jump < 1e-4 * scale, "leaf {leaf}: Hessian jump {jump} (scale {scale})");
            checked += 1;
        }
        assert!(checked > 50);
    }

    #[test]
    fn field_is_continued_outside_the_domain() {
        let f = TSpline::constant(adapted(), 0.5);
        assert!((f.value(Vec3::new(0.0, 0.0, 0.0)) - 0.5).abs() < 1e-6);
        assert!((f.value(Vec3::new(3.0, 0.0, 0.0)) + 1.5).abs() < 1e-6);
        assert_eq!(f.bounds(), Some(Aabb::cube(1.0)));
        assert!(TSpline::new(f.mesh().clone(), vec![0.0; 3]).is_err());
    }
}
