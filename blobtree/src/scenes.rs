//! The paper's metamorphosis sequences (§5) as built-in scenes.
//!
//! All scenes use `I = 1` and `T = 0.5`, so an isolated primitive's surface
//! lies at distance `R/2` from its skeleton (the Blanc–Schlick midpoint).
//! The scenes `sphere` and `torus` are the analytic reference shapes
//! (`isomorph_common::models::{sphere, torus}`: radius 0.3; ring 0.3, tube
//! 0.12) so that `isomorph compare --source sphere --target torus` gives the
//! BlobTree method the same pair as the other methods.
//!
//! | demo | source → target | what it exercises |
//! |---|---|---|
//! | `cube_sphere` | rounded cube → sphere minus three axis-aligned boxes (Fig. 17) | primitive ↔ difference: a difference with a phantom subtrahend is inserted, the animator's phantom a point at the cube's centre (`scale: 0`) as in the paper, so the holes open from an inner cavity; L^∞ box holes; change of genus |
//! | `sphere_propeller` | sphere (radius 0.6) → twisted blend of two rounded rods (Fig. 19) | identity twist inserted, sphere split into two α-weighted copies |
//! | `rook_queen` | rook → queen (Fig. 21) | difference ↔ difference (each slot linked to four of the eight spherical carvings, replicated under the union), identity taper inserted, polygon ↔ point skeletons, per-node speed curves |
//! | `bear_bird` | blob bear → blob bird (Fig. 2) | nearest-centre matching of many blended primitives, segments ↔ polygons |

use crate::correspond::{Link, Phantom};
use crate::error::BlobError;
use crate::error::NodePath;
use crate::generic::{MorphSpec, Speed, SpeedCurve};
use crate::kernel::Kernel;
use crate::node::{Node, Primitive};
use crate::skeleton::Skeleton;
use crate::tree::BlobTree;
use crate::warp::Warp;
use glam::{Affine3A, Vec3};

/// Threshold of every built-in scene.
pub const THRESHOLD: f32 = 0.5;

/// Names of the built-in morphs (see [`demo`]).
pub const DEMOS: [&str; 4] = ["cube_sphere", "sphere_propeller", "rook_queen", "bear_bird"];

/// Names of the built-in scenes (see [`load`]).
pub const NAMES: [&str; 9] =
    ["rounded_cube", "pierced_sphere", "sphere", "propeller", "rook", "queen", "bear", "bird", "torus"];

/// A built-in scene by name ([`NAMES`]), or a scene file (`.json` read as
/// JSON, anything else as RON).
///
/// # Errors
/// [`BlobError::Read`] for an unknown name, an unreadable file or one
/// larger than [`crate::scene::MAX_FILE_BYTES`], and the
/// parse and validation errors of the file.
pub fn load(spec: &str) -> Result<BlobTree, BlobError> {
    let built_in = match spec {
        "rounded_cube" => Some(rounded_cube()),
        "pierced_sphere" => Some(pierced_sphere()),
        "sphere" => Some(sphere()),
        "propeller" => Some(propeller()),
        "rook" => Some(rook()),
        "queen" => Some(queen()),
        "bear" => Some(bear()),
        "bird" => Some(bird()),
        "torus" => Some(torus()),
        _ => None,
    };
    if let Some(tree) = built_in {
        return Ok(tree);
    }
    let path = std::path::Path::new(spec);
    let text = crate::scene::read_text(path, &format!(" (built-in scenes: {})", NAMES.join(", ")))?;
    if path.extension().is_some_and(|e| e == "json") {
        BlobTree::from_json(&text)
    } else {
        BlobTree::from_ron(&text)
    }
}

/// The animator's spec of the built-in morph from scene `source` to scene
/// `target` (e.g. `rook` → `queen`), when that pair is one of [`DEMOS`].
pub fn demo_spec(source: &str, target: &str) -> Option<MorphSpec> {
    let name = format!("{source}_{target}");
    let name = match name.as_str() {
        "rounded_cube_pierced_sphere" => "cube_sphere",
        other => other,
    };
    DEMOS.contains(&name).then(|| demo(name).map(|(_, _, spec)| spec)).flatten()
}

