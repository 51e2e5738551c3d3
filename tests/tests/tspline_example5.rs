//! Yang & Jüttler's Example 5's kind (Fig. 8, a dragon into a tricorn): a
//! dense closed mesh of tens of thousands of triangles morphs into a simple
//! shape elsewhere, turned and smaller, with the alignment (§4.2) undone
//! gradually over the frames (eq. 11). The source is the bunny re-meshed
//! densely (marching cubes of its exact signed distance), the target an
//! ellipsoid. The release figures of this case and of the Stanford dragon
//! (44,894 triangles) are in `docs/EXPERIMENTS.md` ("Issue 17, T-spline:
//! marching triangulation, final refinement, Example 5").

use glam::{Affine3A, Quat, Vec3};
use isomorph_common::alignment::AlignMode;
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::sdf::MeshSdf;
use isomorph_common::{AffineParts, Control, Morph, Shape};
use isomorph_io::inputs::bunny;
use isomorph_tspline::{Align, Outcome, TsplineSettings, morph};

#[test]
fn dense_bunny_becomes_a_turned_ellipsoid() {
    let coarse = bunny();
    let bb = coarse.bounds();
    let size = bb.size().max_element();
    let dense = polygonize(&MeshSdf::new(&coarse).unwrap(), &bb.expanded(0.02 * size), 96, 0.0).unwrap();
    assert!(dense.triangles.len() > 30_000, "{} triangles", dense.triangles.len());
    assert_eq!(dense.edge_stats().boundary_edges, 0);
    // The ellipsoid: half the bunny's size, turned 60° and moved aside.
    let turn = Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 60f32.to_radians());
    let place = Affine3A::from_rotation_translation(turn, bb.center() + Vec3::X * size);
    let ellipsoid = Shape::superellipsoid(Vec3::new(0.3, 0.18, 0.12) * size, 1.0, 1.0).transformed(place);
    let target = polygonize(&ellipsoid, &ellipsoid.aabb().expanded(0.05 * size), 48, 0.0).unwrap();
    let mut settings = TsplineSettings { align: Align::Moments(AlignMode::Affine), ..Default::default() };
    settings.evolve.max_steps = 60;
    let m = morph(&dense, &target, &settings, &Control::new()).unwrap();
    let ev = m.evolution();
    assert_eq!(ev.outcome, Outcome::Converged, "{:?}", ev.steps.last());
    // Endpoints: the sequence starts on the dense source and ends on the
    // target, in world space.
    let first = m.frame_mesh(0.0, 0).unwrap();
    let last = m.frame_mesh(1.0, 0).unwrap();
    let max_gap =
        |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0f32, f32::max);
    assert_eq!(first.positions.len(), dense.positions.len());
    assert!(max_gap(&first.positions, &dense.positions) < 1e-4 * size);
    assert!(max_gap(&last.positions, &target.positions) < 1e-4 * size);
    // The placement moves and turns gradually: mid-way the frame's centre
    // is between the shapes and its rotation about half the alignment's.
    let mid = m.frame_mesh(0.5, 64).unwrap();
    // One body carries the morph mid-way: no cavity, and any piece pinched
    // off a thin part (the ears) is tiny next to it.
    let mut volumes = mid.component_volumes();
    volumes.sort_by(|a, b| b.total_cmp(a));
    assert!(volumes.iter().all(|&v| v > 0.0), "{volumes:?}");
    let strays = volumes[1..].iter().sum::<f64>() / volumes[0];
    assert!(strays < 1e-2, "{volumes:?}");
    eprintln!(
        "{} source triangles, {} coefficients, {} steps, mid frame components {:?}",
        dense.triangles.len(),
        m.tmesh().anchor_count(),
        ev.steps.len(),
        volumes
    );
    let along = (mid.bounds().center() - bb.center()).dot(Vec3::X) / size;
    assert!((0.2..0.8).contains(&along), "mid frame at {along} of the way");
    let full = AffineParts::from_affine(&m.placement(0.0)).unwrap().rotation;
    let half = AffineParts::from_affine(&m.placement(0.5)).unwrap().rotation;
    assert!((half.angle_between(Quat::IDENTITY) - 0.5 * full.angle_between(Quat::IDENTITY)).abs() < 1e-3);
    assert!(m.report().details.get("coefficients").is_some());
}
