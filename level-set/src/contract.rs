//! The level-set morph from two [`Solid`]s ([`LevelSetMorph::new`]): the
//! glue of Breen & Whitaker's pipeline — alignment, true signed distances
//! for the initial embedding and the speed, the evolution, the placement.

use crate::{
    Curvature, EvolveSettings, FrameSchedule, LevelSetError, LevelSetMorph, Placement, Response, Warp,
};
use crate::{
    SolverKind, SparseFieldSolver, SparseInputs, SpeedGrid, SpeedSampler, TargetSpeed, evolve, evolve_sparse,
};
use isomorph_common::alignment::{AlignMode, align};
use isomorph_common::glam::{Affine3A, UVec3, Vec3};
use isomorph_common::mesh::bvh::Lattice;
use isomorph_common::{
    Aabb, AffinePath, Bricks, Control, Grid3, Morph, MorphError, Solid, Stages, check, lattice_for_box,
    validate_inputs,
};
use std::fmt;
use std::sync::Arc;

/// How the source is placed on the target before evolving (Breen §6.2).
#[derive(Clone, Default)]
pub enum Align {
    /// Both shapes where they are.
    #[default]
    None,
    /// Automatic alignment by moments (Breen, Appendix): centroids,
    /// principal axes and a scale per axis.
    Auto,
    /// A user's affine map from source space to target space.
    Map(Affine3A),
    /// A generalized warp `W` from source space to target space (Breen
    /// §6.2), e.g. through landmark pairs: the speed is the target's
    /// distance at `W(x)`, `γ_B(x) = D_B(W(x))`, and frames are placed by
    /// `T(x, α) = (1 − α) x + α W(x)`. `W` should be smooth and one-to-one
    /// near the shapes.
    Warp(Warp),
}

impl fmt::Debug for Align {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Align::None => f.write_str("None"),
            Align::Auto => f.write_str("Auto"),
            Align::Map(m) => f.debug_tuple("Map").field(m).finish(),
            Align::Warp(_) => f.write_str("Warp(..)"),
        }
    }
}

/// Warps are equal when they are the same map (the same `Arc`).
impl PartialEq for Align {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Align::None, Align::None) | (Align::Auto, Align::Auto) => true,
            (Align::Map(a), Align::Map(b)) => a == b,
            (Align::Warp(a), Align::Warp(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

/// How [`LevelSetMorph::new`] stores the distance volumes and the
/// evolution's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum Storage {
    /// [`Storage::Sparse`] from [`SPARSE_FROM`] nodes along the longest edge
    /// up, [`Storage::Dense`] below.
    #[default]
    Auto,
    /// Dense distance volumes (a value per node) for the source and the
    /// speed, then [`evolve`].
    Dense,
    /// No dense grid ([`evolve_sparse`]): the source's distance in a narrow
    /// band of bricks and its side elsewhere, the speed computed per brick
    /// where the surface goes, the overlap judged near the target's
    /// surface. Memory ∝ the surfaces, not the volume; the same frames as
    /// [`Storage::Dense`]. Needs inputs whose signed distance is known
    /// pointwise ([`Solid::exact_field`]: meshes, spheres, boxes, tori,
    /// cylinders), the sparse-field solver and no [`Align::Warp`]; with
    /// others the morph stores densely (the report's `storage` says which).
    Sparse,
}

/// Resolution from which [`Storage::Auto`] stores sparsely.
pub const SPARSE_FROM: u32 = 256;

/// The default budget of kept frames ([`FrameSchedule::Budget`]): between
/// 33 and 66 frames once the evolution is longer than 65 iterations, so the
/// frames of any morph time lie at most `I/32` iterations from a kept one.
pub const FRAME_BUDGET: usize = 32;

/// Settings of [`LevelSetMorph::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct LevelSetSettings {
    /// Grid nodes along the longest edge of the evolution box (8–1024;
    /// default 64).
    pub resolution: u32,
    /// Empty margin around the shapes' box, as a fraction of its size per
    /// side (0–2; default 0.1).
    pub padding: f32,
    /// Placement of the source on the target (default none).
    pub align: Align,
    /// The solver (default Whitaker's sparse field).
    pub solver: SolverKind,
    /// Weight of a mean-curvature term that smooths the evolving surface
    /// away from the target (`None`, the default, for the paper's pure
    /// distance speed); its length scale is half the evolution box.
    pub curvature: Option<f32>,
    /// Iteration cap (default 20 000).
    pub max_iterations: usize,
    /// Which iterations' frames are kept (each costs memory ∝ the surface);
    /// `frame(t)` interpolates between them ([`LevelSetMorph`]). Default
    /// [`FrameSchedule::Budget`] of [`FRAME_BUDGET`]: at most
    /// `2 × FRAME_BUDGET + 2` frames whatever the iteration count.
    pub frames: FrameSchedule,
    /// Largest share of the target's inside (0–1) that may lie in parts the
    /// (aligned) source does not overlap, which the evolution never reaches:
    /// up to it the morph runs and its report warns, above it the morph is
    /// refused with [`MorphError::NoOverlap`] (default 0.05).
    pub max_unreached_share: f32,
    /// Dense or sparse volumes (default [`Storage::Auto`]).
    pub storage: Storage,
}

