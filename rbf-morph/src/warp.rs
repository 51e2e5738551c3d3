//! Warping combined with shape transformation (paper appendix, eq. 4–5).

use crate::error::RbfError;
use crate::interpolant::{Constraint, FitSettings, Interpolant};
use crate::slice::{Slice2, Slice3, sample_lattice};
use crate::transform::{
    ContourMorph, RbfMorph, RbfSettings, TransformSettings, frame_lattice, surface_constraints,
};
use glam::{Mat2, Mat3, Vec2, Vec3};
use isomorph_common::check_time;
use isomorph_common::marching_squares::{Polyline2, marching_squares};
use isomorph_common::{Aabb, Control, Field3, Frame, Grid2, Landmarks, Morph, MorphReport, Solid, Stages};
use rayon::prelude::*;
use std::sync::Arc;

/// A displacement warp `x ↦ w(x)` of `N`-dimensional space: one variational
/// interpolant per coordinate through prescribed displacements.
#[derive(Debug, Clone)]
pub struct DisplacementWarp<const N: usize> {
    components: Vec<Interpolant<N>>,
}

impl<const N: usize> DisplacementWarp<N> {
    /// The warp with `w(points[i]) = displacements[i]` (world units).
    ///
    /// # Errors
    /// [`RbfError::CorrespondenceCount`] when the lengths differ,
    /// [`RbfError::NonFinite`] (`what = "correspondence"`) for a NaN or
    /// infinite coordinate, [`RbfError::TooFewCorrespondences`] for fewer
    /// than `N + 1` points, and the errors of [`Interpolant::fit`] (e.g.
    /// [`RbfError::NotUnisolvent`] for points all on one hyperplane,
    /// [`RbfError::NearDuplicate`] for one point with two displacements).
    pub fn new(points: &[[f32; N]], displacements: &[[f32; N]], fit: &FitSettings) -> Result<Self, RbfError> {
        check_pairs(points, displacements)?;
        let components = (0..N)
            .map(|k| {
                let cs: Vec<Constraint<N>> =
                    points.iter().zip(displacements).map(|(p, d)| Constraint::new(*p, d[k])).collect();
                Interpolant::fit(&cs, fit)
            })
            .collect::<Result<_, _>>()?;
        Ok(Self { components })
    }

    /// The displacement `w(p)`.
    pub fn displacement(&self, p: [f32; N]) -> [f32; N] {
        std::array::from_fn(|k| self.components[k].value(p))
    }

    /// `x + amount · w(x)` for every constraint position `x` (values kept).
    pub fn displace(&self, constraints: &[Constraint<N>], amount: f32) -> Vec<Constraint<N>> {
        constraints
            .par_iter()
            .map(|c| {
                let w = self.displacement(c.position);
                Constraint::new(std::array::from_fn(|k| c.position[k] + amount * w[k]), c.value)
            })
            .collect()
    }

    /// The Jacobian `∂w_k/∂x_j` at `p`, row `k`.
    pub fn jacobian(&self, p: [f32; N]) -> [[f32; N]; N] {
        std::array::from_fn(|k| self.components[k].gradient_f64(p.map(f64::from)).map(|v| v as f32))
    }
}

impl DisplacementWarp<3> {
    /// The warp `W(x) = x + w(x)` through landmark pairs, `W(pᵢ) = qᵢ`
    /// (the appendix's displacement warp with its affine part): the
    /// generalized warp of Breen & Whitaker §6.2 built from the user's
    /// correspondences.
    ///
    /// # Errors
    /// [`DisplacementWarp::new`]'s (the landmarks are already validated).
    pub fn from_landmarks(landmarks: &Landmarks, fit: &FitSettings) -> Result<Self, RbfError> {
        let (points, displacements): (Vec<[f32; 3]>, Vec<[f32; 3]>) =
            landmarks.pairs().iter().map(|&(p, q)| (p.to_array(), (q - p).to_array())).unzip();
        Self::new(&points, &displacements, fit)
    }

    /// The warped point `W(x) = x + w(x)`.
    pub fn apply(&self, x: Vec3) -> Vec3 {
        x + Vec3::from_array(self.displacement(x.to_array()))
    }
}

/// Equal lengths, finite coordinates, at least `N + 1` pairs.
fn check_pairs<const N: usize>(first: &[[f32; N]], second: &[[f32; N]]) -> Result<(), RbfError> {
    if first.len() != second.len() {
        return Err(RbfError::CorrespondenceCount { on_source: first.len(), on_target: second.len() });
    }
    if let Some(index) = first.iter().zip(second).position(|(p, q)| !p.iter().chain(q).all(|x| x.is_finite()))
    {
        return Err(RbfError::NonFinite { index, what: "correspondence" });
    }
    if first.len() < N + 1 {
        return Err(RbfError::TooFewCorrespondences { got: first.len(), needed: N + 1, dim: N });
    }
    Ok(())
}

