//! The BlobTree morph under the morph contract: the conformance suite on
//! built-in scenes, the built-in torus, non-BlobTree inputs and spec files.

use isomorph_blobtree::{BlobMorph, BlobMorphError, BlobSettings, MorphSpec, scenes};
use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Control, Field3, Morph, MorphError, Shape, Side, Solid};
use std::sync::Arc;

fn solid(name: &str) -> Solid {
    Solid::implicit(Arc::new(scenes::load(name).unwrap())).unwrap()
}

fn reference(name: &str) -> isomorph_common::TriMesh {
    let tree = scenes::load(name).unwrap();
    polygonize(&tree, &tree.support().padded(0.05), 160, 0.0).unwrap()
}

#[test]
fn blobtree_conforms_on_sphere_to_torus() {
    let (a, b) = (solid("sphere"), solid("torus"));
    let settings = BlobSettings::default();
    let expect = Expectations {
        source: reference("sphere"),
        target: reference("torus"),
        resolution: 64,
        mean_voxels: 0.05,
        hausdorff_voxels: 0.25,
        converges: true,
    };
    let got = check_morph(|c| BlobMorph::new(&a, &b, &settings, c), &expect);
    // Measured: mean 0.011 / Hausdorff 0.027 voxels (source), 0.017 / 0.069 (target)
    // (scenes at the analytic shapes' size; 0.011 / 0.027 and 0.022 / 0.088 at twice it).
    println!("{got:?}");
    let morph = BlobMorph::new(&a, &b, &settings, &Control::new()).unwrap();
    assert_eq!(morph.frame_mesh(0.0, 64).unwrap().genus(), Some(0));
    assert_eq!(morph.frame_mesh(1.0, 64).unwrap().genus(), Some(1));
}

#[test]
fn the_built_in_torus_is_a_torus() {
    let torus = scenes::load("torus").unwrap();
    // The analytic reference torus' size: surface 0.12 from the ring of
    // radius 0.3 (union of segments: exact along each segment's middle,
    // where one segment dominates; the segments' ends lie at
    // 0.3 · 2 / (1 + cos 7.5°), their middles at that times cos 7.5°).
    let mid = std::f32::consts::TAU / 48.0;
    let along = isomorph_common::glam::Vec3::new(mid.cos(), mid.sin(), 0.0);
    let half_step = (std::f32::consts::PI / 24.0).cos();
    let on_ring = along * 0.3 * 2.0 / (1.0 + half_step) * half_step;
    assert!(torus.value(on_ring + along * 0.114) > 0.0 && torus.value(on_ring + along * 0.126) < 0.0);
    assert!(torus.value(on_ring - along * 0.114) > 0.0 && torus.value(on_ring - along * 0.126) < 0.0);
    assert!(torus.value(isomorph_common::glam::Vec3::ZERO) < 0.0, "the hole is empty");
}

#[test]
fn other_solids_are_unsupported_and_files_load() {
    let sphere = Solid::shape(Shape::sphere(0.3));
    let e = BlobMorph::new(&sphere, &solid("torus"), &BlobSettings::default(), &Control::new()).unwrap_err();
    match e {
        BlobMorphError::Morph(MorphError::UnsupportedInput { side: Side::Source, kind, .. }) => {
            assert_eq!(kind, "analytic shape")
        }
        other => panic!("expected UnsupportedInput, got {other}"),
    }
    assert!(scenes::load("no_such_scene").unwrap_err().to_string().contains("built-in scenes"));
    let dir = std::env::temp_dir().join(format!("isomorph-blob-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("spec.ron");
    std::fs::write(&path, "(speeds: [(a: [], b: [], speed: (start: 0.2, end: 0.8))])").unwrap();
    let spec = MorphSpec::load(&path).unwrap();
    assert_eq!(spec.speeds.len(), 1);
    assert!(MorphSpec::load(&dir.join("missing.ron")).is_err());
    assert_eq!(scenes::demo_spec("rook", "queen").unwrap().links.len(), 8);
    assert!(scenes::demo_spec("sphere", "torus").is_none());
    std::fs::remove_dir_all(dir).unwrap();
}
