//! `isomorph morph`: morph a source into a target with a chosen method.

use crate::blob;
use crate::inputs::{Input, morph_bounds};
use crate::level_set::{self, Align, Solver};
use crate::progress::FrameBar;
use crate::rbf::{self, KernelArg};
use crate::tspline::{self, SpeedArg};
use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use isomorph_blobtree::BlobMorph;
use isomorph_common::export::{ExportSettings, Report, export_sequence};
use isomorph_common::mesh::io::MeshFormat;
use isomorph_common::{DistanceBlend, Morph};
use std::path::PathBuf;

/// Morphing methods available to the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// Linear interpolation of the two signed distance volumes (the naive
    /// baseline every method should beat).
    Baseline,
    /// Breen & Whitaker's level-set morph: the source surface moves along
    /// its normals with the target's signed distance as speed.
    LevelSet,
    /// Turk & O'Brien's variational implicit in 4D: the shapes' surface
    /// constraints at t = 0 and t = separation, one RBF interpolation.
    Rbf,
    /// Yang & Jüttler's T-spline level sets on an adaptive octree.
    Tspline,
    /// Galin, Leclercq & Akkouche's BlobTree morph: source and target are
    /// BlobTree scenes (.ron/.json files or built-in names).
    Blobtree,
}

/// Mesh formats for the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Binary little-endian PLY.
    Ply,
    /// Wavefront OBJ.
    Obj,
}

impl From<Format> for MeshFormat {
    fn from(f: Format) -> Self {
        match f {
            Format::Ply => MeshFormat::PlyBinaryLittleEndian,
            Format::Obj => MeshFormat::Obj,
        }
    }
}

/// Arguments of `isomorph morph`.
#[derive(Debug, Args)]
pub struct MorphArgs {
    /// Morphing method.
    #[arg(long, value_enum, default_value_t = Method::Baseline)]
    pub method: Method,
    /// Source: a built-in shape (sphere, torus, ball, c-shape, mug, chain,
    /// cube, holed-cube, bunny) or a mesh file (.obj, .ply, .stl; closed and outward
    /// oriented); for `--method blobtree`, a BlobTree scene (.ron, .json or a
    /// built-in scene such as rook).
    #[arg(long)]
    pub source: String,
    /// Target: a built-in shape or a mesh file, as for --source.
    #[arg(long)]
    pub target: String,
    /// Grid nodes along the longest edge of the morph's box.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub res: u32,
    /// Number of frames written (t = 0 .. 1 evenly).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(2..=1000))]
    pub frames: u32,
    /// Keep mesh inputs in their own coordinates instead of fitting each into
    /// the built-in shapes' box (centred, longest side 0.9).
    #[arg(long)]
    pub keep_scale: bool,
    /// Level-set only: alignment of the source onto the target: `auto`
    /// (moments), `none`, or a JSON map file as `isomorph align` prints it.
    #[arg(long, default_value = "none", value_parser = level_set::parse_align)]
    pub align: Align,
    /// Level-set only: the solver.
    #[arg(long, value_enum, default_value_t = Solver::Sparse)]
    pub solver: Solver,
    /// The curvature term: `on`, `off` or (level set only) a weight. Level
    /// set: a mean-curvature term that smooths the evolving surface away
    /// from the target (Yang & Jüttler's weighting), `on` = weight 1.
    /// T-spline: `on` is the paper's speed (eq. 8, `--speed paper`), `off`
    /// the distance speed of its Fig. 2 (`--speed distance`).
    #[arg(long, value_parser = parse_curvature, conflicts_with = "speed")]
    pub curvature: Option<CurvatureArg>,
    /// RBF only: surface points per shape (each a boundary and a normal
    /// constraint).
    #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u32).range(4..=20_000))]
    pub points: u32,
    /// RBF only: separation of the shapes along the fourth axis (world units).
    #[arg(long, default_value_t = 1.0, value_parser = parse_separation)]
    pub separation: f32,
    /// RBF only: the radial kernel.
    #[arg(long, value_enum, default_value_t = KernelArg::Tps)]
    pub kernel: KernelArg,
    /// T-spline only: the evolution speed [default: robust].
    #[arg(long, value_enum)]
    pub speed: Option<SpeedArg>,
    /// T-spline only: largest number of surface samples per octree cell.
    #[arg(long)]
    pub nt: Option<usize>,
    /// T-spline only: maximum octree depth (1–7).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=7))]
    pub depth: Option<u32>,
    /// T-spline only: morph step size h (units of the [−1, 1]³ domain).
    #[arg(long)]
    pub step: Option<f64>,
    /// T-spline only: empty margin around the shapes in the [−1, 1]³
    /// domain, as a fraction of their half size [default: 0.2].
    #[arg(long)]
    pub margin: Option<f64>,
    /// T-spline only: the paper's final refinement of the initial fit: split
    /// the octree cells where the fitted surface is farther than this from
    /// the source (units of the [−1, 1]³ domain) and refit.
    #[arg(long)]
    pub refine: Option<f64>,
    /// T-spline only: at most this many refinement rounds (with `--refine`).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=7))]
    pub refine_rounds: u32,
    /// BlobTree only: the animator's links, speed curves and trajectories
    /// (a RON or JSON morph spec); automatic correspondence without it.
    #[arg(long)]
    pub links: Option<PathBuf>,
    /// Output folder for frames, contact_sheet.png and report.json.
    #[arg(long, default_value = "out/morph")]
    pub out: PathBuf,
    /// Mesh format of the frames.
    #[arg(long, value_enum, default_value_t = Format::Ply)]
    pub format: Format,
    /// Print the JSON report (timings, per-frame metrics, endpoint
    /// distances, the method's convergence details) on stdout instead of the
    /// summary table; it is always written to `OUT/report.json` too.
    #[arg(long)]
    pub report: bool,
}

