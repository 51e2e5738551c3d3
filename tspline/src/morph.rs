//! The whole method (paper §4, Fig. 4): alignment (§4.2), normalization to
//! `D = [−1, 1]³`, T-mesh (§3.2), initial fit (§3.2), evolution (§3.3),
//! projection frames at both ends (§4.3) and the combined alignment
//! transforms of eq. 11 (§4.4), as an [`isomorph_common::Morph`].

use crate::error::{TsplineError, check_range};
use crate::evolution::{Evolution, EvolveSettings, evolve};
use crate::fit::{FitReport, FitSettings, Refinement, fit};
use crate::sampling::project;
use crate::tmesh::{TMesh, TMeshSettings};
use crate::tspline::TSpline;
use glam::{Affine3A, DVec3, Mat3, Vec3};
use isomorph_common::alignment::{AlignMode, Moments, align};
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::marching_triangulation::{TriangulationSettings, marching_triangulation};
use isomorph_common::mesh::distance::surface_samples;
use isomorph_common::sdf::MeshSdf;
use isomorph_common::{Aabb, AffineParts, Field3, Frame, Grid3, Morph, TriMesh};
use isomorph_common::{Control, MorphError, MorphReport, Residual, Solid, Stages, check, check_time};
use rayon::prelude::*;
use std::sync::Arc;

/// How the source is placed on the target before the T-mesh is built (paper
/// §4.2); the frames undo the placement gradually (§4.4, eq. 11).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Align {
    /// Both shapes where they are (no transformation to interpolate).
    #[default]
    None,
    /// Automatic alignment by moments (centroids, principal axes and, for
    /// [`AlignMode::Affine`], a scale per axis: the paper's §4.2 after
    /// Breen & Whitaker's Appendix).
    Moments(AlignMode),
    /// A user's affine map from source space to target space (the paper's
    /// interactive alignment); it must preserve orientation (no mirror).
    Map(Affine3A),
}

/// How [`Morph::frame_mesh`] turns a T-spline level set into triangles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Mesher {
    /// Marching cubes over the domain with `res` nodes per axis
    /// ([`isomorph_common::marching_cubes`]).
    #[default]
    MarchingCubes,
    /// Hartmann's marching triangulation, the paper's mesher (§1, §4.4;
    /// [`isomorph_common::marching_triangulation`]): near-equilateral
    /// triangles with edges of about `edge` domain units (`D = [−1, 1]³`,
    /// in `(0, 1]`); `frame_mesh`'s `res` is the seed lattice's
    /// resolution (clamped to 2–1024).
    MarchingTriangulation {
        /// The triangles' edge length, domain units.
        edge: f64,
    },
}

impl Mesher {
    /// The mesher and its edge length as the report states it (e.g.
    /// `marching triangulation, edge 0.02 domain units`).
    pub fn describe(&self) -> String {
        match self {
            Mesher::MarchingCubes => "marching cubes".to_string(),
            Mesher::MarchingTriangulation { edge } => {
                format!("marching triangulation, edge {edge} domain units")
            }
        }
    }
}