/// The analytic reference torus' BlobTree (`isomorph_common::models::torus`:
/// ring radius 0.3 around z, tube radius 0.12): the union of 24 segments
/// along the ring with `R = 0.24`, so joints do not bulge and the surface
/// lies `R/2 = 0.12` from the segments. The segments' ends sit slightly
/// outside the ring (radius `0.3 · 2 / (1 + cos 7.5°)`) so that their
/// distance from the axis stays within ±0.0013 of 0.3 along each segment.
pub fn torus() -> BlobTree {
    let half_step = std::f32::consts::PI / TORUS_SEGMENTS as f32;
    let ends = TORUS_RING * 2.0 / (1.0 + half_step.cos());
    let ring = |i: usize| {
        let a = 2.0 * half_step * i as f32;
        Vec3::new(ends * a.cos(), ends * a.sin(), 0.0)
    };
    tree(Node::union((0..TORUS_SEGMENTS).map(|i| seg(ring(i), ring(i + 1), 2.0 * TORUS_TUBE)).collect()))
}

/// Segments along the built-in torus' ring.
const TORUS_SEGMENTS: usize = 24;
/// Ring radius of the built-in torus (as `isomorph_common::models::torus`).
const TORUS_RING: f32 = 0.3;
/// Tube radius of the built-in torus (as `isomorph_common::models::torus`).
const TORUS_TUBE: f32 = 0.12;

fn prim(skeleton: Skeleton, radius: f32, at: Vec3) -> Node {
    Node::Primitive(
        Primitive::new(skeleton, Kernel::new(1.0, radius, 1.0)).with_frame(Affine3A::from_translation(at)),
    )
}

fn ball(at: Vec3, radius: f32) -> Node {
    prim(Skeleton::Point(Vec3::ZERO), radius, at)
}

fn seg(a: Vec3, b: Vec3, radius: f32) -> Node {
    prim(Skeleton::Segment(a, b), radius, Vec3::ZERO)
}

fn box_node(half: Vec3, radius: f32, at: Vec3, p: f32) -> Node {
    Node::Primitive(
        Primitive::new(Skeleton::cuboid(half), Kernel::new(1.0, radius, 1.0))
            .with_p(p)
            .with_frame(Affine3A::from_translation(at)),
    )
}

fn disc(radius: f32, sides: usize, z: f32, r: f32) -> Node {
    let v = (0..sides)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / sides as f32;
            Vec3::new(radius * a.cos(), radius * a.sin(), 0.0)
        })
        .collect();
    prim(Skeleton::Polygon(v), r, Vec3::new(0.0, 0.0, z))
}

fn tree(root: Node) -> BlobTree {
    BlobTree::new(root, THRESHOLD).expect("built-in scenes are valid")
}

/// A rounded cube: one box skeleton (half size 0.35) offset by 0.25.
pub fn rounded_cube() -> BlobTree {
    tree(box_node(Vec3::splat(0.35), 0.5, Vec3::ZERO, 2.0))
}

/// A sphere (radius 0.7) pierced by three orthogonal square holes
/// (L^∞ offsets of thin boxes): `sphere − (box_x ∪ box_y ∪ box_z)`.
pub fn pierced_sphere() -> BlobTree {
    let hole = |half: Vec3| box_node(half, 0.2, Vec3::ZERO, f32::INFINITY);
    tree(Node::difference(
        ball(Vec3::ZERO, 1.4),
        Node::union(vec![
            hole(Vec3::new(1.0, 0.12, 0.12)),
            hole(Vec3::new(0.12, 1.0, 0.12)),
            hole(Vec3::new(0.12, 0.12, 1.0)),
        ]),
        THRESHOLD,
    ))
}

/// The analytic reference sphere's BlobTree (`isomorph_common::models::sphere`):
/// one point primitive with `R = 0.6`, its surface at radius 0.3.
pub fn sphere() -> BlobTree {
    tree(ball(Vec3::ZERO, 0.6))
}

/// The sphere → propeller demo's sphere (radius 0.6, the propeller's size;
/// twice [`sphere`]).
fn propeller_sphere() -> BlobTree {
    tree(ball(Vec3::ZERO, 1.2))
}

/// Two rounded rods blended and twisted about their common axis (a helix).
pub fn propeller() -> BlobTree {
    let rod = |x: f32| seg(Vec3::new(x, 0.0, -0.7), Vec3::new(x, 0.0, 0.7), 0.36);
    tree(Node::warp(Warp::twist(2.2), Node::blend(vec![rod(-0.2), rod(0.2)])))
}

