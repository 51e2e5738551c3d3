//! Input solids from what a user types ([`load_solid`]): a built-in shape
//! name, the built-in Stanford bunny, a mesh file (OBJ, PLY, STL), a
//! `.npy` volume with its JSON sidecar or a headerless `.raw` volume.
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
use crate::raw::{RawError, RawLayout, load_raw};
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
    /// The node counts and value type of headerless `.raw` volumes (which
    /// cannot say them); `None` refuses `.raw` inputs.
    pub raw: Option<RawLayout>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { fit: true, iso: None, raw: None }
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
    /// A `.raw` volume could not be read.
    #[error(transparent)]
    Raw(#[from] RawError),
    /// A `.raw` volume was given without its layout ([`LoadOptions::raw`]).
    #[error(
        "{spec}: a headerless .raw volume needs its node counts and value type (on the command line: --raw-dims NX,NY,NZ and --raw-type u8|f32)"
    )]
    RawLayoutMissing {
        /// What was given.
        spec: String,
    },
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

/// The sRGB colour (components in `[0, 1]`) of an input without vertex
/// colours that is not a built-in shape, when frames are coloured: a light
/// grey.
pub const UNCOLORED: Vec3 = Vec3::splat(0.75);

/// The colour a built-in input (`isomorph_common::models` names and
/// `bunny`) shows when frames are coloured (sRGB, components in `[0, 1]`);
/// `None` for other names. Each shape has its own, so that a morph between
/// two built-ins shows which colour came from where:
///
/// | shape | colour | | shape | colour |
/// |---|---|---|---|---|
/// | sphere | brick red (0.85, 0.33, 0.25) | | mug | cream (0.9, 0.82, 0.62) |
/// | torus | sky blue (0.25, 0.55, 0.85) | | chain | steel (0.55, 0.6, 0.68) |
/// | ball | amber (0.95, 0.7, 0.2) | | cube | purple (0.55, 0.35, 0.7) |
/// | c-shape | green (0.3, 0.7, 0.4) | | holed-cube | teal (0.2, 0.65, 0.65) |
/// | bunny | fawn (0.8, 0.6, 0.45) | | apple | apple red (0.75, 0.15, 0.15) |
pub fn builtin_color(name: &str) -> Option<Vec3> {
    let [r, g, b] = match name {
        "sphere" => [0.85, 0.33, 0.25],
        "torus" => [0.25, 0.55, 0.85],
        "ball" => [0.95, 0.7, 0.2],
        "c-shape" => [0.3, 0.7, 0.4],
        "mug" => [0.9, 0.82, 0.62],
        "chain" => [0.55, 0.6, 0.68],
        "cube" => [0.55, 0.35, 0.7],
        "holed-cube" => [0.2, 0.65, 0.65],
        "apple" => [0.75, 0.15, 0.15],
        BUNNY => [0.8, 0.6, 0.45],
        _ => return None,
    };
    Some(Vec3::new(r, g, b))
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
/// names), `bunny`, a mesh file (`.obj`, `.ply`, `.stl`), a `.npy`
/// volume (placed by its JSON sidecar, see [`crate::npy`]) or a `.raw`
/// volume of the layout [`LoadOptions::raw`] (voxel units, see
/// [`crate::raw`]). Volumes are signed distances (positive inside) or,
/// with [`LoadOptions::iso`] and for u8 values, levels of a density.
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
    let mut warnings = Vec::new();
    let volume = if !path.is_file() {
        None
    } else if has_extension(path, "npy") {
        let sidecar = crate::npy::sidecar_path(path);
        if !sidecar.is_file() {
            warnings.push(format!(
                "no sidecar {}: the volume is placed in voxel units (spacing 1) with its first voxel at the origin",
                sidecar.display()
            ));
        }
        Some(load_npy(path)?)
    } else if has_extension(path, "raw") {
        let layout = options.raw.ok_or_else(|| InputError::RawLayoutMissing { spec: spec.to_string() })?;
        Some(load_raw(path, layout)?)
    } else {
        None
    };
    if let Some(volume) = volume {
        // A density's level is kept as it is; a distance scales with the lattice.
        let (values, iso) = match volume {
            Volume::F32(grid) => (grid, options.iso),
            Volume::U8(grid) => (
                grid.map(|&v| f32::from(v)).map_err(|e| solid_error(e.into()))?,
                Some(options.iso.unwrap_or(127.5)),
            ),
        };
        let values = match options.fit {
            true => fitted(&values, iso.is_none()).map_err(|e| solid_error(e.into()))?,
            false => values,
        };
        let solid = match iso {
            Some(iso) => Solid::level_volume(&values, iso),
            None => Solid::volume(values),
        };
        return Ok((solid.map_err(solid_error)?, warnings));
    }
    if spec == BUNNY || path.is_file() {
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
    Err(InputError::Unknown { spec: spec.to_string(), names: builtin_names().join(", ") })
}

fn has_extension(path: &Path, extension: &str) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case(extension))
}

