//! Warps (§2): Barr's twist, taper and bend, and affine maps, evaluated as
//! `f ∘ w⁻¹` with analytic inverses.

use glam::{Affine3A, Mat3, Quat, Vec3};
use isomorph_common::Aabb;

/// Smallest taper scale: `r(z) = max(1 + slope·z, TAPER_MIN_SCALE)` keeps the
/// taper invertible everywhere.
pub const TAPER_MIN_SCALE: f32 = 0.05;

/// The default axis of twists, tapers and bends: the local z axis.
pub const DEFAULT_AXIS: Vec3 = Vec3::Z;

/// The default direction of a bend's band: the local y axis.
pub const DEFAULT_ALONG: Vec3 = Vec3::Y;

/// Smallest accepted length (scene units) of a warp's `axis` or of a
/// bend's `along`: shorter vectors have no direction that `f32` resolves
/// (their normalization would overflow or lose most digits).
pub const MIN_AXIS_LENGTH: f32 = 1e-6;

/// Smallest sine of the angle between a bend's `along` and its `axis`:
/// nearer to parallel, the band direction (`along` without its component
/// on the axis) would be mostly rounding error.
pub const MIN_ALONG_SINE: f32 = 1e-3;

/// A space warp.
///
/// Each Barr warp has its own axis (§4.4: "an axis and a rotation angle
/// for the twist"), a direction in the node's local frame; with the
/// default axis `(0, 0, 1)` twist and taper act about the local z axis and
/// the bend in the y–z plane (Barr 1984). A non-default axis is the same
/// warp expressed in a rotated frame `R`: `w(p) = R·w_z(Rᵀ·p)`, where `R`
/// maps z to the axis (and, for the bend, y to `along`). Axes need not be
/// unit vectors (they are normalized when used) but must be finite and at
/// least [`MIN_AXIS_LENGTH`] long.
/// Every warp has an *identity* parameter (rate 0, slope 0, affine identity)
/// used when a warp is matched with a node of another kind (§4.3, Fig. 15).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Warp {
    /// Twist about `axis`: a point at height `h = p·axis` turns about the
    /// axis by `rate · h` radians (counter-clockwise seen from the axis' tip
    /// for a positive rate).
    Twist {
        /// Radians per unit length along the axis.
        rate: f32,
        /// The twist axis through the local origin ([`DEFAULT_AXIS`]: z).
        axis: Vec3,
    },
    /// Taper along `axis`: the components across the axis scale by
    /// `r(h) = max(1 + slope·h, 0.05)` at height `h = p·axis`.
    Taper {
        /// Scale change per unit length along the axis.
        slope: f32,
        /// The taper axis through the local origin ([`DEFAULT_AXIS`]: z).
        axis: Vec3,
    },
    /// Barr's bend in the plane spanned by `along` and `axis`: with local
    /// coordinates `y = p·along`, `z = p·axis` (along the axis, the default
    /// y–z plane), the band `y ∈ [min, max]` bends around the line at
    /// `z = 1/rate` parallel to `along × axis` (x by default) with angle
    /// `rate · (y − centre)`; beyond the band the shape is carried rigidly.
    /// Requires `|rate|·(max − min) ≤ π`.
    /// The inverse is exact for points whose pre-image lies on the near side
    /// of the bend axis (`z < 1/rate`); keep the warped subtree there, as Barr does.
    Bend {
        /// Curvature (radians per unit length); positive bends towards
        /// `+axis`, negative towards `−axis`.
        rate: f32,
        /// `y0`: the undeformed line of the bend.
        centre: f32,
        /// Lower end of the bent band.
        min: f32,
        /// Upper end of the bent band.
        max: f32,
        /// The direction the bend curves towards ([`DEFAULT_AXIS`]: z).
        axis: Vec3,
        /// The direction of the band, in which `centre`, `min` and `max`
        /// are measured ([`DEFAULT_ALONG`]: y); only its component across
        /// `axis` counts (the sine of its angle with `axis` must be at least [`MIN_ALONG_SINE`]).
        along: Vec3,
    },
    /// An affine map (local → world), invertible and orientation preserving.
    Affine(Affine3A),
}

