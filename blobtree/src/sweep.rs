//! Supports swept over an interval of time: conservative boxes holding the
//! support of every instance `C(t)`, `t ∈ [t₀, t₁]`, of a time-varying
//! BlobTree, computed from the ranges its parameters take over the interval
//! (interval arithmetic, the convex-hull property of Bézier curves, and
//! bounds on slerped rotations), not from samples in `t`.
//!
//! The support rules are those of [`crate::BlobTree::support`]: a leaf's
//! skeleton box grown by its radius and mapped by its frame, the union (or
//! intersection) of children, a difference's left child, a warp's image box.
//! Every rule here is applied to *sets* of parameters and returns a box that
//! holds the rule's result for each member, so the swept box holds the
//! support of every instance in the interval.

use crate::node::Primitive;
use crate::warp::{Warp, slerp_axis, widened};
use glam::{Affine3A, Mat3, Quat, Vec3};
use isomorph_common::{Aabb, AffineParts, TransformError};
use std::f32::consts::PI;

/// Slack (radians) added to every non-trivial rotation range: glam's slerp
/// switches to a normalized linear blend for nearby rotations, which leaves
/// the great circle by far less than this.
const ROTATION_SLACK: f32 = 1e-4;

/// The cells (scene units of `Δ = ŷ − y0`) a bend's band is cut into for
/// its image bounds: a fixed grid, so that bounds for narrower parameter
/// ranges are cut at the same places and stay inside those for wider ones.
const BEND_CELL: f32 = 0.02;

/// Most cells a bend's band is cut into (beyond, it is bounded whole).
const BEND_MAX_CELLS: i64 = 512;

/// The critical points `x > 0` (and 0) of [`sinc`] below [`ARGUMENT_LIMIT`]
/// (the roots of `tan x = x`).
const SINC_CRITICAL: [f32; 5] = [0.0, 4.493_409_5, 7.725_251_6, 10.904_122, 14.066_194];

/// The critical points `x > 0` of [`versinc`] below [`ARGUMENT_LIMIT`]
/// (`tan(x/2) = x` and `x = 2πn`).
const VERSINC_CRITICAL: [f32; 4] = [2.331_122_4, 6.283_185_5, 9.208_434, 12.566_371];

/// Where the critical points listed for [`sinc`] and [`versinc`] end:
/// beyond `|x| = ARGUMENT_LIMIT` only their global ranges are used.
const ARGUMENT_LIMIT: f32 = 15.0;

/// A closed interval `[lo, hi]` of reals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Interval {
    /// Lower end.
    pub lo: f32,
    /// Upper end.
    pub hi: f32,
}

impl Interval {
    /// The interval between `a` and `b`, in either order.
    pub fn new(a: f32, b: f32) -> Self {
        Self { lo: a.min(b), hi: a.max(b) }
    }

    /// The single value `v`.
    pub fn point(v: f32) -> Self {
        Self { lo: v, hi: v }
    }

    /// The middle of the interval.
    pub fn mid(self) -> f32 {
        0.5 * (self.lo + self.hi)
    }

    fn width(self) -> f32 {
        self.hi - self.lo
    }

