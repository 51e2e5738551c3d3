//! The generic BlobTree `C(t)` (§4.4) and its [`Morph`] implementation.

use crate::correspond::{Correspondence, Heuristic, Link, Origin, Pair, Phantom, decompose};
use crate::error::{BlobMorphError, NodePath};
use crate::minkowski::MinkowskiPath;
use crate::node::{MAX_MAGNITUDE, NaryOp, Node, Primitive};
use crate::skeleton::Skeleton;
use crate::sweep::{FrameRange, Interval, PrimRange, Span, WarpRange};
use crate::tree::BlobTree;
use crate::warp::Warp;
use glam::{Affine3A, Quat, Vec3};
use isomorph_common::{Aabb, AffineParts};
use isomorph_common::{Control, Frame, Morph, MorphReport, Outcome, Side, Solid, Stages};
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// A speed curve `s(t)` (§4.4): 0 before `start`, 1 after `end`, and in
/// between a curve of the window's local time `u = (t − start)/(end − start)`:
/// `u` itself (linear), `3u² − 2u³` (`smooth`: zero speed at both ends), or,
/// when `points` are given, the free-form monotone piecewise cubic through
/// `(0, 0)`, the points `(u, s)` and `(1, 1)` (Fritsch–Carlson tangents:
/// never decreasing, never overshooting `[0, 1]`, C¹).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Speed {
    /// When the node starts to change (`t`, in `[0, 1]`).
    pub start: f32,
    /// When the node reaches its target (`t`, in `[0, 1]`, after `start`).
    pub end: f32,
    /// Ease in and out.
    pub smooth: bool,
    /// Inner points `(u, s)` of a free-form curve: `u` strictly increasing
    /// in `(0, 1)`, `s` non-decreasing in `[0, 1]` (not with `smooth`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<[f32; 2]>,
}

impl Default for Speed {
    /// `s(t) = t`.
    fn default() -> Self {
        Self { start: 0.0, end: 1.0, smooth: false, points: Vec::new() }
    }
}

impl Speed {
    /// `s(t)`.
    pub fn at(&self, t: f32) -> f32 {
        let u = ((t - self.start) / (self.end - self.start)).clamp(0.0, 1.0);
        if self.smooth {
            u * u * (3.0 - 2.0 * u)
        } else if self.points.is_empty() || u == 0.0 || u == 1.0 {
            u
        } else {
            self.free_form(u)
        }
    }

    /// The monotone cubic through `(0, 0)`, the points and `(1, 1)` at `u ∈ (0, 1)`.
    fn free_form(&self, u: f32) -> f32 {
        let knots: Vec<[f32; 2]> =
            std::iter::once([0.0, 0.0]).chain(self.points.iter().copied()).chain([[1.0, 1.0]]).collect();
        let n = knots.len() - 1;
        let secant: Vec<f32> = knots.windows(2).map(|w| (w[1][1] - w[0][1]) / (w[1][0] - w[0][0])).collect();
        // Fritsch–Carlson: averaged secants, zero at flat steps and local
        // extrema, then limited so that each piece stays monotone.
        let mut tangent = vec![0.0f32; n + 1];
        tangent[0] = secant[0];
        tangent[n] = secant[n - 1];
        for i in 1..n {
            tangent[i] =
                if secant[i - 1] * secant[i] <= 0.0 { 0.0 } else { 0.5 * (secant[i - 1] + secant[i]) };
        }
        for i in 0..n {
            if secant[i] == 0.0 {
                (tangent[i], tangent[i + 1]) = (0.0, 0.0);
                continue;
            }
            let (alpha, beta) = (tangent[i] / secant[i], tangent[i + 1] / secant[i]);
            let norm = alpha.hypot(beta);
            if norm > 3.0 {
                tangent[i] = 3.0 / norm * alpha * secant[i];
                tangent[i + 1] = 3.0 / norm * beta * secant[i];
            }
        }
        let i = knots[1..n].iter().take_while(|k| k[0] <= u).count();
        let ([x0, y0], [x1, y1]) = (knots[i], knots[i + 1]);
        let h = x1 - x0;
        let v = (u - x0) / h;
        let (v2, v3) = (v * v, v * v * v);
        let value = (2.0 * v3 - 3.0 * v2 + 1.0) * y0
            + (v3 - 2.0 * v2 + v) * h * tangent[i]
            + (-2.0 * v3 + 3.0 * v2) * y1
            + (v3 - v2) * h * tangent[i + 1];
        value.clamp(y0, y1)
    }

    /// What is wrong with this curve, if anything.
    fn problem(&self) -> Option<&'static str> {
        let window =
            (0.0..=1.0).contains(&self.start) && (0.0..=1.0).contains(&self.end) && self.start < self.end;
        if !window {
            return Some("start and end must satisfy 0 ≤ start < end ≤ 1");
        }
        if self.smooth && !self.points.is_empty() {
            return Some("give either `smooth` or `points`, not both");
        }
        let knots: Vec<[f32; 2]> =
            std::iter::once([0.0, 0.0]).chain(self.points.iter().copied()).chain([[1.0, 1.0]]).collect();
        let monotone = knots.windows(2).all(|w| w[0][0] < w[1][0] && w[0][1] <= w[1][1]);
        if !monotone || self.points.iter().flatten().any(|v| !v.is_finite()) {
            return Some("points (u, s) need u strictly increasing in (0, 1) and s non-decreasing in [0, 1]");
        }
        None
    }
}

/// The speed curve of the generic node made from source node `a` and target node `b`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedCurve {
    /// Source node path.
    pub a: NodePath,
    /// Target node path.
    pub b: NodePath,
    /// The curve.
    pub speed: Speed,
    /// For two warps of different kinds, which of the two generic warps
    /// `(ω_A →s_A(t) Id) ∘ (Id →s_B(t) ω_B)` of Fig. 16 the curve drives
    /// (default: both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warp: Option<WarpHalf>,
}

/// One of the two generic warps a pair of warps of different kinds becomes
/// (§4.4, Fig. 16: `ω_A →s(t) ω_B = (ω_A →s_A(t) ω_Id) ∘ (ω_Id →s_B(t) ω_B)`),
/// each with its own speed curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarpHalf {
    /// `ω_A → Id`, at speed `s_A(t)`: the source's warp is undone.
    Source,
    /// `Id → ω_B`, at speed `s_B(t)`: the target's warp is applied.
    Target,
}

/// The trajectory of the frame made from source node `a` and target node
/// `b` (§3.4: "the animator controls the location and the orientation of
/// intermediate coordinate systems"): the local frame of a generic leaf
/// (primitive) or the map of a generic affine node. By default the origin
/// moves uniformly on a straight line, the orientation by slerp and the
/// stretch linearly; `handles` bend the origin's path into a cubic Bézier
/// curve, or `keys` make it pass through key positions (a cubic spline)
/// and key orientations (slerp between consecutive keys) at given local
/// times `s`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trajectory {
    /// Source node path.
    pub a: NodePath,
    /// Target node path.
    pub b: NodePath,
    /// The two inner Bézier control points of the origin's path (world
    /// units; not with keyed positions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub handles: Option<[[f32; 3]; 2]>,
    /// Key frames at increasing local times `s ∈ (0, 1)`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keys: Vec<FrameKey>,
}

/// One key frame of a [`Trajectory`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameKey {
    /// The node's local time (after its speed curve), in `(0, 1)`.
    pub s: f32,
    /// The frame origin at `s` (world units; for an affine node, its translation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f32; 3]>,
    /// The frame orientation at `s`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<Orientation>,
}

/// An orientation as a rotation about `axis` by `degrees` (from the world axes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orientation {
    /// The rotation axis (any non-zero length).
    pub axis: [f32; 3],
    /// The angle in degrees (right-handed about `axis`).
    pub degrees: f32,
}

/// A frame's path over the local time `s`, from a [`Trajectory`].
#[derive(Debug, Clone, Default)]
struct FramePath {
    /// Inner Bézier control points of the origin's path.
    handles: Option<[Vec3; 2]>,
    /// Inner origin keys `(s, position)`.
    positions: Vec<(f32, Vec3)>,
    /// Inner orientation keys `(s, rotation)`.
    rotations: Vec<(f32, Quat)>,
}

impl FramePath {
    /// The checked path of `tr`.
    fn new(tr: &Trajectory) -> Result<Self, BlobMorphError> {
        let fail = |problem| BlobMorphError::InvalidKeys { a: tr.a.clone(), b: tr.b.clone(), problem };
        if let Some(&value) = tr
            .handles
            .iter()
            .flatten()
            .flatten()
            .chain(tr.keys.iter().filter_map(|k| k.position.as_ref()).flatten())
            .find(|v| !v.is_finite() || v.abs() > MAX_MAGNITUDE)
        {
            return Err(BlobMorphError::InvalidTrajectory { a: tr.a.clone(), b: tr.b.clone(), value });
        }
        let times = std::iter::once(0.0).chain(tr.keys.iter().map(|k| k.s)).chain([1.0]).collect::<Vec<_>>();
        if !times.windows(2).all(|w| w[0] < w[1]) {
            return Err(fail("key times s must increase strictly within (0, 1)"));
        }
        let positions: Vec<(f32, Vec3)> =
            tr.keys.iter().filter_map(|k| Some((k.s, Vec3::from_array(k.position?)))).collect();
        if tr.handles.is_some() && !positions.is_empty() {
            return Err(fail("give either `handles` or key positions, not both"));
        }
        let mut rotations = Vec::new();
        for k in &tr.keys {
            if let Some(o) = &k.rotate {
                let axis = Vec3::from_array(o.axis);
                let axis = axis.try_normalize().filter(|_| o.degrees.is_finite());
                let axis =
                    axis.ok_or_else(|| fail("a key rotation needs a finite non-zero axis and angle"))?;
                rotations.push((k.s, Quat::from_axis_angle(axis, o.degrees.to_radians())));
            }
        }
        Ok(Self { handles: tr.handles.map(|h| h.map(Vec3::from_array)), positions, rotations })
    }

    /// The frame at `s ∈ (0, 1)` between the end frames `a` and `b`.
    fn at(&self, a: &AffineParts, b: &AffineParts, s: f32) -> AffineParts {
        let mut parts = a.lerp(b, s);
        if let Some([h1, h2]) = self.handles {
            let u = 1.0 - s;
            parts.translation = a.translation * (u * u * u)
                + h1 * (3.0 * u * u * s)
                + h2 * (3.0 * u * s * s)
                + b.translation * (s * s * s);
        } else if !self.positions.is_empty() {
            parts.translation = spline(a.translation, &self.positions, b.translation, s);
        }
        if !self.rotations.is_empty() {
            let keys: Vec<(f32, Quat)> = std::iter::once((0.0, a.rotation))
                .chain(self.rotations.iter().copied())
                .chain([(1.0, b.rotation)])
                .collect();
            let i = keys[1..keys.len() - 1].iter().take_while(|k| k.0 <= s).count();
            let ((s0, q0), (s1, q1)) = (keys[i], keys[i + 1]);
            parts.rotation = q0.slerp(q1, (s - s0) / (s1 - s0)).normalize();
        }
        parts
    }

    /// The frames [`FramePath::at`] gives for `s` in `s ⊆ [0, 1]`: the
    /// interval is cut at the keys, and on each piece the origin lies in
    /// the hull of its Bézier control points (straight, handles, or the
    /// spline's piece), the rotation within the slerp's reach
    /// ([`FrameRange`]).
    fn range(&self, a: &AffineParts, b: &AffineParts, s: Interval) -> FrameRange {
        let mut inner: Vec<f32> = (self.positions.iter().map(|k| k.0))
            .chain(self.rotations.iter().map(|k| k.0))
            .filter(|&k| k > s.lo && k < s.hi)
            .collect();
        inner.sort_by(f32::total_cmp);
        inner.dedup();
        let cuts: Vec<f32> = std::iter::once(s.lo).chain(inner).chain([s.hi]).collect();
        let (ea, eb) = (FrameRange::exact(a), FrameRange::exact(b));
        let mut out: Option<FrameRange> = None;
        for w in cuts.windows(2) {
            let piece = Interval::new(w[0], w[1]);
            let mut r = FrameRange::lerp(&ea, &eb, piece);
            if let Some([h1, h2]) = self.handles {
                r = r.with_translation(crate::sweep::bezier_box(
                    [a.translation, h1, h2, b.translation],
                    piece.lo,
                    piece.hi,
                ));
            } else if !self.positions.is_empty() {
                let mid = 0.5 * (piece.lo + piece.hi);
                let (x0, h, ctrl) = spline_piece(a.translation, &self.positions, b.translation, mid);
                r = r.with_translation(crate::sweep::bezier_box(
                    ctrl,
                    (piece.lo - x0) / h,
                    (piece.hi - x0) / h,
                ));
            }
            if !self.rotations.is_empty() {
                let keys: Vec<(f32, Quat)> = std::iter::once((0.0, a.rotation))
                    .chain(self.rotations.iter().copied())
                    .chain([(1.0, b.rotation)])
                    .collect();
                let mid = 0.5 * (piece.lo + piece.hi);
                let i = keys[1..keys.len() - 1].iter().take_while(|k| k.0 <= mid).count();
                let ((s0, q0), (s1, q1)) = (keys[i], keys[i + 1]);
                r = r.with_slerp(q0, q1, (piece.lo - s0) / (s1 - s0), (piece.hi - s0) / (s1 - s0));
            }
            out = Some(match out {
                None => r,
                Some(o) => o.union(&r),
            });
        }
        out.expect("at least one piece")
    }
}

/// The cubic spline through `(0, start)`, the `keys` and `(1, end)` at
/// `s`: Hermite pieces with Catmull–Rom tangents (central differences over
/// the neighbouring keys, one-sided at the ends), C¹, through every key.
fn spline(start: Vec3, keys: &[(f32, Vec3)], end: Vec3, s: f32) -> Vec3 {
    let (x0, h, [p0, c0, c1, p1]) = spline_piece(start, keys, end, s);
    let v = (s - x0) / h;
    let u = 1.0 - v;
    p0 * (u * u * u) + c0 * (3.0 * u * u * v) + c1 * (3.0 * u * v * v) + p1 * (v * v * v)
}

/// The piece of [`spline`] that plays at `s`: its start `x0`, length `h`
/// and Bézier control points (`p0, p0 + h·m0/3, p1 − h·m1/3, p1` of the
/// Hermite piece with tangents `m0`, `m1`) over `v = (s − x0)/h ∈ [0, 1]`.
fn spline_piece(start: Vec3, keys: &[(f32, Vec3)], end: Vec3, s: f32) -> (f32, f32, [Vec3; 4]) {
    let knots: Vec<(f32, Vec3)> =
        std::iter::once((0.0, start)).chain(keys.iter().copied()).chain([(1.0, end)]).collect();
    let n = knots.len() - 1;
    let tangent = |i: usize| {
        let (l, r) = (i.saturating_sub(1), (i + 1).min(n));
        (knots[r].1 - knots[l].1) / (knots[r].0 - knots[l].0)
    };
    let i = knots[1..n].iter().take_while(|k| k.0 <= s).count();
    let ((x0, p0), (x1, p1)) = (knots[i], knots[i + 1]);
    let h = x1 - x0;
    (x0, h, [p0, p0 + tangent(i) * (h / 3.0), p1 - tangent(i + 1) * (h / 3.0), p1])
}

/// A generic affine node's end maps, decomposed, and its keyed path.
#[derive(Debug, Clone)]
struct AffinePath {
    a: AffineParts,
    b: AffineParts,
    path: FramePath,
}

/// Everything the animator controls (the `--links` file): links, heuristic,
/// speed curves, trajectories.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MorphSpec {
    /// Links between nodes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub links: Vec<Link>,
    /// Pairing where no links are given.
    pub heuristic: Heuristic,
    /// Per-node speed curves.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub speeds: Vec<SpeedCurve>,
    /// Per-leaf origin trajectories.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub trajectories: Vec<Trajectory>,
    /// The animator's phantom parameters (position, skeleton scale, radius, stiffness).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub phantoms: Vec<Phantom>,
    /// Automatic coplanar frames (§3.4, Figs. 10–11): matched pairs of
    /// points, segments and polygons (Euclidean, similarity frames) are
    /// interpolated in frames where both lie in one plane, so their
    /// in-between skeletons stay segments or polygons instead of becoming
    /// polyhedra (default off: the scene's own frames).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub coplanar_frames: bool,
    /// Links for the de Casteljau levels above the first of a Bézier-like
    /// morph ([`BlobMorph::bezier`]); the morph gathers them from the specs
    /// of all its segments. [`GenericTree::new`] ignores them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub levels: Vec<LevelLinks>,
}

