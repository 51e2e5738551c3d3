//! `isomorph morph --method tspline`: Yang & Jüttler's T-spline level-set
//! morph, with a progress bar over the evolution steps.

use crate::inputs::Input;
use anyhow::Context;
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use isomorph_tspline::{MorphSettings, Refinement, Speed, TsplineMorph, morph};
use std::ops::ControlFlow;

/// The evolution speeds on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpeedArg {
    /// The paper's eq. 8, `λ d_B + (1 − λ) κ` with `λ = exp(−d_B²)`
    /// (curvature on; can stall on large growth, which is reported).
    Paper,
    /// `d_B` alone (curvature off, the paper's Fig. 2).
    Distance,
    /// The implementer's note's robust speed: clamped distance plus a small
    /// curvature term (the default: it does not stall).
    Robust,
}

/// T-spline options of `isomorph morph`.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Largest number of surface samples per octree cell (`n_T`).
    pub nt: Option<usize>,
    /// Maximum octree depth.
    pub depth: Option<u32>,
    /// Morph step size `h` (domain units of `[−1, 1]³`).
    pub step: Option<f64>,
    /// Empty margin around the shapes in the domain (fraction of their half
    /// size).
    pub margin: Option<f64>,
    /// The speed function.
    pub speed: SpeedArg,
    /// The final refinement of the initial fit: surface error tolerance
    /// (domain units) and the maximum number of rounds.
    pub refine: Option<(f64, u32)>,
}

/// Runs the T-spline morph of `source` into `target` (both as meshes: a
/// mesh input as it is, a built-in shape polygonized at 64 nodes along its
/// box).
///
/// # Errors
/// T-spline errors: shapes that do not overlap, empty shapes, singular
/// systems, bad settings (including a refinement tolerance outside (0, 2]).
pub fn build(source: &Input, target: &Input, options: Options) -> anyhow::Result<TsplineMorph> {
    let (a, b) = (source.reference(64)?, target.reference(64)?);
    let mut settings = MorphSettings::default();
    if let Some(nt) = options.nt {
        settings.tmesh.max_samples_per_cell = nt;
    }
    if let Some(depth) = options.depth {
        settings.tmesh.max_depth = depth;
    }
    settings.evolve.step = options.step;
    if let Some(margin) = options.margin {
        settings.margin = margin;
    }
    settings.fit.refinement =
        options.refine.map(|(tolerance, rounds)| Refinement { tolerance, max_rounds: rounds as usize });
    // The finest cell of the T-mesh over [−1, 1]³ is 2 / 2^depth.
    let finest = 2.0 / f64::from(1u32 << settings.tmesh.max_depth.min(16));
    settings.evolve.speed = match options.speed {
        SpeedArg::Paper => Speed::Paper,
        SpeedArg::Distance => Speed::Distance,
        SpeedArg::Robust => Speed::Robust { v_max: 0.2, beta: finest },
    };
    let bar = ProgressBar::new(settings.evolve.max_steps as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>12} {spinner} step {pos}  {msg}").expect("valid template"),
    );
    bar.set_prefix("t-spline");
    let result = morph(&a, &b, &settings, &|s| {
        bar.set_position(s.step as u64);
        bar.set_message(format!("RMS to target {:.4}, {} samples", s.rms_to_target, s.samples));
        ControlFlow::Continue(())
    })
    .context("the T-spline morph failed");
    bar.finish_and_clear();
    result
}
