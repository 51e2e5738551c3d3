//! Shape transformation (paper §5): the constraints of shape A placed at
//! `t = 0` and those of shape B at `t = t_max` in one higher dimension, one
//! variational interpolation, and the in-between shapes as slices.

use crate::constraints::{NormalOffset, Subsample, SurfaceSettings, mesh_constraints};
use crate::error::RbfError;
use crate::greedy::{Centres, GreedySettings};
use crate::interpolant::{Constraint, FitSettings, Interpolant};
use crate::slice::{Slice2, Slice3};
use crate::{Factorization, Kernel};
use glam::{UVec2, Vec2, Vec3};
use isomorph_common::MorphError;
use isomorph_common::marching_squares::{Polyline2, marching_squares};
use isomorph_common::{
    Aabb, Control, Frame, Grid2, Morph, MorphReport, Outcome, Residual, Solid, Stages, TriMesh,
};
use isomorph_common::{check, check_time};

/// Settings of a shape transformation.
#[derive(Debug, Clone, PartialEq)]
pub struct TransformSettings {
    /// The fit (kernel, smoothing, duplicates).
    pub fit: FitSettings,
    /// The separation `t_max` of the two shapes along the new axis (default
    /// 1, in the shapes' world units).
    pub separation: f32,
    /// Margin added around the union of the inputs' bounding boxes for
    /// [`Morph::field_bounds`], as a fraction of its diagonal (default 0.1):
    /// in-between shapes may bulge beyond both inputs.
    pub margin: f32,
}

impl Default for TransformSettings {
    fn default() -> Self {
        Self { fit: FitSettings::default(), separation: 1.0, margin: 0.1 }
    }
}

/// Constraints of `N` dimensions lifted to `M = N + extra.len()` dimensions
/// by appending the coordinates `extra` (an embedding into a higher space).
///
/// # Panics
/// If `M != N + extra.len()` (a programming error, not user input).
pub fn lift<const N: usize, const M: usize>(
    constraints: &[Constraint<N>],
    extra: &[f32],
) -> Vec<Constraint<M>> {
    assert_eq!(M, N + extra.len(), "lift: {N} + {} coordinates do not make {M}", extra.len());
    constraints
        .iter()
        .map(|c| {
            Constraint::new(
                std::array::from_fn(|k| if k < N { c.position[k] } else { extra[k - N] }),
                c.value,
            )
        })
        .collect()
}

