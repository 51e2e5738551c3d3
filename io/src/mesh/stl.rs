//! STL: both encodings read here (binary records, a small ASCII parser);
//! the triangle soup is welded into an indexed mesh within a tolerance.

use super::{MeshFormat, MeshIoError, MeshRead, ReadWarning, is_control};
use glam::{DVec3, Vec3};
use isomorph_common::TriMesh;
use std::collections::HashMap;
use std::io::{Read, Write};

const FORMAT: &str = "STL";
/// Bytes before the first binary record: 80-byte header and `u32` count.
const HEADER: usize = 84;
/// Bytes of a binary record: normal, three vertices (12 `f32`), attribute.
const RECORD: usize = 50;
/// Welding tolerance in units in the last place of the largest coordinate
/// magnitude (see [`read_stl`]).
const WELD_ULPS: f64 = 4.0;
/// Welding tolerance cap relative to the bounding-box diagonal.
const WELD_RELATIVE: f64 = 1e-6;

/// One triangle of the soup: three corners.
type Facet = [Vec3; 3];

/// Reads an STL mesh, ASCII or binary.
///
/// **Encoding.** Binary when the size is exactly `84 + 50·n` for the count
/// `n` in the header (even if the header starts with `solid`, as many
/// exporters write); otherwise ASCII when the data starts with `solid` and is
/// text (no control character other than white space, trailing NUL padding
/// aside; bytes that are not UTF-8 are fine, e.g. in solid names); binary
/// otherwise.
///
/// **ASCII** STL is parsed here, token by token: every
/// `solid … endsolid` block is read (CAD multi-body parts write several) and
/// their facets concatenated. Keywords are case-insensitive; facet normals
/// are skipped unparsed (exporters write `nan` and worse there). Text after
/// the last `endsolid` that does not start another `solid` is ignored with
/// [`ReadWarning::StlTrailingText`].
///
/// **Binary** STL: bytes after the declared records (padding, or a header
/// count too small) are ignored with [`ReadWarning::StlTrailingBytes`],
/// which says when they are a whole number of plausible triangles.
///
/// **Welding.** STL stores a triangle soup; corners are welded into shared
/// vertices numbered in order of first appearance, each taking the position
/// of its first occurrence. Two corners weld when every coordinate differs
/// by at most `τ = min(4 ε M, 10⁻⁶ D)`, with `ε = 2⁻²³` the `f32` machine
/// epsilon, `M` the largest coordinate magnitude and `D` the bounding-box
/// diagonal: 4 units in the last place of the largest coordinate, the
/// rounding noise of CAD exporters (a `2.4e-18` where `0` is meant), capped
/// at a millionth of the part so that parts far from the origin keep their
/// fine detail; a real edge is far longer. A corner welds to the earliest
/// vertex within `τ` (a spatial hash with cells of `4τ`, neighbouring cells
/// searched, so pairs are never split by a cell boundary). Welds that are not
/// bit-identical are reported with [`ReadWarning::StlWeldedWithinTolerance`].
/// Stored facet normals are ignored, so the result has no normals. The whole
/// input is read into memory first.
///
/// Warnings are dropped here; [`read_mesh_from_with_warnings`] returns them.
///
/// [`read_mesh_from_with_warnings`]: super::read_mesh_from_with_warnings
///
/// # Errors
/// [`MeshIoError::Parse`] for a malformed facet or a non-finite coordinate
/// (with the byte offset for binary, the line and facet number for ASCII) or
/// binary data shorter than its header, and for data that starts with
/// `solid` but holds a control byte (so it is not ASCII) and does not fit as
/// binary either, the offset and line of that byte;
/// [`MeshIoError::TooLarge`] when the binary triangle count does not fit in
/// the data;
/// [`MeshIoError::Unsupported`] beyond `u32::MAX` distinct vertices;
/// [`MeshIoError::Io`] when reading fails.
pub fn read_stl(reader: impl Read) -> Result<TriMesh, MeshIoError> {
    read(reader).map(|read| read.mesh)
}

