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
mod raw;
mod rbf;
mod reconstruct;
mod sdf;
mod warp;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// Implicit and volumetric 3D shape metamorphosis.
#[derive(Debug, Parser)]
#[command(name = "isomorph", version, about, long_about = None)]
struct Cli {
    /// Largest allocation sized by the input (a grid, a dense system, a
    /// decoded image), e.g. `512M`, `16G` or a byte count; larger requests
    /// are refused with an error instead of exhausting the machine.
    #[arg(long, global = true, value_parser = parse_bytes, default_value = "8G")]
    max_memory: usize,
    #[command(subcommand)]
    command: Command,
}

/// Parses a byte count with an optional binary unit (`K`, `M`, `G`, `T`,
/// optionally followed by `iB` or `B`).
fn parse_bytes(s: &str) -> Result<usize, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let shift = match unit.to_ascii_uppercase().trim_end_matches("IB").trim_end_matches('B') {
        "" => 0,
        "K" => 10,
        "M" => 20,
        "G" => 30,
        "T" => 40,
        _ => return Err(format!("'{s}' is not a size such as 512M or 16G (units K, M, G, T)")),
    };
    let value: f64 = number.trim().parse().map_err(|_| format!("'{s}' is not a size such as 512M or 16G"))?;
    let bytes = value * (1u64 << shift) as f64;
    if bytes.is_nan() || bytes < 1.0 || bytes >= usize::MAX as f64 {
        return Err(format!("'{s}' is not a size between 1 byte and 16 EiB"));
    }
    Ok(bytes as usize)
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
    /// Reconstruct a surface from planar contours (Turk & O'Brien §6): a
    /// JSON file of slices or a folder of PNG slices.
    Reconstruct(reconstruct::ReconstructArgs),
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
    isomorph_common::set_memory_limit(cli.max_memory);
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
        Command::Reconstruct(args) => reconstruct::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", message(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, each cause once: library errors
/// often include their cause in their own message, which `{:#}` would then
/// print twice. The libraries' "raise the memory limit" becomes the option
/// that does it.
fn message(e: &anyhow::Error) -> String {
    isomorph_io::compare::error_chain(e.as_ref()).replace("raise the memory limit", "raise --max-memory")
}