impl Default for LevelSetSettings {
    fn default() -> Self {
        Self {
            resolution: 64,
            padding: 0.1,
            align: Align::None,
            solver: SolverKind::SparseField,
            curvature: None,
            max_iterations: 20_000,
            frames: FrameSchedule::Budget(FRAME_BUDGET),
            max_unreached_share: 0.05,
            storage: Storage::Auto,
        }
    }
}

impl LevelSetSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] naming the field.
    pub fn validate(&self) -> Result<(), MorphError> {
        check::count("resolution", u64::from(self.resolution), 8, 1024)?;
        check::range("padding", f64::from(self.padding), 0.0, 2.0)?;
        check::count("max_iterations", self.max_iterations as u64, 1, 10_000_000)?;
        self.frames.validate()?;
        check::range("max_unreached_share", f64::from(self.max_unreached_share), 0.0, 1.0)?;
        if let Some(w) = self.curvature {
            check::range("curvature", f64::from(w), 0.0, 100.0)?;
        }
        if let Align::Map(m) = &self.align
            && !(m.is_finite() && m.matrix3.determinant().abs() > 1e-12)
        {
            return Err(MorphError::bad_setting("align", format!("{m:?}"), "a finite, invertible map"));
        }
        Ok(())
    }
}

impl LevelSetMorph {
    /// Breen & Whitaker's morph of `source` into `target`: the map `T` of
    /// [`LevelSetSettings::align`], the evolution box (the source and the
    /// target pulled back by `T`, padded), the source's true signed distance
    /// on it as the initial embedding, the target's true signed distance
    /// seen through `T` as the speed `γ_B`, the evolution to convergence,
    /// and frames placed by the interpolated `T(x, α)` (eq. 25–26).
    ///
    /// # Errors
    /// [`MorphError::BadSetting`], the solids' conversion errors,
    /// [`MorphError::Alignment`], [`MorphError::NoOverlap`] when parts of
    /// the target that the (aligned) source does not overlap hold more than
    /// [`LevelSetSettings::max_unreached_share`] of it,
    /// [`MorphError::Cancelled`], and [`evolve`]'s errors.
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &LevelSetSettings,
        control: &Control,
    ) -> Result<Self, LevelSetError> {
        settings.validate()?;
        let warnings = validate_inputs(source, target, control)?;
        let mut stages = Stages::start();
        let res = settings.resolution;
        if let Align::Warp(warp) = &settings.align {
            return Self::warped(source, target, warp, settings, control, warnings, stages);
        }
        let map = match settings.align {
            Align::None | Align::Warp(_) => Affine3A::IDENTITY,
            Align::Map(m) => m,
            Align::Auto => {
                control.progress("alignment", None, String::new);
                let (a, b) = (source.moments(res, control)?, target.moments(res, control)?);
                align(&a, &b, AlignMode::Affine).map_err(MorphError::from)?.map
            }
        };
        if settings.align == Align::Auto {
            stages.lap("alignment");
        }
        let bounds =
            source.bounds().union(&target.bounds().transformed(&map.inverse())).padded(settings.padding);
        if !(bounds.min.is_finite() && bounds.max.is_finite()) {
            return Err(MorphError::InvalidInput(format!(
                "the alignment map carries the target's box to {:?} .. {:?}, which is not finite; check the map",
                bounds.min, bounds.max
            ))
            .into());
        }
        let placement = if map == Affine3A::IDENTITY {
            Placement::Identity
        } else {
            AffinePath::from_identity(&map).map_err(MorphError::from)?.into()
        };
        control.progress("distance volumes", Some(0.0), String::new);
        if let (Some(field), Some(_), true) = (source.exact_field(), target.exact_field(), settings.sparse())
        {
            let (dims, origin, spacing) = lattice_for_box(&bounds, res)?;
            let band = SparseFieldSolver::band_width(spacing);
            let band = control.install(|| Bricks::sample_band(field, dims, origin, spacing, band))?;
            let sampler: SpeedSampler =
                Arc::new(ExactSpeed { target: target.clone(), map, inv_h: 1.0 / spacing });
            let inputs =
                SparseInputs { source: band, origin, spacing, target: sampler, lipschitz: norm_bound(&map) };
            stages.lap("distance volumes");
            let mut morph = evolve_sparse(&inputs, placement, &evolve_settings(settings, &bounds), control)?;
            finish_report(&mut morph, settings, stages, warnings, "sparse");
            return Ok(morph);
        }
        let embedding = source.distance_volume(&bounds, res, control)?;
        control.progress("distance volumes", Some(0.5), String::new);
        let speed = if map == Affine3A::IDENTITY {
            SpeedGrid::from_grid(&target.distance_volume(&bounds, res, control)?, Response::Identity)?
        } else {
            let (dims, origin, spacing) = (embedding.dims(), embedding.origin(), embedding.spacing());
            let field = target.distance_field(dims.max_element(), control)?;
            let lattice = Lattice { dims, origin, step: Vec3::splat(spacing) };
            let distances = control.install(|| field.sample_mapped(&lattice, &map));
            SpeedGrid::from_grid(&Grid3::from_vec(dims, origin, spacing, distances)?, Response::Identity)?
        };
        stages.lap("distance volumes");
        let mut morph = evolve(&embedding, &speed, placement, &evolve_settings(settings, &bounds), control)?;
        finish_report(&mut morph, settings, stages, warnings, "dense");
        Ok(morph)
    }

    /// [`LevelSetMorph::new`] with [`Align::Warp`]: the evolution box holds
    /// the source and the points that `W` carries into the target's box,
    /// the speed is `D_B(W(x))` and frames are placed by `T(x, α)`.
    fn warped(
        source: &Solid,
        target: &Solid,
        warp: &Warp,
        settings: &LevelSetSettings,
        control: &Control,
        warnings: Vec<String>,
        mut stages: Stages,
    ) -> Result<Self, LevelSetError> {
        let bounds = warp_bounds(&source.bounds(), &target.bounds(), warp)?.padded(settings.padding);
        control.progress("distance volumes", Some(0.0), String::new);
        let embedding = source.distance_volume(&bounds, settings.resolution, control)?;
        control.progress("distance volumes", Some(0.5), String::new);
        let (dims, ..) = lattice_for_box(&bounds, settings.resolution)?;
        let field = target.distance_field(dims.max_element(), control)?;
        let speed =
            control.install(|| SpeedGrid::sample(&embedding, &field, |x| warp(x), Response::Identity))?;
        stages.lap("distance volumes");
        let placement = Placement::Warp(Arc::clone(warp));
        let mut morph = evolve(&embedding, &speed, placement, &evolve_settings(settings, &bounds), control)?;
        finish_report(&mut morph, settings, stages, warnings, "dense");
        Ok(morph)
    }
}

