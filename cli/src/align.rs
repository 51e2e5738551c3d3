//! `isomorph align`: the moment alignment (Breen & Whitaker 2001, Appendix)
//! of a source onto a target, printed as JSON, and the aligned source mesh.

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use isomorph_common::alignment::{AlignMode, Alignment, PrincipalFrame, align};
use isomorph_common::glam::Mat4;
use isomorph_common::{Control, Landmarks, validate_inputs};
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_io::mesh::{MeshFormat, write_mesh};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Which parts of the moment map to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// Rotation, translation and a scale per principal axis (Breen's map).
    Affine,
    /// Rotation, translation and the uniform scale of the volume ratio.
    Similarity,
    /// Rotation and translation only.
    Rigid,
}

impl From<Mode> for AlignMode {
    fn from(m: Mode) -> Self {
        match m {
            Mode::Affine => AlignMode::Affine,
            Mode::Similarity => AlignMode::Similarity,
            Mode::Rigid => AlignMode::Rigid,
        }
    }
}

/// Arguments of `isomorph align`.
#[derive(Debug, Args)]
pub struct AlignArgs {
    /// Source: a built-in shape (sphere, torus, ball, c-shape, mug, chain,
    /// cube, holed-cube, apple) or a closed mesh file (.obj, .ply, .stl), in its own coordinates.
    pub source: String,
    /// Target: a built-in shape or a closed mesh file, as for the source.
    pub target: String,
    /// Which parts of the map to keep.
    #[arg(long, value_enum, default_value_t = Mode::Affine)]
    pub mode: Mode,
    /// Grid nodes along the longest edge for the moments of a built-in shape
    /// (meshes use their exact moments) and for polygonizing a built-in source.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=512))]
    pub res: u32,
    /// Fit the map to landmark pairs instead of the moments: the
    /// least-squares affine map carrying the source points onto the target
    /// points (a JSON list of `{"source": [x, y, z], "target": [x, y, z]}`),
    /// printed with its largest and mean misfit (world units).
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
    /// Where to write the aligned source mesh (.ply, .obj or .stl).
    #[arg(long, default_value = "aligned.ply")]
    pub out: PathBuf,
}

/// Runs `isomorph align`: prints the map as JSON on stdout and writes the
/// aligned source mesh.
pub fn run(args: &AlignArgs) -> anyhow::Result<()> {
    let Some(format) = MeshFormat::from_path(&args.out) else {
        bail!("cannot tell the mesh format of {}: use .ply, .obj or .stl", args.out.display());
    };
    let own = LoadOptions { fit: false, ..LoadOptions::default() };
    let control = Control::new();
    let source = load_solid(&args.source, &own)?;
    if let Some(path) = &args.landmarks {
        let landmarks = Landmarks::load(path).context("invalid landmarks")?;
        let map = landmarks.affine();
        let misfit: Vec<f32> =
            landmarks.pairs().iter().map(|&(p, q)| map.transform_point3(p).distance(q)).collect();
        let mesh = source.surface(args.res, &control)?.transformed(&map);
        write_mesh(&mesh, &args.out, format)
            .with_context(|| format!("cannot write {}", args.out.display()))?;
        let report = json!({
            "mode": "landmarks",
            "matrix": matrix_rows(Mat4::from(map)),
            "landmarks": landmarks.pairs().len(),
            "max_misfit": misfit.iter().copied().fold(0.0f32, f32::max),
            "mean_misfit": misfit.iter().sum::<f32>() / misfit.len() as f32,
            "output": args.out.display().to_string(),
        });
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    let target = load_solid(&args.target, &own)?;
    // Open meshes are measured by their winding-number inside: say so.
    for warning in validate_inputs(&source, &target, &control)? {
        eprintln!("warning: {warning}");
    }
    let alignment = align(
        &source.moments(args.res, &control).with_context(|| format!("cannot measure {}", args.source))?,
        &target.moments(args.res, &control).with_context(|| format!("cannot measure {}", args.target))?,
        args.mode.into(),
    )
    .context("cannot align the two shapes")?;
    let mesh = source.surface(args.res, &control)?.transformed(&alignment.map);
    write_mesh(&mesh, &args.out, format).with_context(|| format!("cannot write {}", args.out.display()))?;
    let mut report = alignment_json(&alignment);
    report["output"] = json!(args.out.display().to_string());
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

/// A matrix as 4 rows of 4 numbers (what `--align MAP.json` reads).
fn matrix_rows(m: Mat4) -> Vec<[f32; 4]> {
    (0..4).map(|r| m.row(r).to_array()).collect()
}

/// The map as JSON: `matrix` (4×4, row-major, acting on column vectors
/// `(x, y, z, 1)`), its parts `translation`, `rotation` (unit quaternion
/// `[x, y, z, w]`) and `scale` (along the source's principal axes, the rows
/// of `scale_axes`), so `matrix = T · R · (Aᵀ diag(scale) A)`; and the two
/// principal frames.
fn alignment_json(a: &Alignment) -> Value {
    let parts = a.parts();
    let frame = |f: &PrincipalFrame| {
        json!({
            "centroid": f.centroid.to_array(),
            "volume": f.volume,
            "variances": f.variances.to_array(),
            "axes": (0..3).map(|i| f.axes.col(i).to_array()).collect::<Vec<_>>(),
            "skewness": f.skewness.to_array(),
        })
    };
    json!({
        "mode": a.mode,
        "matrix": matrix_rows(Mat4::from(a.map)),
        "translation": parts.translation.to_array(),
        "rotation": parts.rotation.to_array(),
        "scale": a.scale.to_array(),
        "scale_axes": (0..3).map(|i| a.source.axes.col(i).to_array()).collect::<Vec<_>>(),
        "source": frame(&a.source),
        "target": frame(&a.target),
    })
}