/// Accepts a finite separation in `(0, 100]`.
fn parse_separation(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v > 0.0 && v <= 100.0 { Ok(v) } else { Err(format!("{v} is not in (0, 100]")) }
}

/// Accepts a finite weight in `[0, 100]`.
/// The value of `--curvature`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CurvatureArg {
    /// No curvature term.
    Off,
    /// The method's own curvature term (level set: weight 1).
    On,
    /// Level set only: this weight (in `[0, 100]`).
    Weight(f32),
}

impl CurvatureArg {
    /// The level-set weight (`None` when off).
    pub fn weight(self) -> Option<f32> {
        match self {
            CurvatureArg::Off => None,
            CurvatureArg::On => Some(1.0),
            CurvatureArg::Weight(w) => Some(w),
        }
    }
}

fn parse_curvature(s: &str) -> Result<CurvatureArg, String> {
    match s {
        "on" => Ok(CurvatureArg::On),
        "off" => Ok(CurvatureArg::Off),
        _ => {
            let w: f32 = s.parse().map_err(|e| format!("not on, off or a weight: {e}"))?;
            if (0.0..=100.0).contains(&w) {
                Ok(CurvatureArg::Weight(w))
            } else {
                Err(format!("{w} is not in [0, 100]"))
            }
        }
    }
}

/// Runs `isomorph morph`.
pub fn run(args: &MorphArgs) -> anyhow::Result<()> {
    let report = morph(args)?;
    if args.report {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_summary(&report, args);
    }
    Ok(())
}

