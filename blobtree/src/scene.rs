//! Scene files: BlobTrees as RON or JSON, validated into typed errors that
//! carry the path of the offending node.
//!
//! The format is described in the crate docs ("Scene files"). Reading goes
//! in two steps so that every error names its node: the file is parsed
//! with each node kept as a self-describing [`ron::Value`] (for RON and
//! JSON alike), then each node is read from its value as a
//! `NodeSpec<ron::Value>` — a `kind`-tagged enum with one variant per kind
//! and exactly that kind's fields — whose children stay values until they
//! are read in turn, with their own paths. Reading the whole tree as one
//! tagged enum would turn an unknown kind or a missing field deep in the
//! tree into one parser message without the node's path. Writing
//! serializes a `NodeSpec<Written>` tree directly.
//!
//! Internally tagged enums read their fields through `deserialize_any`;
//! with RON that is fine here: integers are accepted where numbers are
//! expected (`radius: 1`), tuples `(0, 0, 0)` read as arrays, optional
//! fields take a bare value or `Some(..)` (tested below).

use crate::error::{BlobError, NodePath, NodeProblem};
use crate::kernel::Kernel;
use crate::node::{NaryOp, Node, Primitive};
use crate::skeleton::{Polytope, Skeleton};
use crate::tree::BlobTree;
use crate::warp::{DEFAULT_ALONG, DEFAULT_AXIS, Warp};
use glam::{Affine3A, Quat, Vec3};
use serde::{Deserialize, Deserializer, Serialize};

/// The file's top level, `(threshold: 0.5, root: (...))`; `C` is a node (a
/// [`ron::Value`] when reading, a [`Written`] node when writing).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile<C> {
    /// The iso threshold `T` (default 0.5).
    #[serde(default = "default_threshold")]
    threshold: f32,
    /// The tree.
    root: C,
}

fn default_threshold() -> f32 {
    0.5
}

/// One node as written: one variant per `kind`, with exactly the fields
/// that kind uses; `C` is a child node.
#[derive(Debug, Serialize, Deserialize)]
#[serde(
    tag = "kind",
    rename_all = "lowercase",
    deny_unknown_fields,
    expecting = "a node: a record with a `kind`",
    bound(deserialize = "C: Deserialize<'de>", serialize = "C: Serialize")
)]
enum NodeSpec<C> {
    /// A point skeleton (one vertex).
    Point(Leaf),
    /// A segment skeleton (two vertices).
    Segment(Leaf),
    /// A planar convex polygon skeleton (3 to 32 coplanar vertices).
    Polygon(Leaf),
    /// A convex polyhedron skeleton (4 to 32 vertices).
    Polyhedron(Leaf),
    /// A box skeleton given by its half extents.
    Box(BoxLeaf),
    /// Blend (sum) of the children.
    Blend {
        /// The children (≥ 1).
        #[serde(default)]
        children: Vec<C>,
    },
    /// Union (max) of the children.
    Union {
        /// The children (≥ 1).
        #[serde(default)]
        children: Vec<C>,
    },
    /// Intersection (min) of the children.
    Intersection {
        /// The children (≥ 1).
        #[serde(default)]
        children: Vec<C>,
    },
    /// Super-elliptic blend of order `n`.
    Superblend {
        /// The order (≥ 1).
        n: f32,
        /// The children (≥ 1).
        #[serde(default)]
        children: Vec<C>,
    },
    /// Left minus right.
    Difference {
        /// The level `c` (default: the threshold).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        level: Option<f32>,
        /// Left and right.
        #[serde(default)]
        children: Vec<C>,
    },
    /// Barr twist about `axis`.
    Twist {
        /// Radians per unit length along the axis.
        rate: f32,
        /// The axis (default z; written only when not z).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        axis: Option<[f32; 3]>,
        /// The warped child.
        #[serde(default)]
        children: Vec<C>,
    },
    /// Barr taper along `axis`.
    Taper {
        /// Scale change per unit length along the axis.
        slope: f32,
        /// The axis (default z; written only when not z).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        axis: Option<[f32; 3]>,
        /// The warped child.
        #[serde(default)]
        children: Vec<C>,
    },
    /// Barr bend in the plane of `along` and `axis` (default y–z).
    Bend {
        /// Curvature.
        rate: f32,
        /// Centre of the bent region (default 0).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        centre: Option<f32>,
        /// Start of the bent region.
        min: f32,
        /// End of the bent region.
        max: f32,
        /// The direction the bend curves towards (default z; written only when not z).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        axis: Option<[f32; 3]>,
        /// The band's direction (default y; written only when not y).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        along: Option<[f32; 3]>,
        /// The warped child.
        #[serde(default)]
        children: Vec<C>,
    },
    /// An affine map of the child.
    Affine {
        /// The map (`()` or `{}`: the identity).
        #[serde(deserialize_with = "transform_or_empty")]
        frame: Transform,
        /// The mapped child.
        #[serde(default)]
        children: Vec<C>,
    },
    /// A generic tree's time-varying commutative node at one instant
    /// (§4.4): `(1 − s)·from(children) + s·to(children)`.
    Mix {
        /// The source operator.
        from: Operator,
        /// The target operator.
        to: Operator,
        /// The weight of `to`, in `[0, 1]`.
        s: f32,
        /// The children (≥ 1).
        #[serde(default)]
        children: Vec<C>,
    },
}

/// A commutative operator as written in a `mix` node: `"blend"`,
/// `"union"`, `"intersection"`, or a number `n ≥ 1`, the order of a
/// super-elliptic blend.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
enum Operator {
    /// A super-elliptic blend's order.
    Order(f32),
    /// An operator's name.
    Name(String),
}

impl Operator {
    /// The operator as written.
    fn of(op: NaryOp) -> Self {
        match op {
            NaryOp::SuperBlend(n) if n.is_finite() => Operator::Order(n),
            // A super-elliptic blend of infinite order is the union.
            NaryOp::SuperBlend(_) => Operator::Name("union".into()),
            op => Operator::Name(op.name().into()),
        }
    }

    /// The operator, or `None` for an unknown name.
    fn read(&self) -> Option<NaryOp> {
        match self {
            Operator::Order(n) => Some(NaryOp::SuperBlend(*n)),
            Operator::Name(name) => match name.as_str() {
                "blend" => Some(NaryOp::Blend),
                "union" => Some(NaryOp::Union),
                "intersection" => Some(NaryOp::Intersection),
                _ => None,
            },
        }
    }
}