/// Settings of [`TsplineMorph::new`] and [`morph`].
#[derive(Debug, Clone, PartialEq)]
pub struct TsplineSettings {
    /// T-mesh construction (`n_T`, depth, sample spacing).
    pub tmesh: TMeshSettings,
    /// The initial fit.
    pub fit: FitSettings,
    /// The evolution (speed, step size, stopping).
    pub evolve: EvolveSettings,
    /// Placement of the source on the target before the morph (paper
    /// §4.2); [`Align::None`] morphs the shapes where they are.
    pub align: Align,
    /// Empty margin around the aligned shapes inside the domain, as a
    /// fraction of their half size.
    pub margin: f64,
    /// Insert the projection frames of §4.3 at both ends, so the sequence
    /// starts exactly at the source mesh and ends exactly at the target mesh.
    pub projection_frames: bool,
    /// Grid nodes along the longest edge for the surface of a solid that
    /// is not a mesh ([`Solid::surface`]; 8–1024).
    pub surface_resolution: u32,
    /// The paper's final refinement of the *target's* approximation after
    /// the evolution (§3.2, last paragraph): the target's signed distance
    /// is fitted on the evolution's T-mesh by [`fit`], refined where its
    /// error exceeds the tolerance (as [`FitSettings::refinement`] does for
    /// the source), and the result is appended as the last level set
    /// (on its own, finer T-mesh); the target's projection frames start
    /// from it. `None` (default) ends on the evolution's last level set.
    pub target_refinement: Option<Refinement>,
    /// Adapt the T-mesh to the target's geometry as the final refinement
    /// adapts it to the source's (§3.2: the T-mesh follows *both* aligned
    /// objects): before the source is fitted, the target's signed distance
    /// is fitted on the T-mesh and the leaves holding target samples that
    /// its zero set misses by more than the tolerance are split (up to
    /// [`TMeshSettings::max_depth`]) and the fit repeated. Thin target parts
    /// that the sample-count rule of the octree leaves coarse (a handle
    /// thinner than a cell: few samples per cell) then get the coefficients
    /// the evolution needs to grow them. `None` (default) keeps the
    /// octree as built.
    pub target_adaptation: Option<Refinement>,
    /// The mesher of [`Morph::frame_mesh`] for level sets.
    pub mesher: Mesher,
}

/// The defaults: a T-mesh of depth at most 3 (about 500 coefficients
/// around a sphere and a torus; the sphere → torus morph takes 2.4 s end to
/// end on two cores, depth 4 gives 2295 coefficients and 5.7 s), the robust speed with a curvature weight of one finest
/// cell (the paper's eq. 8 stalls large growth, its note §5.2), a margin of
/// 0.2, projection frames, surfaces of non-mesh inputs at 64 nodes.
impl Default for TsplineSettings {
    fn default() -> Self {
        Self {
            tmesh: TMeshSettings { max_depth: 3, ..TMeshSettings::default() },
            fit: FitSettings::default(),
            evolve: EvolveSettings {
                speed: crate::Speed::robust(crate::Speed::ROBUST_BETA_CELLS),
                ..EvolveSettings::default()
            },
            align: Align::None,
            margin: 0.2,
            projection_frames: true,
            surface_resolution: 64,
            target_refinement: None,
            target_adaptation: None,
            mesher: Mesher::MarchingCubes,
        }
    }
}

impl TsplineSettings {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] naming the first bad field.
    pub fn validate(&self) -> Result<(), TsplineError> {
        check_range("margin", self.margin, 0.0, 10.0, "0..=10")?;
        check::count("surface_resolution", u64::from(self.surface_resolution), 8, 1024)?;
        if let Align::Map(m) = self.align
            && !(m.is_finite() && m.matrix3.determinant() > 1e-12)
        {
            let expected = "a finite, invertible, orientation-preserving map";
            return Err(MorphError::bad_setting("align", format!("{m:?}"), expected).into());
        }
        if let Mesher::MarchingTriangulation { edge } = self.mesher {
            check_range("mesher edge", edge, 1e-4, 1.0, "(0, 1] domain units")?;
        }
        for r in [self.target_refinement, self.target_adaptation].into_iter().flatten() {
            FitSettings { refinement: Some(r), ..self.fit.clone() }.validate()?;
        }
        self.tmesh.validate()?;
        self.fit.validate()?;
        self.evolve.validate()
    }
}

/// One frame of the sequence.
#[derive(Debug, Clone)]
enum FrameKind {
    /// A projection frame: mesh in domain coordinates.
    Mesh(Arc<TriMesh>),
    /// A T-spline level set: index into the evolution's coefficient vectors.
    Spline(usize),
    /// The refined approximation of the target after the evolution.
    Refined,
}

/// The field of one frame of a [`TsplineMorph`], in domain coordinates.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum FrameField {
    /// A T-spline level set `L_i`.
    Spline(TSpline),
    /// A projection frame (§4.3): the signed distance to its mesh.
    Mesh(MeshSdf),
}

impl Field3 for FrameField {
    fn value(&self, p: Vec3) -> f32 {
        match self {
            FrameField::Spline(s) => s.value(p),
            FrameField::Mesh(m) => m.value(p),
        }
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        match self {
            FrameField::Spline(s) => s.gradient(p),
            FrameField::Mesh(m) => m.gradient(p),
        }
    }
    fn bounds(&self) -> Option<Aabb> {
        Some(Aabb::cube(1.0))
    }
}