/// The animator's links for one pair of a de Casteljau level `r ≥ 2` of a
/// Bézier-like morph through the shapes `P_0 … P_n` ([`BlobMorph::bezier`]):
/// the correspondence between `P_i^{r−1}(t)` and `P_{i+1}^{r−1}(t)`, made
/// once with these links (children of linked nodes without a link get
/// phantom partners, as in the first level) and kept for every `t`.
/// Without them a level is matched by nearest centres at `t = ½`.
///
/// Node paths `a` name nodes of `P_i^{r−1}`, `b` nodes of `P_{i+1}^{r−1}`,
/// as [`BlobMorph::level_shapes`] returns them and their scene files
/// ([`BlobTree::to_ron`]) write them: their structure does not depend on `t`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LevelLinks {
    /// The level `r`, from 2 to `n` (the number of shapes minus one).
    pub level: usize,
    /// The pair `i`, from 0 to `n − r`: between `P_i^{r−1}` and `P_{i+1}^{r−1}`.
    pub pair: usize,
    /// The links.
    pub links: Vec<Link>,
}

impl MorphSpec {
    /// Reads a RON spec, e.g. `(links: [(a: [0], b: [1, 0])], speeds: [(a: [], b: [], speed: (start: 0.2, end: 0.8))])`.
    ///
    /// # Errors
    /// [`crate::BlobError::Parse`] (wrapped) for malformed text.
    pub fn from_ron(text: &str) -> Result<Self, BlobMorphError> {
        crate::scene::ron_options()
            .from_str(text)
            .map_err(|e| crate::scene::ron_error(&e, "links spec").into())
    }

    /// Reads a JSON spec.
    ///
    /// # Errors
    /// [`crate::BlobError::Parse`] (wrapped) for malformed text.
    pub fn from_json(text: &str) -> Result<Self, BlobMorphError> {
        serde_json::from_str(text).map_err(|e| crate::scene::json_error(&e, "links spec").into())
    }

    /// The spec as pretty RON; [`MorphSpec::from_ron`] reads it back.
    ///
    /// # Errors
    /// [`crate::BlobError::Write`] (wrapped) if serialization fails.
    pub fn to_ron(&self) -> Result<String, BlobMorphError> {
        crate::scene::ron_options()
            .to_string_pretty(self, crate::scene::ron_pretty())
            .map_err(|e| crate::BlobError::Write(e.to_string()).into())
    }

    /// The spec as pretty JSON; [`MorphSpec::from_json`] reads it back.
    ///
    /// # Errors
    /// [`crate::BlobError::Write`] (wrapped) if serialization fails.
    pub fn to_json(&self) -> Result<String, BlobMorphError> {
        serde_json::to_string_pretty(self).map_err(|e| crate::BlobError::Write(e.to_string()).into())
    }

    /// Reads a spec file: JSON for a `.json` extension, RON otherwise.
    ///
    /// # Errors
    /// [`crate::BlobError::Read`] (wrapped) for an unreadable file or one
    /// larger than [`crate::scene::MAX_FILE_BYTES`], and as
    /// [`MorphSpec::from_ron`] / [`MorphSpec::from_json`].
    pub fn load(path: &std::path::Path) -> Result<Self, BlobMorphError> {
        let text = crate::scene::read_text(path, "")?;
        if path.extension().is_some_and(|e| e == "json") {
            Self::from_json(&text)
        } else {
            Self::from_ron(&text)
        }
    }
}

#[derive(Debug, Clone)]
struct GLeaf {
    a: Primitive,
    b: Primitive,
    /// `(1 − s) S_A ⊕ s S_B` with its generic topology (§3.4.1).
    skeleton: Box<MinkowskiPath>,
    frame_a: AffineParts,
    frame_b: AffineParts,
    path: FramePath,
    /// The local boxes of the interpolated skeletons' ends (possibly in
    /// coplanar frames).
    boxes: [Aabb; 2],
    /// The ends as given, as parameter ranges ([`GLeaf::span`]).
    ends: [PrimRange; 2],
    /// Whether the in-betweens use coplanar frames other than the ends'.
    reframed: bool,
}

#[derive(Debug, Clone)]
enum GKind {
    Leaf(Box<GLeaf>),
    Nary(NaryOp, NaryOp),
    Difference(f32, f32),
    /// Source and target warps, and the keyed path of two affine maps.
    Warp(Warp, Warp, Option<Box<AffinePath>>),
}

#[derive(Debug, Clone)]
struct GNode {
    kind: GKind,
    speed: Speed,
    origin: Origin,
    /// Which generic warp of a pair of different kinds this is (Fig. 16).
    half: Option<WarpHalf>,
    children: Vec<GNode>,
}

/// The generic BlobTree: one fixed structure whose parameters depend on `t`.
///
/// Built from the overlapping pair tree of [`crate::decompose`]; every pair
/// of nodes `N_A →s(t) N_B` becomes a time-varying node with its own speed
/// curve `s(t)`:
///
/// - same operator: kept;
/// - blend ↔ union ↔ super-elliptic blend: one super-elliptic blend whose
///   `1/n` moves linearly from `1/n_A` to `1/n_B` (blend: `n = 1`, union:
///   `n = ∞`, reached exactly at `s = 1`);
/// - other commutative pairs: `(1 − s) N_A + s N_B` on the shared children ([`Node::Mix`]);
/// - difference → difference with interpolated reference level;
/// - warps of one kind: interpolated parameters, affine maps as translation ·
///   slerped rotation · stretch ([`isomorph_common::AffineParts::lerp`]);
///   different kinds were already split into two warps through the identity (Fig. 16);
/// - leaves: skeleton `(1 − s) S_A ⊕ s S_B` in the time-varying local frame
///   (origin uniform and straight unless the animator gives a
///   [`Trajectory`] — Bézier handles or key frames — orientation by
///   quaternion slerp, stretch linearly; optionally coplanar frames,
///   [`MorphSpec::coplanar_frames`]), generic topology built once ([`MinkowskiPath`]); `I, R, k`
///   linear; the L^p exponent linear (§3.4.3), or `1/p` linear when one end
///   is `p = ∞`.
///
/// The threshold is `T(t) = (1 − t) T_A + t T_B`. At `t = 0` every node is
/// exactly its source node and at `t = 1` its target node, so `C(0) ≡ A` and
/// `C(1) ≡ B`.
#[derive(Debug, Clone)]
pub struct GenericTree {
    root: GNode,
    thresholds: (f32, f32),
    pair: Pair,
}

fn frame_parts(
    p: &Primitive,
    a: &Option<NodePath>,
    b: &Option<NodePath>,
) -> Result<AffineParts, BlobMorphError> {
    AffineParts::from_affine(&p.frame)
        .map_err(|source| transform_error(&Origin { a: a.clone(), b: b.clone() }, source))
}

/// The error of the pair from `origin` whose maps cannot be decomposed.
fn transform_error(origin: &Origin, source: isomorph_common::TransformError) -> BlobMorphError {
    BlobMorphError::Transform {
        a: origin.a.clone().unwrap_or_default(),
        b: origin.b.clone().unwrap_or_default(),
        source,
    }
}

/// The generic node of `pair` and below; `coplanar`: automatic coplanar
/// frames for flat leaf pairs ([`MorphSpec::coplanar_frames`]);
/// `topologies`: for each leaf in depth-first order, a generic topology
/// known to hold for its skeletons ([`MinkowskiPath::reseated`]), else
/// `None` (built).
fn build(
    pair: &Pair,
    coplanar: bool,
    topologies: &mut dyn Iterator<Item = Option<&MinkowskiPath>>,
) -> Result<GNode, BlobMorphError> {
    let origin = pair.origin().clone();
    let mut build = |p: &Pair| build(p, coplanar, topologies);
    let (kind, children) = match pair {
        Pair::Leaf { a: ends_a, b: ends_b, .. } => {
            // The ends are returned as given; the in-betweens interpolate
            // the same primitives, possibly re-expressed in coplanar frames.
            let reframed = if coplanar { crate::coplanar::coplanar_frames(ends_a, ends_b) } else { None };
            let (a, b) = match &reframed {
                Some((a, b)) => (a, b),
                None => (&**ends_a, &**ends_b),
            };
            let pa = a
                .skeleton
                .polytope()
                .map_err(|p| crate::BlobError::node(&origin.a.clone().unwrap_or_default(), p))?;
            let pb = b
                .skeleton
                .polytope()
                .map_err(|p| crate::BlobError::node(&origin.b.clone().unwrap_or_default(), p))?;
            let frame_a = frame_parts(a, &origin.a, &origin.b)?;
            let frame_b = frame_parts(b, &origin.a, &origin.b)?;
            let end = |p: &Primitive, path: &Option<NodePath>| -> Result<PrimRange, BlobMorphError> {
                let poly = p
                    .skeleton
                    .polytope()
                    .map_err(|e| crate::BlobError::node(&path.clone().unwrap_or_default(), e))?;
                PrimRange::exact(p, &poly.bounds()).map_err(|source| transform_error(&origin, source))
            };
            let ends = [end(ends_a, &origin.a)?, end(ends_b, &origin.b)?];
            let leaf = GLeaf {
                a: (**ends_a).clone(),
                b: (**ends_b).clone(),
                boxes: [pa.bounds(), pb.bounds()],
                skeleton: Box::new(
                    topologies
                        .next()
                        .flatten()
                        .and_then(|known| known.reseated(&pa, &pb))
                        .unwrap_or_else(|| MinkowskiPath::new(&pa, &pb)),
                ),
                frame_a,
                frame_b,
                path: FramePath::default(),
                ends,
                reframed: reframed.is_some(),
            };
            (GKind::Leaf(Box::new(leaf)), Vec::new())
        }
        Pair::Nary { a, b, children, .. } => {
            (GKind::Nary(*a, *b), children.iter().map(&mut build).collect::<Result<_, _>>()?)
        }
        Pair::Difference { a, b, left, right, .. } => {
            (GKind::Difference(*a, *b), vec![build(left)?, build(right)?])
        }
        Pair::Warp { a, b, child, .. } => (GKind::Warp(*a, *b, None), vec![build(child)?]),
    };
    let mut node = GNode { kind, speed: Speed::default(), origin, half: None, children };
    // Fig. 16: a warp pair of different kinds is two warps of one origin,
    // the source's over the target's.
    if let [lower @ GNode { kind: GKind::Warp(..), .. }] = &mut node.children[..]
        && matches!(node.kind, GKind::Warp(..))
        && lower.origin == node.origin
        && node.origin.a.is_some()
        && node.origin.b.is_some()
    {
        (node.half, lower.half) = (Some(WarpHalf::Source), Some(WarpHalf::Target));
    }
    Ok(node)
}

/// The pairs the correspondence made under the commutative nodes of
/// `pair` (children matched by links or the heuristic), as links: given
/// back to [`decompose`] on trees of the same structure they make the same
/// choices.
fn links_of(pair: &Pair) -> Vec<Link> {
    fn walk<'a>(pair: &'a Pair, seen: &mut HashSet<(&'a NodePath, &'a NodePath)>, out: &mut Vec<Link>) {
        match pair {
            Pair::Leaf { .. } => {}
            Pair::Nary { children, .. } => {
                for c in children {
                    if let Origin { a: Some(a), b: Some(b) } = c.origin()
                        && seen.insert((a, b))
                    {
                        out.push(Link { a: a.clone(), b: b.clone() });
                    }
                    walk(c, seen, out);
                }
            }
            Pair::Difference { left, right, .. } => {
                walk(left, seen, out);
                walk(right, seen, out);
            }
            Pair::Warp { child, .. } => walk(child, seen, out),
        }
    }
    let mut out = Vec::new();
    walk(pair, &mut HashSet::new(), &mut out);
    out
}

/// Applies `f` to every node whose origin `(a, b)` is a key of `wanted`,
/// with each of that key's indices in order; one traversal for all keys.
fn for_matching(
    node: &mut GNode,
    wanted: &HashMap<(&NodePath, &NodePath), Vec<usize>>,
    f: &mut dyn FnMut(usize, &mut GNode),
) {
    if let (Some(a), Some(b)) = (&node.origin.a, &node.origin.b)
        && let Some(ks) = wanted.get(&(a, b)).cloned()
    {
        for k in ks {
            f(k, node);
        }
    }
    for c in &mut node.children {
        for_matching(c, wanted, f);
    }
}

/// `1/n` of a member of the super-elliptic family (blend 1, union 0).
fn ricci_inverse(op: NaryOp) -> Option<f32> {
    match op {
        NaryOp::Blend => Some(1.0),
        NaryOp::Union => Some(0.0),
        NaryOp::SuperBlend(n) => Some(1.0 / n),
        NaryOp::Intersection => None,
    }
}

fn lerp(a: f32, b: f32, s: f32) -> f32 {
    a + (b - a) * s
}

impl GLeaf {
    /// The parameter ranges of [`GLeaf::at`] for `s` in `s`.
    fn span(&self, s: Interval) -> Vec<PrimRange> {
        let [ea, eb] = &self.ends;
        if s.hi <= 0.0 {
            return vec![*ea];
        }
        if s.lo >= 1.0 {
            return vec![*eb];
        }
        let inner = Interval::new(s.lo.max(0.0), s.hi.min(1.0));
        let radius = Interval::point(self.a.kernel.radius).lerp(Interval::point(self.b.kernel.radius), inner);
        let frame = self.path.range(&self.frame_a, &self.frame_b, inner);
        let mut ranges = vec![PrimRange::blend(&self.boxes[0], &self.boxes[1], radius, frame, inner)];
        // The ends are the primitives as given, in other frames than the
        // coplanar ones the in-betweens use.
        if self.reframed && s.lo <= 0.0 {
            ranges.push(*ea);
        }
        if self.reframed && s.hi >= 1.0 {
            ranges.push(*eb);
        }
        ranges
    }

    fn at(&self, s: f32) -> Primitive {
        if s <= 0.0 {
            return self.a.clone();
        }
        if s >= 1.0 {
            return self.b.clone();
        }
        let (a, b) = (&self.a, &self.b);
        let p = if a.p.is_finite() && b.p.is_finite() {
            lerp(a.p, b.p, s)
        } else {
            let inv = lerp(1.0 / a.p, 1.0 / b.p, s);
            if inv <= 0.0 { f32::INFINITY } else { 1.0 / inv }
        };
        let parts = self.path.at(&self.frame_a, &self.frame_b, s);
        Primitive {
            skeleton: Skeleton::Generic(self.skeleton.at(s)),
            kernel: a.kernel.lerp(&b.kernel, s),
            p,
            frame: parts.to_affine(),
        }
    }
}

/// Whether a node `a →s b` is the intersection for every `s` in `s` (see
/// [`GNode::at`]: `a` at `s ≤ 0`, `b` at `s ≥ 1`, a blend of the two between).
fn always_intersection(a: NaryOp, b: NaryOp, s: Interval) -> bool {
    let i = NaryOp::Intersection;
    if a == b || s.hi <= 0.0 {
        a == i
    } else if s.lo >= 1.0 {
        b == i
    } else {
        false
    }
}

/// Whether `a → b` is instantiated as a blend of the two scaled operators
/// in a tree of fixed structure (see [`GNode::at`]).
fn scaled_pair(a: NaryOp, b: NaryOp) -> bool {
    a != b && (ricci_inverse(a).is_none() || ricci_inverse(b).is_none())
}

/// The span of a commutative node `a → b` over `s` with the children's
/// spans `children`, in the structure [`GNode::at`] gives it.
fn nary_span(a: NaryOp, b: NaryOp, s: Interval, fixed: bool, children: Vec<Span>) -> Span {
    if fixed && scaled_pair(a, b) {
        let from = Span::Nary { intersection: a == NaryOp::Intersection, children: children.clone() };
        let to = Span::Nary { intersection: b == NaryOp::Intersection, children };
        Span::Nary { intersection: false, children: vec![from, to] }
    } else {
        Span::Nary { intersection: always_intersection(a, b, s), children }
    }
}

