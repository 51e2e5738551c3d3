//! Evaluation time of a large slice by the treecode and directly: `n`
//! centres on a sphere (t = 0) and a torus (t = 1), moment-free seeded
//! weights (not a fit), the t = 0.5 slice on a `res³` lattice over
//! [-0.5, 0.5]³ in one batch:
//!
//! `cargo run --release -p isomorph-rbf --example eval_scale -- 100000 128`
//!
//! Prints the treecode's time, and the direct time and largest difference
//! on every 64th lattice point.

use isomorph_common::Field3;
use isomorph_common::glam::Vec3;
use isomorph_rbf::{Evaluation, Kernel, Slice3};
use std::f32::consts::{PI, TAU};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let res: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(128);
    let kernel = args.get(3).and_then(|s| Kernel::from_name(s)).unwrap_or_default();
    let golden = PI * (3.0 - 5.0f32.sqrt());
    let (mut centres, mut offsets, mut weights) = (Vec::new(), Vec::new(), Vec::new());
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut random = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let per = n / 4;
    for i in 0..per {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / per as f32;
        let r = (1.0 - z * z).sqrt();
        let (s, c) = (golden * i as f32).sin_cos();
        let (u, v) = (TAU * i as f32 / per as f32, (golden * i as f32) % TAU);
        for (radius, w) in [(0.3f32, 1.0f32), (0.29, -1.0)] {
            centres.push([radius * r * c, radius * r * s, radius * z]);
            offsets.push(0.25);
            weights.push(w + 0.1 * random());
        }
        for (tube, w) in [(0.12f32, 1.0f32), (0.11, -1.0)] {
            let ring = 0.3 + tube * v.cos();
            centres.push([ring * u.cos(), ring * u.sin(), tube * v.sin()]);
            offsets.push(0.25);
            weights.push(w + 0.1 * random());
        }
    }
    let slice = Slice3::from_sources(kernel, &centres, &offsets, &weights);
    let h = 1.0 / (res - 1) as f32;
    let points: Vec<Vec3> = (0..res * res * res)
        .map(|i| Vec3::new((i % res) as f32, ((i / res) % res) as f32, (i / res / res) as f32) * h - 0.5)
        .collect();
    let mut fast = vec![0.0f32; points.len()];
    let start = Instant::now();
    slice.clone().with_evaluation(Evaluation::Treecode).values(&points, &mut fast);
    let tree_s = start.elapsed().as_secs_f64();
    let some: Vec<Vec3> = points.iter().step_by(64).copied().collect();
    let mut direct = vec![0.0f32; some.len()];
    let start = Instant::now();
    slice.with_evaluation(Evaluation::Direct).values(&some, &mut direct);
    let direct_s = start.elapsed().as_secs_f64();
    let worst = fast.iter().step_by(64).zip(&direct).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    let range =
        direct.iter().fold(f32::MIN, |m, v| m.max(*v)) - direct.iter().fold(f32::MAX, |m, v| m.min(*v));
    println!(
        "{} centres, {res}³ points: treecode {tree_s:.2} s; direct on every 64th point {direct_s:.2} s \
         (×64 = {:.1} s); max |difference| {worst:.3e}, range {range:.3e}",
        centres.len(),
        direct_s * 64.0
    );
}
