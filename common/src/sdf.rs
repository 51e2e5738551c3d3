//! Exact signed distance to a triangle mesh, positive inside ([`MeshSdf`],
//! [`mesh_sdf_grid`]).
//!
//! The magnitude is the exact Euclidean distance to the nearest triangle,
//! found with a [`TriangleBvh`]. The sign comes from one of two inside tests
//! ([`SignMode`]):
//! - [`SignMode::WindingNumber`] (the default): inside where the
//!   [generalized winding number](crate::mesh::winding) exceeds ½. Exact for
//!   closed, consistently oriented meshes (self-intersecting ones included,
//!   where overlaps count as inside), and still sensible for open, unwelded
//!   or partly flipped meshes such as the Utah teapot.
//! - [`SignMode::Pseudonormal`]: the side of the *angle-weighted
//!   pseudonormal* of the nearest feature (face, edge or vertex; Bærentzen &
//!   Aanæs, IEEE TVCG 2005). Exact and cheap for closed, consistently
//!   oriented meshes without self-intersections; only locally plausible
//!   otherwise.
//!
//! # Distance volumes
//! [`MeshSdf::sample_lattice`] and [`mesh_sdf_grid`] compute the exact signed
//! distance at every node of a lattice. Distances come from
//! [`TriangleBvh::nearest_on_lattice`] (block-wise candidate lists, no
//! per-node tree descent). With the winding-number sign on a *closed* mesh
//! (every edge used equally often in both directions, so the winding number
//! is an integer off the surface) the sign is propagated instead of
//! evaluated: the open ball of radius `|d(x)|` about a node contains no
//! surface, so when the balls of two neighbours overlap (`|d(x)| + |d(y)| >
//! |x − y|`) their union is a connected surface-free set and both have the
//! same winding number. Signs flow along such x, y and z links, and the
//! winding number is evaluated only once per region reached that way. The
//! result is the same as evaluating the winding number at every node. On an
//! open mesh the winding number is not constant on such balls and is
//! evaluated at every node.
//!
//! With [`VolumeMode::NarrowBand`] only the nodes within a band around the
//! surface get the exact distance (blocks of nodes entirely beyond it are
//! skipped after one tree query); closest-point fast marching fills the
//! rest from the band's nearest surface points, with the sign of the band
//! region that reaches each node. The mesh's exact closest points are
//! propagated as points (not as tangent discs, which would cut its creases
//! and corners). Accuracy, as tested on the bunny at 64³ with a two-voxel
//! band: exact to `1e-5` of the box size in the band, and beyond it within
//! the closest-point propagation's error: at most 0.35 voxel, at nodes next
//! to the medial axis whose true closest point did not travel through their
//! neighbours (tested below 0.4 voxel; see [`crate::fast_marching`]).
//! Exact everywhere stays the default: the block-wise lattice search is so
//! cheap that it is also the faster mode at the sizes measured (see
//! `docs/EXPERIMENTS.md`; bench `mesh_sdf/bunny/128` and
//! `mesh_sdf/bunny/band/128`).
//!
//! # Narrow bands of bricks
//! [`MeshSdf::sample_band_bricks`] (what [`Bricks::sample_band`] calls for a
//! mesh, the sparse level set's source) stores the distance only in the
//! 8³ bricks that come within a band of the surface and the side
//! elsewhere. Each brick is one block of the lattice search (one tree
//! query at its centre decides whether it is near), so the band's values
//! are bitwise those of [`MeshSdf::sample_lattice`]. The signs of a closed
//! mesh flow as above, across brick faces too, and also from a far brick
//! (the surface-free ball about its centre holds the whole brick) to its
//! neighbours: one winding number per region of band nodes and far bricks
//! so linked, in the manner of OpenVDB's sign flood fill.
//!
//! # Scale
//! Squared `f32` distances overflow for meshes larger than about 10¹⁹ and
//! underflow for meshes smaller than about 10⁻¹⁹, and the inside tests
//! multiply lengths too. So [`MeshSdf`] works in a normalized frame: it
//! multiplies the mesh by the power of two that brings its largest
//! coordinate near 1, and every query point and lattice by the same factor,
//! then divides the distances by it. Changing exponents only, this is exact:
//! results are the same as in world units wherever those did not overflow,
//! and a mesh at any finite scale, from subnormal coordinates to the largest
//! `f32`, gets the same signs and (scaled) distances as its unit-size copy.
//! Points too far from the mesh to express in that frame (farther from the
//! origin than 2⁶⁰ times its largest coordinate) get minus their distance to the centre of its bounding box, which
//! differs from the true distance by less than `f32` rounding there. A mesh
//! whose triangles all collapse to one point is refused
//! ([`SdfError::ZeroExtent`]), as one with non-finite coordinates is.
//!
//! # Example
//! ```
//! use isomorph_common::sdf::{MeshSdf, SdfSettings, mesh_sdf_grid};
//! use isomorph_common::{Aabb, Field3, TriMesh, glam::Vec3};
//!
//! // A tetrahedron, counter-clockwise seen from outside.
//! let mesh = TriMesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//! )?;
//! let sdf = MeshSdf::new(&mesh)?;
//! assert!((sdf.value(Vec3::splat(0.1)) - 0.1).abs() < 1e-6); // 0.1 from three faces
//! assert!((sdf.value(Vec3::new(-2.0, 0.0, 0.0)) + 2.0).abs() < 1e-6);
//!
//! // A 17-node-wide distance volume over the padded box.
//! let grid = mesh_sdf_grid(&mesh, &mesh.bounds().padded(0.1), 17, SdfSettings::default())?;
//! assert_eq!(grid.dims().x, 17);
//! assert!((grid.trilinear(Vec3::splat(0.1)) - 0.1).abs() < 0.05);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::fast_marching::{FastMarchingError, FastMarchingSettings, Seed, Update, march_with_discs};
use crate::grid::lattice_for_box;
use crate::mesh::bvh::{ClosestPoint, Lattice, TriangleBvh};
use crate::mesh::winding::{DEFAULT_BETA, WindingNumber};
use crate::{Aabb, Bricks, Field3, Grid3, GridError, TriMesh};
use glam::{Affine3A, UVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

mod band;

/// Errors of [`MeshSdf`] construction and sampling.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SdfError {
    /// The mesh has no triangle.
    #[error("the mesh has no triangles; a distance field needs a surface")]
    EmptyMesh,
    /// The mesh failed validation.
    #[error(transparent)]
    Mesh(#[from] crate::MeshError),
    /// The output grid could not be set up.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Filling the grid beyond the narrow band failed.
    #[error(transparent)]
    FastMarching(#[from] FastMarchingError),
    /// A narrow-band width that is not finite and positive.
    #[error("narrow band width {0} is not finite and positive")]
    BadBand(f32),
    /// Every triangle corner is the same point: there is no surface of
    /// positive size (also what remains of a small mesh far from the origin
    /// once `f32` positions have rounded it away).
    #[error(
        "the mesh's triangles all collapse to one point; a distance field needs a surface of positive size"
    )]
    ZeroExtent,
}

