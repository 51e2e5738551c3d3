//! Wavefront OBJ: `v`, `vn` and `f` records (every other record is skipped).

use super::{MeshIoError, MeshRead, ReadWarning, is_control};
use glam::Vec3;
use isomorph_common::TriMesh;
use std::io::{self, BufRead, Write};

const FORMAT: &str = "OBJ";

/// The longest OBJ line [`read_obj`] accepts, in bytes (4 MiB), counting
/// the lines joined by `\` continuations; a longer line is a
/// [`MeshIoError::LineTooLong`].
pub const OBJ_MAX_LINE_BYTES: usize = 4 << 20;

/// Marks a vertex that no face corner has given a normal yet.
const NO_NORMAL: u32 = u32::MAX;

/// Distinct keywords reported by [`ReadWarning::ObjStatementsSkipped`]; the
/// rest are counted under `"…"`.
const MAX_SKIPPED_KEYWORDS: usize = 16;

/// OBJ statements that are read but not used (grouping, smoothing,
/// materials, texture and parameter-space vertices, the free-form
/// attributes), skipped without a word.
const IGNORED: [&str; 30] = [
    "vt",
    "vp",
    "g",
    "o",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "cstype",
    "deg",
    "bmat",
    "step",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "res",
];

/// OBJ geometry statements this reader does not build (lines, points, curves
/// and surfaces); skipped with a [`ReadWarning::ObjStatementsSkipped`].
const UNREAD_GEOMETRY: [&str; 9] = ["l", "p", "curv", "curv2", "surf", "bsp", "bzp", "cdc", "cdp"];

/// Whether `keyword` names geometry this reader skips (for warnings).
pub(super) fn is_unread_geometry(keyword: &str) -> bool {
    UNREAD_GEOMETRY.contains(&keyword)
}

/// Reads a Wavefront OBJ mesh.
///
/// Vertices keep their file order (unreferenced ones included); all objects
/// and groups go into one mesh; polygons (`f`, and the old `fo`) are
/// fan-triangulated; negative (relative) indices are resolved. Normals are
/// kept when every face corner names one (`v//vn` or `v/vt/vn`), each vertex
/// always gets the same normal and all are finite; vertices used by no face
/// then get a zero normal. Vertex colours (the common extension `v x y z r
/// g b`, floats in `0..1`) are kept when every vertex has one; when only
/// some have, they are dropped with [`ReadWarning::ObjColorsDropped`].
/// Texture coordinates, materials and `w` weights (`v x y z w`) are
/// ignored, and texture indices are not checked.
///
/// Lines end at `\n`, `\r\n` or a lone `\r` (old Mac files); a line whose
/// last non-blank character is `\` continues on the next one (unless it
/// holds a `#` comment), as Rhino writes long `f` lines. A line may hold at
/// most [`OBJ_MAX_LINE_BYTES`].
///
/// Leniency, reported through [`read_mesh_from_with_warnings`]
/// (`read_obj` itself drops the warnings): a face corner naming a normal or
/// texture coordinate while none is defined before it loses that reference
/// ([`ReadWarning::ObjNormalsDropped`], [`ReadWarning::ObjTexturesDropped`]);
/// unknown statements and the geometry not built (`l`, `p`, curves,
/// surfaces) are skipped ([`ReadWarning::ObjStatementsSkipped`]).
///
/// What is not an OBJ file: data holding a control character (other than
/// tab, line feed, form feed, carriage return), i.e. binary data, is refused
/// at the first line holding one; text in which no line is a known OBJ
/// statement (only comments and blank lines are fine: an empty mesh) is
/// refused at its first statement. Names in `g`, `o`, `usemtl` and comments
/// may be in any encoding.
///
/// [`read_mesh_from_with_warnings`]: super::read_mesh_from_with_warnings
///
/// # Errors
/// [`MeshIoError::Parse`] with the line number for a bad number, a
/// non-finite coordinate, a face with fewer than three corners, an index of 0
/// or one that refers to a vertex or normal not defined before it (when some
/// are), more vertices or normals than `u32` indices reach, or data that is
/// not an OBJ file (see above); [`MeshIoError::LineTooLong`];
/// [`MeshIoError::Io`] when reading fails.
pub fn read_obj(reader: impl BufRead) -> Result<TriMesh, MeshIoError> {
    read(reader).map(|read| read.mesh)
}

