//! The T-spline method from the command line: `--align auto|none|MAP.json`
//! (paper §4.2, frames placed by eq. 11), its knobs (minimum depth, sample
//! spacing, step cap, distance-field weight, the robust speed's β,
//! projection frames), their range
//! errors, and the paper speed's stall printed as a warning.

mod common;

use common::{assert_ok, isomorph, morph, read_json, scratch, stderr};
use isomorph_common::glam::{Affine3A, Quat, Vec3};
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, Shape};
use isomorph_io::mesh::{MeshFormat, write_mesh};
use std::path::Path;

/// A bar with a ball off its axes (its moment frame is unique).
fn bar() -> Shape {
    Shape::cuboid(Vec3::new(0.3, 0.12, 0.08)).union(Shape::sphere(0.11).translated(Vec3::new(0.2, 0.06, 0.0)))
}

/// The source: the bar turned 90° about z, scaled by 1.5 and moved.
fn motion() -> Affine3A {
    Affine3A::from_scale_rotation_translation(
        Vec3::splat(1.5),
        Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
        Vec3::new(0.1, -0.05, 0.0),
    )
}

/// Writes the source and target bars as PLY files into `dir`.
fn write_pair(dir: &Path) -> (String, String) {
    std::fs::create_dir_all(dir).unwrap();
    let bounds = Aabb::cube(0.8);
    let source = polygonize(&bar().transformed(motion()), &bounds, 48, 0.0).unwrap();
    let target = polygonize(&bar(), &bounds, 48, 0.0).unwrap();
    let (a, b) = (dir.join("source.ply"), dir.join("target.ply"));
    write_mesh(&source, &a, MeshFormat::PlyBinaryLittleEndian).unwrap();
    write_mesh(&target, &b, MeshFormat::PlyBinaryLittleEndian).unwrap();
    (a.to_string_lossy().into_owned(), b.to_string_lossy().into_owned())
}

/// Runs `isomorph morph --method tspline` with `args`, expecting success,
/// and returns the JSON report it prints.
fn morph_report(args: &[&str]) -> serde_json::Value {
    let base = ["morph", "--method", "tspline", "--res", "32", "--frames", "3", "--report", "--keep-scale"];
    let o = isomorph(&[&base[..], args].concat());
    assert_ok(&o);
    serde_json::from_slice(&o.stdout).expect("stdout is the JSON report")
}

fn numbers(text: &serde_json::Value) -> Vec<f64> {
    text.as_str().unwrap().split_whitespace().map(|x| x.parse().unwrap()).collect()
}

