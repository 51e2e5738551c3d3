//! Colour through the morph (Breen & Whitaker Fig. 13): frames carry the
//! inputs' vertex colours, looked up at the closest surface point of each
//! input as the method places it and blended by t; uncoloured exports stay
//! as they were.

use glam::{Affine3A, DVec3, Vec3};
use isomorph_common::mesh::color::ColorLookup;
use isomorph_common::mesh::primitives::{torus, uv_sphere};
use isomorph_common::{BlendSettings, Control, DistanceBlend, Morph, Solid, TriMesh};
use isomorph_io::export::{ExportSettings, FrameColors, export_sequence};
use isomorph_io::mesh::read_mesh;
use isomorph_levelset::{Align, LevelSetMorph, LevelSetSettings};
use std::path::PathBuf;

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("isomorph-colours-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `mesh` with each vertex coloured by `paint` of its position.
fn painted(mesh: TriMesh, paint: impl Fn(Vec3) -> Vec3) -> TriMesh {
    let colors = mesh.positions.iter().map(|&p| paint(p)).collect();
    mesh.with_colors(colors).unwrap()
}

/// The closest point of triangle `abc` to `p` as barycentric weights
/// (Ericson, *Real-Time Collision Detection* §5.1.5), in f64, with its
/// squared distance: an independent brute-force reference.
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (f64, DVec3) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    let weights = if d1 <= 0.0 && d2 <= 0.0 {
        DVec3::X
    } else {
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        let (vc, vb, va) = (d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4);
        if d3 >= 0.0 && d4 <= d3 {
            DVec3::Y
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            let v = d1 / (d1 - d3);
            DVec3::new(1.0 - v, v, 0.0)
        } else if d6 >= 0.0 && d5 <= d6 {
            DVec3::Z
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            let w = d2 / (d2 - d6);
            DVec3::new(1.0 - w, 0.0, w)
        } else if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            DVec3::new(0.0, 1.0 - w, w)
        } else {
            let denom = 1.0 / (va + vb + vc);
            let (v, w) = (vb * denom, vc * denom);
            DVec3::new(1.0 - v - w, v, w)
        }
    };
    let q = weights.x * a + weights.y * b + weights.z * c;
    ((p - q).length_squared(), weights)
}

/// The colour of `mesh` at its point closest to `p`, by trying every
/// triangle.
fn brute_force_color(mesh: &TriMesh, p: Vec3) -> Vec3 {
    let colors = mesh.colors.as_ref().unwrap();
    let mut best = (f64::INFINITY, Vec3::ZERO);
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize].as_dvec3());
        let (d2, w) = closest_on_triangle(p.as_dvec3(), a, b, c);
        if d2 < best.0 {
            let [ca, cb, cc] = tri.map(|i| colors[i as usize].as_dvec3());
            best = (d2, (w.x * ca + w.y * cb + w.z * cc).as_vec3());
        }
    }
    best.1
}

fn lookup(mesh: &TriMesh) -> ColorLookup {
    ColorLookup::new(mesh, Vec3::ZERO).unwrap()
}

/// Largest component difference between the colours of a written frame
/// and `expected` per vertex.
fn worst(frame: &TriMesh, expected: impl Fn(Vec3) -> Vec3) -> f32 {
    let colors = frame.colors.as_ref().expect("the frame file has colours");
    frame
        .positions
        .iter()
        .zip(colors)
        .map(|(&p, c)| (*c - expected(p)).abs().max_element())
        .fold(0.0, f32::max)
}