/// [`read_stl`] with its warnings.
pub(super) fn read(mut reader: impl Read) -> Result<MeshRead, MeshIoError> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes)?;
    let mut warnings = Vec::new();
    let soup = if is_binary(&bytes) {
        read_binary(&bytes, &mut warnings).map_err(|e| ascii_hint(&bytes, e))?
    } else {
        read_ascii(&bytes, &mut warnings)?
    };
    let mesh = weld(&soup, &mut warnings)?;
    Ok(MeshRead { mesh, warnings })
}

/// The triangle count a binary header claims, if there is a header.
fn binary_count(bytes: &[u8]) -> Option<u32> {
    let count = bytes.get(HEADER - 4..HEADER)?;
    Some(u32::from_le_bytes([count[0], count[1], count[2], count[3]]))
}

/// Decides binary versus ASCII (see [`read_stl`]).
fn is_binary(bytes: &[u8]) -> bool {
    let exact_size = binary_count(bytes)
        .is_some_and(|n| (HEADER as u64 + RECORD as u64 * u64::from(n)) == bytes.len() as u64);
    let solid = bytes.trim_ascii_start().get(..5).is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
    let end = bytes.iter().rposition(|&b| b != 0).map_or(0, |i| i + 1);
    exact_size || !solid || bytes[..end].iter().any(|&b| is_control(b))
}

/// When data that starts with `solid` failed as binary STL for its size:
/// an error naming the control byte that kept it from being read as ASCII,
/// as well as the binary reading, rather than a bare (bogus) triangle count.
fn ascii_hint(bytes: &[u8], error: MeshIoError) -> MeshIoError {
    let solid = bytes.trim_ascii_start().get(..5).is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
    let binary = match &error {
        MeshIoError::TooLarge { claimed, available, .. } => {
            format!("its header claims {claimed} triangles where the data holds at most {available}")
        }
        _ if bytes.len() < HEADER => format!("it is shorter than the {HEADER}-byte header"),
        _ => return error,
    };
    match bytes.iter().position(|&b| is_control(b)) {
        Some(at) if solid => {
            let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
            let message = format!(
                "the data starts with 'solid' like ASCII STL, but byte {at} is the control character \
                 0x{:02x}, which text does not hold; read as binary STL, {binary}",
                bytes[at]
            );
            MeshIoError::parse(FORMAT, Some(line), Some(at as u64), &message)
        }
        _ => error,
    }
}

/// The corners of binary record `record`.
fn binary_corners(record: &[u8]) -> Facet {
    let float = |at: usize| f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]]);
    let corner = |k: usize| Vec3::new(float(12 + 12 * k), float(16 + 12 * k), float(20 + 12 * k));
    [corner(0), corner(1), corner(2)]
}

fn read_binary(bytes: &[u8], warnings: &mut Vec<ReadWarning>) -> Result<Vec<Facet>, MeshIoError> {
    let count = binary_count(bytes).ok_or_else(|| {
        MeshIoError::parse(
            FORMAT,
            None,
            Some(bytes.len() as u64),
            &format!("binary STL needs an {HEADER}-byte header, the data has {} bytes", bytes.len()),
        )
    })?;
    let available = ((bytes.len() - HEADER) / RECORD) as u64;
    if u64::from(count) > available {
        return Err(MeshIoError::TooLarge {
            format: FORMAT,
            what: "triangles".to_owned(),
            claimed: u64::from(count),
            available,
        });
    }
    // The count was checked against the data size.
    let end = HEADER + RECORD * count as usize;
    let mut soup = Vec::with_capacity(count as usize);
    for (t, record) in bytes[HEADER..end].chunks_exact(RECORD).enumerate() {
        let corners = binary_corners(record);
        if let Some(k) = corners.iter().position(|p| !p.is_finite()) {
            let offset = (HEADER + t * RECORD + 12 + 12 * k) as u64;
            let message = format!("triangle {t} has a non-finite coordinate");
            return Err(MeshIoError::parse(FORMAT, None, Some(offset), &message));
        }
        soup.push(corners);
    }
    let trailing = &bytes[end..];
    if !trailing.is_empty() {
        let records = plausible_records(trailing, &soup);
        warnings.push(ReadWarning::StlTrailingBytes {
            declared: count,
            bytes: trailing.len() as u64,
            records,
        });
    }
    Ok(soup)
}