/// The two half-way warps of the appendix: `w_A` on shape A (the source),
/// `w_B` on shape B (the target).
#[derive(Debug, Clone)]
pub struct HalfwayWarps<const N: usize> {
    source: DisplacementWarp<N>,
    target: DisplacementWarp<N>,
}

impl<const N: usize> HalfwayWarps<N> {
    /// `w_A(a_i) = (b_i − a_i)/2` and `w_B(b_i) = (a_i − b_i)/2` for the
    /// corresponding points `on_source[i] = a_i`, `on_target[i] = b_i`.
    ///
    /// # Errors
    /// As [`DisplacementWarp::new`].
    pub fn new(on_source: &[[f32; N]], on_target: &[[f32; N]], fit: &FitSettings) -> Result<Self, RbfError> {
        check_pairs(on_source, on_target)?;
        let half = |from: &[[f32; N]], to: &[[f32; N]]| -> Vec<[f32; N]> {
            from.iter().zip(to).map(|(a, b)| std::array::from_fn(|k| 0.5 * (b[k] - a[k]))).collect()
        };
        Ok(Self {
            source: DisplacementWarp::new(on_source, &half(on_source, on_target), fit)?,
            target: DisplacementWarp::new(on_target, &half(on_target, on_source), fit)?,
        })
    }

    /// `w_A`, taking the source half-way to the target.
    pub fn source(&self) -> &DisplacementWarp<N> {
        &self.source
    }

    /// `w_B`, taking the target half-way to the source.
    pub fn target(&self) -> &DisplacementWarp<N> {
        &self.target
    }

    /// The unwarping of eq. 4–5 at morph time `τ ∈ [0, 1]`: the warp and the
    /// amount with `u(x, τ) = x + amount · w(x)`.
    pub fn unwarp_at(&self, tau: f32) -> (&DisplacementWarp<N>, f32) {
        if tau <= 0.5 { (&self.source, 1.0 - 2.0 * tau) } else { (&self.target, 2.0 * tau - 1.0) }
    }
}

/// Shape transformation between two 3D shapes with feature alignment by
/// warping (appendix): the 4D implicit is fitted between the half-way warped
/// shapes and its slices are unwarped. Implements [`Morph`]; frame 0 is the
/// source and frame 1 the target.
///
/// From user correspondences `a_i ↔ b_i` two displacement warps are fitted
/// by variational interpolation, one per coordinate: `w_A(a_i) = (b_i − a_i)/2`
/// takes shape A half-way to B and `w_B(b_i) = (a_i − b_i)/2` takes B
/// half-way to A. The constraints of A are displaced by `w_A`, those of B by
/// `w_B`, and the shape transformation is fitted between the warped shapes
/// (the paper's Fig. 9, top row). The frames are then unwarped: with morph
/// time `τ ∈ [0, 1]` (the paper's `t = 2τ` for `t_max = 2`), the frame is
/// `G(x, τ) = F(u(x, τ), τ)` with
///
/// ```text
/// u(x, τ) = x + (1 − 2τ) w_A(x)   for τ ≤ ½      (eq. 4)
/// u(x, τ) = x + (2τ − 1) w_B(x)   for τ > ½      (eq. 5)
/// ```
///
/// so `τ = 0` undoes the warp of A (the frame is A), `τ = 1` undoes that of
/// B, and the middle frame is not warped. A feature `a_i ↔ b_i` travels from
/// `a_i` to the midpoint `(a_i + b_i)/2` at `τ = ½` and on to `b_i`.
///
/// Choice where the paper leaves it open: the paper displaces the boundary
/// constraints; here the normal constraints are displaced by the same warp,
/// so that they stay inside the warped boundary (the warp is smooth, so a
/// small inward offset stays inward).
///
/// ```
/// use glam::Vec3;
/// use isomorph_common::{Aabb, Field3, Morph, Shape};
/// use isomorph_rbf::constraints::{field_constraints, NormalOffset, Subsample, SurfaceSettings};
/// use isomorph_rbf::WarpedMorph;
/// use isomorph_rbf::TransformSettings;
///
/// let s = SurfaceSettings { offset: NormalOffset::Absolute(0.01), subsample: Subsample::FarthestPoint(40) };
/// let shift = Vec3::X * 0.3;
/// let a = field_constraints(&Shape::sphere(0.2), &Aabb::cube(0.5), 16, &s)?;
/// let b = field_constraints(&Shape::sphere(0.2).translated(shift), &Aabb::cube(0.6), 16, &s)?;
/// // The poles of A correspond to those of B.
/// let on_a = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|d| d * 0.2);
/// let on_b = on_a.map(|p| p + shift);
/// let settings = TransformSettings { separation: 0.2, ..Default::default() };
/// let morph = WarpedMorph::from_constraints(&a, &b, &on_a, &on_b, &settings)?;
/// // Half-way, the sphere is half-way: its centre is at 0.15, its pole
/// // (0.2, 0, 0) near 0.35 (the in-between sphere bulges slightly).
/// let mid = morph.frame(0.5)?.field;
/// assert!(mid.value(Vec3::X * 0.15) > 0.0);
/// assert!(mid.value(Vec3::X * 0.33) > 0.0 && mid.value(Vec3::X * 0.39) < 0.0);
/// assert!(mid.value(-Vec3::X * 0.03) > 0.0 && mid.value(-Vec3::X * 0.09) < 0.0);
/// # Ok::<(), isomorph_rbf::RbfError>(())
/// ```
#[derive(Debug, Clone)]
pub struct WarpedMorph {
    warped: RbfMorph,
    warps: Arc<HalfwayWarps<3>>,
    bounds: Aabb,
    report: MorphReport,
}

