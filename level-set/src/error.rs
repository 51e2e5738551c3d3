//! Errors of the level-set morph.

use isomorph_common::GridError;

/// What can go wrong setting up or running a level-set morph.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LevelSetError {
    /// A grid could not be made (memory limit) or two grids do not share a lattice.
    #[error(transparent)]
    Grid(#[from] GridError),
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
    /// A component of the target does not overlap the source (Breen & Whitaker
    /// §4): the evolving surface can never reach it. Align the shapes first
    /// (`isomorph_common::alignment`) or pass a transform.
    #[error(
        "{components} of {total} target component(s) do not overlap the source; the level-set morph \
         cannot reach them (align the shapes or pass a transform)"
    )]
    NoOverlap {
        /// Target components without any inside node shared with the source.
        components: usize,
        /// All target components.
        total: usize,
    },
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
    /// A morph time outside `[0, 1]` or NaN.
    #[error("time {0} is outside [0, 1]")]
    InvalidTime(f32),
}
