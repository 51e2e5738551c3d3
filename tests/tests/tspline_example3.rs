//! Yang & Jüttler's Example 3 (Fig. 6): the built-in apple morphing into
//! the Utah teapot from `data/` (open and unwelded: the morph's target is
//! the zero set of its winding-number distance, which caps the spout's open
//! end and separates the lid along its open seam). The teapot's handle is a
//! tube about half a depth-4 cell across: the octree's sample-count rule
//! leaves it coarse and the evolution stalls without it, so the T-mesh is
//! adapted to the target as well (`TsplineSettings::target_adaptation`, up
//! to depth 5). Away from the front, where the step would lift `f` through
//! zero, the evolution holds `ḟ = 0` (`EvolveSettings::hold_fraction` ½):
//! without it, small pieces of surface are born above the knob, beside it
//! and at the spout in about a third of the level sets. Measured figures
//! are in `docs/EXPERIMENTS.md` ("Issue 17, T-spline: Example 3 converged"
//! and the seventh session's "held cells").

use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{Control, Morph};
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_tspline::{Outcome, Refinement, Speed, TsplineMorph, TsplineSettings};

/// Example 3's settings: depth 5 where the target's fit needs it, `n_T` 40
/// so that the octree alone stays mostly at depth 4 and below, held cells
/// at `c` = ½.
fn example3_settings() -> TsplineSettings {
    let mut s = TsplineSettings::default();
    s.tmesh.max_depth = 5;
    s.tmesh.max_samples_per_cell = 40;
    s.target_adaptation = Some(Refinement { tolerance: 0.02, max_rounds: 2 });
    s.evolve.speed = Speed::Robust { v_max: 0.2, beta_cells: 0.5 };
    s.evolve.max_steps = 150;
    s.evolve.hold_fraction = 0.5;
    s
}

/// Per level set (marching cubes at 64 nodes), the volume of every piece
/// other than the largest, over the largest's (world units³).
fn stray_fractions(m: &TsplineMorph) -> Vec<Vec<f64>> {
    let (ma, _) = m.projection_frame_counts();
    let n = (m.frame_count() - 1) as f32;
    (0..m.evolution().frames.len())
        .map(|k| {
            let mut v = m.frame_mesh((ma + k) as f32 / n, 64).unwrap().component_volumes();
            v.sort_by(|a, b| b.total_cmp(a));
            v[1..].iter().map(|x| x / v[0]).collect()
        })
        .collect()
}

#[test]
#[ignore = "about 90 s of CPU (6–8 min wall on the loaded shared 2-core machine): run with --ignored; figures in docs/EXPERIMENTS.md"]
fn apple_becomes_the_utah_teapot() {
    let options = LoadOptions::default();
    let apple = load_solid("apple", &options).unwrap();
    let teapot = load_solid(concat!(env!("CARGO_MANIFEST_DIR"), "/../data/teapot.ply"), &options).unwrap();
    let s = example3_settings();
    let m = TsplineMorph::new(&apple, &teapot, &s, &Control::new()).unwrap();
    let ev = m.evolution();
    let finest = m.tmesh().finest_cell();
    // Converged: two-sided RMS under a tenth of the finest cell and every
    // zero-set sample within half a cell of the target.
    assert_eq!(ev.outcome, Outcome::Converged, "{:?}", ev.steps.last());
    assert!(ev.final_error < 0.1 * finest, "{} against {}", ev.final_error, 0.1 * finest);
    assert!(m.report().details.get("target_adaptation_rounds").is_some());
    // The last level set is within three finest cells of every part of the
    // target (measured: 2.3 cells, 0.078 world units on a teapot about 1
    // wide; 2.5 cells without the held cells).
    let (ma, _) = m.projection_frame_counts();
    let n = (m.frame_count() - 1) as f32;
    let last = m.frame_mesh((ma + ev.frames.len() - 1) as f32 / n, 96).unwrap();
    let target = m.frame_mesh(1.0, 0).unwrap();
    let d = surface_distance(&last, &target, 20_000).unwrap();
    let world_cell = finest * f64::from(m.frame_transform(ma).matrix3.x_axis.length());
    assert!(
        f64::from(d.hausdorff) < 3.0 * world_cell,
        "Hausdorff {} against {world_cell} per cell",
        d.hausdorff
    );
    // Pieces besides the body (marching cubes at 64 nodes; those above
    // 1e-6 of its volume, so not the target's own speck of zero volume at
    // the spout's tip). Measured with the held cells: in 14 of 78 level
    // sets, at most 2 at once, the largest 2.3e-4 of the body; without
    // them: in 25 of 77, up to 6 at once, the largest 6.4e-3.
    let strays = stray_fractions(&m);
    let pieces: Vec<usize> = strays.iter().map(|v| v.iter().filter(|&&x| x.abs() > 1e-6).count()).collect();
    eprintln!("pieces per level set {pieces:?}");
    for (k, v) in strays.iter().enumerate().filter(|(_, v)| !v.is_empty()) {
        eprintln!("level set {k}: {v:?}");
    }
    let largest = strays.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(largest < 1e-3, "largest piece {largest} of the body");
    let with_pieces = pieces.iter().filter(|&&p| p > 0).count();
    assert!(4 * with_pieces < pieces.len(), "pieces in {with_pieces} of {} level sets", pieces.len());
    assert!(pieces.iter().all(|&p| p <= 2), "{pieces:?}");
    assert!(ev.steps.iter().any(|s| s.held_cells > 0), "the hold acted");
    eprintln!(
        "coefficients {}, steps {}, RMS {:.4}, surface distance mean {:.4} Hausdorff {:.4} (world; cell {world_cell:.4}), \
         last level set {:?}, target {:?}",
        m.tmesh().anchor_count(),
        ev.steps.len(),
        ev.final_error,
        d.mean,
        d.hausdorff,
        last.metrics(),
        target.metrics()
    );
}
