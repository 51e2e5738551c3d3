//! Sparse storage (narrow-band source, lazy speed, overlap judged near the
//! target, frames polygonized plane by plane) gives the dense storage's
//! morph: the same kept frames at every iteration kept, on small grids.

use isomorph_common::glam::{Quat, Vec3};
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::{Aabb, Bricks, Control, Field3, Grid3, Morph, Shape, Solid, Value, lattice_for_box};
use isomorph_levelset::{
    Align, FrameSchedule, LevelSetMorph, LevelSetSettings, Response, SparseFieldSolver, SpeedGrid,
    SpeedSampler, Storage, check_overlap, check_overlap_sparse,
};
use std::sync::Arc;

/// Runs the morph with both storages and checks every kept frame: the same
/// count, iterations and times, values within `tolerance` (world units) at
/// every node, and the mesh of the sparse morph's frame (polygonized plane
/// by plane) equal to marching cubes of its dense frame grid.
fn same_morph(source: &Solid, target: &Solid, settings: LevelSetSettings, tolerance: f32) {
    let control = Control::new();
    let run = |storage| {
        let settings = LevelSetSettings { storage, ..settings.clone() };
        LevelSetMorph::new(source, target, &settings, &control).unwrap()
    };
    let (dense, sparse) = (run(Storage::Dense), run(Storage::Sparse));
    let storage = |m: &LevelSetMorph| m.report().details.get("storage").cloned();
    assert_eq!(storage(&dense), Some(Value::from("dense")));
    assert_eq!(storage(&sparse), Some(Value::from("sparse")));
    assert_eq!(dense.len(), sparse.len(), "kept frames");
    assert_eq!(dense.converged(), sparse.converged());
    assert!(dense.len() > 3, "{} frames", dense.len());
    for n in 0..dense.len() {
        let (a, b) = (&dense.frames()[n], &sparse.frames()[n]);
        assert_eq!((a.iteration, a.time), (b.iteration, b.time), "frame {n}");
        let (a, b) = (dense.frame_grid(n).unwrap(), sparse.frame_grid(n).unwrap());
        assert!(a.same_lattice(&b));
        let worst = a.data().iter().zip(b.data()).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max);
        assert!(worst <= tolerance, "frame {n}: values differ by {worst}");
    }
    // Kept or interpolated (t = 0.5, 0.37 fall between kept iterations).
    for t in [0.0, 0.37, 0.5, 1.0] {
        let frame = sparse.frame(t).unwrap();
        let mut expected = marching_cubes(&frame.field, 0.0);
        expected.transform(&frame.transform);
        let got = sparse.frame_mesh(t, 0).unwrap();
        assert_eq!(got.triangles, expected.triangles, "t = {t}");
        assert_eq!(got.positions, expected.positions, "t = {t}");
    }
}

/// The reference case (sphere → torus) at 48³: analytic distances on both
/// sides, so the two storages see bitwise the same values.
#[test]
fn sphere_into_torus_is_the_same_with_sparse_storage() {
    let settings =
        LevelSetSettings { resolution: 48, frames: FrameSchedule::EveryIterations(5), ..Default::default() };
    let (source, target) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(Shape::torus(0.3, 0.12)));
    same_morph(&source, &target, settings, 1e-6);
}

/// Meshes aligned by moments (a non-identity map, so the speed is read
/// through it) at 40³: the mesh distance sampled per band brick against the
/// dense lattice sample.
#[test]
fn aligned_meshes_are_the_same_with_sparse_storage() {
    let mesh = |shape: &Shape| {
        let grid = Grid3::sample_box(shape, &Aabb::cube(0.6), 28).unwrap();
        Solid::mesh(marching_cubes(&grid, 0.0)).unwrap()
    };
    let source = mesh(&Shape::cuboid(Vec3::new(0.25, 0.18, 0.12)).rotated(Quat::from_rotation_z(0.4)));
    let target = mesh(&Shape::torus(0.28, 0.1).rotated(Quat::from_rotation_x(0.7)));
    let settings = LevelSetSettings {
        resolution: 40,
        frames: FrameSchedule::EveryIterations(5),
        align: Align::Auto,
        ..Default::default()
    };
    same_morph(&source, &target, settings, 1e-6);
}

/// The overlap judged on the source's band and the target near its surface
/// equals the dense judgement: a target of three parts (a torus, a ball the
/// source misses, and two balls joined by a rod thinner than a voxel that
/// runs between the nodes), at an odd size whose edge bricks are cut.
#[test]
fn sparse_overlap_equals_the_dense_one() {
    let res = 45;
    let (dims, origin, h) = lattice_for_box(&Aabb::cube(0.55), res).unwrap();
    let rod = Shape::cylinder(0.3 * h, 0.2).rotated(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
    let target = Shape::torus(0.3, 0.1)
        .union(Shape::sphere(0.07).translated(Vec3::new(0.0, 0.0, 0.4)))
        .union(Shape::sphere(0.08).translated(Vec3::new(-0.2, 0.0, -0.38)))
        .union(Shape::sphere(0.08).translated(Vec3::new(0.2, 0.0, -0.38)))
        .union(rod.translated(Vec3::new(0.0, 0.5 * h, -0.38 + 0.5 * h)));
    let source_shape = Shape::sphere(0.3);
    let source = Grid3::sample(&source_shape, dims, origin, h).unwrap();
    let speed = SpeedGrid::sample(&source, &target, |x| x, Response::Identity).unwrap();
    let dense = check_overlap(&source, &speed, 1.0).unwrap();
    assert_eq!(dense.parts, 3, "{dense:?}");
    assert_eq!(dense.missed.len(), 2, "{dense:?}");
    let band = Bricks::sample_band(&source_shape, dims, origin, h, SparseFieldSolver::band_width(h)).unwrap();
    let inv_h = 1.0 / h;
    let sampler: SpeedSampler = Arc::new(move |x| target.value(x) * inv_h);
    let sparse = check_overlap_sparse(&band, (origin, h), &sampler, 1.0, 1.0).unwrap();
    assert_eq!(sparse, dense);
    // Over the allowed share, both refuse.
    assert!(check_overlap_sparse(&band, (origin, h), &sampler, 1.0, 0.01).is_err());
    assert!(check_overlap(&source, &speed, 0.01).is_err());
}
