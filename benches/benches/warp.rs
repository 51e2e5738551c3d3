//! Benchmarks of True's volume warping: the full antialiased (box filter)
//! warp, the local update after moving one control point, and the
//! table-driven vs separable vs direct evaluation of the deformation mapping array.
//!
//! `cargo bench -p isomorph-benches --bench warp -- pushforward_box/256`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{UVec3, Vec3};
use isomorph_benches::torus_grid;
use isomorph_common::Grid3;
use isomorph_warp::{
    BSplineMap, CoefficientTable, DeformationArray, Evaluator, Filter, VolumeWarp, WarpSettings,
};
use std::hint::black_box;

/// Control points per axis: 11 leaves 8 regions, so 128 and 256 are integer
/// multiples (G = 16 and 32) and the table of §5.2 applies.
const CSIZE: u32 = 11;

/// The reference torus as a u8 density (0–255, surface at 127.5, about two
/// voxels of smooth transition).
fn torus_density(n: u32) -> Grid3<u8> {
    let grid = torus_grid(n);
    let h = grid.spacing();
    grid.map(|d| (127.5 + 64.0 * d / h).clamp(0.0, 255.0) as u8).expect("bench grid fits")
}

/// A smooth random-looking map: every control point displaced by up to
/// `amplitude` voxels (deterministic).
fn wobbly_map(n: u32, amplitude: f32) -> BSplineMap {
    let mut map = BSplineMap::identity(UVec3::splat(n), CSIZE).expect("valid lattice");
    for k in 0..CSIZE {
        for j in 0..CSIZE {
            for i in 0..CSIZE {
                let p = Vec3::new(i as f32, j as f32, k as f32);
                let d = Vec3::new(
                    (1.3 * p.y + 0.7 * p.z).sin(),
                    (0.9 * p.x + 1.1 * p.z).cos(),
                    (1.7 * p.x - 0.5 * p.y).sin(),
                );
                map.set_displacement(UVec3::new(i, j, k), amplitude * d).expect("finite");
            }
        }
    }
    map
}

fn settings() -> WarpSettings {
    WarpSettings { csize: CSIZE, pad: 4, filter: Filter::Box, ..WarpSettings::default() }
}

fn pushforward_box(c: &mut Criterion) {
    let mut group = c.benchmark_group("pushforward_box");
    group.sample_size(10);
    let n = 256u32;
    let mut warp = VolumeWarp::new(torus_density(n), settings()).expect("warp fits");
    let maps = [wobbly_map(n, 6.0), wobbly_map(n, -6.0)];
    let mut which = 0;
    group.throughput(Throughput::Elements(u64::from(n).pow(3)));
    group.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter(|| {
            which ^= 1;
            warp.set_map(black_box(maps[which].clone())).expect("same lattice");
        })
    });
    group.finish();
}

fn local_update(c: &mut Criterion) {
    let mut group = c.benchmark_group("local_update");
    group.sample_size(20);
    let n = 128u32;
    let mut warp = VolumeWarp::with_map(torus_density(n), wobbly_map(n, 3.0), settings()).expect("warp fits");
    let control = UVec3::new(5, 4, 6);
    let rest = warp.map().control_point(control).expect("inside");
    let positions = [rest + Vec3::new(4.0, -2.0, 1.0), rest];
    let mut which = 0;
    group.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter(|| {
            which ^= 1;
            warp.move_control_points(black_box(&[(control, positions[which])])).expect("valid move")
        })
    });
    group.finish();
}

fn map_eval(c: &mut Criterion) {
    let mut group = c.benchmark_group("map_eval");
    group.sample_size(10);
    let n = 128u32;
    let map = wobbly_map(n, 3.0);
    let table = CoefficientTable::new(&map).expect("128 is a multiple of 8 regions");
    let mut array = DeformationArray::identity(UVec3::splat(n)).expect("fits");
    group.throughput(Throughput::Elements(u64::from(n).pow(3)));
    for (name, evaluator) in [
        ("table", Evaluator::Table(&table)),
        ("separable", Evaluator::Separable),
        ("direct", Evaluator::Direct),
    ] {
        group.bench_function(BenchmarkId::new(name, n), |b| {
            b.iter(|| array.update(black_box(&map), evaluator, UVec3::ZERO, UVec3::splat(n)))
        });
    }
    group.finish();
}

criterion_group!(benches, pushforward_box, local_update, map_eval);
criterion_main!(benches);
