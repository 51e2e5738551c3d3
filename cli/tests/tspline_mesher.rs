//! The T-spline method's output options from the command line: `--mesher
//! marching-cubes|marching-triangulation --mesh-edge L` (the report names
//! the mesher; marching triangulation gives the near-equilateral triangles
//! the README documents), `--refine-target TOL` (the final refinement of
//! the target's approximation, paper §3.2, appended as the last level set),
//! and `--sampler marching-cubes|marching-triangulation --sample-edge C` (the
//! evolution's zero-set samples, §3.3).

mod common;

use common::{assert_ok, morph, read_json, scratch};
use isomorph_common::marching_triangulation::{TriangleQuality, triangle_quality};
use isomorph_io::mesh::read_mesh;
use std::path::Path;

/// Runs `isomorph morph --method tspline --source sphere --target torus`
/// with `extra`, writing frames into `out`; returns `report.json`.
fn run(out: &Path, extra: &[&str]) -> serde_json::Value {
    let base = ["--res", "40", "--frames", "5", "--format", "ply", "--out", out.to_str().unwrap()];
    let o = morph("tspline", "sphere", "torus", &[&base[..], extra].concat());
    assert_ok(&o);
    read_json(out.join("report.json"))
}

/// The triangle quality of the mid frame (a level set: the projection
/// frames are at the ends).
fn mid_frame_quality(out: &Path, report: &serde_json::Value) -> TriangleQuality {
    let frames = report["frames"].as_array().expect("frames in the report");
    let file = frames[frames.len() / 2]["file"].as_str().expect("a frame file");
    triangle_quality(&read_mesh(out.join(file)).unwrap()).expect("triangles")
}

#[test]
fn the_mesher_is_reported_and_marching_triangulation_gives_better_triangles() {
    let dir = scratch("tspline-mesher");
    let cubes = dir.join("cubes");
    let report = run(&cubes, &["--mesher", "marching-cubes"]);
    assert_eq!(report["morph"]["details"]["mesher"], "marching cubes", "{}", report["morph"]);
    let mc = mid_frame_quality(&cubes, &report);

    let tri = dir.join("triangulation");
    let report = run(&tri, &["--mesher", "marching-triangulation", "--mesh-edge", "0.05"]);
    let mesher = report["morph"]["details"]["mesher"].as_str().unwrap_or_default();
    assert_eq!(mesher, "marching triangulation, edge 0.05 domain units", "{}", report["morph"]);
    let mt = mid_frame_quality(&tri, &report);
    // The README's figures: mean smallest angle about 51° against 31–36°
    // for marching cubes, edge spread about 0.11 against 0.35–0.42.
    assert!(mt.mean_min_angle > 45.0 && mt.mean_min_angle > mc.mean_min_angle + 10.0, "{mt:?} vs {mc:?}");
    assert!(mt.edge_spread < 0.2 && mt.edge_spread < 0.5 * mc.edge_spread, "{mt:?} vs {mc:?}");
    assert!(mt.below_20_degrees < 0.01, "{mt:?}");
    // Same shape either way: the mid frames agree in components and genus.
    let mid = |r: &serde_json::Value| {
        let f = &r["frames"][r["frames"].as_array().unwrap().len() / 2];
        (f["components"].clone(), f["genus"].clone())
    };
    assert_eq!(mid(&report), mid(&read_json(cubes.join("report.json"))));

    // A bad edge names its range.
    let o = morph("tspline", "sphere", "torus", &["--mesher", "marching-triangulation", "--mesh-edge", "2"]);
    let err = common::stderr(&o);
    assert!(!o.status.success() && err.contains("(0, 1] domain units"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn refine_target_appends_a_finer_fit_of_the_target() {
    let dir = scratch("tspline-refine-target");
    let plain = dir.join("plain");
    // Coarse (depth 2, n_T large) so that the refinement has cells to split.
    let coarse = ["--depth", "3", "--nt", "400"];
    let report = run(&plain, &coarse);
    let details = &report["morph"]["details"];
    assert!(details["target_refinement_coefficients"].is_null(), "{details}");
    let (level_sets, coefficients) =
        (details["level_sets"].clone(), details["coefficients"].as_u64().unwrap());

    let refined = dir.join("refined");
    let report =
        run(&refined, &[&coarse[..], &["--refine-target", "0.004", "--refine-rounds", "2"]].concat());
    let details = &report["morph"]["details"];
    assert_eq!(details["level_sets"], level_sets, "the evolution is the same: {details}");
    let rounds = details["target_refinement_rounds"].as_u64().unwrap();
    assert!((1..=2).contains(&rounds), "{details}");
    let finer = details["target_refinement_coefficients"].as_u64().unwrap();
    assert!(finer > coefficients, "{finer} coefficients refined vs {coefficients}: {details}");
    // The sequence still ends exactly on the target.
    let e = &report["endpoints"]["target"];
    assert!(e["hausdorff_voxels"].as_f64().unwrap() < 0.1, "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_sampler_option_reaches_the_evolution() {
    let dir = scratch("tspline-sampler");
    let coarse = ["--no-projection-frames"];
    let cubes = run(&dir.join("cubes"), &coarse);
    let details = &cubes["morph"]["details"];
    assert_eq!(details["sampler"], "marching cubes", "the default: {details}");
    let mc_samples = details["first_step_samples"].as_u64().unwrap();

    let args = [&coarse[..], &["--sampler", "marching-triangulation", "--sample-edge", "0.5"]].concat();
    let tri = run(&dir.join("triangulation"), &args);
    let details = &tri["morph"]["details"];
    assert_eq!(details["sampler"], "marching triangulation, edge 0.5 finest cells", "{details}");
    // Uniform points half a finest cell apart are fewer than the marching
    // cubes' vertices at 3 nodes per finest cell.
    let mt_samples = details["first_step_samples"].as_u64().unwrap();
    assert!(mt_samples > 0 && mt_samples < mc_samples, "{mt_samples} vs {mc_samples}");
    assert_eq!(tri["morph"]["outcome"], "converged", "{}", tri["morph"]);

    // A bad spacing names its range; the options belong to the T-spline method.
    let o =
        morph("tspline", "sphere", "torus", &["--sampler", "marching-triangulation", "--sample-edge", "9"]);
    let err = common::stderr(&o);
    assert!(!o.status.success() && err.contains("0.05..=4"), "{err}");
    let o = morph("level-set", "sphere", "torus", &["--sampler", "marching-triangulation"]);
    let err = common::stderr(&o);
    assert!(!o.status.success() && err.contains("--sampler (tspline)"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
