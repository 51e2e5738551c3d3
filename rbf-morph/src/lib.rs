//! Shape transformation with variational implicit functions after Greg Turk
//! and James F. O'Brien, *Shape Transformation Using Variational Implicit
//! Functions*, SIGGRAPH 1999 (`../shared/papers/turk-obrien-1999-…`).
//!
//! Two `N`-dimensional shapes become one implicit function in `N + 1`
//! dimensions: boundary constraints (value 0) and inward normal constraints
//! (value 1) of shape A are placed at `t = 0`, those of shape B at
//! `t = t_max`, and one variational (thin-plate / polyharmonic) interpolation
//! through all of them gives `f(x, t)`. The in-between shape at `t` is the
//! zero set of the slice, positive inside.
//!
//! # Paper sections → items
//! | paper | items |
//! |---|---|
//! | §3 variational interpolation, eq. 2–3, the bordered system | [`Interpolant`], [`FitSettings`], [`FitReport`], [`Kernel`], [`Solver`] |
//! | §4.1 constraints from a grayscale image | [`image_constraints`] |
//! | §4.2 constraints from points with normals / meshes | [`constraints`] |
//! | §5.1, §5.2 shape transformation in N + 1 dimensions, §6.2 separation | [`RbfMorph`], [`RbfSettings`], [`ContourMorph`], [`lift`] |
//! | §6, §6.1, §6.2 surface reconstruction from parallel (any spacing) and non-parallel contours | [`ContourSet`], [`Plane`], [`ContourSurface`] |
//! | appendix: warping by point correspondences, eq. 4–5 unwarping | [`WarpedContourMorph`] for 2D shapes as in Fig. 9, [`WarpedMorph`] for 3D, [`HalfwayWarps`], [`DisplacementWarp`] |
//! | §7 influence shapes (triangle in N + 2, tetrahedron in N + 3 dimensions) | [`InfluenceShapes`], [`InfluencePath`] |
//! | §5.2 polygonizing only near the surface (the paper uses Bloomenthal's continuation polygonizer) | `isomorph_common::marching_cubes::level_set_mesh` |
//! | fast evaluation of slices (what the paper's Bloomenthal polygonizer calls) | [`Slice3`], [`Slice2`] |
//!
//! # Choices where the paper leaves details open
//! - **Kernel**: `r² log r` (eq. 2) is the default; `r³` is selectable
//!   ([`Kernel`] documents how each shapes the in-between frames).
//! - **Solver**: the paper uses symmetric LU. Here the polynomial part is
//!   projected out with `D + 1` Householder reflectors applied from both
//!   sides, and the remaining symmetric positive definite block is factored
//!   by Cholesky (faer, f64, in place) — accurate to about 1e-10 where LU
//!   loses 4–6 digits; Bunch–Kaufman `LBLᵀ` is the fallback when Cholesky
//!   fails. When the constraints form two groups well apart — the two
//!   shapes at `t = 0` and `t = t_max` — the default [`Solver::Auto`] uses
//!   the **slab solver** instead: each shape's diagonal block is factored by
//!   Cholesky, the smooth coupling between the shapes is approximated at
//!   rank 64 (randomized range finder), and together they precondition
//!   conjugate gradients, run in f64 to the backward error of a direct
//!   solve (4 iterations with `r² log r`, 8 with `r³` on the reference case).
//!   That is about a quarter of the dense factorization's flops; if it does
//!   not converge the dense Cholesky runs. From [`HIERARCHICAL_MIN`] = 4000
//!   constraints (both kernels; measured: there it takes 1.7× less CPU
//!   and half the memory of the slab solver, at 3000 as much CPU, at 2000
//!   more) [`Solver::Auto`] uses the **hierarchical solver**
//!   ([`Solver::Hierarchical`], [`Factorization::Hierarchical`]) instead:
//!   a kd-type cluster tree over the `N + 1`-dimensional constraint points,
//!   the kernel matrix as an H-matrix (strong admissibility
//!   `max(diam) ≤ 3 dist`, far blocks compressed by partially pivoted
//!   adaptive cross approximation to a relative Frobenius tolerance
//!   `ε = 1e-12` wherever that is smaller than the dense block, near blocks
//!   dense, all in f64), the same Householder
//!   projection onto the null space of `Pᵀ` applied implicitly, and
//!   flexible GMRES preconditioned by the two-level overlapping domain
//!   decomposition of Beatson, Light & Billings (FastRBF's): local
//!   interpolation problems of at most 128 points plus an overlap of half
//!   their diameter (at most 320 points), factored once by Cholesky and
//!   stored in single precision (the preconditioner only approximates the
//!   inverse; FGMRES works in f64), and a coarse
//!   problem of about 1500 points fitted to the residual the local
//!   corrections leave (multiplicative, one more H-matrix product per
//!   iteration). The cluster tree never splits a layer of equal
//!   coordinates, so each subdomain is a patch of one of the two shapes
//!   whatever their point counts. GMRES stops at a relative residual of
//!   `1e-11`, or when its normwise backward error
//!   `‖g − B y‖ / (‖B‖ ‖y‖ + ‖g‖)` reaches round-off (`1.1e-16`, what the
//!   dense Cholesky attains; real meshes' close boundary and normal
//!   constraints give `rcond` ~1e-10, and then the relative residual stops
//!   near 1e-10); if it does not converge within 300 iterations the dense
//!   Cholesky runs, or [`RbfError::NotConverged`] is returned when the
//!   dense system would not fit in memory. **Error bound**: the weights
//!   solve the H-matrix system to `1e-11 ‖h‖` (or that backward error),
//!   and the H-matrix differs
//!   from `Φ` by at most about `ε ‖Φ‖_F` (tested against the dense product);
//!   so the residual at the constraints is about `1e-11 ‖h‖ + ε ‖Φ‖_F ‖d‖`
//!   (reported, evaluated through the H-matrix), and on the reference case
//!   the fitted function agrees with the dense solve to within 1e-6 of its
//!   range at probe points in and around the constraints (both kernels;
//!   tested at 3000 constraints, and at 2000, 8000 and 16000 in a
//!   release-only test: at most 9e-8 of the range).
//!
//!   Scaling on the reference case (sphere → torus in 4D, boundary and
//!   inward normal constraints; the `fit_scale` example: `cargo run
//!   --release -p isomorph-rbf --example fit_scale -- N KERNEL
//!   hierarchical`; process user CPU and peak resident memory from
//!   `/usr/bin/time`, including the constraints' construction; on a
//!   2-core machine shared with other jobs at load 12–15, so wall times
//!   were 2.5–5× these CPU times):
//!
//!   | constraints | `r² log r`: GMRES | CPU | peak memory | `r³`: GMRES | CPU | peak memory |
//!   |---|---|---|---|---|---|---|
//!   | 4000 | 11 | 0.44 s | 80 MB | 19 | 0.56 s | 81 MB |
//!   | 8000 | 13 | 1.00 s | 128 MB | 21 | 1.17 s | 129 MB |
//!   | 16000 | 14 | 2.41 s | 236 MB | 28 | 3.60 s | 238 MB |
//!   | 32000 | 15 | 5.55 s | 478 MB | 26 | 6.69 s | 483 MB |
//!   | 64000 | 26 | 15.9 s | 1.06 GB | 58 | 26.2 s | 1.08 GB |
//!   | 100000 | 19 | 28.8 s | 1.78 GB | 46 | 35.0 s | 1.78 GB |
//!
//!   Since this table, the factorization reuses its work buffers and
//!   stores middle-size far-field terms as scaled `i32`: at 100000, on an
//!   idle machine, 17 and 45 GMRES steps, 28.7 s and 43.4 s of CPU (13.1 s
//!   and 21.0 s of fit wall time), 1.50 and 1.49 GB peak.
//!
//!   Time grows about as `n^1.3` and memory as `n log n`; 100000
//!   constraints fit within 2 GB with either kernel (`r³`'s systems are
//!   worse conditioned, `rcond` 5e-14 at 100000, so GMRES needs more
//!   steps). The dense Cholesky would need 12 `n²` bytes (2.9 GiB at
//!   16000, 75 GiB at 100000). On real meshes
//!   (the bunny → Stanford dragon morph, `--points 10000` and `25000`:
//!   23678 and 48572 constraints, `rcond` ~1e-9) the iteration takes 18
//!   and 24 steps, 6.8 s and 20 s of CPU, 0.5 and 1.2 GB; the whole
//!   `isomorph morph --method rbf --points 25000 --res 128 --frames 9`
//!   command takes 50 s (98 s of CPU), ending 0.04 voxels (mean) from
//!   the target.
//!   Measurement history and commands: `docs/EXPERIMENTS.md` (issue 21).
//!   The reciprocal condition number
//!   and the largest residual at the constraints are reported in
//!   [`FitReport`].
//! - **Greedy centres** ([`Centres::Greedy`], `--tolerance` on the command
//!   line): FastRBF's "fit to an accuracy" through a growing subset of
//!   the constraints, new centres taken worst first but spread over space
//!   (the [`GreedySettings`] docs). The residuals that decide each round
//!   are exact (`f64` sums), not the fast evaluation's. On 1,000,000
//!   constraints of the reference case (the `greedy_scale` example,
//!   `r² log r`) a tolerance of 2e-2 of the normal value is reached at
//!   every constraint with 21173 centres in 6 rounds: 96 s of CPU, 0.42 GB
//!   peak. Samples of a real mesh at its own resolution need nearly all of
//!   their points at 1e-1 or tighter; past half of them the fit takes all.
//! - **Near-duplicate constraints** (shared mesh vertices) are merged when
//!   their values agree and rejected with [`RbfError::NearDuplicate`] when
//!   they contradict ([`DuplicatePolicy`]); **smoothing** `λ` is offered for
//!   noisy data.
//! - **Normal offset**: `k = 0.01` of the bounding-box diagonal by default
//!   ([`constraints::NormalOffset`]); one pixel for images.
//!
//! - **Contours** (§6): polylines decide inside by even-odd nesting, not by
//!   orientation; their normal constraints lie in the slice plane; the
//!   bounds grow until they enclose the rounded caps.
//! - **Warping** (appendix): the normal constraints are displaced with the
//!   boundary constraints (the paper names only the latter), so they stay
//!   inside the warped shapes; frames are unwarped by pulling the slice back
//!   through eq. 4–5, with the chain-rule gradient.
//!
//! # Guarantees
//! - Interpolation is exact: the f64 interpolant matches every (merged)
//!   constraint to 1e-8 relative (tested, also by proptest on random sets in
//!   2–6 D, with both kernels); the hierarchical solver to its stopping
//!   rule, which on large ill-conditioned sets (`rcond` ~1e-12) leaves up
//!   to a few 1e-8 (reported in [`FitReport::max_residual`]). Slices
//!   evaluate in f32 and agree with it to about 1e-4 of the unit
//!   constraint value on the analytic reference shapes; at the large,
//!   cancelling weights of real meshes (`Σ|λ|` 2e7 for bunny → teapot at
//!   1500 points) their error reaches ~0.1–0.9, so the morph's frames
//!   ([`RbfMorph`]'s `frame_mesh`) recompute the lattice nodes near the
//!   surface and in small islands with the exact `f64` sum, and the greedy
//!   fit its deciding residuals.
//! - Bad input (too few constraints, coplanar positions, NaN, singular
//!   systems, blank images) is a typed [`RbfError`], never a panic.
//! - Fast evaluation ([`Evaluation::Auto`] from 2000 centres, or
//!   [`Evaluation::Treecode`]) differs from the direct sum by at most
//!   `ε Σ_j |λ_j| R_max^k` in normalized coordinates (`ε` = 1e-4 for both
//!   kernels, `k` = 2 for `r² log r`, 3 for `r³`, `R_max` the largest
//!   point–centre distance; [`treecode`] module docs), plus the `f32`
//!   round-off both share (tested on lattices at t = 0 and 0.5, at scattered
//!   points at t = 0.5). The bound ignores the
//!   weights' cancellation, so the tests also check the error against the
//!   slice's range of fitted morphs: on lattices at t = 0 and 0.5 within
//!   2e-5 (`r² log r`) and 3e-4 (`r³`, whose larger weights raise the
//!   round-off); at scattered points at t = 0.5 within 1e-4 (at t = 0,
//!   1.8e-4 was measured: `docs/EXPERIMENTS.md`).
//! - Results do not depend on the number of threads.
//!
//! Non-guarantees: the zero set of a slice between the two shapes has no
//! bound on its distance to either input (that is the point of the method);
//! the dense fit costs `O(n³)` time and `12 n²` bytes (3 GiB at 16000
//! constraints); from 2000 centres ([`Evaluation::Auto`], the default) large
//! batches of points go through a treecode ([`treecode`]: far field
//! interpolated within a stated bound, near field exact) and whole
//! lattices of 3D slices (`Grid3::fill_from`, `Field3::values_on_lattice`)
//! through the [`dual_tree`] (the same bound); smaller cases, and
//! [`Evaluation::Direct`], sum every centre at every point.
//!
//! # Cost
//! The dense fit is `O(n³)` time and `12 n²` bytes for `n` constraints (the
//! hierarchical one, from 4000: see the solver choice above);
//! evaluating a slice is `O(n)` per point directly, about `O(log n)` per
//! point by the [`treecode`] and the [`dual_tree`], and frame meshes
//! evaluate it only near the surface. At the defaults ([`RbfSettings`]: 400 points per shape,
//! 1600 constraints) a morph is built in a fraction of a second; measured
//! figures are in `docs/EXPERIMENTS.md` (`cargo bench -p isomorph-benches
//! --bench rbf`).

