//! Warps (§2): Barr's twist, taper and bend, and affine maps, evaluated as
//! `f ∘ w⁻¹` with analytic inverses.

use glam::{Affine3A, Mat3, Vec3};
use isomorph_common::Aabb;

/// Smallest taper scale: `r(z) = max(1 + slope·z, TAPER_MIN_SCALE)` keeps the
/// taper invertible everywhere.
pub const TAPER_MIN_SCALE: f32 = 0.05;

/// A space warp.
///
/// Twist and taper act about the local z axis, the bend in the y–z plane
/// (Barr 1984); put the warp under an affine node to choose other axes.
/// Every warp has an *identity* parameter (rate 0, slope 0, affine identity)
/// used when a warp is matched with a node of another kind (§4.3, Fig. 15).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Warp {
    /// Twist about z: a point at height `z` turns by `rate · z` radians.
    Twist {
        /// Radians per unit length.
        rate: f32,
    },
    /// Taper along z: `x, y` scale by `r(z) = max(1 + slope·z, 0.05)`.
    Taper {
        /// Scale change per unit length.
        slope: f32,
    },
    /// Barr's bend in the y–z plane: the band `y ∈ [min, max]` bends around
    /// the axis at `z = 1/rate` with angle `rate · (y − centre)`; beyond the
    /// band the shape is carried rigidly. Requires `|rate|·(max − min) ≤ π`.
    /// The inverse is exact for points whose pre-image lies on the near side
    /// of the bend axis (`z < 1/rate`); keep the warped subtree there, as Barr does.
    Bend {
        /// Curvature (radians per unit length); negative bends towards −z.
        rate: f32,
        /// `y0`: the undeformed line of the bend.
        centre: f32,
        /// Lower end of the bent band.
        min: f32,
        /// Upper end of the bent band.
        max: f32,
    },
    /// An affine map (local → world), invertible and orientation preserving.
    Affine(Affine3A),
}

