//! Shape transformation with variational implicit functions after Turk &
//! O'Brien, *Shape Transformation Using Variational Implicit Functions*,
//! SIGGRAPH 1999.
#![doc = "TODO"]

pub mod constraints;
pub mod error;
pub mod image;
pub mod interpolant;
pub mod kernel;
pub mod slice;
pub mod transform;

mod duplicates;
mod solve;

pub use duplicates::DuplicatePolicy;
pub use error::RbfError;
pub use interpolant::{Constraint, FitReport, FitSettings, Interpolant};
pub use kernel::Kernel;
pub use slice::{Slice2, Slice3};
pub use solve::Factorization;
pub use transform::{ContourMorph, RbfMorph, TransformSettings};