/// A finished T-spline morph: the fixed T-mesh, one coefficient vector per
/// level set, the projection frames and the placement transforms.
#[derive(Debug, Clone)]
pub struct TsplineMorph {
    mesh: Arc<TMesh>,
    evolution: Evolution,
    fit: FitReport,
    /// The final refinement of the target's approximation and its report.
    refined_target: Option<(TSpline, FitReport)>,
    mesher: Mesher,
    frames: Vec<FrameKind>,
    source_frames: usize,
    target_frames: usize,
    /// Domain → working space (the target's world space).
    denormalize: Affine3A,
    /// The alignment and its eq. 11 path (`None` without alignment).
    placement: Option<Placement>,
    world: Aabb,
    report: MorphReport,
}

impl TsplineMorph {
    /// The fixed T-mesh.
    pub fn tmesh(&self) -> &Arc<TMesh> {
        &self.mesh
    }

    /// The evolution: coefficient vectors, per-step statistics, outcome.
    pub fn evolution(&self) -> &Evolution {
        &self.evolution
    }

    /// How well the initial level set fits the source.
    pub fn fit_report(&self) -> &FitReport {
        &self.fit
    }

    /// The target's approximation after the evolution's final refinement
    /// ([`TsplineSettings::target_refinement`]; `None` without it): the
    /// last level set of the sequence, on its own T-mesh, and the fit's
    /// report (its rounds' errors are distances to the target).
    pub fn refined_target(&self) -> Option<(&TSpline, &FitReport)> {
        self.refined_target.as_ref().map(|(s, r)| (s, r))
    }

    /// Total frames `m_A + n_l + m_B` (plus one with the target's final
    /// refinement).
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// Projection frames at the start (`m_A`) and at the end (`m_B`).
    pub fn projection_frame_counts(&self) -> (usize, usize) {
        (self.source_frames, self.target_frames)
    }

    /// The level set `L_i` (`i < n_l`) as a T-spline in domain coordinates.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] for `i >= n_l`.
    pub fn level_set(&self, i: usize) -> Result<TSpline, TsplineError> {
        let c =
            self.evolution.frames.get(i).ok_or_else(|| {
                MorphError::bad_setting("level set index", i, "below the number of level sets")
            })?;
        TSpline::new(self.mesh.clone(), c.clone())
    }

    /// The sequence parameter `u = i / (m_A + n_l + m_B − 1)` of frame `i`
    /// (eq. 11; 0 for a single frame).
    pub fn frame_u(&self, i: usize) -> f32 {
        if self.frames.len() > 1 { i as f32 / (self.frames.len() - 1) as f32 } else { 0.0 }
    }

    /// Domain coordinates → world coordinates of frame `i`:
    /// [`TsplineMorph::placement`] at [`TsplineMorph::frame_u`] after the
    /// domain's denormalization.
    pub fn frame_transform(&self, i: usize) -> Affine3A {
        self.placement(self.frame_u(i)) * self.denormalize
    }

    /// The source-to-target map `T` the shapes were aligned with (§4.2;
    /// `None` without alignment): the T-mesh is built on `T(source)` and the
    /// target, both in the target's world space.
    pub fn alignment_map(&self) -> Option<Affine3A> {
        self.placement.as_ref().map(|p| p.map)
    }

    /// Eq. 11: the map `W(u)` from the aligned working space (the target's
    /// world space) to the world placement of the sequence at
    /// `u ∈ [0, 1]` (clamped; NaN counts as 0). `W(0) = T⁻¹` puts frames
    /// back on the source, `W(1)` is the identity; in between the
    /// translation (of the source's centroid) and the stretch are
    /// interpolated linearly and the rotation by quaternion slerp, so
    /// [`AffineParts::from_affine`] of `W(u)` gives
    /// `slerp(R(T⁻¹), I, u)` and `(1 − u) S(T⁻¹) + u I`. The identity
    /// without alignment.
    pub fn placement(&self, u: f32) -> Affine3A {
        match &self.placement {
            Some(p) => p.at(u),
            None => Affine3A::IDENTITY,
        }
    }

