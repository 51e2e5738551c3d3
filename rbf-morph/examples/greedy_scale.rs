//! Greedy centre selection (FastRBF's "fit to an accuracy") at up to
//! millions of constraints: a sphere (radius 0.3) at t = 0 and a torus
//! (R = 0.3, r = 0.12) at t = 1, each sampled at `total / 4` analytic
//! surface points (Fibonacci spiral) giving a boundary (0) and an inward
//! normal (1, offset 0.01) constraint:
//!
//! `cargo run --release -p isomorph-rbf --example greedy_scale -- 1000000 0.01 tps`
//!
//! Arguments: constraints, tolerance (relative to the normal value), kernel
//! (`tps`, `r3`), most centres (default 16000), centres of the first round
//! (default 1000). Prints the rounds (centres, largest residual over every
//! constraint), the time, an exact f64 check of the residual at 20000
//! constraints spread over the set, and the peak resident memory (Linux
//! `VmHWM`).

use isomorph_rbf::{Centres, Constraint, FitSettings, GreedySettings, Interpolant, Kernel};
use std::f32::consts::{PI, TAU};
use std::time::Instant;

/// The constraints of `n` surface points per shape.
fn sphere_torus(n: usize) -> Vec<Constraint<4>> {
    let golden = PI * (3.0 - 5.0f32.sqrt());
    let mut out = Vec::with_capacity(4 * n);
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let r = (1.0 - z * z).sqrt();
        let (s, c) = (golden * i as f32).sin_cos();
        let d = [r * c, r * s, z];
        out.push(Constraint::new([0.3 * d[0], 0.3 * d[1], 0.3 * d[2], 0.0], 0.0));
        out.push(Constraint::new([0.29 * d[0], 0.29 * d[1], 0.29 * d[2], 0.0], 1.0));
        // The torus: u around the ring, v around the tube (golden angle).
        let (u, v) = (TAU * i as f32 / n as f32, (golden * i as f32) % TAU);
        for (tube, value) in [(0.12f32, 0.0f32), (0.11, 1.0)] {
            let ring = 0.3 + tube * v.cos();
            out.push(Constraint::new([ring * u.cos(), ring * u.sin(), tube * v.sin(), 1.0], value));
        }
    }
    out
}

/// The process's peak resident memory in MB (Linux), if known.
fn peak_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let total: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
    let tolerance: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1e-2);
    let kernel = args.get(3).and_then(|s| Kernel::from_name(s)).unwrap_or_default();
    let defaults = GreedySettings::default();
    let max_centres: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(defaults.max_centres);
    let cs = sphere_torus(total / 4);
    let initial: usize = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(defaults.initial);
    let greedy = GreedySettings { tolerance, max_centres, initial };
    let settings =
        FitSettings { centres: Centres::Greedy(greedy), ..FitSettings::default().with_kernel(kernel) };
    let start = Instant::now();
    let fit = match Interpolant::fit(&cs, &settings) {
        Ok(fit) => fit,
        Err(e) => {
            eprintln!("greedy fit failed: {e}");
            std::process::exit(1);
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    let report = fit.report();
    let greedy = report.greedy.clone().expect("a greedy report");
    for round in &greedy.rounds {
        println!("round: {} centres, max residual {:.3e}", round.centres, round.max_residual);
    }
    // An exact (f64, direct) check at constraints spread over the set.
    let step = (cs.len() / 20_000).max(1);
    let exact = cs
        .iter()
        .step_by(step)
        .map(|c| (fit.value_f64(c.position.map(f64::from)) - f64::from(c.value)).abs())
        .fold(0.0, f64::max);
    println!(
        "{} constraints, {kernel:?}, tolerance {tolerance}: {} centres, converged {}, max residual {:.3e} \
         (exact f64 at every {step}th: {exact:.3e}), {seconds:.1} s, peak {:.0} MB",
        cs.len(),
        fit.len(),
        greedy.converged,
        report.max_residual.unwrap_or(f64::NAN),
        peak_mb().unwrap_or(f64::NAN),
    );
}
