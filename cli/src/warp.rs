//! `isomorph warp`: True's B-spline volume warp of a shape or mesh, driven by
//! dragged points (direct manipulation) and/or moved control points.

use crate::inputs::Input;
use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use isomorph_common::glam::Vec3;
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::mesh::io::{MeshFormat, write_mesh};
use isomorph_common::render::{RenderSettings, contact_sheet_titled, render};
use isomorph_common::{Grid3, npy};
use isomorph_warp::{Evaluation, Filter, Handle, VolumeWarp, WarpSettings};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `isomorph warp`.
#[derive(Debug, Args)]
pub struct WarpArgs {
    /// A built-in shape (sphere, torus, ball, c-shape, mug, chain, cube) or a
    /// mesh file (.obj, .ply, .stl), kept in its own coordinates.
    pub input: String,
    /// Drag the surface point X,Y,Z by DX,DY,DZ (world units), e.g.
    /// `--drag 0.3,0,0:0.2,0,0`. Repeat for several points; all land exactly
    /// where asked unless they conflict (then least squares).
    #[arg(long = "drag", value_parser = parse_pair)]
    pub drags: Vec<(Vec3, Vec3)>,
    /// Move control point I,J,K by DX,DY,DZ (world units), e.g.
    /// `--move 4,4,4:0,0.1,0`. Applied after the drags.
    #[arg(long = "move", value_parser = parse_pair)]
    pub moves: Vec<(Vec3, Vec3)>,
    /// Region of influence of the drags (world units): only control points
    /// resting within this distance of a dragged point move.
    #[arg(long)]
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
    #[arg(long)]
    pub pad: Option<u32>,
    /// Output folder: warped.npy (+ .json sidecar), source.obj, warped.obj,
    /// before_after.png.
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

/// Parses `A,B,C:D,E,F` into two vectors.
fn parse_pair(s: &str) -> Result<(Vec3, Vec3), String> {
    let (a, b) = s.split_once(':').ok_or_else(|| format!("'{s}' is not of the form X,Y,Z:DX,DY,DZ"))?;
    let vec = |t: &str| -> Result<Vec3, String> {
        let v: Vec<f32> = t
            .split(',')
            .map(|x| x.trim().parse::<f32>().map_err(|e| format!("'{x}': {e}")))
            .collect::<Result<_, _>>()?;
        match v[..] {
            [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
            _ => Err(format!("'{t}' is not three finite numbers")),
        }
    };
    Ok((vec(a)?, vec(b)?))
}

/// Runs `isomorph warp`.
pub fn run(args: &WarpArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let input = Input::parse(&args.input, false)?;
    let distance = Grid3::sample_box(input.field(), &input.bounds().padded(0.15), args.res)
        .with_context(|| format!("cannot sample the distance field of {}", args.input))?;
    // Density as in the thesis: 0–255, surface at 127.5, a two-voxel ramp.
    let h = distance.spacing();
    let density = distance.map(|d| (127.5 + 64.0 * d / h).clamp(0.0, 255.0) as u8)?;
    let to_voxels = |p: Vec3| distance.to_grid(p);
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
    let as_f32 = |g: &Grid3<u8>| g.map(|&v| f32::from(v) / 255.0);
    let warped = as_f32(target)?;
    let npy_path = args.out.join("warped.npy");
    npy::save_npy(&warped, &npy_path)?;
    let before = marching_cubes(&as_f32(&density)?, 0.5);
    let after = marching_cubes(&warped, 0.5);
    for (mesh, name) in [(&before, "source.obj"), (&after, "warped.obj")] {
        let path = args.out.join(name);
        write_mesh(mesh, &path, MeshFormat::Obj)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let view = RenderSettings::default();
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
    println!("  wrote {} (+ .json), source.obj, warped.obj, before_after.png", npy_path.display());
    Ok(())
}
