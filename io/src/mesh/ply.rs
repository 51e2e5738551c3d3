//! PLY (ASCII, binary little- and big-endian) through `ply-rs-bw`, with the
//! element loop, the count checks and the error locations done here.

use super::{MeshFormat, MeshIoError, MeshRead, ReadWarning};
use glam::Vec3;
use isomorph_common::TriMesh;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyDef, PropertyType,
    ScalarType,
};
use ply_rs_bw::writer::Writer;
use std::collections::HashSet;
use std::io::{self, Read, Write};

const FORMAT: &str = "PLY";

/// Names of the vertex colour properties.
const COLORS: [&str; 3] = ["red", "green", "blue"];

/// Names of the face property holding the vertex indices.
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// Reads a PLY mesh (ASCII or binary of either byte order, detected from the
/// header).
///
/// Uses the `vertex` element (`x y z` of any scalar type, usually `float` or
/// `double`; `nx ny nz` when all three are present; `red green blue` when
/// all three are present, as vertex colours: `float`/`double` taken as they
/// are (`0..1`), 16-bit integers divided by 65535, other integers by 255;
/// `alpha` is ignored) and the `face` element
/// (a `vertex_indices` or `vertex_index` list of any integer type); other
/// elements and properties are skipped. Faces with more than three vertices
/// are fan-triangulated. The whole input is read into memory first.
///
/// An element or a property of one element declared twice is refused (the
/// columns after it would shift), and so is an ASCII record line with more
/// values than its element's properties take. Data after the last declared
/// element (more records than the header counts, or junk) is ignored with
/// [`ReadWarning::PlyTrailingData`], blank lines after an ASCII payload
/// excepted; warnings are dropped here, [`read_mesh_from_with_warnings`]
/// returns them.
///
/// [`read_mesh_from_with_warnings`]: super::read_mesh_from_with_warnings
///
/// # Errors
/// [`MeshIoError::Parse`] for a malformed header (with its line) or one that
/// declares an element or property twice, a malformed (in ASCII also an
/// overlong) or truncated record (with its line for ASCII, its byte offset for binary),
/// a face with fewer than three vertices or a negative index;
/// [`MeshIoError::TooLarge`] when an element count cannot fit in the data;
/// [`MeshIoError::Unsupported`] without `vertex` `x y z`, for a face list of
/// non-integers or an element without properties;
/// [`MeshIoError::Mesh`] for an index out of range or a non-finite
/// coordinate; [`MeshIoError::Io`] when reading fails.
pub fn read_ply(reader: impl Read) -> Result<TriMesh, MeshIoError> {
    read(reader).map(|read| read.mesh)
}

/// [`read_ply`] with its warnings.
pub(super) fn read(mut reader: impl Read) -> Result<MeshRead, MeshIoError> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes)?;
    parse(&bytes)
}

