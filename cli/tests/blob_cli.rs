//! The BlobTree method's Bézier-like morph from the command line: a links
//! spec given with `--via` is the last pair's, and its `levels` link the
//! de Casteljau levels above the first (honoured, or refused by name).

mod common;

use common::{assert_ok, morph, scratch, stderr};
use std::path::Path;

#[test]
fn via_takes_a_links_spec_with_level_links() {
    let out = scratch("blob_levels");
    std::fs::create_dir_all(&out).unwrap();
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../blobtree/scenes");
    let spec = shipped.join("rook_queen_bear.levels.links.ron");
    let frames = out.join("frames");
    let args = [
        "--via",
        "queen",
        "--links",
        spec.to_str().unwrap(),
        "--res",
        "24",
        "--frames",
        "3",
        "--no-preview",
        "--report",
        "--out",
        frames.to_str().unwrap(),
    ];
    let o = morph("blobtree", "rook", "bear", &args);
    assert_ok(&o);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["morph"]["details"]["via mode"], "bezier", "{report}");
    for end in ["source", "target"] {
        let e = &report["endpoints"][end];
        assert!(e["mean_voxels"].as_f64().unwrap() < 0.5, "{end}: {e}");
    }
    // A level link naming a node the level-1 shapes lack is one error naming the level.
    let bad = out.join("bad.links.ron");
    std::fs::write(&bad, "(levels: [(level: 2, pair: 0, links: [(a: [99], b: [0])])])").unwrap();
    let args = [
        "--via",
        "queen",
        "--links",
        bad.to_str().unwrap(),
        "--res",
        "16",
        "--out",
        frames.to_str().unwrap(),
    ];
    let o = morph("blobtree", "rook", "bear", &args);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("de Casteljau level 2, pair 0") && err.contains("does not exist"), "{err}");
    // Level links without control shapes are refused.
    let args = ["--links", bad.to_str().unwrap(), "--res", "16", "--out", frames.to_str().unwrap()];
    let o = morph("blobtree", "rook", "bear", &args);
    assert!(!o.status.success() && stderr(&o).contains("levels"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&out);
}
