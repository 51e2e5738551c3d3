//! `isomorph morph --method level-set`: the unreached-share option.

mod common;

use common::{isomorph, read_json, scratch};

#[test]
fn max_unreached_is_a_checked_level_set_option() {
    let out = scratch("level_set_unreached");
    let dir = out.to_str().unwrap();
    let base =
        ["morph", "--source", "sphere", "--target", "torus", "--res", "24", "--frames", "2", "--out", dir];
    let run = |extra: &[&str]| isomorph(&[&base[..], extra].concat());
    let o = run(&["--method", "level-set", "--max-unreached", "1.5"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("max_unreached_share") && err.contains("[0, 1]"), "{err}");
    let o = run(&["--method", "rbf", "--max-unreached", "0.1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--max-unreached (level-set)"), "{err}");
    // Every part of the torus overlaps the sphere: nothing is left unreached
    // even when nothing may be.
    let o = run(&["--method", "level-set", "--max-unreached", "0"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = read_json(out.join("report.json"));
    let details = &report["morph"]["details"];
    assert_eq!((details["target_parts"].as_u64(), details["unreached_share"].as_f64()), (Some(1), Some(0.0)));
}
