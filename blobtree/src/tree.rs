//! The evaluable BlobTree: validated, with a bounding box per subtree,
//! implementing [`Field3`] as `potential − T` (positive inside).

use crate::error::{BlobError, NodePath, NodeProblem};
use crate::kernel::Kernel;
use crate::node::{MAX_SUPPORT, NaryOp, Node};
use crate::skeleton::Polytope;
use crate::warp::Warp;
use glam::{Affine3A, Mat3, Vec3};
use isomorph_common::{Aabb, Field3};

/// Children per node kept on the stack during evaluation; larger nodes fall
/// back to a heap buffer.
const STACK_CHILDREN: usize = 16;

#[derive(Debug, Clone)]
struct Leaf {
    poly: Polytope,
    kernel: Kernel,
    p: f32,
    to_local: Affine3A,
    /// Transposed linear part of `to_local` (maps local gradients to world).
    grad_map: Mat3,
}

#[derive(Debug, Clone)]
enum Op {
    Leaf(Box<Leaf>),
    Nary(NaryOp),
    Mix(NaryOp, NaryOp, f32),
    Difference(f32),
    /// A warp and the turn of its own frame (`Warp::turn`), computed once.
    Warp(Warp, Option<Mat3>),
}

#[derive(Debug, Clone)]
struct Compiled {
    bounds: Aabb,
    op: Op,
    children: Vec<Compiled>,
}

/// An evaluable BlobTree with threshold `T`; its [`Field3`] value is
/// `potential(p) − T`.
///
/// **Pruning is exact.** Every primitive's field is exactly zero at distance
/// ≥ `R` from its skeleton (the L^p ball of radius `R` lies in the L^∞ box
/// of half-size `R`), every operator maps all-zero children to zero, so a
/// subtree contributes exactly `0.0` outside its box and skipping it never
/// changes a value ([`BlobTree::set_pruning`] switches it off for comparison).
/// Boxes: union/blend of children, intersection of children for `∩`, the
/// left child's for a difference, the image box for a warp.
#[derive(Debug, Clone)]
pub struct BlobTree {
    root: Node,
    threshold: f32,
    compiled: Compiled,
    pruning: bool,
}

/// Two trees are equal when their descriptions (nodes and threshold) are.
impl PartialEq for BlobTree {
    fn eq(&self, other: &Self) -> bool {
        self.root == other.root && self.threshold == other.threshold
    }
}

impl BlobTree {
    /// Validates and compiles `root` with iso threshold `threshold`.
    ///
    /// # Errors
    /// [`BlobError::InvalidThreshold`] unless `0 < threshold ≤ MAX_MAGNITUDE`;
    /// [`BlobError::InvalidNode`] (with the node's path) for any invalid node,
    /// including a support box beyond [`crate::node::MAX_SUPPORT`].
    pub fn new(root: Node, threshold: f32) -> Result<Self, BlobError> {
        if !(threshold > 0.0 && threshold <= crate::node::MAX_MAGNITUDE) {
            return Err(BlobError::InvalidThreshold(threshold));
        }
        root.validate()?;
        let compiled = compile(&root, &NodePath::root())?;
        Ok(Self { root, threshold, compiled, pruning: true })
    }

    /// The tree description.
    pub fn root(&self) -> &Node {
        &self.root
    }

    /// The iso threshold `T`.
    pub fn threshold(&self) -> f32 {
        self.threshold
    }

    /// Turns bounding-box pruning on (default) or off. Values are identical
    /// either way; only the speed differs.
    pub fn set_pruning(&mut self, on: bool) {
        self.pruning = on;
    }

    /// The box outside of which the potential is exactly zero.
    pub fn support(&self) -> Aabb {
        self.compiled.bounds
    }