#[test]
fn end_frames_reproduce_the_inputs_colours_and_uncoloured_exports_stay_uncoloured() {
    let source = painted(uv_sphere(Vec3::new(-0.05, 0.0, 0.0), 0.3, 16, 32), |p| {
        (p * 1.5 + Vec3::splat(0.5)).clamp(Vec3::ZERO, Vec3::ONE)
    });
    let target = painted(torus(0.28, 0.12, 32, 16), |p| Vec3::new(p.z.abs() * 3.0, 0.9, 1.0 - p.x.abs()));
    let control = Control::new();
    let (a, b) = (Solid::mesh(source.clone()).unwrap(), Solid::mesh(target.clone()).unwrap());
    let morph =
        DistanceBlend::new(&a, &b, &BlendSettings { resolution: 28, padding: 0.1 }, &control).unwrap();
    let colors = FrameColors { source: lookup(&source), target: lookup(&target) };
    let dir = out_dir("ends");
    let settings = ExportSettings {
        frames: 3,
        out_dir: dir.clone(),
        colors: Some(colors),
        preview: false,
        ..ExportSettings::default()
    };
    let exported = export_sequence(&morph, &settings, &control).unwrap();
    let first = read_mesh(dir.join("frame_000.ply")).unwrap();
    let last = read_mesh(dir.join("frame_002.ply")).unwrap();
    assert_eq!(first.positions, exported.meshes[0].positions);
    // Written as bytes: within half a level, plus rounding.
    let level = 1.0 / 255.0;
    let at_source = worst(&first, |p| brute_force_color(&source, p));
    assert!(at_source <= level, "t = 0: off the source's colours by {at_source}");
    let at_target = worst(&last, |p| brute_force_color(&target, p));
    assert!(at_target <= level, "t = 1: off the target's colours by {at_target}");
    // The middle frame is neither.
    let middle = read_mesh(dir.join("frame_001.ply")).unwrap();
    assert!(worst(&middle, |p| brute_force_color(&source, p)) > 0.1);
    assert!(worst(&middle, |p| brute_force_color(&target, p)) > 0.1);

    // Without colours: no colour in any output, and the same frames.
    let plain_dir = out_dir("plain");
    let plain = ExportSettings { out_dir: plain_dir.clone(), colors: None, ..settings };
    let exported_plain = export_sequence(&morph, &plain, &control).unwrap();
    for (coloured, uncoloured) in exported.meshes.iter().zip(&exported_plain.meshes) {
        assert_eq!(coloured.positions, uncoloured.positions);
        assert_eq!(uncoloured.colors, None);
    }
    let header = std::fs::read(plain_dir.join("frame_000.ply")).unwrap();
    assert!(!header.windows(3).any(|w| w == b"red"), "an uncoloured frame file names a colour");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&plain_dir).unwrap();
}

#[test]
fn level_set_frames_take_colours_from_where_the_method_placed_them() {
    // A small sphere grows into a larger one 0.6 away, placed by the
    // translation (Breen eq. 25): every frame is a sphere about the
    // source's centre in field space, moved part of the way. Both are
    // coloured by direction from their centre, in different palettes.
    let offset = Vec3::new(0.6, 0.0, 0.0);
    let source = painted(uv_sphere(Vec3::ZERO, 0.12, 48, 96), |p| p / 0.24 + Vec3::splat(0.5));
    let source_paint = |d: Vec3| d * 0.5 + Vec3::splat(0.5);
    let target_paint = |d: Vec3| Vec3::new(0.5 - 0.5 * d.y, 0.5 + 0.5 * d.z, 0.5 - 0.5 * d.x);
    let target = painted(uv_sphere(offset, 0.25, 48, 96), |p| target_paint((p - offset) / 0.25));
    let control = Control::new();
    let (a, b) = (Solid::mesh(source.clone()).unwrap(), Solid::mesh(target.clone()).unwrap());
    let settings = LevelSetSettings {
        resolution: 40,
        align: Align::Map(Affine3A::from_translation(offset)),
        ..LevelSetSettings::default()
    };
    let morph = LevelSetMorph::new(&a, &b, &settings, &control).unwrap();
    let dir = out_dir("level-set");
    let export = ExportSettings {
        frames: 5,
        out_dir: dir.clone(),
        colors: Some(FrameColors { source: lookup(&source), target: lookup(&target) }),
        contact_sheet: false,
        preview: false,
        ..ExportSettings::default()
    };
    let exported = export_sequence(&morph, &export, &control).unwrap();
    let mut between = 0;
    for (i, frame) in exported.meshes.iter().enumerate() {
        let t = i as f32 / 4.0;
        let centre = morph.world_transform(t).unwrap().transform_point3(Vec3::ZERO);
        let direction = |p: Vec3| (p - centre).normalize();
        let placed = worst(frame, |p| source_paint(direction(p)).lerp(target_paint(direction(p)), t));
        assert!(placed < 0.03, "t = {t}: {placed} off the colours where the frame came from");
        if centre.distance(Vec3::ZERO) > 0.1 && centre.distance(offset) > 0.1 {
            // Looked up where the frame lies instead, the source's colours
            // would come from the wrong side.
            let unplaced =
                worst(frame, |p| source_paint(p.normalize()).lerp(target_paint((p - offset).normalize()), t));
            assert!(unplaced > 0.2, "t = {t}: the placement makes no difference ({unplaced})");
            between += 1;
        }
    }
    assert!(between > 0, "no frame is placed between the inputs");
    std::fs::remove_dir_all(&dir).unwrap();
}