    /// The T-spline of frame `i` (a level set or the refined target).
    fn frame_spline(&self, i: usize) -> Result<TSpline, TsplineError> {
        match (&self.frames[i], &self.refined_target) {
            (FrameKind::Spline(k), _) => self.level_set(*k),
            (FrameKind::Refined, Some((spline, _))) => Ok(spline.clone()),
            _ => Err(MorphError::bad_setting("frame index", i, "a level-set frame").into()),
        }
    }

    fn index(&self, t: f32) -> Result<usize, TsplineError> {
        let t = check_time(t)?;
        Ok((t * (self.frames.len() - 1) as f32).round() as usize)
    }
}

impl Morph for TsplineMorph {
    type Field = FrameField;
    type Error = TsplineError;

    fn method(&self) -> &'static str {
        "tspline"
    }

    fn frame(&self, t: f32) -> Result<Frame<FrameField>, TsplineError> {
        let i = self.index(t)?;
        let field = match &self.frames[i] {
            FrameKind::Mesh(m) => FrameField::Mesh(MeshSdf::new(m)?),
            FrameKind::Spline(_) | FrameKind::Refined => FrameField::Spline(self.frame_spline(i)?),
        };
        Ok(Frame { field, iso: 0.0, transform: self.frame_transform(i) })
    }

    /// The domain `D = [−1, 1]³`.
    fn field_bounds(&self) -> Aabb {
        Aabb::cube(1.0)
    }

    fn world_bounds(&self) -> Aabb {
        self.world
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }

    /// Projection frames are returned as meshes directly; level sets are
    /// meshed by [`TsplineSettings::mesher`]: marching cubes over the domain
    /// with `res` nodes per axis, or marching triangulation seeded from a
    /// lattice of `res` nodes.
    fn frame_mesh(&self, t: f32, res: u32) -> Result<TriMesh, TsplineError> {
        let i = self.index(t)?;
        let mut mesh = match &self.frames[i] {
            FrameKind::Mesh(m) => (**m).clone(),
            FrameKind::Spline(_) | FrameKind::Refined => {
                let spline = self.frame_spline(i)?;
                match self.mesher {
                    Mesher::MarchingCubes => {
                        let grid = Grid3::sample_box(&spline, &Aabb::cube(1.0), res)?;
                        marching_cubes(&grid, 0.0)
                    }
                    Mesher::MarchingTriangulation { edge } => {
                        let settings = TriangulationSettings {
                            edge: edge as f32,
                            seed_resolution: res.clamp(2, 1024),
                            ..Default::default()
                        };
                        marching_triangulation(&spline, &Aabb::cube(1.0), 0.0, &settings)?.0
                    }
                }
            }
        };
        mesh.transform(&self.frame_transform(i));
        Ok(mesh)
    }

    /// [`TsplineMorph::frame_transform`], without making the frame.
    fn world_transform(&self, t: f32) -> Result<Affine3A, TsplineError> {
        Ok(self.frame_transform(self.index(t)?))
    }
}

/// Runs the whole method from a source to a target mesh (closed, outward
/// oriented, world units). `control` sees every evolution step and cancels
/// between steps; the work runs on its threads.
///
/// # Errors
/// [`TsplineError::EmptyShape`] for a mesh without area,
/// [`TsplineError::NonFinite`], [`MorphError::Mesh`] for invalid meshes,
/// [`MorphError::Alignment`] when alignment is asked for an open mesh,
/// [`TsplineError::NoOverlap`] when the shapes do not overlap after
/// alignment, [`TsplineError::Singular`], [`MorphError::BadSetting`],
/// [`MorphError::Cancelled`].
pub fn morph(
    source: &TriMesh,
    target: &TriMesh,
    settings: &TsplineSettings,
    control: &Control,
) -> Result<TsplineMorph, TsplineError> {
    control.install(|| morph_on_pool(source, target, settings, control, Stages::start()))
}

