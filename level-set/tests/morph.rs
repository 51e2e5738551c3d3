//! End-to-end behaviour of the level-set morph on the paper's cases.

use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{Aabb, Field3, Grid3, Shape, TriMesh, models};
use isomorph_common::{Control, DistanceBlend, Morph, MorphError};
use isomorph_levelset::{
    EvolveSettings, FrameSchedule, LevelSetError, LevelSetMorph, Placement, Response, SolverKind, SpeedGrid,
    evolve,
};

/// Sphere r = 0.3 → torus R = 0.3, r = 0.12 in [-0.5, 0.5]³ (the reference case).
fn sphere_torus(res: u32, solver: SolverKind) -> (LevelSetMorph, Grid3<f32>, Shape) {
    let (source, speed) = reference_case(res);
    let torus = Shape::torus(0.3, 0.12);
    let settings = EvolveSettings { solver, ..EvolveSettings::default() };
    let morph = evolve(&source, &speed, Placement::Identity, &settings, &Control::new()).unwrap();
    (morph, source, torus)
}

/// The reference case's source (signed distance grid) and target speed at `res³`.
fn reference_case(res: u32) -> (Grid3<f32>, SpeedGrid) {
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), res).unwrap();
    let speed = SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, Response::Identity).unwrap();
    (source, speed)
}

/// The reference case at `res³` evolved with each of `settings`, and its
/// source.
fn reference_runs<const N: usize>(
    res: u32,
    settings: [EvolveSettings; N],
) -> (Grid3<f32>, [LevelSetMorph; N]) {
    let (source, speed) = reference_case(res);
    let runs = settings.map(|s| evolve(&source, &speed, Placement::Identity, &s, &Control::new()).unwrap());
    (source, runs)
}

/// Mean and max distance (voxels) of the mesh's vertices to the zero set of
/// an exact distance field.
fn vertex_error(mesh: &TriMesh, exact: &dyn Field3, h: f32) -> (f32, f32) {
    let d: Vec<f32> = mesh.positions.iter().map(|&p| exact.value(p).abs() / h).collect();
    (d.iter().sum::<f32>() / d.len() as f32, d.iter().fold(0.0f32, |a, &b| a.max(b)))
}

#[test]
fn sphere_becomes_the_torus_with_the_sparse_field() {
    let (morph, source, torus) = sphere_torus(48, SolverKind::SparseField);
    let h = source.spacing();
    assert!(morph.converged(), "iterations {}", morph.stats().len());
    let first = morph.frame_mesh(0.0, 0).unwrap();
    let (mean0, max0) = vertex_error(&first, &Shape::sphere(0.3), h);
    assert!(mean0 < 0.05 && max0 < 0.2, "first frame off the sphere: mean {mean0}, max {max0}");
    let last = morph.frame_mesh(1.0, 0).unwrap();
    let (mean, max) = vertex_error(&last, &torus, h);
    eprintln!("sparse 48³: {} iterations, mean {mean:.4} max {max:.4} voxels", morph.stats().len());
    assert!(mean < 0.1 && max < 0.5, "last frame off the torus: mean {mean}, max {max} voxels");
    assert_eq!(last.genus(), Some(1));
    assert_eq!(last.connected_components(), 1);
}

/// The converged surface lies within the grid's own floor: marching cubes of
/// the analytic torus's exact distance sampled on the same lattice. With
/// the paper's city-block layers and trilinear speed the sparse field ended
/// at 0.0099 voxel mean / 0.068 max at 64³ (floor 0.0035 / 0.016), failing
/// both bounds.
#[test]
fn the_converged_surface_is_as_close_to_the_torus_as_the_grid_allows() {
    let (morph, source, torus) = sphere_torus(64, SolverKind::SparseField);
    let h = source.spacing();
    assert!(morph.converged(), "iterations {}", morph.stats().len());
    let exact = Grid3::sample_box(&torus, &Aabb::cube(0.5), 64).unwrap();
    let (floor_mean, floor_max) =
        vertex_error(&isomorph_common::marching_cubes::marching_cubes(&exact, 0.0), &torus, h);
    let (mean, max) = vertex_error(&morph.frame_mesh(1.0, 0).unwrap(), &torus, h);
    eprintln!(
        "sparse 64³: {} iterations, mean {mean:.4} max {max:.4} voxels (floor {floor_mean:.4} / {floor_max:.4})",
        morph.stats().len()
    );
    assert!(
        mean <= floor_mean + 0.001 && max <= floor_max + 0.004,
        "last frame off the torus: mean {mean}, max {max} voxels; the grid's floor {floor_mean} / {floor_max}"
    );
}