/// How [`MeshSdf`] decides inside from outside (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SignMode {
    /// Inside where the generalized winding number exceeds ½: robust to
    /// holes, duplicate and flipped triangles.
    #[default]
    WindingNumber,
    /// The side of the nearest feature's angle-weighted pseudonormal: exact
    /// only for closed, consistently oriented, self-intersection-free meshes.
    Pseudonormal,
}

/// Settings of [`MeshSdf`] and [`mesh_sdf_grid`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct SdfSettings {
    /// The inside test.
    pub sign: SignMode,
    /// Accuracy parameter β of the fast winding number
    /// ([`WindingNumber::with_accuracy`]); only the threshold at ½ matters,
    /// so the default [`DEFAULT_BETA`] is ample.
    pub winding_accuracy: f32,
    /// How [`MeshSdf::sample_grid`] fills a volume: exact everywhere (the
    /// default) or exact in a narrow band and marched beyond it.
    pub volume: VolumeMode,
}

/// How a distance volume is filled (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum VolumeMode {
    /// The exact signed distance at every node.
    #[default]
    Exact,
    /// The exact signed distance at every node within `width` (world units)
    /// of the surface, then closest-point fast marching
    /// ([`crate::fast_marching`]) from those nodes over the rest of the grid.
    NarrowBand {
        /// Half-width of the exact band, world units.
        width: f32,
    },
}

impl Default for SdfSettings {
    fn default() -> Self {
        Self { sign: SignMode::default(), winding_accuracy: DEFAULT_BETA, volume: VolumeMode::default() }
    }
}

impl SdfSettings {
    /// These settings with the volume mode `volume`.
    pub fn with_volume(mut self, volume: VolumeMode) -> Self {
        self.volume = volume;
        self
    }

    /// These settings with the inside test `sign`.
    pub fn with_sign(mut self, sign: SignMode) -> Self {
        self.sign = sign;
        self
    }
}

/// Angle-weighted pseudonormals, per triangle: face, the three edges
/// (edge `c` joins corners `c` and `c + 1`) and the three corners.
#[derive(Debug, Clone)]
struct Pseudonormals {
    face: Vec<Vec3>,
    edges: Vec<[Vec3; 3]>,
    corners: Vec<[Vec3; 3]>,
}

/// Barycentric coordinates at or below this count as zero when choosing the
/// nearest feature.
const FEATURE_EPS: f32 = 1e-6;

impl Pseudonormals {
    fn new(mesh: &TriMesh) -> Self {
        let mut face = Vec::with_capacity(mesh.triangles.len());
        let mut vertex = vec![Vec3::ZERO; mesh.positions.len()];
        let mut edge: HashMap<(u32, u32), Vec3> = HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
        let key = |u: u32, v: u32| (u.min(v), u.max(v));
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = mesh.corners(t);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            face.push(n);
            for c in 0..3 {
                let (a, b) = (
                    (p[(c + 1) % 3] - p[c]).normalize_or_zero(),
                    (p[(c + 2) % 3] - p[c]).normalize_or_zero(),
                );
                vertex[tri[c] as usize] += a.dot(b).clamp(-1.0, 1.0).acos() * n;
                *edge.entry(key(tri[c], tri[(c + 1) % 3])).or_insert(Vec3::ZERO) += n;
            }
        }
        let edges =
            mesh.triangles.iter().map(|t| [0, 1, 2].map(|c| edge[&key(t[c], t[(c + 1) % 3])])).collect();
        let corners = mesh.triangles.iter().map(|t| t.map(|v| vertex[v as usize])).collect();
        Self { face, edges, corners }
    }

    /// Pseudonormal of the feature (vertex, edge or face) holding `hit`'s point.
    fn at(&self, hit: &ClosestPoint) -> Vec3 {
        let t = hit.triangle as usize;
        match hit.barycentric.to_array().map(|b| b <= FEATURE_EPS) {
            [true, true, _] => self.corners[t][2],
            [true, _, true] => self.corners[t][1],
            [_, true, true] => self.corners[t][0],
            [true, false, false] => self.edges[t][1],
            [false, true, false] => self.edges[t][2],
            [false, false, true] => self.edges[t][0],
            _ => self.face[t],
        }
    }
}

/// Query points farther than this from the origin of a [`MeshSdf`]'s
/// normalized frame, where the mesh lies within 4 units of the origin, are
/// measured to the centre of its box instead (relative difference below
/// 2⁻⁵⁷; the tree's squared distances would overflow beyond 2⁶³).
const FAR: f32 = 1_152_921_504_606_846_976.0; // 2⁶⁰

/// The inside test of a [`MeshSdf`].
#[derive(Debug, Clone)]
enum Sign {
    Winding(WindingNumber),
    Pseudonormal(Pseudonormals),
}

/// Signed distance to a triangle mesh (positive inside), usable as a
/// [`Field3`]; see the [module docs](self).
///
/// The tree and the inside test hold the mesh in a normalized frame (see
/// [Scale](self#scale)); the public methods take and return world units.
#[derive(Debug, Clone)]
pub struct MeshSdf {
    bvh: TriangleBvh,
    sign: Sign,
    closed: bool,
    bounds: Aabb,
    volume: VolumeMode,
    /// The power of two taking world coordinates to the normalized frame
    /// (its reciprocal, [`MeshSdf::unit`], takes distances back).
    scale: f32,
}

impl MeshSdf {
    /// Builds the distance tree and the default inside test (winding number).
    ///
    /// # Errors
    /// [`SdfError::EmptyMesh`] for a mesh without triangles, [`SdfError::Mesh`]
    /// for invalid indices or non-finite coordinates, [`SdfError::ZeroExtent`]
    /// when all triangle corners coincide.
    pub fn new(mesh: &TriMesh) -> Result<Self, SdfError> {
        Self::with_settings(mesh, SdfSettings::default())
    }