impl Warp {
    /// The warp's kind name (`"twist"`, `"taper"`, `"bend"`, `"affine"`).
    pub fn kind(&self) -> &'static str {
        match self {
            Warp::Twist { .. } => "twist",
            Warp::Taper { .. } => "taper",
            Warp::Bend { .. } => "bend",
            Warp::Affine(_) => "affine",
        }
    }

    /// The identity warp of the same kind (Fig. 15's inserted operator).
    pub fn identity_like(&self) -> Warp {
        match *self {
            Warp::Twist { .. } => Warp::Twist { rate: 0.0 },
            Warp::Taper { .. } => Warp::Taper { slope: 0.0 },
            Warp::Bend { centre, min, max, .. } => Warp::Bend { rate: 0.0, centre, min, max },
            Warp::Affine(_) => Warp::Affine(Affine3A::IDENTITY),
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// A [`crate::NodeProblem`] for non-finite values, a bend band with
    /// `min > max` or more than half a turn, or a singular/mirrored affine map.
    pub fn validate(&self) -> Result<(), crate::NodeProblem> {
        use crate::NodeProblem as P;
        use crate::node::check_magnitude;
        match *self {
            Warp::Twist { rate } if !rate.is_finite() => Err(P::NotFinite("rate")),
            Warp::Twist { rate } => check_magnitude("rate", &[rate]),
            Warp::Taper { slope } if !slope.is_finite() => Err(P::NotFinite("slope")),
            Warp::Taper { slope } => check_magnitude("slope", &[slope]),
            Warp::Bend { rate, centre, min, max } => {
                if ![rate, centre, min, max].iter().all(|v| v.is_finite()) {
                    Err(P::NotFinite("bend"))
                } else if min > max {
                    Err(P::Warp("bend band min > max"))
                } else if rate.abs() * (max - min) > std::f32::consts::PI + 1e-6 {
                    Err(P::Warp("bend angle |rate|·(max − min) exceeds π"))
                } else {
                    check_magnitude("rate", &[rate])?;
                    check_magnitude("centre", &[centre])?;
                    check_magnitude("min", &[min])?;
                    check_magnitude("max", &[max])
                }
            }
            Warp::Affine(m) => {
                isomorph_common::AffineParts::from_affine(&m).map_err(P::Transform)?;
                check_magnitude("frame", &m.to_cols_array())
            }
        }
    }

    /// The forward map `w(p)`.
    pub fn forward(&self, p: Vec3) -> Vec3 {
        match *self {
            Warp::Twist { rate } => {
                let (s, c) = (rate * p.z).sin_cos();
                Vec3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z)
            }
            Warp::Taper { slope } => {
                let r = taper_scale(slope, p.z);
                Vec3::new(r * p.x, r * p.y, p.z)
            }
            Warp::Bend { rate, centre, min, max } => {
                if rate.abs() < BEND_EPS {
                    return p;
                }
                if rate < 0.0 {
                    let q = bend_forward(-rate, centre, min, max, p * FLIP_Z);
                    return q * FLIP_Z;
                }
                bend_forward(rate, centre, min, max, p)
            }
            Warp::Affine(m) => m.transform_point3(p),
        }
    }

    /// The inverse map `w⁻¹(p)`.
    pub fn inverse(&self, p: Vec3) -> Vec3 {
        match *self {
            Warp::Twist { rate } => {
                let (s, c) = (rate * p.z).sin_cos();
                Vec3::new(c * p.x + s * p.y, -s * p.x + c * p.y, p.z)
            }
            Warp::Taper { slope } => {
                let r = taper_scale(slope, p.z);
                Vec3::new(p.x / r, p.y / r, p.z)
            }
            Warp::Bend { rate, centre, min, max } => {
                if rate.abs() < BEND_EPS {
                    return p;
                }
                if rate < 0.0 {
                    return bend_inverse(-rate, centre, min, max, p * FLIP_Z) * FLIP_Z;
                }
                bend_inverse(rate, centre, min, max, p)
            }
            Warp::Affine(m) => m.inverse().transform_point3(p),
        }
    }

    /// The inverse point and the transposed Jacobian of `w⁻¹` at `p`
    /// (maps a child gradient to the warped field's gradient). Analytic for
    /// twist, taper and affine; central differences (step 1e-4) for the bend.
    pub fn inverse_with_jacobian_t(&self, p: Vec3) -> (Vec3, Mat3) {
        match *self {
            Warp::Twist { rate } => {
                let (s, c) = (rate * p.z).sin_cos();
                let q = Vec3::new(c * p.x + s * p.y, -s * p.x + c * p.y, p.z);
                // Rows of J: ∂q/∂(X,Y,Z).
                let j = Mat3::from_cols(
                    Vec3::new(c, -s, 0.0),
                    Vec3::new(s, c, 0.0),
                    Vec3::new(rate * (-p.x * s + p.y * c), rate * (-p.x * c - p.y * s), 1.0),
                );
                (q, j.transpose())
            }
            Warp::Taper { slope } => {
                let r = taper_scale(slope, p.z);
                let dr = if 1.0 + slope * p.z > TAPER_MIN_SCALE { slope } else { 0.0 };
                let q = Vec3::new(p.x / r, p.y / r, p.z);
                let j = Mat3::from_cols(
                    Vec3::new(1.0 / r, 0.0, 0.0),
                    Vec3::new(0.0, 1.0 / r, 0.0),
                    Vec3::new(-p.x * dr / (r * r), -p.y * dr / (r * r), 1.0),
                );
                (q, j.transpose())
            }
            Warp::Affine(m) => {
                let inv = m.inverse();
                (inv.transform_point3(p), Mat3::from(inv.matrix3).transpose())
            }
            Warp::Bend { .. } => {
                let h = 1e-4;
                let col = |e: Vec3| (self.inverse(p + e * h) - self.inverse(p - e * h)) / (2.0 * h);
                let j = Mat3::from_cols(col(Vec3::X), col(Vec3::Y), col(Vec3::Z));
                (self.inverse(p), j.transpose())
            }
        }
    }

    /// A box containing `w⁻¹(region)` (every point the warped field reads
    /// its child at for a point of `region`), or `None` where no cheap bound
    /// is known (the bend).
    pub(crate) fn preimage_bounds(&self, region: &Aabb) -> Option<Aabb> {
        if region.is_empty() {
            return Some(*region);
        }
        match *self {
            // The inverse turns about z too: the same disc holds it.
            Warp::Twist { .. } => Some(self.image_bounds(region)),
            Warp::Taper { slope } => {
                let r0 = taper_scale(slope, region.min.z);
                let r1 = taper_scale(slope, region.max.z);
                // `r` is monotone in z, so over the box it lies in [r0, r1] (either order).
                let inv_max = 1.0 / r0.min(r1);
                let a = region.min.abs().max(region.max.abs()) * inv_max;
                Some(Aabb::new(Vec3::new(-a.x, -a.y, region.min.z), Vec3::new(a.x, a.y, region.max.z)))
            }
            Warp::Bend { .. } => None,
            Warp::Affine(m) => Some(region.transformed(&m.inverse())),
        }
    }

    /// A box containing the image under `w` of everything in `child`.
    pub fn image_bounds(&self, child: &Aabb) -> Aabb {
        if child.is_empty() {
            return *child;
        }
        match *self {
            Warp::Twist { .. } => {
                let rho = child.corners().iter().map(|c| c.truncate().length()).fold(0.0f32, f32::max);
                Aabb::new(Vec3::new(-rho, -rho, child.min.z), Vec3::new(rho, rho, child.max.z))
            }
            Warp::Taper { slope } => {
                let r0 = taper_scale(slope, child.min.z);
                let r1 = taper_scale(slope, child.max.z);
                let (lo, hi) = (r0.min(r1), r0.max(r1));
                let range = |a: f32, b: f32| {
                    let c = [lo * a, lo * b, hi * a, hi * b];
                    (
                        c.iter().copied().fold(f32::INFINITY, f32::min),
                        c.iter().copied().fold(f32::NEG_INFINITY, f32::max),
                    )
                };
                let (x0, x1) = range(child.min.x, child.max.x);
                let (y0, y1) = range(child.min.y, child.max.y);
                Aabb::new(Vec3::new(x0, y0, child.min.z), Vec3::new(x1, y1, child.max.z))
            }
            Warp::Bend { rate, centre, min, max } => {
                if rate.abs() < BEND_EPS {
                    return *child;
                }
                // Every image point is a rotation about the bend axis
                // (y0, 1/k) of the child point shifted in y by −(ŷ − y0),
                // so it lies within the disc through the farthest shifted corner.
                let axis_z = 1.0 / rate;
                let shifts = [-(max - centre), -(min - centre)];
                let mut rad2 = 0.0f32;
                for c in child.corners() {
                    for s in shifts {
                        let dy = c.y + s - centre;
                        let dz = c.z - axis_z;
                        rad2 = rad2.max(dy * dy + dz * dz);
                    }
                }
                let r = rad2.sqrt() * (1.0 + 1e-5) + 1e-6;
                let disc = Aabb::new(
                    Vec3::new(child.min.x, centre - r, axis_z - r),
                    Vec3::new(child.max.x, centre + r, axis_z + r),
                );
                // The disc grows like 1/rate as the bend straightens; the
                // swept bound has no such blow-up. Both hold the image.
                let p = crate::sweep::Interval::point;
                disc.intersection(&crate::sweep::bend_image(p(rate), p(centre), p(min), p(max), child))
            }
            Warp::Affine(m) => child.transformed(&m),
        }
    }

    /// Parameter interpolation between two warps of the same kind (§4.4):
    /// rates, slopes and bend bands linearly, affine maps as translation ·
    /// rotation (quaternion slerp) · stretch. `None` if the kinds differ or an
    /// affine map cannot be decomposed.
    pub fn lerp(&self, other: &Warp, s: f32) -> Option<Warp> {
        let l = |a: f32, b: f32| a + (b - a) * s;
        Some(match (*self, *other) {
            (Warp::Twist { rate: a }, Warp::Twist { rate: b }) => Warp::Twist { rate: l(a, b) },
            (Warp::Taper { slope: a }, Warp::Taper { slope: b }) => Warp::Taper { slope: l(a, b) },
            (
                Warp::Bend { rate: a, centre: c0, min: m0, max: x0 },
                Warp::Bend { rate: b, centre: c1, min: m1, max: x1 },
            ) => Warp::Bend { rate: l(a, b), centre: l(c0, c1), min: l(m0, m1), max: l(x0, x1) },
            (Warp::Affine(a), Warp::Affine(b)) => {
                if s == 0.0 {
                    return Some(Warp::Affine(a));
                }
                if s == 1.0 {
                    return Some(Warp::Affine(b));
                }
                let pa = isomorph_common::AffineParts::from_affine(&a).ok()?;
                let pb = isomorph_common::AffineParts::from_affine(&b).ok()?;
                Warp::Affine(pa.lerp(&pb, s).to_affine())
            }
            _ => return None,
        })
    }
}

