//! Scene files: BlobTrees as RON or JSON, validated into typed errors that
//! carry the path of the offending node.
//!
//! Every node is a record with a `kind` and the fields that kind uses:
//!
//! | kind | fields |
//! |---|---|
//! | `point`, `segment`, `polygon`, `polyhedron` | `vertices` (1, 2, 3 to 32 coplanar, 4 to 32), `radius`, optional `intensity` (1), `stiffness` (1), `p` (2; a number ≥ 1 or `"inf"`), `frame` |
//! | `box` | `half` (half extents) instead of `vertices`; a polyhedron skeleton |
//! | `blend`, `union`, `intersection` | `children` (≥ 1) |
//! | `superblend` | `n` (≥ 1), `children` |
//! | `difference` | `children` (2: left, right), optional `level` (the threshold) |
//! | `twist`, `taper` | `rate` / `slope`, `children` (1) |
//! | `bend` | `rate`, `centre`, `min`, `max`, `children` (1) |
//! | `affine` | `frame`, `children` (1) |
//!
//! A `frame` is `(translate: (x, y, z), rotate: (axis: (x, y, z), degrees: a), scale: (x, y, z))`
//! (all optional; applied as translate · rotate · scale) or `(matrix: (...12 numbers...))`,
//! column-major 3×4. The file is `(threshold: 0.5, root: (...))`.
//!
//! ```
//! use isomorph_blobtree::BlobTree;
//! use isomorph_common::Field3;
//!
//! let scene = r#"(threshold: 0.5, root: (kind: "blend", children: [
//!     (kind: "point", vertices: [(0, 0, 0)], radius: 1.0),
//!     (kind: "segment", vertices: [(0.5, 0, 0), (1, 0, 0)], radius: 0.8, p: "inf"),
//! ]))"#;
//! let tree = BlobTree::from_ron(scene)?;
//! assert!(tree.value(glam::Vec3::ZERO) > 0.0);
//! let bad = r#"(root: (kind: "blend", children: [(kind: "point", vertices: [(0, 0, 0)], radius: -1)]))"#;
//! let err = BlobTree::from_ron(bad).unwrap_err();
//! assert_eq!(err.to_string(), "node root/0: radius of influence must be positive, got -1");
//! # Ok::<(), isomorph_blobtree::BlobError>(())
//! ```

use crate::error::{BlobError, NodePath, NodeProblem};
use crate::kernel::Kernel;
use crate::node::{NaryOp, Node, Primitive};
use crate::skeleton::Skeleton;
use crate::tree::BlobTree;
use crate::warp::Warp;
use glam::{Affine3A, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// The file's top level.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The iso threshold `T` (default 0.5).
    #[serde(default = "default_threshold")]
    pub threshold: f32,
    /// The tree.
    pub root: RawNode,
}

fn default_threshold() -> f32 {
    0.5
}

/// The L^p exponent as written: a number, or `"inf"`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
pub enum RawExponent {
    /// A finite exponent.
    Number(f32),
    /// `"inf"` / `"infinity"`.
    Text(String),
}

/// A rotation as axis and angle in degrees.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRotation {
    /// Rotation axis (normalized on reading).
    pub axis: [f32; 3],
    /// Angle in degrees.
    pub degrees: f32,
}

/// A frame or affine map as written.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RawTransform {
    /// Translation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f32; 3]>,
    /// Rotation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotate: Option<RawRotation>,
    /// Per-axis scale.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<[f32; 3]>,
    /// Column-major 3×4 matrix (replaces the other fields).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matrix: Option<[f32; 12]>,
}

/// One node as written (see the module docs for which fields each kind uses).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
#[allow(missing_docs)]
pub struct RawNode {
    pub kind: String,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub children: Vec<RawNode>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub vertices: Vec<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub half: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p: Option<RawExponent>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame: Option<RawTransform>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slope: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub centre: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<f32>,
}