/// Settings of [`WarpedMorph::new`]: those of the plain transformation and
/// the user's correspondences.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WarpedSettings {
    /// Sampling and fit of the shapes, as for [`RbfMorph::new`].
    pub rbf: RbfSettings,
    /// Corresponding points `(on the source, on the target)` in world units;
    /// at least 4, not all on one plane.
    pub correspondences: Vec<(Vec3, Vec3)>,
}

impl WarpedMorph {
    /// The contract's constructor: samples both solids' surface constraints
    /// as [`RbfMorph::new`] does, then fits the half-way warps from
    /// `settings.correspondences` and the 4D implicit between the warped
    /// shapes ([`WarpedMorph::from_constraints`]).
    ///
    /// ```
    /// use glam::Vec3;
    /// use isomorph_common::{Control, Field3, Morph, Shape, Solid};
    /// use isomorph_rbf::{RbfSettings, WarpedMorph, WarpedSettings};
    ///
    /// let shift = Vec3::X * 0.5;
    /// let a = Solid::shape(Shape::sphere(0.2));
    /// let b = Solid::shape(Shape::sphere(0.2).translated(shift));
    /// let poles = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|d| d * 0.2);
    /// let settings = WarpedSettings {
    ///     rbf: RbfSettings { points: 100, ..Default::default() },
    ///     correspondences: poles.iter().map(|&p| (p, p + shift)).collect(),
    /// };
    /// let morph = WarpedMorph::new(&a, &b, &settings, &Control::new())?;
    /// // Half-way the sphere has slid half-way (the plain transformation
    /// // blends two spheres in place instead).
    /// assert!(morph.frame(0.5)?.field.value(shift * 0.5) > 0.0);
    /// # Ok::<(), isomorph_rbf::RbfError>(())
    /// ```
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting),
    /// [`RbfError::TooFewCorrespondences`] and [`RbfError::NonFinite`] before
    /// any work, [`MorphError::Cancelled`](isomorph_common::MorphError::Cancelled),
    /// the solids' conversion errors, and those of
    /// [`WarpedMorph::from_constraints`].
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &WarpedSettings,
        control: &Control,
    ) -> Result<Self, RbfError> {
        settings.rbf.validate()?;
        let (on_source, on_target): (Vec<Vec3>, Vec<Vec3>) = settings.correspondences.iter().copied().unzip();
        let arrays = |p: &[Vec3]| p.iter().map(|v| v.to_array()).collect::<Vec<_>>();
        check_pairs(&arrays(&on_source), &arrays(&on_target))?;
        let warnings = isomorph_common::validate_inputs(source, target, control)?;
        control.install(|| {
            let mut stages = Stages::start();
            let [a, b] = surface_constraints(source, target, &settings.rbf, control)?;
            stages.lap("constraints");
            control.progress("fit", None, || {
                format!("{} constraints in 4D, {} correspondences", a.len() + b.len(), on_source.len())
            });
            let mut morph =
                Self::from_constraints(&a, &b, &on_source, &on_target, &settings.rbf.transform())?;
            control.check()?;
            stages.lap("fit");
            morph.report = morph.report.with_stages(stages).with_warnings(warnings);
            Ok(morph)
        })
    }

    /// Fits the warps from the corresponding points `on_source[i] ↔
    /// on_target[i]` (with [`TransformSettings::fit`]), displaces the
    /// constraints of each shape half-way, and fits the 4D implicit between
    /// the warped shapes (the paper-level constructor: constraints made by
    /// the caller).
    ///
    /// # Errors
    /// Those of [`HalfwayWarps::new`] and [`RbfMorph::from_constraints`].
    pub fn from_constraints(
        source: &[Constraint<3>],
        target: &[Constraint<3>],
        on_source: &[Vec3],
        on_target: &[Vec3],
        settings: &TransformSettings,
    ) -> Result<Self, RbfError> {
        let arrays = |p: &[Vec3]| p.iter().map(|v| v.to_array()).collect::<Vec<_>>();
        let warps = HalfwayWarps::new(&arrays(on_source), &arrays(on_target), &settings.fit)?;
        let warped = RbfMorph::from_constraints(
            &warps.source().displace(source, 1.0),
            &warps.target().displace(target, 1.0),
            settings,
        )?;
        let inputs: Vec<Vec3> = source.iter().chain(target).map(|c| Vec3::from_array(c.position)).collect();
        let inputs = Aabb::from_points(&inputs);
        let bounds = inputs.expanded(settings.margin * inputs.diagonal()).union(&warped.field_bounds());
        let mut report = warped.report().clone();
        report.method = "rbf-warp";
        report = report.with_detail("correspondences", on_source.len());
        Ok(Self { warped, warps: Arc::new(warps), bounds, report })
    }

    /// The transformation between the warped shapes, before unwarping (the
    /// paper's Fig. 9, top row).
    pub fn warped(&self) -> &RbfMorph {
        &self.warped
    }

    /// The two half-way warps.
    pub fn warps(&self) -> &HalfwayWarps<3> {
        &self.warps
    }

    /// The unwarped frame at morph time `t ∈ [0, 1]`.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`](isomorph_common::MorphError::InvalidTime) for NaN or `t ∉ [0, 1]`.
    pub fn slice(&self, t: f32) -> Result<WarpedSlice, RbfError> {
        let t = check_time(t)?;
        Ok(WarpedSlice {
            slice: self.warped.slice(t)?,
            warps: Arc::clone(&self.warps),
            tau: t,
            bounds: self.bounds,
        })
    }
}