    fn hull(self, o: Self) -> Self {
        Self { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    fn add(self, o: Self) -> Self {
        Self { lo: self.lo + o.lo, hi: self.hi + o.hi }
    }

    fn sub(self, o: Self) -> Self {
        Self { lo: self.lo - o.hi, hi: self.hi - o.lo }
    }

    fn mul(self, o: Self) -> Self {
        let p = [self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi];
        Self {
            lo: p.into_iter().fold(f32::INFINITY, f32::min),
            hi: p.into_iter().fold(f32::NEG_INFINITY, f32::max),
        }
    }

    fn abs_max(self) -> f32 {
        self.lo.abs().max(self.hi.abs())
    }

    /// `{(1 − s) a + s b : a ∈ self, b ∈ o, s ∈ s}` for `s ⊆ [0, 1]`: the
    /// extremes are at the ends of `s` (the blend is linear in `s`).
    pub fn lerp(self, o: Self, s: Self) -> Self {
        let at = |x: f32, y: f32, s: f32| x + (y - x) * s;
        Self {
            lo: at(self.lo, o.lo, s.lo).min(at(self.lo, o.lo, s.hi)),
            hi: at(self.hi, o.hi, s.lo).max(at(self.hi, o.hi, s.hi)),
        }
    }

    /// The range of `f` over this interval: its values at the ends and at
    /// the critical points `±c` inside (exact, so a narrower interval gets a
    /// range inside a wider one's).
    fn range_of(self, f: impl Fn(f32) -> f32, critical: &[f32]) -> Self {
        let mut r = Self::new(f(self.lo), f(self.hi));
        for c in critical.iter().flat_map(|&c| [c, -c]) {
            if self.lo < c && c < self.hi {
                r = r.hull(Self::point(f(c)));
            }
        }
        r
    }

    /// The exact range of `sin(x + phase)` over this interval.
    fn sin_range(self, phase: f32) -> Self {
        let (a, b) = (self.lo + phase, self.hi + phase);
        let mut r = Self::new(a.sin(), b.sin());
        let hit = |c: f32| {
            let n = ((a - c) / (2.0 * PI)).ceil();
            c + 2.0 * PI * n <= b
        };
        if hit(0.5 * PI) {
            r.hi = 1.0;
        }
        if hit(-0.5 * PI) {
            r.lo = -1.0;
        }
        r
    }
}

/// `{(1 − s) a + s b}` componentwise for points `a`, `b` ranging over two boxes.
fn lerp_box(a: &Aabb, b: &Aabb, s: Interval) -> Aabb {
    let c =
        |k: usize| Interval { lo: a.min[k], hi: a.max[k] }.lerp(Interval { lo: b.min[k], hi: b.max[k] }, s);
    let (x, y, z) = (c(0), c(1), c(2));
    Aabb::new(Vec3::new(x.lo, y.lo, z.lo), Vec3::new(x.hi, y.hi, z.hi))
}

/// The box of the control points of the part `v ∈ [v0, v1]` of the cubic
/// Bézier curve with controls `c` (blossoms `f(v0,v0,v0) … f(v1,v1,v1)`):
/// the curve part lies in their convex hull.
pub(crate) fn bezier_box(c: [Vec3; 4], v0: f32, v1: f32) -> Aabb {
    let blossom = |u: [f32; 3]| {
        let mut p = c.to_vec();
        for ui in u {
            p = p.windows(2).map(|w| w[0] * (1.0 - ui) + w[1] * ui).collect();
        }
        p[0]
    };
    Aabb::from_points(&[
        blossom([v0, v0, v0]),
        blossom([v0, v0, v1]),
        blossom([v0, v1, v1]),
        blossom([v1, v1, v1]),
    ])
}

/// A set of affine maps `translation · rotation · stretch`
/// ([`AffineParts`]): translations in a box, rotations within `spread`
/// radians (rotation angle) of `rotation`, stretches entrywise in
/// `[stretch_lo, stretch_hi]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FrameRange {
    translation: Aabb,
    rotation: Quat,
    /// Largest rotation angle from `rotation`; `≥ π` means any rotation.
    spread: f32,
    stretch_lo: Mat3,
    stretch_hi: Mat3,
}

impl FrameRange {
    /// The single map `parts`.
    pub fn exact(parts: &AffineParts) -> Self {
        Self {
            translation: Aabb::new(parts.translation, parts.translation),
            rotation: parts.rotation,
            spread: 0.0,
            stretch_lo: parts.stretch,
            stretch_hi: parts.stretch,
        }
    }

    /// A range holding both.
    pub fn union(&self, o: &FrameRange) -> FrameRange {
        let spread = self.spread.max(self.rotation.angle_between(o.rotation) + o.spread);
        FrameRange {
            translation: self.translation.union(&o.translation),
            rotation: self.rotation,
            spread,
            stretch_lo: Mat3::from_cols_array(&elementwise(&self.stretch_lo, &o.stretch_lo, f32::min)),
            stretch_hi: Mat3::from_cols_array(&elementwise(&self.stretch_hi, &o.stretch_hi, f32::max)),
        }
    }

    /// The maps `AffineParts::lerp(x, y, s)` for `x` in `a`, `y` in `b`,
    /// `s` in `s ⊆ [0, 1]`.
    ///
    /// Translations and stretches blend linearly. The rotation
    /// `slerp(q_x, q_y, s)` is within `θ·|s − s_m|` of `slerp(q_a, q_b, s)`'s
    /// value at the middle `s_m` (`θ` the angle between the centres), plus
    /// what moving the ends by up to `φ = max(φ_a, φ_b)` can do: on the unit
    /// quaternion sphere a geodesic of length `L < π/2` moves by at most
    /// `φ·(1 + 1/cos(L/2))` (its Jacobi fields: the normal part is at most
    /// `1/cos(L/2)` times the larger end motion, the tangential part at most
    /// that motion). When the ends' rotations may be half a turn apart the
    /// result is any rotation.
    pub fn lerp(a: &FrameRange, b: &FrameRange, s: Interval) -> FrameRange {
        let theta = a.rotation.angle_between(b.rotation);
        let rotation = a.rotation.slerp(b.rotation, s.mid()).normalize();
        let ends = a.spread.max(b.spread);
        let reach = theta + a.spread + b.spread;
        let spread = if ends == 0.0 {
            theta * 0.5 * s.width() + if theta > 0.0 { ROTATION_SLACK } else { 0.0 }
        } else if reach < PI {
            // `reach / 2` is the longest geodesic on the quaternion sphere.
            ends * (1.0 + 1.0 / (reach / 4.0).cos()) + theta * 0.5 * s.width() + ROTATION_SLACK
        } else {
            PI
        };
        FrameRange {
            translation: lerp_box(&a.translation, &b.translation, s),
            rotation,
            spread,
            stretch_lo: lerp_mat(&a.stretch_lo, &b.stretch_lo, s, true),
            stretch_hi: lerp_mat(&a.stretch_hi, &b.stretch_hi, s, false),
        }
    }