/// When `trailing` is a whole number of records that look like triangles
/// (finite, not all zero bytes, within the bounding box of the declared
/// `soup` grown by its own size on every side): how many.
fn plausible_records(trailing: &[u8], soup: &[Facet]) -> Option<u64> {
    if !trailing.len().is_multiple_of(RECORD) {
        return None;
    }
    let (lo, hi) = soup
        .iter()
        .flatten()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let size = hi - lo;
    let near = |p: Vec3| soup.is_empty() || (p.cmpge(lo - size).all() && p.cmple(hi + size).all());
    trailing
        .chunks_exact(RECORD)
        .all(|record| {
            let corners = binary_corners(record);
            record.iter().any(|&b| b != 0) && corners.iter().all(|&p| p.is_finite() && near(p))
        })
        .then_some((trailing.len() / RECORD) as u64)
}

/// Whitespace-separated tokens of ASCII STL with their line numbers (lines
/// end at `\n`, `\r\n` or a lone `\r`).
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// 1-based line of `pos`.
    line: usize,
}

impl<'a> Tokens<'a> {
    /// Skips white space, counting line breaks.
    fn skip_space(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
            let lone_cr = b == b'\r' && self.bytes.get(self.pos) != Some(&b'\n');
            self.line += usize::from(b == b'\n' || lone_cr);
        }
    }

    /// The next token and its line.
    fn next(&mut self) -> Option<(&'a [u8], usize)> {
        self.skip_space();
        let start = self.pos;
        let len = self.bytes[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(self.bytes.len() - start);
        self.pos += len;
        (len > 0).then(|| (&self.bytes[start..start + len], self.line))
    }

    /// The next token, part of `what` in facet `t`.
    fn need(&mut self, t: usize, what: &str) -> Result<(&'a [u8], usize), MeshIoError> {
        self.next().ok_or_else(|| {
            MeshIoError::parse(FORMAT, Some(self.line), None, &format!("facet {t}: the data ends in {what}"))
        })
    }

    /// Reads the keyword `word` in facet `t`.
    fn expect(&mut self, t: usize, word: &str) -> Result<(), MeshIoError> {
        match self.need(t, &format!("'{word}'"))? {
            (token, _) if is(token, word) => Ok(()),
            (token, line) => {
                let message = format!("facet {t}: expected '{word}', found '{}'", quote(token));
                Err(MeshIoError::parse(FORMAT, Some(line), None, &message))
            }
        }
    }

    /// Skips the rest of the current line (a solid's name), line break
    /// included.
    fn skip_line(&mut self) {
        let rest = &self.bytes[self.pos..];
        match rest.iter().position(|&b| b == b'\n' || b == b'\r') {
            Some(i) => {
                self.pos += i;
                let crlf = rest[i] == b'\r' && rest.get(i + 1) == Some(&b'\n');
                self.pos += 1 + usize::from(crlf);
                self.line += 1;
            }
            None => self.pos = self.bytes.len(),
        }
    }
}

/// Whether `token` is the keyword `word` (case-insensitive).
fn is(token: &[u8], word: &str) -> bool {
    token.eq_ignore_ascii_case(word.as_bytes())
}

/// A short quote of a token for error messages.
fn quote(token: &[u8]) -> String {
    String::from_utf8_lossy(&token[..token.len().min(40)]).into_owned()
}

