//! The hierarchical solver on constraints from a real scanned mesh (the
//! Stanford bunny shipped in `data/`), placed as a shape transformation
//! places them: unequal point counts at `t = 0` and `t = 1`, uneven
//! spacing, and normal constraints closer to other parts of the surface
//! than to their own boundary point. Before the cluster tree kept the two
//! layers apart, GMRES stagnated on such input (relative residual ~0.5
//! after 300 iterations) and the dense solve ran instead.

use isomorph_common::glam::{Affine3A, Vec3};
use isomorph_common::{Control, Solid};
use isomorph_io::inputs::{LoadOptions, load_solid};
use isomorph_rbf::constraints::{NormalOffset, Subsample, SurfaceSettings, mesh_constraints};
use isomorph_rbf::{Constraint, Factorization, FitSettings, Interpolant, Kernel, Solver, lift};

/// The bunny as the CLI loads it (fitted to the unit box).
fn bunny() -> Solid {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/bunny.ply");
    load_solid(path, &LoadOptions::default()).unwrap()
}

/// Boundary and normal constraints of `points` farthest-point samples of
/// the bunny moved by `map` (the RBF morph's §4.2 constraints, offset 0.01
/// of the diagonal).
fn constraints(solid: &Solid, map: Affine3A, points: usize) -> Vec<Constraint<3>> {
    let mesh = solid.surface(64, &Control::new()).unwrap().transformed(&map);
    let s = SurfaceSettings {
        offset: NormalOffset::RelativeToDiagonal(0.01),
        subsample: Subsample::FarthestPoint(points),
    };
    mesh_constraints(&mesh, &s).unwrap()
}

#[test]
fn hierarchical_solver_converges_on_bunny_constraints_with_unequal_layers() {
    let solid = bunny();
    let source = constraints(&solid, Affine3A::IDENTITY, 700);
    let turned = Affine3A::from_rotation_y(1.3) * Affine3A::from_translation(Vec3::new(0.05, 0.0, 0.0));
    let target = constraints(&solid, turned, 300);
    let mut cs = lift::<3, 4>(&source, &[0.0]);
    cs.extend(lift::<3, 4>(&target, &[1.0]));
    assert_eq!(cs.len(), 2000);
    let kernel = Kernel::ThinPlate;
    let fit =
        |solver| Interpolant::fit(&cs, &FitSettings { solver, ..FitSettings::default().with_kernel(kernel) });
    let fast = fit(Solver::Hierarchical).unwrap();
    let report = fast.report();
    assert!(report.fallback.is_none(), "the dense fallback ran: {report:?}");
    let Factorization::Hierarchical { iterations, .. } = report.factorization else {
        panic!("not solved by the hierarchical solver: {report:?}");
    };
    assert!(iterations <= 40, "{iterations} GMRES iterations");
    assert!(report.max_residual.unwrap() < 1e-8, "{report:?}");
    // The same function as the dense solve, within 1e-6 of its range, at
    // the constraints and between the two shapes.
    let dense = fit(Solver::Dense).unwrap();
    let probes = cs.iter().step_by(7).map(|c| c.position).chain(cs.iter().step_by(11).map(|c| {
        let mut p = c.position;
        p[3] = 0.5;
        p
    }));
    let (mut worst, mut lo, mut hi) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
    for p in probes {
        let x = p.map(f64::from);
        let (f, d) = (fast.value_f64(x), dense.value_f64(x));
        worst = worst.max((f - d).abs());
        lo = lo.min(d);
        hi = hi.max(d);
    }
    assert!(worst <= 1e-6 * (hi - lo), "max |f_H − f_dense| {worst:e}, range {}", hi - lo);
}
