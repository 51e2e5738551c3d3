//! T-spline level-set metamorphosis (work in progress).

mod basis;
mod bspline;
mod error;
mod tmesh;
mod tspline;

pub use basis::Eval;
pub use error::TsplineError;
pub use tmesh::{MAX_DEPTH, TMesh, TMeshSettings};
pub use tspline::TSpline;
mod fit;
mod lsq;
pub use fit::{FitReport, FitSettings, fit};
mod evolution;
mod sampling;
pub use evolution::{EvolveSettings, Evolution, Outcome, Speed, StepStats, evolve};
