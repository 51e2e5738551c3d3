//! CSG scan conversion (Breen & Whitaker 2001, §6.1): an analytic [`Shape`]
//! turned into a signed distance volume, positive inside.
//!
//! A CSG tree's field is exact only in places (outside a union, inside an
//! intersection; superellipsoids give a radial distance), but its zero set and
//! sign are exact. Scan conversion keeps those and replaces the magnitudes:
//!
//! 1. sample the field on the lattice (sign of every node);
//! 2. for the nodes next to the surface (a sign change to a 6-neighbour, and
//!    the layer beyond), find the closest point on the evaluated CSG surface:
//!    the zero crossing of the node's grid edges by bisection on the field
//!    (always a surface point), refined by Chopp's projection (Newton steps
//!    onto `f = 0` alternating with steps that make the offset normal to the
//!    surface, gradient by central differences) when that lands on the
//!    surface closer to the node; every accepted point is verified by its
//!    field value (`|f| / |∇f|` under 10⁻³ voxel);
//! 3. fast-march the rest of the grid from those exact values
//!    ([`crate::fast_marching`], closest-point propagation by default).
//!
//! Near the surface the result is the distance to the closest point found
//! (exact up to the projection's convergence, ≲ 10⁻³ voxel on smooth parts);
//! farther away the error is that of the marching update (see
//! [`crate::fast_marching`]); at concave creases of the CSG surface the
//! closest point may lie on the crease, where the projection falls back to the
//! nearest verified surface point found.
//!
//! ```
//! use isomorph_common::fast_marching::FastMarchingSettings;
//! use isomorph_common::scan_conversion::scan_convert;
//! use isomorph_common::{Aabb, models};
//!
//! // Breen's "C": CSG of superellipsoids, whose field is only a bound.
//! let sdf = scan_convert(&models::c_shape(), &Aabb::cube(0.5), 40, &FastMarchingSettings::default())?;
//! // Left side of the ring, solid; the ring is 0.2 wide there (x from −0.4 to −0.2).
//! let h = sdf.spacing();
//! let d = isomorph_common::Field3::value(&sdf, glam::Vec3::new(-0.3, 0.0, 0.0));
//! assert!(d > 0.0 && d < 0.1 + h);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::fast_marching::band::{Surface, interface_seeds};
use crate::fast_marching::{FastMarchingError, FastMarchingSettings, march_band};
use crate::grid::lattice_for_box;
use crate::{Aabb, Grid3, GridError, Shape, ShapeError};
use glam::{UVec3, Vec3};

/// Errors of [`scan_convert`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScanError {
    /// The shape has a bad parameter or placement.
    #[error(transparent)]
    Shape(#[from] ShapeError),
    /// The box or resolution gives no valid lattice, or it does not fit memory.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Marching failed; [`FastMarchingError::NoInterface`] means the shape's
    /// surface does not cross the lattice.
    #[error(transparent)]
    FastMarching(#[from] FastMarchingError),
}

/// Bisection steps on a grid edge (the crossing to 2⁻²⁴ of the edge).
const BISECTIONS: usize = 24;
/// Central-difference step of the field gradient, in voxels.
const GRADIENT_STEP: f32 = 0.01;

/// The shape's zero set seen in grid units.
struct ShapeSurface<'a> {
    shape: &'a Shape,
    values: &'a [f32],
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
}

impl ShapeSurface<'_> {
    fn field(&self, p: Vec3) -> f32 {
        self.shape.distance(self.origin + self.spacing * p)
    }
}

