//! End-to-end tests of the baseline morph through the sequence exporter.

use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::{BlendSettings, CancelToken, Control, DistanceBlend, Morph, Solid, models};
use isomorph_io::export::{ExportError, ExportSettings, export_sequence};
use isomorph_io::mesh::read_mesh;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

const RES: u32 = 48;

fn blend(a: &Solid, b: &Solid, res: u32) -> DistanceBlend {
    let settings = BlendSettings { resolution: res, ..Default::default() };
    DistanceBlend::new(a, b, &settings, &Control::new()).unwrap()
}

/// Breen & Whitaker Fig. 6: interpolating the distance volumes of shapes
/// that do not overlap (the mug and the chain) makes pieces of the target
/// appear detached from the source — more components than either input.
#[test]
fn baseline_pops_pieces_out_of_thin_air() {
    let (mug, chain) = (Solid::shape(models::mug()), Solid::shape(models::chain()));
    let morph = blend(&mug, &chain, 64);
    let components: Vec<usize> =
        (0..=10).map(|i| morph.frame_mesh(i as f32 / 10.0, 64).unwrap().metrics().components).collect();
    assert_eq!(components[0], 1, "the mug is one piece");
    assert_eq!(components[10], 3, "the chain has three links");
    let most = *components.iter().max().unwrap();
    assert!(most > 3, "expected a frame with detached pieces, components per frame: {components:?}");
}

#[test]
fn exporter_writes_what_the_report_says() {
    let dir = std::env::temp_dir().join(format!("isomorph-e2e-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (ball, c) = (Solid::shape(models::ball()), Solid::shape(models::c_shape()));
    let morph = blend(&ball, &c, RES);
    let control = Control::new();
    let source_ref = ball.surface(96, &control).unwrap().into_owned();
    let target_ref = c.surface(96, &control).unwrap().into_owned();
    let settings = ExportSettings {
        frames: 5,
        resolution: RES,
        out_dir: dir.clone(),
        source_reference: Some(source_ref.clone()),
        target_reference: Some(target_ref),
        distance_samples: 5000,
        ..ExportSettings::default()
    };
    let calls = Arc::new(AtomicUsize::new(0));
    let counter = calls.clone();
    let counting = Control::new().with_progress(move |p| {
        if p.stage == "frames" {
            counter.fetch_add(1, Ordering::Relaxed);
        }
    });
    let report = export_sequence(&morph, &settings, &counting).unwrap().report;
    assert_eq!(calls.load(Ordering::Relaxed), 5);
    assert_eq!(report.frames.len(), 5);
    assert_eq!(report.morph.method, "baseline");
    for f in &report.frames {
        let mesh = read_mesh(dir.join(&f.file)).unwrap();
        assert_eq!(mesh.positions.len(), f.vertices);
        assert_eq!(mesh.triangles.len(), f.triangles);
    }
    // Endpoints reproduce the inputs up to the sampling of a 48³ grid.
    let source = report.endpoints.source.unwrap();
    let target = report.endpoints.target.unwrap();
    assert!(source.mean_voxels < 0.25 && source.hausdorff_voxels < 1.0, "{source:?}");
    assert!(target.mean_voxels < 0.25 && target.hausdorff_voxels < 1.5, "{target:?}");
    // Frame 0 measured independently agrees with the report.
    let first = read_mesh(dir.join(&report.frames[0].file)).unwrap();
    let d = surface_distance(&first, &source_ref, 5000).unwrap();
    assert!((d.mean - source.mean).abs() < 0.2 * source.mean + 1e-4, "{d:?} vs {source:?}");
    assert!(dir.join("contact_sheet.png").is_file() && dir.join("report.json").is_file());

    // Cancelling stops the export with an error.
    let token = CancelToken::new();
    token.cancel();
    let cancelled = export_sequence(&morph, &settings, &Control::new().with_cancel(token));
    assert!(matches!(cancelled, Err(ExportError::Cancelled(_))), "{cancelled:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
