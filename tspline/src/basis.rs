//! The trivariate blending functions `B_i = N[ξ^i](x) N[η^i](y) N[ζ^i](z)`
//! (paper eq. 1) and their rational normalization `R_i = B_i / Σ_j B_j`
//! with first and second derivatives (note §2.2), evaluated only for the few
//! anchors whose support meets the leaf containing the point.

use crate::tmesh::{Anchor, TMesh};
use glam::{DMat3, DVec3};

/// A symmetric 3×3 matrix as `[xx, yy, zz, xy, xz, yz]`.
pub(crate) type Sym3 = [f64; 6];

/// Converts a [`Sym3`] to a full matrix.
pub(crate) fn sym_to_mat(s: &Sym3) -> DMat3 {
    DMat3::from_cols(DVec3::new(s[0], s[3], s[4]), DVec3::new(s[3], s[1], s[5]), DVec3::new(s[4], s[5], s[2]))
}

/// `B`, `∇B` and the Hessian of one anchor's blending function at `p`.
#[inline]
pub(crate) fn blend(anchor: &Anchor, p: DVec3) -> (f64, DVec3, Sym3) {
    let x = anchor.pieces[0].eval(p.x);
    if x == [0.0; 3] {
        return (0.0, DVec3::ZERO, [0.0; 6]);
    }
    product(x, anchor.pieces[1].eval(p.y), anchor.pieces[2].eval(p.z))
}

/// `B = N(x) N(y) N(z)` with its gradient and Hessian from the univariate
/// factors' values and first and second derivatives.
#[inline]
fn product([x0, x1, x2]: [f64; 3], [y0, y1, y2]: [f64; 3], [z0, z1, z2]: [f64; 3]) -> (f64, DVec3, Sym3) {
    let b = x0 * y0 * z0;
    let g = DVec3::new(x1 * y0 * z0, x0 * y1 * z0, x0 * y0 * z1);
    let h = [x2 * y0 * z0, x0 * y2 * z0, x0 * y0 * z2, x1 * y1 * z0, x1 * y0 * z1, x0 * y1 * z1];
    (b, g, h)
}

/// The non-zero blending functions at one point: the leaf, the anchors of
/// its list and their `B`, `∇B`, `H B`, plus the sums `D`, `∇D`, `H D`.
#[derive(Debug, Clone, Default)]
pub(crate) struct LocalBasis {
    /// Leaf containing the point.
    pub leaf: usize,
    /// Blending function values per local anchor.
    pub b: Vec<f64>,
    /// Gradients per local anchor.
    pub db: Vec<DVec3>,
    /// Hessians per local anchor.
    pub hb: Vec<Sym3>,
    /// `D = Σ B_i`.
    pub d: f64,
    /// `∇D`.
    pub dd: DVec3,
    /// `H D`.
    pub hd: Sym3,
    /// Per axis: the leaf's distinct univariate factors at the point.
    factors: [Vec<[f64; 3]>; 3],
}

impl LocalBasis {
    /// Evaluates the distinct univariate factors of the leaf containing `p`
    /// (value, first and second derivative) into `self.factors`.
    fn factors_at(&mut self, mesh: &TMesh, p: DVec3) {
        self.leaf = mesh.locate(p);
        let f = mesh.leaf_factors(self.leaf);
        for (axis, out) in self.factors.iter_mut().enumerate() {
            out.clear();
            out.extend(f.axes[axis].iter().map(|pc| pc.eval(p[axis])));
        }
    }

    /// Locates `p`, evaluates its leaf's factors and empties the sums.
    fn start(&mut self, mesh: &TMesh, p: DVec3) {
        self.factors_at(mesh, p);
        self.b.clear();
        self.db.clear();
        self.hb.clear();
        self.d = 0.0;
        self.dd = DVec3::ZERO;
        self.hd = [0.0; 6];
    }

    /// Evaluates every blending function of the leaf containing `p` with
    /// its gradient (`b`, `db`, `d`, `dd`; no Hessians).
    pub fn at(&mut self, mesh: &TMesh, p: DVec3) {
        self.start(mesh, p);
        let [fx, fy, fz] = &self.factors;
        for index in &mesh.leaf_factors(self.leaf).index {
            let ([x0, x1, _], [y0, y1, _], [z0, z1, _]) =
                (fx[index[0] as usize], fy[index[1] as usize], fz[index[2] as usize]);
            let b = x0 * y0 * z0;
            let g = DVec3::new(x1 * y0 * z0, x0 * y1 * z0, x0 * y0 * z1);
            self.b.push(b);
            self.db.push(g);
            self.d += b;
            self.dd += g;
        }
    }

