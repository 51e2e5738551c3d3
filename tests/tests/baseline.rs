//! End-to-end tests of the baseline morph through the generic exporter.

use isomorph_common::export::{ExportProgress, ExportSettings, export_sequence};
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::mesh::distance::surface_distance;
use isomorph_common::mesh::io::read_mesh;
use isomorph_common::{DistanceBlend, Morph};
use isomorph_common::{Aabb, models};
use std::sync::atomic::{AtomicUsize, Ordering};

const RES: u32 = 48;

fn ball_to_c() -> DistanceBlend {
    DistanceBlend::from_fields(&models::ball(), &models::c_shape(), &Aabb::cube(0.5), RES).unwrap()
}

/// Breen & Whitaker Fig. 6: interpolating distance volumes makes pieces of the
/// target appear detached from the source — more components than either input.
#[test]
fn baseline_pops_pieces_out_of_thin_air() {
    let morph = ball_to_c();
    let components: Vec<usize> =
        (0..=20).map(|i| morph.frame_mesh(i as f32 / 20.0, RES).unwrap().metrics().components).collect();
    assert_eq!(components[0], 1, "the ball is one piece");
    assert_eq!(components[20], 1, "the C is one piece");
    let most = *components.iter().max().unwrap();
    assert!(most > 1, "expected a frame with detached pieces, components per frame: {components:?}");
}

#[test]
fn exporter_writes_what_the_report_says() {
    let dir = std::env::temp_dir().join(format!("isomorph-e2e-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let morph = ball_to_c();
    let source_ref = polygonize(&models::ball(), &Aabb::cube(0.5), 96, 0.0).unwrap();
    let target_ref = polygonize(&models::c_shape(), &Aabb::cube(0.5), 96, 0.0).unwrap();
    let settings = ExportSettings {
        frames: 5,
        resolution: RES,
        out_dir: dir.clone(),
        source_reference: Some(source_ref.clone()),
        target_reference: Some(target_ref),
        distance_samples: 5000,
        ..ExportSettings::default()
    };
    let calls = AtomicUsize::new(0);
    let report = export_sequence(&morph, &settings, &|p| {
        if matches!(p, ExportProgress::Frame { .. }) {
            calls.fetch_add(1, Ordering::Relaxed);
        }
        true
    })
    .unwrap();
    assert_eq!(calls.load(Ordering::Relaxed), 5);
    assert_eq!(report.frames.len(), 5);
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
    let cancelled = export_sequence(&morph, &settings, &|_| false);
    assert!(cancelled.is_err());
    let _ = std::fs::remove_dir_all(&dir);
}
