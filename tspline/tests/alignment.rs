//! §4.2 alignment and §4.4 eq. 11: a source turned by 90° and scaled by 1.5
//! relative to its target (an asymmetric bar, so that the turn is
//! observable and the moments recover it) is aligned onto the target, the
//! T-mesh is built on the aligned shapes, and the frames are placed by
//! `W(u)`: translation and stretch linear, rotation slerped. The endpoints
//! reproduce the inputs in world space (the conformance suite).

use glam::{Affine3A, Quat, Vec3};
use isomorph_common::alignment::{AlignMode, Moments};
use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{AffineParts, Control, Morph, Shape, Solid};
use isomorph_tspline::{Align, TsplineMorph, TsplineSettings};
use std::f32::consts::FRAC_PI_2;

/// A bar with a ball on one end, off its long axis: no mirror symmetry
/// across the bar's x or y axis, so the moment frame is unique.
fn target_shape() -> Shape {
    Shape::cuboid(Vec3::new(0.3, 0.12, 0.08))
        .union(Shape::sphere(0.11).translated(Vec3::new(0.2, 0.06, 0.0)))
        .translated(Vec3::new(0.05, 0.02, -0.03))
}

/// Source = `MOTION(target)`: turned 90° about z, scaled by 1.5, moved.
fn motion() -> Affine3A {
    Affine3A::from_scale_rotation_translation(
        Vec3::splat(1.5),
        Quat::from_rotation_z(FRAC_PI_2),
        Vec3::new(0.15, -0.1, 0.05),
    )
}

fn settings(align: Align) -> TsplineSettings {
    let mut s = TsplineSettings { align, surface_resolution: 48, ..Default::default() };
    s.tmesh.max_depth = 3;
    s
}

fn solids() -> (Solid, Solid) {
    (Solid::shape(target_shape().transformed(motion())), Solid::shape(target_shape()))
}

/// The angle (radians) between two rotations.
fn angle_between(a: Quat, b: Quat) -> f32 {
    a.angle_between(b)
}

/// Runs the conformance suite (frame 0 is the source and frame 1 the
/// target in world space, exactly: projection frames) and returns the morph.
fn conforming(align: Align) -> TsplineMorph {
    let (source, target) = solids();
    let s = settings(align);
    let control = Control::new();
    let res = s.surface_resolution;
    let expect = Expectations {
        source: source.surface(res, &control).unwrap().into_owned(),
        target: target.surface(res, &control).unwrap().into_owned(),
        resolution: 64,
        mean_voxels: 0.01,
        hausdorff_voxels: 0.01,
        converges: true,
    };
    let got = check_morph(|c| TsplineMorph::new(&source, &target, &s, c), &expect);
    println!("{got:?}");
    TsplineMorph::new(&source, &target, &s, &control).unwrap()
}

/// Eq. 11 read off `W(u)` against the interpolation of `T⁻¹`'s parts.
fn assert_follows_eq_11(m: &TsplineMorph, tol: f32) {
    let inverse = AffineParts::from_affine(&m.alignment_map().unwrap().inverse()).unwrap();
    for u in [0.0, 0.25, 0.5, 0.75, 1.0] {
        let w = AffineParts::from_affine(&m.placement(u)).unwrap();
        let rotation = inverse.rotation.slerp(Quat::IDENTITY, u);
        let stretch = inverse.stretch * (1.0 - u) + glam::Mat3::IDENTITY * u;
        assert!(angle_between(w.rotation, rotation) < tol, "u {u}: {w:?} vs rotation {rotation:?}");
        assert!(w.stretch.abs_diff_eq(stretch, tol), "u {u}: {w:?} vs stretch {stretch:?}");
    }
    // The centre of the turn (the aligned source's centroid, ≈ the
    // target's) moves on a straight line.
    let source = solids().0.surface(48, &Control::new()).unwrap().into_owned();
    let centroid = Moments::from_mesh(&source).unwrap().centroid.as_vec3();
    let centre = m.alignment_map().unwrap().transform_point3(centroid);
    let at = |u: f32| m.placement(u).transform_point3(centre);
    assert!(at(0.0).distance(centroid) < tol && at(1.0).distance(centre) < tol);
    for u in [0.25, 0.5, 0.75] {
        let line = centroid.lerp(centre, u);
        assert!(at(u).distance(line) < tol, "u {u}: {} vs {line}", at(u));
    }
}

