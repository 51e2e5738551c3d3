//! Automatic alignment of two solids by their moments (Breen & Whitaker
//! 2001, Appendix), and the interpolated transform `T(x, α)` of their eq. 25.
//!
//! # Moments
//! [`Moments`] holds the volume, centroid, covariance (second central moments
//! per unit volume, length²) and third central moments (per unit volume,
//! length³) of a solid, computed
//! - from a closed triangle mesh **exactly**, by summing signed tetrahedra
//!   spanned by a reference point and each triangle ([`Moments::from_mesh`]);
//! - from a grid of a positive-inside field with subvoxel partial-volume
//!   weights ([`Moments::from_grid`], [`Moments::from_field`]).
//!
//! Breen counts interior grid points with equal weight; the partial-volume
//! weights here make the moments converge at second order in the spacing
//! instead of first, so small grids already give stable axes.
//!
//! # Alignment map
//! Each solid gets a [`PrincipalFrame`]: its centroid `c`, the unit
//! eigenvectors of its covariance as the columns of a rotation `R` (ordered by
//! *increasing* eigenvalue, as Breen's x, y, z), and the eigenvalues `λ`. The
//! map from source `A` to target `B` is, in the column-vector form glam uses,
//!
//! ```text
//! x' = c_B + R_B · S · R_Aᵀ · (x − c_A)
//! ```
//!
//! which is Breen's row-vector eq. 34, `p' = (p − c_A) R_A S R_Bᵀ + c_B`,
//! transposed. [`AlignMode`] chooses `S`:
//! - [`AlignMode::Affine`]: `S = diag(√(λ_B,i / λ_A,i))`. The eigenvalues are
//!   variances (length²), so the per-axis *length* ratio is the square root of
//!   their ratio, exactly Breen's eq. 33;
//! - [`AlignMode::Similarity`]: `S = s·I` with `s = ∛(V_B / V_A)`;
//! - [`AlignMode::Rigid`]: `S = I` (rotation and translation only).
//!
//! # Axis signs
//! An eigenvector is only defined up to sign, which Breen leaves open; a wrong
//! sign turns the source upside down. Here each axis `e` is oriented so that
//! the standardized third central moment (skewness) along it,
//! `γ = E[((x − c)·e)³] / λ^{3/2}`, is positive. When `|γ| ≤`
//! [`SKEW_TOLERANCE`] (the shape is symmetric, or nearly, along that axis) the
//! sign is chosen deterministically instead: the axis' largest world
//! component is made positive. Finally, if the three axes form a left-handed
//! frame, the axis with the smallest `|γ|` (the least reliable sign) is
//! flipped, so `R` is always a proper rotation and the map never mirrors.
//!
//! # Equal eigenvalues
//! When two eigenvalues agree to within [`EQUAL_EIGENVALUES`] (relative) —
//! a cylinder, a cone, any solid of revolution — their eigenvectors are
//! arbitrary within their plane, and whatever the eigensolver returns there
//! is rounding noise. They are replaced by a choice tied to the world axes:
//! the world axis with the longest projection onto that plane (normalized)
//! takes the lower slot, its cross product with the distinct axis the upper
//! one. When all three agree (a sphere, a cube) the frame is the world axes.
//! Signs then follow the rules above. So two such solids that differ only by
//! a translation and scale get no spurious rotation, and the result is
//! deterministic.
//!
//! **Limits.** Moments see a solid only up to its symmetries of second and
//! third order: shapes with (near) zero skewness along an axis are aligned up
//! to a half-turn about it, and shapes with (near) equal eigenvalues are
//! aligned only up to a rotation in the plane of those axes (the fallback
//! above picks one; a rotated cube is not turned back). The map is still a
//! finite, proper, non-singular transform in those cases; check
//! [`PrincipalFrame::min_relative_gap`] to detect them. An anisotropic scale
//! is recovered only when it acts along the shape's own principal axes
//! (anything else also shears the covariance), and only while it keeps the
//! eigenvalue order.
//!
//! # Example
//! A mug turned and moved is put back in place by the rigid alignment of its
//! grid moments onto those of the original:
//! ```
//! use isomorph_common::alignment::{AlignMode, Moments, align};
//! use isomorph_common::glam::{Affine3A, Quat, Vec3};
//! use isomorph_common::models;
//!
//! let motion = Affine3A::from_rotation_translation(
//!     Quat::from_rotation_z(0.7) * Quat::from_rotation_x(-0.4),
//!     Vec3::new(0.2, -0.1, 0.3),
//! );
//! let mug = models::mug();
//! let moved = models::mug().transformed(motion);
//! let source = Moments::from_field(&moved, &moved.aabb(), 40)?;
//! let target = Moments::from_field(&mug, &mug.aabb(), 40)?;
//! let alignment = align(&source, &target, AlignMode::Rigid)?;
//! // Source-to-target map ∘ motion ≈ identity.
//! let p = Vec3::new(0.1, 0.2, -0.3);
//! let back = alignment.map.transform_point3(motion.transform_point3(p));
//! assert!(back.distance(p) < 0.01, "{back} vs {p}");
//! // The time path for a morph: identity at t = 0, the map at t = 1.
//! assert!(alignment.at(0.0).abs_diff_eq(Affine3A::IDENTITY, 1e-6));
//! assert!(alignment.at(1.0).abs_diff_eq(alignment.map, 1e-5));
//! # Ok::<(), isomorph_common::alignment::AlignError>(())
//! ```

