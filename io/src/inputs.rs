//! Input solids from what a user types ([`load_solid`]): a built-in shape
//! name, the built-in Stanford bunny, a mesh file (OBJ, PLY, STL) or a
//! `.npy` volume with its JSON sidecar.
//!
//! ```
//! use isomorph_io::inputs::{LoadOptions, load_solid};
//!
//! let torus = load_solid("torus", &LoadOptions::default())?;
//! assert_eq!(torus.kind(), "analytic shape");
//! let bunny = load_solid("bunny", &LoadOptions::default())?;
//! // Fitted into the built-in shapes' box: centred, longest side 0.9.
//! assert!((bunny.bounds().size().max_element() - 0.9).abs() < 1e-5);
//! # Ok::<(), isomorph_io::inputs::InputError>(())
//! ```

use crate::mesh::{MeshFormat, MeshIoError, MeshRead, read_mesh_from, read_mesh_with_warnings};
use crate::npy::{NpyError, Volume, load_npy};
use isomorph_common::glam::{Affine3A, Quat, Vec3};
use isomorph_common::{Aabb, Grid3, MorphError, Solid, TriMesh, models};
use std::path::Path;

/// Longest box side of an input after fitting (world units): the built-in
/// shapes all live in `[-0.5, 0.5]³`.
pub const FIT_SIZE: f32 = 0.9;

/// Name of the built-in bunny mesh.
pub const BUNNY: &str = "bunny";

/// The Stanford bunny (`data/bunny.ply`, see `data/README.md` for its
/// source and attribution).
const BUNNY_PLY: &[u8] = include_bytes!("../../data/bunny.ply");

/// How [`load_solid`] reads an input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadOptions {
    /// Centre mesh and volume inputs and scale them uniformly so that the
    /// longest side of their box is [`FIT_SIZE`] (default `true`); without
    /// it they keep their own coordinates. Built-in shapes are never moved.
    pub fit: bool,
    /// For volumes: the surface level. `None` reads f32 volumes as signed
    /// distances (positive inside, surface at 0) and u8 volumes as densities
    /// with the surface at 127.5 (True's convention); with a level, values
    /// above it are inside and the volume is redistanced.
    pub iso: Option<f32>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { fit: true, iso: None }
    }
}

/// Errors of [`load_solid`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
    /// The spec names no built-in shape and no existing file.
    #[error("'{spec}' is neither a built-in shape ({names}) nor an existing file")]
    Unknown {
        /// What was given.
        spec: String,
        /// The built-in names.
        names: String,
    },
    /// A mesh file could not be read.
    #[error("cannot read the mesh {path}: {source}")]
    Mesh {
        /// The file.
        path: String,
        /// The cause.
        source: MeshIoError,
    },
    /// A volume file could not be read.
    #[error(transparent)]
    Volume(#[from] NpyError),
    /// The input cannot be a solid (empty mesh, non-finite values, no
    /// surface in a volume).
    #[error("{spec}: {source}")]
    Solid {
        /// What was given.
        spec: String,
        /// The cause.
        source: MorphError,
    },
}

/// The built-in shape names [`load_solid`] accepts.
pub fn builtin_names() -> Vec<&'static str> {
    models::NAMES.iter().copied().chain([BUNNY]).collect()
}

/// The built-in Stanford bunny in its own coordinates (y up, about 9.65
/// units tall).
///
/// # Panics
/// Never: the embedded file is checked by a test.
pub fn bunny() -> TriMesh {
    read_mesh_from(BUNNY_PLY, MeshFormat::PlyBinaryLittleEndian).expect("the embedded bunny is a valid PLY")
}

/// The solid named by `spec`: a built-in shape (`isomorph_common::models`
/// names), `bunny`, a mesh file (`.obj`, `.ply`, `.stl`) or a `.npy`
/// volume (placed by its JSON sidecar, see [`crate::npy`]).
///
/// # Errors
/// [`InputError`] naming the input and what is wrong with it.
pub fn load_solid(spec: &str, options: &LoadOptions) -> Result<Solid, InputError> {
    load_solid_with_warnings(spec, options).map(|(solid, _)| solid)
}

