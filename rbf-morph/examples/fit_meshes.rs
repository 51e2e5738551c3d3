//! Fit of the RBF morph's constraints between two real meshes, as
//! `isomorph morph --method rbf` makes them (meshes fitted to the unit box,
//! `points` farthest-point samples per shape, boundary and inward normal
//! constraints, source at t = 0 and target at t = 1):
//!
//! `cargo run --release -p isomorph-rbf --example fit_meshes -- SOURCE TARGET POINTS [KERNEL] [SOLVER]`
//!
//! Prints the constraints' hygiene figures (closest pairs against the
//! normal offset, normal constraints nearer another part of the surface
//! than their own point), the fit report, the fit time and the peak memory.

use isomorph_common::Control;
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_rbf::constraints::{NormalOffset, Subsample, SurfaceSettings, mesh_constraints};
use isomorph_rbf::{Centres, Constraint, FitSettings, GreedySettings, Interpolant, Kernel, Solver, lift};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!(
            "usage: fit_meshes SOURCE TARGET POINTS [tps|r3] [auto|dense|hierarchical|greedy=TOL] [compare|residual]"
        );
        std::process::exit(2);
    }
    let points: usize = args[3].parse().expect("POINTS is a number");
    let kernel = args.get(4).and_then(|s| Kernel::from_name(s)).unwrap_or_default();
    let solver = match args.get(5).map(String::as_str) {
        Some("dense") => Solver::Dense,
        Some("hierarchical") => Solver::Hierarchical,
        _ => Solver::Auto,
    };
    // `greedy=TOL` in place of a solver: greedy centres to that tolerance.
    let centres = match args.get(5).and_then(|s| s.strip_prefix("greedy=")) {
        Some(tol) => Centres::Greedy(GreedySettings {
            tolerance: tol.parse().expect("a tolerance"),
            ..GreedySettings::default()
        }),
        None => Centres::All,
    };
    let surface = SurfaceSettings {
        offset: NormalOffset::RelativeToDiagonal(0.01),
        subsample: Subsample::FarthestPoint(points),
    };
    let control = Control::new();
    let shapes: Vec<Vec<Constraint<3>>> = args[1..3]
        .iter()
        .map(|spec| {
            let solid = load_solid(spec, &LoadOptions::default()).expect("readable input");
            let mesh = solid.surface(64, &control).expect("a surface");
            mesh_constraints(&mesh, &surface).expect("constraints")
        })
        .collect();
    for (name, cs) in ["source", "target"].iter().zip(&shapes) {
        hygiene(name, cs);
    }
    let mut cs = lift::<3, 4>(&shapes[0], &[0.0]);
    cs.extend(lift::<3, 4>(&shapes[1], &[1.0]));
    let start = Instant::now();
    let fit =
        Interpolant::fit(&cs, &FitSettings { solver, centres, ..FitSettings::default().with_kernel(kernel) });
    println!("{} constraints, {kernel:?}: fit {:.2} s", cs.len(), start.elapsed().as_secs_f64());
    match &fit {
        Ok(fit) => println!("{:?}", fit.report()),
        Err(e) => println!("error: {e}"),
    }
    match (&fit, args.get(6).map(String::as_str)) {
        (Ok(fit), Some("compare")) => compare(fit, &cs, kernel),
        (Ok(fit), Some("residual")) => residual(fit, &cs),
        _ => {}
    }
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let peak = status.lines().find(|l| l.starts_with("VmHWM")).unwrap_or("VmHWM: ?");
    println!("peak memory {peak}");
}

