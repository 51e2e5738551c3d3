//! Writing a [`Grid3<f32>`] as a NumPy `.npy` array plus a JSON sidecar with
//! its placement in the world.
//!
//! # Layout
//! The `.npy` file (format version 1.0) holds the values as little-endian
//! `f32` (`'<f4'`) in C order with shape `(nz, ny, nx)`: **x varies fastest**,
//! exactly the grid's own storage order, so the bytes are written as they are.
//! In NumPy, `a = np.load("f.npy")` gives `a[k, j, i]` = the value at node
//! `(i, j, k)`, whose world position is `origin + spacing · (i, j, k)`.
//!
//! The sidecar (`f.json` next to `f.npy`, see [`sidecar_path`]) is a
//! [`NpyMetadata`]: origin, spacing, dims, the array shape and axis order and
//! the sign convention (**positive inside**, as every field in isomorph).
//!
//! # Example
//! ```
//! use isomorph_common::{Aabb, Grid3, Shape, npy};
//! let grid = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 9)?;
//! let mut bytes = Vec::new();
//! npy::write_npy(&grid, &mut bytes)?;
//! assert_eq!(&bytes[..6], b"\x93NUMPY");
//! let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
//! let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
//! assert!(header.contains("'shape': (9, 9, 9)"));
//! // The values follow the header, x fastest: the centre node is inside.
//! let centre = 10 + header_len + 4 * grid.index(4, 4, 4);
//! let v = f32::from_le_bytes(bytes[centre..centre + 4].try_into().unwrap());
//! assert!((v - 0.3).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::Grid3;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The `.npy` magic string.
const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The preamble and header together are padded to a multiple of this many
/// bytes, as NumPy does, so the data starts aligned.
const ALIGNMENT: usize = 64;

/// Values per chunk when converting to little-endian bytes.
const CHUNK: usize = 1 << 14;

/// Errors of [`save_npy`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NpyError {
    /// Creating or writing a file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The sidecar could not be serialized.
    #[error("cannot serialize the sidecar of {path}: {source}")]
    Json {
        /// The sidecar file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: serde_json::Error,
    },
}

/// The JSON sidecar of a `.npy` grid: how its array maps to the world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NpyMetadata {
    /// NumPy dtype of the values: always `"<f4"` (little-endian f32).
    pub dtype: String,
    /// Array shape in C order: `[nz, ny, nx]`.
    pub shape: [u32; 3],
    /// Grid axis of each array axis: always `"zyx"` (the last array axis, x,
    /// varies fastest).
    pub axis_order: String,
    /// Node counts along x, y, z.
    pub dims: [u32; 3],
    /// World position of node `(0, 0, 0)`, i.e. of `array[0, 0, 0]` (x, y, z;
    /// world units).
    pub origin: [f32; 3],
    /// Distance between neighbouring nodes along every axis (world units).
    pub spacing: f32,
    /// Sign convention: always `"positive inside"` (values are positive
    /// inside the shape, zero on its surface, negative outside).
    pub sign: String,
}

impl NpyMetadata {
    /// The sidecar describing `grid`.
    pub fn of(grid: &Grid3<f32>) -> Self {
        let d = grid.dims();
        NpyMetadata {
            dtype: "<f4".into(),
            shape: [d.z, d.y, d.x],
            axis_order: "zyx".into(),
            dims: d.to_array(),
            origin: grid.origin().to_array(),
            spacing: grid.spacing(),
            sign: "positive inside".into(),
        }
    }
}

/// The `.npy` version 1.0 preamble and header for a C-order little-endian
/// f32 array of `shape`, padded with spaces and ended by a newline so that
/// its length is a multiple of 64.
pub fn npy_header(shape: [u32; 3]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}, {}), }}",
        shape[0], shape[1], shape[2]
    );
    // magic (6) + version (2) + header length (2) + dict + padding + '\n'
    let unpadded = MAGIC.len() + 4 + dict.len() + 1;
    let total = unpadded.div_ceil(ALIGNMENT) * ALIGNMENT;
    let header_len = (total - MAGIC.len() - 4) as u16;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    out
}

/// Writes `grid` as a `.npy` array of shape `(nz, ny, nx)` (see the module
/// docs) to `writer`.
///
/// # Errors
/// Any error of `writer`.
pub fn write_npy(grid: &Grid3<f32>, mut writer: impl Write) -> io::Result<()> {
    let d = grid.dims();
    writer.write_all(&npy_header([d.z, d.y, d.x]))?;
    let mut bytes = Vec::with_capacity(4 * CHUNK.min(grid.len()));
    for chunk in grid.data().chunks(CHUNK) {
        bytes.clear();
        bytes.extend(chunk.iter().flat_map(|v| v.to_le_bytes()));
        writer.write_all(&bytes)?;
    }
    writer.flush()
}