impl Morph for WarpedMorph {
    type Field = WarpedSlice;
    type Error = RbfError;

    fn method(&self) -> &'static str {
        "rbf-warp"
    }

    fn frame(&self, t: f32) -> Result<Frame<WarpedSlice>, RbfError> {
        Ok(Frame { field: self.slice(t)?, iso: 0.0, transform: glam::Affine3A::IDENTITY })
    }

    fn field_bounds(&self) -> Aabb {
        self.bounds
    }

    fn world_bounds(&self) -> Aabb {
        self.bounds
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }
}

/// An unwarped frame `G(x) = F(u(x, τ), τ)` of a [`WarpedMorph`]: a
/// [`Field3`], positive inside, surface at 0, with the chain-rule gradient.
#[derive(Debug, Clone)]
pub struct WarpedSlice {
    slice: Slice3,
    warps: Arc<HalfwayWarps<3>>,
    tau: f32,
    bounds: Aabb,
}

impl WarpedSlice {
    /// `u(p, τ)`: where `p` of the frame sits in the warped morph's slice.
    pub fn unwarp(&self, p: Vec3) -> Vec3 {
        let (warp, amount) = self.warps.unwarp_at(self.tau);
        p + amount * Vec3::from_array(warp.displacement(p.to_array()))
    }
}

impl Field3 for WarpedSlice {
    fn value(&self, p: Vec3) -> f32 {
        self.slice.value(self.unwarp(p))
    }

    /// `∇G(p) = (I + amount · Dw(p))ᵀ ∇F(u(p))`.
    fn gradient(&self, p: Vec3) -> Vec3 {
        let (warp, amount) = self.warps.unwarp_at(self.tau);
        let jacobian = Mat3::from_cols_array_2d(&warp.jacobian(p.to_array())).transpose();
        (Mat3::IDENTITY + amount * jacobian).transpose() * self.slice.gradient(self.unwarp(p))
    }

    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        let moved: Vec<Vec3> = points.par_iter().map(|&p| self.unwarp(p)).collect();
        self.slice.values(&moved, out);
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(self.bounds)
    }
}