/// Parses a complete PLY file held in memory.
fn parse(bytes: &[u8]) -> Result<MeshRead, MeshIoError> {
    if !bytes.starts_with(b"ply") {
        return Err(MeshIoError::parse(FORMAT, Some(1), None, "not a PLY file (no 'ply' on the first line)"));
    }
    let parser = Parser::<Record>::new();
    let mut reader = Reader::new(bytes);
    let header = parser.read_header(&mut reader).map_err(|e| {
        let line = e.line();
        let text = e.to_string();
        let message = line.and_then(|l| text.strip_prefix(&format!("Line {l}: "))).unwrap_or(&text);
        MeshIoError::parse(FORMAT, line, None, message)
    })?;
    let payload_start = bytes.len() - reader.get_ref().len();
    check_unique_names(&bytes[..payload_start])?;
    check_counts(&header, bytes.len() - payload_start)?;
    let layout = Layout::of(&header)?;

    let header_lines = bytes[..payload_start].iter().filter(|&&b| b == b'\n').count();
    let mut payload =
        Payload { bytes, pos: payload_start, line: header_lines, encoding: header.encoding, parser };
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut colors = Vec::new();
    let mut triangles = Vec::new();
    let mut indices = Vec::new();
    for def in header.elements.values() {
        match def.name.as_str() {
            "vertex" => {
                // The count was checked against the data size.
                positions.reserve_exact(def.count);
                if layout.normals {
                    normals.reserve_exact(def.count);
                }
                if layout.color_scale.is_some() {
                    colors.reserve_exact(def.count);
                }
                for i in 0..def.count {
                    let record = payload.record(def, i)?;
                    positions.push(Vec3::from_array(record.position));
                    if layout.normals {
                        normals.push(Vec3::from_array(record.normal));
                    }
                    if let Some(scale) = layout.color_scale {
                        colors.push(Vec3::from_array(record.color) / scale);
                    }
                }
            }
            "face" => {
                triangles.reserve(def.count);
                for i in 0..def.count {
                    let (record, line, offset) = payload.located_record(def, i)?;
                    fan(&record, &mut indices, &mut triangles).map_err(|message| {
                        MeshIoError::parse(FORMAT, line, offset, &format!("face {i}: {message}"))
                    })?;
                }
            }
            _ => {
                for i in 0..def.count {
                    payload.record(def, i)?;
                }
            }
        }
    }
    let normals = (layout.normals && normals.iter().all(|n| n.is_finite())).then_some(normals);
    let colors = layout.color_scale.is_some().then_some(colors);
    let mesh = TriMesh { positions, triangles, normals, colors };
    mesh.validate()?;
    let rest = &bytes[payload.pos..];
    let ascii = header.encoding == Encoding::Ascii;
    let warnings = if rest.is_empty() || (ascii && rest.trim_ascii().is_empty()) {
        Vec::new()
    } else {
        // Blank lines before ASCII junk count as part of it.
        vec![ReadWarning::PlyTrailingData {
            bytes: rest.len() as u64,
            offset: payload.pos as u64,
            line: ascii.then_some(payload.line + 1),
        }]
    };
    Ok(MeshRead { mesh, warnings })
}

/// Refuses a header that declares an element twice, or a property twice in
/// one element: `ply-rs-bw` keeps only one of them, so every column after it
/// would be read into the wrong property.
fn check_unique_names(header: &[u8]) -> Result<(), MeshIoError> {
    let mut elements = HashSet::new();
    let mut properties = HashSet::new();
    let mut element: &[u8] = b"";
    for (number, line) in header.split(|&b| b == b'\n').enumerate() {
        let mut tokens = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
        let lossy = String::from_utf8_lossy;
        let message = match tokens.next() {
            Some(b"element") => {
                properties.clear();
                element = tokens.next().unwrap_or_default();
                if elements.insert(element) {
                    continue;
                }
                format!("element '{}' is declared twice", lossy(element))
            }
            Some(b"property") => {
                let name = tokens.next_back().unwrap_or_default();
                if properties.insert(name) {
                    continue;
                }
                format!("property '{}' is declared twice in element '{}'", lossy(name), lossy(element))
            }
            _ => continue,
        };
        return Err(MeshIoError::parse(FORMAT, Some(number + 1), None, &message));
    }
    Ok(())
}

/// What the header offers.
struct Layout {
    /// The vertex element has `nx ny nz`.
    normals: bool,
    /// The vertex element has `red green blue`: the value of full
    /// intensity (1 for floats, 255 or 65535 for integers).
    color_scale: Option<f32>,
}

