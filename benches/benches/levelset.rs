//! Benchmarks of the level-set morph (Breen & Whitaker): the issue's
//! reference case, sphere r = 0.3 → torus R = 0.3, r = 0.12 in [-0.5, 0.5]³
//! on N³ nodes with the target signed distance as speed.
//!
//! `cargo bench -p isomorph-benches --bench levelset -- morph/sphere_torus/sparse/128`
//! `cargo bench -p isomorph-benches --bench levelset -- step/sphere_torus/sparse/1024`
//! `cargo bench -p isomorph-benches --bench levelset -- memory/sphere_torus/512` (one size per run:
//! the peak resident set is the process's)
//! `cargo bench -p isomorph-benches --bench levelset -- cli/sphere_torus/128`
//! `cargo bench -p isomorph-benches --bench levelset -- real/bunny_teapot/128` (real meshes; set
//! `ISOMORPH_BENCH_TARGET` to another mesh file for `real/bunny_<its name>/N`)

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use isomorph_cli::methods::{Method, Settings, build, load_input};
use isomorph_common::sdf::{MeshSdf, SdfSettings, VolumeMode};
use isomorph_common::{Aabb, Bricks, Bytes, Control, Field3, Grid3, Morph, Shape, Solid, lattice_for_box};
use isomorph_io::export::{ExportSettings, export_sequence};
use isomorph_levelset::{
    Align, DenseSolver, EvolveSettings, FrameSchedule, LevelSetMorph, LevelSetSettings, Placement, Response,
    Solver, SolverKind, SparseFieldSolver, SpeedGrid, StepParams, Storage, evolve,
};
use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Prints the error of the final surface (marching-cubes vertices) against
/// the analytic torus, in voxels, with the iterations it took, beside the
/// grid's own floor: the same error for marching cubes of the torus's exact
/// distance sampled on the same lattice.
fn print_accuracy(n: u32, morph: &LevelSetMorph, voxel: f32) {
    let torus = Shape::torus(0.3, 0.12);
    let error = |mesh: &isomorph_common::TriMesh| {
        let errors: Vec<f32> = mesh.positions.iter().map(|&p| torus.value(p).abs() / voxel).collect();
        let mean = errors.iter().sum::<f32>() / errors.len() as f32;
        (mean, errors.iter().copied().fold(0.0, f32::max))
    };
    let mesh = morph.frame_mesh(1.0, 0).unwrap();
    let (mean, max) = error(&mesh);
    let exact = Grid3::sample_box(&torus, &Aabb::cube(0.5), n).unwrap();
    let (floor_mean, floor_max) = error(&isomorph_common::marching_cubes::marching_cubes(&exact, 0.0));
    println!(
        "accuracy/sphere_torus/sparse/{n}: {} iterations (converged: {}), surface error mean {mean:.4}, \
         max {max:.4} voxels (the grid's floor: mean {floor_mean:.4}, max {floor_max:.4}), genus {:?}",
        morph.stats().len(),
        morph.converged(),
        mesh.genus()
    );
}

/// Source distance grid and target speed of the reference case.
fn case(n: u32) -> (Grid3<f32>, SpeedGrid) {
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), n).unwrap();
    let speed = SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, Response::Identity).unwrap();
    (source, speed)
}

/// The whole evolution (distance volumes given). The sparse field runs to
/// convergence; the dense solver runs to the same evolution time (eq. 17's
/// `t`) that the sparse field needed, since its zero set then lies where the
/// sparse one converged (tested in `level-set/tests/morph.rs`) while its
/// RMS statistics keep moving with the far level sets. Its time step is
/// bounded by the largest target distance anywhere on the grid, so it
/// needs several times the sparse field's iterations (with eq. 24's third
/// of a voxel per iteration: about 600 against 84 at 64³, about 2400 at
/// 128³, some 2 minutes a run here, so `dense/128` takes some 20 minutes
/// for criterion's ten samples). Before timing, each size prints
/// the sparse field's final surface error against the analytic torus.
fn morph(c: &mut Criterion) {
    let mut group = c.benchmark_group("morph/sphere_torus");
    group.sample_size(10);
    let settings =
        EvolveSettings { frames: FrameSchedule::EveryIterations(usize::MAX), ..Default::default() };
    for n in [64u32, 128, 256] {
        // Built (and the accuracy printed) only when a bench of this size is selected.
        let mut setup = None;
        let mut prepare = || {
            let (source, speed) = case(n);
            let sparse = evolve(&source, &speed, Placement::Identity, &settings, &Control::new()).unwrap();
            print_accuracy(n, &sparse, source.spacing());
            (source, speed, sparse.end_time())
        };
        group.bench_function(BenchmarkId::new("sparse", n), |b| {
            let (source, speed, _) = setup.get_or_insert_with(&mut prepare);
            b.iter(|| {
                black_box(
                    evolve(source, speed, Placement::Identity, &settings, &Control::new()).unwrap().len(),
                )
            })
        });
        if n <= 128 {
            group.bench_function(BenchmarkId::new("dense", n), |b| {
                let (source, speed, end_time) = setup.get_or_insert_with(&mut prepare);
                let dense = EvolveSettings {
                    solver: SolverKind::Dense,
                    end_time: *end_time,
                    max_iterations: 100_000,
                    ..settings
                };
                b.iter(|| {
                    black_box(
                        evolve(source, speed, Placement::Identity, &dense, &Control::new()).unwrap().len(),
                    )
                })
            });
        }
    }
    // 512³ through `LevelSetMorph::new` with sparse storage (no dense grid;
    // the whole pipeline: band source, overlap, evolution; one kept frame in
    // a thousand). Run with `--sample-size 10` at least; one run takes minutes.
    group.bench_function(BenchmarkId::new("sparse", 512), |b| {
        b.iter(|| black_box(sparse_morph(512, 1000).stats().len()))
    });
    group.finish();
}

