//! A whole morph as one USD stage (`.usda`, USD's text form): one `Mesh`
//! prim whose points, face counts, face indices, normals and extent carry a
//! time sample per frame, so that Blender, Houdini and usdview play the
//! sequence, topology changes included.
//!
//! Written directly: the format is plain text, and no well-kept Rust crate
//! writes USD. Frame `i` is time code `i`; the stage declares the time range,
//! the frame rate, metres per unit and the up axis.
//!
//! ```
//! use isomorph_common::{TriMesh, glam::Vec3};
//! use isomorph_io::usd::{UsdSettings, write_usda};
//!
//! let tetrahedron = TriMesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//! )?;
//! let mut text = Vec::new();
//! write_usda(&[tetrahedron.clone(), tetrahedron], &UsdSettings::default(), &mut text)?;
//! let text = String::from_utf8(text).unwrap();
//! assert!(text.starts_with("#usda 1.0") && text.contains("endTimeCode = 1"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use isomorph_common::TriMesh;
use isomorph_common::glam::Vec3;
use std::fmt::Write as _;
use std::io::{self, Write};

/// How [`write_usda`] describes the stage.
#[derive(Debug, Clone, PartialEq)]
pub struct UsdSettings {
    /// Frames (time codes) per second.
    pub frames_per_second: f64,
    /// Metres per world unit.
    pub meters_per_unit: f64,
    /// The up axis, `"Y"` or `"Z"`.
    pub up_axis: &'static str,
    /// The stage's documentation string (e.g. the method and inputs).
    pub doc: String,
    /// sRGB display colour of the surface, 0–1, unless every frame has
    /// vertex colours ([`TriMesh::colors`]): those are then written as a
    /// per-vertex `primvars:displayColor` sample per frame.
    pub color: [f32; 3],
}

impl Default for UsdSettings {
    /// 24 frames per second, 1 metre per unit, Y up, a pale blue.
    fn default() -> Self {
        Self {
            frames_per_second: 24.0,
            meters_per_unit: 1.0,
            up_axis: "Y",
            doc: "isomorph morph".into(),
            color: [0.55, 0.65, 0.8],
        }
    }
}

/// Writes `frames` (time codes 0, 1, …) as one USD stage in text form.
///
/// # Errors
/// [`io::Error`] from the writer, or `InvalidInput` for no frames.
pub fn write_usda(frames: &[TriMesh], settings: &UsdSettings, mut out: impl Write) -> io::Result<()> {
    if frames.is_empty() {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, "a USD morph needs at least one frame"));
    }
    let mut s = String::new();
    let _ = write!(
        s,
        "#usda 1.0\n(\n    defaultPrim = \"morph\"\n    doc = {doc:?}\n    endTimeCode = {end}\n    framesPerSecond = \
         {fps}\n    metersPerUnit = {mpu}\n    startTimeCode = 0\n    timeCodesPerSecond = {fps}\n    upAxis = \
         \"{up}\"\n)\n\ndef Xform \"morph\" (\n    kind = \"component\"\n)\n{{\n    def Mesh \"surface\"\n    {{\n",
        doc = settings.doc,
        end = frames.len() - 1,
        fps = settings.frames_per_second,
        mpu = settings.meters_per_unit,
        up = settings.up_axis,
    );
    out.write_all(s.as_bytes())?;
    let attribute = |out: &mut dyn Write, declaration: &str, sample: &dyn Fn(&TriMesh, &mut String)| {
        writeln!(out, "        {declaration}.timeSamples = {{")?;
        for (i, mesh) in frames.iter().enumerate() {
            let mut line = format!("            {i}: [");
            sample(mesh, &mut line);
            line.push_str("],\n");
            out.write_all(line.as_bytes())?;
        }
        writeln!(out, "        }}")
    };
    attribute(&mut out, "float3[] extent", &|m, s| {
        if !m.positions.is_empty() {
            let b = m.bounds();
            push_vectors(s, [b.min, b.max].iter());
        }
    })?;
    attribute(&mut out, "int[] faceVertexCounts", &|m, s| push_list(s, m.triangles.iter().map(|_| 3)))?;
    attribute(&mut out, "int[] faceVertexIndices", &|m, s| push_list(s, m.triangles.iter().flatten()))?;
    // Metadata in its own declaration: USD's text format puts none after
    // a time-sample map.
    writeln!(out, "        normal3f[] normals (\n            interpolation = \"vertex\"\n        )")?;
    attribute(&mut out, "normal3f[] normals", &|m, s| push_vectors(s, m.vertex_normals().iter()))?;
    attribute(&mut out, "point3f[] points", &|m, s| push_vectors(s, m.positions.iter()))?;
    if frames.iter().all(|m| m.colors.is_some()) {
        writeln!(
            out,
            "        color3f[] primvars:displayColor (\n            interpolation = \"vertex\"\n        )"
        )?;
        attribute(&mut out, "color3f[] primvars:displayColor", &|m, s| {
            push_vectors(s, m.colors.iter().flatten());
        })?;
    } else {
        let [r, g, b] = settings.color;
        writeln!(out, "        color3f[] primvars:displayColor = [({r}, {g}, {b})]")?;
    }
    write!(
        out,
        "        uniform token orientation = \"rightHanded\"\n        uniform token subdivisionScheme = \
         \"none\"\n    }}\n}}\n"
    )
}