    /// As [`Self::at`], plus the Hessians `hb` and `hd` that
    /// [`Self::combine`] needs.
    pub fn at_with_hessians(&mut self, mesh: &TMesh, p: DVec3) {
        self.start(mesh, p);
        let [fx, fy, fz] = &self.factors;
        for index in &mesh.leaf_factors(self.leaf).index {
            let (b, g, h) = product(fx[index[0] as usize], fy[index[1] as usize], fz[index[2] as usize]);
            self.b.push(b);
            self.db.push(g);
            self.hb.push(h);
            self.d += b;
            self.dd += g;
            for (acc, v) in self.hd.iter_mut().zip(h) {
                *acc += v;
            }
        }
    }

    /// `f(p) = Σ c_i B_i / Σ B_i` alone (no derivatives), from the leaf's
    /// distinct factors.
    pub fn value(&mut self, mesh: &TMesh, coeffs: &[f64], p: DVec3) -> f64 {
        self.factors_at(mesh, p);
        let [fx, fy, fz] = &self.factors;
        let list = mesh.leaf_anchors(self.leaf);
        let (mut n, mut d) = (0.0, 0.0);
        for (&i, index) in list.iter().zip(&mesh.leaf_factors(self.leaf).index) {
            let b = fx[index[0] as usize][0] * fy[index[1] as usize][0] * fz[index[2] as usize][0];
            n += coeffs[i as usize] * b;
            d += b;
        }
        if d > 0.0 { n / d } else { 0.0 }
    }

    /// The rational basis `R_i = B_i / D` and its gradients
    /// `∇R_i = (∇B_i − R_i ∇D) / D` into `r`, `dr` (local order). Returns
    /// false when `D = 0` (the point is outside every support).
    pub fn rational(&self, r: &mut Vec<f64>, dr: &mut Vec<DVec3>) -> bool {
        r.clear();
        dr.clear();
        if self.d <= 0.0 {
            return false;
        }
        let inv = 1.0 / self.d;
        for (b, g) in self.b.iter().zip(&self.db) {
            let ri = b * inv;
            r.push(ri);
            dr.push((*g - ri * self.dd) * inv);
        }
        true
    }

    /// Value and gradient of `f = Σ c_i B_i / D` (after [`Self::at`] or
    /// [`Self::at_with_hessians`]), `coeffs` by global anchor index.
    pub fn value_gradient(&self, mesh: &TMesh, coeffs: &[f64]) -> (f64, DVec3) {
        if self.d <= 0.0 {
            return (0.0, DVec3::ZERO);
        }
        let (mut n, mut dn) = (0.0, DVec3::ZERO);
        for ((&i, b), db) in mesh.leaf_anchors(self.leaf).iter().zip(&self.b).zip(&self.db) {
            let c = coeffs[i as usize];
            n += c * b;
            dn += c * *db;
        }
        let f = n / self.d;
        (f, (dn - f * self.dd) / self.d)
    }

    /// Value, gradient and Hessian of `f = Σ c_i B_i / D` (after
    /// [`Self::at_with_hessians`]), `coeffs` by global anchor index.
    pub fn combine(&self, mesh: &TMesh, coeffs: &[f64]) -> Eval {
        debug_assert_eq!(self.hb.len(), self.b.len(), "combine needs at_with_hessians");
        if self.d <= 0.0 {
            return Eval::default();
        }
        let list = mesh.leaf_anchors(self.leaf);
        let mut n = 0.0;
        let mut dn = DVec3::ZERO;
        let mut hn = [0.0; 6];
        for (k, &i) in list.iter().enumerate() {
            let c = coeffs[i as usize];
            n += c * self.b[k];
            dn += c * self.db[k];
            for (acc, v) in hn.iter_mut().zip(self.hb[k]) {
                *acc += c * v;
            }
        }
        rational_derivatives(n, dn, &hn, self.d, self.dd, &self.hd)
    }
}