use crate::transform::{AffineParts, AffinePath, TransformError};
use crate::{Aabb, Field3, Grid3, GridError, MeshError, TriMesh};
use glam::{Affine3A, DMat3, DVec3, Mat3, Quat, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Standardized skewness at or below which an axis counts as symmetric and
/// its sign is chosen by the deterministic fallback (see the module docs).
pub const SKEW_TOLERANCE: f64 = 1e-3;

/// Smallest ratio of the least to the largest covariance eigenvalue accepted;
/// below it (an aspect ratio under 1 : 10⁴) the solid counts as flat.
pub const FLAT_RATIO: f64 = 1e-8;

/// Relative eigenvalue gap `(λ_{i+1} − λ_i) / λ_{i+1}` at or below which two
/// principal axes count as equal and are replaced by the world-axis fallback
/// (see the module docs). Grid moments ([`Moments::from_field`]) of a
/// cylinder or torus in a general orientation show gaps of about 3e-3 at 24
/// nodes along the longest edge and 3e-4 at 64 (the sharp rims cut the
/// lattice unevenly; a sphere's stay below 1e-7), so this leaves a margin.
pub const EQUAL_EIGENVALUES: f64 = 1e-2;

/// Largest `|Σ area vectors| / Σ |area vectors|` of a mesh accepted as closed.
pub const OPEN_TOLERANCE: f64 = 1e-6;

/// Triangles per parallel work item of [`Moments::from_mesh`] (fixed, so that
/// the summation order, and thus the result, does not depend on the threads).
const MESH_CHUNK: usize = 4096;

/// Why moments or an alignment cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AlignError {
    /// The solid has no volume: an empty mesh or grid, a mesh whose signed
    /// volume vanishes (flat, or as much facing in as out), or a field that is
    /// nowhere positive.
    #[error("the shape is empty (zero volume)")]
    Empty,
    /// A grid value, a mesh coordinate or a moment is NaN (or infinite where a
    /// finite number is needed).
    #[error("the shape's data or moments are not finite")]
    NonFinite,
    /// The covariance is (nearly) singular: the solid is flat or a line, so
    /// its principal axes and scales are not defined. Values ascending, length².
    #[error(
        "the shape is flat: covariance eigenvalues {eigenvalues:?} (smallest ≤ {FLAT_RATIO:e} × largest)"
    )]
    Degenerate {
        /// The covariance eigenvalues, ascending.
        eigenvalues: [f64; 3],
    },
    /// The mesh is not closed: its triangle area vectors do not sum to zero,
    /// so it bounds no solid (relative imbalance given).
    #[error(
        "the mesh is not closed (area-vector imbalance {imbalance:e} > {OPEN_TOLERANCE:e}); close its holes"
    )]
    OpenMesh {
        /// `|Σ area vectors| / Σ |area vectors|`.
        imbalance: f64,
    },
    /// The mesh failed validation (bad index, non-finite coordinate).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Sampling a field into a grid failed.
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// Volume, centroid, covariance and third central moments of a solid.
///
/// All central moments are per unit volume (averages over the solid), in f64.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Volume (world units³), positive.
    pub volume: f64,
    /// Centroid (world units).
    pub centroid: DVec3,
    /// Covariance `E[(x − c)(x − c)ᵀ]` (world units²), symmetric.
    pub covariance: DMat3,
    /// Third central moments `E[(x − c)_i (x − c)_j (x − c)_k]` (world
    /// units³), indexed `[i][j][k]`, fully symmetric.
    pub third: [[[f64; 3]; 3]; 3],
}

/// Raw moments about a reference point `r`: `∫1`, `∫y`, `∫y⊗y`, `∫y⊗y⊗y`
/// with `y = x − r`, accumulated in f64.
#[derive(Debug, Clone, Copy, PartialEq)]
struct RawMoments {
    m0: f64,
    m1: [f64; 3],
    m2: [[f64; 3]; 3],
    m3: [[[f64; 3]; 3]; 3],
}

impl RawMoments {
    const ZERO: RawMoments = RawMoments { m0: 0.0, m1: [0.0; 3], m2: [[0.0; 3]; 3], m3: [[[0.0; 3]; 3]; 3] };

    fn add(mut self, o: &RawMoments) -> RawMoments {
        self.m0 += o.m0;
        for i in 0..3 {
            self.m1[i] += o.m1[i];
            for j in 0..3 {
                self.m2[i][j] += o.m2[i][j];
                for k in 0..3 {
                    self.m3[i][j][k] += o.m3[i][j][k];
                }
            }
        }
        self
    }

    fn negated(self) -> RawMoments {
        RawMoments {
            m0: -self.m0,
            m1: self.m1.map(|v| -v),
            m2: self.m2.map(|r| r.map(|v| -v)),
            m3: self.m3.map(|m| m.map(|r| r.map(|v| -v))),
        }
    }

    /// Adds the solid tetrahedron `(r, a, b, c)` (corners relative to `r`)
    /// with signed volume `a · (b × c) / 6`. The integral of a cubic form over a
    /// simplex is `V · n! d! / (n + d)! · h_n(corner values)` with `h_n` the
    /// complete homogeneous symmetric polynomial; polarizing
    /// `h_2 = (p1² + p2)/2` and `h_3 = (p1³ + 3 p1 p2 + 2 p3)/6` in the power
    /// sums `p_k` gives the tensors below (`s` = corner sum, `Q` = Σ corner ⊗
    /// corner; the apex `r` is the zero corner).
    fn add_tetrahedron(&mut self, [a, b, c]: [DVec3; 3]) {
        let v = a.dot(b.cross(c)) / 6.0;
        let s = a + b + c;
        let q = |i: usize, j: usize| a[i] * a[j] + b[i] * b[j] + c[i] * c[j];
        self.m0 += v;
        for i in 0..3 {
            self.m1[i] += v * s[i] / 4.0;
            for j in 0..3 {
                self.m2[i][j] += v / 20.0 * (s[i] * s[j] + q(i, j));
                for k in 0..3 {
                    let cubes = a[i] * a[j] * a[k] + b[i] * b[j] * b[k] + c[i] * c[j] * c[k];
                    self.m3[i][j][k] += v / 120.0
                        * (s[i] * s[j] * s[k]
                            + s[i] * q(j, k)
                            + s[j] * q(i, k)
                            + s[k] * q(i, j)
                            + 2.0 * cubes);
                }
            }
        }
    }

    /// Adds the part of the axis-aligned cube of edge `h` centred at `p`
    /// (relative to `r`) that is inside: the fraction `w` of it, modelled as
    /// the slab of depth `w·h` on the side of the unit inward normal `n` (zero
    /// for a whole voxel). Its mass sits at the slab's centre
    /// `p + n (1 − w) h / 2` with the slab's spread, `h²/12` across `n` and
    /// `(w h)²/12` along it (exact for a cut parallel to a face, and the slab
    /// is symmetric, so it adds no third central moment of its own).
    fn add_voxel(&mut self, p: DVec3, h: f64, w: f64, n: DVec3) {
        let dv = w * h * h * h;
        let c = p + n * ((1.0 - w) * h / 2.0);
        let (across, along) = (h * h / 12.0, (w * h) * (w * h) / 12.0);
        let delta = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
        let spread = |i: usize, j: usize| across * delta(i, j) + (along - across) * n[i] * n[j];
        self.m0 += dv;
        for i in 0..3 {
            self.m1[i] += dv * c[i];
            for j in 0..3 {
                self.m2[i][j] += dv * (c[i] * c[j] + spread(i, j));
                for k in 0..3 {
                    let cross = c[i] * spread(j, k) + c[j] * spread(i, k) + c[k] * spread(i, j);
                    self.m3[i][j][k] += dv * (c[i] * c[j] * c[k] + cross);
                }
            }
        }
    }