/// [`read_obj`] with its warnings.
pub(super) fn read(reader: impl BufRead) -> Result<MeshRead, MeshIoError> {
    let mut lines = Lines { reader, after_cr: false, physical: 0 };
    let mut parser = ObjParser::default();
    let mut line = Vec::new();
    while let Some(number) = lines.next(&mut line)? {
        parser
            .line(&line, number)
            .map_err(|message| MeshIoError::parse(FORMAT, Some(number), None, &message))?;
    }
    parser.finish()
}

/// Logical lines of OBJ text: any line break, `\` continuations, bounded
/// length.
struct Lines<R> {
    reader: R,
    /// The last physical line ended with `\r`: a `\n` next belongs to it.
    after_cr: bool,
    /// Physical lines read so far.
    physical: usize,
}

impl<R: BufRead> Lines<R> {
    /// Reads the next logical line into `line` (without line breaks, a
    /// continuation `\` becoming a space); its first physical line number,
    /// or `None` at the end of the data.
    fn next(&mut self, line: &mut Vec<u8>) -> Result<Option<usize>, MeshIoError> {
        line.clear();
        let first = self.physical + 1;
        loop {
            let start = line.len();
            if !self.physical_line(line, first)? {
                return Ok((self.physical >= first).then_some(first));
            }
            let end =
                line[start..].iter().rposition(|&b| b != b' ' && b != b'\t').map_or(start, |i| start + i);
            if line.get(end) != Some(&b'\\') || line.contains(&b'#') {
                return Ok(Some(first));
            }
            line.truncate(end);
            line.push(b' ');
        }
    }

    /// Appends the next physical line to `out`, without its line break;
    /// false when the data ended before any byte of it.
    fn physical_line(&mut self, out: &mut Vec<u8>, first: usize) -> Result<bool, MeshIoError> {
        let mut seen = false;
        loop {
            let buf = match self.reader.fill_buf() {
                Ok(buf) => buf,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e.into()),
            };
            if buf.is_empty() {
                self.physical += usize::from(seen);
                return Ok(seen);
            }
            if std::mem::take(&mut self.after_cr) && buf[0] == b'\n' {
                self.reader.consume(1);
                continue;
            }
            seen = true;
            let end = buf.iter().position(|&b| b == b'\n' || b == b'\r');
            let take = end.unwrap_or(buf.len());
            if out.len() + take > OBJ_MAX_LINE_BYTES {
                return Err(MeshIoError::LineTooLong {
                    format: FORMAT,
                    line: first,
                    limit: OBJ_MAX_LINE_BYTES,
                });
            }
            out.extend_from_slice(&buf[..take]);
            match end {
                Some(i) => {
                    self.after_cr = buf[i] == b'\r';
                    self.reader.consume(i + 1);
                    self.physical += 1;
                    return Ok(true);
                }
                None => self.reader.consume(take),
            }
        }
    }
}

/// Corners whose references were dropped, and the first line of one.
#[derive(Default)]
struct Dropped {
    corners: u64,
    first_line: usize,
}

impl Dropped {
    fn add(&mut self, line: usize) {
        if self.corners == 0 {
            self.first_line = line;
        }
        self.corners += 1;
    }
}

/// Lines of one skipped keyword.
struct Skipped {
    keyword: String,
    lines: u64,
    first_line: usize,
}

