//! Shared fixtures of the isomorph benchmarks: the reference shapes and grids
//! the bench IDs name, so every bench file measures the same inputs.

use glam::{UVec3, Vec3};
use isomorph_common::{Grid3, Shape, models};
use std::path::PathBuf;

/// The reference torus (R = 0.3, r = 0.12) sampled as a signed distance on
/// `n³` nodes over `[-0.5, 0.5]³`.
///
/// # Panics
/// If the grid does not fit the memory limit (benches only use small sizes).
pub fn torus_grid(n: u32) -> Grid3<f32> {
    let spacing = 1.0 / (n - 1) as f32;
    Grid3::sample(&models::torus(), UVec3::splat(n), Vec3::splat(-0.5), spacing).expect("bench grid fits")
}

/// The reference torus as an analytic shape.
pub fn torus() -> Shape {
    models::torus()
}

/// Path of a file in the repository's `data/` folder.
pub fn data_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join("data").join(name)
}
