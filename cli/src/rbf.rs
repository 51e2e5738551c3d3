//! `isomorph contours`: Turk & O'Brien's variational implicit shape
//! transformation of 2D images (`isomorph morph --method rbf` is the 3D one).

use crate::options::KernelArg;
use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use isomorph_common::glam::UVec2;
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, ContourBlend, Control, Grid2};
use isomorph_io::mesh::{MeshFormat, write_mesh};
use isomorph_io::png_gray::read_png_gray;
use isomorph_io::render::{Image, RenderSettings, contact_sheet_titled, render};
use isomorph_rbf::{ContourMorph, FitSettings, TransformSettings, figures, image_constraints};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `isomorph contours`.
#[derive(Debug, Args)]
pub struct ContoursArgs {
    /// The first shape: a grayscale PNG (inside bright, boundary at
    /// mid-gray) or the paper's `x` or `o`.
    pub a: String,
    /// The second shape, as the first.
    pub b: String,
    /// Number of in-between images (t = 0 .. 1 evenly).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(2..=200))]
    pub frames: u32,
    /// Pixels along each side of the frame images.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=2048))]
    pub res: u32,
    /// Separation of the two shapes along the third axis (units of the
    /// image width).
    #[arg(long, default_value_t = 1.0)]
    pub separation: f32,
    /// The radial kernel.
    #[arg(long, value_enum, default_value_t = KernelArg::Tps)]
    pub kernel: KernelArg,
    /// `rbf`: the variational transformation; `baseline`: the linear blend
    /// of the two shapes' signed distances (the paper's Figs. 2–3, top
    /// row), for comparison.
    #[arg(long, value_enum, default_value_t = ContourMethod::Rbf)]
    pub method: ContourMethod,
    /// Output folder: frame_NNN.png, contact_sheet.png and, for `rbf`,
    /// spacetime.ply (the 3D surface whose slices are the frames).
    #[arg(long, default_value = "out/contours")]
    pub out: PathBuf,
}

/// The 2D morphs of `isomorph contours`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ContourMethod {
    /// Turk & O'Brien's variational implicit in 3D.
    Rbf,
    /// Linear interpolation of the signed distances.
    Baseline,
}

/// A 2D input: a PNG or one of the paper's letters.
fn image(spec: &str) -> anyhow::Result<Grid2<f32>> {
    match spec {
        "x" => Ok(figures::x_image(64)),
        "o" => Ok(figures::o_image(64)),
        path => read_png_gray(path.as_ref()).with_context(|| format!("cannot read the image {path}")),
    }
}

/// Runs `isomorph contours`.
pub fn contours(args: &ContoursArgs) -> anyhow::Result<()> {
    if !(args.separation.is_finite() && args.separation > 0.0) {
        bail!("--separation must be finite and positive, got {}", args.separation);
    }
    let start = Instant::now();
    let (image_a, image_b) = (image(&args.a)?, image(&args.b)?);
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let frame_times = (0..args.frames).map(|i| i as f32 / (args.frames - 1) as f32);
    let (frames, summary) = match args.method {
        ContourMethod::Baseline => {
            let blend = ContourBlend::new(&image_a, &image_b, 0.5, args.res, &Control::new())?;
            let frames =
                frame_times.map(|t| Ok((t, blend.frame_grid(t)?))).collect::<anyhow::Result<Vec<_>>>()?;
            (frames, "baseline distance blend".to_string())
        }
        ContourMethod::Rbf => {
            let a = image_constraints(&image_a, 0.5).with_context(|| format!("no shape in {}", args.a))?;
            let b = image_constraints(&image_b, 0.5).with_context(|| format!("no shape in {}", args.b))?;
            let settings = TransformSettings {
                fit: FitSettings::default().with_kernel(args.kernel.into()),
                separation: args.separation,
                ..TransformSettings::default()
            };
            let morph =
                ContourMorph::new(&a, &b, &settings).context("cannot fit the variational implicit")?;
            let frames = frame_times
                .map(|t| Ok((t, morph.frame_grid(t, args.res)?)))
                .collect::<anyhow::Result<Vec<_>>>()?;
            (frames, spacetime(&morph, args)? + &format!(" from {} constraints in 3D", a.len() + b.len()))
        }
    };
    let mut tiles = Vec::new();
    for (i, (t, grid)) in frames.iter().enumerate() {
        let picture = silhouette(grid);
        picture.write_png(args.out.join(format!("frame_{i:03}.png")))?;
        tiles.push((picture, format!("t = {t:.2}")));
    }
    contact_sheet_titled(
        &tiles,
        5,
        &format!("isomorph contours ({}): {} -> {}", args.method.name(), args.a, args.b),
    )
    .write_png(args.out.join("contact_sheet.png"))?;
    println!(
        "contours {} -> {}: {} frames in {:.2} s; {summary}",
        args.a,
        args.b,
        args.frames,
        start.elapsed().as_secs_f64(),
    );
    println!("  wrote {}/frame_*.png, contact_sheet.png", args.out.display());
    Ok(())
}

impl ContourMethod {
    /// The name on the command line.
    fn name(self) -> &'static str {
        match self {
            ContourMethod::Rbf => "rbf",
            ContourMethod::Baseline => "baseline",
        }
    }
}

/// Writes the space-time surface (the 3D implicit itself, t along z) as
/// spacetime.ply and .png; returns a summary.
fn spacetime(morph: &ContourMorph, args: &ContoursArgs) -> anyhow::Result<String> {
    let (lo, hi) = morph.bounds();
    let whole = morph.interpolant().slice3(&[])?;
    let bounds = Aabb::new(lo.extend(-0.1 * args.separation), hi.extend(1.1 * args.separation));
    let surface = polygonize(&whole, &bounds, 96, 0.0)?;
    write_mesh(&surface, args.out.join("spacetime.ply"), MeshFormat::PlyBinaryLittleEndian)?;
    render(&surface, &RenderSettings::default()).write_png(args.out.join("spacetime.png"))?;
    Ok(format!(
        "space-time surface (spacetime.ply, .png): {} triangles, genus {:?},",
        surface.triangles.len(),
        surface.genus()
    ))
}

/// The inside (value > 0) of a slice as a dark shape on white, y up.
fn silhouette(grid: &Grid2<f32>) -> Image {
    let UVec2 { x: w, y: h } = grid.dims();
    let mut picture = Image::new(w, h, [250, 250, 248]);
    for j in 0..h {
        for i in 0..w {
            if grid.get(i, j).is_some_and(|&v| v > 0.0) {
                picture.set(i64::from(i), i64::from(h - 1 - j), [70, 110, 170]);
            }
        }
    }
    picture
}
