//! Errors of the T-spline morph.

use isomorph_common::alignment::AlignError;
use isomorph_common::sdf::SdfError;
use isomorph_common::{GridError, MeshError, TransformError};

/// What can go wrong building, fitting or evolving a T-spline level set.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TsplineError {
    /// A setting is out of its range.
    #[error("setting {name} = {value} is out of range ({expected})")]
    BadSetting {
        /// The setting's name.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// An input shape has no surface (no triangle of positive area, or no
    /// sample point): there is nothing to morph.
    #[error("the {0} shape is empty (no surface to sample)")]
    EmptyShape(&'static str),
    /// An input has NaN or infinite coordinates or distances.
    #[error("the {0} input has a NaN or infinite value")]
    NonFinite(&'static str),
    /// Source and target do not overlap after alignment and normalization;
    /// the evolution can only reach a target that overlaps the source
    /// (Breen & Whitaker's convergence condition, paper §4.2).
    #[error(
        "source and target do not overlap after alignment (no source sample lies inside the target \
         and no target sample inside the source); align them or move them together"
    )]
    NoOverlap,
    /// A sparse least-squares system could not be factorized (not positive
    /// definite: raise the Tikhonov weight).
    #[error("the {0} least-squares system is singular or not positive definite; raise the Tikhonov weight")]
    Singular(&'static str),
    /// A mesh input failed validation.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A distance field could not be built.
    #[error(transparent)]
    Sdf(#[from] SdfError),
    /// A grid could not be made (memory limit).
    #[error(transparent)]
    Grid(#[from] GridError),
    /// The moment alignment failed (open mesh, degenerate moments).
    #[error(transparent)]
    Align(#[from] AlignError),
    /// An alignment transform cannot be interpolated.
    #[error(transparent)]
    Transform(#[from] TransformError),
    /// The progress callback asked to stop.
    #[error("cancelled by the progress callback")]
    Cancelled,
    /// A morph time outside `[0, 1]` or NaN.
    #[error("time {0} is outside [0, 1]")]
    InvalidTime(f32),
}

/// Checks `lo <= value <= hi` (and finiteness) for a setting.
pub(crate) fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<(), TsplineError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(TsplineError::BadSetting { name, value, expected })
    }
}
