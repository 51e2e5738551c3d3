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
#[derive(Debug, Args)]
pub struct BlobArgs {
    /// A BlobTree scene file (.ron or .json) or a built-in scene (rounded_cube,
    /// pierced_sphere, sphere, torus, propeller, rook, queen, bear, bird).
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
    // Name the scene in its errors (a read error names it already).
    let tree = scenes::load(&args.scene).map_err(|e| match e {
        e @ BlobError::Read { .. } => anyhow::Error::new(e),
        e => anyhow::Error::new(e).context(format!("scene {}", args.scene)),
    })?;
    let start = Instant::now();
    let mesh = tree.mesh(args.res).with_context(|| format!("cannot polygonize scene {}", args.scene))?;
    let seconds = start.elapsed().as_secs_f64();
    if mesh.is_empty() {
        anyhow::bail!(
            "scene {}: no surface at {}³ samples (its features are smaller than a sample); raise --res or \
             enlarge the small primitives",
            args.scene,
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