/// The largest scene or links file read, in bytes (64 MiB): a file is read
/// whole, so larger ones (or endless streams) are refused before they fill
/// the memory.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// Reads the file at `path` (at most [`MAX_FILE_BYTES`]); `hint` is added
/// to the message of a file that cannot be opened.
pub(crate) fn read_text(path: &std::path::Path, hint: &str) -> Result<String, BlobError> {
    use std::io::Read;
    let fail = |message: String| BlobError::Read { path: path.display().to_string(), message };
    let file = std::fs::File::open(path).map_err(|e| fail(format!("{e}{hint}")))?;
    let mut text = String::new();
    file.take(MAX_FILE_BYTES + 1).read_to_string(&mut text).map_err(|e| fail(e.to_string()))?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(fail(format!("the file is larger than {} MiB", MAX_FILE_BYTES >> 20)));
    }
    Ok(text)
}

/// The deepest node level a scene file may have (the root is level 0).
/// The readers' own nesting limits lie beyond it (RON: four levels per
/// node and a few for a leaf's fields; JSON: a fixed 128), so a file is
/// refused for its depth before it can exhaust the stack.
pub const MAX_DEPTH: usize = 48;

/// Nesting levels the RON reader accepts.
const RON_NESTING: usize = 4 * MAX_DEPTH + 16;

pub(crate) fn ron_options() -> ron::Options {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .with_recursion_limit(RON_NESTING)
}

/// What a reader's nesting limit means for a `what` ("scene", "links spec").
fn too_deep(what: &'static str, at: String) -> String {
    if what == "scene" {
        format!("the scene nests deeper than {MAX_DEPTH} levels of nodes ({at})")
    } else {
        format!("the {what} nests too deeply ({at})")
    }
}

/// A RON parse error of a `what` ("scene", "links spec") in the user's terms.
pub(crate) fn ron_error(e: &ron::error::SpannedError, what: &'static str) -> BlobError {
    let message = match e.code {
        ron::Error::ExceededRecursionLimit => {
            too_deep(what, format!("line {}, column {}", e.span.start.line, e.span.start.col))
        }
        _ => e.to_string(),
    };
    BlobError::Parse { format: "RON", what, message }
}

/// A JSON parse error of a `what` ("scene", "links spec") in the user's terms.
pub(crate) fn json_error(e: &serde_json::Error, what: &'static str) -> BlobError {
    let message = if e.to_string().starts_with("recursion limit exceeded") {
        too_deep(what, format!("line {}, column {}", e.line(), e.column()))
    } else {
        e.to_string()
    };
    BlobError::Parse { format: "JSON", what, message }
}

impl BlobTree {
    /// Reads a RON scene.
    ///
    /// # Errors
    /// [`BlobError::Parse`] for malformed RON; otherwise as [`BlobTree::from_scene`].
    pub fn from_ron(text: &str) -> Result<Self, BlobError> {
        let file: SceneFile = ron_options().from_str(text).map_err(|e| ron_error(&e, "scene"))?;
        Self::from_scene(&file)
    }

    /// Reads a JSON scene.
    ///
    /// # Errors
    /// [`BlobError::Parse`] for malformed JSON; otherwise as [`BlobTree::from_scene`].
    pub fn from_json(text: &str) -> Result<Self, BlobError> {
        let file: SceneFile = serde_json::from_str(text).map_err(|e| json_error(&e, "scene"))?;
        Self::from_scene(&file)
    }

    /// Builds a tree from a parsed scene.
    ///
    /// # Errors
    /// [`BlobError::InvalidNode`] with the offending node's path (unknown
    /// kinds, missing fields, negative radii, NaN, `p < 1`, empty nodes, …),
    /// [`BlobError::InvalidThreshold`], [`BlobError::EmptyScene`] when the
    /// potential can nowhere exceed the threshold.
    pub fn from_scene(file: &SceneFile) -> Result<Self, BlobError> {
        if !(file.threshold > 0.0 && file.threshold <= crate::node::MAX_MAGNITUDE) {
            return Err(BlobError::InvalidThreshold(file.threshold));
        }
        let root = from_raw(&file.root, &NodePath::root(), file.threshold)?;
        let tree = BlobTree::new(root, file.threshold)?;
        let peak = tree.root().peak_bound();
        if peak <= file.threshold {
            return Err(BlobError::EmptyScene { peak, threshold: file.threshold });
        }
        Ok(tree)
    }

