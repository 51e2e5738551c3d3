//! The level-set morph from two [`Solid`]s ([`LevelSetMorph::new`]): the
//! glue of Breen & Whitaker's pipeline — alignment, true signed distances
//! for the initial embedding and the speed, the evolution, the placement.

use crate::{Curvature, EvolveSettings, FrameSchedule, LevelSetError, LevelSetMorph, Placement, Response};
use crate::{SolverKind, SpeedGrid, evolve};
use isomorph_common::alignment::{AlignMode, align};
use isomorph_common::glam::Affine3A;
use isomorph_common::{
    AffinePath, Control, Morph, MorphError, Solid, Stages, check, lattice_for_box, validate_inputs,
};

/// How the source is placed on the target before evolving (Breen §6.2).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Align {
    /// Both shapes where they are.
    #[default]
    None,
    /// Automatic alignment by moments (Breen, Appendix): centroids,
    /// principal axes and a scale per axis.
    Auto,
    /// A user's affine map from source space to target space.
    Map(Affine3A),
}

/// Settings of [`LevelSetMorph::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
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
    /// Keep a frame every this many iterations (default 1: every iteration,
    /// each costs memory ∝ the surface).
    pub keep_every: usize,
    /// Largest share of the target's inside (0–1) that may lie in parts the
    /// (aligned) source does not overlap, which the evolution never reaches:
    /// up to it the morph runs and its report warns, above it the morph is
    /// refused with [`MorphError::NoOverlap`] (default 0.05).
    pub max_unreached_share: f32,
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
            keep_every: 1,
            max_unreached_share: 0.05,
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
        check::count("keep_every", self.keep_every as u64, 1, 10_000_000)?;
        check::range("max_unreached_share", f64::from(self.max_unreached_share), 0.0, 1.0)?;
        if let Some(w) = self.curvature {
            check::range("curvature", f64::from(w), 0.0, 100.0)?;
        }
        if let Align::Map(m) = self.align
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
        let map = match settings.align {
            Align::None => Affine3A::IDENTITY,
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
        control.progress("distance volumes", Some(0.0), String::new);
        let embedding = source.distance_volume(&bounds, res, control)?;
        control.progress("distance volumes", Some(0.5), String::new);
        let speed = if map == Affine3A::IDENTITY {
            SpeedGrid::from_grid(&target.distance_volume(&bounds, res, control)?, Response::Identity)?
        } else {
            let (dims, ..) = lattice_for_box(&bounds, res)?;
            let field = target.distance_field(dims.max_element(), control)?;
            control.install(|| {
                SpeedGrid::sample(&embedding, &field, |x| map.transform_point3(x), Response::Identity)
            })?
        };
        stages.lap("distance volumes");
        let placement = if map == Affine3A::IDENTITY {
            Placement::Identity
        } else {
            AffinePath::from_identity(&map).map_err(MorphError::from)?.into()
        };
        let evolve_settings = EvolveSettings {
            solver: settings.solver,
            max_iterations: settings.max_iterations,
            // λ = exp(−(D/ℓ)²) with ℓ half the box, as Yang & Jüttler's
            // exp(−d²) on their [−1, 1]³ domain.
            curvature: settings
                .curvature
                .map(|weight| Curvature { weight, length: 0.5 * bounds.size().max_element() }),
            frames: FrameSchedule::EveryIterations(settings.keep_every),
            max_unreached_share: settings.max_unreached_share,
            ..EvolveSettings::default()
        };
        let mut morph = evolve(&embedding, &speed, placement, &evolve_settings, control)?;
        let evolution = std::mem::take(&mut morph.report_mut().stages);
        let mut report = morph.report().clone().with_stages(stages).with_warnings(warnings);
        report.stages.extend(evolution);
        if let Align::Auto | Align::Map(_) = settings.align {
            report = report.with_detail("aligned", true);
        }
        *morph.report_mut() = report;
        Ok(morph)
    }
}
