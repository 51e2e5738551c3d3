//! The BlobTree description (§2): skeletal primitives at the leaves,
//! blending, Boolean and warping operators at the nodes.

use crate::error::{BlobError, NodePath, NodeProblem};
use crate::kernel::Kernel;
use crate::skeleton::Skeleton;
use crate::warp::Warp;
use glam::{Affine3A, Vec3};

/// The largest magnitude accepted for a length, position, intensity,
/// stiffness or warp parameter (and for the threshold): `f32` geometry
/// beyond it cannot be resolved next to unit-sized features, and squared
/// distances would overflow. Radii must also be at least `1 / MAX_MAGNITUDE`.
pub const MAX_MAGNITUDE: f32 = 1e6;

/// The largest coordinate any node's support box may reach (nested frames
/// and warps can multiply parameters below [`MAX_MAGNITUDE`]).
pub const MAX_SUPPORT: f32 = 1e9;

/// `Err(OutOfRange)` unless every value in `values` has magnitude ≤ [`MAX_MAGNITUDE`].
pub(crate) fn check_magnitude(field: &'static str, values: &[f32]) -> Result<(), NodeProblem> {
    match values.iter().find(|v| v.abs() > MAX_MAGNITUDE) {
        Some(&value) => Err(NodeProblem::OutOfRange { field, value, expected: "a magnitude ≤ 1e6" }),
        None => Ok(()),
    }
}

/// A skeletal primitive `{R, S, d, g}` (§3.5): a local frame, a convex
/// skeleton, an L^p distance and a Blanc–Schlick field function.
#[derive(Debug, Clone, PartialEq)]
pub struct Primitive {
    /// The skeleton in local coordinates.
    pub skeleton: Skeleton,
    /// Field-function parameters `I, R, k`.
    pub kernel: Kernel,
    /// The L^p exponent `p ∈ [1, ∞]` (2: Euclidean), measured along the local axes.
    pub p: f32,
    /// Local frame → world (rotation, translation, optionally scale).
    pub frame: Affine3A,
}

impl Primitive {
    /// A primitive with the identity frame and the Euclidean metric.
    pub fn new(skeleton: Skeleton, kernel: Kernel) -> Self {
        Self { skeleton, kernel, p: 2.0, frame: Affine3A::IDENTITY }
    }

    /// The same primitive with another frame.
    pub fn with_frame(mut self, frame: Affine3A) -> Self {
        self.frame = frame;
        self
    }

    /// The same primitive with another L^p exponent.
    pub fn with_p(mut self, p: f32) -> Self {
        self.p = p;
        self
    }

    /// The skeleton centre in world space.
    pub fn centre(&self) -> Vec3 {
        self.frame.transform_point3(self.skeleton.centre())
    }

    pub(crate) fn validate(&self) -> Result<(), NodeProblem> {
        let k = &self.kernel;
        if !k.intensity.is_finite() {
            return Err(NodeProblem::NotFinite("intensity"));
        }
        if !k.radius.is_finite() {
            return Err(NodeProblem::NotFinite("radius"));
        }
        if !k.stiffness.is_finite() {
            return Err(NodeProblem::NotFinite("stiffness"));
        }
        if k.radius <= 0.0 {
            return Err(NodeProblem::NonPositiveRadius(k.radius));
        }
        if k.intensity < 0.0 {
            return Err(NodeProblem::NegativeIntensity(k.intensity));
        }
        if k.stiffness < 0.0 {
            return Err(NodeProblem::NegativeStiffness(k.stiffness));
        }
        if !(1.0 / MAX_MAGNITUDE..=MAX_MAGNITUDE).contains(&k.radius) {
            return Err(NodeProblem::OutOfRange {
                field: "radius",
                value: k.radius,
                expected: "1e-6 ≤ radius ≤ 1e6",
            });
        }
        check_magnitude("intensity", &[k.intensity])?;
        check_magnitude("stiffness", &[k.stiffness])?;
        let vertices = self.skeleton.vertices();
        check_magnitude("vertices", &vertices.iter().flat_map(|v| v.to_array()).collect::<Vec<f32>>())?;
        if p_invalid(self.p) {
            return Err(if self.p.is_nan() {
                NodeProblem::NotFinite("p")
            } else {
                NodeProblem::ExponentBelowOne(self.p)
            });
        }
        isomorph_common::AffineParts::from_affine(&self.frame).map_err(NodeProblem::Transform)?;
        check_magnitude("frame", &self.frame.to_cols_array())?;
        Ok(())
    }
}

