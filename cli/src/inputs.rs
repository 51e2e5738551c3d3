//! Morph inputs: built-in shape names or mesh files, turned into signed
//! distance fields (positive inside) and reference surfaces.

use anyhow::{Context, bail};
use isomorph_common::alignment::Moments;
use isomorph_common::glam::{Affine3A, Quat, Vec3};
use isomorph_common::mesh::io::{MeshFormat, read_mesh, read_mesh_from};
use isomorph_common::sdf::MeshSdf;
use isomorph_common::{Aabb, Field3, Shape, TriMesh, marching_cubes::polygonize, models};
use std::path::Path;

/// Longest box side of a mesh input after fitting (world units).
pub const FIT_SIZE: f32 = 0.9;

/// The Stanford bunny (`data/bunny.ply`, see `data/README.md` for its
/// source and attribution), built in as the mesh named `bunny`.
const BUNNY_PLY: &[u8] = include_bytes!("../../data/bunny.ply");

/// Name of the built-in bunny mesh.
pub const BUNNY: &str = "bunny";

/// A shape to morph: analytic or a mesh.
pub enum Input {
    /// A built-in model (see `isomorph_common::models::NAMES`).
    Builtin(Shape),
    /// A closed triangle mesh read from a file.
    Mesh(TriMesh, Box<MeshSdf>),
}

impl Input {
    /// A built-in shape name, or else a mesh file path.
    ///
    /// With `fit`, a mesh is centred and uniformly scaled so that the longest
    /// side of its box is [`FIT_SIZE`], matching the built-in shapes, which all
    /// live in `[-0.5, 0.5]³`; without it, the mesh keeps its own coordinates.
    pub fn parse(spec: &str, fit: bool) -> anyhow::Result<Self> {
        if let Some(shape) = models::by_name(spec) {
            return Ok(Input::Builtin(shape));
        }
        let path = Path::new(spec);
        let mut mesh = if spec == BUNNY {
            read_mesh_from(BUNNY_PLY, MeshFormat::PlyBinaryLittleEndian).context("the built-in bunny")?
        } else if path.exists() {
            read_mesh(path).with_context(|| format!("cannot read {spec}"))?
        } else {
            bail!(
                "'{spec}' is neither a built-in shape ({}, {BUNNY}) nor an existing mesh file",
                models::NAMES.join(", ")
            );
        };
        if fit {
            let b = mesh.bounds();
            let scale = FIT_SIZE / b.size().max_element().max(f32::MIN_POSITIVE);
            mesh.transform(&Affine3A::from_scale_rotation_translation(
                Vec3::splat(scale),
                Quat::IDENTITY,
                -scale * b.center(),
            ));
        }
        let sdf =
            MeshSdf::new(&mesh).with_context(|| format!("cannot build the distance field of {spec}"))?;
        Ok(Input::Mesh(mesh, Box::new(sdf)))
    }

    /// The signed distance field (positive inside).
    pub fn field(&self) -> &dyn Field3 {
        match self {
            Input::Builtin(s) => s,
            Input::Mesh(_, sdf) => sdf.as_ref(),
        }
    }

    /// A box containing the shape.
    pub fn bounds(&self) -> Aabb {
        match self {
            Input::Builtin(s) => s.aabb(),
            Input::Mesh(m, _) => m.bounds(),
        }
    }

    /// Exact moments of a mesh; grid moments (`res` nodes along the longest
    /// edge) of a built-in shape over its box.
    ///
    /// # Errors
    /// Degenerate or empty shapes, see [`Moments`].
    pub fn moments(&self, res: u32) -> anyhow::Result<Moments> {
        Ok(match self {
            Input::Mesh(mesh, _) => Moments::from_mesh(mesh)?,
            Input::Builtin(shape) => Moments::from_field(shape, &shape.aabb(), res)?,
        })
    }

    /// The surface to compare frames with: the mesh itself, or the built-in
    /// shape polygonized at `res` nodes along the longest edge.
    pub fn reference(&self, res: u32) -> anyhow::Result<TriMesh> {
        Ok(match self {
            Input::Builtin(s) => polygonize(s, &s.aabb().padded(0.05), res, 0.0)?,
            Input::Mesh(m, _) => m.clone(),
        })
    }
}

/// The box the morph lives in: both inputs with 10 % padding per side.
pub fn morph_bounds(a: &Input, b: &Input) -> Aabb {
    a.bounds().union(&b.bounds()).padded(0.1)
}
