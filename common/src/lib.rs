//! The shared core of isomorph: fields, grids, analytic shapes, triangle
//! meshes, polygonization, mesh metrics, affine transforms, the [`Morph`]
//! trait with its sequence exporter, and a software preview renderer.
//!
//! # Conventions
//! - **Positive inside**: every field is positive inside a shape, zero on its
//!   surface and negative outside. A field with another iso level says so.
//! - World space is `f32` with [`glam`] types; grids are cubic-voxel, x-fastest.
//! - Errors are typed per failure domain; nothing panics on user input.

pub mod aabb;
pub mod alignment;
pub mod export;
pub mod fast_marching;
pub mod field;
pub mod grid;
pub mod marching_cubes;
pub mod marching_squares;
pub mod mesh;
pub mod models;
pub mod morph;
pub mod npy;
pub mod render;
pub mod scan_conversion;
pub mod sdf;
pub mod shape;
pub mod transform;

pub use aabb::Aabb;
pub use field::{Bounded, Field3};
pub use glam;
pub use grid::{Grid2, Grid3, GridError};
pub use mesh::{MeshError, TriMesh};
pub use morph::{Frame, Morph};
pub use shape::{Shape, ShapeError};
pub use transform::{AffineParts, AffinePath, TransformError};