    /// Polygonizes the surface `potential = T` with marching cubes over the
    /// support box (padded by 5 %), `res` samples along its longest edge.
    ///
    /// # Errors
    /// As [`isomorph_common::marching_cubes::polygonize`] (grid too small or too large).
    pub fn mesh(&self, res: u32) -> Result<isomorph_common::TriMesh, isomorph_common::GridError> {
        isomorph_common::marching_cubes::polygonize(self, &self.support().padded(0.05), res, 0.0)
    }

    /// The potential (before subtracting `T`) at `p`.
    pub fn potential(&self, p: Vec3) -> f32 {
        self.eval::<false>(&self.compiled, p).0
    }

    /// The potential and its gradient at `p` (analytic except under bends).
    pub fn potential_gradient(&self, p: Vec3) -> (f32, Vec3) {
        self.eval::<true>(&self.compiled, p)
    }

    /// Bounds `[lo, hi]` on `node`'s potential over `region` (anywhere when
    /// `None`), by interval arithmetic: zero where the region misses the
    /// node's box (pruning is exact); for a primitive, the kernel (decreasing
    /// in the distance) at the distance from the region's centre to the
    /// skeleton ± how far the distance can move within the region (the L^p
    /// distance, `p ≥ 1`, moves by at most `√3` times the Euclidean step in
    /// local space, which `to_local` stretches by at most its Frobenius
    /// norm); the n-ary operators and the mix are nondecreasing in every
    /// child (potentials are ≥ 0, superblend orders ≥ 1); the difference is
    /// decreasing in its right child, at most its left child, and piecewise
    /// linear in the left child with one kink (at `2c`); a warp reads its
    /// child over the region's pre-image.
    fn potential_range(&self, node: &Compiled, region: Option<&Aabb>) -> [f32; 2] {
        if region.is_some_and(|r| r.intersection(&node.bounds).is_empty()) {
            return [0.0, 0.0];
        }
        match &node.op {
            Op::Leaf(leaf) => {
                let k = &leaf.kernel;
                let Some(region) = region else {
                    return [0.0, k.intensity];
                };
                let m = leaf.to_local.matrix3;
                let stretch =
                    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared())
                        .sqrt();
                let reach = 0.5 * region.diagonal() * stretch * 3f32.sqrt();
                let d = leaf.poly.lp_distance(leaf.to_local.transform_point3(region.center()), leaf.p);
                let at = |d: f32| if d >= k.radius { 0.0 } else { k.value(d) };
                [at(d + reach), at((d - reach).max(0.0))]
            }
            Op::Nary(op) => {
                let [lo, hi] = self.children_ranges(node, region);
                [op.apply(&lo, None), op.apply(&hi, None)]
            }
            Op::Mix(a, b, s) => {
                let [lo, hi] = self.children_ranges(node, region);
                let [a0, a1] = [a.apply(&lo, None), a.apply(&hi, None)];
                let [b0, b1] = [b.apply(&lo, None), b.apply(&hi, None)];
                let scaled =
                    |w: f32, lo: f32, hi: f32| if w >= 0.0 { [w * lo, w * hi] } else { [w * hi, w * lo] };
                let ([p0, p1], [q0, q1]) = (scaled(1.0 - s, a0, a1), scaled(*s, b0, b1));
                [p0 + q0, p1 + q1]
            }
            Op::Difference(c) => {
                let [l0, l1] = self.potential_range(&node.children[0], region);
                let [_, r1] = self.potential_range(&node.children[1], region);
                let at = |fl: f32| difference::<false>(fl, Vec3::ZERO, r1, Vec3::ZERO, *c).0;
                let mut lo = at(l0).min(at(l1));
                if l0 < 2.0 * c && 2.0 * c < l1 {
                    lo = lo.min(at(2.0 * c));
                }
                [lo, l1.max(0.0)]
            }
            Op::Warp(w, _) => {
                let pre = region.and_then(|r| w.preimage_bounds(r));
                self.potential_range(&node.children[0], pre.as_ref())
            }
        }
    }

    /// The lower and the upper bounds of every child of `node` over `region`.
    fn children_ranges(&self, node: &Compiled, region: Option<&Aabb>) -> [Vec<f32>; 2] {
        let (lo, hi) =
            node.children.iter().map(|c| self.potential_range(c, region)).map(|[a, b]| (a, b)).unzip();
        [lo, hi]
    }

    fn eval<const G: bool>(&self, node: &Compiled, p: Vec3) -> (f32, Vec3) {
        if self.pruning && !node.bounds.contains(p) {
            return (0.0, Vec3::ZERO);
        }
        match &node.op {
            Op::Leaf(leaf) => {
                let x = leaf.to_local.transform_point3(p);
                if G {
                    let (d, dgrad) = leaf.poly.distance(x, leaf.p);
                    if d >= leaf.kernel.radius {
                        return (0.0, Vec3::ZERO);
                    }
                    let (v, dv) = leaf.kernel.value_derivative(d);
                    (v, leaf.grad_map * (dgrad * dv))
                } else {
                    let d = leaf.poly.lp_distance(x, leaf.p);
                    if d >= leaf.kernel.radius {
                        return (0.0, Vec3::ZERO);
                    }
                    (leaf.kernel.value(d), Vec3::ZERO)
                }
            }
            Op::Nary(op) => self.nary::<G>(node, p, *op, None),
            Op::Mix(a, b, s) => self.nary::<G>(node, p, *a, Some((*b, *s))),
            Op::Difference(c) => {
                let (fl, gl) = self.eval::<G>(&node.children[0], p);
                let (fr, gr) = self.eval::<G>(&node.children[1], p);
                difference::<G>(fl, gl, fr, gr, *c)
            }
            Op::Warp(w, turn) => {
                if G {
                    let (q, jt) = w.turned_inverse_with_jacobian_t(*turn, p);
                    let (v, g) = self.eval::<G>(&node.children[0], q);
                    (v, jt * g)
                } else {
                    self.eval::<G>(&node.children[0], w.turned_inverse(*turn, p))
                }
            }
        }
    }

    fn nary<const G: bool>(
        &self,
        node: &Compiled,
        p: Vec3,
        op: NaryOp,
        mix: Option<(NaryOp, f32)>,
    ) -> (f32, Vec3) {
        if !G && mix.is_none() {
            // Streaming value-only path for the plain operators (same order
            // of operations as `NaryOp::apply`, so identical results).
            let it = node.children.iter().map(|c| self.eval::<false>(c, p).0);
            match op {
                NaryOp::Blend => return (it.fold(0.0, |a, v| a + v), Vec3::ZERO),
                NaryOp::Union => {
                    return (it.fold(f32::NEG_INFINITY, |a, v| if v > a { v } else { a }), Vec3::ZERO);
                }
                NaryOp::Intersection => {
                    return (it.fold(f32::INFINITY, |a, v| if v < a { v } else { a }), Vec3::ZERO);
                }
                NaryOp::SuperBlend(_) => {}
            }
        }
        let n = node.children.len();
        let mut vs = [0.0f32; STACK_CHILDREN];
        let mut gs = [Vec3::ZERO; STACK_CHILDREN];
        let (mut vh, mut gh) = (Vec::new(), Vec::new());
        let (vals, grads): (&mut [f32], &mut [Vec3]) = if n <= STACK_CHILDREN {
            (&mut vs[..n], &mut gs[..n])
        } else {
            vh.resize(n, 0.0);
            gh.resize(n, Vec3::ZERO);
            (&mut vh[..], &mut gh[..])
        };
        for (i, c) in node.children.iter().enumerate() {
            let (v, g) = self.eval::<G>(c, p);
            vals[i] = v;
            grads[i] = g;
        }
        let mut ga = Vec3::ZERO;
        let fa = op.apply(vals, if G { Some((grads, &mut ga)) } else { None });
        match mix {
            None => (fa, ga),
            Some((to, s)) => {
                let mut gb = Vec3::ZERO;
                let fb = to.apply(vals, if G { Some((grads, &mut gb)) } else { None });
                ((1.0 - s) * fa + s * fb, (1.0 - s) * ga + s * gb)
            }
        }
    }
}

