//! The reference case: sphere r = 0.3 → torus R = 0.3, r = 0.12 in
//! [-0.5, 0.5]³ on N³ nodes, speed = target signed distance. Prints the
//! iterations, the evolution time and the error of the final surface
//! (marching-cubes vertices) against the analytic torus, in voxels. The
//! dense solver runs for the evolution time the sparse field needed.
//!
//! `cargo run --release -p isomorph-levelset --example reference_case -- 128 sparse`

use isomorph_common::{Aabb, Control, Field3, Grid3, Morph, Shape};
use isomorph_levelset::{EvolveSettings, FrameSchedule, Placement, Response, SolverKind, SpeedGrid, evolve};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: u32 = args.next().map_or(Ok(128), |a| a.parse())?;
    let solver = match args.next().as_deref() {
        Some("dense") => SolverKind::Dense,
        _ => SolverKind::SparseField,
    };
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), n)?;
    let torus = Shape::torus(0.3, 0.12);
    let speed = SpeedGrid::sample(&source, &torus, |x| x, Response::Identity)?;
    let mut settings =
        EvolveSettings { solver, frames: FrameSchedule::EveryIterations(usize::MAX), ..Default::default() };
    if solver == SolverKind::Dense {
        let sparse = EvolveSettings { solver: SolverKind::SparseField, ..settings };
        settings.end_time =
            evolve(&source, &speed, Placement::Identity, &sparse, &Control::new())?.end_time();
        settings.max_iterations = 100_000;
    }
    let start = Instant::now();
    let morph = evolve(&source, &speed, Placement::Identity, &settings, &Control::new())?;
    let seconds = start.elapsed().as_secs_f64();
    let mesh = morph.frame_mesh(1.0, 0)?;
    let h = source.spacing();
    let errors: Vec<f32> = mesh.positions.iter().map(|&p| torus.value(p).abs() / h).collect();
    let mean = errors.iter().sum::<f32>() / errors.len() as f32;
    let max = errors.iter().fold(0.0f32, |a, &b| a.max(b));
    let last = morph.stats().last().copied().unwrap_or_default();
    println!(
        "{solver:?} {n}^3: {} iterations in {seconds:.3} s (converged: {}), final RMS distance {:.4} voxels; \
         surface error vs analytic torus: mean {mean:.4}, max {max:.4} voxels; genus {:?}",
        morph.stats().len(),
        morph.converged(),
        last.rms_distance,
        mesh.genus()
    );
    Ok(())
}
