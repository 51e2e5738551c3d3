//! Times [`redistance`] on the bench's 256³ torus (R = 0.3, r = 0.12 over
//! [-0.5, 0.5]³, distance times a smooth factor in [1, 2]) and reports its
//! error against the exact torus distance, everywhere and within two voxels
//! of the surface. Run with
//! `cargo run --release -p isomorph-common --example redistance_timing [n] [runs]`.

use glam::{UVec3, Vec3};
use isomorph_common::fast_marching::{FastMarchingSettings, redistance};
use isomorph_common::{Grid3, Shape};
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1).map(|s| s.parse().ok());
    let n: u32 = args.next().flatten().unwrap_or(256);
    let runs: usize = args.next().flatten().map_or(5, |r: u32| r as usize).max(1);
    let torus = Shape::torus(0.3, 0.12);
    let field = |p: Vec3| torus.distance(p) * (1.5 + 0.5 * (3.0 * p.x).sin() * (2.0 * p.y).cos());
    let grid =
        Grid3::sample(&field, UVec3::splat(n), Vec3::splat(-0.5), 1.0 / (n - 1) as f32).expect("grid fits");
    let settings = FastMarchingSettings::default();
    let mut times = Vec::with_capacity(runs);
    let mut sdf = None;
    let cpu = cpu_seconds();
    for _ in 0..runs {
        let t = Instant::now();
        sdf = Some(redistance(&grid, &settings).expect("torus has a surface"));
        times.push(t.elapsed().as_secs_f64());
    }
    let cpu = cpu_seconds().map(|c| (c - cpu.unwrap_or(0.0)) / runs as f64);
    times.sort_by(f64::total_cmp);
    println!(
        "redistance {n}³: median {:.3} s, min {:.3} s over {runs} runs; {:.2} s of CPU time per run",
        times[runs / 2],
        times[0],
        cpu.unwrap_or(f64::NAN)
    );
    let sdf = sdf.expect("at least one run");
    let h = sdf.spacing();
    let (mut all, mut near) = (0.0f32, 0.0f32);
    for (index, &v) in sdf.data().iter().enumerate() {
        let m = sdf.node_of(index);
        let d = torus.distance(sdf.position(m.x, m.y, m.z));
        let e = (v - d).abs() / h;
        all = all.max(e);
        if d.abs() <= 2.0 * h {
            near = near.max(e);
        }
    }
    println!("max error {all:.4} voxel, within 2 voxels of the surface {near:.4} voxel");
}

/// User plus system CPU time of this process (all threads) in seconds, from
/// `/proc/self/stat` (Linux; `None` elsewhere).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name, which ends with the last ')'.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
