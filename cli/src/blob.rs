//! `isomorph blob`: polygonize and preview one BlobTree; the BlobTree
//! inputs of `isomorph morph --method blobtree`.

use anyhow::{Context, bail};
use clap::Args;
use isomorph_blobtree::{BlobTree, MorphSpec, scenes};
use isomorph_common::Field3;
use isomorph_common::mesh::io::{MeshFormat, write_mesh};
use isomorph_common::render::{RenderSettings, render};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Built-in BlobTree scenes (Galin et al. §5), usable wherever a scene
/// file is.
pub const SCENES: [&str; 8] =
    ["rounded_cube", "pierced_sphere", "sphere", "propeller", "rook", "queen", "bear", "bird"];

/// A built-in scene by name, or a scene file (`.ron` or `.json`).
///
/// # Errors
/// Unknown names, unreadable files, and the scene's parse and validation
/// errors (which name the offending node's path).
pub fn load_tree(spec: &str) -> anyhow::Result<BlobTree> {
    let builtin = match spec {
        "rounded_cube" => Some(scenes::rounded_cube()),
        "pierced_sphere" => Some(scenes::pierced_sphere()),
        "sphere" => Some(scenes::sphere()),
        "propeller" => Some(scenes::propeller()),
        "rook" => Some(scenes::rook()),
        "queen" => Some(scenes::queen()),
        "bear" => Some(scenes::bear()),
        "bird" => Some(scenes::bird()),
        _ => None,
    };
    if let Some(tree) = builtin {
        return Ok(tree);
    }
    let path = Path::new(spec);
    if !path.exists() {
        bail!("'{spec}' is neither a built-in BlobTree ({}) nor a scene file", SCENES.join(", "));
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {spec}"))?;
    let tree = match path.extension().and_then(|e| e.to_str()) {
        Some("ron") => BlobTree::from_ron(&text),
        Some("json") => BlobTree::from_json(&text),
        _ => bail!("{spec}: a BlobTree scene is a .ron or .json file"),
    };
    tree.with_context(|| format!("invalid scene {spec}"))
}

/// The built-in morphs of [`scenes::DEMOS`] by their source and target scene
/// names.
const DEMO_PAIRS: [(&str, &str, &str); 4] = [
    ("rounded_cube", "pierced_sphere", "cube_sphere"),
    ("sphere", "propeller", "sphere_propeller"),
    ("rook", "queen", "rook_queen"),
    ("bear", "bird", "bear_bird"),
];

/// The animator's morph spec (links, speed curves, trajectories) from a
/// `.ron` or `.json` file; without one, the built-in spec of a built-in pair
/// (e.g. rook → queen, whose links and speed curves keep it in one piece),
/// else the default (automatic correspondence).
///
/// # Errors
/// Unreadable or malformed files.
pub fn load_spec(path: Option<&Path>, source: &str, target: &str) -> anyhow::Result<MorphSpec> {
    let Some(path) = path else {
        let demo = DEMO_PAIRS.iter().find(|(a, b, _)| (*a, *b) == (source, target));
        return Ok(demo
            .and_then(|(_, _, name)| scenes::demo(name))
            .map(|(_, _, spec)| spec)
            .unwrap_or_default());
    };
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let spec = match path.extension().and_then(|e| e.to_str()) {
        Some("json") => MorphSpec::from_json(&text),
        _ => MorphSpec::from_ron(&text),
    };
    spec.with_context(|| format!("invalid links file {}", path.display()))
}

/// Arguments of `isomorph blob`.
#[derive(Debug, Args)]
pub struct BlobArgs {
    /// A BlobTree scene file (.ron or .json) or a built-in scene (rounded_cube,
    /// pierced_sphere, sphere, propeller, rook, queen, bear, bird).
    pub scene: String,
    /// Samples along the longest edge of the tree's support box.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub res: u32,
    /// Output folder: surface.ply and preview.png.
    #[arg(long, default_value = "out/blob")]
    pub out: PathBuf,
}

/// Runs `isomorph blob`.
pub fn run(args: &BlobArgs) -> anyhow::Result<()> {
    let tree = load_tree(&args.scene)?;
    let start = Instant::now();
    let mesh = tree.mesh(args.res)?;
    let seconds = start.elapsed().as_secs_f64();
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let path = args.out.join("surface.ply");
    write_mesh(&mesh, &path, MeshFormat::PlyBinaryLittleEndian)
        .with_context(|| format!("cannot write {}", path.display()))?;
    render(&mesh, &RenderSettings::default()).write_png(args.out.join("preview.png"))?;
    let m = mesh.metrics();
    let genus = m.genus.map_or("-".to_string(), |g| g.to_string());
    let support = tree.bounds().unwrap_or(tree.support());
    println!(
        "{}: threshold {}, support {:.3} .. {:.3}; {}³ samples in {seconds:.3} s: {} vertices, {} triangles, \
         {} components, genus {genus}",
        args.scene,
        tree.threshold(),
        support.min,
        support.max,
        args.res,
        m.vertices,
        m.triangles,
        m.components
    );
    println!("  wrote {} and preview.png", path.display());
    Ok(())
}
