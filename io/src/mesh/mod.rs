//! Reading and writing [`TriMesh`] as Wavefront OBJ, PLY (ASCII, binary
//! little- and big-endian) and STL (ASCII and binary).
//!
//! [`read_mesh`] picks the format from the file extension and, for PLY and
//! STL, the encoding from the content; [`read_mesh_from`] and the per-format
//! readers [`read_obj`], [`read_ply`] and [`read_stl`] parse any reader (for
//! example bytes in memory). [`read_mesh_with_warnings`] and
//! [`read_mesh_from_with_warnings`] also return what the reader accepted
//! but had to say ([`MeshRead`], [`ReadWarning`]); the other readers drop
//! those warnings. [`write_mesh`] and [`write_mesh_to`] write every
//! [`MeshFormat`].
//!
//! # What is kept
//! - Positions exactly (f32). Text formats are written with the shortest
//!   decimal that round-trips each `f32`, so every format round-trips
//!   positions bit for bit.
//! - Triangles; polygons are fan-triangulated (`0,i,i+1`) on read.
//! - Per-vertex colours (sRGB in `[0, 1]`, [`TriMesh::colors`]) in PLY
//!   (`red green blue`; written as `uchar`, so within 1/510) and OBJ (the
//!   common `v x y z r g b` extension, floats, written with the shortest
//!   round-tripping decimal). STL has none; they are not written there.
//! - Per-vertex normals in OBJ (`vn`, when every face corner names one and
//!   each vertex always gets the same one) and PLY (`nx ny nz`). Non-finite
//!   normals are dropped (the normals are then `None`), because they can be
//!   recomputed with [`TriMesh::compute_normals`].
//! - STL stores a triangle soup; the reader welds positions that differ by at
//!   most a tolerance `τ = min(4 ε M, 10⁻⁶ D)` per coordinate (4 `f32` ulps of
//!   the largest coordinate magnitude `M`, capped at a millionth of the
//!   bounding-box diagonal `D`; see [`read_stl`]), so a closed CAD part whose
//!   exporter left rounding noise (`2.4e-18` for `0`) reads back closed.
//!   Vertices are numbered in order of first appearance and keep their first
//!   occurrence's position; welds that were not bit-identical are reported
//!   ([`ReadWarning::StlWeldedWithinTolerance`]). Every `solid` of an ASCII
//!   STL is read. Face normals in STL are ignored on read and recomputed on
//!   write.
//! - What is not kept is said: OBJ geometry this reader does not build (`l`,
//!   `p`, curves, surfaces) and unknown statements, dropped normal or texture
//!   references, and data after the declared PLY elements or binary STL
//!   triangles, or after the last ASCII STL `endsolid`, each give a
//!   [`ReadWarning`].
//!
//! # Hostile input
//! Malformed, truncated or random input gives a [`MeshIoError`] naming the
//! problem and, where known, the line (OBJ, ASCII PLY, ASCII STL) or the byte
//! offset (binary formats); it never panics, and no claim in the data makes
//! a reader allocate beyond the data itself:
//! - Element counts from a header are checked against the bytes actually
//!   present before anything is allocated from them
//!   ([`MeshIoError::TooLarge`]); PLY and STL input is first read into
//!   memory, so allocation follows the real data, never a claim.
//! - OBJ is read line by line, a line holding at most
//!   [`OBJ_MAX_LINE_BYTES`] (4 MiB): a "line" without end (a huge file
//!   without line breaks, a device) is a [`MeshIoError::LineTooLong`] naming
//!   the line, not an unbounded buffer. Lines end at `\n`, `\r\n` or a
//!   lone `\r`; `\` at the end of a line joins the next one.
//! - Data that is not the format is refused rather than read as an empty
//!   mesh: OBJ with a control character (binary data) or in which no line is
//!   an OBJ statement; a PLY without `ply` first; a PLY header declaring an
//!   element, or a property of one element, twice, or an ASCII PLY record
//!   with more values than its properties take (columns would shift).
//! - STL encoding: binary when the size is exactly `84 + 50·n` for the
//!   header's count `n` (whatever the header text, `solid` included); ASCII
//!   when it starts with `solid` and is text (bytes that are not UTF-8 are
//!   fine, e.g. in names); binary otherwise. A binary file with trailing
//!   bytes is read with a warning that says whether those bytes look like
//!   triangles the header did not count.
//!
//! Every mesh returned has passed [`TriMesh::validate`]: indices are in range
//! and positions are finite.
//!
//! # Crates used, and where not
//! - **PLY**: `ply-rs-bw` parses the header and decodes each element record
//!   (ASCII and binary, any scalar and list types). The element loop is ours:
//!   it checks each header count against the remaining bytes first and
//!   reports the byte offset or line of a broken record. Duplicate names are
//!   checked here (`ply-rs-bw` keeps one silently). Writing uses its `Writer`
//!   record by record.
//! - **STL**: `stl_io` writes binary STL; both encodings are read here.
//!   Binary STL (50-byte records, a dozen lines) because `stl_io` decides
//!   "ASCII" for any file starting with `solid `, which many binary exporters
//!   put in the 80-byte header, and it does not check the triangle count
//!   against the file size. ASCII STL (a small token parser) because
//!   `stl_io` 0.11 stops after the first `solid … endsolid` block, so CAD
//!   multi-body files lost every body but the first, refuses text that is
//!   not UTF-8, and reports errors without a line. ASCII STL is written here
//!   (`stl_io` writes binary only).
//! - **OBJ**: read by a small parser here rather than with `tobj`, because
//!   `tobj` (4.0) renumbers vertices in order of first use and drops
//!   unreferenced ones (so OBJ and PLY of the same mesh would not give the
//!   same vertex array), reports errors without a line number, and panics
//!   with an arithmetic overflow in debug builds on a relative texture index
//!   such as `f 1/-3 2/1 3/1`. The writer is a few lines here.