/// A rook: base and body blended, under a top cut by two crossing slots.
pub fn rook() -> BlobTree {
    let base = disc(0.4, 8, -0.75, 0.3);
    let body = seg(Vec3::new(0.0, 0.0, -0.7), Vec3::new(0.0, 0.0, 0.3), 0.5);
    let top = disc(0.25, 8, 0.45, 0.5);
    let slot = |half: Vec3| box_node(half, 0.2, Vec3::new(0.0, 0.0, 0.75), f32::INFINITY);
    let cut = Node::union(vec![slot(Vec3::new(0.6, 0.06, 0.15)), slot(Vec3::new(0.06, 0.6, 0.15))]);
    tree(Node::union(vec![Node::blend(vec![base, body]), Node::difference(top, cut, THRESHOLD)]))
}

/// A queen: base and tapered body blended, under a crown carved by eight
/// small spheres around its rim.
pub fn queen() -> BlobTree {
    let base = disc(0.4, 8, -0.75, 0.3);
    let body = Node::warp(Warp::taper(-0.35), seg(Vec3::new(0.0, 0.0, -0.7), Vec3::new(0.0, 0.0, 0.5), 0.46));
    let crown = ball(Vec3::new(0.0, 0.0, 0.75), 0.9);
    let carvings = (0..8)
        .map(|i| {
            let a = std::f32::consts::TAU * (i as f32 + 0.5) / 8.0;
            ball(Vec3::new(0.45 * a.cos(), 0.45 * a.sin(), 0.95), 0.3)
        })
        .collect();
    tree(Node::union(vec![
        Node::blend(vec![base, body]),
        Node::difference(crown, Node::union(carvings), THRESHOLD),
    ]))
}

/// A blob bear: body, head, ears, snout, arms and legs, all blended.
pub fn bear() -> BlobTree {
    let v = Vec3::new;
    tree(Node::blend(vec![
        ball(v(0.0, 0.0, 0.0), 1.1),
        ball(v(0.0, 0.0, 0.62), 0.8),
        ball(v(-0.22, 0.0, 0.9), 0.3),
        ball(v(0.22, 0.0, 0.9), 0.3),
        ball(v(0.0, -0.3, 0.58), 0.3),
        seg(v(-0.35, 0.0, 0.2), v(-0.55, -0.15, -0.1), 0.35),
        seg(v(0.35, 0.0, 0.2), v(0.55, -0.15, -0.1), 0.35),
        seg(v(-0.2, 0.0, -0.35), v(-0.25, -0.05, -0.75), 0.4),
        seg(v(0.2, 0.0, -0.35), v(0.25, -0.05, -0.75), 0.4),
    ]))
}

/// A blob bird: ellipsoidal body, head, beak, triangular wings and tail, legs.
pub fn bird() -> BlobTree {
    let v = Vec3::new;
    let tri = |a: Vec3, b: Vec3, c: Vec3, r: f32| prim(Skeleton::Polygon(vec![a, b, c]), r, Vec3::ZERO);
    tree(Node::blend(vec![
        seg(v(0.0, 0.15, 0.05), v(0.0, -0.15, -0.05), 0.9),
        ball(v(0.0, -0.3, 0.5), 0.6),
        seg(v(0.0, -0.5, 0.5), v(0.0, -0.75, 0.45), 0.18),
        tri(v(-0.2, 0.1, 0.15), v(-0.8, 0.2, 0.3), v(-0.25, -0.2, 0.1), 0.2),
        tri(v(0.2, 0.1, 0.15), v(0.8, 0.2, 0.3), v(0.25, -0.2, 0.1), 0.2),
        tri(v(0.0, 0.4, 0.0), v(-0.15, 0.75, 0.1), v(0.15, 0.75, 0.1), 0.2),
        seg(v(-0.12, 0.0, -0.3), v(-0.12, 0.0, -0.75), 0.15),
        seg(v(0.12, 0.0, -0.3), v(0.12, 0.0, -0.75), 0.15),
    ]))
}