    /// Rotations `slerp(q0, q1, v)` for `v ∈ [v0, v1]` (exact ends), with
    /// this range's translations and stretches.
    pub fn with_slerp(mut self, q0: Quat, q1: Quat, v0: f32, v1: f32) -> FrameRange {
        let theta = q0.angle_between(q1);
        self.rotation = q0.slerp(q1, 0.5 * (v0 + v1)).normalize();
        self.spread = theta * 0.5 * (v1 - v0) + if theta > 0.0 { ROTATION_SLACK } else { 0.0 };
        self
    }

    /// The rotations within `spread` radians of `rotation` (`≥ π`: any
    /// rotation), without translation or stretch.
    pub fn rotations(rotation: Quat, spread: f32) -> FrameRange {
        FrameRange {
            translation: Aabb::new(Vec3::ZERO, Vec3::ZERO),
            rotation,
            spread,
            stretch_lo: Mat3::IDENTITY,
            stretch_hi: Mat3::IDENTITY,
        }
    }

    /// For a range of rotations (`FrameRange::rotations`, or blends of
    /// such ranges): the range of their inverses (`R⁻¹` is as far from
    /// `R_c⁻¹` as `R` from `R_c`).
    fn inverse_rotations(&self) -> FrameRange {
        FrameRange::rotations(self.rotation.conjugate(), self.spread)
    }

    /// Whether the range is the identity alone.
    fn is_identity(&self) -> bool {
        *self == FrameRange::rotations(Quat::IDENTITY, 0.0)
    }

    /// This range with translations in `translation`.
    pub fn with_translation(mut self, translation: Aabb) -> FrameRange {
        self.translation = translation;
        self
    }

    /// A box holding the image of `local` under every map of the range:
    /// `T + R_c·M_c·x` plus a ball for the stretch's spread (`‖ΔM‖_F·|x|`)
    /// and the rotation's (`2 sin(φ/2)·‖M‖·|x|`), intersected with the box
    /// that any rotation allows (`|R M x| ≤ ‖M‖·|x|`).
    pub fn apply(&self, local: &Aabb) -> Aabb {
        if local.is_empty() {
            return *local;
        }
        let mc = (self.stretch_lo + self.stretch_hi) * 0.5;
        let dm = (self.stretch_hi - self.stretch_lo) * 0.5;
        let frob = |m: &Mat3| m.to_cols_array().iter().map(|v| v * v).sum::<f32>().sqrt();
        let (nf, mf) = (frob(&dm), frob(&mc));
        let reach = local.min.abs().max(local.max.abs()).length();
        let turn = if self.spread >= PI { 2.0 } else { 2.0 * (0.5 * self.spread).sin() };
        let rho = (nf + turn * (mf + nf)) * reach;
        let core = local.transformed(&Affine3A::from_mat3(Mat3::from_quat(self.rotation) * mc));
        let near = Aabb::new(core.min + self.translation.min - rho, core.max + self.translation.max + rho);
        let any = (mf + nf) * reach;
        near.intersection(&Aabb::new(self.translation.min - any, self.translation.max + any))
    }
}

fn elementwise(a: &Mat3, b: &Mat3, f: fn(f32, f32) -> f32) -> [f32; 9] {
    let (a, b) = (a.to_cols_array(), b.to_cols_array());
    std::array::from_fn(|i| f(a[i], b[i]))
}

/// The lower (`low`) or upper end of the entrywise linear blend of two
/// matrix ranges' ends over `s`.
fn lerp_mat(a: &Mat3, b: &Mat3, s: Interval, low: bool) -> Mat3 {
    let (a, b) = (a.to_cols_array(), b.to_cols_array());
    Mat3::from_cols_array(&std::array::from_fn(|i| {
        let r = Interval::point(a[i]).lerp(Interval::point(b[i]), s);
        if low { r.lo } else { r.hi }
    }))
}

/// The parameters of a set of primitives that matter to their supports:
/// the ranges of the local skeleton box's corners, of the radius, and of
/// the frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PrimRange {
    /// Where the skeleton box's lower corner lies.
    low: Aabb,
    /// Where the skeleton box's upper corner lies.
    high: Aabb,
    radius: Interval,
    frame: FrameRange,
}