/// `a, b, c` into `s`.
fn push_list<T: std::fmt::Display>(s: &mut String, items: impl Iterator<Item = T>) {
    for (i, v) in items.enumerate() {
        let _ = write!(s, "{}{v}", if i == 0 { "" } else { ", " });
    }
}

/// `(x, y, z), …` into `s`.
fn push_vectors<'a>(s: &mut String, items: impl Iterator<Item = &'a Vec3>) {
    for (i, v) in items.enumerate() {
        let _ = write!(s, "{}({}, {}, {})", if i == 0 { "" } else { ", " }, v.x, v.y, v.z);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::mesh::primitives::{torus, uv_sphere};

    /// The time samples of `name` as lists of numbers, one per frame: a
    /// small reader of what [`write_usda`] writes.
    fn samples(text: &str, name: &str) -> Vec<Vec<f32>> {
        let start = text.find(&format!("{name}.timeSamples = {{")).expect("the attribute");
        let body = &text[start..];
        let body = &body[body.find('\n').unwrap() + 1..body.find("\n        }").unwrap()];
        body.lines()
            .map(|line| {
                let list = &line[line.find('[').unwrap() + 1..line.rfind(']').unwrap()];
                list.split(|c: char| !(c.is_ascii_digit() || "-.e".contains(c)))
                    .filter(|t| !t.is_empty())
                    .map(|t| t.parse().unwrap())
                    .collect()
            })
            .collect()
    }

    #[test]
    fn every_sample_is_its_frame() {
        let frames = [uv_sphere(Vec3::ZERO, 0.3, 6, 8), torus(0.3, 0.1, 8, 6)];
        let mut bytes = Vec::new();
        write_usda(&frames, &UsdSettings::default(), &mut bytes).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        let points = samples(&text, "point3f[] points");
        let indices = samples(&text, "int[] faceVertexIndices");
        let counts = samples(&text, "int[] faceVertexCounts");
        let normals = samples(&text, "normal3f[] normals");
        assert_eq!(points.len(), 2);
        for (i, mesh) in frames.iter().enumerate() {
            let want: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
            // Exact: Rust prints the shortest decimal that reads back as the same f32.
            assert_eq!(points[i], want, "points of frame {i}");
            let want: Vec<f32> = mesh.triangles.iter().flatten().map(|&v| v as f32).collect();
            assert_eq!(indices[i], want, "indices of frame {i}");
            assert!(counts[i].iter().all(|&c| c == 3.0) && counts[i].len() == mesh.triangles.len());
            assert_eq!(normals[i].len(), 3 * mesh.positions.len());
        }
        assert!(text.contains("endTimeCode = 1") && text.contains("upAxis = \"Y\""));
        assert!(text.contains("primvars:displayColor = [(0.55, 0.65, 0.8)]"), "uncoloured: one colour");

        // Coloured frames: one colour per vertex and frame.
        let colored: Vec<TriMesh> = frames
            .iter()
            .map(|m| {
                let colors = m.positions.iter().map(|p| p.abs().min(Vec3::ONE)).collect();
                m.clone().with_colors(colors).unwrap()
            })
            .collect();
        let mut bytes = Vec::new();
        write_usda(&colored, &UsdSettings::default(), &mut bytes).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        let colors = samples(&text, "color3f[] primvars:displayColor");
        for (i, mesh) in colored.iter().enumerate() {
            let want: Vec<f32> = mesh.colors.iter().flatten().flat_map(|c| c.to_array()).collect();
            assert_eq!(colors[i], want, "colours of frame {i}");
        }
        assert!(!text.contains("displayColor = ["));
        assert!(write_usda(&[], &UsdSettings::default(), Vec::new()).is_err());
    }
}