fn morph_on_pool(
    source: &TriMesh,
    target: &TriMesh,
    settings: &TsplineSettings,
    control: &Control,
    mut stages: Stages,
) -> Result<TsplineMorph, TsplineError> {
    settings.validate()?;
    for (name, m) in [("source", source), ("target", target)] {
        m.validate()?;
        if m.is_empty() || surface_samples(m, 1).is_none() {
            return Err(TsplineError::EmptyShape(name));
        }
    }
    // §4.2: the source is mapped into the target's frame.
    let placement = match settings.align {
        Align::None => None,
        Align::Moments(mode) => {
            let source_moments = Moments::from_mesh(source)?;
            let al = align(&source_moments, &Moments::from_mesh(target)?, mode)?;
            Some(Placement::new(al.map, al.parts(), source_moments.centroid.as_vec3())?)
        }
        Align::Map(map) => {
            // Turn and stretch about the source's centroid (its box centre
            // for a mesh that is not closed), as the moments' path does.
            let centre = Moments::from_mesh(source)
                .map(|m| m.centroid.as_vec3())
                .unwrap_or_else(|_| source.bounds().center());
            let parts = AffineParts::from_affine(&map)?;
            Some(Placement::new(map, parts, centre)?)
        }
    };
    let aligned = match &placement {
        Some(p) => source.transformed(&p.map),
        None => source.clone(),
    };
    // §3.2: normalize into D = [−1, 1]³ with a margin.
    let bounds = aligned.bounds().union(&target.bounds());
    let half = 0.5 * bounds.size().max_element() * (1.0 + settings.margin as f32);
    if !(half.is_finite() && half > 0.0) {
        return Err(TsplineError::NonFinite("bounds"));
    }
    let center = bounds.center();
    let denormalize =
        Affine3A::from_scale_rotation_translation(Vec3::splat(half), glam::Quat::IDENTITY, center);
    let normalize = denormalize.inverse();
    let a = aligned.transformed(&normalize);
    let b = target.transformed(&normalize);
    let (samples_a, samples_b) = (uniform_samples(&a, settings)?, uniform_samples(&b, settings)?);
    // The inputs' exact signed distances, sampled once on a lattice four
    // times finer than the finest T-mesh cell (33³ to 129³ nodes) and
    // interpolated trilinearly: the fit and every evolution step query them
    // at thousands of points, and an exact query (BVH and winding number)
    // costs microseconds.
    let res = (4u32 << settings.tmesh.max_depth.min(5)).max(32) + 1;
    let domain = Aabb::cube(1.0);
    let (grid_a, grid_b) =
        (MeshSdf::new(&a)?.sample_grid(&domain, res)?, MeshSdf::new(&b)?.sample_grid(&domain, res)?);
    let da = |p: DVec3| f64::from(grid_a.trilinear(p.as_vec3()));
    let db = |p: DVec3| f64::from(grid_b.trilinear(p.as_vec3()));
    let overlap = samples_a.par_iter().any(|&p| db(p) > 0.0) || samples_b.par_iter().any(|&p| da(p) > 0.0);
    if !overlap {
        return Err(TsplineError::NoOverlap);
    }
    let all: Vec<DVec3> = samples_a.iter().chain(&samples_b).copied().collect();
    control.check()?;
    control.progress("fit", None, || format!("{} surface samples", all.len()));
    let mut mesh = Arc::new(TMesh::build(&all, &settings.tmesh)?);
    let adaptation = match settings.target_adaptation {
        Some(r) => {
            control.progress("target adaptation", None, String::new);
            let fit_settings = FitSettings { refinement: Some(r), ..settings.fit.clone() };
            let (adapted, report) = fit(mesh, db, &samples_b, &fit_settings)?;
            mesh = adapted.mesh().clone();
            stages.lap("target adaptation");
            control.check()?;
            Some(report)
        }
        None => None,
    };
    let (initial, fit_report) = fit(mesh, da, &samples_a, &settings.fit)?;
    stages.lap("fit");
    control.check()?;
    // The final refinement may have refined the T-mesh; it stays fixed from here on.
    let mesh = initial.mesh().clone();
    let evolution = evolve(&initial, db, &samples_b, &settings.evolve, control)?;
    stages.lap("evolution");
    // §3.2, last paragraph: the final refinement, now of the target's
    // approximation, on the T-mesh the evolution used.
    let refined_target = match settings.target_refinement {
        Some(r) => {
            control.check()?;
            control.progress("target refinement", None, String::new);
            let fit_settings = FitSettings { refinement: Some(r), ..settings.fit.clone() };
            let refined = fit(mesh.clone(), db, &samples_b, &fit_settings)?;
            stages.lap("target refinement");
            Some(refined)
        }
        None => None,
    };
    let h = settings.evolve.step_size(mesh.finest_cell());
    let mut frames = Vec::new();
    let (mut source_frames, mut target_frames) = (0, 0);
    if settings.projection_frames {
        let start = projection_frames(&a, &initial, h);
        source_frames = start.len();
        frames.extend(start.into_iter().map(|m| FrameKind::Mesh(Arc::new(m))));
    }
    frames.extend((0..evolution.frames.len()).map(FrameKind::Spline));
    if refined_target.is_some() {
        frames.push(FrameKind::Refined);
    }
    if settings.projection_frames {
        let last = match &refined_target {
            Some((spline, _)) => spline.clone(),
            None => TSpline::new(mesh.clone(), evolution.frames.last().cloned().unwrap_or_default())?,
        };
        let mut end = projection_frames(&b, &last, h);
        end.reverse();
        target_frames = end.len();
        frames.extend(end.into_iter().map(|m| FrameKind::Mesh(Arc::new(m))));
    }
    stages.lap("projection frames");
    let mut report = report(&evolution, &fit_report, &frames, stages, settings);
    if let Some(fit) = &adaptation {
        let first = fit.rounds.first().map_or(f64::NAN, |r| r.max_surface_error);
        report = report
            .with_detail("target_adaptation_rounds", fit.rounds.len().saturating_sub(1))
            .with_detail("target_adaptation_max_surface_error_before", first)
            .with_detail("target_adaptation_max_surface_error", fit.max_surface_error);
    }
    if let Some((_, fit)) = &refined_target {
        report = report
            .with_detail("target_refinement_coefficients", fit.coefficients)
            .with_detail("target_refinement_rounds", fit.rounds.len().saturating_sub(1))
            .with_detail("target_refinement_max_surface_error", fit.max_surface_error);
    }
    if let Some(p) = &placement {
        let parts = p.parts;
        let (axis, angle) = parts.rotation.to_axis_angle();
        let kind = match settings.align {
            Align::Moments(mode) => format!("moments ({mode:?})").to_lowercase(),
            _ => "map".to_string(),
        };
        report = report
            .with_detail("alignment", kind)
            .with_detail("alignment_rotation_degrees", f64::from(angle.to_degrees()))
            .with_detail("alignment_rotation_axis", format!("{:.4} {:.4} {:.4}", axis.x, axis.y, axis.z))
            .with_detail(
                "alignment_scale",
                format!("{:.4} {:.4} {:.4}", parts.scale().x, parts.scale().y, parts.scale().z),
            );
    }
    let mut morph = TsplineMorph {
        mesh,
        evolution,
        fit: fit_report,
        refined_target,
        mesher: settings.mesher,
        frames,
        source_frames,
        target_frames,
        denormalize,
        placement,
        world: Aabb::EMPTY,
        report,
    };
    let maps = (0..morph.frames.len()).map(|i| morph.frame_transform(i));
    morph.world = isomorph_common::placed_bounds(&Aabb::cube(1.0), maps.collect::<Vec<_>>());
    Ok(morph)
}