impl PrimRange {
    /// One primitive, its skeleton box `bounds` (local frame).
    ///
    /// # Errors
    /// When the primitive's frame is singular or a reflection.
    pub fn exact(p: &Primitive, bounds: &Aabb) -> Result<Self, TransformError> {
        let frame = FrameRange::exact(&AffineParts::from_affine(&p.frame)?);
        Ok(Self::blend(bounds, bounds, Interval::point(p.kernel.radius), frame, Interval::point(0.0)))
    }

    /// The primitives with local skeleton boxes `(1 − s) box_a + s box_b`
    /// for `s` in `s` (the box of a Minkowski blend of two skeletons),
    /// radii in `radius` and frames in `frame`.
    pub fn blend(box_a: &Aabb, box_b: &Aabb, radius: Interval, frame: FrameRange, s: Interval) -> Self {
        let corner = |v: Vec3| Aabb::new(v, v);
        Self {
            low: lerp_box(&corner(box_a.min), &corner(box_b.min), s),
            high: lerp_box(&corner(box_a.max), &corner(box_b.max), s),
            radius,
            frame,
        }
    }

    /// The blends of two sets of primitives over `s` (a generic leaf with
    /// the linear frame path: skeleton boxes and radii linearly, frames as
    /// [`FrameRange::lerp`]).
    pub fn lerp(a: &PrimRange, b: &PrimRange, s: Interval) -> PrimRange {
        PrimRange {
            low: lerp_box(&a.low, &b.low, s),
            high: lerp_box(&a.high, &b.high, s),
            radius: a.radius.lerp(b.radius, s),
            frame: FrameRange::lerp(&a.frame, &b.frame, s),
        }
    }

    /// A box holding the support of every primitive in the range.
    pub fn support(&self) -> Aabb {
        let r = self.radius.hi.max(0.0);
        self.frame.apply(&Aabb::new(self.low.min - r, self.high.max + r))
    }
}

/// The ranges of a warp's parameters. `axes` is a range of rotations of
/// the warps' own frames ([`Warp`]): every warp of the range is
/// `R·w(Rᵀ·p)` for some `R` in it and `w` the warp about the default axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum WarpRange {
    /// Twists (their image boxes do not depend on the rate).
    Twist {
        /// Their frames (for twist and taper, which commute with turns
        /// about their axis: the rotations taking z to their axes).
        axes: FrameRange,
    },
    /// Tapers.
    Taper {
        /// Slope.
        slope: Interval,
        /// Their frames, as for twists.
        axes: FrameRange,
    },
    /// Bends.
    Bend {
        /// Curvature.
        rate: Interval,
        /// Undeformed line `y0`.
        centre: Interval,
        /// Lower end of the band.
        min: Interval,
        /// Upper end of the band.
        max: Interval,
        /// Their frames (z to the axis, y to the band's direction).
        axes: FrameRange,
    },
    /// Affine maps.
    Affine(FrameRange),
}

impl WarpRange {
    /// One warp.
    ///
    /// # Errors
    /// When an affine map is singular or a reflection.
    pub fn exact(w: &Warp) -> Result<Self, TransformError> {
        let p = Interval::point;
        let axes = FrameRange::rotations(w.rotation().unwrap_or(Quat::IDENTITY), 0.0);
        Ok(match *w {
            Warp::Twist { .. } => WarpRange::Twist { axes },
            Warp::Taper { slope, .. } => WarpRange::Taper { slope: p(slope), axes },
            Warp::Bend { rate, centre, min, max, .. } => {
                WarpRange::Bend { rate: p(rate), centre: p(centre), min: p(min), max: p(max), axes }
            }
            Warp::Affine(m) => WarpRange::Affine(FrameRange::exact(&AffineParts::from_affine(&m)?)),
        })
    }

