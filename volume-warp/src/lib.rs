//! Volume warping with trivariate cubic B-splines after T. J. True, *Volume
//! Warping*, M.S. thesis, Brown University, 1992
//! (`../shared/papers/true-1992-volume-warping.txt`).
//!
//! A sampled density (a `u8` voxmap, 0–255 with the surface at 127.5 as in
//! the thesis, or an `f32` field) is *pushed forward* through a smooth map
//! `B` of space defined by a lattice of control points: the warped volume
//! at `B(x)` holds the source density at `x`. Moving control points, or
//! dragging points of the volume directly, bends the shape; only the
//! regions a control point influences are recomputed.
//!
//! # Paper sections → modules
//! | thesis | module (source file): items |
//! |---|---|
//! | §5.1 basis `B0…B3`, eq. 3 | [`basis`], `map` ([`BSplineMap`]) |
//! | §5.5 control point placement (identity map) | [`BSplineMap::identity`] |
//! | §5.2 rapid evaluation, table eq. 4, eq. 5 | `table` ([`CoefficientTable`], [`DeformationArray`]); beyond the thesis, its tensor-product factorization [`Evaluation::Separable`] |
//! | §5.3 map-and-round, main loop with local updates | `pushforward` ([`Filter::Round`]), `warp` ([`VolumeWarp::move_control_points`]) |
//! | §5.4 antialiasing box filter, weight normalization | `pushforward` ([`Filter::Box`]) |
//! | §6 direct manipulation (after Hsu et al. 1992) | `manipulate` ([`solve_drag`], [`VolumeWarp::drag`]) |
//! | beyond the thesis: backward resampling by Newton inversion | [`Filter::Backward`], [`BSplineMap::inverse`] |
//! | the map in world space (`Fn(Vec3) -> Vec3`, approximate inverse), one volume's warp animated ([`WarpAnimation`]) | `morph` ([`WorldMap`]) |
//! | the morph contract: two solids warped towards each other and cross-dissolved | `contract` ([`WarpMorph`], [`WarpMorphSettings`], [`WarpSpec`]) |
//!
//! # Choices where the thesis is open
//! - Coordinates are source voxel indices; a lattice of `C` points per axis
//!   spans `C − 3` regions of `h = n/(C − 3)` voxels. The table of §5.2 needs
//!   `h` to be an integer `G` ([`Evaluation::Table`]). [`Evaluation::Auto`]
//!   uses the tensor-product factorization of the same weight products
//!   ([`Evaluation::Separable`]: 4 terms per voxel instead of 64, any size),
//!   which measured 4.5× faster than the table; table, separable and direct
//!   evaluation agree to 1e-5 voxels (tested).
//! - Control points are stored as displacements from their rest positions,
//!   so the untouched lattice reproduces the input bit for bit.
//! - The target is the source padded by `pad` voxels per side (the thesis'
//!   TSIZE − ISIZE); density pushed beyond it is dropped.
//! - Local updates subtract the old contribution exactly instead of
//!   zeroing the old footprint (the thesis' shortcut), so they equal a full
//!   recompute up to float rounding (tested with random moves).
//! - Map-and-round averages voxels that land on the same target voxel.
//! - **Folds** (control points moved so far that `B` is not injective) are
//!   not rejected: as the thesis says, the box filter handles them by
//!   averaging overlapping images (weight above one is divided out);
//!   the backward filter shows one sheet. [`DeformationArray::folded_cells`]
//!   (via [`VolumeWarp::deformation`]) counts the voxel cells where the map
//!   folds, so callers can detect and report them.
//!
//! # Guarantees
//! Identity map ⇒ the target equals the source (padded) exactly, for `u8`
//! and `f32` and every filter; a whole-voxel translation shifts exactly;
//! results do not depend on the thread count. Not guaranteed: exact mass
//! conservation (the box filter's bounding boxes over-cover sheared voxels;
//! the weight normalization compensates only approximately).
//!
//! # The morph contract
//! [`WarpMorph::new`] morphs two [`Solid`](isomorph_common::Solid)s by
//! warping both densities towards each other and cross-dissolving them
//! its correspondence is the moment alignment by default,
//! or landmarks solved by direct manipulation.
//!
//! ```
//! use isomorph_common::{Control, Morph, Shape, Solid, models};
//! use isomorph_warp::{WarpMorph, WarpMorphSettings};
//!
//! let (ball, torus) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(models::torus()));
//! let morph = WarpMorph::new(&ball, &torus, &WarpMorphSettings::default(), &Control::new())?;
//! assert_eq!(morph.frame_mesh(0.0, 0)?.genus(), Some(0));
//! assert_eq!(morph.frame_mesh(1.0, 0)?.genus(), Some(1));
//! # Ok::<(), isomorph_warp::WarpError>(())
//! ```
//!
//! # Cost
//! A full box-filtered warp of a 256³ `u8` volume takes about 0.3 s on two
//! cores and a one-control-point local update of 128³ under 10 ms
//! (`cargo bench -p isomorph-benches --bench warp`; figures and history in
//! `docs/EXPERIMENTS.md`). A [`WarpMorph`] frame costs two backward warps
//! of its lattice.

//! # Example: one volume, direct manipulation
//! ```
//! use isomorph_common::Grid3;
//! use isomorph_warp::{Filter, Handle, VolumeWarp, WarpSettings};
//! use glam::{UVec3, Vec3};
//!
//! // A 24³ u8 density: a ball of radius 5 voxels at (10, 12, 12).
//! let mut ball = Grid3::new(UVec3::splat(24), Vec3::ZERO, 1.0, 0u8)?;
//! for n in 0..ball.len() {
//!     let d = 5.0 - (ball.node_of(n).as_vec3() - Vec3::new(10.0, 12.0, 12.0)).length();
//!     ball.data_mut()[n] = (127.5 + 64.0 * d).clamp(0.0, 255.0) as u8;
//! }
//! let settings = WarpSettings { csize: 7, pad: 2, filter: Filter::Box, ..Default::default() };
//! let mut warp = VolumeWarp::new(ball.clone(), settings)?;
//! // The identity warp reproduces the input (shifted by the padding).
//! assert_eq!(warp.target().get(12, 14, 14), ball.get(10, 12, 12));
//!
//! // Drag the ball's centre 4 voxels along +x.
//! let drag = warp.drag(&[Handle { point: Vec3::new(10.0, 12.0, 12.0), goal: Vec3::new(14.0, 12.0, 12.0) }], None)?;
//! assert!(drag.residual < 1e-3);
//! // The centre's density now sits 4 voxels further along x (+2 padding).
//! assert!(*warp.target().get(18, 14, 14).unwrap() > 200);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod basis;
mod contract;
mod error;
mod manipulate;
mod map;
mod morph;
mod pushforward;
mod table;
mod warp;

pub use contract::{WarpMorph, WarpMorphSettings, WarpSpec};
pub use error::WarpError;
pub use manipulate::{Drag, Handle, solve_drag};
pub use map::BSplineMap;
pub use morph::{WarpAnimation, WorldMap};
pub use pushforward::{Density, Filter};
pub use table::{CoefficientTable, DeformationArray, Evaluation, Evaluator};
pub use warp::{MAX_PAD, VolumeWarp, WarpSettings};
