//! Headerless `.raw` volumes: values only, x fastest, then y, then z, with
//! the node counts and the value type given by the caller (the file has no
//! header to say them).
//!
//! The volume sits at the origin with unit spacing (voxel units); callers
//! place it (e.g. [`crate::inputs::load_solid`] fits it like a mesh).
//!
//! ```
//! use isomorph_common::glam::UVec3;
//! use isomorph_io::npy::Volume;
//! use isomorph_io::raw::{RawLayout, RawType, read_raw};
//!
//! let layout = RawLayout { dims: UVec3::new(2, 2, 2), value: RawType::U8 };
//! let Volume::U8(grid) = read_raw(&[0, 0, 0, 0, 255, 255, 255, 255][..], layout, "eight.raw")? else {
//!     unreachable!()
//! };
//! assert_eq!(grid.get(1, 1, 1), Some(&255)); // the upper z slice is material
//! let short = read_raw(&[0u8; 7][..], layout, "seven.raw").unwrap_err();
//! assert_eq!(short.to_string(), "seven.raw: 7 bytes, but 2×2×2 u8 values need 8");
//! # Ok::<(), isomorph_io::raw::RawError>(())
//! ```

use crate::npy::Volume;
use glam::{UVec3, Vec3};
use isomorph_common::{Grid3, GridError, MemoryLimitError, reserve_memory};
use std::fmt;
use std::io::{self, Read};
use std::path::Path;

/// The value type of a `.raw` volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RawType {
    /// Bytes: densities 0–255, material at 255, surface at 127.5 (True's
    /// convention).
    U8,
    /// Little-endian `f32`: a field, positive inside, surface at 0 unless a
    /// level is given.
    F32,
}

impl RawType {
    /// Bytes per value.
    pub fn size(self) -> u64 {
        match self {
            RawType::U8 => 1,
            RawType::F32 => 4,
        }
    }
}

impl fmt::Display for RawType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RawType::U8 => "u8",
            RawType::F32 => "f32",
        })
    }
}

/// What the caller says of a `.raw` file: node counts and value type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawLayout {
    /// Nodes along x, y, z (each at least 2).
    pub dims: UVec3,
    /// The value type.
    pub value: RawType,
}

impl RawLayout {
    /// The file size this layout needs, `None` when it exceeds `u64`.
    pub fn bytes(&self) -> Option<u64> {
        [self.dims.y, self.dims.z]
            .into_iter()
            .try_fold(u64::from(self.dims.x), |n, d| n.checked_mul(u64::from(d)))
            .and_then(|n| n.checked_mul(self.value.size()))
    }
}

