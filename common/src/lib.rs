//! The geometry core of isomorph and its morph contract: fields, grids,
//! analytic shapes and CSG, triangle meshes with their metrics and exact
//! distances, polygonization, fast marching, scan conversion, moment
//! alignment, affine interpolation — and the [`Morph`] trait every method
//! implements, with its input type [`Solid`], its [`Control`] (progress,
//! cancellation, threads), its typed [`MorphReport`] and shared
//! [`MorphError`] kinds, and the naive baseline [`DistanceBlend`].
//!
//! # Papers → modules
//! | source | here |
//! |---|---|
//! | Breen & Whitaker 2001, §6.1 scan conversion of CSG models | [`scan_conversion`], [`Solid::distance_volume`] |
//! | Breen & Whitaker, Appendix: alignment by moments (centroid, principal axes, per-axis scale) | [`alignment`] |
//! | Breen & Whitaker eq. 25–26, Yang & Jüttler eq. 11: interpolated affine placement | [`AffineParts`], [`AffinePath`] |
//! | Breen & Whitaker Fig. 6, Turk & O'Brien Fig. 3 top row: the distance-volume blend | [`DistanceBlend`] |
//! | Breen & Whitaker's CSG of Barr superellipsoids (their Figs. 4–13) | [`Shape`], [`models`] |
//! | OpenVDB's sparse bricks (Museth 2013): values near a surface, a background side elsewhere | [`Bricks`] |
//! | Sethian's fast marching; Chopp's subvoxel projection | [`fast_marching`] |
//! | Lorensen & Cline's marching cubes (with a consistent face rule), marching squares | [`marching_cubes`], [`marching_squares`] |
//! | Hartmann 1998, the marching method (near-equilateral triangles of a chosen edge length; Yang & Jüttler's mesher) | [`marching_triangulation`] |
//! | exact mesh distance with generalized winding numbers (Barill et al. 2018) | [`sdf`], [`mesh::winding`], [`mesh::bvh`] |
//!
//! # Conventions
//! - **Positive inside**: every field is positive inside a shape, zero on its
//!   surface and negative outside. A field with another iso level says so.
//! - World space is `f32` with [`glam`] types; grids are cubic-voxel, x-fastest.
//! - Errors are typed per failure domain; nothing panics on user input.
//!
//! # Guarantees
//! - Marching cubes output is closed, 2-manifold and consistently oriented
//!   (outward) for level sets that do not reach the grid border (exhaustive
//!   tests over all cube cases), and the same for any thread count.
//! - Mesh distances are exact to rounding; their sign is the generalized
//!   winding number's, exact for closed meshes and sensible for open ones.
//! - [`Solid::distance_volume`] is a true signed distance for every kind of
//!   solid (scan conversion for CSG, never the raw CSG field).
//! - Grids refuse to allocate over the process-wide memory limit
//!   ([`set_memory_limit`]) with [`GridError::TooLarge`].
//!
//! Not guaranteed: the distance fields filled by fast marching are exact only
//! next to the surface (errors up to a few tenths of a voxel farther away,
//! see [`fast_marching`]); the CSG field of a [`Shape`] is a distance only
//! in places.
//!
//! # Example
//! ```
//! use isomorph_common::{BlendSettings, Control, DistanceBlend, Morph, Solid, models};
//!
//! // The naive baseline between Breen's mug and chain (CSG models,
//! // scan-converted to true signed distances): the blend pops pieces out of
//! // thin air where the shapes do not overlap.
//! let (mug, chain) = (Solid::shape(models::mug()), Solid::shape(models::chain()));
//! let settings = BlendSettings { resolution: 64, ..Default::default() };
//! let morph = DistanceBlend::new(&mug, &chain, &settings, &Control::new())?;
//! let mesh = morph.frame_mesh(0.3, 64)?;
//! assert_eq!(mesh.edge_stats().boundary_edges, 0); // closed
//! // The chain has three links; this frame has many more pieces: the
//! // artefact the morphing methods exist to avoid.
//! assert!(mesh.connected_components() > 3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod aabb;
pub mod alignment;
mod bricks;
#[cfg(feature = "conformance")]
pub mod conformance;
mod control;
pub mod fast_marching;
mod field;
mod grid;
mod landmarks;
pub mod marching_cubes;
pub mod marching_squares;
pub mod marching_triangulation;
pub mod mesh;
pub mod models;
mod morph;
pub mod scan_conversion;
pub mod sdf;
mod shape;
mod solid;
mod transform;

pub use aabb::Aabb;
pub use bricks::{BRICK, Bricks, NodeStore};
pub use control::{CancelToken, Control, Progress};
pub use field::{Bounded, Field3, GRADIENT_STEP};
pub use glam;
pub use grid::{
    Bytes, DEFAULT_MEMORY_LIMIT, Grid2, Grid3, GridError, MemoryLimitError, lattice_for_box, memory_limit,
    reserve_memory, set_memory_limit, trilinear_blend, values_by_rows,
};
pub use landmarks::{LandmarkError, Landmarks, MIN_LANDMARKS};
pub use mesh::trimesh::{MeshError, TriMesh};
pub use morph::{
    BlendSettings, BoxedError, BoxedMorph, ContourBlend, Details, DistanceBlend, DynField, Frame, MissedPart,
    Morph, MorphError, MorphExt, MorphFailure, MorphReport, Outcome, Residual, Side, StageTime, Stages,
    Value, check, check_time, placed_bounds,
};
pub use shape::{PlacedShape, Shape, ShapeError};
pub use solid::{DistanceField, Implicit, PROBE_RESOLUTION, Solid, validate_inputs};
pub use transform::{AffineParts, AffinePath, TransformError};
