//! Skeletal implicit BlobTrees and their metamorphosis after Galin, Leclercq &
//! Akkouche, *Morphing the BlobTree*, Computer Graphics Forum 19(4), 2000
//! (with the blob morphing of Galin & Akkouche, Eurographics 1996, it builds on).
//!
//! A BlobTree is a tree of skeletal primitives (leaves) combined by blending,
//! Boolean and warping operators (nodes). The surface is where the potential
//! equals the threshold `T`; [`BlobTree`] implements
//! [`isomorph_common::Field3`] as `potential − T`, positive inside. A morph
//! between two BlobTrees matches and decomposes them into overlapping
//! equivalent trees and builds one *generic* tree `C(t)` whose parameters
//! vary with time: `C(0) ≡ A`, `C(1) ≡ B` ([`BlobMorph`] implements
//! [`isomorph_common::Morph`]).
//!
//! # Paper sections → API
//!
//! Everything is at the crate root except the built-in scenes, which are
//! the [`scenes`] namespace (`scenes::load`, `scenes::demo`, …).
//!
//! | paper | items |
//! |---|---|
//! | §2 Blanc–Schlick field function `g(r)` (`I`, `R`, `k`) | [`Kernel`] |
//! | §2 convex skeletons, L^p distances | [`Skeleton`], [`Polytope`], [`lp_norm`] |
//! | §2 blend, union (max), intersection (min), difference, super-elliptic blend, warps `f ∘ w⁻¹` | [`Node`], [`NaryOp`], [`Primitive`], [`Warp`], [`BlobTree`] |
//! | scene files (RON / JSON, below) | [`BlobTree::from_ron`], [`BlobTree::from_json`], [`BlobTree::to_ron`], [`BlobTree::to_json`], [`scenes::load`] |
//! | §3.1–3.3, §4.1–4.3 correspondence, decomposition, phantoms | [`decompose`], [`Correspondence`], [`Pair`], [`Link`], [`Heuristic`], [`Phantom`], [`split`] |
//! | §1, §3 genericity: saved in-betweens (`isomorph morph --scenes`), morphs through key shapes | [`BlobTree::to_ron`] of a frame (`mix` nodes), [`BlobMorph::through`], [`KeyShape`]; Bézier-like control shapes: [`BlobMorph::bezier`], [`ViaMode`] |
//! | §3.4.1 Minkowski-sum skeleton interpolation, generic topology | [`MinkowskiPath`] |
//! | §3.4.2–3.5, §4.4 generic elements and nodes, frames, speed `s(t)`, `T(t)` | [`GenericTree`], [`BlobMorph`], [`MorphSpec`], [`SpeedCurve`], [`Trajectory`] |
//! | §5 sequences (cube → pierced sphere, sphere → propeller, rook → queen, bear → bird) | [`scenes`] |
//!
//! # Scene files
//!
//! Examples of every built-in scene and links spec ship in the crate's
//! `scenes/` folder (`blobtree/scenes/` in the repository: `rook.ron`,
//! `queen.ron`, `rounded_cube.ron`, `pierced_sphere.ron`, `propeller.ron`,
//! `bear.ron`, `bird.ron`, `sphere.ron`, `torus.ron`, the rook → queen
//! links `rook_queen.links.ron`, the cube → pierced sphere phantom of
//! Fig. 17 `cube_sphere.links.ron`, and `bear_bird.every_feature.links.ron`,
//! which uses every control), and a hand-written pair: `bent_rods.ron`
//! (a bend about its own axes) with `propeller_bent_rods.links.ron` (the
//! speeds of the two halves of a twist ↔ bend pair, `warp: source |
//! target`); a test keeps them equal to the built-ins and checks the examples.
//! `isomorph blob --dump NAME [--format ron|json]` prints any built-in
//! scene or built-in morph's links spec.
//!
//! A scene is `(threshold: 0.5, root: (...))` in RON, or the same as JSON
//! (`{"threshold": 0.5, "root": {...}}`). `threshold` is the iso value `T`
//! (optional, default 0.5; in `(0, 1e6]`): the surface is where the
//! potential equals `T`, and the field is `potential − T`, positive
//! inside. Every node is a record with a `kind` and exactly the fields
//! that kind uses (any other field is an error naming the node). Lengths
//! and positions are in scene units (the world units of the meshes); angles
//! in degrees.
//!
//! | kind | fields (defaults in parentheses) |
//! |---|---|
//! | `point`, `segment`, `polygon`, `polyhedron` | `vertices`: the skeleton, in the primitive's local frame (1, 2, 3 to 32 coplanar, 4 to 32 spanning 3D; the convex hull is used); `radius`: `R > 0`, the radius of influence (the field is 0 beyond it; an isolated primitive's surface lies `R/2` from its skeleton when `I = 1, T = 0.5`); `intensity`: `I ≥ 0` (1), the field on the skeleton; `stiffness`: `k ≥ 0` (1), Blanc–Schlick's shape parameter; `p`: the L^p exponent of the distance, a number ≥ 1 or `"inf"` (2, Euclidean; measured along the local axes); `frame`: local → world map (identity) |
//! | `box` | `half` (half extents) instead of `vertices`; a polyhedron skeleton `[-half, half]`; other fields as above |
//! | `blend` | `children` (≥ 1): the sum of their fields |
//! | `union`, `intersection` | `children` (≥ 1): their maximum, minimum |
//! | `superblend` | `n` (≥ 1): `(Σ f_i^n)^(1/n)` (`n = 1` blend, large `n` → union); `children` (≥ 1) |
//! | `difference` | `children` (2: left minus right); `level` (the scene's threshold): the reference level `c` (see [`Node::Difference`]) |
//! | `twist` | `rate`: radians per unit length along the axis (a point at height `h = p·axis` turns by `rate·h` about the axis, counter-clockwise seen from its tip); `axis` (`(0, 0, 1)`): the twist axis through the local origin, a direction (any length ≥ 1e-6, normalized; not written when z); `children` (1) |
//! | `taper` | `slope`: scale change per unit length along `axis` (the components across the axis scale by `max(1 + slope·h, 0.05)`); `axis` (`(0, 0, 1)`), as for `twist`; `children` (1) |
//! | `bend` | `rate`: curvature (1 / units), positive towards `axis`, negative away; `centre` (0), `min`, `max`: the undeformed line and the bent band, coordinates along `along`; `axis` (`(0, 0, 1)`): the direction the bend curves towards; `along` (`(0, 1, 0)`): the band's direction (only its part across `axis` counts; it must not be within 1e-3 (sine) of parallel to it). The bend is in the plane of `along` and `axis` (default y–z), about lines parallel to `along × axis` (x); the bend angle `rate·(max − min)` is at most π in magnitude; `children` (1) |
//! | `affine` | `frame`: the map applied to the child (`()` or `{}`: identity); `children` (1) |
//! | `mix` | a generic tree's time-varying node at one instant (§4.4), as saved in-betweens contain: `from`, `to`: operators (`"blend"`, `"union"`, `"intersection"`, or a number `n ≥ 1`, a super-elliptic blend's order); `s` in `[0, 1]`: the field is `(1 − s)·from(children) + s·to(children)`; `children` (≥ 1) |
//!
//! A `frame` is `(translate: (x, y, z), rotate: (axis: (x, y, z), degrees: a), scale: (x, y, z))`
//! (all optional; applied as translate · rotate · scale, so a local point
//! is scaled, rotated, then moved) or `(matrix: (...12 numbers...))`,
//! column-major 3×4 (the three axes' images, then the translation).
//! Numbers may be written as integers; in JSON, points and matrices are
//! arrays; RON accepts `// comments`.
//!
//! **Node paths** name a node by the child indices leading to it from the
//! root: `[]` is the root, `[1, 0]` the first child of the root's second
//! child (a difference's left child is 0, its right child 1; a warp's child
//! 0). They count the nodes as written in the file (consecutive `affine`
//! nodes stay separate nodes). Errors name the node by its path
//! (`node root/1/0: …`), and links specs use them.
//!
//! **Links specs** (`isomorph morph --method blobtree --links FILE`,
//! [`MorphSpec`]) hold the animator's controls; every field is optional:
//!
//! | field | meaning |
//! |---|---|
//! | `links: [(a: PATH, b: PATH), …]` | source node `a` corresponds to target node `b` (§3.1); a node with several links is split (§3.2, §4.2); children of linked nodes without a link get phantom partners (§3.3); links must respect the hierarchy (a link's parents are matched) |
//! | `heuristic: nearest_centre`, `hierarchical` or `all_children` | how children of matched nodes without links are paired (default `nearest_centre`: nearest skeleton centres; `hierarchical`: nearest centres relative to their parents, recursively; `all_children`: every child with every child) ([`Heuristic`]) |
//! | `speeds: [(a: PATH, b: PATH, speed: (start: 0.2, end: 0.8, smooth: true)), …]` | the speed `s(t)` of the generic node made from `a` and `b` (§4.4): 0 before `start`, 1 after `end`, linear or smooth (`3u² − 2u³`) in between (defaults 0, 1, false); or free-form with `points: [(u, s), …]`, a monotone piecewise cubic through `(0, 0)`, the points and `(1, 1)` over the window ([`Speed`]); for two warps of different kinds, which become `(ω_A →s_A(t) Id) ∘ (Id →s_B(t) ω_B)` (Fig. 16), `warp: source` or `warp: target` gives `s_A` or `s_B` alone (default: both) ([`WarpHalf`]) |
//! | `trajectories: [(a: PATH, b: PATH, handles: ((x, y, z), (x, y, z))), …]` | the two inner control points (world units) of the cubic Bézier curve the frame origin of the generic leaf or affine node `a → b` follows (default: uniform straight motion, slerped orientation); or key frames `keys: [(s: 0.5, position: (x, y, z), rotate: (axis: (x, y, z), degrees: a)), …]` at increasing local times `s ∈ (0, 1)`, each with a position and/or an orientation: the origin follows the cubic spline (Catmull–Rom tangents) through the end origins and the key positions, the orientation slerps from key to key ([`Trajectory`], [`FrameKey`]) |
//! | `coplanar_frames: true` | automatic coplanar frames (§3.4, Figs. 10–11): matched points, segments and polygons are interpolated in local frames where both lie in one plane, so in-between skeletons stay segments or polygons (default `false`) |
//! | `phantoms: [(target: PATH, position: (x, y, z), radius: R, stiffness: k, scale: f), …]` | the phantom partner of a node without correspondence (§3.3, Fig. 17; [`Phantom`]): name the node by `source: PATH` or `target: PATH`; its phantom's skeletons are centred at `position` (world units) and scaled by `f ≥ 0` about that centre (`0`: every skeleton becomes that point, as Fig. 17's phantom sphere at the cube's centre), its primitives get radius `R` and stiffness `k` (each optional; default: the node's own, `f = 1`); its intensity stays 0 |
//! | `levels: [(level: 2, pair: 0, links: [(a: PATH, b: PATH), …]), …]` | a Bézier-like morph through control shapes `P_0 … P_n` only (`--via`, [`BlobMorph::bezier`]): links for pair `i` of de Casteljau level `r` (`2 ≤ r ≤ n`, `0 ≤ i ≤ n − r`), the correspondence between the level-`(r − 1)` shapes `P_i^{r−1}` and `P_{i+1}^{r−1}`, made once with these links (children of linked nodes without a link get phantoms) and kept for every `t`; without them a level pairs nearest centres at `t = ½`. Paths name nodes of those shapes as [`BlobMorph::level_shapes`] returns them and [`BlobTree::to_ron`] writes them (their structure does not depend on `t`). The morph gathers `levels` from every pair's spec (with `--via`, the `--links` file is the last pair's, and `--via-links FILE`, one per `--via` shape, gives the spec of the pair arriving at that shape) ([`LevelLinks`]) |
//!
//! A full scene and a links spec for it, as in the shipped files:
//!
//! ```
//! use isomorph_blobtree::{BlobMorph, BlobTree, MorphSpec, scenes};
//! use isomorph_common::Field3;
//!
//! let scene = r#"(threshold: 0.5, root: (kind: "union", children: [
//!     (kind: "blend", children: [                                    // root/0
//!         (kind: "point", vertices: [(0, 0, 0)], radius: 1.0),       // root/0/0
//!         (kind: "segment", vertices: [(0.5, 0, 0), (1, 0, 0)], radius: 0.8, p: "inf"),
//!     ]),
//!     (kind: "difference", level: 0.5, children: [                  // root/1
//!         (kind: "twist", rate: 0.5, axis: (0, 1, 0), children: [      // about local y
//!             (kind: "box", half: (0.2, 0.2, 0.5), radius: 0.4, intensity: 1.2, stiffness: 0.8,
//!              frame: (translate: (0, 1, 0), rotate: (axis: (1, 0, 0), degrees: 30)))]),
//!         (kind: "affine", frame: (scale: (1, 2, 1)), children: [
//!             (kind: "polygon", vertices: [(0, 0.9, 0.5), (0.2, 0.9, 0.5), (0, 1.1, 0.5)], radius: 0.3)]),
//!     ]),
//! ]))"#;
//! let a = BlobTree::from_ron(scene)?;
//! assert!(a.value(glam::Vec3::ZERO) > 0.0);
//! // The same scene as JSON, written and read back.
//! assert_eq!(BlobTree::from_json(&a.to_json()?)?.root(), a.root());
//! let b = scenes::load("rook")?;
//! let spec = MorphSpec::from_ron(r#"(
//!     links: [(a: [0], b: [0]), (a: [1], b: [1])],
//!     heuristic: nearest_centre,
//!     speeds: [(a: [1], b: [1], speed: (start: 0.2, end: 0.8, smooth: true))],
//!     trajectories: [(a: [0, 0], b: [0, 1], handles: ((0, 0, 0.3), (0, 0, 0.6)))],
//! )"#)?;
//! let morph = BlobMorph::from_trees(&a, &b, &spec)?;
//! # let _ = morph;
//! // A shipped file is a scene like any other.
//! let rook = BlobTree::from_ron(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/rook.ron")))?;
//! assert_eq!(rook.root(), b.root());
//! // Errors name the node by its path.
//! let bad = r#"(root: (kind: "blend", children: [(kind: "point", vertices: [(0, 0, 0)], radius: -1)]))"#;
//! let err = BlobTree::from_ron(bad).unwrap_err();
//! assert_eq!(err.to_string(), "node root/0: radius of influence must be positive, got -1");
//! let typo = r#"(root: (kind: "point", vertices: [(0, 0, 0)], radius: 1, stifness: 2))"#;
//! assert!(BlobTree::from_ron(typo).unwrap_err().to_string().contains("node root: a `point` node has no field `stifness`"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Choices where the paper leaves details open
//!
//! - **Difference**: the paper does not print it. We use the BlobTree's
//!   `min(f_L, 2c − f_R)` (the subtrahend reflected about the level `c = T`),
//!   extended above `2c` so that a null (phantom) subtrahend is *exactly*
//!   neutral — which the paper's difference insertion (Fig. 14) needs — and
//!   clamped at 0 so that pruning stays exact. The level `c` is stored in the
//!   node and scales with it, so `αN` is exactly `α` times `N` (§4.2).
//! - **L^p distance** `min_q ‖x − q‖_p` is exact for every skeleton kind
//!   (oblique polygons and polyhedra by a closed-form per-face plane solve
//!   plus exact edge minimization, see [`Polytope::lp_distance`]), so iso-surfaces of a
//!   primitive are `S ⊕ B_p(r)`. The L^p axes are the primitive's local axes. `p` is interpolated linearly (§3.4.3), or
//!   through `1/p` when an end is `p = ∞`.
//! - **Super-elliptic blend of a split child**: copies are weighted
//!   `α^{1/n}` so their super-elliptic blend equals the original.
//! - **Unlinked children under an intersection** are linked to the nearest
//!   child instead of getting a phantom (a null field is not neutral for `min`).
//! - **Trajectories** (§3.4: the origin follows a cubic spline curve, the
//!   orientations are interpolated by quaternion slerp): by default the origin moves uniformly on a straight line, the rotation by
//!   slerp, the stretch linearly ([`isomorph_common::AffineParts::lerp`]);
//!   the animator bends the origin's path into a cubic Bézier curve
//!   (`handles`), or keys positions (a C¹ cubic spline with Catmull–Rom
//!   tangents through the keys) and orientations (slerp from key to key),
//!   for leaves and affine nodes alike. Twists, tapers and bends act about
//!   their own axes in the node's local frame, so the affine node above
//!   one places that frame and carries its trajectory (the paper's warps
//!   of internal nodes); a
//!   trajectory on a frameless node (an operator, a difference, a twist,
//!   taper or bend) is refused ([`BlobMorphError::FramelessTrajectory`]). Keys are at the node's local time
//!   `s`, after its speed curve.
//! - **Phantom parameters**: position, skeleton size (`scale`, down to a
//!   point), radius and stiffness; the
//!   intensity of a phantom stays 0 (a phantom with an intensity would
//!   change the end shape it belongs to).
//! - **Coplanar frames** (`coplanar_frames`): local x along a segment or a
//!   polygon's principal axis, z along the polygon's normal (two segments:
//!   the normal of the plane they span), origin at the skeleton's centroid,
//!   signs chosen for the least turn; a point takes its partner's
//!   orientation. Only for Euclidean metrics and similarity frames, where
//!   re-expressing a primitive leaves its field unchanged.
//! - **Hierarchical matching** compares children's centres relative to
//!   the mean of their siblings' centres.
//! - **Control shapes** (`--via`, [`ViaMode`]): by default the paper's
//!   Bézier-like morph ([`BlobMorph::bezier`]): the pairwise generic trees
//!   are combined by de Casteljau's construction, each level the generic
//!   tree of the two instances below it at the same `t`, so a primitive
//!   matched through all the shapes has the skeleton `⊕ B_i^n(t) S_i` and
//!   the parameters `Σ B_i^n(t) x_i`; the source and the target are
//!   reproduced, the shapes in between approached, not reached. The
//!   correspondence of the levels above the first is the nearest-centre
//!   heuristic on the shapes at `t = ½`, kept for every `t`. `--via-mode
//!   chain` ([`BlobMorph::through`], not in the paper) joins the pairwise
//!   generic trees end to end at evenly spaced times instead, so the morph
//!   passes through every key shape (continuous, with a change of speed at
//!   the keys).
//! - **Warps**: Barr twist, taper and bend, each with its own axis (§4.4
//!   names "an axis and a rotation angle for the twist"): a warp about
//!   `axis` is the warp about z in a frame turned to it (`w = Q ∘ w_z ∘
//!   Q⁻¹`, `Q` taking z to the axis; for the bend also y to `along`), so
//!   its bounds are the z warp's bounds turned (the box of a turned box's
//!   corners). Defaults (z; the bend in the y–z plane) are evaluated
//!   without turning, exactly as before axes existed. Matched warps of one
//!   kind interpolate the rate linearly and the axis along the great
//!   circle at constant angular speed (a bend's frame by quaternion
//!   slerp); warps of different kinds go through the identity (Fig. 16),
//!   each keeping its axis. The taper scale is clamped at 0.05 to stay
//!   invertible.
//!
//! # Guarantees
//!
//! - Pruning by per-subtree bounding boxes never changes a value (tested
//!   bit-for-bit on random trees).
//! - Decomposed trees have the same field as the inputs everywhere (proptest
//!   on random trees), and `C(0)`, `C(1)` reproduce the inputs.
//! - Invalid input — bad scene files, NaN, negative radii, `p < 1`, links
//!   breaking the hierarchy, bad speed curves — is a typed error, never a panic.
//! - Hostile sizes are refused up front with a typed error naming the node
//!   and field: magnitudes beyond [`MAX_MAGNITUDE`] (`1e6`; radii also
//!   below `1e-6`), support boxes beyond [`MAX_SUPPORT`], skeletons
//!   with more than [`MAX_VERTICES`] vertices, scene files nested
//!   deeper than [`MAX_DEPTH`] nodes, scenes whose potential cannot
//!   reach the threshold, and correspondences needing more than
//!   [`MAX_PAIRS`] node pairs or [`MAX_VERTEX_PAIRS`]
//!   skeleton vertex pairs (the all-children heuristic on wide nodes).
//!   Matching is otherwise near-linear (k-d tree for nearest centres);
//!   scene and links files are read up to [`MAX_FILE_BYTES`].
//!
//! Not guaranteed: intermediate shapes keep the topology of either end
//! (they do for the built-in rook → queen, which is tested); gradients under
//! bends and of non-Euclidean polytope distances are central differences.
//!
//! # Performance
//!
//! Evaluation prunes every subtree outside its bounding box, exactly (about
//! 7× faster on the rook → queen demo); batches run in parallel with rayon.
//! Benches: `cargo bench -p isomorph-benches --bench blobtree`; figures in
//! the repository's `docs/EXPERIMENTS.md`.
//!
//! # Example
//!
//! ```
//! use isomorph_blobtree::{BlobMorph, BlobSettings, BlobTree};
//! use isomorph_common::{Control, Field3, Morph, Solid};
//! use glam::Vec3;
//! use std::sync::Arc;
//!
//! let a = BlobTree::from_ron(r#"(root: (kind: "point", vertices: [(0, 0, 0)], radius: 1.0))"#)?;
//! let b = BlobTree::from_ron(r#"(root: (kind: "union", children: [
//!     (kind: "segment", vertices: [(-0.5, 0, 0), (0.5, 0, 0)], radius: 0.6),
//!     (kind: "box", half: (0.1, 0.1, 0.4), radius: 0.4, p: "inf"),
//! ]))"#)?;
//! let (sa, sb) = (Solid::implicit(Arc::new(a))?, Solid::implicit(Arc::new(b.clone()))?);
//! let morph = BlobMorph::new(&sa, &sb, &BlobSettings::default(), &Control::new())?;
//! // The ends are the inputs: the ball's surface is at distance R/2 = 0.5.
//! let start = morph.frame(0.0)?.field;
//! assert!(start.value(Vec3::new(0.49, 0.0, 0.0)) > 0.0);
//! assert!(start.value(Vec3::new(0.51, 0.0, 0.0)) < 0.0);
//! let end = morph.frame(1.0)?.field;
//! assert!((end.value(Vec3::new(0.7, 0.0, 0.0)) - b.value(Vec3::new(0.7, 0.0, 0.0))).abs() < 1e-6);
//! // In between, the shape is one blob that can be polygonized.
//! let mesh = morph.frame_mesh(0.5, 32)?;
//! assert_eq!(mesh.connected_components(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod coplanar;
mod correspond;
mod error;
mod generic;
mod hull;
mod kernel;
mod minkowski;
mod node;
mod scene;
pub mod scenes;
mod skeleton;
mod sweep;
mod tree;
mod warp;

pub use correspond::{
    Correspondence, Heuristic, Link, MAX_PAIRS, MAX_VERTEX_PAIRS, Origin, Pair, Phantom, decompose, split,
};
pub use error::{BlobError, BlobMorphError, NodePath, NodeProblem, Side};
pub use generic::{
    BlobMorph, BlobSettings, FrameKey, GenericTree, KeyShape, LevelLinks, MorphSpec, Orientation, Speed,
    SpeedCurve, Trajectory, ViaMode, WarpHalf,
};
pub use kernel::Kernel;
pub use minkowski::MinkowskiPath;
pub use node::{MAX_MAGNITUDE, MAX_SUPPORT, NaryOp, Node, Primitive};
pub use scene::{MAX_DEPTH, MAX_FILE_BYTES};
pub use skeleton::{MAX_VERTICES, Polytope, Skeleton, lp_norm};
pub use tree::BlobTree;
pub use warp::{DEFAULT_ALONG, DEFAULT_AXIS, MIN_ALONG_SINE, MIN_AXIS_LENGTH, TAPER_MIN_SCALE, Warp};

#[cfg(test)]
mod testutil;
