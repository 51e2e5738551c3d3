//! The solvers refuse grids over the process-wide memory limit with a typed
//! error (own test binary: the limit is global to the process).

use isomorph_common::set_memory_limit;
use isomorph_common::{Aabb, Grid3, GridError, MorphError, Shape};
use isomorph_levelset::{DenseSolver, LevelSetError, SparseFieldSolver};

#[test]
fn solvers_over_the_memory_limit_are_errors() {
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 40).unwrap();
    // The source grid itself (4 bytes per node) fits; the solvers' state does not.
    set_memory_limit(source.len() * 4);
    let too_large =
        |e: LevelSetError| matches!(e, LevelSetError::Morph(MorphError::Grid(GridError::TooLarge { .. })));
    assert!(too_large(DenseSolver::new(&source).unwrap_err()));
    assert!(too_large(SparseFieldSolver::new(&source).unwrap_err()));
}
