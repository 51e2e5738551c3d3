//! Benchmarks of the shared core: marching cubes, grid fill, mesh parsing,
//! mesh signed distance, colour lookup.
//!
//! `cargo bench -p isomorph-benches --bench common -- marching_cubes/torus/256`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{UVec3, Vec3};
use isomorph_benches::{data_path, torus, torus_grid};
use isomorph_common::Grid3;
use isomorph_common::alignment::Moments;
use isomorph_common::fast_marching::{FastMarchingSettings, redistance};
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::mesh::bvh::Lattice;
use isomorph_common::mesh::color::ColorLookup;
use isomorph_common::sdf::{MeshSdf, SdfSettings, VolumeMode};
use isomorph_io::mesh::{MeshFormat, read_mesh, read_mesh_from};
use std::hint::black_box;
use std::io::Cursor;

fn marching_cubes_torus(c: &mut Criterion) {
    let mut group = c.benchmark_group("marching_cubes/torus");
    group.sample_size(20);
    for n in [128u32, 256] {
        let grid = torus_grid(n);
        group.throughput(Throughput::Elements(u64::from(n - 1).pow(3)));
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| marching_cubes(black_box(&grid), 0.0))
        });
    }
    group.finish();
}

fn grid_fill_torus(c: &mut Criterion) {
    let mut group = c.benchmark_group("grid_fill/torus");
    group.sample_size(10);
    let n = 256u32;
    let shape = torus();
    let mut grid = Grid3::new(UVec3::splat(n), Vec3::splat(-0.5), 1.0 / (n - 1) as f32, 0.0f32).unwrap();
    group.throughput(Throughput::Elements(u64::from(n).pow(3)));
    group.bench_function(BenchmarkId::from_parameter(n), |b| b.iter(|| grid.fill_from(black_box(&shape))));
    group.finish();
}

/// Redistancing the 256³ torus from a field with the right zero set but
/// non-distance values (the torus distance times a smooth factor in [1, 2]).
fn redistance_torus(c: &mut Criterion) {
    let mut group = c.benchmark_group("redistance/torus");
    group.sample_size(10);
    let n = 256u32;
    let shape = torus();
    let field = |p: Vec3| shape.distance(p) * (1.5 + 0.5 * (3.0 * p.x).sin() * (2.0 * p.y).cos());
    let grid = Grid3::sample(&field, UVec3::splat(n), Vec3::splat(-0.5), 1.0 / (n - 1) as f32).unwrap();
    let settings = FastMarchingSettings::default();
    group.throughput(Throughput::Elements(u64::from(n).pow(3)));
    group.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter(|| redistance(black_box(&grid), &settings).unwrap())
    });
    group.finish();
}

fn mesh_io_bunny(c: &mut Criterion) {
    let mut group = c.benchmark_group("mesh_io");
    for (id, file, format) in [
        ("bunny_ply", "bunny.ply", MeshFormat::PlyBinaryLittleEndian),
        ("bunny_obj", "bunny.obj", MeshFormat::Obj),
    ] {
        let bytes = std::fs::read(data_path(file)).expect("bunny in data/");
        group.throughput(Throughput::Bytes(bytes.len() as u64));
        group.bench_function(id, |b| {
            b.iter(|| read_mesh_from(Cursor::new(black_box(&bytes)), format).unwrap())
        });
    }
    group.finish();
}

fn moments(c: &mut Criterion) {
    let mut group = c.benchmark_group("moments");
    group.sample_size(10);
    let grid = torus_grid(128);
    group.throughput(Throughput::Elements(grid.len() as u64));
    group.bench_function("grid/torus/128", |b| b.iter(|| Moments::from_grid(black_box(&grid)).unwrap()));
    let bunny = read_mesh(data_path("bunny.ply")).expect("bunny in data/");
    group.throughput(Throughput::Elements(bunny.triangles.len() as u64));
    group.bench_function("mesh/bunny", |b| b.iter(|| Moments::from_mesh(black_box(&bunny)).unwrap()));
    group.finish();
}

/// Exact signed distance (winding-number sign) of the bunny on `n³` nodes
/// spanning its bounding box padded 10 % per side, tree builds included.
fn mesh_sdf_bunny(c: &mut Criterion) {
    let mut group = c.benchmark_group("mesh_sdf/bunny");
    group.sample_size(10);
    let mesh = read_mesh(data_path("bunny.ply")).expect("bunny in data/");
    let n = 128u32;
    let lattice = Lattice::spanning(&mesh.bounds().padded(0.1), UVec3::splat(n));
    group.throughput(Throughput::Elements(u64::from(n).pow(3)));
    group.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter(|| MeshSdf::new(black_box(&mesh)).unwrap().sample_lattice(&lattice))
    });
    // Exact in a two-voxel band, closest-point fast marching beyond.
    let bounds = mesh.bounds().padded(0.1);
    let width = 2.0 * bounds.size().max_element() / (n - 1) as f32;
    let settings = SdfSettings::default().with_volume(VolumeMode::NarrowBand { width });
    group.bench_function(BenchmarkId::new("band", n), |b| {
        b.iter(|| {
            MeshSdf::with_settings(black_box(&mesh), settings).unwrap().sample_grid(&bounds, n).unwrap()
        })
    });
    group.finish();
}

/// The colours of a frame's vertices from a coloured input
/// ([`ColorLookup`], what the sequence exporter does twice per coloured
/// frame): the bunny painted by position, queried at its own vertices
/// moved 1 % of its height out along their normals, as a frame near it.
fn color_lookup_bunny(c: &mut Criterion) {
    let bunny = read_mesh(data_path("bunny.ply")).expect("bunny in data/");
    let size = bunny.bounds().size();
    let colors = bunny.positions.iter().map(|p| (*p - bunny.bounds().min) / size).collect();
    let painted = bunny.clone().with_colors(colors).expect("one colour per vertex");
    let offset = 0.01 * size.y;
    let normals = bunny.vertex_normals();
    let points: Vec<Vec3> = bunny.positions.iter().zip(&normals).map(|(p, n)| *p + offset * *n).collect();
    let mut group = c.benchmark_group("color_lookup");
    group.throughput(Throughput::Elements(points.len() as u64));
    group.bench_function("build/bunny", |b| {
        b.iter(|| ColorLookup::new(black_box(&painted), Vec3::ONE).unwrap())
    });
    let lookup = ColorLookup::new(&painted, Vec3::ONE).unwrap();
    let mut out = vec![Vec3::ZERO; points.len()];
    group.bench_function("query/bunny_near", |b| b.iter(|| lookup.colors_at(black_box(&points), &mut out)));
    group.finish();
}

criterion_group!(
    benches,
    marching_cubes_torus,
    grid_fill_torus,
    redistance_torus,
    mesh_io_bunny,
    moments,
    mesh_sdf_bunny,
    color_lookup_bunny
);
criterion_main!(benches);
