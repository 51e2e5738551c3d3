//! Benchmarks of the variational implicit shape transformation (Turk &
//! O'Brien): the reference case, a sphere (r = 0.3) at t = 0 and a
//! torus (R = 0.3, r = 0.12) at t = 1, each with n surface points giving a
//! boundary and an inward normal constraint (offset 0.01), so 4n constraints
//! in 4D with a degree-one polynomial.
//!
//! `cargo bench -p isomorph-benches --bench rbf -- fit/sphere_torus_4d/8000`
//! `cargo bench -p isomorph-benches --bench rbf -- fit/sphere_torus_4d/100000`
//! `cargo bench -p isomorph-benches --bench rbf -- fit/sphere_torus_4d/r3/100000`
//! `cargo bench -p isomorph-benches --bench rbf -- eval_grid/sphere_torus_4d/8000/64`
//! `cargo bench -p isomorph-benches --bench rbf -- eval_grid_r3/sphere_torus_4d/8000/64`
//! `cargo bench -p isomorph-benches --bench rbf -- eval_grid/sphere_torus_4d/100000/128`
//! `cargo bench -p isomorph-benches --bench rbf -- eval_grid/sphere_torus_4d/100000/128/t0`
//! `cargo bench -p isomorph-benches --bench rbf -- polygonize/sphere_torus_4d/8000/64`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use isomorph_common::marching_cubes::{SparseSettings, polygonize_near_surface};
use isomorph_common::marching_cubes::{marching_cubes, polygonize};
use isomorph_common::{Aabb, Grid3};
use isomorph_rbf::constraints::{NormalOffset, Subsample, SurfaceSettings, field_constraints};
use isomorph_rbf::{FitSettings, Interpolant, Kernel, RbfMorph, Slice3, TransformSettings, lift};
use std::hint::black_box;

/// The reference case: a sphere (radius 0.3) and a torus (R = 0.3,
/// r = 0.12), each with `total / 4` farthest-point samples of its surface
/// (polygonized at 64³ over `[-0.5, 0.5]³`, at 160³ above 16000
/// constraints so that there are enough vertices) giving a boundary and an
/// inward normal constraint at offset 0.01.
fn shapes(total: usize) -> [Vec<isomorph_rbf::Constraint<3>>; 2] {
    let s = SurfaceSettings {
        offset: NormalOffset::Absolute(0.01),
        subsample: Subsample::FarthestPoint(total / 4),
    };
    let resolution = if total > 16_000 { 160 } else { 64 };
    [isomorph_common::Shape::sphere(0.3), isomorph_common::Shape::torus(0.3, 0.12)]
        .map(|shape| field_constraints(&shape, &Aabb::cube(0.5), resolution, &s).unwrap())
}

/// The 4D constraints of the reference case with `total` constraints.
fn constraints(total: usize) -> Vec<isomorph_rbf::Constraint<4>> {
    let [a, b] = shapes(total);
    let mut all = lift::<3, 4>(&a, &[0.0]);
    all.extend(lift::<3, 4>(&b, &[1.0]));
    all
}

/// The reference morph (sphere at `t = 0`, torus at `t = 1`).
fn reference_morph(total: usize, kernel: Kernel) -> RbfMorph {
    let [a, b] = shapes(total);
    let settings =
        TransformSettings { fit: FitSettings::default().with_kernel(kernel), ..Default::default() };
    RbfMorph::from_constraints(&a, &b, &settings).unwrap()
}

/// The fit (solve, rcond estimate, residual check) at 2000 to 100000
/// constraints with the default solver ([`isomorph_rbf::Solver::Auto`]:
/// the slab solver below the hierarchical solver's crossover, the
/// hierarchical solver, H-matrix and GMRES, above it), both kernels. Each
/// bench prints the process's peak resident memory during it (Linux: the
/// peak is reset through `/proc/self/clear_refs` before the bench and read
/// from `VmHWM` after it).
fn fit(c: &mut Criterion) {
    let mut group = c.benchmark_group("fit/sphere_torus_4d");
    group.sample_size(10);
    for total in [2000usize, 4000, 8000, 16000, 32000, 100_000] {
        let cs = constraints(total);
        for (name, kernel) in [("", Kernel::ThinPlate), ("r3/", Kernel::Cubic)] {
            let settings = FitSettings::default().with_kernel(kernel);
            let id = format!("{name}{total}");
            let reset = std::fs::write("/proc/self/clear_refs", "5").is_ok();
            // Read inside the bench: criterion calls it only when its ID
            // passes the filter.
            let mut peak = None;
            group.bench_function(BenchmarkId::from_parameter(&id), |b| {
                b.iter(|| Interpolant::fit(black_box(&cs), &settings).unwrap());
                peak = peak_kb().filter(|_| reset);
            });
            if let Some(kb) = peak {
                eprintln!("fit/sphere_torus_4d/{id}: peak resident memory {kb} KB");
            }
        }
    }
    group.finish();
}

/// The process's peak resident memory in KB since the last reset (Linux
/// `VmHWM`), if known.
fn peak_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()
}

/// The t = 0.5 slice evaluated on 64³ nodes over [-0.5, 0.5]³, at 2000 to
/// 16000 constraints (each morph is fitted only when its bench runs).
fn eval_grid(c: &mut Criterion) {
    for (group_name, kernel) in
        [("eval_grid/sphere_torus_4d", Kernel::ThinPlate), ("eval_grid_r3/sphere_torus_4d", Kernel::Cubic)]
    {
        let mut group = c.benchmark_group(group_name);
        group.sample_size(10);
        for total in [2000usize, 4000, 8000, 16000] {
            let slice = std::cell::OnceCell::new();
            let n = 64u32;
            let mut grid =
                Grid3::new(glam::UVec3::splat(n), glam::Vec3::splat(-0.5), 1.0 / (n - 1) as f32, 0.0f32)
                    .unwrap();
            group.throughput(Throughput::Elements(u64::from(n).pow(3)));
            group.bench_function(BenchmarkId::new(total.to_string(), n), |b| {
                let slice = slice.get_or_init(|| reference_morph(total, kernel).slice(0.5).unwrap());
                b.iter(|| grid.fill_from(black_box(slice)))
            });
        }
        group.finish();
    }
}

