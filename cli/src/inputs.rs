//! Morph inputs: built-in shape names or mesh files, turned into signed
//! distance fields (positive inside) and reference surfaces.

use anyhow::{Context, bail};
use isomorph_common::mesh::io::read_mesh;
use isomorph_common::sdf::MeshSdf;
use isomorph_common::{Aabb, Field3, Shape, TriMesh, marching_cubes::polygonize, models};
use std::path::Path;

/// A shape to morph: analytic or a mesh.
pub enum Input {
    /// A built-in model (see `isomorph_common::models::NAMES`).
    Builtin(String, Shape),
    /// A closed triangle mesh read from a file.
    Mesh(String, TriMesh, MeshSdf),
}

impl Input {
    /// A built-in shape name, or else a mesh file path.
    pub fn parse(spec: &str) -> anyhow::Result<Self> {
        if let Some(shape) = models::by_name(spec) {
            return Ok(Input::Builtin(spec.to_string(), shape));
        }
        let path = Path::new(spec);
        if !path.exists() {
            bail!("'{spec}' is neither a built-in shape ({}) nor an existing mesh file", models::NAMES.join(", "));
        }
        let mesh = read_mesh(path).with_context(|| format!("cannot read {spec}"))?;
        let sdf = MeshSdf::new(&mesh).with_context(|| format!("cannot build the distance field of {spec}"))?;
        Ok(Input::Mesh(spec.to_string(), mesh, sdf))
    }

    /// The signed distance field (positive inside).
    pub fn field(&self) -> &dyn Field3 {
        match self {
            Input::Builtin(_, s) => s,
            Input::Mesh(_, _, sdf) => sdf,
        }
    }

    /// A box containing the shape.
    pub fn bounds(&self) -> Aabb {
        match self {
            Input::Builtin(_, s) => s.aabb(),
            Input::Mesh(_, m, _) => m.bounds(),
        }
    }

    /// The surface to compare frames with: the mesh itself, or the built-in
    /// shape polygonized at `res` nodes along the longest edge.
    pub fn reference(&self, res: u32) -> anyhow::Result<TriMesh> {
        Ok(match self {
            Input::Builtin(_, s) => polygonize(s, &s.aabb().padded(0.05), res, 0.0)?,
            Input::Mesh(_, m, _) => m.clone(),
        })
    }

    /// The name given on the command line.
    pub fn name(&self) -> &str {
        match self {
            Input::Builtin(n, _) | Input::Mesh(n, ..) => n,
        }
    }
}

/// The box the morph lives in: both inputs with 10 % padding per side.
pub fn morph_bounds(a: &Input, b: &Input) -> Aabb {
    a.bounds().union(&b.bounds()).padded(0.1)
}