/// Values of `f` along a lattice row parallel to x (fixed `y`, `z`) inside
/// one leaf: the anchors' `c_i N(y) N(z)` and `N(y) N(z)` are summed per
/// distinct x factor once per row and leaf, so a point costs one univariate
/// evaluation per distinct x factor (about four) instead of one product per
/// anchor (64 or more).
#[derive(Debug, Clone, Default)]
pub(crate) struct RowValues {
    /// The leaf and `(y, z)` the sums belong to.
    key: Option<(usize, f64, f64)>,
    /// `Σ c_i N(y) N(z)` per distinct x factor.
    num: Vec<f64>,
    /// `Σ N(y) N(z)` per distinct x factor.
    den: Vec<f64>,
    /// The leaf's distinct y and z factors at `(y, z)`.
    fy: Vec<f64>,
    fz: Vec<f64>,
}

impl RowValues {
    /// `f(p)` for `p` in `leaf` (as [`LocalBasis::value`], to round-off).
    pub fn value(&mut self, mesh: &TMesh, coeffs: &[f64], leaf: usize, p: DVec3) -> f64 {
        let factors = mesh.leaf_factors(leaf);
        if self.key != Some((leaf, p.y, p.z)) {
            self.key = Some((leaf, p.y, p.z));
            self.fy.clear();
            self.fy.extend(factors.axes[1].iter().map(|pc| pc.value(p.y)));
            self.fz.clear();
            self.fz.extend(factors.axes[2].iter().map(|pc| pc.value(p.z)));
            self.num.clear();
            self.num.resize(factors.axes[0].len(), 0.0);
            self.den.clear();
            self.den.resize(factors.axes[0].len(), 0.0);
            for (&i, index) in mesh.leaf_anchors(leaf).iter().zip(&factors.index) {
                let yz = self.fy[index[1] as usize] * self.fz[index[2] as usize];
                self.num[index[0] as usize] += coeffs[i as usize] * yz;
                self.den[index[0] as usize] += yz;
            }
        }
        let (mut n, mut d) = (0.0, 0.0);
        for ((pc, num), den) in factors.axes[0].iter().zip(&self.num).zip(&self.den) {
            let x = pc.value(p.x);
            n += x * num;
            d += x * den;
        }
        if d > 0.0 { n / d } else { 0.0 }
    }
}

/// Value, gradient and Hessian of `N / D` from those of `N` and `D` (note
/// §2.2): `∇f = (∇N − f ∇D)/D`, `H f = (H N − f H D − ∇f ∇Dᵀ − ∇D ∇fᵀ)/D`.
pub(crate) fn rational_derivatives(n: f64, dn: DVec3, hn: &Sym3, d: f64, dd: DVec3, hd: &Sym3) -> Eval {
    let f = n / d;
    let g = (dn - f * dd) / d;
    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let h: Sym3 = std::array::from_fn(|k| {
        let (a, b) = pairs[k];
        (hn[k] - f * hd[k] - g[a] * dd[b] - dd[a] * g[b]) / d
    });
    Eval { value: f, gradient: g, hessian: sym_to_mat(&h) }
}

/// Value, gradient and Hessian of a T-spline function at a point (domain
/// units, `f64`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Eval {
    /// `f(p)`.
    pub value: f64,
    /// `∇f(p)`; points into the shape (towards larger values).
    pub gradient: DVec3,
    /// The Hessian `H f(p)` (symmetric).
    pub hessian: DMat3,
}

impl Eval {
    /// Mean curvature of the level set through the point, `κ = div(∇f/|∇f|)/2
    /// = (|∇f|² tr H − ∇fᵀ H ∇f) / (2 |∇f|³)` (note §6). With the
    /// positive-inside convention it is **negative on convex parts** (for
    /// `f = r − |x|` it is `−1/r`), so that `ḟ = κ |∇f|` is mean-curvature
    /// flow (convex parts shrink). Zero where `∇f` vanishes.
    pub fn mean_curvature(&self) -> f64 {
        let g = self.gradient;
        let len2 = g.length_squared();
        if len2 <= 1e-24 {
            return 0.0;
        }
        let h = self.hessian;
        let trace = h.x_axis.x + h.y_axis.y + h.z_axis.z;
        (len2 * trace - g.dot(h * g)) / (2.0 * len2 * len2.sqrt())
    }
}
