//! Correspondence and decomposition (§3.1–3.3, §4.2–4.3): turning two
//! BlobTrees `A`, `B` into equivalent trees `A'`, `B'` that *overlap*
//! (their nodes and leaves match bijectively).

use crate::error::{BlobMorphError, NodePath, Side};
use crate::node::{MAX_MAGNITUDE, NaryOp, Node, Primitive};
use crate::warp::Warp;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// The most node pairs a decomposition may create. The all-children
/// heuristic makes `n_A × n_B` pairs per matched node pair (and splitting
/// multiplies subtrees), so wide or deep trees could otherwise need
/// unbounded time and memory; [`decompose`] refuses them with
/// [`BlobMorphError::TooManyPairs`] before building them.
pub const MAX_PAIRS: usize = 1 << 18;

/// The most skeleton vertex pairs a decomposition may create: the sum over
/// its leaf pairs of `n_A · n_B`, the candidate vertices of their Minkowski
/// interpolations (§3.4.1), whose generic topology costs up to about 0.06 s
/// for two 32-vertex polyhedra. [`decompose`] refuses more with
/// [`BlobMorphError::TooManyPairs`].
pub const MAX_VERTEX_PAIRS: usize = 1 << 19;

/// An animator's link between a node of the source and a node of the target.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Link {
    /// Source node path.
    pub a: NodePath,
    /// Target node path.
    pub b: NodePath,
}

/// Automatic pairing of the children of two matched commutative nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Heuristic {
    /// Match every child of `N_A` with every child of `N_B` (`n_A × n_B` pairs;
    /// often featureless, §4.3).
    AllChildren,
    /// Link every child to the child of the other node whose skeleton centre
    /// is nearest (both directions, so every child has a partner).
    #[default]
    NearestCentre,
    /// Hierarchical matching (§3.1): as `NearestCentre`, but positions are
    /// taken relative to the parents, which are matched already — each
    /// child's centre minus the mean of its siblings' centres — so parts
    /// that moved with their parent still find their counterparts, at every
    /// level down the trees.
    Hierarchical,
}

/// The overlapping pair of trees: a tree of matched node pairs.
#[derive(Debug, Clone, PartialEq)]
pub enum Pair {
    /// Two matched primitives (one may be a phantom).
    Leaf {
        /// Source primitive.
        a: Box<Primitive>,
        /// Target primitive.
        b: Box<Primitive>,
        /// Original paths of the matched nodes (`None` for a phantom).
        origin: Origin,
    },
    /// Two matched commutative nodes with bijectively matched children.
    Nary {
        /// Source operator.
        a: NaryOp,
        /// Target operator.
        b: NaryOp,
        /// Matched children.
        children: Vec<Pair>,
        /// Original paths.
        origin: Origin,
    },
    /// Two matched differences.
    Difference {
        /// Source reference level.
        a: f32,
        /// Target reference level.
        b: f32,
        /// Left children.
        left: Box<Pair>,
        /// Right children.
        right: Box<Pair>,
        /// Original paths.
        origin: Origin,
    },
    /// Two matched warps of one kind.
    Warp {
        /// Source warp.
        a: Warp,
        /// Target warp.
        b: Warp,
        /// Matched children.
        child: Box<Pair>,
        /// Original paths.
        origin: Origin,
    },
}

/// The original source and target nodes a pair came from (`None` where the
/// node was inserted or is a phantom).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Origin {
    /// Source node path.
    pub a: Option<NodePath>,
    /// Target node path.
    pub b: Option<NodePath>,
}

impl Pair {
    /// One side of the pair tree: `A'` for [`Side::Source`], `B'` for
    /// [`Side::Target`]. Both are equivalent to the inputs (same field).
    pub fn side(&self, side: Side) -> Node {
        fn pick<T: Clone>(side: Side, a: &T, b: &T) -> T {
            if side == Side::Source { a.clone() } else { b.clone() }
        }
        match self {
            Pair::Leaf { a, b, .. } => Node::Primitive(*pick(side, a, b)),
            Pair::Nary { a, b, children, .. } => {
                Node::Nary { op: pick(side, a, b), children: children.iter().map(|c| c.side(side)).collect() }
            }
            Pair::Difference { a, b, left, right, .. } => Node::Difference {
                left: Box::new(left.side(side)),
                right: Box::new(right.side(side)),
                level: pick(side, a, b),
            },
            Pair::Warp { a, b, child, .. } => {
                Node::Warp { warp: pick(side, a, b), child: Box::new(child.side(side)) }
            }
        }
    }

    /// The original paths of this pair.
    pub fn origin(&self) -> &Origin {
        match self {
            Pair::Leaf { origin, .. }
            | Pair::Nary { origin, .. }
            | Pair::Difference { origin, .. }
            | Pair::Warp { origin, .. } => origin,
        }
    }

    /// Number of matched leaf pairs.
    pub fn leaf_count(&self) -> usize {
        match self {
            Pair::Leaf { .. } => 1,
            Pair::Nary { children, .. } => children.iter().map(Pair::leaf_count).sum(),
            Pair::Difference { left, right, .. } => left.leaf_count() + right.leaf_count(),
            Pair::Warp { child, .. } => child.leaf_count(),
        }
    }
}

