//! `isomorph morph --method level-set`: the unreached-share option and
//! landmark files.

mod common;

use common::{assert_ok, isomorph, morph, read_json, scratch, stderr};

#[test]
fn max_unreached_is_a_checked_level_set_option() {
    let out = scratch("level_set_unreached");
    let dir = out.to_str().unwrap();
    let base =
        ["morph", "--source", "sphere", "--target", "torus", "--res", "24", "--frames", "2", "--out", dir];
    let run = |extra: &[&str]| isomorph(&[&base[..], extra].concat());
    let o = run(&["--method", "level-set", "--max-unreached", "1.5"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("max_unreached_share") && err.contains("[0, 1]"), "{err}");
    let o = run(&["--method", "rbf", "--max-unreached", "0.1"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("--max-unreached (level-set)"), "{err}");
    // Every part of the torus overlaps the sphere: nothing is left unreached
    // even when nothing may be.
    let o = run(&["--method", "level-set", "--max-unreached", "0"]);
    assert_ok(&o);
    let report: serde_json::Value = read_json(out.join("report.json"));
    let details = &report["morph"]["details"];
    assert_eq!((details["target_parts"].as_u64(), details["unreached_share"].as_f64()), (Some(1), Some(0.0)));
}

/// A landmarks file of `pairs` in `dir`.
fn landmarks_file(dir: &std::path::Path, name: &str, pairs: &[([f32; 3], [f32; 3])]) -> String {
    let records: Vec<serde_json::Value> =
        pairs.iter().map(|(p, q)| serde_json::json!({"source": p, "target": q})).collect();
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string(&records).unwrap()).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn landmark_files_drive_the_level_set_and_bad_ones_are_refused() {
    let out = scratch("level_set_landmarks");
    std::fs::create_dir_all(&out).unwrap();
    // A shift of (0.1, 0.05, 0) at the sphere's six poles.
    let shift = [0.1, 0.05, 0.0];
    let poles: Vec<([f32; 3], [f32; 3])> =
        [[0.3, 0., 0.], [-0.3, 0., 0.], [0., 0.3, 0.], [0., -0.3, 0.], [0., 0., 0.3], [0., 0., -0.3]]
            .iter()
            .map(|p| (*p, [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]))
            .collect();
    let good = landmarks_file(&out, "shift.json", &poles);
    let frames = out.join("frames");
    let run = |file: &str, extra: &[&str]| {
        let base =
            ["morph", "--method", "level-set", "--source", "sphere", "--target", "ball", "--res", "32"];
        let tail = ["--frames", "3", "--no-preview", "--landmarks", file, "--out", frames.to_str().unwrap()];
        isomorph(&[&base[..], extra, &tail[..]].concat())
    };
    // The ball is a smaller sphere elsewhere: through the warp the target
    // is seen where the source is, and the frames end on the ball.
    for warp in ["rbf", "bspline"] {
        let o = run(&good, &["--landmark-warp", warp]);
        assert!(o.status.success(), "{warp}: {}", stderr(&o));
        let report = read_json(frames.join("report.json"));
        assert_eq!(report["morph"]["details"]["warped"], true, "{report}");
        let end = &report["endpoints"]["target"];
        assert!(end["mean_voxels"].as_f64().unwrap() < 1.0, "{warp}: {end}");
    }
    // Bad files: each error says what is wrong.
    let three = landmarks_file(&out, "three.json", &poles[..3]);
    let flat: Vec<_> = poles.iter().map(|&(p, q)| ([p[0], p[1] + 0.5 * p[2], 0.0], q)).collect();
    let flat = landmarks_file(&out, "flat.json", &flat);
    let mut twice = poles.clone();
    twice.push((poles[0].0, [9.0, 9.0, 9.0]));
    let twice = landmarks_file(&out, "twice.json", &twice);
    let nan = out.join("nan.json");
    std::fs::write(&nan, r#"[{"source": [0, 0, 0], "target": [NaN, 0, 0]}]"#).unwrap();
    let missing = out.join("missing.json");
    for (file, expected) in [
        (three.as_str(), "at least 4"),
        (flat.as_str(), "one plane"),
        (twice.as_str(), "different target points"),
        (nan.to_str().unwrap(), "JSON list"),
        (missing.to_str().unwrap(), "cannot read"),
    ] {
        let o = run(file, &[]);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains(expected), "{file}: {err}");
    }
    // Landmarks and an alignment both place the source: refused.
    let o = run(&good, &["--align", "auto"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("--align and landmarks"), "{err}");
    // `align --landmarks` prints the affine part as a map `--align` reads.
    let aligned = out.join("aligned.ply");
    let o = isomorph(&["align", "sphere", "ball", "--landmarks", &good, "--out", aligned.to_str().unwrap()]);
    assert_ok(&o);
    let map: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(map["max_misfit"].as_f64().unwrap() < 1e-5, "{map}");
    assert!((map["matrix"][0][3].as_f64().unwrap() - 0.1).abs() < 1e-5, "{map}");
    let map_file = out.join("map.json");
    std::fs::write(&map_file, o.stdout).unwrap();
    let o = morph(
        "level-set",
        "sphere",
        "ball",
        &[
            "--res",
            "24",
            "--frames",
            "2",
            "--no-preview",
            "--align",
            map_file.to_str().unwrap(),
            "--out",
            frames.to_str().unwrap(),
        ],
    );
    assert_ok(&o);
}

#[test]
fn a_saved_warp_map_drives_the_level_set() {
    let out = scratch("level_set_warp_map");
    let warp_dir = out.join("warp");
    // Drag the sphere's +x pole a little further out: `isomorph warp` writes
    // the edited map as map.json beside the warped shape.
    let o = isomorph(&[
        "warp",
        "sphere",
        "--drag",
        "0.3,0,0:0.1,0,0",
        "--res",
        "32",
        "--out",
        warp_dir.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let (map, warped) = (warp_dir.join("map.json"), warp_dir.join("warped.obj"));
    let frames = out.join("frames");
    let run = |extra: &[&str]| {
        let base =
            ["morph", "--method", "level-set", "--source", "sphere", "--target", warped.to_str().unwrap()];
        let tail = [
            "--res",
            "32",
            "--frames",
            "3",
            "--no-preview",
            "--keep-scale",
            "--out",
            frames.to_str().unwrap(),
        ];
        isomorph(&[&base[..], extra, &tail[..]].concat())
    };
    let o = run(&["--warp-map", map.to_str().unwrap()]);
    assert_ok(&o);
    let report = read_json(frames.join("report.json"));
    assert_eq!(report["morph"]["details"]["warped"], true, "{report}");
    // Through the map the target is the source itself: the evolution has
    // next to nothing to do, and the placed frames end on the warped shape.
    assert!(report["morph"]["iterations"].as_u64().unwrap() < 20, "{report}");
    let end = &report["endpoints"]["target"];
    assert!(end["mean_voxels"].as_f64().unwrap() < 1.0, "{end}");
    let o = run(&["--warp-map", map.to_str().unwrap(), "--align", "auto"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("--warp-map places the source"), "{err}");
    let o = run(&["--warp-map", out.join("missing.json").to_str().unwrap()]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("invalid warp map"), "{err}");
}