/// The middle frame in world space is the target placed by `W(u)` (the
/// aligned source and the target coincide, so the level sets are the target
/// in the working space), and its long axis is turned by `90° (1 − u)`.
fn assert_middle_frame_is_placed(m: &TsplineMorph) {
    let i = m.frame_count() / 2;
    let u = m.frame_u(i);
    let frame = m.frame_mesh(u, 64).unwrap();
    let target = solids().1.surface(48, &Control::new()).unwrap().transformed(&m.placement(u));
    let d = surface_distance(&frame, &target, 4000).unwrap();
    println!("frame {i} of {} (u {u}): {d:?}", m.frame_count());
    assert!(d.mean < 0.01 && d.hausdorff < 0.05, "frame {i} (u {u}): {d:?}");
    let long_axis = |mesh: &isomorph_common::TriMesh| {
        Moments::from_mesh(mesh).unwrap().principal_frame().unwrap().axes.z_axis.as_vec3()
    };
    let long = long_axis(&frame);
    let original = long_axis(&solids().1.surface(48, &Control::new()).unwrap());
    let expected = Quat::from_rotation_z(FRAC_PI_2 * (1.0 - u)) * original;
    let degrees = long.dot(expected).abs().min(1.0).acos().to_degrees();
    assert!(degrees < 1.5, "frame {i} (u {u}): long axis {long}, expected {expected} ({degrees}°)");
    let volume = |mesh: &isomorph_common::TriMesh| mesh.signed_volume();
    let scale = f64::from(1.5 * (1.0 - u) + u);
    let ratio = volume(&frame) / volume(&solids().1.surface(48, &Control::new()).unwrap());
    assert!((ratio / scale.powi(3) - 1.0).abs() < 0.05, "volume ratio {ratio}, scale {scale}");
}

#[test]
fn a_user_map_is_interpolated_by_eq_11() {
    let m = conforming(Align::Map(motion().inverse()));
    assert!(m.alignment_map().unwrap().abs_diff_eq(motion().inverse(), 1e-6));
    // The placement runs from the source's (T⁻¹ = MOTION) to the target's.
    assert!(m.placement(0.0).abs_diff_eq(motion(), 1e-5), "{:?}", m.placement(0.0));
    assert!(m.placement(1.0).abs_diff_eq(Affine3A::IDENTITY, 1e-5));
    // Halfway: a 45° turn about z and a scale of 1.25.
    let half = AffineParts::from_affine(&m.placement(0.5)).unwrap();
    let turn = Quat::from_rotation_z(FRAC_PI_2 / 2.0);
    assert!(angle_between(half.rotation, turn) < 1e-3, "{half:?}");
    assert!(half.stretch.abs_diff_eq(glam::Mat3::from_diagonal(Vec3::splat(1.25)), 1e-3), "{half:?}");
    assert_follows_eq_11(&m, 1e-3);
    assert_middle_frame_is_placed(&m);
    let details = format!("{:?}", m.report().details);
    assert!(details.contains("alignment_rotation_degrees"), "{details}");
}

#[test]
fn moment_alignment_recovers_the_turn_and_the_scale() {
    let m = conforming(Align::Moments(AlignMode::Affine));
    // The moments find MOTION⁻¹ (up to the meshes' sampling).
    let inverse = AffineParts::from_affine(&m.alignment_map().unwrap().inverse()).unwrap();
    assert!(angle_between(inverse.rotation, Quat::from_rotation_z(FRAC_PI_2)) < 1e-2, "{inverse:?}");
    assert!((inverse.scale() - Vec3::splat(1.5)).abs().max_element() < 1e-2, "{inverse:?}");
    // Halfway: 45° and 1.25 (to the moments' accuracy), exactly eq. 11 of
    // the map found.
    let half = AffineParts::from_affine(&m.placement(0.5)).unwrap();
    assert!(angle_between(half.rotation, Quat::from_rotation_z(FRAC_PI_2 / 2.0)) < 1e-2, "{half:?}");
    assert!((half.scale() - Vec3::splat(1.25)).abs().max_element() < 1e-2, "{half:?}");
    assert_follows_eq_11(&m, 1e-3);
    assert_middle_frame_is_placed(&m);
}

#[test]
fn mirror_maps_are_refused() {
    let (source, target) = solids();
    let mirror = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let e = TsplineMorph::new(&source, &target, &settings(Align::Map(mirror)), &Control::new()).unwrap_err();
    assert!(e.to_string().contains("align"), "{e}");
}