/// The reference case's state at `n³` without any dense grid: the source
/// sampled in a narrow band of bricks (`SparseFieldSolver::from_field`) and
/// the target speed computed per brick where the band goes
/// (`SpeedGrid::lazy`), as at 512³ and 1024³ the dense grids would not fit
/// the memory targets.
fn lean_case(n: u32) -> (SparseFieldSolver, SpeedGrid) {
    let (dims, origin, spacing) = lattice_for_box(&Aabb::cube(0.5), n).unwrap();
    let solver = SparseFieldSolver::from_field(&Shape::sphere(0.3), dims, origin, spacing).unwrap();
    let (torus, inv_h) = (Shape::torus(0.3, 0.12), 1.0 / spacing);
    let speed = SpeedGrid::lazy(dims, origin, spacing, Arc::new(move |x| torus.value(x) * inv_h)).unwrap();
    (solver, speed)
}

/// One iteration of the evolution, on a solver that keeps evolving from
/// the source (criterion's warm-up already takes it part or most of the way
/// to the torus): the steady per-iteration cost, which grows like the
/// surface for the sparse field (bricked state, lazy speed: `lean_case`)
/// and like the volume for the dense solver. Each solver is stepped in
/// place, so its state stays as warm in the caches as during a real morph.
/// States are built only for the sizes the filter selects.
fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step/sphere_torus");
    group.sample_size(10);
    let params = StepParams::default();
    for n in [64u32, 128, 256, 512, 1024] {
        let mut sparse = None;
        group.bench_function(BenchmarkId::new("sparse", n), |b| {
            let (solver, speed) = sparse.get_or_insert_with(|| lean_case(n));
            b.iter(|| black_box(solver.step(speed, &params)))
        });
        if n <= 256 {
            let mut dense = None;
            group.bench_function(BenchmarkId::new("dense", n), |b| {
                let (solver, speed) = dense.get_or_insert_with(|| {
                    let (source, speed) = case(n);
                    (DenseSolver::new(&source).unwrap(), speed)
                });
                b.iter(|| black_box(solver.step(speed, &params)))
            });
        }
    }
    group.finish();
}

/// Peak memory of the whole reference morph at `n³` through
/// `LevelSetMorph::new` with sparse storage (what the command line and
/// Python run from 256 up), run once to convergence keeping one frame in
/// ten (`FrameSchedule::EveryIterations(10)`; the library's default keeps
/// [`FRAME_BUDGET`](isomorph_levelset::FRAME_BUDGET) to 66 frames):
/// prints the process's peak resident set (`VmHWM` of `/proc/self/status`,
/// reset through `/proc/self/clear_refs` before the run, so it holds this
/// run alone plus the process's own baseline), the report's stored and
/// peak bytes, the iterations, the stage times and the wall time of that
/// one run. The lattice is the reference's (padding chosen so the box's
/// long edges are [-0.5, 0.5]). Criterion then times polygonizing the last
/// frame (plane by plane, no dense grid). `ISOMORPH_BENCH_MAX_ITERATIONS`
/// caps the iterations (the print then says "converged: false").
fn memory(c: &mut Criterion) {
    let mut group = c.benchmark_group("memory/sphere_torus");
    group.sample_size(10);
    for n in [512u32, 1024] {
        let mut state = None;
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            let morph = state.get_or_insert_with(|| {
                let _ = std::fs::write("/proc/self/clear_refs", "5");
                let start = Instant::now();
                let morph = sparse_morph(n, 10);
                let report = morph.report();
                println!(
                    "memory/sphere_torus/{n}: peak RSS {} (VmHWM); report: {} kept frames {}, peak {}; \
                     {} iterations (converged: {}), {:.1} s; stages {:?}",
                    Bytes(peak_rss()),
                    morph.len(),
                    Bytes(report.stored_bytes),
                    Bytes(report.peak_bytes.unwrap_or(0)),
                    morph.stats().len(),
                    morph.converged(),
                    start.elapsed().as_secs_f64(),
                    report.stages,
                );
                morph
            });
            b.iter(|| black_box(morph.frame_mesh(1.0, 0).unwrap().triangles.len()))
        });
    }
    group.finish();
}