mod obj;
mod ply;
mod stl;

pub use obj::{OBJ_MAX_LINE_BYTES, read_obj};
pub use ply::read_ply;
pub use stl::read_stl;

use isomorph_common::{MeshError, TriMesh};
use std::fmt;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// A mesh file format with its encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (text; `v`, `vn`, `f`).
    Obj,
    /// PLY with an ASCII payload.
    PlyAscii,
    /// PLY with a binary little-endian payload (the usual one).
    PlyBinaryLittleEndian,
    /// PLY with a binary big-endian payload.
    PlyBinaryBigEndian,
    /// ASCII STL (`solid` / `facet` / `vertex` text).
    StlAscii,
    /// Binary STL (80-byte header, triangle count, 50-byte records).
    StlBinary,
}

impl MeshFormat {
    /// The format for a path's extension (case-insensitive): `.obj` → OBJ,
    /// `.ply` → binary little-endian PLY, `.stl` → binary STL. `None` for any
    /// other extension.
    ///
    /// Readers detect ASCII versus binary PLY and STL from the content, so the
    /// encoding chosen here only matters for writing.
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::PlyBinaryLittleEndian),
            "stl" => Some(MeshFormat::StlBinary),
            _ => None,
        }
    }

    /// The usual file extension, without the dot (`"obj"`, `"ply"`, `"stl"`).
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::PlyAscii | MeshFormat::PlyBinaryLittleEndian | MeshFormat::PlyBinaryBigEndian => {
                "ply"
            }
            MeshFormat::StlAscii | MeshFormat::StlBinary => "stl",
        }
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::PlyAscii => "ASCII PLY",
            MeshFormat::PlyBinaryLittleEndian => "binary little-endian PLY",
            MeshFormat::PlyBinaryBigEndian => "binary big-endian PLY",
            MeshFormat::StlAscii => "ASCII STL",
            MeshFormat::StlBinary => "binary STL",
        })
    }
}