/// Builds the inputs, runs the morph and exports it; returns the report.
pub fn morph(args: &MorphArgs) -> anyhow::Result<Report> {
    let reference_res = (2 * args.res).min(256);
    let mut settings = ExportSettings {
        frames: args.frames as usize,
        resolution: args.res,
        out_dir: args.out.clone(),
        format: args.format.into(),
        ..ExportSettings::default()
    };
    let label = format!("{:?}", args.method).to_lowercase();
    if args.method == Method::Blobtree {
        let (a, b) = (blob::load_tree(&args.source)?, blob::load_tree(&args.target)?);
        let spec = blob::load_spec(args.links.as_deref(), &args.source, &args.target)?;
        settings.source_reference = Some(a.mesh(reference_res)?);
        settings.target_reference = Some(b.mesh(reference_res)?);
        let morph = BlobMorph::new(&a, &b, &spec).context("cannot set up the BlobTree morph")?;
        return export(&morph, &settings, &label);
    }
    let source = Input::parse(&args.source, !args.keep_scale)?;
    let target = Input::parse(&args.target, !args.keep_scale)?;
    settings.source_reference = Some(source.reference(reference_res)?);
    settings.target_reference = Some(target.reference(reference_res)?);
    match args.method {
        Method::Baseline => {
            let bounds = morph_bounds(&source, &target);
            let morph = DistanceBlend::from_fields(source.field(), target.field(), &bounds, args.res)
                .context("cannot set up the baseline morph")?;
            export(&morph, &settings, &label)
        }
        Method::LevelSet => {
            let options = level_set::Options {
                align: args.align.clone(),
                solver: args.solver,
                res: args.res,
                curvature: args.curvature.and_then(CurvatureArg::weight),
            };
            export(&level_set::build(&source, &target, &options)?, &settings, &label)
        }
        Method::Rbf => {
            let options = rbf::Options {
                points: args.points as usize,
                separation: args.separation,
                kernel: args.kernel,
            };
            export(&rbf::build(&source, &target, options)?, &settings, &label)
        }
        Method::Tspline => {
            let options = tspline::Options {
                nt: args.nt,
                depth: args.depth,
                step: args.step,
                margin: args.margin,
                speed: match (args.speed, args.curvature) {
                    (Some(speed), _) => speed,
                    (None, None) => SpeedArg::Robust,
                    (None, Some(CurvatureArg::On)) => SpeedArg::Paper,
                    (None, Some(CurvatureArg::Off)) => SpeedArg::Distance,
                    (None, Some(CurvatureArg::Weight(_))) => {
                        bail!("the T-spline morph takes --curvature on or off, not a weight")
                    }
                },
                refine: args.refine.map(|tolerance| (tolerance, args.refine_rounds)),
            };
            export(&tspline::build(&source, &target, options)?, &settings, &label)
        }
        Method::Blobtree => bail!("BlobTree morphs take BlobTree scenes"),
    }
}

/// Exports `morph` with a progress bar over the frames.
fn export<M: Morph>(morph: &M, settings: &ExportSettings, label: &str) -> anyhow::Result<Report> {
    let bar = FrameBar::new(label, settings.frames);
    let report = export_sequence(morph, settings, &|p| bar.update(p))?;
    bar.finish();
    Ok(report)
}

/// Prints where the files went and the per-frame metrics.
pub fn print_summary(report: &Report, args: &MorphArgs) {
    println!(
        "{} morph {} -> {} at {}^3: {} frames in {:.2} s",
        report.method,
        args.source,
        args.target,
        args.res,
        report.frames.len(),
        report.total_seconds
    );
    println!("  {:>5} {:>9} {:>10} {:>5} {:>5}", "t", "vertices", "triangles", "comp", "genus");
    for f in &report.frames {
        let genus = f.genus.map_or("-".to_string(), |g| g.to_string());
        println!("  {:>5.2} {:>9} {:>10} {:>5} {:>5}", f.t, f.vertices, f.triangles, f.components, genus);
    }
    for (name, e) in [("source", report.endpoints.source), ("target", report.endpoints.target)] {
        if let Some(e) = e {
            println!(
                "  {name} match: mean {:.3} voxels, Hausdorff {:.3} voxels",
                e.mean_voxels, e.hausdorff_voxels
            );
        }
    }
    println!("  wrote {}/frame_*.{{ply,obj}}, contact_sheet.png, report.json", args.out.display());
}
