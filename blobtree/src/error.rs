//! Typed errors: scene validation (with the path of the offending node) and
//! metamorphosis set-up.

use isomorph_common::{GridError, MorphFailure, TransformError};
use std::fmt;

/// The position of a node in a BlobTree: child indices from the root
/// (`[]` is the root, `[1, 0]` the first child of the root's second child).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct NodePath(pub Vec<usize>);

impl NodePath {
    /// The root's path.
    pub fn root() -> Self {
        Self(Vec::new())
    }

    /// The path of this node's child `i`.
    pub fn child(&self, i: usize) -> Self {
        let mut v = self.0.clone();
        v.push(i);
        Self(v)
    }

    /// The parent's path (`None` for the root).
    pub fn parent(&self) -> Option<Self> {
        let (_, rest) = self.0.split_last()?;
        Some(Self(rest.to_vec()))
    }
}

impl fmt::Display for NodePath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("root")?;
        for i in &self.0 {
            write!(f, "/{i}")?;
        }
        Ok(())
    }
}

/// What is wrong with one node of a BlobTree description.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NodeProblem {
    /// The `kind` string names no node or skeleton kind.
    #[error("unknown kind {0:?}")]
    UnknownKind(String),
    /// A field required by this kind is missing.
    #[error("missing field `{0}`")]
    MissingField(&'static str),
    /// A parameter is NaN or infinite.
    #[error("parameter `{0}` is NaN or infinite")]
    NotFinite(&'static str),
    /// The radius of influence is zero or negative.
    #[error("radius of influence must be positive, got {0}")]
    NonPositiveRadius(f32),
    /// The intensity is negative (zero is allowed: phantom element).
    #[error("intensity must be ≥ 0, got {0}")]
    NegativeIntensity(f32),
    /// The Blanc–Schlick stiffness is negative (the kernel then has a pole).
    #[error("stiffness must be ≥ 0, got {0}")]
    NegativeStiffness(f32),
    /// The L^p exponent is below 1 (not a metric).
    #[error("L^p exponent must be in [1, ∞], got {0}")]
    ExponentBelowOne(f32),
    /// The super-elliptic blend order is below 1.
    #[error("super-elliptic blend order must be ≥ 1, got {0}")]
    OrderBelowOne(f32),
    /// An operator node has no child (or a binary/unary node the wrong number).
    #[error("{kind} node needs {expected} children, has {got}")]
    WrongChildCount {
        /// The node kind.
        kind: &'static str,
        /// What the kind needs (`"≥ 1"`, `"2"`, `"1"`).
        expected: &'static str,
        /// How many it has.
        got: usize,
    },
    /// A skeleton has the wrong number of vertices for its kind.
    #[error("{kind} skeleton needs {expected} vertices, has {got}")]
    WrongVertexCount {
        /// Skeleton kind.
        kind: &'static str,
        /// What the kind needs.
        expected: &'static str,
        /// How many were given.
        got: usize,
    },
    /// The skeleton's vertices span fewer (or more) dimensions than its kind:
    /// a segment of coincident points, a non-planar polygon, a flat polyhedron.
    #[error("{0} skeleton has the wrong dimension (degenerate or not planar)")]
    WrongDimension(&'static str),
    /// A frame or affine node is singular, mirrored or not finite.
    #[error("transform: {0}")]
    Transform(TransformError),
    /// A warp's parameters are out of range.
    #[error("warp: {0}")]
    Warp(&'static str),
    /// A difference level must be ≥ 0.
    #[error("difference level must be ≥ 0, got {0}")]
    NegativeLevel(f32),
    /// A finite parameter is too large (or a radius too small) to be
    /// resolved in `f32` ([`crate::node::MAX_MAGNITUDE`]).
    #[error("`{field}` = {value:?} is out of range: expected {expected}")]
    OutOfRange {
        /// The field as written in a scene (`"radius"`, `"vertices"`, `"frame"`, …).
        field: &'static str,
        /// The offending value.
        value: f32,
        /// What is accepted.
        expected: &'static str,
    },
    /// The node lies deeper than [`crate::scene::MAX_DEPTH`] levels in a scene file.
    #[error("the scene nests deeper than {0} levels of nodes")]
    TooDeep(usize),
    /// The node's support box is not finite or reaches beyond
    /// [`crate::node::MAX_SUPPORT`] (nested frames or warps scale it too far).
    #[error("its support box reaches {0:?}, beyond ±1e9 (nested frames or warps scale it too far)")]
    SupportTooLarge(f32),
}

/// Errors of building, loading or saving a BlobTree.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BlobError {
    /// One node is invalid; `path` says which.
    #[error("node {path}: {problem}")]
    InvalidNode {
        /// Where the node is.
        path: NodePath,
        /// What is wrong.
        problem: NodeProblem,
    },
    /// The iso threshold `T` must be positive and at most
    /// [`crate::node::MAX_MAGNITUDE`].
    #[error("threshold must be in (0, 1e6], got {0:?}")]
    InvalidThreshold(f32),
    /// The scene has no inside: its potential is at most `peak` (an upper
    /// bound from the intensities) everywhere, not above the threshold.
    #[error(
        "the scene is empty: its potential never exceeds {peak:?} (intensities, blended), not above the \
         threshold {threshold:?}"
    )]
    EmptyScene {
        /// Upper bound of the potential.
        peak: f32,
        /// The threshold.
        threshold: f32,
    },
    /// The text is not valid RON / JSON for a scene or a links spec.
    #[error("cannot parse the {format} {what}: {message}")]
    Parse {
        /// `"RON"` or `"JSON"`.
        format: &'static str,
        /// `"scene"` or `"links spec"` (a [`crate::MorphSpec`]).
        what: &'static str,
        /// The parser's message (with line and column).
        message: String,
    },
    /// Serialization failed.
    #[error("cannot write the scene: {0}")]
    Write(String),
    /// A scene or spec file could not be read, or a scene name is unknown.
    #[error("cannot read {path}: {message}")]
    Read {
        /// The path or name given.
        path: String,
        /// Why.
        message: String,
    },
}

