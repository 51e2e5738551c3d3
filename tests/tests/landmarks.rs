//! Correspondence-driven level-set morphs (Breen & Whitaker §6.2): a body
//! whose fin points along +x morphs into the same body with the fin along
//! +y. Without landmarks the level set shrinks the old fin away and grows
//! a new one (the paper's dart → X-29 problem); with landmarks the target
//! is seen through the warp `W` they define, and the fin travels.

use isomorph_cli::methods::{LandmarkWarp, landmark_warp};
use isomorph_common::glam::Vec3;
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{Control, Landmarks, Morph, Solid, TriMesh, Value, models};
use isomorph_levelset::{Align, LevelSetMorph, LevelSetSettings};
use std::f32::consts::FRAC_PI_2;

const RES: u32 = 64;
const FRAMES: usize = 9;
const BODY: f32 = models::FIN_BALL_RADIUS;

fn finned(angle: f32) -> Solid {
    Solid::shape(models::finned_ball(angle))
}

fn landmarks() -> Landmarks {
    models::fin_turn_landmarks()
}

fn morph(align: Align) -> LevelSetMorph {
    let settings = LevelSetSettings { resolution: RES, align, ..Default::default() };
    LevelSetMorph::new(&finned(0.0), &finned(FRAC_PI_2), &settings, &Control::new()).unwrap()
}

fn frames(morph: &LevelSetMorph) -> Vec<TriMesh> {
    (0..FRAMES).map(|i| morph.frame_mesh(i as f32 / (FRAMES - 1) as f32, RES).unwrap()).collect()
}

/// The fin's tip in a frame: the vertex farthest from the body's centre.
fn tip(mesh: &TriMesh) -> Vec3 {
    mesh.positions.iter().copied().fold(Vec3::ZERO, |t, p| if p.length() > t.length() { p } else { t })
}

/// Largest turn (radians) of the tip between consecutive frames, and the
/// shortest the fin gets (tip distance beyond the body).
fn tip_path(frames: &[TriMesh]) -> (f32, f32) {
    let tips: Vec<Vec3> = frames.iter().map(tip).collect();
    let jump = tips.windows(2).map(|w| w[0].angle_between(w[1])).fold(0.0, f32::max);
    let shortest = tips.iter().map(|t| t.length() - BODY).fold(f32::INFINITY, f32::min);
    (jump, shortest)
}

fn voxel(morph: &LevelSetMorph) -> f32 {
    morph.field_bounds().size().max_element() / (RES - 1) as f32
}

#[test]
fn with_landmarks_the_fin_travels_without_it_regrows() {
    let plain = morph(Align::None);
    let warp = landmark_warp(&landmarks(), LandmarkWarp::Rbf, 8).unwrap();
    let guided = morph(Align::Warp(warp));
    let (plain_jump, plain_shortest) = tip_path(&frames(&plain));
    let (guided_jump, guided_shortest) = tip_path(&frames(&guided));
    println!(
        "tip: largest turn between frames {:.1}° without landmarks, {:.1}° with; fin length at its shortest {:.3} without, {:.3} with",
        plain_jump.to_degrees(),
        guided_jump.to_degrees(),
        plain_shortest,
        guided_shortest
    );
    // Without landmarks the tip stays at +x while that fin shrinks, then
    // jumps to the regrown fin at +y.
    assert!(plain_jump > 60f32.to_radians(), "{}", plain_jump.to_degrees());
    // With landmarks it turns a quarter circle in eight steps.
    assert!(guided_jump < 25f32.to_radians(), "{}", guided_jump.to_degrees());
    assert!(guided_shortest > plain_shortest + 0.03, "{guided_shortest} vs {plain_shortest}");
}

#[test]
fn a_landmark_morph_runs_from_the_source_to_the_target() {
    let lm = landmarks();
    for kind in [LandmarkWarp::Rbf, LandmarkWarp::Bspline] {
        let m = morph(Align::Warp(landmark_warp(&lm, kind, 8).unwrap()));
        let h = voxel(&m);
        let control = Control::new();
        let source = finned(0.0).surface(RES, &control).unwrap().into_owned();
        let target = finned(FRAC_PI_2).surface(RES, &control).unwrap().into_owned();
        let (first, last) = (m.frame_mesh(0.0, RES).unwrap(), m.frame_mesh(1.0, RES).unwrap());
        let d0 = surface_distance(&first, &source, 4000).unwrap();
        let d1 = surface_distance(&last, &target, 4000).unwrap();
        println!(
            "{kind:?}: first frame mean {:.2} / max {:.2} vox from the source, last frame {:.2} / {:.2} from the target",
            d0.mean / h,
            d0.hausdorff / h,
            d1.mean / h,
            d1.hausdorff / h
        );
        assert!(d0.mean < 0.5 * h && d0.hausdorff < 1.5 * h, "{kind:?} start {d0:?}");
        assert!(d1.mean < h && d1.hausdorff < 3.0 * h, "{kind:?} end {d1:?}");
        // Every landmark ends where its partner is: the last frame passes
        // within a voxel of each target point.
        for &(_, q) in lm.pairs() {
            let gap = last.positions.iter().map(|p| p.distance(q)).fold(f32::INFINITY, f32::min);
            assert!(gap < h, "{kind:?}: landmark {q} is {:.2} voxels from the last frame", gap / h);
        }
        assert_eq!(m.report().details.get("warped"), Some(&Value::Bool(true)));
    }
}

#[test]
fn a_warped_frame_knows_where_its_points_came_from() {
    // The colour lookup reads the inputs at `ends_of`: for the mid-way fin
    // tip that is the source's tip and the target's tip, not the empty
    // space where the turning fin happens to be.
    let m = morph(Align::Warp(landmark_warp(&landmarks(), LandmarkWarp::Rbf, 8).unwrap()));
    let mid = tip(&m.frame_mesh(0.5, RES).unwrap());
    let [on_source, on_target] = m.ends_of(0.5, &[mid]).unwrap();
    let (source_tip, target_tip) = (Vec3::new(0.58, 0.0, 0.0), Vec3::new(0.0, 0.58, 0.0));
    // Within 0.1 of the tips (the fin is 0.4 long; the mid-way tip itself
    // is about 0.4 from both, where a lookup at the frame would read).
    println!("mid-way tip {mid} came from {} and goes to {}", on_source[0], on_target[0]);
    assert!(mid.distance(source_tip) > 0.3 && mid.distance(target_tip) > 0.3, "{mid}");
    assert!(on_source[0].distance(source_tip) < 0.1, "{} from the source's tip", on_source[0]);
    assert!(on_target[0].distance(target_tip) < 0.1, "{} from the target's tip", on_target[0]);
    // Frame 0 is the source where it is.
    let p = Vec3::new(0.1, -0.2, 0.15);
    assert!(m.ends_of(0.0, &[p]).unwrap()[0][0].distance(p) < 1e-5);
}