impl Layout {
    /// Checks that the header describes a mesh this reader handles.
    fn of(header: &Header) -> Result<Layout, MeshIoError> {
        let unsupported = |message: String| MeshIoError::Unsupported { format: FORMAT, message };
        let scalar = |def: &ElementDef, name: &str| {
            matches!(def.properties.get(name), Some(PropertyDef { data_type: PropertyType::Scalar(_), .. }))
        };
        let vertex =
            header.elements.get("vertex").ok_or_else(|| unsupported("no 'vertex' element".into()))?;
        if let Some(missing) = ["x", "y", "z"].into_iter().find(|name| !scalar(vertex, name)) {
            return Err(unsupported(format!("the 'vertex' element has no scalar property '{missing}'")));
        }
        if u32::try_from(vertex.count).is_err() {
            return Err(unsupported(format!("{} vertices (indices are u32)", vertex.count)));
        }
        if let Some(face) = header.elements.get("face").filter(|face| face.count > 0) {
            let list = FACE_LISTS.iter().find_map(|name| face.properties.get(*name));
            match list.map(|p| &p.data_type) {
                Some(PropertyType::List(count, item)) if is_integer(count) && is_integer(item) => {}
                Some(other) => {
                    return Err(unsupported(format!("face index list of type {other:?} (integers needed)")));
                }
                None => return Err(unsupported("the 'face' element has no 'vertex_indices' list".into())),
            }
        }
        if let Some(empty) = header.elements.values().find(|e| e.count > 0 && e.properties.is_empty()) {
            return Err(unsupported(format!("element '{}' has records but no properties", empty.name)));
        }
        let color_scale = match COLORS.map(|name| vertex.properties.get(name).map(|p| &p.data_type)) {
            [Some(PropertyType::Scalar(r)), Some(PropertyType::Scalar(_)), Some(PropertyType::Scalar(_))] => {
                Some(match r {
                    ScalarType::Float | ScalarType::Double => 1.0,
                    ScalarType::Short | ScalarType::UShort => 65535.0,
                    _ => 255.0,
                })
            }
            _ => None,
        };
        Ok(Layout { normals: ["nx", "ny", "nz"].into_iter().all(|name| scalar(vertex, name)), color_scale })
    }
}

fn is_integer(t: &ScalarType) -> bool {
    !matches!(t, ScalarType::Float | ScalarType::Double)
}

/// Bytes of a binary scalar.
fn scalar_size(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes a record of `def` can take: binary scalars and list
/// counts (empty lists); in ASCII one character and a separator per property.
fn min_record_size(def: &ElementDef, encoding: Encoding) -> u64 {
    match encoding {
        Encoding::Ascii => 2 * def.properties.len() as u64,
        Encoding::BinaryBigEndian | Encoding::BinaryLittleEndian => def
            .properties
            .values()
            .map(|p| match &p.data_type {
                PropertyType::Scalar(t) | PropertyType::List(t, _) => scalar_size(t),
            })
            .sum(),
    }
}

/// Checks every element count against the payload bytes available, before
/// anything is allocated from a count.
fn check_counts(header: &Header, payload_len: usize) -> Result<(), MeshIoError> {
    // The last ASCII line may lack its line break.
    let slack = u64::from(header.encoding == Encoding::Ascii);
    let mut remaining = payload_len as u64 + slack;
    for def in header.elements.values() {
        let size = min_record_size(def, header.encoding).max(1);
        let count = u64::try_from(def.count).unwrap_or(u64::MAX);
        let need = count.saturating_mul(size);
        if need > remaining {
            return Err(MeshIoError::TooLarge {
                format: FORMAT,
                what: format!("'{}' elements", def.name),
                claimed: count,
                available: remaining / size,
            });
        }
        remaining -= need;
    }
    Ok(())
}

/// Fan-triangulates the index list of a face record into `triangles`.
fn fan(record: &Record, indices: &mut Vec<u32>, triangles: &mut Vec<[u32; 3]>) -> Result<(), String> {
    indices.clear();
    match &record.indices {
        Some(Property::ListChar(v)) => widen(v, indices),
        Some(Property::ListUChar(v)) => widen(v, indices),
        Some(Property::ListShort(v)) => widen(v, indices),
        Some(Property::ListUShort(v)) => widen(v, indices),
        Some(Property::ListInt(v)) => widen(v, indices),
        Some(Property::ListUInt(v)) => widen(v, indices),
        _ => Err("no integer vertex index list".into()),
    }?;
    if indices.len() < 3 {
        return Err(format!("{} vertices (at least 3 needed)", indices.len()));
    }
    let first = indices[0];
    triangles.extend(indices[1..].windows(2).map(|pair| [first, pair[0], pair[1]]));
    Ok(())
}

/// Appends integer indices as `u32`, rejecting negative ones.
fn widen<T: Copy + Into<i64>>(values: &[T], out: &mut Vec<u32>) -> Result<(), String> {
    for &v in values {
        let v: i64 = v.into();
        out.push(u32::try_from(v).map_err(|_| format!("negative vertex index {v}"))?);
    }
    Ok(())
}

/// The payload after the header, read record by record.
struct Payload<'a> {
    bytes: &'a [u8],
    /// Byte offset of the next record.
    pos: usize,
    /// Lines before the next record (ASCII).
    line: usize,
    encoding: Encoding,
    parser: Parser<Record>,
}