impl BlobError {
    pub(crate) fn node(path: &NodePath, problem: NodeProblem) -> Self {
        Self::InvalidNode { path: path.clone(), problem }
    }
}

/// Which of the two shapes of a morph (the shared core's).
pub use isomorph_common::Side;

/// Errors of setting up or evaluating a BlobTree metamorphosis.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BlobMorphError {
    /// One of the kinds every morph method shares: a time outside
    /// `[0, 1]`, an input that is not a BlobTree, cancellation, grids.
    #[error(transparent)]
    Morph(#[from] isomorph_common::MorphError),
    /// A source or target tree (or an instantiated frame) is invalid.
    #[error(transparent)]
    Blob(#[from] BlobError),
    /// A link names a node that does not exist.
    #[error("link names {side} node {path}, which does not exist")]
    NoSuchNode {
        /// Which tree.
        side: Side,
        /// The path given.
        path: NodePath,
    },
    /// A link is not compatible with the tree hierarchy: its nodes' parents
    /// are never matched, so it can never be used (§4: nodes at a level are
    /// matched only when their ancestors are).
    #[error("link {a} ↔ {b} breaks the hierarchy: the parents of its nodes are not matched")]
    LinkBreaksHierarchy {
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
    },
    /// A speed curve is malformed (NaN, outside `[0, 1]`, an empty window,
    /// free-form points that are not monotone).
    #[error("speed curve for {a} ↔ {b}: {problem}")]
    InvalidSpeed {
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
        /// What is wrong.
        problem: &'static str,
    },
    /// A speed curve or trajectory names a pair of nodes that the
    /// correspondence never matched.
    #[error("{what} for {a} ↔ {b}: these nodes are not matched with each other")]
    UnmatchedPair {
        /// `"speed curve"` or `"trajectory"`.
        what: &'static str,
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
    },
    /// A trajectory names a matched pair whose generic node has no frame to
    /// move: an n-ary operator, a difference, or a twist, taper or bend
    /// (these act about their local axes; the affine node above one is its
    /// frame).
    #[error(
        "trajectory for {a} ↔ {b}: their generic node is a {kind}, which has no frame to move; give trajectories \
         to leaves and affine nodes (to move a twist, taper or bend, to the affine node above it)"
    )]
    FramelessTrajectory {
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
        /// The generic node's kind (`"blend"`, `"difference"`, `"twist"`, …).
        kind: &'static str,
    },
    /// A trajectory handle coordinate is NaN, infinite or beyond
    /// [`crate::node::MAX_MAGNITUDE`].
    #[error(
        "trajectory for {a} ↔ {b}: handle coordinate {value:?} is out of range: expected a magnitude ≤ 1e6"
    )]
    InvalidTrajectory {
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
        /// The offending coordinate.
        value: f32,
    },
    /// A trajectory's key frames are malformed.
    #[error("trajectory for {a} ↔ {b}: {problem}")]
    InvalidKeys {
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
        /// What is wrong.
        problem: &'static str,
    },
    /// The decomposition would need more than `limit` node pairs
    /// ([`crate::correspond::MAX_PAIRS`]) or skeleton vertex pairs
    /// ([`crate::correspond::MAX_VERTEX_PAIRS`]): typically the
    /// all-children heuristic on wide nodes (`n_A × n_B` pairs) or many links.
    #[error(
        "matching the trees needs more than {limit} {what} (exceeded under {a} ↔ {b}); use the \
         nearest_centre heuristic or fewer links"
    )]
    TooManyPairs {
        /// `"node pairs"` or `"skeleton vertex pairs"`.
        what: &'static str,
        /// Source node under which the limit was exceeded.
        a: NodePath,
        /// Target node under which the limit was exceeded.
        b: NodePath,
        /// The limit.
        limit: usize,
    },
    /// Two matched affine nodes or frames cannot be interpolated (mirror).
    #[error("affine maps at {a} ↔ {b} cannot be interpolated")]
    Transform {
        /// Source node.
        a: NodePath,
        /// Target node.
        b: NodePath,
        /// Why (printed as the error's source, not in its message).
        source: TransformError,
    },
    /// A phantom's parameters in the links spec are invalid, or name a
    /// node that gets no phantom (it has a partner).
    #[error("phantom for {side} node {path}: {problem}")]
    Phantom {
        /// The side of the node the phantom partners.
        side: Side,
        /// The node.
        path: NodePath,
        /// What is wrong.
        problem: &'static str,
    },
    /// One segment of a morph through key shapes failed to build (segment
    /// `index` goes from key shape `index` to `index + 1`; the source is
    /// key 0, the target the last).
    #[error("segment {index} of the morph (key shape {index} → {next})", next = index + 1)]
    Segment {
        /// The segment.
        index: usize,
        /// Why (printed as the error's source).
        source: Box<BlobMorphError>,
    },
    /// The correspondence of a de Casteljau level above the first (a
    /// Bézier-like morph) failed with the links given for it
    /// ([`crate::LevelLinks`]): pair `pair` of level `level`.
    #[error("de Casteljau level {level}, pair {pair}")]
    Level {
        /// The level `r ≥ 2`.
        level: usize,
        /// The pair `i`: between `P_i^{r−1}` and `P_{i+1}^{r−1}`.
        pair: usize,
        /// Why (printed as the error's source).
        source: Box<BlobMorphError>,
    },
}

impl From<GridError> for BlobMorphError {
    fn from(e: GridError) -> Self {
        BlobMorphError::Morph(e.into())
    }
}

impl MorphFailure for BlobMorphError {
    fn shared(&self) -> Option<&isomorph_common::MorphError> {
        match self {
            BlobMorphError::Morph(e) => Some(e),
            BlobMorphError::Segment { source, .. } | BlobMorphError::Level { source, .. } => source.shared(),
            _ => None,
        }
    }
}
