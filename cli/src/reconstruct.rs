//! `isomorph reconstruct`: Turk & O'Brien's surface reconstruction from
//! planar contours (§6): one variational implicit in 3D through the
//! contours of every slice, parallel at any spacing or in any orientation.

use crate::options::KernelArg;
use anyhow::{Context, bail};
use clap::Args;
use isomorph_common::glam::{Vec2, Vec3};
use isomorph_io::mesh::{MeshFormat, write_mesh};
use isomorph_io::png_gray::read_png_gray;
use isomorph_io::render::{RenderSettings, render};
use isomorph_rbf::{ContourSet, FitSettings, Plane, ReconstructSettings};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `isomorph reconstruct`.
#[derive(Debug, Args)]
pub struct ReconstructArgs {
    /// The slices: a JSON file (see the README: each slice a plane, `z` or
    /// `origin`/`u`/`v`, with `polylines` or a grayscale `image`) or a folder
    /// of grayscale PNG slices (bright inside), stacked in name order.
    pub slices: PathBuf,
    /// For a folder: the distance between consecutive slices, in units of
    /// the image width (each image spans [−0.5, 0.5] along its longer side).
    #[arg(long, default_value_t = 0.1)]
    pub spacing: f32,
    /// Grid nodes along the longest edge of the surface's box.
    #[arg(long, default_value_t = 96, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub res: u32,
    /// The radial kernel (`tps`: the thinnest plate through the contours;
    /// `r3`: triharmonic).
    #[arg(long, value_enum, default_value_t = KernelArg::Tps)]
    pub kernel: KernelArg,
    /// Output folder: surface.ply and surface.png.
    #[arg(long, default_value = "out/reconstruct")]
    pub out: PathBuf,
}

/// The JSON slices file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SlicesFile {
    slices: Vec<SliceSpec>,
}

/// One slice: a plane and its shape.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SliceSpec {
    /// The plane `z = const` (x, y as the 2D coordinates)...
    z: Option<f32>,
    /// ... or a plane through `origin` spanned by `u` and `v`.
    origin: Option<[f32; 3]>,
    u: Option<[f32; 3]>,
    v: Option<[f32; 3]>,
    /// Closed polylines in the plane's 2D coordinates (inside by even-odd
    /// nesting)...
    polylines: Option<Vec<Vec<[f32; 2]>>>,
    /// ... or a grayscale image (a path relative to the JSON file).
    image: Option<PathBuf>,
}

impl SliceSpec {
    fn plane(&self) -> anyhow::Result<Plane> {
        Ok(match (self.z, self.origin, self.u, self.v) {
            (Some(z), None, None, None) => Plane::at_z(z)?,
            (None, Some(o), Some(u), Some(v)) => Plane::new(o.into(), u.into(), v.into())?,
            _ => bail!("give either `z` or all of `origin`, `u` and `v`"),
        })
    }
}

/// Runs `isomorph reconstruct`.
pub fn run(args: &ReconstructArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let set = if args.slices.is_dir() { folder(&args.slices, args.spacing)? } else { file(&args.slices)? };
    let settings = ReconstructSettings {
        fit: FitSettings::default().with_kernel(args.kernel.into()),
        ..ReconstructSettings::default()
    };
    let surface = set.fit(&settings).context("cannot fit the variational implicit")?;
    let mesh = surface.mesh(args.res)?;
    if mesh.triangles.is_empty() {
        bail!("the reconstructed surface is empty at --res {}", args.res);
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    write_mesh(&mesh, args.out.join("surface.ply"), MeshFormat::PlyBinaryLittleEndian)?;
    render(&mesh, &RenderSettings::default()).write_png(args.out.join("surface.png"))?;
    println!(
        "reconstruct {}: {} constraints, {} triangles, {} component(s), genus {:?}, in {:.2} s",
        args.slices.display(),
        set.len(),
        mesh.triangles.len(),
        mesh.connected_components(),
        mesh.genus(),
        start.elapsed().as_secs_f64()
    );
    println!("  wrote {}/surface.ply, surface.png", args.out.display());
    Ok(())
}

/// The contours of a JSON slices file.
fn file(path: &Path) -> anyhow::Result<ContourSet> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let spec: SlicesFile =
        serde_json::from_str(&text).with_context(|| format!("{} is not a slices file", path.display()))?;
    if spec.slices.is_empty() {
        bail!("{}: no slices", path.display());
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut set = ContourSet::new();
    for (i, slice) in spec.slices.iter().enumerate() {
        let mut add = || -> anyhow::Result<()> {
            let plane = slice.plane()?;
            match (&slice.polylines, &slice.image) {
                (Some(lines), None) => {
                    let lines: Vec<Vec<Vec2>> =
                        lines.iter().map(|l| l.iter().map(|&p| Vec2::from(p)).collect()).collect();
                    set.add_polylines(&plane, &lines)?;
                }
                (None, Some(image)) => {
                    let image = dir.join(image);
                    let grid =
                        read_png_gray(&image).with_context(|| format!("cannot read {}", image.display()))?;
                    set.add_image(&plane, &grid, 0.5)?;
                }
                _ => bail!("give either `polylines` or `image`"),
            }
            Ok(())
        };
        add().with_context(|| format!("{}: slice {i}", path.display()))?;
    }
    Ok(set)
}

/// The contours of a folder of PNG slices at z = index × `spacing`.
fn folder(dir: &Path, spacing: f32) -> anyhow::Result<ContourSet> {
    if !(spacing.is_finite() && spacing > 0.0) {
        bail!("--spacing must be finite and positive, got {spacing}");
    }
    let mut images: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")))
        .collect();
    images.sort();
    if images.len() < 2 {
        bail!("{}: {} PNG slices; a reconstruction needs at least 2", dir.display(), images.len());
    }
    let mut set = ContourSet::new();
    for (i, image) in images.iter().enumerate() {
        let grid = read_png_gray(image).with_context(|| format!("cannot read {}", image.display()))?;
        let z = Vec3::Z * spacing * i as f32;
        let plane = Plane::new(z, Vec3::X, Vec3::Y)?;
        set.add_image(&plane, &grid, 0.5).with_context(|| format!("slice {}", image.display()))?;
    }
    Ok(set)
}