fn read_ascii(bytes: &[u8], warnings: &mut Vec<ReadWarning>) -> Result<Vec<Facet>, MeshIoError> {
    let mut tokens = Tokens { bytes, pos: 0, line: 1 };
    let mut soup = Vec::new();
    let mut solids = 0;
    loop {
        let start = tokens.pos;
        let Some((token, line)) = tokens.next() else { break };
        let is_solid = token.get(..5).is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
        if !is_solid {
            if solids == 0 {
                let message = format!("expected 'solid', found '{}'", quote(token));
                return Err(MeshIoError::parse(FORMAT, Some(line), None, &message));
            }
            let skipped = bytes[start..].trim_ascii_start();
            warnings.push(ReadWarning::StlTrailingText { bytes: skipped.len() as u64, line });
            break;
        }
        tokens.skip_line();
        solid(&mut tokens, &mut soup)?;
        solids += 1;
    }
    Ok(soup)
}

/// Reads the facets of one solid, up to and including its `endsolid` line.
fn solid(tokens: &mut Tokens<'_>, soup: &mut Vec<Facet>) -> Result<(), MeshIoError> {
    let error = |line: usize, message: String| MeshIoError::parse(FORMAT, Some(line), None, &message);
    loop {
        let t = soup.len();
        let Some((token, line)) = tokens.next() else {
            return Err(error(tokens.line, "the data ends inside a solid (no 'endsolid')".to_owned()));
        };
        if is(token, "endsolid") {
            tokens.skip_line();
            return Ok(());
        }
        if !is(token, "facet") {
            return Err(error(line, format!("expected 'facet' or 'endsolid', found '{}'", quote(token))));
        }
        tokens.expect(t, "normal")?;
        for _ in 0..3 {
            tokens.need(t, "the normal")?;
        }
        tokens.expect(t, "outer")?;
        tokens.expect(t, "loop")?;
        let mut corners = [Vec3::ZERO; 3];
        for corner in &mut corners {
            tokens.expect(t, "vertex")?;
            for c in 0..3 {
                let (token, line) = tokens.need(t, "a vertex")?;
                let value =
                    std::str::from_utf8(token).ok().and_then(|s| s.parse::<f32>().ok()).ok_or_else(|| {
                        error(
                            line,
                            format!("facet {t}: vertex coordinate '{}' is not a number", quote(token)),
                        )
                    })?;
                if !value.is_finite() {
                    return Err(error(line, format!("facet {t} has a non-finite coordinate")));
                }
                corner[c] = value;
            }
        }
        tokens.expect(t, "endloop")?;
        tokens.expect(t, "endfacet")?;
        soup.push(corners);
    }
}

/// The welding tolerance of `soup` (see [`read_stl`]).
fn tolerance(soup: &[Facet]) -> f64 {
    let (mut lo, mut hi, mut magnitude) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0.0f64);
    for p in soup.iter().flatten() {
        let p = p.as_dvec3();
        lo = lo.min(p);
        hi = hi.max(p);
        magnitude = magnitude.max(p.abs().max_element());
    }
    if soup.is_empty() {
        return 0.0;
    }
    (WELD_ULPS * f64::from(f32::EPSILON) * magnitude).min(WELD_RELATIVE * (hi - lo).length())
}

/// Marks the end of a cell's chain of vertices.
const NONE: u32 = u32::MAX;

