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
//! **Limits.** Moments see a solid only up to its symmetries of second and
//! third order: shapes with (near) zero skewness along an axis are aligned up
//! to a half-turn about it, and shapes with two (near) equal eigenvalues — a
//! cylinder, a cube, a sphere — are aligned up to a rotation in the plane of
//! those axes (the eigenvectors there are arbitrary). The map is still a
//! finite, proper, non-singular transform in those cases; check
//! [`PrincipalFrame::min_relative_gap`] to detect them. An anisotropic scale
//! is recovered only when it acts along the shape's own principal axes
//! (anything else also shears the covariance), and only while it keeps the
//! eigenvalue order.

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

    /// Adds a solid axis-aligned cube of edge `h` centred at `p` (relative to
    /// `r`), weighted by `w`: a point mass plus the cube's own spread `h²/12`.
    fn add_voxel(&mut self, p: DVec3, h: f64, w: f64) {
        let dv = w * h * h * h;
        let e = h * h / 12.0;
        let delta = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
        self.m0 += dv;
        for i in 0..3 {
            self.m1[i] += dv * p[i];
            for j in 0..3 {
                self.m2[i][j] += dv * (p[i] * p[j] + e * delta(i, j));
                for k in 0..3 {
                    let spread = p[i] * delta(j, k) + p[j] * delta(i, k) + p[k] * delta(i, j);
                    self.m3[i][j][k] += dv * (p[i] * p[j] * p[k] + e * spread);
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
    /// at nodes next to a sign change (one of the six neighbours has the other
    /// sign), and `w = 1` (`φ > 0`) or `0` elsewhere. For a signed distance
    /// (`|∇φ| = 1`) this is `0.5 + φ/h`, the exact fraction of a voxel cut by
    /// a plane parallel to a face; dividing by the central-difference gradient
    /// makes the weight independent of the field's scale, so any
    /// positive-inside field works, not only distances. The voxel's own spread
    /// (`h²/12` per axis) is included, so a fully interior region's moments are
    /// exact for its voxelization.
    ///
    /// The solid should lie inside the grid (a positive value on the grid's
    /// boundary counts, but the solid is then cut there). Infinite values are
    /// accepted as "far inside/outside". Parallel over fixed z-slabs summed in
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
                        let w = partial_volume(grid, i, j, k);
                        if w > 0.0 {
                            let p = grid.position(i, j, k).as_dvec3() - reference;
                            raw.add_voxel(p, h as f64, w);
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
        let res = res.max(2);
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

/// Partial-volume weight of node `(i, j, k)` (see [`Moments::from_grid`]).
fn partial_volume(grid: &Grid3<f32>, i: u32, j: u32, k: u32) -> f64 {
    let dims = grid.dims();
    let data = grid.data();
    let v = data[grid.index(i, j, k)];
    let inside = v > 0.0;
    let n = [i, j, k];
    let near_surface = (0..3).any(|axis| {
        [n[axis].checked_sub(1), Some(n[axis] + 1).filter(|&m| m < dims[axis])].into_iter().flatten().any(
            |m| {
                let mut q = n;
                q[axis] = m;
                (data[grid.index(q[0], q[1], q[2])] > 0.0) != inside
            },
        )
    });
    let step = if inside { 1.0 } else { 0.0 };
    if !near_surface {
        return step;
    }
    let slope = grid.node_gradient(i, j, k).length() as f64;
    let w = 0.5 + v as f64 / (grid.spacing() as f64 * slope);
    if slope > 0.0 && w.is_finite() { w.clamp(0.0, 1.0) } else { step }
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
    /// holds only up to that rotation.
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
