//! Files and pictures of isomorph, kept out of the geometry core: mesh files
//! ([`mesh`]: OBJ, PLY, STL), NumPy and headerless volumes ([`npy`],
//! [`raw`]), the software preview
//! renderer ([`render`]) and the sequence exporter ([`export`]) that
//! polygonizes the frames of any [`isomorph_common::Morph`] and writes
//! meshes, a contact sheet and `report.json`.

pub mod compare;
pub mod export;
pub mod inputs;
pub mod mesh;
pub mod npy;
pub mod png_gray;
pub mod raw;
pub mod render;
pub mod usd;