    /// Builds the distance tree and the inside test chosen by `settings`.
    ///
    /// # Errors
    /// As [`MeshSdf::new`].
    pub fn with_settings(mesh: &TriMesh, settings: SdfSettings) -> Result<Self, SdfError> {
        mesh.validate()?;
        if mesh.is_empty() {
            return Err(SdfError::EmptyMesh);
        }
        let (lo, hi) =
            mesh.triangles.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(mesh.positions[v as usize]), hi.max(mesh.positions[v as usize]))
            });
        if hi == lo {
            return Err(SdfError::ZeroExtent);
        }
        let scale = mesh.unit_scale();
        let local = mesh.scaled(scale);
        let sign = match settings.sign {
            SignMode::WindingNumber => {
                Sign::Winding(WindingNumber::new(&local).with_accuracy(settings.winding_accuracy))
            }
            SignMode::Pseudonormal => Sign::Pseudonormal(Pseudonormals::new(&local)),
        };
        let bounds = mesh.bounds();
        Ok(Self {
            bvh: TriangleBvh::new(&local),
            sign,
            closed: is_closed(mesh),
            bounds,
            volume: settings.volume,
            scale,
        })
    }

    /// One unit of the normalized frame in world units (exact: a power of two).
    #[inline]
    fn unit(&self) -> f32 {
        1.0 / self.scale
    }

    /// `p` in the normalized frame, or `None` beyond [`FAR`] (or not finite).
    #[inline]
    fn local(&self, p: Vec3) -> Option<Vec3> {
        let q = p * self.scale;
        (q.abs().max_element() <= FAR).then_some(q)
    }

    /// Signed distance of a finite point beyond [`FAR`]: outside, at its
    /// distance from the box centre (computed in `f64`, which cannot overflow).
    fn far_away(&self, p: Vec3) -> f32 {
        let center = 0.5 * (self.bounds.min.as_dvec3() + self.bounds.max.as_dvec3());
        -((p.as_dvec3() - center).length() as f32)
    }

    /// The inside test in use.
    pub fn sign_mode(&self) -> SignMode {
        match self.sign {
            Sign::Winding(_) => SignMode::WindingNumber,
            Sign::Pseudonormal(_) => SignMode::Pseudonormal,
        }
    }

    /// True when every edge of the mesh is used as often in one direction
    /// as in the other (a closed, consistently oriented surface, possibly
    /// with duplicated parts): then the winding number is an integer off the
    /// surface and grid sampling can propagate signs.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The nearest surface point to `p`, with its triangle, in world units;
    /// `None` for a non-finite `p` or one farther from the origin than 2⁶⁰
    /// times the mesh's largest coordinate (see [Scale](self#scale)). The squared distance overflows to infinity
    /// (or underflows) for distances beyond the `f32` range of squares, about
    /// 10¹⁹ (or 10⁻¹⁹); [`MeshSdf::signed_distance`] has the distance itself.
    pub fn closest(&self, p: Vec3) -> Option<ClosestPoint> {
        let hit = self.bvh.closest(self.local(p)?)?;
        Some(ClosestPoint {
            point: hit.point * self.unit(),
            distance_squared: hit.distance_squared * self.unit() * self.unit(),
            ..hit
        })
    }

    /// True when `p` is inside by the chosen test (false for a non-finite `p`).
    pub fn is_inside(&self, p: Vec3) -> bool {
        self.local(p).is_some_and(|q| self.is_inside_local(q))
    }

    /// [`MeshSdf::is_inside`] for a point `q` of the normalized frame.
    fn is_inside_local(&self, q: Vec3) -> bool {
        match &self.sign {
            Sign::Winding(wn) => wn.is_inside(q),
            Sign::Pseudonormal(normals) => {
                self.bvh.closest(q).is_some_and(|hit| Self::pseudonormal_inside(normals, q, &hit))
            }
        }
    }

    /// Signed distance at `p` (positive inside); NaN for a non-finite `p`.
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        if !p.is_finite() {
            return f32::NAN;
        }
        match self.local(p) {
            Some(q) => self.bvh.closest(q).map_or(f32::NAN, |hit| self.signed(q, &hit) * self.unit()),
            None => self.far_away(p),
        }
    }

    /// The signed distance at `p` given its nearest point `hit`, both in the
    /// normalized frame.
    fn signed(&self, p: Vec3, hit: &ClosestPoint) -> f32 {
        let distance = hit.distance_squared.sqrt();
        let inside = match &self.sign {
            Sign::Winding(wn) => wn.is_inside(p),
            Sign::Pseudonormal(normals) => Self::pseudonormal_inside(normals, p, hit),
        };
        if inside { distance } else { -distance }
    }

    fn pseudonormal_inside(normals: &Pseudonormals, p: Vec3, hit: &ClosestPoint) -> bool {
        (p - hit.point).dot(normals.at(hit)) <= 0.0
    }

    /// The exact signed distance at every node of `lattice`, x-fastest
    /// (see the [module docs](self) for how signs are found); NaN
    /// everywhere for a lattice with a non-finite origin or step.
    pub fn sample_lattice(&self, lattice: &Lattice) -> Vec<f32> {
        match self.local_lattice(lattice) {
            Some(local) => {
                let mut out = self.sample_local(&local);
                out.iter_mut().for_each(|d| *d *= self.unit());
                out
            }
            None => {
                let (nx, ny) = (lattice.dims.x as usize, lattice.dims.y as usize);
                let points: Vec<Vec3> = (0..lattice.len())
                    .map(|n| {
                        lattice.position((n % nx) as u32, ((n / nx) % ny) as u32, (n / (nx * ny)) as u32)
                    })
                    .collect();
                let mut out = vec![0.0; points.len()];
                self.values(&points, &mut out);
                out
            }
        }
    }

    /// The exact signed distance (world units) at the image under `map` of
    /// every node of `lattice` (x fastest), for the level set's speed
    /// through an alignment map: [`Field3::values`] at those points, to the
    /// last bit but for a point nearly equidistant from two triangles (a
    /// search in another order may settle on the other, a rounding apart).
    /// The nearest points come from one coherent batch query; on a closed
    /// mesh with the winding-number sign the signs are propagated as in
    /// [`MeshSdf::sample_lattice`] (an affine map keeps neighbours a fixed
    /// distance apart per axis, `|A eₐ|` times the step), so the winding
    /// number is evaluated once per region instead of at every node.
    pub fn sample_mapped(&self, lattice: &Lattice, map: &Affine3A) -> Vec<f32> {
        self.sample_mapped_nodes(lattice, UVec3::ZERO, lattice.dims, map)
    }

    /// [`MeshSdf::sample_mapped`] at the nodes `first + (i, j, k)`,
    /// `(i, j, k) < dims` (x fastest), of `lattice`, placed as the whole
    /// lattice places them (bitwise): a brick of a larger lattice.
    ///
    /// Works through slabs of z-layers in parallel (the sign propagation's
    /// own work items), so its memory is the slabs in flight, not the
    /// whole lattice's points and hits.
    pub fn sample_mapped_nodes(
        &self,
        lattice: &Lattice,
        first: UVec3,
        dims: UVec3,
        map: &Affine3A,
    ) -> Vec<f32> {
        let slab = (dims.x as usize * dims.y as usize * SIGN_SLABS).max(1);
        let mut out = vec![0.0; Lattice { dims, ..*lattice }.len()];
        out.par_chunks_mut(slab).enumerate().for_each(|(s, out)| {
            let z = (s * SIGN_SLABS) as u32;
            let layers = UVec3::new(dims.x, dims.y, (dims.z - z).min(SIGN_SLABS as u32));
            out.copy_from_slice(&self.mapped_slab(lattice, first + UVec3::Z * z, layers, map));
        });
        out
    }

    /// [`MeshSdf::sample_mapped_nodes`] of at most [`SIGN_SLABS`] z-layers.
    fn mapped_slab(&self, lattice: &Lattice, first: UVec3, dims: UVec3, map: &Affine3A) -> Vec<f32> {
        let points: Vec<Vec3> = (0..Lattice { dims, ..*lattice }.len())
            .into_par_iter()
            .map(|n| map.transform_point3(lattice.position_in_box(first, dims, n)))
            .collect();
        if let (Sign::Winding(wn), true, Some(_)) = (&self.sign, self.closed, points.first()) {
            // Points beyond the normalized frame's reach become NaN there (no hit).
            let local: Vec<Vec3> = points.par_iter().map(|&p| self.local(p).unwrap_or(Vec3::NAN)).collect();
            let mut hits = vec![None; points.len()];
            self.bvh.closest_many(&local, &mut hits);
            let mut d: Vec<f32> =
                hits.par_iter().map(|h| h.map_or(f32::NAN, |h| h.distance_squared.sqrt())).collect();
            // Otherwise some image lies beyond the normalized frame: point by point below.
            if d.par_iter().all(|v| v.is_finite()) {
                let columns = [map.matrix3.x_axis, map.matrix3.y_axis, map.matrix3.z_axis];
                let spacing = Vec3::from_array(columns.map(|a| Vec3::from(a).length()))
                    * lattice.step.abs()
                    * self.scale;
                let reach = local.par_iter().map(|p| p.abs().max_element()).reduce(|| 0.0, f32::max);
                propagate_signs_by(wn, dims, spacing, reach, |n| local[n], &mut d);
                d.par_iter_mut().for_each(|v| *v *= self.unit());
                return d;
            }
        }
        let mut out = vec![0.0; points.len()];
        self.values(&points, &mut out);
        out
    }

    /// `lattice` in the normalized frame; `None` when a node lies beyond
    /// [`FAR`] there (while the lattice itself is finite and not empty).
    fn local_lattice(&self, lattice: &Lattice) -> Option<Lattice> {
        let local = Lattice {
            dims: lattice.dims,
            origin: lattice.origin * self.scale,
            step: lattice.step * self.scale,
        };
        let world_finite = lattice.origin.is_finite() && lattice.step.is_finite();
        if lattice.is_empty() || !world_finite {
            return Some(local);
        }
        let last = lattice.dims - UVec3::ONE;
        let far = local.position(last.x, last.y, last.z);
        (local.origin.abs().max_element() <= FAR && far.abs().max_element() <= FAR).then_some(local)
    }

    /// [`MeshSdf::sample_lattice`] on a lattice of the normalized frame,
    /// in its units.
    fn sample_local(&self, lattice: &Lattice) -> Vec<f32> {
        let hits = self.bvh.nearest_on_lattice(lattice).expect("MeshSdf always has triangles");
        let mut out: Vec<f32> = hits.iter().map(|h| h.distance).collect();
        if out.is_empty() || !lattice.origin.is_finite() || !lattice.step.is_finite() {
            return out;
        }
        let nodes = lattice.dims.x as usize;
        match &self.sign {
            Sign::Pseudonormal(normals) => {
                out.par_chunks_mut(nodes).zip(hits.par_chunks(nodes)).enumerate().for_each(
                    |(row, (o, h))| {
                        for (i, (o, hit)) in o.iter_mut().zip(h).enumerate() {
                            let p = row_position(lattice, row, i);
                            let inside = self
                                .bvh
                                .closest_point_of(p, hit)
                                .is_some_and(|c| Self::pseudonormal_inside(normals, p, &c));
                            if !inside {
                                *o = -*o;
                            }
                        }
                    },
                );
            }
            Sign::Winding(wn) if self.closed => propagate_signs(wn, lattice, &mut out),
            Sign::Winding(wn) => {
                out.par_chunks_mut(nodes).enumerate().for_each(|(row, o)| {
                    for (i, o) in o.iter_mut().enumerate() {
                        if !wn.is_inside(row_position(lattice, row, i)) {
                            *o = -*o;
                        }
                    }
                });
            }
        }
        drop(hits);
        out
    }

    /// The exact signed distance on a grid over `bounds` with `res` nodes
    /// along its longest edge (cubic voxels, see [`lattice_for_box`]).
    ///
    /// # Errors
    /// [`SdfError::Grid`] for `res < 2`, an empty or non-finite box, or a
    /// grid over the memory limit.
    pub fn sample_grid(&self, bounds: &Aabb, res: u32) -> Result<Grid3<f32>, SdfError> {
        let (dims, origin, spacing) = lattice_for_box(bounds, res)?;
        // Allocate (and check the memory limit) before the work.
        let mut grid = Grid3::new(dims, origin, spacing, 0.0f32)?;
        let lattice = Lattice { dims, origin, step: Vec3::splat(spacing) };
        match self.volume {
            VolumeMode::Exact => grid.data_mut().copy_from_slice(&self.sample_lattice(&lattice)),
            VolumeMode::NarrowBand { width } => grid = self.sample_marched(&lattice, width)?,
        }
        Ok(grid)
    }

    /// The exact signed distance within `width` of the surface, marched
    /// beyond (closest-point propagation from the band's nearest points);
    /// exact everywhere for a lattice beyond the normalized frame's reach.
    fn sample_marched(&self, world: &Lattice, width: f32) -> Result<Grid3<f32>, SdfError> {
        if !(width.is_finite() && width > 0.0) {
            return Err(SdfError::BadBand(width));
        }
        let Some(lattice) = self.local_lattice(world) else {
            return Ok(Grid3::from_vec(world.dims, world.origin, world.step.x, self.sample_lattice(world))?);
        };
        let (lattice, width) = (&lattice, width * self.scale);
        let hits = self.bvh.nearest_on_lattice_within(lattice, width).ok_or(SdfError::EmptyMesh)?;
        let (nx, ny) = (lattice.dims.x as usize, lattice.dims.y as usize);
        let seeds: Vec<Seed> = hits
            .par_iter()
            .enumerate()
            .filter(|(_, hit)| hit.distance <= width)
            .filter_map(|(n, hit)| {
                let node = UVec3::new((n % nx) as u32, ((n / nx) % ny) as u32, (n / (nx * ny)) as u32);
                let p = lattice.origin + lattice.step * node.as_vec3();
                let closest = self.bvh.closest_point_of(p, hit)?;
                let distance = self.signed(p, &closest);
                Some(Seed { node, distance, closest_point: Some(closest.point) })
            })
            .collect();
        drop(hits);
        let settings = FastMarchingSettings { update: Update::ClosestPoint, max_distance: None };
        let local = march_with_discs(lattice.dims, lattice.origin, lattice.step.x, &seeds, &settings, false)?;
        let mut data = local.into_data();
        data.iter_mut().for_each(|d| *d *= self.unit());
        Ok(Grid3::from_vec(world.dims, world.origin, world.step.x, data)?)
    }
}