/// Errors of mesh file reading and writing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshIoError {
    /// Reading or writing the file or stream failed (missing file, no
    /// permission, disk full, ...).
    #[error("I/O error{}: {source}", on_path(.path.as_deref()))]
    Io {
        /// The file, when the error came from [`read_mesh`] or [`write_mesh`].
        path: Option<PathBuf>,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The path's extension names no supported format.
    #[error("cannot tell the mesh format of {} from its extension; use .obj, .ply or .stl", .path.display())]
    UnknownFormat {
        /// The path given.
        path: PathBuf,
    },
    /// The data is malformed: bad syntax, a bad number, a truncated record.
    #[error("malformed {format} data{}: {message}", location(*.line, *.offset))]
    Parse {
        /// Format family: `"OBJ"`, `"PLY"` or `"STL"`.
        format: &'static str,
        /// 1-based line number (text data), when known.
        line: Option<usize>,
        /// Byte offset from the start of the data (binary data), when known.
        offset: Option<u64>,
        /// What is wrong.
        message: String,
    },
    /// The data is well-formed but uses something this reader does not
    /// handle, such as a PLY without `x y z` vertex properties or with
    /// floating-point face indices, or more than `u32::MAX` vertices.
    #[error("unsupported {format} content: {message}")]
    Unsupported {
        /// Format family: `"OBJ"`, `"PLY"` or `"STL"`.
        format: &'static str,
        /// What is not supported.
        message: String,
    },
    /// A header claims more records than the data can hold: the file is
    /// truncated or its header is corrupt. Checked before any allocation.
    #[error(
        "{format} header claims {claimed} {what}, but the remaining data holds at most {available} \
         (truncated file or corrupt header)"
    )]
    TooLarge {
        /// Format family: `"PLY"` or `"STL"`.
        format: &'static str,
        /// What was counted, e.g. `"triangles"` or `"'vertex' elements"`.
        what: String,
        /// The count the header claims.
        claimed: u64,
        /// The most that fit in the bytes actually present.
        available: u64,
    },
    /// A text line is longer than the reader accepts (see
    /// [`OBJ_MAX_LINE_BYTES`]): the data has no line breaks, so it is not the
    /// text file it should be. Reported before the line is held in memory.
    #[error("{format} line {line} is longer than {limit} bytes (no line break: not a text file?)")]
    LineTooLong {
        /// Format family: `"OBJ"`.
        format: &'static str,
        /// 1-based number of the line.
        line: usize,
        /// The longest line accepted, in bytes.
        limit: usize,
    },
    /// The data parsed, but the mesh is invalid (an index out of range, a
    /// non-finite coordinate); for writing, the mesh given is invalid.
    #[error("invalid mesh: {0}")]
    Mesh(#[from] MeshError),
}

impl From<io::Error> for MeshIoError {
    fn from(source: io::Error) -> Self {
        MeshIoError::Io { path: None, source }
    }
}

impl MeshIoError {
    /// Attaches `path` to an I/O error that has none.
    fn at_path(self, path: &Path) -> Self {
        match self {
            MeshIoError::Io { path: None, source } => {
                MeshIoError::Io { path: Some(path.to_path_buf()), source }
            }
            other => other,
        }
    }

    /// A [`MeshIoError::Parse`] with a tidied message.
    fn parse(format: &'static str, line: Option<usize>, offset: Option<u64>, message: &str) -> Self {
        MeshIoError::Parse { format, line, offset, message: tidy(message) }
    }
}

/// `" on PATH"` or nothing, for error messages.
fn on_path(path: Option<&Path>) -> String {
    path.map(|p| format!(" on {}", p.display())).unwrap_or_default()
}

/// `" at line N"`, `" at byte N"` or nothing, for error messages.
fn location(line: Option<usize>, offset: Option<u64>) -> String {
    match (line, offset) {
        (Some(line), _) => format!(" at line {line}"),
        (None, Some(offset)) => format!(" at byte {offset}"),
        (None, None) => String::new(),
    }
}

/// Puts a message from a parser crate on one line and bounds its length (a
/// hostile line quoted in a message could be megabytes long).
fn tidy(message: &str) -> String {
    const MAX_CHARS: usize = 300;
    let mut out: String = message.split_whitespace().collect::<Vec<_>>().join(" ");
    if let Some((cut, _)) = out.char_indices().nth(MAX_CHARS) {
        out.truncate(cut);
        out.push('…');
    }
    out
}

/// A mesh as read, with what the reader accepted but had to say about it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshRead {
    /// The mesh; it has passed [`TriMesh::validate`].
    pub mesh: TriMesh,
    /// What was ignored, dropped or repaired on the way, in file order per
    /// kind; empty for a clean file.
    pub warnings: Vec<ReadWarning>,
}