    /// Central moments per unit volume about the centroid.
    fn central(&self, reference: DVec3) -> Result<Moments, AlignError> {
        let v = self.m0;
        if v.is_nan() {
            return Err(AlignError::NonFinite);
        }
        if v <= 0.0 {
            return Err(AlignError::Empty);
        }
        let c = self.m1.map(|m| m / v);
        let e2 = self.m2.map(|r| r.map(|m| m / v));
        let covariance = DMat3::from_cols_array_2d(&std::array::from_fn(|j| {
            std::array::from_fn(|i| e2[i][j] - c[i] * c[j])
        }));
        let third = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                std::array::from_fn(|k| {
                    self.m3[i][j][k] / v - (c[i] * e2[j][k] + c[j] * e2[i][k] + c[k] * e2[i][j])
                        + 2.0 * c[i] * c[j] * c[k]
                })
            })
        });
        let moments = Moments { volume: v, centroid: reference + DVec3::from_array(c), covariance, third };
        let finite = v.is_finite()
            && moments.centroid.is_finite()
            && moments.covariance.is_finite()
            && moments.third.iter().flatten().flatten().all(|t| t.is_finite());
        if finite { Ok(moments) } else { Err(AlignError::NonFinite) }
    }
}

impl Moments {
    /// Exact moments of the solid bounded by a closed, consistently oriented
    /// triangle mesh: the signed tetrahedra from the bounding-box centre to
    /// every triangle are summed in closed form (the classic polyhedral mass
    /// properties; integrals of monomials over simplices).
    ///
    /// A mesh whose triangles all face inward gives the same moments as the
    /// outward one (its negative signed volume is flipped). Parallel over fixed
    /// chunks of triangles, summed in order: the result does not depend on the
    /// thread count.
    ///
    /// # Errors
    /// [`AlignError::Mesh`] for an invalid mesh, [`AlignError::Empty`] for no
    /// triangles or a vanishing volume, [`AlignError::OpenMesh`] when the area
    /// vectors do not cancel (holes, stray triangles), [`AlignError::NonFinite`]
    /// on overflow.
    pub fn from_mesh(mesh: &TriMesh) -> Result<Moments, AlignError> {
        mesh.validate()?;
        if mesh.is_empty() {
            return Err(AlignError::Empty);
        }
        let reference = mesh.bounds().center().as_dvec3();
        let chunks: Vec<(RawMoments, DVec3, f64)> = mesh
            .triangles
            .par_chunks(MESH_CHUNK)
            .map(|tris| {
                let mut raw = RawMoments::ZERO;
                let (mut area_vector, mut area) = (DVec3::ZERO, 0.0);
                for tri in tris {
                    let [a, b, c] = tri.map(|i| mesh.positions[i as usize].as_dvec3() - reference);
                    let n = (b - a).cross(c - a);
                    area_vector += n;
                    area += n.length();
                    raw.add_tetrahedron([a, b, c]);
                }
                (raw, area_vector, area)
            })
            .collect();
        let (mut raw, area_vector, area) =
            chunks.iter().fold((RawMoments::ZERO, DVec3::ZERO, 0.0), |(r, av, a), (cr, cav, ca)| {
                (r.add(cr), av + *cav, a + ca)
            });
        if area <= 0.0 {
            return Err(AlignError::Empty);
        }
        let imbalance = area_vector.length() / area;
        if imbalance.is_nan() {
            return Err(AlignError::NonFinite);
        }
        if imbalance > OPEN_TOLERANCE {
            return Err(AlignError::OpenMesh { imbalance });
        }
        if raw.m0 < 0.0 {
            raw = raw.negated();
        }
        // A volume at rounding level of the box is no solid (flat or cancelling).
        let size = mesh.bounds().size().as_dvec3();
        if raw.m0 <= 1e-12 * size.max_element().powi(3) {
            return Err(AlignError::Empty);
        }
        raw.central(reference)
    }

    /// Moments of the solid where a grid of a positive-inside field is
    /// positive. Each node stands for the voxel (cube of edge `h` = spacing)
    /// centred on it, weighted by the fraction of it inside:
    ///
    /// `w = clamp(0.5 + φ / (h · |∇φ|), 0, 1)`
    ///
    /// at every node (`∇φ` by central differences), and `w = 1` (`φ > 0`) or
    /// `0` where the gradient vanishes or `φ` is infinite. `φ / |∇φ|` is the
    /// first-order distance to the surface, so far from it `w` is 0 or 1, and
    /// for a signed distance (`|∇φ| = 1`) `w = 0.5 + φ/h` is the exact fraction
    /// of a voxel cut by a plane parallel to a face. Dividing by the gradient
    /// makes the weight independent of the field's scale, so any
    /// positive-inside field works, not only distances. The weight is
    /// continuous in `φ`, so a surface running exactly through nodes (`φ = 0`
    /// up to rounding) is measured the same on either side of zero. A cut
    /// voxel's mass is placed at the centre of the slab of depth `w·h` on the
    /// inward side (along `∇φ`) with that slab's spread, and a whole voxel's
    /// spread (`h²/12` per axis) is included, so a face parallel to the grid
    /// is measured exactly, and edges, curved or slanted surfaces give errors
    /// of second order in `h` (measured: about `0.2 h²` in the variances of a
    /// box, and relative errors of 3e-3 at 32 nodes and 8e-4 at 64 in the
    /// volume and variances of an ellipsoid).
    ///
    /// The solid should lie inside the grid (a positive value on the grid's
    /// boundary counts, but the solid is then cut there). Infinite values are
    /// accepted as "far inside/outside" (where a neighbour is infinite the
    /// node counts as whole or empty). Parallel over fixed z-slabs summed in
    /// order: the result does not depend on the thread count.
    ///
    /// # Errors
    /// [`AlignError::NonFinite`] for a NaN value, [`AlignError::Empty`] when no
    /// node is inside.
    pub fn from_grid(grid: &Grid3<f32>) -> Result<Moments, AlignError> {
        if grid.data().par_iter().any(|v| v.is_nan()) {
            return Err(AlignError::NonFinite);
        }
        let reference = grid.bounds().center().as_dvec3();
        let dims = grid.dims();
        let h = grid.spacing();
        let slabs: Vec<RawMoments> = (0..dims.z)
            .into_par_iter()
            .map(|k| {
                let mut raw = RawMoments::ZERO;
                for j in 0..dims.y {
                    for i in 0..dims.x {
                        let (w, n) = partial_volume(grid, i, j, k);
                        if w > 0.0 {
                            let p = grid.position(i, j, k).as_dvec3() - reference;
                            raw.add_voxel(p, h as f64, w, n);
                        }
                    }
                }
                raw
            })
            .collect();
        slabs.iter().fold(RawMoments::ZERO, |a, b| a.add(b)).central(reference)
    }