/// A built-in morph by name (one of [`DEMOS`]): source, target and the
/// animator's spec (nearest-centre heuristic; `rook_queen` adds links from
/// each slot to the four carvings along its axis, and speed curves that
/// shape the carvings during the first half).
pub fn demo(name: &str) -> Option<(BlobTree, BlobTree, MorphSpec)> {
    let (a, b) = match name {
        "cube_sphere" => (rounded_cube(), pierced_sphere()),
        "sphere_propeller" => (propeller_sphere(), propeller()),
        "rook_queen" => (rook(), queen()),
        "bear_bird" => (bear(), bird()),
        _ => return None,
    };
    let mut spec = MorphSpec::default();
    if name == "rook_queen" {
        // Animator links: the slot along x splits into the four carvings
        // nearest the x axis, the slot along y into the other four; the
        // carvings take shape ahead of the rest (per-node speed curves, §4.4)
        // so no cutter ever severs the crown's tip.
        for (slot, carvings) in [(0usize, [0usize, 3, 4, 7]), (1, [1, 2, 5, 6])] {
            for c in carvings {
                let (a, b) = (NodePath(vec![1, 1, slot]), NodePath(vec![1, 1, c]));
                spec.links.push(Link { a: a.clone(), b: b.clone() });
                spec.speeds.push(SpeedCurve {
                    a,
                    b,
                    speed: Speed { start: 0.0, end: 0.5, ..Speed::default() },
                    warp: None,
                });
            }
        }
    }
    if name == "cube_sphere" {
        // Fig. 17: the cube is rewritten as the cube minus a phantom of the
        // three boxes, "a sphere that the animator located at the center of
        // the cube": the boxes grow out of that point.
        spec.phantoms.push(Phantom {
            target: Some(NodePath(vec![1])),
            position: Some([0.0; 3]),
            scale: Some(0.0),
            ..Default::default()
        });
    }
    Some((a, b, spec))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BlobMorph;
    use isomorph_common::{Field3, Morph};

    fn components(m: &BlobMorph, t: f32, res: u32) -> usize {
        m.frame_mesh(t, res).unwrap().connected_components()
    }

    #[test]
    fn every_demo_builds_and_reproduces_its_ends() {
        for name in DEMOS {
            let (a, b, spec) = demo(name).unwrap();
            let m = BlobMorph::from_trees(&a, &b, &spec).unwrap();
            let (f0, f1) = (m.frame(0.0).unwrap().field, m.frame(1.0).unwrap().field);
            for i in 0..300 {
                let p = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin())
                    * 1.1;
                assert!((f0.value(p) - a.value(p)).abs() < 1e-5, "{name} C(0) at {p}");
                assert!((f1.value(p) - b.value(p)).abs() < 1e-5, "{name} C(1) at {p}");
            }
            for k in 0..=10 {
                let f = m.frame(k as f32 / 10.0).unwrap().field;
                assert!(f.value(Vec3::new(0.1, 0.2, 0.3)).is_finite(), "{name}");
            }
        }
        assert!(demo("teapot").is_none());
    }

    #[test]
    fn pierced_sphere_has_genus_five() {
        let (a, b, spec) = demo("cube_sphere").unwrap();
        let m = BlobMorph::from_trees(&a, &b, &spec).unwrap();
        let start = m.frame_mesh(0.0, 48).unwrap();
        let end = m.frame_mesh(1.0, 48).unwrap();
        assert_eq!(start.genus(), Some(0));
        // Three crossing tunnels open the ball in six places: genus 6 − 1.
        assert_eq!(end.genus(), Some(5), "three orthogonal crossing holes");
        assert_eq!(end.connected_components(), 1);
        // The same through the tree's own mesher.
        assert_eq!(pierced_sphere().mesh(48).unwrap().genus(), Some(5));
        assert_eq!(rounded_cube().mesh(24).unwrap().genus(), Some(0));
    }

    /// Regression: `isomorph morph --method blobtree --source pierced_sphere
    /// --target pierced_sphere --res 16` came out empty (every coarse block
    /// corner of the sparse mesher lay where the field is flat at `−T`). The
    /// frame meshes must be the full grid's marching cubes mesh, at every
    /// resolution around it.
    #[test]
    fn pierced_sphere_frames_are_whole_at_coarse_resolutions() {
        let a = pierced_sphere();
        let m = BlobMorph::from_trees(&a, &a, &MorphSpec::default()).unwrap();
        for res in [12, 16, 20] {
            for t in [0.0, 1.0] {
                let mesh = m.frame_mesh(t, res).unwrap();
                let field = m.frame(t).unwrap().field;
                let full = isomorph_common::marching_cubes::polygonize(
                    &field,
                    &m.field_bounds().expanded(1e-4),
                    res,
                    0.0,
                )
                .unwrap();
                assert!(!mesh.triangles.is_empty(), "res {res}, t = {t}");
                assert_eq!(mesh.triangles.len(), full.triangles.len(), "res {res}, t = {t}");
                assert_eq!(mesh.triangles, full.triangles, "res {res}, t = {t}");
                assert_eq!(mesh.positions, full.positions, "res {res}, t = {t}");
                // At res 12 the thin shell between the holes falls apart on
                // the full grid too (12 pieces); from 16 on it is whole.
                if res >= 16 {
                    assert_eq!(mesh.connected_components(), 1, "res {res}, t = {t}");
                    assert_eq!(mesh.genus(), Some(5), "res {res}, t = {t}");
                }
            }
        }
    }

    /// Every rook → queen frame is one piece (nothing pops out of thin air).
    #[test]
    fn rook_to_queen_frames_are_single_components() {
        let (a, b, spec) = demo("rook_queen").unwrap();
        let m = BlobMorph::from_trees(&a, &b, &spec).unwrap();
        for k in 0..=40 {
            let t = k as f32 / 40.0;
            assert_eq!(components(&m, t, 40), 1, "frame t = {t}");
        }
    }

    /// The in-betweens the paper shows (Figs. 2, 17, 19): the sphere
    /// splits into the propeller's rods and the bear becomes the bird in one
    /// sphere-like piece at every frame. In Fig. 17 the pierced sphere's
    /// boxes grow out of the phantom sphere at the cube's centre, so the
    /// holes open from the inside: one outer shell throughout, an enclosed
    /// cavity first (a void, never an outer piece), then the three tunnels
    /// break through together, the genus going from 0 straight to 5 and
    /// staying there, with no void left.
    #[test]
    fn in_betweens_keep_one_piece_and_the_genus_changes_once() {
        let frames = |name: &str| {
            let (a, b, spec) = demo(name).unwrap();
            let m = BlobMorph::from_trees(&a, &b, &spec).unwrap();
            (0..=20)
                .map(|k| {
                    let m = m.frame_mesh(k as f32 / 20.0, 48).unwrap().metrics();
                    (m.components - m.voids, m.voids, m.genus)
                })
                .collect::<Vec<_>>()
        };
        for name in ["sphere_propeller", "bear_bird"] {
            let seen = frames(name);
            assert!(seen.iter().all(|&f| f == (1, 0, Some(0))), "{name}: (shells, voids, genus) {seen:?}");
        }
        let seen = frames("cube_sphere");
        assert!(seen.iter().all(|&(shells, _, _)| shells == 1), "cube → sphere: {seen:?}");
        let genus: Vec<Option<i64>> = seen.iter().map(|&(_, _, g)| g).collect();
        let first_open = genus.iter().position(|&g| g == Some(5)).expect("the tunnels open");
        assert!(genus[..first_open].iter().all(|&g| g == Some(0)), "{genus:?}");
        assert!(genus[first_open..].iter().all(|&g| g == Some(5)), "{genus:?}");
        let voids: Vec<usize> = seen.iter().map(|&(_, v, _)| v).collect();
        assert!(voids[..first_open].contains(&1), "the cavity before the tunnels: {voids:?}");
        assert!(voids.iter().all(|&v| v <= 1) && voids[first_open..].iter().all(|&v| v == 0), "{voids:?}");
    }

    /// The first point of the zero set along `from + t·dir`, `t` in
    /// `(0, reach]` (inside at `t = 0`), by bisection.
    fn surface_along(tree: &BlobTree, from: Vec3, dir: Vec3, reach: f32) -> Vec3 {
        assert!(tree.value(from) > 0.0 && tree.value(from + dir * reach) < 0.0, "{from} {dir}");
        let (mut lo, mut hi) = (0.0f32, reach);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if tree.value(from + dir * mid) > 0.0 { lo = mid } else { hi = mid }
        }
        from + dir * (0.5 * (lo + hi))
    }

    /// The built-in `sphere` and `torus` are the analytic reference shapes:
    /// points of their zero sets lie within 5% of the tube radius (0.006)
    /// of the analytic surfaces, sampled all around.
    #[test]
    fn sphere_and_torus_match_the_analytic_shapes() {
        let (sphere, reference) = (super::sphere(), isomorph_common::models::sphere());
        let mut worst = 0.0f32;
        for i in 0..200 {
            // Fibonacci directions.
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 200.0;
            let a = i as f32 * 2.399_963;
            let dir = Vec3::new((1.0 - z * z).sqrt() * a.cos(), (1.0 - z * z).sqrt() * a.sin(), z);
            let p = surface_along(&sphere, Vec3::ZERO, dir, 0.6);
            worst = worst.max(reference.distance(p).abs());
        }
        assert!(worst < 1e-4, "sphere: surface {worst} from radius 0.3");
        let (torus, reference) = (super::torus(), isomorph_common::models::torus());
        let (mut worst, mut sum, mut n) = (0.0f32, 0.0f32, 0);
        for i in 0..96 {
            let phi = std::f32::consts::TAU * (i as f32 + 0.37) / 96.0;
            let radial = Vec3::new(phi.cos(), phi.sin(), 0.0);
            for j in 0..24 {
                let theta = std::f32::consts::TAU * j as f32 / 24.0;
                let dir = radial * theta.cos() + Vec3::Z * theta.sin();
                let p = surface_along(&torus, radial * 0.3, dir, 0.25);
                let d = reference.distance(p).abs();
                worst = worst.max(d);
                sum += (p - radial * 0.3).length();
                n += 1;
            }
        }
        let mean_tube = sum / n as f32;
        assert!(worst < 0.05 * 0.12, "torus: surface up to {worst} from the analytic torus");
        assert!((mean_tube - 0.12).abs() < 0.01 * 0.12, "torus: mean tube radius {mean_tube}");
        println!("torus: worst distance to the analytic torus {worst:.5}, mean tube radius {mean_tube:.5}");
        assert!(torus.value(Vec3::ZERO) < 0.0, "the hole is empty");
    }

    /// The sphere → propeller demo keeps its sphere of radius 0.6.
    #[test]
    fn the_propeller_demo_keeps_its_large_sphere() {
        let (a, _, _) = demo("sphere_propeller").unwrap();
        let p = surface_along(&a, Vec3::ZERO, Vec3::X, 1.2);
        assert!((p.x - 0.6).abs() < 1e-4, "{p}");
    }

    /// The shipped links spec that uses every control of [`MorphSpec`]
    /// (hand-written, for [`bear`] → [`bird`]).
    const EVERY_FEATURE: &str = "bear_bird.every_feature.links.ron";

    /// The shipped links spec with de Casteljau level links (hand-written,
    /// for the Bézier-like rook → queen → bear).
    const LEVELS: &str = "rook_queen_bear.levels.links.ron";

    /// The shipped example scene with a bend about its own axes
    /// (hand-written: the propeller's rods bent), and the links spec of
    /// the propeller → bent rods morph, which gives each of the two
    /// generic warps of a twist ↔ bend pair its own speed (`warp:`).
    const BENT_RODS: &str = "bent_rods.ron";
    const WARP_HALVES: &str = "propeller_bent_rods.links.ron";

    /// The folder of shipped example files (`blobtree/scenes/`).
    fn shipped() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
    }

    /// Checks `text` against the shipped file `name`, or writes it there when
    /// `ISOMORPH_BLESS` is set (to regenerate the folder after a change).
    fn check_shipped(name: &str, text: &str) {
        let path = shipped().join(name);
        if std::env::var_os("ISOMORPH_BLESS").is_some() {
            std::fs::write(&path, text).unwrap();
            return;
        }
        let file = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            file == text,
            "{} differs from the built-in; rerun with ISOMORPH_BLESS=1 to regenerate it",
            path.display()
        );
    }

    /// Every built-in scene and built-in links spec ships as a RON file in
    /// `blobtree/scenes/` that is exactly what `to_ron` writes for it and
    /// loads back into the same tree; the folder holds nothing else but the
    /// hand-written examples.
    #[test]
    fn shipped_files_equal_the_built_ins() {
        let mut expected = [EVERY_FEATURE, LEVELS, BENT_RODS, WARP_HALVES].map(String::from).to_vec();
        for name in NAMES {
            let tree = load(name).unwrap();
            let file = format!("{name}.ron");
            check_shipped(&file, &tree.to_ron().unwrap());
            let again = load(shipped().join(&file).to_str().unwrap()).unwrap();
            assert_eq!(again.root(), tree.root(), "{file}");
            assert_eq!(again.threshold(), tree.threshold(), "{file}");
            expected.push(file);
        }
        for name in DEMOS {
            let (_, _, spec) = demo(name).unwrap();
            if spec == MorphSpec::default() {
                continue;
            }
            let file = format!("{name}.links.ron");
            check_shipped(&file, &spec.to_ron().unwrap());
            assert_eq!(MorphSpec::load(&shipped().join(&file)).unwrap(), spec, "{file}");
            expected.push(file);
        }
        let mut present: Vec<String> = std::fs::read_dir(shipped())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        present.sort();
        expected.sort();
        assert_eq!(present, expected, "blobtree/scenes/ holds exactly the built-ins and the examples");
    }

    /// The shipped example spec sets every field of [`MorphSpec`] and
    /// drives a bear → bird morph that reproduces both ends.
    #[test]
    fn the_every_feature_spec_uses_every_control() {
        let spec = MorphSpec::load(&shipped().join(EVERY_FEATURE)).unwrap();
        // Every field given (a field added to MorphSpec must be added to the file).
        // (`levels` need a Bézier morph: `rook_queen_bear.levels.links.ron` shows them.)
        let MorphSpec { links, heuristic: _, speeds, trajectories, phantoms, coplanar_frames, levels: _ } =
            &spec;
        assert!(
            !links.is_empty()
                && !speeds.is_empty()
                && !trajectories.is_empty()
                && !phantoms.is_empty()
                && *coplanar_frames,
            "{spec:?}"
        );
        assert!(speeds.iter().any(|c| c.speed.smooth) && speeds.iter().any(|c| !c.speed.points.is_empty()));
        // Phantom skeleton scaling (on a segment, where it shows) and a
        // node split by two links.
        assert!(
            phantoms.iter().any(|p| p.scale.is_some_and(|f| f != 1.0) && p.source == Some(NodePath(vec![8])))
        );
        assert!(links.iter().filter(|l| l.a.0 == [7]).count() == 2);
        assert!(trajectories.iter().any(|t| t.handles.is_some()));
        assert!(
            trajectories.iter().any(|t| t.keys.iter().any(|k| k.position.is_some() && k.rotate.is_some()))
        );
        let text = std::fs::read_to_string(shipped().join(EVERY_FEATURE)).unwrap();
        assert!(text.contains("heuristic:"));
        let (a, b) = (bear(), bird());
        let m = BlobMorph::from_trees(&a, &b, &spec).unwrap();
        assert_reproduces_ends(&m, &a, &b);
        for k in 0..=8 {
            assert_eq!(components(&m, k as f32 / 8.0, 40), 1, "t = {}", k as f32 / 8.0);
        }
    }

    /// `C(0)` is `a` and `C(1)` is `b` to 1e-5 at 300 points of the unit box.
    fn assert_reproduces_ends(m: &BlobMorph, a: &BlobTree, b: &BlobTree) {
        for i in 0..300 {
            let p = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
            assert!((m.frame(0.0).unwrap().field.value(p) - a.value(p)).abs() < 1e-5, "C(0) at {p}");
            assert!((m.frame(1.0).unwrap().field.value(p) - b.value(p)).abs() < 1e-5, "C(1) at {p}");
        }
    }

    /// The shipped propeller → bent rods example (the speed curves of the
    /// two halves of a twist ↔ bend pair, `warp: source | target`, Fig. 16;
    /// a bend about its own axes): the morph reproduces both ends; over
    /// the first half only the twist unwinds, over the second only the
    /// bend (about x, in the x–z plane) sets in, the rods straight at
    /// `t = ½`; every frame is one piece and saved frames reload to the
    /// same field. The same spec without `warp:` drives both warps at once.
    #[test]
    fn the_warp_halves_spec_unwinds_then_bends() {
        let spec = MorphSpec::load(&shipped().join(WARP_HALVES)).unwrap();
        assert_eq!(spec.speeds.len(), 2);
        assert!(spec.speeds.iter().all(|c| c.warp.is_some()));
        let (a, b) = (propeller(), load(shipped().join(BENT_RODS).to_str().unwrap()).unwrap());
        let Node::Warp { warp: Warp::Bend { axis, along, .. }, .. } = b.root() else {
            panic!("{:?}", b.root())
        };
        assert_eq!((*axis, *along), (Vec3::X, Vec3::Z));
        let g = crate::GenericTree::new(&a, &b, &spec).unwrap();
        let rates = |t: f32| {
            let n = g.node_at(t);
            let Node::Warp { warp: Warp::Twist { rate: twist, .. }, child } = &n else { panic!("{n:?}") };
            let Node::Warp { warp: Warp::Bend { rate: bend, axis, .. }, .. } = **child else {
                panic!("{child:?}")
            };
            assert_eq!(axis, Vec3::X);
            (*twist, bend)
        };
        let near = |(x, y): (f32, f32), (u, v): (f32, f32)| (x - u).abs() < 1e-5 && (y - v).abs() < 1e-5;
        assert!(near(rates(0.25), (1.1, 0.0)), "{:?}", rates(0.25));
        assert!(near(rates(0.5), (0.0, 0.0)), "{:?}", rates(0.5));
        assert!(near(rates(0.75), (0.0, 0.45)), "{:?}", rates(0.75));
        let both = MorphSpec::from_ron("(speeds: [(a: [], b: [], speed: (end: 0.5))])").unwrap();
        let (twist, bend) = match crate::GenericTree::new(&a, &b, &both).unwrap().node_at(0.25) {
            Node::Warp { warp: Warp::Twist { rate, .. }, child } => match *child {
                Node::Warp { warp: Warp::Bend { rate: bend, .. }, .. } => (rate, bend),
                other => panic!("{other:?}"),
            },
            other => panic!("{other:?}"),
        };
        assert!(near((twist, bend), (1.1, 0.45)), "{twist} {bend}");
        let m = BlobMorph::from_trees(&a, &b, &spec).unwrap();
        assert_reproduces_ends(&m, &a, &b);
        for k in 0..=8 {
            let t = k as f32 / 8.0;
            assert_eq!(components(&m, t, 40), 1, "t = {t}");
            let frame = g.at(t).unwrap();
            let again = BlobTree::from_ron(&frame.to_ron().unwrap()).unwrap();
            for i in 0..300 {
                let p = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
                assert!((again.value(p) - frame.value(p)).abs() <= 1e-6, "t = {t} at {p}");
            }
        }
    }

    /// The shipped level-links spec drives the Bézier-like rook → queen →
    /// bear: its level-2 links are the ones the morph keeps (the carving
    /// balls in ring order, where nearest centres turn the ring), and the
    /// morph reproduces both ends.
    #[test]
    fn the_level_links_spec_is_honoured() {
        let spec = MorphSpec::load(&shipped().join(LEVELS)).unwrap();
        assert!(spec.links.is_empty() && spec.levels.len() == 1);
        let (rook, bear) = (rook(), bear());
        let key = |shape: BlobTree, spec: MorphSpec| crate::KeyShape { shape, spec };
        let queen = key(queen(), demo_spec("rook", "queen").unwrap());
        let m = crate::BlobMorph::bezier(&rook, &[queen.clone(), key(bear.clone(), spec.clone())]).unwrap();
        let automatic =
            crate::BlobMorph::bezier(&rook, &[queen, key(bear.clone(), MorphSpec::default())]).unwrap();
        let carving = |m: &crate::BlobMorph, k: usize| {
            m.level_links(2, 0).iter().any(|l| l.a.0 == [1, 1, k] && l.b.0 == [1, 1, k])
        };
        assert!((0..8).all(|k| carving(&m, k)));
        assert!(!(0..8).all(|k| carving(&automatic, k)), "the example should change the automatic choice");
        for i in 0..300 {
            let p = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
            assert!((m.frame(0.0).unwrap().field.value(p) - rook.value(p)).abs() < 1e-5, "C(0) at {p}");
            assert!((m.frame(1.0).unwrap().field.value(p) - bear.value(p)).abs() < 1e-5, "C(1) at {p}");
        }
    }

    /// An endless stream is refused after MAX_FILE_BYTES instead of filling
    /// the memory.
    #[cfg(unix)]
    #[test]
    fn endless_files_are_refused() {
        match load("/dev/zero") {
            Err(BlobError::Read { path, message }) => {
                assert_eq!(path, "/dev/zero");
                assert_eq!(message, "the file is larger than 64 MiB");
            }
            other => panic!("expected a read error, got {other:?}"),
        }
        let e = MorphSpec::load(std::path::Path::new("/dev/zero")).unwrap_err().to_string();
        assert_eq!(e, "cannot read /dev/zero: the file is larger than 64 MiB");
    }
}