#[test]
fn align_auto_and_a_map_file_place_the_tspline_frames() {
    let dir = scratch("tspline-align");
    let (source, target) = write_pair(&dir);
    let out = dir.join("auto");
    let common = ["--source", source.as_str(), "--target", target.as_str(), "--depth", "3"];
    let report = morph_report(&[&common[..], &["--align", "auto", "--out", out.to_str().unwrap()]].concat());
    let m = &report["morph"];
    assert_eq!(m["converged"], true, "{m}");
    let details = &m["details"];
    assert_eq!(details["alignment"], "moments (affine)", "{details}");
    // The moments find the inverse motion: a 90° turn about z, scale 1/1.5.
    let degrees = details["alignment_rotation_degrees"].as_f64().unwrap();
    assert!((degrees - 90.0).abs() < 1.0, "{details}");
    let axis = numbers(&details["alignment_rotation_axis"]);
    assert!(axis[2].abs() > 0.999, "{details}");
    for s in numbers(&details["alignment_scale"]) {
        assert!((s - 1.0 / 1.5).abs() < 0.02, "{details}");
    }
    // The endpoints are the inputs in world space.
    for end in ["source", "target"] {
        let e = &report["endpoints"][end];
        assert!(e["hausdorff_voxels"].as_f64().unwrap() < 0.1, "{end}: {e}");
    }

    // The same map from a file (as `isomorph align` writes it).
    let map = dir.join("map.json");
    let rows = motion().inverse().to_cols_array_2d();
    let m4 = [
        [rows[0][0], rows[1][0], rows[2][0], rows[3][0]],
        [rows[0][1], rows[1][1], rows[2][1], rows[3][1]],
        [rows[0][2], rows[1][2], rows[2][2], rows[3][2]],
        [0.0, 0.0, 0.0, 1.0],
    ];
    std::fs::write(&map, serde_json::json!({ "matrix": m4 }).to_string()).unwrap();
    let out = dir.join("map");
    let args = ["--align", map.to_str().unwrap(), "--out", out.to_str().unwrap()];
    let report = morph_report(&[&common[..], &args[..]].concat());
    let details = &report["morph"]["details"];
    assert_eq!(details["alignment"], "map", "{details}");
    assert!((details["alignment_rotation_degrees"].as_f64().unwrap() - 90.0).abs() < 1e-3, "{details}");
    assert_eq!(report["morph"]["converged"], true);

    // Without alignment the bars barely overlap: no alignment detail.
    let out = dir.join("none");
    let args = ["--align", "none", "--max-steps", "2", "--out", out.to_str().unwrap()];
    let report = morph_report(&[&common[..], &args[..]].concat());
    assert!(report["morph"]["details"]["alignment"].is_null());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tspline_knobs_reach_the_settings_and_bad_values_name_their_range() {
    let dir = scratch("tspline-knobs");
    let pair = ["--source", "sphere", "--target", "torus"];
    // Coarse and capped: three steps, no projection frames.
    let knobs = [
        "--depth",
        "3",
        "--min-depth",
        "3",
        "--sample-spacing",
        "0.08",
        "--max-steps",
        "3",
        "--distance-weight",
        "0.01",
        "--stall-steps",
        "20",
        "--far-field-weight",
        "10",
        "--beta-cells",
        "0.25",
        "--hold-fraction",
        "0.5",
        "--no-projection-frames",
    ];
    let out = dir.join("knobs");
    let report = morph_report(&[&pair[..], &knobs[..], &["--out", out.to_str().unwrap()]].concat());
    let m = &report["morph"];
    assert_eq!(m["iterations"], 3, "{m}");
    assert_eq!(m["outcome"], "iteration_cap", "{m}");
    // Without projection frames every frame is a level set: the fit and 3 steps.
    assert_eq!(m["details"]["frames"], 4, "{m}");
    assert_eq!(m["details"]["level_sets"], 4, "{m}");
    // A uniform depth-3 T-mesh: 9³ coefficients.
    assert_eq!(m["details"]["coefficients"], 729, "{m}");
    assert_eq!(m["details"]["speed"], "robust (v_max 0.2, beta 0.25 finest cells)", "{m}");
    assert_eq!(m["details"]["hold_fraction"], 0.5, "{m}");
    assert!(m["details"]["held_cells"].is_u64(), "{m}");
    let warnings = format!("{}", m["warnings"]);
    assert!(warnings.contains("step cap (3)"), "{warnings}");

    // `--depth 1` runs (the minimum depth follows it down).
    let out = dir.join("depth1");
    let report = morph_report(
        &[&pair[..], &["--depth", "1", "--max-steps", "2", "--out", out.to_str().unwrap()]].concat(),
    );
    assert_eq!(report["morph"]["details"]["coefficients"], 27, "{}", report["morph"]);

    // Out-of-range values are one error line naming the option or field and the range.
    let run = |extra: &[&str]| {
        let o = isomorph(
            &[&["morph", "--method", "tspline"][..], &pair[..], extra, &["--out", out.to_str().unwrap()]]
                .concat(),
        );
        assert!(!o.status.success(), "{extra:?} was accepted");
        stderr(&o)
    };
    let err = run(&["--depth", "9"]);
    assert!(err.contains("--depth") && err.contains("1..=7"), "{err}");
    let err = run(&["--depth", "3", "--min-depth", "4"]);
    assert!(err.contains("min_depth = 4") && err.contains("0..=max_depth"), "{err}");
    let err = run(&["--sample-spacing", "0"]);
    assert!(err.contains("sample_spacing = 0") && err.contains("1e-4..=2"), "{err}");
    let err = run(&["--distance-weight=-1"]);
    assert!(err.contains("distance_weight = -1"), "{err}");
    let err = run(&["--far-field-weight=-1"]);
    assert!(err.contains("far_field_weight = -1"), "{err}");
    let err = run(&["--hold-fraction", "2"]);
    assert!(err.contains("hold_fraction = 2") && err.contains("0..=1"), "{err}");
    let err = run(&["--stall-steps", "0"]);
    assert!(err.contains("stall_steps = 0") && err.contains(">= 1"), "{err}");
    let err = run(&["--beta-cells", "11"]);
    assert!(err.contains("--beta-cells") && err.contains("[0, 10]"), "{err}");
    let err = run(&["--speed", "paper", "--beta-cells", "0.5"]);
    assert!(err.contains("--beta-cells") && err.contains("--speed robust"), "{err}");
    // The help states the range and the library's default.
    let help = String::from_utf8(isomorph(&["morph", "--help"]).stdout).unwrap();
    let help = help.split_whitespace().collect::<Vec<_>>().join(" ");
    let default = format!("[default: the library's, {}]", isomorph_tspline::Speed::ROBUST_BETA_CELLS);
    assert!(help.contains("(0 to 10;") && help.contains(&default), "{help}");
    // The knobs belong to the T-spline method.
    let o = morph("level-set", "sphere", "torus", &["--max-steps", "3"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("--max-steps (tspline)"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_paper_speed_stall_is_printed_and_reported() {
    let dir = scratch("tspline-paper");
    let out = dir.join("paper");
    // Sphere → torus converges with the paper's speed (the shapes overlap
    // closely); growing the sphere into the chain's links stalls.
    let args =
        ["morph", "--method", "tspline", "--speed", "paper", "--source", "sphere", "--target", "chain"];
    let more = ["--res", "32", "--frames", "3", "--depth", "3", "--out", out.to_str().unwrap()];
    let o = isomorph(&[&args[..], &more[..]].concat());
    assert_ok(&o);
    let err = stderr(&o);
    assert!(err.contains("stalled") && err.contains("robust speed"), "{err}");
    let report: serde_json::Value = read_json(out.join("report.json"));
    assert_eq!(report["morph"]["outcome"], "stalled", "{}", report["morph"]);
    assert!(format!("{}", report["morph"]["warnings"]).contains("stalled"));
    let _ = std::fs::remove_dir_all(&dir);
}
