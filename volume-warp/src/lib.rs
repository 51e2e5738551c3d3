//! Volume warping with trivariate cubic B-splines after T. J. True, *Volume
//! Warping*, M.S. thesis, 1992.

pub mod basis;
mod error;
pub mod map;
pub mod table;

pub use error::WarpError;
pub use map::BSplineMap;
pub use table::{CoefficientTable, DeformationArray, Evaluation};