    /// The tree as a scene description.
    pub fn to_scene(&self) -> SceneFile {
        SceneFile { threshold: self.threshold(), root: to_raw(self.root()) }
    }

    /// The scene as pretty RON.
    ///
    /// # Errors
    /// [`BlobError::Write`] if serialization fails.
    pub fn to_ron(&self) -> Result<String, BlobError> {
        ron_options()
            .to_string_pretty(&self.to_scene(), ron::ser::PrettyConfig::default())
            .map_err(|e| BlobError::Write(e.to_string()))
    }

    /// The scene as pretty JSON (infinite exponents written as `"inf"`).
    ///
    /// # Errors
    /// [`BlobError::Write`] if serialization fails.
    pub fn to_json(&self) -> Result<String, BlobError> {
        serde_json::to_string_pretty(&self.to_scene()).map_err(|e| BlobError::Write(e.to_string()))
    }
}

fn from_raw(raw: &RawNode, path: &NodePath, threshold: f32) -> Result<Node, BlobError> {
    let err = |p: NodeProblem| BlobError::node(path, p);
    if path.0.len() > MAX_DEPTH {
        return Err(err(NodeProblem::TooDeep(MAX_DEPTH)));
    }
    let need = |v: Option<f32>, name: &'static str| v.ok_or(err(NodeProblem::MissingField(name)));
    let children = |expected: &'static str, ok: &dyn Fn(usize) -> bool| -> Result<Vec<Node>, BlobError> {
        if !ok(raw.children.len()) {
            return Err(err(NodeProblem::WrongChildCount {
                kind: kind_name(&raw.kind),
                expected,
                got: raw.children.len(),
            }));
        }
        raw.children.iter().enumerate().map(|(i, c)| from_raw(c, &path.child(i), threshold)).collect()
    };
    let v3 = |a: &[f32; 3]| Vec3::from_array(*a);
    let kind = raw.kind.as_str();
    Ok(match kind {
        "point" | "segment" | "polygon" | "polyhedron" | "box" => {
            if !raw.children.is_empty() {
                return Err(err(NodeProblem::WrongChildCount {
                    kind: kind_name(kind),
                    expected: "0",
                    got: raw.children.len(),
                }));
            }
            let vs: Vec<Vec3> = raw.vertices.iter().map(v3).collect();
            let count = |expected: &'static str| {
                err(NodeProblem::WrongVertexCount { kind: kind_name(kind), expected, got: vs.len() })
            };
            let skeleton = match kind {
                "point" if vs.len() == 1 => Skeleton::Point(vs[0]),
                "point" => return Err(count("1")),
                "segment" if vs.len() == 2 => Skeleton::Segment(vs[0], vs[1]),
                "segment" => return Err(count("2")),
                "polygon" => Skeleton::Polygon(vs),
                "polyhedron" => Skeleton::Polyhedron(vs),
                _ => Skeleton::cuboid(v3(&raw.half.ok_or(err(NodeProblem::MissingField("half")))?)),
            };
            let p = match &raw.p {
                None => 2.0,
                Some(RawExponent::Number(p)) => *p,
                Some(RawExponent::Text(t))
                    if matches!(t.to_ascii_lowercase().as_str(), "inf" | "infinity") =>
                {
                    f32::INFINITY
                }
                Some(RawExponent::Text(_)) => return Err(err(NodeProblem::NotFinite("p"))),
            };
            let kernel = Kernel::new(
                raw.intensity.unwrap_or(1.0),
                need(raw.radius, "radius")?,
                raw.stiffness.unwrap_or(1.0),
            );
            let frame = match &raw.frame {
                Some(f) => transform(f).map_err(err)?,
                None => Affine3A::IDENTITY,
            };
            Node::Primitive(Primitive { skeleton, kernel, p, frame })
        }
        "blend" | "union" | "intersection" | "superblend" => {
            let op = match kind {
                "blend" => NaryOp::Blend,
                "union" => NaryOp::Union,
                "intersection" => NaryOp::Intersection,
                _ => NaryOp::SuperBlend(need(raw.n, "n")?),
            };
            Node::Nary { op, children: children("≥ 1", &|n| n >= 1)? }
        }
        "difference" => {
            let mut c = children("2", &|n| n == 2)?;
            let right = c.pop().expect("two children");
            let left = c.pop().expect("two children");
            Node::difference(left, right, raw.level.unwrap_or(threshold))
        }
        "twist" | "taper" | "bend" | "affine" => {
            let child = children("1", &|n| n == 1)?.pop().expect("one child");
            let warp = match kind {
                "twist" => Warp::Twist { rate: need(raw.rate, "rate")? },
                "taper" => Warp::Taper { slope: need(raw.slope, "slope")? },
                "bend" => Warp::Bend {
                    rate: need(raw.rate, "rate")?,
                    centre: raw.centre.unwrap_or(0.0),
                    min: need(raw.min, "min")?,
                    max: need(raw.max, "max")?,
                },
                _ => Warp::Affine(
                    transform(raw.frame.as_ref().ok_or(err(NodeProblem::MissingField("frame")))?)
                        .map_err(err)?,
                ),
            };
            Node::warp(warp, child)
        }
        other => return Err(err(NodeProblem::UnknownKind(other.to_string()))),
    })
}