    /// Moments of a positive-inside field over `bounds`, sampled with `res`
    /// nodes along the longest edge (see [`crate::grid::lattice_for_box`]) and
    /// measured by [`Moments::from_grid`]. The box is padded by two voxels per
    /// side so that a solid touching it is not cut; the sampling error of the
    /// covariance is of order `(h / size)²`.
    ///
    /// # Errors
    /// [`AlignError::Grid`] when the grid cannot be built (`res < 2`, an empty
    /// or non-finite box, memory), otherwise as [`Moments::from_grid`].
    pub fn from_field<F: Field3 + ?Sized>(field: &F, bounds: &Aabb, res: u32) -> Result<Moments, AlignError> {
        let res = res.clamp(2, u32::MAX - 4);
        let pad = 2.0 * bounds.size().max_element() / (res - 1) as f32;
        let grid = Grid3::sample_box(field, &bounds.expanded(pad), res + 4)?;
        Moments::from_grid(&grid)
    }

    /// The third central moment along direction `u` (not normalized):
    /// `E[((x − c)·u)³] = Σ T_ijk u_i u_j u_k`.
    pub fn third_moment_along(&self, u: DVec3) -> f64 {
        let mut sum = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    sum += self.third[i][j][k] * u[i] * u[j] * u[k];
                }
            }
        }
        sum
    }

    /// The principal frame: centroid, covariance eigenvectors ordered by
    /// increasing eigenvalue with signs fixed by skewness, right-handed (see
    /// the module docs).
    ///
    /// # Errors
    /// [`AlignError::NonFinite`] for non-finite moments or eigenvalues,
    /// [`AlignError::Empty`] for a non-positive volume,
    /// [`AlignError::Degenerate`] for a flat solid (smallest eigenvalue ≤
    /// [`FLAT_RATIO`] × largest).
    pub fn principal_frame(&self) -> Result<PrincipalFrame, AlignError> {
        if self.volume.is_nan() || !self.covariance.is_finite() || !self.centroid.is_finite() {
            return Err(AlignError::NonFinite);
        }
        if self.volume <= 0.0 {
            return Err(AlignError::Empty);
        }
        let cov = self.covariance;
        let mat = nalgebra::Matrix3::from_fn(|r, c| 0.5 * (cov.col(c)[r] + cov.col(r)[c]));
        let eig = mat.symmetric_eigen();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let values = order.map(|i| eig.eigenvalues[i]);
        if values.iter().any(|v| !v.is_finite()) {
            return Err(AlignError::NonFinite);
        }
        if values[0] <= FLAT_RATIO * values[2] || values[2] <= 0.0 {
            return Err(AlignError::Degenerate { eigenvalues: values });
        }
        let mut axes = order.map(|i| {
            let col = eig.eigenvectors.column(i);
            DVec3::new(col[0], col[1], col[2]).normalize()
        });
        snap_equal_axes(&values, &mut axes);
        let standardized = |axis: DVec3, lambda: f64| self.third_moment_along(axis) / lambda.powf(1.5);
        let mut skewness = [0.0; 3];
        for a in 0..3 {
            let gamma = standardized(axes[a], values[a]);
            let flip = if gamma.abs() > SKEW_TOLERANCE {
                gamma < 0.0
            } else {
                let largest = (0..3).fold(0, |m, c| if axes[a][c].abs() > axes[a][m].abs() { c } else { m });
                axes[a][largest] < 0.0
            };
            if flip {
                axes[a] = -axes[a];
            }
            skewness[a] = if flip { -gamma } else { gamma };
        }
        if axes[0].dot(axes[1].cross(axes[2])) < 0.0 {
            let weakest = (0..3).fold(0, |m, a| if skewness[a].abs() < skewness[m].abs() { a } else { m });
            axes[weakest] = -axes[weakest];
            skewness[weakest] = -skewness[weakest];
        }
        Ok(PrincipalFrame {
            centroid: self.centroid,
            axes: DMat3::from_cols(axes[0], axes[1], axes[2]),
            variances: DVec3::from_array(values),
            skewness: DVec3::from_array(skewness),
            volume: self.volume,
        })
    }
}

/// Replaces the eigenvectors of (nearly) equal eigenvalues, which are
/// arbitrary within their plane or space, by a deterministic choice tied to
/// the world axes (see the module docs): all three equal → the world axes;
/// one pair equal → the world axis with the longest projection onto the
/// pair's plane, and its right-handed complement about the distinct axis.
fn snap_equal_axes(values: &[f64; 3], axes: &mut [DVec3; 3]) {
    let equal = |i: usize| values[i + 1] - values[i] <= EQUAL_EIGENVALUES * values[i + 1];
    let world = [DVec3::X, DVec3::Y, DVec3::Z];
    let (low, distinct) = match (equal(0), equal(1)) {
        (false, false) => return,
        (true, true) => {
            *axes = world;
            return;
        }
        (true, false) => (0, 2),
        (false, true) => (1, 0),
    };
    let w = axes[distinct];
    let u = world
        .map(|e| e - e.dot(w) * w)
        .into_iter()
        .fold(DVec3::ZERO, |best, p| if p.length_squared() > best.length_squared() { p } else { best })
        .normalize();
    axes[low] = u;
    axes[low + 1] = w.cross(u);
}

