//! Writing a [`Grid3<f32>`] as a NumPy `.npy` array plus a JSON sidecar with
//! its placement in the world, and reading `.npy` volumes back
//! ([`load_npy`]: f32, f64 or u8 values, C or Fortran order).
//!
//! The format is a short text header and raw values, so it is read and
//! written here directly rather than through a dependency.
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
//! use isomorph_common::{Aabb, Grid3, Shape};
//! use isomorph_io::npy;
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

use glam::{UVec3, Vec3};
use isomorph_common::{Grid3, GridError};
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

/// Errors of [`save_npy`] and [`load_npy`].
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
    /// A file is not a `.npy` volume this reader understands.
    #[error("{path}: {reason}")]
    Format {
        /// The file being read.
        path: PathBuf,
        /// What is wrong, and what is accepted.
        reason: String,
    },
    /// The volume does not fit the memory limit or has too few nodes.
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// A volume read from a `.npy` file.
#[derive(Debug, Clone, PartialEq)]
pub enum Volume {
    /// Floating-point values (`<f4`, `<f8` or `>f4`/`>f8`, converted to
    /// f32): a field, positive inside, surface at 0 unless stated otherwise.
    F32(Grid3<f32>),
    /// Bytes (`|u1`): densities 0–255, material at 255, surface at 127.5
    /// (True's convention).
    U8(Grid3<u8>),
}

impl Volume {
    /// Node counts along x, y, z.
    pub fn dims(&self) -> UVec3 {
        match self {
            Volume::F32(g) => g.dims(),
            Volume::U8(g) => g.dims(),
        }
    }
}

/// Element types [`read_npy`] accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dtype {
    F32 { little: bool },
    F64 { little: bool },
    U8,
}

impl Dtype {
    fn parse(descr: &str) -> Option<Self> {
        Some(match descr {
            "<f4" => Dtype::F32 { little: true },
            ">f4" => Dtype::F32 { little: false },
            "<f8" => Dtype::F64 { little: true },
            ">f8" => Dtype::F64 { little: false },
            "|u1" | "<u1" | ">u1" => Dtype::U8,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Dtype::F32 { .. } => 4,
            Dtype::F64 { .. } => 8,
            Dtype::U8 => 1,
        }
    }
}

/// The value of `key` in a NumPy header dict (`'key': value`), up to the
/// next top-level comma.
fn header_entry<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let start = header.find(&format!("'{key}'"))? + key.len() + 2;
    let rest = header[start..].trim_start().strip_prefix(':')?.trim_start();
    let end = if rest.starts_with('(') { rest.find(')')? + 1 } else { rest.find([',', '}'])? };
    Some(rest[..end].trim())
}