/// The state of an OBJ read.
#[derive(Default)]
struct ObjParser {
    positions: Vec<Vec3>,
    /// The colours of the `v` records that have one (`v x y z r g b`).
    colors: Vec<Vec3>,
    /// The line of the first `v` record without a colour.
    uncolored: Option<usize>,
    /// The `vn` records.
    normals: Vec<Vec3>,
    /// How many `vt` records came so far.
    texcoords: usize,
    triangles: Vec<[u32; 3]>,
    /// Per vertex: the `vn` index its face corners name, or [`NO_NORMAL`].
    vertex_normal: Vec<u32>,
    /// Some face corner named no normal.
    corner_without_normal: bool,
    /// Some vertex was given two different normals.
    normals_conflict: bool,
    /// Scratch: the (vertex, normal) corners of the current face.
    corners: Vec<(u32, Option<u32>)>,
    /// Some line held a known OBJ statement.
    recognized: bool,
    /// Normal references dropped (no `vn` before them).
    normals_dropped: Dropped,
    /// Texture references dropped (no `vt` before them).
    textures_dropped: Dropped,
    /// Skipped statements by keyword, in order of first appearance.
    skipped: Vec<Skipped>,
}

impl ObjParser {
    /// Parses logical line `number` (without its line break).
    fn line(&mut self, line: &[u8], number: usize) -> Result<(), String> {
        if let Some(&byte) = line.iter().find(|&&b| is_control(b)) {
            return Err(format!("control byte 0x{byte:02x}: binary data, not an OBJ file"));
        }
        let line = match line.iter().position(|&b| b == b'#') {
            Some(hash) => &line[..hash],
            None => line,
        };
        let mut tokens = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
        let Some(keyword) = tokens.next() else { return Ok(()) };
        match keyword {
            b"v" => {
                if self.positions.len() >= NO_NORMAL as usize {
                    return Err(format!("more than {} vertices", NO_NORMAL - 1));
                }
                let p = vec3(&mut tokens, "vertex")?;
                if !p.is_finite() {
                    return Err(format!("vertex {} has a non-finite coordinate", self.positions.len() + 1));
                }
                match color(tokens) {
                    Some(c) => self.colors.push(c),
                    None => {
                        self.uncolored.get_or_insert(number);
                    }
                }
                self.positions.push(p);
                self.vertex_normal.push(NO_NORMAL);
            }
            b"vn" => {
                if self.normals.len() >= NO_NORMAL as usize {
                    return Err(format!("more than {} normals", NO_NORMAL - 1));
                }
                self.normals.push(vec3(&mut tokens, "normal")?);
            }
            b"f" | b"fo" => self.face(tokens, number)?,
            b"vt" => self.texcoords += 1,
            _ => {
                let known = std::str::from_utf8(keyword).is_ok_and(|k| IGNORED.contains(&k));
                if !known {
                    self.skip(keyword, number);
                    let geometry = std::str::from_utf8(keyword).is_ok_and(is_unread_geometry);
                    if !geometry {
                        return Ok(());
                    }
                }
            }
        }
        self.recognized = true;
        Ok(())
    }

    /// Counts a skipped statement under its keyword.
    fn skip(&mut self, keyword: &[u8], number: usize) {
        let keyword = if self.skipped.len() < MAX_SKIPPED_KEYWORDS
            || self.skipped.iter().any(|s| s.keyword.as_bytes() == keyword)
        {
            String::from_utf8_lossy(&keyword[..keyword.len().min(32)]).into_owned()
        } else {
            "…".to_owned()
        };
        match self.skipped.iter_mut().find(|s| s.keyword == keyword) {
            Some(s) => s.lines += 1,
            None => self.skipped.push(Skipped { keyword, lines: 1, first_line: number }),
        }
    }