#[test]
fn dense_and_sparse_solvers_agree() {
    let res = 32;
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), res).unwrap();
    let speed = SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, Response::Identity).unwrap();
    let run = |solver| {
        let settings = EvolveSettings {
            solver,
            max_time_step: 1.0 / (3.0 * speed.max_abs()),
            frames: FrameSchedule::EveryIterations(15),
            max_iterations: 150,
            rms_change: 0.0,
            rms_distance: 0.0,
            settled_rms_distance: 0.0,
            ..EvolveSettings::default()
        };
        evolve(&source, &speed, Placement::Identity, &settings, &Control::new()).unwrap()
    };
    let (sparse, dense) = (run(SolverKind::SparseField), run(SolverKind::Dense));
    assert_eq!(sparse.len(), dense.len());
    let h = source.spacing();
    for n in 0..sparse.len() {
        assert_eq!(sparse.frames()[n].iteration, dense.frames()[n].iteration);
        // The kept frames of the same iteration (the two solvers' travels,
        // which place `frame(t)`, measure their different active sets).
        let a = marching_cubes(&sparse.frame_grid(n).unwrap(), 0.0);
        let b = marching_cubes(&dense.frame_grid(n).unwrap(), 0.0);
        let d = isomorph_common::mesh::distance::surface_distance(&a, &b, 4000).unwrap();
        assert!(d.hausdorff / h < 1.0, "frame {n}: Hausdorff {} voxels", d.hausdorff / h);
    }
}

#[test]
fn ball_to_c_never_pops_pieces_but_the_blend_does() {
    let (ball, c) = (models::by_name("ball").unwrap(), models::by_name("c-shape").unwrap());
    let bounds = Aabb::cube(0.5);
    let res = 40;
    let source = Grid3::sample_box(&ball, &bounds, res).unwrap();
    let target = Grid3::sample_box(&c, &bounds, res).unwrap();
    let speed = SpeedGrid::from_grid(&target, Response::Identity).unwrap();
    let settings = EvolveSettings { frames: FrameSchedule::EveryIterations(5), ..EvolveSettings::default() };
    let morph = evolve(&source, &speed, Placement::Identity, &settings, &Control::new()).unwrap();
    let most = (0..morph.len())
        .map(|n| morph.frame_mesh(n as f32 / (morph.len() - 1) as f32, 0).unwrap().connected_components())
        .max()
        .unwrap();
    assert_eq!(most, 1, "the level-set morph split into {most} pieces");
    let blend = DistanceBlend::from_grids(source, target).unwrap();
    let blend_most =
        (0..=20).map(|i| blend.frame_mesh(i as f32 / 20.0, 0).unwrap().connected_components()).max();
    assert!(blend_most.unwrap() > 1, "the baseline blend was expected to pop pieces (Breen Fig. 6)");
    let last = morph.frame_mesh(1.0, 0).unwrap();
    let reference = isomorph_common::marching_cubes::marching_cubes(&speed_grid_world(&c, &bounds, res), 0.0);
    let d = isomorph_common::mesh::distance::surface_distance(&last, &reference, 4000).unwrap();
    let h = 1.0 / (res - 1) as f32;
    assert!(
        d.mean / h < 0.5 && d.hausdorff / h < 1.5,
        "mean {} Hausdorff {} voxels",
        d.mean / h,
        d.hausdorff / h
    );
}

fn speed_grid_world(shape: &Shape, bounds: &Aabb, res: u32) -> Grid3<f32> {
    Grid3::sample_box(shape, bounds, res).unwrap()
}

