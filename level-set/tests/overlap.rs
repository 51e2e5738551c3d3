//! The overlap judgement (Breen & Whitaker §4) on the target, not on its
//! sampling: a small part the source cannot reach is a warning, a large one
//! an error naming its share, and a thin feature that coarse sampling
//! splits stays one part.

use isomorph_common::glam::{Quat, Vec3};
use isomorph_common::{Aabb, Control, Grid3, Morph, MorphError, Shape, Solid, Value};
use isomorph_levelset::{LevelSetError, LevelSetMorph, LevelSetSettings, Response, SpeedGrid, check_overlap};

fn settings() -> LevelSetSettings {
    LevelSetSettings { resolution: 40, ..Default::default() }
}

#[test]
fn a_small_unreached_part_is_a_warning_and_the_morph_runs() {
    let source = Solid::shape(Shape::sphere(0.3));
    // A ball of radius 0.06 far from the source: (0.06 / 0.3)³ ≈ 0.8 % of
    // the target's inside.
    let blob = Shape::sphere(0.06).translated(Vec3::new(0.7, 0.0, 0.0));
    let target = Solid::shape(Shape::torus(0.3, 0.12).union(blob));
    let morph = LevelSetMorph::new(&source, &target, &settings(), &Control::new()).unwrap();
    let report = morph.report();
    let warning = report.warnings.iter().find(|w| w.contains("not reached")).expect("a warning");
    assert!(warning.contains("1 of 2 target part(s)"), "{warning}");
    let Some(Value::Float(share)) = report.details.get("unreached_share").cloned() else {
        panic!("no unreached_share in {report:?}");
    };
    assert!(share > 0.002 && share < 0.02, "share {share}");
    assert!(morph.converged(), "{report:?}");
    // The morph ends on the torus, without the blob.
    let last = morph.frame_mesh(1.0, 0).unwrap();
    assert_eq!((last.connected_components(), last.genus()), (1, Some(1)));
}

#[test]
fn a_large_unreached_part_is_refused_with_its_share() {
    let source = Solid::shape(Shape::sphere(0.3));
    // A second ball of radius 0.25 far away: 0.25³ / (0.3³ + 0.25³) ≈ 37 %.
    let far = Shape::sphere(0.25).translated(Vec3::new(0.9, 0.0, 0.0));
    let target = Solid::shape(Shape::sphere(0.3).union(far));
    let e = LevelSetMorph::new(&source, &target, &settings(), &Control::new()).unwrap_err();
    let LevelSetError::Morph(MorphError::NoOverlap { ref missed, total, allowed }) = e else {
        panic!("expected NoOverlap, got {e:?}");
    };
    assert_eq!((missed.len(), total, allowed), (1, 2, 0.05));
    assert!((0.3..0.45).contains(&missed[0].share), "{missed:?}");
    assert!(missed[0].min.x > 0.55 && missed[0].max.x < 1.2, "{missed:?}");
    let message = e.to_string();
    let percent = format!("{:.1} %", 100.0 * missed[0].share);
    assert!(message.contains(&percent) && message.contains("max_unreached_share"), "{message}");
    // Allowing that share lets it run, with the warning.
    let lenient = LevelSetSettings { max_unreached_share: 0.5, ..settings() };
    let morph = LevelSetMorph::new(&source, &target, &lenient, &Control::new()).unwrap();
    assert!(morph.report().warnings.iter().any(|w| w.contains("not reached")));
}

/// Two balls joined by a rod of radius 0.3 voxel that runs between the grid
/// nodes: no node is inside the rod, so the sampled target falls into two
/// pieces, but the target is one part and the source, overlapping one ball,
/// reaches it.
#[test]
fn a_thin_feature_split_by_sampling_stays_one_part() {
    let res = 33;
    let bounds = Aabb::cube(0.5);
    let h = 1.0 / (res - 1) as f32;
    let offset = Vec3::new(0.0, 0.5 * h, 0.5 * h);
    let rod = Shape::cylinder(0.3 * h, 0.35).rotated(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
    let dumbbell = Shape::sphere(0.12)
        .translated(Vec3::new(-0.3, 0.0, 0.0))
        .union(Shape::sphere(0.12).translated(Vec3::new(0.3, 0.0, 0.0)))
        .union(rod.translated(offset));
    let source =
        Grid3::sample_box(&Shape::sphere(0.1).translated(Vec3::new(-0.3, 0.0, 0.0)), &bounds, res).unwrap();
    let speed = SpeedGrid::sample(&source, &dumbbell, |x| x, Response::Identity).unwrap();
    // The sampled target is two pieces: no node lies inside the rod.
    let rod_nodes = (0..source.len())
        .filter(|&n| {
            let c = source.node_of(n);
            let p = source.position(c.x, c.y, c.z);
            p.x.abs() < 0.15 && speed.node_value(n) > 0.0
        })
        .count();
    assert_eq!(rod_nodes, 0, "the rod was meant to fall between the nodes");
    let overlap = check_overlap(&source, &speed, 0.0).unwrap();
    assert_eq!((overlap.parts, overlap.missed.len()), (1, 0), "{overlap:?}");
    assert_eq!(overlap.warning(), None);
    // Two balls really apart (a gap of several voxels) stay two parts.
    let apart = Shape::sphere(0.12)
        .translated(Vec3::new(-0.3, 0.0, 0.0))
        .union(Shape::sphere(0.12).translated(Vec3::new(0.3, 0.0, 0.0)));
    let speed = SpeedGrid::sample(&source, &apart, |x| x, Response::Identity).unwrap();
    let overlap = check_overlap(&source, &speed, 0.6).unwrap();
    assert_eq!((overlap.parts, overlap.missed.len()), (2, 1), "{overlap:?}");
    assert!((overlap.unreached_share() - 0.5).abs() < 0.05, "{overlap:?}");
    assert!(check_overlap(&source, &speed, 0.4).is_err());
}

#[test]
fn the_unreached_share_setting_is_checked() {
    let (s, t) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(Shape::torus(0.3, 0.12)));
    for bad in [-0.1, 1.5, f32::NAN] {
        let settings = LevelSetSettings { max_unreached_share: bad, ..settings() };
        let e = LevelSetMorph::new(&s, &t, &settings, &Control::new()).unwrap_err();
        let message = e.to_string();
        assert!(
            matches!(e, LevelSetError::Morph(MorphError::BadSetting { name: "max_unreached_share", .. }))
                && message.contains("[0, 1]"),
            "{message}"
        );
    }
}