/// Partial-volume weight of node `(i, j, k)` and the unit inward normal of
/// the cut (zero for a whole or empty voxel); see [`Moments::from_grid`].
fn partial_volume(grid: &Grid3<f32>, i: u32, j: u32, k: u32) -> (f64, DVec3) {
    let v = grid.data()[grid.index(i, j, k)];
    let step = (if v > 0.0 { 1.0 } else { 0.0 }, DVec3::ZERO);
    if v.is_infinite() {
        return step;
    }
    let gradient = grid.node_gradient(i, j, k).as_dvec3();
    let slope = gradient.length();
    let w = 0.5 + v as f64 / (grid.spacing() as f64 * slope);
    if !(slope > 0.0 && slope.is_finite() && w.is_finite()) {
        step
    } else if w >= 1.0 {
        (1.0, DVec3::ZERO)
    } else if w <= 0.0 {
        (0.0, DVec3::ZERO)
    } else {
        (w, gradient / slope)
    }
}

/// A solid's centroid and principal axes: the intrinsic frame Breen's
/// Appendix aligns.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PrincipalFrame {
    /// Centroid (world units).
    pub centroid: DVec3,
    /// Unit principal axes as columns, ordered by increasing variance; a
    /// proper rotation (det = +1) mapping frame coordinates to world
    /// directions (Breen's `R` of eq. 30).
    pub axes: DMat3,
    /// Covariance eigenvalues along the axes (world units², ascending).
    pub variances: DVec3,
    /// Standardized third central moment `E[((x − c)·e)³] / λ^{3/2}` along
    /// each axis after orientation (dimensionless; ≥ 0 except where the sign
    /// came from the fallback or the handedness fix).
    pub skewness: DVec3,
    /// Volume of the solid (world units³).
    pub volume: f64,
}

impl PrincipalFrame {
    /// The smallest relative gap `(λ_{i+1} − λ_i) / λ_{i+1}` between
    /// consecutive eigenvalues. Near zero the axes of that pair are arbitrary
    /// within their plane (a solid of revolution, a cube), and the alignment
    /// holds only up to that rotation; at or below [`EQUAL_EIGENVALUES`] the
    /// axes came from the world-axis fallback (see the module docs).
    pub fn min_relative_gap(&self) -> f64 {
        let l = self.variances;
        ((l.y - l.x) / l.y).min((l.z - l.y) / l.z)
    }
}

/// Which parts of the moment map [`align`] keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AlignMode {
    /// Rotation, translation and a scale per principal axis (Breen's map).
    Affine,
    /// Rotation, translation and the uniform scale `∛(V_target / V_source)`.
    Similarity,
    /// Rotation and translation only.
    Rigid,
}

/// The map taking a source solid onto a target solid, with the frames it was
/// built from. Serializable (e.g. to JSON) as is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Alignment {
    /// The mode the map was built with.
    pub mode: AlignMode,
    /// Source-to-target map `x ↦ c_B + R_B S R_Aᵀ (x − c_A)` (column vectors).
    pub map: Affine3A,
    /// The scale `S` along each source principal axis (dimensionless).
    pub scale: DVec3,
    /// The source's principal frame (`A`).
    pub source: PrincipalFrame,
    /// The target's principal frame (`B`).
    pub target: PrincipalFrame,
}

/// Aligns `source` onto `target` by their moments (Breen's Appendix; see the
/// module docs for the map, the axis signs and the limits).
///
/// # Errors
/// As [`Moments::principal_frame`] for either solid.
pub fn align(source: &Moments, target: &Moments, mode: AlignMode) -> Result<Alignment, AlignError> {
    let a = source.principal_frame()?;
    let b = target.principal_frame()?;
    let scale = match mode {
        AlignMode::Affine => {
            DVec3::from_array(std::array::from_fn(|i| (b.variances[i] / a.variances[i]).sqrt()))
        }
        AlignMode::Similarity => DVec3::splat((b.volume / a.volume).cbrt()),
        AlignMode::Rigid => DVec3::ONE,
    };
    if !scale.is_finite() {
        return Err(AlignError::NonFinite);
    }
    let linear = b.axes * DMat3::from_diagonal(scale) * a.axes.transpose();
    let translation = b.centroid - linear * a.centroid;
    let map = Affine3A::from_mat3_translation(linear.as_mat3(), translation.as_vec3());
    Ok(Alignment { mode, map, scale, source: a, target: b })
}

impl Alignment {
    /// The map split exactly (no SVD) into translation, rotation `R_B R_Aᵀ`
    /// and stretch `R_A S R_Aᵀ` (symmetric positive definite).
    pub fn parts(&self) -> AffineParts {
        let (ra, rb) = (self.source.axes, self.target.axes);
        let rotation = Quat::from_mat3(&(rb * ra.transpose()).as_mat3()).normalize();
        let stretch = (ra * DMat3::from_diagonal(self.scale) * ra.transpose()).as_mat3();
        AffineParts { translation: Vec3::from(self.map.translation), rotation, stretch }
    }

    /// Breen's `T(x, α)` (eq. 25) from the identity to [`Alignment::map`]:
    /// translation and stretch linear in α, rotation slerped about the
    /// *world origin*.
    ///
    /// # Errors
    /// [`TransformError`] when the map cannot be decomposed (only for extreme
    /// scale ratios).
    pub fn path(&self) -> Result<AffinePath, TransformError> {
        AffinePath::from_identity(&self.map)
    }

