//! The T-mesh adapted to the target as well as to the source
//! ([`TsplineSettings::target_adaptation`]): a thin target part that the
//! octree's sample-count rule leaves coarse gets the coefficients the
//! evolution needs to reach it.

use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, Control, Morph, Shape, Value};
use isomorph_tspline::{Outcome, Refinement, TsplineSettings, morph};

#[test]
fn adapting_the_tmesh_to_a_thin_target_refines_it_where_the_target_fit_misses() {
    let bounds = Aabb::cube(0.5);
    let source = polygonize(&Shape::sphere(0.3), &bounds, 32, 0.0).unwrap();
    // A thin ring: its tube is about one depth-4 cell across.
    let target = polygonize(&Shape::torus(0.3, 0.05), &bounds, 64, 0.0).unwrap();
    let mut s = TsplineSettings::default();
    // An octree that stops early (many samples allowed per cell), so the
    // thin tube sits in coarse cells unless the target's fit refines them.
    s.tmesh.max_depth = 4;
    s.tmesh.min_depth = 2;
    s.tmesh.max_samples_per_cell = 200;
    s.evolve.max_steps = 30;
    let plain = morph(&source, &target, &s, &Control::new()).unwrap();
    assert!(plain.report().details.get("target_adaptation_rounds").is_none());

    s.target_adaptation = Some(Refinement { tolerance: 0.005, max_rounds: 2 });
    let adapted = morph(&source, &target, &s, &Control::new()).unwrap();
    let details = &adapted.report().details;
    let number = |key: &str| match details.get(key) {
        Some(Value::Int(i)) => *i as f64,
        Some(Value::Float(x)) => *x,
        other => panic!("{key}: {other:?}"),
    };
    let rounds = number("target_adaptation_rounds");
    assert!((1.0..=2.0).contains(&rounds), "{details:?}");
    let (before, after) =
        (number("target_adaptation_max_surface_error_before"), number("target_adaptation_max_surface_error"));
    assert!(after < 0.5 * before, "the target's fit error {before} → {after}");
    let (n0, n1) = (plain.tmesh().anchor_count(), adapted.tmesh().anchor_count());
    assert!(n1 > n0, "{n0} → {n1} coefficients");
    // The evolution on the adapted T-mesh converges, and no farther from
    // the ring than on the plain one (Example 3's handle,
    // `tests/tests/tspline_example3.rs` of `isomorph-tests`, is the case
    // that stalls without it).
    assert_eq!(adapted.evolution().outcome, Outcome::Converged, "{:?}", adapted.evolution().steps.last());
    let (e0, e1) = (plain.evolution().final_error, adapted.evolution().final_error);
    assert!(e1 <= e0, "two-sided RMS {e0} → {e1}");
    eprintln!(
        "coefficients {n0} → {n1}, target fit error {before:.4} → {after:.4}, final error {e0:.4} ({:?}) → {e1:.4} ({:?})",
        plain.evolution().outcome,
        adapted.evolution().outcome
    );
}