    /// The warp kind's name, as [`Warp::kind`].
    pub fn kind(&self) -> &'static str {
        match self {
            WarpRange::Twist { .. } => "twist",
            WarpRange::Taper { .. } => "taper",
            WarpRange::Bend { .. } => "bend",
            WarpRange::Affine(_) => "affine",
        }
    }

    /// The blends of two ranges of one kind over `s` (as [`Warp::lerp`]);
    /// `None` for different kinds.
    pub fn lerp(a: &WarpRange, b: &WarpRange, s: Interval) -> Option<WarpRange> {
        Some(match (a, b) {
            (WarpRange::Twist { axes: x }, WarpRange::Twist { axes: y }) => {
                WarpRange::Twist { axes: lerp_axes(x, y, s) }
            }
            (WarpRange::Taper { slope: x, axes: ax }, WarpRange::Taper { slope: y, axes: ay }) => {
                WarpRange::Taper { slope: x.lerp(*y, s), axes: lerp_axes(ax, ay, s) }
            }
            (
                WarpRange::Bend { rate: r0, centre: c0, min: m0, max: x0, axes: a0 },
                WarpRange::Bend { rate: r1, centre: c1, min: m1, max: x1, axes: a1 },
            ) => WarpRange::Bend {
                rate: r0.lerp(*r1, s),
                centre: c0.lerp(*c1, s),
                min: m0.lerp(*m1, s),
                max: x0.lerp(*x1, s),
                axes: if a0 == a1 { *a0 } else { FrameRange::lerp(a0, a1, s) },
            },
            (WarpRange::Affine(x), WarpRange::Affine(y)) => WarpRange::Affine(FrameRange::lerp(x, y, s)),
            _ => return None,
        })
    }

    /// A box holding the image of `child` under every warp of the range:
    /// for rotated frames, the child's box taken into the frames (every
    /// inverse rotation of the range), bounded there, and taken back.
    pub fn image(&self, child: &Aabb) -> Aabb {
        if child.is_empty() {
            return *child;
        }
        let axes = match self {
            WarpRange::Twist { axes } | WarpRange::Taper { axes, .. } | WarpRange::Bend { axes, .. } => axes,
            WarpRange::Affine(frame) => return frame.apply(child),
        };
        if axes.is_identity() {
            return self.image_local(child);
        }
        let local = widened(&axes.inverse_rotations().apply(child));
        widened(&axes.apply(&self.image_local(&local)))
    }

    /// `WarpRange::image` of a non-empty box for the warps about the
    /// default axes.
    fn image_local(&self, child: &Aabb) -> Aabb {
        match self {
            WarpRange::Twist { .. } => Warp::twist(0.0).image_bounds_local(child),
            WarpRange::Taper { slope, .. } => {
                let z = Interval { lo: child.min.z, hi: child.max.z };
                let one = Interval::point(1.0);
                let r = one.add(slope.mul(z));
                let floor = crate::warp::TAPER_MIN_SCALE;
                let r = Interval { lo: r.lo.max(floor), hi: r.hi.max(floor) };
                let x = r.mul(Interval { lo: child.min.x, hi: child.max.x });
                let y = r.mul(Interval { lo: child.min.y, hi: child.max.y });
                Aabb::new(Vec3::new(x.lo, y.lo, z.lo), Vec3::new(x.hi, y.hi, z.hi))
            }
            WarpRange::Bend { rate, centre, min, max, .. } => bend_image(*rate, *centre, *min, *max, child),
            WarpRange::Affine(frame) => frame.apply(child),
        }
    }
}

/// The frames of twists or tapers whose axes are `slerp_axis(u, v, s')`
/// ([`Warp::lerp`]) for axes `u` of `a`, `v` of `b` and `s'` in `s`, as a
/// cone of axes turned into rotations (an axis within `φ` of the cone's
/// axis `c` is reached by a rotation within `φ` of the shortest one taking
/// z to `c`). Exact ends: the great-circle arc from `u` to `v` over `s` lies
/// within `θ·|s|/2` of its middle. Otherwise every point of a shortest arc
/// between the two cones lies in the smallest cone holding both (convex
/// while its radius is below π/2; any axis beyond). Nearly opposite
/// exact ends (where the arc's plane is a matter of rounding) give any axis.
fn lerp_axes(a: &FrameRange, b: &FrameRange, s: Interval) -> FrameRange {
    if a == b {
        return *a;
    }
    let any = FrameRange::rotations(Quat::IDENTITY, PI);
    let (na, nb) = (a.rotation * Vec3::Z, b.rotation * Vec3::Z);
    let theta = na.angle_between(nb);
    let (centre, radius) = if a.spread == 0.0 && b.spread == 0.0 {
        if theta > PI - 1e-2 {
            return any;
        }
        (slerp_axis(na, nb, s.mid()), 0.5 * theta * s.width())
    } else if theta + b.spread <= a.spread {
        (na, a.spread)
    } else if theta + a.spread <= b.spread {
        (nb, b.spread)
    } else {
        let r = 0.5 * (theta + a.spread + b.spread);
        if r >= 0.5 * PI {
            return any;
        }
        (slerp_axis(na, nb, (r - a.spread) / theta), r)
    };
    FrameRange::rotations(Quat::from_rotation_arc(Vec3::Z, centre.normalize()), radius + ROTATION_SLACK)
}

/// `sin x / x`.
fn sinc(x: f32) -> f32 {
    if x.abs() < 1e-4 { 1.0 - x * x / 6.0 } else { x.sin() / x }
}

/// `(1 − cos x) / x = 2 sin²(x/2) / x` (odd, 0 at 0).
fn versinc(x: f32) -> f32 {
    if x.abs() < 1e-4 {
        0.5 * x
    } else {
        let h = (0.5 * x).sin();
        2.0 * h * h / x
    }
}