/// The exact signed distance of `mesh` (positive inside) on a grid over
/// `bounds` with `res` nodes along the longest edge: [`MeshSdf::with_settings`]
/// followed by [`MeshSdf::sample_grid`].
///
/// # Errors
/// As [`MeshSdf::new`] and [`MeshSdf::sample_grid`].
pub fn mesh_sdf_grid(
    mesh: &TriMesh,
    bounds: &Aabb,
    res: u32,
    settings: SdfSettings,
) -> Result<Grid3<f32>, SdfError> {
    MeshSdf::with_settings(mesh, settings)?.sample_grid(bounds, res)
}

impl Field3 for MeshSdf {
    fn value(&self, p: Vec3) -> f32 {
        self.signed_distance(p)
    }

    /// Batch evaluation with coherent nearest-point queries
    /// ([`TriangleBvh::closest_many`]); for whole lattices
    /// [`MeshSdf::sample_lattice`] is much faster.
    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "values: points and out differ in length");
        // Points beyond the normalized frame's reach become NaN there (no hit).
        let local: Vec<Vec3> = points.iter().map(|&p| self.local(p).unwrap_or(Vec3::NAN)).collect();
        let mut hits = vec![None; points.len()];
        self.bvh.closest_many(&local, &mut hits);
        for (((o, &p), &q), hit) in out.iter_mut().zip(points).zip(&local).zip(&hits) {
            *o = match hit {
                Some(hit) => self.signed(q, hit) * self.unit(),
                None if p.is_finite() => self.far_away(p),
                None => f32::NAN,
            };
        }
    }

    /// The exact signed distance at every node ([`MeshSdf::sample_lattice`]).
    fn values_on_lattice(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        let lattice = Lattice { dims, origin, step: Vec3::splat(spacing) };
        assert_eq!(out.len(), lattice.len(), "values_on_lattice: out does not match the lattice");
        out.copy_from_slice(&self.sample_lattice(&lattice));
    }

    /// The band bricks solved as blocks of the lattice search, the signs
    /// found once per region ([`MeshSdf::sample_band_bricks`]).
    fn band_bricks(
        &self,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<Bricks<f32>, GridError> {
        self.sample_band_bricks(dims, origin, spacing, band)
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(self.bounds)
    }
}

