//! Errors of the level-set morph.

use isomorph_common::{GridError, MorphError, MorphFailure};

/// What can go wrong setting up or running a level-set morph: the shared
/// kinds ([`MorphError`]: bad settings and times, no overlap, grids and
/// memory, cancellation, input conversions) and the grid-level input
/// problems of [`crate::evolve`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LevelSetError {
    /// One of the kinds every method shares.
    #[error(transparent)]
    Morph(#[from] MorphError),
    /// An input grid holds a NaN or infinite value.
    #[error("the {what} grid has a NaN or infinite value at node {node}")]
    NonFinite {
        /// Which input (`"source"`, `"target"`, `"speed"`).
        what: &'static str,
        /// Linear index of the first bad node.
        node: usize,
    },
    /// An input shape has no node inside (or no node outside): there is no
    /// surface to evolve or to evolve towards.
    #[error("the {0} shape has no surface on the grid (no sign change between nodes)")]
    NoSurface(&'static str),
}

impl From<GridError> for LevelSetError {
    fn from(e: GridError) -> Self {
        LevelSetError::Morph(MorphError::Grid(e))
    }
}

impl MorphFailure for LevelSetError {
    fn shared(&self) -> Option<&MorphError> {
        match self {
            LevelSetError::Morph(e) => Some(e),
            _ => None,
        }
    }
}