/// The sidecar file of a `.npy` path: the same path with extension `.json`.
pub fn sidecar_path(npy: &Path) -> PathBuf {
    npy.with_extension("json")
}

/// Writes `grid` to `path` as `.npy` and its [`NpyMetadata`] (pretty JSON) to
/// [`sidecar_path`]`(path)`. Returns the sidecar's path.
///
/// # Errors
/// [`NpyError::Io`] when a file cannot be created or written,
/// [`NpyError::Json`] if the sidecar cannot be serialized.
pub fn save_npy(grid: &Grid3<f32>, path: &Path) -> Result<PathBuf, NpyError> {
    fn io_error(path: &Path) -> impl FnOnce(io::Error) -> NpyError {
        let path = path.to_path_buf();
        move |source| NpyError::Io { path, source }
    }
    let file = File::create(path).map_err(io_error(path))?;
    write_npy(grid, BufWriter::new(file)).map_err(io_error(path))?;
    let sidecar = sidecar_path(path);
    let json = serde_json::to_string_pretty(&NpyMetadata::of(grid))
        .map_err(|source| NpyError::Json { path: sidecar.clone(), source })?;
    std::fs::write(&sidecar, json + "\n").map_err(io_error(&sidecar))?;
    Ok(sidecar)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{UVec3, Vec3};

    /// Splits `.npy` bytes into (version, header text, data bytes).
    fn parse(bytes: &[u8]) -> ((u8, u8), &str, &[u8]) {
        assert_eq!(&bytes[..6], MAGIC);
        let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        ((bytes[6], bytes[7]), std::str::from_utf8(&bytes[10..10 + len]).unwrap(), &bytes[10 + len..])
    }

    #[test]
    fn header_is_numpy_v1_and_aligned() {
        for shape in [[1, 1, 1], [3, 4, 5], [1024, 999, 100_000]] {
            let h = npy_header(shape);
            assert_eq!(h.len() % ALIGNMENT, 0);
            let (version, text, rest) = parse(&h);
            assert_eq!(version, (1, 0));
            assert!(rest.is_empty());
            assert!(text.ends_with('\n'));
            let dict = format!(
                "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}, {}), }}",
                shape[0], shape[1], shape[2]
            );
            assert_eq!(text.trim_end(), dict);
        }
    }

    #[test]
    fn values_are_little_endian_x_fastest() {
        let dims = UVec3::new(4, 3, 2);
        let data = (0..24).map(|v| v as f32 * 0.5 - 3.0).collect();
        let grid = Grid3::from_vec(dims, Vec3::new(-1.0, 0.5, 2.0), 0.25, data).unwrap();
        let mut bytes = Vec::new();
        write_npy(&grid, &mut bytes).unwrap();
        let (_, text, values) = parse(&bytes);
        assert!(text.contains("'shape': (2, 3, 4)"), "{text}");
        assert_eq!(values.len(), 24 * 4);
        // array[k, j, i] sits at ((k * ny + j) * nx + i) * 4.
        for (k, j, i) in [(0, 0, 0), (1, 2, 3), (0, 1, 2), (1, 0, 1)] {
            let at = ((k * 3 + j) * 4 + i) * 4;
            let v = f32::from_le_bytes(values[at..at + 4].try_into().unwrap());
            assert_eq!(v, *grid.get(i as u32, j as u32, k as u32).unwrap());
        }
        assert_eq!(&values[4..8], &(-2.5f32).to_le_bytes());
    }

    #[test]
    fn save_writes_the_array_and_its_sidecar() {
        let dir = std::env::temp_dir().join(format!("isomorph-npy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("grid.npy");
        let grid = Grid3::new(UVec3::new(5, 2, 3), Vec3::new(0.1, -0.2, 0.3), 0.05, 1.5f32).unwrap();
        let sidecar = save_npy(&grid, &path).unwrap();
        assert_eq!(sidecar, dir.join("grid.json"));
        let bytes = std::fs::read(&path).unwrap();
        let (_, text, values) = parse(&bytes);
        assert!(text.contains("'shape': (3, 2, 5)"));
        assert!(values.chunks(4).all(|v| v == 1.5f32.to_le_bytes()));
        let meta: NpyMetadata = serde_json::from_slice(&std::fs::read(&sidecar).unwrap()).unwrap();
        assert_eq!(meta, NpyMetadata::of(&grid));
        assert_eq!((meta.shape, meta.dims, meta.spacing), ([3, 2, 5], [5, 2, 3], 0.05));
        assert_eq!(meta.origin, [0.1, -0.2, 0.3]);
        assert_eq!((meta.sign.as_str(), meta.axis_order.as_str()), ("positive inside", "zyx"));
        let missing = dir.join("no/such/dir/grid.npy");
        assert!(matches!(save_npy(&grid, &missing), Err(NpyError::Io { path, .. }) if path == missing));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
