//! Colour through the morph, end to end: coloured input files colour the
//! frames, `--colour` colours built-in shapes, and neither leaves the
//! output as it was.

mod common;

use common::{assert_ok, morph, scratch, stderr};
use isomorph_common::glam::Vec3;
use isomorph_common::mesh::primitives::uv_sphere;
use isomorph_io::inputs::builtin_color;
use isomorph_io::mesh::read_mesh;
use std::path::Path;

fn baseline(source: &str, target: &str, out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["--res", "24", "--frames", "3", "--no-preview", "--out", out.to_str().unwrap()];
    args.extend(extra);
    let o = morph("baseline", source, target, &args);
    assert_ok(&o);
    stderr(&o)
}

#[test]
fn colour_flag_paints_builtins_and_its_absence_writes_no_colour() {
    let out = scratch("colour-builtins");
    baseline("sphere", "torus", &out, &["--colour"]);
    for (file, name) in [("frame_000.ply", "sphere"), ("frame_002.ply", "torus")] {
        let frame = read_mesh(out.join(file)).unwrap();
        let expected = builtin_color(name).unwrap();
        let colors = frame.colors.expect("coloured frame");
        let off = colors.iter().map(|c| (*c - expected).abs().max_element()).fold(0.0, f32::max);
        assert!(off <= 0.5 / 255.0 + 1e-6, "{file}: {off} off the {name}'s colour");
    }
    let plain = scratch("colour-none");
    baseline("sphere", "torus", &plain, &[]);
    assert_eq!(read_mesh(plain.join("frame_001.ply")).unwrap().colors, None);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&plain);
}

#[test]
fn coloured_files_colour_the_frames_and_partial_obj_colours_are_reported() {
    let dir = scratch("colour-files");
    std::fs::create_dir_all(&dir).unwrap();
    // A sphere red on top, blue below, as OBJ `v x y z r g b`.
    let sphere = uv_sphere(Vec3::ZERO, 0.4, 12, 24);
    let mut obj = String::new();
    for p in &sphere.positions {
        let (r, b) = if p.z > 0.0 { (1, 0) } else { (0, 1) };
        obj += &format!("v {} {} {} {r} 0 {b}\n", p.x, p.y, p.z);
    }
    for t in &sphere.triangles {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    let path = dir.join("painted.obj");
    std::fs::write(&path, &obj).unwrap();
    let out = dir.join("out");
    baseline(path.to_str().unwrap(), "cube", &out, &[]);
    let first = read_mesh(out.join("frame_000.ply")).unwrap();
    let colors = first.colors.expect("frames of a coloured input are coloured");
    // Fitted, the sphere keeps its centre at the origin: red above, blue below.
    for (p, c) in first.positions.iter().zip(&colors) {
        if p.z.abs() > 0.15 {
            let expected = if p.z > 0.0 { Vec3::X } else { Vec3::Z };
            assert!((*c - expected).abs().max_element() < 0.01, "{p}: {c}");
        }
    }
    // The uncoloured target (a built-in) shows its own colour at t = 1.
    let last = read_mesh(out.join("frame_002.ply")).unwrap();
    let cube = builtin_color("cube").unwrap();
    assert!(last.colors.unwrap().iter().all(|c| (*c - cube).abs().max_element() < 0.01));

    // One vertex without a colour: read without colours, with a warning.
    let partial = obj.replacen(" 1 0 0\n", "\n", 1);
    let partial_path = dir.join("partial.obj");
    std::fs::write(&partial_path, partial).unwrap();
    let out = dir.join("partial_out");
    let stderr = baseline(partial_path.to_str().unwrap(), "cube", &out, &[]);
    assert!(stderr.contains("have no colour") && stderr.contains("dropped"), "{stderr}");
    assert_eq!(read_mesh(out.join("frame_000.ply")).unwrap().colors, None);
    let _ = std::fs::remove_dir_all(&dir);
}