/// Welds a triangle soup into an indexed mesh (see [`read_stl`]).
fn weld(soup: &[Facet], warnings: &mut Vec<ReadWarning>) -> Result<TriMesh, MeshIoError> {
    let tolerance = tolerance(soup);
    let cell = 4.0 * tolerance;
    // Cell of one coordinate; with no tolerance, the value itself (`-0.0`
    // as `0.0`), so only equal values meet.
    let key = |x: f64| if cell > 0.0 { (x / cell).floor() as i64 } else { (x + 0.0).to_bits() as i64 };
    // Last vertex put in each cell; `previous[v]`: the one before it there.
    // Vertices in one cell are more than `tolerance` apart in some
    // coordinate, so a cell of `4 tolerance` holds at most 4³ of them: the
    // work per corner is bounded whatever the input.
    let mut cells: HashMap<[i64; 3], u32> = HashMap::new();
    let mut previous: Vec<u32> = Vec::new();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut triangles = Vec::with_capacity(soup.len());
    let (mut nearby, mut collapsed) = (0u64, 0u64);
    for facet in soup {
        let mut triangle = [0u32; 3];
        for (slot, &p) in triangle.iter_mut().zip(facet) {
            let q = p.as_dvec3();
            let range = |x: f64| key(x - tolerance)..=key(x + tolerance);
            let mut found = NONE;
            for x in range(q.x) {
                for y in range(q.y) {
                    for z in range(q.z) {
                        let mut v = cells.get(&[x, y, z]).copied().unwrap_or(NONE);
                        while v != NONE {
                            let d = (positions[v as usize].as_dvec3() - q).abs().max_element();
                            if d <= tolerance && v < found {
                                found = v;
                            }
                            v = previous[v as usize];
                        }
                    }
                }
            }
            *slot = if found != NONE {
                nearby += u64::from(positions[found as usize] != p);
                found
            } else {
                let v = u32::try_from(positions.len()).ok().filter(|&v| v != NONE).ok_or_else(|| {
                    MeshIoError::Unsupported {
                        format: FORMAT,
                        message: "more than u32::MAX - 1 distinct vertices".to_owned(),
                    }
                })?;
                let home = [key(q.x), key(q.y), key(q.z)];
                previous.push(cells.insert(home, v).unwrap_or(NONE));
                positions.push(p);
                v
            };
        }
        let [a, b, c] = triangle;
        let [p, q, r] = *facet;
        collapsed += u64::from((a == b && p != q) || (b == c && q != r) || (a == c && p != r));
        triangles.push(triangle);
    }
    if nearby > 0 {
        warnings.push(ReadWarning::StlWeldedWithinTolerance {
            corners: nearby,
            tolerance,
            collapsed_triangles: collapsed,
        });
    }
    let mesh = TriMesh { positions, triangles, normals: None, colors: None };
    mesh.validate()?;
    Ok(mesh)
}

/// The unit normal of triangle `t` (zero when degenerate).
fn face_normal(mesh: &TriMesh, t: usize) -> Vec3 {
    let [a, b, c] = mesh.corners(t);
    (b - a).cross(c - a).normalize_or_zero()
}