/// [`load_solid`], with what the file readers noticed and read leniently
/// (e.g. dropped normal references, tolerance welding; see
/// [`crate::mesh::ReadWarning`]), for the caller to show.
///
/// # Errors
/// As [`load_solid`].
pub fn load_solid_with_warnings(
    spec: &str,
    options: &LoadOptions,
) -> Result<(Solid, Vec<String>), InputError> {
    if let Some(shape) = models::by_name(spec) {
        return Ok((Solid::shape(shape), Vec::new()));
    }
    let solid_error = |source| InputError::Solid { spec: spec.to_string(), source };
    let path = Path::new(spec);
    if spec == BUNNY || (path.is_file() && !is_npy(path)) {
        let MeshRead { mut mesh, warnings } = if spec == BUNNY {
            MeshRead { mesh: bunny(), warnings: Vec::new() }
        } else {
            read_mesh_with_warnings(path)
                .map_err(|source| InputError::Mesh { path: spec.to_string(), source })?
        };
        if options.fit {
            mesh.transform(&fit_map(&mesh.bounds()));
        }
        let warnings = warnings.iter().map(ToString::to_string).collect();
        return Ok((Solid::mesh(mesh).map_err(solid_error)?, warnings));
    }
    if path.is_file() {
        let (values, iso) = match load_npy(path)? {
            Volume::F32(grid) => (grid, options.iso),
            Volume::U8(grid) => (
                grid.map(|&v| f32::from(v)).map_err(|e| solid_error(e.into()))?,
                Some(options.iso.unwrap_or(127.5)),
            ),
        };
        let values = if options.fit { fitted(&values).map_err(|e| solid_error(e.into()))? } else { values };
        let solid = match iso {
            Some(iso) => Solid::level_volume(&values, iso),
            None => Solid::volume(values),
        };
        return Ok((solid.map_err(solid_error)?, Vec::new()));
    }
    Err(InputError::Unknown { spec: spec.to_string(), names: builtin_names().join(", ") })
}

fn is_npy(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// The uniform scale and translation that centres `bounds` at the origin
/// with its longest side [`FIT_SIZE`].
fn fit_map(bounds: &Aabb) -> Affine3A {
    let scale = FIT_SIZE / bounds.size().max_element().max(f32::MIN_POSITIVE);
    Affine3A::from_scale_rotation_translation(Vec3::splat(scale), Quat::IDENTITY, -scale * bounds.center())
}

/// A volume fitted like a mesh: its lattice moved and scaled, its
/// distances scaled by the same factor (so a distance stays a distance).
fn fitted(values: &Grid3<f32>) -> Result<Grid3<f32>, isomorph_common::GridError> {
    let map = fit_map(&values.bounds());
    let scale = map.matrix3.x_axis.x;
    let data = values.data().iter().map(|v| v * scale).collect();
    Grid3::from_vec(values.dims(), map.transform_point3(values.origin()), values.spacing() * scale, data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::npy::save_npy;
    use isomorph_common::{Control, Field3, Shape};

    #[test]
    fn names_meshes_and_volumes_load() {
        assert_eq!(bunny().triangles.len(), 3674);
        for name in builtin_names() {
            load_solid(name, &LoadOptions::default()).unwrap();
        }
        assert!(matches!(
            load_solid("no-such-thing", &LoadOptions::default()),
            Err(InputError::Unknown { .. })
        ));

        // A signed distance volume round-trips through .npy and keeps or
        // fits its coordinates.
        let dir = std::env::temp_dir().join(format!("isomorph-inputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let grid = Grid3::sample_box(&Shape::sphere(2.0), &Aabb::cube(3.0), 25).unwrap();
        let path = dir.join("ball.npy");
        save_npy(&grid, &path).unwrap();
        let spec = path.to_str().unwrap();
        let kept = load_solid(spec, &LoadOptions { fit: false, iso: None }).unwrap();
        assert_eq!(kept.kind(), "distance volume");
        let d = kept.distance_field(0, &Control::new()).unwrap();
        assert!((d.value(Vec3::ZERO) - 2.0).abs() < 1e-5);
        let fit = load_solid(spec, &LoadOptions::default()).unwrap();
        let d = fit.distance_field(0, &Control::new()).unwrap();
        // The box [-3, 3]³ becomes [-0.45, 0.45]³: the radius 2 becomes 0.3.
        assert!((d.value(Vec3::ZERO) - 0.3).abs() < 1e-5, "{}", d.value(Vec3::ZERO));
        // As a level set at 1: the ball of radius 1.
        let level = load_solid(spec, &LoadOptions { fit: false, iso: Some(1.0) }).unwrap();
        let d = level.distance_field(0, &Control::new()).unwrap();
        assert!((d.value(Vec3::ZERO) - 1.0).abs() < 0.05, "{}", d.value(Vec3::ZERO));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
