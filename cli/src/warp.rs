//! `isomorph warp`: True's B-spline volume warp of a shape or mesh, driven by
//! dragged points (direct manipulation) and/or moved control points.

use crate::raw::RawArgs;
use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use isomorph_cli::parse::parse_pair;
use isomorph_common::glam::Vec3;
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::{Control, Grid3};
use isomorph_io::export::{ExportSettings, export_sequence};
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_io::mesh::{MeshFormat, write_mesh};
use isomorph_io::npy::{self, Volume};
use isomorph_io::raw::load_raw;
use isomorph_io::render::{Camera, RenderSettings, contact_sheet_titled, render};
use isomorph_warp::{Density, Evaluation, Filter, Handle, VolumeWarp, WarpAnimation, WarpSettings};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `isomorph warp`.
#[derive(Debug, Args)]
pub struct WarpArgs {
    /// A built-in shape (sphere, torus, ball, c-shape, mug, chain, cube, holed-cube, apple), a
    /// mesh file (.obj, .ply, .stl), kept in its own coordinates, or a volume:
    /// `.npy` (u8 densities 0–255, surface at 127.5; or f32/f64 fields,
    /// positive inside, surface at 0; placed by its `.json` sidecar if any,
    /// else in voxel units) or `.raw` (with `--raw-dims`).
    pub input: String,
    /// The layout of a `.raw` input.
    #[command(flatten)]
    pub raw: RawArgs,
    /// Drag the surface point X,Y,Z by DX,DY,DZ (world units), e.g.
    /// `--drag 0.3,0,0:0.2,0,0`. Repeat for several points; all land exactly
    /// where asked unless they conflict (then least squares).
    #[arg(long = "drag", value_parser = parse_pair, allow_hyphen_values = true)]
    pub drags: Vec<(Vec3, Vec3)>,
    /// Move control point I,J,K by DX,DY,DZ (world units), e.g.
    /// `--move 4,4,4:0,0.1,0`. Applied after the drags.
    #[arg(long = "move", value_parser = parse_pair, allow_hyphen_values = true)]
    pub moves: Vec<(Vec3, Vec3)>,
    /// Region of influence of the drags (world units): only control points
    /// resting within this distance of a dragged point move.
    #[arg(long, value_parser = parse_radius)]
    pub radius: Option<f32>,
    /// Control points per axis (the thesis' CSIZE, at least 4).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(4..=256))]
    pub csize: u32,
    /// How the density is pushed to the warped volume.
    #[arg(long, value_enum, default_value_t = FilterArg::Box)]
    pub filter: FilterArg,
    /// Grid nodes along the longest edge of the input's padded box.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub res: u32,
    /// Empty voxels added on every side of the warped volume (default: 4
    /// plus the longest drag or move, so the warped shape stays inside).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(isomorph_warp::MAX_PAD)))]
    pub pad: Option<u32>,
    /// Also write the warp as an animation of K frames from the identity to
    /// the edited map (every frame a B-spline warp) into OUT/frames, with
    /// its contact sheet and report.
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=1000))]
    pub frames: Option<u32>,
    /// Output folder: warped.npy (+ .json sidecar; density 0–1, surface at
    /// 0.5, f32 without quantization for f32 inputs), source.obj,
    /// warped.obj, before_after.png.
    #[arg(long)]
    pub out: PathBuf,
}

/// The `--filter` choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FilterArg {
    /// The antialiasing box filter (thesis §5.4).
    Box,
    /// Map each voxel centre and round (thesis §5.3; aliases).
    Round,
    /// Backward resampling by Newton inversion of the map.
    Backward,
}

/// Parses a positive finite radius.
fn parse_radius(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(r) if r.is_finite() && r > 0.0 => Ok(r),
        _ => Err(format!("'{s}' is not a positive radius (world units)")),
    }
}

/// The input as a density volume (True's convention: material high, the
/// surface at the middle level): u8 volumes as they are (0–255, surface at
/// 127.5); f32 fields (positive inside, surface at 0) and shapes and meshes
/// (their distance fields sampled at `res` nodes along the longest edge)
/// as f32 densities 0–1 with the surface at 0.5, never quantized.
fn density(args: &WarpArgs) -> anyhow::Result<Volume> {
    let volume = if args.input.ends_with(".npy") {
        Some(npy::load_npy(Path::new(&args.input))?)
    } else if args.input.ends_with(".raw") {
        let layout = args
            .raw
            .layout()
            .with_context(|| format!("{}: a .raw volume needs --raw-dims NX,NY,NZ", args.input))?;
        Some(load_raw(Path::new(&args.input), layout)?)
    } else {
        None
    };
    Ok(match volume {
        Some(Volume::U8(grid)) => Volume::U8(grid),
        Some(Volume::F32(field)) => {
            if let Some(node) = field.data().iter().position(|v| !v.is_finite()) {
                bail!("{}: value at node {node} is not finite", args.input);
            }
            Volume::F32(to_density(&field)?)
        }
        None => {
            let input = load_solid(&args.input, &LoadOptions { fit: false, ..LoadOptions::default() })?;
            let distance = input
                .distance_volume(&input.bounds().padded(0.15), args.res, &Control::new())
                .with_context(|| format!("cannot sample the distance field of {}", args.input))?;
            Volume::F32(to_density(&distance)?)
        }
    })
}