/// A written node: a [`NodeSpec`] whose children are written nodes.
#[derive(Debug, Serialize)]
#[serde(transparent)]
struct Written(NodeSpec<Written>);

/// A primitive with a vertex skeleton (`point`, `segment`, `polygon`,
/// `polyhedron`).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Leaf {
    /// The skeleton's vertices.
    #[serde(default)]
    vertices: Vec<[f32; 3]>,
    /// Radius of influence `R`.
    radius: f32,
    /// Intensity `I` (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    intensity: Option<f32>,
    /// Stiffness `k` (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stiffness: Option<f32>,
    /// The L^p exponent (default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    p: Option<Exponent>,
    /// The primitive's frame (default: the identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    frame: Option<Transform>,
}

/// A primitive with a box skeleton.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxLeaf {
    /// Half extents.
    half: [f32; 3],
    /// Radius of influence `R`.
    radius: f32,
    /// Intensity `I` (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    intensity: Option<f32>,
    /// Stiffness `k` (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stiffness: Option<f32>,
    /// The L^p exponent (default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    p: Option<Exponent>,
    /// The primitive's frame (default: the identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    frame: Option<Transform>,
}

/// The L^p exponent as written: a number, or `"inf"`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
enum Exponent {
    /// A finite exponent.
    Number(f32),
    /// `"inf"` / `"infinity"`.
    Text(String),
}

/// A rotation as axis and angle in degrees.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Rotation {
    /// Rotation axis (normalized on reading).
    axis: [f32; 3],
    /// Angle in degrees.
    degrees: f32,
}

/// A frame or affine map as written: translate · rotate · scale, or a
/// column-major 3×4 `matrix` (which replaces the other fields).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct Transform {
    /// Translation.
    #[serde(skip_serializing_if = "Option::is_none")]
    translate: Option<[f32; 3]>,
    /// Rotation.
    #[serde(skip_serializing_if = "Option::is_none")]
    rotate: Option<Rotation>,
    /// Per-axis scale.
    #[serde(skip_serializing_if = "Option::is_none")]
    scale: Option<[f32; 3]>,
    /// Column-major 3×4 matrix.
    #[serde(skip_serializing_if = "Option::is_none")]
    matrix: Option<[f32; 12]>,
}

/// A node as parsed: a self-describing value, with duplicate record fields
/// refused (a plain [`ron::Value`] map would keep one of them silently).
#[derive(Debug)]
struct Parsed(ron::Value);

impl<'de> Deserialize<'de> for Parsed {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ParsedVisitor).map(Parsed)
    }
}

/// Builds a [`ron::Value`] like ron's own visitor, checking records for
/// duplicate fields at every level.
struct ParsedVisitor;

