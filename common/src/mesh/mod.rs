//! Triangle meshes: [`TriMesh`](crate::TriMesh) (at the crate root),
//! metrics, distances, procedural primitives, colour lookup. File IO lives in the
//! `isomorph-io` crate.

pub mod bvh;
pub mod color;
pub mod distance;
pub mod metrics;
pub mod primitives;
pub(crate) mod trimesh;
pub mod winding;
