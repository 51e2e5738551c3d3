//! The paper's Fig. 2 effect with the shapes of its captions: a "T"
//! ([`demo::letter_t`]) morphing into a "C" ([`demo::letter_c`]), judged by
//! the number of connected components of every level set. With the distance
//! speed (`λ ≡ 1`, Fig. 2) the T's bar is cut in its middle and its end
//! becomes a second component that then vanishes. The paper's speed splits
//! this layout too (measured 1, 1, 1, 2, 2, 2, 2, 2, 2: its curvature weight
//! `1 − exp(−d_B²)` is largest at the bar's middle, farthest from the C); the
//! Fig. 3 comparison is tested with the shapes of the paper's text, "┌" →
//! "┐", in `tests/corner.rs`.

use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, Morph};
use isomorph_tspline::{MorphSettings, Speed, demo, morph};
use std::ops::ControlFlow;

/// Maximum octree depth: finest cells of 0.125 domain units, the T's bar
/// (half width 0.07 world ≈ 0.12 domain units) is about two cells wide.
const DEPTH: u32 = 4;

/// Runs the first `steps` evolution steps of the T → C morph with `speed`
/// and returns the component count of every level set (the initial one
/// first), polygonized over the domain with 40 nodes per axis.
fn components_per_level_set(speed: Speed, steps: usize) -> Vec<usize> {
    let bounds = Aabb::cube(0.5);
    let source = polygonize(&demo::letter_t(), &bounds, 40, 0.0).unwrap();
    let target = polygonize(&demo::letter_c(), &bounds, 40, 0.0).unwrap();
    let mut s = MorphSettings::default();
    s.tmesh.max_depth = DEPTH;
    s.tmesh.min_depth = 3;
    // A wide margin keeps the level set clear of the domain boundary (see
    // the crate docs' known issues).
    s.margin = 0.5;
    s.projection_frames = false;
    s.evolve.speed = speed;
    // Half a finest cell per step, so that the split lasts several frames.
    s.evolve.step = Some(0.5 * 2.0 / f64::from(1u32 << DEPTH));
    s.evolve.max_steps = steps;
    let m = morph(&source, &target, &s, &|_| ControlFlow::Continue(())).unwrap();
    assert_eq!(m.evolution().frames.len(), steps + 1, "{:?}", m.evolution().outcome);
    (0..m.frame_count())
        .map(|i| {
            let t = i as f32 / (m.frame_count() - 1) as f32;
            m.frame_mesh(t, 40).unwrap().connected_components()
        })
        .collect()
}

#[test]
fn distance_speed_splits_the_t() {
    let counts = components_per_level_set(Speed::Distance, 8);
    eprintln!("components per level set: {counts:?}");
    assert_eq!(counts[0], 1, "the initial level set is the T");
    assert!(counts.iter().any(|&c| c >= 2), "the bar is cut: {counts:?}");
    assert_eq!(counts.last(), Some(&1), "the cut-off end vanishes: {counts:?}");
}