/// Weights for the centres `positions` (4D): seeded pseudo-random values in
/// `[-1, 1]` with their degree-one moments removed (`Σ λ_j p(x_j) = 0` for
/// every degree-one `p`, as the weights of a fit satisfy), by least squares.
fn moment_free_weights(positions: &[[f32; 4]]) -> Vec<f32> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut weights: Vec<f64> = positions
        .iter()
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect();
    let basis = |p: &[f32; 4]| [1.0, f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), f64::from(p[3])];
    // Normal equations (PᵀP) a = Pᵀλ, then λ ← λ − P a.
    let mut m = [[0.0f64; 6]; 5];
    for (p, w) in positions.iter().zip(&weights) {
        let b = basis(p);
        for r in 0..5 {
            for c in 0..5 {
                m[r][c] += b[r] * b[c];
            }
            m[r][5] += b[r] * w;
        }
    }
    for col in 0..5 {
        let pivot = (col..5).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs())).unwrap();
        m.swap(col, pivot);
        let pivot_row = m[col];
        for (r, row) in m.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / pivot_row[col];
                row.iter_mut().zip(&pivot_row).skip(col).for_each(|(v, p)| *v -= f * p);
            }
        }
    }
    let a: Vec<f64> = (0..5).map(|r| m[r][5] / m[r][r]).collect();
    for (p, w) in positions.iter().zip(weights.iter_mut()) {
        *w -= basis(p).iter().zip(&a).map(|(b, a)| b * a).sum::<f64>();
    }
    weights.into_iter().map(|w| w as f32).collect()
}

/// The t = 0.5 slice of a function with centres at the reference case's
/// 16000 to 100000 constraint positions on the 128³ lattice over
/// [-0.5, 0.5]³, at the default evaluation (`Evaluation::Auto`: the dual
/// tree on lattices from 2000 centres); at 100000 also the end slice t = 0
/// (`…/100000/128/t0`), where all the sphere's centres lie in the slice
/// (the slowest case of the dual tree).
/// The weights do not come from a fit (the fit of 100000 constraints takes
/// minutes): [`moment_free_weights`], through `Slice3::from_sources`; the
/// cost of evaluation does not depend on the weights' values.
fn eval_grid_large(c: &mut Criterion) {
    let mut group = c.benchmark_group("eval_grid/sphere_torus_4d");
    group.sample_size(10);
    let cases = [(16_000usize, 0.5f32, ""), (32_000, 0.5, ""), (100_000, 0.5, ""), (100_000, 0.0, "/t0")];
    for (total, t, suffix) in cases {
        let slice = std::cell::OnceCell::new();
        let n = 128u32;
        let mut grid =
            Grid3::new(glam::UVec3::splat(n), glam::Vec3::splat(-0.5), 1.0 / (n - 1) as f32, 0.0f32).unwrap();
        group.throughput(Throughput::Elements(u64::from(n).pow(3)));
        group.bench_function(BenchmarkId::new(total.to_string(), format!("{n}{suffix}")), |b| {
            let slice = slice.get_or_init(|| {
                let cs = constraints(total);
                let positions: Vec<[f32; 4]> = cs.iter().map(|c| c.position).collect();
                let centres: Vec<[f32; 3]> = positions.iter().map(|p| [p[0], p[1], p[2]]).collect();
                let offsets: Vec<f32> = positions.iter().map(|p| (p[3] - t).powi(2)).collect();
                Slice3::from_sources(Kernel::ThinPlate, &centres, &offsets, &moment_free_weights(&positions))
            });
            b.iter(|| grid.fill_from(black_box(slice)))
        });
    }
    group.finish();
}

/// The t = 0.5 frame as a mesh on the 64³ lattice over [-0.5, 0.5]³: the
/// near-surface polygonizer (`polygonize/…`), the full grid and marching
/// cubes (`polygonize/…/full`), and marching cubes alone (`…/mc_only`).
fn polygonize_slice(c: &mut Criterion) {
    let mut group = c.benchmark_group("polygonize/sphere_torus_4d");
    group.sample_size(10);
    let total = 8000usize;
    let morph = reference_morph(total, Kernel::ThinPlate);
    let slice = morph.slice(0.5).unwrap();
    let settings = SparseSettings::default();
    group.bench_function(BenchmarkId::new(total.to_string(), 64), |b| {
        b.iter(|| polygonize_near_surface(black_box(&slice), &Aabb::cube(0.5), 64, 0.0, &settings).unwrap())
    });
    group.bench_function(BenchmarkId::new(format!("{total}/full"), 64), |b| {
        b.iter(|| polygonize(black_box(&slice), &Aabb::cube(0.5), 64, 0.0).unwrap())
    });
    // Marching cubes alone on the sampled grid, for reference.
    let grid = Grid3::sample_box(&slice, &Aabb::cube(0.5), 64).unwrap();
    group.bench_function(BenchmarkId::new(format!("{total}/mc_only"), 64), |b| {
        b.iter(|| marching_cubes(black_box(&grid), 0.0))
    });
    group.finish();
}

criterion_group!(benches, fit, eval_grid, eval_grid_large, polygonize_slice);
criterion_main!(benches);