/// The contract's report of a finished morph.
fn report(
    evolution: &Evolution,
    fit: &FitReport,
    frames: &[FrameKind],
    stages: Stages,
    settings: &TsplineSettings,
) -> MorphReport {
    use crate::evolution::Outcome as Stop;
    use isomorph_common::Outcome;
    let outcome = match evolution.outcome {
        Stop::Converged => Outcome::Converged,
        Stop::Stalled | Stop::Vanished => Outcome::Stalled,
        Stop::StepLimit => Outcome::IterationCap,
    };
    let coefficients: usize = evolution.frames.iter().map(Vec::len).sum();
    let meshes: usize = frames
        .iter()
        .map(|f| match f {
            FrameKind::Mesh(m) => m.positions.len() * 12 + m.triangles.len() * 12,
            FrameKind::Spline(_) | FrameKind::Refined => 0,
        })
        .sum();
    let stored = coefficients * size_of::<f64>() + meshes;
    let mut report = MorphReport::new("tspline", outcome)
        .with_iterations(evolution.steps.len())
        .with_residual(Residual {
            what: "two-sided RMS distance of the last level set to the target",
            value: evolution.final_error,
            unit: "domain units ([-1, 1]^3)",
        })
        .with_stages(stages)
        .with_memory(stored, None)
        .with_detail("coefficients", fit.coefficients)
        .with_detail("fit_max_surface_error", fit.max_surface_error)
        .with_detail("level_sets", evolution.frames.len())
        .with_detail("frames", frames.len())
        .with_detail("mesher", settings.mesher.describe())
        .with_detail("speed", settings.evolve.speed.describe())
        .with_detail("sampler", settings.evolve.sampler.describe())
        .with_detail("first_step_samples", evolution.steps.first().map_or(0, |s| s.samples))
        .with_detail("stall_steps", settings.evolve.stall_steps)
        .with_detail("far_field_weight", settings.evolve.far_field_weight)
        .with_detail("hold_fraction", settings.evolve.hold_fraction)
        .with_detail("held_cells", evolution.steps.iter().map(|s| s.held_cells).sum::<usize>());
    let steps = evolution.steps.len();
    let warning = match evolution.outcome {
        Stop::Vanished => Some("the zero set vanished during the evolution".to_string()),
        Stop::Stalled => Some(format!(
            "the T-spline evolution stalled after {steps} steps: its two-sided RMS distance to the target \
             ({:.4} domain units) did not drop by 1 % over {} steps{}",
            evolution.final_error,
            settings.evolve.stall_steps,
            if settings.evolve.speed == crate::Speed::Paper {
                "; the paper's speed (eq. 8) lets curvature dominate far from the target, try the robust speed"
            } else {
                ""
            }
        )),
        Stop::StepLimit => Some(format!(
            "the T-spline evolution reached its step cap ({}) at a two-sided RMS distance of {:.4} domain units",
            settings.evolve.max_steps, evolution.final_error
        )),
        Stop::Converged => None,
    };
    if let Some(w) = warning {
        report = report.with_warnings([w]);
    }
    report
}