#[test]
fn bad_inputs_are_typed_errors() {
    let bounds = Aabb::cube(0.5);
    let source =
        Grid3::sample_box(&Shape::sphere(0.1).translated(glam::Vec3::new(-0.3, 0.0, 0.0)), &bounds, 24)
            .unwrap();
    let far = Shape::sphere(0.1).translated(glam::Vec3::new(0.3, 0.0, 0.0));
    let speed = SpeedGrid::sample(&source, &far, |x| x, Response::Identity).unwrap();
    let settings = EvolveSettings::default();
    let none = Control::new();
    assert!(matches!(
        evolve(&source, &speed, Placement::Identity, &settings, &none),
        Err(LevelSetError::Morph(MorphError::NoOverlap { ref missed, total: 1, .. })) if missed.len() == 1 && missed[0].share == 1.0
    ));
    let empty = source.map(|_| -1.0f32).unwrap();
    assert!(matches!(
        evolve(&empty, &speed, Placement::Identity, &settings, &none),
        Err(LevelSetError::NoSurface("source"))
    ));
    assert!(matches!(
        SpeedGrid::from_grid(&empty, Response::Identity),
        Err(LevelSetError::NoSurface("target"))
    ));
    let mut nan = source.clone();
    nan.data_mut()[7] = f32::NAN;
    assert!(matches!(
        evolve(&nan, &speed, Placement::Identity, &settings, &none),
        Err(LevelSetError::NonFinite { what: "source", node: 7 })
    ));
    let other = Grid3::sample_box(&Shape::sphere(0.3), &bounds, 20).unwrap();
    assert!(matches!(
        evolve(&other, &speed, Placement::Identity, &settings, &none),
        Err(LevelSetError::Morph(MorphError::Grid(_)))
    ));
    let zero = EvolveSettings { max_iterations: 0, ..settings };
    assert!(matches!(
        evolve(&source, &speed, Placement::Identity, &zero, &none),
        Err(LevelSetError::Morph(MorphError::BadSetting { .. }))
    ));
    for front_step in [0.0, 0.6, f32::NAN] {
        let bad = EvolveSettings { front_step, ..settings };
        assert!(matches!(
            evolve(&source, &speed, Placement::Identity, &bad, &none),
            Err(LevelSetError::Morph(MorphError::BadSetting { name: "front_step", .. }))
        ));
    }
}

/// Half a voxel per iteration for the fastest front (the default) instead
/// of eq. 24's third reaches the same converged surface in fewer
/// iterations: the two final meshes lie within a fiftieth of a voxel of
/// each other, and the paper's step needs at least a quarter more
/// iterations.
#[test]
fn the_half_voxel_front_step_converges_to_the_papers_surface_sooner() {
    let with = |front_step| EvolveSettings { front_step, ..EvolveSettings::default() };
    let (source, [half, paper]) = reference_runs(48, [with(0.5), with(1.0 / 3.0)]);
    assert!(half.converged() && paper.converged());
    let (a, b) = (half.frame_mesh(1.0, 0).unwrap(), paper.frame_mesh(1.0, 0).unwrap());
    let d = surface_distance(&a, &b, 4000).unwrap();
    let h = source.spacing();
    assert!(d.hausdorff / h < 0.02, "final surfaces {} voxels apart (Hausdorff)", d.hausdorff / h);
    let (fast, slow) = (half.stats().len(), paper.stats().len());
    assert!(4 * slow >= 5 * fast, "{fast} iterations at half a voxel, {slow} at a third");
}

#[test]
fn curvature_regularized_morph_still_lands_on_the_target() {
    use isomorph_levelset::Curvature;
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 40).unwrap();
    let torus = Shape::torus(0.3, 0.12);
    let speed = SpeedGrid::sample(&source, &torus, |x| x, Response::Identity).unwrap();
    let curvature = Some(Curvature { weight: 2.0, length: 0.5 });
    let settings = EvolveSettings { curvature, ..EvolveSettings::default() };
    let morph = evolve(&source, &speed, Placement::Identity, &settings, &Control::new()).unwrap();
    assert!(morph.converged());
    let last = morph.frame_mesh(1.0, 0).unwrap();
    let (mean, max) = vertex_error(&last, &torus, source.spacing());
    assert!(mean < 0.1 && max < 0.5, "mean {mean}, max {max} voxels");
    assert_eq!(last.genus(), Some(1));
    // The curvature term is active: the step is bounded by 1/(6w).
    assert!(morph.stats().iter().all(|s| s.dt <= 1.0 / 12.0 + 1e-6));
}

