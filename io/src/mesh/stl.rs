//! STL: binary records read here, ASCII read through `stl_io`; the triangle
//! soup is welded into an indexed mesh.

use super::{MeshFormat, MeshIoError};
use glam::Vec3;
use isomorph_common::TriMesh;
use std::collections::HashMap;
use std::io::{self, Cursor, Read, Write};

const FORMAT: &str = "STL";
/// Bytes before the first binary record: 80-byte header and `u32` count.
const HEADER: usize = 84;
/// Bytes of a binary record: normal, three vertices (12 `f32`), attribute.
const RECORD: usize = 50;

/// Reads an STL mesh, ASCII or binary.
///
/// The encoding is detected from the content: binary when the size matches
/// the triangle count in the header exactly (even if the header starts with
/// `solid`), ASCII when the data starts with `solid` and is UTF-8 text, binary
/// otherwise. Bit-identical positions are welded into one vertex (`-0.0`
/// equals `0.0`), numbered in order of first appearance; stored facet normals
/// are ignored, so the result has no normals. The whole input is read into
/// memory first.
///
/// # Errors
/// [`MeshIoError::Parse`] for a malformed facet or a non-finite coordinate
/// (with the byte offset for binary, the facet number for ASCII) or binary
/// data shorter than its header; [`MeshIoError::TooLarge`] when the binary
/// triangle count does not fit in the data; [`MeshIoError::Unsupported`]
/// beyond `u32::MAX` distinct vertices; [`MeshIoError::Io`] when reading
/// fails.
pub fn read_stl(mut reader: impl Read) -> Result<TriMesh, MeshIoError> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes)?;
    if is_binary(&bytes) { read_binary(&bytes) } else { read_ascii(&bytes) }
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
    exact_size || !(bytes.trim_ascii_start().starts_with(b"solid") && std::str::from_utf8(bytes).is_ok())
}

fn read_binary(bytes: &[u8]) -> Result<TriMesh, MeshIoError> {
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
    let mut welder = Welder::with_capacity(count as usize);
    for (t, record) in bytes[HEADER..].chunks_exact(RECORD).take(count as usize).enumerate() {
        let float =
            |at: usize| f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]]);
        let corner = |k: usize| Vec3::new(float(12 + 12 * k), float(16 + 12 * k), float(20 + 12 * k));
        let corners = [corner(0), corner(1), corner(2)];
        if let Some(k) = corners.iter().position(|p| !p.is_finite()) {
            let offset = (HEADER + t * RECORD + 12 + 12 * k) as u64;
            let message = format!("triangle {t} has a non-finite coordinate");
            return Err(MeshIoError::parse(FORMAT, None, Some(offset), &message));
        }
        welder.push(corners)?;
    }
    welder.finish()
}

fn read_ascii(bytes: &[u8]) -> Result<TriMesh, MeshIoError> {
    // `stl_io` wants `solid ` with a space on the first line; an unnamed
    // `solid` (or leading blank space) gets one.
    let body = bytes.trim_ascii_start();
    let patched;
    let data = if body.starts_with(b"solid ") {
        body
    } else {
        patched = [b"solid ", body.strip_prefix(b"solid").unwrap_or(body)].concat();
        &patched[..]
    };
    let mut cursor = Cursor::new(data);
    let stl_error = |facet: Option<usize>, e: io::Error| {
        let message = match facet {
            Some(t) => format!("facet {t}: {e}"),
            None => e.to_string(),
        };
        MeshIoError::parse(FORMAT, None, None, &message)
    };
    let facets = stl_io::create_stl_reader(&mut cursor).map_err(|e| stl_error(None, e))?;
    let mut welder = Welder::with_capacity(0);
    for (t, facet) in facets.enumerate() {
        let facet = facet.map_err(|e| stl_error(Some(t), e))?;
        welder.push(facet.vertices.map(|v| Vec3::from_array(v.0)))?;
    }
    welder.finish()
}

/// Welds a triangle soup into an indexed mesh.
struct Welder {
    /// Position bit patterns (with `-0.0` as `0.0`) → vertex index.
    index: HashMap<[u32; 3], u32>,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Welder {
    fn with_capacity(triangles: usize) -> Self {
        Welder { index: HashMap::new(), positions: Vec::new(), triangles: Vec::with_capacity(triangles) }
    }

    fn push(&mut self, corners: [Vec3; 3]) -> Result<(), MeshIoError> {
        let mut triangle = [0; 3];
        for (slot, p) in triangle.iter_mut().zip(corners) {
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            let next = self.positions.len();
            *slot = match self.index.get(&key) {
                Some(&i) => i,
                None => {
                    let i = u32::try_from(next).map_err(|_| MeshIoError::Unsupported {
                        format: FORMAT,
                        message: "more than u32::MAX distinct vertices".to_owned(),
                    })?;
                    self.index.insert(key, i);
                    self.positions.push(p);
                    i
                }
            };
        }
        self.triangles.push(triangle);
        Ok(())
    }

    fn finish(self) -> Result<TriMesh, MeshIoError> {
        let mesh = TriMesh { positions: self.positions, triangles: self.triangles, normals: None };
        mesh.validate()?;
        Ok(mesh)
    }
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
}
