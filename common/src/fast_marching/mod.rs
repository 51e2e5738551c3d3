//! Fast marching (Sethian) on cubic-voxel grids: signed distance from seeds,
//! redistancing of any level-set grid, and the marching stage of CSG scan
//! conversion.
//!
//! The front advances from the seeds in order of distance, on both sides of
//! the surface at once (**positive inside**). Each node is one packed 8-byte
//! cell (distance; Far / Trial / Known state, side, seed flag and surface
//! element), and the narrow band is a monotone radix heap of `(distance,
//! node)` pairs (Eikonal updates) or a queue of one-voxel shells
//! (closest-point propagation), so a run does no per-node allocation.
//! Three node updates are offered ([`Update`]):
//!
//! | update | what it computes | sphere, r = 10 voxels, exact seeds within 1 voxel: max error, within 3 voxels | torus 64³ by [`redistance`]: max error, within 2 voxels |
//! |---|---|---|---|
//! | [`Update::FirstOrder`] | first-order upwind Eikonal `\|∇u\| = 1`, quadratic over 1–3 upwind axes; O(h), the error grows with the distance | 0.88, 0.14 voxel | 0.59, 0.07 voxel |
//! | [`Update::SecondOrder`] | Sethian's second-order one-sided stencil, first order where the second upwind node is not Known; O(h²) in smooth regions | 0.31, 0.05 voxel | 0.19, 0.03 voxel |
//! | [`Update::ClosestPoint`] (default) | each node inherits the surface element (closest point and tangent disc) of a neighbour; distance = to that disc; ≲ 0.06 voxel for planes | 0.26, 0.22 voxel | 0.16, 0.05 voxel |
//!
//! (Bounds asserted by the tests: first order < 1 voxel, second order
//! < 0.35, closest point < 0.3 from one seed layer; [`redistance`] < 0.25
//! and < 0.05 near the surface with closest points.) Closest-point
//! propagation errs where a node's true closest point is not propagated
//! through its neighbours (near medial axes, and next to a single seed
//! layer on the concave side, which is why [`redistance`] and scan
//! conversion seed two layers). It is also the faster mode: its front is
//! relaxed shell by shell, large shells in parallel by z-slabs, while the
//! Eikonal updates run the classic sequential heap.
//!
//! Cost: near-linear in the number of nodes (the shells of closest-point
//! propagation hold each node once; the Eikonal updates pay a radix heap).
//! Bench: `cargo bench -p isomorph-benches --bench common --
//! redistance/torus/256` (figures in `docs/EXPERIMENTS.md`).
//!
//! [`redistance`] turns any grid whose zero level set is right but whose
//! values are not distances (a sign field, a scaled or clamped field) into a
//! signed distance: the nodes next to a sign change get the exact distance to
//! the trilinearly interpolated zero set (Chopp's projection, checked against
//! the edge crossings), then the front marches out from them. The zero set
//! moves by at most the interpolation error, far below a voxel.
//!
//! ```
//! use glam::{UVec3, Vec3};
//! use isomorph_common::fast_marching::{FastMarchingSettings, redistance};
//! use isomorph_common::Grid3;
//!
//! // A ball of radius 0.3 whose field is not a distance.
//! let field = |p: Vec3| 0.09 - p.length_squared();
//! let grid = Grid3::sample(&field, UVec3::splat(33), Vec3::splat(-0.5), 1.0 / 32.0)?;
//! let sdf = redistance(&grid, &FastMarchingSettings::default())?;
//! for (index, value) in sdf.data().iter().enumerate() {
//!     let n = sdf.node_of(index);
//!     let exact = 0.3 - sdf.position(n.x, n.y, n.z).length();
//!     assert!((value - exact).abs() < 0.3 / 32.0); // under 0.3 voxel everywhere
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub(crate) mod band;
mod heap;
pub(crate) mod march;
#[cfg(test)]
mod tests;

use crate::{Grid3, GridError};
use glam::{UVec3, Vec3};
use march::{BandSeed, Marcher};
use rayon::prelude::*;