impl GNode {
    /// The leaves below this node, depth first.
    fn leaves<'a>(&'a self, out: &mut Vec<&'a GLeaf>) {
        if let GKind::Leaf(leaf) = &self.kind {
            out.push(leaf);
        }
        for c in &self.children {
            c.leaves(out);
        }
    }

    /// Where each leaf below is at `t`, depth first: at its source (`s ≤
    /// 0`: the source skeleton), its target (`s ≥ 1`) or between (the
    /// generic skeleton, in the generic topology's vertex order).
    fn leaf_phases(&self, t: f32, out: &mut Vec<std::cmp::Ordering>) {
        if let GKind::Leaf(_) = self.kind {
            let s = self.speed.at(t);
            out.push(if s <= 0.0 {
                std::cmp::Ordering::Less
            } else if s >= 1.0 {
                std::cmp::Ordering::Greater
            } else {
                std::cmp::Ordering::Equal
            });
        }
        for c in &self.children {
            c.leaf_phases(t, out);
        }
    }

    /// The ranges of the nodes [`GNode::at`] gives for `t` in `t` (speed
    /// curves are non-decreasing, so `s` ranges over `[s(t₀), s(t₁)]`).
    fn span(&self, t: Interval, fixed: bool) -> Result<Span, BlobMorphError> {
        let s = Interval::new(self.speed.at(t.lo), self.speed.at(t.hi));
        let mut kids = self.children.iter().map(|c| c.span(t, fixed)).collect::<Result<Vec<_>, _>>()?;
        Ok(match &self.kind {
            GKind::Leaf(leaf) => Span::Leaf(leaf.span(s)),
            GKind::Nary(a, b) => nary_span(*a, *b, s, fixed, kids),
            GKind::Difference(..) => {
                let right = kids.pop().expect("two children");
                let left = kids.pop().expect("two children");
                Span::Difference(Box::new(left), Box::new(right))
            }
            GKind::Warp(a, b, keyed) => {
                let exact = |w: &Warp| WarpRange::exact(w).map_err(|e| transform_error(&self.origin, e));
                let (ra, rb) = (exact(a)?, exact(b)?);
                let inner = Interval::new(s.lo.max(0.0), s.hi.min(1.0));
                let range = if s.hi <= 0.0 {
                    ra
                } else if s.lo >= 1.0 {
                    rb
                } else if let Some(k) = keyed {
                    WarpRange::Affine(k.path.range(&k.a, &k.b, inner))
                } else {
                    WarpRange::lerp(&ra, &rb, inner).unwrap_or(ra)
                };
                Span::Warp(range, Box::new(kids.pop().expect("one child")))
            }
        })
    }

    /// The node at `t`. With `fixed`, a pair of commutative operators
    /// outside the super-elliptic family is instantiated as the equivalent
    /// blend of the two scaled operators, `(1 − s) N_A + s N_B` (§4.2
    /// scaling nodes), even at `s ∈ {0, 1}`: the same value as the mix node,
    /// with a structure that does not change with `t` (what a further
    /// correspondence, [`BlobMorph::bezier`], needs).
    fn at(&self, t: f32, fixed: bool) -> Node {
        let s = self.speed.at(t);
        let kids = || self.children.iter().map(|c| c.at(t, fixed)).collect::<Vec<Node>>();
        match &self.kind {
            GKind::Leaf(leaf) => Node::Primitive(leaf.at(s)),
            GKind::Nary(a, b) if fixed && scaled_pair(*a, *b) => {
                let children = kids();
                let from = Node::Nary { op: *a, children: children.clone() }.scaled(1.0 - s);
                let to = Node::Nary { op: *b, children }.scaled(s);
                Node::Nary { op: NaryOp::Blend, children: vec![from, to] }
            }
            GKind::Nary(a, b) => {
                let op = if s <= 0.0 || a == b {
                    Some(*a)
                } else if s >= 1.0 {
                    Some(*b)
                } else if let (Some(ia), Some(ib)) = (ricci_inverse(*a), ricci_inverse(*b)) {
                    let inv = lerp(ia, ib, s);
                    Some(NaryOp::SuperBlend(if inv <= 0.0 { f32::INFINITY } else { (1.0 / inv).max(1.0) }))
                } else {
                    None
                };
                match op {
                    Some(op) => Node::Nary { op, children: kids() },
                    None => Node::Mix { from: *a, to: *b, s, children: kids() },
                }
            }
            GKind::Difference(a, b) => {
                let mut k = kids();
                let right = k.pop().expect("two children");
                let left = k.pop().expect("two children");
                Node::difference(left, right, lerp(*a, *b, s))
            }
            GKind::Warp(a, b, keyed) => {
                let w = if s <= 0.0 {
                    *a
                } else if s >= 1.0 {
                    *b
                } else if let Some(k) = keyed {
                    Warp::Affine(k.path.at(&k.a, &k.b, s).to_affine())
                } else {
                    a.lerp(b, s).unwrap_or(*a)
                };
                Node::Warp { warp: w, child: Box::new(kids().pop().expect("one child")) }
            }
        }
    }
}

impl GenericTree {
    /// Matches, decomposes and builds the generic tree of `a → b`.
    ///
    /// # Errors
    /// Link errors of [`decompose`]; [`BlobMorphError::InvalidSpeed`],
    /// [`BlobMorphError::InvalidTrajectory`], [`BlobMorphError::UnmatchedPair`] for
    /// bad speed curves and trajectories (handles must be finite with
    /// magnitudes ≤ [`MAX_MAGNITUDE`]).
    pub fn new(a: &BlobTree, b: &BlobTree, spec: &MorphSpec) -> Result<Self, BlobMorphError> {
        Self::built(a, b, spec, None)
    }

    /// [`GenericTree::new`]; with `known`, a tree of the same pair
    /// structure whose leaves' generic topologies hold for these ends too
    /// (reused, not rebuilt, where the skeletons' vertex counts agree).
    fn built(
        a: &BlobTree,
        b: &BlobTree,
        spec: &MorphSpec,
        known: Option<&GenericTree>,
    ) -> Result<Self, BlobMorphError> {
        let corr = Correspondence {
            links: spec.links.clone(),
            heuristic: spec.heuristic,
            phantoms: spec.phantoms.clone(),
        };
        let pair = decompose(a.root(), a.threshold(), b.root(), b.threshold(), &corr)?;
        let mut leaves = Vec::new();
        if let Some(k) = known {
            k.root.leaves(&mut leaves);
        }
        let mut topologies = leaves.into_iter().map(|l| Some(&*l.skeleton)).chain(std::iter::repeat(None));
        let mut root = build(&pair, spec.coplanar_frames, &mut topologies)?;
        // Later curves for the same node override earlier ones.
        let mut speeds: HashMap<_, Vec<usize>> = HashMap::new();
        for (k, sc) in spec.speeds.iter().enumerate() {
            if let Some(problem) = sc.speed.problem() {
                return Err(BlobMorphError::InvalidSpeed { a: sc.a.clone(), b: sc.b.clone(), problem });
            }
            speeds.entry((&sc.a, &sc.b)).or_default().push(k);
        }
        let (mut paired, mut matched) = (vec![false; spec.speeds.len()], vec![false; spec.speeds.len()]);
        for_matching(&mut root, &speeds, &mut |k, n| {
            paired[k] = true;
            if spec.speeds[k].warp.is_none_or(|w| n.half == Some(w)) {
                n.speed = spec.speeds[k].speed.clone();
                matched[k] = true;
            }
        });
        if let Some(k) = (0..spec.speeds.len()).find(|&k| !matched[k]) {
            let (a, b) = (spec.speeds[k].a.clone(), spec.speeds[k].b.clone());
            return Err(if paired[k] {
                let problem = "`warp` picks one of the two warps of a pair of different kinds (Fig. 16); \
                               these nodes are not such a pair";
                BlobMorphError::InvalidSpeed { a, b, problem }
            } else {
                BlobMorphError::UnmatchedPair { what: "speed curve", a, b }
            });
        }
        let mut trajectories: HashMap<_, Vec<usize>> = HashMap::new();
        let mut paths = Vec::with_capacity(spec.trajectories.len());
        for (k, tr) in spec.trajectories.iter().enumerate() {
            paths.push(FramePath::new(tr)?);
            trajectories.entry((&tr.a, &tr.b)).or_default().push(k);
        }
        let mut matched = vec![false; spec.trajectories.len()];
        // The kind of a matched generic node without a frame, per trajectory.
        let mut frameless: Vec<Option<&'static str>> = vec![None; spec.trajectories.len()];
        let mut failed = None;
        for_matching(&mut root, &trajectories, &mut |k, n| match &mut n.kind {
            GKind::Leaf(l) => {
                l.path = paths[k].clone();
                matched[k] = true;
            }
            GKind::Warp(Warp::Affine(ma), Warp::Affine(mb), keyed) => {
                let tr = &spec.trajectories[k];
                let parts = |m: &Affine3A| {
                    AffineParts::from_affine(m).map_err(|source| BlobMorphError::Transform {
                        a: tr.a.clone(),
                        b: tr.b.clone(),
                        source,
                    })
                };
                match (parts(ma), parts(mb)) {
                    (Ok(a), Ok(b)) => *keyed = Some(Box::new(AffinePath { a, b, path: paths[k].clone() })),
                    (Err(e), _) | (_, Err(e)) => failed = Some(e),
                }
                matched[k] = true;
            }
            GKind::Nary(op, _) => frameless[k] = frameless[k].or(Some(op.name())),
            GKind::Difference(..) => frameless[k] = frameless[k].or(Some("difference")),
            GKind::Warp(w, ..) => frameless[k] = frameless[k].or(Some(w.kind())),
        });
        if let Some(e) = failed {
            return Err(e);
        }
        if let Some(k) = (0..spec.trajectories.len()).find(|&k| !matched[k]) {
            let (a, b) = (spec.trajectories[k].a.clone(), spec.trajectories[k].b.clone());
            return Err(match frameless[k] {
                Some(kind) => BlobMorphError::FramelessTrajectory { a, b, kind },
                None => BlobMorphError::UnmatchedPair { what: "trajectory", a, b },
            });
        }
        Ok(Self { root, thresholds: (a.threshold(), b.threshold()), pair })
    }

    /// The overlapping decomposition `A'`, `B'` this tree interpolates.
    pub fn pair(&self) -> &Pair {
        &self.pair
    }

    /// The threshold `T(t)`.
    pub fn threshold_at(&self, t: f32) -> f32 {
        lerp(self.thresholds.0, self.thresholds.1, t)
    }

    /// The instantiated tree description at `t` (unchecked `t`).
    pub fn node_at(&self, t: f32) -> Node {
        self.root.at(t, false)
    }

    /// `C(t)` with a structure independent of `t` (mix nodes as blends of
    /// scaled operators; the same field as [`GenericTree::at`]).
    fn at_fixed(&self, t: f32) -> Result<BlobTree, BlobMorphError> {
        Ok(BlobTree::new(self.root.at(t, true), self.threshold_at(t))?)
    }

    /// The evaluable BlobTree `C(t)`.
    ///
    /// # Errors
    /// [`BlobMorphError::Morph`] for `t ∉ [0, 1]` or NaN; [`BlobMorphError::Blob`] if
    /// an instantiated node is invalid (not expected for valid inputs).
    pub fn at(&self, t: f32) -> Result<BlobTree, BlobMorphError> {
        let t = isomorph_common::check_time(t)?;
        Ok(BlobTree::new(self.node_at(t), self.threshold_at(t))?)
    }
}

/// A shape between the source and the target (`isomorph morph --via`): a
/// key shape the chained morph passes through or a control shape of the
/// Bézier-like morph ([`ViaMode`]), with the links spec of the pairwise
/// generic tree that arrives at it.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyShape {
    /// The shape.
    pub shape: BlobTree,
    /// The animator's controls of the segment from the previous key shape
    /// (or the source) to this one; node paths `a` name the previous
    /// shape's nodes, `b` this one's.
    pub spec: MorphSpec,
}

/// Settings of [`BlobMorph::new`]: the animator's controls.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlobSettings {
    /// Links, pairing heuristic, speed curves and trajectories of the
    /// segment that arrives at the target (the whole morph without `via`;
    /// default: the nearest-centre heuristic, no links); its `levels`
    /// (like those of the `via` specs) link a Bézier morph's upper levels.
    pub spec: MorphSpec,
    /// Key shapes between the source and the target (default none),
    /// combined as `via_mode` says.
    pub via: Vec<KeyShape>,
    /// How the morph uses the key shapes `via` (default: the paper's
    /// Bézier-like combination).
    pub via_mode: ViaMode,
}

/// How a morph through key shapes combines the pairwise generic trees
/// (`isomorph morph --via-mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViaMode {
    /// The paper's Bézier-like metamorphosis, "control knots replaced by
    /// control BlobTrees" (§1, §3): the generic trees of consecutive shapes
    /// combined by de Casteljau's construction ([`BlobMorph::bezier`]). The
    /// source and the target are reproduced; the shapes in between are
    /// control shapes, approached but (as Bézier control points) in general
    /// not reached.
    #[default]
    Bezier,
    /// The generic trees of consecutive shapes played one after the other
    /// ([`BlobMorph::through`]): the morph passes through every key shape,
    /// at evenly spaced times (continuous, with a change of speed at the
    /// keys). Not in the paper; an interpolating alternative.
    Chain,
}

/// The BlobTree metamorphosis as a [`Morph`]: frames are `C(t)` as fields
/// (`potential − T(t)`, iso 0, identity placement).
///
/// ```
/// use isomorph_blobtree::{BlobMorph, BlobSettings, scenes};
/// use isomorph_common::{Control, Morph, Solid};
/// use std::sync::Arc;
///
/// let sphere = Solid::implicit(Arc::new(scenes::load("sphere")?))?;
/// let torus = Solid::implicit(Arc::new(scenes::load("torus")?))?;
/// let morph = BlobMorph::new(&sphere, &torus, &BlobSettings::default(), &Control::new())?;
/// assert_eq!(morph.frame_mesh(1.0, 48)?.genus(), Some(1));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct BlobMorph {
    /// The generic trees from each key shape to the next (one without key shapes).
    segments: Vec<GenericTree>,
    /// How the segments combine.
    mode: ViaMode,
    /// Bézier mode: for each de Casteljau level `r ≥ 2` and each `i`, the
    /// correspondence between `P_i^{r−1}` and `P_{i+1}^{r−1}`, computed
    /// once so the morph is continuous in `t`.
    levels: Vec<Vec<LevelPair>>,
    bounds: Aabb,
    report: MorphReport,
}