/// Shape transformation between two 2D shapes with feature alignment by
/// warping — the appendix as the paper describes it (Fig. 9: X → O): the 3D
/// implicit is fitted between the half-way warped shapes
/// ([`WarpedContourMorph::warped`], Fig. 9 top row) and its slices are
/// unwarped (bottom row).
///
/// ```
/// use glam::Vec2;
/// use isomorph_rbf::WarpedContourMorph;
/// use isomorph_rbf::{Constraint, TransformSettings};
///
/// // A circle of radius 0.2 (boundary 0, centre 1), and the same moved by 0.3.
/// let circle = |c: Vec2| -> Vec<Constraint<2>> {
///     let mut cs: Vec<_> = (0..24)
///         .map(|i| {
///             let p = c + 0.2 * Vec2::from_angle(i as f32 * std::f32::consts::TAU / 24.0);
///             Constraint::new(p.to_array(), 0.0)
///         })
///         .collect();
///     cs.push(Constraint::new(c.to_array(), 1.0));
///     cs
/// };
/// let shift = Vec2::new(0.3, 0.0);
/// let on_a = [Vec2::X, Vec2::Y, -Vec2::X, -Vec2::Y].map(|d| 0.2 * d);
/// let on_b = on_a.map(|p| p + shift);
/// let settings = TransformSettings { separation: 0.2, ..Default::default() };
/// let morph = WarpedContourMorph::new(&circle(Vec2::ZERO), &circle(shift), &on_a, &on_b, &settings)?;
/// // Half-way the circle is centred half-way.
/// let mid = morph.slice(0.5)?;
/// assert!(mid.value(Vec2::new(0.15, 0.0)) > 0.0);
/// assert!(mid.value(Vec2::new(0.32, 0.0)) > 0.0 && mid.value(Vec2::new(0.4, 0.0)) < 0.0);
/// # Ok::<(), isomorph_rbf::RbfError>(())
/// ```
#[derive(Debug, Clone)]
pub struct WarpedContourMorph {
    warped: ContourMorph,
    warps: Arc<HalfwayWarps<2>>,
    lo: Vec2,
    hi: Vec2,
}

impl WarpedContourMorph {
    /// Fits the warps from the corresponding points `on_source[i] ↔
    /// on_target[i]` (with [`TransformSettings::fit`]), displaces the
    /// constraints of each shape half-way, and fits the 3D implicit between
    /// the warped shapes.
    ///
    /// # Errors
    /// Those of [`HalfwayWarps::new`] and [`ContourMorph::new`].
    pub fn new(
        source: &[Constraint<2>],
        target: &[Constraint<2>],
        on_source: &[Vec2],
        on_target: &[Vec2],
        settings: &TransformSettings,
    ) -> Result<Self, RbfError> {
        let arrays = |p: &[Vec2]| p.iter().map(|v| v.to_array()).collect::<Vec<_>>();
        let warps = HalfwayWarps::new(&arrays(on_source), &arrays(on_target), &settings.fit)?;
        let warped = ContourMorph::new(
            &warps.source().displace(source, 1.0),
            &warps.target().displace(target, 1.0),
            settings,
        )?;
        let (mut lo, mut hi) = warped.bounds();
        let inputs = source.iter().chain(target).map(|c| Vec2::from_array(c.position));
        let (in_lo, in_hi) = inputs.fold((lo, hi), |(l, h), p| (l.min(p), h.max(p)));
        let pad = settings.margin * (in_hi - in_lo).length();
        (lo, hi) = (lo.min(in_lo - pad), hi.max(in_hi + pad));
        Ok(Self { warped, warps: Arc::new(warps), lo, hi })
    }

    /// The transformation between the warped shapes, before unwarping (the
    /// paper's Fig. 9, top row).
    pub fn warped(&self) -> &ContourMorph {
        &self.warped
    }

    /// The two half-way warps.
    pub fn warps(&self) -> &HalfwayWarps<2> {
        &self.warps
    }

    /// The box (min, max corners) containing both inputs, the warped shapes
    /// and the margin.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        (self.lo, self.hi)
    }

    /// The unwarped 2D field at morph time `t ∈ [0, 1]`.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`](isomorph_common::MorphError::InvalidTime) for NaN or `t ∉ [0, 1]`.
    pub fn slice(&self, t: f32) -> Result<WarpedSlice2, RbfError> {
        Ok(WarpedSlice2 { slice: self.warped.slice(t)?, warps: Arc::clone(&self.warps), tau: t })
    }

    /// The shape at `t` sampled over [`WarpedContourMorph::bounds`] with
    /// `res` nodes along the longer edge.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`](isomorph_common::MorphError::InvalidTime); [`MorphError::Grid`](isomorph_common::MorphError::Grid) for `res < 2`.
    pub fn frame_grid(&self, t: f32, res: u32) -> Result<Grid2<f32>, RbfError> {
        let (dims, spacing) = frame_lattice(self.lo, self.hi, res)?;
        let slice = self.slice(t)?;
        Ok(sample_lattice(dims, self.lo, spacing, |points, out| slice.values(points, out))?)
    }

    /// The contours (iso 0) of the shape at `t`, counter-clockwise around
    /// inside regions (holes clockwise).
    ///
    /// # Errors
    /// As [`WarpedContourMorph::frame_grid`].
    pub fn contours(&self, t: f32, res: u32) -> Result<Vec<Polyline2>, RbfError> {
        Ok(marching_squares(&self.frame_grid(t, res)?, 0.0))
    }
}

