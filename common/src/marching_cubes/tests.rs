use super::table::{CASES, FACES, boundary_successors, edge_on_face};
use super::*;
use crate::marching_squares::crossing_parameter;
use glam::UVec3;
use proptest::prelude::*;
use std::collections::HashMap;
use std::f32::consts::PI;

/// A grid at the origin with unit spacing and values `f(i, j, k)`.
fn grid_from(dims: UVec3, mut f: impl FnMut(u32, u32, u32) -> f32) -> Grid3<f32> {
    let mut data = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
    for k in 0..dims.z {
        for j in 0..dims.y {
            for i in 0..dims.x {
                data.push(f(i, j, k));
            }
        }
    }
    Grid3::from_vec(dims, Vec3::ZERO, 1.0, data).unwrap()
}

/// Checks that every directed edge occurs once and its reverse once (closed,
/// consistently oriented), that every vertex is used and its link is one
/// cycle (2-manifold).
fn check_closed_manifold(mesh: &TriMesh) -> Result<(), String> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    let mut links: Vec<HashMap<u32, u32>> = vec![HashMap::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for r in 0..3 {
            let (a, b, c) = (t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
            if a == b {
                return Err(format!("triangle {t:?} repeats a vertex"));
            }
            *directed.entry((a, b)).or_default() += 1;
            if links[a as usize].insert(b, c).is_some() {
                return Err(format!("vertex {a}: link edge from {b} twice"));
            }
        }
    }
    for (&(a, b), &n) in &directed {
        if n != 1 || directed.get(&(b, a)) != Some(&1) {
            return Err(format!("edge {a}->{b} used {n} times, reverse {:?}", directed.get(&(b, a))));
        }
    }
    for (v, link) in links.iter().enumerate() {
        let Some((&start, _)) = link.iter().next() else {
            return Err(format!("vertex {v} is unused"));
        };
        let (mut at, mut steps) = (start, 0);
        loop {
            at = *link.get(&at).ok_or_else(|| format!("vertex {v}: link is not closed"))?;
            steps += 1;
            if at == start {
                break;
            }
        }
        if steps != link.len() {
            return Err(format!("vertex {v}: link has {} edges but its cycle {steps}", link.len()));
        }
    }
    Ok(())
}