/// Something a reader accepted but did not keep or had to repair. Its
/// [`Display`](fmt::Display) form is a sentence for the user.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReadWarning {
    /// OBJ face corners name a normal (`v//vn`, `v/vt/vn`) while no `vn` is
    /// defined before them; the normal references were dropped.
    #[error(
        "OBJ: {corners} face corners from line {first_line} on name a normal, but no 'vn' is defined \
         before them; the normal references were dropped"
    )]
    ObjNormalsDropped {
        /// Face corners concerned.
        corners: u64,
        /// Line of the first one.
        first_line: usize,
    },
    /// OBJ face corners name a texture coordinate (`v/vt`) while no `vt` is
    /// defined before them; the references were dropped (texture
    /// coordinates are never kept).
    #[error(
        "OBJ: {corners} face corners from line {first_line} on name a texture coordinate, but no 'vt' is \
         defined before them; the references were dropped"
    )]
    ObjTexturesDropped {
        /// Face corners concerned.
        corners: u64,
        /// Line of the first one.
        first_line: usize,
    },
    /// Some OBJ vertices carry a colour (`v x y z r g b`) and others do
    /// not: the colours were dropped (a mesh has a colour for every vertex
    /// or none).
    #[error(
        "OBJ: {uncolored} of {vertices} vertices have no colour (first on line {first_line}), so the vertex colours were dropped"
    )]
    ObjColorsDropped {
        /// Vertices without a colour.
        uncolored: usize,
        /// All vertices.
        vertices: usize,
        /// Line of the first vertex without a colour.
        first_line: usize,
    },
    /// OBJ statements skipped: unknown keywords, or geometry this reader does
    /// not build (`l` lines, `p` points, curves and surfaces). One warning
    /// per keyword; past 16 keywords the rest are counted under `"…"`.
    #[error(
        "OBJ: {lines} '{keyword}' statements from line {first_line} on were skipped ({})",
        skipped_reason(.keyword)
    )]
    ObjStatementsSkipped {
        /// The keyword (lossy UTF-8, at most 32 bytes).
        keyword: String,
        /// Lines with this keyword.
        lines: u64,
        /// The first of them.
        first_line: usize,
    },
    /// Data after the last element the PLY header declares was ignored
    /// (blank lines after an ASCII payload are not reported).
    #[error(
        "PLY: {bytes} bytes after the last declared element{} were ignored; the header's element counts \
         may be too small",
        location(*.line, Some(*.offset))
    )]
    PlyTrailingData {
        /// Bytes ignored.
        bytes: u64,
        /// Byte offset where they start.
        offset: u64,
        /// Line where they start (ASCII).
        line: Option<usize>,
    },
    /// Bytes after the triangles a binary STL header declares were ignored.
    #[error(
        "binary STL: {bytes} bytes after the {declared} triangles the header declares were ignored{}",
        uncounted(*.records)
    )]
    StlTrailingBytes {
        /// The header's triangle count.
        declared: u32,
        /// Bytes ignored.
        bytes: u64,
        /// When the ignored bytes are a whole number of 50-byte records
        /// that look like triangles (finite, not all zero, near the declared
        /// ones): how many. The header then probably under-counts.
        records: Option<u64>,
    },
    /// Text after the last `endsolid` of an ASCII STL that does not start
    /// another `solid` was ignored.
    #[error("ASCII STL: {bytes} bytes after the last 'endsolid', from line {line} on, were ignored")]
    StlTrailingText {
        /// Bytes ignored.
        bytes: u64,
        /// Line where they start.
        line: usize,
    },
    /// STL corners that were close but not bit-identical were welded (see
    /// [`read_stl`] for the tolerance).
    #[error(
        "STL: {corners} triangle corners were welded to a vertex within {tolerance:e} of them (not \
         bit-identical){}",
        collapsed(*.collapsed_triangles)
    )]
    StlWeldedWithinTolerance {
        /// Corners welded to a vertex at a different position.
        corners: u64,
        /// The tolerance used (per coordinate).
        tolerance: f64,
        /// Triangles that lost their area because two of their corners were
        /// welded together (they are kept, with a repeated index).
        collapsed_triangles: u64,
    },
}

/// Why an OBJ keyword is skipped, for [`ReadWarning::ObjStatementsSkipped`].
fn skipped_reason(keyword: &str) -> &'static str {
    if obj::is_unread_geometry(keyword) { "geometry this reader does not build" } else { "unknown statement" }
}

/// The under-count remark of [`ReadWarning::StlTrailingBytes`].
fn uncounted(records: Option<u64>) -> String {
    records
        .map(|n| {
            format!(
                "; they are exactly {n} more 50-byte records that look like triangles, so the header's count \
                 probably under-counts"
            )
        })
        .unwrap_or_default()
}

/// The collapse remark of [`ReadWarning::StlWeldedWithinTolerance`].
fn collapsed(triangles: u64) -> String {
    if triangles == 0 { String::new() } else { format!("; {triangles} triangles collapsed to zero area") }
}

/// Control bytes other than tab, line feed, form feed and carriage return:
/// never in a text mesh file, always (in practice) in binary data.
fn is_control(byte: u8) -> bool {
    (byte < 0x20 && !matches!(byte, b'\t' | b'\n' | 0x0c | b'\r')) || byte == 0x7f
}