/// The span of the generic tree of `pair` (a de Casteljau level above the
/// first, whose ends' spans over `t` are `a` and `b`) over `t`: every pair
/// takes its ends' ranges from the nodes its origin names (a phantom the
/// other end's, an inserted identity warp its own), blended over `s = t`.
fn level_span(pair: &Pair, a: &Span, b: &Span, t: Interval) -> Result<Span, BlobMorphError> {
    let origin = pair.origin();
    fn find<'s>(
        side: Side,
        tree: &'s Span,
        path: &Option<NodePath>,
    ) -> Result<Option<&'s Span>, BlobMorphError> {
        match path {
            None => Ok(None),
            Some(p) => {
                tree.at(&p.0).map(Some).ok_or_else(|| BlobMorphError::NoSuchNode { side, path: p.clone() })
            }
        }
    }
    let (na, nb) = (find(Side::Source, a, &origin.a)?, find(Side::Target, b, &origin.b)?);
    let rec = |p: &Pair| level_span(p, a, b, t).map(Box::new);
    Ok(match pair {
        Pair::Leaf { .. } => {
            let leaf = |n: Option<&Span>| match n {
                Some(Span::Leaf(p)) => Some(p.clone()),
                _ => None,
            };
            let missing = |side: Side, path: &Option<NodePath>| BlobMorphError::NoSuchNode {
                side,
                path: path.clone().unwrap_or_default(),
            };
            // A phantom has its partner's geometry.
            let pa = leaf(na).or(if origin.a.is_none() { leaf(nb) } else { None });
            let pb = leaf(nb).or(if origin.b.is_none() { leaf(na) } else { None });
            let pa = pa.ok_or_else(|| missing(Side::Source, &origin.a))?;
            let pb = pb.ok_or_else(|| missing(Side::Target, &origin.b))?;
            Span::Leaf(pa.iter().flat_map(|x| pb.iter().map(|y| PrimRange::lerp(x, y, t))).collect())
        }
        Pair::Nary { a: oa, b: ob, children, .. } => {
            let kids = children.iter().map(|c| level_span(c, a, b, t)).collect::<Result<Vec<_>, _>>()?;
            nary_span(*oa, *ob, t, true, kids)
        }
        Pair::Difference { left, right, .. } => Span::Difference(rec(left)?, rec(right)?),
        Pair::Warp { a: wa, b: wb, child, .. } => {
            // The node's own warp range if it is a warp of the pair's kind;
            // a phantom's is its partner's; otherwise an inserted identity.
            let range = |own: Option<&Span>, present: bool, other: Option<&Span>, w: &Warp| {
                let node = if present { own } else { other };
                match node {
                    Some(Span::Warp(r, _)) if r.kind() == w.kind() => Ok(*r),
                    _ => WarpRange::exact(w).map_err(|e| transform_error(origin, e)),
                }
            };
            let ra = range(na, origin.a.is_some(), nb, wa)?;
            let rb = range(nb, origin.b.is_some(), na, wb)?;
            let w = WarpRange::lerp(&ra, &rb, t).unwrap_or(ra);
            Span::Warp(w, rec(child)?)
        }
    })
}

/// The level links of every key shape's spec.
fn level_links(keys: &[KeyShape]) -> Vec<LevelLinks> {
    keys.iter().flat_map(|k| k.spec.levels.iter().cloned()).collect()
}

/// The correspondence of one pair of a de Casteljau level above the first.
#[derive(Debug, Clone)]
struct LevelPair {
    /// Its pairs as links (replayed at every `t`).
    spec: MorphSpec,
    /// Its generic tree between the shapes at `t = ½`: the pair tree (the
    /// same structure at every `t`) and the leaves' generic topologies,
    /// which hold at every `t` where the level-1 leaves are strictly
    /// between their ends: a Minkowski vertex `(i, j)` is extreme when the
    /// normal cones of `a_i` and `b_j` overlap, whatever the positive
    /// weights, and every level's skeletons are positive combinations of
    /// the same level-1 skeletons.
    generic: GenericTree,
}

/// Intervals of `t` per segment (per control shape beyond the source, for
/// a Bézier-like morph) over which the frames' supports are bounded.
const BOUND_INTERVALS: usize = 32;

/// The BlobTree inside `solid`, else [`isomorph_common::MorphError::UnsupportedInput`].
fn as_tree(solid: &Solid, side: Side) -> Result<&BlobTree, isomorph_common::MorphError> {
    solid.as_implicit().and_then(|i| i.as_any().downcast_ref::<BlobTree>()).ok_or(
        isomorph_common::MorphError::UnsupportedInput {
            method: "blobtree",
            side,
            kind: solid.kind(),
            hint: BLOBTREE_INPUT,
        },
    )
}

/// What a BlobTree morph takes instead of other solids.
const BLOBTREE_INPUT: &str = "a BlobTree scene (a built-in scene name or a .ron/.json scene file)";

impl BlobMorph {
    /// The morph between two solids that are BlobTrees
    /// ([`Solid::implicit`] of a [`BlobTree`], e.g. from [`crate::scenes::load`]).
    ///
    /// # Errors
    /// [`isomorph_common::MorphError::UnsupportedInput`] for any other
    /// solid, [`isomorph_common::MorphError::Cancelled`], and as
    /// [`BlobMorph::from_trees`].
    pub fn new(
        source: &Solid,
        target: &Solid,
        settings: &BlobSettings,
        control: &Control,
    ) -> Result<Self, BlobMorphError> {
        let (a, b) = (as_tree(source, Side::Source)?, as_tree(target, Side::Target)?);
        let warnings = isomorph_common::validate_inputs(source, target, control)?;
        let mut keys = settings.via.clone();
        keys.push(KeyShape { shape: b.clone(), spec: settings.spec.clone() });
        control.install(|| {
            let mut stages = Stages::start();
            control.progress("correspondence", None, String::new);
            control.check()?;
            let segments = Self::segments_of(a, &keys, control)?;
            let mut morph = Self::combined(segments, settings.via_mode, &level_links(&keys))?;
            stages.lap("correspondence");
            morph.bounds = morph.support(control)?;
            stages.lap("bounds");
            morph.report = morph.report.with_stages(stages).with_warnings(warnings);
            Ok(morph)
        })
    }

    /// The morph `a → b` under the animator's `spec` (the paper-level
    /// constructor, without a [`Control`]).
    ///
    /// # Errors
    /// As [`GenericTree::new`].
    pub fn from_trees(a: &BlobTree, b: &BlobTree, spec: &MorphSpec) -> Result<Self, BlobMorphError> {
        let generic = GenericTree::new(a, b, spec)?;
        Self::finished(vec![generic], ViaMode::Chain, &spec.levels)
    }

    /// The morph from `source` through the key shapes `keys` (the last is
    /// the target), built by combining pairwise generic trees (§1, §3:
    /// "genericity … enables us to combine several interpolations"): the
    /// generic tree `C_i` of key `i → i + 1` (under key `i + 1`'s spec)
    /// runs over `t ∈ [i/n, (i + 1)/n]` for `n` segments, so `C(i/n)` is
    /// exactly key shape `i` and the shape is continuous in `t`. Each
    /// segment keeps its own correspondence, speed curves and
    /// trajectories.
    ///
    /// # Errors
    /// [`isomorph_common::MorphError::BadSetting`] without key shapes;
    /// [`BlobMorphError::Segment`] wrapping the errors of
    /// [`GenericTree::new`] for the segment that failed.
    pub fn through(source: &BlobTree, keys: &[KeyShape]) -> Result<Self, BlobMorphError> {
        Self::finished(Self::segments_of(source, keys, &Control::new())?, ViaMode::Chain, &level_links(keys))
    }

    /// The Bézier-like morph (§1, §3: "combine interpolations together so
    /// as to define a Bézier-like metamorphosis where control knots are
    /// replaced by control BlobTree shapes") from `source` with the control
    /// shapes `controls` (the last is the target).
    ///
    /// With the shapes `P_0 = source, P_1, …, P_n`, the generic trees
    /// `C_i` of `P_i → P_{i+1}` (under `controls[i]`'s spec) are the first
    /// level of de Casteljau's construction, `P_i^1(t) = C_i(t)`; level `r`
    /// is the generic tree of the two shapes below it, instantiated at the
    /// same `t`: `P_i^r(t) = (P_i^{r−1}(t) → P_{i+1}^{r−1}(t))(t)`, and the
    /// morph is `C(t) = P_0^n(t)`. For convex skeletons and linear
    /// parameters this is the Bernstein form: the skeleton of a primitive
    /// matched through all the shapes is `⊕_i B_i^n(t) S_i` (Kaul &
    /// Rossignac's Bézier Minkowski combination), its intensity, radius,
    /// stiffness and exponent `Σ_i B_i^n(t) x_i`, the threshold likewise.
    /// `C(0)` is the source and `C(1)` the target; the inner shapes are
    /// control shapes, generally not reached.
    ///
    /// The correspondence of each level `r ≥ 2` is made once, on the
    /// shapes at `t = ½`, with the links the controls' specs give for it
    /// ([`LevelLinks`]) and by the nearest-centre heuristic elsewhere, and kept as links
    /// for every `t` (instances of a generic tree share one structure, mix
    /// nodes written as blends of scaled operators), so `C(t)` is
    /// continuous in `t`.
    ///
    /// # Errors
    /// As [`BlobMorph::through`]; a level's correspondence fails as
    /// [`GenericTree::new`], wrapped in [`BlobMorphError::Level`]; level
    /// links for a level or pair the morph does not have are
    /// [`isomorph_common::MorphError::BadSetting`] (as are any level links
    /// given to [`BlobMorph::through`] or [`BlobMorph::from_trees`]).
    pub fn bezier(source: &BlobTree, controls: &[KeyShape]) -> Result<Self, BlobMorphError> {
        Self::finished(
            Self::segments_of(source, controls, &Control::new())?,
            ViaMode::Bezier,
            &level_links(controls),
        )
    }

    /// The morph of `segments` combined as `mode` says, with its bounds and report.
    fn finished(
        segments: Vec<GenericTree>,
        mode: ViaMode,
        given: &[LevelLinks],
    ) -> Result<Self, BlobMorphError> {
        let mut morph = Self::combined(segments, mode, given)?;
        morph.bounds = morph.support(&Control::new())?;
        Ok(morph)
    }

    /// The morph of `segments` combined as `mode` says (Bézier: the
    /// correspondences of the de Casteljau levels, made at `t = ½` with the
    /// `given` links), bounds not yet computed.
    fn combined(
        segments: Vec<GenericTree>,
        mode: ViaMode,
        given: &[LevelLinks],
    ) -> Result<Self, BlobMorphError> {
        let n = segments.len();
        if let Some(l) = given
            .iter()
            .find(|l| mode != ViaMode::Bezier || !(2..=n).contains(&l.level) || l.pair > n - l.level)
        {
            let expected = if mode == ViaMode::Bezier && n > 1 {
                format!(
                    "a level from 2 to {n} and a pair from 0 to n − level (a Bézier morph through {} shapes)",
                    n + 1
                )
            } else {
                "no level links: they need a Bézier-like morph through control shapes (--via)".into()
            };
            return Err(isomorph_common::MorphError::BadSetting {
                name: "levels",
                value: format!("level {}, pair {}", l.level, l.pair),
                expected,
            }
            .into());
        }
        let mut levels = Vec::new();
        if mode == ViaMode::Bezier {
            let mut row = segments.iter().map(|g| g.at_fixed(0.5)).collect::<Result<Vec<_>, _>>()?;
            while row.len() > 1 {
                let level = levels.len() + 2;
                let (mut specs, mut next) = (Vec::new(), Vec::new());
                for (pair, w) in row.windows(2).enumerate() {
                    let links = given
                        .iter()
                        .filter(|l| (l.level, l.pair) == (level, pair))
                        .flat_map(|l| l.links.iter().cloned())
                        .collect();
                    let wrap = |e| BlobMorphError::Level { level, pair, source: Box::new(e) };
                    let corr = Correspondence { links, ..Correspondence::default() };
                    let (a, b) = (&w[0], &w[1]);
                    let matched =
                        decompose(a.root(), a.threshold(), b.root(), b.threshold(), &corr).map_err(wrap)?;
                    // The tree is built with the links every frame replays,
                    // so that its leaves come in the frames' order.
                    let spec = MorphSpec { links: links_of(&matched), ..MorphSpec::default() };
                    let generic = GenericTree::new(a, b, &spec).map_err(wrap)?;
                    next.push(generic.at_fixed(0.5)?);
                    specs.push(LevelPair { spec, generic });
                }
                levels.push(specs);
                row = next;
            }
        }
        let report = Self::report_of(&segments, mode);
        Ok(Self { segments, mode, levels, bounds: Aabb::EMPTY, report })
    }

    /// The generic tree of every segment `source → keys[0] → keys[1] → …`.
    fn segments_of(
        source: &BlobTree,
        keys: &[KeyShape],
        control: &Control,
    ) -> Result<Vec<GenericTree>, BlobMorphError> {
        if keys.is_empty() {
            return Err(isomorph_common::MorphError::BadSetting {
                name: "keys",
                value: "0".into(),
                expected: "at least one key shape (the target)".into(),
            }
            .into());
        }
        let mut from = source;
        let mut segments = Vec::with_capacity(keys.len());
        for (index, key) in keys.iter().enumerate() {
            control.check()?;
            let segment = GenericTree::new(from, &key.shape, &key.spec)
                .map_err(|e| BlobMorphError::Segment { index, source: Box::new(e) })?;
            segments.push(segment);
            from = &key.shape;
        }
        Ok(segments)
    }

    /// The segment that plays at `t ∈ [0, 1]` and its local time: segment
    /// `i` covers `[i/n, (i + 1)/n]`, and at a key time `i/n` (computed the
    /// same way) the local time is exactly 0.
    fn locate(&self, t: f32) -> (&GenericTree, f32) {
        let n = self.segments.len();
        let knot = |i: usize| i as f32 / n as f32;
        let i = (1..n).rev().find(|&i| t >= knot(i)).unwrap_or(0);
        let u = ((t - knot(i)) / (knot(i + 1) - knot(i))).clamp(0.0, 1.0);
        (&self.segments[i], u)
    }

    /// The Bézier-like `C(t)` by de Casteljau's construction (see
    /// [`BlobMorph::bezier`]).
    fn casteljau(&self, t: f32) -> Result<BlobTree, BlobMorphError> {
        let mut row = self.row(self.segments.len(), t)?;
        Ok(row.pop().expect("one shape is left"))
    }

    /// The shapes `P_i^level(t)` of de Casteljau level `level ≥ 1`.
    fn row(&self, level: usize, t: f32) -> Result<Vec<BlobTree>, BlobMorphError> {
        self.row_with(level, t, self.reuses_topologies(t))
    }

    /// Whether frames at `t` reuse the levels' generic topologies made at
    /// `t = ½` ([`LevelPair::generic`]): every level-1 leaf is at the same
    /// phase (at its source, between, at its target) at both instants, so
    /// its skeletons are the same polytope or the same generic one.
    fn reuses_topologies(&self, t: f32) -> bool {
        let phases = |t: f32| {
            let mut out = Vec::new();
            self.segments.iter().for_each(|g| g.root.leaf_phases(t, &mut out));
            out
        };
        phases(t) == phases(0.5)
    }

    /// [`BlobMorph::row`], reusing the generic topologies or not.
    fn row_with(&self, level: usize, t: f32, reuse: bool) -> Result<Vec<BlobTree>, BlobMorphError> {
        let mut row = self.segments.iter().map(|g| g.at_fixed(t)).collect::<Result<Vec<_>, _>>()?;
        for pairs in &self.levels[..level - 1] {
            row = row
                .windows(2)
                .zip(pairs)
                .map(|(w, p)| {
                    GenericTree::built(&w[0], &w[1], &p.spec, reuse.then_some(&p.generic))?.at_fixed(t)
                })
                .collect::<Result<_, _>>()?;
        }
        Ok(row)
    }

    /// The links the correspondence of pair `pair` of de Casteljau level
    /// `level ≥ 2` keeps for every `t` (the given [`LevelLinks`] and the
    /// pairs nearest centres made at `t = ½`); empty for a level or pair
    /// the morph does not have.
    pub fn level_links(&self, level: usize, pair: usize) -> &[Link] {
        level
            .checked_sub(2)
            .and_then(|r| self.levels.get(r)?.get(pair))
            .map_or(&[], |level| level.spec.links.as_slice())
    }

    /// The shapes `P_0^r(t) … P_{n−r}^r(t)` of de Casteljau level `r`
    /// (`level`, from 1 to `n`) of a Bézier-like morph through `n + 1`
    /// shapes ([`BlobMorph::bezier`]); level 1 is the pairwise generic
    /// trees. Their structure does not depend on `t` (mix nodes are written
    /// as blends of scaled operators): the node paths of
    /// [`LevelLinks`] for level `r + 1` name their nodes.
    ///
    /// # Errors
    /// [`isomorph_common::MorphError::InvalidTime`] for `t ∉ [0, 1]`;
    /// [`isomorph_common::MorphError::BadSetting`] for a level outside
    /// `1..=n` or a morph that is not Bézier-like.
    pub fn level_shapes(&self, level: usize, t: f32) -> Result<Vec<BlobTree>, BlobMorphError> {
        let t = isomorph_common::check_time(t)?;
        let n = self.segments.len();
        if self.mode != ViaMode::Bezier || !(1..=n).contains(&level) {
            return Err(isomorph_common::MorphError::BadSetting {
                name: "level",
                value: level.to_string(),
                expected: format!("1 to {n} in a Bézier-like morph"),
            }
            .into());
        }
        self.row(level, t)
    }