fn p_invalid(p: f32) -> bool {
    p.is_nan() || p < 1.0
}

/// An n-ary commutative operator (`{∪, ∩, +}` and Ricci's super-elliptic blend).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NaryOp {
    /// Blend: the sum of the children's fields.
    Blend,
    /// Union: the maximum.
    Union,
    /// Intersection: the minimum.
    Intersection,
    /// Super-elliptic blend of order `n ≥ 1`: `(Σ f_i^n)^(1/n)`; `n = 1` is
    /// the blend, `n = ∞` the union.
    SuperBlend(f32),
}

impl NaryOp {
    /// The operator's name.
    pub fn name(&self) -> &'static str {
        match self {
            NaryOp::Blend => "blend",
            NaryOp::Union => "union",
            NaryOp::Intersection => "intersection",
            NaryOp::SuperBlend(_) => "superblend",
        }
    }

    /// Applies the operator to child values (and gradients when `grads` is
    /// given, written to `grad`). Empty input gives 0.
    #[inline]
    pub(crate) fn apply(&self, vals: &[f32], grads: Option<(&[Vec3], &mut Vec3)>) -> f32 {
        match *self {
            NaryOp::Blend => {
                if let Some((g, out)) = grads {
                    *out = g.iter().copied().sum();
                }
                vals.iter().sum()
            }
            NaryOp::Union | NaryOp::Intersection => {
                let want_max = matches!(self, NaryOp::Union);
                let mut best = 0usize;
                for (i, &v) in vals.iter().enumerate() {
                    if (want_max && v > vals[best]) || (!want_max && v < vals[best]) {
                        best = i;
                    }
                }
                if let Some((g, out)) = grads {
                    *out = g.get(best).copied().unwrap_or(Vec3::ZERO);
                }
                vals.get(best).copied().unwrap_or(0.0)
            }
            NaryOp::SuperBlend(n) => {
                let m = vals.iter().copied().fold(0.0f32, f32::max);
                if m <= 0.0 {
                    if let Some((_, out)) = grads {
                        *out = Vec3::ZERO;
                    }
                    return 0.0;
                }
                if n.is_infinite() {
                    return NaryOp::Union.apply(vals, grads);
                }
                let sum: f32 = vals.iter().map(|&v| (v / m).powf(n)).sum();
                let f = m * sum.powf(1.0 / n);
                if let Some((g, out)) = grads {
                    *out = vals
                        .iter()
                        .zip(g)
                        .filter(|(v, _)| **v > 0.0)
                        .map(|(&v, &gi)| gi * (v / f).powf(n - 1.0))
                        .sum();
                }
                f
            }
        }
    }
}

/// A BlobTree node.
#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    /// A skeletal primitive (leaf).
    Primitive(Primitive),
    /// A commutative n-ary operator over ≥ 1 children.
    Nary {
        /// The operator.
        op: NaryOp,
        /// The children.
        children: Vec<Node>,
    },
    /// The time-varying commutative node of §4.4 at one instant:
    /// `(1 − s)·from(children) + s·to(children)`. Generic trees produce it;
    /// it is rarely written by hand.
    Mix {
        /// The source operator.
        from: NaryOp,
        /// The target operator.
        to: NaryOp,
        /// The weight of `to`, in `[0, 1]`.
        s: f32,
        /// The children.
        children: Vec<Node>,
    },
    /// Difference `left − right`: `max(0, min(f_L, c + (max(f_L, 2c) − c)(1 − f_R/c)))`
    /// with `c` the node's reference `level` (the threshold `T` by default).
    /// For `f_L ≤ 2c` this is the BlobTree's `min(f_L, 2c − f_R)`; the
    /// extension above `2c` makes a null (phantom) right child exactly neutral.
    Difference {
        /// The shape cut from.
        left: Box<Node>,
        /// The shape cut away.
        right: Box<Node>,
        /// Reference level `c ≥ 0` (usually the tree's threshold; scaled with the node).
        level: f32,
    },
    /// A warp applied to its child: `f ∘ w⁻¹`.
    Warp {
        /// The warp.
        warp: Warp,
        /// The warped subtree.
        child: Box<Node>,
    },
}

