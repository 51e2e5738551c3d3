//! `isomorph morph --method level-set`: Breen & Whitaker's level-set morph
//! with optional moment alignment and a progress bar over the iterations.

use crate::inputs::Input;
use anyhow::{Context, bail};
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use isomorph_common::alignment::{AlignMode, align};
use isomorph_common::glam::{Affine3A, Mat4};
use isomorph_common::{AffinePath, Grid3};
use isomorph_levelset::{
    Curvature, EvolveSettings, FrameSchedule, LevelSetMorph, Placement, Response, SolverKind, SpeedGrid,
    evolve,
};
use std::path::{Path, PathBuf};

/// How the source is placed on the target before evolving (Breen §6.2).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Align {
    /// Automatic alignment by moments (Breen, Appendix): centroids,
    /// principal axes and per-axis scale.
    Auto,
    /// Use both shapes where they are.
    None,
    /// The map in a JSON file with a `matrix` entry (4×4, row-major, acting
    /// on column vectors `(x, y, z, 1)`), as `isomorph align` prints it.
    File(PathBuf),
}

/// Parses `--align`: `auto`, `none` or the path of a JSON map.
pub fn parse_align(s: &str) -> Result<Align, String> {
    match s {
        "auto" => Ok(Align::Auto),
        "none" => Ok(Align::None),
        path if path.ends_with(".json") => Ok(Align::File(PathBuf::from(path))),
        other => Err(format!("'{other}' is not auto, none or a .json file")),
    }
}

/// Reads an affine map written by `isomorph align` (its `matrix` entry).
///
/// # Errors
/// Unreadable files, a missing or malformed `matrix`, a last row other than
/// `0 0 0 1`, non-finite entries or a singular map.
pub fn read_map(path: &Path) -> anyhow::Result<Affine3A> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let rows: [[f32; 4]; 4] = serde_json::from_value(json["matrix"].clone())
        .with_context(|| format!("{}: expected \"matrix\": 4 rows of 4 numbers", path.display()))?;
    if rows[3] != [0.0, 0.0, 0.0, 1.0] {
        bail!("{}: the matrix's last row must be 0 0 0 1 (an affine map)", path.display());
    }
    let map = Affine3A::from_mat4(Mat4::from_cols_array_2d(&rows).transpose());
    if !map.is_finite() || map.matrix3.determinant().abs() < 1e-12 {
        bail!("{}: the map is not finite and invertible", path.display());
    }
    Ok(map)
}

/// The level-set solver on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Solver {
    /// Whitaker's sparse field (fast; cost ∝ surface).
    Sparse,
    /// Up-wind scheme over the whole grid (the slow reference).
    Dense,
}

/// Level-set options of `isomorph morph`.
#[derive(Debug, Clone)]
pub struct Options {
    /// Alignment of source onto target.
    pub align: Align,
    /// Solver.
    pub solver: Solver,
    /// Grid nodes along the longest edge of the evolution box.
    pub res: u32,
    /// Weight of the mean-curvature term, if any.
    pub curvature: Option<f32>,
}

/// Evolves `source` into `target`; frames are kept at every iteration (each
/// costs memory proportional to the surface) and placed by the interpolated
/// alignment `T(x, α)`.
///
/// # Errors
/// Alignment, grid and level-set errors (e.g. shapes that do not overlap).
pub fn build(source: &Input, target: &Input, options: &Options) -> anyhow::Result<LevelSetMorph> {
    let map = match &options.align {
        Align::None => Affine3A::IDENTITY,
        Align::Auto => {
            let (a, b) = (source.moments(options.res)?, target.moments(options.res)?);
            align(&a, &b, AlignMode::Affine).context("cannot align the shapes")?.map
        }
        Align::File(path) => read_map(path)?,
    };
    // The evolution happens in source space: the box holds the source and the
    // target pulled back by T.
    let inverse = map.inverse();
    let bounds = source.bounds().union(&target.bounds().transformed(&inverse)).padded(0.1);
    let grid = Grid3::sample_box(source.field(), &bounds, options.res)?;
    let speed = SpeedGrid::sample(&grid, target.field(), |x| map.transform_point3(x), Response::Identity)?;
    let placement =
        if map == Affine3A::IDENTITY { Placement::Identity } else { AffinePath::from_identity(&map)?.into() };
    let settings = EvolveSettings {
        solver: match options.solver {
            Solver::Sparse => SolverKind::SparseField,
            Solver::Dense => SolverKind::Dense,
        },
        max_iterations: 20_000,
        // λ = exp(−(D/ℓ)²) with ℓ half the box, as Yang & Jüttler's
        // exp(−d²) on their [−1, 1]³ domain.
        curvature: options
            .curvature
            .map(|weight| Curvature { weight, length: 0.5 * bounds.size().max_element() }),
        frames: FrameSchedule::EveryIterations(1),
        ..EvolveSettings::default()
    };
    let bar = ProgressBar::new(settings.max_iterations as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>12} {spinner} iteration {pos}  {msg}")
            .expect("valid template"),
    );
    bar.set_prefix("level-set");
    let morph = evolve(&grid, &speed, placement, &settings, &|p| {
        bar.set_position(p.iteration as u64);
        bar.set_message(format!("RMS distance {:.3} voxels", p.stats.rms_distance));
    })
    .context("the level-set evolution failed")?;
    bar.finish_and_clear();
    Ok(morph)
}