//! # Example: a 3D morph
//! ```
//! use isomorph_common::{Control, Morph, Shape, Solid};
//! use isomorph_rbf::{Kernel, RbfMorph, RbfSettings};
//!
//! let sphere = Solid::shape(Shape::sphere(0.3));
//! let cube = Solid::shape(Shape::rounded_cuboid(glam::Vec3::splat(0.25), 0.05));
//! let settings = RbfSettings { points: 80, kernel: Kernel::ThinPlate, ..Default::default() };
//! let morph = RbfMorph::new(&sphere, &cube, &settings, &Control::new())?;
//! assert!(morph.report().residual.as_ref().unwrap().value < 1e-8);
//! let mid = morph.frame_mesh(0.5, 32)?;
//! assert_eq!(mid.connected_components(), 1);
//! # Ok::<(), isomorph_rbf::RbfError>(())
//! ```
//!
//! The paper-level pieces stay public: [`constraints`] makes constraints
//! from meshes and fields, [`RbfMorph::from_constraints`] fits them with
//! [`TransformSettings`], [`Interpolant::fit`] fits any constraint set in
//! 2–6 dimensions, and [`ContourMorph`] morphs 2D shapes (e.g. images read
//! with `isomorph_io::png_gray::read_png_gray` and made into constraints
//! with [`image_constraints`]).

