//! Two shapes (mesh files, `.npy` volumes or built-in names) → the baseline
//! distance blend → frames, contact sheet and report in a folder.
//!
//! `cargo run --release -p isomorph-io --example blend_files -- data/bunny.ply torus out/blend`

use isomorph_common::{BlendSettings, Control, DistanceBlend};
use isomorph_io::export::{ExportSettings, export_sequence};
use isomorph_io::inputs::{LoadOptions, load_solid};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [source, target, out] = args.as_slice() else {
        return Err("usage: blend_files SOURCE TARGET OUT_DIR".into());
    };
    let options = LoadOptions::default();
    let (a, b) = (load_solid(source, &options)?, load_solid(target, &options)?);
    let control = Control::new().with_progress(|p| eprintln!("{} {}", p.stage, p.message));
    let settings = BlendSettings::default();
    let morph = DistanceBlend::new(&a, &b, &settings, &control)?;
    let export = ExportSettings {
        resolution: settings.resolution,
        out_dir: out.into(),
        source_reference: Some(a.surface(settings.resolution, &control)?.into_owned()),
        target_reference: Some(b.surface(settings.resolution, &control)?.into_owned()),
        ..ExportSettings::default()
    };
    let report = export_sequence(&morph, &export, &control)?.report;
    for f in &report.frames {
        println!(
            "t = {:.2}: {} triangles, {} component(s), genus {:?}",
            f.t, f.triangles, f.components, f.genus
        );
    }
    println!("wrote {out}/frame_*.ply, contact_sheet.png, report.json");
    Ok(())
}