/// The difference operator with reference level `c` (see [`Node::Difference`]).
#[inline]
fn difference<const G: bool>(fl: f32, gl: Vec3, fr: f32, gr: Vec3, c: f32) -> (f32, Vec3) {
    if c <= 0.0 {
        // A fully phantom difference (all intensities and the level scaled to 0).
        return (0.0, Vec3::ZERO);
    }
    let (cut, gcut) = if fl <= 2.0 * c {
        (2.0 * c - fr, -gr)
    } else {
        let w = 1.0 - fr / c;
        (c + (fl - c) * w, gl * w - gr * ((fl - c) / c))
    };
    let (v, g) = if fl <= cut { (fl, gl) } else { (cut, gcut) };
    if v <= 0.0 { (0.0, Vec3::ZERO) } else { (v, if G { g } else { Vec3::ZERO }) }
}

/// Compiles `node` (at `path`, validated), refusing support boxes that are
/// not finite or reach beyond [`MAX_SUPPORT`].
fn compile(node: &Node, path: &NodePath) -> Result<Compiled, BlobError> {
    let kids = |children: &[Node]| -> Result<Vec<Compiled>, BlobError> {
        children.iter().enumerate().map(|(i, c)| compile(c, &path.child(i))).collect()
    };
    let compiled = match node {
        Node::Primitive(prim) => {
            // Validated by the caller.
            let poly = prim.skeleton.polytope().expect("validated skeleton");
            let r = prim.kernel.radius;
            let bounds = poly.bounds().expanded(r).transformed(&prim.frame);
            let to_local = prim.frame.inverse();
            let leaf = Leaf {
                poly,
                kernel: prim.kernel,
                p: prim.p,
                to_local,
                grad_map: Mat3::from(to_local.matrix3).transpose(),
            };
            Compiled { bounds, op: Op::Leaf(Box::new(leaf)), children: Vec::new() }
        }
        Node::Nary { op, children } => {
            let children = kids(children)?;
            let bounds = nary_bounds(*op, &children);
            Compiled { bounds, op: Op::Nary(*op), children }
        }
        Node::Mix { from, to, s, children } => {
            let children = kids(children)?;
            let a = nary_bounds(*from, &children);
            let b = nary_bounds(*to, &children);
            let bounds = if *s == 0.0 {
                a
            } else if *s == 1.0 {
                b
            } else {
                a.union(&b)
            };
            Compiled { bounds, op: Op::Mix(*from, *to, *s), children }
        }
        Node::Difference { left, right, level } => {
            let children = vec![compile(left, &path.child(0))?, compile(right, &path.child(1))?];
            Compiled { bounds: children[0].bounds, op: Op::Difference(*level), children }
        }
        Node::Warp { warp, child } => {
            let c = compile(child, &path.child(0))?;
            Compiled {
                bounds: warp.image_bounds(&c.bounds),
                op: Op::Warp(*warp, warp.turn()),
                children: vec![c],
            }
        }
    };
    let b = compiled.bounds;
    if !b.is_empty() {
        let reach = b.min.abs().max(b.max.abs()).max_element();
        if !b.min.is_finite() || !b.max.is_finite() || reach > MAX_SUPPORT {
            return Err(BlobError::node(path, NodeProblem::SupportTooLarge(reach)));
        }
    }
    Ok(compiled)
}

