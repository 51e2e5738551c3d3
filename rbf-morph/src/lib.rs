//! Shape transformation with variational implicit functions after Turk &
//! O'Brien, *Shape Transformation Using Variational Implicit Functions*,
//! SIGGRAPH 1999.
#![doc = "TODO"]

pub mod error;
pub mod interpolant;
pub mod kernel;
pub mod slice;

mod duplicates;
mod solve;

pub use duplicates::DuplicatePolicy;
pub use error::RbfError;
pub use interpolant::{Constraint, FitReport, FitSettings, Interpolant};
pub use kernel::Kernel;
pub use slice::{Slice2, Slice3};
pub use solve::Factorization;