#[test]
fn mug_becomes_the_chain_after_moment_alignment() {
    use isomorph_common::alignment::{AlignMode, Moments, align};
    let bounds = Aabb::cube(0.5);
    let res = 64;
    let (mug, chain) = (models::by_name("mug").unwrap(), models::by_name("chain").unwrap());
    let moments = |s: &Shape| Moments::from_field(s, &bounds, res).unwrap();
    let map = align(&moments(&mug), &moments(&chain), AlignMode::Affine).unwrap().map;
    let region = mug.aabb().union(&chain.aabb().transformed(&map.inverse())).padded(0.1);
    let source = Grid3::sample_box(&mug, &region, res).unwrap();
    let speed = SpeedGrid::sample(&source, &chain, |x| map.transform_point3(x), Response::Identity).unwrap();
    let path = isomorph_common::AffinePath::from_identity(&map).unwrap();
    let morph = evolve(&source, &speed, path.into(), &EvolveSettings::default(), &Control::new()).unwrap();
    assert!(morph.converged());
    // Frames are placed by T(x, n/(N − 1)): the last one lies in the chain's space.
    let last = morph.frame_mesh(1.0, 0).unwrap();
    let reference = Grid3::sample_box(&chain, &bounds, 96).unwrap();
    let reference = isomorph_common::marching_cubes::marching_cubes(&reference, 0.0);
    let d = isomorph_common::mesh::distance::surface_distance(&last, &reference, 6000).unwrap();
    // Voxel of the evolution grid, measured in the target's space.
    let h = source.spacing() * map.matrix3.determinant().cbrt();
    assert!(
        d.mean / h < 0.5 && d.hausdorff / h < 1.5,
        "mean {} Hausdorff {} voxels",
        d.mean / h,
        d.hausdorff / h
    );
    assert_eq!(last.connected_components(), 3, "the three links");
    let first = morph.frame_mesh(0.0, 0).unwrap();
    assert_eq!(first.genus(), Some(1), "the mug with its handle");
}

#[test]
fn warp_placement_carries_the_last_frame_onto_the_target() {
    use isomorph_common::glam::Vec3;
    // A non-affine generalized warp W (a shear that bends along y): the
    // speed is the torus seen through W, and frames are placed by
    // T(x, α) = (1 − α) x + α W(x).
    let warp = |p: Vec3| Vec3::new(p.x + 0.4 * p.y * p.y, p.y, p.z);
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 48).unwrap();
    let torus = Shape::torus(0.3, 0.12);
    let speed = SpeedGrid::sample(&source, &torus, warp, Response::Identity).unwrap();
    let morph =
        evolve(&source, &speed, Placement::warp(warp), &EvolveSettings::default(), &Control::new()).unwrap();
    assert!(morph.converged());
    let h = source.spacing();
    let worst = |mesh: &TriMesh, field: &dyn Field3| {
        mesh.positions.iter().map(|&p| field.value(p).abs() / h).fold(0.0f32, f32::max)
    };
    // Frame 1 lies on the torus in the target's own space (the distance
    // is only Lipschitz through W, so allow a voxel), frame 0 on the sphere.
    let last = morph.frame_mesh(1.0, 0).unwrap();
    assert!(worst(&last, &torus) < 1.0, "last frame off the torus by {} voxels", worst(&last, &torus));
    let first = morph.frame_mesh(0.0, 0).unwrap();
    let sphere = Shape::sphere(0.3);
    assert!(worst(&first, &sphere) < 0.5, "first frame off the sphere by {} voxels", worst(&first, &sphere));
    assert_eq!(morph.report().details.get("placement"), Some(&isomorph_common::Value::Text("warp".into())));
}