/// The animator's parameters of one phantom (§3.3, Fig. 17): the
/// null-intensity partner a node without correspondence gets on the other
/// side. By default the phantom has the node's skeletons, radii and
/// stiffnesses; these fields move and reshape it (the paper's `S_B`, `R_B`,
/// `k_B`), so the node grows from (or shrinks into) another place, skeleton
/// and size. Fig. 17's phantom, "a sphere that the animator located at the
/// center of the cube", is `position` at the centre with `scale: 0`. Its
/// intensity stays 0 — that is what makes it a phantom and keeps the end
/// shape the input.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Phantom {
    /// The source node whose phantom (in the target) this is; give
    /// exactly one of `source` and `target`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<NodePath>,
    /// The target node whose phantom (in the source) this is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target: Option<NodePath>,
    /// Where the phantom is centred (world units): its skeletons are moved
    /// by `position − centre of the node` in the node's space (exactly a
    /// world translation unless the node holds warps). Default: in place.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f32; 3]>,
    /// The radius of influence `R` of its primitives (default: the node's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// The stiffness `k` of its primitives (default: the node's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f32>,
    /// The factor (≥ 0, unitless; default 1) its skeletons are scaled by
    /// about the phantom's centre (`position`, or the node's centre): 0
    /// collapses every skeleton to a point there, so the node's primitives
    /// grow out of that point (a Minkowski interpolation from a point). The
    /// centre is taken through the inverse of the warps inside the node, so
    /// the scaling is exact in world space unless the node holds warps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<f32>,
}

impl Phantom {
    /// The side and path of the node this phantom partners.
    fn node(&self) -> Result<(Side, &NodePath), BlobMorphError> {
        match (&self.source, &self.target) {
            (Some(p), None) => Ok((Side::Source, p)),
            (None, Some(p)) => Ok((Side::Target, p)),
            (a, b) => Err(BlobMorphError::Phantom {
                side: if a.is_some() { Side::Source } else { Side::Target },
                path: a.clone().or_else(|| b.clone()).unwrap_or_default(),
                problem: "give exactly one of `source` and `target`",
            }),
        }
    }

    /// Checks the parameters' ranges.
    fn check(&self) -> Result<(Side, &NodePath), BlobMorphError> {
        let (side, path) = self.node()?;
        let fail = |problem| Err(BlobMorphError::Phantom { side, path: path.clone(), problem });
        if self.position.is_some_and(|p| p.iter().any(|v| !v.is_finite() || v.abs() > MAX_MAGNITUDE)) {
            return fail("`position` must be finite with magnitudes ≤ 1e6");
        }
        if self.radius.is_some_and(|r| !(1.0 / MAX_MAGNITUDE..=MAX_MAGNITUDE).contains(&r)) {
            return fail("`radius` must be in [1e-6, 1e6]");
        }
        if self.stiffness.is_some_and(|k| !(0.0..=MAX_MAGNITUDE).contains(&k)) {
            return fail("`stiffness` must be in [0, 1e6]");
        }
        if self.scale.is_some_and(|k| !(0.0..=MAX_MAGNITUDE).contains(&k)) {
            return fail("`scale` must be in [0, 1e6]");
        }
        Ok((side, path))
    }
}

/// How to match two trees.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Correspondence {
    /// Animator links (any level, one-to-many allowed).
    pub links: Vec<Link>,
    /// Pairing for matched commutative nodes without links.
    pub heuristic: Heuristic,
    /// The animator's phantom parameters.
    pub phantoms: Vec<Phantom>,
}

/// A phantom's reshaping, applied to each of its primitives.
#[derive(Debug, Clone, Copy)]
struct Reshape {
    /// Translation of the skeletons.
    shift: Vec3,
    /// Radius of influence, if set.
    radius: Option<f32>,
    /// Stiffness, if set.
    stiffness: Option<f32>,
    /// Scale factor of the skeletons, if set, about `pivot`.
    scale: Option<f32>,
    /// The phantom's centre before the shift, in the space of the node
    /// being paired (mapped through the warps met on the way down).
    pivot: Vec3,
}

struct Ctx<'a> {
    links: &'a [Link],
    used: Vec<bool>,
    /// Links by their pair of paths (for [`consume`]).
    by_pair: HashMap<(&'a NodePath, &'a NodePath), Vec<usize>>,
    /// Links by their source path (for the links between two nodes' children).
    by_source: HashMap<&'a NodePath, Vec<usize>>,
    heuristic: Heuristic,
    /// Threshold of each side (level of inserted difference nodes).
    thresholds: (f32, f32),
    /// Node pairs created so far (at most [`MAX_PAIRS`]).
    pairs: usize,
    /// Skeleton vertex pairs of the leaf pairs so far (at most [`MAX_VERTEX_PAIRS`]).
    vertex_pairs: usize,
    /// The animator's phantoms by the node they partner.
    phantoms: HashMap<(Side, NodePath), &'a Phantom>,
    /// The phantom nodes met so far.
    phantoms_used: HashSet<(Side, NodePath)>,
}

impl Ctx<'_> {
    /// Whether `n` more node pairs fit in [`MAX_PAIRS`] (under the matched
    /// nodes `pa ↔ pb`, named in the error).
    fn room(&self, n: usize, pa: Option<&NodePath>, pb: Option<&NodePath>) -> Result<(), BlobMorphError> {
        if self.pairs.checked_add(n).is_some_and(|total| total <= MAX_PAIRS) {
            Ok(())
        } else {
            Err(BlobMorphError::TooManyPairs {
                what: "node pairs",
                a: pa.cloned().unwrap_or_default(),
                b: pb.cloned().unwrap_or_default(),
                limit: MAX_PAIRS,
            })
        }
    }

    /// Accounts for the leaf pair `x ↔ y` (with `pa ↔ pb`, named in the error).
    fn reserve_leaf(
        &mut self,
        x: &Primitive,
        y: &Primitive,
        pa: Option<&NodePath>,
        pb: Option<&NodePath>,
    ) -> Result<(), BlobMorphError> {
        let n = x.skeleton.vertex_count().saturating_mul(y.skeleton.vertex_count());
        match self.vertex_pairs.checked_add(n) {
            Some(total) if total <= MAX_VERTEX_PAIRS => {
                self.vertex_pairs = total;
                Ok(())
            }
            _ => Err(BlobMorphError::TooManyPairs {
                what: "skeleton vertex pairs",
                a: pa.cloned().unwrap_or_default(),
                b: pb.cloned().unwrap_or_default(),
                limit: MAX_VERTEX_PAIRS,
            }),
        }
    }

    /// Accounts for one more node pair.
    fn reserve(&mut self, pa: Option<&NodePath>, pb: Option<&NodePath>) -> Result<(), BlobMorphError> {
        self.room(1, pa, pb)?;
        self.pairs += 1;
        Ok(())
    }
}

