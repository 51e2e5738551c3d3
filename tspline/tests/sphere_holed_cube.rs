//! The paper's Example 2: a sphere morphing into a cube with holes.

use isomorph_common::marching_cubes::polygonize;
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{Aabb, Morph, Shape};
use isomorph_tspline::{MorphSettings, Outcome, Speed, demo, morph};
use std::ops::ControlFlow;

#[test]
#[ignore = "heavy: about a minute in release (14744 coefficients at depth 5, 15 steps of about \
            40000 zero-set samples); run with `cargo test --release -p isomorph-tspline --test \
            sphere_holed_cube -- --ignored`"]
fn sphere_becomes_a_genus_three_holed_cube() {
    let bounds = Aabb::cube(0.5);
    let source = polygonize(&Shape::sphere(0.3), &bounds, 40, 0.0).unwrap();
    let target = polygonize(&demo::holed_cube(), &bounds, 64, 0.0).unwrap();
    assert_eq!(target.genus(), Some(3));
    let mut settings = MorphSettings::default();
    // Depth 5 makes the holes 7 finest cells wide (at depth 4 a plug of
    // positive f stays in each); margin 0.5 keeps the cube's faces away
    // from the domain boundary (at 0.2 open sheets appear there).
    settings.tmesh.max_depth = 5;
    settings.margin = 0.5;
    settings.evolve.speed = Speed::Robust { v_max: 0.2, beta: 0.0625 };
    settings.evolve.max_steps = 60;
    let t0 = std::time::Instant::now();
    let m = morph(&source, &target, &settings, &|s| {
        eprintln!("{:.1}s {s:?}", t0.elapsed().as_secs_f64());
        ControlFlow::Continue(())
    })
    .unwrap();
    let ev = m.evolution();
    eprintln!(
        "outcome {:?} error {} coefficients {} steps {}",
        ev.outcome,
        ev.final_error,
        m.tmesh().anchor_count(),
        ev.steps.len()
    );
    let n = ev.frames.len();
    let (ma, mb) = m.projection_frame_counts();
    let last_level_set = m.frame_mesh((ma + n - 1) as f32 / (m.frame_count() - 1) as f32, 96).unwrap();
    eprintln!("genus {:?} components {}", last_level_set.genus(), last_level_set.connected_components());
    let d = surface_distance(&last_level_set, &target, 4000).unwrap();
    eprintln!("{d:?}");
    assert_eq!(last_level_set.genus(), Some(3));
    assert_eq!(last_level_set.connected_components(), 1);
    assert!(d.mean < 0.01, "{d:?}");
    assert!(matches!(ev.outcome, Outcome::Converged | Outcome::Stalled));
    // The projection frames make the sequence end exactly at the target.
    let close = |a: &[glam::Vec3], b: &[glam::Vec3]| {
        a.len() == b.len() && a.iter().zip(b).all(|(p, q)| (*p - *q).length() < 1e-5)
    };
    assert!(close(&m.frame_mesh(1.0, 64).unwrap().positions, &target.positions));
    assert!(close(&m.frame_mesh(0.0, 64).unwrap().positions, &source.positions));
    let _ = mb;
}