    /// The map at time `t ∈ [0, 1]` (clamped; NaN counts as 0), turning and
    /// stretching about the source centroid while that centroid moves on the
    /// straight line to the target's: `x ↦ c(t) + R(t) S(t) (x − c_A)` with
    /// `c(t) = c_A + t (c_B − c_A)`. Unlike [`Alignment::path`] the solid does
    /// not swing around the world origin. `at(0)` is the identity and `at(1)`
    /// is [`Alignment::map`].
    pub fn at(&self, t: f32) -> Affine3A {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let linear = AffineParts { translation: Vec3::ZERO, ..self.parts() };
        let m = AffineParts::IDENTITY.lerp(&linear, t).to_affine().matrix3;
        let (ca, cb) = (self.source.centroid.as_vec3(), self.target.centroid.as_vec3());
        let centre = ca.lerp(cb, t);
        Affine3A::from_mat3_translation(Mat3::from(m), centre - Mat3::from(m) * ca)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::marching_cubes::polygonize;
    use crate::mesh::distance::surface_distance;
    use crate::sdf::MeshSdf;
    use crate::{Shape, models};
    use proptest::prelude::*;

    fn bunny() -> TriMesh {
        crate::mesh::metrics::test_meshes::bunny()
    }

    /// The unit corner tetrahedron `(0, e_x, e_y, e_z)` moved by `offset`,
    /// outward wound.
    fn tetrahedron(offset: DVec3) -> TriMesh {
        let corners = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        TriMesh::new(
            corners.map(|c| (c + offset).as_vec3()).to_vec(),
            vec![[1, 2, 3], [0, 2, 1], [0, 1, 3], [0, 3, 2]],
        )
        .unwrap()
    }

    /// An axis-aligned box mesh with the given half extents, outward wound.
    fn box_mesh(half: Vec3) -> TriMesh {
        let positions = (0..8)
            .map(|c| half * Vec3::new([-1.0, 1.0][c & 1], [-1.0, 1.0][(c >> 1) & 1], [-1.0, 1.0][c >> 2]))
            .collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
        TriMesh::new(positions, triangles).unwrap()
    }

    fn mirrored(mesh: &TriMesh) -> TriMesh {
        let mut m = mesh.transformed(&Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        m
    }

    fn max_deviation(mesh: &TriMesh, map: &Affine3A) -> f32 {
        mesh.positions.iter().map(|&p| map.transform_point3(p).distance(p)).fold(0.0, f32::max)
    }

    #[test]
    fn tetrahedron_moments_are_exact() {
        // ∫ x^a y^b z^c over the corner tetrahedron is a! b! c! / (a + b + c + 3)!.
        let offset = DVec3::new(3.0, -2.0, 5.0);
        for mesh in [tetrahedron(offset), {
            let mut m = tetrahedron(offset);
            m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
            m
        }] {
            let m = Moments::from_mesh(&mesh).unwrap();
            assert!((m.volume - 1.0 / 6.0).abs() < 1e-12);
            assert!(m.centroid.abs_diff_eq(offset + DVec3::splat(0.25), 1e-12));
            for i in 0..3 {
                for j in 0..3 {
                    let want = if i == j { 3.0 / 80.0 } else { -1.0 / 80.0 };
                    assert!((m.covariance.col(j)[i] - want).abs() < 1e-12, "cov {i}{j}");
                    for k in 0..3 {
                        let distinct = [i == j, j == k, i == k].iter().filter(|&&e| e).count();
                        let want = match distinct {
                            3 => 1.0 / 160.0,  // μ_xxx
                            1 => -1.0 / 480.0, // μ_xxy
                            _ => 1.0 / 480.0,  // μ_xyz
                        };
                        assert!((m.third[i][j][k] - want).abs() < 1e-12, "third {i}{j}{k}");
                    }
                }
            }
        }
    }

    #[test]
    fn grid_moments_of_a_box_are_close_to_exact() {
        let half = Vec3::new(0.3, 0.2, 0.1);
        let offset = Vec3::new(0.05, -0.1, 0.02);
        let shape = Shape::cuboid(half).translated(offset);
        let m = Moments::from_field(&shape, &shape.aabb(), 48).unwrap();
        let exact =
            Moments::from_mesh(&box_mesh(half).transformed(&Affine3A::from_translation(offset))).unwrap();
        assert!((m.volume / exact.volume - 1.0).abs() < 5e-3, "{} vs {}", m.volume, exact.volume);
        assert!(m.centroid.abs_diff_eq(exact.centroid, 1e-4), "{} vs {}", m.centroid, exact.centroid);
        let h = 0.6 / 47.0;
        for i in 0..3 {
            // Second order in the spacing: off by a fraction of h² per axis.
            let (got, want) = (m.covariance.col(i)[i], exact.covariance.col(i)[i]);
            assert!((got - want).abs() < 0.25 * h * h, "axis {i}: {got} vs {want}");
        }
        assert!(m.third.iter().flatten().flatten().all(|t| t.abs() < 1e-5));
    }

    #[test]
    fn grid_moments_of_the_bunny_agree_with_its_mesh_moments() {
        let mesh = bunny();
        let exact = Moments::from_mesh(&mesh).unwrap();
        let sdf = MeshSdf::new(&mesh).unwrap();
        let grid = Moments::from_field(&sdf, &mesh.bounds(), 40).unwrap();
        let size = mesh.bounds().size().max_element() as f64;
        assert!((exact.volume - 194.28837).abs() < 1e-3, "{}", exact.volume);
        assert!((grid.volume / exact.volume - 1.0).abs() < 5e-3, "{} vs {}", grid.volume, exact.volume);
        assert!(grid.centroid.distance(exact.centroid) < 1e-3 * size);
        let cov_error =
            (grid.covariance - exact.covariance).to_cols_array().iter().map(|v| v.abs()).fold(0.0, f64::max);
        assert!(
            cov_error < 5e-3 * exact.covariance.to_cols_array().iter().map(|v| v.abs()).fold(0.0, f64::max)
        );
        let (fa, fb) = (grid.principal_frame().unwrap(), exact.principal_frame().unwrap());
        for i in 0..3 {
            let cos = fa.axes.col(i).dot(fb.axes.col(i));
            assert!(cos > 0.999, "axis {i}: cos {cos}; skewness {} vs {}", fa.skewness, fb.skewness);
        }
    }

    #[test]
    fn frames_are_proper_rotations_even_for_a_mirror_image() {
        let mesh = bunny();
        let frame = Moments::from_mesh(&mesh).unwrap().principal_frame().unwrap();
        let mirror = Moments::from_mesh(&mirrored(&mesh)).unwrap().principal_frame().unwrap();
        for f in [frame, mirror] {
            assert!((f.axes.determinant() - 1.0).abs() < 1e-9);
            assert!((f.axes.transpose() * f.axes).abs_diff_eq(DMat3::IDENTITY, 1e-9));
            assert!(f.variances.x < f.variances.y && f.variances.y < f.variances.z);
        }
        // The bunny is skewed along every axis: all signs come from skewness.
        assert!(frame.skewness.min_element() > SKEW_TOLERANCE, "{}", frame.skewness);
        // A mirror cannot be undone by a rotation, but the map stays proper.
        let alignment = align(
            &Moments::from_mesh(&mirrored(&mesh)).unwrap(),
            &Moments::from_mesh(&mesh).unwrap(),
            AlignMode::Affine,
        )
        .unwrap();
        assert!(alignment.map.matrix3.determinant() > 0.0);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// The bunny moved by a random rotation, a scale along its own
        /// principal axes (keeping their order) and a translation is mapped
        /// back onto itself by the affine alignment of its exact moments.
        #[test]
        fn affine_round_trip_of_the_bunny(
            axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
            angle in -3.1f64..3.1,
            scale in (0.5f64..2.0, 0.5f64..2.0, 0.5f64..2.0),
            offset in (-20.0f64..20.0, -20.0f64..20.0, -20.0f64..20.0),
        ) {
            let mesh = bunny();
            let moments = Moments::from_mesh(&mesh).unwrap();
            let frame = moments.principal_frame().unwrap();
            let scale = DVec3::from(scale);
            let v = frame.variances * scale * scale;
            prop_assume!(v.y > 1.05 * v.x && v.z > 1.05 * v.y);
            let rotation = DMat3::from_axis_angle(DVec3::from(axis).normalize(), angle);
            let linear = rotation * frame.axes * DMat3::from_diagonal(scale) * frame.axes.transpose();
            let translation = DVec3::from(offset) + frame.centroid - linear * frame.centroid;
            let motion = Affine3A::from_mat3_translation(linear.as_mat3(), translation.as_vec3());
            let moved = mesh.transformed(&motion);

            let alignment = align(&Moments::from_mesh(&moved).unwrap(), &moments, AlignMode::Affine).unwrap();
            prop_assert!(alignment.scale.abs_diff_eq(scale.recip(), 1e-6), "{} vs {}", alignment.scale, scale.recip());
            let back = moved.transformed(&alignment.map);
            let size = mesh.bounds().size().max_element();
            prop_assert!(max_deviation(&mesh, &(alignment.map * motion)) < 1e-4 * size);
            let d = surface_distance(&back, &mesh, 2000).unwrap();
            prop_assert!(d.hausdorff < 1e-4 * size, "{:?}", d);
        }
    }

    #[test]
    fn rigid_mode_preserves_volume_and_similarity_recovers_the_scale() {
        let mesh = bunny();
        let moments = Moments::from_mesh(&mesh).unwrap();
        let motion = Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.5),
            glam::Quat::from_euler(glam::EulerRot::YXZ, 1.0, -0.5, 2.0),
            Vec3::new(4.0, -3.0, 7.0),
        );
        let moved = mesh.transformed(&motion);
        let moved_moments = Moments::from_mesh(&moved).unwrap();

        let rigid = align(&moved_moments, &moments, AlignMode::Rigid).unwrap();
        assert_eq!(rigid.scale, DVec3::ONE);
        assert!((rigid.map.matrix3.determinant() - 1.0).abs() < 1e-5);
        let rigid_back = moved.transformed(&rigid.map);
        assert!((rigid_back.signed_volume() / moved.signed_volume() - 1.0).abs() < 1e-5);
        // The rigid map puts the centroid and axes in place; the size stays.
        let back_frame = Moments::from_mesh(&rigid_back).unwrap().principal_frame().unwrap();
        assert!(back_frame.centroid.distance(moments.centroid) < 1e-4);
        assert!((back_frame.axes.transpose() * rigid.target.axes).abs_diff_eq(DMat3::IDENTITY, 1e-5));

        let similar = align(&moved_moments, &moments, AlignMode::Similarity).unwrap();
        assert!(similar.scale.abs_diff_eq(DVec3::splat(1.0 / 1.5), 1e-6), "{}", similar.scale);
        assert!(max_deviation(&mesh, &(similar.map * motion)) < 1e-4);
    }

