//! `isomorph compare`: every method (or a list) on one input pair, side by
//! side: each method's frames and report, one contact sheet with a row per
//! method, and a table as JSON, Markdown and a self-contained HTML page.

use crate::morph::Io;
use crate::options::{MethodArgs, refuse_foreign};
use crate::progress;
use anyhow::Context;
use clap::{ArgMatches, Args};
use isomorph_cli::methods::{Method, build};
use isomorph_common::Control;
use isomorph_io::compare::{Candidate, Comparison, Status, compare};
use isomorph_io::export::reference_surfaces;
use std::path::PathBuf;

/// Arguments of `isomorph compare`.
#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    /// The methods to run, comma-separated, or `all`.
    #[arg(long, default_value = "all", value_parser = parse_methods)]
    pub methods: MethodList,
    /// Inputs, resolution, frames.
    #[command(flatten)]
    pub io: Io,
    /// Method options (each applies to its method only).
    #[command(flatten)]
    pub options: MethodArgs,
    /// Output folder: one subfolder per method, compare.png, compare.json,
    /// compare.md, compare.html.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
}

/// The value of `--methods`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MethodList(pub Vec<Method>);

fn parse_methods(s: &str) -> Result<MethodList, String> {
    if s == "all" {
        return Ok(MethodList(Method::ALL.to_vec()));
    }
    let mut list = Vec::new();
    for name in s.split(',').map(str::trim) {
        let method = Method::from_name(name).ok_or_else(|| {
            let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
            format!("unknown method '{name}' (expected all or some of {})", names.join(", "))
        })?;
        if !list.contains(&method) {
            list.push(method);
        }
    }
    Ok(MethodList(list))
}

/// Runs `isomorph compare`.
///
/// # Errors
/// Bad options, unreadable inputs, files that cannot be written,
/// cancellation. A method that fails is a row of the table, not an error.
pub fn run(args: &CompareArgs, matches: &ArgMatches) -> anyhow::Result<()> {
    let methods = &args.methods.0;
    refuse_foreign(matches, methods)?;
    let io = args.io.for_options(&args.options);
    let (control, bar) = progress::control("compare", io.threads.map(|n| n as usize))?;
    let settings = io.settings(&args.options)?;
    // The shared references: the inputs as the non-BlobTree methods read them.
    let shared = io.inputs(Method::Baseline);
    let export = match &shared {
        Ok(inputs) => io.export(args.out.clone(), inputs, &control)?,
        Err(_) => io.export(args.out.clone(), &io.inputs(Method::Blobtree)?, &control)?,
    };
    let candidates = methods
        .iter()
        .map(|&method| candidate(method, &io, &settings, &control))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let comparison = compare(&io.source, &io.target, candidates, &export, &control);
    bar.finish_and_clear();
    let comparison =
        comparison.with_context(|| format!("cannot write the comparison to {}", args.out.display()))?;
    print_table(&comparison);
    println!("  wrote {}/compare.{{png,json,md,html}} and one folder per method", args.out.display());
    Ok(())
}

/// `method` on the inputs as it reads them, or why it cannot run.
fn candidate(
    method: Method,
    io: &Io,
    settings: &isomorph_cli::methods::Settings,
    control: &Control,
) -> anyhow::Result<Candidate> {
    let name = method.name().to_string();
    let inputs = match io.inputs(method) {
        Ok(inputs) => inputs,
        Err(e) => return Ok(Candidate { name, build: Err(format!("{e:#}")), references: None }),
    };
    let references = if method == Method::Blobtree {
        Some(reference_surfaces(&inputs.0, &inputs.1, io.resolution(), control)?)
    } else {
        None
    };
    let settings = settings.clone();
    Ok(Candidate {
        name,
        build: Ok(Box::new(move |control: &Control| build(method, &inputs.0, &inputs.1, &settings, control))),
        references,
    })
}

/// The table on stdout.
fn print_table(c: &Comparison) {
    println!("compare {} -> {} at {}^3, {} frames", c.source, c.target, c.resolution, c.frames);
    println!(
        "  {:<10} {:>8} {:>9} {:>9} {:>12} {:>12} {:>5}",
        "method", "status", "build s", "frames s", "source mean", "target mean", "comp"
    );
    let num = |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
    for r in &c.rows {
        let status = match r.status {
            Status::Ok if r.converged == Some(false) => "stalled",
            Status::Ok => "ok",
            Status::Skipped => "skipped",
            Status::Failed => "failed",
        };
        println!(
            "  {:<10} {:>8} {:>9} {:>9} {:>12} {:>12} {:>5}",
            r.method,
            status,
            num(r.build_seconds, 2),
            num(r.export_seconds, 2),
            num(r.source_mean_voxels.map(f64::from), 3),
            num(r.target_mean_voxels.map(f64::from), 3),
            r.max_components.map_or("-".to_string(), |n| n.to_string())
        );
        if let Some(reason) = &r.reason {
            println!("  {:<10} {reason}", "");
        }
    }
}
