//! The typed errors of volume warping.

use glam::{UVec3, Vec3};
use isomorph_common::{GridError, MorphError, MorphFailure};

/// What can go wrong when building or editing a warp: the kinds every
/// morph method shares ([`MorphError`]) and the warp's own.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WarpError {
    /// One of the kinds every method shares (bad settings and times,
    /// cancellation, input conversion, grids).
    #[error(transparent)]
    Morph(#[from] MorphError),
    /// The control lattice has fewer than 4 points along an axis (one cubic
    /// B-spline region needs 4).
    #[error(
        "control lattice {controls} is too small: a cubic B-spline needs at least 4 control points per axis"
    )]
    LatticeTooSmall {
        /// Control points per axis given.
        controls: UVec3,
    },
    /// The lattice has more regions (`controls − 3`) along an axis than the
    /// source has voxels: a region would be smaller than one voxel.
    #[error(
        "control lattice {controls} is too fine for a source of {source_dims} voxels: \
         at most one region (controls − 3) per voxel along each axis"
    )]
    LatticeTooFine {
        /// Control points per axis given.
        controls: UVec3,
        /// Source voxels per axis.
        source_dims: UVec3,
    },
    /// A control point index is outside the lattice.
    #[error("control point {index} is outside the lattice of {controls} points")]
    ControlOutOfRange {
        /// The index given.
        index: UVec3,
        /// Control points per axis.
        controls: UVec3,
    },
    /// A position, displacement or point given is NaN or infinite.
    #[error("{what} is not finite: {value}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// The offending value.
        value: Vec3,
    },
    /// A source density is NaN or infinite.
    #[error("the source volume has a NaN or infinite value at voxel {0}")]
    NonFiniteDensity(usize),
    /// The table-driven evaluation (thesis §5.2) was requested but the source
    /// size is not an integer multiple `G` of the region count along some axis.
    #[error(
        "table evaluation needs source dims {source_dims} to be integer multiples of the \
         region counts {regions} (thesis §5.2); use Evaluation::Direct or Auto"
    )]
    NotTableable {
        /// Source voxels per axis.
        source_dims: UVec3,
        /// Regions (`controls − 3`) per axis.
        regions: UVec3,
    },
    /// Two things that must have the same dimensions do not.
    #[error("dimension mismatch: {0}")]
    Mismatch(String),
    /// A direct-manipulation handle has no free control point in its support
    /// (its region of influence excludes every control point that moves it).
    #[error("handle {0} cannot move: no control point inside the region of influence affects it")]
    Unreachable(usize),
    /// A saved map ([`crate::WorldMap::from_json`]) could not be read.
    #[error("not a B-spline map file as `isomorph warp` writes it: {0}")]
    MapFile(String),
}

impl From<GridError> for WarpError {
    fn from(e: GridError) -> Self {
        WarpError::Morph(MorphError::Grid(e))
    }
}

impl MorphFailure for WarpError {
    fn shared(&self) -> Option<&MorphError> {
        match self {
            WarpError::Morph(e) => Some(e),
            _ => None,
        }
    }
}