impl<'de> serde::de::Visitor<'de> for ParsedVisitor {
    type Value = ron::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a scene value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<ron::Value, E> {
        Ok(ron::Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<ron::Value, E> {
        Ok(ron::Value::Number(ron::value::Number::new(v)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<ron::Value, E> {
        Ok(ron::Value::Number(ron::value::Number::new(v)))
    }
    fn visit_f32<E>(self, v: f32) -> Result<ron::Value, E> {
        Ok(ron::Value::Number(ron::value::Number::new(v)))
    }
    fn visit_f64<E>(self, v: f64) -> Result<ron::Value, E> {
        Ok(ron::Value::Number(ron::value::Number::new(v)))
    }
    fn visit_char<E>(self, v: char) -> Result<ron::Value, E> {
        Ok(ron::Value::Char(v))
    }
    fn visit_str<E>(self, v: &str) -> Result<ron::Value, E> {
        Ok(ron::Value::String(v.to_owned()))
    }
    fn visit_string<E>(self, v: String) -> Result<ron::Value, E> {
        Ok(ron::Value::String(v))
    }
    fn visit_none<E>(self) -> Result<ron::Value, E> {
        Ok(ron::Value::Option(None))
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<ron::Value, D::Error> {
        Ok(ron::Value::Option(Some(Box::new(Parsed::deserialize(d)?.0))))
    }
    fn visit_unit<E>(self) -> Result<ron::Value, E> {
        Ok(ron::Value::Unit)
    }
    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<ron::Value, D::Error> {
        Ok(Parsed::deserialize(d)?.0)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<ron::Value, A::Error> {
        let mut items = Vec::new();
        while let Some(Parsed(item)) = seq.next_element()? {
            items.push(item);
        }
        Ok(ron::Value::Seq(items))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<ron::Value, A::Error> {
        let mut out = ron::Map::new();
        while let Some((Parsed(key), Parsed(value))) = map.next_entry()? {
            let name = match &key {
                ron::Value::String(s) => s.clone(),
                other => format!("{other:?}"),
            };
            if out.insert(key, value).is_some() {
                return Err(serde::de::Error::custom(format_args!("duplicate field `{name}`")));
            }
        }
        Ok(ron::Value::Map(out))
    }
}

/// A transform, where RON's `()` (which a self-describing reader sees as a
/// unit, not as an empty record) also means the identity.
fn transform_or_empty<'de, D: Deserializer<'de>>(d: D) -> Result<Transform, D::Error> {
    Ok(Option::<Transform>::deserialize(d)?.unwrap_or_default())
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

/// How scenes and links specs are written: indented records, arrays on one line.
pub(crate) fn ron_pretty() -> ron::ser::PrettyConfig {
    ron::ser::PrettyConfig::default().compact_arrays(true)
}

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
    /// Reads a RON scene (the format is in the crate docs).
    ///
    /// # Errors
    /// [`BlobError::Parse`] for malformed RON (and for a node with a field
    /// its kind does not have or of the wrong type, naming the node);
    /// otherwise the validation errors listed at [`BlobTree::from_json`].
    pub fn from_ron(text: &str) -> Result<Self, BlobError> {
        let file: SceneFile<Parsed> = ron_options().from_str(text).map_err(|e| ron_error(&e, "scene"))?;
        Self::from_scene(file, "RON")
    }

    /// Reads a JSON scene (the format is in the crate docs).
    ///
    /// # Errors
    /// [`BlobError::Parse`] for malformed JSON (and for a node with a field
    /// its kind does not have or of the wrong type, naming the node);
    /// [`BlobError::InvalidNode`] with the offending node's path (unknown
    /// kinds, missing fields, negative radii, NaN, `p < 1`, wrong numbers of
    /// children or vertices, …), [`BlobError::InvalidThreshold`],
    /// [`BlobError::EmptyScene`] when the potential can nowhere exceed the
    /// threshold.
    pub fn from_json(text: &str) -> Result<Self, BlobError> {
        let file: SceneFile<Parsed> = serde_json::from_str(text).map_err(|e| json_error(&e, "scene"))?;
        Self::from_scene(file, "JSON")
    }

    /// Builds a tree from a parsed scene file (`format`: `"RON"` or `"JSON"`).
    fn from_scene(file: SceneFile<Parsed>, format: &'static str) -> Result<Self, BlobError> {
        if !(file.threshold > 0.0 && file.threshold <= crate::node::MAX_MAGNITUDE) {
            return Err(BlobError::InvalidThreshold(file.threshold));
        }
        let root = read_node(file.root.0, &NodePath::root(), file.threshold, format)?;
        let tree = BlobTree::new(root, file.threshold)?;
        let peak = tree.root().peak_bound();
        if peak <= file.threshold {
            return Err(BlobError::EmptyScene { peak, threshold: file.threshold });
        }
        Ok(tree)
    }

    /// The tree as a scene file.
    fn to_scene(&self) -> SceneFile<Written> {
        SceneFile { threshold: self.threshold(), root: write_node(self.root()) }
    }

    /// The scene as pretty RON; [`BlobTree::from_ron`] reads it back to
    /// the same tree.
    ///
    /// # Errors
    /// [`BlobError::Write`] if serialization fails.
    pub fn to_ron(&self) -> Result<String, BlobError> {
        ron_options()
            .to_string_pretty(&self.to_scene(), ron_pretty())
            .map_err(|e| BlobError::Write(e.to_string()))
    }

    /// The scene as pretty JSON (infinite exponents written as `"inf"`);
    /// [`BlobTree::from_json`] reads it back to the same tree.
    ///
    /// # Errors
    /// [`BlobError::Write`] if serialization fails.
    pub fn to_json(&self) -> Result<String, BlobError> {
        serde_json::to_string_pretty(&self.to_scene()).map_err(|e| BlobError::Write(e.to_string()))
    }
}

/// The node kinds, as written.
const KINDS: [&str; 15] = [
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
    "mix",
];

/// The kind written in a node's value, if it has a readable one.
fn kind_of(value: &ron::Value) -> Option<&str> {
    let ron::Value::Map(map) = value else { return None };
    match map.get(&ron::Value::String("kind".into())) {
        Some(ron::Value::String(kind)) => Some(kind),
        _ => None,
    }
}

/// Reads one node (and its children) from its value; errors name `path`.
fn read_node(
    value: ron::Value,
    path: &NodePath,
    threshold: f32,
    format: &'static str,
) -> Result<Node, BlobError> {
    let err = |p: NodeProblem| BlobError::node(path, p);
    if path.0.len() > MAX_DEPTH {
        return Err(err(NodeProblem::TooDeep(MAX_DEPTH)));
    }
    if let ron::Value::Map(map) = &value
        && let Some(kind) = map.get(&ron::Value::String("kind".into()))
        && !matches!(kind, ron::Value::String(_))
    {
        // Serde would take an integer as the index of a kind.
        let message =
            format!("node {path}: `kind` must be a string (one of {}), got {kind:?}", KINDS.join(", "));
        return Err(BlobError::Parse { format, what: "scene", message });
    }
    let kind = kind_of(&value).map(str::to_owned);
    let spec = NodeSpec::<ron::Value>::deserialize(value).map_err(|e| match e {
        ron::Error::NoSuchEnumVariant { found, .. } => err(NodeProblem::UnknownKind(found)),
        ron::Error::MissingStructField { field, .. } => err(NodeProblem::MissingField(field)),
        ron::Error::NoSuchStructField { expected, found, .. } => BlobError::Parse {
            format,
            what: "scene",
            message: format!(
                "node {path}: a `{}` node has no field `{found}` (its fields: {})",
                kind.as_deref().unwrap_or("?"),
                expected.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", ")
            ),
        },
        other => BlobError::Parse { format, what: "scene", message: format!("node {path}: {other}") },
    })?;
    let children = |kids: Vec<ron::Value>,
                    expected: &'static str,
                    ok: fn(usize) -> bool,
                    kind: &'static str| {
        if !ok(kids.len()) {
            return Err(err(NodeProblem::WrongChildCount { kind, expected, got: kids.len() }));
        }
        kids.into_iter().enumerate().map(|(i, c)| read_node(c, &path.child(i), threshold, format)).collect()
    };
    let at_least_one = |n: usize| n >= 1;
    let two = |n: usize| n == 2;
    let one = |n: usize| n == 1;
    let unary = |kids, kind| -> Result<Node, BlobError> {
        let mut kids: Vec<Node> = children(kids, "1", one, kind)?;
        Ok(kids.pop().expect("one child"))
    };
    Ok(match spec {
        NodeSpec::Point(leaf) => {
            let skeleton = match leaf.vertices.as_slice() {
                [v] => Skeleton::Point(Vec3::from_array(*v)),
                vs => return Err(vertex_count(path, "point", "1", vs.len())),
            };
            primitive(skeleton, leaf.radius, leaf.intensity, leaf.stiffness, leaf.p, leaf.frame)
                .map_err(err)?
        }
        NodeSpec::Segment(leaf) => {
            let skeleton = match leaf.vertices.as_slice() {
                [a, b] => Skeleton::Segment(Vec3::from_array(*a), Vec3::from_array(*b)),
                vs => return Err(vertex_count(path, "segment", "2", vs.len())),
            };
            primitive(skeleton, leaf.radius, leaf.intensity, leaf.stiffness, leaf.p, leaf.frame)
                .map_err(err)?
        }
        NodeSpec::Polygon(leaf) => {
            let skeleton = Skeleton::Polygon(leaf.vertices.iter().map(|v| Vec3::from_array(*v)).collect());
            primitive(skeleton, leaf.radius, leaf.intensity, leaf.stiffness, leaf.p, leaf.frame)
                .map_err(err)?
        }
        NodeSpec::Polyhedron(leaf) => {
            let skeleton = Skeleton::Polyhedron(leaf.vertices.iter().map(|v| Vec3::from_array(*v)).collect());
            primitive(skeleton, leaf.radius, leaf.intensity, leaf.stiffness, leaf.p, leaf.frame)
                .map_err(err)?
        }
        NodeSpec::Box(b) => {
            let skeleton = Skeleton::cuboid(Vec3::from_array(b.half));
            primitive(skeleton, b.radius, b.intensity, b.stiffness, b.p, b.frame).map_err(err)?
        }
        NodeSpec::Blend { children: kids } => {
            Node::Nary { op: NaryOp::Blend, children: children(kids, "≥ 1", at_least_one, "blend")? }
        }
        NodeSpec::Union { children: kids } => {
            Node::Nary { op: NaryOp::Union, children: children(kids, "≥ 1", at_least_one, "union")? }
        }
        NodeSpec::Intersection { children: kids } => Node::Nary {
            op: NaryOp::Intersection,
            children: children(kids, "≥ 1", at_least_one, "intersection")?,
        },
        NodeSpec::Superblend { n, children: kids } => Node::Nary {
            op: NaryOp::SuperBlend(n),
            children: children(kids, "≥ 1", at_least_one, "superblend")?,
        },
        NodeSpec::Difference { level, children: kids } => {
            let mut c: Vec<Node> = children(kids, "2", two, "difference")?;
            let right = c.pop().expect("two children");
            let left = c.pop().expect("two children");
            Node::difference(left, right, level.unwrap_or(threshold))
        }
        // Warps are built as written, never concatenated with a child
        // affine map ([`Node::warp`] does that), so that node paths in a
        // links spec name the nodes of the file.
        NodeSpec::Twist { rate, axis, children: kids } => {
            warped(Warp::Twist { rate, axis: direction(axis, DEFAULT_AXIS) }, unary(kids, "twist")?)
        }
        NodeSpec::Taper { slope, axis, children: kids } => {
            warped(Warp::Taper { slope, axis: direction(axis, DEFAULT_AXIS) }, unary(kids, "taper")?)
        }
        NodeSpec::Bend { rate, centre, min, max, axis, along, children: kids } => {
            let (axis, along) = (direction(axis, DEFAULT_AXIS), direction(along, DEFAULT_ALONG));
            warped(
                Warp::Bend { rate, centre: centre.unwrap_or(0.0), min, max, axis, along },
                unary(kids, "bend")?,
            )
        }
        NodeSpec::Affine { frame, children: kids } => {
            let map = transform(&frame).map_err(err)?;
            warped(Warp::Affine(map), unary(kids, "affine")?)
        }
        NodeSpec::Mix { from, to, s, children: kids } => {
            let op = |o: &Operator, field: &str| {
                o.read().ok_or_else(|| BlobError::Parse {
                    format,
                    what: "scene",
                    message: format!(
                        "node {path}: `{field}` must be \"blend\", \"union\", \"intersection\" or a \
                         super-elliptic blend's order n ≥ 1, got {o:?}"
                    ),
                })
            };
            let (from, to) = (op(&from, "from")?, op(&to, "to")?);
            Node::Mix { from, to, s, children: children(kids, "≥ 1", at_least_one, "mix")? }
        }
    })
}

/// A written direction, or `default` when absent.
fn direction(written: Option<[f32; 3]>, default: Vec3) -> Vec3 {
    written.map_or(default, Vec3::from_array)
}

/// A direction to write: `None` (left out) when it is the default.
fn written_direction(v: Vec3, default: Vec3) -> Option<[f32; 3]> {
    (v != default).then(|| v.to_array())
}

/// `warp` over `child`, as one node.
fn warped(warp: Warp, child: Node) -> Node {
    Node::Warp { warp, child: Box::new(child) }
}

fn vertex_count(path: &NodePath, kind: &'static str, expected: &'static str, got: usize) -> BlobError {
    BlobError::node(path, NodeProblem::WrongVertexCount { kind, expected, got })
}

/// A primitive from its written fields (defaults: `I = 1`, `k = 1`, `p = 2`,
/// identity frame).
fn primitive(
    skeleton: Skeleton,
    radius: f32,
    intensity: Option<f32>,
    stiffness: Option<f32>,
    p: Option<Exponent>,
    frame: Option<Transform>,
) -> Result<Node, NodeProblem> {
    let p = match p {
        None => 2.0,
        Some(Exponent::Number(p)) => p,
        Some(Exponent::Text(t)) if matches!(t.to_ascii_lowercase().as_str(), "inf" | "infinity") => {
            f32::INFINITY
        }
        Some(Exponent::Text(_)) => return Err(NodeProblem::NotFinite("p")),
    };
    let kernel = Kernel::new(intensity.unwrap_or(1.0), radius, stiffness.unwrap_or(1.0));
    let frame = match &frame {
        Some(f) => transform(f)?,
        None => Affine3A::IDENTITY,
    };
    Ok(Node::Primitive(Primitive { skeleton, kernel, p, frame }))
}

fn transform(t: &Transform) -> Result<Affine3A, NodeProblem> {
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

/// A map as a `matrix` transform.
fn matrix(m: &Affine3A) -> Transform {
    let mut cols = [0.0f32; 12];
    m.write_cols_to_slice(&mut cols);
    Transform { matrix: Some(cols), ..Transform::default() }
}

/// A frame as written: `translate` alone when the map is a translation
/// (read back exactly), else the matrix.
fn frame_of(m: &Affine3A) -> Transform {
    if m.matrix3 == glam::Mat3A::IDENTITY {
        Transform { translate: Some(m.translation.to_array()), ..Transform::default() }
    } else {
        matrix(m)
    }
}

/// `Some(v)` unless `v` is the field's default (left out of written files).
fn unless_default(v: f32, default: f32) -> Option<f32> {
    (v != default).then_some(v)
}

fn write_node(node: &Node) -> Written {
    let a = |v: &Vec3| v.to_array();
    let kids = |children: &[Node]| children.iter().map(write_node).collect();
    Written(match node {
        Node::Primitive(p) => {
            let vertices = p.skeleton.vertices();
            // An instant of a Minkowski interpolation is written as the
            // kind its vertices' hull has, which is how it is read back.
            let kind = match &p.skeleton {
                Skeleton::Generic(_) => {
                    ["point", "segment", "polygon", "polyhedron"][Polytope::hull(&vertices).dimension()]
                }
                s => s.kind(),
            };
            let leaf = Leaf {
                vertices: vertices.iter().map(a).collect(),
                radius: p.kernel.radius,
                intensity: unless_default(p.kernel.intensity, 1.0),
                stiffness: unless_default(p.kernel.stiffness, 1.0),
                p: (p.p != 2.0).then(|| {
                    if p.p.is_infinite() { Exponent::Text("inf".into()) } else { Exponent::Number(p.p) }
                }),
                frame: (p.frame != Affine3A::IDENTITY).then(|| frame_of(&p.frame)),
            };
            let half = vertices.last().copied().unwrap_or_default();
            match kind {
                "polyhedron" if p.skeleton == Skeleton::cuboid(half) => NodeSpec::Box(BoxLeaf {
                    half: half.to_array(),
                    radius: leaf.radius,
                    intensity: leaf.intensity,
                    stiffness: leaf.stiffness,
                    p: leaf.p,
                    frame: leaf.frame,
                }),
                "point" => NodeSpec::Point(leaf),
                "segment" => NodeSpec::Segment(leaf),
                "polygon" => NodeSpec::Polygon(leaf),
                _ => NodeSpec::Polyhedron(leaf),
            }
        }
        Node::Mix { from, to, s, children } => NodeSpec::Mix {
            from: Operator::of(*from),
            to: Operator::of(*to),
            s: *s,
            children: kids(children),
        },
        Node::Nary { op, children } => match *op {
            NaryOp::Blend => NodeSpec::Blend { children: kids(children) },
            NaryOp::Union => NodeSpec::Union { children: kids(children) },
            NaryOp::Intersection => NodeSpec::Intersection { children: kids(children) },
            NaryOp::SuperBlend(n) => NodeSpec::Superblend { n, children: kids(children) },
        },
        Node::Difference { left, right, level } => {
            NodeSpec::Difference { level: Some(*level), children: vec![write_node(left), write_node(right)] }
        }
        Node::Warp { warp, child } => {
            let children = vec![write_node(child)];
            match *warp {
                Warp::Twist { rate, axis } => {
                    NodeSpec::Twist { rate, axis: written_direction(axis, DEFAULT_AXIS), children }
                }
                Warp::Taper { slope, axis } => {
                    NodeSpec::Taper { slope, axis: written_direction(axis, DEFAULT_AXIS), children }
                }
                Warp::Bend { rate, centre, min, max, axis, along } => NodeSpec::Bend {
                    rate,
                    centre: Some(centre),
                    min,
                    max,
                    axis: written_direction(axis, DEFAULT_AXIS),
                    along: written_direction(along, DEFAULT_ALONG),
                    children,
                },
                Warp::Affine(m) => NodeSpec::Affine { frame: frame_of(&m), children },
            }
        }
    })
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

    fn ron(text: &str) -> BlobTree {
        BlobTree::from_ron(text).unwrap_or_else(|e| panic!("{text}: {e}"))
    }

    /// A shape off every axis, for the warp-axis tests.
    const SHAPE: &str = r#"(kind: "blend", children: [
        (kind: "segment", vertices: [(0.15, -0.1, -0.6), (0.25, 0.1, 0.6)], radius: 0.45),
        (kind: "box", half: (0.3, 0.1, 0.15), radius: 0.3, frame: (translate: (0, 0.3, 0.2))),
        (kind: "point", vertices: [(-0.3, 0.2, -0.1)], radius: 0.4)])"#;

    /// Points spread over `[-1.3, 1.3]³`, denser near the origin.
    fn spread_points() -> impl Iterator<Item = Vec3> {
        (0..600).map(|i| {
            Vec3::new((i as f32 * 0.377).sin(), (i as f32 * 0.613).cos(), (i as f32 * 0.231).sin())
                * (0.4 + 0.1 * (i % 10) as f32)
        })
    }

    /// A warp about another axis is the warp about z of the shape turned
    /// by the rotation `Q` taking z to that axis (and y to a bend's
    /// `along`): `w_axis = Q ∘ w_z ∘ Q⁻¹`, written as affine nodes around a
    /// default warp. Twist, taper and bend, several axes, unnormalized
    /// ones included; values equal to 1e-5, gradients to 1e-3 (2e-2 under
    /// bends, whose gradients are central differences).
    #[test]
    fn a_warp_about_an_axis_is_the_turned_warp_about_z() {
        // (fields of the warp, the same warp's default fields, rotation axis and degrees of Q)
        let cases = [
            (
                r#"kind: "twist", rate: 1.5, axis: (1, 0, 0)"#,
                r#"kind: "twist", rate: 1.5"#,
                "(0, 1, 0)",
                90.0,
            ),
            (r#"kind: "twist", rate: -2, axis: (0, 3, 0)"#, r#"kind: "twist", rate: -2"#, "(1, 0, 0)", -90.0),
            (
                r#"kind: "taper", slope: -0.5, axis: (1, 0, 0)"#,
                r#"kind: "taper", slope: -0.5"#,
                "(0, 1, 0)",
                90.0,
            ),
            (
                r#"kind: "taper", slope: 0.4, axis: (0, 0, -1)"#,
                r#"kind: "taper", slope: 0.4"#,
                "(1, 0, 0)",
                180.0,
            ),
            (
                r#"kind: "bend", rate: 0.8, centre: 0.1, min: -0.6, max: 0.7, axis: (1, 0, 0), along: (0, 1, 0)"#,
                r#"kind: "bend", rate: 0.8, centre: 0.1, min: -0.6, max: 0.7"#,
                "(0, 1, 0)",
                90.0,
            ),
            (
                // Q: z → x, y → z (a third of a turn about (1, 1, 1)); `along` need not be across the axis.
                r#"kind: "bend", rate: -0.6, min: -0.8, max: 0.8, axis: (2, 0, 0), along: (0.5, 0, 1)"#,
                r#"kind: "bend", rate: -0.6, min: -0.8, max: 0.8"#,
                "(1, 1, 1)",
                120.0,
            ),
        ];
        for (warp, default, axis, degrees) in cases {
            let a = ron(&format!("(root: ({warp}, children: [{SHAPE}]))"));
            let b = ron(&format!(
                r#"(root: (kind: "affine", frame: (rotate: (axis: {axis}, degrees: {degrees})), children: [
                    ({default}, children: [
                        (kind: "affine", frame: (rotate: (axis: {axis}, degrees: {minus})), children: [{SHAPE}])])]))"#,
                minus = -degrees
            ));
            let (mut worst, mut worst_grad, mut inside) = (0.0f32, 0.0f32, 0);
            for p in spread_points() {
                worst = worst.max((a.value(p) - b.value(p)).abs());
                worst_grad = worst_grad.max((a.gradient(p) - b.gradient(p)).length());
                inside += usize::from(a.value(p) > 0.0);
            }
            assert!(worst <= 1e-5, "{warp}: values differ by {worst}");
            // Analytic gradients for twists and tapers; central differences (step 1e-4) under bends.
            let grad_tolerance = if warp.contains("bend") { 2e-2 } else { 1e-3 };
            assert!(worst_grad <= grad_tolerance, "{warp}: gradients differ by {worst_grad}");
            assert!(inside > 20, "{warp}: the test points should reach the inside ({inside})");
            // The rotated warp's box holds its field: pruning changes nothing.
            let mut full = a.clone();
            full.set_pruning(false);
            for p in spread_points() {
                assert_eq!(a.potential(p), full.potential(p), "{warp} at {p}");
                assert!(a.support().contains(p) || full.potential(p) == 0.0, "{warp} at {p}");
            }
        }
        // The same axis written otherwise (default z written out, scaled) is the same warp.
        let z = ron(&format!(r#"(root: (kind: "twist", rate: 1.5, children: [{SHAPE}]))"#));
        let written =
            ron(&format!(r#"(root: (kind: "twist", rate: 1.5, axis: (0, 0, 1), children: [{SHAPE}]))"#));
        assert_eq!(z.root(), written.root());
        let scaled =
            ron(&format!(r#"(root: (kind: "twist", rate: 1.5, axis: (0, 0, 7), children: [{SHAPE}]))"#));
        for p in spread_points() {
            assert!((z.value(p) - scaled.value(p)).abs() <= 1e-6, "{p}");
        }
    }

    /// Bad axes are typed errors naming the node and the field: a zero or
    /// too short axis, a non-finite one (built directly: RON and JSON
    /// numbers are finite), a bend's `along` parallel to its axis, and an
    /// axis that is not three numbers.
    #[test]
    fn bad_axes_are_typed_errors() {
        let (p, e) = problem(&format!(
            r#"(root: (kind: "union", children: [(kind: "twist", rate: 1, axis: (0, 0, 0), children: [{SHAPE}])]))"#
        ));
        assert_eq!(p, vec![0]);
        assert!(matches!(e, NodeProblem::OutOfRange { field: "axis", .. }), "{e:?}");
        let (_, e) = problem(&format!(
            r#"(root: (kind: "taper", slope: 1, axis: (1e-7, 0, 0), children: [{SHAPE}]))"#
        ));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "axis", .. }), "{e:?}");
        let (_, e) =
            problem(&format!(r#"(root: (kind: "taper", slope: 1, axis: (1e7, 0, 0), children: [{SHAPE}]))"#));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "axis", .. }), "{e:?}");
        let (_, e) = problem(&format!(
            r#"(root: (kind: "bend", rate: 1, min: -1, max: 1, axis: (1, 0, 0), along: (-2, 0.001, 0), children: [{SHAPE}]))"#
        ));
        assert_eq!(e, NodeProblem::Warp("bend `along` is (nearly) parallel to its `axis`"));
        let (_, e) = problem(&format!(
            r#"(root: (kind: "bend", rate: 1, min: -1, max: 1, along: (0, 0, 0), children: [{SHAPE}]))"#
        ));
        assert!(matches!(e, NodeProblem::OutOfRange { field: "along", .. }), "{e:?}");
        let short = BlobTree::from_ron(&format!(
            r#"(root: (kind: "twist", rate: 1, axis: (0, 1), children: [{SHAPE}]))"#
        ));
        assert!(matches!(short, Err(BlobError::Parse { .. })), "{short:?}");
        let leaf = ron(&format!("(root: {SHAPE})")).root().clone();
        for (warp, field) in [
            (Warp::Twist { rate: 1.0, axis: Vec3::new(f32::NAN, 0.0, 1.0) }, "axis"),
            (Warp::Taper { slope: 0.1, axis: Vec3::new(0.0, f32::INFINITY, 1.0) }, "axis"),
            (
                Warp::Bend {
                    rate: 0.5,
                    centre: 0.0,
                    min: -1.0,
                    max: 1.0,
                    axis: Vec3::Z,
                    along: Vec3::new(0.0, f32::NAN, 0.0),
                },
                "along",
            ),
        ] {
            let e = BlobTree::new(Node::warp(warp, leaf.clone()), 0.5).unwrap_err();
            assert!(
                matches!(&e, BlobError::InvalidNode { problem: NodeProblem::NotFinite(f), .. } if *f == field),
                "{e:?}"
            );
        }
    }

    /// Warps with axes write them (and only them: default axes are left
    /// out, so files without axes are written as before) and read back to
    /// the same tree, bit for bit, through RON and JSON.
    #[test]
    fn warp_axes_round_trip_and_defaults_are_not_written() {
        let text = format!(
            r#"(root: (kind: "twist", rate: 0.9, axis: (0.6, 0, 0.8), children: [
                (kind: "taper", slope: -0.3, axis: (0, 1, 0.1), children: [
                    (kind: "bend", rate: 0.5, min: -1, max: 1, axis: (0.2, 1, 0), along: (1, 0, 0.3), children: [
                        (kind: "bend", rate: 0.4, min: -1, max: 1, children: [{SHAPE}])])])]))"#
        );
        let tree = ron(&text);
        let written = tree.to_ron().unwrap();
        for field in [
            "axis: (0.6, 0.0, 0.8)",
            "axis: (0.0, 1.0, 0.1)",
            "axis: (0.2, 1.0, 0.0)",
            "along: (1.0, 0.0, 0.3)",
        ] {
            assert!(written.contains(field), "{field} in\n{written}");
        }
        assert_eq!(written.matches("axis").count(), 3, "{written}");
        assert_eq!(written.matches("along").count(), 1, "{written}");
        assert_eq!(BlobTree::from_ron(&written).unwrap(), tree);
        assert_eq!(BlobTree::from_json(&tree.to_json().unwrap()).unwrap(), tree);
        let plain = ron(&format!(r#"(root: (kind: "twist", rate: 0.9, children: [{SHAPE}]))"#));
        assert!(!plain.to_ron().unwrap().contains("axis") && !plain.to_json().unwrap().contains("axis"));
    }

    /// The tagged format reads RON through `deserialize_any`: integers and
    /// floats, tuples, bare and `Some(..)` optional fields, every `p` and
    /// `frame` form read as they did, and JSON gives the same trees.
    #[test]
    fn numbers_tuples_options_and_frames_read_as_before() {
        let float = ron(r#"(root: (kind: "point", vertices: [(0.0, 0.0, 0.0)], radius: 1.0))"#);
        let int = ron(r#"(root: (kind: "point", vertices: [(0, 0, 0)], radius: 1))"#);
        assert_eq!(float.root(), int.root());
        let Node::Primitive(p) = int.root() else { panic!("a primitive") };
        assert_eq!((p.kernel, p.p, p.frame), (Kernel::new(1.0, 1.0, 1.0), 2.0, Affine3A::IDENTITY));
        // Optional fields: bare, `Some(..)`, or absent (defaults).
        let bare = ron(
            r#"(root: (kind: "segment", vertices: [(0,0,0), (1,0,0)], radius: 1, intensity: 2, stiffness: 0.5, p: 3))"#,
        );
        let some = ron(
            r#"(root: (kind: "segment", vertices: [(0,0,0), (1,0,0)], radius: 1, intensity: Some(2), stiffness: Some(0.5), p: Some(3)))"#,
        );
        assert_eq!(bare.root(), some.root());
        let Node::Primitive(p) = bare.root() else { panic!("a primitive") };
        assert_eq!((p.kernel, p.p), (Kernel::new(2.0, 1.0, 0.5), 3.0));
        for inf in [r#""inf""#, r#""Infinity""#, "inf"] {
            let t = ron(&format!(r#"(root: (kind: "box", half: (1, 2, 3), radius: 1, p: {inf}))"#));
            let Node::Primitive(p) = t.root() else { panic!("a primitive") };
            assert_eq!(p.p, f32::INFINITY);
            assert_eq!(p.skeleton, Skeleton::cuboid(Vec3::new(1.0, 2.0, 3.0)));
        }
        let (_, e) = problem(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, p: "big"))"#);
        assert_eq!(e, NodeProblem::NotFinite("p"));
        // Frames: translate · rotate · scale, or a matrix; `()` is the identity.
        let trs = ron(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1,
                frame: (translate: (1, 0, 0), rotate: (axis: (0, 0, 2), degrees: 90), scale: (2, 2, 2))))"#);
        let Node::Primitive(p) = trs.root() else { panic!("a primitive") };
        let expected = Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_axis_angle(Vec3::Z, 90f32.to_radians()),
            Vec3::X,
        );
        assert_eq!(p.frame, expected);
        let mut cols = [0.0; 12];
        expected.write_cols_to_slice(&mut cols);
        let m = cols.map(|c| c.to_string()).join(", ");
        let matrix = ron(&format!(
            r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, frame: (matrix: ({m}))))"#
        ));
        assert_eq!(matrix.root(), trs.root());
        for empty in ["()", "(translate: None)"] {
            let t = ron(&format!(
                r#"(root: (kind: "affine", frame: {empty}, children: [(kind: "point", vertices: [(0,0,0)], radius: 1)]))"#
            ));
            assert!(matches!(t.root(), Node::Warp { warp: Warp::Affine(m), .. } if *m == Affine3A::IDENTITY));
        }
        // The same scenes as JSON.
        let json = |text: &str| BlobTree::from_json(text).unwrap_or_else(|e| panic!("{text}: {e}"));
        assert_eq!(
            json(r#"{"root": {"kind": "point", "vertices": [[0, 0, 0]], "radius": 1}}"#).root(),
            int.root()
        );
        assert_eq!(
            json(r#"{"root": {"kind": "segment", "vertices": [[0,0,0], [1,0,0]], "radius": 1, "intensity": 2, "stiffness": 0.5, "p": 3, "frame": null}}"#)
                .root(),
            bare.root()
        );
        assert_eq!(
            json(&format!(r#"{{"root": {{"kind": "point", "vertices": [[0,0,0]], "radius": 1, "frame": {{"matrix": [{m}]}}}}}}"#))
                .root(),
            trs.root()
        );
        let t = json(
            r#"{"root": {"kind": "affine", "frame": {}, "children": [{"kind": "point", "vertices": [[0,0,0]], "radius": 1}]}}"#,
        );
        assert!(matches!(t.root(), Node::Warp { warp: Warp::Affine(m), .. } if *m == Affine3A::IDENTITY));
        // Defaults of operators: a difference's level is the threshold, a bend's centre 0.
        let t = ron(
            r#"(threshold: 0.4, root: (kind: "bend", rate: 1, min: -1, max: 1, children: [(kind: "difference", children: [
                (kind: "point", vertices: [(0,0,0)], radius: 1), (kind: "point", vertices: [(1,0,0)], radius: 1)])]))"#,
        );
        let Node::Warp { warp, child } = t.root() else { panic!("a warp") };
        assert_eq!(*warp, Warp::bend(1.0, 0.0, -1.0, 1.0));
        assert!(matches!(**child, Node::Difference { level, .. } if level == 0.4));
    }

    /// Fields a kind does not have (misspelled, or another kind's), repeated
    /// fields and non-string kinds are refused with the node's path.
    #[test]
    fn unknown_and_repeated_fields_are_clear_errors() {
        let parse = |r: Result<BlobTree, BlobError>| match r {
            Err(BlobError::Parse { format, message, .. }) => (format, message),
            other => panic!("expected a parse error, got {other:?}"),
        };
        let (f, m) = parse(BlobTree::from_ron(
            r#"(root: (kind: "blend", children: [(kind: "point", vertices: [(0,0,0)], radius: 1),
                (kind: "point", vertices: [(0,0,0)], radius: 1, stifness: 2)]))"#,
        ));
        assert_eq!(f, "RON");
        assert_eq!(
            m,
            "node root/1: a `point` node has no field `stifness` (its fields: `vertices`, `radius`, \
             `intensity`, `stiffness`, `p`, `frame`)"
        );
        let (f, m) = parse(BlobTree::from_json(
            r#"{"root": {"kind": "taper", "slope": 0.1, "min": 0, "children": [{"kind": "point", "vertices": [[0,0,0]], "radius": 1}]}}"#,
        ));
        assert_eq!(f, "JSON");
        assert!(m.starts_with("node root: a `taper` node has no field `min`"), "{m}");
        let (_, m) = parse(BlobTree::from_ron(
            r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, half: (1,1,1)))"#,
        ));
        assert!(m.starts_with("node root: a `point` node has no field `half`"), "{m}");
        let (_, m) = parse(BlobTree::from_ron(
            r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, children: []))"#,
        ));
        assert!(m.contains("has no field `children`"), "{m}");
        let (_, m) = parse(BlobTree::from_ron(
            r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, radius: 2))"#,
        ));
        assert!(m.contains("duplicate field `radius`"), "{m}");
        let (_, m) = parse(BlobTree::from_json(
            r#"{"root": {"kind": "point", "vertices": [[0,0,0]], "radius": 1, "radius": 2}}"#,
        ));
        assert!(m.contains("duplicate field `radius`"), "{m}");
        let (_, m) =
            parse(BlobTree::from_ron(r#"(root: (kind: "union", children: [(kind: 1, radius: 1)]))"#));
        assert!(m.starts_with("node root/0: `kind` must be a string"), "{m}");
        let (_, m) =
            parse(BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: "big"))"#));
        assert!(m.starts_with("node root: "), "{m}");
        let (_, m) = parse(BlobTree::from_ron(
            r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1), colour: 2)"#,
        ));
        assert!(m.contains("colour"), "{m}");
        assert_eq!(problem(r#"(root: (radius: 1))"#), (vec![], NodeProblem::MissingField("kind")));
        assert_eq!(
            problem(r#"(root: (kind: "union", children: [(kind: "taper", children: [])]))"#),
            (vec![0], NodeProblem::MissingField("slope"))
        );
        assert_eq!(
            BlobTree::from_json(r#"{"root": {"kind": "union", "children": [{"kind": "Point"}]}}"#)
                .unwrap_err()
                .to_string(),
            r#"node root/0: unknown kind "Point""#
        );
    }

    /// Node paths in a links spec name the nodes of the file as written:
    /// consecutive affine nodes are read as separate nodes (they used to
    /// be concatenated, which shifted every path below them).
    #[test]
    fn consecutive_affine_nodes_keep_their_paths() {
        let pair = r#"(kind: "blend", children: [
            (kind: "point", vertices: [(0,0,0)], radius: 0.5), (kind: "point", vertices: [(0.3,0,0)], radius: 0.5)])"#;
        let a = ron(&format!(
            r#"(root: (kind: "affine", frame: (translate: (0.1, 0, 0)), children: [
                (kind: "affine", frame: (scale: (2, 2, 2)), children: [{pair}])]))"#
        ));
        assert!(matches!(a.root().get(&NodePath(vec![0])), Some(Node::Warp { warp: Warp::Affine(_), .. })));
        assert!(matches!(a.root().get(&NodePath(vec![0, 0, 1])), Some(Node::Primitive(_))));
        // The same field as the concatenated map.
        let merged = Node::affine(
            Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0)),
            Node::affine(
                Affine3A::from_scale(Vec3::splat(2.0)),
                ron(&format!("(root: {pair})")).root().clone(),
            ),
        );
        assert!(matches!(&merged, Node::Warp { child, .. } if matches!(**child, Node::Nary { .. })));
        let merged = BlobTree::new(merged, 0.5).unwrap();
        for i in 0..100 {
            let p = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
            assert!((a.value(p) - merged.value(p)).abs() < 1e-6, "at {p}");
        }
        // A links spec written against the file finds its nodes.
        let b = ron(&format!("(root: {pair})"));
        let spec =
            crate::MorphSpec::from_ron("(links: [(a: [0, 0, 1], b: [0]), (a: [0, 0, 0], b: [1])])").unwrap();
        let g = crate::GenericTree::new(&a, &b, &spec).unwrap();
        assert_eq!(g.pair().leaf_count(), 2);
        let wrong = crate::MorphSpec::from_ron("(links: [(a: [0, 1], b: [0])])").unwrap();
        assert!(crate::GenericTree::new(&a, &b, &wrong).is_err());
    }

    /// The time-varying `mix` node is a scene kind: written and read back
    /// to the same node, its operators by name or super-elliptic order,
    /// with bad operators and weights refused by node.
    #[test]
    fn mix_nodes_round_trip_and_are_checked() {
        let ball = |x: f32| format!(r#"(kind: "point", vertices: [({x}, 0, 0)], radius: 1)"#);
        let text = format!(
            r#"(root: (kind: "mix", from: "union", to: 2.5, s: 0.25, children: [{}, {}]))"#,
            ball(0.0),
            ball(0.4)
        );
        let t = ron(&text);
        assert!(matches!(
            t.root(),
            Node::Mix { from: NaryOp::Union, to: NaryOp::SuperBlend(n), s, .. } if *n == 2.5 && *s == 0.25
        ));
        assert_eq!(BlobTree::from_ron(&t.to_ron().unwrap()).unwrap().root(), t.root());
        assert_eq!(BlobTree::from_json(&t.to_json().unwrap()).unwrap().root(), t.root());
        let e = BlobTree::from_ron(&text.replace(r#""union""#, r#""max""#)).unwrap_err().to_string();
        assert!(e.contains("node root: `from` must be"), "{e}");
        let (p, e) = problem(&text.replace("0.25", "1.5"));
        assert_eq!(
            (p, e),
            (vec![], NodeProblem::OutOfRange { field: "s", value: 1.5, expected: "0 ≤ s ≤ 1" })
        );
        let (_, e) = problem(&text.replace("2.5", "0.5"));
        assert_eq!(e, NodeProblem::OrderBelowOne(0.5));
    }

    /// Every built-in scene is written and read back to the same tree.
    #[test]
    fn built_in_scenes_round_trip_exactly() {
        for name in crate::scenes::NAMES {
            let tree = crate::scenes::load(name).unwrap();
            let again = BlobTree::from_ron(&tree.to_ron().unwrap()).unwrap();
            assert_eq!(again.root(), tree.root(), "{name} through RON");
            assert_eq!(again.threshold(), tree.threshold());
            let again = BlobTree::from_json(&tree.to_json().unwrap()).unwrap();
            assert_eq!(again.root(), tree.root(), "{name} through JSON");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Random trees of every node kind are written and read back to
        /// the same tree, through RON and JSON.
        #[test]
        fn random_trees_round_trip_exactly(node in crate::testutil::tree()) {
            let Ok(tree) = BlobTree::new(node, 0.5) else { return Ok(()) };
            if tree.root().peak_bound() <= 0.5 {
                return Ok(());
            }
            let ron_text = tree.to_ron().unwrap();
            let again = BlobTree::from_ron(&ron_text).unwrap();
            proptest::prop_assert_eq!(again.root(), tree.root(), "{}", ron_text);
            let json_text = tree.to_json().unwrap();
            let again = BlobTree::from_json(&json_text).unwrap();
            proptest::prop_assert_eq!(again.root(), tree.root(), "{}", json_text);
        }
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
        // (A degenerate box: the radius is refused first. This used to be a
        // point carrying a `half`, which the old reader ignored and the
        // tagged format refuses as a field points do not have.)
        let err =
            BlobTree::from_ron(&scene(r#"(kind: "box", half: (0,0,0), radius: 1e30)"#.into())).unwrap_err();
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