/// The sparse path's speed `D_B(T(x)) / h` from a target with an exact
/// distance; a brick at a time from one batch query
/// ([`Solid::exact_mapped_nodes`]).
struct ExactSpeed {
    /// The target (an exact distance: [`Solid::exact_field`]).
    target: Solid,
    /// Breen's `T`, from the evolving space into the target's.
    map: Affine3A,
    /// Voxels per world unit.
    inv_h: f32,
}

impl TargetSpeed for ExactSpeed {
    fn at(&self, x: Vec3) -> f32 {
        let x = if self.map == Affine3A::IDENTITY { x } else { self.map.transform_point3(x) };
        self.target.exact_field().map_or(f32::NAN, |f| f.value(x)) * self.inv_h
    }

    fn on_nodes(&self, (origin, spacing): (Vec3, f32), first: UVec3, dims: UVec3, out: &mut [f32]) {
        let lattice = Lattice { dims: first + dims, origin, step: Vec3::splat(spacing) };
        let distances = self.target.exact_mapped_nodes(&lattice, first, dims, &self.map);
        match distances {
            Some(d) => out.iter_mut().zip(d).for_each(|(o, d)| *o = d * self.inv_h),
            None => out.fill(f32::NAN),
        }
    }
}

impl LevelSetSettings {
    /// Whether [`Self::storage`] asks for sparse storage at this resolution
    /// with this solver (the inputs decide the rest).
    fn sparse(&self) -> bool {
        let wanted = match self.storage {
            Storage::Auto => self.resolution >= SPARSE_FROM,
            Storage::Dense => false,
            Storage::Sparse => true,
        };
        wanted && self.solver == SolverKind::SparseField
    }
}