impl TsplineMorph {
    /// Yang & Jüttler's morph of `source` into `target`: their surfaces
    /// (a closed mesh itself; an open mesh or any other solid as marching
    /// cubes of its true distance volume, winding-number sign, at
    /// [`TsplineSettings::surface_resolution`], with a report warning for an
    /// open mesh) through [`morph`].
    ///
    /// # Errors
    /// As [`morph`], plus the solids' conversion errors.
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &TsplineSettings,
        control: &Control,
    ) -> Result<Self, TsplineError> {
        settings.validate()?;
        let warnings = isomorph_common::validate_inputs(source, target, control)?;
        let mut stages = Stages::start();
        let res = settings.surface_resolution;
        control.progress("surfaces", None, String::new);
        let (a, note_a) = closed_surface(source, "source", res, control)?;
        let (b, note_b) = closed_surface(target, "target", res, control)?;
        stages.lap("surfaces");
        let mut morph = control.install(|| morph_on_pool(&a, &b, settings, control, stages))?;
        morph.report.warnings.extend(warnings.into_iter().chain(note_a).chain(note_b));
        Ok(morph)
    }
}

/// The surface the morph starts from or ends on: a closed mesh as it is;
/// a solid that is not a mesh, or an open mesh (e.g. the Utah teapot's
/// unwelded patches, whose spout and handle pass into the body), as marching
/// cubes of its true signed distance (winding-number sign) with `res` nodes
/// along its box's longest edge, so that every surface sample lies on the
/// boundary of the solid's inside. For an open mesh the second value is a
/// report warning saying so.
fn closed_surface<'a>(
    solid: &'a Solid,
    name: &str,
    res: u32,
    control: &Control,
) -> Result<(std::borrow::Cow<'a, TriMesh>, Option<String>), TsplineError> {
    let surface = solid.surface(res, control)?;
    let open = surface.edge_stats().boundary_edges;
    if open == 0 {
        return Ok((surface, None));
    }
    let volume = solid.distance_volume(&solid.bounds().padded(0.05), res, control)?;
    let note = format!(
        "the {name} mesh is open ({open} boundary edges): the morph uses the zero set of its \
         winding-number signed distance at {res} nodes instead"
    );
    Ok((std::borrow::Cow::Owned(marching_cubes(&volume, 0.0)), Some(note)))
}