    /// Parses the corners of an `f` record on line `number` and
    /// fan-triangulates them.
    fn face<'a>(&mut self, tokens: impl Iterator<Item = &'a [u8]>, number: usize) -> Result<(), String> {
        self.corners.clear();
        for token in tokens {
            let mut parts = token.split(|&b| b == b'/');
            let vertex = resolve(parts.next().unwrap_or_default(), self.positions.len(), "vertices")?;
            if parts.next().is_some_and(|t| !t.is_empty()) && self.texcoords == 0 {
                self.textures_dropped.add(number);
            }
            let normal = match parts.next() {
                Some(part) if !part.is_empty() && self.normals.is_empty() => {
                    self.normals_dropped.add(number);
                    None
                }
                Some(part) if !part.is_empty() => Some(resolve(part, self.normals.len(), "normals")?),
                _ => None,
            };
            self.corners.push((vertex, normal));
        }
        if self.corners.len() < 3 {
            return Err(format!("a face needs at least 3 vertices, found {}", self.corners.len()));
        }
        for &(vertex, normal) in &self.corners {
            let Some(normal) = normal else {
                self.corner_without_normal = true;
                continue;
            };
            let slot = &mut self.vertex_normal[vertex as usize];
            if *slot == NO_NORMAL {
                *slot = normal;
            } else if *slot != normal && self.normals[*slot as usize] != self.normals[normal as usize] {
                self.normals_conflict = true;
            }
        }
        let first = self.corners[0].0;
        for pair in self.corners[1..].windows(2) {
            self.triangles.push([first, pair[0].0, pair[1].0]);
        }
        Ok(())
    }

    /// The mesh, with normals when they are complete and consistent, and the
    /// warnings.
    fn finish(self) -> Result<MeshRead, MeshIoError> {
        if !self.recognized
            && let Some(first) = self.skipped.first()
        {
            let message = format!(
                "not an OBJ file: no line holds an OBJ statement (this one starts with '{}')",
                first.keyword
            );
            return Err(MeshIoError::parse(FORMAT, Some(first.first_line), None, &message));
        }
        let usable = !self.triangles.is_empty() && !self.corner_without_normal && !self.normals_conflict;
        let normals = usable
            .then(|| {
                self.vertex_normal
                    .iter()
                    .map(|&k| if k == NO_NORMAL { Vec3::ZERO } else { self.normals[k as usize] })
                    .collect::<Vec<_>>()
            })
            .filter(|normals| normals.iter().all(|n| n.is_finite()));
        let mut warnings = Vec::new();
        let colors = match self.uncolored {
            None if !self.positions.is_empty() => Some(self.colors),
            Some(first_line) if !self.colors.is_empty() => {
                let vertices = self.positions.len();
                let uncolored = vertices - self.colors.len();
                warnings.push(ReadWarning::ObjColorsDropped { uncolored, vertices, first_line });
                None
            }
            _ => None,
        };
        let mesh = TriMesh { positions: self.positions, triangles: self.triangles, normals, colors };
        mesh.validate()?;
        let Dropped { corners, first_line } = self.normals_dropped;
        if corners > 0 {
            warnings.push(ReadWarning::ObjNormalsDropped { corners, first_line });
        }
        let Dropped { corners, first_line } = self.textures_dropped;
        if corners > 0 {
            warnings.push(ReadWarning::ObjTexturesDropped { corners, first_line });
        }
        warnings.extend(self.skipped.into_iter().map(|Skipped { keyword, lines, first_line }| {
            ReadWarning::ObjStatementsSkipped { keyword, lines, first_line }
        }));
        Ok(MeshRead { mesh, warnings })
    }
}

/// The colour of a `v` record after its `x y z`: exactly three further
/// numbers; `None` otherwise (none, a `w` weight, or anything else).
fn color<'a>(rest: impl Iterator<Item = &'a [u8]>) -> Option<Vec3> {
    let mut rgb = [0.0f32; 3];
    let mut count = 0;
    for token in rest {
        let value = std::str::from_utf8(token).ok()?.parse().ok()?;
        *rgb.get_mut(count)? = value;
        count += 1;
    }
    (count == 3).then(|| Vec3::from_array(rgb))
}

/// Parses three numbers (further ones, such as `w` or colours, are ignored).
fn vec3<'a>(tokens: &mut impl Iterator<Item = &'a [u8]>, what: &str) -> Result<Vec3, String> {
    let mut xyz = [0.0f32; 3];
    for (i, c) in xyz.iter_mut().enumerate() {
        let token = tokens.next().ok_or_else(|| format!("a {what} needs 3 coordinates, found {i}"))?;
        *c = std::str::from_utf8(token).ok().and_then(|s| s.parse().ok()).ok_or_else(|| {
            format!("{what} coordinate '{}' is not a number", String::from_utf8_lossy(token))
        })?;
    }
    Ok(Vec3::from_array(xyz))
}