const BEND_EPS: f32 = 1e-8;
const FLIP_Z: Vec3 = Vec3::new(1.0, 1.0, -1.0);

fn taper_scale(slope: f32, z: f32) -> f32 {
    (1.0 + slope * z).max(TAPER_MIN_SCALE)
}

fn bend_forward(k: f32, y0: f32, ymin: f32, ymax: f32, p: Vec3) -> Vec3 {
    let yh = p.y.clamp(ymin, ymax);
    let theta = k * (yh - y0);
    let (s, c) = theta.sin_cos();
    let inv_k = 1.0 / k;
    Vec3::new(p.x, -s * (p.z - inv_k) + y0 + c * (p.y - yh), c * (p.z - inv_k) + inv_k + s * (p.y - yh))
}

fn bend_inverse(k: f32, y0: f32, ymin: f32, ymax: f32, q: Vec3) -> Vec3 {
    use std::f32::consts::PI;
    let inv_k = 1.0 / k;
    let (tmin, tmax) = (k * (ymin - y0), k * (ymax - y0));
    let tmid = 0.5 * (tmin + tmax);
    let mut phi = (q.y - y0).atan2(inv_k - q.z);
    // Unwrap around the band's middle angle.
    let mut d = phi - tmid;
    d -= (2.0 * PI) * ((d + PI) / (2.0 * PI)).floor();
    phi = tmid + d;
    if (tmin..=tmax).contains(&phi) {
        let y = y0 + phi * inv_k;
        let z = inv_k - ((q.y - y0).powi(2) + (inv_k - q.z).powi(2)).sqrt();
        Vec3::new(q.x, y, z)
    } else {
        let (theta, yh) = if phi > tmax { (tmax, ymax) } else { (tmin, ymin) };
        let (s, c) = theta.sin_cos();
        let y = yh + s * (q.z - inv_k) + c * (q.y - y0);
        let z = inv_k + c * (q.z - inv_k) - s * (q.y - y0);
        Vec3::new(q.x, y, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn warps() -> Vec<Warp> {
        vec![
            Warp::Twist { rate: 1.3 },
            Warp::Taper { slope: 0.4 },
            Warp::Bend { rate: 0.8, centre: 0.1, min: -0.6, max: 0.9 },
            Warp::Bend { rate: -0.5, centre: 0.0, min: -1.0, max: 1.0 },
            Warp::Affine(Affine3A::from_scale_rotation_translation(
                Vec3::new(1.5, 0.7, 1.0),
                Quat::from_rotation_y(0.4),
                Vec3::new(0.2, -0.1, 0.3),
            )),
        ]
    }

    fn sample_points() -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..7 {
            for j in 0..7 {
                for k in 0..7 {
                    v.push(Vec3::new(i as f32 - 3.0, j as f32 - 3.0, k as f32 - 3.0) * 0.25);
                }
            }
        }
        v
    }

    #[test]
    fn inverse_undoes_forward() {
        for w in warps() {
            for p in sample_points() {
                let back = w.inverse(w.forward(p));
                assert!((back - p).length() < 2e-4, "{w:?} at {p}: {back}");
            }
        }
    }

    #[test]
    fn identity_parameters_give_identity() {
        for w in warps() {
            let id = w.identity_like();
            for p in sample_points() {
                assert!((id.inverse(p) - p).length() < 1e-6, "{id:?}");
                assert!((id.forward(p) - p).length() < 1e-6, "{id:?}");
            }
        }
    }

    #[test]
    fn jacobians_match_differences() {
        for w in warps() {
            for p in sample_points().into_iter().step_by(17) {
                let (_, jt) = w.inverse_with_jacobian_t(p);
                let h = 1e-3;
                for (axis, e) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
                    let fd = (w.inverse(p + e * h) - w.inverse(p - e * h)) / (2.0 * h);
                    // Column `axis` of J is row `axis` of Jᵀ.
                    let row = jt.row(axis);
                    assert!((row - fd).length() < 5e-3, "{w:?} at {p}: {row} vs {fd}");
                }
            }
        }
    }

    #[test]
    fn image_bounds_contain_warped_samples() {
        let child = Aabb::new(Vec3::new(-0.5, -0.7, -0.4), Vec3::new(0.6, 0.8, 0.5));
        for w in warps() {
            let b = w.image_bounds(&child).expanded(1e-5);
            for i in 0..=10 {
                for j in 0..=10 {
                    for k in 0..=10 {
                        let t = Vec3::new(i as f32, j as f32, k as f32) / 10.0;
                        let p = child.min + (child.max - child.min) * t;
                        assert!(b.contains(w.forward(p)), "{w:?}: {} not in {b:?}", w.forward(p));
                    }
                }
            }
        }
    }

    #[test]
    fn bad_parameters_are_rejected() {
        assert!(Warp::Twist { rate: f32::NAN }.validate().is_err());
        assert!(Warp::Bend { rate: 3.0, centre: 0.0, min: -1.0, max: 1.0 }.validate().is_err());
        assert!(Warp::Bend { rate: 0.1, centre: 0.0, min: 1.0, max: -1.0 }.validate().is_err());
        assert!(Warp::Affine(Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0))).validate().is_err());
    }
}