fn kind_name(kind: &str) -> &'static str {
    const KINDS: [&str; 14] = [
        "point",
        "segment",
        "polygon",
        "polyhedron",
        "box",
        "blend",
        "union",
        "intersection",
        "superblend",
        "difference",
        "twist",
        "taper",
        "bend",
        "affine",
    ];
    KINDS.iter().find(|k| **k == kind).copied().unwrap_or("node")
}

fn transform(t: &RawTransform) -> Result<Affine3A, NodeProblem> {
    if let Some(m) = t.matrix {
        if m.iter().any(|v| !v.is_finite()) {
            return Err(NodeProblem::NotFinite("matrix"));
        }
        return Ok(Affine3A::from_cols_slice(&m));
    }
    let tr = Vec3::from_array(t.translate.unwrap_or([0.0; 3]));
    let sc = Vec3::from_array(t.scale.unwrap_or([1.0; 3]));
    let rot = match &t.rotate {
        None => Quat::IDENTITY,
        Some(r) => {
            let axis = Vec3::from_array(r.axis);
            if !axis.is_finite() || !r.degrees.is_finite() {
                return Err(NodeProblem::NotFinite("rotate"));
            }
            let axis = axis.try_normalize().ok_or(NodeProblem::NotFinite("rotate.axis"))?;
            Quat::from_axis_angle(axis, r.degrees.to_radians())
        }
    };
    if !tr.is_finite() || !sc.is_finite() {
        return Err(NodeProblem::NotFinite("frame"));
    }
    Ok(Affine3A::from_scale_rotation_translation(sc, rot, tr))
}

fn raw_transform(m: &Affine3A) -> Option<RawTransform> {
    if *m == Affine3A::IDENTITY {
        return None;
    }
    let mut cols = [0.0f32; 12];
    m.write_cols_to_slice(&mut cols);
    Some(RawTransform { matrix: Some(cols), ..RawTransform::default() })
}