/// The reference morph at `n³` through `LevelSetMorph::new` with sparse
/// storage, keeping a frame every `keep_every` iterations.
fn sparse_morph(n: u32, keep_every: usize) -> LevelSetMorph {
    let defaults = LevelSetSettings::default();
    let settings = LevelSetSettings {
        max_iterations: max_iterations().unwrap_or(defaults.max_iterations),
        resolution: n,
        // The union of the shapes' boxes is 0.84 across: 0.08 per side makes it [-0.5, 0.5].
        padding: 0.08 / 0.84,
        storage: Storage::Sparse,
        frames: FrameSchedule::EveryIterations(keep_every),
        ..defaults
    };
    let (source, target) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(Shape::torus(0.3, 0.12)));
    LevelSetMorph::new(&source, &target, &settings, &Control::new()).unwrap()
}

/// An iteration cap for [`sparse_morph`] from `ISOMORPH_BENCH_MAX_ITERATIONS`
/// (e.g. to measure the memory of a 1024³ morph's setup and first
/// iterations where the whole run would take hours); none when unset.
fn max_iterations() -> Option<usize> {
    std::env::var("ISOMORPH_BENCH_MAX_ITERATIONS").ok().and_then(|v| v.parse().ok())
}

/// The process's peak resident set (`VmHWM`, bytes; 0 where
/// `/proc/self/status` is not available).
fn peak_rss() -> usize {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap_or("VmHWM: 0 kB");
    line.split_whitespace().nth(1).and_then(|kb| kb.parse::<usize>().ok()).unwrap_or(0) * 1024
}

