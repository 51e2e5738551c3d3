//! End-to-end tests of the `isomorph` binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn isomorph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_isomorph")).args(args).output().expect("the binary runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("isomorph-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn bunny() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/bunny.ply").to_string_lossy().into_owned()
}

#[test]
fn demo_writes_frames_sheet_and_report() {
    let out = scratch("demo");
    let o = isomorph(&["demo", "--res", "32", "--frames", "4", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "demo failed: {}", String::from_utf8_lossy(&o.stderr));
    let dir = out.join("baseline_ball_to_c");
    for f in ["frame_000.ply", "frame_003.ply", "contact_sheet.png", "report.json"] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["method"], "baseline");
    assert_eq!(report["resolution"], 32);
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4);
    for key in ["t", "vertices", "triangles", "components", "genus", "area", "volume", "seconds"] {
        assert!(frames[0].get(key).is_some(), "frame key {key} missing");
    }
    for end in ["source", "target"] {
        let e = &report["endpoints"][end];
        for key in ["mean", "hausdorff", "mean_voxels", "hausdorff_voxels"] {
            assert!(e[key].as_f64().is_some(), "endpoint {end}.{key} missing");
        }
        // The baseline reproduces its inputs at t = 0 and 1 up to sampling.
        assert!(e["mean_voxels"].as_f64().unwrap() < 0.5, "{end}: {e}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn info_prints_bunny_metrics_as_json() {
    let o = isomorph(&["info", &bunny(), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["vertices"], 1839);
    assert_eq!(v["triangles"], 3674);
    assert_eq!(v["components"], 1);
    assert_eq!(v["euler"], 2);
    assert_eq!(v["genus"], 0);
    assert_eq!(v["boundary_edges"], 0);
    assert_eq!(v["nonmanifold_edges"], 0);
    assert!((v["area"].as_f64().unwrap() - 218.68927).abs() < 1e-3);
    assert!((v["volume"].as_f64().unwrap() - 194.28837).abs() < 1e-3);
}

#[test]
fn morph_of_a_mesh_into_a_builtin_shape() {
    let out = scratch("morph");
    let o = isomorph(&[
        "morph",
        "--method",
        "baseline",
        "--source",
        &bunny(),
        "--target",
        "sphere",
        "--res",
        "24",
        "--frames",
        "3",
        "--format",
        "obj",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("frame_002.obj").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bad_input_is_one_clear_line_and_nonzero_exit() {
    let o = isomorph(&["morph", "--source", "no-such-shape", "--target", "sphere"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.starts_with("error: "), "{err}");
    assert!(err.contains("no-such-shape") && err.contains("sphere"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");

    let garbage = scratch("garbage.ply");
    std::fs::write(&garbage, b"ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n1 2").unwrap();
    let o = isomorph(&["info", garbage.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: "));
    let _ = std::fs::remove_file(&garbage);

    let o = isomorph(&["morph", "--source", "sphere", "--target", "torus", "--res", "2"]);
    assert!(!o.status.success(), "resolution below the minimum is rejected");
}
