//! The `isomorph` command line tool: run the demo, morph shapes and meshes,
//! inspect meshes, write distance volumes, align and warp shapes. `isomorph --help`
//! lists the commands.

mod align;
mod blob;
mod demo;
mod info;
mod inputs;
mod level_set;
mod morph;
mod progress;
mod rbf;
mod sdf;
mod tspline;
mod warp;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Implicit and volumetric 3D shape metamorphosis.
#[derive(Debug, Parser)]
#[command(name = "isomorph", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Write a complete example (frames, contact sheet, report) into a folder.
    Demo(demo::DemoArgs),
    /// Morph a source shape or mesh into a target and export the frames.
    Morph(morph::MorphArgs),
    /// Print metrics of a mesh file (OBJ, PLY or STL).
    Info(info::InfoArgs),
    /// Write the signed distance volume of a shape or mesh as NumPy .npy
    /// (f32, shape (nz, ny, nx), x fastest) plus a JSON sidecar.
    Sdf(sdf::SdfArgs),
    /// Align a source onto a target by their moments: print the map as JSON
    /// and write the aligned source mesh.
    Align(align::AlignArgs),
    /// Transform one 2D shape into another (Turk & O'Brien): PNG frames of
    /// the in-between shapes and the 3D space-time surface.
    Contours(rbf::ContoursArgs),
    /// Polygonize one BlobTree (scene file or built-in) and preview it.
    Blob(blob::BlobArgs),
    /// Warp a shape or mesh with True's trivariate B-spline volume warp: drag
    /// surface points or move control points; writes the warped volume
    /// (.npy), meshes and a before/after PNG.
    Warp(warp::WarpArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Morph(args) => morph::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Sdf(args) => sdf::run(&args),
        Command::Align(args) => align::run(&args),
        Command::Warp(args) => warp::run(&args),
        Command::Blob(args) => blob::run(&args),
        Command::Contours(args) => rbf::contours(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
