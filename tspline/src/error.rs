//! Errors of the T-spline morph.

use isomorph_common::alignment::AlignError;
use isomorph_common::sdf::SdfError;
use isomorph_common::{GridError, MeshError, MorphError, MorphFailure, TransformError};

/// What can go wrong building, fitting or evolving a T-spline level set.
/// What can go wrong: the kinds every method shares ([`MorphError`]: bad
/// settings and times, cancellation, grids, meshes, distances, alignment)
/// and the T-spline method's own.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TsplineError {
    /// One of the kinds every method shares.
    #[error(transparent)]
    Morph(#[from] MorphError),
    /// An input has no surface to sample.
    #[error("the {0} shape is empty (no surface to sample)")]
    EmptyShape(&'static str),
    /// An input or an intermediate result is not finite.
    #[error("the {0} input has a NaN or infinite value")]
    NonFinite(&'static str),
    /// No sample of either shape lies inside the other.
    #[error(
        "source and target do not overlap after alignment (no source sample lies inside the target \
         and no target sample inside the source); align them or move them together"
    )]
    NoOverlap,
    /// A least-squares system could not be solved.
    #[error("the {0} least-squares system is singular or not positive definite; raise the Tikhonov weight")]
    Singular(&'static str),
}

macro_rules! shared_from {
    ($($t:ty),*) => {$(
        impl From<$t> for TsplineError {
            fn from(e: $t) -> Self {
                TsplineError::Morph(MorphError::from(e))
            }
        }
    )*};
}
shared_from!(MeshError, SdfError, GridError, AlignError, TransformError);

impl MorphFailure for TsplineError {
    fn shared(&self) -> Option<&MorphError> {
        match self {
            TsplineError::Morph(e) => Some(e),
            _ => None,
        }
    }
}

/// `lo ≤ value ≤ hi`, else [`MorphError::BadSetting`] naming the setting.
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
        Err(MorphError::bad_setting(name, isomorph_common::check::number(value), expected).into())
    }
}
