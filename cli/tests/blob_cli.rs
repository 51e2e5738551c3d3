//! The BlobTree method's Bézier-like morph from the command line: a links
//! spec given with `--via` is the last pair's, and its `levels` link the
//! de Casteljau levels above the first (honoured, or refused by name).

mod common;

use common::{assert_ok, isomorph, morph, scratch, stderr};
use std::path::{Path, PathBuf};

/// The error output of `isomorph morph --method METHOD` from `source` to
/// `target` with `args`, which must fail.
fn refused(method: &str, source: &str, target: &str, args: &[&str]) -> String {
    let o = morph(method, source, target, args);
    assert!(!o.status.success(), "{method} {source} -> {target} {args:?} succeeded");
    stderr(&o)
}

/// A fresh scratch folder and the path of a file shipped in `blobtree/scenes/`.
fn setup(scratch_name: &str, shipped_file: &str) -> (PathBuf, PathBuf) {
    let out = scratch(scratch_name);
    std::fs::create_dir_all(&out).unwrap();
    (out, Path::new(env!("CARGO_MANIFEST_DIR")).join("../blobtree/scenes").join(shipped_file))
}

#[test]
fn via_takes_a_links_spec_with_level_links() {
    let (out, spec) = setup("blob_levels", "rook_queen_bear.levels.links.ron");
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
    let err = refused("blobtree", "rook", "bear", &args);
    assert!(err.contains("de Casteljau level 2, pair 0") && err.contains("does not exist"), "{err}");
    // Level links without control shapes are refused.
    let args = ["--links", bad.to_str().unwrap(), "--res", "16", "--out", frames.to_str().unwrap()];
    let err = refused("blobtree", "rook", "bear", &args);
    assert!(err.contains("levels"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

/// `--via-links` gives each pair arriving at a `--via` shape its own spec:
/// the shipped rook → queen spec given explicitly draws exactly the frames
/// of the built-in default, automatic matching (an empty spec) others; a
/// link to a missing node names the pair's segment, an unreadable spec its
/// file and pair, and a wrong count is refused.
#[test]
fn via_links_give_each_pair_its_spec() {
    let (out, shipped) = setup("blob_via_links", "rook_queen.links.ron");
    let empty = out.join("empty.links.ron");
    std::fs::write(&empty, "()").unwrap();
    let frame = |via_links: &[&Path], name: &str| {
        let frames = out.join(name);
        let mut args =
            vec!["--via", "queen", "--via-mode", "chain", "--res", "24", "--frames", "5", "--no-preview"];
        for path in via_links {
            args.extend(["--via-links", path.to_str().unwrap()]);
        }
        args.extend(["--out", frames.to_str().unwrap()]);
        let o = morph("blobtree", "rook", "bear", &args);
        assert_ok(&o);
        std::fs::read(frames.join("frame_001.ply")).unwrap()
    };
    let default = frame(&[], "default");
    assert_eq!(frame(&[&shipped], "shipped"), default, "the shipped spec is the built-in default");
    assert_ne!(frame(&[&empty], "automatic"), default, "automatic matching gives another in-between");
    // A link to a node the rook lacks names the segment; a malformed file its path and pair.
    let (bad, frames) = (out.join("bad.links.ron"), out.join("bad"));
    let (bad_file, empty_file, out_dir) =
        (bad.to_str().unwrap(), empty.to_str().unwrap(), frames.to_str().unwrap());
    let args = ["--via", "queen", "--via-links", bad_file, "--res", "16", "--out", out_dir];
    std::fs::write(&bad, "(links: [(a: [99], b: [0])])").unwrap();
    let err = refused("blobtree", "rook", "bear", &args);
    assert!(err.contains("segment 0") && err.contains("root/99, which does not exist"), "{err}");
    std::fs::write(&bad, "(links: [(a: [[99], b: [0])])").unwrap();
    let err = refused("blobtree", "rook", "bear", &args);
    assert!(err.contains("rook → queen") && err.contains("bad.links.ron"), "{err}");
    // One --via-links per --via, or none.
    let args = ["--via", "queen", "--via-links", empty_file, "--via-links", empty_file, "--out", out_dir];
    let err = refused("blobtree", "rook", "bear", &args);
    assert!(err.contains("one --via-links per --via"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

/// `--scenes` writes every frame's generic tree `C(t)` as a scene file
/// beside its mesh, which loads back into the morph's field at that `t`
/// (the shipped rook file into the queen, automatic correspondence).
#[test]
fn scenes_save_each_frame_as_a_blobtree() {
    use isomorph_blobtree::{BlobMorph, scenes};
    let (out, rook_file) = setup("blob_scenes", "rook.ron");
    let frames = out.join("frames");
    let args =
        ["--res", "16", "--frames", "3", "--no-preview", "--scenes", "--out", frames.to_str().unwrap()];
    assert_ok(&morph("blobtree", rook_file.to_str().unwrap(), "queen", &args));
    let (rook, queen) = (scenes::rook(), scenes::queen());
    let expected = BlobMorph::from_trees(&rook, &queen, &Default::default()).unwrap();
    frames_reload(&frames, &expected, 3);
    // The scenes are the BlobTree method's: other methods refuse the option.
    let err = refused("level-set", "sphere", "torus", &["--scenes", "--out", frames.to_str().unwrap()]);
    assert!(err.contains("--scenes"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

/// Checks that the `count` scene files `--scenes` wrote in `frames` (at
/// evenly spaced `t`) load back into `expected`'s field at their `t`, to
/// 1e-6 on an 8³ lattice over the support box of the middle frame; returns
/// their texts.
fn frames_reload(frames: &Path, expected: &isomorph_blobtree::BlobMorph, count: usize) -> Vec<String> {
    use isomorph_blobtree::BlobTree;
    use isomorph_common::{Field3, Morph};
    let support = expected.frame(0.5).unwrap().field.support();
    (0..count)
        .map(|i| {
            let t = i as f32 / (count - 1) as f32;
            let text = std::fs::read_to_string(frames.join(format!("frame_{i:03}.ron"))).unwrap();
            let saved = BlobTree::from_ron(&text).unwrap();
            let field = expected.frame(t).unwrap().field;
            for k in 0..512u16 {
                let cell = isomorph_common::glam::UVec3::new(
                    u32::from(k % 8),
                    u32::from(k / 8 % 8),
                    u32::from(k / 64),
                );
                let p = support.min + (support.max - support.min) * cell.as_vec3() / 7.0;
                assert!((saved.value(p) - field.value(p)).abs() <= 1e-6, "t = {t} at {p}");
            }
            text
        })
        .collect()
}

/// The shipped propeller → bent rods example from the command line: the
/// bend about its own axes (`bent_rods.ron`) and the speeds of the two
/// halves of the twist ↔ bend pair (`propeller_bent_rods.links.ron`).
/// Saved frames keep the bend's axes (written only where they are not the
/// defaults) and load back into the morph's field; `--dump` writes the
/// scene with its axes.
#[test]
fn warp_axes_and_warp_halves_from_the_command_line() {
    use isomorph_blobtree::{BlobMorph, MorphSpec, scenes};
    let (out, bent) = setup("blob_warp_axes", "bent_rods.ron");
    let spec_file = bent.with_file_name("propeller_bent_rods.links.ron");
    let frames = out.join("frames");
    let args = [
        "--links",
        spec_file.to_str().unwrap(),
        "--res",
        "16",
        "--frames",
        "5",
        "--no-preview",
        "--scenes",
        "--out",
        frames.to_str().unwrap(),
    ];
    assert_ok(&morph("blobtree", "propeller", bent.to_str().unwrap(), &args));
    let spec = MorphSpec::load(&spec_file).unwrap();
    let target = scenes::load(bent.to_str().unwrap()).unwrap();
    let expected = BlobMorph::from_trees(&scenes::propeller(), &target, &spec).unwrap();
    let texts = frames_reload(&frames, &expected, 5);
    // t = 0.25: the twist half undone, the bend (about x) not started; t = 0.75: the twist gone.
    for text in &texts[1..] {
        assert!(text.contains("axis: (1.0, 0.0, 0.0)") && text.contains("along: (0.0, 0.0, 1.0)"), "{text}");
        assert_eq!(text.matches("axis").count(), 1, "the twist's default axis is not written: {text}");
    }
    assert!(texts[1].contains("rate: 1.1"), "{}", texts[1]);
    // `--dump` writes the example with its axes, as RON and JSON, back to the same tree.
    for (format, read) in [
        ("ron", isomorph_blobtree::BlobTree::from_ron as fn(&str) -> _),
        ("json", isomorph_blobtree::BlobTree::from_json),
    ] {
        let o = isomorph(&["blob", "--dump", bent.to_str().unwrap(), "--format", format]);
        assert_ok(&o);
        let text = String::from_utf8(o.stdout).unwrap();
        assert!(text.contains("along"), "{text}");
        assert_eq!(read(&text).unwrap(), target, "{format}");
    }
    let _ = std::fs::remove_dir_all(&out);
}