/// An unwarped 2D frame `G(x) = F(u(x, τ), τ)` of a [`WarpedContourMorph`]:
/// positive inside, curve at 0.
#[derive(Debug, Clone)]
pub struct WarpedSlice2 {
    slice: Slice2,
    warps: Arc<HalfwayWarps<2>>,
    tau: f32,
}

impl WarpedSlice2 {
    /// `u(p, τ)`: where `p` of the frame sits in the warped morph's slice.
    pub fn unwarp(&self, p: Vec2) -> Vec2 {
        let (warp, amount) = self.warps.unwarp_at(self.tau);
        p + amount * Vec2::from_array(warp.displacement(p.to_array()))
    }

    /// The value at `p`.
    pub fn value(&self, p: Vec2) -> f32 {
        self.slice.value(self.unwarp(p))
    }

    /// The gradient `(I + amount · Dw(p))ᵀ ∇F(u(p))` (points inward).
    pub fn gradient(&self, p: Vec2) -> Vec2 {
        let (warp, amount) = self.warps.unwarp_at(self.tau);
        let jacobian = Mat2::from_cols_array_2d(&warp.jacobian(p.to_array())).transpose();
        (Mat2::IDENTITY + amount * jacobian).transpose() * self.slice.gradient(self.unwarp(p))
    }