/// Fits one `M`-dimensional interpolant through `N`-dimensional shapes
/// placed at the given extra coordinates.
fn fit_embedded<const N: usize, const M: usize>(
    shapes: &[(&[Constraint<N>], &[f32], &'static str)],
    fit: &FitSettings,
) -> Result<Interpolant<M>, RbfError> {
    let mut all = Vec::new();
    for (cs, at, name) in shapes {
        if cs.is_empty() {
            return Err(RbfError::EmptyShape(name));
        }
        all.extend(lift::<N, M>(cs, at));
    }
    Interpolant::fit(&all, fit)
}

/// Checks the settings, fits source at `t = 0` and target at `t = t_max`,
/// and returns the interpolant with the inputs' box grown by the margin.
fn fit_pair<const N: usize, const M: usize>(
    source: &[Constraint<N>],
    target: &[Constraint<N>],
    settings: &TransformSettings,
) -> Result<(Interpolant<M>, [f32; N], [f32; N]), RbfError> {
    check_separation(settings)?;
    let interpolant = fit_embedded::<N, M>(
        &[(source, &[0.0], "source"), (target, &[settings.separation], "target")],
        &settings.fit,
    )?;
    let (mut lo, mut hi) = ([f32::INFINITY; N], [f32::NEG_INFINITY; N]);
    for c in source.iter().chain(target) {
        for k in 0..N {
            lo[k] = lo[k].min(c.position[k]);
            hi[k] = hi[k].max(c.position[k]);
        }
    }
    let margin = settings.margin * (0..N).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f32>().sqrt();
    Ok((interpolant, lo.map(|v| v - margin), hi.map(|v| v + margin)))
}

fn check_separation(settings: &TransformSettings) -> Result<(), RbfError> {
    if !(settings.separation > 0.0 && settings.separation.is_finite()) {
        return Err(MorphError::bad_setting("separation", settings.separation, "a finite number > 0").into());
    }
    if !(settings.margin >= 0.0 && settings.margin.is_finite()) {
        return Err(MorphError::bad_setting("margin", settings.margin, "a finite number ≥ 0").into());
    }
    Ok(())
}

/// Most surface points per shape for an exact fit: `4 · points` = 100000
/// constraints, which the hierarchical solver (`Solver::Auto` from 4000
/// constraints) fits in under 2 GB.
const MOST_POINTS: u64 = 25_000;

/// Most surface points per shape with greedy centres.
const MOST_GREEDY_POINTS: u64 = 250_000;

/// Settings of [`RbfMorph::new`]: how many surface points of each solid
/// become constraints, and the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct RbfSettings {
    /// Surface points per shape, chosen by farthest-point sampling (each
    /// gives a boundary and a normal constraint: `4 · points` constraints in
    /// all; 8–25000, or up to 250000 with a [`RbfSettings::tolerance`];
    /// default 400). The exact fit costs `O(points³)`.
    pub points: usize,
    /// The separation `t_max` of the shapes along the fourth axis, in world
    /// units (paper §6.2: small keeps local features, large lets the global
    /// shape lead; > 0, default 1).
    pub separation: f32,
    /// The radial basis function (default `r² log r`, eq. 2).
    pub kernel: Kernel,
    /// Inward offset of the normal constraints as a fraction of each
    /// shape's bounding-box diagonal (§4.2's `k`; (0, 0.2], default 0.01).
    pub normal_offset: f32,
    /// Nodes along the longest edge of the grid on which non-mesh solids
    /// are polygonized to find their surface points (16–1024, default 64).
    pub surface_resolution: u32,
    /// Margin around both shapes' boxes for [`Morph::field_bounds`], as a
    /// fraction of the union's diagonal (0–2, default 0.1): in-between
    /// shapes may bulge beyond both inputs.
    pub margin: f32,
    /// Fit to this tolerance through greedily chosen centres (FastRBF's
    /// "fit to an accuracy", [`Centres::Greedy`]) instead of interpolating
    /// every constraint: relative to the normal constraints' value, from
    /// 1e-3 to 1. With it, `points` may go up to 250000 per shape. Default
    /// `None` (exact).
    pub tolerance: Option<f64>,
}

impl Default for RbfSettings {
    fn default() -> Self {
        Self {
            points: 400,
            separation: 1.0,
            kernel: Kernel::ThinPlate,
            normal_offset: 0.01,
            surface_resolution: 64,
            margin: 0.1,
            tolerance: None,
        }
    }
}

impl RbfSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] naming the field, its value and the range.
    pub fn validate(&self) -> Result<(), MorphError> {
        let most_points = if self.tolerance.is_some() { MOST_GREEDY_POINTS } else { MOST_POINTS };
        check::count("points", self.points as u64, 8, most_points)?;
        if let Some(tolerance) = self.tolerance {
            GreedySettings { tolerance, ..GreedySettings::default() }.validate()?;
        }
        check::positive("separation", f64::from(self.separation))?;
        check::range("normal_offset", f64::from(self.normal_offset), 1e-6, 0.2)?;
        check::count("surface_resolution", u64::from(self.surface_resolution), 16, 1024)?;
        check::range("margin", f64::from(self.margin), 0.0, 2.0)
    }
}

impl RbfSettings {
    /// The paper-level settings of the fit these settings describe.
    pub fn transform(&self) -> TransformSettings {
        let centres = match self.tolerance {
            Some(tolerance) => Centres::Greedy(GreedySettings { tolerance, ..GreedySettings::default() }),
            None => Centres::All,
        };
        TransformSettings {
            fit: FitSettings { centres, ..FitSettings::default().with_kernel(self.kernel) },
            separation: self.separation,
            margin: self.margin,
        }
    }
}