impl Payload<'_> {
    /// Reads record `index` of element `def`.
    fn record(&mut self, def: &ElementDef, index: usize) -> Result<Record, MeshIoError> {
        self.located_record(def, index).map(|(record, ..)| record)
    }

    /// Reads record `index` of element `def`, with its line (ASCII) or byte
    /// offset (binary) for later error messages.
    fn located_record(
        &mut self,
        def: &ElementDef,
        index: usize,
    ) -> Result<(Record, Option<usize>, Option<u64>), MeshIoError> {
        let start = self.pos;
        let mut rest = &self.bytes[start..];
        let (line, offset) = match self.encoding {
            Encoding::Ascii => {
                self.line += 1;
                (Some(self.line), None)
            }
            _ => (None, Some(start as u64)),
        };
        let result = match self.encoding {
            Encoding::Ascii => {
                let end = rest.iter().position(|&b| b == b'\n').map_or(rest.len(), |i| i + 1);
                let text = &rest[..end];
                rest = &rest[end..];
                match std::str::from_utf8(text) {
                    _ if text.is_empty() => Err("the data ends before this record".to_owned()),
                    Ok(text) => self
                        .parser
                        .read_ascii_element(text, def)
                        .map_err(|e| e.to_string())
                        .and_then(|record| extra_values(text, def).map(|()| record)),
                    Err(_) => Err("the line is not valid UTF-8".to_owned()),
                }
            }
            Encoding::BinaryLittleEndian => {
                self.parser.read_little_endian_element(&mut rest, def).map_err(binary)
            }
            Encoding::BinaryBigEndian => self.parser.read_big_endian_element(&mut rest, def).map_err(binary),
        };
        self.pos = self.bytes.len() - rest.len();
        match result {
            Ok(record) => Ok((record, line, offset)),
            Err(message) => Err(MeshIoError::parse(
                FORMAT,
                line,
                offset,
                &format!("'{}' record {index}: {message}", def.name),
            )),
        }
    }
}

/// Refuses an ASCII record line holding more values than the properties of
/// `def` take (`ply-rs-bw` ignores them): the header and the data disagree,
/// so the values read may be the wrong columns. Called once the record
/// parsed, so every list count is a valid integer.
fn extra_values(line: &str, def: &ElementDef) -> Result<(), String> {
    let mut tokens = line.split_ascii_whitespace();
    let mut taken = 0usize;
    for property in def.properties.values() {
        let values = match property.data_type {
            PropertyType::Scalar(_) => 1,
            PropertyType::List(..) => {
                taken += 1;
                match tokens.next().map(str::parse::<usize>) {
                    Some(Ok(count)) => count,
                    _ => return Ok(()),
                }
            }
        };
        taken = taken.saturating_add(values);
        if tokens.by_ref().take(values).count() < values {
            return Ok(());
        }
    }
    match tokens.count() {
        0 => Ok(()),
        extra => Err(format!("{} values where the header's properties take {taken}", taken + extra)),
    }
}

/// The message of a binary record error.
fn binary(e: ply_rs_bw::parser::ParseError) -> String {
    if e.kind() == io::ErrorKind::UnexpectedEof {
        "the data ends inside this record".to_owned()
    } else {
        e.to_string()
    }
}