/// Errors of fast marching and redistancing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FastMarchingError {
    /// The working arrays or the result do not fit the memory limit.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// The grid has more nodes than 32-bit node indices can address.
    #[error("grid of {0} nodes is too large for fast marching (at most 2^32 − 1 nodes)")]
    TooManyNodes(u64),
    /// Closest-point propagation has more seeds than its 27-bit seed
    /// indices can address.
    #[error("{0} seeds are too many for closest-point propagation (at most 2^27 − 1)")]
    TooManySeeds(usize),
    /// An input value is NaN.
    #[error("value at node {node} is NaN; redistancing needs a sign at every node")]
    NaN {
        /// The node `(i, j, k)`.
        node: UVec3,
    },
    /// The grid has no sign change and no zero node, so it has no surface.
    #[error(
        "the grid has no zero crossing (all values are on one side), so there is no surface to measure from"
    )]
    NoInterface,
    /// [`march`] was called without seeds.
    #[error("fast marching needs at least one seed")]
    NoSeeds,
    /// A seed lies outside the grid or has a non-finite distance or closest point.
    #[error("seed {0} is invalid: node outside the grid, or a non-finite distance or closest point")]
    BadSeed(usize),
    /// [`Update::ClosestPoint`] was asked for but a seed has no closest point.
    #[error("seed {0} has no closest point, which Update::ClosestPoint needs")]
    MissingClosestPoint(usize),
    /// `max_distance` is not positive (NaN, zero or negative).
    #[error("max_distance must be positive, got {0}")]
    BadMaxDistance(f32),
}

/// How a Trial node's distance is computed from its accepted neighbours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Update {
    /// First-order upwind solution of `|∇u| = 1` (error O(h), growing with
    /// the distance from the seeds).
    FirstOrder,
    /// Sethian's second-order upwind stencil where two upwind nodes are
    /// Known and monotone, first order elsewhere (error O(h²) in smooth
    /// regions).
    SecondOrder,
    /// Closest-point propagation: each node takes the seed surface point of
    /// an accepted neighbour that is nearest to it; the distance is the
    /// Euclidean distance to that point. The most accurate and fastest
    /// choice; needs a closest point on every seed.
    #[default]
    ClosestPoint,
}

/// Settings of [`march`] and [`redistance`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FastMarchingSettings {
    /// The node update (default: closest-point propagation).
    pub update: Update,
    /// Stop the front at this distance (world units): nodes farther away
    /// keep `±max_distance` with their side's sign (narrow-band use).
    /// `None` marches the whole grid.
    pub max_distance: Option<f32>,
}

/// A node with a known signed distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// The node `(i, j, k)`.
    pub node: UVec3,
    /// Signed distance there (world units, positive inside). Its sign also
    /// gives the side of the nodes reached from it; zero is on the surface.
    pub distance: f32,
    /// The surface point nearest to the node (world coordinates); required
    /// by [`Update::ClosestPoint`], ignored by the Eikonal updates.
    pub closest_point: Option<Vec3>,
}

/// The front's stopping distance in voxels and the value of unreached nodes
/// in world units.
fn limits(settings: &FastMarchingSettings, spacing: f32) -> Result<(f32, f32), FastMarchingError> {
    match settings.max_distance {
        None => Ok((f32::INFINITY, f32::INFINITY)),
        Some(d) if d > 0.0 => Ok((d / spacing, d)),
        Some(d) => Err(FastMarchingError::BadMaxDistance(d)),
    }
}

/// Signed distance on the `dims` lattice at `origin` with `spacing`, marched
/// out from `seeds` (positive inside).
///
/// Every node takes the side of the seed region that reaches it first; nodes
/// beyond `max_distance` get `±max_distance` with the side of the region
/// around them (flood fill from the reached nodes). Nodes reached only from
/// zero-distance seeds, with no signed seed anywhere, count as outside.
/// Where several seeds name the same node, the smallest distance wins.
///
/// # Errors
/// [`FastMarchingError::NoSeeds`], [`FastMarchingError::BadSeed`],
/// [`FastMarchingError::MissingClosestPoint`] (closest-point update),
/// [`FastMarchingError::BadMaxDistance`], and lattice or memory errors.
///
/// ```
/// use glam::{UVec3, Vec3};
/// use isomorph_common::fast_marching::{FastMarchingSettings, Seed, Update, march};
///
/// // The plane z = 0.25 seen from nodes on both sides (inside below it).
/// let (h, dims) = (0.1, UVec3::splat(8));
/// let mut seeds = Vec::new();
/// for (k, d) in [(2, 0.05), (3, -0.05)] {
///     for j in 0..8 {
///         for i in 0..8 {
///             let x = Vec3::new(i as f32, j as f32, k as f32) * h;
///             seeds.push(Seed { node: UVec3::new(i, j, k), distance: d, closest_point: Some(x.with_z(0.25)) });
///         }
///     }
/// }
/// let settings = FastMarchingSettings { update: Update::FirstOrder, max_distance: None };
/// let grid = march(dims, Vec3::ZERO, h, &seeds, &settings)?;
/// assert!((grid.get(3, 3, 7).unwrap() + 0.45).abs() < 1e-5); // 0.45 outside
/// assert!((grid.get(3, 3, 0).unwrap() - 0.25).abs() < 1e-5); // 0.25 inside
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn march(
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
    seeds: &[Seed],
    settings: &FastMarchingSettings,
) -> Result<Grid3<f32>, FastMarchingError> {
    march_with_discs(dims, origin, spacing, seeds, settings, true)
}

