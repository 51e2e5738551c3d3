//! The warp-and-dissolve morph under the morph contract: the conformance
//! suite on the reference pair with the default settings, the alignment
//! carrying a distant source, landmarks, and settings errors.

use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::glam::{Affine3A, Quat, Vec3};
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, Control, Morph, MorphError, Shape, Solid, models};
use isomorph_warp::{WarpError, WarpMorph, WarpMorphSettings, WarpSpec};

fn reference(shape: &Shape) -> isomorph_common::TriMesh {
    polygonize(shape, &Aabb::cube(0.5), 128, 0.0).unwrap()
}

#[test]
fn warp_conforms_with_its_defaults() {
    let (a, b) = (Shape::sphere(0.3), models::torus());
    let (sa, sb) = (Solid::shape(a.clone()), Solid::shape(b.clone()));
    let settings = WarpMorphSettings::default();
    let expect = Expectations {
        source: reference(&a),
        target: reference(&b),
        resolution: settings.resolution,
        mean_voxels: 0.05,
        hausdorff_voxels: 0.25,
        converges: true,
    };
    let got = check_morph(|c| WarpMorph::new(&sa, &sb, &settings, c), &expect);
    // Measured: mean 0.014 / Hausdorff 0.027 voxels (source), 0.019 / 0.066 (target).
    println!("{got:?}");
}

/// A small rotated sphere far from a torus: the alignment carries it over,
/// so the middle frame sits between them, one piece, instead of the two
/// fading blobs of a plain cross-dissolve.
#[test]
fn alignment_carries_a_distant_source() {
    let moved = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.6),
        Quat::from_rotation_z(0.7),
        Vec3::new(1.2, 0.0, 0.0),
    );
    let source = Solid::shape(Shape::sphere(0.3).transformed(moved));
    let target = Solid::shape(models::torus());
    let aligned = WarpMorph::new(&source, &target, &WarpMorphSettings::default(), &Control::new()).unwrap();
    let mid = aligned.frame_mesh(0.5, 0).unwrap();
    assert_eq!(mid.connected_components(), 1);
    let c = mid.bounds().center();
    assert!((c.x - 0.6).abs() < 0.1, "middle frame centred at {c}");
    let plain = WarpMorphSettings { spec: WarpSpec::Identity, ..Default::default() };
    let dissolve = WarpMorph::new(&source, &target, &plain, &Control::new()).unwrap();
    // Both halves are below the 0.5 density at t = 0.5: nothing or two
    // separate blobs, never one piece in the middle.
    let mid = dissolve.frame_mesh(0.5, 0).unwrap();
    assert_ne!(mid.connected_components(), 1);
}

/// Landmarks: a sphere's centre dragged onto a displaced sphere's.
#[test]
fn landmarks_move_their_points() {
    let a = Solid::shape(Shape::sphere(0.25));
    let b = Solid::shape(Shape::sphere(0.25).translated(Vec3::new(0.2, 0.0, 0.0)));
    let spec = WarpSpec::Landmarks(vec![(Vec3::ZERO, Vec3::new(0.2, 0.0, 0.0))]);
    let settings = WarpMorphSettings { spec, ..Default::default() };
    let morph = WarpMorph::new(&a, &b, &settings, &Control::new()).unwrap();
    let map = morph.source_map(1.0).unwrap();
    let (o, h) = (morph.source().origin(), morph.source().spacing());
    let moved = o + h * map.eval((Vec3::ZERO - o) / h);
    assert!(moved.distance(Vec3::new(0.2, 0.0, 0.0)) < 1e-3, "landmark lands at {moved}");
    let mid = morph.frame_mesh(0.5, 0).unwrap();
    assert!((mid.bounds().center().x - 0.1).abs() < 0.03, "{:?}", mid.bounds());
}

#[test]
fn bad_settings_name_the_field() {
    let s = Solid::shape(Shape::sphere(0.3));
    for (bad, name) in [
        (WarpMorphSettings { resolution: 4, ..Default::default() }, "resolution = 4"),
        (WarpMorphSettings { control_spacing: 0, ..Default::default() }, "control_spacing = 0"),
        (WarpMorphSettings { spec: WarpSpec::Landmarks(vec![]), ..Default::default() }, "landmark"),
        (
            WarpMorphSettings {
                spec: WarpSpec::Landmarks(vec![(Vec3::NAN, Vec3::ZERO)]),
                ..Default::default()
            },
            "finite",
        ),
    ] {
        let e = WarpMorph::new(&s, &s, &bad, &Control::new()).unwrap_err();
        assert!(matches!(e, WarpError::Morph(MorphError::BadSetting { .. })), "{e}");
        assert!(e.to_string().contains(name), "{e}");
    }
}
