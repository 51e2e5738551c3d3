//! 3D shape metamorphosis with T-spline level sets after Yang & Jüttler,
//! *3D Shape Metamorphosis Based on T-spline Level Sets*, The Visual
//! Computer 23, 2007 (`../shared/papers/yang-juettler-2007-…`), with the
//! least-squares evolution of Yang, Fuchs, Jüttler & Scherzer (SMI 2006)
//! as reconstructed in the implementer's note
//! (`../shared/papers/notes/TSPLINE.md`).
//!
//! The in-between shapes are zero sets of one trivariate cubic T-spline
//! function `f(x) = Σ c_i B_i(x) / Σ B_i(x)` (eq. 1, positive inside) on a
//! T-mesh that stays fixed for the whole morph: only the coefficient vector
//! changes from frame to frame.
//!
//! # Paper sections → modules
//! | paper | here |
//! |---|---|
//! | §3.1 T-spline level sets, eq. 1–2 | [`TSpline`] (`tspline.rs`), blending functions and their rational derivatives (`basis.rs`, `bspline.rs`) |
//! | §3.2 T-mesh by octree subdivision (`n_T`, depth ≤ 6) | [`TMesh`], [`TMeshSettings`] (`tmesh.rs`; knots by Sederberg's ray casting, note §3.3) |
//! | §3.2 initial fit, eq. 3–4 | [`fit`], [`FitSettings`], [`FitReport`] (`fit.rs`, sparse normal equations in `lsq.rs`, faer sparse Cholesky) |
//! | §3.2 final refinement | of the source fit: [`FitSettings::refinement`], [`Refinement`], [`FitReport::rounds`], [`TMesh::refined`]; of the target after the evolution (§3.2, last paragraph): [`TsplineSettings::target_refinement`], [`TsplineMorph::refined_target`]; the T-mesh adapted to the target as well ("generated adaptively from the geometry of both objects"): [`TsplineSettings::target_adaptation`] |
//! | §3.3 evolution, eq. 5–9, speed eq. 8 | [`evolve`], [`EvolveSettings`], [`Speed`], [`Evolution`] (`evolution.rs`; zero-set samples by marching cubes or the paper's marching triangulation, then Newton projection, [`Sampler`] in `sampling.rs`) |
//! | §4.2 alignment | [`TsplineSettings::align`], [`Align`]: moments (`isomorph_common::alignment`) or a user's map; the T-mesh is built on the aligned shapes |
//! | §4.3 projection frames, eq. 10 | [`morph`] (`morph.rs`) |
//! | §1, §4.4 marching triangulation (Hartmann 1998, ref. \[10\]) of the frames | [`TsplineSettings::mesher`], [`Mesher`] over [`isomorph_common::marching_triangulation`] |
//! | §4.4 combined alignment transforms, eq. 11 | [`TsplineMorph::placement`] (`W(u)`: translation and stretch linear, rotation slerped), [`TsplineMorph::frame_transform`], `tests/alignment.rs` |
//! | §3.3 Fig. 2–3 | [`demo::corner_source`], [`demo::corner_target`], `tests/corner.rs` ("┌" → "┐", the shapes of the paper's text); [`demo::letter_t`], [`demo::letter_c`], `tests/t_to_c.rs` ("T" → "C", its captions) |
//! | §5 examples | Example 1: [`demo::petal_torus`], `tests/tests/tspline_example1.rs` of `isomorph-tests`; Example 2: [`isomorph_common::models::holed_cube`], [`demo::holed_cube_settings`]; Example 3's source: [`isomorph_common::models::apple`] (open targets such as the Utah teapot enter as their winding-number zero set, see [`TsplineMorph::new`]; the teapot with [`TsplineSettings::target_adaptation`]: `tests/tests/tspline_example3.rs` of `isomorph-tests`); Example 5's kind (a dense mesh into a turned ellipsoid, alignment interpolated): `tests/tests/tspline_example5.rs` of `isomorph-tests` |
//!
//! # Choices where the paper is silent (see the note)
//! - Anchors at every leaf vertex including hanging ones; local knot vectors
//!   by 3D ray casting; outside the domain the last knot spacing repeats.
//!   The octree is 2:1 balanced and refined to a minimum depth.
//! - Eq. 4's uniform points are replaced by a per-leaf midpoint quadrature of
//!   eq. 3 (the same integral, points dense where the T-mesh is fine).
//! - The evolution's least squares: velocity rows on the zero set,
//!   distance-field rows `2∇f·∇ḟ = −(|∇f|² − 1)/τ` on the zero set and at
//!   `±h` along the normal, Tikhonov damping (note §5.3).
//! - Against pieces of surface born away from the front (not in the
//!   paper): rows `ḟ = 0` at the centres of leaves without a zero and out
//!   of the front's reach ([`EvolveSettings::far_field_weight`]), and,
//!   opt-in, at the finest cells that a step would lift through zero away
//!   from the front, with the step solved again
//!   ([`EvolveSettings::hold_fraction`]; Example 3 uses ½: pieces in 14
//!   instead of 25 of its level sets, the largest 2.3e-4 of the body
//!   instead of 6.4e-3).
//! - `κ` is the mean curvature `div(∇f/|∇f|)/2`, negative on convex parts for a
//!   positive-inside field, so eq. 8 is used verbatim (see `evolution` docs).
//! - Stopping: two-sided RMS distance below the tolerance, a stall (no 1 %
//!   progress over several steps, reported as [`Outcome::Stalled`]), or the
//!   step cap.
//!
//! # Which speed the tests and demos use
//! [`Speed::Paper`] (eq. 8) is the default and is used for the shrinking
//! sphere test. As the note predicts (§5.2), far from the target its
//! curvature term dominates and growth stalls. The growth tests, the
//! sphere → holed cube example ([`demo::holed_cube_settings`]), the bunny
//! bench and `isomorph demo` therefore use the note's [`Speed::Robust`]
//! (`v = clamp(d_B, ±0.2) + β (1 − λ) κ`, `β` a finest cell or less).
//! The paper's Example 1 (bunny → petal torus, [`demo::example1_settings`])
//! uses eq. 8 on a T-mesh of depth at most 5 and keeps one component in
//! every level set. [`Speed::Distance`] (`λ ≡ 1`) is Breen & Whitaker's
//! speed, for the paper's Fig. 2 comparison. With [`TsplineMorph`]'s defaults otherwise,
//! the paper's speed converges for sphere → torus, holed cube, C and cube,
//! and stalls for sphere → chain (18 steps), sphere → mug and ball → C
//! (measured 2026-11 with `isomorph morph --speed paper`); a stall ends as
//! [`Outcome::Stalled`] with a report warning naming the step, the error
//! and the robust speed, which the command line prints.
//!
//! # Alignment and placement (§4.2, §4.4)
//! [`TsplineSettings::align`] places the source on the target (moments, or
//! a user's map `T`); the T-mesh, the fit and the evolution all work on
//! `T(source)` and the target in the target's world space. Frame `i` is
//! placed in the world by [`TsplineMorph::placement`]`(u_i)`, eq. 11's
//! `W(u)`: `T⁻¹` at `u = 0`, the identity at `u = 1`, the source centroid's
//! translation and the stretch linear and the rotation slerped in between.
//! The working space is the target's world space, not a principal frame:
//! a target turned off the axes gets an axis-aligned T-mesh around its
//! larger box (Example 2 with the cube turned needs depth 4 where the
//! upright cube converges at depth 3; `tests/example2_aligned.rs`).
//!
//! # Guarantees and limits
//! - `f` is C² (cubic blending functions, `Σ B_i > 0` on `D`); evaluation
//!   visits only the blending functions of the leaf containing the point and
//!   agrees with the sum over all of them (tested).
//! - On refined T-meshes the rational T-spline space is poorer than a
//!   tensor-product space: near T-junctions the fitted distance has
//!   `|∇f|` down to ≈ 0.8 and the curvature is noisy (mean error ≈ 0.8 for a
//!   sphere of mean curvature 2, against < 0.1 on a uniform mesh; measured in
//!   the `fit` tests).
//! - New target components far from the evolving surface are never created
//!   (note §5.5): align the shapes so that they overlap.
//! - **The distance-field weight decides whether narrow features open.**
//!   The distance-field rows ask `|∇f| = 1`; a tunnel narrower than a few
//!   finest cells needs `f` far from a distance function, so a strong
//!   constraint keeps a plug in it. Measured with sphere → holed cube on the
//!   depth-3 T-mesh (729 coefficients, holes 1.4 finest cells wide; step
//!   one finest cell, up to 60 steps):
//!
//!   | `distance_weight` | result |
//!   |---|---|
//!   | 0.1 (the default until 2026-11) | stalls after 14 steps, genus 0 plus sheets, mean distance 0.038 |
//!   | 0.01 | genus 3 by step 9, then strays appear (3–7 components after step 48) |
//!   | 0.001 (default) | genus 3 from step 5 on, one component to step 60, mean distance 0.0028 |
//!
//!   Sphere → torus on the same mesh: 0.1 stalls at genus 8 or with extra
//!   components for every step size tried (0.25, 0.5 and 1 finest cell);
//!   0.001 and 0.003 end on the torus, one component, in all but one of
//!   twelve runs (step sizes × source resolutions). Hence the defaults:
//!   `distance_weight` 0.001, step half a finest cell, tolerance a tenth of
//!   it, and convergence only when every zero-set sample is within half a
//!   finest cell of the target, so a piece pinched off on the way must
//!   vanish before the morph stops. `|∇f|` then ranges over about 0.4–1.5
//!   on the zero set instead of 0.8–1.2.
//! - **Keep a margin.** The domain boundary gets only weak rows; with the
//!   cube's faces 1.3 finest cells inside `D` (margin 0.2, depth 4) open
//!   sheets appeared there. The holed-cube settings use margin 0.5.
//! - **The curvature speed's no-split result (Fig. 3) holds for "┌" → "┐"
//!   but not for "T" → "C"**, and for "┌" → "┐" only with limits (see
//!   below).
//! - Cost: one evolution step costs the zero-set samples (marching cubes on
//!   a lattice of a third of the smallest leaf, culled per leaf, then Newton
//!   projection), `O(samples × support²)` assembly and a sparse Cholesky
//!   factorization of the `n × n` normal matrix whose symbolic part is
//!   reused across steps; steps cost more with the number of surface
//!   samples (`∝ area / h_min²`) than with `n`.
//!
//! Measurements (performance, the final refinement, the paper's "┌" → "┐"
//! and "T" → "C" cases) are in the repository's `docs/EXPERIMENTS.md`.
//!
//! # Example
//! The whole method from two solids (here CSG-free shapes; meshes,
//! distance volumes and implicits work the same way):
//! ```
//! use isomorph_common::{Control, Morph, Shape, Solid, models};
//! use isomorph_tspline::{TsplineMorph, TsplineSettings};
//!
//! let (sphere, torus) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(models::torus()));
//! let morph = TsplineMorph::new(&sphere, &torus, &TsplineSettings::default(), &Control::new())?;
//! assert!(morph.report().converged);
//! // Projection frames end the sequence exactly on the target's surface.
//! assert_eq!(morph.frame_mesh(1.0, 0)?.genus(), Some(1));
//! # Ok::<(), isomorph_tspline::TsplineError>(())
//! ```
//!
//! The paper-level steps, fit and evolution, on their own:
//! ```
//! use glam::DVec3;
//! use isomorph_common::Control;
//! use isomorph_tspline::{EvolveSettings, FitSettings, Outcome, TMesh, TMeshSettings, demo, evolve, fit};
//! use std::sync::Arc;
//!
//! // A T-mesh refined around spheres of radius 0.6 and 0.4 (domain units).
//! let (a, b) = (demo::sphere_samples(800, 0.6, DVec3::ZERO), demo::sphere_samples(800, 0.4, DVec3::ZERO));
//! let samples: Vec<DVec3> = a.iter().chain(&b).copied().collect();
//! let mut settings = TMeshSettings::default();
//! settings.max_depth = 4;
//! let mesh = Arc::new(TMesh::build(&samples, &settings)?);
//! // Fit the source's signed distance (positive inside), then evolve.
//! let (f0, report) = fit(mesh, |p: DVec3| 0.6 - p.length(), &a, &FitSettings::default())?;
//! assert!(report.max_surface_error < 0.02);
//! let target = |p: DVec3| 0.4 - p.length();
//! let run = evolve(&f0, target, &b, &EvolveSettings::default(), &Control::new())?;
//! assert_eq!(run.outcome, Outcome::Converged);
//! # Ok::<(), isomorph_tspline::TsplineError>(())
//! ```

mod basis;
mod bspline;
pub mod demo;
mod error;
mod evolution;
mod fit;
mod lsq;
mod morph;
mod sampling;
mod tmesh;
mod tspline;

pub use basis::Eval;
pub use error::TsplineError;
pub use evolution::{Evolution, EvolveSettings, Outcome, Speed, StepStats, evolve};
pub use fit::{FitReport, FitRound, FitSettings, Refinement, fit};
pub use morph::{Align, FrameField, Mesher, TsplineMorph, TsplineSettings, morph};
pub use sampling::Sampler;
pub use tmesh::{MAX_DEPTH, TMesh, TMeshSettings};
pub use tspline::TSpline;
