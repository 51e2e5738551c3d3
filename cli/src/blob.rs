//! `isomorph blob`: polygonize and preview one BlobTree.

use anyhow::Context;
use clap::Args;
use isomorph_blobtree::{BlobError, scenes};
use isomorph_common::Field3;
use isomorph_io::mesh::{MeshFormat, write_mesh};
use isomorph_io::render::{RenderSettings, render};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `isomorph blob`.
///
/// Scene and links-spec files (RON or JSON) are described in the
/// isomorph-blobtree crate docs, section "Scene files"
/// (`cargo doc -p isomorph-blobtree --open`); examples of both ship in
/// `blobtree/scenes/`.
#[derive(Debug, Args)]
#[command(after_help = FORMAT_HELP)]
pub struct BlobArgs {
    /// A BlobTree scene file (.ron or .json) or a built-in scene (rounded_cube,
    /// pierced_sphere, sphere, torus, propeller, rook, queen, bear, bird).
    #[arg(required_unless_present = "dump")]
    pub scene: Option<String>,
    /// Print a scene (a built-in name or a file) or a built-in morph's links
    /// spec (cube_sphere, sphere_propeller, rook_queen, bear_bird) to
    /// standard output, as a file `--format` reads back, and exit.
    #[arg(long, value_name = "NAME", conflicts_with = "scene")]
    pub dump: Option<String>,
    /// The format `--dump` writes.
    #[arg(long, value_enum, default_value = "ron", requires = "dump")]
    pub format: DumpFormat,
    /// Samples along the longest edge of the tree's support box.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub res: u32,
    /// Output folder: surface.ply and preview.png.
    #[arg(long, default_value = "out/blob")]
    pub out: PathBuf,
}

/// Where the scene and links-spec formats are described (shown by `--help`).
const FORMAT_HELP: &str = "Scene and links-spec files: see the isomorph-blobtree crate docs, section \
\"Scene files\" (cargo doc -p isomorph-blobtree --open), and the examples in blobtree/scenes/. \
`isomorph blob --dump rook` prints a built-in scene to start from.";

/// The file format `isomorph blob --dump` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DumpFormat {
    /// Rusty Object Notation (the crate's own scene files).
    Ron,
    /// JSON.
    Json,
}

/// Loads a scene by built-in name or path, naming it in its errors (a read
/// error names it already).
fn load(scene: &str) -> anyhow::Result<isomorph_blobtree::BlobTree> {
    scenes::load(scene).map_err(|e| match e {
        e @ BlobError::Read { .. } => anyhow::Error::new(e),
        e => anyhow::Error::new(e).context(format!("scene {scene}")),
    })
}

/// `isomorph blob --dump NAME`: the scene (or a built-in morph's links spec) as text.
fn dump(name: &str, format: DumpFormat) -> anyhow::Result<String> {
    if let Some((_, _, spec)) = scenes::demo(name) {
        return Ok(match format {
            DumpFormat::Ron => spec.to_ron(),
            DumpFormat::Json => spec.to_json(),
        }?);
    }
    let tree = load(name)?;
    Ok(match format {
        DumpFormat::Ron => tree.to_ron(),
        DumpFormat::Json => tree.to_json(),
    }?)
}

/// Runs `isomorph blob`.
pub fn run(args: &BlobArgs) -> anyhow::Result<()> {
    let scene = match (&args.dump, &args.scene) {
        (Some(name), _) => {
            println!("{}", dump(name, args.format)?);
            return Ok(());
        }
        (None, Some(scene)) => scene,
        (None, None) => anyhow::bail!("give a scene (a file or a built-in name) or --dump NAME"),
    };
    let tree = load(scene)?;
    let start = Instant::now();
    let mesh = tree.mesh(args.res).with_context(|| format!("cannot polygonize scene {scene}"))?;
    let seconds = start.elapsed().as_secs_f64();
    if mesh.is_empty() {
        anyhow::bail!(
            "scene {scene}: no surface at {}³ samples (its features are smaller than a sample); raise --res or \
             enlarge the small primitives",
            args.res
        );
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let path = args.out.join("surface.ply");
    write_mesh(&mesh, &path, MeshFormat::PlyBinaryLittleEndian)
        .with_context(|| format!("cannot write {}", path.display()))?;
    render(&mesh, &RenderSettings::default()).write_png(args.out.join("preview.png"))?;
    let m = mesh.metrics();
    let genus = m.genus.map_or("-".to_string(), |g| g.to_string());
    let support = tree.bounds().unwrap_or(tree.support());
    println!(
        "{scene}: threshold {}, support {:.3} .. {:.3}; {}³ samples in {seconds:.3} s: {} vertices, {} triangles, \
         {} components, genus {genus}",
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