/// Errors of [`read_raw`] and [`load_raw`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RawError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The file's length is not what the layout needs.
    #[error("{path}: {bytes} bytes, but {}×{}×{} {value} values need {}", dims.x, dims.y, dims.z,
        needed.map_or("more than 2^64".to_string(), |n| n.to_string()))]
    Size {
        /// The file.
        path: String,
        /// Its length.
        bytes: u64,
        /// The layout's node counts.
        dims: UVec3,
        /// The layout's value type.
        value: RawType,
        /// The length the layout needs (`None`: more than `u64` holds).
        needed: Option<u64>,
    },
    /// The values do not fit the memory limit.
    #[error(transparent)]
    Memory(#[from] MemoryLimitError),
    /// The node counts make no grid (fewer than 2 along an axis).
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// Reads a `.raw` volume of `layout` from `reader` (`path` names it in
/// errors), checking the length against the layout and the memory limit
/// before allocating the grid.
///
/// # Errors
/// [`RawError::Size`] when the data is shorter or longer than the layout
/// needs, [`RawError::Memory`], [`RawError::Grid`] for dims below 2,
/// [`RawError::Io`].
pub fn read_raw(reader: impl Read, layout: RawLayout, path: &str) -> Result<Volume, RawError> {
    if layout.dims.min_element() < 2 {
        return Err(GridError::TooSmall { dims: layout.dims, min: 2 }.into());
    }
    let needed = layout.bytes();
    let size_error =
        |bytes| RawError::Size { path: path.into(), bytes, dims: layout.dims, value: layout.value, needed };
    // A layout beyond the address space cannot fit the memory limit.
    let need = needed.and_then(|n| usize::try_from(n).ok()).unwrap_or(usize::MAX);
    // The bytes plus the f32 grid the caller makes of them.
    let values = need / layout.value.size() as usize;
    reserve_memory(
        || format!("the .raw volume {path}"),
        need.saturating_add(values.saturating_mul(4)),
        "read a smaller volume",
    )?;
    let mut bytes = Vec::with_capacity(need);
    // One byte more than needed shows a longer file without reading it all.
    reader
        .take(need as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| RawError::Io { path: path.into(), source })?;
    if bytes.len() != need {
        return Err(size_error(bytes.len() as u64));
    }
    let (origin, spacing) = (Vec3::ZERO, 1.0);
    Ok(match layout.value {
        RawType::U8 => Volume::U8(Grid3::from_vec(layout.dims, origin, spacing, bytes)?),
        RawType::F32 => {
            let values =
                bytes.chunks_exact(4).map(|v| f32::from_le_bytes([v[0], v[1], v[2], v[3]])).collect();
            Volume::F32(Grid3::from_vec(layout.dims, origin, spacing, values)?)
        }
    })
}

/// Reads the `.raw` file at `path` (see [`read_raw`]); its length is
/// compared with the layout before anything is read.
///
/// # Errors
/// As [`read_raw`].
pub fn load_raw(path: &Path, layout: RawLayout) -> Result<Volume, RawError> {
    let name = path.display().to_string();
    let io_error = |source| RawError::Io { path: name.clone(), source };
    let file = std::fs::File::open(path).map_err(io_error)?;
    let bytes = file.metadata().map_err(io_error)?.len();
    if layout.bytes() != Some(bytes) {
        return Err(RawError::Size {
            path: name,
            bytes,
            dims: layout.dims,
            value: layout.value,
            needed: layout.bytes(),
        });
    }
    read_raw(io::BufReader::new(file), layout, &name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_values_are_little_endian_x_fastest() {
        let values: Vec<f32> = (0..12).map(|i| i as f32 - 5.5).collect();
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let layout = RawLayout { dims: UVec3::new(3, 2, 2), value: RawType::F32 };
        let Volume::F32(grid) = read_raw(&bytes[..], layout, "x.raw").unwrap() else { panic!("f32 volume") };
        assert_eq!(grid.get(2, 1, 1), Some(&5.5));
        assert_eq!(grid.get(1, 0, 1), Some(&1.5));
    }

    #[test]
    fn wrong_lengths_and_absurd_dims_are_errors() {
        let layout = RawLayout { dims: UVec3::new(2, 2, 2), value: RawType::F32 };
        let long = read_raw(&[0u8; 33][..], layout, "long.raw").unwrap_err();
        assert_eq!(long.to_string(), "long.raw: 33 bytes, but 2×2×2 f32 values need 32");
        let huge = RawLayout { dims: UVec3::splat(u32::MAX), value: RawType::F32 };
        assert!(matches!(read_raw(&[0u8; 4][..], huge, "huge.raw"), Err(RawError::Memory(_))));
        let big = RawLayout { dims: UVec3::splat(1 << 16), value: RawType::U8 };
        assert!(matches!(read_raw(&[0u8; 4][..], big, "big.raw"), Err(RawError::Memory(_))));
        let flat = RawLayout { dims: UVec3::new(4, 4, 1), value: RawType::U8 };
        assert!(matches!(read_raw(&[0u8; 16][..], flat, "flat.raw"), Err(RawError::Grid(_))));
    }

    #[test]
    fn load_checks_the_file_length_first() {
        let dir = std::env::temp_dir().join(format!("isomorph-raw-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("cube.raw");
        std::fs::write(&path, [7u8; 27]).unwrap();
        let layout = RawLayout { dims: UVec3::splat(3), value: RawType::U8 };
        assert_eq!(load_raw(&path, layout).unwrap().dims(), UVec3::splat(3));
        let wrong = RawLayout { dims: UVec3::splat(4), value: RawType::U8 };
        assert!(matches!(load_raw(&path, wrong), Err(RawError::Size { bytes: 27, needed: Some(64), .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