/// Position of node `i` of x-row `row` (row index `j + ny · k`).
#[inline]
fn row_position(lattice: &Lattice, row: usize, i: usize) -> Vec3 {
    let ny = lattice.dims.y as usize;
    lattice.position(i as u32, (row % ny) as u32, (row / ny) as u32)
}

/// True when every undirected edge of `mesh` is used equally often in both
/// directions (edges of a repeated index are ignored).
fn is_closed(mesh: &TriMesh) -> bool {
    let mut balance: HashMap<(u32, u32), i32> = HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
    for t in &mesh.triangles {
        for c in 0..3 {
            let (u, v) = (t[c], t[(c + 1) % 3]);
            if u != v {
                *balance.entry((u.min(v), u.max(v))).or_insert(0) += if u < v { 1 } else { -1 };
            }
        }
    }
    balance.values().all(|&b| b == 0)
}

/// Slabs of z-layers per parallel work item of [`propagate_signs`]; signs
/// cross layer links only inside one item.
const SIGN_SLABS: usize = 8;
/// Relative margin on the ball-containment test of a sign link, far above
/// the rounding of exact `f32` distances.
const LINK_MARGIN: f32 = 1e-4;

/// Signs the unsigned distances `d` of a closed mesh's lattice by
/// propagation through surface-free balls, evaluating the winding number
/// once per region reached (see the [module docs](self)).
fn propagate_signs(wn: &WindingNumber, lattice: &Lattice, d: &mut [f32]) {
    let last = lattice.dims.saturating_sub(UVec3::ONE);
    let reach = lattice.origin.abs().max(lattice.position(last.x, last.y, last.z).abs()).max_element();
    let nx = lattice.dims.x as usize;
    let position = |n: usize| row_position(lattice, n / nx, n % nx);
    propagate_signs_by(wn, lattice.dims, lattice.step.abs(), reach, position, d);
}

