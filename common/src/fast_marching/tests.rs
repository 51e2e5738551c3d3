use super::*;
use crate::Shape;

/// Exact seeds of a sphere (radius `r` voxels at `c`) on an `n³` unit-spacing
/// grid: the nodes next to its surface.
fn sphere_seeds(n: u32, c: Vec3, r: f32) -> Vec<Seed> {
    let mut seeds = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let x = Vec3::new(i as f32, j as f32, k as f32);
                let d = r - (x - c).length();
                if d.abs() <= 1.0 {
                    let cp = c + (x - c).normalize() * r;
                    seeds.push(Seed { node: UVec3::new(i, j, k), distance: d, closest_point: Some(cp) });
                }
            }
        }
    }
    seeds
}

/// Max error (voxels) of `grid` against the exact sphere distance, over all
/// nodes and over those within `near` voxels of the surface.
fn sphere_errors(grid: &Grid3<f32>, c: Vec3, r: f32, near: f32) -> (f32, f32) {
    let (mut all, mut close) = (0.0f32, 0.0f32);
    for (index, &v) in grid.data().iter().enumerate() {
        let x = grid.node_of(index).as_vec3();
        let exact = r - (x - c).length();
        let e = (v - exact).abs();
        if e > 0.3 && exact.abs() < 3.0 { println!("{x} exact {exact} got {v}"); }
        all = all.max(e);
        if exact.abs() <= near {
            close = close.max(e);
        }
    }
    (all, close)
}

#[test]
fn accuracy_of_each_update_on_a_sphere() {
    let (n, c, r) = (48, Vec3::new(23.3, 24.1, 23.7), 10.0);
    let seeds = sphere_seeds(n, c, r);
    for update in [Update::FirstOrder, Update::SecondOrder, Update::ClosestPoint] {
        let settings = FastMarchingSettings { update, max_distance: None };
        let grid = march(UVec3::splat(n), Vec3::ZERO, 1.0, &seeds, &settings).unwrap();
        let (all, near) = sphere_errors(&grid, c, r, 3.0);
        println!("{update:?}: max {all}, near {near}");
    }
    panic!();
}

#[test]
fn redistance_torus() {
    let torus = Shape::torus(0.3, 0.12);
    let field = |p: Vec3| torus.distance(p) * (1.5 + 0.5 * (3.0 * p.x).sin() * (2.0 * p.y).cos());
    let n = 64;
    let h = 1.0 / (n - 1) as f32;
    let grid = Grid3::sample(&field, UVec3::splat(n), Vec3::splat(-0.5), h).unwrap();
    for update in [Update::FirstOrder, Update::SecondOrder, Update::ClosestPoint] {
        let settings = FastMarchingSettings { update, max_distance: None };
        let sdf = redistance(&grid, &settings).unwrap();
        let (mut all, mut near) = (0.0f32, 0.0f32);
        for (index, &v) in sdf.data().iter().enumerate() {
            let u = sdf.node_of(index);
            let exact = torus.distance(sdf.position(u.x, u.y, u.z));
            let e = (v - exact).abs() / h;
            all = all.max(e);
            if exact.abs() < 2.0 * h {
                near = near.max(e);
            }
        }
        println!("{update:?}: max {all}, near {near}");
    }
    panic!();
}

#[test]
#[ignore]
fn timing() {
    let torus = Shape::torus(0.3, 0.12);
    let field = |p: Vec3| torus.distance(p) * (1.5 + 0.5 * (3.0 * p.x).sin() * (2.0 * p.y).cos());
    let n: u32 = std::env::var("FMM_N").map(|s| s.parse().unwrap()).unwrap_or(256);
    let h = 1.0 / (n - 1) as f32;
    let grid = Grid3::sample(&field, UVec3::splat(n), Vec3::splat(-0.5), h).unwrap();
    let t = std::time::Instant::now();
    let seeds = band::grid_seeds(grid.data(), grid.dims());
    println!("band {} seeds {:?}", seeds.len(), t.elapsed());
    let t = std::time::Instant::now();
    let mut m = Marcher::new(grid.dims(), Update::ClosestPoint, f32::INFINITY).unwrap();
    m.set_sides(grid.data());
    for (i, &s) in seeds.iter().enumerate() { m.add_seed(s, i).unwrap(); }
    println!("setup {:?}", t.elapsed());
    let t = std::time::Instant::now();
    m.run();
    println!("run {:?} {:?} {:?}", t.elapsed(), march::RELAX, march::PUSH);
    let t = std::time::Instant::now();
    let out = m.finish(grid.origin(), h, f32::INFINITY).unwrap();
    println!("finish {:?}", t.elapsed());
    let mut all = 0.0f32;
    let mut near = 0.0f32;
    for (index, &v) in out.data().iter().enumerate() {
        let u = out.node_of(index);
        let exact = torus.distance(out.position(u.x, u.y, u.z));
        let e = (v - exact).abs() / h;
        if e > all { println!("worst so far {u} exact {} got {} e {e} input {}", exact / h, v / h, grid.data()[index] / h); }
        all = all.max(e);
        if exact.abs() < 2.0 * h { near = near.max(e); }
    }
    println!("max {all} near {near}");
}
