//! Volume warping with trivariate cubic B-splines after T. J. True, *Volume
//! Warping*, M.S. thesis, 1992.

pub mod basis;
mod error;
pub mod manipulate;
pub mod map;
pub mod pushforward;
pub mod table;
pub mod warp;

pub use error::WarpError;
pub use manipulate::{Drag, Handle, solve_drag};
pub use map::BSplineMap;
pub use pushforward::{Density, Filter};
pub use table::{CoefficientTable, DeformationArray, Evaluation};
pub use warp::{VolumeWarp, WarpSettings};
