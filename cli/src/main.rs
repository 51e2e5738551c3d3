//! The `isomorph` command line tool: run the demo, morph shapes and meshes,
//! and inspect meshes. `isomorph --help` lists the commands.

mod demo;
mod info;
mod inputs;
mod morph;
mod progress;

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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Morph(args) => morph::run(&args),
        Command::Info(args) => info::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
