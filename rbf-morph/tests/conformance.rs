//! The variational-implicit morph under the morph contract: the conformance
//! suite on the reference pair with the default settings, a mesh input, and
//! settings errors that name the field.

use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::glam;
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::mesh::primitives::uv_sphere;
use isomorph_common::{Aabb, Control, Morph, MorphError, Shape, Solid, models};
use isomorph_rbf::{RbfError, RbfMorph, RbfSettings};

fn reference(shape: &Shape) -> isomorph_common::TriMesh {
    polygonize(shape, &Aabb::cube(0.5), 128, 0.0).unwrap()
}

#[test]
fn rbf_conforms_with_its_defaults() {
    let (a, b) = (Shape::sphere(0.3), models::torus());
    let (sa, sb) = (Solid::shape(a.clone()), Solid::shape(b.clone()));
    let settings = RbfSettings::default();
    let expect = Expectations {
        source: reference(&a),
        target: reference(&b),
        resolution: 64,
        mean_voxels: 0.05,
        hausdorff_voxels: 0.25,
        converges: true,
    };
    let got = check_morph(|c| RbfMorph::new(&sa, &sb, &settings, c), &expect);
    // Measured: mean 0.009 / Hausdorff 0.02 voxels (source), 0.014 / 0.05 (target).
    println!("{got:?}");
    let morph = RbfMorph::new(&sa, &sb, &settings, &Control::new()).unwrap();
    let report = morph.report();
    assert_eq!(report.details.get("constraints").map(|v| format!("{v:?}")), Some("Int(1600)".into()));
    assert!(report.residual.as_ref().unwrap().value < 1e-8, "{report:?}");
    // The sphere opens into the torus: one component throughout.
    for t in [0.25, 0.5, 0.75] {
        assert_eq!(morph.frame_mesh(t, 64).unwrap().connected_components(), 1, "t = {t}");
    }
}

/// A mesh input is sampled by its own vertices (no polygonization).
#[test]
fn mesh_inputs_morph() {
    let sphere = Solid::mesh(uv_sphere(glam::Vec3::ZERO, 0.3, 24, 48)).unwrap();
    let torus = Solid::shape(models::torus());
    let morph = RbfMorph::new(&sphere, &torus, &RbfSettings::default(), &Control::new()).unwrap();
    let start = morph.frame_mesh(0.0, 64).unwrap();
    let worst = start.positions.iter().map(|p| (p.length() - 0.3).abs()).fold(0.0f32, f32::max);
    assert!(worst < 0.01, "frame 0 off the sphere by {worst}");
}

#[test]
fn bad_settings_name_the_field() {
    let s = Solid::shape(Shape::sphere(0.3));
    for (bad, name) in [
        (RbfSettings { points: 2, ..Default::default() }, "points = 2"),
        (RbfSettings { separation: 0.0, ..Default::default() }, "separation = 0"),
        (RbfSettings { normal_offset: f32::NAN, ..Default::default() }, "normal_offset = NaN"),
        (RbfSettings { surface_resolution: 4, ..Default::default() }, "surface_resolution = 4"),
    ] {
        let e = RbfMorph::new(&s, &s, &bad, &Control::new()).unwrap_err();
        assert!(matches!(e, RbfError::Morph(MorphError::BadSetting { .. })), "{e}");
        assert!(e.to_string().contains(name), "{e}");
    }
}
