//! The solvers refuse grids over the process-wide memory limit with a typed
//! error (own test binary: the limit is global to the process).

use isomorph_common::set_memory_limit;
use isomorph_common::{Aabb, Grid3, GridError, MorphError, Shape};
use isomorph_levelset::{DenseSolver, LevelSetError, SparseFieldSolver};

#[test]
fn solvers_over_the_memory_limit_are_errors() {
    let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 40).unwrap();
    // Just under one dense f32 array: the dense solver and the sparse field
    // with dense storage are refused; the bricked sparse field, whose state
    // grows with the surface, runs.
    set_memory_limit(source.len() * 4 - 1);
    let too_large =
        |e: LevelSetError| matches!(e, LevelSetError::Morph(MorphError::Grid(GridError::TooLarge { .. })));
    assert!(too_large(DenseSolver::new(&source).unwrap_err()));
    let dense_storage = SparseFieldSolver::<Vec<f32>, Vec<i8>>::with_storage(&source);
    assert!(too_large(dense_storage.unwrap_err()));
    assert!(SparseFieldSolver::new(&source).unwrap().active_len() > 0);
}
