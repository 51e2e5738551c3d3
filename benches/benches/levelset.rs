//! Benchmarks of the level-set morph (Breen & Whitaker): the issue's
//! reference case, sphere r = 0.3 → torus R = 0.3, r = 0.12 in [-0.5, 0.5]³
//! on N³ nodes with the target signed distance as speed.
//!
//! `cargo bench -p isomorph-benches --bench levelset -- morph/sphere_torus/sparse/128`
//! `cargo bench -p isomorph-benches --bench levelset -- step/sphere_torus`

use criterion::{BatchSize, BenchmarkId, Criterion, criterion_group, criterion_main};
use isomorph_common::{Aabb, Grid3, Shape};
use isomorph_levelset::{
    DenseSolver, EvolveSettings, FrameSchedule, Response, Solver, SparseFieldSolver, SpeedGrid, StepParams,
    evolve,
};
use std::hint::black_box;

/// Source distance grid and target speed of the reference case.
fn case(n: u32) -> (Grid3<f32>, SpeedGrid) {
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), n).unwrap();
    let speed = SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, Response::Identity).unwrap();
    (source, speed)
}

/// The whole sparse-field evolution to convergence (distance volumes
/// given). The dense solver is benched per iteration only: bound by eq. 24
/// over the whole grid it needs thousands of iterations for the same
/// evolution time (`cargo run --release -p isomorph-levelset --example
/// reference_case -- 64 dense` times one whole run).
fn morph(c: &mut Criterion) {
    let mut group = c.benchmark_group("morph/sphere_torus");
    group.sample_size(10);
    let settings =
        EvolveSettings { frames: FrameSchedule::EveryIterations(usize::MAX), ..Default::default() };
    for n in [64u32, 128, 256] {
        let (source, speed) = case(n);
        group.bench_function(BenchmarkId::new("sparse", n), |b| {
            b.iter(|| black_box(evolve(&source, &speed, None, &settings, &|_| {}).unwrap().len()))
        });
    }
    group.finish();
}

/// One iteration from the source state: the per-iteration cost, which
/// grows like the surface for the sparse field and like the volume for the
/// dense solver.
fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step/sphere_torus");
    group.sample_size(10);
    for n in [64u32, 128, 256] {
        let (source, speed) = case(n);
        let params = StepParams::default();
        let sparse = SparseFieldSolver::new(&source).unwrap();
        group.bench_function(BenchmarkId::new("sparse", n), |b| {
            b.iter_batched_ref(
                || sparse.clone(),
                |s| black_box(s.step(&speed, &params)),
                BatchSize::LargeInput,
            )
        });
        let dense = DenseSolver::new(&source).unwrap();
        group.bench_function(BenchmarkId::new("dense", n), |b| {
            b.iter_batched_ref(
                || dense.clone(),
                |s| black_box(s.step(&speed, &params)),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, morph, step);
criterion_main!(benches);