    #[test]
    fn grid_alignment_maps_a_moved_csg_model_onto_itself() {
        // The C is mirror symmetric in y and z (zero skewness there), so its
        // frame is fixed up to a half-turn about x, which is a symmetry.
        let motion = Affine3A::from_rotation_translation(
            glam::Quat::from_euler(glam::EulerRot::ZXY, 2.0, 0.6, -1.2),
            Vec3::new(0.3, -0.2, 0.1),
        );
        for (name, shape) in [("c-shape", models::c_shape()), ("mug", models::mug())] {
            let moved = shape.clone().transformed(motion);
            let res = 40;
            let alignment = align(
                &Moments::from_field(&moved, &moved.aabb(), res).unwrap(),
                &Moments::from_field(&shape, &shape.aabb(), res).unwrap(),
                AlignMode::Rigid,
            )
            .unwrap();
            let h = shape.aabb().size().max_element() / (res - 1) as f32;
            let back =
                polygonize(&moved, &moved.aabb().padded(0.05), res, 0.0).unwrap().transformed(&alignment.map);
            let original = polygonize(&shape, &shape.aabb().padded(0.05), res, 0.0).unwrap();
            let d = surface_distance(&back, &original, 2000).unwrap();
            // The floor: the two polygonizations put back by the exact inverse.
            let moved_mesh = polygonize(&moved, &moved.aabb().padded(0.05), res, 0.0).unwrap();
            let floor =
                surface_distance(&moved_mesh.transformed(&motion.inverse()), &original, 2000).unwrap();
            assert!(d.mean < floor.mean + 0.05 * h, "{name}: {d:?} vs {floor:?}, voxel {h}");
            assert!(d.hausdorff < floor.hausdorff + 0.25 * h, "{name}: {d:?} vs {floor:?}, voxel {h}");
        }
    }