/// The boundary and inward normal constraints (§4.2) of `settings.points`
/// surface points of each solid (the mesh itself, or the polygonized
/// distance volume of other solids).
pub(crate) fn surface_constraints(
    source: &Solid,
    target: &Solid,
    settings: &RbfSettings,
    control: &Control,
) -> Result<[Vec<Constraint<3>>; 2], RbfError> {
    Ok([
        solid_constraints(source, settings, 0.0, control)?,
        solid_constraints(target, settings, 0.5, control)?,
    ])
}

/// The boundary and normal constraints of one solid's surface (of
/// [`RbfSettings::points`] points); `done` is the share of the constraint
/// stage already reported.
pub(crate) fn solid_constraints(
    solid: &Solid,
    settings: &RbfSettings,
    done: f32,
    control: &Control,
) -> Result<Vec<Constraint<3>>, RbfError> {
    let surface = SurfaceSettings {
        offset: NormalOffset::RelativeToDiagonal(settings.normal_offset),
        subsample: Subsample::FarthestPoint(settings.points),
    };
    control.progress("constraints", Some(done), String::new);
    let mesh = solid.surface(settings.surface_resolution, control)?;
    let constraints = mesh_constraints(&mesh, &surface)?;
    control.check()?;
    Ok(constraints)
}

/// Transformation between two 3D shapes through one 4D variational implicit
/// (§5.2); implements [`Morph`] with [`Slice3`] frames (iso 0, positive
/// inside, field space = world space).
///
/// The separation `t_max` is the user's local/global control (§6.2): small
/// separations keep only features that nearly coincide in A and B, large
/// ones let the global shape guide the in-between shapes (which then round
/// off and bulge more, especially with the `r³` kernel).
///
/// ```
/// use isomorph_common::{Control, Morph, Shape, Solid};
/// use isomorph_rbf::{RbfMorph, RbfSettings};
///
/// let sphere = Solid::shape(Shape::sphere(0.3));
/// let torus = Solid::shape(Shape::torus(0.3, 0.12));
/// let settings = RbfSettings { points: 200, ..Default::default() };
/// let morph = RbfMorph::new(&sphere, &torus, &settings, &Control::new())?;
/// assert!(morph.interpolant().report().max_residual.unwrap() < 1e-8);
/// let torus_frame = morph.frame_mesh(1.0, 48)?;
/// assert_eq!(torus_frame.genus(), Some(1));
/// # Ok::<(), isomorph_rbf::RbfError>(())
/// ```
#[derive(Debug, Clone)]
pub struct RbfMorph {
    interpolant: Interpolant<4>,
    separation: f32,
    bounds: Aabb,
    report: MorphReport,
}