/// [`propagate_signs`] on any lattice of `dims` nodes whose neighbours along
/// axis `a` lie `spacing[a]` apart (an affine image of a lattice), node `n`
/// (x fastest) at `position(n)`; `reach` bounds the nodes' coordinates
/// (and so the rounding of their positions).
fn propagate_signs_by(
    wn: &WindingNumber,
    dims: UVec3,
    spacing: Vec3,
    reach: f32,
    position: impl Fn(usize) -> Vec3 + Sync,
    d: &mut [f32],
) {
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    // Node positions are rounded to f32: two neighbours can be farther apart
    // than the step by the rounding of both (a sixteenth of a unit at 10⁶).
    let limits = spacing * (1.0 + LINK_MARGIN) + Vec3::splat(4.0 * f32::EPSILON * reach + f32::MIN_POSITIVE);
    // Two nodes one step apart along an axis share a sign when their
    // surface-free balls overlap: the distances add up to more than the step.
    let linked = |a: f32, b: f32, axis: usize| a + b > limits[axis];
    d.par_chunks_mut(nx * ny * SIGN_SLABS).enumerate().for_each(|(chunk, d)| {
        // 0: unknown, 1: inside, -1: outside.
        let mut sign = vec![0i8; d.len()];
        let inside =
            |index: usize| if wn.is_inside(position(chunk * nx * ny * SIGN_SLABS + index)) { 1 } else { -1 };
        for row_start in (0..d.len()).step_by(nx) {
            let row = row_start..row_start + nx;
            // Inherit from the row below (y) or the layer below (z).
            for x in row.clone() {
                if row_start % (nx * ny) >= nx && linked(d[x], d[x - nx], 1) {
                    sign[x] = sign[x - nx];
                } else if x >= nx * ny && linked(d[x], d[x - nx * ny], 2) {
                    sign[x] = sign[x - nx * ny];
                }
            }
            // Sweep along the row both ways, then evaluate what is left.
            for x in row.start + 1..row.end {
                if sign[x] == 0 && linked(d[x], d[x - 1], 0) {
                    sign[x] = sign[x - 1];
                }
            }
            for x in (row.start..row.end - 1).rev() {
                if sign[x] == 0 && linked(d[x], d[x + 1], 0) {
                    sign[x] = sign[x + 1];
                }
            }
            for x in row.clone() {
                if sign[x] == 0 {
                    sign[x] =
                        if x > row.start && linked(d[x], d[x - 1], 0) { sign[x - 1] } else { inside(x) };
                }
            }
        }
        for (d, s) in d.iter_mut().zip(&sign) {
            if *s < 0 {
                *d = -*d;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::metrics::test_meshes::{bunny, cube, read_obj, torus, uv_sphere};
    use glam::UVec3;

    fn box_sd(p: Vec3) -> f32 {
        let q = p.abs() - Vec3::ONE;
        -(q.max(Vec3::ZERO).length() + q.max_element().min(0.0))
    }

    #[test]
    fn narrow_band_volume_is_exact_in_the_band_and_close_beyond() {
        let mesh = bunny();
        let bounds = mesh.bounds().padded(0.1);
        let exact = mesh_sdf_grid(&mesh, &bounds, 64, SdfSettings::default()).unwrap();
        let h = exact.spacing();
        let width = 2.0 * h;
        let settings = SdfSettings::default().with_volume(VolumeMode::NarrowBand { width });
        let banded = mesh_sdf_grid(&mesh, &bounds, 64, settings).unwrap();
        assert!(banded.same_lattice(&exact));
        let size = bounds.size().max_element();
        let (mut in_band, mut worst_band, mut worst_far) = (0, 0.0f32, 0.0f32);
        for (&b, &e) in banded.data().iter().zip(exact.data()) {
            assert_eq!(b > 0.0, e > 0.0, "sign differs: band {b}, exact {e}");
            if e.abs() <= width {
                in_band += 1;
                worst_band = worst_band.max((b - e).abs());
            } else {
                worst_far = worst_far.max((b - e).abs());
            }
        }
        assert!(in_band > 10_000, "{in_band} band nodes");
        assert!(worst_band <= 1e-5 * size, "band error {worst_band} > 1e-5 · {size}");
        // Closest-point propagation: measured 0.35 voxel at worst (inside,
        // next to the medial axis), 6 of ~200k far nodes above 0.3.
        assert!(worst_far < 0.4 * h, "beyond the band: {} voxels", worst_far / h);
        let bad = SdfSettings::default().with_volume(VolumeMode::NarrowBand { width: -1.0 });
        assert_eq!(mesh_sdf_grid(&mesh, &bounds, 16, bad).unwrap_err(), SdfError::BadBand(-1.0));
    }

    #[test]
    fn mapped_lattices_equal_pointwise_values() {
        let map = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.3, 0.8, 1.1),
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 1.1),
            Vec3::new(0.05, -0.1, 0.02),
        ) * Affine3A::from_mat3(glam::Mat3::from_cols(Vec3::X, Vec3::new(0.2, 1.0, 0.0), Vec3::Z));
        let mut open = torus(0.3, 0.1, 24, 12);
        open.triangles.truncate(open.triangles.len() - 30);
        for (mesh, closed) in [(bunny(), true), (torus(0.3, 0.1, 24, 12), true), (open, false)] {
            let sdf = MeshSdf::new(&mesh).unwrap();
            assert_eq!(sdf.is_closed(), closed);
            let b = mesh.bounds().padded(0.3);
            let lattice = Lattice { dims: UVec3::new(21, 17, 19), origin: b.min, step: b.size() / 18.0 };
            let mapped = sdf.sample_mapped(&lattice, &map);
            let points: Vec<Vec3> = (0..lattice.len())
                .map(|n| {
                    let (x, y, z) = (n % 21, (n / 21) % 17, n / (21 * 17));
                    map.transform_point3(lattice.position(x as u32, y as u32, z as u32))
                })
                .collect();
            let mut pointwise = vec![0.0; points.len()];
            sdf.values(&points, &mut pointwise);
            let inside = mapped.iter().filter(|&&v| v > 0.0).count();
            assert!(inside > 50 && inside < lattice.len() - 50, "{inside} inside");
            for (n, (a, b)) in mapped.iter().zip(&pointwise).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "node {n}: {a} against {b} (closed: {closed})");
            }
        }
    }

    #[test]
    fn cube_distances_are_exact_with_the_right_sign() {
        for sign in [SignMode::WindingNumber, SignMode::Pseudonormal] {
            let sdf = MeshSdf::with_settings(&cube(1.0), SdfSettings::default().with_sign(sign)).unwrap();
            assert_eq!(sdf.sign_mode(), sign);
            assert!(sdf.is_closed());
            for p in [
                Vec3::ZERO,
                Vec3::new(0.5, 0.2, -0.9),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(1.5, 1.5, 0.0),
                Vec3::new(2.0, 2.0, 2.0),
                Vec3::new(1.0 + 1e-4, 0.3, 0.99),
                Vec3::new(0.999, 0.999, -0.999),
            ] {
                let (got, want) = (sdf.value(p), box_sd(p));
                assert!((got - want).abs() < 1e-5, "{sign:?} at {p}: got {got}, want {want}");
                assert_eq!(sdf.is_inside(p), want > 0.0);
            }
        }
    }

    #[test]
    fn grid_matches_pointwise_evaluation() {
        // Closed (propagated signs) and open (per-node winding numbers) meshes,
        // both sign modes, against single-point queries.
        let mut holed = uv_sphere(Vec3::ZERO, 1.0, 12, 24);
        holed.triangles.remove(40);
        for (mesh, closed) in [(torus(1.0, 0.4, 32, 16), true), (holed, false)] {
            for sign in [SignMode::WindingNumber, SignMode::Pseudonormal] {
                let sdf = MeshSdf::with_settings(&mesh, SdfSettings::default().with_sign(sign)).unwrap();
                assert_eq!(sdf.is_closed(), closed);
                let grid = sdf.sample_grid(&mesh.bounds().padded(0.15), 21).unwrap();
                // The generic grid fill goes through `Field3::values`.
                let filled = Grid3::sample_box(&sdf, &mesh.bounds().padded(0.15), 21).unwrap();
                assert!(grid.data().iter().zip(filled.data()).all(|(a, b)| (a - b).abs() < 1e-5));
                for (index, &got) in grid.data().iter().enumerate() {
                    let n = grid.node_of(index);
                    let p = grid.position(n.x, n.y, n.z);
                    let want = sdf.signed_distance(p);
                    assert!((got - want).abs() < 1e-5, "{sign:?} at {p}: grid {got}, point {want}");
                }
            }
        }
    }

    #[test]
    fn winding_sign_agrees_with_pseudonormals_on_the_bunny() {
        let mesh = bunny();
        let bounds = mesh.bounds().padded(0.1);
        let wn = mesh_sdf_grid(&mesh, &bounds, 40, SdfSettings::default()).unwrap();
        let pn = mesh_sdf_grid(&mesh, &bounds, 40, SdfSettings::default().with_sign(SignMode::Pseudonormal))
            .unwrap();
        let inside = wn.data().iter().filter(|&&d| d > 0.0).count();
        assert!(inside > 1000, "{inside} nodes inside");
        for (a, b) in wn.data().iter().zip(pn.data()) {
            assert_eq!(a, b);
        }
    }

    /// The libigl reference volume of `shared/data` (64³ nodes over the
    /// bunny's box padded 10 %, C order with z fastest, negative inside).
    #[test]
    fn bunny_matches_libigl() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/bunny_sdf64_igl_wn.f32");
        let bytes = std::fs::read(path).unwrap();
        let reference: Vec<f32> =
            bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        let n = 64;
        assert_eq!(reference.len(), n * n * n);
        let mesh = bunny();
        let bounds = mesh.bounds().padded(0.1);
        let lattice = Lattice::spanning(&bounds, UVec3::splat(n as u32));
        let tolerance = 1e-5 * bounds.size().max_element();
        for sign in [SignMode::WindingNumber, SignMode::Pseudonormal] {
            let sdf = MeshSdf::with_settings(&mesh, SdfSettings::default().with_sign(sign)).unwrap();
            let ours = sdf.sample_lattice(&lattice);
            let (mut flipped, mut worst) = (0, 0.0f32);
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        let (a, b) = (ours[i + n * (j + n * k)], -reference[(i * n + j) * n + k]);
                        if (a > 0.0) != (b > 0.0) {
                            flipped += 1;
                        } else {
                            worst = worst.max((a - b).abs());
                        }
                    }
                }
            }
            assert_eq!(flipped, 0, "{sign:?}: sign disagreements");
            assert!(worst <= tolerance, "{sign:?}: largest difference {worst}");
        }
    }

    #[test]
    fn teapot_grid_has_a_sensible_inside() {
        let teapot = read_obj(concat!(env!("CARGO_MANIFEST_DIR"), "/../data/teapot.obj"));
        let sdf = MeshSdf::new(&teapot).unwrap();
        assert!(!sdf.is_closed());
        let grid = sdf.sample_grid(&teapot.bounds().padded(0.1), 24).unwrap();
        // Inside the body (y up), outside above the lid and beside it.
        assert!(grid.trilinear(Vec3::ZERO) > 3.0);
        assert!(grid.trilinear(Vec3::new(0.0, 9.5, 0.0)) < 0.0);
        assert!(grid.trilinear(Vec3::new(0.0, 0.0, 11.5)) < 0.0);
        let inside = grid.data().iter().filter(|&&d| d > 0.0).count();
        assert!(inside > 500, "{inside} nodes inside");
    }

    /// A mesh at scale `factor`, sampled on the lattice scaled likewise,
    /// gives the unit mesh's signs and `factor` times its distances, in both
    /// sign modes, on closed and open meshes, on lattices and single points.
    #[test]
    fn distances_scale_with_the_mesh() {
        let mut holed = uv_sphere(Vec3::ZERO, 1.0, 12, 24);
        holed.triangles.remove(40);
        let lattice = Lattice::spanning(&Aabb::cube(1.3), UVec3::new(15, 13, 11));
        for (name, mesh) in
            [("cube", cube(1.0)), ("sphere", uv_sphere(Vec3::ZERO, 1.0, 12, 24)), ("holed", holed)]
        {
            for sign in [SignMode::WindingNumber, SignMode::Pseudonormal] {
                let settings = SdfSettings::default().with_sign(sign);
                let unit = MeshSdf::with_settings(&mesh, settings).unwrap().sample_lattice(&lattice);
                let inside = unit.iter().filter(|&&d| d > 0.0).count();
                assert!(inside > 100 && inside < unit.len() - 100, "{name}: {inside} nodes inside");
                for factor in [1e13f32, 1e20, 1e30, 1e-20, 1e-38, 1e-40] {
                    let sdf = MeshSdf::with_settings(&mesh.scaled(factor), settings).unwrap();
                    let scaled =
                        Lattice { origin: lattice.origin * factor, step: lattice.step * factor, ..lattice };
                    let got = sdf.sample_lattice(&scaled);
                    // Rounding of the scaled coordinates: relative to f32 precision, or
                    // to the subnormal spacing 2⁻¹⁴⁹ below 2⁻¹²⁶.
                    let tolerance = 1e-5 + 16.0 * 2f64.powi(-149) / f64::from(factor);
                    for (n, (&g, &u)) in got.iter().zip(&unit).enumerate() {
                        let g = f64::from(g) / f64::from(factor);
                        assert!(
                            (g - f64::from(u)).abs() <= tolerance,
                            "{name}, {sign:?}, × {factor:e}, node {n}: {g} vs {u}"
                        );
                        assert_eq!(g > 0.0, u > 0.0, "{name}, {sign:?}, × {factor:e}, node {n}: {g} vs {u}");
                    }
                    // The same through single points.
                    for p in [Vec3::ZERO, Vec3::new(0.3, -0.5, 0.2), Vec3::new(1.2, 0.1, -0.4)] {
                        let (got, want) = (
                            sdf.signed_distance(p * factor),
                            MeshSdf::with_settings(&mesh, settings).unwrap().value(p),
                        );
                        let got = f64::from(got) / f64::from(factor);
                        assert!(
                            (got - f64::from(want)).abs() <= tolerance,
                            "{name} × {factor:e} at {p}: {got} vs {want}"
                        );
                        assert_eq!(sdf.is_inside(p * factor), want > 0.0);
                    }
                }
            }
        }
    }

    #[test]
    fn narrow_band_volume_scales_with_the_mesh() {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 16, 32);
        let h = 2.6 / 23.0;
        let volume = |factor: f32, volume: VolumeMode| {
            let bounds = Aabb::new(Vec3::splat(-1.3 * factor), Vec3::splat(1.3 * factor));
            let grid =
                mesh_sdf_grid(&mesh.scaled(factor), &bounds, 24, SdfSettings::default().with_volume(volume))
                    .unwrap();
            grid.data().iter().map(|&d| f64::from(d) / f64::from(factor)).collect::<Vec<_>>()
        };
        let unit = volume(1.0, VolumeMode::Exact);
        for factor in [1.0, 1e20f32, 1e30, 1e-20, 1e-36] {
            let exact = volume(factor, VolumeMode::Exact);
            let band = volume(factor, VolumeMode::NarrowBand { width: 2.0 * h * factor });
            assert_eq!((exact.len(), band.len()), (unit.len(), unit.len()));
            // Exact in the band, within the marching's 0.4 voxel beyond (as at unit size).
            for ((&e, &b), &u) in exact.iter().zip(&band).zip(&unit) {
                assert!((e - u).abs() <= 1e-5 && (e > 0.0) == (u > 0.0), "× {factor:e}: {e} vs {u}");
                let tolerance = if e.abs() <= 2.0 * f64::from(h) { 1e-5 } else { 0.4 * f64::from(h) };
                assert!((b - e).abs() <= tolerance && (b > 0.0) == (e > 0.0), "× {factor:e}: {b} vs {e}");
            }
        }
    }

    /// Extreme but finite meshes are handled; what cannot be is an error.
    #[test]
    fn extreme_meshes() {
        // Coordinates up to 3·10³⁸: the box's extent overflows f32.
        let huge = MeshSdf::new(&cube(1.0).scaled(3e38)).unwrap();
        assert!(huge.bounds.size().x.is_infinite());
        for (p, want) in
            [(Vec3::ZERO, 3e38), (Vec3::new(1.5e38, 0.0, 0.0), 1.5e38), (Vec3::new(0.0, -2e38, 2.5e38), 5e37)]
        {
            assert!(
                (huge.signed_distance(p) / want - 1.0).abs() < 1e-5,
                "at {p}: {}",
                huge.signed_distance(p)
            );
        }
        // Unit size far from the origin: the positions' own rounding (1/16
        // at 10⁶) is the only limit; distances between them are exact.
        let offset = Vec3::new(1e6, -1e6, 1e6);
        let far = cube(1.0).transformed(&glam::Affine3A::from_translation(offset));
        let sdf = MeshSdf::new(&far).unwrap();
        let lattice = Lattice::spanning(
            &Aabb::new(Vec3::splat(-1.3) + offset, Vec3::splat(1.3) + offset),
            UVec3::splat(12),
        );
        let got = sdf.sample_lattice(&lattice);
        for (n, &g) in got.iter().enumerate() {
            let (nx, ny) = (12, 12);
            let p = lattice.position((n % nx) as u32, (n / nx % ny) as u32, (n / (nx * ny)) as u32);
            assert!((g - box_sd(p - offset)).abs() < 1e-6, "at {p}: {g} vs {}", box_sd(p - offset));
        }
        // At 10⁸ the unit cube rounds away to one point.
        let gone = cube(1.0).transformed(&glam::Affine3A::from_translation(Vec3::splat(1e8)));
        assert_eq!(MeshSdf::new(&gone).unwrap_err(), SdfError::ZeroExtent);
        // Points far beyond a tiny mesh are measured to its centre; a lattice
        // spanning both evaluates node by node.
        let tiny = MeshSdf::new(&cube(1.0).scaled(1e-38)).unwrap();
        assert!((tiny.signed_distance(Vec3::new(3.0, 4.0, 0.0)) + 5.0).abs() < 1e-6);
        assert!(!tiny.is_inside(Vec3::X) && tiny.closest(Vec3::X).is_none());
        let wide = tiny.sample_lattice(&Lattice::spanning(&Aabb::cube(1.0), UVec3::splat(3)));
        assert_eq!(wide[13], 1e-38, "the centre node is inside");
        assert!((wide[0] + 3f32.sqrt()).abs() < 1e-6 && (wide[14] + 1.0).abs() < 1e-6, "{wide:?}");
        let band = SdfSettings::default().with_volume(VolumeMode::NarrowBand { width: 0.1 });
        let grid = MeshSdf::with_settings(&cube(1.0).scaled(1e-38), band)
            .unwrap()
            .sample_grid(&Aabb::cube(1.0), 3)
            .unwrap();
        let lattice = Lattice { dims: grid.dims(), origin: grid.origin(), step: Vec3::splat(grid.spacing()) };
        assert_eq!(grid.data(), &tiny.sample_lattice(&lattice)[..]);
    }

    #[test]
    fn errors() {
        assert_eq!(MeshSdf::new(&TriMesh::default()).unwrap_err(), SdfError::EmptyMesh);
        let sdf = MeshSdf::new(&cube(1.0)).unwrap();
        assert!(matches!(sdf.sample_grid(&Aabb::cube(1.0), 1), Err(SdfError::Grid(_))));
        assert!(matches!(sdf.sample_grid(&Aabb::EMPTY, 8), Err(SdfError::Grid(_))));
        assert!(sdf.signed_distance(Vec3::NAN).is_nan());
        assert!(!sdf.is_inside(Vec3::NAN) && sdf.closest(Vec3::INFINITY).is_none());
        // Non-finite coordinates, and triangles that are all one point.
        let mut bad = cube(1.0);
        bad.positions[3].y = f32::INFINITY;
        assert!(matches!(MeshSdf::new(&bad), Err(SdfError::Mesh(crate::MeshError::NonFinite(3)))));
        let point = TriMesh::new(vec![Vec3::ONE; 3], vec![[0, 1, 2], [2, 1, 0]]).unwrap();
        assert_eq!(MeshSdf::new(&point).unwrap_err(), SdfError::ZeroExtent);
    }
}