/// Enclosed volume by the divergence theorem (positive for outward triangles).
fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.corners(t).map(|p| p.as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Number of grid edges whose nodes differ in sign.
fn crossed_edges(grid: &Grid3<f32>, iso: f32) -> usize {
    let d = grid.dims();
    let inside = |i, j, k| grid.get(i, j, k).is_some_and(|&v| v > iso);
    let mut n = 0;
    for k in 0..d.z {
        for j in 0..d.y {
            for i in 0..d.x {
                let s = inside(i, j, k);
                n += [(i + 1 < d.x, (1, 0, 0)), (j + 1 < d.y, (0, 1, 0)), (k + 1 < d.z, (0, 0, 1))]
                    .iter()
                    .filter(|&&(ok, (a, b, c))| ok && inside(i + a, j + b, k + c) != s)
                    .count();
            }
        }
    }
    n
}

/// A tiny seeded generator (splitmix64) for reproducible magnitudes.
struct Rng(u64);
impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[test]
fn fan_diagonals_never_lie_in_a_cube_face() {
    for case in 0..=255u8 {
        let next = boundary_successors(case);
        let c = &CASES[case as usize];
        for t in &c.triangles[..c.count as usize] {
            for r in 0..3 {
                let (a, b) = (t[r], t[(r + 1) % 3]);
                let segment = next[a as usize] == b || next[b as usize] == a;
                let same_face = (0..FACES.len()).any(|f| edge_on_face(a, f) && edge_on_face(b, f));
                assert!(segment || !same_face, "case {case:08b}: diagonal {a}-{b} lies in a face");
            }
        }
    }
}

#[test]
fn every_single_cube_case_is_closed_manifold_and_outward() {
    let mut rng = Rng(7);
    for case in 0..256u32 {
        for random in [false, true] {
            let mut corner = [0.0f32; 8];
            for (c, v) in corner.iter_mut().enumerate() {
                let m = if random { 0.05 + rng.next_f32() } else { 1.0 };
                *v = if case >> c & 1 == 1 { m } else { -m };
            }
            let g = grid_from(UVec3::splat(4), |i, j, k| {
                let inner = |x: u32| (1..=2).contains(&x);
                if inner(i) && inner(j) && inner(k) {
                    corner[((i - 1) + 2 * (j - 1) + 4 * (k - 1)) as usize]
                } else {
                    -1.0
                }
            });
            let mesh = marching_cubes(&g, 0.0);
            assert_eq!(mesh.positions.len(), crossed_edges(&g, 0.0), "case {case:08b}");
            check_closed_manifold(&mesh).unwrap_or_else(|e| panic!("case {case:08b}: {e}"));
            let vol = signed_volume(&mesh);
            assert!(case == 0 || vol > 0.0, "case {case:08b} random {random}: volume {vol}");
        }
    }
}

#[test]
fn every_pair_of_face_adjacent_cells_is_closed_manifold() {
    for axis in 0..3 {
        let mut dims = UVec3::splat(4);
        dims[axis] = 5;
        for config in 0..4096u32 {
            let g = grid_from(dims, |i, j, k| {
                let n = UVec3::new(i, j, k);
                let local = n.as_ivec3() - glam::IVec3::ONE;
                let mut ext = glam::IVec3::splat(1);
                ext[axis] = 2;
                if local.cmplt(glam::IVec3::ZERO).any() || local.cmpgt(ext).any() {
                    return -1.0;
                }
                // Linear index of the node in the 2-cell block, axis-major last.
                let mut size = glam::IVec3::splat(2);
                size[axis] = 3;
                let bitpos = local.x + size.x * (local.y + size.y * local.z);
                if config >> bitpos & 1 == 1 { 1.0 } else { -1.0 }
            });
            let mesh = marching_cubes(&g, 0.0);
            check_closed_manifold(&mesh).unwrap_or_else(|e| panic!("axis {axis} config {config:012b}: {e}"));
            assert!(config == 0 || signed_volume(&mesh) > 0.0, "axis {axis} config {config:012b}");
        }
    }
}

/// Sphere SDFs combined by max (union), sampled on `n³` unit-spaced nodes
/// with the border nodes forced outside.
fn spheres_grid(n: u32, spheres: &[(Vec3, f32)]) -> Grid3<f32> {
    grid_from(UVec3::splat(n), |i, j, k| {
        if [i, j, k].iter().any(|&c| c == 0 || c == n - 1) {
            return -1.0;
        }
        let p = Vec3::new(i as f32, j as f32, k as f32);
        spheres.iter().map(|&(c, r)| r - p.distance(c)).fold(f32::NEG_INFINITY, f32::max)
    })
}

fn sphere_strategy(n: u32) -> impl Strategy<Value = Vec<(Vec3, f32)>> {
    let lo = 1.5f32;
    let hi = n as f32 - 2.5;
    prop::collection::vec(((lo..hi, lo..hi, lo..hi), 0.3f32..(n as f32 / 4.0)), 1..5)
        .prop_map(|v| v.into_iter().map(|((x, y, z), r)| (Vec3::new(x, y, z), r)).collect())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn union_of_spheres_is_closed_outward_and_on_edges(spheres in sphere_strategy(14), iso in -0.3f32..0.3) {
        let g = spheres_grid(14, &spheres);
        let mesh = marching_cubes(&g, iso);
        prop_assert!(mesh.validate().is_ok());
        prop_assert_eq!(mesh.positions.len(), crossed_edges(&g, iso));
        if let Err(e) = check_closed_manifold(&mesh) {
            return Err(TestCaseError::fail(e));
        }
        prop_assert!(mesh.is_empty() || signed_volume(&mesh) > 0.0);
        for &p in &mesh.positions {
            let q = g.to_grid(p);
            let integral = (0..3).filter(|&a| (q[a] - q[a].round()).abs() < 1e-4).count();
            prop_assert!(integral >= 2, "vertex {} is not on a grid edge", q);
            let v = g.trilinear(p);
            prop_assert!((v - iso).abs() < 1e-4, "value {} at vertex {}, iso {}", v, q, iso);
        }
    }

    #[test]
    fn single_sphere_volume_is_close_to_the_analytic_one(
        c in (7.0f32..9.0, 7.0f32..9.0, 7.0f32..9.0),
        r in 4.0f32..6.0,
    ) {
        let g = spheres_grid(17, &[(Vec3::new(c.0, c.1, c.2), r)]);
        let mesh = marching_cubes(&g, 0.0);
        let expected = 4.0 / 3.0 * std::f64::consts::PI * (r as f64).powi(3);
        let vol = signed_volume(&mesh);
        // Chordal error of a sphere of radius r voxels: O(1/r²) relative.
        let tol = expected * 0.8 / (r as f64).powi(2);
        prop_assert!((vol - expected).abs() < tol, "volume {}, expected {}, tolerance {}", vol, expected, tol);
    }

    #[test]
    fn values_exactly_at_iso_keep_the_mesh_closed(seed in any::<u64>()) {
        let mut rng = Rng(seed);
        let g = grid_from(UVec3::splat(7), |i, j, k| {
            let r = rng.next_f32();
            if [i, j, k].iter().any(|&c| c == 0 || c == 6) { -1.0 } else { (r * 3.0).floor() - 1.0 }
        });
        let mesh = marching_cubes(&g, 0.0);
        if let Err(e) = check_closed_manifold(&mesh) {
            return Err(TestCaseError::fail(e));
        }
    }
}

#[test]
fn sphere_volume_matches_the_analytic_one() {
    let r = 0.35f32;
    let mesh = polygonize(&|p: Vec3| r - p.length(), &Aabb::cube(0.5), 64, 0.0).unwrap();
    check_closed_manifold(&mesh).unwrap();
    let expected = 4.0 / 3.0 * std::f64::consts::PI * (r as f64).powi(3);
    let vol = signed_volume(&mesh);
    assert!((vol - expected).abs() < 0.01 * expected, "volume {vol}, expected {expected}");
}

#[test]
fn torus_is_closed_with_genus_one() {
    let torus = |p: Vec3| 0.12 - glam::Vec2::new(p.truncate().length() - 0.3, p.z).length();
    let mesh = polygonize(&torus, &Aabb::cube(0.5), 48, 0.0).unwrap();
    check_closed_manifold(&mesh).unwrap();
    // Euler characteristic V - E + F = 0 with E = 3F/2.
    assert_eq!(2 * mesh.positions.len(), mesh.triangles.len());
    let expected = 2.0 * (PI as f64).powi(2) * 0.3 * 0.12f64.powi(2);
    let vol = signed_volume(&mesh);
    assert!((vol - expected).abs() < 0.03 * expected, "volume {vol}, expected {expected}");
}

/// Straightforward per-cell marching cubes with a hash map of edge vertices,
/// positions computed by the same expressions, to check the bit-mask fast path.
fn reference_triangles(g: &Grid3<f32>, iso: f32) -> Vec<[[u32; 3]; 3]> {
    let d = g.dims();
    let (o, h) = (g.origin(), g.spacing());
    let val = |i: u32, j: u32, k: u32| g.data()[g.index(i, j, k)];
    let mut out = Vec::new();
    let mut memo: HashMap<(u32, u32, u32, u8), Vec3> = HashMap::new();
    for k in 0..d.z - 1 {
        for j in 0..d.y - 1 {
            for i in 0..d.x - 1 {
                let case = (0..8).fold(0usize, |c, n| {
                    c | ((val(i + (n & 1), j + (n >> 1 & 1), k + (n >> 2)) > iso) as usize) << n
                });
                let mut vertex = |e: u8| {
                    let (a, b) = ((e & 1) as u32, (e >> 1 & 1) as u32);
                    let (ni, nj, nk, axis) = match e {
                        0..4 => (i, j + a, k + b, 0),
                        4..8 => (i + a, j, k + b, 1),
                        _ => (i + a, j + b, k, 2),
                    };
                    *memo.entry((ni, nj, nk, axis)).or_insert_with(|| {
                        let base = o + h * Vec3::new(0.0, nj as f32, nk as f32);
                        let v0 = val(ni, nj, nk);
                        match axis {
                            0 => {
                                base + Vec3::new(
                                    h * (ni as f32 + crossing_parameter(v0, val(ni + 1, nj, nk), iso)),
                                    0.0,
                                    0.0,
                                )
                            }
                            1 => {
                                base + Vec3::new(
                                    h * ni as f32,
                                    h * crossing_parameter(v0, val(ni, nj + 1, nk), iso),
                                    0.0,
                                )
                            }
                            _ => {
                                base + Vec3::new(
                                    h * ni as f32,
                                    0.0,
                                    h * crossing_parameter(v0, val(ni, nj, nk + 1), iso),
                                )
                            }
                        }
                    })
                };
                let c = &CASES[case];
                for t in &c.triangles[..c.count as usize] {
                    out.push(t.map(|e| vertex(e).to_array().map(f32::to_bits)));
                }
            }
        }
    }
    out
}

/// Triangles as position bit patterns, each rotated to start at its smallest
/// corner, sorted.
fn canonical(tris: Vec<[[u32; 3]; 3]>) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<_> = tris
        .into_iter()
        .map(|t| {
            let m = (0..3).min_by_key(|&r| t[r]).unwrap();
            [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
        })
        .collect();
    v.sort_unstable();
    v
}

fn blobby_grid(dims: UVec3) -> Grid3<f32> {
    let f = |p: Vec3| {
        let s = (p.x * 0.31).sin() + (p.y * 0.23).cos() + (p.z * 0.17 + p.x * 0.05).sin();
        s - 0.4
    };
    let mut g = grid_from(dims, |i, j, k| f(Vec3::new(i as f32, j as f32, k as f32)));
    let origin = Vec3::new(-1.5, 0.25, 3.0);
    g = Grid3::from_vec(dims, origin, 0.37, g.into_data()).unwrap();
    g
}

#[test]
fn fast_path_matches_the_reference_across_words_and_slabs() {
    let g = blobby_grid(UVec3::new(130, 23, 29));
    let mesh = marching_cubes(&g, 0.1);
    let ours = (0..mesh.triangles.len())
        .map(|t| mesh.corners(t).map(|p| p.to_array().map(f32::to_bits)))
        .collect::<Vec<_>>();
    assert_eq!(canonical(ours), canonical(reference_triangles(&g, 0.1)));
    assert_eq!(mesh.positions.len(), crossed_edges(&g, 0.1));
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let g = blobby_grid(UVec3::new(70, 33, 61));
    let many = marching_cubes(&g, 0.0);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let one = pool.install(|| marching_cubes(&g, 0.0));
    assert!(!many.is_empty());
    assert_eq!(many, one);
}

#[test]
fn nan_counts_as_outside_and_never_panics() {
    let mut rng = Rng(3);
    let base = spheres_grid(16, &[(Vec3::splat(7.5), 5.0)]);
    let data: Vec<f32> =
        base.data().iter().map(|&v| if rng.next_f32() < 0.1 { f32::NAN } else { v }).collect();
    let g = Grid3::from_vec(base.dims(), base.origin(), base.spacing(), data).unwrap();
    let mesh = marching_cubes(&g, 0.0);
    assert!(mesh.validate().is_ok());
    check_closed_manifold(&mesh).unwrap();
    let all_nan = Grid3::new(UVec3::splat(5), Vec3::ZERO, 1.0, f32::NAN).unwrap();
    assert!(marching_cubes(&all_nan, 0.0).is_empty());
    let infinite =
        grid_from(
            UVec3::splat(4),
            |i, j, k| if (i, j, k) == (1, 1, 1) { f32::INFINITY } else { f32::NEG_INFINITY },
        );
    let mesh = marching_cubes(&infinite, 0.0);
    assert!(mesh.validate().is_ok());
    check_closed_manifold(&mesh).unwrap();
}

#[test]
fn level_set_reaching_the_border_is_open_and_small_grids_are_empty() {
    let g = grid_from(UVec3::splat(5), |i, _, _| 1.5 - i as f32);
    let mesh = marching_cubes(&g, 0.0);
    assert_eq!(mesh.triangles.len(), 2 * 4 * 4);
    assert!(check_closed_manifold(&mesh).is_err());
    // Normals point towards decreasing values (+x).
    assert!(mesh.vertex_normals().iter().all(|n| (*n - Vec3::X).length() < 1e-5));
    let flat = grid_from(UVec3::new(5, 5, 1), |_, _, _| 1.0);
    assert!(marching_cubes(&flat, 0.0).is_empty());
    assert!(matches!(polygonize(&|_: Vec3| 1.0, &Aabb::cube(1.0), 1, 0.0), Err(GridError::TooSmall { .. })));
}