    /// Values at `points` into `out`, parallel.
    ///
    /// # Panics
    /// If `points` and `out` differ in length.
    pub fn values(&self, points: &[Vec2], out: &mut [f32]) {
        let moved: Vec<Vec2> = points.par_iter().map(|&p| self.unwarp(p)).collect();
        self.slice.values(&moved, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::{NormalOffset, Subsample, SurfaceSettings, field_constraints};
    use isomorph_common::Shape;
    use isomorph_common::mesh::distance::surface_distance;

    fn sphere(centre: Vec3) -> Vec<Constraint<3>> {
        let s =
            SurfaceSettings { offset: NormalOffset::Absolute(0.01), subsample: Subsample::FarthestPoint(60) };
        field_constraints(
            &Shape::sphere(0.2).translated(centre),
            &Aabb::new(centre - 0.3, centre + 0.3),
            16,
            &s,
        )
        .unwrap()
    }

    fn poles(centre: Vec3) -> Vec<Vec3> {
        [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|d| centre + 0.2 * d).to_vec()
    }

    /// Where the surface crosses the x axis on either side of the field's
    /// largest value on `[0, 0.3]` (bisection).
    fn crossings(f: &impl Field3) -> (f32, f32) {
        let centre = (0..=300)
            .map(|i| i as f32 * 0.001)
            .max_by(|a, b| f.value(Vec3::X * *a).total_cmp(&f.value(Vec3::X * *b)))
            .unwrap();
        let find = |dir: f32| {
            let (mut lo, mut hi) = (centre, centre + dir * 0.5);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if f.value(Vec3::X * mid) > 0.0 { lo = mid } else { hi = mid }
            }
            lo
        };
        (find(-1.0), find(1.0))
    }

    #[test]
    fn displacement_warp_interpolates_the_correspondences() {
        let points = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.3]];
        let moves = [[0.1, 0.0], [0.0, 0.2], [-0.1, 0.1], [0.0, 0.0], [0.3, -0.2]];
        let warp = DisplacementWarp::<2>::new(&points, &moves, &FitSettings::default()).unwrap();
        for (p, d) in points.iter().zip(&moves) {
            let got = warp.displacement(*p);
            assert!((got[0] - d[0]).abs() < 1e-6 && (got[1] - d[1]).abs() < 1e-6, "{got:?} vs {d:?}");
        }
        let moved = warp.displace(&[Constraint::new(points[4], 1.0)], 0.5);
        assert!((moved[0].position[0] - 0.65).abs() < 1e-6 && moved[0].value == 1.0);
        // Half-way warps: a_i + w_A(a_i) = b_i + w_B(b_i), the midpoint.
        let targets: Vec<[f32; 2]> =
            points.iter().zip(&moves).map(|(p, d)| [p[0] + d[0], p[1] + d[1]]).collect();
        let halfway = HalfwayWarps::new(&points, &targets, &FitSettings::default()).unwrap();
        for (a, b) in points.iter().zip(&targets) {
            let (wa, wb) = (halfway.source().displacement(*a), halfway.target().displacement(*b));
            for k in 0..2 {
                assert!((a[k] + wa[k] - (b[k] + wb[k])).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn translated_sphere_moves_along_its_correspondences() {
        let shift = Vec3::new(0.3, 0.0, 0.0);
        let (a, b) = (sphere(Vec3::ZERO), sphere(shift));
        // A small separation (§6.2): identical warped shapes stay nearly
        // identical in between (measured radius 0.21 half-way, 0.16 with t_max = 1).
        let settings = TransformSettings { separation: 0.2, ..Default::default() };
        let morph =
            WarpedMorph::from_constraints(&a, &b, &poles(Vec3::ZERO), &poles(shift), &settings).unwrap();
        // A pure translation is the warps' polynomial part: w_A ≡ shift / 2.
        let w = Vec3::from_array(morph.warps().source().displacement([0.1, -0.2, 0.05]));
        assert!(w.distance(shift * 0.5) < 1e-5, "{w}");
        // The ends reproduce A and B.
        for (t, centre) in [(0.0, Vec3::ZERO), (1.0, shift)] {
            let got = morph.frame_mesh(t, 40).unwrap();
            let want = isomorph_common::marching_cubes::polygonize(
                &Shape::sphere(0.2).translated(centre),
                &Aabb::new(centre - 0.3, centre + 0.3),
                64,
                0.0,
            )
            .unwrap();
            let d = surface_distance(&got, &want, 3000).unwrap();
            assert!(d.mean < 0.005 && d.hausdorff < 0.02, "t={t}: {d:?}");
            // The constraints themselves, exactly (f32 slice evaluation).
            let frame = morph.frame(t).unwrap().field;
            let input = if t == 0.0 { &a } else { &b };
            let worst = input.iter().map(|c| (frame.value(Vec3::from_array(c.position)) - c.value).abs());
            assert!(worst.fold(0.0, f32::max) < 2e-3, "t={t}");
        }
        // The sphere translates: its centre is at 0.3 τ and the pole
        // a = (0.2, 0, 0) ↔ b = (0.5, 0, 0) is near 0.2 + 0.3 τ (the midpoint
        // of its correspondence at τ = ½).
        for tau in [0.25f32, 0.5, 0.75] {
            let f = morph.frame(tau).unwrap().field;
            let (lo, hi) = crossings(&f);
            assert!((0.5 * (lo + hi) - 0.3 * tau).abs() < 0.005, "τ={tau}: centre {}", 0.5 * (lo + hi));
            assert!((hi - (0.2 + 0.3 * tau)).abs() < 0.015, "τ={tau}: pole at {hi}");
            // The analytic gradient matches central differences.
            let p = Vec3::new(hi, 0.05, 0.02);
            let e = 1e-3;
            let fd = Vec3::new(
                f.value(p + Vec3::X * e) - f.value(p - Vec3::X * e),
                f.value(p + Vec3::Y * e) - f.value(p - Vec3::Y * e),
                f.value(p + Vec3::Z * e) - f.value(p - Vec3::Z * e),
            ) / (2.0 * e);
            let g = f.gradient(p);
            assert!((g - fd).length() < 0.02 * g.length(), "τ={tau}: {g} vs {fd}");
        }
        // Without the warp the two spheres blend into an elongated blob
        // (measured half-length 0.27 half-way) instead of moving.
        let plain = RbfMorph::from_constraints(&a, &b, &settings).unwrap();
        let (lo, hi) = crossings(&plain.frame(0.5).unwrap().field);
        assert!(hi - lo > 0.5, "plain half-way length {}", hi - lo);
    }

    /// A circle of radius 0.2 around `c`: boundary constraints and 1 at
    /// the centre.
    fn circle(c: Vec2) -> Vec<Constraint<2>> {
        let mut cs: Vec<Constraint<2>> = (0..32)
            .map(|i| Constraint::new((c + 0.2 * Vec2::from_angle(i as f32 * 0.196_349_55)).to_array(), 0.0))
            .collect();
        cs.push(Constraint::new(c.to_array(), 1.0));
        cs
    }

    #[test]
    fn translated_circle_moves_along_its_correspondences_in_2d() {
        let shift = Vec2::new(0.3, 0.0);
        let (a, b) = (circle(Vec2::ZERO), circle(shift));
        let on_a: Vec<Vec2> = [Vec2::X, Vec2::Y, -Vec2::X, -Vec2::Y].map(|d| 0.2 * d).to_vec();
        let on_b: Vec<Vec2> = on_a.iter().map(|p| *p + shift).collect();
        let settings = TransformSettings { separation: 0.2, ..Default::default() };
        let morph = WarpedContourMorph::new(&a, &b, &on_a, &on_b, &settings).unwrap();
        // The ends reproduce the inputs' constraints, although the fitted
        // (warped) shapes are both centred half-way.
        for (t, input) in [(0.0, &a), (1.0, &b)] {
            let frame = morph.slice(t).unwrap();
            let worst = input.iter().map(|c| (frame.value(Vec2::from_array(c.position)) - c.value).abs());
            assert!(worst.fold(0.0, f32::max) < 2e-3, "t={t}");
            let warped = morph.warped().slice(t).unwrap();
            assert!(warped.value(Vec2::new(0.15, 0.0)) > 0.9, "t={t}: warped shapes are centred half-way");
        }
        // Along x the frame's curve crosses at centre ± 0.2 with the centre
        // at 0.3 τ (bisection from the centre outwards).
        for tau in [0.25f32, 0.5, 0.75] {
            let f = morph.slice(tau).unwrap();
            let centre = 0.3 * tau;
            assert!(f.value(Vec2::new(centre, 0.0)) > 0.5, "τ={tau}");
            let crossing = |dir: f32| {
                let (mut lo, mut hi) = (centre, centre + dir * 0.4);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if f.value(Vec2::new(mid, 0.0)) > 0.0 { lo = mid } else { hi = mid }
                }
                lo
            };
            let (left, right) = (crossing(-1.0), crossing(1.0));
            assert!((0.5 * (left + right) - centre).abs() < 0.005, "τ={tau}: {left} .. {right}");
            assert!((right - left - 0.4).abs() < 0.03, "τ={tau}: diameter {}", right - left);
            let p = Vec2::new(right, 0.07);
            let e = 1e-3;
            let fd = Vec2::new(
                f.value(p + Vec2::X * e) - f.value(p - Vec2::X * e),
                f.value(p + Vec2::Y * e) - f.value(p - Vec2::Y * e),
            ) / (2.0 * e);
            assert!((f.gradient(p) - fd).length() < 0.02 * fd.length(), "τ={tau}: {} vs {fd}", f.gradient(p));
        }
        assert_eq!(morph.contours(0.5, 64).unwrap().len(), 1);
        // Without the warp the two circles blend in place: half-way the
        // shape is dented or split instead of a circle at 0.15.
        let plain = ContourMorph::new(&a, &b, &settings).unwrap().slice(0.5).unwrap();
        assert!(
            plain.value(Vec2::new(0.15, 0.0)) < 0.5 * morph.slice(0.5).unwrap().value(Vec2::new(0.15, 0.0))
        );
    }

    #[test]
    fn identity_correspondences_give_the_plain_transformation() {
        let (a, b) = (sphere(Vec3::ZERO), sphere(Vec3::new(0.1, 0.05, 0.0)));
        let points = poles(Vec3::ZERO);
        let settings = TransformSettings::default();
        let warped = WarpedMorph::from_constraints(&a, &b, &points, &points, &settings).unwrap();
        let plain = RbfMorph::from_constraints(&a, &b, &settings).unwrap();
        let probe: Vec<Vec3> =
            (0..50).map(|i| Vec3::new((i as f32).sin(), (i as f32 * 1.7).cos(), 0.3) * 0.3).collect();
        for t in [0.0, 0.3, 0.5, 0.8, 1.0] {
            let (mut got, mut want) = (vec![0.0; probe.len()], vec![0.0; probe.len()]);
            warped.frame(t).unwrap().field.values(&probe, &mut got);
            plain.frame(t).unwrap().field.values(&probe, &mut want);
            assert_eq!(got, want, "t={t}");
        }
    }

    #[test]
    fn bad_correspondences_are_typed_errors() {
        let a = sphere(Vec3::ZERO);
        let s = TransformSettings::default();
        let p = poles(Vec3::ZERO);
        assert!(matches!(
            WarpedMorph::from_constraints(&a, &a, &p, &p[..5], &s),
            Err(RbfError::CorrespondenceCount { on_source: 6, on_target: 5 })
        ));
        let mut nan = p.clone();
        nan[2].y = f32::NAN;
        assert!(matches!(
            WarpedMorph::from_constraints(&a, &a, &p, &nan, &s),
            Err(RbfError::NonFinite { what: "correspondence", .. })
        ));
        assert!(matches!(
            WarpedMorph::from_constraints(&a, &a, &p[..3], &p[..3], &s),
            Err(RbfError::TooFewCorrespondences { got: 3, needed: 4, dim: 3 })
        ));
        // Four points in one plane do not determine a 3D warp.
        let flat = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE.with_z(0.0)];
        assert!(matches!(
            WarpedMorph::from_constraints(&a, &a, &flat, &flat, &s),
            Err(RbfError::NotUnisolvent { .. })
        ));
        let m = WarpedMorph::from_constraints(&a, &a, &p, &p, &s).unwrap();
        assert!(matches!(m.frame(-0.1), Err(RbfError::Morph(isomorph_common::MorphError::InvalidTime(_)))));
    }
}
