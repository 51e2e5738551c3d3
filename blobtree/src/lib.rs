//! Skeletal implicit BlobTrees and their metamorphosis after Galin, Leclercq &
//! Akkouche, *Morphing the BlobTree*, Computer Graphics Forum 19(4), 2000.

pub mod correspond;
pub mod error;
pub mod generic;
pub mod hull;
pub mod kernel;
pub mod minkowski;
pub mod node;
pub mod scene;
pub mod scenes;
pub mod skeleton;
pub mod tree;
pub mod warp;

pub use correspond::{Correspondence, Heuristic, Link, Origin, Pair, decompose};
pub use error::{BlobError, MorphError, NodePath, NodeProblem, Side};
pub use generic::{BlobMorph, GenericTree, MorphSpec, Speed, SpeedCurve, Trajectory};
pub use kernel::Kernel;
pub use minkowski::MinkowskiPath;
pub use node::{NaryOp, Node, Primitive};
pub use skeleton::{Polytope, Skeleton};
pub use tree::BlobTree;
pub use warp::Warp;

#[cfg(test)]
mod testutil;