/// Resolves a 1-based or negative (relative) OBJ index against the `count`
/// `items` (a plural noun) defined so far, to a 0-based index.
fn resolve(token: &[u8], count: usize, items: &str) -> Result<u32, String> {
    let text = String::from_utf8_lossy(token);
    let index: i64 = text.parse().map_err(|_| format!("index '{text}' into {items} is not an integer"))?;
    let resolved = match index {
        0 => return Err(format!("index 0 into {items} (OBJ indices start at 1)")),
        i if i > 0 => i - 1,
        i => count as i64 + i,
    };
    if resolved < 0 || resolved >= count as i64 {
        return Err(format!("index {index} is out of range: {count} {items} defined before this line"));
    }
    // `count` never exceeds `u32::MAX`, see `ObjParser::line`.
    Ok(resolved as u32)
}

/// Writes `v` (`v x y z r g b` with colours), optional `vn` (one per
/// vertex) and `f` records with 1-based
/// indices; coordinates use the shortest decimal that round-trips the `f32`.
pub(super) fn write_obj(mesh: &TriMesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "# isomorph: {} vertices, {} triangles", mesh.positions.len(), mesh.triangles.len())?;
    match &mesh.colors {
        Some(colors) => {
            for (p, c) in mesh.positions.iter().zip(colors) {
                writeln!(out, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z)?;
            }
        }
        None => {
            for p in &mesh.positions {
                writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
            }
        }
    }
    if let Some(normals) = &mesh.normals {
        for n in normals {
            writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        if mesh.normals.is_some() {
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(out, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<TriMesh, MeshIoError> {
        read_obj(text.as_bytes())
    }

    fn parse_line(err: Result<TriMesh, MeshIoError>) -> Option<usize> {
        match err {
            Err(MeshIoError::Parse { format: "OBJ", line, .. }) => line,
            other => panic!("expected an OBJ parse error, got {other:?}"),
        }
    }

    #[test]
    fn polygons_groups_comments_and_relative_indices() {
        let mesh = read(
            "# a pentagon and a triangle in two groups\n\
             o first\nv 0 0 0\nv 1 0 0\nv 1 1 0 # trailing comment\nv 0.5 1.5 0\nv 0 1 0\n\
             vt 0 0\nf 1/1 2/1 3/1 4/1 5/1\n\
             g second\nv 0 0 1\r\nf -1 -5 -4\r\n",
        )
        .unwrap();
        assert_eq!(mesh.positions.len(), 6);
        assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 1, 2]]);
        assert!(mesh.normals.is_none());
    }

    #[test]
    fn unreferenced_vertices_keep_their_place() {
        let mesh = read("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 2 3 4\n").unwrap();
        assert_eq!(mesh.positions[0], Vec3::splat(9.0));
        assert_eq!(mesh.triangles, vec![[1, 2, 3]]);
    }

    #[test]
    fn normals_kept_only_when_complete_and_consistent() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 7 7 7\nvn 0 0 1\nvn 0 0 1\nvn 1 0 0\n";
        let ok = read(&format!("{base}f 1//1 2//2 3//1\n")).unwrap();
        let n = ok.normals.expect("complete normals are kept");
        assert_eq!(n, vec![Vec3::Z, Vec3::Z, Vec3::Z, Vec3::ZERO]);
        // Same vertex, different normal (a hard edge): no per-vertex normals.
        assert!(read(&format!("{base}f 1//1 2//1 3//1\nf 1//3 3//1 2//1\n")).unwrap().normals.is_none());
        // A corner without a normal.
        assert!(read(&format!("{base}f 1//1 2 3//1\n")).unwrap().normals.is_none());
        // Non-finite normal.
        let nan = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan 0 1\nf 1//1 2//1 3//1\n";
        assert!(read(nan).unwrap().normals.is_none());
    }

    #[test]
    fn bad_input_names_the_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert_eq!(parse_line(read(&format!("{tri}f 1 2 4\n"))), Some(4));
        assert_eq!(parse_line(read(&format!("{tri}f 1 2 0\n"))), Some(4));
        assert_eq!(parse_line(read(&format!("{tri}f 1 2 -4\n"))), Some(4));
        assert_eq!(parse_line(read(&format!("{tri}f 1 2\n"))), Some(4));
        assert_eq!(parse_line(read(&format!("{tri}f 1 2 x\n"))), Some(4));
        assert_eq!(parse_line(read(&format!("{tri}vn 0 0 1\nf 1//2 2 3\n"))), Some(5), "one vn defined");
        assert_eq!(parse_line(read(&format!("{tri}f 1 2 99999999999999999999999\n"))), Some(4));
        assert_eq!(parse_line(read("v 0 0\n")), Some(1));
        assert_eq!(parse_line(read("v 0 0 zero\n")), Some(1));
        assert_eq!(parse_line(read("\n\nv nan 0 0\n")), Some(3));
        assert_eq!(parse_line(read("v inf 0 0\n")), Some(1));
        assert_eq!(parse_line(read("v 0 0 \u{0}\n")), Some(1));
        // Forward references are not allowed.
        assert_eq!(parse_line(read("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")), Some(1));
    }

    /// Reads `text` with its warnings.
    fn warned(text: &[u8]) -> MeshRead {
        super::read(text).unwrap()
    }

    #[test]
    fn a_line_without_end_is_refused_at_the_limit() {
        // An endless "line" (a device, or a huge file without line breaks):
        // refused once it passes the limit, without holding more.
        let endless = io::BufReader::new(io::repeat(b'7'));
        match read_obj(endless) {
            Err(MeshIoError::LineTooLong { format: "OBJ", line: 1, limit: OBJ_MAX_LINE_BYTES }) => {}
            other => panic!("{other:?}"),
        }
        let after = io::Read::chain(&b"v 0 0 0\r\n\n"[..], io::repeat(b' '));
        assert!(matches!(read_obj(io::BufReader::new(after)), Err(MeshIoError::LineTooLong { line: 3, .. })));
        // Exactly at the limit is still a line.
        let long = [b"# ".as_slice(), &vec![b'x'; OBJ_MAX_LINE_BYTES - 2], b"\nv 0 0 0\n"].concat();
        assert_eq!(read_obj(&long[..]).unwrap().positions.len(), 1);
    }

    #[test]
    fn any_line_break_ends_a_line() {
        let tri = "v 0 0 0\rv 1 0 0\r\nv 0 1 0\nf 1 2 3\r";
        let mesh = read(tri).unwrap();
        assert_eq!((mesh.positions.len(), mesh.triangles.len()), (3, 1), "old Mac line breaks");
        // CRLF is one break, even when a buffer boundary falls between its
        // bytes; a lone CR is one too.
        for capacity in [1, 2, 3, 64] {
            let text = b"v 0 0 0\r\n\r\n\rv 0 x 0\r\n";
            let reader = io::BufReader::with_capacity(capacity, &text[..]);
            assert_eq!(parse_line(read_obj(reader)), Some(4), "capacity {capacity}");
        }
    }

    #[test]
    fn backslash_continues_a_line() {
        let base = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
        for face in ["f 1 2 \\\n 3 4\n", "f 1 2\\\r\n3 4\r\n", "f 1 \\ \n2 \\\n3 4", "f 1 2 3 \\\n4"] {
            let mesh = read(&format!("{base}{face}")).unwrap_or_else(|e| panic!("{face:?}: {e}"));
            assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]], "{face:?}");
        }
        // Errors name the first line of the joined line; later lines keep
        // their numbers. A comment ending in a backslash joins nothing.
        assert_eq!(parse_line(read(&format!("{base}f 1 2 \\\n 3 9\n"))), Some(5));
        assert_eq!(parse_line(read(&format!("{base}f 1 2 \\\n 3 4\nv x 0 0\n"))), Some(7));
        let comment = read(&format!("{base}# C:\\models\\\nf 1 2 3\n")).unwrap();
        assert_eq!(comment.triangles.len(), 1);
    }

    #[test]
    fn binary_or_foreign_data_is_not_an_obj_file() {
        let not_obj = |bytes: &[u8]| match read_obj(bytes) {
            Err(MeshIoError::Parse { line, message, .. }) => {
                assert!(message.contains("not an OBJ file"), "{message}");
                line
            }
            other => panic!("{other:?}"),
        };
        // Random bytes with control characters; text with no OBJ statement.
        assert_eq!(not_obj(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"), Some(2));
        assert_eq!(not_obj(b"# notes\n\nhello world\nsecond line\n"), Some(3));
        assert_eq!(not_obj(b"v 0 0 0\nv 1 0 0\n\x01\x02\n"), Some(3));
        // Comments alone are a valid empty OBJ; real statements this reader
        // does not use are read without a word.
        assert_eq!(warned(b"# empty\n\n"), MeshRead { mesh: TriMesh::default(), warnings: vec![] });
        let real = warned(
            b"# exported\nmtllib a.mtl\no cube\ng side\nusemtl red\ns 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
              vt 0 0\nvt 1 0\nvt 0 1\nvp 0.5\nf 1/1 2/2 3/3\ns off\n",
        );
        assert_eq!(real.mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(real.warnings, vec![]);
    }

    #[test]
    fn skipped_statements_are_reported() {
        let read = warned(b"v 0 0 0\nv 1 0 0\nl 1 2\nfoo 7\nl 2 1\nv 0 1 0\nf 1 2 3\n");
        assert_eq!(read.mesh.triangles.len(), 1);
        let skipped = |keyword: &str, lines, first_line| ReadWarning::ObjStatementsSkipped {
            keyword: keyword.to_owned(),
            lines,
            first_line,
        };
        assert_eq!(read.warnings, vec![skipped("l", 2, 3), skipped("foo", 1, 4)]);
        assert!(read.warnings[0].to_string().contains("geometry this reader does not build"));
        // Many distinct unknown keywords: a bounded list.
        let many: String = (0..100).map(|i| format!("k{i} 1\n")).collect();
        let read = warned(format!("v 0 0 0\n{many}").as_bytes());
        assert_eq!(read.warnings.len(), MAX_SKIPPED_KEYWORDS + 1);
        assert_eq!(read.warnings.last(), Some(&skipped("…", 100 - MAX_SKIPPED_KEYWORDS as u64, 18)));
    }

    #[test]
    fn dangling_normal_and_texture_references_are_dropped_with_a_warning() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let read = warned(format!("{tri}f 1//1 2//2 3//3\nf 3/1/1 2/1 1/1/1\n").as_bytes());
        assert_eq!(read.mesh.triangles, vec![[0, 1, 2], [2, 1, 0]]);
        assert!(read.mesh.normals.is_none());
        assert_eq!(
            read.warnings,
            vec![
                ReadWarning::ObjNormalsDropped { corners: 5, first_line: 4 },
                ReadWarning::ObjTexturesDropped { corners: 3, first_line: 5 },
            ]
        );
        assert!(read.warnings[0].to_string().contains("no 'vn'"), "{}", read.warnings[0]);
        // With normals defined, a bad reference is still an error.
        assert_eq!(parse_line(read_obj(format!("{tri}vn 0 0 1\nf 1//1 2//2 3//1\n").as_bytes())), Some(5));
    }

    #[test]
    fn non_utf8_in_skipped_records_is_fine() {
        let mut bytes = b"g caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
        bytes.extend_from_slice(b"# \xff\xfe\n");
        assert_eq!(read_obj(&bytes[..]).unwrap().triangles.len(), 1);
    }

    #[test]
    fn writer_round_trips_with_and_without_normals() {
        let mut mesh = TriMesh::new(
            vec![
                Vec3::new(0.1, -0.0, 1e-30),
                Vec3::new(1e30, 0.3, -2.5),
                Vec3::new(f32::MIN_POSITIVE, 1.0, 7.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        for with_normals in [false, true] {
            if with_normals {
                mesh.compute_normals();
            }
            let mut bytes = Vec::new();
            write_obj(&mesh, &mut bytes).unwrap();
            let back = read_obj(&bytes[..]).unwrap();
            let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&back.positions), bits(&mesh.positions));
            assert_eq!(back.triangles, mesh.triangles);
            assert_eq!(back.normals, mesh.normals);
        }
    }
}