/// A box holding the images of `child` under Barr's bends with parameters
/// in the given ranges.
///
/// The bend maps `(x, y, z)` to `(x, y', z')` with `ŷ = clamp(y, min, max)`,
/// `Δ = ŷ − y0`, `e = y − ŷ`, `θ = kΔ`:
/// `y' = y0 + e cos θ − z sin θ + Δ sinc θ`, `z' = z cos θ + e sin θ + Δ (1 − cos θ)/θ`
/// (the same as rotating about the axis at `z = 1/k`, without the axis: no
/// blow-up as `k → 0`). `y` is split into the parts below, inside and above
/// the band, `Δ` into the cells of a fixed grid ([`BEND_CELL`]); on each,
/// the exact ranges of the functions of `θ` (ends and critical points) and
/// interval arithmetic. Every step is inclusion-monotone: narrower
/// parameter ranges give a box inside a wider ranges' box.
pub(crate) fn bend_image(k: Interval, y0: Interval, lo: Interval, hi: Interval, child: &Aabb) -> Aabb {
    let (ys, z) =
        (Interval { lo: child.min.y, hi: child.max.y }, Interval { lo: child.min.z, hi: child.max.z });
    let clamp = |y: f32, l: f32, h: f32| y.max(l).min(h);
    let off = |y: f32, l: f32, h: f32| (y - h).max(0.0) + (y - l).min(0.0);
    let parts = [(ys.lo, ys.hi.min(lo.hi)), (ys.lo.max(lo.lo), ys.hi.min(hi.hi)), (ys.lo.max(hi.lo), ys.hi)];
    let mut out = Aabb::EMPTY;
    for (a, b) in parts {
        if a > b {
            continue;
        }
        let yh = Interval { lo: clamp(a, lo.lo, hi.lo), hi: clamp(b, lo.hi, hi.hi) };
        let e = Interval { lo: off(a, lo.hi, hi.hi), hi: off(b, lo.lo, hi.lo) };
        let delta = yh.sub(y0);
        // One cell more at each end against rounding in the division.
        let (first, last) =
            ((delta.lo / BEND_CELL).floor() as i64 - 1, (delta.hi / BEND_CELL).ceil() as i64 + 1);
        let cells = if last - first > BEND_MAX_CELLS {
            vec![delta]
        } else {
            (first..last)
                .map(|j| Interval {
                    lo: delta.lo.max(j as f32 * BEND_CELL),
                    hi: delta.hi.min((j + 1) as f32 * BEND_CELL),
                })
                .filter(|d| d.lo <= d.hi)
                .collect()
        };
        for d in cells {
            let theta = k.mul(d);
            let (sin, cos) = (theta.sin_range(0.0), theta.sin_range(0.5 * PI));
            let far = theta.abs_max() > ARGUMENT_LIMIT;
            let sc = if far { Interval::new(-0.2173, 1.0) } else { theta.range_of(sinc, &SINC_CRITICAL) };
            let vc =
                if far { Interval::new(-0.7247, 0.7247) } else { theta.range_of(versinc, &VERSINC_CRITICAL) };
            let y = y0.add(cos.mul(e)).sub(sin.mul(z)).add(d.mul(sc));
            let zz = cos.mul(z).add(sin.mul(e)).add(d.mul(vc));
            out = out
                .union(&Aabb::new(Vec3::new(child.min.x, y.lo, zz.lo), Vec3::new(child.max.x, y.hi, zz.hi)));
        }
    }
    out
}

/// The ranges of a time-varying BlobTree over an interval of time, node by
/// node, in the structure of its instances (the same child indices, so a
/// node path names the same node in an instance and here).
#[derive(Debug, Clone)]
pub(crate) enum Span {
    /// Primitives: each instance's parameters lie in one of the ranges
    /// (a leaf whose ends are written in other frames than its in-betweens
    /// has one range per frame choice: merging them would be loose).
    Leaf(Vec<PrimRange>),
    /// A commutative node; `intersection`: its operator is `∩` at every
    /// instant (its support is then the children's intersection, else
    /// their union).
    Nary {
        /// Whether the operator is always the intersection.
        intersection: bool,
        /// The children.
        children: Vec<Span>,
    },
    /// A difference (its support is the left child's).
    Difference(Box<Span>, Box<Span>),
    /// A warp.
    Warp(WarpRange, Box<Span>),
}