/// Prints the closest pairs of one shape's constraints (pairs of boundary
/// point `b` and normal point `b − k n`) against the offset `k`.
fn hygiene(name: &str, cs: &[Constraint<3>]) {
    let p = |c: &Constraint<3>| glam::Vec3::from_array(c.position);
    let k = cs.chunks(2).map(|pair| p(&pair[0]).distance(p(&pair[1]))).fold(0.0f32, f32::max);
    let boundary: Vec<glam::Vec3> = cs.iter().step_by(2).map(p).collect();
    let normal: Vec<glam::Vec3> = cs.iter().skip(1).step_by(2).map(p).collect();
    // Distance from `q` to the nearest boundary point other than the `i`-th.
    let nearest_other = |i: usize, q: glam::Vec3| {
        boundary
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, b)| b.distance(q))
            .fold(f32::INFINITY, f32::min)
    };
    // Normal points nearer another boundary point than their own.
    let mut crossing = [0usize; 3];
    let mut closest_other = f32::INFINITY;
    for (i, q) in normal.iter().enumerate() {
        let d = nearest_other(i, *q);
        closest_other = closest_other.min(d);
        for (slot, frac) in crossing.iter_mut().zip([1.0, 0.5, 0.25]) {
            if d < frac * k {
                *slot += 1;
            }
        }
    }
    let mut nn_boundary: Vec<f32> = boundary.iter().enumerate().map(|(i, b)| nearest_other(i, *b)).collect();
    nn_boundary.sort_by(f32::total_cmp);
    let q = |f: f64| nn_boundary[((nn_boundary.len() - 1) as f64 * f) as usize];
    println!(
        "{name}: {} points, offset k {k:.4}; nearest-boundary spacing min {:.2e} p1 {:.2e} median {:.2e} p99 {:.2e}; \
         normal points nearer another boundary point than k: {}, than k/2: {}, than k/4: {} (closest {closest_other:.2e})",
        boundary.len(),
        q(0.0),
        q(0.01),
        q(0.5),
        q(0.99),
        crossing[0],
        crossing[1],
        crossing[2],
    );
}

/// Prints the exact (f64, direct sum) residuals `|f(x_i) − h_i|` of `fit`
/// at every constraint: largest, 99th percentile, and how many exceed
/// 1e-3, 1e-2 and 1e-1 (the normal constraints' value is 1).
fn residual(fit: &Interpolant<4>, cs: &[Constraint<4>]) {
    use rayon::prelude::*;
    let start = Instant::now();
    let mut r: Vec<f64> = cs
        .par_iter()
        .map(|c| (fit.value_f64(c.position.map(f64::from)) - f64::from(c.value)).abs())
        .collect();
    r.sort_by(f64::total_cmp);
    let over = |t: f64| r.iter().filter(|&&x| x > t).count();
    println!(
        "exact residual at {} constraints ({:.1} s): max {:.3e}, p99 {:.3e}, median {:.3e}; over 1e-3: {}, 1e-2: {}, 1e-1: {}",
        r.len(),
        start.elapsed().as_secs_f64(),
        r[r.len() - 1],
        r[(r.len() - 1) * 99 / 100],
        r[r.len() / 2],
        over(1e-3),
        over(1e-2),
        over(1e-1)
    );
}

/// Compares `fit` with the dense solve at probe points: every 7th
/// constraint, and a 24⁴ lattice over the constraints' box (so between
/// the shapes and away from them).
fn compare(fit: &Interpolant<4>, cs: &[Constraint<4>], kernel: Kernel) {
    let start = Instant::now();
    let dense = Interpolant::fit(
        cs,
        &FitSettings { solver: Solver::Dense, ..FitSettings::default().with_kernel(kernel) },
    )
    .expect("dense fit");
    println!("dense fit {:.2} s, {:?}", start.elapsed().as_secs_f64(), dense.report());
    let (mut lo, mut hi) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4]);
    for c in cs {
        for k in 0..4 {
            lo[k] = lo[k].min(f64::from(c.position[k]));
            hi[k] = hi[k].max(f64::from(c.position[k]));
        }
    }
    let m = 24usize;
    let lattice = (0..m.pow(4)).map(|i| {
        std::array::from_fn::<f64, 4, _>(|k| {
            let j = (i / m.pow(k as u32)) % m;
            lo[k] + (hi[k] - lo[k]) * j as f64 / (m - 1) as f64
        })
    });
    let at_constraints = cs.iter().step_by(7).map(|c| c.position.map(f64::from));
    for (name, probes) in
        [("constraints", at_constraints.collect::<Vec<_>>()), ("lattice", lattice.collect())]
    {
        let (mut worst, mut flo, mut fhi, mut sign) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY, 0usize);
        for x in &probes {
            let (f, d) = (fit.value_f64(*x), dense.value_f64(*x));
            worst = worst.max((f - d).abs());
            flo = flo.min(d);
            fhi = fhi.max(d);
            sign += usize::from((f > 0.0) != (d > 0.0));
        }
        println!(
            "{name}: {} probes, max |f_H - f_dense| {worst:.3e}, range of f_dense {:.3e}, sign differs at {sign}",
            probes.len(),
            fhi - flo
        );
    }
}