#[test]
fn a_run_that_stops_improving_under_the_settled_distance_has_converged() {
    // Thresholds no run reaches: only the settle rule (or the cap) stops it.
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 32).unwrap();
    let speed = SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, Response::Identity).unwrap();
    let run = |settled_rms_distance| {
        let settings = EvolveSettings {
            rms_distance: 0.0,
            rms_change: 0.0,
            settled_rms_distance,
            settle_iterations: 20,
            stall_iterations: 60,
            max_iterations: 2000,
            ..EvolveSettings::default()
        };
        evolve(&source, &speed, Placement::Identity, &settings, &Control::new()).unwrap()
    };
    let settled = run(0.05);
    let best = settled.stats().iter().map(|s| s.rms_distance).fold(f32::INFINITY, f32::min);
    assert!(settled.report().converged, "{:?}", settled.report().outcome);
    assert!(best <= 0.05, "best RMS distance {best} voxels");
    // Without the rule the same run is a stall, 40 iterations later.
    let stalled = run(0.0);
    assert!(!stalled.report().converged, "{:?}", stalled.report().outcome);
    assert_eq!(stalled.stats()[..settled.stats().len()], *settled.stats());
    // The settle rule fired 20 iterations after the last 1 % improvement,
    // the stall 60 after it (at the round-off floor, where the RMS distance
    // still wanders by a few per cent, that may be a later improvement).
    let last_improvement = |stats: &[isomorph_levelset::StepStats]| {
        let (mut best, mut at) = (f32::INFINITY, 0);
        for (i, s) in stats.iter().enumerate() {
            if s.rms_distance < 0.99 * best {
                (best, at) = (s.rms_distance, i + 1);
            }
        }
        at
    };
    assert_eq!(settled.stats().len(), last_improvement(settled.stats()) + 20);
    assert_eq!(stalled.stats().len(), last_improvement(stalled.stats()) + 60);
}

/// Under a small frame budget (4: between 5 and 10 kept frames) the same
/// evolution gives, at every morph time, the frame of the morph that kept
/// every iteration: the same mesh where that iteration was kept (always at
/// `t = 0` and `t = 1`), otherwise a surface interpolated between the two
/// kept frames that bracket it, within the Hausdorff distance between those
/// two frames (plus half a voxel for the sampled distances) of the true one.
#[test]
fn a_frame_budget_gives_the_every_iteration_frames() {
    let with = |frames| EvolveSettings { frames, ..EvolveSettings::default() };
    let schedules = [with(FrameSchedule::EveryIterations(1)), with(FrameSchedule::Budget(4))];
    let (source, [all, budget]) = reference_runs(40, schedules);
    let iterations = all.stats().len();
    assert_eq!(all.stats(), budget.stats(), "the kept frames changed the evolution");
    assert_eq!(all.len(), iterations + 1);
    assert!((5..=10).contains(&budget.len()), "{} kept frames of {iterations} iterations", budget.len());
    assert!(budget.stored_bytes() * 4 < all.stored_bytes());
    let h = source.spacing();
    assert_eq!(all.travel(), budget.travel());
    let kept = |n: usize| marching_cubes(&all.frame_grid(n).unwrap(), 0.0);
    let mut interpolated = 0;
    for k in 0..=20 {
        let t = k as f32 / 20.0;
        let (exact, got) = (all.frame_mesh(t, 0).unwrap(), budget.frame_mesh(t, 0).unwrap());
        // Morph time `t` shows travel `t × total`; the budget's kept frames
        // around it.
        let travel = budget.travel();
        let at = f64::from(t) * travel[iterations];
        let frames = budget.frames();
        let after = frames.partition_point(|f| travel[f.iteration] < at);
        if t == 1.0 || travel[frames[after].iteration] == at {
            assert_eq!(got.positions, exact.positions, "t = {t}: its iteration was kept");
            continue;
        }
        interpolated += 1;
        let (a, b) = (frames[after - 1].iteration, frames[after].iteration);
        let apart = surface_distance(&kept(a), &kept(b), 4000).unwrap().hausdorff;
        let off = surface_distance(&got, &exact, 4000).unwrap();
        assert!(
            off.hausdorff <= apart + 0.5 * h,
            "t = {t} (travel {at:.2} between iterations {a} and {b}): {} voxels off, the kept frames {} voxels apart",
            off.hausdorff / h,
            apart / h
        );
    }
    assert!(interpolated > 5, "only {interpolated} interpolated frames");
}
