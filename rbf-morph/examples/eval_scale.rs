//! Evaluation time of a large slice on a lattice by the dual tree and
//! directly: `n`
//! centres on a sphere (t = 0) and a torus (t = 1), seeded ±1 weights
//! (not a fit), a slice (default t = 0.5) on a `res³` lattice over
//! [-0.5, 0.5]³ (`Field3::values_on_lattice`):
//!
//! `cargo run --release -p isomorph-rbf --example eval_scale -- 100000 128`
//!
//! The third argument is the kernel (`tps`, `r3`), the fourth the slice's
//! `t` (default 0.5). With a fifth argument `sparse` (`… 100000 128 tps
//! 0.5 sparse`), times the
//! near-surface polygonizer on the treecode and directly instead.
//!
//! Prints the dual tree's time, and the direct time and largest difference
//! on every 61st lattice node.

use isomorph_common::Field3;
use isomorph_common::glam::{UVec3, Vec3};
use isomorph_rbf::{Evaluation, Kernel, Slice3};
use std::f32::consts::{PI, TAU};
use std::time::Instant;

/// Every how many lattice nodes the direct sum is taken for comparison.
const STRIDE: usize = 61;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let res: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(128);
    let kernel = args.get(3).and_then(|s| Kernel::from_name(s)).unwrap_or_default();
    let t: f32 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(0.5);
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
            offsets.push(t * t);
            weights.push(w + 0.1 * random());
        }
        for (tube, w) in [(0.12f32, 1.0f32), (0.11, -1.0)] {
            let ring = 0.3 + tube * v.cos();
            centres.push([ring * u.cos(), ring * u.sin(), tube * v.sin()]);
            offsets.push((1.0 - t) * (1.0 - t));
            weights.push(w + 0.1 * random());
        }
    }
    let slice = Slice3::from_sources(kernel, &centres, &offsets, &weights);
    if args.get(5).is_some_and(|a| a == "sparse") {
        near_surface(&slice, res as u32);
        return;
    }
    let h = 1.0 / (res - 1) as f32;
    let dims = UVec3::splat(res as u32);
    let mut fast = vec![0.0f32; res * res * res];
    let (start, cpu) = (Instant::now(), user_seconds());
    slice.clone().with_evaluation(Evaluation::Treecode).values_on_lattice(
        dims,
        Vec3::splat(-0.5),
        h,
        &mut fast,
    );
    let (tree_s, tree_cpu) = (start.elapsed().as_secs_f64(), user_seconds() - cpu);
    // The same nodes as `values_by_rows` forms them.
    let node = |i: usize| {
        let yz = Vec3::splat(-0.5) + h * Vec3::new(0.0, ((i / res) % res) as f32, (i / res / res) as f32);
        yz + Vec3::new(h * (i % res) as f32, 0.0, 0.0)
    };
    let some: Vec<Vec3> = (0..res * res * res).step_by(STRIDE).map(node).collect();
    let mut direct = vec![0.0f32; some.len()];
    let (start, cpu) = (Instant::now(), user_seconds());
    slice.with_evaluation(Evaluation::Direct).values(&some, &mut direct);
    let (direct_s, direct_cpu) = (start.elapsed().as_secs_f64(), user_seconds() - cpu);
    let worst = fast.iter().step_by(STRIDE).zip(&direct).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    let range =
        direct.iter().fold(f32::MIN, |m, v| m.max(*v)) - direct.iter().fold(f32::MAX, |m, v| m.min(*v));
    println!(
        "{} centres, {res}³ lattice: dual tree {tree_s:.2} s ({tree_cpu:.2} s user CPU); direct on every {STRIDE}th node {direct_s:.2} s \
         ({direct_cpu:.2} s user; ×{STRIDE} = {:.1} s, {:.1} s user); max |difference| {worst:.3e}, range {range:.3e}, {:.2e} of the range",
        centres.len(),
        direct_s * STRIDE as f64,
        direct_cpu * STRIDE as f64,
        worst / range
    );
}

/// The process's user CPU time in seconds (Linux `/proc/self/stat`, 100
/// ticks per second), or 0 where it cannot be read.
fn user_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            s.rsplit(')').next().and_then(|rest| rest.split_whitespace().nth(11)?.parse::<f64>().ok())
        })
        .map_or(0.0, |ticks| ticks / 100.0)
}

/// Times the near-surface polygonizer of `slice` at `res` by the treecode
/// and directly, and prints both meshes' sizes and nodes evaluated. The
/// weights are not a fit, so the level is the median of the slice on an
/// 8³ lattice rather than 0.
fn near_surface(slice: &Slice3, res: u32) {
    use isomorph_common::Aabb;
    use isomorph_common::marching_cubes::{SparseSettings, polygonize_near_surface};
    let mut coarse = vec![0.0f32; 512];
    slice.values_on_lattice(UVec3::splat(8), Vec3::splat(-0.5), 1.0 / 7.0, &mut coarse);
    coarse.sort_by(f32::total_cmp);
    let iso = coarse[256];
    for evaluation in [Evaluation::Treecode, Evaluation::Direct] {
        let field = slice.clone().with_evaluation(evaluation);
        let (start, cpu) = (Instant::now(), user_seconds());
        let (mesh, stats) =
            polygonize_near_surface(&field, &Aabb::cube(0.5), res, iso, &SparseSettings::default()).unwrap();
        println!(
            "{evaluation:?}: {:.2} s ({:.2} s user CPU), {} of {} nodes evaluated, {} vertices, {} triangles",
            start.elapsed().as_secs_f64(),
            user_seconds() - cpu,
            stats.evaluated,
            stats.nodes,
            mesh.positions.len(),
            mesh.triangles.len()
        );
    }
}
