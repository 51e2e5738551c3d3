//! `isomorph morph`: morph a source into a target with a chosen method.

use crate::options::{MethodArgs, refuse_foreign};
use crate::progress;
use crate::raw::RawArgs;
use anyhow::Context;
use clap::{ArgMatches, Args, ValueEnum};
use isomorph_cli::methods::{Method, Settings, build, load_input_with_warnings};
use isomorph_common::mesh::color::ColorLookup;
use isomorph_common::{Control, Solid, TriMesh};
use isomorph_io::export::{ExportSettings, FrameColors, Report, export_sequence};
use isomorph_io::inputs::{LoadOptions, UNCOLORED, builtin_color};
use isomorph_io::mesh::MeshFormat;
use std::path::{Path, PathBuf};

/// Mesh formats for the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Binary little-endian PLY.
    Ply,
    /// Wavefront OBJ.
    Obj,
    /// One USD stage (`morph.usda`) holding every frame as a time sample,
    /// instead of one file per frame.
    Usd,
}

impl Format {
    /// The frame file format (PLY for `usd`, whose frames are not written
    /// one by one).
    fn mesh_format(self) -> MeshFormat {
        match self {
            Format::Ply | Format::Usd => MeshFormat::PlyBinaryLittleEndian,
            Format::Obj => MeshFormat::Obj,
        }
    }
}

/// The inputs and outputs shared by `morph` and `compare`.
#[derive(Debug, Clone, Args)]
pub struct Io {
    /// Source: a built-in shape (sphere, torus, ball, c-shape, mug, chain,
    /// cube, holed-cube, apple, bunny), a mesh file (.obj, .ply, .stl), a `.npy`
    /// volume (signed distance, positive inside, placed by its JSON
    /// sidecar; u8 densities with the surface at 127.5), a `.raw` volume
    /// (with `--raw-dims`, `--raw-type`), or a BlobTree scene
    /// (.ron/.json, or a built-in scene for `--method blobtree`).
    #[arg(long)]
    pub source: String,
    /// Target, as the source.
    #[arg(long)]
    pub target: String,
    /// Grid nodes along the longest edge: the frames' resolution, and the
    /// grid of the methods that sample their inputs (baseline, level set,
    /// warp) [default: 64].
    #[arg(long, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub res: Option<u32>,
    /// Number of frames written (t = 0 .. 1 evenly).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(2..=1000))]
    pub frames: u32,
    /// Keep mesh and volume inputs in their own coordinates instead of
    /// fitting each into the built-in shapes' box (centred, longest side
    /// 0.9); implied by landmarks, which are given in those coordinates.
    #[arg(long)]
    pub keep_scale: bool,
    /// The surface level of volume inputs: values above it are inside (the
    /// volume is redistanced); default: f32 volumes are signed distances,
    /// u8 volumes densities with the surface at 127.5.
    #[arg(long)]
    pub iso: Option<f32>,
    /// The layout of `.raw` volume inputs.
    #[command(flatten)]
    pub raw: RawArgs,
    /// Threads to use (default: all cores); results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Mesh format of the frames.
    #[arg(long, value_enum, default_value_t = Format::Ply)]
    pub format: Format,
    /// Do not write preview.gif (the frames' renders as a loop).
    #[arg(long)]
    pub no_preview: bool,
    /// Colour the frames even when no input mesh has vertex colours:
    /// built-in shapes in their own colours, other inputs light grey.
    /// Frames are always coloured when an input mesh has vertex colours
    /// (PLY `red green blue`, OBJ `v x y z r g b`): each vertex blends the
    /// source's and the target's colour at their closest points by t.
    #[arg(long, visible_alias = "color")]
    pub colour: bool,
}

impl Io {
    /// The frames' resolution.
    pub fn resolution(&self) -> u32 {
        self.res.unwrap_or(64)
    }

    /// Loads the inputs for `method`, printing what the readers noticed.
    ///
    /// # Errors
    /// Unreadable or unknown inputs.
    pub fn inputs(&self, method: Method) -> anyhow::Result<(Solid, Solid)> {
        Ok((self.load(method, &self.source)?, self.load(method, &self.target)?))
    }