/// Density as in the thesis from a field (positive inside, world units):
/// 0–1, surface at 0.5, a ramp four voxels wide.
fn to_density(field: &Grid3<f32>) -> anyhow::Result<Grid3<f32>> {
    let h = field.spacing();
    Ok(field.map(|d| (0.5 + 0.25 * d / h).clamp(0.0, 1.0))?)
}

/// Runs `isomorph warp`.
pub fn run(args: &WarpArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    match density(args)? {
        Volume::U8(density) => warp_density(args, density, 255.0, start),
        Volume::F32(density) => warp_density(args, density, 1.0, start),
    }
}

/// Warps `density` (values up to `full`, surface at `full / 2`) as the
/// arguments say and writes the results; `start` is when the command began.
fn warp_density<T: Density>(
    args: &WarpArgs,
    density: Grid3<T>,
    full: f32,
    start: Instant,
) -> anyhow::Result<()> {
    let h = density.spacing();
    let to_voxels = |p: Vec3| density.to_grid(p);
    let filter = match args.filter {
        FilterArg::Box => Filter::Box,
        FilterArg::Round => Filter::Round,
        FilterArg::Backward => Filter::Backward,
    };
    let longest = args.drags.iter().chain(&args.moves).map(|(_, d)| d.length()).fold(0.0f32, f32::max);
    let pad = args.pad.unwrap_or(4 + (longest / h).ceil().min(1024.0) as u32);
    let settings = WarpSettings { csize: args.csize, pad, filter, evaluation: Evaluation::Auto };
    let mut warp = VolumeWarp::new(density.clone(), settings)?;
    let set_up = start.elapsed().as_secs_f64();
    let edit = Instant::now();
    if !args.drags.is_empty() {
        let handles: Vec<Handle> =
            args.drags.iter().map(|&(p, d)| Handle { point: to_voxels(p), goal: to_voxels(p + d) }).collect();
        let drag = warp.drag(&handles, args.radius.map(|r| r / h))?;
        println!("drag: {} control points moved, largest miss {:.4} voxels", drag.moves.len(), drag.residual);
    }
    for &(index, d) in &args.moves {
        if index.cmplt(Vec3::ZERO).any() || index.fract() != Vec3::ZERO {
            bail!("control point index {index} is not three non-negative integers");
        }
        let c = index.as_uvec3();
        let position = warp.map().control_point(c)? + d / h;
        warp.move_control_points(&[(c, position)])?;
    }
    let editing = edit.elapsed().as_secs_f64();
    let folded = warp.deformation().folded_cells();
    if folded > 0 {
        println!(
            "warning: the map folds space in {folded} voxel cells (not injective); overlapping parts are averaged"
        );
    }

    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let target = warp.target();
    let as_f32 = |g: &Grid3<T>| g.map(|&v| v.to_f32() / full);
    let warped = as_f32(target)?;
    let npy_path = args.out.join("warped.npy");
    npy::save_npy(&warped, &npy_path)?;
    // The map in world coordinates: `morph --method level-set --warp-map`
    // reads it as Breen & Whitaker's generalized warp.
    let map_path = args.out.join("map.json");
    std::fs::write(&map_path, warp.world_map().to_json())
        .with_context(|| format!("cannot write {}", map_path.display()))?;
    let before = marching_cubes(&as_f32(&density)?, 0.5);
    let after = marching_cubes(&warped, 0.5);
    for (mesh, name) in [(&before, "source.obj"), (&after, "warped.obj")] {
        let path = args.out.join(name);
        write_mesh(mesh, &path, MeshFormat::Obj)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    // One camera for both, so the edit shows as a change of shape and size.
    let both = before.bounds().union(&after.bounds());
    let view =
        RenderSettings { camera: Some(Camera::fit(&both, Camera::DEFAULT_VIEW_DIR)), ..Default::default() };
    let sheet = contact_sheet_titled(
        &[(render(&before, &view), "before".to_string()), (render(&after, &view), "after".to_string())],
        2,
        &format!("isomorph warp: {}", args.input),
    );
    sheet.write_png(args.out.join("before_after.png"))?;
    let d = target.dims();
    println!(
        "{}: {} x {} x {} warped voxels, CSIZE {}, {:?} filter; set-up {set_up:.3} s, edits {editing:.3} s, total {:.3} s",
        args.input,
        d.x,
        d.y,
        d.z,
        args.csize,
        args.filter,
        start.elapsed().as_secs_f64()
    );
    println!("  wrote {} (+ .json), map.json, source.obj, warped.obj, before_after.png", npy_path.display());
    if let Some(frames) = args.frames {
        let animation = WarpAnimation::new(density, warp.map().clone(), settings, full / 2.0)?;
        let export = ExportSettings {
            frames: frames as usize,
            out_dir: args.out.join("frames"),
            ..ExportSettings::default()
        };
        let report = export_sequence(&animation, &export, &Control::new())?.report;
        println!(
            "  wrote {} frames of the warp animation to {}",
            report.frames.len(),
            export.out_dir.display()
        );
    }
    Ok(())
}