/// Parses `.npy` bytes into a volume on the lattice `origin`, `spacing`.
///
/// The array must be three-dimensional. In C order, shape `(nz, ny, nx)`
/// (the last axis fastest, as [`write_npy`] writes); in Fortran order, shape
/// `(nx, ny, nz)` (the first axis fastest). Either way grid x is the fastest
/// axis, so the bytes are used in place.
///
/// Every size derived from the header (header length, value count, byte
/// count) is computed with checked arithmetic: a header claiming more than
/// fits is a [`NpyError::Format`], never a wrapped product.
///
/// # Errors
/// [`NpyError::Format`] (`path` names the source) for a bad magic string,
/// version, header, dtype, shape (including one whose size overflows) or
/// length; [`NpyError::Grid`] for memory.
pub fn read_npy(bytes: &[u8], origin: Vec3, spacing: f32, path: &Path) -> Result<Volume, NpyError> {
    let bad = |reason: String| NpyError::Format { path: path.to_path_buf(), reason };
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err(bad("not a .npy file (no \\x93NUMPY magic)".into()));
    }
    let (header_start, header_len) = match bytes[6] {
        1 => (10, usize::from(u16::from_le_bytes([bytes[8], bytes[9]]))),
        2 | 3 if bytes.len() >= 12 => {
            (12, u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize)
        }
        v => return Err(bad(format!(".npy format version {v} is not supported (1, 2 or 3)"))),
    };
    let data_start = usize::checked_add(header_start, header_len)
        .ok_or_else(|| bad(format!("header length {header_len} overflows")))?;
    let header = bytes
        .get(header_start..data_start)
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or_else(|| bad("truncated or non-text header".into()))?;
    let descr = header_entry(header, "descr").map(|d| d.trim_matches(['\'', '"']));
    let dtype = descr
        .and_then(Dtype::parse)
        .ok_or_else(|| bad(format!("dtype {descr:?} is not supported (f4, f8 or u1)")))?;
    let fortran = match header_entry(header, "fortran_order") {
        Some("False") => false,
        Some("True") => true,
        other => return Err(bad(format!("fortran_order {other:?} is not True or False"))),
    };
    let shape: Vec<u32> = header_entry(header, "shape")
        .map(|s| s.trim_matches(['(', ')']).split(',').filter(|t| !t.trim().is_empty()))
        .ok_or_else(|| bad("no shape in the header".into()))?
        .map(|t| t.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|e| bad(format!("bad shape: {e}")))?;
    let [a, b, c] = shape[..] else {
        return Err(bad(format!("the array has shape {shape:?}; a volume needs three axes")));
    };
    let dims = if fortran { UVec3::new(a, b, c) } else { UVec3::new(c, b, a) };
    let count = u64::from(a).checked_mul(u64::from(b)).and_then(|ab| ab.checked_mul(u64::from(c)));
    let size = count.and_then(|n| n.checked_mul(dtype.size() as u64));
    let (Some(count), Some(size)) = (count, size) else {
        return Err(bad(format!(
            "shape {shape:?} of {}-byte values holds more than 2^64 bytes",
            dtype.size()
        )));
    };
    let data = &bytes[data_start..];
    if data.len() as u64 != size {
        return Err(bad(format!("{} data bytes for {count} values of {} bytes", data.len(), dtype.size())));
    }
    let requested = usize::try_from(count).ok().and_then(|n| n.checked_mul(4)).unwrap_or(usize::MAX);
    if requested > isomorph_common::memory_limit() {
        return Err(GridError::TooLarge { dims, requested, limit: isomorph_common::memory_limit() }.into());
    }
    Ok(match dtype {
        Dtype::U8 => Volume::U8(Grid3::from_vec(dims, origin, spacing, data.to_vec())?),
        Dtype::F32 { little } => {
            let values = data
                .chunks_exact(4)
                .map(|v| {
                    let v = [v[0], v[1], v[2], v[3]];
                    if little { f32::from_le_bytes(v) } else { f32::from_be_bytes(v) }
                })
                .collect();
            Volume::F32(Grid3::from_vec(dims, origin, spacing, values)?)
        }
        Dtype::F64 { little } => {
            let values = data
                .chunks_exact(8)
                .map(|v| {
                    let v: [u8; 8] = v.try_into().expect("chunks of 8");
                    (if little { f64::from_le_bytes(v) } else { f64::from_be_bytes(v) }) as f32
                })
                .collect();
            Volume::F32(Grid3::from_vec(dims, origin, spacing, values)?)
        }
    })
}