/// Matches and decomposes `a` (threshold `ta`) and `b` (threshold `tb`) into
/// a pair tree whose two sides overlap.
///
/// Starting from the roots, each matched pair of nodes gets links between
/// its children — the animator's [`Link`]s when given for that pair,
/// otherwise a [`Heuristic`] — and the children are decomposed so that the
/// links become a bijection:
///
/// - **commutative ↔ commutative** (`∪ ∩ + ` super-blend): a child with
///   `m` links is split into `m` copies: replicated under union and
///   intersection, `α`-weighted copies with `α = 1/m` (a partition of unity)
///   under a blend, and `α^{1/n}`-weighted under a super-elliptic blend of
///   order `n` (`Σ (α^{1/n} f)^n = f^n`). Unlinked children get a *phantom*
///   partner (§3.3: null intensity, skeleton, `R`, `k` copied) — except
///   under an intersection, where a null field is not neutral, so they are
///   linked to the nearest child instead.
/// - **primitive ↔ commutative**: the primitive becomes the only child of a
///   node of the partner's operator (a one-child node equals its child), then
///   as above (the sphere of "sphere → propeller" splits into two).
/// - **difference ↔ difference**: left ↔ left, right ↔ right.
/// - **difference ↔ other**: a difference is inserted above the other node,
///   with a phantom of the partner's right child (Fig. 14).
/// - **warp ↔ warp** of one kind: child ↔ child; of different kinds, each side
///   gets the identity of the other's kind (Fig. 16); **warp ↔ other**: the
///   identity warp of the same kind is inserted above the other (Fig. 15).
///
/// Inputs are user trees; an instantiated [`Node::Mix`] (a frame of another
/// morph) is matched as its dominant operator, so for such inputs `A'` is
/// only approximately `A`.
///
/// Links are only followed under matched parents (§4: "nodes at a given
/// level should not be matched unless their ancestor nodes have also been
/// paired"); a link that is never reachable is an error.
///
/// Near-linear in the sizes of the trees and of the result (nearest
/// centres through a k-d tree, links and degrees through hash maps).
///
/// # Errors
/// [`BlobMorphError::NoSuchNode`] for links to missing nodes,
/// [`BlobMorphError::LinkBreaksHierarchy`] for links whose parents are never matched,
/// [`BlobMorphError::TooManyPairs`] when the result would have more than
/// [`MAX_PAIRS`] node pairs.
pub fn decompose(
    a: &Node,
    ta: f32,
    b: &Node,
    tb: f32,
    corr: &Correspondence,
) -> Result<Pair, BlobMorphError> {
    for l in &corr.links {
        if a.get(&l.a).is_none() {
            return Err(BlobMorphError::NoSuchNode { side: Side::Source, path: l.a.clone() });
        }
        if b.get(&l.b).is_none() {
            return Err(BlobMorphError::NoSuchNode { side: Side::Target, path: l.b.clone() });
        }
    }
    let mut by_pair: HashMap<_, Vec<usize>> = HashMap::new();
    let mut by_source: HashMap<_, Vec<usize>> = HashMap::new();
    for (i, l) in corr.links.iter().enumerate() {
        by_pair.entry((&l.a, &l.b)).or_default().push(i);
        by_source.entry(&l.a).or_default().push(i);
    }
    let mut phantoms = HashMap::new();
    for ph in &corr.phantoms {
        let (side, path) = ph.check()?;
        let tree = if side == Side::Source { a } else { b };
        if tree.get(path).is_none() {
            return Err(BlobMorphError::NoSuchNode { side, path: path.clone() });
        }
        phantoms.insert((side, path.clone()), ph);
    }
    let mut ctx = Ctx {
        links: &corr.links,
        used: vec![false; corr.links.len()],
        by_pair,
        by_source,
        heuristic: corr.heuristic,
        thresholds: (ta, tb),
        pairs: 0,
        vertex_pairs: 0,
        phantoms,
        phantoms_used: HashSet::new(),
    };
    let root = NodePath::root();
    consume(&mut ctx, &root, &root);
    let pair = pair(a, Some(&root), b, Some(&root), &mut ctx)?;
    if let Some(i) = ctx.used.iter().position(|u| !u) {
        let l = &corr.links[i];
        return Err(BlobMorphError::LinkBreaksHierarchy { a: l.a.clone(), b: l.b.clone() });
    }
    let unused = corr
        .phantoms
        .iter()
        .filter_map(|ph| ph.node().ok())
        .find(|&(side, path)| !ctx.phantoms_used.contains(&(side, path.clone())));
    if let Some((side, path)) = unused {
        return Err(BlobMorphError::Phantom {
            side,
            path: path.clone(),
            problem: "the node is matched, it has no phantom",
        });
    }
    Ok(pair)
}

fn consume(ctx: &mut Ctx<'_>, pa: &NodePath, pb: &NodePath) {
    if let Some(ids) = ctx.by_pair.get(&(pa, pb)) {
        for &i in ids {
            ctx.used[i] = true;
        }
    }
}

fn child(p: Option<&NodePath>, i: usize) -> Option<NodePath> {
    p.map(|p| p.child(i))
}