/// An upper bound on the norm of `map`'s linear part (how far a point
/// moves per unit moved before the map): the square root of the infinity
/// norm of `AᵀA`, which bounds its largest eigenvalue; exact for diagonal
/// maps.
fn norm_bound(map: &Affine3A) -> f32 {
    let a = isomorph_common::glam::Mat3::from(map.matrix3);
    let ata = a.transpose() * a;
    let rows = [ata.row(0), ata.row(1), ata.row(2)];
    rows.iter().map(|r| r.abs().element_sum()).fold(0.0, f32::max).sqrt()
}

/// The evolution's settings from the morph's, on the box `bounds`.
fn evolve_settings(settings: &LevelSetSettings, bounds: &Aabb) -> EvolveSettings {
    EvolveSettings {
        solver: settings.solver,
        max_iterations: settings.max_iterations,
        // λ = exp(−(D/ℓ)²) with ℓ half the box, as Yang & Jüttler's
        // exp(−d²) on their [−1, 1]³ domain.
        curvature: settings
            .curvature
            .map(|weight| Curvature { weight, length: 0.5 * bounds.size().max_element() }),
        frames: settings.frames,
        max_unreached_share: settings.max_unreached_share,
        ..EvolveSettings::default()
    }
}

/// Puts the pipeline's stages (before the evolution's own), the input
/// warnings, the storage (`"dense"` or `"sparse"`) and whether the shapes
/// were aligned into `morph`'s report.
fn finish_report(
    morph: &mut LevelSetMorph,
    settings: &LevelSetSettings,
    stages: Stages,
    warnings: Vec<String>,
    storage: &'static str,
) {
    let evolution = std::mem::take(&mut morph.report_mut().stages);
    let mut report =
        morph.report().clone().with_stages(stages).with_warnings(warnings).with_detail("storage", storage);
    report.stages.extend(evolution);
    match settings.align {
        Align::Auto | Align::Map(_) => report = report.with_detail("aligned", true),
        Align::Warp(_) => report = report.with_detail("warped", true),
        Align::None => {}
    }
    *morph.report_mut() = report;
}

/// Lattice points per axis of the search for `W⁻¹(target box)`.
const WARP_PROBES: usize = 33;

/// The box of the source and of the points `x` whose image `W(x)` lies in
/// the target's box, found on a lattice over the two boxes widened by their
/// size on every side (a warp through landmarks near the shapes moves
/// points by at most about that much), grown by one lattice step.
fn warp_bounds(source: &Aabb, target: &Aabb, warp: &Warp) -> Result<Aabb, MorphError> {
    let both = source.union(target);
    let search = both.expanded(both.size().max_element());
    let step = search.size() / (WARP_PROBES - 1) as f32;
    let mut found = *source;
    let mut any = false;
    for k in 0..WARP_PROBES {
        for j in 0..WARP_PROBES {
            for i in 0..WARP_PROBES {
                let x = search.min + step * Vec3::new(i as f32, j as f32, k as f32);
                let y = warp(x);
                if !y.is_finite() {
                    return Err(MorphError::InvalidInput(format!(
                        "the warp sends {x} to a non-finite point"
                    )));
                }
                if target.contains(y) {
                    found = found.including(x);
                    any = true;
                }
            }
        }
    }
    if !any {
        return Err(MorphError::InvalidInput(
            "the warp carries no point near the shapes into the target's box; check the landmarks".into(),
        ));
    }
    Ok(found.expanded(step.max_element()))
}
