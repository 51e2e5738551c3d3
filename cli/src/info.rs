//! `isomorph info MESH`: mesh metrics as a table or JSON.

use anyhow::Context;
use clap::Args;
use isomorph_io::mesh::{MeshRead, read_mesh_with_warnings};
use std::path::PathBuf;

/// Arguments of `isomorph info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Mesh file (.obj, .ply or .stl).
    mesh: PathBuf,
    /// Print JSON (keys: vertices, triangles, area, volume, components, euler,
    /// genus, boundary_edges, nonmanifold_edges) instead of a table.
    #[arg(long)]
    json: bool,
}

/// Runs `isomorph info`.
pub fn run(args: &InfoArgs) -> anyhow::Result<()> {
    let MeshRead { mesh, warnings } = read_mesh_with_warnings(&args.mesh)
        .with_context(|| format!("cannot read {}", args.mesh.display()))?;
    for warning in &warnings {
        eprintln!("warning: {}: {warning}", args.mesh.display());
    }
    let m = mesh.metrics();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&m)?);
        return Ok(());
    }
    let b = mesh.bounds();
    let genus = m.genus.map_or("n/a (not a closed manifold)".to_string(), |g| g.to_string());
    println!("{}", args.mesh.display());
    println!("  vertices           {}", m.vertices);
    println!("  triangles          {}", m.triangles);
    println!("  bounds             {:.6} .. {:.6}", b.min, b.max);
    println!("  area               {:.6}", m.area);
    println!("  volume             {:.6}", m.volume);
    println!("  components         {}", m.components);
    println!("  euler              {}", m.euler);
    println!("  genus              {genus}");
    println!("  boundary edges     {}", m.boundary_edges);
    println!("  non-manifold edges {}", m.nonmanifold_edges);
    Ok(())
}
