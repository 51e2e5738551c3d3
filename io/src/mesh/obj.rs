//! Wavefront OBJ: `v`, `vn` and `f` records (every other record is skipped).

use super::MeshIoError;
use glam::Vec3;
use isomorph_common::TriMesh;
use std::io::{self, BufRead, Write};

const FORMAT: &str = "OBJ";

/// Marks a vertex that no face corner has given a normal yet.
const NO_NORMAL: u32 = u32::MAX;

/// Reads a Wavefront OBJ mesh.
///
/// Vertices keep their file order (unreferenced ones included); all objects
/// and groups go into one mesh; polygons are fan-triangulated; negative
/// (relative) indices are resolved. Normals are kept when every face corner
/// names one (`v//vn` or `v/vt/vn`), each vertex always gets the same normal
/// and all are finite; vertices used by no face then get a zero normal.
/// Texture coordinates, materials, `w` weights and vertex colours are
/// ignored.
///
/// # Errors
/// [`MeshIoError::Parse`] with the line number for a bad number, a
/// non-finite coordinate, a face with fewer than three corners, an index of 0
/// or one that refers to a vertex or normal not defined before it, or more
/// vertices or normals than `u32` indices reach; [`MeshIoError::Io`] when
/// reading fails.
pub fn read_obj(mut reader: impl BufRead) -> Result<TriMesh, MeshIoError> {
    let mut parser = ObjParser::default();
    let mut line = Vec::new();
    let mut number = 0;
    loop {
        line.clear();
        if reader.read_until(b'\n', &mut line)? == 0 {
            break;
        }
        number += 1;
        parser.line(&line).map_err(|message| MeshIoError::parse(FORMAT, Some(number), None, &message))?;
    }
    parser.finish()
}

/// The state of an OBJ read.
#[derive(Default)]
struct ObjParser {
    positions: Vec<Vec3>,
    /// The `vn` records.
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per vertex: the `vn` index its face corners name, or [`NO_NORMAL`].
    vertex_normal: Vec<u32>,
    /// Some face corner named no normal.
    corner_without_normal: bool,
    /// Some vertex was given two different normals.
    normals_conflict: bool,
    /// Scratch: the (vertex, normal) corners of the current face.
    corners: Vec<(u32, Option<u32>)>,
}

impl ObjParser {
    /// Parses one line (with or without its line break).
    fn line(&mut self, line: &[u8]) -> Result<(), String> {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(hash) => &line[..hash],
            None => line,
        };
        let mut tokens = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
        match tokens.next() {
            Some(b"v") => {
                if self.positions.len() >= NO_NORMAL as usize {
                    return Err(format!("more than {} vertices", NO_NORMAL - 1));
                }
                let p = vec3(&mut tokens, "vertex")?;
                if !p.is_finite() {
                    return Err(format!("vertex {} has a non-finite coordinate", self.positions.len() + 1));
                }
                self.positions.push(p);
                self.vertex_normal.push(NO_NORMAL);
            }
            Some(b"vn") => {
                if self.normals.len() >= NO_NORMAL as usize {
                    return Err(format!("more than {} normals", NO_NORMAL - 1));
                }
                self.normals.push(vec3(&mut tokens, "normal")?);
            }
            Some(b"f") => self.face(tokens)?,
            _ => {}
        }
        Ok(())
    }

    /// Parses the corners of an `f` record and fan-triangulates them.
    fn face<'a>(&mut self, tokens: impl Iterator<Item = &'a [u8]>) -> Result<(), String> {
        self.corners.clear();
        for token in tokens {
            let mut parts = token.split(|&b| b == b'/');
            let vertex = resolve(parts.next().unwrap_or_default(), self.positions.len(), "vertices")?;
            let _texture = parts.next();
            let normal = match parts.next() {
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

    /// The mesh, with normals when they are complete and consistent.
    fn finish(self) -> Result<TriMesh, MeshIoError> {
        let usable = !self.triangles.is_empty() && !self.corner_without_normal && !self.normals_conflict;
        let normals = usable
            .then(|| {
                self.vertex_normal
                    .iter()
                    .map(|&k| if k == NO_NORMAL { Vec3::ZERO } else { self.normals[k as usize] })
                    .collect::<Vec<_>>()
            })
            .filter(|normals| normals.iter().all(|n| n.is_finite()));
        let mesh = TriMesh { positions: self.positions, triangles: self.triangles, normals };
        mesh.validate()?;
        Ok(mesh)
    }
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

/// Writes `v`, optional `vn` (one per vertex) and `f` records with 1-based
/// indices; coordinates use the shortest decimal that round-trips the `f32`.
pub(super) fn write_obj(mesh: &TriMesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "# isomorph: {} vertices, {} triangles", mesh.positions.len(), mesh.triangles.len())?;
    for p in &mesh.positions {
        writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
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
        assert_eq!(parse_line(read(&format!("{tri}f 1//1 2 3\n"))), Some(4), "no vn defined");
        assert_eq!(parse_line(read(&format!("{tri}f 1 2 99999999999999999999999\n"))), Some(4));
        assert_eq!(parse_line(read("v 0 0\n")), Some(1));
        assert_eq!(parse_line(read("v 0 0 zero\n")), Some(1));
        assert_eq!(parse_line(read("\n\nv nan 0 0\n")), Some(3));
        assert_eq!(parse_line(read("v inf 0 0\n")), Some(1));
        assert_eq!(parse_line(read("v 0 0 \u{0}\n")), Some(1));
        // Forward references are not allowed.
        assert_eq!(parse_line(read("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")), Some(1));
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
