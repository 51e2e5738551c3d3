//! Times marching cubes on a 256³ grid of a torus signed distance
//! (R = 0.3, r = 0.12 over [-0.5, 0.5]³). Run with
//! `cargo run --release -p isomorph-common --example mc_timing [runs]`.

use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::{Aabb, Grid3};
use std::time::Instant;

fn main() {
    let runs: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(15);
    let torus = |p: glam::Vec3| 0.12 - glam::Vec2::new(p.truncate().length() - 0.3, p.z).length();
    let t = Instant::now();
    let grid = Grid3::sample_box(&torus, &Aabb::cube(0.5), 256).expect("grid fits");
    println!("sampling {:?}: {:.1} ms", grid.dims(), t.elapsed().as_secs_f64() * 1e3);
    let mut times = Vec::with_capacity(runs);
    let mut sizes = (0, 0);
    for _ in 0..runs {
        let t = Instant::now();
        let mesh = marching_cubes(&grid, 0.0);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        sizes = (mesh.positions.len(), mesh.triangles.len());
    }
    times.sort_by(f64::total_cmp);
    println!(
        "marching cubes: median {:.1} ms, min {:.1} ms over {runs} runs; {} vertices, {} triangles",
        times[runs / 2],
        times[0],
        sizes.0,
        sizes.1
    );
}