/// The whole `isomorph morph --method level-set --source sphere --target
/// torus --res 128 --frames 8` through the library, as the command runs it
/// (the same library calls, not the binary): the inputs' reference surfaces
/// for the endpoint distances ([`ExportSettings::with_inputs`]), both distance
/// volumes, the evolution keeping frames within the default budget
/// ([`FRAME_BUDGET`](isomorph_levelset::FRAME_BUDGET)), and the 8 frames
/// polygonized, measured and written with the contact sheet and report
/// (no `preview.gif`: the reference command passes `--no-preview`).
fn cli(c: &mut Criterion) {
    let mut group = c.benchmark_group("cli/sphere_torus");
    group.sample_size(10).measurement_time(Duration::from_secs(45));
    let res = 128;
    let out = std::env::temp_dir().join(format!("isomorph-bench-cli-{}", std::process::id()));
    group.bench_function(BenchmarkId::from_parameter(res), |b| {
        b.iter(|| black_box(command("sphere", "torus", res, Align::None, 8, &out)))
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&out);
}

/// `isomorph morph --method level-set --source SOURCE --target TARGET --res
/// RES --align auto|none --frames FRAMES --no-preview --out OUT` through
/// the library, as the command runs it: both inputs loaded (meshes fitted
/// into the built-in shapes' box), the morph, and the frames polygonized,
/// measured against the inputs and written with the contact sheet and
/// report. Returns the frames written.
fn command(
    source: &str,
    target: &str,
    res: u32,
    align: Align,
    frames: usize,
    out: &std::path::Path,
) -> usize {
    let (method, control) = (Method::LevelSet, Control::new());
    let source = load_input(method, source, &Default::default()).expect("source");
    let target = load_input(method, target, &Default::default()).expect("target");
    let mut settings = Settings::default().with_resolution(res);
    settings.level_set.align = align;
    let morph = build(method, &source, &target, &settings, &control).expect("morphs");
    let export = ExportSettings {
        frames,
        resolution: res,
        out_dir: out.to_path_buf(),
        preview: false,
        ..ExportSettings::default()
    }
    .with_inputs(&source, &target, &control)
    .expect("reference surfaces");
    export_sequence(&*morph, &export, &control).expect("exports").report.frames.len()
}

/// Real meshes end to end: the bunny (`data/bunny.ply`) into the Utah
/// teapot (`data/teapot.ply`, open and unwelded: its inside from the
/// winding number), with automatic alignment and 9 frames, at 128³ (dense
/// storage) and 256³ (sparse), through [`command`]. The target is the file
/// named by `ISOMORPH_BENCH_TARGET` when set (e.g. the Stanford dragon of
/// `../shared/data`, which must not be committed: `real/bunny_dragon_res3_closed/N`).
fn real(c: &mut Criterion) {
    let data = |name: &str| format!("{}/../data/{name}", env!("CARGO_MANIFEST_DIR"));
    let target = std::env::var("ISOMORPH_BENCH_TARGET").unwrap_or_else(|_| data("teapot.ply"));
    let name =
        std::path::Path::new(&target).file_stem().map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
    let mut group = c.benchmark_group(format!("real/bunny_{name}"));
    group.sample_size(10);
    let out = std::env::temp_dir().join(format!("isomorph-bench-real-{}", std::process::id()));
    for res in [128u32, 256] {
        group.bench_function(BenchmarkId::from_parameter(res), |b| {
            b.iter(|| black_box(command(&data("bunny.ply"), &target, res, Align::Auto, 9, &out)))
        });
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&out);
}

/// The source distance volume of a mesh three ways, at 256³ and 512³ over
/// the mesh's box padded by 10 % per side: exact at every node
/// (`far_field/MESH/exact/N`), exact within the band and closest-point fast
/// marching beyond (`narrow_band/N`), and exact within the band with only
/// the side elsewhere (`sign_only/N`, `Bricks::sample_band`, what sparse
/// storage uses: each band brick one block of the lattice search, signs
/// once per region), and the same band through single values
/// (`sign_only_by_points/N`, `Bricks::sample_band_by_points`: a tree query
/// and a winding number per band node, the sparse path before it used the
/// lattice search). The band is the sparse field's (`band_width`, 4
/// voxels); within it all four give the exact distance (the first three
/// bitwise, the last up to the rounding of the batch queries), so they
/// differ in time and memory only. The mesh is `data/bunny.ply`, or the file named by
/// `ISOMORPH_BENCH_MESH` (e.g. the dragon, which must not be committed).
fn far_field(c: &mut Criterion) {
    let mut group = c.benchmark_group("far_field");
    group.sample_size(10);
    let path = std::env::var("ISOMORPH_BENCH_MESH")
        .unwrap_or_else(|_| format!("{}/../data/bunny.ply", env!("CARGO_MANIFEST_DIR")));
    let name =
        std::path::Path::new(&path).file_stem().map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
    let mut mesh = None;
    let mut load = || {
        let m = isomorph_io::mesh::read_mesh(&path).expect("the bench mesh");
        let sdf = MeshSdf::new(&m).unwrap();
        (m.bounds().padded(0.1), sdf, m)
    };
    for n in [256u32, 512] {
        group.bench_function(BenchmarkId::new(format!("{name}/exact"), n), |b| {
            let (bounds, sdf, _) = mesh.get_or_insert_with(&mut load);
            b.iter(|| black_box(sdf.sample_grid(bounds, n).unwrap().len()))
        });
        group.bench_function(BenchmarkId::new(format!("{name}/narrow_band"), n), |b| {
            let (bounds, _, m) = mesh.get_or_insert_with(&mut load);
            let h = lattice_for_box(bounds, n).unwrap().2;
            let volume = VolumeMode::NarrowBand { width: SparseFieldSolver::band_width(h) };
            let banded = MeshSdf::with_settings(m, SdfSettings::default().with_volume(volume)).unwrap();
            b.iter(|| black_box(banded.sample_grid(bounds, n).unwrap().len()))
        });
        group.bench_function(BenchmarkId::new(format!("{name}/sign_only"), n), |b| {
            let (bounds, sdf, _) = mesh.get_or_insert_with(&mut load);
            let (dims, origin, h) = lattice_for_box(bounds, n).unwrap();
            b.iter(|| {
                let band =
                    Bricks::sample_band(&*sdf, dims, origin, h, SparseFieldSolver::band_width(h)).unwrap();
                black_box(band.allocated())
            })
        });
        group.bench_function(BenchmarkId::new(format!("{name}/sign_only_by_points"), n), |b| {
            let (bounds, sdf, _) = mesh.get_or_insert_with(&mut load);
            let (dims, origin, h) = lattice_for_box(bounds, n).unwrap();
            b.iter(|| {
                let band =
                    Bricks::sample_band_by_points(&*sdf, dims, origin, h, SparseFieldSolver::band_width(h))
                        .unwrap();
                black_box(band.allocated())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, morph, step, memory, cli, real, far_field);
criterion_main!(benches);