impl Surface for ShapeSurface<'_> {
    fn values(&self) -> &[f32] {
        self.values
    }

    fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Field value (world units) and its gradient per voxel.
    fn sample(&self, p: Vec3) -> (f32, Vec3) {
        let e = GRADIENT_STEP;
        let g = Vec3::new(
            self.field(p + Vec3::X * e) - self.field(p - Vec3::X * e),
            self.field(p + Vec3::Y * e) - self.field(p - Vec3::Y * e),
            self.field(p + Vec3::Z * e) - self.field(p - Vec3::Z * e),
        ) / (2.0 * e);
        (self.field(p), g)
    }

    /// Bisection on the field along the edge.
    fn edge_zero(&self, a: Vec3, b: Vec3, va: f32, _vb: f32) -> f32 {
        let inside = va > 0.0;
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if (self.field(a + mid * (b - a)) > 0.0) == inside {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// The signed distance volume (positive inside) of `shape` over `bounds`,
/// with `res` nodes along the longest edge (cubic voxels, see
/// [`lattice_for_box`]). `settings` choose the marching update and an
/// optional narrow band (`max_distance`, world units).
///
/// # Errors
/// [`ScanError::Shape`] for an invalid shape, [`ScanError::Grid`] for a bad
/// box or resolution or too little memory, [`ScanError::FastMarching`] when
/// the surface does not cross the lattice or the settings are invalid.
pub fn scan_convert(
    shape: &Shape,
    bounds: &Aabb,
    res: u32,
    settings: &FastMarchingSettings,
) -> Result<Grid3<f32>, ScanError> {
    shape.validate()?;
    let (dims, origin, spacing) = lattice_for_box(bounds, res)?;
    let grid = Grid3::sample(shape, dims, origin, spacing)?;
    let surface = ShapeSurface { shape, values: grid.data(), dims, origin, spacing };
    let seeds = interface_seeds(&surface);
    Ok(march_band(grid.data(), &grid, &seeds, settings)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models;

    /// Max error (voxels) against an exact distance, overall and within 2 voxels.
    fn errors(grid: &Grid3<f32>, exact: &Shape) -> (f32, f32) {
        let h = grid.spacing();
        let (mut all, mut near) = (0.0f32, 0.0f32);
        for (index, &v) in grid.data().iter().enumerate() {
            let n = grid.node_of(index);
            let d = exact.distance(grid.position(n.x, n.y, n.z));
            let e = (v - d).abs() / h;
            all = all.max(e);
            if d.abs() < 2.0 * h {
                near = near.max(e);
            }
        }
        (all, near)
    }

    #[test]
    fn sphere_and_box_match_their_exact_distances() {
        let settings = FastMarchingSettings::default();
        let sphere = Shape::sphere(0.3).translated(Vec3::new(0.013, -0.021, 0.007));
        let grid = scan_convert(&sphere, &Aabb::cube(0.5), 48, &settings).unwrap();
        let (all, near) = errors(&grid, &sphere);
        assert!(all < 0.3 && near < 0.05, "sphere: max {all} voxels, near {near}");
        // A rotated box: its closest points lie on edges and corners too.
        let cuboid = Shape::cuboid(Vec3::new(0.3, 0.2, 0.25)).rotated(glam::Quat::from_rotation_z(0.3));
        let grid = scan_convert(&cuboid, &Aabb::cube(0.5), 48, &settings).unwrap();
        let (all, near) = errors(&grid, &cuboid);
        assert!(all < 0.3 && near < 0.3, "box: max {all} voxels, near {near}");
    }

    /// Breen's models: the sign is the shape's everywhere, every zero crossing
    /// of a grid edge is consistent with the distances at its ends (a node
    /// is no farther from the surface than the crossing), and the gradient
    /// has unit length away from medial axes, unlike the raw CSG field.
    #[test]
    fn breen_models_become_distance_volumes() {
        for name in ["mug", "chain", "ball", "c-shape"] {
            let shape = models::by_name(name).unwrap();
            let grid = scan_convert(&shape, &Aabb::cube(0.5), 40, &FastMarchingSettings::default()).unwrap();
            let (h, dims) = (grid.spacing(), grid.dims());
            let mut worst_crossing = 0.0f32;
            for (index, &v) in grid.data().iter().enumerate() {
                let n = grid.node_of(index);
                let p = grid.position(n.x, n.y, n.z);
                let f = shape.distance(p);
                assert!(f == 0.0 || (f > 0.0) == (v > 0.0), "{name}: sign differs at {p}");
                for axis in 0..3 {
                    let mut m = n;
                    m[axis] += 1;
                    if m[axis] >= dims[axis] {
                        continue;
                    }
                    let q = grid.position(m.x, m.y, m.z);
                    let w = *grid.get(m.x, m.y, m.z).unwrap();
                    if (f > 0.0) == (shape.distance(q) > 0.0) {
                        continue;
                    }
                    let (mut lo, mut hi) = (0.0f32, 1.0f32);
                    for _ in 0..30 {
                        let mid = 0.5 * (lo + hi);
                        if (shape.distance(p + mid * (q - p)) > 0.0) == (f > 0.0) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let t = 0.5 * (lo + hi);
                    worst_crossing =
                        worst_crossing.max((v.abs() - t * h) / h).max((w.abs() - (1.0 - t) * h) / h);
                }
            }
            assert!(
                worst_crossing < 0.02,
                "{name}: a node is {worst_crossing} voxels farther than a crossing"
            );
            let unit = |g: &Grid3<f32>| {
                let mut lengths = Vec::new();
                for k in 1..dims.z - 1 {
                    for j in 1..dims.y - 1 {
                        for i in 1..dims.x - 1 {
                            lengths.push(g.node_gradient(i, j, k).length());
                        }
                    }
                }
                lengths.iter().filter(|&&l| (l - 1.0).abs() < 0.05).count() as f32 / lengths.len() as f32
            };
            let share = unit(&grid);
            assert!(share > 0.9, "{name}: only {share} of the nodes have |∇d| within 5% of 1");
            if name == "c-shape" {
                let raw = Grid3::sample(&shape, dims, grid.origin(), h).unwrap();
                assert!(unit(&raw) < share - 0.1, "the raw superellipsoid field is not a distance");
            }
        }
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let settings = FastMarchingSettings::default();
        let bad = Shape::sphere(-1.0);
        assert!(matches!(scan_convert(&bad, &Aabb::cube(0.5), 16, &settings), Err(ScanError::Shape(_))));
        let far = Shape::sphere(0.1).translated(Vec3::splat(3.0));
        assert_eq!(
            scan_convert(&far, &Aabb::cube(0.5), 16, &settings),
            Err(ScanError::FastMarching(FastMarchingError::NoInterface))
        );
        let sphere = Shape::sphere(0.3);
        assert!(matches!(scan_convert(&sphere, &Aabb::cube(0.5), 1, &settings), Err(ScanError::Grid(_))));
    }
}