impl RbfMorph {
    /// Samples `settings.points` surface points of each solid (the mesh
    /// itself, or the polygonized distance volume of other solids),
    /// makes their boundary and inward normal constraints (§4.2) and fits
    /// the 4D implicit with the source at `t = 0` and the target at
    /// `t = separation`.
    ///
    /// Cancellation is checked between the stages; the fit itself (0.1 s at
    /// the defaults, `O(points³)`) runs to its end.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`], [`MorphError::Cancelled`], the solids'
    /// conversion errors, and those of [`RbfMorph::from_constraints`].
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &RbfSettings,
        control: &Control,
    ) -> Result<Self, RbfError> {
        settings.validate()?;
        let warnings = isomorph_common::validate_inputs(source, target, control)?;
        control.install(|| {
            let mut stages = Stages::start();
            let [a, b] = surface_constraints(source, target, settings, control)?;
            stages.lap("constraints");
            control.progress("fit", None, || format!("{} constraints in 4D", a.len() + b.len()));
            let mut morph = Self::from_constraints(&a, &b, &settings.transform())?;
            control.check()?;
            stages.lap("fit");
            morph.report = morph.report.with_stages(stages).with_warnings(warnings);
            Ok(morph)
        })
    }

    /// Fits the 4D implicit through `source` at `t = 0` and `target` at
    /// `t = separation` (the paper-level constructor: constraints made by
    /// the caller, e.g. with [`crate::constraints`]).
    ///
    /// ```
    /// use glam::Vec3;
    /// use isomorph_common::{Aabb, Field3, Morph, Shape};
    /// use isomorph_rbf::constraints::{field_constraints, NormalOffset, SurfaceSettings, Subsample};
    /// use isomorph_rbf::{RbfMorph, TransformSettings};
    ///
    /// let s = SurfaceSettings { offset: NormalOffset::Absolute(0.01), subsample: Subsample::FarthestPoint(60) };
    /// let a = field_constraints(&Shape::sphere(0.3), &Aabb::cube(0.5), 16, &s).unwrap();
    /// let b = field_constraints(&Shape::sphere(0.2).translated(Vec3::X * 0.1), &Aabb::cube(0.5), 16, &s).unwrap();
    /// let morph = RbfMorph::from_constraints(&a, &b, &TransformSettings::default()).unwrap();
    /// let start = morph.frame(0.0).unwrap().field;
    /// assert!(start.value(Vec3::new(0.3, 0.0, 0.0)).abs() < 0.05); // on the sphere
    /// assert!(start.value(Vec3::ZERO) > 0.0); // inside
    /// ```
    ///
    /// # Errors
    /// [`RbfError::EmptyShape`] for an empty constraint set,
    /// [`MorphError::BadSetting`] for a bad separation or margin, and the
    /// errors of [`Interpolant::fit`].
    pub fn from_constraints(
        source: &[Constraint<3>],
        target: &[Constraint<3>],
        settings: &TransformSettings,
    ) -> Result<Self, RbfError> {
        let (interpolant, lo, hi) = fit_pair::<3, 4>(source, target, settings)?;
        let bounds = Aabb::new(Vec3::from_array(lo), Vec3::from_array(hi));
        let fit = interpolant.report();
        let n = fit.constraints;
        // The greedy selection is iterative: converged when every constraint
        // is within its tolerance, capped at its most centres otherwise.
        let outcome = match &fit.greedy {
            None => Outcome::Direct,
            Some(g) if g.converged => Outcome::Converged,
            Some(_) => Outcome::IterationCap,
        };
        // The dense factorizations hold the n × n matrix and its factor; the
        // hierarchical solver counts its own; the slab solver's working
        // memory is not estimated here.
        let peak = match fit.factorization {
            Factorization::Cholesky | Factorization::Lblt => Some(12 * n * n),
            Factorization::Hierarchical { bytes, .. } => Some(bytes),
            _ => None,
        };
        let mut report = MorphReport::new("rbf", outcome)
            .with_rcond(fit.rcond)
            .with_memory(n * (4 + 1) * size_of::<f64>(), peak)
            .with_detail("constraints", n)
            .with_detail("merged", fit.merged)
            .with_detail("factorization", format!("{:?}", fit.factorization).as_str());
        if let Some(f) = fit.fallback {
            report = report.with_warnings([format!(
                "the hierarchical solver did not converge ({} GMRES iterations, relative residual {:.2e}); \
                 the {n} constraints were solved densely instead (exact, but O(n²) memory and much slower)",
                f.iterations, f.residual
            )]);
        }
        if let Some(g) = &fit.greedy {
            report = report
                .with_iterations(g.rounds.len())
                .with_detail("input_constraints", source.len() + target.len());
        }
        if let Some(r) = fit.max_residual {
            report = report.with_residual(Residual {
                what: "largest residual at the constraints",
                value: r,
                unit: "relative",
            });
        }
        Ok(Self { interpolant, separation: settings.separation, bounds, report })
    }

    /// The 4D interpolant (its report tells the conditioning).
    pub fn interpolant(&self) -> &Interpolant<4> {
        &self.interpolant
    }

    /// The separation `t_max`.
    pub fn separation(&self) -> f32 {
        self.separation
    }

    /// The slice at morph time `t ∈ [0, 1]` (4D coordinate `t · t_max`).
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`] for NaN or `t ∉ [0, 1]`.
    pub fn slice(&self, t: f32) -> Result<Slice3, RbfError> {
        let t = check_time(t)?;
        Ok(self.interpolant.slice3(&[t * self.separation])?.with_bounds(self.bounds))
    }
}

/// Frames are slices of the 4D implicit in world space (identity transform);
/// [`Morph::frame_mesh`] is [`Slice3::polygonize`] over the field bounds
/// (grown by `1e-4` as the default polygonizer grows them): the whole
/// lattice by the dual tree for many centres, its doubtful nodes confirmed
/// by the exact sum, the near-surface direct sum for few.
impl Morph for RbfMorph {
    type Field = Slice3;
    type Error = RbfError;

    fn method(&self) -> &'static str {
        "rbf"
    }

    fn frame(&self, t: f32) -> Result<Frame<Slice3>, RbfError> {
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

    /// The dual tree's doubtful lattice nodes are confirmed by the exact
    /// `f64` sum before marching cubes: every same-side region of at most
    /// 64 nodes, and the nodes within twice the fast error (measured at 512
    /// nodes beside the surface) of zero, nearest first, up to 2e8 kernel
    /// terms per frame. The fast far field's error at the large weights of
    /// real meshes (~0.1–0.6) would otherwise leave specks and cut necks.
    fn frame_mesh(&self, t: f32, res: u32) -> Result<TriMesh, RbfError> {
        let time = f64::from(check_time(t)? * self.separation);
        let exact =
            |p: Vec3| self.interpolant.value_f64([f64::from(p.x), f64::from(p.y), f64::from(p.z), time]);
        Ok(self.slice(t)?.polygonize_confirmed(&self.bounds.expanded(1e-4), res, Some(&exact))?)
    }
}

/// Transformation between two 2D shapes through one 3D variational implicit
/// (§5.1, Fig. 1 and 3): slices are [`Slice2`] fields, contours come from
/// marching squares, and the whole 3D implicit is available for the
/// space-time surface.
#[derive(Debug, Clone)]
pub struct ContourMorph {
    interpolant: Interpolant<3>,
    separation: f32,
    lo: Vec2,
    hi: Vec2,
}

impl ContourMorph {
    /// Fits the 3D implicit through `source` at `t = 0` and `target` at
    /// `t = separation`.
    ///
    /// # Errors
    /// As [`RbfMorph::new`].
    pub fn new(
        source: &[Constraint<2>],
        target: &[Constraint<2>],
        settings: &TransformSettings,
    ) -> Result<Self, RbfError> {
        let (interpolant, lo, hi) = fit_pair::<2, 3>(source, target, settings)?;
        let (lo, hi) = (Vec2::from_array(lo), Vec2::from_array(hi));
        Ok(Self { interpolant, separation: settings.separation, lo, hi })
    }

    /// The 3D implicit `f(x, y, t)` (the space-time shape of Fig. 1).
    pub fn interpolant(&self) -> &Interpolant<3> {
        &self.interpolant
    }

    /// The separation `t_max`.
    pub fn separation(&self) -> f32 {
        self.separation
    }

    /// The box (min, max corners) containing both inputs plus the margin.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        (self.lo, self.hi)
    }

    /// The 2D field of the shape at morph time `t ∈ [0, 1]`.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`] for NaN or `t ∉ [0, 1]`.
    pub fn slice(&self, t: f32) -> Result<Slice2, RbfError> {
        let t = check_time(t)?;
        self.interpolant.slice2(&[t * self.separation])
    }

    /// The shape at `t` sampled over [`ContourMorph::bounds`] with `res`
    /// nodes along the longer edge.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`]; [`MorphError::Grid`] for `res < 2`.
    pub fn frame_grid(&self, t: f32, res: u32) -> Result<Grid2<f32>, RbfError> {
        let (dims, spacing) = frame_lattice(self.lo, self.hi, res)?;
        Ok(self.slice(t)?.sample(dims, self.lo, spacing)?)
    }

    /// The contours (iso 0) of the shape at `t`, counter-clockwise around
    /// inside regions (holes clockwise).
    ///
    /// # Errors
    /// As [`ContourMorph::frame_grid`].
    pub fn contours(&self, t: f32, res: u32) -> Result<Vec<Polyline2>, RbfError> {
        Ok(marching_squares(&self.frame_grid(t, res)?, 0.0))
    }
}