/// Writes binary (through `stl_io`) or ASCII STL.
pub(super) fn write_stl(mesh: &TriMesh, out: &mut impl Write, format: MeshFormat) -> Result<(), MeshIoError> {
    if format == MeshFormat::StlAscii {
        writeln!(out, "solid isomorph")?;
        for t in 0..mesh.triangles.len() {
            let n = face_normal(mesh, t);
            writeln!(out, "  facet normal {} {} {}\n    outer loop", n.x, n.y, n.z)?;
            for p in mesh.corners(t) {
                writeln!(out, "      vertex {} {} {}", p.x, p.y, p.z)?;
            }
            writeln!(out, "    endloop\n  endfacet")?;
        }
        writeln!(out, "endsolid isomorph")?;
        return Ok(());
    }
    if u32::try_from(mesh.triangles.len()).is_err() {
        return Err(MeshIoError::Unsupported {
            format: FORMAT,
            message: format!("{} triangles; binary STL holds at most u32::MAX", mesh.triangles.len()),
        });
    }
    let facets = (0..mesh.triangles.len()).map(|t| stl_io::Triangle {
        normal: stl_io::Normal::new(face_normal(mesh, t).to_array()),
        vertices: mesh.corners(t).map(|p| stl_io::Vertex::new(p.to_array())),
    });
    stl_io::write_stl(out, facets)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> TriMesh {
        TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    fn written(mesh: &TriMesh, format: MeshFormat) -> Vec<u8> {
        let mut bytes = Vec::new();
        write_stl(mesh, &mut bytes, format).unwrap();
        bytes
    }

    #[test]
    fn both_encodings_weld_back_to_the_tetrahedron() {
        let mesh = tetrahedron();
        for format in [MeshFormat::StlAscii, MeshFormat::StlBinary] {
            let back = read_stl(&written(&mesh, format)[..]).unwrap();
            // Order of first appearance in the triangles: 0, 2, 1, 3.
            assert_eq!(back.positions, vec![Vec3::ZERO, Vec3::Y, Vec3::X, Vec3::Z], "{format}");
            assert_eq!(back.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [2, 1, 3]], "{format}");
        }
    }

    #[test]
    fn binary_with_solid_header_is_binary() {
        let mut bytes = written(&tetrahedron(), MeshFormat::StlBinary);
        bytes[..12].copy_from_slice(b"solid tetra ");
        assert_eq!(read_stl(&bytes[..]).unwrap().triangles.len(), 4);
    }

    #[test]
    fn unnamed_ascii_solid_and_negative_zero() {
        let text = "solid\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n\
                    endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex -0 0 0\nvertex 0 1 0\n\
                    vertex 0 0 1\nendloop\nendfacet\nendsolid\n";
        let mesh = read_stl(text.as_bytes()).unwrap();
        assert_eq!(mesh.positions.len(), 4, "-0 welds with 0");
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn hostile_binary_input() {
        // 4 billion triangles claimed in a 134-byte file.
        let mut bytes = written(&tetrahedron(), MeshFormat::StlBinary);
        bytes.truncate(HEADER + RECORD);
        bytes[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            read_stl(&bytes[..]),
            Err(MeshIoError::TooLarge { claimed: 4_294_967_295, available: 1, .. })
        ));
        // Shorter than the header.
        assert!(matches!(read_stl(&[0u8; 40][..]), Err(MeshIoError::Parse { offset: Some(40), .. })));
        // NaN in the third corner of the second triangle.
        let mut bytes = written(&tetrahedron(), MeshFormat::StlBinary);
        let at = HEADER + RECORD + 12 + 24 + 4;
        bytes[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let offset = (HEADER + RECORD + 36) as u64;
        assert!(
            matches!(read_stl(&bytes[..]), Err(MeshIoError::Parse { offset: Some(o), .. }) if o == offset)
        );
    }

    #[test]
    fn hostile_ascii_input() {
        let facet =
            "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
        let ok = format!("solid x\n{facet}{facet}endsolid x\n");
        assert_eq!(read_stl(ok.as_bytes()).unwrap().triangles.len(), 2);
        for bad in [
            ok.replacen("vertex 1 0 0", "vertex nan 0 0", 1),
            ok.replacen("vertex 1 0 0", "vertex 1 0", 1),
            ok.replacen("endloop", "endlop", 1),
            ok.replace("endsolid x\n", ""),
        ] {
            assert!(matches!(read_stl(bad.as_bytes()), Err(MeshIoError::Parse { .. })), "{bad}");
        }
        let second = format!("solid x\n{facet}{}endsolid x\n", facet.replace("vertex 0 1 0", "vertex 0 x 0"));
        match read_stl(second.as_bytes()) {
            Err(MeshIoError::Parse { message, .. }) => assert!(message.starts_with("facet 1:"), "{message}"),
            other => panic!("{other:?}"),
        }
    }

    const FACET: &str =
        "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";

    fn warned(bytes: &[u8]) -> MeshRead {
        read(bytes).unwrap()
    }

    #[test]
    fn every_ascii_solid_is_read() {
        let second = FACET.replace("vertex 0 1 0", "vertex 0 0 1");
        let text = format!("solid a\n{FACET}endsolid a\nsolid b\r\n{second}{FACET}endsolid b\n");
        let read = warned(text.as_bytes());
        assert_eq!(read.mesh.triangles, vec![[0, 1, 2], [0, 1, 3], [0, 1, 2]]);
        assert_eq!(read.warnings, vec![]);
        // Upper-case keywords, `nan` normals, no line break at the end.
        let shouting =
            format!("SOLID\n{}ENDSOLID", FACET.to_uppercase().replace("NORMAL 0 0 1", "normal nan -nan 0"));
        assert_eq!(warned(shouting.as_bytes()).mesh.triangles.len(), 1);
        // Text after the last solid is reported, not read.
        let junk = format!("solid a\n{FACET}endsolid a\n\n{FACET}");
        let read = warned(junk.as_bytes());
        assert_eq!(read.mesh.triangles.len(), 1);
        assert_eq!(read.warnings, vec![ReadWarning::StlTrailingText { bytes: FACET.len() as u64, line: 11 }]);
    }

    #[test]
    fn ascii_with_bytes_that_are_not_utf8_is_ascii() {
        // A Latin-1 name used to send this to the binary reader ("header
        // claims 540024881 triangles").
        let text = [b"solid caf\xe9\n".as_slice(), FACET.as_bytes(), b"endsolid caf\xe9\n"].concat();
        assert_eq!(read_stl(&text[..]).unwrap().triangles.len(), 1);
        let mut bad = format!("solid x\n{}", FACET.replace("vertex 1 0 0", "vertex 1# 0 0")).into_bytes();
        bad.iter_mut().filter(|b| **b == b'#').for_each(|b| *b = 0xb0);
        match read_stl(&bad[..]) {
            Err(MeshIoError::Parse { line: Some(5), message, .. }) => {
                assert!(message.contains("is not a number"), "{message}")
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn ascii_that_is_not_text_names_the_byte() {
        let text = format!("solid x\n{FACET}{FACET}endsolid x\n").into_bytes();
        let mut bad = text.clone();
        bad[40] = 0x01;
        match read_stl(&bad[..]) {
            Err(e @ MeshIoError::Parse { line: Some(4), offset: Some(40), .. }) => {
                let message = e.to_string();
                assert!(message.contains("byte 40 is the control character 0x01"), "{message}");
                assert!(message.contains("triangles where the data holds at most"), "{message}");
            }
            other => panic!("{other:?}"),
        }
        let short = b"solid x\n\x02";
        assert!(read_stl(&short[..]).unwrap_err().to_string().contains("shorter than the 84-byte header"));
    }

    #[test]
    fn binary_bytes_after_the_declared_triangles_are_reported() {
        let mut bytes = written(&tetrahedron(), MeshFormat::StlBinary);
        bytes[..6].copy_from_slice(b"solid ");
        let exact = bytes.len();
        let trailing = |extra: &[u8]| {
            let read = warned(&[&bytes[..], extra].concat());
            assert_eq!(read.mesh.triangles.len(), 4, "the declared triangles are read");
            read.warnings
        };
        let records = |bytes, records| vec![ReadWarning::StlTrailingBytes { declared: 4, bytes, records }];
        // Padding.
        assert_eq!(trailing(&[0; 7]), records(7, None));
        assert_eq!(trailing(&[0; 100]), records(100, None), "zero records are padding");
        // Two more triangles than the header counts.
        let more = trailing(&bytes[HEADER..HEADER + 2 * RECORD]);
        assert_eq!(more, records(100, Some(2)));
        assert!(more[0].to_string().contains("exactly 2 more 50-byte records"), "{}", more[0]);
        // Far-away or non-finite "records" are not triangles.
        let mut far = bytes[HEADER..HEADER + RECORD].to_vec();
        far[12..16].copy_from_slice(&1e9f32.to_le_bytes());
        assert_eq!(trailing(&far), records(50, None));
        assert_eq!(exact, HEADER + 4 * RECORD);
    }

    /// The 12 triangles of the unit cube as a soup, outward.
    fn cube_soup() -> Vec<Facet> {
        let corner = |i: usize| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).map(|t| t.map(corner)).collect()
    }

    #[test]
    fn noisy_cad_coordinates_weld_closed() {
        let mut soup = cube_soup();
        // CAD noise: 1e-12 where 0 is meant, an ulp off where 1 is meant.
        for (t, facet) in soup.iter_mut().enumerate() {
            for (k, p) in facet.iter_mut().enumerate() {
                if (t + k) % 3 == 0 {
                    *p = p
                        .to_array()
                        .map(|c| if c == 0.0 { 1e-12 } else { f32::from_bits(c.to_bits() + 1) })
                        .into();
                }
            }
        }
        let mesh = TriMesh {
            positions: soup.iter().flatten().copied().collect(),
            triangles: (0..12).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
            normals: None,
            colors: None,
        };
        let read = warned(&written(&mesh, MeshFormat::StlBinary));
        assert_eq!(read.mesh.positions.len(), 8);
        assert_eq!(read.mesh.edge_stats().boundary_edges, 0, "closed");
        assert_eq!(read.mesh.genus(), Some(0));
        // The first occurrence's position is kept.
        assert_eq!(read.mesh.positions[0], soup[0][0]);
        match &read.warnings[..] {
            [ReadWarning::StlWeldedWithinTolerance { corners, tolerance, collapsed_triangles: 0 }] => {
                assert!(*corners > 0);
                assert_eq!(
                    *tolerance,
                    4.0 * f64::from(f32::EPSILON) * f64::from(f32::from_bits(1.0f32.to_bits() + 1))
                );
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn welding_is_not_split_by_cell_boundaries() {
        let mut soup = cube_soup();
        let tol = tolerance(&soup);
        let cell = 4.0 * tol;
        let boundary = (0.5 / cell).round() * cell;
        let [below, above] = [-0.3, 0.3].map(|d| (boundary + d * tol) as f32);
        assert_ne!((f64::from(below) / cell).floor(), (f64::from(above) / cell).floor(), "straddles");
        soup.push([Vec3::new(below, 0.5, 0.5), Vec3::new(0.5, 0.7, 0.5), Vec3::new(0.5, 0.5, 0.7)]);
        soup.push([Vec3::new(above, 0.5, 0.5), Vec3::new(0.5, 0.5, 0.7), Vec3::new(0.5, 0.6, 0.6)]);
        let mut warnings = Vec::new();
        let mesh = weld(&soup, &mut warnings).unwrap();
        assert_eq!(mesh.triangles[12][0], mesh.triangles[13][0]);
        assert_eq!(mesh.positions.len(), 8 + 4);
    }

    #[test]
    fn fine_meshes_keep_their_vertices() {
        // Strips of triangles 1e-5 apart near the unit cube (84 ulps at 1)
        // and 1e-3 apart near x = 1000 (16 ulps there, but the part is tiny).
        for (origin, step) in [(Vec3::ZERO, 1e-5f32), (Vec3::new(1000.0, 0.0, 0.0), 1e-3)] {
            let mut soup = cube_soup();
            if origin.x > 0.0 {
                soup.clear();
            }
            let at = |i: usize, j: usize| origin + Vec3::new(i as f32 * step, j as f32 * step, 0.0);
            for i in 0..10 {
                soup.push([at(i, 0), at(i + 1, 0), at(i, 1)]);
                soup.push([at(i + 1, 0), at(i + 1, 1), at(i, 1)]);
            }
            let mut warnings = Vec::new();
            let mesh = weld(&soup, &mut warnings).unwrap();
            let expected = if origin.x > 0.0 { 22 } else { 8 + 22 - 1 };
            assert_eq!(mesh.positions.len(), expected, "{origin}");
            assert_eq!(warnings, vec![], "{origin}");
        }
    }
}
