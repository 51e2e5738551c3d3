//! Where a frame's stray components (specks) come from: the fitted function
//! or its fast evaluation.
//!
//! `cargo run --release -p isomorph-rbf --example frame_specks -- SOURCE TARGET POINTS RES T...`
//!
//! Fits the RBF morph as `isomorph morph --method rbf` does (inputs fitted
//! to the unit box, `POINTS` per shape), then for each time `T` polygonizes
//! the frame in each of the modes of `MODES` (comma-separated; default
//! all): `sparse` (near its surface, default evaluation), `lattice` (the
//! whole lattice by the dual tree, with its error against the exact sum),
//! `frame` (as the CLI writes it: the lattice with its small sign islands
//! confirmed by the exact sum) and `direct` (near the surface, direct
//! sum), counts the components of each, and at one vertex of each of
//! the smallest components prints the default (treecode), direct `f32` and
//! exact `f64` values and the distance to the nearest constraint.

use glam::Vec3;
use isomorph_common::Grid3;
use isomorph_common::marching_cubes::{level_set_mesh, marching_cubes};
use isomorph_common::{Control, Field3, Morph, TriMesh};
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_rbf::{Evaluation, RbfMorph, RbfSettings};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 6 {
        eprintln!("usage: frame_specks SOURCE TARGET POINTS RES T...");
        std::process::exit(2);
    }
    let points: usize = args[3].parse().expect("POINTS is a number");
    let res: u32 = args[4].parse().expect("RES is a number");
    let times: Vec<f32> = args[5..].iter().map(|s| s.parse().expect("T is a number")).collect();
    let control = Control::new();
    let load = |spec: &str| load_solid(spec, &LoadOptions::default()).expect("readable input");
    let (source, target) = (load(&args[1]), load(&args[2]));
    let settings = RbfSettings { points, ..RbfSettings::default() };
    let start = Instant::now();
    let morph = RbfMorph::new(&source, &target, &settings, &control).expect("the fit");
    println!("fit {:.1} s: {:?}", start.elapsed().as_secs_f64(), morph.interpolant().report());
    let w = morph.interpolant().weights();
    let mut order: Vec<usize> = (0..w.len()).collect();
    order.sort_by(|&a, &b| w[b].abs().total_cmp(&w[a].abs()));
    let sum: f64 = w.iter().map(|v| v.abs()).sum();
    println!(
        "weights: sum |w| {sum:.3e}, max {:.3e}, median {:.3e}, 99th {:.3e}, largest at {:?}",
        w[order[0]].abs(),
        w[order[w.len() / 2]].abs(),
        w[order[w.len() / 100]].abs(),
        &order[..10]
    );
    for &t in &times {
        let slice = morph.slice(t).expect("a slice");
        let modes = std::env::var("MODES").unwrap_or_else(|_| "sparse,lattice,frame,direct".into());
        for name in modes.split(',') {
            let evaluation = if name == "direct" { Evaluation::Direct } else { Evaluation::Auto };
            let field = slice.clone().with_evaluation(evaluation);
            let (start, cpu0) = (Instant::now(), cpu_seconds());
            let bounds = morph.field_bounds();
            let mesh = if name == "frame" {
                // What the CLI writes: the lattice with its small sign
                // islands confirmed by the exact sum.
                morph.frame_mesh(t, res).expect("a frame")
            } else if name == "lattice" {
                let grid = Grid3::sample_box(&field, &bounds.expanded(1e-4), res).expect("a grid");
                let cpu = cpu_seconds() - cpu0;
                // The lattice values against the exact f64 sum at every
                // 101st node within 5 of the surface value.
                let (mut worst, mut count) = (0.0f64, 0);
                for n in (0..grid.len()).step_by(101) {
                    let v = grid.data()[n];
                    if v.abs() < 5.0 {
                        let c = grid.node_of(n);
                        let p = grid.position(c.x, c.y, c.z);
                        let x = [p.x, p.y, p.z, t * morph.separation()].map(f64::from);
                        worst = worst.max((f64::from(v) - morph.interpolant().value_f64(x)).abs());
                        count += 1;
                    }
                }
                println!(
                    "  lattice: {cpu:.1} s CPU; max |lattice − exact f64| {worst:.3e} at {count} nodes within 5 of 0"
                );
                marching_cubes(&grid, 0.0)
            } else {
                level_set_mesh(&field, &bounds, res, 0.0).expect("a mesh")
            };
            let parts = components(&mesh);
            let sizes: Vec<usize> = parts.iter().map(Vec::len).collect();
            println!(
                "t = {t} {name}: {:.1} s wall, {:.1} s CPU, {} vertices, {} components, sizes {:?}",
                start.elapsed().as_secs_f64(),
                cpu_seconds() - cpu0,
                mesh.positions.len(),
                parts.len(),
                &sizes[..sizes.len().min(12)]
            );
            for part in parts.iter().skip(1).take(6) {
                let p = mesh.positions[part[0]];
                let tree = slice.clone().with_evaluation(Evaluation::Treecode);
                let mut batch = vec![p; 1];
                batch.extend((0..4999).map(|i| p + Vec3::splat(1e-3 * (i as f32 / 5000.0))));
                let mut out = vec![0.0; batch.len()];
                tree.values(&batch, &mut out);
                let exact = morph.interpolant().value_f64([
                    f64::from(p.x),
                    f64::from(p.y),
                    f64::from(p.z),
                    f64::from(t * morph.separation()),
                ]);
                println!(
                    "  speck of {} vertices at {p}: treecode {:.3e}, direct f32 {:.3e}, exact f64 {:.3e}, gradient {:.3e}",
                    part.len(),
                    out[0],
                    slice.value(p),
                    exact,
                    slice.gradient(p).length()
                );
            }
        }
    }
}

/// The vertex sets of the mesh's components, largest first.
fn components(mesh: &TriMesh) -> Vec<Vec<usize>> {
    let n = mesh.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    for tri in &mesh.triangles {
        let a = find(&mut parent, tri[0] as usize);
        for &v in &tri[1..] {
            let b = find(&mut parent, v as usize);
            if a != b {
                parent[b] = a;
            }
        }
    }
    let mut groups = std::collections::HashMap::<usize, Vec<usize>>::new();
    for v in 0..n {
        let r = find(&mut parent, v);
        groups.entry(r).or_default().push(v);
    }
    let mut parts: Vec<Vec<usize>> = groups.into_values().collect();
    parts.sort_by_key(|p| std::cmp::Reverse(p.len()));
    parts
}

/// User + system CPU time of this process so far (from `/proc/self/stat`,
/// in clock ticks of 1/100 s).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat.rsplit(')').next().unwrap_or("").split_whitespace().collect();
    let ticks = |i: usize| fields.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}
