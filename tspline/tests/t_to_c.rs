//! The paper's Fig. 2 effect with the shapes of its captions: a "T"
//! ([`demo::letter_t`]) morphing into a "C" ([`demo::letter_c`]), judged by
//! the number of connected components of every level set. With the distance
//! speed (`λ ≡ 1`, Fig. 2) the T's bar is cut in its middle and its end
//! becomes a second component that then vanishes (measured 1, 1, 2, 2, 1,
//! 1, 1, 3, 1: a small stray at step 7 is gone by step 8). The paper's speed splits
//! this layout too (measured 1, 1, 1, 2, 2, 2, 2, 2, 2: its curvature weight
//! `1 − exp(−d_B²)` is largest at the bar's middle, farthest from the C); the
//! Fig. 3 comparison is tested with the shapes of the paper's text, "┌" →
//! "┐", in `tests/corner.rs`.

mod common;

use isomorph_tspline::{Speed, demo};

/// Maximum octree depth: finest cells of 0.125 domain units, the T's bar
/// (half width 0.07 world ≈ 0.12 domain units) is about two cells wide.
const DEPTH: u32 = 4;

/// Runs the first `steps` evolution steps of the T → C morph with `speed`
/// and returns the component count of every level set (the initial one
/// first), polygonized over the domain with 40 nodes per axis.
fn components_per_level_set(speed: Speed, steps: usize) -> Vec<usize> {
    // A wide margin keeps the level set clear of the domain boundary (see
    // the crate docs); half a finest cell per step, so that the split lasts
    // several frames.
    let shapes = (&demo::letter_t(), &demo::letter_c(), 40);
    let m = common::run(shapes, DEPTH, 0.5, speed, (steps, 8));
    assert_eq!(m.evolution().frames.len(), steps + 1, "{:?}", m.evolution().outcome);
    common::components_per_frame(&m)
}

#[test]
fn distance_speed_splits_the_t() {
    let counts = components_per_level_set(Speed::Distance, 8);
    eprintln!("components per level set: {counts:?}");
    assert_eq!(counts[0], 1, "the initial level set is the T");
    assert!(counts.iter().any(|&c| c >= 2), "the bar is cut: {counts:?}");
    assert_eq!(counts.last(), Some(&1), "the cut-off end vanishes: {counts:?}");
}
