//! Fit time and peak memory of the reference case (sphere at t = 0, torus
//! at t = 1, boundary and inward normal constraints) at a given size:
//!
//! `cargo run --release -p isomorph-rbf --example fit_scale -- 100000 tps hierarchical`
//!
//! Arguments: constraints, kernel (`tps`, `r3`), solver (`auto`, `dense`,
//! `hierarchical`). Prints the fit report, the fit time and the process's
//! peak resident memory (Linux `VmHWM`).

use isomorph_common::{Aabb, Shape};
use isomorph_rbf::constraints::{NormalOffset, Subsample, SurfaceSettings, field_constraints};
use isomorph_rbf::{FitSettings, Interpolant, Kernel, Solver, lift};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let total: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(16_000);
    let kernel = args.get(2).and_then(|s| Kernel::from_name(s)).unwrap_or_default();
    let solver = match args.get(3).map(String::as_str) {
        Some("dense") => Solver::Dense,
        Some("hierarchical") => Solver::Hierarchical,
        _ => Solver::Auto,
    };
    let s = SurfaceSettings {
        offset: NormalOffset::Absolute(0.01),
        subsample: Subsample::FarthestPoint(total / 4),
    };
    let shapes = [Shape::sphere(0.3), Shape::torus(0.3, 0.12)]
        .map(|shape| field_constraints(&shape, &Aabb::cube(0.5), 128, &s).unwrap());
    let mut cs = lift::<3, 4>(&shapes[0], &[0.0]);
    cs.extend(lift::<3, 4>(&shapes[1], &[1.0]));
    let start = Instant::now();
    let fit =
        Interpolant::fit(&cs, &FitSettings { solver, ..FitSettings::default().with_kernel(kernel) }).unwrap();
    println!(
        "{} constraints, {kernel:?}: fit {:.2} s, {:?}",
        cs.len(),
        start.elapsed().as_secs_f64(),
        fit.report()
    );
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let peak = status.lines().find(|l| l.starts_with("VmHWM")).unwrap_or("VmHWM: ?");
    println!("peak memory {peak}");
}
