use super::*;
use crate::Shape;

/// Exact seeds of a sphere (radius `r` voxels at `c`) on an `n³` unit-spacing
/// grid: the nodes within one voxel of its surface.
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

/// Max error of `grid` against `exact` in voxels, over all nodes and over
/// those within `near` voxels of the surface.
fn max_errors(grid: &Grid3<f32>, exact: impl Fn(Vec3) -> f32, near: f32) -> (f32, f32) {
    let h = grid.spacing();
    let (mut all, mut close) = (0.0f32, 0.0f32);
    for (index, &v) in grid.data().iter().enumerate() {
        let n = grid.node_of(index);
        let d = exact(grid.position(n.x, n.y, n.z));
        let e = (v - d).abs() / h;
        all = all.max(e);
        if d.abs() <= near * h {
            close = close.max(e);
        }
    }
    (all, close)
}

fn settings(update: Update) -> FastMarchingSettings {
    FastMarchingSettings { update, max_distance: None }
}

/// The documented accuracy of each update: a sphere of radius 10 voxels in a
/// 48³ grid, seeded exactly within one voxel of its surface, marched out to
/// 30 voxels.
#[test]
fn accuracy_of_each_update_on_a_sphere() {
    let (n, c, r) = (48, Vec3::new(23.3, 24.1, 23.7), 10.0);
    let seeds = sphere_seeds(n, c, r);
    let exact = |p: Vec3| r - (p - c).length();
    let run = |update| march(UVec3::splat(n), Vec3::ZERO, 1.0, &seeds, &settings(update)).unwrap();
    let (first, first_near) = max_errors(&run(Update::FirstOrder), exact, 3.0);
    let (second, second_near) = max_errors(&run(Update::SecondOrder), exact, 3.0);
    let (cp, cp_near) = max_errors(&run(Update::ClosestPoint), exact, 3.0);
    println!("first {first} {first_near}, second {second} {second_near}, cp {cp} {cp_near}");
    assert!(first < 1.0 && first_near < 0.2, "first order: {first}, near {first_near}");
    assert!(second < 0.35 && second_near < 0.06, "second order: {second}, near {second_near}");
    assert!(second < 0.5 * first, "second order must beat first order");
    assert!(cp < 0.3 && cp_near < 0.3, "closest point: {cp}, near {cp_near}");
}

/// Planes: first and second order are exact along an axis; closest-point
/// propagation is near exact for any orientation, off only where a node's
/// propagated closest point lies beyond the tangent disc (checked off the
/// grid's faces, at nodes whose closest point on the plane lies in the grid:
/// the rest of the plane is not seeded).
#[test]
fn planes_are_exact() {
    let n = 20;
    for (normal, update, tolerance) in [
        (Vec3::Z, Update::FirstOrder, 1e-5),
        (Vec3::Z, Update::SecondOrder, 1e-5),
        (Vec3::new(1.0, 2.0, 2.0) / 3.0, Update::ClosestPoint, 0.06),
    ] {
        let offset = 9.3;
        let exact = |p: Vec3| offset - p.dot(normal); // inside below the plane
        let mut seeds = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let x = Vec3::new(i as f32, j as f32, k as f32);
                    let d = exact(x);
                    if d.abs() <= 1.0 {
                        let cp = x + d * normal;
                        seeds.push(Seed { node: UVec3::new(i, j, k), distance: d, closest_point: Some(cp) });
                    }
                }
            }
        }
        let grid = march(UVec3::splat(n), Vec3::ZERO, 1.0, &seeds, &settings(update)).unwrap();
        for (index, &v) in grid.data().iter().enumerate() {
            let x = grid.node_of(index).as_vec3();
            let cp = x + exact(x) * normal;
            let interior = |p: Vec3| p.cmpge(Vec3::ONE).all() && p.cmple(Vec3::splat(n as f32 - 2.0)).all();
            if interior(x) && interior(cp) {
                assert!((v - exact(x)).abs() < tolerance, "{update:?} at {x}: {v} vs {}", exact(x));
            }
        }
    }
}

/// The torus distance times a smooth factor in [1, 2] on `n³` nodes.
fn scaled_torus(n: u32) -> (Shape, Grid3<f32>) {
    let torus = Shape::torus(0.3, 0.12);
    let field = |p: Vec3| torus.distance(p) * (1.5 + 0.5 * (3.0 * p.x).sin() * (2.0 * p.y).cos());
    let grid = Grid3::sample(&field, UVec3::splat(n), Vec3::splat(-0.5), 1.0 / (n - 1) as f32).unwrap();
    (torus, grid)
}

