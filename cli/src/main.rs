//! The `isomorph` command line tool: run the demo, morph and compare shapes
//! and meshes, inspect meshes, write distance volumes, align and warp
//! shapes. `isomorph --help` lists the commands. The morphs themselves are
//! the libraries' (through [`isomorph_cli::methods`]); this binary parses
//! arguments, drives progress bars and prints summaries.

mod align;
mod blob;
mod compare;
mod demo;
mod info;
mod morph;
mod options;
mod progress;
mod rbf;
mod sdf;
mod warp;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
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
    /// Run several methods on one pair side by side: frames, one contact
    /// sheet with a row per method, and a table (JSON, Markdown, HTML).
    Compare(compare::CompareArgs),
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
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let sub = |name: &str| matches.subcommand_matches(name).expect("the parsed subcommand");
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Morph(args) => morph::run(&args, sub("morph")),
        Command::Compare(args) => compare::run(&args, sub("compare")),
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