impl Node {
    /// A primitive leaf.
    pub fn primitive(p: Primitive) -> Node {
        Node::Primitive(p)
    }

    /// A blend (sum) of `children`.
    pub fn blend(children: Vec<Node>) -> Node {
        Node::Nary { op: NaryOp::Blend, children }
    }

    /// A union (max) of `children`.
    pub fn union(children: Vec<Node>) -> Node {
        Node::Nary { op: NaryOp::Union, children }
    }

    /// An intersection (min) of `children`.
    pub fn intersection(children: Vec<Node>) -> Node {
        Node::Nary { op: NaryOp::Intersection, children }
    }

    /// A super-elliptic blend of order `n`.
    pub fn super_blend(n: f32, children: Vec<Node>) -> Node {
        Node::Nary { op: NaryOp::SuperBlend(n), children }
    }

    /// `left − right` with reference level `level` (pass the tree's threshold).
    pub fn difference(left: Node, right: Node, level: f32) -> Node {
        Node::Difference { left: Box::new(left), right: Box::new(right), level }
    }

    /// `warp` applied to `child`. Affine maps over affine nodes are
    /// concatenated into one node (§2: "consecutive affine transformations
    /// may be concatenated").
    pub fn warp(warp: Warp, child: Node) -> Node {
        match (warp, child) {
            (Warp::Affine(outer), Node::Warp { warp: Warp::Affine(inner), child }) => {
                Node::Warp { warp: Warp::Affine(outer * inner), child }
            }
            (warp, child) => Node::Warp { warp, child: Box::new(child) },
        }
    }

    /// `child` placed by an affine map (concatenated with an affine child).
    pub fn affine(map: Affine3A, child: Node) -> Node {
        Node::warp(Warp::Affine(map), child)
    }