#[test]
fn redistance_recovers_the_torus_distance() {
    let (torus, grid) = scaled_torus(64);
    for (update, max, near) in
        [(Update::ClosestPoint, 0.25, 0.05), (Update::SecondOrder, 0.3, 0.1), (Update::FirstOrder, 0.8, 0.15)]
    {
        let sdf = redistance(&grid, &settings(update)).unwrap();
        let (all, close) = max_errors(&sdf, |p| torus.distance(p), 2.0);
        println!("{update:?}: {all} {close}");
        assert!(all < max && close < near, "{update:?}: max {all} voxels, near the surface {close}");
        // The sign never changes.
        assert!(sdf.data().iter().zip(grid.data()).all(|(a, b)| (*a > 0.0) == (*b > 0.0)));
    }
}

/// On 128³ nodes the shells are large enough to be relaxed in parallel by
/// z-slabs; the result must be as accurate as on 64³.
#[test]
fn redistance_in_parallel_slabs_keeps_its_accuracy() {
    let (torus, grid) = scaled_torus(128);
    let sdf = redistance(&grid, &FastMarchingSettings::default()).unwrap();
    let (all, close) = max_errors(&sdf, |p| torus.distance(p), 2.0);
    println!("128³: {all} {close}");
    assert!(all < 0.25 && close < 0.05, "max {all} voxels, near the surface {close}");
}

#[test]
fn zero_nodes_stay_on_the_surface() {
    // The plane x = 0.5 passes through a layer of nodes.
    let field = |p: Vec3| 3.0 * (0.5 - p.x);
    let grid = Grid3::sample(&field, UVec3::splat(9), Vec3::ZERO, 0.125).unwrap();
    let sdf = redistance(&grid, &FastMarchingSettings::default()).unwrap();
    for (index, &v) in sdf.data().iter().enumerate() {
        let p = sdf.node_of(index).as_vec3() * 0.125;
        assert!((v - (0.5 - p.x)).abs() < 1e-5, "at {p}: {v}");
    }
}

#[test]
fn max_distance_stops_the_front() {
    let (torus, grid) = scaled_torus(32);
    let h = grid.spacing();
    let limit = 3.0 * h;
    let settings = FastMarchingSettings { max_distance: Some(limit), ..Default::default() };
    let sdf = redistance(&grid, &settings).unwrap();
    for (index, &v) in sdf.data().iter().enumerate() {
        let n = sdf.node_of(index);
        let d = torus.distance(sdf.position(n.x, n.y, n.z));
        if d.abs() < 2.5 * h {
            assert!((v - d).abs() < 0.25 * h, "{v} vs {d}");
        } else if d.abs() > 3.5 * h {
            assert_eq!(v, limit.copysign(d), "unreached nodes keep ±max_distance with their sign");
        }
    }
    // From seeds, unreached regions get their side by flood fill.
    let (n, c, r) = (32, Vec3::splat(15.5), 10.0);
    let seeds = sphere_seeds(n, c, r);
    let settings = FastMarchingSettings { max_distance: Some(2.0), update: Update::SecondOrder };
    let grid = march(UVec3::splat(n), Vec3::ZERO, 1.0, &seeds, &settings).unwrap();
    assert_eq!(*grid.get(15, 15, 15).unwrap(), 2.0, "centre is inside");
    assert_eq!(*grid.get(0, 0, 0).unwrap(), -2.0, "corner is outside");
}

#[test]
fn bad_inputs_are_typed_errors() {
    let mut grid = Grid3::new(UVec3::splat(4), Vec3::ZERO, 1.0, 1.0f32).unwrap();
    let default = FastMarchingSettings::default();
    assert_eq!(redistance(&grid, &default), Err(FastMarchingError::NoInterface));
    *grid.get_mut(1, 2, 3).unwrap() = f32::NAN;
    assert_eq!(redistance(&grid, &default), Err(FastMarchingError::NaN { node: UVec3::new(1, 2, 3) }));
    *grid.get_mut(1, 2, 3).unwrap() = -1.0;
    let bad = FastMarchingSettings { max_distance: Some(0.0), ..default };
    assert_eq!(redistance(&grid, &bad), Err(FastMarchingError::BadMaxDistance(0.0)));
    let dims = UVec3::splat(4);
    assert_eq!(march(dims, Vec3::ZERO, 1.0, &[], &default), Err(FastMarchingError::NoSeeds));
    let outside = Seed { node: UVec3::new(4, 0, 0), distance: 0.5, closest_point: Some(Vec3::ZERO) };
    assert_eq!(march(dims, Vec3::ZERO, 1.0, &[outside], &default), Err(FastMarchingError::BadSeed(0)));
    let bare = Seed { node: UVec3::ZERO, distance: 0.5, closest_point: None };
    assert_eq!(
        march(dims, Vec3::ZERO, 1.0, &[bare], &default),
        Err(FastMarchingError::MissingClosestPoint(0))
    );
    assert!(march(dims, Vec3::ZERO, 1.0, &[bare], &settings(Update::FirstOrder)).is_ok());
    assert!(matches!(march(dims, Vec3::ZERO, -1.0, &[bare], &default), Err(FastMarchingError::Grid(_))));
}