/// Reads a `.npy` volume (see [`read_npy`]). Its placement comes from the
/// [`NpyMetadata`] sidecar when one exists (as [`save_npy`] writes it), else
/// the volume sits at the origin with unit spacing (voxel units).
///
/// # Errors
/// [`NpyError::Io`] for unreadable files, [`NpyError::Format`] for a
/// malformed array or sidecar or one whose dims disagree, and
/// [`NpyError::Grid`] for memory.
pub fn load_npy(path: &Path) -> Result<Volume, NpyError> {
    let io_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| NpyError::Io { path, source }
    };
    let bytes = std::fs::read(path).map_err(io_error(path))?;
    let sidecar = sidecar_path(path);
    let meta: Option<NpyMetadata> = match std::fs::read(&sidecar) {
        Ok(json) => Some(serde_json::from_slice(&json).map_err(|e| NpyError::Format {
            path: sidecar.clone(),
            reason: format!("not an isomorph sidecar: {e}"),
        })?),
        Err(_) => None,
    };
    let (origin, spacing) = meta.as_ref().map_or((Vec3::ZERO, 1.0), |m| (Vec3::from(m.origin), m.spacing));
    if !(origin.is_finite() && spacing.is_finite() && spacing > 0.0) {
        return Err(NpyError::Format {
            path: sidecar,
            reason: "origin or spacing is not finite and positive".into(),
        });
    }
    let volume = read_npy(&bytes, origin, spacing, path)?;
    if let Some(m) = meta
        && UVec3::from(m.dims) != volume.dims()
    {
        return Err(NpyError::Format {
            path: sidecar,
            reason: format!("the sidecar says dims {:?}, the array has {}", m.dims, volume.dims()),
        });
    }
    Ok(volume)
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

    #[test]
    fn read_gives_back_what_write_wrote() {
        let dims = UVec3::new(4, 3, 2);
        let data: Vec<f32> = (0..24).map(|v| v as f32 * 0.25 - 1.0).collect();
        let grid = Grid3::from_vec(dims, Vec3::new(-1.0, 0.5, 2.0), 0.25, data).unwrap();
        let mut bytes = Vec::new();
        write_npy(&grid, &mut bytes).unwrap();
        let here = Path::new("mem.npy");
        let Volume::F32(back) = read_npy(&bytes, grid.origin(), 0.25, here).unwrap() else { panic!("f32") };
        assert_eq!(back, grid);
        // Truncated data, a 2D shape and an unknown dtype are refused.
        assert!(matches!(
            read_npy(&bytes[..bytes.len() - 1], Vec3::ZERO, 1.0, here),
            Err(NpyError::Format { .. })
        ));
        assert!(matches!(read_npy(b"not numpy at all", Vec3::ZERO, 1.0, here), Err(NpyError::Format { .. })));
        let other = |dict: &str, data: &[u8]| read_npy(&npy_bytes(dict, data), Vec3::ZERO, 1.0, here);
        let flat = other("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", &[0; 24]);
        assert!(matches!(flat, Err(NpyError::Format { reason, .. }) if reason.contains("three axes")));
        let complex = other("{'descr': '<c8', 'fortran_order': False, 'shape': (1, 1, 1), }", &[0; 8]);
        assert!(matches!(complex, Err(NpyError::Format { reason, .. }) if reason.contains("dtype")));
        // Fortran-order bytes: shape (nx, ny, nz), x fastest.
        let bytes: Vec<u8> = (0..24).collect();
        let Ok(Volume::U8(g)) =
            other("{'descr': '|u1', 'fortran_order': True, 'shape': (4, 3, 2), }", &bytes)
        else {
            panic!("u8 Fortran volume")
        };
        assert_eq!(g.dims(), dims);
        assert_eq!(*g.get(3, 2, 1).unwrap(), 23);
        // Big-endian f8 is converted.
        let be: Vec<u8> = (0..8).flat_map(|v| (f64::from(v) * 0.5).to_be_bytes()).collect();
        let Ok(Volume::F32(g)) = other("{'descr': '>f8', 'fortran_order': False, 'shape': (2, 2, 2), }", &be)
        else {
            panic!("f64 volume")
        };
        assert_eq!(*g.get(1, 1, 1).unwrap(), 3.5);
    }

    /// `.npy` version 1.0 bytes with header `dict` and `data`.
    fn npy_bytes(dict: &str, data: &[u8]) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[1, 0]);
        b.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        b.extend_from_slice(dict.as_bytes());
        b.extend_from_slice(data);
        b
    }

    #[test]
    fn huge_shapes_are_refused_without_overflow() {
        let here = Path::new("huge.npy");
        // The value or byte counts of these shapes pass u64: the old
        // products wrapped in release builds and panicked in debug builds.
        for (descr, shape) in [
            ("<f8", "(4294967295, 4294967295, 4294967295)"),
            ("<f4", "(4294967295, 4294967295, 2)"),
            ("<f8", "(2147483648, 2147483648, 4)"),
            ("|u1", "(4294967295, 4294967295, 4294967295)"),
        ] {
            let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
            match read_npy(&npy_bytes(&dict, &[0; 16]), Vec3::ZERO, 1.0, here) {
                Err(NpyError::Format { reason, .. }) => assert!(reason.contains("2^64"), "{shape}: {reason}"),
                other => panic!("{shape}: {other:?}"),
            }
        }
        // 2^62 values of 4 bytes: the byte count 2^64 wrapped to 0, which
        // matched empty data.
        let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2147483648, 2147483648, 1), }";
        assert!(matches!(
            read_npy(&npy_bytes(dict, &[]), Vec3::ZERO, 1.0, here),
            Err(NpyError::Format { .. })
        ));
        // Version 3 header length near u32::MAX points past the data.
        let mut v3 = MAGIC.to_vec();
        v3.extend_from_slice(&[3, 0]);
        v3.extend_from_slice(&u32::MAX.to_le_bytes());
        v3.extend_from_slice(b"{}");
        assert!(matches!(read_npy(&v3, Vec3::ZERO, 1.0, here), Err(NpyError::Format { .. })));
    }

    #[test]
    fn load_uses_the_sidecar_placement() {
        let dir = std::env::temp_dir().join(format!("isomorph-npy-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("sphere.npy");
        let grid =
            Grid3::sample_box(&isomorph_common::Shape::sphere(0.3), &isomorph_common::Aabb::cube(0.5), 9)
                .unwrap();
        save_npy(&grid, &path).unwrap();
        assert_eq!(load_npy(&path).unwrap(), Volume::F32(grid.clone()));
        // Without the sidecar: voxel units at the origin.
        std::fs::remove_file(sidecar_path(&path)).unwrap();
        let Volume::F32(bare) = load_npy(&path).unwrap() else { panic!("f32") };
        assert_eq!((bare.origin(), bare.spacing(), bare.data()), (Vec3::ZERO, 1.0, grid.data()));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