/// [`march`], with closest points standing for tangent discs (`discs`, the
/// public behaviour: right for smooth surfaces sampled about a voxel apart)
/// or for themselves only (exact closest points of a mesh, whose creases
/// and corners a disc would cut).
pub(crate) fn march_with_discs(
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
    seeds: &[Seed],
    settings: &FastMarchingSettings,
    discs: bool,
) -> Result<Grid3<f32>, FastMarchingError> {
    // Validate the lattice first (a grid constructor reports bad geometry).
    Grid3::new(UVec3::ONE, origin, spacing, 0u8)?;
    let (limit, unreached) = limits(settings, spacing)?;
    if seeds.is_empty() {
        return Err(FastMarchingError::NoSeeds);
    }
    let mut marcher = Marcher::new(dims, settings.update, limit, None)?;
    for (number, seed) in seeds.iter().enumerate() {
        let n = seed.node;
        let cp_ok = seed.closest_point.is_none_or(|c| c.is_finite());
        if n.cmpge(dims).any() || !seed.distance.is_finite() || !cp_ok {
            return Err(FastMarchingError::BadSeed(number));
        }
        let index = n.x + dims.x * (n.y + dims.y * n.z);
        let inside = (seed.distance != 0.0).then_some(seed.distance > 0.0);
        let closest = seed.closest_point.map(|c| (c - origin) / spacing);
        let disc = closest
            .filter(|_| discs)
            .and_then(|c| (n.as_vec3() - c).try_normalize())
            .map(|n| (n, march::DISC_RADIUS));
        let band = BandSeed { index, distance: seed.distance.abs() / spacing, inside, closest, disc };
        marcher.add_seed(band, number)?;
    }
    marcher.run();
    marcher.finish(origin, spacing, unreached)
}

/// Re-initializes the zero level set of `grid` (positive inside) as a signed
/// distance on the same lattice, keeping the zero set where trilinear
/// interpolation puts it.
///
/// Values only matter through their sign and, next to a sign change, their
/// ratio along grid edges; any monotone rescaling of a field near its surface
/// redistances the same. Nodes with value exactly zero stay zero. With
/// `max_distance`, nodes farther away get `±max_distance` (sign of the input).
///
/// # Errors
/// [`FastMarchingError::NaN`] for a NaN value, [`FastMarchingError::NoInterface`]
/// when the grid has no sign change and no zero node,
/// [`FastMarchingError::BadMaxDistance`], and memory errors.
pub fn redistance(
    grid: &Grid3<f32>,
    settings: &FastMarchingSettings,
) -> Result<Grid3<f32>, FastMarchingError> {
    let values = grid.data();
    if let Some(index) = values.par_iter().position_any(|v| v.is_nan()) {
        return Err(FastMarchingError::NaN { node: grid.node_of(index) });
    }
    let seeds = band::grid_seeds(values, grid.dims());
    march_band(values, grid, &seeds, settings)
}

/// Marches out from band `seeds` (grid units) with each node's side taken
/// from the sign of `values` on `lattice`'s nodes.
///
/// # Errors
/// [`FastMarchingError::NoInterface`] without seeds,
/// [`FastMarchingError::BadMaxDistance`], and memory errors.
pub(crate) fn march_band(
    values: &[f32],
    lattice: &Grid3<f32>,
    seeds: &[BandSeed],
    settings: &FastMarchingSettings,
) -> Result<Grid3<f32>, FastMarchingError> {
    let (limit, unreached) = limits(settings, lattice.spacing())?;
    if seeds.is_empty() {
        return Err(FastMarchingError::NoInterface);
    }
    let mut marcher = Marcher::new(lattice.dims(), settings.update, limit, Some(values))?;
    for (number, &seed) in seeds.iter().enumerate() {
        marcher.add_seed(seed, number)?;
    }
    marcher.run();
    marcher.finish(lattice.origin(), lattice.spacing(), unreached)
}
