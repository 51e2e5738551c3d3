//! A small topology-changing morph that runs in the dev profile: a sphere
//! becomes a torus (genus 0 → 1) on a coarse T-mesh; also the bad-input
//! errors of the pipeline.

use isomorph_common::marching_cubes::polygonize;
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{Aabb, CancelToken, Control, Morph, MorphError, Shape, TriMesh};
use isomorph_tspline::{Speed, TsplineError, TsplineSettings, morph};

fn settings() -> TsplineSettings {
    let mut s = TsplineSettings::default();
    s.tmesh.max_depth = 3;
    s.tmesh.min_depth = 3;
    s.evolve.speed = Speed::Robust { v_max: 0.2, beta_cells: 1.0 };
    s.evolve.max_steps = 40;
    s
}

#[test]
fn sphere_becomes_a_torus() {
    let bounds = Aabb::cube(0.5);
    let source = polygonize(&Shape::sphere(0.3), &bounds, 32, 0.0).unwrap();
    let target = polygonize(&Shape::torus(0.3, 0.15), &bounds, 40, 0.0).unwrap();
    let m = morph(&source, &target, &settings(), &Control::new()).unwrap();
    let ev = m.evolution();
    let (ma, mb) = m.projection_frame_counts();
    assert!(ma >= 1 && mb >= 1);
    assert_eq!(m.frame_count(), ma + ev.frames.len() + mb);
    let n = m.frame_count() - 1;
    let first = m.frame_mesh(ma as f32 / n as f32, 64).unwrap();
    let last = m.frame_mesh((ma + ev.frames.len() - 1) as f32 / n as f32, 64).unwrap();
    assert_eq!(first.genus(), Some(0), "the initial level set is a sphere");
    assert_eq!(last.genus(), Some(1), "the final level set is a torus ({:?})", ev.outcome);
    let d = surface_distance(&last, &target, 2000).unwrap();
    assert!(d.mean < 0.05, "{d:?} {:?} {} components", ev.outcome, last.connected_components());
    // No piece pinched off on the way stays behind: the evolution only
    // converges when every zero-set sample is near the target.
    assert_eq!(last.connected_components(), 1);
    assert_eq!(ev.outcome, isomorph_tspline::Outcome::Converged);
    // The projection frames end exactly at the inputs.
    let close = |a: &[glam::Vec3], b: &[glam::Vec3]| {
        a.len() == b.len() && a.iter().zip(b).all(|(p, q)| (*p - *q).length() < 1e-5)
    };
    assert!(close(&m.frame_mesh(0.0, 0).unwrap().positions, &source.positions));
    assert!(close(&m.frame_mesh(1.0, 0).unwrap().positions, &target.positions));
    assert!(matches!(m.frame(1.5), Err(TsplineError::Morph(MorphError::InvalidTime(_)))));
}

#[test]
fn bad_inputs_are_typed_errors() {
    let bounds = Aabb::cube(0.5);
    let a = polygonize(&Shape::sphere(0.1).translated(glam::Vec3::splat(-0.3)), &bounds, 32, 0.0).unwrap();
    let b = polygonize(&Shape::sphere(0.1).translated(glam::Vec3::splat(0.3)), &bounds, 32, 0.0).unwrap();
    let go = Control::new();
    assert!(matches!(morph(&a, &b, &settings(), &go), Err(TsplineError::NoOverlap)));
    assert!(matches!(
        morph(&TriMesh::default(), &b, &settings(), &go),
        Err(TsplineError::EmptyShape("source"))
    ));
    let mut bad = settings();
    bad.tmesh.max_depth = 12;
    assert!(matches!(
        morph(&a, &a, &bad, &go),
        Err(TsplineError::Morph(MorphError::BadSetting { name: "max_depth", .. }))
    ));
    let mut nan = a.clone();
    nan.positions[0].x = f32::NAN;
    assert!(morph(&nan, &a, &settings(), &go).is_err());
    // Cancellation at the first evolution step.
    let c = polygonize(&Shape::sphere(0.25), &bounds, 32, 0.0).unwrap();
    let d = polygonize(&Shape::sphere(0.3), &bounds, 32, 0.0).unwrap();
    let token = CancelToken::new();
    let trip = token.clone();
    let stop = Control::new().with_cancel(token).with_progress(move |p| {
        if p.stage == "evolution" {
            trip.cancel();
        }
    });
    assert!(matches!(morph(&c, &d, &settings(), &stop), Err(TsplineError::Morph(MorphError::Cancelled))));
}