    /// Loads the input `spec` for `method` as the source and target are
    /// read, printing what the readers noticed.
    fn load(&self, method: Method, spec: &str) -> anyhow::Result<Solid> {
        let options = LoadOptions { fit: !self.keep_scale, iso: self.iso, raw: self.raw.layout() };
        let (solid, warnings) =
            load_input_with_warnings(method, spec, &options).with_context(|| format!("input {spec}"))?;
        for warning in warnings {
            eprintln!("warning: {spec}: {warning}");
        }
        Ok(solid)
    }

    /// These inputs as `options` need them: landmarks are points in the
    /// inputs' own coordinates, so with landmarks mesh and volume inputs keep
    /// their scale (as with `--keep-scale`).
    pub fn for_options(&self, options: &MethodArgs) -> Io {
        Io { keep_scale: self.keep_scale || options.has_landmarks(), ..self.clone() }
    }

    /// The method settings: the libraries' defaults, `--res` where given,
    /// and the method options.
    ///
    /// # Errors
    /// An unreadable map or links file.
    pub fn settings(&self, options: &MethodArgs) -> anyhow::Result<Settings> {
        let mut settings = Settings::default();
        if let Some(res) = self.res {
            settings = settings.with_resolution(res);
        }
        let mut settings = options.apply(settings, &self.source, &self.target)?;
        settings.rbf_influence = options
            .influence
            .iter()
            .map(|spec| self.load(Method::Rbf, spec))
            .collect::<anyhow::Result<_>>()?;
        Ok(settings)
    }

    /// Export settings writing into `out`, with the inputs' surfaces as
    /// references for the endpoint distances and, when frames are coloured
    /// (`--colour` or an input with vertex colours), as colour sources.
    ///
    /// # Errors
    /// Inputs whose surface cannot be made.
    pub fn export(
        &self,
        out: PathBuf,
        inputs: &(Solid, Solid),
        control: &Control,
    ) -> anyhow::Result<ExportSettings> {
        let settings = ExportSettings {
            frames: self.frames as usize,
            resolution: self.resolution(),
            out_dir: out,
            format: self.format.mesh_format(),
            frame_files: self.format != Format::Usd,
            usd: self.format == Format::Usd,
            preview: !self.no_preview,
            ..ExportSettings::default()
        }
        .with_inputs(&inputs.0, &inputs.1, control)?;
        let colors = match (&settings.source_reference, &settings.target_reference) {
            (Some(source), Some(target))
                if self.colour || source.colors.is_some() || target.colors.is_some() =>
            {
                let lookup = |spec: &str, surface: &TriMesh| {
                    ColorLookup::new(surface, builtin_color(spec).unwrap_or(UNCOLORED))
                        .with_context(|| format!("the colours of {spec}"))
                };
                Some(FrameColors {
                    source: lookup(&self.source, source)?,
                    target: lookup(&self.target, target)?,
                })
            }
            _ => None,
        };
        Ok(ExportSettings { colors, ..settings })
    }
}

/// Arguments of `isomorph morph`.
#[derive(Debug, Clone, Args)]
pub struct MorphArgs {
    /// Morphing method.
    #[arg(long, value_enum, default_value_t = Method::Baseline)]
    pub method: Method,
    /// Inputs, resolution, frames.
    #[command(flatten)]
    pub io: Io,
    /// Method options.
    #[command(flatten)]
    pub options: MethodArgs,
    /// Output folder for frames, contact_sheet.png and report.json.
    #[arg(long, default_value = "out/morph")]
    pub out: PathBuf,
    /// Print the JSON report (timings, per-frame metrics, endpoint
    /// distances, the method's report) on stdout instead of the summary
    /// table; it is always written to `OUT/report.json` too.
    #[arg(long)]
    pub report: bool,
}

/// Runs `isomorph morph`; `matches` are its parsed arguments (to refuse
/// options of other methods).
pub fn run(args: &MorphArgs, matches: &ArgMatches) -> anyhow::Result<()> {
    refuse_foreign(matches, &[args.method])?;
    let io = args.io.for_options(&args.options);
    let settings = io.settings(&args.options)?;
    let report = morph(args.method, &io, &settings, &args.out)?;
    if args.options.scenes {
        write_scenes(&io, &settings, &args.out)?;
    }
    if args.report {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_summary(&report, &io, &args.out);
        if args.options.scenes {
            println!("  wrote {}/frame_*.ron (the frames as BlobTree scenes)", args.out.display());
        }
    }
    Ok(())
}