    /// `C(t)` for `t ∈ [0, 1]`.
    fn shape_at(&self, t: f32) -> Result<BlobTree, BlobMorphError> {
        match self.mode {
            ViaMode::Bezier if self.segments.len() > 1 => self.casteljau(t),
            _ => {
                let (segment, u) = self.locate(t);
                segment.at(u)
            }
        }
    }

    /// A box holding the support of `C(t)` for every `t ∈ [0, 1]`, padded
    /// by 5 %: the union of the swept supports ([`BlobMorph::swept`]) over
    /// [`BOUND_INTERVALS`] intervals per segment.
    fn support(&self, control: &Control) -> Result<Aabb, BlobMorphError> {
        let steps = BOUND_INTERVALS * self.segments.len();
        let mut bounds = Aabb::EMPTY;
        for i in 0..steps {
            let t = Interval::new(i as f32 / steps as f32, (i + 1) as f32 / steps as f32);
            control.progress("bounds", Some(t.lo), String::new);
            control.check()?;
            bounds = bounds.union(&self.swept(t)?);
        }
        Ok(bounds.padded(0.05))
    }

    /// A box holding the support of `C(t)` for every `t` in `t`, by
    /// construction (not by sampling): the ranges every parameter takes
    /// over the interval, through every de Casteljau level, pushed through
    /// the support rules ([`crate::sweep`]).
    fn swept(&self, t: Interval) -> Result<Aabb, BlobMorphError> {
        let n = self.segments.len();
        if self.mode == ViaMode::Bezier && n > 1 {
            let mut row =
                self.segments.iter().map(|g| g.root.span(t, true)).collect::<Result<Vec<_>, _>>()?;
            for (r, pairs) in self.levels.iter().enumerate() {
                row = row
                    .windows(2)
                    .zip(pairs)
                    .enumerate()
                    .map(|(pair, (w, p))| {
                        level_span(p.generic.pair(), &w[0], &w[1], t).map_err(|e| BlobMorphError::Level {
                            level: r + 2,
                            pair,
                            source: Box::new(e),
                        })
                    })
                    .collect::<Result<_, _>>()?;
            }
            return Ok(row[0].support());
        }
        // Segment `i` plays over `[i/n, (i + 1)/n]` at local time `n·t − i`.
        let mut bounds = Aabb::EMPTY;
        for (i, segment) in self.segments.iter().enumerate() {
            let local = |t: f32| (t * n as f32 - i as f32).clamp(0.0, 1.0);
            let (lo, hi) = (local(t.lo), local(t.hi));
            if lo < hi {
                bounds = bounds.union(&segment.root.span(Interval::new(lo, hi), false)?.support());
            }
        }
        Ok(bounds)
    }

    fn report_of(segments: &[GenericTree], mode: ViaMode) -> MorphReport {
        let leaves: usize = segments.iter().map(|g| g.pair().leaf_count()).sum();
        let report = MorphReport::new("blobtree", Outcome::Direct)
            .with_memory(leaves * size_of::<GLeaf>(), None)
            .with_detail("generic leaves", leaves);
        if segments.len() == 1 {
            return report;
        }
        let mode = match mode {
            ViaMode::Bezier => "bezier",
            ViaMode::Chain => "chain",
        };
        report.with_detail("key shapes", segments.len() + 1).with_detail("via mode", mode)
    }

    /// The generic tree of the first segment (of the whole morph when it
    /// has no key shapes in between).
    pub fn generic(&self) -> &GenericTree {
        &self.segments[0]
    }

    /// The pairwise generic trees, from each key (or control) shape to the
    /// next: the segments of a chained morph, the first de Casteljau level
    /// of a Bézier-like one.
    pub fn segments(&self) -> &[GenericTree] {
        &self.segments
    }
}

impl Morph for BlobMorph {
    type Field = BlobTree;
    type Error = BlobMorphError;

