//! Normal constraints near thin parts (`constraints` module docs): an
//! inward offset larger than the local thickness put the normal constraint
//! (value 1) beyond the opposite side of the surface, and the fitted
//! function then came out positive outside the shape (stray bubbles in the
//! RBF morph's frames). The offsets are now validated.

use isomorph_common::Control;
use isomorph_common::glam::Vec3;
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_rbf::constraints::{NormalOffset, SurfaceSettings, mesh_constraints, surface_constraints};
use isomorph_rbf::{Constraint, FitSettings, Interpolant};

/// Every normal constraint (value 1) follows its boundary constraint
/// (value 0); returns the (boundary, normal) position pairs.
fn pairs(cs: &[Constraint<3>]) -> Vec<(Vec3, Vec3)> {
    let mut out = Vec::new();
    for (i, c) in cs.iter().enumerate() {
        if c.value == 1.0 {
            assert_eq!(cs[i - 1].value, 0.0, "normal constraint {i} does not follow a boundary constraint");
            out.push((Vec3::from_array(cs[i - 1].position), Vec3::from_array(c.position)));
        }
    }
    out
}

#[test]
fn bunny_normal_constraints_are_nearest_their_own_point() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/bunny.ply");
    let solid = load_solid(path, &LoadOptions::default()).unwrap();
    let mesh = solid.surface(64, &Control::new()).unwrap();
    let cs = mesh_constraints(&mesh, &SurfaceSettings::default()).unwrap();
    let pairs = pairs(&cs);
    let k = 0.01 * isomorph_common::Aabb::from_points(&mesh.positions).diagonal();
    // Before the validation some normal points were nearer a vertex of the
    // other side (normal facing away) than their own; none may be now.
    let normals = mesh.vertex_normals();
    let mut shrunk = 0;
    for &(b, n) in &pairs {
        let own = n.distance_squared(b);
        let outward = (b - n).normalize();
        let nearest = mesh
            .positions
            .iter()
            .zip(&normals)
            .filter(|&(_, m)| m.dot(outward) < 0.0)
            .map(|(p, _)| n.distance_squared(*p))
            .fold(f32::MAX, f32::min);
        assert!(nearest > own, "normal point {n} is nearer a vertex of the other side than its own {b}");
        assert!(own.sqrt() <= k * 1.0001 && own.sqrt() >= k / 16.0 * 0.999, "offset {} of {k}", own.sqrt());
        shrunk += usize::from(own.sqrt() < 0.99 * k);
    }
    assert!(pairs.len() >= mesh.positions.len() - 5, "{} normal constraints", pairs.len());
    assert!((1..=30).contains(&shrunk), "{shrunk} offsets shrunk");
}

#[test]
fn a_plate_thinner_than_the_offset_stays_negative_outside() {
    // A square plate 0.008 thick: the default offset (0.01 of the diagonal,
    // 0.0141) is larger than the thickness, so unvalidated normal points
    // of the top face land 0.006 below the bottom face, and vice versa.
    let h = 0.004;
    let (mut points, mut normals) = (Vec::new(), Vec::new());
    for i in 0..=10 {
        for j in 0..=10 {
            let (x, y) = (i as f32 * 0.1 - 0.5, j as f32 * 0.1 - 0.5);
            for side in [1.0f32, -1.0] {
                points.push(Vec3::new(x, y, side * h));
                normals.push(Vec3::Z * side);
            }
        }
    }
    let settings = SurfaceSettings { offset: NormalOffset::RelativeToDiagonal(0.01), ..Default::default() };
    let cs = surface_constraints(&points, &normals, &settings).unwrap();
    for (b, n) in pairs(&cs) {
        assert!(n.z.abs() < h, "normal point {n} of {b} is outside the plate");
    }
    let f = Interpolant::fit(&cs, &FitSettings::default()).unwrap();
    for i in 2..=8 {
        for j in 2..=8 {
            let (x, y) = (f64::from(i) * 0.1 - 0.5, f64::from(j) * 0.1 - 0.5);
            // At the samples: between samples 0.1 apart the fit of a plate
            // 0.008 thick is free to dip.
            let h = f64::from(h);
            assert!(f.value_f64([x, y, 0.0]) > 0.0, "outside at the mid-plane ({x}, {y})");
            for z in [h + 0.003, -h - 0.003] {
                let v = f.value_f64([x, y, z]);
                assert!(v < 0.0, "inside ({v}) at ({x}, {y}, {z}), outside the plate");
            }
        }
    }
}