    /// The node's kind name.
    pub fn kind(&self) -> &'static str {
        match self {
            Node::Primitive(_) => "primitive",
            Node::Nary { op, .. } => op.name(),
            Node::Mix { .. } => "mix",
            Node::Difference { .. } => "difference",
            Node::Warp { warp, .. } => warp.kind(),
        }
    }

    /// The children in order (empty for a primitive).
    pub fn children(&self) -> Vec<&Node> {
        match self {
            Node::Primitive(_) => Vec::new(),
            Node::Nary { children, .. } | Node::Mix { children, .. } => children.iter().collect(),
            Node::Difference { left, right, .. } => vec![left, right],
            Node::Warp { child, .. } => vec![child],
        }
    }

    /// The node at `path` below this one.
    pub fn get(&self, path: &NodePath) -> Option<&Node> {
        let mut n = self;
        for &i in &path.0 {
            n = *n.children().get(i)?;
        }
        Some(n)
    }

    /// Number of primitives below (and including) this node.
    pub fn leaf_count(&self) -> usize {
        match self {
            Node::Primitive(_) => 1,
            _ => self.children().iter().map(|c| c.leaf_count()).sum(),
        }
    }

    /// The scaled node `αN` (§4.2): every intensity and difference level
    /// multiplied by `α ≥ 0`. Its field is exactly `α` times this node's.
    pub fn scaled(&self, alpha: f32) -> Node {
        match self {
            Node::Primitive(p) => {
                let mut p = p.clone();
                p.kernel.intensity *= alpha;
                Node::Primitive(p)
            }
            Node::Nary { op, children } => {
                Node::Nary { op: *op, children: children.iter().map(|c| c.scaled(alpha)).collect() }
            }
            Node::Mix { from, to, s, children } => Node::Mix {
                from: *from,
                to: *to,
                s: *s,
                children: children.iter().map(|c| c.scaled(alpha)).collect(),
            },
            Node::Difference { left, right, level } => Node::Difference {
                left: Box::new(left.scaled(alpha)),
                right: Box::new(right.scaled(alpha)),
                level: level * alpha,
            },
            Node::Warp { warp, child } => Node::Warp { warp: *warp, child: Box::new(child.scaled(alpha)) },
        }
    }

    /// The phantom of this subtree (§3.3): the same structure, skeletons,
    /// radii and stiffnesses with null intensity — a null field.
    pub fn phantom(&self) -> Node {
        self.scaled(0.0)
    }

    /// An upper bound of this node's potential anywhere: the intensity of a
    /// primitive, the sum over a blend (and a super-elliptic blend, whose
    /// value is at most the sum), the maximum over a union, the minimum over
    /// an intersection, the left child's for a difference, the child's for
    /// a warp. A tree whose bound is at most its threshold has no inside.
    pub fn peak_bound(&self) -> f32 {
        let kids = || self.children().into_iter().map(Node::peak_bound);
        match self {
            Node::Primitive(p) => p.kernel.intensity,
            Node::Nary { op: NaryOp::Union, .. } => kids().fold(0.0, f32::max),
            Node::Nary { op: NaryOp::Intersection, .. } => kids().fold(f32::INFINITY, f32::min),
            Node::Nary { .. } | Node::Mix { .. } => kids().sum(),
            Node::Difference { left, .. } => left.peak_bound(),
            Node::Warp { child, .. } => child.peak_bound(),
        }
    }

    /// The centre of the skeletons below (world space; warps applied forward),
    /// used by the nearest-centre matching heuristic.
    pub fn centre(&self) -> Vec3 {
        let mut acc = (Vec3::ZERO, 0usize);
        self.accumulate_centres(&|p| p, &mut acc);
        if acc.1 == 0 { Vec3::ZERO } else { acc.0 / acc.1 as f32 }
    }

    fn accumulate_centres(&self, map: &dyn Fn(Vec3) -> Vec3, acc: &mut (Vec3, usize)) {
        match self {
            Node::Primitive(p) => {
                acc.0 += map(p.centre());
                acc.1 += 1;
            }
            Node::Warp { warp, child } => {
                let w = *warp;
                child.accumulate_centres(&|p| map(w.forward(p)), acc)
            }
            Node::Difference { left, .. } => left.accumulate_centres(map, acc),
            _ => {
                for c in self.children() {
                    c.accumulate_centres(map, acc)
                }
            }
        }
    }

    /// Checks every node, depth first.
    ///
    /// # Errors
    /// [`BlobError::InvalidNode`] with the path of the first offending node.
    pub fn validate(&self) -> Result<(), BlobError> {
        self.validate_at(&NodePath::root())
    }

    fn validate_at(&self, path: &NodePath) -> Result<(), BlobError> {
        let err = |p: NodeProblem| BlobError::node(path, p);
        match self {
            Node::Primitive(p) => {
                p.validate().map_err(err)?;
                p.skeleton.polytope().map_err(err)?;
            }
            Node::Nary { op, children } | Node::Mix { from: op, children, .. } => {
                if children.is_empty() {
                    return Err(err(NodeProblem::WrongChildCount {
                        kind: op.name(),
                        expected: "≥ 1",
                        got: 0,
                    }));
                }
                let ops: Vec<NaryOp> = match self {
                    Node::Mix { to, s, .. } => {
                        if s.is_nan() {
                            return Err(err(NodeProblem::NotFinite("s")));
                        }
                        if !(0.0..=1.0).contains(s) {
                            return Err(err(NodeProblem::OutOfRange {
                                field: "s",
                                value: *s,
                                expected: "0 ≤ s ≤ 1",
                            }));
                        }
                        vec![*op, *to]
                    }
                    _ => vec![*op],
                };
                for op in ops {
                    if let NaryOp::SuperBlend(n) = op {
                        if n.is_nan() {
                            return Err(err(NodeProblem::NotFinite("n")));
                        }
                        if n < 1.0 {
                            return Err(err(NodeProblem::OrderBelowOne(n)));
                        }
                    }
                }
            }
            Node::Difference { level, .. } => {
                if !level.is_finite() {
                    return Err(err(NodeProblem::NotFinite("level")));
                }
                if *level < 0.0 {
                    return Err(err(NodeProblem::NegativeLevel(*level)));
                }
                check_magnitude("level", &[*level]).map_err(err)?;
            }
            Node::Warp { warp, .. } => warp.validate().map_err(err)?,
        }
        for (i, c) in self.children().into_iter().enumerate() {
            c.validate_at(&path.child(i))?;
        }
        Ok(())
    }
}