/// Loads the inputs, builds `method` with `settings` and exports its frames
/// into `out`; returns the report.
///
/// # Errors
/// Inputs, settings, the method's and the exporter's errors.
pub fn morph(method: Method, io: &Io, settings: &Settings, out: &Path) -> anyhow::Result<Report> {
    let (control, bar) = progress::control(method.name(), io.threads.map(|n| n as usize))?;
    let inputs = io.inputs(method)?;
    // The export's references (the inputs' surfaces, polygonized) are made
    // while the morph is built: the method's serial parts leave a core idle.
    let (morph, export) = std::thread::scope(|scope| {
        let export = scope.spawn(|| io.export(out.to_path_buf(), &inputs, &control));
        let morph = build(method, &inputs.0, &inputs.1, settings, &control);
        let export = export.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (morph, export)
    });
    let morph = morph.with_context(|| format!("the {} morph failed", method.name()))?;
    for warning in &morph.report().warnings {
        bar.suspend(|| eprintln!("warning: {warning}"));
    }
    let export = export?;
    let exported = export_sequence(&*morph, &export, &control);
    bar.finish_and_clear();
    let report = exported.with_context(|| format!("cannot export the frames to {}", out.display()))?.report;
    for warning in &report.warnings {
        eprintln!("warning: {warning}");
    }
    if !report.morph.converged {
        let off = report.endpoints.target.map_or(String::new(), |e| match e.hausdorff_voxels {
            h if h < 0.5 => {
                format!(" (its last frame still matches the target within {h:.2} voxels, Hausdorff)")
            }
            h => format!(" (its last frame is {h:.2} voxels off the target, Hausdorff)"),
        });
        eprintln!(
            "warning: the {} morph did not reach its goal ({:?}){off}; see report.json",
            report.method, report.morph.outcome
        );
    }
    Ok(report)
}

/// Writes the BlobTree morph's frames `C(t)` at the mesh frames' times as
/// scene files `out/frame_NNN.ron` (`isomorph morph --scenes`). The morph
/// is built again from the inputs: the boxed morph the exporter used gives
/// its frames as opaque fields, not as BlobTrees.
///
/// # Errors
/// The inputs', the morph's and the files' errors.
fn write_scenes(io: &Io, settings: &Settings, out: &Path) -> anyhow::Result<()> {
    use isomorph_common::Morph;
    let (source, target) = io.inputs(Method::Blobtree)?;
    let morph = isomorph_blobtree::BlobMorph::new(&source, &target, &settings.blobtree, &Control::new())?;
    // The exporter's times: `frames ≥ 2` (checked by clap).
    for i in 0..io.frames {
        let t = i as f32 / (io.frames - 1) as f32;
        let path = out.join(format!("frame_{i:03}.ron"));
        std::fs::write(&path, morph.frame(t)?.field.to_ron()?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

/// Prints where the files went and the per-frame metrics.
pub fn print_summary(report: &Report, io: &Io, out: &Path) {
    let m = &report.morph;
    println!(
        "{} morph {} -> {}: {:?} in {:.2} s{}; {} frames at {}^3 in {:.2} s",
        report.method,
        io.source,
        io.target,
        m.outcome,
        m.total_seconds(),
        m.iterations.map_or(String::new(), |n| format!(" ({n} iterations)")),
        report.frames.len(),
        report.resolution,
        report.export_seconds
    );
    println!(
        "  {:>5} {:>9} {:>10} {:>5} {:>5} {:>5}",
        "t", "vertices", "triangles", "comp", "voids", "genus"
    );
    for f in &report.frames {
        let genus = f.genus.map_or("-".to_string(), |g| g.to_string());
        println!(
            "  {:>5.2} {:>9} {:>10} {:>5} {:>5} {:>5}",
            f.t, f.vertices, f.triangles, f.components, f.voids, genus
        );
    }
    for (name, e) in [("source", report.endpoints.source), ("target", report.endpoints.target)] {
        if let Some(e) = e {
            println!(
                "  {name} match: mean {:.3} voxels, Hausdorff {:.3} voxels",
                e.mean_voxels, e.hausdorff_voxels
            );
        }
    }
    let frames = match io.format {
        Format::Usd => "morph.usda",
        Format::Ply => "frame_*.ply",
        Format::Obj => "frame_*.obj",
    };
    let preview = if io.no_preview { "" } else { ", preview.gif" };
    println!("  wrote {}/{frames}, contact_sheet.png{preview}, report.json", out.display());
}