/// The uniform scale and translation that centres `bounds` at the origin
/// with its longest side [`FIT_SIZE`].
fn fit_map(bounds: &Aabb) -> Affine3A {
    let scale = FIT_SIZE / bounds.size().max_element().max(f32::MIN_POSITIVE);
    Affine3A::from_scale_rotation_translation(Vec3::splat(scale), Quat::IDENTITY, -scale * bounds.center())
}

/// A volume fitted like a mesh: its lattice moved and scaled, and, when
/// `distances`, its values scaled by the same factor (so a distance stays a
/// distance; a density keeps its level).
fn fitted(values: &Grid3<f32>, distances: bool) -> Result<Grid3<f32>, isomorph_common::GridError> {
    let map = fit_map(&values.bounds());
    let scale = if distances { map.matrix3.x_axis.x } else { 1.0 };
    let data = values.data().iter().map(|v| v * scale).collect();
    let spacing = values.spacing() * map.matrix3.x_axis.x;
    Grid3::from_vec(values.dims(), map.transform_point3(values.origin()), spacing, data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::npy::save_npy;
    use isomorph_common::{Control, Field3, Shape};

    #[test]
    fn every_builtin_has_its_own_colour() {
        let colors: Vec<Vec3> = builtin_names().iter().map(|n| builtin_color(n).expect(n)).collect();
        for (i, a) in colors.iter().enumerate() {
            assert!(a.cmpge(Vec3::ZERO).all() && a.cmple(Vec3::ONE).all(), "{a}");
            assert!(colors[..i].iter().all(|b| (*a - *b).abs().max_element() > 0.05), "{a} repeats");
        }
        assert_eq!(builtin_color("teapot.ply"), None);
    }

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
        let kept = load_solid(spec, &LoadOptions { fit: false, ..LoadOptions::default() }).unwrap();
        assert_eq!(kept.kind(), "distance volume");
        let d = kept.distance_field(0, &Control::new()).unwrap();
        assert!((d.value(Vec3::ZERO) - 2.0).abs() < 1e-5);
        let fit = load_solid(spec, &LoadOptions::default()).unwrap();
        let d = fit.distance_field(0, &Control::new()).unwrap();
        // The box [-3, 3]³ becomes [-0.45, 0.45]³: the radius 2 becomes 0.3.
        assert!((d.value(Vec3::ZERO) - 0.3).abs() < 1e-5, "{}", d.value(Vec3::ZERO));
        // As a level set at 1: the ball of radius 1.
        let level =
            load_solid(spec, &LoadOptions { fit: false, iso: Some(1.0), ..LoadOptions::default() }).unwrap();
        let d = level.distance_field(0, &Control::new()).unwrap();
        assert!((d.value(Vec3::ZERO) - 1.0).abs() < 0.05, "{}", d.value(Vec3::ZERO));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A u8 density ball of radius `r` voxels in an `n³` `.raw` file, with
    /// True's two-voxel ramp (64 levels per voxel around 127.5).
    fn density_ball(dir: &Path, n: u32, r: f32) -> std::path::PathBuf {
        let c = (n - 1) as f32 / 2.0;
        let bytes: Vec<u8> = (0..n * n * n)
            .map(|i| {
                let p = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
                (127.5 + 64.0 * (r - p.distance(Vec3::splat(c)))).clamp(0.0, 255.0) as u8
            })
            .collect();
        let path = dir.join("ball.raw");
        std::fs::write(&path, bytes).unwrap();
        path
    }

    #[test]
    fn raw_densities_load_kept_and_fitted() {
        let dir = std::env::temp_dir().join(format!("isomorph-inputs-raw-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = density_ball(&dir, 33, 10.0);
        let spec = path.to_str().unwrap();
        assert!(matches!(
            load_solid(spec, &LoadOptions::default()),
            Err(InputError::RawLayoutMissing { .. })
        ));
        let raw = Some(RawLayout { dims: glam::UVec3::splat(33), value: crate::raw::RawType::U8 });
        let kept = load_solid(spec, &LoadOptions { fit: false, raw, ..LoadOptions::default() }).unwrap();
        let centre = kept.distance_field(0, &Control::new()).unwrap().value(Vec3::splat(16.0));
        assert!((centre - 10.0).abs() < 0.3, "kept: {centre} voxels, not 10");
        // Fitted, the 32-voxel box becomes 0.9 wide: the level stays at
        // 127.5 and the radius becomes 10 · 0.9 / 32.
        let fitted = load_solid(spec, &LoadOptions { raw, ..LoadOptions::default() }).unwrap();
        let centre = fitted.distance_field(0, &Control::new()).unwrap().value(Vec3::ZERO);
        let expected = 10.0 * 0.9 / 32.0;
        assert!((centre - expected).abs() < 0.01, "fitted: {centre}, not {expected}");
        let wrong = Some(RawLayout { dims: glam::UVec3::splat(32), value: crate::raw::RawType::U8 });
        let err = load_solid(spec, &LoadOptions { raw: wrong, ..LoadOptions::default() }).unwrap_err();
        assert!(err.to_string().contains("35937 bytes, but 32×32×32 u8 values need 32768"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
