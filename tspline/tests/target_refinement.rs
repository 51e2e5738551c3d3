//! The final refinement of the target's approximation after the evolution
//! (paper §3.2, last paragraph) and the paper's mesher for the frames
//! (marching triangulation, §4.4), through the whole morph.

use isomorph_common::marching_cubes::polygonize;
use isomorph_common::marching_triangulation::triangle_quality;
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{Aabb, Control, Morph, Shape};
use isomorph_tspline::{Mesher, Outcome, Refinement, TsplineSettings, morph};

#[test]
fn refining_the_target_brings_the_last_level_set_closer() {
    let bounds = Aabb::cube(0.5);
    let source = polygonize(&Shape::sphere(0.3), &bounds, 32, 0.0).unwrap();
    let target = polygonize(&Shape::torus(0.3, 0.12), &bounds, 48, 0.0).unwrap();
    let mut s = TsplineSettings {
        mesher: Mesher::MarchingTriangulation { edge: 0.03 },
        target_refinement: Some(Refinement { tolerance: 0.002, max_rounds: 2 }),
        ..Default::default()
    };
    // An octree that stops early (many samples allowed per cell), so the
    // refinement has depth left to add.
    s.tmesh.max_depth = 4;
    s.tmesh.min_depth = 2;
    s.tmesh.max_samples_per_cell = 200;
    s.evolve.max_steps = 40;
    let m = morph(&source, &target, &s, &Control::new()).unwrap();
    assert_eq!(m.evolution().outcome, Outcome::Converged);
    let (refined, fit) = m.refined_target().expect("refined");
    assert!(fit.rounds.len() >= 2, "at least one refinement round: {:?}", fit.rounds);
    assert!(refined.mesh().anchor_count() > m.tmesh().anchor_count());
    let (ma, mb) = m.projection_frame_counts();
    let levels = m.evolution().frames.len();
    assert_eq!(m.frame_count(), ma + levels + 1 + mb);
    let n = (m.frame_count() - 1) as f32;
    let evolved = m.frame_mesh((ma + levels - 1) as f32 / n, 64).unwrap();
    let last = m.frame_mesh((ma + levels) as f32 / n, 64).unwrap();
    for mesh in [&evolved, &last] {
        assert_eq!(mesh.edge_stats().boundary_edges, 0);
        assert_eq!(mesh.genus(), Some(1));
    }
    let (before, after) =
        (surface_distance(&evolved, &target, 4000).unwrap(), surface_distance(&last, &target, 4000).unwrap());
    assert!(after.mean < 0.7 * before.mean, "mean distance {} → {}", before.mean, after.mean);
    assert!(after.hausdorff < before.hausdorff, "Hausdorff {} → {}", before.hausdorff, after.hausdorff);
    // The frames come from the marching triangulation: near-uniform
    // triangles of about the edge asked for (0.03 domain units, 0.0167 world
    // units here), unlike the marching-cubes mesh of the same level set.
    let q = triangle_quality(&last).unwrap();
    assert!(q.mean_min_angle > 40.0 && q.edge_spread < 0.3, "{q:?}");
    let world_edge = 0.03 * (m.frame_transform(0).matrix3.x_axis.length() as f64);
    assert!((q.mean_edge / world_edge - 1.0).abs() < 0.2, "{} against {world_edge}", q.mean_edge);
    // The projection frames end exactly on the target.
    let end = m.frame_mesh(1.0, 0).unwrap();
    assert_eq!(end.positions.len(), target.positions.len());
    assert!(end.positions.iter().zip(&target.positions).all(|(p, q)| (*p - *q).length() < 1e-5));
    eprintln!(
        "coefficients {} → {}, rounds {}, mean distance {:.5} → {:.5}, Hausdorff {:.5} → {:.5}, {q:?}",
        m.tmesh().anchor_count(),
        refined.mesh().anchor_count(),
        fit.rounds.len() - 1,
        before.mean,
        after.mean,
        before.hausdorff,
        after.hausdorff
    );
}
