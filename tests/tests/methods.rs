//! Every method through the one contract: built by the registry with its
//! library defaults from the same inputs, boxed, exported by the same
//! exporter and held to the same checks.

use isomorph_cli::methods::{Method, Settings, build, load_input};
use isomorph_common::{CancelToken, Control, MorphError, MorphFailure};
use isomorph_io::compare::{Candidate, Status, compare};
use isomorph_io::export::{ExportSettings, export_sequence};

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("isomorph-methods-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Sphere → torus with every method's defaults: each succeeds, starts on
/// the sphere (genus 0) and ends on the torus (genus 1) within a voxel on
/// average, with closed frames.
#[test]
fn every_method_morphs_sphere_into_torus_with_its_defaults() {
    let control = Control::new();
    let dir = scratch("sphere-torus");
    for method in Method::ALL {
        let source = load_input(method, "sphere", &Default::default()).unwrap();
        let target = load_input(method, "torus", &Default::default()).unwrap();
        let morph = build(method, &source, &target, &Settings::default(), &control)
            .unwrap_or_else(|e| panic!("{}: {e}", method.name()));
        assert_eq!(morph.method(), method.name());
        assert!(morph.report().converged, "{}: {:?}", method.name(), morph.report().outcome);
        let settings = ExportSettings {
            frames: 5,
            resolution: 64,
            out_dir: dir.join(method.name()),
            contact_sheet: false,
            source_reference: Some(source.surface(96, &control).unwrap().into_owned()),
            target_reference: Some(target.surface(96, &control).unwrap().into_owned()),
            distance_samples: 5000,
            ..ExportSettings::default()
        };
        let report = export_sequence(&*morph, &settings, &control).unwrap().report;
        let genus = report.genus_sequence();
        assert_eq!((genus[0], genus[4]), (Some(0), Some(1)), "{}: genus {genus:?}", method.name());
        for (end, e) in [("source", report.endpoints.source), ("target", report.endpoints.target)] {
            let e = e.unwrap();
            println!(
                "{} {end}: mean {:.3}, Hausdorff {:.3} voxels",
                method.name(),
                e.mean_voxels,
                e.hausdorff_voxels
            );
            assert!(e.mean_voxels < 1.0, "{} {end}: {e:?}", method.name());
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Shared error kinds reach generic code through the boxed form.
#[test]
fn boxed_errors_keep_their_shared_kinds() {
    let source = load_input(Method::Baseline, "sphere", &Default::default()).unwrap();
    let target = load_input(Method::Baseline, "torus", &Default::default()).unwrap();
    let token = CancelToken::new();
    token.cancel();
    let cancelled = Control::new().with_cancel(token);
    for method in Method::ALL {
        let (a, b) = if method == Method::Blobtree {
            (
                load_input(method, "sphere", &Default::default()).unwrap(),
                load_input(method, "torus", &Default::default()).unwrap(),
            )
        } else {
            (source.clone(), target.clone())
        };
        let e = build(method, &a, &b, &Settings::default(), &cancelled)
            .err()
            .expect("cancelled before it starts");
        assert!(e.is_cancelled(), "{}: {e}", method.name());
    }
    // The BlobTree method takes BlobTrees only, and says so.
    let e = build(Method::Blobtree, &source, &target, &Settings::default(), &Control::new()).err().unwrap();
    assert!(matches!(e.shared(), Some(MorphError::UnsupportedInput { .. })), "{e}");
    // A bad setting names its field.
    let mut bad = Settings::default();
    bad.level_set.resolution = 2;
    let e = build(Method::LevelSet, &source, &target, &bad, &Control::new()).err().unwrap();
    assert!(e.to_string().contains("resolution"), "{e}");
}

/// `compare` runs the methods side by side and writes its table; a method
/// that cannot take the inputs is a skipped row with the reason, not a
/// failure of the run.
#[test]
fn compare_writes_a_row_per_method() {
    let control = Control::new();
    let dir = scratch("compare");
    let candidates = [Method::Baseline, Method::LevelSet, Method::Blobtree]
        .into_iter()
        .map(|method| {
            let name = method.name().to_string();
            let inputs = (
                load_input(Method::Baseline, "sphere", &Default::default()).unwrap(),
                load_input(Method::Baseline, "torus", &Default::default()).unwrap(),
            );
            Candidate {
                name,
                build: Ok(Box::new(move |c: &Control| {
                    build(method, &inputs.0, &inputs.1, &Settings::default(), c)
                })),
                references: None,
            }
        })
        .collect();
    let settings =
        ExportSettings { frames: 3, resolution: 40, out_dir: dir.clone(), ..ExportSettings::default() };
    let table = compare("sphere", "torus", candidates, &settings, &control).unwrap();
    let status: Vec<Status> = table.rows.iter().map(|r| r.status).collect();
    assert_eq!(status, [Status::Ok, Status::Ok, Status::Skipped]);
    assert!(table.rows[2].reason.as_deref().unwrap_or("").contains("BlobTree"), "{:?}", table.rows[2]);
    for f in ["compare.png", "compare.json", "compare.md", "compare.html", "level-set/report.json"] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