    fn method(&self) -> &'static str {
        "blobtree"
    }

    fn frame(&self, t: f32) -> Result<Frame<BlobTree>, BlobMorphError> {
        let field = self.shape_at(isomorph_common::check_time(t)?)?;
        Ok(Frame { field, iso: 0.0, transform: Affine3A::IDENTITY })
    }

    /// A box holding the support of every frame `C(t)`, `t ∈ [0, 1]`, by construction
    /// (interval bounds of every parameter over 32 intervals of `t` per segment, not
    /// samples), padded by 5 %.
    fn field_bounds(&self) -> Aabb {
        self.bounds
    }

    fn world_bounds(&self) -> Aabb {
        self.bounds
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil;
    use crate::{Kernel, Polytope};
    use isomorph_common::Field3;
    use proptest::prelude::*;
    use std::f32::consts::FRAC_PI_2;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

        /// C(0) ≡ A and C(1) ≡ B, in-between frames are finite, for random trees.
        #[test]
        fn endpoints_reproduce_the_inputs(a in testutil::tree(), b in testutil::tree()) {
            let (ta, tb) = (BlobTree::new(a, 0.5).unwrap(), BlobTree::new(b, 0.4).unwrap());
            let g = GenericTree::new(&ta, &tb, &MorphSpec::default()).unwrap();
            let (c0, c1) = (g.at(0.0).unwrap(), g.at(1.0).unwrap());
            let mid = g.at(0.37).unwrap();
            for p in testutil::points() {
                prop_assert!((c0.value(p) - ta.value(p)).abs() < 1e-5 * (1.0 + ta.value(p).abs()), "C(0) at {}", p);
                prop_assert!((c1.value(p) - tb.value(p)).abs() < 1e-5 * (1.0 + tb.value(p).abs()), "C(1) at {}", p);
                prop_assert!(mid.value(p).is_finite());
                prop_assert!(mid.gradient(p).is_finite());
            }
        }

        /// An in-between of random trees (mix nodes of every operator pair,
        /// Minkowski skeletons of every dimension) saved as a scene loads back
        /// into the same field.
        #[test]
        fn random_in_betweens_reload_to_the_same_field(a in testutil::tree(), b in testutil::tree(), t in 0.05f32..0.95) {
            let (ta, tb) = (BlobTree::new(a, 0.5).unwrap(), BlobTree::new(b, 0.4).unwrap());
            let frame = GenericTree::new(&ta, &tb, &MorphSpec::default()).unwrap().at(t).unwrap();
            // (An in-between may have no inside; a scene file must have one.)
            prop_assume!(frame.root().peak_bound() > frame.threshold());
            let text = frame.to_ron().unwrap();
            let again = BlobTree::from_ron(&text).unwrap();
            for p in testutil::points() {
                let (v, w) = (frame.value(p), again.value(p));
                prop_assert!((v - w).abs() <= 1e-6 * (1.0 + v.abs()), "at {}: {} vs {}\n{}", p, v, w, text);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

        /// The Bézier-like morph through a random control tree (mix nodes of
        /// every operator pair written as blends of scaled operators at the
        /// higher level) starts at the source and ends at the target; its
        /// in-betweens are finite.
        #[test]
        fn bezier_endpoints_reproduce_random_trees(a in testutil::tree(), b in testutil::tree(), c in testutil::tree()) {
            let (ta, tb, tc) =
                (BlobTree::new(a, 0.5).unwrap(), BlobTree::new(b, 0.4).unwrap(), BlobTree::new(c, 0.45).unwrap());
            let key = |t: &BlobTree| KeyShape { shape: t.clone(), spec: MorphSpec::default() };
            let m = BlobMorph::bezier(&ta, &[key(&tb), key(&tc)]).unwrap();
            let (c0, c1, mid) = (m.frame(0.0).unwrap().field, m.frame(1.0).unwrap().field, m.frame(0.37).unwrap().field);
            for p in testutil::points() {
                prop_assert!((c0.value(p) - ta.value(p)).abs() < 1e-5 * (1.0 + ta.value(p).abs()), "C(0) at {}", p);
                prop_assert!((c1.value(p) - tc.value(p)).abs() < 1e-5 * (1.0 + tc.value(p).abs()), "C(1) at {}", p);
                prop_assert!(mid.value(p).is_finite());
            }
        }

    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

        /// The bounds of a Bézier morph through three random trees (every
        /// node kind, bends interpolated from rate 0 included) hold the
        /// support of the frame at every instant sampled densely in each
        /// bounding interval: its ends and two inner instants. (Sampled
        /// bounds once missed a frame between samples here: the recorded
        /// regression seed of this file, support ±80.6 against ±74.7.)
        #[test]
        fn bezier_bounds_hold_every_frame(a in testutil::tree(), b in testutil::tree(), c in testutil::tree()) {
            let trees = [(a, 0.5), (b, 0.4), (c, 0.45)].map(|(n, t)| BlobTree::new(n, t).unwrap());
            let keys: Vec<KeyShape> =
                trees[1..].iter().map(|t| KeyShape { shape: t.clone(), spec: MorphSpec::default() }).collect();
            let m = BlobMorph::bezier(&trees[0], &keys).unwrap();
            prop_assert!(frames_are_held(&m, &[0.0, 0.137, 0.61, 1.0]).is_ok(), "{:?}", frames_are_held(&m, &[0.0, 0.137, 0.61, 1.0]));
        }

        /// The same for the plain two-shape morph.
        #[test]
        fn generic_bounds_hold_every_frame(a in testutil::tree(), b in testutil::tree()) {
            let (ta, tb) = (BlobTree::new(a, 0.5).unwrap(), BlobTree::new(b, 0.4).unwrap());
            let m = BlobMorph::from_trees(&ta, &tb, &MorphSpec::default()).unwrap();
            let check = frames_are_held(&m, &[0.0, 0.03, 0.29, 0.5, 0.77, 1.0]);
            prop_assert!(check.is_ok(), "{:?}", check);
        }
    }

    /// Checks that the swept bound of every bounding interval, and the
    /// morph's bounds, hold the frame supports at the instants `lo + f·(hi − lo)`
    /// for every fraction `f` in `fractions`.
    fn frames_are_held(m: &BlobMorph, fractions: &[f32]) -> Result<(), String> {
        let steps = BOUND_INTERVALS * m.segments.len();
        for i in 0..steps {
            let t = Interval::new(i as f32 / steps as f32, (i + 1) as f32 / steps as f32);
            let swept = m.swept(t).map_err(|e| e.to_string())?;
            let slack = 1e-5 * (1.0 + swept.min.abs().max(swept.max.abs()).max_element());
            for f in fractions {
                let u = (t.lo + f * (t.hi - t.lo)).min(1.0);
                let real = m.shape_at(u).map_err(|e| e.to_string())?.support();
                if !holds(&swept.expanded(slack), &real) || !holds(&m.field_bounds(), &real) {
                    return Err(format!("t = {u}: {real:?} outside {swept:?} / {:?}", m.field_bounds()));
                }
            }
        }
        Ok(())
    }

    /// A bend matched with no warp interpolates from the identity (rate 0,
    /// §4.3): near t = 0 the frames are nearly straight. Their supports
    /// stay near the inputs' (a bend's image box no longer grows like
    /// 1/rate), and the bounds hold every frame near 0, where sampled
    /// bounds missed them.
    #[test]
    fn bends_from_the_identity_are_bounded_near_the_start() {
        let ball = |x: f32| {
            Node::Primitive(Primitive::new(
                Skeleton::Point(Vec3::new(x, 0.3, 0.0)),
                Kernel::new(1.0, 0.6, 1.0),
            ))
        };
        let a = BlobTree::new(ball(0.0), 0.5).unwrap();
        let bend = Warp::bend(0.49, 0.0, -0.8, 0.8);
        let b = BlobTree::new(Node::warp(bend, ball(0.2)), 0.5).unwrap();
        let m = BlobMorph::from_trees(&a, &b, &MorphSpec::default()).unwrap();
        let reach = |b: &Aabb| b.min.abs().max(b.max.abs()).max_element();
        for t in [1e-6, 1e-4, 0.002, 0.013, 0.03, 0.2, 0.5] {
            let support = m.shape_at(t).unwrap().support();
            assert!(reach(&support) < 2.0, "t = {t}: {support:?}");
            assert!(holds(&m.field_bounds(), &support), "t = {t}");
        }
        assert!(reach(&m.field_bounds()) < 2.5, "{:?}", m.field_bounds());
        frames_are_held(&m, &[0.0, 0.01, 0.5, 1.0]).unwrap();
    }

    /// Three de Casteljau levels (four control shapes: a box, a segment, a
    /// triangle and a point, each turned and moved): the swept bounds of
    /// the levels above the second hold every frame.
    #[test]
    fn bezier_bounds_hold_through_three_levels() {
        let shape = |node: &str, axis: &str, degrees: f32, at: &str| {
            BlobTree::from_ron(&format!(
                "(root: (kind: \"blend\", children: [{node}, (kind: \"point\", vertices: [(0, 0, 0)], radius: 0.5,                  frame: (translate: {at}, rotate: (axis: {axis}, degrees: {degrees})))]))"
            ))
            .unwrap()
        };
        let trees = [
            shape(r#"(kind: "box", half: (0.4, 0.1, 0.2), radius: 0.3)"#, "(0, 0, 1)", 30.0, "(0.5, 0, 0)"),
            shape(
                r#"(kind: "segment", vertices: [(0, -0.5, 0), (0, 0.5, 0.2)], radius: 0.4, frame: (rotate: (axis: (1, 1, 0), degrees: 70)))"#,
                "(1, 0, 0)",
                80.0,
                "(0, 0.6, 0)",
            ),
            shape(
                r#"(kind: "polygon", vertices: [(0, 0, 0), (0.6, 0, 0), (0, 0.5, 0.1)], radius: 0.3, frame: (translate: (0, 0, 1)))"#,
                "(0, 1, 0)",
                150.0,
                "(-0.4, 0, 0.2)",
            ),
            shape(
                r#"(kind: "point", vertices: [(0.2, 0.3, 0)], radius: 0.6)"#,
                "(0, 0, 1)",
                -90.0,
                "(0, -0.5, 0)",
            ),
        ];
        let keys: Vec<KeyShape> =
            trees[1..].iter().map(|t| KeyShape { shape: t.clone(), spec: MorphSpec::default() }).collect();
        let m = BlobMorph::bezier(&trees[0], &keys).unwrap();
        assert_eq!(m.levels.len(), 2);
        frames_are_held(&m, &[0.0, 0.3, 0.71, 1.0]).unwrap();
    }

    /// Matched twists, tapers and bends about different axes (§4.4): the
    /// generic warps turn their axes (the root twist's half way at
    /// `t = ½`, its rate linear), the swept bounds hold every frame of the
    /// two-shape morph and of a Bézier-like morph through a third shape
    /// with other axes (de Casteljau levels blend ranges of axes), and
    /// saved frames reload to the same field through RON and JSON.
    #[test]
    fn warps_about_different_axes_morph_within_their_bounds() {
        let shape = |twist: &str, taper: &str, bend: &str| {
            BlobTree::from_ron(&format!(
                r#"(root: (kind: "twist", {twist}, children: [(kind: "blend", children: [
                    (kind: "taper", {taper}, children: [
                        (kind: "segment", vertices: [(0.3, 0, -0.6), (0.3, 0, 0.6)], radius: 0.4)]),
                    (kind: "bend", min: -0.7, max: 0.7, {bend}, children: [
                        (kind: "segment", vertices: [(-0.3, -0.6, 0), (-0.3, 0.6, 0.1)], radius: 0.4)]),
                ])]))"#
            ))
            .unwrap()
        };
        let a = shape("rate: 2", "slope: -0.4", "rate: 0.8");
        let b = shape(
            "rate: -1, axis: (2, 0, 0)",
            "slope: 0.5, axis: (0, 1, 1)",
            "rate: -0.6, axis: (1, 0, 0), along: (0, 0, 1)",
        );
        let c = shape(
            "rate: 1, axis: (0, 1, 0)",
            "slope: 0.3, axis: (1, 1, 0)",
            "rate: 0.5, axis: (0, 1, 0), along: (1, 0, 0)",
        );
        let g = GenericTree::new(&a, &b, &MorphSpec::default()).unwrap();
        let Node::Warp { warp: Warp::Twist { rate, axis }, .. } = g.node_at(0.5) else { panic!() };
        assert!((rate - 0.5).abs() < 1e-6, "{rate}");
        assert!((axis - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-5, "{axis}");
        let m = BlobMorph::from_trees(&a, &b, &MorphSpec::default()).unwrap();
        frames_are_held(&m, &[0.0, 0.1, 0.37, 0.5, 0.81, 1.0]).unwrap();
        let keys = [c, b].map(|shape| KeyShape { shape, spec: MorphSpec::default() });
        let bezier = BlobMorph::bezier(&a, &keys).unwrap();
        frames_are_held(&bezier, &[0.0, 0.3, 0.71, 1.0]).unwrap();
        for t in [0.2, 0.5, 0.77] {
            let frame = g.at(t).unwrap();
            let ron = BlobTree::from_ron(&frame.to_ron().unwrap()).unwrap();
            let json = BlobTree::from_json(&frame.to_json().unwrap()).unwrap();
            for p in testutil::points() {
                let v = frame.value(p);
                assert!(
                    (ron.value(p) - v).abs() <= 1e-6 && (json.value(p) - v).abs() <= 1e-6,
                    "t = {t} at {p}"
                );
            }
        }
    }

    /// `outer` holds `inner` (an empty box is held by any).
    fn holds(outer: &Aabb, inner: &Aabb) -> bool {
        inner.is_empty() || (outer.contains(inner.min) && outer.contains(inner.max))
    }

    /// Links given for de Casteljau level 2 are honoured: three shapes of
    /// two points each (at x = ±1); by nearest centres level 2 pairs
    /// each point with the one on its side, with the given crossed links
    /// each with the one opposite, so at t = ½ both points meet at the
    /// origin. The paths are those of the level-1 shapes as written to a
    /// scene file. Bad level links are refused with the level named.
    #[test]
    fn level_links_are_honoured() {
        let pair = BlobTree::from_ron(
            r#"(root: (kind: "blend", children: [
                (kind: "point", vertices: [(-1, 0, 0)], radius: 1),
                (kind: "point", vertices: [(1, 0, 0)], radius: 1)]))"#,
        )
        .unwrap();
        let key = |spec: MorphSpec| KeyShape { shape: pair.clone(), spec };
        let automatic =
            BlobMorph::bezier(&pair, &[key(MorphSpec::default()), key(MorphSpec::default())]).unwrap();
        let crossed = MorphSpec::from_ron(
            "(levels: [(level: 2, pair: 0, links: [(a: [0], b: [1]), (a: [1], b: [0])])])",
        )
        .unwrap();
        let m = BlobMorph::bezier(&pair, &[key(MorphSpec::default()), key(crossed.clone())]).unwrap();
        let recorded = &m.levels[0][0].spec.links;
        for (a, b) in [(0, 1), (1, 0)] {
            assert!(recorded.contains(&Link { a: NodePath(vec![a]), b: NodePath(vec![b]) }), "{recorded:?}");
        }
        assert!(
            !automatic.levels[0][0].spec.links.contains(&Link { a: NodePath(vec![0]), b: NodePath(vec![1]) })
        );
        // The level-1 shapes keep their paths when written and read back.
        for shape in m.level_shapes(1, 0.3).unwrap() {
            let text = shape.to_ron().unwrap();
            let again = BlobTree::from_ron(&text).unwrap();
            assert_eq!(again.to_ron().unwrap(), text);
            assert!(again.root().get(&NodePath(vec![1])).is_some());
            assert!(testutil::points().into_iter().all(|p| (again.value(p) - shape.value(p)).abs() < 1e-6));
        }
        let mid = |m: &BlobMorph| m.frame(0.5).unwrap().field.potential(Vec3::ZERO);
        assert!((mid(&m) - 2.0).abs() < 1e-5, "{}", mid(&m));
        assert!(mid(&automatic) < 0.5, "{}", mid(&automatic));
        // The ends are kept; the morph is continuous.
        for p in testutil::points() {
            assert!((m.frame(0.0).unwrap().field.value(p) - pair.value(p)).abs() < 1e-6);
            assert!((m.frame(1.0).unwrap().field.value(p) - pair.value(p)).abs() < 1e-6);
        }
        // Bad level links.
        let error = |spec: &str, mode: ViaMode| {
            let spec = MorphSpec::from_ron(spec).unwrap();
            let keys = [key(MorphSpec::default()), key(spec)];
            match mode {
                ViaMode::Bezier => BlobMorph::bezier(&pair, &keys),
                ViaMode::Chain => BlobMorph::through(&pair, &keys),
            }
            .unwrap_err()
        };
        let e = error("(levels: [(level: 2, pair: 0, links: [(a: [2], b: [0])])])", ViaMode::Bezier);
        assert!(
            matches!(&e, BlobMorphError::Level { level: 2, pair: 0, source } if matches!(**source, BlobMorphError::NoSuchNode { .. })),
            "{e:?}"
        );
        for bad in
            ["(levels: [(level: 3, pair: 0, links: [])])", "(levels: [(level: 2, pair: 1, links: [])])"]
        {
            let e = error(bad, ViaMode::Bezier).to_string();
            assert!(e.contains("levels") && e.contains("from 2 to 2"), "{e}");
        }
        let e = error("(levels: [(level: 2, pair: 0, links: [])])", ViaMode::Chain).to_string();
        assert!(e.contains("Bézier"), "{e}");
        assert!(BlobMorph::from_trees(&pair, &pair, &crossed).is_err());
        assert!(m.level_shapes(2, 0.5).unwrap().len() == 1 && m.level_shapes(3, 0.5).is_err());
    }

    /// The Bézier-like rook → queen → bear of the demo (the queen with its
    /// built-in links).
    fn rook_queen_bear() -> BlobMorph {
        let keys = [
            KeyShape {
                shape: crate::scenes::queen(),
                spec: crate::scenes::demo_spec("rook", "queen").unwrap(),
            },
            KeyShape { shape: crate::scenes::bear(), spec: MorphSpec::default() },
        ];
        BlobMorph::bezier(&crate::scenes::rook(), &keys).unwrap()
    }

    /// The built-in rook → queen → bear Bézier morph: the swept bounds hold
    /// the frames' supports (in every fourth bounding interval, at its start
    /// and middle) and are not much larger than the frames' supports are.
    #[test]
    fn bezier_bounds_of_scenes_hold_the_frames() {
        let m = rook_queen_bear();
        let steps = BOUND_INTERVALS * m.segments.len();
        let mut seen = Aabb::EMPTY;
        for i in (0..steps).step_by(4) {
            let t = Interval::new(i as f32 / steps as f32, (i + 1) as f32 / steps as f32);
            let swept = m.swept(t).unwrap();
            for u in [t.lo, t.mid()] {
                let real = m.shape_at(u).unwrap().support();
                assert!(
                    holds(&swept.expanded(1e-5 * (1.0 + swept.diagonal())), &real),
                    "t = {u}: {real:?} outside {swept:?}"
                );
                assert!(holds(&m.field_bounds(), &real), "t = {u}");
                seen = seen.union(&real);
            }
        }
        let (bound, sampled) = (m.field_bounds().diagonal(), seen.padded(0.05).diagonal());
        assert!(bound <= 1.2 * sampled, "bounds diagonal {bound} against the sampled frames' {sampled}");
    }

    /// Frames of the Bézier-like rook → queen → bear built on the level-2
    /// generic topologies made at `t = ½` are the frames built from scratch.
    #[test]
    fn reused_topologies_give_the_same_frames() {
        let m = rook_queen_bear();
        let b = m.world_bounds();
        let reused: Vec<f32> = (1..20).map(|k| k as f32 / 20.0).filter(|&t| m.reuses_topologies(t)).collect();
        assert!(reused.len() >= 3, "{reused:?}");
        for t in reused {
            let reused = m.row_with(2, t, true).unwrap().pop().unwrap();
            let built = m.row_with(2, t, false).unwrap().pop().unwrap();
            for i in 0..400 {
                let u = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
                let p = b.center() + b.size() * 0.5 * u;
                assert!((reused.value(p) - built.value(p)).abs() < 1e-5, "t = {t} at {p}");
            }
        }
        assert!(!m.reuses_topologies(0.0) && !m.reuses_topologies(1.0));
    }

    /// §1 "genericity": `C(t)` saved as a scene file at any `t` loads back
    /// into the same field (mix nodes, Minkowski skeletons, interpolated
    /// warps, frames and thresholds included), for every built-in morph.
    #[test]
    fn intermediate_shapes_save_and_reload_to_the_same_field() {
        for name in crate::scenes::DEMOS {
            let (a, b, spec) = crate::scenes::demo(name).unwrap();
            let g = GenericTree::new(&a, &b, &spec).unwrap();
            let support = g.at(0.5).unwrap().support();
            for t in [0.0, 0.1, 0.37, 0.5, 0.81, 1.0] {
                let frame = g.at(t).unwrap();
                let ron = BlobTree::from_ron(&frame.to_ron().unwrap()).unwrap();
                let json = BlobTree::from_json(&frame.to_json().unwrap()).unwrap();
                assert_eq!(ron.threshold(), frame.threshold());
                let mut worst = 0.0f32;
                for i in 0..2000 {
                    let u = Vec3::new(
                        (i as f32 * 0.377).sin(),
                        (i as f32 * 0.613).cos(),
                        (i as f32 * 0.231).sin(),
                    ) * 0.5
                        + 0.5;
                    let p = support.min + (support.max - support.min) * u;
                    let v = frame.value(p);
                    worst = worst.max((ron.value(p) - v).abs()).max((json.value(p) - v).abs());
                }
                assert!(worst <= 1e-6, "{name} at t = {t}: reloaded field differs by {worst}");
            }
        }
    }

    /// The Bézier-like morph through control shapes (§1, §3) against the
    /// Bernstein form computed here from the control primitives alone:
    /// skeleton `⊕ B_i^n(t) S_i` (the hull of the weighted vertex sums),
    /// intensity, radius, stiffness and threshold `Σ B_i^n(t) x_i`; for
    /// three and four control shapes. The ends are the source and the
    /// target; an inner control shape is approached, not reached.
    #[test]
    fn bezier_morph_is_the_bernstein_combination_of_its_control_primitives() {
        let shape = |skeleton: Skeleton, kernel: Kernel, at: Vec3, threshold: f32| {
            let p = Primitive::new(skeleton, kernel).with_frame(Affine3A::from_translation(at));
            BlobTree::new(Node::Primitive(p), threshold).unwrap()
        };
        let controls = [
            (
                Skeleton::Segment(Vec3::new(-0.3, 0.0, 0.0), Vec3::new(0.3, 0.0, 0.0)),
                Kernel::new(1.0, 0.8, 0.5),
                Vec3::ZERO,
                0.5,
            ),
            (
                Skeleton::Polygon(vec![
                    Vec3::new(-0.2, -0.1, 0.0),
                    Vec3::new(0.25, -0.1, 0.0),
                    Vec3::new(0.0, 0.3, 0.0),
                ]),
                Kernel::new(1.4, 0.6, 1.0),
                Vec3::new(0.1, 0.5, 0.0),
                0.4,
            ),
            (
                Skeleton::cuboid(Vec3::new(0.1, 0.2, 0.15)),
                Kernel::new(0.9, 0.7, 0.2),
                Vec3::new(0.2, -0.1, 0.3),
                0.55,
            ),
            (Skeleton::Point(Vec3::ZERO), Kernel::new(1.2, 0.9, 0.0), Vec3::new(-0.3, 0.1, -0.2), 0.45),
        ];
        let shapes: Vec<BlobTree> =
            controls.iter().map(|(s, k, at, th)| shape(s.clone(), *k, *at, *th)).collect();
        let points: Vec<Vec3> = (0..400)
            .map(|i| {
                Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin()) * 0.9
            })
            .collect();
        for count in [3, 4] {
            let n = count - 1;
            let keys: Vec<KeyShape> = shapes[1..count]
                .iter()
                .map(|s| KeyShape { shape: s.clone(), spec: MorphSpec::default() })
                .collect();
            let m = BlobMorph::bezier(&shapes[0], &keys).unwrap();
            let binomial = |i: usize| (1..=i).fold(1.0f32, |b, j| b * (n + 1 - j) as f32 / j as f32);
            for t in [0.0f32, 0.2, 0.5, 0.77, 1.0] {
                let w: Vec<f32> = (0..count)
                    .map(|i| binomial(i) * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32))
                    .collect();
                // Every weighted sum of one vertex (in world coordinates) per control skeleton.
                let mut sums = vec![Vec3::ZERO];
                for (i, (s, _, at, _)) in controls[..count].iter().enumerate() {
                    let (verts, wi) = (s.vertices(), w[i]);
                    sums =
                        sums.iter().flat_map(|&p| verts.iter().map(move |&v| p + wi * (v + *at))).collect();
                }
                let blend = |f: &dyn Fn(&Kernel) -> f32| -> f32 {
                    controls[..count].iter().zip(&w).map(|(c, wi)| wi * f(&c.1)).sum()
                };
                let kernel =
                    Kernel::new(blend(&|k| k.intensity), blend(&|k| k.radius), blend(&|k| k.stiffness));
                let threshold: f32 = controls[..count].iter().zip(&w).map(|(c, wi)| wi * c.3).sum();
                let expected = BlobTree::new(
                    Node::Primitive(Primitive::new(Skeleton::Generic(Polytope::hull(&sums)), kernel)),
                    threshold,
                )
                .unwrap();
                let frame = m.frame(t).unwrap().field;
                assert!((frame.threshold() - threshold).abs() < 1e-6, "{count} shapes, t = {t}");
                for &p in &points {
                    let (v, e) = (frame.value(p), expected.value(p));
                    assert!((v - e).abs() < 1e-5, "{count} shapes, t = {t}, at {p}: {v} vs Bernstein {e}");
                }
                if t == 0.0 || t == 1.0 {
                    let end = if t == 0.0 { &shapes[0] } else { &shapes[n] };
                    for &p in &points {
                        assert!((frame.value(p) - end.value(p)).abs() < 1e-6, "{count} shapes, end t = {t}");
                    }
                }
            }
            // The first control shape is not reached at its chained time 1/n.
            let near = m.frame(1.0 / n as f32).unwrap().field;
            let gap =
                points.iter().map(|&p| (near.value(p) - shapes[1].value(p)).abs()).fold(0.0f32, f32::max);
            assert!(gap > 0.05, "{count} shapes: the control shape is interpolated ({gap})");
        }
    }

    /// The Bézier-like morph of built-in scenes (rook, queen as the control
    /// shape, bear): the source and target at the ends, the level-2 generic
    /// tree of the two pairwise instances at `t = ½`, saved in-betweens
    /// reload to the same field, and `C(t)` is continuous in `t`.
    #[test]
    fn bezier_morph_of_scenes_reproduces_the_ends_and_is_continuous() {
        use crate::scenes;
        let (source, control, target) =
            (scenes::load("rook").unwrap(), scenes::load("queen").unwrap(), scenes::load("bear").unwrap());
        let keys = [
            KeyShape { shape: control.clone(), spec: scenes::demo_spec("rook", "queen").unwrap() },
            KeyShape { shape: target.clone(), spec: MorphSpec::default() },
        ];
        let m = BlobMorph::bezier(&source, &keys).unwrap();
        let chain = BlobMorph::through(&source, &keys).unwrap();
        let bounds = m.world_bounds();
        let points: Vec<Vec3> = (0..600)
            .map(|i| {
                let u = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin());
                bounds.min + (bounds.max - bounds.min) * (u * 0.5 + 0.5)
            })
            .collect();
        let gap = |x: &BlobTree, y: &BlobTree| {
            points.iter().map(|&p| (x.value(p) - y.value(p)).abs()).fold(0.0, f32::max)
        };
        assert!(gap(&m.frame(0.0).unwrap().field, &source) < 1e-6);
        assert!(gap(&m.frame(1.0).unwrap().field, &target) < 1e-6);
        // De Casteljau at t = ½: the generic tree of the instances C_01(½), C_12(½).
        let half = |g: &GenericTree| g.at(0.5).unwrap();
        let level2 =
            GenericTree::new(&half(&m.segments()[0]), &half(&m.segments()[1]), &MorphSpec::default())
                .unwrap()
                .at(0.5)
                .unwrap();
        let mid = m.frame(0.5).unwrap().field;
        assert!(gap(&mid, &level2) < 1e-6, "C(½) is not the de Casteljau combination");
        assert!(gap(&mid, &control) > 0.05, "the control shape is interpolated");
        assert!(gap(&mid, &chain.frame(0.5).unwrap().field) > 0.05, "the same as the chained morph");
        for t in [0.13, 0.5, 0.81] {
            let frame = m.frame(t).unwrap().field;
            let again = BlobTree::from_ron(&frame.to_ron().unwrap()).unwrap();
            assert!(gap(&frame, &again) <= 1e-6, "saved in-between at t = {t}");
        }
        for k in 0..=10 {
            let t = (k as f32 / 10.0).min(1.0 - 1e-3);
            let (x, y) = (m.frame(t).unwrap().field, m.frame(t + 1e-3).unwrap().field);
            assert!(gap(&x, &y) < 2e-2, "jump between t = {t} and {}: {}", t + 1e-3, gap(&x, &y));
        }
        assert!(
            matches!(m.report().details.get("via mode"), Some(isomorph_common::Value::Text(s)) if s == "bezier")
        );
    }

    /// A morph through key shapes (`--via`) is each key shape exactly at
    /// its time `i/n`, the source and target at the ends, and continuous
    /// across the keys; a failing segment is named.
    #[test]
    fn key_shapes_are_reproduced_at_their_times() {
        use crate::scenes;
        let key = |name: &str, spec: MorphSpec| KeyShape { shape: scenes::load(name).unwrap(), spec };
        let spec = |a: &str, b: &str| scenes::demo_spec(a, b).unwrap_or_default();
        let source = scenes::load("rook").unwrap();
        let keys = [
            key("queen", spec("rook", "queen")),
            key("bear", MorphSpec::default()),
            key("rounded_cube", MorphSpec::default()),
        ];
        let m = BlobMorph::through(&source, &keys).unwrap();
        assert_eq!(m.segments().len(), 3);
        let shapes = [&source, &keys[0].shape, &keys[1].shape, &keys[2].shape];
        let points: Vec<Vec3> = (0..500)
            .map(|i| Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.23).sin()))
            .collect();
        for (i, shape) in shapes.iter().enumerate() {
            let t = i as f32 / 3.0;
            let frame = m.frame(t).unwrap().field;
            assert_eq!(frame.threshold(), shape.threshold());
            for &p in &points {
                assert!((frame.value(p) - shape.value(p)).abs() < 1e-6, "key {i} at t = {t}, {p}");
            }
        }
        // Continuous across a key: just before and after t = 1/3 both
        // approach the queen.
        let (before, after) =
            (m.frame(1.0 / 3.0 - 1e-4).unwrap().field, m.frame(1.0 / 3.0 + 1e-4).unwrap().field);
        for &p in &points {
            assert!((before.value(p) - after.value(p)).abs() < 1e-2, "at {p}");
        }
        // The same morph through the Morph constructor and the settings' via.
        let settings =
            BlobSettings { spec: MorphSpec::default(), via: keys[..2].to_vec(), via_mode: ViaMode::Chain };
        let solid = |t: &BlobTree| Solid::implicit(std::sync::Arc::new(t.clone())).unwrap();
        let boxed =
            BlobMorph::new(&solid(&source), &solid(&keys[2].shape), &settings, &Control::new()).unwrap();
        assert!(matches!(boxed.report().details.get("key shapes"), Some(isomorph_common::Value::Int(4))));
        for &p in points.iter().step_by(10) {
            assert_eq!(boxed.frame(0.2).unwrap().field.value(p), m.frame(0.2).unwrap().field.value(p));
        }
        assert!(m.world_bounds().contains(Vec3::ZERO));
        // A bad link in the second segment is named by its segment.
        let bad = MorphSpec {
            links: vec![Link { a: NodePath(vec![7]), b: NodePath::root() }],
            ..MorphSpec::default()
        };
        let keys = [key("queen", MorphSpec::default()), key("bear", bad)];
        let e = BlobMorph::through(&source, &keys).unwrap_err();
        assert!(matches!(e, BlobMorphError::Segment { index: 1, .. }), "{e:?}");
        assert_eq!(e.to_string(), "segment 1 of the morph (key shape 1 → 2)");
        assert!(BlobMorph::through(&source, &[]).is_err());
    }

    /// Fig. 17: the animator places and sizes the phantom the rounded cube
    /// gets for the pierced sphere's boxes; the ends stay the inputs, the
    /// in-betweens change, and bad phantom parameters are named errors.
    #[test]
    fn phantom_parameters_place_and_size_the_phantom() {
        let (a, b, _) = crate::scenes::demo("cube_sphere").unwrap();
        let spec = MorphSpec::from_ron(
            "(phantoms: [(target: [1], position: (0.2, 0, 0), radius: 0.3, stiffness: 2)])",
        )
        .unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        let plain = GenericTree::new(&a, &b, &MorphSpec::default()).unwrap();
        // A' = cube − phantom(boxes): the phantom boxes are moved by 0.2 along x and resized.
        let Node::Difference { right, .. } = g.pair().side(crate::Side::Source) else {
            panic!("a difference")
        };
        let Node::Difference { right: before, .. } = plain.pair().side(crate::Side::Source) else { panic!() };
        assert_eq!(right.leaf_count(), 3);
        assert!((right.centre() - before.centre() - Vec3::new(0.2, 0.0, 0.0)).length() < 1e-6);
        for leaf in right.children() {
            let Node::Primitive(p) = leaf else { panic!("{leaf:?}") };
            assert_eq!((p.kernel.intensity, p.kernel.radius, p.kernel.stiffness), (0.0, 0.3, 2.0));
        }
        let points = testutil::points();
        let (c0, c1) = (g.at(0.0).unwrap(), g.at(1.0).unwrap());
        for &p in &points {
            assert!((c0.value(p) - a.value(p)).abs() < 1e-6, "C(0) at {p}");
            assert!((c1.value(p) - b.value(p)).abs() < 1e-6, "C(1) at {p}");
        }
        let (mid, mid_plain) = (g.at(0.5).unwrap(), plain.at(0.5).unwrap());
        let changed = points.iter().filter(|&&p| (mid.value(p) - mid_plain.value(p)).abs() > 1e-3).count();
        assert!(changed > 0, "the phantom changes the in-betweens");
        let error = |text: &str| GenericTree::new(&a, &b, &MorphSpec::from_ron(text).unwrap()).unwrap_err();
        assert_eq!(
            error("(phantoms: [(target: [], radius: 0.3)])").to_string(),
            "phantom for target node root: the node is matched, it has no phantom"
        );
        assert!(matches!(error("(phantoms: [(target: [5])])"), BlobMorphError::NoSuchNode { .. }));
        assert!(error("(phantoms: [(target: [1], radius: -1)])").to_string().contains("`radius` must be"));
        assert!(error("(phantoms: [(source: [], target: [1])])").to_string().contains("exactly one"));
        assert!(
            error("(phantoms: [(target: [1], position: (0, NaN, 0))])").to_string().contains("`position`")
        );
    }

    /// Fig. 17 as printed: the rounded cube's phantom of the pierced
    /// sphere's boxes is "a sphere that the animator located at the center
    /// of the cube" (`scale: 0`): every phantom skeleton is that point, the
    /// boxes grow out of it (the skeleton at `t` is the target box scaled by
    /// `t`), and the ends are the inputs. Under a warp the collapsed phantom
    /// sits at the node's centre in world space.
    #[test]
    fn phantom_skeletons_collapse_to_a_point_and_grow() {
        let (a, b, _) = crate::scenes::demo("cube_sphere").unwrap();
        let spec =
            MorphSpec::from_ron("(phantoms: [(target: [1], position: (0.1, 0, 0), scale: 0)])").unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        let Node::Difference { right, .. } = g.pair().side(crate::Side::Source) else {
            panic!("a difference")
        };
        assert_eq!(right.leaf_count(), 3);
        for leaf in right.children() {
            let Node::Primitive(p) = leaf else { panic!("{leaf:?}") };
            assert_eq!(p.skeleton.kind(), "point");
            assert!((p.centre() - Vec3::new(0.1, 0.0, 0.0)).length() < 1e-6, "{}", p.centre());
            assert_eq!(p.kernel.intensity, 0.0);
        }
        let points = testutil::points();
        let (c0, c1) = (g.at(0.0).unwrap(), g.at(1.0).unwrap());
        for &p in &points {
            assert!((c0.value(p) - a.value(p)).abs() < 1e-6, "C(0) at {p}");
            assert!((c1.value(p) - b.value(p)).abs() < 1e-6, "C(1) at {p}");
        }
        let Node::Difference { right: boxes, .. } = b.root() else { panic!("the pierced sphere") };
        let extent = |p: &Primitive| {
            let world: Vec<Vec3> =
                p.skeleton.vertices().iter().map(|&v| p.frame.transform_point3(v)).collect();
            Aabb::from_points(&world).size()
        };
        for t in [0.25f32, 0.5, 0.75] {
            let Node::Difference { right, .. } = g.node_at(t) else { panic!("a difference at {t}") };
            for (leaf, target) in right.children().into_iter().zip(boxes.children()) {
                let (Node::Primitive(p), Node::Primitive(q)) = (leaf, target) else { panic!("leaves") };
                let (got, want) = (extent(p), extent(q) * t);
                assert!((got - want).abs().max_element() < 1e-5, "t = {t}: {got} vs {want}");
            }
        }
        // A phantom holding a twist collapses onto the node's centre.
        let a = BlobTree::from_ron(
            r#"(root: (kind: "blend", children: [(kind: "point", vertices: [(0, 0, 0)], radius: 1)]))"#,
        )
        .unwrap();
        let b = BlobTree::from_ron(
            r#"(root: (kind: "blend", children: [(kind: "point", vertices: [(0, 0, 0)], radius: 1),
                (kind: "twist", rate: 1.5, children: [(kind: "segment", vertices: [(1, 0, 0), (1, 0.5, 1)], radius: 0.5)])]))"#,
        )
        .unwrap();
        let links = "links: [(a: [], b: []), (a: [0], b: [0])]";
        let spec = MorphSpec::from_ron(&format!("({links}, phantoms: [(target: [1], scale: 0)])")).unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        let source = g.pair().side(crate::Side::Source);
        let phantom = source.children()[1];
        let Node::Warp { child, .. } = phantom else { panic!("{phantom:?}") };
        assert!(matches!(&**child, Node::Primitive(p) if p.skeleton.kind() == "point"));
        let centre = b.root().children()[1].centre();
        assert!((phantom.centre() - centre).length() < 1e-5, "{} vs {centre}", phantom.centre());
        let bad = MorphSpec::from_ron(&format!("({links}, phantoms: [(target: [1], scale: -1)])")).unwrap();
        let error = GenericTree::new(&a, &b, &bad);
        assert!(error.unwrap_err().to_string().contains("`scale` must be in [0, 1e6]"));
    }

    #[test]
    fn bad_speed_curves_are_errors() {
        let a = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1))"#).unwrap();
        let spec = |s: &str| MorphSpec::from_ron(s).unwrap();
        let bad = spec("(speeds: [(a: [], b: [], speed: (start: 0.8, end: 0.2))])");
        assert!(matches!(BlobMorph::from_trees(&a, &a, &bad), Err(BlobMorphError::InvalidSpeed { .. })));
        let nan = spec("(speeds: [(a: [], b: [], speed: (start: NaN, end: 0.2))])");
        assert!(matches!(BlobMorph::from_trees(&a, &a, &nan), Err(BlobMorphError::InvalidSpeed { .. })));
        let elsewhere = spec("(speeds: [(a: [0], b: [], speed: (start: 0.1, end: 0.2))])");
        assert!(matches!(
            BlobMorph::from_trees(&a, &a, &elsewhere),
            Err(BlobMorphError::UnmatchedPair { .. })
        ));
        let ok = spec("(speeds: [(a: [], b: [], speed: (start: 0.2, end: 0.6, smooth: true))])");
        let m = BlobMorph::from_trees(&a, &a, &ok).unwrap();
        assert!(matches!(
            m.frame(1.5),
            Err(BlobMorphError::Morph(isomorph_common::MorphError::InvalidTime(_)))
        ));
        assert!(matches!(
            m.frame(f32::NAN),
            Err(BlobMorphError::Morph(isomorph_common::MorphError::InvalidTime(_)))
        ));
        assert!(MorphSpec::from_ron("(links: 3)").is_err());
    }

    /// A bad links spec says it is the links spec (not a scene), and a bad
    /// links file names the file.
    #[test]
    fn bad_links_files_say_what_they_are() {
        let e = MorphSpec::from_ron("(links: 3)").unwrap_err().to_string();
        assert!(e.starts_with("cannot parse the RON links spec: "), "{e}");
        let e = MorphSpec::from_json("{\"links\": 3}").unwrap_err().to_string();
        assert!(e.starts_with("cannot parse the JSON links spec: "), "{e}");
        let path = std::env::temp_dir().join(format!("isomorph-blobtree-missing-{}.ron", std::process::id()));
        let e = MorphSpec::load(&path).unwrap_err().to_string();
        assert!(e.starts_with(&format!("cannot read {}", path.display())), "{e}");
    }

    /// No error prints its cause twice when its source chain is printed too
    /// (the CLI prints `error: message: source: …`).
    #[test]
    fn causes_are_printed_once() {
        use std::error::Error;
        let errors: Vec<BlobMorphError> = vec![
            BlobMorphError::Transform {
                a: NodePath::root(),
                b: NodePath::root(),
                source: isomorph_common::TransformError::Reflection,
            },
            MorphSpec::from_ron("(links: 3)").unwrap_err(),
            BlobMorphError::from(isomorph_common::MorphError::InvalidTime(2.0)),
            BlobMorphError::Blob(BlobTree::from_ron("(root: (kind: 3))").unwrap_err()),
        ];
        for e in errors {
            let mut chain = vec![e.to_string()];
            let mut next = e.source();
            while let Some(s) = next {
                chain.push(s.to_string());
                next = s.source();
            }
            for w in chain.windows(2) {
                assert!(!w[0].contains(&w[1]), "{w:?} prints its cause twice");
            }
        }
    }

    #[test]
    fn speed_curves_delay_a_node() {
        let a = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1))"#).unwrap();
        let b = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(1,0,0)], radius: 1))"#).unwrap();
        let spec = MorphSpec {
            speeds: vec![SpeedCurve {
                a: NodePath::root(),
                b: NodePath::root(),
                speed: Speed { start: 0.5, end: 1.0, ..Speed::default() },
                warp: None,
            }],
            ..MorphSpec::default()
        };
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        // Nothing moves before t = 0.5; halfway through the window the point is at x = 0.5.
        assert_eq!(g.at(0.4).unwrap().potential(Vec3::ZERO), 1.0);
        assert!((g.at(0.75).unwrap().potential(Vec3::new(0.5, 0.0, 0.0)) - 1.0).abs() < 1e-6);
    }

    /// Free-form speed curves pass through their points, never decrease,
    /// stay in `[0, 1]`, are continuous, and drive a node; bad points are refused.
    #[test]
    fn free_form_speed_curves_are_monotone_and_interpolate() {
        let curve =
            Speed { points: vec![[0.3, 0.05], [0.5, 0.1], [0.6, 0.7], [0.8, 0.7]], ..Speed::default() };
        assert!(curve.problem().is_none());
        for [u, s] in &curve.points {
            assert!((curve.at(*u) - s).abs() < 1e-6, "s({u}) = {} ≠ {s}", curve.at(*u));
        }
        assert_eq!((curve.at(0.0), curve.at(1.0)), (0.0, 1.0));
        let mut last = 0.0;
        for k in 0..=2000 {
            let s = curve.at(k as f32 / 2000.0);
            assert!((last..=1.0).contains(&s), "at {}: {s} after {last}", k as f32 / 2000.0);
            assert!(s - last < 0.01, "a jump at {}", k as f32 / 2000.0);
            last = s;
        }
        // Flat between equal values (no overshoot), inside a start/end window.
        assert_eq!(curve.at(0.7), 0.7);
        let windowed = Speed { start: 0.5, end: 1.0, ..curve.clone() };
        assert_eq!((windowed.at(0.4), windowed.at(0.75)), (0.0, 0.1));
        for bad in
            [vec![[0.5, 0.4], [0.4, 0.5]], vec![[0.5, 0.6], [0.6, 0.5]], vec![[0.0, 0.1]], vec![[0.5, 1.5]]]
        {
            assert!(Speed { points: bad.clone(), ..Speed::default() }.problem().is_some(), "{bad:?}");
        }
        assert!(Speed { smooth: true, ..curve.clone() }.problem().is_some());
        // Through a generic tree: the point is at x = 0.1 when t = 0.5.
        let a = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1))"#).unwrap();
        let b = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(1,0,0)], radius: 1))"#).unwrap();
        let spec = MorphSpec::from_ron("(speeds: [(a: [], b: [], speed: (points: [(0.5, 0.1)]))])").unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        assert!((g.at(0.5).unwrap().potential(Vec3::new(0.1, 0.0, 0.0)) - 1.0).abs() < 1e-6);
        let bad =
            MorphSpec::from_ron("(speeds: [(a: [], b: [], speed: (points: [(0.5, 0.9), (0.6, 0.2)]))])")
                .unwrap();
        let e = GenericTree::new(&a, &b, &bad).unwrap_err().to_string();
        assert!(e.starts_with("speed curve for root ↔ root: points (u, s) need"), "{e}");
    }

    /// Key-framed trajectories: a leaf's frame and an affine node's map pass
    /// through the key positions and orientations at their local times,
    /// move continuously, keep the ends; malformed keys are refused.
    #[test]
    fn key_framed_trajectories_pass_through_their_keys() {
        let seg = |at: &str| {
            BlobTree::from_ron(&format!(
                r#"(root: (kind: "segment", vertices: [(0,0,0), (1,0,0)], radius: 0.5, frame: (translate: {at})))"#
            ))
            .unwrap()
        };
        let (a, b) = (seg("(0, 0, 0)"), seg("(2, 0, 0)"));
        let spec = MorphSpec::from_ron(
            "(trajectories: [(a: [], b: [], keys: [
                (s: 0.25, position: (0, 1, 0)),
                (s: 0.5, position: (1, 1, 0), rotate: (axis: (0, 0, 1), degrees: 90)),
                (s: 0.75, position: (2, 1, 0)),
            ])])",
        )
        .unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        let frame_at = |t: f32| {
            let Node::Primitive(p) = g.node_at(t) else { panic!("a leaf") };
            p.frame
        };
        assert!(frame_at(0.25).translation.abs_diff_eq(glam::Vec3A::new(0.0, 1.0, 0.0), 1e-6));
        let mid = frame_at(0.5);
        assert!(
            mid.abs_diff_eq(
                Affine3A::from_rotation_translation(
                    Quat::from_rotation_z(FRAC_PI_2),
                    Vec3::new(1.0, 1.0, 0.0)
                ),
                1e-5
            ),
            "{mid:?}"
        );
        // The segment's end (1, 0, 0) is carried to (1, 2, 0): the field's maximum is there.
        assert!((g.at(0.5).unwrap().potential(Vec3::new(1.0, 2.0, 0.0)) - 1.0).abs() < 1e-5);
        assert!(frame_at(0.75).translation.abs_diff_eq(glam::Vec3A::new(2.0, 1.0, 0.0), 1e-6));
        for k in 0..200 {
            let (t0, t1) = (k as f32 / 200.0, (k + 1) as f32 / 200.0);
            let step = (frame_at(t1).translation - frame_at(t0).translation).length();
            assert!(step < 0.05, "a jump of {step} at t = {t0}");
        }
        for p in testutil::points() {
            assert!((g.at(0.0).unwrap().value(p) - a.value(p)).abs() < 1e-6);
            assert!((g.at(1.0).unwrap().value(p) - b.value(p)).abs() < 1e-6);
        }
        // An affine node's map follows its keys too.
        let placed = |x: f32| {
            BlobTree::from_ron(&format!(
                r#"(root: (kind: "affine", frame: (translate: ({x}, 0, 0)), children: [(kind: "point", vertices: [(0,0,0)], radius: 1)]))"#
            ))
            .unwrap()
        };
        let spec =
            MorphSpec::from_ron("(trajectories: [(a: [], b: [], keys: [(s: 0.5, position: (0.5, 1, 0))])])")
                .unwrap();
        let g = GenericTree::new(&placed(0.0), &placed(1.0), &spec).unwrap();
        assert!((g.at(0.5).unwrap().potential(Vec3::new(0.5, 1.0, 0.0)) - 1.0).abs() < 1e-5);
        // Malformed keys.
        let error = |text: &str| {
            GenericTree::new(&a, &b, &MorphSpec::from_ron(text).unwrap()).unwrap_err().to_string()
        };
        assert!(
            error("(trajectories: [(a: [], b: [], keys: [(s: 0.5), (s: 0.4)])])")
                .contains("increase strictly")
        );
        assert!(error("(trajectories: [(a: [], b: [], keys: [(s: 1.0)])])").contains("increase strictly"));
        assert!(
            error("(trajectories: [(a: [], b: [], handles: ((0,0,0), (1,0,0)), keys: [(s: 0.5, position: (0,0,0))])])")
                .contains("not both")
        );
        assert!(
            error(
                "(trajectories: [(a: [], b: [], keys: [(s: 0.5, rotate: (axis: (0, 0, 0), degrees: 10))])])"
            )
            .contains("non-zero axis")
        );
    }

    /// Figs. 10–11: with automatic coplanar frames, two skew segments
    /// interpolate through segments and a segment and a triangle in other
    /// planes through polygons (without: a parallelogram and a
    /// polyhedron); the ends are the inputs either way.
    #[test]
    fn coplanar_frames_keep_in_between_skeletons_flat() {
        let scene = |node: &str| BlobTree::from_ron(&format!("(root: {node})")).unwrap();
        let a = scene(r#"(kind: "segment", vertices: [(-0.5, 0, 0), (0.5, 0, 0)], radius: 0.4)"#);
        let b = scene(r#"(kind: "segment", vertices: [(0, -0.4, 0.3), (0, 0.4, 0.5)], radius: 0.4)"#);
        let c = scene(
            r#"(kind: "polygon", vertices: [(0, 0, -0.4), (0, 0.5, 0.2), (0.1, -0.3, 0.3)], radius: 0.4)"#,
        );
        let dimension = |g: &GenericTree| {
            let Node::Primitive(p) = g.node_at(0.5) else { panic!("a leaf") };
            p.skeleton.polytope().unwrap().dimension()
        };
        let flat = MorphSpec { coplanar_frames: true, ..MorphSpec::default() };
        for (target, own, coplanar) in [(&b, 2, 1), (&c, 3, 2)] {
            let plain = GenericTree::new(&a, target, &MorphSpec::default()).unwrap();
            let g = GenericTree::new(&a, target, &flat).unwrap();
            assert_eq!((dimension(&plain), dimension(&g)), (own, coplanar));
            for p in testutil::points() {
                assert_eq!(g.at(0.0).unwrap().value(p), a.value(p));
                assert_eq!(g.at(1.0).unwrap().value(p), target.value(p));
            }
            // Continuous: no jump from the ends into the coplanar frames.
            for p in testutil::points() {
                assert!((g.at(1e-4).unwrap().value(p) - a.value(p)).abs() < 1e-2, "at {p}");
                assert!((g.at(1.0 - 1e-4).unwrap().value(p) - target.value(p)).abs() < 1e-2, "at {p}");
            }
        }
        assert!(MorphSpec::from_ron("(coplanar_frames: true)").unwrap().coplanar_frames);
    }

    #[test]
    fn trajectories_bend_the_path_but_keep_the_ends() {
        let a = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1))"#).unwrap();
        let b = BlobTree::from_ron(
            r#"(root: (kind: "point", vertices: [(0,0,0)], radius: 1, frame: (translate: (1, 0, 0))))"#,
        )
        .unwrap();
        let spec = MorphSpec::from_json(
            r#"{"trajectories": [{"a": [], "b": [], "handles": [[0, 1, 0], [1, 1, 0]]}]}"#,
        )
        .unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        // Bézier midpoint: (P0 + 3 P1 + 3 P2 + P3) / 8 = (0.5, 0.75, 0).
        let mid = g.at(0.5).unwrap();
        assert!((mid.potential(Vec3::new(0.5, 0.75, 0.0)) - 1.0).abs() < 1e-5);
        assert_eq!(g.at(1.0).unwrap().potential(Vec3::X), 1.0);
        let bad = MorphSpec::from_json(
            r#"{"trajectories": [{"a": [0], "b": [], "handles": [[0, 1, 0], [1, 1, 0]]}]}"#,
        )
        .unwrap();
        assert!(matches!(
            GenericTree::new(&a, &b, &bad),
            Err(BlobMorphError::UnmatchedPair { what: "trajectory", .. })
        ));
        let far = MorphSpec::from_json(
            r#"{"trajectories": [{"a": [], "b": [], "handles": [[0, 1e38, 0], [1, 1, 0]]}]}"#,
        )
        .unwrap();
        assert!(matches!(
            GenericTree::new(&a, &b, &far),
            Err(BlobMorphError::InvalidTrajectory { value: 1e38, .. })
        ));
    }

    /// A trajectory on a matched node without a frame (an operator, a
    /// twist) is refused as such, naming the kind and where frames are; on
    /// the affine node above the twist it moves the twist's axis.
    #[test]
    fn trajectories_on_frameless_nodes_say_where_frames_are() {
        let scene = |rate: f32, x: f32| {
            BlobTree::from_ron(&format!(
                r#"(root: (kind: "blend", children: [(kind: "affine", frame: (translate: ({x}, 0, 0)), children: [
                    (kind: "twist", rate: {rate}, children: [
                        (kind: "segment", vertices: [(0, 0, -0.5), (0.2, 0, 0.5)], radius: 0.5)])])]))"#
            ))
            .unwrap()
        };
        let (a, b) = (scene(0.0, 0.0), scene(2.0, 1.0));
        let run = |pa: &str, pb: &str| {
            let spec =
                format!("(trajectories: [(a: {pa}, b: {pb}, keys: [(s: 0.5, position: (0.5, 1, 0))])])");
            GenericTree::new(&a, &b, &MorphSpec::from_ron(&spec).unwrap())
        };
        for (path, kind) in [("[]", "blend"), ("[0, 0]", "twist")] {
            let err = run(path, path).unwrap_err();
            assert!(
                matches!(&err, BlobMorphError::FramelessTrajectory { kind: k, .. } if *k == kind),
                "{path}: {err}"
            );
            assert!(err.to_string().contains("affine node above it"), "{err}");
        }
        let g = run("[0]", "[0]").unwrap();
        // The twist's axis (through the affine node's origin) passes the key at s = ½.
        let mid = g.at(0.5).unwrap();
        let Node::Nary { children, .. } = mid.root() else { panic!("a blend") };
        let Node::Warp { warp: Warp::Affine(m), .. } = children[0] else { panic!("{:?}", children[0]) };
        assert!((Vec3::from(m.translation) - Vec3::new(0.5, 1.0, 0.0)).length() < 1e-6, "{m:?}");
    }

    #[test]
    fn different_warps_compose_through_the_identity() {
        // Fig. 16: twist ↔ bend becomes twist(→ id) ∘ bend(id →).
        let a = BlobTree::from_ron(
            r#"(root: (kind: "twist", rate: 2, children: [(kind: "segment", vertices: [(0.2,0,-0.5), (0.2,0,0.5)], radius: 0.5)]))"#,
        )
        .unwrap();
        let b = BlobTree::from_ron(
            r#"(root: (kind: "bend", rate: 0.8, min: -0.5, max: 0.5, children: [(kind: "segment", vertices: [(0,-0.5,0), (0,0.5,0)], radius: 0.5)]))"#,
        )
        .unwrap();
        let g = GenericTree::new(&a, &b, &MorphSpec::default()).unwrap();
        let n = g.node_at(0.5);
        let Node::Warp { warp: Warp::Twist { rate, .. }, child } = &n else { panic!("{n:?}") };
        assert!((rate - 1.0).abs() < 1e-6);
        assert!(
            matches!(**child, Node::Warp { warp: Warp::Bend { rate, .. }, .. } if (rate - 0.4).abs() < 1e-6)
        );
        for p in testutil::points() {
            assert!((g.at(0.0).unwrap().value(p) - a.value(p)).abs() < 1e-5);
            assert!((g.at(1.0).unwrap().value(p) - b.value(p)).abs() < 1e-5);
        }
        // The paper's s_A and s_B: the twist unwinds over [0, ½], then the
        // bend winds up over [½, 1]; a curve without `warp` drives both.
        let spec = MorphSpec::from_ron(
            "(speeds: [(a: [], b: [], warp: source, speed: (end: 0.5)), (a: [], b: [], warp: target, speed: (start: 0.5))])",
        )
        .unwrap();
        let g = GenericTree::new(&a, &b, &spec).unwrap();
        let rates = |t: f32| {
            let n = g.node_at(t);
            let Node::Warp { warp: Warp::Twist { rate: twist, .. }, child } = &n else { panic!("{n:?}") };
            let Node::Warp { warp: Warp::Bend { rate: bend, .. }, .. } = **child else { panic!("{child:?}") };
            (*twist, bend)
        };
        for (t, want) in [(0.25, (1.0, 0.0)), (0.5, (0.0, 0.0)), (0.75, (0.0, 0.4)), (1.0, (0.0, 0.8))] {
            let got = rates(t);
            assert!((got.0 - want.0).abs() < 1e-6 && (got.1 - want.1).abs() < 1e-6, "t = {t}: {got:?}");
        }
        let both = MorphSpec::from_ron("(speeds: [(a: [], b: [], speed: (end: 0.5))])").unwrap();
        let n = GenericTree::new(&a, &b, &both).unwrap().node_at(0.25);
        let Node::Warp { warp: Warp::Twist { rate, .. }, child } = &n else { panic!("{n:?}") };
        assert!((rate - 1.0).abs() < 1e-6);
        assert!(
            matches!(**child, Node::Warp { warp: Warp::Bend { rate, .. }, .. } if (rate - 0.4).abs() < 1e-6)
        );
        // `warp` on a pair that is not two warps of different kinds is refused.
        let err = GenericTree::new(
            &a,
            &a,
            &MorphSpec::from_ron("(speeds: [(a: [], b: [], warp: source, speed: (end: 0.5))])").unwrap(),
        )
        .unwrap_err();
        assert!(err.to_string().contains("not such a pair"), "{err}");
    }

    #[test]
    fn frames_and_blend_union_transition() {
        use glam::Quat;
        // A blend of two segments → a union of the same segments, rotated frame.
        let seg = |x: f32| {
            Node::Primitive(
                Primitive::new(Skeleton::Segment(Vec3::ZERO, Vec3::Z), crate::Kernel::new(1.0, 0.8, 1.0))
                    .with_frame(Affine3A::from_translation(Vec3::X * x)),
            )
        };
        let a = BlobTree::new(Node::blend(vec![seg(-0.3), seg(0.3)]), 0.5).unwrap();
        let rot = Affine3A::from_rotation_translation(Quat::from_rotation_y(1.0), Vec3::ZERO);
        let b = BlobTree::new(Node::affine(rot, Node::union(vec![seg(-0.3), seg(0.3)])), 0.5).unwrap();
        let g = GenericTree::new(&a, &b, &MorphSpec::default()).unwrap();
        // Halfway: a super-elliptic blend of order 2 under a half rotation.
        let n = g.node_at(0.5);
        let Node::Warp { warp: Warp::Affine(m), child } = &n else { panic!("{n:?}") };
        assert!(m.abs_diff_eq(Affine3A::from_rotation_y(0.5), 1e-5));
        assert!(matches!(**child, Node::Nary { op: NaryOp::SuperBlend(n), .. } if (n - 2.0).abs() < 1e-6));
    }
}
