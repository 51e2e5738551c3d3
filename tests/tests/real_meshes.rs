//! The level set on real meshes, end to end as the command line runs it
//! (registry, exporter, endpoint distances against the inputs): the Stanford
//! bunny from `data/` into the Utah teapot from `data/` (open, unwelded: its
//! inside comes from the winding-number sign) and into a generated dense,
//! thin-armed closed surface (a sea urchin: a ball with fourteen thin arms,
//! polygonized finely, some 60 000 triangles).
//!
//! Each morph must run at the level set's default resolution and at 128³,
//! keep every frame a finite, non-empty surface, start on the bunny and end
//! on the target within stated voxel distances, with the components the
//! shapes have; where the default grid is too coarse for the target (the
//! urchin's arms at 64³), the export must say where and name the finer
//! resolution, which then morphs it. The 256³ runs are release-only (`cargo test --release -p
//! isomorph-tests --test real_meshes`): unoptimised they would take minutes.

use isomorph_cli::methods::{Method, Settings, build, load_input};
use isomorph_common::glam::Vec3;
use isomorph_common::marching_cubes::level_set_mesh;
use isomorph_common::{Aabb, Control, Field3, Solid, TriMesh};
use isomorph_io::export::{ExportSettings, Exported, export_sequence};

fn data(name: &str) -> String {
    format!("{}/../data/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The bunny, fitted into the built-in shapes' box as the command line
/// loads it.
fn bunny() -> Solid {
    load_input(Method::LevelSet, &data("bunny.ply"), &Default::default()).unwrap()
}

/// A sea urchin: a ball of radius 0.17 with 14 arms (capsules of radius
/// 0.022, reaching 0.42 from the centre) along the cube's face and corner
/// directions; the distance to the union (exact outside).
#[derive(Debug)]
struct Urchin {
    arms: Vec<Vec3>,
}

impl Urchin {
    const BALL: f32 = 0.17;
    const ARM: f32 = 0.022;
    const REACH: f32 = 0.42;

    fn new() -> Self {
        let mut arms = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for i in 0..8 {
            let s = |bit: i32| if i & bit == 0 { 1.0 } else { -1.0 };
            arms.push(Vec3::new(s(1), s(2), s(4)).normalize());
        }
        Self { arms }
    }
}

impl Field3 for Urchin {
    /// Positive inside.
    fn value(&self, p: Vec3) -> f32 {
        let capsule = |axis: Vec3| {
            let along = p.dot(axis).clamp(0.0, Self::REACH - Self::ARM);
            Self::ARM - (p - along * axis).length()
        };
        self.arms.iter().map(|&a| capsule(a)).fold(Self::BALL - p.length(), f32::max)
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(Aabb::cube(Self::REACH + 0.05))
    }
}

/// The urchin as a mesh: marching cubes of its field at 288 nodes along the
/// box (arms about 13 nodes across), the dense thin-featured input.
fn urchin_mesh() -> TriMesh {
    let urchin = Urchin::new();
    level_set_mesh(&urchin, &urchin.bounds().unwrap(), 288, 0.0).unwrap()
}

/// Builds the level set from `source` to `target` at `res` (the library
/// default when `None`) and exports `frames` frames measured against the
/// inputs, as `isomorph morph` does.
fn morph(source: &Solid, target: &Solid, res: Option<u32>, frames: usize, name: &str) -> Exported {
    let control = Control::new();
    let mut settings = Settings::default();
    if let Some(res) = res {
        settings = settings.with_resolution(res);
    }
    let morph = build(Method::LevelSet, source, target, &settings, &control)
        .unwrap_or_else(|e| panic!("{name} at {res:?}: {e}"));
    println!("{name}: {:?}", morph.report());
    assert!(morph.report().converged, "{name}: {:?}", morph.report().outcome);
    // One directory per input and resolution: the tests run in parallel,
    // and each removes its own when done.
    let res = settings.level_set.resolution;
    let out = std::env::temp_dir().join(format!("isomorph-real-{}-{name}-{res}", std::process::id()));
    let export = ExportSettings {
        frames,
        resolution: res,
        out_dir: out.clone(),
        frame_files: false,
        contact_sheet: false,
        preview: false,
        ..ExportSettings::default()
    }
    .with_inputs(source, target, &control)
    .unwrap();
    let exported = export_sequence(&*morph, &export, &control).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    exported
}

/// Limits, in voxels, of an endpoint's mean and Hausdorff distance.
#[derive(Debug, Clone, Copy)]
struct Within {
    mean: f32,
    hausdorff: f32,
}

/// Every frame a finite non-empty surface; the endpoints within `source`
/// and `target` of the inputs (the target unchecked when `None`); the first
/// frame one component (the bunny), the last `last_components`.
fn check(exported: &Exported, name: &str, source: Within, target: Option<Within>, last_components: usize) {
    let report = &exported.report;
    for (frame, mesh) in report.frames.iter().zip(&exported.meshes) {
        assert!(frame.triangles > 0, "{name}: the frame at t = {} is empty", frame.t);
        assert!(mesh.positions.iter().all(|p| p.is_finite()), "{name}: t = {}", frame.t);
        assert!(frame.area > 0.0 && frame.volume > 0.0, "{name}: t = {}: {frame:?}", frame.t);
    }
    let components: Vec<usize> = report.frames.iter().map(|f| f.components).collect();
    println!("{name}: components {components:?}, endpoints {:?}", report.endpoints);
    println!("{name}: warnings {:?}", report.warnings);
    assert_eq!(components[0], 1, "{name}: {components:?}");
    assert_eq!(*components.last().unwrap(), last_components, "{name}: {components:?}");
    for (end, e, within) in
        [("source", report.endpoints.source, Some(source)), ("target", report.endpoints.target, target)]
    {
        let e = e.unwrap_or_else(|| panic!("{name}: no {end} distance"));
        let Some(within) = within else { continue };
        assert!(e.mean_voxels <= within.mean, "{name} {end}: {e:?}");
        assert!(e.hausdorff_voxels <= within.hausdorff, "{name} {end}: {e:?}");
    }
}

/// The frame's own surface, never farther than a voxel on average and two
/// at worst (the bunny's ears are thinner than two voxels at 64³).
const ON_THE_BUNNY: Within = Within { mean: 0.1, hausdorff: 2.0 };

/// The teapot's reference is its own open patch soup, whose spout and
/// handle run on inside the body where no frame can follow: the mean stays
/// small, the Hausdorff distance is that of the hidden ends, a fixed world
/// distance (measured 2.7 voxels at 64³, 5.4 at 128³): at most 3.5 voxels of
/// the 64³ grid at `res`.
fn on_the_teapot(res: u32) -> Within {
    Within { mean: 0.25, hausdorff: 3.5 * (res - 1) as f32 / 63.0 }
}

/// The bunny into the teapot at `res` (the default when `None`); the
/// export's warnings.
fn bunny_into_teapot(res: Option<u32>) -> Vec<String> {
    let teapot = load_input(Method::LevelSet, &data("teapot.ply"), &Default::default()).unwrap();
    let exported = morph(&bunny(), &teapot, res, 5, "teapot");
    let within = on_the_teapot(res.unwrap_or(Settings::default().level_set.resolution));
    check(&exported, &format!("teapot at {res:?}"), ON_THE_BUNNY, Some(within), 1);
    exported.report.warnings
}

/// The bunny into the urchin at `res` (the default when `None`), checked
/// against the urchin within `target` (unchecked when `None`).
fn bunny_into_urchin(res: Option<u32>, target: Option<Within>) -> Exported {
    let mesh = urchin_mesh();
    assert!(mesh.triangles.len() > 30_000, "{} triangles", mesh.triangles.len());
    let metrics = mesh.metrics();
    assert_eq!((metrics.components, metrics.genus), (1, Some(0)));
    let urchin = Solid::mesh(mesh).unwrap();
    let exported = morph(&bunny(), &urchin, res, 5, "urchin");
    check(&exported, &format!("urchin at {res:?}"), ON_THE_BUNNY, target, 1);
    exported
}

/// The point `(x, y, z)` a warning names after `after`.
fn place_in(warning: &str, after: &str) -> Vec3 {
    let start = warning.find(after).unwrap_or_else(|| panic!("no {after:?} in {warning:?}")) + after.len();
    let end = start + warning[start..].find(')').unwrap();
    let c: Vec<f32> = warning[start..end].split(", ").map(|c| c.parse().unwrap()).collect();
    Vec3::new(c[0], c[1], c[2])
}

#[test]
fn bunny_into_teapot_at_the_default_resolution() {
    bunny_into_teapot(None);
}

/// The teapot's rim is a sheet thinner than a voxel at 128³: sampled on the
/// morph's lattice it falls into one-node islands (the target's own
/// marching cubes there has 8 components), which the level set dissolves;
/// the last frame is the teapot's one component. Its hidden spout end is
/// reported as what it is, an inner sheet, not as a part the grid is too
/// coarse for.
#[test]
fn bunny_into_teapot_at_128() {
    let warnings = bunny_into_teapot(Some(128));
    let warning = warnings.iter().find(|w| w.starts_with("the last frame")).expect("the hidden spout end");
    assert!(warning.contains("inside the frame's solid ("), "{warning}");
    assert!(warning.contains("an inner sheet of an open"), "{warning}");
    assert!(!warning.contains("--res"), "{warning}");
}

/// At the level set's default resolution (64³) the urchin's arms are about
/// 3 voxels across, and the sparse field does not grow them their full
/// length (the column's tip stalls: `docs/EXPERIMENTS.md`, ninth session).
/// The export says so: its warning names a place on an arm that the last
/// frame does not reach, and the finer resolution that reaches it
/// ([`bunny_into_a_dense_thin_armed_surface_at_128`] shows that it does).
#[test]
fn bunny_into_a_dense_thin_armed_surface_at_the_default_resolution_is_reported() {
    let exported = bunny_into_urchin(None, None);
    let res = Settings::default().level_set.resolution;
    let warning = exported.report.warnings.iter().find(|w| w.starts_with("the last frame"));
    let warning = warning.expect("a warning that the last frame is off the target");
    assert!(warning.contains(&format!("`--res {}`", 2 * res)), "{warning}");
    let p = place_in(warning, "does not reach the target near (");
    // On an arm's surface (within a voxel), beyond the ball.
    let voxel = exported.report.voxel_size;
    assert!(Urchin::new().value(p).abs() <= voxel, "{p} is not on the urchin");
    assert!(p.length() > Urchin::BALL + 3.0 * voxel, "{p} is on the ball, not an arm");
}

#[test]
fn bunny_into_a_dense_thin_armed_surface_at_128() {
    bunny_into_urchin(Some(128), Some(Within { mean: 0.1, hausdorff: 2.0 }));
}

#[cfg(not(debug_assertions))]
#[test]
fn bunny_into_the_teapot_and_the_urchin_at_256() {
    let teapot = load_input(Method::LevelSet, &data("teapot.ply"), &Default::default()).unwrap();
    let exported = morph(&bunny(), &teapot, Some(256), 5, "teapot-256");
    check(&exported, "teapot at 256", ON_THE_BUNNY, Some(on_the_teapot(256)), 1);
    let urchin = Solid::mesh(urchin_mesh()).unwrap();
    let exported = morph(&bunny(), &urchin, Some(256), 5, "urchin-256");
    check(&exported, "urchin at 256", ON_THE_BUNNY, Some(Within { mean: 0.1, hausdorff: 2.0 }), 1);
}
