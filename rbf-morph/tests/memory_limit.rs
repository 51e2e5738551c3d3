//! A dense system over the process-wide memory limit is a typed error raised
//! before the matrix is allocated (own test binary: the limit is global to
//! the process).

use isomorph_common::{MorphError, set_memory_limit};
use isomorph_rbf::{Constraint, FitSettings, Interpolant, RbfError};

#[test]
fn a_system_over_the_memory_limit_is_refused_before_allocation() {
    // 2000 distinct constraints on a 13 × 13 × 12 lattice: an 8 × 2000² = 32 MB matrix.
    let constraints: Vec<Constraint<3>> = (0..2000u32)
        .map(|i| {
            let c = [i % 13, (i / 13) % 13, i / 169].map(|x| x as f32 / 13.0);
            Constraint::new(c, (i % 2) as f32)
        })
        .collect();
    set_memory_limit(16 << 20);
    let err = Interpolant::fit(&constraints, &FitSettings::default()).unwrap_err();
    match &err {
        RbfError::Morph(MorphError::Memory(e)) => {
            assert!(e.requested >= 8 * 2000 * 2000, "{e}");
            assert_eq!(e.limit, 16 << 20);
        }
        other => panic!("expected the memory limit, got {other}"),
    }
    let message = err.to_string();
    assert!(message.contains("2000 constraints") && message.contains("fewer constraints"), "{message}");
    // Under a limit that holds it, the same fit works.
    set_memory_limit(1 << 30);
    assert!(Interpolant::fit(&constraints, &FitSettings::default()).is_ok());
}