/// Reads a mesh file; the format comes from the extension (see
/// [`MeshFormat::from_path`]) and, for PLY and STL, the encoding from the
/// content.
///
/// # Errors
/// [`MeshIoError::UnknownFormat`] for an unknown extension,
/// [`MeshIoError::Io`] (with the path) when the file cannot be read, and the
/// errors of [`read_mesh_from`].
///
/// Warnings are dropped; [`read_mesh_with_warnings`] returns them.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<TriMesh, MeshIoError> {
    read_mesh_with_warnings(path).map(|read| read.mesh)
}

/// [`read_mesh`], with the [`ReadWarning`]s: what the reader ignored,
/// dropped or repaired.
///
/// # Errors
/// Those of [`read_mesh`].
pub fn read_mesh_with_warnings(path: impl AsRef<Path>) -> Result<MeshRead, MeshIoError> {
    let path = path.as_ref();
    let format =
        MeshFormat::from_path(path).ok_or_else(|| MeshIoError::UnknownFormat { path: path.to_path_buf() })?;
    let file = File::open(path).map_err(|e| MeshIoError::from(e).at_path(path))?;
    read_mesh_from_with_warnings(file, format).map_err(|e| e.at_path(path))
}

/// Reads a mesh in the family of `format` (OBJ, PLY or STL) from any reader,
/// for example a byte slice in memory. For PLY and STL the encoding (ASCII or
/// binary, and the PLY byte order) is detected from the content, so any PLY or
/// STL variant of `format` will do.
///
/// # Errors
/// [`MeshIoError::Io`] when reading fails, [`MeshIoError::Parse`] for
/// malformed or truncated data, [`MeshIoError::TooLarge`] when a header claims
/// more than the data holds, [`MeshIoError::Unsupported`] for content this
/// reader does not handle, [`MeshIoError::LineTooLong`] for an OBJ line
/// without end and [`MeshIoError::Mesh`] for an index out of range or a
/// non-finite coordinate.
///
/// Warnings are dropped; [`read_mesh_from_with_warnings`] returns them.
pub fn read_mesh_from(reader: impl Read, format: MeshFormat) -> Result<TriMesh, MeshIoError> {
    read_mesh_from_with_warnings(reader, format).map(|read| read.mesh)
}

/// [`read_mesh_from`], with the [`ReadWarning`]s: what the reader ignored,
/// dropped or repaired.
///
/// # Errors
/// Those of [`read_mesh_from`].
pub fn read_mesh_from_with_warnings(reader: impl Read, format: MeshFormat) -> Result<MeshRead, MeshIoError> {
    match format {
        MeshFormat::Obj => obj::read(BufReader::new(reader)),
        MeshFormat::PlyAscii | MeshFormat::PlyBinaryLittleEndian | MeshFormat::PlyBinaryBigEndian => {
            ply::read(reader)
        }
        MeshFormat::StlAscii | MeshFormat::StlBinary => stl::read(reader),
    }
}

/// Writes `mesh` to the file `path` (created or truncated) in `format`.
///
/// # Errors
/// [`MeshIoError::Mesh`] when the mesh does not pass [`TriMesh::validate`]
/// (nothing is written then), [`MeshIoError::Io`] (with the path) when the
/// file cannot be written, and the errors of [`write_mesh_to`].
pub fn write_mesh(mesh: &TriMesh, path: impl AsRef<Path>, format: MeshFormat) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    mesh.validate()?;
    let file = File::create(path).map_err(|e| MeshIoError::from(e).at_path(path))?;
    write_mesh_to(mesh, file, format).map_err(|e| e.at_path(path))
}

/// Writes `mesh` in `format` to any writer (buffered internally).
///
/// Normals, when present, are written to OBJ (`vn`, one per vertex) and PLY
/// (`nx ny nz`); STL gets each triangle's unit normal (zero when degenerate).
///
/// # Errors
/// [`MeshIoError::Mesh`] when the mesh does not pass [`TriMesh::validate`]
/// (nothing is written then), [`MeshIoError::Unsupported`] for binary STL with
/// more than `u32::MAX` triangles, [`MeshIoError::Io`] when writing fails.
pub fn write_mesh_to(mesh: &TriMesh, writer: impl Write, format: MeshFormat) -> Result<(), MeshIoError> {
    mesh.validate()?;
    let mut out = BufWriter::new(writer);
    match format {
        MeshFormat::Obj => obj::write_obj(mesh, &mut out)?,
        MeshFormat::PlyAscii | MeshFormat::PlyBinaryLittleEndian | MeshFormat::PlyBinaryBigEndian => {
            ply::write_ply(mesh, &mut out, format)?
        }
        MeshFormat::StlAscii | MeshFormat::StlBinary => stl::write_stl(mesh, &mut out, format)?,
    }
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests;
