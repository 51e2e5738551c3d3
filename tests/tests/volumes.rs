//! Volume inputs end to end: a shape read back from a `.npy` distance
//! volume morphs like the same shape given as a mesh, and two volumes on
//! different lattices are resampled, not refused.

use isomorph_common::glam::{UVec3, Vec3};
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::mesh::primitives::uv_sphere;
use isomorph_common::{Aabb, Control, Grid3, Morph, Shape, Solid};
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_io::npy::save_npy;
use isomorph_levelset::{LevelSetMorph, LevelSetSettings};

const RES: u32 = 48;

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("isomorph-volumes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Mean surface distance between the frames of `a` and `b` at `t`, in
/// voxels of `a`'s frame lattice.
fn frame_gap(a: &LevelSetMorph, b: &LevelSetMorph, t: f32) -> f32 {
    let (ma, mb) = (a.frame_mesh(t, RES).unwrap(), b.frame_mesh(t, RES).unwrap());
    let voxel = a.world_bounds().size().max_element() / (RES - 1) as f32;
    surface_distance(&ma, &mb, 4000).unwrap().mean / voxel
}

#[test]
fn a_npy_distance_volume_morphs_like_its_mesh() {
    let control = Control::new();
    let mesh = uv_sphere(Vec3::new(0.05, 0.0, 0.0), 0.3, 96, 192);
    let as_mesh = Solid::mesh(mesh.clone()).unwrap();
    // The mesh's exact distance on a finer lattice of its own, written and
    // read back as a user's file would be.
    let volume = as_mesh.distance_volume(&Aabb::cube(0.5), 97, &control).unwrap();
    let dir = scratch("npy");
    let path = dir.join("sphere.npy");
    save_npy(&volume, &path).unwrap();
    let kept = LoadOptions { fit: false, ..LoadOptions::default() };
    let as_volume = load_solid(path.to_str().unwrap(), &kept).unwrap();
    assert_eq!(as_volume.kind(), "distance volume");

    let torus = Solid::shape(Shape::torus(0.3, 0.12));
    let settings = LevelSetSettings { resolution: RES, ..Default::default() };
    let from_mesh = LevelSetMorph::new(&as_mesh, &torus, &settings, &control).unwrap();
    let from_volume = LevelSetMorph::new(&as_volume, &torus, &settings, &control).unwrap();
    for t in [0.0, 0.5, 1.0] {
        let gap = frame_gap(&from_mesh, &from_volume, t);
        assert!(gap < 0.1, "t = {t}: the frames are {gap} voxels apart");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn volumes_on_different_lattices_are_resampled() {
    let control = Control::new();
    // The source on a coarse lattice shifted off the origin, the target on
    // a fine one over a larger box: neither matches the morph's lattice.
    let sphere =
        Grid3::sample(&|p: Vec3| 0.3 - p.length(), UVec3::splat(41), Vec3::splat(-0.53), 0.027).unwrap();
    let torus_shape = Shape::torus(0.3, 0.12);
    let torus = Grid3::sample_box(&torus_shape, &Aabb::cube(0.7), 131).unwrap();
    let (source, target) = (Solid::volume(sphere).unwrap(), Solid::volume(torus).unwrap());
    let settings = LevelSetSettings { resolution: RES, ..Default::default() };
    let morph = LevelSetMorph::new(&source, &target, &settings, &control).unwrap();
    assert!(morph.report().converged);
    let last = morph.frame_mesh(1.0, RES).unwrap();
    assert_eq!(last.genus(), Some(1));
    let truth = Solid::shape(torus_shape).surface(96, &control).unwrap().into_owned();
    let voxel = morph.world_bounds().size().max_element() / (RES - 1) as f32;
    let d = surface_distance(&last, &truth, 4000).unwrap();
    assert!(d.mean / voxel < 0.5 && d.hausdorff / voxel < 1.5, "end {:?} in voxels of {voxel}", d);
}