fn to_raw(node: &Node) -> RawNode {
    let a = |v: Vec3| v.to_array();
    match node {
        Node::Primitive(p) => {
            let (kind, vertices) = match &p.skeleton {
                Skeleton::Point(c) => ("point", vec![a(*c)]),
                Skeleton::Segment(x, y) => ("segment", vec![a(*x), a(*y)]),
                Skeleton::Polygon(v) => ("polygon", v.iter().map(|v| a(*v)).collect()),
                Skeleton::Polyhedron(v) => ("polyhedron", v.iter().map(|v| a(*v)).collect()),
                Skeleton::Generic(poly) => {
                    (p.skeleton.kind(), poly.vertices().iter().map(|v| a(*v)).collect())
                }
            };
            RawNode {
                kind: kind.into(),
                vertices,
                intensity: Some(p.kernel.intensity),
                radius: Some(p.kernel.radius),
                stiffness: Some(p.kernel.stiffness),
                p: Some(if p.p.is_infinite() {
                    RawExponent::Text("inf".into())
                } else {
                    RawExponent::Number(p.p)
                }),
                frame: raw_transform(&p.frame),
                ..RawNode::default()
            }
        }
        Node::Nary { op, children } | Node::Mix { from: op, children, .. } => RawNode {
            kind: op.name().into(),
            n: if let NaryOp::SuperBlend(n) = op { Some(*n) } else { None },
            children: children.iter().map(to_raw).collect(),
            ..RawNode::default()
        },
        Node::Difference { left, right, level } => RawNode {
            kind: "difference".into(),
            level: Some(*level),
            children: vec![to_raw(left), to_raw(right)],
            ..RawNode::default()
        },
        Node::Warp { warp, child } => {
            let mut r =
                RawNode { kind: warp.kind().into(), children: vec![to_raw(child)], ..RawNode::default() };
            match *warp {
                Warp::Twist { rate } => r.rate = Some(rate),
                Warp::Taper { slope } => r.slope = Some(slope),
                Warp::Bend { rate, centre, min, max } => {
                    (r.rate, r.centre, r.min, r.max) = (Some(rate), Some(centre), Some(min), Some(max))
                }
                Warp::Affine(m) => r.frame = raw_transform(&m).or(Some(RawTransform::default())),
            }
            r
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::Field3;

    fn problem(text: &str) -> (Vec<usize>, NodeProblem) {
        match BlobTree::from_ron(text) {
            Err(BlobError::InvalidNode { path, problem }) => (path.0, problem),
            other => panic!("expected a node error, got {other:?}"),
        }
    }

    #[test]
    fn malformed_scenes_are_typed_errors_with_paths() {
        let (p, e) = problem(
            r#"(root: (kind: "union", children: [(kind: "point", vertices: [(0,0,0)], radius: 1), (kind: "blob")]))"#,
        );
        assert_eq!((p, e), (vec![1], NodeProblem::UnknownKind("blob".into())));
        let (p, e) = problem(r#"(root: (kind: "twist", rate: 1, children: [(kind: "blend")]))"#);
        assert_eq!(p, vec![0]);
        assert!(matches!(e, NodeProblem::WrongChildCount { got: 0, .. }));
        let (_, e) = problem(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, p: 0.5))"#);
        assert_eq!(e, NodeProblem::ExponentBelowOne(0.5));
        let (_, e) = problem(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: NaN))"#);
        assert_eq!(e, NodeProblem::NotFinite("radius"));
        let (_, e) = problem(r#"(root: (kind: "segment", vertices: [(0,0,0)], radius: 1))"#);
        assert!(matches!(e, NodeProblem::WrongVertexCount { got: 1, .. }));
        let (p, e) = problem(
            r#"(root: (kind: "difference", children: [(kind: "box", half: (1,1,1), radius: 1), (kind: "point", vertices: [(0,0,0)])]))"#,
        );
        assert_eq!((p, e), (vec![1], NodeProblem::MissingField("radius")));
        assert!(matches!(
            BlobTree::from_ron("(root: (kind: 3))"),
            Err(BlobError::Parse { format: "RON", .. })
        ));
        assert!(matches!(BlobTree::from_json("{\"root\": 1}"), Err(BlobError::Parse { format: "JSON", .. })));
        assert!(matches!(
            BlobTree::from_json(
                r#"{"threshold": -1, "root": {"kind": "point", "vertices": [[0,0,0]], "radius": 1}}"#
            ),
            Err(BlobError::InvalidThreshold(_))
        ));
    }

    #[test]
    fn scenes_round_trip_through_ron_and_json() {
        let text = r#"(threshold: 0.4, root: (kind: "difference", children: [
            (kind: "twist", rate: 0.7, children: [(kind: "superblend", n: 2, children: [
                (kind: "box", half: (0.3, 0.2, 0.5), radius: 0.4, stiffness: 0.5, p: "inf"),
                (kind: "segment", vertices: [(0,0,0), (0,0,0.6)], radius: 0.3,
                 frame: (translate: (0.2, 0, 0), rotate: (axis: (0, 1, 0), degrees: 30))),
            ])]),
            (kind: "bend", rate: 0.5, min: -1, max: 1, children: [
                (kind: "affine", frame: (scale: (1, 2, 1)), children: [
                    (kind: "polygon", vertices: [(0,0,0.5), (0.3,0,0.5), (0,0.3,0.5)], radius: 0.2)])]),
        ]))"#;
        let tree = BlobTree::from_ron(text).unwrap();
        let again = BlobTree::from_ron(&tree.to_ron().unwrap()).unwrap();
        let json = BlobTree::from_json(&tree.to_json().unwrap()).unwrap();
        for i in 0..200 {
            let p =
                Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin()) * 0.8;
            assert!((tree.value(p) - again.value(p)).abs() < 1e-5);
            assert!((tree.value(p) - json.value(p)).abs() < 1e-5);
        }
        assert_eq!(again.threshold(), 0.4);
    }

    /// Finite but absurd magnitudes (which used to polygonize to nothing, or
    /// to a NaN grid) are refused up front, naming the node and the field.
    #[test]
    fn huge_and_tiny_magnitudes_are_refused_by_name() {
        let ball = |extra: &str| format!(r#"(kind: "point", vertices: [(0,0,0)], radius: 1{extra})"#);
        let scene = |node: String| format!(r#"(root: (kind: "blend", children: [{}, {node}]))"#, ball(""));
        let (p, e) = problem(&scene(r#"(kind: "point", vertices: [(0,0,0)], radius: 1e30)"#.into()));
        assert_eq!(p, vec![1]);
        assert_eq!(
            e,
            NodeProblem::OutOfRange { field: "radius", value: 1e30, expected: "1e-6 ≤ radius ≤ 1e6" }
        );
        let (_, e) = problem(&scene(r#"(kind: "point", vertices: [(0,0,0)], radius: 1e-9)"#.into()));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "radius", .. }));
        let (p, e) = problem(&scene(r#"(kind: "point", vertices: [(1e38,0,0)], radius: 1)"#.into()));
        assert_eq!(
            (p, e),
            (
                vec![1],
                NodeProblem::OutOfRange { field: "vertices", value: 1e38, expected: "a magnitude ≤ 1e6" }
            )
        );
        let (_, e) = problem(&scene(ball(", frame: (translate: (0, 1e38, 0))")));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "frame", value: 1e38, .. }));
        let (_, e) = problem(&scene(ball(", intensity: 1e20")));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "intensity", .. }));
        let (_, e) = problem(&scene(format!(r#"(kind: "twist", rate: 1e9, children: [{}])"#, ball(""))));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "rate", .. }));
        let err = BlobTree::from_ron(&scene(ball(", half: (0,0,0)").replace("radius: 1", "radius: 1e30")))
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "node root/1: `radius` = 1e30 is out of range: expected 1e-6 ≤ radius ≤ 1e6"
        );
        // Each frame within range, but nested under a twist they scale the leaf to 1e10.
        let nested = format!(
            r#"(root: (kind: "affine", frame: (scale: (1e5, 1e5, 1e5)), children: [(kind: "twist", rate: 1,
                children: [(kind: "affine", frame: (scale: (1e5, 1e5, 1e5)), children: [{}])])]))"#,
            ball("")
        );
        let (p, e) = problem(&nested);
        assert_eq!(p, Vec::<usize>::new());
        assert!(matches!(e, NodeProblem::SupportTooLarge(r) if r > 1e9), "{e:?}");
        assert!(matches!(
            BlobTree::from_ron(&format!("(threshold: 1e30, root: {})", ball(""))),
            Err(BlobError::InvalidThreshold(_))
        ));
    }

    /// A scene whose potential cannot reach the threshold has no surface.
    #[test]
    fn scenes_without_inside_are_refused() {
        let faint = r#"(root: (kind: "union", children: [
            (kind: "point", vertices: [(0,0,0)], radius: 1, intensity: 0.3),
            (kind: "point", vertices: [(0.2,0,0)], radius: 1, intensity: 0.5)]))"#;
        assert_eq!(
            BlobTree::from_ron(faint).unwrap_err(),
            BlobError::EmptyScene { peak: 0.5, threshold: 0.5 }
        );
        // Blended, the same two reach 0.8 > 0.5 (where they overlap).
        let tree = BlobTree::from_ron(&faint.replace("union", "blend")).unwrap();
        assert!(tree.value(Vec3::new(0.1, 0.0, 0.0)) > 0.0);
    }

    /// A scene nested `depth` operator levels deep around one ball.
    fn nested(depth: usize, json: bool) -> String {
        let ball = if json {
            r#"{"kind": "point", "vertices": [[0,0,0]], "radius": 1}"#
        } else {
            r#"(kind: "point", vertices: [(0,0,0)], radius: 1)"#
        };
        let (open, close) = if json {
            (r#"{"kind": "blend", "children": ["#, "]}")
        } else {
            (r#"(kind: "blend", children: ["#, "])")
        };
        let body = format!("{}{ball}{}", open.repeat(depth), close.repeat(depth));
        if json { format!(r#"{{"root": {body}}}"#) } else { format!("(root: {body})") }
    }

    /// Too deep a file is refused with a message a user can act on (no
    /// parser options or library names), shallower ones load.
    #[test]
    fn deep_nesting_is_refused_in_plain_words() {
        assert!(BlobTree::from_ron(&nested(MAX_DEPTH, false)).is_ok());
        assert!(BlobTree::from_json(&nested(MAX_DEPTH, true)).is_ok());
        for depth in [MAX_DEPTH + 1, MAX_DEPTH + 3, 100, 10_000] {
            for err in [BlobTree::from_ron(&nested(depth, false)), BlobTree::from_json(&nested(depth, true))]
            {
                let text = err.unwrap_err().to_string();
                assert!(text.contains("the scene nests deeper than 48 levels of nodes"), "{depth}: {text}");
                assert!(!text.contains("serde_stacker") && !text.contains("recursion_limit"), "{text}");
            }
        }
    }

    /// Skeletons with more vertices than [`crate::skeleton::MAX_VERTICES`]
    /// are refused before their hull is built.
    #[test]
    fn oversized_skeletons_are_refused() {
        let ring = |n: usize| {
            (0..n)
                .map(|i| {
                    let a = std::f32::consts::TAU * i as f32 / n as f32;
                    format!("({}, {}, 0)", a.cos(), a.sin())
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        let scene = |n: usize| format!(r#"(root: (kind: "polygon", vertices: [{}], radius: 0.5))"#, ring(n));
        assert!(BlobTree::from_ron(&scene(32)).is_ok());
        let (p, e) = problem(&scene(5000));
        assert_eq!(p, Vec::<usize>::new());
        assert_eq!(e, NodeProblem::WrongVertexCount { kind: "polygon", expected: "≤ 32", got: 5000 });
    }
}