fn nary_bounds(op: NaryOp, children: &[Compiled]) -> Aabb {
    match op {
        NaryOp::Intersection => children
            .iter()
            .fold(Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX)), |b, c| b.intersection(&c.bounds)),
        _ => children.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.bounds)),
    }
}

/// A BlobTree is a [`Solid`](isomorph_common::Solid) input
/// (`Solid::implicit(Arc::new(tree))`) that the BlobTree morph recovers as
/// itself and the other methods sample as a field.
impl isomorph_common::Implicit for BlobTree {
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

impl Field3 for BlobTree {
    /// `potential(p) − T`: positive inside.
    fn value(&self, p: Vec3) -> f32 {
        self.potential(p) - self.threshold
    }

    /// The analytic gradient of the potential (bends by central differences).
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.potential_gradient(p).1
    }

    /// Batch evaluation: when the whole batch misses the support box the
    /// answer is `−T` everywhere without touching the tree.
    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "values: points and out differ in length");
        if self.pruning {
            let batch = Aabb::from_points(points);
            if batch.intersection(&self.compiled.bounds).is_empty() {
                out.fill(-self.threshold);
                return;
            }
        }
        for (o, &p) in out.iter_mut().zip(points) {
            *o = self.potential(p) - self.threshold;
        }
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(self.compiled.bounds)
    }

    /// Interval bounds of the potential over `region` (exactly `−T` where
    /// the region misses every support), minus `T`, widened by a relative
    /// `1e-4` for rounding: what lets the sparse polygonizer skip the flat
    /// outside without losing surface.
    fn range(&self, region: &Aabb) -> Option<[f32; 2]> {
        let [lo, hi] = self.potential_range(&self.compiled, Some(region));
        let pad = 1e-4 * (1.0 + lo.abs().max(hi.abs()));
        Some([lo - self.threshold - pad, hi - self.threshold + pad])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil;
    use crate::{Kernel, Primitive, Skeleton};
    use proptest::prelude::*;

    fn euclidean(n: &Node) -> Node {
        match n {
            Node::Primitive(p) => Node::Primitive(p.clone().with_p(2.0)),
            Node::Nary { op, children } => {
                Node::Nary { op: *op, children: children.iter().map(euclidean).collect() }
            }
            Node::Mix { .. } => n.clone(),
            Node::Difference { left, right, level } => {
                Node::difference(euclidean(left), euclidean(right), *level)
            }
            Node::Warp { warp, child } => Node::Warp { warp: *warp, child: Box::new(euclidean(child)) },
        }
    }

    fn ball(c: Vec3, r: f32) -> Node {
        Node::Primitive(Primitive::new(Skeleton::Point(c), Kernel::new(1.0, r, 1.0)))
    }

    #[test]
    fn primitive_fields_match_closed_forms() {
        let k = Kernel::new(1.5, 2.0, 0.5);
        let seg = Primitive::new(Skeleton::Segment(Vec3::ZERO, Vec3::Z), k)
            .with_frame(Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.0)));
        let tree = BlobTree::new(Node::Primitive(seg), 0.5).unwrap();
        // Distance from (1, 0.7, 0.5) to the translated segment is 0.7.
        let v = tree.potential(Vec3::new(1.0, 0.7, 0.5));
        assert!((v - k.value(0.7)).abs() < 1e-6);
        assert!((tree.value(Vec3::new(1.0, 0.7, 0.5)) - (k.value(0.7) - 0.5)).abs() < 1e-6);
        // Box skeleton with p = ∞: the field depends on the max-norm offset.
        let cube = Primitive::new(Skeleton::cuboid(Vec3::splat(0.5)), k).with_p(f32::INFINITY);
        let tree = BlobTree::new(Node::Primitive(cube), 0.5).unwrap();
        assert!((tree.potential(Vec3::new(1.2, 0.9, -0.3)) - k.value(0.7)).abs() < 1e-6);
        assert_eq!(tree.potential(Vec3::new(0.1, 0.2, 0.3)), 1.5);
    }

    #[test]
    fn operators_combine_as_printed() {
        let (a, b) = (ball(Vec3::ZERO, 1.0), ball(Vec3::X * 0.5, 1.0));
        let p = Vec3::new(0.2, 0.3, 0.0);
        let fa = BlobTree::new(a.clone(), 0.5).unwrap().potential(p);
        let fb = BlobTree::new(b.clone(), 0.5).unwrap().potential(p);
        let eval = |n: Node| BlobTree::new(n, 0.5).unwrap().potential(p);
        assert!((eval(Node::blend(vec![a.clone(), b.clone()])) - (fa + fb)).abs() < 1e-6);
        assert_eq!(eval(Node::union(vec![a.clone(), b.clone()])), fa.max(fb));
        assert_eq!(eval(Node::intersection(vec![a.clone(), b.clone()])), fa.min(fb));
        let n = 3.0;
        let sb = (fa.powf(n) + fb.powf(n)).powf(1.0 / n);
        assert!((eval(Node::super_blend(n, vec![a.clone(), b.clone()])) - sb).abs() < 1e-6);
        assert!((eval(Node::super_blend(1.0, vec![a.clone(), b.clone()])) - (fa + fb)).abs() < 1e-6);
        assert_eq!(eval(Node::super_blend(f32::INFINITY, vec![a.clone(), b.clone()])), fa.max(fb));
        // Difference below 2T is the classical min(f_L, 2T − f_R).
        let d = eval(Node::difference(a.clone(), b.clone(), 0.5));
        assert!((d - fa.min(1.0 - fb).max(0.0)).abs() < 1e-6);
        // A phantom right child is neutral.
        assert_eq!(eval(Node::difference(a.clone(), b.phantom(), 0.5)), fa);
        // Twist about z of a point on the axis changes nothing there.
        let w = Node::warp(Warp::twist(2.0), a.clone());
        assert_eq!(eval(w), fa);
        // Consecutive affine maps are concatenated into one node.
        let m1 = Affine3A::from_translation(Vec3::X);
        let m2 = Affine3A::from_scale(Vec3::splat(2.0));
        let n = Node::affine(m1, Node::affine(m2, a));
        assert!(matches!(&n, Node::Warp { child, .. } if matches!(**child, Node::Primitive(_))));
    }

    #[test]
    fn invalid_nodes_report_their_path() {
        let bad = Node::blend(vec![ball(Vec3::ZERO, 1.0), Node::union(vec![ball(Vec3::X, -1.0)])]);
        let err = BlobTree::new(bad, 0.5).unwrap_err();
        match err {
            BlobError::InvalidNode { path, problem } => {
                assert_eq!(path.0, vec![1, 0]);
                assert!(matches!(problem, crate::NodeProblem::NonPositiveRadius(_)));
            }
            e => panic!("{e}"),
        }
        assert!(matches!(BlobTree::new(Node::union(vec![]), 0.5), Err(BlobError::InvalidNode { .. })));
        assert!(matches!(
            BlobTree::new(ball(Vec3::ZERO, 1.0), f32::NAN),
            Err(BlobError::InvalidThreshold(_))
        ));
        let lp = Node::Primitive(Primitive::new(Skeleton::Point(Vec3::ZERO), Kernel::default()).with_p(0.5));
        assert!(matches!(
            BlobTree::new(lp, 0.5),
            Err(BlobError::InvalidNode { problem: crate::NodeProblem::ExponentBelowOne(_), .. })
        ));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// `range` bounds every value in its box (what lets the sparse
        /// polygonizer skip a block without losing surface): 5³ samples of
        /// random boxes, big and small, on random trees with every node kind.
        #[test]
        fn range_bounds_every_value_in_the_box(
            node in testutil::tree(),
            centre in prop::array::uniform3(-1.5f32..1.5),
            half in prop::array::uniform3(0.005f32..0.8),
        ) {
            let tree = BlobTree::new(node, 0.5).unwrap();
            let region = Aabb::new(Vec3::from(centre) - Vec3::from(half), Vec3::from(centre) + Vec3::from(half));
            let [lo, hi] = tree.range(&region).unwrap();
            prop_assert!(lo <= hi);
            for i in 0..125 {
                let f = Vec3::new((i % 5) as f32, ((i / 5) % 5) as f32, (i / 25) as f32) / 4.0;
                let p = region.min + f * region.size();
                let v = tree.value(p);
                prop_assert!(lo <= v && v <= hi, "{v} at {p} outside [{lo}, {hi}] over {region:?}");
            }
            // Far from every support the bounds are tight: exactly flat at −T.
            let far = Aabb::new(Vec3::splat(40.0), Vec3::splat(41.0));
            let [flo, fhi] = tree.range(&far).unwrap();
            prop_assert!(flo <= -0.5 && (-0.5..0.0).contains(&fhi), "[{flo}, {fhi}]");
        }

        /// Pruning never changes a value (bit-identical), and the support box
        /// really bounds the non-zero potential.
        #[test]
        fn pruned_equals_unpruned(node in testutil::tree()) {
            let pruned = BlobTree::new(node, 0.5).unwrap();
            let mut full = pruned.clone();
            full.set_pruning(false);
            let support = pruned.support();
            for p in testutil::points() {
                let (a, b) = (pruned.potential(p), full.potential(p));
                prop_assert_eq!(a, b, "at {}", p);
                if !support.contains(p) {
                    prop_assert_eq!(b, 0.0);
                }
            }
            let pts = testutil::points();
            let mut out = vec![0.0; pts.len()];
            pruned.values(&pts, &mut out);
            for (o, p) in out.iter().zip(&pts) {
                prop_assert_eq!(*o, full.value(*p));
            }
        }

        /// Analytic gradients agree with central differences away from kinks
        /// (Euclidean metric: the L^∞ and L^1 fields have kinks along ridges).
        #[test]
        fn gradients_match_differences(node in testutil::tree()) {
            let tree = BlobTree::new(euclidean(&node), 0.5).unwrap();
            let h = 1e-3f32;
            let mut checked = 0;
            for p in testutil::points().into_iter().step_by(7) {
                let (v, g) = tree.potential_gradient(p);
                if v <= 0.0 { continue; }
                let fd = Vec3::new(
                    tree.potential(p + Vec3::X * h) - tree.potential(p - Vec3::X * h),
                    tree.potential(p + Vec3::Y * h) - tree.potential(p - Vec3::Y * h),
                    tree.potential(p + Vec3::Z * h) - tree.potential(p - Vec3::Z * h),
                ) / (2.0 * h);
                // Skip points at kinks (min/max switches, skeleton edges):
                // there one-sided slopes differ.
                let fd2 = Vec3::new(
                    tree.potential(p + Vec3::X * 2.0 * h) - tree.potential(p - Vec3::X * 2.0 * h),
                    tree.potential(p + Vec3::Y * 2.0 * h) - tree.potential(p - Vec3::Y * 2.0 * h),
                    tree.potential(p + Vec3::Z * 2.0 * h) - tree.potential(p - Vec3::Z * 2.0 * h),
                ) / (4.0 * h);
                if (fd - fd2).length() > 1e-2 * (1.0 + fd.length()) { continue; }
                // A kink within h of p: the one-sided slopes differ.
                let forward = Vec3::new(
                    tree.potential(p + Vec3::X * h) - v,
                    tree.potential(p + Vec3::Y * h) - v,
                    tree.potential(p + Vec3::Z * h) - v,
                ) / h;
                let backward = Vec3::new(
                    v - tree.potential(p - Vec3::X * h),
                    v - tree.potential(p - Vec3::Y * h),
                    v - tree.potential(p - Vec3::Z * h),
                ) / h;
                if (forward - backward).length() > 5e-2 * (1.0 + fd.length()) { continue; }
                checked += 1;
                prop_assert!((g - fd).length() < 3e-2 * (1.0 + fd.length()), "at {}: {} vs {}", p, g, fd);
            }
            let _ = checked;
        }
    }
}