impl Span {
    /// A box holding the support of every instance.
    pub fn support(&self) -> Aabb {
        match self {
            Span::Leaf(ranges) => ranges.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.support())),
            Span::Nary { intersection: true, children } => {
                children.iter().fold(Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX)), |b, c| {
                    b.intersection(&c.support())
                })
            }
            Span::Nary { children, .. } => children.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.support())),
            Span::Difference(left, _) => left.support(),
            Span::Warp(w, child) => w.image(&child.support()),
        }
    }

    /// The node at `path` (child indices from here), if any.
    pub fn at(&self, path: &[usize]) -> Option<&Span> {
        let Some((&i, rest)) = path.split_first() else {
            return Some(self);
        };
        let child = match self {
            Span::Leaf(_) => None,
            Span::Nary { children, .. } => children.get(i),
            Span::Difference(l, r) => [l, r].get(i).map(|c| &***c),
            Span::Warp(_, c) => (i == 0).then_some(&**c),
        }?;
        child.at(rest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Affine3A;

    /// The ranges of sin, cos, sinc and versinc hold dense samples of the
    /// functions and reach their extremes (critical points listed right).
    #[test]
    fn function_ranges_are_exact() {
        type Case = (fn(f32) -> f32, fn(Interval) -> Interval);
        let fs: [Case; 4] = [
            (f32::sin, |x| x.sin_range(0.0)),
            (f32::cos, |x| x.sin_range(0.5 * PI)),
            (sinc, |x| x.range_of(sinc, &SINC_CRITICAL)),
            (versinc, |x| x.range_of(versinc, &VERSINC_CRITICAL)),
        ];
        for (f, range) in &fs {
            for (a, w) in [(-14.5, 29.0), (-3.0, 1.0), (0.3, 4.5), (-7.0, 5.0), (2.0, 0.01), (-0.01, 0.02)] {
                let x = Interval::new(a, a + w);
                let r = range(x);
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for i in 0..=20000 {
                    let v = f(x.lo + x.width() * i as f32 / 20000.0);
                    (lo, hi) = (lo.min(v), hi.max(v));
                }
                assert!(r.lo <= lo + 1e-6 && r.hi >= hi - 1e-6, "{x:?}: {r:?} vs [{lo}, {hi}]");
                assert!(r.lo >= lo - 1e-4 && r.hi <= hi + 1e-4, "{x:?}: {r:?} vs [{lo}, {hi}]");
            }
        }
    }

    /// A bend's image box for a narrower parameter range lies inside the
    /// box for a wider one (what makes swept bounds hold each instant's).
    #[test]
    fn bend_images_nest() {
        let child = Aabb::new(Vec3::new(-0.5, -1.3, -0.4), Vec3::new(0.6, 1.2, 0.9));
        let inner = Aabb::new(Vec3::new(-0.4, -1.1, -0.3), Vec3::new(0.5, 1.0, 0.8));
        let wide = bend_image(
            Interval::new(0.0, 0.5),
            Interval::new(-0.1, 0.1),
            Interval::new(-0.9, -0.7),
            Interval::new(0.7, 0.9),
            &child,
        );
        for i in 0..=10 {
            let u = i as f32 / 10.0;
            let p = Interval::point;
            let narrow =
                bend_image(p(0.5 * u), p(0.2 * u - 0.1), p(-0.9 + 0.2 * u), p(0.9 - 0.2 * u), &inner);
            assert!(
                wide.expanded(1e-5).contains(narrow.min) && wide.expanded(1e-5).contains(narrow.max),
                "{narrow:?} vs {wide:?}"
            );
        }
    }

    /// Bends with parameters drawn from the ranges map sample points of the
    /// child box into the range's image box, including rates through 0.
    #[test]
    fn bend_ranges_hold_every_bend() {
        let child = Aabb::new(Vec3::new(-0.5, -1.3, -0.4), Vec3::new(0.6, 1.2, 0.9));
        let cases = [
            (Interval::new(-0.02, 0.03), Interval::point(0.0), Interval::point(-0.8), Interval::point(0.8)),
            (
                Interval::new(0.5, 0.9),
                Interval::new(0.1, 0.2),
                Interval::new(-0.9, -0.6),
                Interval::new(0.7, 1.0),
            ),
            (Interval::point(-1.2), Interval::point(0.3), Interval::point(-1.0), Interval::point(1.2)),
            (Interval::point(0.0), Interval::point(0.0), Interval::point(-0.5), Interval::point(0.5)),
        ];
        for (k, y0, lo, hi) in cases {
            let image = bend_image(k, y0, lo, hi, &child).expanded(1e-5);
            for n in 0..6 {
                let u = n as f32 / 5.0;
                let w = Warp::bend(
                    k.lo + (k.hi - k.lo) * u,
                    y0.lo + (y0.hi - y0.lo) * (1.0 - u),
                    lo.lo + (lo.hi - lo.lo) * u,
                    hi.lo + (hi.hi - hi.lo) * (1.0 - u),
                );
                for i in 0..=8 {
                    for j in 0..=8 {
                        for l in 0..=8 {
                            let f = Vec3::new(i as f32, j as f32, l as f32) / 8.0;
                            let p = child.min + (child.max - child.min) * f;
                            assert!(
                                image.contains(w.forward(p)),
                                "{w:?}: {} outside {image:?}",
                                w.forward(p)
                            );
                        }
                    }
                }
            }
        }
    }

    /// Ranges of twists, tapers and bends about interpolated axes hold the
    /// warped child box's samples for every warp they stand for: blends of
    /// two exact warps over sub-intervals of `s`, and blends of two such
    /// blends (ranges with spreads, as de Casteljau levels make), for
    /// axes a quarter turn, nearly opposite and exactly opposite apart.
    #[test]
    fn axis_ranges_hold_every_blended_warp() {
        let child = Aabb::new(Vec3::new(-0.5, -0.7, -0.4), Vec3::new(0.6, 0.8, 0.5));
        let corners = |w: &Warp| {
            let mut v = Vec::new();
            for i in 0..=4 {
                for j in 0..=4 {
                    for k in 0..=4 {
                        let f = Vec3::new(i as f32, j as f32, k as f32) / 4.0;
                        v.push(w.forward(child.min + (child.max - child.min) * f));
                    }
                }
            }
            v
        };
        let bend = |rate: f32, axis: Vec3, along: Vec3| Warp::Bend {
            rate,
            centre: 0.1,
            min: -0.8,
            max: 0.8,
            axis,
            along,
        };
        let triples = [
            (
                Warp::Twist { rate: 1.5, axis: Vec3::Z },
                Warp::Twist { rate: -1.0, axis: Vec3::X },
                Warp::Twist { rate: 0.5, axis: Vec3::new(0.0, 1.0, 0.2) },
            ),
            (
                Warp::Taper { slope: 0.4, axis: Vec3::new(0.0, 0.1, -1.0) },
                Warp::Taper { slope: -0.5, axis: Vec3::new(0.0, 0.0, 1.0) },
                Warp::Taper { slope: 0.2, axis: -Vec3::Z },
            ),
            (
                bend(0.8, Vec3::Z, Vec3::Y),
                bend(-0.5, Vec3::X, Vec3::Z),
                bend(0.3, Vec3::Y, Vec3::new(1.0, 0.0, 1.0)),
            ),
        ];
        for (wa, wb, wc) in triples {
            let exact = |w: &Warp| WarpRange::exact(w).unwrap();
            for k in 0..4 {
                let s = Interval { lo: k as f32 / 4.0, hi: (k + 1) as f32 / 4.0 };
                let ab = WarpRange::lerp(&exact(&wa), &exact(&wb), s).unwrap();
                let bc = WarpRange::lerp(&exact(&wb), &exact(&wc), s).unwrap();
                let abc = WarpRange::lerp(&ab, &bc, s).unwrap();
                let (b1, b2) = (ab.image(&child).expanded(1e-5), abc.image(&child).expanded(1e-5));
                for i in 0..=6 {
                    let t = s.lo + s.width() * i as f32 / 6.0;
                    let w1 = wa.lerp(&wb, t).unwrap();
                    let w2 = w1.lerp(&wb.lerp(&wc, t).unwrap(), t).unwrap();
                    for p in corners(&w1) {
                        assert!(b1.contains(p), "{w1:?}: {p} outside {b1:?}");
                    }
                    for p in corners(&w2) {
                        assert!(b2.contains(p), "{w2:?}: {p} outside {b2:?}");
                    }
                }
            }
        }
    }

    /// Slerped frames over an interval, and blends of two such ranges, hold
    /// the images of box corners under the maps they stand for.
    #[test]
    fn frame_ranges_hold_their_maps() {
        let pa = AffineParts::from_affine(&Affine3A::from_scale_rotation_translation(
            Vec3::new(1.0, 1.5, 0.7),
            Quat::from_rotation_y(0.3),
            Vec3::new(0.1, 0.2, -0.3),
        ))
        .unwrap();
        let pb = AffineParts::from_affine(&Affine3A::from_scale_rotation_translation(
            Vec3::new(0.8, 1.0, 1.2),
            Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.2).normalize(), 2.0),
            Vec3::new(-0.4, 0.5, 0.3),
        ))
        .unwrap();
        let pc = AffineParts::from_affine(&Affine3A::from_rotation_z(-1.0)).unwrap();
        let local = Aabb::new(Vec3::new(-0.3, -0.2, -0.5), Vec3::new(0.4, 0.1, 0.6));
        for k in 0..8 {
            let s = Interval { lo: k as f32 / 8.0, hi: (k + 1) as f32 / 8.0 };
            let ab = FrameRange::lerp(&FrameRange::exact(&pa), &FrameRange::exact(&pb), s);
            let bc = FrameRange::lerp(&FrameRange::exact(&pb), &FrameRange::exact(&pc), s);
            let abc = FrameRange::lerp(&ab, &bc, s);
            let (b1, b2) = (ab.apply(&local).expanded(1e-5), abc.apply(&local).expanded(1e-5));
            for i in 0..=10 {
                let t = s.lo + s.width() * i as f32 / 10.0;
                let m1 = pa.lerp(&pb, t);
                let m2 = m1.lerp(&pb.lerp(&pc, t), t);
                for c in local.corners() {
                    assert!(b1.contains(m1.to_affine().transform_point3(c)), "t = {t}");
                    assert!(b2.contains(m2.to_affine().transform_point3(c)), "t = {t}");
                }
            }
        }
    }
}
