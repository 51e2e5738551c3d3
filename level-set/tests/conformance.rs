//! The level-set morph under the morph contract: the conformance suite on
//! the reference pair with the default settings, alignment, overlap,
//! settings and cancellation.

use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::glam::{Affine3A, Vec3};
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, CancelToken, Control, Field3, Morph, MorphError, Shape, Solid, models};
use isomorph_levelset::{Align, FrameSchedule, LevelSetError, LevelSetMorph, LevelSetSettings};

fn reference(shape: &Shape) -> isomorph_common::TriMesh {
    polygonize(shape, &Aabb::cube(0.5), 128, 0.0).unwrap()
}

#[test]
fn level_set_conforms_with_its_defaults() {
    let (a, b) = (Shape::sphere(0.3), models::torus());
    let (sa, sb) = (Solid::shape(a.clone()), Solid::shape(b.clone()));
    let settings = LevelSetSettings::default();
    let expect = Expectations {
        source: reference(&a),
        target: reference(&b),
        resolution: settings.resolution,
        mean_voxels: 0.15,
        hausdorff_voxels: 0.6,
        converges: true,
    };
    let got = check_morph(|c| LevelSetMorph::new(&sa, &sb, &settings, c), &expect);
    println!("{got:?}");
}

/// A source far from and smaller than its target: without alignment no part
/// of the target is reached (an error naming the part); with moment
/// alignment the morph runs, ends on the target in the world, and its
/// frames are placed by the interpolated map.
#[test]
fn alignment_makes_a_distant_pair_morph() {
    let moved = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.5),
        isomorph_common::glam::Quat::from_rotation_z(0.7),
        Vec3::new(1.5, 0.2, 0.0),
    );
    let torus = models::torus();
    let source = Solid::shape(Shape::sphere(0.3).transformed(moved));
    let target = Solid::shape(torus.clone());
    let plain = LevelSetSettings { resolution: 48, ..Default::default() };
    match LevelSetMorph::new(&source, &target, &plain, &Control::new()) {
        Err(LevelSetError::Morph(MorphError::NoOverlap { missed, total, .. })) => {
            assert_eq!((missed.len(), total), (1, 1));
            assert!((missed[0].share - 1.0).abs() < 1e-6 && missed[0].nodes > 0, "{missed:?}");
        }
        other => panic!("expected NoOverlap, got {other:?}"),
    }
    let aligned = LevelSetSettings { align: Align::Auto, ..plain };
    let morph = LevelSetMorph::new(&source, &target, &aligned, &Control::new()).unwrap();
    // The speed is the torus's distance seen through an anisotropic map, not
    // a distance in source space: the surface settles a hundredth of a voxel
    // above the RMS threshold and the evolution stops as stalled.
    let report = morph.report();
    assert!(report.residual.as_ref().unwrap().value < 0.05, "{report:?}");
    let last = morph.frame_mesh(1.0, 0).unwrap();
    let worst = last.positions.iter().map(|&p| torus.value(p).abs()).fold(0.0f32, f32::max);
    let voxel = morph.field_bounds().size().max_element() / 47.0;
    // The affine alignment maps the sphere's moments onto the torus's, so
    // the evolution happens in the scaled source space: allow the scale.
    assert!(worst < 2.0 * voxel, "last frame off the torus by {worst} ({voxel} per voxel)");
    let first = morph.frame_mesh(0.0, 0).unwrap();
    assert!(first.bounds().center().distance(Vec3::new(1.5, 0.2, 0.0)) < 0.05, "{:?}", first.bounds());
    for t in [0.0, 0.5, 1.0] {
        let b = morph.frame_mesh(t, 0).unwrap().bounds();
        let w = morph.world_bounds();
        assert!(w.contains(b.min) && w.contains(b.max), "frame {t} {b:?} outside {w:?}");
    }
}

#[test]
fn bad_settings_name_the_field_and_cancel_stops() {
    let s = Solid::shape(Shape::sphere(0.3));
    let t = Solid::shape(models::torus());
    for (bad, name) in [
        (LevelSetSettings { resolution: 3, ..Default::default() }, "resolution = 3"),
        (LevelSetSettings { curvature: Some(-1.0), ..Default::default() }, "curvature"),
        (LevelSetSettings { frames: FrameSchedule::Budget(0), ..Default::default() }, "frames"),
    ] {
        let e = LevelSetMorph::new(&s, &t, &bad, &Control::new()).unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    }
    let token = CancelToken::new();
    let trip = token.clone();
    // Cancel once the evolution has started.
    let control = Control::new().with_cancel(token).with_progress(move |p| {
        if p.stage == "evolution" {
            trip.cancel();
        }
    });
    let e = LevelSetMorph::new(&s, &t, &LevelSetSettings::default(), &control).unwrap_err();
    assert!(matches!(e, LevelSetError::Morph(MorphError::Cancelled)), "{e}");
}