/// One PLY record as this reader needs it; unknown properties are ignored.
#[derive(Default)]
struct Record {
    position: [f32; 3],
    normal: [f32; 3],
    /// Colour as stored (not yet divided by its full intensity).
    color: [f32; 3],
    /// The face's vertex index list, as declared.
    indices: Option<Property>,
}

impl PropertyAccess for Record {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.position[0],
            "y" => &mut self.position[1],
            "z" => &mut self.position[2],
            "nx" => &mut self.normal[0],
            "ny" => &mut self.normal[1],
            "nz" => &mut self.normal[2],
            "red" => &mut self.color[0],
            "green" => &mut self.color[1],
            "blue" => &mut self.color[2],
            _ if FACE_LISTS.contains(&name) => {
                self.indices = Some(property);
                return PropertyAccessResult::Set;
            }
            _ => return PropertyAccessResult::Ignored,
        };
        // A list named like a coordinate can only occur outside `vertex`,
        // whose x/y/z/nx/ny/nz are checked to be scalars.
        match property.to_f32_lossy() {
            Some(value) => {
                *slot = value;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

/// One record to write: a vertex (position, normal, colour) or a face.
struct OutRecord {
    position: Vec3,
    normal: Vec3,
    color: [u8; 3],
    face: [u32; 3],
}

impl PropertyAccess for OutRecord {
    fn new() -> Self {
        OutRecord { position: Vec3::ZERO, normal: Vec3::ZERO, color: [0; 3], face: [0; 3] }
    }

    fn get_uchar(&self, name: &str) -> Option<u8> {
        COLORS.iter().position(|&c| c == name).map(|i| self.color[i])
    }

    fn get_float(&self, name: &str) -> Option<f32> {
        match name {
            "x" => Some(self.position.x),
            "y" => Some(self.position.y),
            "z" => Some(self.position.z),
            "nx" => Some(self.normal.x),
            "ny" => Some(self.normal.y),
            "nz" => Some(self.normal.z),
            _ => None,
        }
    }

    fn get_list_uint(&self, name: &str) -> Option<&[u32]> {
        (name == FACE_LISTS[0]).then_some(&self.face[..])
    }
}

/// Writes `vertex` (`float x y z`, `nx ny nz` with normals, `uchar red
/// green blue` with colours, rounded to the nearest of 256 levels) and
/// `face` (`list uchar uint vertex_indices`) in the encoding of `format`.
pub(super) fn write_ply<W: Write>(mesh: &TriMesh, out: &mut W, format: MeshFormat) -> io::Result<()> {
    let encoding = match format {
        MeshFormat::PlyAscii => Encoding::Ascii,
        MeshFormat::PlyBinaryBigEndian => Encoding::BinaryBigEndian,
        _ => Encoding::BinaryLittleEndian,
    };
    let property = |name: &str, t| PropertyDef::new(name.to_owned(), t);
    let mut vertex = ElementDef::new("vertex".to_owned());
    vertex.count = mesh.positions.len();
    let names: &[&str] =
        if mesh.normals.is_some() { &["x", "y", "z", "nx", "ny", "nz"] } else { &["x", "y", "z"] };
    for &name in names {
        vertex.properties.insert(name.to_owned(), property(name, PropertyType::Scalar(ScalarType::Float)));
    }
    if mesh.colors.is_some() {
        for name in COLORS {
            vertex
                .properties
                .insert(name.to_owned(), property(name, PropertyType::Scalar(ScalarType::UChar)));
        }
    }
    let mut face = ElementDef::new("face".to_owned());
    face.count = mesh.triangles.len();
    let list = PropertyType::List(ScalarType::UChar, ScalarType::UInt);
    face.properties.insert(FACE_LISTS[0].to_owned(), property(FACE_LISTS[0], list));

    let mut header = Header::new();
    header.encoding = encoding;
    header.comments.push("written by isomorph".to_owned());
    header.elements.insert(vertex.name.clone(), vertex.clone());
    header.elements.insert(face.name.clone(), face.clone());

    let writer = Writer::<OutRecord>::new();
    writer.write_header(out, &header)?;
    let write = |out: &mut W, record: &OutRecord, def: &ElementDef| match encoding {
        Encoding::Ascii => writer.write_ascii_element(out, record, def),
        Encoding::BinaryBigEndian => writer.write_big_endian_element(out, record, def),
        Encoding::BinaryLittleEndian => writer.write_little_endian_element(out, record, def),
    };
    let mut record = OutRecord::new();
    for (i, &position) in mesh.positions.iter().enumerate() {
        record.position = position;
        record.normal = mesh.normals.as_ref().map_or(Vec3::ZERO, |n| n[i]);
        record.color = mesh.colors.as_ref().map_or([0; 3], |c| color_bytes(c[i]));
        write(out, &record, &vertex)?;
    }
    for &triangle in &mesh.triangles {
        record.face = triangle;
        write(out, &record, &face)?;
    }
    Ok(())
}

/// A colour in `[0, 1]` as bytes, rounded to the nearest level (clamped).
pub(super) fn color_bytes(color: Vec3) -> [u8; 3] {
    (color.clamp(Vec3::ZERO, Vec3::ONE) * 255.0).round().to_array().map(|c| c as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<TriMesh, MeshIoError> {
        read_ply(text.as_bytes())
    }

    const QUAD_CUBE: &str = "ply\nformat ascii 1.0\ncomment unit cube of quads\n\
        element vertex 8\nproperty double x\nproperty double y\nproperty double z\n\
        element face 6\nproperty list uchar int vertex_index\nend_header\n\
        0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n\
        4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n";

    #[test]
    fn ascii_quads_are_fan_triangulated() {
        let mesh = read(QUAD_CUBE).unwrap();
        assert_eq!(mesh.positions.len(), 8);
        assert_eq!(mesh.positions[6], Vec3::ONE);
        assert_eq!(mesh.triangles.len(), 12);
        assert_eq!(mesh.triangles[0..2], [[0, 3, 2], [0, 2, 1]]);
        // Outward orientation survives: the divergence-theorem volume is +1.
        let volume: f32 = (0..12).map(|t| mesh.corners(t)).map(|[a, b, c]| a.dot(b.cross(c)) / 6.0).sum();
        assert!((volume - 1.0).abs() < 1e-6, "volume {volume}");
    }

    #[test]
    fn other_elements_and_properties_are_skipped() {
        let text = "ply\nformat ascii 1.0\nelement material 2\nproperty uchar red\n\
            property list uint float weights\n\
            element vertex 3\nproperty float nx\nproperty short x\nproperty float y\nproperty float z\n\
            property uchar alpha\nelement face 1\nproperty uchar flags\n\
            property list ushort uint vertex_indices\nelement edge 1\nproperty int v1\nend_header\n\
            1 2 0.5 0.25\n2 0\n\
            0.5 1 0 0 7\n0 2 0 0 7\n0 0 3 0 7\n9 3 0 1 2\n5\n";
        let mesh = read(text).unwrap();
        assert_eq!(mesh.positions, vec![Vec3::X, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)]);
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert!(mesh.normals.is_none(), "only nx: no normals");
    }

    #[test]
    fn header_problems_are_reported() {
        let head = "ply\nformat binary_little_endian 1.0\n";
        // Zero padding, so that the element counts fit in the data.
        let err = |text: &str| read_ply(&[text.as_bytes(), &[0; 64]].concat()[..]).unwrap_err();
        assert!(matches!(err("plx\n"), MeshIoError::Parse { format: "PLY", line: Some(1), .. }));
        assert!(matches!(
            err(&format!("{head}element vertex 1\nproperty flaot x\nend_header\n")),
            MeshIoError::Parse { line: Some(4), .. }
        ));
        assert!(matches!(err(&format!("{head}element vertex 0\n")), MeshIoError::Parse { .. }));
        assert!(matches!(
            err(&format!("{head}element point 1\nproperty float x\nend_header\n")),
            MeshIoError::Unsupported { .. }
        ));
        assert!(matches!(
            err(&format!("{head}element vertex 1\nproperty float x\nproperty float y\nend_header\n")),
            MeshIoError::Unsupported { .. }
        ));
        let xyz = "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n";
        assert!(matches!(
            err(&format!(
                "{head}{xyz}element face 1\nproperty list uchar float vertex_indices\nend_header\n"
            )),
            MeshIoError::Unsupported { .. }
        ));
        assert!(matches!(
            err(&format!("{head}{xyz}element junk 50\nend_header\n")),
            MeshIoError::Unsupported { .. }
        ));
    }

    #[test]
    fn absurd_counts_are_rejected_before_allocation() {
        let xyz = "property float x\nproperty float y\nproperty float z\n";
        for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
            let text =
                format!("ply\nformat {format} 1.0\nelement vertex 1000000000000\n{xyz}end_header\n0 0 0\n");
            match read(&text) {
                Err(MeshIoError::TooLarge { claimed: 1_000_000_000_000, available, .. }) => {
                    assert!(available <= 6, "{format}: available {available}")
                }
                other => panic!("{format}: {other:?}"),
            }
            let faces = format!(
                "ply\nformat {format} 1.0\nelement vertex 0\n{xyz}element face 18446744073709551615\n\
                 property list uchar int vertex_indices\nend_header\n"
            );
            assert!(matches!(read(&faces), Err(MeshIoError::TooLarge { .. })), "{format}");
        }
    }

    #[test]
    fn record_errors_carry_line_or_offset() {
        let xyz = "property float x\nproperty float y\nproperty float z\n";
        let ascii = format!(
            "ply\nformat ascii 1.0\nelement vertex 3\n{xyz}element face 1\n\
             property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n"
        );
        assert!(matches!(read(&ascii), Err(MeshIoError::Parse { line: Some(11), .. })), "{:?}", read(&ascii));
        let negative = ascii.replace("1 0 zero", "1 0 0").replace("3 0 1 2", "3 0 -1 2");
        assert!(matches!(read(&negative), Err(MeshIoError::Parse { line: Some(13), .. })));
        let two = ascii.replace("1 0 zero", "1 0 0").replace("3 0 1 2", "2 0 1");
        assert!(matches!(read(&two), Err(MeshIoError::Parse { line: Some(13), .. })));
        let out_of_range = ascii.replace("1 0 zero", "1 0 0").replace("3 0 1 2", "3 0 1 3");
        assert!(matches!(read(&out_of_range), Err(MeshIoError::Mesh(_))));

        // Binary: a face list claiming 200 indices runs past the end.
        let mut bytes = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex 1\n{xyz}element face 1\n\
             property list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        let header = bytes.len() as u64;
        bytes.extend_from_slice(&[0; 12]);
        bytes.extend_from_slice(&[200, 0, 0, 0, 0]);
        match read_ply(&bytes[..]) {
            Err(MeshIoError::Parse { offset: Some(offset), line: None, .. }) => {
                assert_eq!(offset, header + 12)
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn non_finite_coordinates_are_errors_and_normals_dropped() {
        let xyz = "property float x\nproperty float y\nproperty float z\n";
        let mut bytes =
            format!("ply\nformat binary_big_endian 1.0\nelement vertex 2\n{xyz}end_header\n").into_bytes();
        for v in [1.0f32, 2.0, 3.0, f32::NAN, 0.0, 0.0] {
            bytes.extend_from_slice(&v.to_be_bytes());
        }
        assert!(matches!(
            read_ply(&bytes[..]),
            Err(MeshIoError::Mesh(isomorph_common::MeshError::NonFinite(1)))
        ));

        let normals = format!(
            "ply\nformat ascii 1.0\nelement vertex 1\n{xyz}property float nx\nproperty float ny\n\
             property float nz\nend_header\n0 0 0 1 0 0\n"
        );
        assert_eq!(read(&normals).unwrap().normals, Some(vec![Vec3::X]));
        let big = normals.replace("0 0 0 1 0 0", "0 0 0 1e39 0 0");
        assert_eq!(read(&big).unwrap().normals, None, "1e39 overflows f32");
    }

    #[test]
    fn names_declared_twice_are_refused() {
        // Old behaviour: the second 'x' replaced the first, so 'y' and 'z'
        // were read from the wrong columns.
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                    property float x\nproperty float z\nend_header\n1 2 3 4\n";
        match read(text) {
            Err(MeshIoError::Parse { line: Some(6), message, .. }) => {
                assert_eq!(message, "property 'x' is declared twice in element 'vertex'")
            }
            other => panic!("{other:?}"),
        }
        let elements = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                        property float z\nelement vertex 1\nproperty float x\nend_header\n1 2 3\n4\n";
        assert!(matches!(read(elements), Err(MeshIoError::Parse { line: Some(7), .. })));
        // The same name in two elements is fine.
        let ok = QUAD_CUBE
            .replace("element face 6\n", "element face 6\nproperty uchar x\n")
            .replace("\n4 ", "\n7 4 ");
        assert_eq!(read(&ok).unwrap().triangles.len(), 12);
    }

    #[test]
    fn ascii_records_with_extra_values_are_refused() {
        // A property missing from the header: 4 values per vertex line.
        let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0\n1 0 0 0.5\n3 0 1 1\n";
        match read(text) {
            Err(MeshIoError::Parse { line: Some(11), message, .. }) => {
                assert_eq!(message, "'vertex' record 1: 4 values where the header's properties take 3")
            }
            other => panic!("{other:?}"),
        }
        let face = text.replace("1 0 0 0.5", "1 0 0").replace("3 0 1 1", "3 0 1 1 7");
        assert!(matches!(read(&face), Err(MeshIoError::Parse { line: Some(12), .. })), "{:?}", read(&face));
        assert_eq!(read(&face.replace("3 0 1 1 7", "3 0 1 1")).unwrap().triangles, vec![[0, 1, 1]]);
    }

    #[test]
    fn data_after_the_declared_elements_is_reported() {
        let warned = |bytes: &[u8]| super::read(bytes).unwrap();
        assert_eq!(warned(QUAD_CUBE.as_bytes()).warnings, vec![]);
        assert_eq!(warned(format!("{QUAD_CUBE}\n \r\n").as_bytes()).warnings, vec![], "blank lines");
        // A seventh face the header does not count.
        let extra = format!("{QUAD_CUBE}4 0 1 2 3\n");
        let read = warned(extra.as_bytes());
        assert_eq!(read.mesh.triangles.len(), 12);
        let offset = QUAD_CUBE.len() as u64;
        assert_eq!(read.warnings, vec![ReadWarning::PlyTrailingData { bytes: 10, offset, line: Some(25) }]);
        assert!(read.warnings[0].to_string().contains("at line 25"), "{}", read.warnings[0]);
        // Binary: any byte after the last record.
        let mesh = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        let mut bytes = Vec::new();
        write_ply(&mesh, &mut bytes, MeshFormat::PlyBinaryLittleEndian).unwrap();
        let end = bytes.len() as u64;
        bytes.extend_from_slice(&[0, 0, 7]);
        let read = warned(&bytes);
        assert_eq!(read.mesh, mesh);
        assert_eq!(read.warnings, vec![ReadWarning::PlyTrailingData { bytes: 3, offset: end, line: None }]);
    }

    #[test]
    fn big_endian_is_really_big_endian() {
        let mesh = TriMesh::new(vec![Vec3::new(1.0, 2.0, 3.0); 3], vec![[0, 1, 2]]).unwrap();
        let mut bytes = Vec::new();
        write_ply(&mesh, &mut bytes, MeshFormat::PlyBinaryBigEndian).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("format binary_big_endian 1.0"));
        let payload = bytes.len() - 3 * 12 - 13;
        assert_eq!(bytes[payload..payload + 4], 1.0f32.to_be_bytes());
        assert_eq!(read_ply(&bytes[..]).unwrap(), mesh);
    }
}
