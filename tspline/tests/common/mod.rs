//! Shared set-up of the Fig. 2–3 comparisons (`t_to_c.rs`, `corner.rs`).

use isomorph_common::Control;
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, Morph, Shape};
use isomorph_tspline::{Speed, TsplineMorph, TsplineSettings, morph};

/// Morphs `source` into `target` (polygonized with `res` nodes over
/// `[−0.5, 0.5]³`) on a T-mesh of maximum depth `depth` (minimum 3) with
/// `margin`, `speed`, a step of half a finest cell, at most `max_steps`
/// steps and no projection frames; `stall_steps` as in `EvolveSettings`.
pub fn run(
    (source, target, res): (&Shape, &Shape, u32),
    depth: u32,
    margin: f64,
    speed: Speed,
    (max_steps, stall_steps): (usize, usize),
) -> TsplineMorph {
    let bounds = Aabb::cube(0.5);
    let source = polygonize(source, &bounds, res, 0.0).unwrap();
    let target = polygonize(target, &bounds, res, 0.0).unwrap();
    let mut s = TsplineSettings::default();
    s.tmesh.max_depth = depth;
    s.tmesh.min_depth = 3;
    s.margin = margin;
    s.projection_frames = false;
    s.evolve.speed = speed;
    s.evolve.step = Some(0.5 * 2.0 / f64::from(1u32 << depth));
    s.evolve.max_steps = max_steps;
    s.evolve.stall_steps = stall_steps;
    morph(&source, &target, &s, &Control::new()).unwrap()
}

/// The connected components of every frame (the initial level set first),
/// polygonized over the domain with 40 nodes per axis.
pub fn components_per_frame(m: &TsplineMorph) -> Vec<usize> {
    (0..m.frame_count())
        .map(|i| {
            let t = i as f32 / (m.frame_count() - 1) as f32;
            m.frame_mesh(t, 40).unwrap().connected_components()
        })
        .collect()
}