fn pair(
    a: &Node,
    pa: Option<&NodePath>,
    b: &Node,
    pb: Option<&NodePath>,
    ctx: &mut Ctx<'_>,
) -> Result<Pair, BlobMorphError> {
    ctx.reserve(pa, pb)?;
    let origin = Origin { a: pa.cloned(), b: pb.cloned() };
    let structural = |ctx: &mut Ctx<'_>, ca: &Option<NodePath>, cb: &Option<NodePath>| {
        if let (Some(x), Some(y)) = (ca, cb) {
            consume(ctx, x, y);
        }
    };
    Ok(match (a, b) {
        (Node::Warp { warp: wa, child: ca }, Node::Warp { warp: wb, child: cb }) => {
            let (qa, qb) = (child(pa, 0), child(pb, 0));
            structural(ctx, &qa, &qb);
            let inner = pair(ca, qa.as_ref(), cb, qb.as_ref(), ctx)?;
            if wa.kind() == wb.kind() {
                Pair::Warp { a: *wa, b: *wb, child: Box::new(inner), origin }
            } else {
                // Fig. 16: (ω_A → Id) ∘ (Id → ω_B).
                let lower = Pair::Warp {
                    a: wb.identity_like(),
                    b: *wb,
                    child: Box::new(inner),
                    origin: origin.clone(),
                };
                Pair::Warp { a: *wa, b: wa.identity_like(), child: Box::new(lower), origin }
            }
        }
        (Node::Warp { warp: wa, child: ca }, _) => {
            let inner = pair(ca, child(pa, 0).as_ref(), b, pb, ctx)?;
            Pair::Warp { a: *wa, b: wa.identity_like(), child: Box::new(inner), origin }
        }
        (_, Node::Warp { warp: wb, child: cb }) => {
            let inner = pair(a, pa, cb, child(pb, 0).as_ref(), ctx)?;
            Pair::Warp { a: wb.identity_like(), b: *wb, child: Box::new(inner), origin }
        }
        (
            Node::Difference { left: la, right: ra, level: ca },
            Node::Difference { left: lb, right: rb, level: cb },
        ) => {
            let (la_p, lb_p, ra_p, rb_p) = (child(pa, 0), child(pb, 0), child(pa, 1), child(pb, 1));
            structural(ctx, &la_p, &lb_p);
            structural(ctx, &ra_p, &rb_p);
            let left = pair(la, la_p.as_ref(), lb, lb_p.as_ref(), ctx)?;
            let right = pair(ra, ra_p.as_ref(), rb, rb_p.as_ref(), ctx)?;
            Pair::Difference { a: *ca, b: *cb, left: Box::new(left), right: Box::new(right), origin }
        }
        (Node::Difference { left, right, level }, _) => {
            // Fig. 14: B becomes difference(B, phantom of A's right child).
            let l = pair(left, child(pa, 0).as_ref(), b, pb, ctx)?;
            let r = with_phantom(right, child(pa, 1), Side::Source, None, ctx)?;
            Pair::Difference { a: *level, b: ctx.thresholds.1, left: Box::new(l), right: Box::new(r), origin }
        }
        (_, Node::Difference { left, right, level }) => {
            let l = pair(a, pa, left, child(pb, 0).as_ref(), ctx)?;
            let r = with_phantom(right, child(pb, 1), Side::Target, None, ctx)?;
            Pair::Difference { a: ctx.thresholds.0, b: *level, left: Box::new(l), right: Box::new(r), origin }
        }
        (Node::Primitive(x), Node::Primitive(y)) => {
            ctx.reserve_leaf(x, y, pa, pb)?;
            Pair::Leaf { a: Box::new(x.clone()), b: Box::new(y.clone()), origin }
        }
        _ => {
            let (op_a, kids_a) = commutative(a, pa);
            let (op_b, kids_b) = commutative(b, pb);
            let (op_a, op_b, children) = match_children(op_a, &kids_a, op_b, &kids_b, pa, pb, ctx)?;
            Pair::Nary { a: op_a, b: op_b, children, origin }
        }
    })
}

type Kid<'a> = (&'a Node, Option<NodePath>);

/// A commutative node's operator and children with their paths; a primitive
/// is a one-child node of the partner's kind (its child keeps its own path).
fn commutative<'a>(n: &'a Node, p: Option<&NodePath>) -> (NaryOp, Vec<Kid<'a>>) {
    match n {
        Node::Nary { op, children } => {
            (*op, children.iter().enumerate().map(|(i, c)| (c, child(p, i))).collect())
        }
        Node::Mix { from, children, s, to } => {
            // An instantiated mix with s ∈ {0, 1} is a plain node; otherwise
            // its children are matched and the dominant operator used.
            let op = if *s < 0.5 { *from } else { *to };
            (op, children.iter().enumerate().map(|(i, c)| (c, child(p, i))).collect())
        }
        _ => (NaryOp::Union, vec![(n, p.cloned())]),
    }
}

