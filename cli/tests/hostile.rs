//! Hostile and unusable input through the command line: a clear error and a
//! nonzero exit, never an abort or wrong files with exit status 0.

mod common;

use common::{isomorph, morph, stderr};
use std::path::PathBuf;

/// An empty scratch folder.
fn scratch(name: &str) -> PathBuf {
    let dir = common::scratch(&format!("hostile-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A unit cube as OBJ text, faces reversed when `inside_out`.
fn cube_obj(inside_out: bool) -> String {
    let mut s = String::new();
    for i in 0..8 {
        let p = [i & 1, (i >> 1) & 1, (i >> 2) & 1].map(|b| b as f32 - 0.5);
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    for q in quads {
        let q = if inside_out { [q[3], q[2], q[1], q[0]] } else { q };
        s += &format!("f {} {} {} {}\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
    }
    s
}

#[test]
fn unusable_meshes_are_refused_by_every_method() {
    let dir = scratch("unusable");
    let triangle = dir.join("triangle.obj");
    std::fs::write(&triangle, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let flipped = dir.join("flipped.obj");
    std::fs::write(&flipped, cube_obj(true)).unwrap();
    let polygon = dir.join("polygon.obj");
    let mut text: String = (0..200)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 200.0;
            format!("v {} {} 0\n", a.cos(), a.sin())
        })
        .collect();
    text += &format!("f {}\n", (1..=200).map(|i| i.to_string()).collect::<Vec<_>>().join(" "));
    std::fs::write(&polygon, text).unwrap();
    for method in ["baseline", "level-set", "rbf", "warp", "tspline"] {
        for (input, expected) in [(&triangle, "empty"), (&flipped, "inside out"), (&polygon, "empty")] {
            let out = dir.join(format!("{method}-out"));
            let o = morph(
                method,
                input.to_str().unwrap(),
                "sphere",
                &["--res", "24", "--frames", "3", "--out", out.to_str().unwrap()],
            );
            let err = stderr(&o);
            assert!(!o.status.success(), "{method} accepted {}: {err}", input.display());
            assert!(err.contains(expected) && err.contains("source"), "{method}, {}: {err}", input.display());
            assert!(!out.join("frame_000.ply").exists(), "{method} wrote frames");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs an RBF sphere → torus morph with `points` per shape under
/// `--max-memory 64M` and checks that it fails with the one-line memory
/// message and writes no frame; returns that message.
fn rbf_over_64m(points: &str) -> String {
    let dir = scratch(&format!("memory-{points}"));
    let o = isomorph(&[
        "--max-memory",
        "64M",
        "morph",
        "--method",
        "rbf",
        "--points",
        points,
        "--source",
        "sphere",
        "--target",
        "torus",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("over the memory limit of 64.0 MiB") && err.contains("--max-memory"), "{err}");
    assert!(err.contains("fewer constraints"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!dir.join("frame_000.ply").exists(), "frames written");
    let _ = std::fs::remove_dir_all(&dir);
    err
}

#[test]
fn a_dense_system_over_the_memory_limit_is_an_error_naming_the_option() {
    // 900 points per shape give 3600 constraints: below `HIERARCHICAL_MIN`,
    // so the dense solver (12 n² bytes, 198 MiB) is the one chosen.
    rbf_over_64m("900");
    let o = isomorph(&["--max-memory", "lots", "info", "x.obj"]);
    assert!(!o.status.success() && stderr(&o).contains("512M"), "{}", stderr(&o));
}

#[test]
fn the_hierarchical_solver_over_the_memory_limit_is_an_error_before_it_fits() {
    // 2500 points per shape give 10000 constraints: the hierarchical
    // solver, whose H-matrix, preconditioner and GMRES basis need some
    // 100 MiB; it checks them against the limit before allocating them.
    let err = rbf_over_64m("2500");
    assert!(err.contains("the hierarchical solver of") && err.contains("constraints needs"), "{err}");
}

#[test]
fn user_numbers_that_would_wrap_or_mislead_are_refused() {
    let dir = scratch("numbers");
    let out = dir.join("warp");
    let o = isomorph(&["warp", "sphere", "--pad", "4294967295", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("--pad"), "{}", stderr(&o));
    assert!(!out.join("warped.npy").exists());
    let o = isomorph(&[
        "warp",
        "sphere",
        "--drag",
        "0.3,0,0:0.1,0,0",
        "--radius=-19.2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success() && stderr(&o).contains("positive radius"), "{}", stderr(&o));
    let o = morph("tspline", "sphere", "torus", &["--step", "1e-300", "--out", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("1e-300") && err.len() < 300, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn lenient_reads_are_reported() {
    let dir = scratch("lenient");
    let obj = dir.join("normals.obj");
    let mut text = cube_obj(false);
    text = text.replace("f 1 3 4 2", "f 1//1 3//1 4//1 2//1");
    std::fs::write(&obj, text).unwrap();
    let o = isomorph(&["info", obj.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).starts_with("warning: ") && stderr(&o).contains("normal"), "{}", stderr(&o));
    // A volume without its sidecar is placed in voxel units, and says so.
    let npy = dir.join("sphere.npy");
    let o = isomorph(&["sdf", "sphere", "--res", "16", "--out", npy.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_file(dir.join("sphere.json")).unwrap();
    let frames = dir.join("frames");
    let o = morph(
        "baseline",
        npy.to_str().unwrap(),
        "sphere",
        &["--res", "16", "--frames", "2", "--no-preview", "--out", frames.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("no sidecar") && stderr(&o).contains("voxel units"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}