impl Warp {
    /// A twist of `rate` radians per unit length about the local z axis.
    pub fn twist(rate: f32) -> Warp {
        Warp::Twist { rate, axis: DEFAULT_AXIS }
    }

    /// A taper of `slope` per unit length along the local z axis.
    pub fn taper(slope: f32) -> Warp {
        Warp::Taper { slope, axis: DEFAULT_AXIS }
    }

    /// A bend of curvature `rate` of the band `y ∈ [min, max]` (undeformed
    /// line `y = centre`) in the local y–z plane.
    pub fn bend(rate: f32, centre: f32, min: f32, max: f32) -> Warp {
        Warp::Bend { rate, centre, min, max, axis: DEFAULT_AXIS, along: DEFAULT_ALONG }
    }

    /// The warp's kind name (`"twist"`, `"taper"`, `"bend"`, `"affine"`).
    pub fn kind(&self) -> &'static str {
        match self {
            Warp::Twist { .. } => "twist",
            Warp::Taper { .. } => "taper",
            Warp::Bend { .. } => "bend",
            Warp::Affine(_) => "affine",
        }
    }

    /// The identity warp of the same kind and axes (Fig. 15's inserted operator).
    pub fn identity_like(&self) -> Warp {
        match *self {
            Warp::Twist { axis, .. } => Warp::Twist { rate: 0.0, axis },
            Warp::Taper { axis, .. } => Warp::Taper { slope: 0.0, axis },
            Warp::Bend { centre, min, max, axis, along, .. } => {
                Warp::Bend { rate: 0.0, centre, min, max, axis, along }
            }
            Warp::Affine(_) => Warp::Affine(Affine3A::IDENTITY),
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// A [`crate::NodeProblem`] for non-finite values, an axis or a bend's
    /// `along` shorter than [`MIN_AXIS_LENGTH`], an `along` making an angle
    /// with the axis whose sine is below [`MIN_ALONG_SINE`], a bend band
    /// with `min > max` or more than half a turn, or a
    /// singular/mirrored affine map.
    pub fn validate(&self) -> Result<(), crate::NodeProblem> {
        use crate::NodeProblem as P;
        use crate::node::check_magnitude;
        match *self {
            Warp::Twist { rate, axis } => {
                if !rate.is_finite() {
                    return Err(P::NotFinite("rate"));
                }
                check_axis("axis", axis)?;
                check_magnitude("rate", &[rate])
            }
            Warp::Taper { slope, axis } => {
                if !slope.is_finite() {
                    return Err(P::NotFinite("slope"));
                }
                check_axis("axis", axis)?;
                check_magnitude("slope", &[slope])
            }
            Warp::Bend { rate, centre, min, max, axis, along } => {
                if ![rate, centre, min, max].iter().all(|v| v.is_finite()) {
                    return Err(P::NotFinite("bend"));
                }
                check_axis("axis", axis)?;
                check_axis("along", along)?;
                let a = axis.normalize();
                if (along - a * along.dot(a)).length() < MIN_ALONG_SINE * along.length() {
                    Err(P::Warp("bend `along` is (nearly) parallel to its `axis`"))
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

    /// The rotation of the warp's own frame (z to the axis; for a bend y to
    /// `along`, x to `along × axis`), or `None` for the default axes (and
    /// for affine maps), which are evaluated without rotating. Twists and
    /// tapers commute with turns about their axis, so any rotation taking
    /// z to the axis gives the same warp; this is the shortest one.
    pub(crate) fn rotation(&self) -> Option<Quat> {
        match *self {
            Warp::Twist { axis, .. } | Warp::Taper { axis, .. } if axis != DEFAULT_AXIS => {
                Some(Quat::from_rotation_arc(DEFAULT_AXIS, axis.normalize()))
            }
            Warp::Bend { axis, along, .. } if axis != DEFAULT_AXIS || along != DEFAULT_ALONG => {
                let a = axis.normalize();
                let b = (along - a * along.dot(a)).normalize();
                Some(Quat::from_mat3(&Mat3::from_cols(b.cross(a), b, a)).normalize())
            }
            _ => None,
        }
    }

    /// The turn of the warp's own frame as a matrix (see
    /// `turned_inverse`), `None` for the default axes.
    pub(crate) fn turn(&self) -> Option<Mat3> {
        self.rotation().map(Mat3::from_quat)
    }

    /// The forward map `w(p)`.
    pub fn forward(&self, p: Vec3) -> Vec3 {
        match self.turn() {
            Some(m) => m * self.forward_local(m.transpose() * p),
            None => self.forward_local(p),
        }
    }

    /// The inverse map `w⁻¹(p)`.
    pub fn inverse(&self, p: Vec3) -> Vec3 {
        self.turned_inverse(self.turn(), p)
    }

    /// The inverse map with the frame's turn `turn` (`turn`)
    /// computed once by the caller (the compiled tree keeps it).
    pub(crate) fn turned_inverse(&self, turn: Option<Mat3>, p: Vec3) -> Vec3 {
        match turn {
            Some(m) => m * self.inverse_local(m.transpose() * p),
            None => self.inverse_local(p),
        }
    }

    /// The inverse point and the transposed Jacobian of `w⁻¹` at `p`
    /// (maps a child gradient to the warped field's gradient). Analytic for
    /// twist, taper and affine; central differences (step 1e-4) for the bend.
    /// With a turned frame `R`: `Jᵀ = R·J_zᵀ·Rᵀ`.
    pub fn inverse_with_jacobian_t(&self, p: Vec3) -> (Vec3, Mat3) {
        self.turned_inverse_with_jacobian_t(self.turn(), p)
    }

    /// `inverse_with_jacobian_t` with the frame's turn computed by the caller.
    pub(crate) fn turned_inverse_with_jacobian_t(&self, turn: Option<Mat3>, p: Vec3) -> (Vec3, Mat3) {
        match turn {
            Some(m) => {
                let mt = m.transpose();
                let (q, jt) = self.inverse_jacobian_local(mt * p);
                (m * q, m * jt * mt)
            }
            None => self.inverse_jacobian_local(p),
        }
    }

    /// A box containing `w⁻¹(region)` (every point the warped field reads
    /// its child at for a point of `region`), or `None` where no cheap bound
    /// is known (the bend).
    pub(crate) fn preimage_bounds(&self, region: &Aabb) -> Option<Aabb> {
        if region.is_empty() {
            return Some(*region);
        }
        match self.rotation() {
            Some(r) => self.preimage_bounds_local(&rotated(region, r.inverse())).map(|b| rotated(&b, r)),
            None => self.preimage_bounds_local(region),
        }
    }

    /// A box containing the image under `w` of everything in `child`.
    pub fn image_bounds(&self, child: &Aabb) -> Aabb {
        if child.is_empty() {
            return *child;
        }
        match self.rotation() {
            Some(r) => rotated(&self.image_bounds_local(&rotated(child, r.inverse())), r),
            None => self.image_bounds_local(child),
        }
    }

    /// `forward` in the warp's own frame (axis z, band along y).
    fn forward_local(&self, p: Vec3) -> Vec3 {
        match *self {
            Warp::Twist { rate, .. } => {
                let (s, c) = (rate * p.z).sin_cos();
                Vec3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z)
            }
            Warp::Taper { slope, .. } => {
                let r = taper_scale(slope, p.z);
                Vec3::new(r * p.x, r * p.y, p.z)
            }
            Warp::Bend { rate, centre, min, max, .. } => {
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

    /// `inverse` in the warp's own frame.
    fn inverse_local(&self, p: Vec3) -> Vec3 {
        match *self {
            Warp::Twist { rate, .. } => {
                let (s, c) = (rate * p.z).sin_cos();
                Vec3::new(c * p.x + s * p.y, -s * p.x + c * p.y, p.z)
            }
            Warp::Taper { slope, .. } => {
                let r = taper_scale(slope, p.z);
                Vec3::new(p.x / r, p.y / r, p.z)
            }
            Warp::Bend { rate, centre, min, max, .. } => {
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

    /// `inverse_with_jacobian_t` in the warp's own frame.
    fn inverse_jacobian_local(&self, p: Vec3) -> (Vec3, Mat3) {
        match *self {
            Warp::Twist { rate, .. } => {
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
            Warp::Taper { slope, .. } => {
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
                let col =
                    |e: Vec3| (self.inverse_local(p + e * h) - self.inverse_local(p - e * h)) / (2.0 * h);
                let j = Mat3::from_cols(col(Vec3::X), col(Vec3::Y), col(Vec3::Z));
                (self.inverse_local(p), j.transpose())
            }
        }
    }

    /// `preimage_bounds` of a non-empty region in the warp's own frame.
    fn preimage_bounds_local(&self, region: &Aabb) -> Option<Aabb> {
        match *self {
            // The inverse turns about z too: the same disc holds it.
            Warp::Twist { .. } => Some(self.image_bounds_local(region)),
            Warp::Taper { slope, .. } => {
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

    /// `image_bounds` of a non-empty box in the warp's own frame.
    pub(crate) fn image_bounds_local(&self, child: &Aabb) -> Aabb {
        match *self {
            Warp::Twist { .. } => {
                let rho = child.corners().iter().map(|c| c.truncate().length()).fold(0.0f32, f32::max);
                Aabb::new(Vec3::new(-rho, -rho, child.min.z), Vec3::new(rho, rho, child.max.z))
            }
            Warp::Taper { slope, .. } => {
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
            Warp::Bend { rate, centre, min, max, .. } => {
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
    /// rates, slopes and bend bands linearly; twist and taper axes along
    /// the great circle between them at constant angular speed; a bend's frame (axis and band direction) by
    /// quaternion slerp; affine maps as translation · rotation (quaternion
    /// slerp) · stretch. Equal axes are kept as they are. `None` if the
    /// kinds differ or an affine map cannot be decomposed.
    pub fn lerp(&self, other: &Warp, s: f32) -> Option<Warp> {
        let l = |a: f32, b: f32| a + (b - a) * s;
        Some(match (*self, *other) {
            (Warp::Twist { rate: a, axis: u }, Warp::Twist { rate: b, axis: v }) => {
                Warp::Twist { rate: l(a, b), axis: slerp_axis(u, v, s) }
            }
            (Warp::Taper { slope: a, axis: u }, Warp::Taper { slope: b, axis: v }) => {
                Warp::Taper { slope: l(a, b), axis: slerp_axis(u, v, s) }
            }
            (
                w0 @ Warp::Bend { rate: a, centre: c0, min: m0, max: x0, axis: u0, along: v0 },
                w1 @ Warp::Bend { rate: b, centre: c1, min: m1, max: x1, axis: u1, along: v1 },
            ) => {
                let (axis, along) = if (u0, v0) == (u1, v1) {
                    (u0, v0)
                } else {
                    let id = Quat::IDENTITY;
                    let q = w0.rotation().unwrap_or(id).slerp(w1.rotation().unwrap_or(id), s);
                    (q * DEFAULT_AXIS, q * DEFAULT_ALONG)
                };
                Warp::Bend { rate: l(a, b), centre: l(c0, c1), min: l(m0, m1), max: l(x0, x1), axis, along }
            }
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

/// The direction at fraction `s` of the great-circle arc from `u` to `v`
/// (directions of the two vectors), at constant angular speed: `u` turned
/// by `s` times the shortest rotation taking `u` to `v` (for opposite
/// directions, a fixed half turn about an axis across `u`). Equal vectors
/// are returned unchanged.
pub(crate) fn slerp_axis(u: Vec3, v: Vec3, s: f32) -> Vec3 {
    if u == v {
        return u;
    }
    let u = u.normalize();
    Quat::IDENTITY.slerp(Quat::from_rotation_arc(u, v.normalize()), s) * u
}

/// Checks one axis vector: finite, at most [`crate::MAX_MAGNITUDE`], at
/// least [`MIN_AXIS_LENGTH`] long.
fn check_axis(field: &'static str, v: Vec3) -> Result<(), crate::NodeProblem> {
    if !v.is_finite() {
        return Err(crate::NodeProblem::NotFinite(field));
    }
    crate::node::check_magnitude(field, &v.to_array())?;
    if v.length() < MIN_AXIS_LENGTH {
        return Err(crate::NodeProblem::OutOfRange {
            field,
            value: v.length(),
            expected: "a direction: a vector of length ≥ 1e-6",
        });
    }
    Ok(())
}

/// A box holding the image of `b` under the rotation `r` (the box of its
/// rotated corners), `widened`.
fn rotated(b: &Aabb, r: Quat) -> Aabb {
    if b.is_empty() {
        return *b;
    }
    widened(&b.transformed(&Affine3A::from_quat(r)))
}

/// `b` widened by a few ulps of its largest coordinate: a box computed
/// through a rotation then holds the points the warps compute through the
/// same rotation in another order of operations.
pub(crate) fn widened(b: &Aabb) -> Aabb {
    let reach = b.min.abs().max(b.max.abs()).max_element();
    b.expanded(4.0 * f32::EPSILON * reach)
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
            Warp::twist(1.3),
            Warp::taper(0.4),
            Warp::bend(0.8, 0.1, -0.6, 0.9),
            Warp::bend(-0.5, 0.0, -1.0, 1.0),
            Warp::Twist { rate: -1.1, axis: Vec3::new(0.3, -0.8, 0.5) },
            Warp::Taper { slope: -0.6, axis: Vec3::new(2.0, 0.5, -1.0) },
            Warp::Bend {
                rate: 0.7,
                centre: -0.1,
                min: -0.8,
                max: 0.6,
                axis: Vec3::new(1.0, 0.2, 0.1),
                along: Vec3::new(0.3, 0.2, 1.0),
            },
            Warp::Bend { rate: -0.4, centre: 0.2, min: -1.0, max: 1.0, axis: Vec3::X, along: -Vec3::Z },
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

    /// With the default axes the warps are Barr's about z (bend in the
    /// y–z plane), bit for bit as before axes existed: the formulas written
    /// out here, and the image boxes of the unrotated frame.
    #[test]
    fn default_axes_are_the_warps_about_z_bit_for_bit() {
        let (k, slope) = (1.3f32, 0.4f32);
        let child = Aabb::new(Vec3::new(-0.5, -0.7, -0.4), Vec3::new(0.6, 0.8, 0.5));
        for p in sample_points() {
            let (s, c) = (k * p.z).sin_cos();
            assert_eq!(Warp::twist(k).inverse(p), Vec3::new(c * p.x + s * p.y, -s * p.x + c * p.y, p.z));
            assert_eq!(Warp::twist(k).forward(p), Vec3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z));
            let r = (1.0 + slope * p.z).max(TAPER_MIN_SCALE);
            assert_eq!(Warp::taper(slope).inverse(p), Vec3::new(p.x / r, p.y / r, p.z));
            assert_eq!(Warp::taper(slope).forward(p), Vec3::new(r * p.x, r * p.y, p.z));
            let bend = Warp::bend(0.8, 0.1, -0.6, 0.9);
            assert_eq!(bend.forward(p), bend_forward(0.8, 0.1, -0.6, 0.9, p));
            assert_eq!(bend.inverse(p), bend_inverse(0.8, 0.1, -0.6, 0.9, p));
        }
        for w in warps().into_iter().filter(|w| w.rotation().is_none()) {
            assert_eq!(w.image_bounds(&child), w.image_bounds_local(&child), "{w:?}");
        }
        assert_eq!(warps().iter().filter(|w| w.rotation().is_none()).count(), 5);
    }

    /// Matched warps of one kind with different axes (§4.4): rates
    /// linearly, twist and taper axes along the great circle at constant
    /// angular speed, a bend's frame by slerp (axis and band direction
    /// stay unit and across each other); equal axes are kept exactly;
    /// opposite axes still give a unit axis.
    #[test]
    fn matched_warps_interpolate_their_axes() {
        let a = Warp::Twist { rate: 2.0, axis: Vec3::Z };
        let b = Warp::Twist { rate: -1.0, axis: Vec3::new(3.0, 0.0, 0.0) };
        for s in [0.0, 0.25, 0.5, 0.9, 1.0] {
            let Some(Warp::Twist { rate, axis }) = a.lerp(&b, s) else { panic!() };
            assert!((rate - (2.0 - 3.0 * s)).abs() < 1e-6);
            let angle = s * std::f32::consts::FRAC_PI_2;
            assert!((axis - Vec3::new(angle.sin(), 0.0, angle.cos())).length() < 1e-5, "{s}: {axis}");
        }
        let t = Warp::Taper { slope: 0.2, axis: Vec3::new(0.0, 1.0, 1.0) };
        let Some(Warp::Taper { slope, axis }) =
            t.lerp(&Warp::Taper { slope: 0.6, axis: Vec3::new(0.0, 1.0, 1.0) }, 0.5)
        else {
            panic!()
        };
        assert!((slope - 0.4).abs() < 1e-6);
        assert_eq!(axis, Vec3::new(0.0, 1.0, 1.0));
        let Some(Warp::Twist { axis, .. }) = a.lerp(&Warp::Twist { rate: 1.0, axis: -Vec3::Z }, 0.5) else {
            panic!()
        };
        assert!((axis.length() - 1.0).abs() < 1e-5 && axis.z.abs() < 1e-5, "{axis}");
        let b0 = Warp::bend(0.5, 0.0, -1.0, 1.0);
        let b1 = Warp::Bend { rate: 0.3, centre: 0.2, min: -0.5, max: 0.5, axis: Vec3::X, along: Vec3::Z };
        let Some(Warp::Bend { rate, centre, axis, along, .. }) = b0.lerp(&b1, 0.5) else { panic!() };
        assert!((rate - 0.4).abs() < 1e-6 && (centre - 0.1).abs() < 1e-6);
        assert!((axis.length() - 1.0).abs() < 1e-5 && (along.length() - 1.0).abs() < 1e-5);
        assert!(axis.dot(along).abs() < 1e-5, "{axis} {along}");
        // Half way between the frames (z, y) and (x, z): a third of a turn
        // about (1, 1, 1) takes one to the other; half of it is 60°.
        let q = Quat::from_axis_angle(Vec3::ONE.normalize(), std::f32::consts::FRAC_PI_3);
        assert!(
            (axis - q * Vec3::Z).length() < 1e-5 && (along - q * Vec3::Y).length() < 1e-5,
            "{axis} {along}"
        );
        assert_eq!(b0.lerp(&Warp::bend(0.1, 0.0, -1.0, 1.0), 0.3).map(|w| w.rotation()), Some(None));
    }

    #[test]
    fn bad_parameters_are_rejected() {
        assert!(Warp::twist(f32::NAN).validate().is_err());
        assert!(Warp::bend(3.0, 0.0, -1.0, 1.0).validate().is_err());
        assert!(Warp::bend(0.1, 0.0, 1.0, -1.0).validate().is_err());
        assert!(Warp::Affine(Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0))).validate().is_err());
    }
}