// Index loops mirror the formulas of the numeric code (reflectors, slices).
#![allow(clippy::needless_range_loop)]

pub mod constraints;
pub mod dual_tree;
pub mod figures;

mod error;
mod greedy;
mod image;
mod influence;
mod interpolant;
mod islands;
mod kernel;
mod reconstruct;
mod slice;
mod transform;
pub mod treecode;
mod warp;

mod duplicates;
mod hierarchical;
mod hmatrix;
mod slab;
mod solve;

pub use duplicates::DuplicatePolicy;
pub use error::RbfError;
pub use greedy::{Centres, GreedyReport, GreedyRound, GreedySettings};
pub use hierarchical::IterativeFailure;
pub use image::image_constraints;
pub use influence::{InfluencePath, InfluenceShapes};
pub use interpolant::{Constraint, FitReport, FitSettings, Interpolant};
pub use kernel::Kernel;
pub use reconstruct::{ContourSet, ContourSurface, Plane, ReconstructSettings};
pub use slice::{Slice2, Slice3};
pub use solve::{Factorization, HIERARCHICAL_MIN, Solver};
pub use transform::{ContourMorph, RbfMorph, RbfSettings, TransformSettings, lift};
pub use treecode::Evaluation;
pub use warp::{
    DisplacementWarp, HalfwayWarps, WarpedContourMorph, WarpedMorph, WarpedSettings, WarpedSlice,
    WarpedSlice2,
};