fn match_children(
    op_a: NaryOp,
    kids_a: &[Kid<'_>],
    op_b: NaryOp,
    kids_b: &[Kid<'_>],
    pa: Option<&NodePath>,
    pb: Option<&NodePath>,
    ctx: &mut Ctx<'_>,
) -> Result<(NaryOp, NaryOp, Vec<Pair>), BlobMorphError> {
    // A wrapped primitive takes the partner's operator (a one-child node of
    // any commutative kind equals its child).
    let (op_a, op_b) = match (
        kids_a.len() == 1 && kids_a[0].1.as_ref() == pa,
        kids_b.len() == 1 && kids_b[0].1.as_ref() == pb,
    ) {
        (true, false) => (op_b, op_b),
        (false, true) => (op_a, op_a),
        _ => (op_a, op_b),
    };
    let mut centres_a: Vec<Vec3> = kids_a.iter().map(|(n, _)| n.centre()).collect();
    let mut centres_b: Vec<Vec3> = kids_b.iter().map(|(n, _)| n.centre()).collect();
    if ctx.heuristic == Heuristic::Hierarchical {
        for centres in [&mut centres_a, &mut centres_b] {
            let mean = centres.iter().copied().sum::<Vec3>() / centres.len().max(1) as f32;
            centres.iter_mut().for_each(|c| *c -= mean);
        }
    }
    // User links at this level, in the order they were given.
    let index_b: HashMap<&NodePath, usize> =
        kids_b.iter().enumerate().filter_map(|(j, (_, p))| Some((p.as_ref()?, j))).collect();
    let mut linked: Vec<(usize, usize, usize)> = Vec::new();
    for (i, (_, p)) in kids_a.iter().enumerate() {
        let Some(ids) = p.as_ref().and_then(|p| ctx.by_source.get(p)) else { continue };
        for &li in ids {
            if let Some(&j) = index_b.get(&ctx.links[li].b) {
                linked.push((li, i, j));
            }
        }
    }
    linked.sort_unstable();
    let mut edges: Vec<(Option<usize>, Option<usize>)> = Vec::new();
    let mut seen: HashSet<(usize, usize)> = HashSet::new();
    for &(li, i, j) in &linked {
        ctx.used[li] = true;
        if seen.insert((i, j)) {
            edges.push((Some(i), Some(j)));
        }
    }
    if edges.is_empty() {
        match ctx.heuristic {
            Heuristic::AllChildren => {
                // Refuse before enumerating: n_A × n_B pairs.
                let n = kids_a.len().saturating_mul(kids_b.len());
                ctx.room(n, pa, pb)?;
                for i in 0..kids_a.len() {
                    for j in 0..kids_b.len() {
                        edges.push((Some(i), Some(j)));
                    }
                }
            }
            Heuristic::NearestCentre | Heuristic::Hierarchical => {
                let (near_a, near_b) = (KdTree::new(&centres_a), KdTree::new(&centres_b));
                for (i, c) in centres_a.iter().enumerate() {
                    if let Some(j) = near_b.nearest(*c) {
                        seen.insert((i, j));
                        edges.push((Some(i), Some(j)));
                    }
                }
                for (j, c) in centres_b.iter().enumerate() {
                    if let Some(i) = near_a.nearest(*c)
                        && seen.insert((i, j))
                    {
                        edges.push((Some(i), Some(j)));
                    }
                }
            }
        }
    } else {
        // Unlinked children: phantoms, or the nearest child under an intersection.
        let mut has_a = vec![false; kids_a.len()];
        let mut has_b = vec![false; kids_b.len()];
        for &(i, j) in &seen {
            (has_a[i], has_b[j]) = (true, true);
        }
        let near_b = (op_b == NaryOp::Intersection).then(|| KdTree::new(&centres_b));
        for (i, c) in centres_a.iter().enumerate() {
            if !has_a[i] {
                edges.push((Some(i), near_b.as_ref().and_then(|t| t.nearest(*c))));
            }
        }
        let near_a = (op_a == NaryOp::Intersection).then(|| KdTree::new(&centres_a));
        for (j, c) in centres_b.iter().enumerate() {
            if !has_b[j] {
                edges.push((near_a.as_ref().and_then(|t| t.nearest(*c)), Some(j)));
            }
        }
    }
    let mut deg_a = vec![0usize; kids_a.len()];
    let mut deg_b = vec![0usize; kids_b.len()];
    for &(i, j) in &edges {
        if let Some(i) = i {
            deg_a[i] += 1;
        }
        if let Some(j) = j {
            deg_b[j] += 1;
        }
    }
    let mut out = Vec::with_capacity(edges.len());
    for &(i, j) in &edges {
        let pair = match (i, j) {
            (Some(i), Some(j)) => {
                let x = split(kids_a[i].0, op_a, deg_a[i]);
                let y = split(kids_b[j].0, op_b, deg_b[j]);
                if let (Some(p), Some(q)) = (&kids_a[i].1, &kids_b[j].1) {
                    consume(ctx, p, q);
                }
                pair(&x, kids_a[i].1.as_ref(), &y, kids_b[j].1.as_ref(), ctx)?
            }
            (Some(i), None) => with_phantom(
                &split(kids_a[i].0, op_a, deg_a[i]),
                kids_a[i].1.clone(),
                Side::Source,
                None,
                ctx,
            )?,
            (None, Some(j)) => with_phantom(
                &split(kids_b[j].0, op_b, deg_b[j]),
                kids_b[j].1.clone(),
                Side::Target,
                None,
                ctx,
            )?,
            (None, None) => continue,
        };
        out.push(pair);
    }
    Ok((op_a, op_b, out))
}

/// A static k-d tree over skeleton centres answering "which is nearest to
/// `q`" exactly as a linear scan would: the least Euclidean length, ties
/// to the lowest index.
struct KdTree {
    /// Points with their indices, each range's median at its middle, split
    /// along x, y, z by depth.
    points: Vec<(Vec3, usize)>,
}

impl KdTree {
    fn new(points: &[Vec3]) -> Self {
        fn arrange(pts: &mut [(Vec3, usize)], axis: usize) {
            if pts.len() <= 1 {
                return;
            }
            let mid = pts.len() / 2;
            pts.select_nth_unstable_by(mid, |x, y| x.0[axis].total_cmp(&y.0[axis]));
            let (left, right) = pts.split_at_mut(mid);
            arrange(left, (axis + 1) % 3);
            arrange(&mut right[1..], (axis + 1) % 3);
        }
        let mut points: Vec<(Vec3, usize)> = points.iter().copied().zip(0..).collect();
        arrange(&mut points, 0);
        Self { points }
    }

    fn nearest(&self, q: Vec3) -> Option<usize> {
        fn search(pts: &[(Vec3, usize)], axis: usize, q: Vec3, best: &mut Option<(f32, usize)>) {
            if pts.is_empty() {
                return;
            }
            let mid = pts.len() / 2;
            let (p, i) = pts[mid];
            let d = (p - q).length();
            let better = match *best {
                None => true,
                Some((bd, bi)) => d.total_cmp(&bd).then(i.cmp(&bi)).is_lt(),
            };
            if better {
                *best = Some((d, i));
            }
            let diff = q[axis] - p[axis];
            let (near, far) =
                if diff < 0.0 { (&pts[..mid], &pts[mid + 1..]) } else { (&pts[mid + 1..], &pts[..mid]) };
            search(near, (axis + 1) % 3, q, best);
            // Points beyond the splitting plane are at least |diff| away.
            if best.is_none_or(|(bd, _)| diff.abs() <= bd || bd.is_nan()) {
                search(far, (axis + 1) % 3, q, best);
            }
        }
        let mut best = None;
        search(&self.points, 0, q, &mut best);
        best.map(|(_, i)| i)
    }
}

/// One of `m` copies of `node` under `op` whose copies add up to `node`
/// (§4.2): replication under `∪`/`∩`, `α = 1/m` under a blend, `α^{1/n}`
/// under a super-elliptic blend of order `n`.
pub fn split(node: &Node, op: NaryOp, m: usize) -> Node {
    if m <= 1 {
        return node.clone();
    }
    let alpha = 1.0 / m as f32;
    match op {
        NaryOp::Union | NaryOp::Intersection => node.clone(),
        NaryOp::Blend => node.scaled(alpha),
        NaryOp::SuperBlend(n) if n.is_infinite() => node.clone(),
        NaryOp::SuperBlend(n) => node.scaled(alpha.powf(1.0 / n)),
    }
}

/// Pairs `node` (on `side`) with its own phantom on the other side, node
/// by node; the animator's [`Phantom`] for a node reshapes the phantom's
/// primitives below it (`reshape`: the one inherited from above).
fn with_phantom(
    node: &Node,
    path: Option<NodePath>,
    side: Side,
    reshape: Option<Reshape>,
    ctx: &mut Ctx<'_>,
) -> Result<Pair, BlobMorphError> {
    let (pa, pb) = if side == Side::Source { (path.as_ref(), None) } else { (None, path.as_ref()) };
    ctx.reserve(pa, pb)?;
    if let Node::Primitive(p) = node {
        ctx.reserve_leaf(p, p, pa, pb)?;
    }
    let mut reshape = reshape;
    if let Some(p) = &path
        && let Some(&ph) = ctx.phantoms.get(&(side, p.clone()))
    {
        ctx.phantoms_used.insert((side, p.clone()));
        let centre = node.centre();
        reshape = Some(Reshape {
            shift: ph.position.map_or(Vec3::ZERO, |q| Vec3::from_array(q) - centre),
            radius: ph.radius,
            stiffness: ph.stiffness,
            scale: ph.scale,
            pivot: centre,
        });
    }
    let mut phantom = node.phantom();
    if let (Node::Primitive(p), Some(r)) = (&mut phantom, reshape) {
        p.frame = glam::Affine3A::from_translation(r.shift) * p.frame;
        p.kernel.radius = r.radius.unwrap_or(p.kernel.radius);
        p.kernel.stiffness = r.stiffness.unwrap_or(p.kernel.stiffness);
        if let Some(factor) = r.scale {
            // An affine frame keeps ratios: scaling about the pivot's
            // local image is the scaling about the pivot.
            let pivot = p.frame.inverse().transform_point3(r.pivot + r.shift);
            p.skeleton = p.skeleton.scaled_about(pivot, factor);
        }
    }
    if let (Node::Warp { warp, .. }, Some(r)) = (node, reshape.as_mut()) {
        r.pivot = warp.inverse(r.pivot);
    }
    let origin = match side {
        Side::Source => Origin { a: path.clone(), b: None },
        Side::Target => Origin { a: None, b: path.clone() },
    };
    let (x, y) = if side == Side::Source { (node, &phantom) } else { (&phantom, node) };
    let mut kids = |i: usize| with_phantom(node.children()[i], child(path.as_ref(), i), side, reshape, ctx);
    Ok(match (x, y) {
        (Node::Primitive(a), Node::Primitive(b)) => {
            Pair::Leaf { a: Box::new(a.clone()), b: Box::new(b.clone()), origin }
        }
        (Node::Nary { op, children }, _) | (Node::Mix { from: op, children, .. }, _) => Pair::Nary {
            a: *op,
            b: *op,
            children: (0..children.len()).map(kids).collect::<Result<_, _>>()?,
            origin,
        },
        (Node::Difference { level: la, .. }, Node::Difference { level: lb, .. }) => {
            Pair::Difference { a: *la, b: *lb, left: Box::new(kids(0)?), right: Box::new(kids(1)?), origin }
        }
        (Node::Warp { warp, .. }, _) => Pair::Warp { a: *warp, b: *warp, child: Box::new(kids(0)?), origin },
        _ => unreachable!("a phantom has the structure of its node"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil;
    use crate::{BlobTree, Kernel, Skeleton};
    use glam::Vec3;
    use proptest::prelude::*;

    fn same_structure(x: &Node, y: &Node) -> bool {
        let kind = |n: &Node| match n {
            Node::Primitive(_) => "leaf",
            Node::Nary { .. } | Node::Mix { .. } => "nary",
            Node::Difference { .. } => "difference",
            Node::Warp { warp, .. } => warp.kind(),
        };
        kind(x) == kind(y)
            && x.children().len() == y.children().len()
            && x.children().iter().zip(y.children()).all(|(a, b)| same_structure(a, b))
    }

    fn check_equivalent(orig: &Node, dec: &Node) -> Result<(), TestCaseError> {
        let t0 = BlobTree::new(orig.clone(), 0.5).unwrap();
        let t1 = BlobTree::new(dec.clone(), 0.5).map_err(|e| TestCaseError::fail(e.to_string()))?;
        for p in testutil::points() {
            let (u, v) = (t0.potential(p), t1.potential(p));
            prop_assert!((u - v).abs() <= 1e-5 * (1.0 + u.abs()), "at {}: {} vs {}", p, u, v);
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

        /// A' ≡ A and B' ≡ B (same field everywhere) and A', B' overlap, for
        /// every heuristic.
        #[test]
        fn decomposition_is_equivalent_and_overlapping(a in testutil::tree(), b in testutil::tree(), h in 0usize..3) {
            let corr = Correspondence {
                links: vec![],
                heuristic: [Heuristic::AllChildren, Heuristic::NearestCentre, Heuristic::Hierarchical][h],
                phantoms: vec![],
            };
            let pair = decompose(&a, 0.5, &b, 0.5, &corr).unwrap();
            let (a2, b2) = (pair.side(Side::Source), pair.side(Side::Target));
            prop_assert!(same_structure(&a2, &b2));
            check_equivalent(&a, &a2)?;
            check_equivalent(&b, &b2)?;
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

        /// With random user links between the roots' children (plus phantoms
        /// for the unlinked ones) the decomposition stays exact.
        #[test]
        fn linked_decomposition_is_equivalent(
            a in testutil::tree(),
            b in testutil::tree(),
            links in prop::collection::vec((0usize..3, 0usize..3), 1..4),
        ) {
            let (Node::Nary { children: ca, .. }, Node::Nary { children: cb, .. }) = (&a, &b) else {
                return Ok(());
            };
            let links: Vec<Link> = links
                .into_iter()
                .filter(|(i, j)| *i < ca.len() && *j < cb.len())
                .map(|(i, j)| Link { a: NodePath(vec![i]), b: NodePath(vec![j]) })
                .collect();
            let corr = Correspondence { links, heuristic: Heuristic::NearestCentre, phantoms: vec![] };
            let pair = decompose(&a, 0.5, &b, 0.5, &corr).unwrap();
            let (a2, b2) = (pair.side(Side::Source), pair.side(Side::Target));
            prop_assert!(same_structure(&a2, &b2));
            check_equivalent(&a, &a2)?;
            check_equivalent(&b, &b2)?;
        }
    }

    fn ball(c: Vec3) -> Node {
        Node::Primitive(crate::Primitive::new(Skeleton::Point(c), Kernel::new(1.0, 0.6, 1.0)))
    }

    #[test]
    fn user_links_split_and_phantom() {
        let a = Node::blend(vec![ball(Vec3::ZERO), ball(Vec3::X)]);
        let b = Node::blend(vec![ball(Vec3::Y), ball(Vec3::Z), ball(-Vec3::X)]);
        // Child 0 of A goes to children 0 and 1 of B; child 2 of B is unlinked.
        let corr = Correspondence {
            links: vec![
                Link { a: NodePath(vec![0]), b: NodePath(vec![0]) },
                Link { a: NodePath(vec![0]), b: NodePath(vec![1]) },
            ],
            heuristic: Heuristic::NearestCentre,
            phantoms: vec![],
        };
        let pair = decompose(&a, 0.5, &b, 0.5, &corr).unwrap();
        // 2 links + A's child 1 with a phantom + B's child 2 with a phantom.
        assert_eq!(pair.leaf_count(), 4);
        let a2 = pair.side(Side::Source);
        let Node::Nary { children, .. } = &a2 else { panic!() };
        let intensities: Vec<f32> = children
            .iter()
            .map(|c| if let Node::Primitive(p) = c { p.kernel.intensity } else { -1.0 })
            .collect();
        assert_eq!(intensities, vec![0.5, 0.5, 1.0, 0.0]);
    }

    /// Hierarchical matching pairs the parts of two groups that moved
    /// together by their places in the groups, where nearest centres in
    /// world space pair both source groups with one target group.
    #[test]
    fn hierarchical_matching_follows_the_parents() {
        let group = |x: f32| Node::blend(vec![ball(Vec3::new(x, 0.3, 0.0)), ball(Vec3::new(x, -0.3, 0.0))]);
        let a = Node::blend(vec![group(-1.0), group(1.0)]);
        let b = Node::blend(vec![group(2.0), group(4.0)]);
        let corr = |heuristic| Correspondence { links: vec![], heuristic, phantoms: vec![] };
        let nearest = decompose(&a, 0.5, &b, 0.5, &corr(Heuristic::NearestCentre)).unwrap();
        assert!(nearest.leaf_count() > 4, "nearest centres split a group");
        let hierarchical = decompose(&a, 0.5, &b, 0.5, &corr(Heuristic::Hierarchical)).unwrap();
        assert_eq!(hierarchical.leaf_count(), 4, "a bijection, group to group and ball to ball");
        let Pair::Nary { children, .. } = &hierarchical else { panic!("{hierarchical:?}") };
        for (k, group) in children.iter().enumerate() {
            assert_eq!(group.origin(), &Origin { a: Some(NodePath(vec![k])), b: Some(NodePath(vec![k])) });
            let Pair::Nary { children: balls, .. } = group else { panic!("{group:?}") };
            for (j, ball) in balls.iter().enumerate() {
                assert_eq!(ball.origin().a, Some(NodePath(vec![k, j])));
                assert_eq!(ball.origin().b, Some(NodePath(vec![k, j])));
            }
        }
        assert_eq!(serde_json::to_string(&Heuristic::Hierarchical).unwrap(), "\"hierarchical\"");
        check_equivalent(&a, &hierarchical.side(Side::Source)).unwrap();
        check_equivalent(&b, &hierarchical.side(Side::Target)).unwrap();
    }

    #[test]
    fn bad_links_are_errors() {
        let a = Node::blend(vec![Node::union(vec![ball(Vec3::ZERO)]), ball(Vec3::X)]);
        let b = Node::blend(vec![ball(Vec3::Y), ball(Vec3::Z)]);
        let corr = |a: Vec<usize>, b: Vec<usize>| Correspondence {
            links: vec![Link { a: NodePath(a), b: NodePath(b) }],
            heuristic: Heuristic::NearestCentre,
            phantoms: vec![],
        };
        assert!(matches!(
            decompose(&a, 0.5, &b, 0.5, &corr(vec![5], vec![0])),
            Err(BlobMorphError::NoSuchNode { side: Side::Source, .. })
        ));
        // A grandchild of A linked with B's root: its parent is never matched with anything above B's root.
        assert!(matches!(
            decompose(&a, 0.5, &b, 0.5, &corr(vec![0, 0], vec![])),
            Err(BlobMorphError::LinkBreaksHierarchy { .. })
        ));
        assert!(decompose(&a, 0.5, &b, 0.5, &corr(vec![0], vec![1])).is_ok());
    }

    /// A blend of `n` balls on a 16 × 16 × … lattice.
    fn wide(n: usize) -> Node {
        Node::blend(
            (0..n)
                .map(|i| ball(Vec3::new((i % 16) as f32, ((i / 16) % 16) as f32, (i / 256) as f32) * 0.3))
                .collect(),
        )
    }

    /// 1500 × 1500 children under the all-children heuristic would be 2.25 M
    /// pairs: refused (before they are enumerated) with the node named.
    #[test]
    fn all_children_on_wide_nodes_is_refused() {
        let a = wide(1500);
        let corr = Correspondence { links: vec![], heuristic: Heuristic::AllChildren, phantoms: vec![] };
        match decompose(&a, 0.5, &a, 0.5, &corr) {
            Err(BlobMorphError::TooManyPairs { what, a, b, limit }) => {
                assert_eq!(
                    (what, a, b, limit),
                    ("node pairs", NodePath::root(), NodePath::root(), MAX_PAIRS)
                );
            }
            other => panic!("expected TooManyPairs, got {other:?}"),
        }
        // Within the limit it still pairs every child with every child.
        let small = wide(40);
        assert_eq!(decompose(&small, 0.5, &small, 0.5, &corr).unwrap().leaf_count(), 1600);
    }

    /// 100 × 100 boxes are only 10⁴ node pairs, but 64 vertex pairs each
    /// (the Minkowski candidates): refused by the vertex-pair limit.
    #[test]
    fn many_polyhedron_pairs_are_refused() {
        let boxes = |n: usize| {
            let b = |i: usize| {
                let p = crate::Primitive::new(Skeleton::cuboid(Vec3::splat(0.1)), Kernel::new(1.0, 0.3, 1.0));
                Node::Primitive(p.with_frame(glam::Affine3A::from_translation(Vec3::X * i as f32)))
            };
            Node::blend((0..n).map(b).collect())
        };
        let corr = Correspondence { links: vec![], heuristic: Heuristic::AllChildren, phantoms: vec![] };
        assert!(matches!(
            decompose(&boxes(100), 0.5, &boxes(100), 0.5, &corr),
            Err(BlobMorphError::TooManyPairs { what: "skeleton vertex pairs", limit: MAX_VERTEX_PAIRS, .. })
        ));
        assert_eq!(decompose(&boxes(60), 0.5, &boxes(60), 0.5, &corr).unwrap().leaf_count(), 3600);
        assert!(matches!(
            decompose(&wide(100), 0.5, &wide(100), 0.5, &corr),
            Ok(pair) if pair.leaf_count() == 10_000
        ));
    }

    /// The same wide scene under nearest centres: one pair per child, and
    /// splitting one child 1500 ways stays within the limit.
    #[test]
    fn nearest_centre_on_wide_nodes_pairs_each_child() {
        let a = wide(1500);
        let corr = Correspondence::default();
        let pair = decompose(&a, 0.5, &a, 0.5, &corr).unwrap();
        assert_eq!(pair.leaf_count(), 1500);
        let one = ball(Vec3::ZERO);
        let pair = decompose(&one, 0.5, &a, 0.5, &corr).unwrap();
        assert_eq!(pair.leaf_count(), 1500);
        // 1500 copies of intensity 1/1500 add up to the ball (to rounding).
        let (t0, t1) =
            (BlobTree::new(one, 0.5).unwrap(), BlobTree::new(pair.side(Side::Source), 0.5).unwrap());
        for p in testutil::points() {
            assert!((t0.potential(p) - t1.potential(p)).abs() < 1e-4, "at {p}");
        }
    }

    /// The k-d tree answers exactly as a linear scan (least length, first index).
    #[test]
    fn kd_tree_nearest_matches_a_linear_scan() {
        let mut points: Vec<Vec3> = (0..300)
            .map(|k| {
                let k = k as f32;
                Vec3::new((k * 1.7).sin(), (k * 2.3).cos(), (k * 0.9).sin()).round() * 0.5
            })
            .collect();
        points.extend_from_slice(&points.clone()[..50]);
        let tree = KdTree::new(&points);
        for k in 0..500 {
            let k = k as f32;
            let q = Vec3::new((k * 0.37).sin(), (k * 0.61).cos(), (k * 0.23).sin()) * 0.9;
            let brute = points
                .iter()
                .enumerate()
                .min_by(|x, y| (*x.1 - q).length().total_cmp(&(*y.1 - q).length()))
                .map(|(i, _)| i);
            assert_eq!(tree.nearest(q), brute, "at {q}");
        }
        assert_eq!(KdTree::new(&[]).nearest(Vec3::ZERO), None);
    }
}