/// Uniform surface samples with the T-mesh's spacing (domain units).
fn uniform_samples(mesh: &TriMesh, settings: &TsplineSettings) -> Result<Vec<DVec3>, TsplineError> {
    let area = mesh.area();
    let count = (area / (settings.tmesh.sample_spacing * settings.tmesh.sample_spacing)).ceil();
    let count = count.clamp(16.0, 4e6) as usize;
    let pts = surface_samples(mesh, count).ok_or(TsplineError::EmptyShape("input"))?;
    Ok(pts.into_iter().map(|p| p.as_dvec3()).collect())
}

/// §4.3: the mesh's vertices moved towards their foot points on the level
/// set (eq. 10, `v̇ = q − v`) by explicit Euler steps of at most `h`, until
/// every vertex is on it (at most 64 frames). The first frame is the mesh.
fn projection_frames(mesh: &TriMesh, spline: &TSpline, h: f64) -> Vec<TriMesh> {
    let mut frames = vec![mesh.clone()];
    let mut current = mesh.clone();
    for _ in 0..64 {
        let moves: Vec<Vec3> = current
            .positions
            .par_iter()
            .map(|&v| {
                let v64 = v.as_dvec3();
                match project(spline, v64, 0.5) {
                    Some(s) => {
                        let d = s.p - v64;
                        let len = d.length();
                        (if len > h { d * (h / len) } else { d }).as_vec3()
                    }
                    None => Vec3::ZERO,
                }
            })
            .collect();
        let largest = moves.iter().fold(0.0f32, |m, d| m.max(d.length()));
        if f64::from(largest) < 1e-4 * h {
            break;
        }
        for (p, d) in current.positions.iter_mut().zip(&moves) {
            *p += *d;
        }
        frames.push(current.clone());
    }
    frames
}

/// The alignment `T` (source → target) and its eq. 11 path: `W(u) = A(u) T⁻¹`
/// with `A(u): x ↦ c(u) + L(u) (x − c_A)`, `c(u)` the source centroid `c_A`
/// moved linearly to `T(c_A)`, and `L(u) = slerp(I, R, u) ((1 − u) I + u S)`
/// for `T`'s linear part `R S`. Then `W(u)` has the rotation
/// `slerp(R⁻¹, I, u)` and the stretch `(1 − u) S(T⁻¹) + u I` of eq. 11.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Placement {
    /// Source → target.
    map: Affine3A,
    /// Target → source.
    inverse: Affine3A,
    /// `T`'s rotation and stretch (the translation is unused).
    parts: AffineParts,
    /// The source point turned and stretched about (its centroid).
    centre: Vec3,
}

impl Placement {
    fn new(map: Affine3A, parts: AffineParts, centre: Vec3) -> Result<Self, TsplineError> {
        let inverse = map.inverse();
        if !(inverse.is_finite() && centre.is_finite()) {
            return Err(TsplineError::NonFinite("alignment"));
        }
        Ok(Self { map, inverse, parts, centre })
    }

    /// `W(u)` (see the type's docs).
    fn at(&self, u: f32) -> Affine3A {
        let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
        let linear = AffineParts { translation: Vec3::ZERO, ..self.parts };
        let m = Mat3::from(AffineParts::IDENTITY.lerp(&linear, u).to_affine().matrix3);
        let centre = self.centre.lerp(self.map.transform_point3(self.centre), u);
        Affine3A::from_mat3_translation(m, centre - m * self.centre) * self.inverse
    }
}