    #[test]
    fn equal_eigenvalues_fall_back_to_world_axes() {
        let bounds = Aabb::cube(0.5);
        // Sphere → a smaller, moved sphere: no rotation, exact scale.
        let sphere = Moments::from_field(&Shape::sphere(0.3), &bounds, 32).unwrap();
        let target_shape = Shape::sphere(0.15).translated(Vec3::new(0.1, 0.2, -0.05));
        let target = Moments::from_field(&target_shape, &target_shape.aabb(), 32).unwrap();
        for mode in [AlignMode::Affine, AlignMode::Similarity, AlignMode::Rigid] {
            let a = align(&sphere, &target, mode).unwrap();
            assert!(a.map.is_finite());
            assert!(a.source.min_relative_gap() <= EQUAL_EIGENVALUES, "{}", a.source.variances);
            assert_eq!(a.source.axes, DMat3::IDENTITY);
            assert_eq!(a.target.axes, DMat3::IDENTITY);
            let s = if mode == AlignMode::Rigid { 1.0 } else { 0.5 };
            assert!(
                a.map.matrix3.abs_diff_eq(glam::Mat3A::from_diagonal(Vec3::splat(s)), 5e-3),
                "{mode:?}: {:?}",
                a.map
            );
            assert!(Vec3::from(a.map.translation).abs_diff_eq(Vec3::new(0.1, 0.2, -0.05), 1e-3));
        }
        // A cylinder turned about its own axis and moved: the distinct axis is
        // aligned, the equal pair snaps to the same world axes, so no turn.
        let cylinder = Shape::cylinder(0.15, 0.35);
        let turned = cylinder.clone().transformed(Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(0.8),
            Vec3::new(0.2, 0.0, 0.1),
        ));
        let a = align(
            &Moments::from_field(&turned, &turned.aabb(), 32).unwrap(),
            &Moments::from_field(&cylinder, &cylinder.aabb(), 32).unwrap(),
            AlignMode::Affine,
        )
        .unwrap();
        assert!(a.source.min_relative_gap() <= EQUAL_EIGENVALUES);
        assert!(
            a.source.axes.col(2).abs_diff_eq(DVec3::Z, 1e-6)
                || a.source.axes.col(2).abs_diff_eq(-DVec3::Z, 1e-6)
        );
        // No turn: diagonal up to rounding, with the sampling error of the two
        // (differently placed) grids in the scales.
        let m = a.map.matrix3;
        assert!(
            (m - glam::Mat3A::from_diagonal(Vec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z)))
                .abs_diff_eq(glam::Mat3A::ZERO, 1e-6)
        );
        assert!(m.abs_diff_eq(glam::Mat3A::IDENTITY, 3e-3), "{:?}", a.map);
        assert!(Vec3::from(a.map.translation).abs_diff_eq(Vec3::new(-0.2, 0.0, -0.1), 2e-3));

        // Tilted in a general direction: the pair's gap is sampling noise, the
        // axis is put upright, and the twist about it is a symmetry.
        let tilt = Affine3A::from_rotation_translation(
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, -0.4),
            Vec3::new(0.05, -0.1, 0.0),
        );
        let tilted = cylinder.clone().transformed(tilt);
        let a = align(
            &Moments::from_field(&tilted, &tilted.aabb(), 32).unwrap(),
            &Moments::from_field(&cylinder, &cylinder.aabb(), 32).unwrap(),
            AlignMode::Rigid,
        )
        .unwrap();
        assert!(a.source.min_relative_gap() <= EQUAL_EIGENVALUES, "{}", a.source.variances);
        let axis = a.map.transform_vector3(tilt.transform_vector3(Vec3::Z));
        assert!(axis.abs_diff_eq(Vec3::Z, 1e-3) || axis.abs_diff_eq(-Vec3::Z, 1e-3), "{axis}");
        let h = cylinder.aabb().size().max_element() / 31.0;
        let back = polygonize(&tilted, &tilted.aabb().padded(0.05), 32, 0.0).unwrap().transformed(&a.map);
        let original = polygonize(&cylinder, &cylinder.aabb().padded(0.05), 32, 0.0).unwrap();
        let d = surface_distance(&back, &original, 2000).unwrap();
        assert!(d.mean < 0.1 * h, "{d:?}, voxel {h}");
    }

    #[test]
    fn degenerate_inputs_are_typed_errors() {
        assert_eq!(Moments::from_mesh(&TriMesh::default()), Err(AlignError::Empty));
        // Nowhere positive inside the box.
        let far = Shape::sphere(0.1).translated(Vec3::splat(5.0));
        assert_eq!(Moments::from_field(&far, &Aabb::cube(0.5), 16), Err(AlignError::Empty));
        let mut nan = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 8).unwrap();
        nan.data_mut()[10] = f32::NAN;
        assert_eq!(Moments::from_grid(&nan), Err(AlignError::NonFinite));
        // A tetrahedron missing a face bounds nothing.
        let mut open = tetrahedron(DVec3::ZERO);
        open.triangles.pop();
        assert!(matches!(Moments::from_mesh(&open), Err(AlignError::OpenMesh { .. })));
        // A square and its back face: closed, but of zero volume.
        let square = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]],
        )
        .unwrap();
        assert_eq!(Moments::from_mesh(&square), Err(AlignError::Empty));
        // A sheet of finite but tiny thickness has a singular covariance.
        let sheet = Moments::from_mesh(&box_mesh(Vec3::new(1.0, 1.0, 1e-5))).unwrap();
        let good = Moments::from_mesh(&bunny()).unwrap();
        for (a, b) in [(&sheet, &good), (&good, &sheet)] {
            assert!(matches!(align(a, b, AlignMode::Rigid), Err(AlignError::Degenerate { .. })));
        }
        let nan_moments = Moments { centroid: DVec3::NAN, ..good };
        assert_eq!(nan_moments.principal_frame(), Err(AlignError::NonFinite));
        let no_volume = Moments { volume: 0.0, ..good };
        assert_eq!(no_volume.principal_frame(), Err(AlignError::Empty));
        let bad = TriMesh { positions: vec![Vec3::ZERO], triangles: vec![[0, 0, 1]], ..TriMesh::default() };
        assert!(matches!(Moments::from_mesh(&bad), Err(AlignError::Mesh(_))));
    }

    #[test]
    fn time_path_runs_from_identity_to_the_map() {
        let mesh = bunny();
        let motion = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.2, 1.2, 1.2),
            glam::Quat::from_rotation_y(1.3),
            Vec3::new(10.0, 0.0, -5.0),
        );
        let a = align(
            &Moments::from_mesh(&mesh.transformed(&motion)).unwrap(),
            &Moments::from_mesh(&mesh).unwrap(),
            AlignMode::Affine,
        )
        .unwrap();
        assert!(a.parts().to_affine().abs_diff_eq(a.map, 1e-4));
        assert!(a.at(0.0).abs_diff_eq(Affine3A::IDENTITY, 1e-6));
        assert!(a.at(f32::NAN).abs_diff_eq(Affine3A::IDENTITY, 1e-6));
        assert!(a.at(1.0).abs_diff_eq(a.map, 1e-4));
        assert!(a.path().unwrap().at(1.0).abs_diff_eq(a.map, 1e-4));
        // Half way, the source centroid sits half way to the target's.
        let (ca, cb) = (a.source.centroid.as_vec3(), a.target.centroid.as_vec3());
        assert!(a.at(0.5).transform_point3(ca).abs_diff_eq(ca.lerp(cb, 0.5), 1e-4));
        let det = a.at(0.5).matrix3.determinant();
        assert!(det > 0.0 && det.is_finite());
        // Serializable as is.
        let json = serde_json::to_string(&a).unwrap();
        assert!(json.contains("\"mode\":\"affine\""));
    }
}