/// The lattice of a 2D frame over the box `lo..hi` with `res` nodes along
/// the longer edge: its node counts and spacing.
pub(crate) fn frame_lattice(lo: Vec2, hi: Vec2, res: u32) -> Result<(UVec2, f32), RbfError> {
    if res < 2 {
        let dims = glam::UVec3::new(res, res, 1);
        return Err(isomorph_common::GridError::TooSmall { dims, min: 2 }.into());
    }
    let size = hi - lo;
    let spacing = size.max_element() / (res - 1) as f32;
    Ok((UVec2::new((size.x / spacing).ceil() as u32 + 1, (size.y / spacing).ceil() as u32 + 1), spacing))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::image_constraints;
    use isomorph_common::marching_cubes::polygonize;
    use isomorph_common::mesh::distance::surface_distance;
    use isomorph_common::{Field3, Shape};

    /// A sphere (radius 0.3) at `t = 0` and a torus (R = 0.3, r = 0.12) at
    /// `t = 1`, `n` farthest-point surface samples each, normal offset 0.01.
    fn reference(n: usize, kernel: crate::Kernel) -> RbfMorph {
        use crate::constraints::field_constraints;
        let s =
            SurfaceSettings { offset: NormalOffset::Absolute(0.01), subsample: Subsample::FarthestPoint(n) };
        let a = field_constraints(&Shape::sphere(0.3), &Aabb::cube(0.5), 64, &s).unwrap();
        let b = field_constraints(&Shape::torus(0.3, 0.12), &Aabb::cube(0.5), 64, &s).unwrap();
        let settings =
            TransformSettings { fit: FitSettings::default().with_kernel(kernel), ..Default::default() };
        RbfMorph::from_constraints(&a, &b, &settings).unwrap()
    }

    #[test]
    fn sphere_to_torus_endpoints_reproduce_the_inputs() {
        for kernel in [crate::Kernel::ThinPlate, crate::Kernel::Cubic] {
            let morph = reference(250, kernel);
            assert!(morph.interpolant().report().max_residual.unwrap() < 1e-8);
            let box_ = Aabb::cube(0.55);
            for (t, shape) in [(0.0, Shape::sphere(0.3)), (1.0, Shape::torus(0.3, 0.12))] {
                let got = morph.frame_mesh(t, 48).unwrap();
                let want = polygonize(&shape, &box_, 96, 0.0).unwrap();
                let d = surface_distance(&got, &want, 4000).unwrap();
                // Grid spacing of the frame mesh is 0.021; 250 points per shape.
                assert!(d.mean < 0.01 && d.hausdorff < 0.04, "{kernel:?} t={t}: {d:?}");
                assert_eq!(got.connected_components(), 1);
                assert_eq!(got.genus(), Some(if t == 0.0 { 0 } else { 1 }), "{kernel:?} t={t}");
            }
            // The middle frame is one closed piece between the two.
            let mid = morph.frame_mesh(0.5, 40).unwrap();
            assert_eq!(mid.connected_components(), 1);
        }
    }

    #[test]
    fn slice_batch_matches_exact_evaluation() {
        let morph = reference(120, crate::Kernel::ThinPlate);
        let slice = morph.slice(0.37).unwrap();
        let pts: Vec<Vec3> = (0..333)
            .map(|i| {
                Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.91).cos(), (i as f32 * 0.13).sin()) * 0.5
            })
            .collect();
        let mut out = vec![0.0; pts.len()];
        slice.values(&pts, &mut out);
        for (p, v) in pts.iter().zip(&out) {
            let exact = morph.interpolant().value_f64([p.x, p.y, p.z, 0.37].map(f64::from));
            // f32 evaluation: about 1e-4 of the unit constraint value, i.e. 1e-6
            // world units of surface position where |∇f| ≈ 1 / 0.01.
            assert!((f64::from(*v) - exact).abs() < 2e-4 * (1.0 + exact.abs()), "at {p}: {v} vs {exact}");
            assert_eq!(*v, slice.value(*p));
        }
        let p = Vec3::new(0.1, 0.2, 0.05);
        let g = slice.gradient(p);
        let e = morph.interpolant().gradient_f64([0.1, 0.2, 0.05, 0.37].map(|x: f32| f64::from(x)));
        assert!((g - Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32)).length() < 1e-3 * (1.0 + g.length()));
        assert!(matches!(morph.slice(1.5), Err(RbfError::Morph(MorphError::InvalidTime(_)))));
        assert!(matches!(morph.frame(f32::NAN), Err(RbfError::Morph(MorphError::InvalidTime(_)))));
    }

    #[test]
    fn x_to_o_changes_topology() {
        let (x, o) = (crate::figures::x_image(32), crate::figures::o_image(32));
        let a = image_constraints(&x, 0.5).unwrap();
        let b = image_constraints(&o, 0.5).unwrap();
        let morph = ContourMorph::new(&a, &b, &TransformSettings::default()).unwrap();
        let holes = |t: f32| {
            let cs = morph.contours(t, 64).unwrap();
            assert!(cs.iter().all(|c| c.closed), "open contour at t={t}");
            let outer = cs.iter().filter(|c| c.signed_area() > 0.0).count();
            let inner = cs.iter().filter(|c| c.signed_area() < 0.0).count();
            (outer, inner)
        };
        assert_eq!(holes(0.0), (1, 0), "X: one piece without holes");
        assert_eq!(holes(1.0), (1, 1), "O: one ring");
        // Every frame is one piece (no pieces popping up); a hole opens on the way.
        let mut opened = None;
        for k in 0..=10 {
            let t = k as f32 / 10.0;
            let (outer, inner) = holes(t);
            assert_eq!(outer, 1, "t={t}");
            if inner > 0 && opened.is_none() {
                opened = Some(t);
            }
        }
        let opened = opened.unwrap();
        assert!(opened > 0.0 && opened <= 1.0);
        // The X's boundary constraints are on the t = 0 contour (f32 slice
        // evaluation: 2e-3 of the unit value is 1e-4 world units here).
        let s0 = morph.slice(0.0).unwrap();
        let worst =
            a.iter().step_by(2).map(|c| s0.value(Vec2::from_array(c.position)).abs()).fold(0.0, f32::max);
        assert!(worst < 2e-3, "{worst}");
    }

    #[test]
    fn bad_morph_input() {
        let s = TransformSettings { separation: 0.0, ..Default::default() };
        let a = vec![Constraint::new([0.0, 0.0], 0.0); 3];
        assert!(matches!(ContourMorph::new(&a, &a, &s), Err(RbfError::Morph(MorphError::BadSetting { .. }))));
        assert!(matches!(
            ContourMorph::new(&a, &[], &TransformSettings::default()),
            Err(RbfError::EmptyShape("target"))
        ));
        let lifted: Vec<Constraint<4>> = lift(&[Constraint::new([1.0, 2.0], 3.0)], &[4.0, 5.0]);
        assert_eq!(lifted[0], Constraint::new([1.0, 2.0, 4.0, 5.0], 3.0));
    }
}
