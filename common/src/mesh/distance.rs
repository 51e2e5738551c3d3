//! Two-sided surface distance between meshes ([`surface_distance`]): how far
//! one surface strays from another, sampled on both.
//!
//! Each surface is sampled area-uniformly (stratified over the cumulative
//! triangle area, low-discrepancy points inside each triangle, plus every
//! vertex), and each sample's exact distance to the other surface is found
//! with a [`TriangleBvh`]. The sampling is deterministic: the same meshes and
//! sample count always give the same figures.
//!
//! Both meshes are first multiplied by the power of two that brings the
//! larger one's coordinates near 1 (exact), so that squared `f32`
//! distances neither overflow nor underflow at any mesh scale; the figures
//! are scaled back in `f64`.

use super::bvh::{BvhBuild, TriangleBvh};
use super::trimesh::unit_scale;
use crate::{Aabb, TriMesh};
use glam::Vec3;
use rayon::prelude::*;

/// Distances between two surfaces, in world units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SurfaceDistance {
    /// Mean distance over the samples of both surfaces.
    pub mean: f32,
    /// Root mean square distance over the samples of both surfaces.
    pub rms: f32,
    /// Largest sampled distance in either direction: the sampled (two-sided)
    /// Hausdorff distance, a lower bound of the true one that converges as
    /// the sample count grows.
    pub hausdorff: f32,
}

/// Errors of [`surface_distance`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DistanceError {
    /// One of the meshes has no triangle of positive area.
    #[error("the {which} mesh has no surface (no triangle of positive area)")]
    EmptySurface {
        /// `"first"` or `"second"`.
        which: &'static str,
    },
    /// A mesh failed validation.
    #[error(transparent)]
    Mesh(#[from] crate::MeshError),
}

/// Two-sided distance between the surfaces of `a` and `b`: `samples` points
/// on each surface (plus their vertices) measured against the other.
///
/// # Errors
/// [`DistanceError::Mesh`] for invalid meshes, [`DistanceError::EmptySurface`]
/// when either has zero area.
///
/// # Example
/// ```
/// use isomorph_common::{Shape, marching_cubes::polygonize};
/// use isomorph_common::mesh::distance::surface_distance;
/// let box_ = isomorph_common::Aabb::cube(0.5);
/// let small = polygonize(&Shape::sphere(0.30), &box_, 48, 0.0).unwrap();
/// let large = polygonize(&Shape::sphere(0.35), &box_, 48, 0.0).unwrap();
/// let d = surface_distance(&small, &large, 2000).unwrap();
/// assert!((d.mean - 0.05).abs() < 0.005 && (d.hausdorff - 0.05).abs() < 0.01);
/// ```
pub fn surface_distance(a: &TriMesh, b: &TriMesh, samples: usize) -> Result<SurfaceDistance, DistanceError> {
    let frame = a.bounds().union(&b.bounds());
    let a = IndexedSurface::new(a, &frame)?;
    let b = IndexedSurface::new(b, &frame)?;
    a.distance_to(&b, samples)
}

/// A surface indexed once for any number of distance measurements
/// ([`IndexedSurface::distance_to`], [`IndexedSurface::distance_to_reference`]):
/// its [`TriangleBvh`], built in the frame multiplied by the power of two
/// that brings the coordinates of a given box near 1 (see the [module
/// docs](self)). Index every surface that will be compared in the same box
/// (e.g. the box of all of them), so that no point needs rescaling.
#[derive(Debug, Clone)]
pub struct IndexedSurface {
    /// The mesh multiplied by `scale`.
    mesh: TriMesh,
    /// The tree over `mesh`.
    bvh: TriangleBvh,
    /// The power of two the world was multiplied by.
    scale: f32,
}

/// Sum, sum of squares and maximum of one-sided distances, and their count.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    sum: f64,
    squares: f64,
    max: f64,
    count: usize,
}

impl Sums {
    /// The sums of `distances` (world units).
    fn of(distances: impl ParallelIterator<Item = f64>) -> Sums {
        distances
            .fold(Sums::default, |s, d| Sums {
                sum: s.sum + d,
                squares: s.squares + d * d,
                max: s.max.max(d),
                count: s.count + 1,
            })
            .reduce(Sums::default, |x, y| Sums {
                sum: x.sum + y.sum,
                squares: x.squares + y.squares,
                max: x.max.max(y.max),
                count: x.count + y.count,
            })
    }

    /// The two-sided figures of the two one-sided sums `self` and `other`.
    fn both_ways(self, other: Sums) -> SurfaceDistance {
        let n = (self.count + other.count).max(1) as f64;
        SurfaceDistance {
            mean: ((self.sum + other.sum) / n) as f32,
            rms: ((self.squares + other.squares) / n).sqrt() as f32,
            hausdorff: self.max.max(other.max) as f32,
        }
    }
}

impl IndexedSurface {
    /// Indexes `mesh` for distances in the box `frame` (which picks the
    /// scale of the computation; the mesh's own box is added to it).
    ///
    /// The tree is built in Morton order ([`BvhBuild::Morton`]): a surface
    /// is queried at its samples (thousands), usually fewer times than it
    /// has triangles, so the build, not the queries, is the larger cost.
    ///
    /// # Errors
    /// [`DistanceError::Mesh`] for an invalid mesh.
    pub fn new(mesh: &TriMesh, frame: &Aabb) -> Result<Self, DistanceError> {
        mesh.validate()?;
        let frame = frame.union(&mesh.bounds());
        let magnitude =
            if frame.is_empty() { 0.0 } else { frame.min.abs().max(frame.max.abs()).max_element() };
        let scale = unit_scale(magnitude);
        let mesh = mesh.scaled(scale);
        Ok(Self { bvh: TriangleBvh::with_build(&mesh, BvhBuild::Morton), mesh, scale })
    }

    /// Sums of the distances (world units) from `points`, given in this
    /// index's scaled frame, to the surface.
    fn sums(&self, points: &[Vec3]) -> Sums {
        let mut closest = vec![None; points.len()];
        self.bvh.closest_many(points, &mut closest);
        let unit = 1.0 / f64::from(self.scale);
        Sums::of(
            closest
                .par_iter()
                .map(|c| c.map_or(0.0, |c| f64::from(c.distance_squared.max(0.0)).sqrt() * unit)),
        )
    }

    /// The point of `points` (world units) farthest from this surface, with
    /// its distance (world units): where another surface, sampled at
    /// `points`, strays farthest from this one. `None` without points.
    pub fn farthest_of(&self, points: &[Vec3]) -> Option<(Vec3, f32)> {
        let mut closest = vec![None; points.len()];
        self.bvh.closest_many(&self.rescaled(points.to_vec(), 1.0), &mut closest);
        let (i, d2) = closest
            .iter()
            .enumerate()
            .map(|(i, c)| (i, c.map_or(0.0, |c| c.distance_squared.max(0.0))))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        Some((points[i], d2.sqrt() / self.scale))
    }

    /// `points` of another index's frame (scale `from`) in this one's.
    fn rescaled(&self, points: Vec<Vec3>, from: f32) -> Vec<Vec3> {
        if from == self.scale {
            return points;
        }
        let ratio = self.scale / from;
        points.into_iter().map(|p| p * ratio).collect()
    }

    /// Two-sided distance between this surface and `other`: `samples`
    /// points on each (plus their vertices) measured against the other's
    /// tree, as [`surface_distance`] does, without building either tree
    /// again.
    ///
    /// # Errors
    /// [`DistanceError::EmptySurface`] when either has zero area (`"first"`
    /// is `self`).
    pub fn distance_to(
        &self,
        other: &IndexedSurface,
        samples: usize,
    ) -> Result<SurfaceDistance, DistanceError> {
        let here =
            surface_samples(&self.mesh, samples).ok_or(DistanceError::EmptySurface { which: "first" })?;
        let there =
            surface_samples(&other.mesh, samples).ok_or(DistanceError::EmptySurface { which: "second" })?;
        let outward = other.sums(&other.rescaled(here, self.scale));
        Ok(outward.both_ways(self.sums(&self.rescaled(there, other.scale))))
    }

    /// The two-sided sampled Hausdorff distance between this surface and
    /// `other` (world units): [`IndexedSurface::distance_to`]'s `hausdorff`
    /// (the same samples), without the mean, so that each sample only needs
    /// its exact distance when it may be the largest
    /// ([`TriangleBvh::farthest_distance_squared`]): several times faster.
    ///
    /// # Errors
    /// As [`IndexedSurface::distance_to`].
    pub fn hausdorff_to(&self, other: &IndexedSurface, samples: usize) -> Result<f32, DistanceError> {
        let here =
            surface_samples(&self.mesh, samples).ok_or(DistanceError::EmptySurface { which: "first" })?;
        let there =
            surface_samples(&other.mesh, samples).ok_or(DistanceError::EmptySurface { which: "second" })?;
        let farthest = |index: &IndexedSurface, points: Vec<Vec3>| {
            let d2 = index.bvh.farthest_distance_squared(&points).unwrap_or(0.0);
            f64::from(d2.max(0.0)).sqrt() / f64::from(index.scale)
        };
        let (outward, inward) = rayon::join(
            || farthest(other, other.rescaled(here, self.scale)),
            || farthest(self, self.rescaled(there, other.scale)),
        );
        Ok(outward.max(inward) as f32)
    }

    /// Two-sided distance between this surface and a reference surface that
    /// is known by points on it (`reference_points`, world units: e.g.
    /// [`surface_samples`] of its mesh) and by its own unsigned distance
    /// (`reference_distance`, world units, e.g. the exact distance of the
    /// solid it bounds): `samples` points on this surface (plus its
    /// vertices) measured by `reference_distance`, and every reference point
    /// against this surface's tree.
    ///
    /// # Errors
    /// [`DistanceError::EmptySurface`] when this surface has zero area
    /// (`"first"`) or `reference_points` is empty (`"second"`).
    pub fn distance_to_reference(
        &self,
        samples: usize,
        reference_points: &[Vec3],
        reference_distance: impl Fn(Vec3) -> f32 + Sync,
    ) -> Result<SurfaceDistance, DistanceError> {
        if reference_points.is_empty() {
            return Err(DistanceError::EmptySurface { which: "second" });
        }
        let here =
            surface_samples(&self.mesh, samples).ok_or(DistanceError::EmptySurface { which: "first" })?;
        let unit = 1.0 / self.scale;
        let outward = Sums::of(here.par_iter().map(|&p| f64::from(reference_distance(p * unit).abs())));
        let inward = self.sums(&self.rescaled(reference_points.to_vec(), 1.0));
        Ok(outward.both_ways(inward))
    }
}

/// `count` area-uniform points on the surface of `mesh` followed by its
/// vertices; `None` when the surface has zero area.
///
/// Stratified: sample `i` falls at cumulative area `(i + ½)/count` of the
/// total, so every triangle gets its share to within one sample; inside the
/// triangle it takes the `i`-th point of the R2 low-discrepancy sequence,
/// folded into the triangle.
pub fn surface_samples(mesh: &TriMesh, count: usize) -> Option<Vec<Vec3>> {
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0f64;
    for t in 0..mesh.triangles.len() {
        let [p, q, r] = mesh.corners(t);
        total += 0.5 * f64::from((q - p).cross(r - p).length());
        cumulative.push(total);
    }
    if total <= 0.0 || total.is_nan() {
        return None;
    }
    // R2 sequence constants (Roberts 2018): 1/g and 1/g² for the plastic number g.
    const A1: f64 = 0.754_877_666_246_692_8;
    const A2: f64 = 0.569_840_290_998_053_3;
    let mut points = Vec::with_capacity(count + mesh.positions.len());
    for i in 0..count {
        let target = (i as f64 + 0.5) / count as f64 * total;
        let t = cumulative.partition_point(|&c| c < target).min(cumulative.len() - 1);
        let (mut u, mut v) = ((0.5 + A1 * i as f64).fract(), (0.5 + A2 * i as f64).fract());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let [p, q, r] = mesh.corners(t);
        points.push(p + (q - p) * u as f32 + (r - p) * v as f32);
    }
    points.extend_from_slice(&mesh.positions);
    Some(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::marching_cubes::polygonize;
    use crate::{Aabb, Shape};

    fn sphere(r: f32, res: u32) -> TriMesh {
        polygonize(&Shape::sphere(r), &Aabb::cube(0.5), res, 0.0).unwrap()
    }

    #[test]
    fn identical_meshes_are_at_distance_zero() {
        let m = sphere(0.3, 32);
        let d = surface_distance(&m, &m, 1000).unwrap();
        assert!(d.hausdorff < 1e-6 && d.mean < 1e-7, "{d:?}");
    }

    #[test]
    fn the_farthest_point_is_found_with_its_distance() {
        let index = IndexedSurface::new(&sphere(0.3, 48), &Aabb::cube(0.5)).unwrap();
        let mut points =
            vec![Vec3::new(0.3, 0.0, 0.0), Vec3::new(0.0, 0.45, 0.0), Vec3::new(0.0, 0.0, -0.32)];
        let (p, d) = index.farthest_of(&points).unwrap();
        assert_eq!(p, Vec3::new(0.0, 0.45, 0.0));
        assert!((d - 0.15).abs() < 2e-3, "{d}");
        points.push(Vec3::ZERO); // the centre, a radius from every side
        let (p, d) = index.farthest_of(&points).unwrap();
        assert_eq!(p, Vec3::ZERO);
        assert!((d - 0.3).abs() < 2e-3, "{d}");
        assert_eq!(index.farthest_of(&[]), None);
    }

    #[test]
    fn concentric_spheres_are_their_radius_gap_apart() {
        let d = surface_distance(&sphere(0.2, 64), &sphere(0.3, 64), 4000).unwrap();
        assert!((d.mean - 0.1).abs() < 2e-3, "{d:?}");
        assert!((d.hausdorff - 0.1).abs() < 4e-3, "{d:?}");
        assert!((d.rms - d.mean).abs() < 1e-3 && d.rms >= d.mean, "{d:?}");
    }

    #[test]
    fn figures_scale_with_the_meshes() {
        let (a, b) = (sphere(0.2, 32), sphere(0.3, 32));
        let unit = surface_distance(&a, &b, 1000).unwrap();
        for factor in [1e25f32, 1e-25, 1e-40] {
            let d = surface_distance(&a.scaled(factor), &b.scaled(factor), 1000).unwrap();
            for (got, want) in [(d.mean, unit.mean), (d.rms, unit.rms), (d.hausdorff, unit.hausdorff)] {
                let got = f64::from(got) / f64::from(factor);
                // Subnormal coordinates (× 10⁻⁴⁰) are rounded to 2⁻¹⁴⁹: 10⁻⁵ of the radius.
                let tolerance = if factor < 1e-37 { 2e-3 } else { 1e-4 };
                assert!((got / f64::from(want) - 1.0).abs() < tolerance, "× {factor:e}: {d:?} vs {unit:?}");
            }
        }
    }

    #[test]
    fn hausdorff_alone_equals_the_full_measure() {
        let box_ = Aabb::cube(0.5);
        let a = sphere(0.2, 40);
        let torus = polygonize(&Shape::torus(0.25, 0.08), &box_, 48, 0.0).unwrap();
        let mut far = a.clone();
        far.append(&a.transformed(&glam::Affine3A::from_translation(Vec3::new(0.9, 0.0, 0.0))));
        for (x, y) in [(&a, &torus), (&torus, &a), (&a, &far), (&far, &torus), (&a, &a)] {
            let (x, y) = (IndexedSurface::new(x, &box_).unwrap(), IndexedSurface::new(y, &box_).unwrap());
            for samples in [0, 1000] {
                let full = x.distance_to(&y, samples).unwrap().hausdorff;
                let alone = x.hausdorff_to(&y, samples).unwrap();
                assert_eq!(alone, full, "{samples} samples");
            }
        }
        let empty = TriMesh::new(vec![], vec![]).unwrap();
        let e = IndexedSurface::new(&empty, &box_).unwrap();
        let s = IndexedSurface::new(&a, &box_).unwrap();
        assert!(matches!(s.hausdorff_to(&e, 10), Err(DistanceError::EmptySurface { which: "second" })));
    }

    #[test]
    fn distance_is_symmetric_and_sees_a_far_piece() {
        let a = sphere(0.2, 32);
        let mut b = a.clone();
        b.append(&a.transformed(&glam::Affine3A::from_translation(Vec3::new(2.0, 0.0, 0.0))));
        let ab = surface_distance(&a, &b, 1000).unwrap();
        let ba = surface_distance(&b, &a, 1000).unwrap();
        // The far copy is 2 units away, minus the sphere's width at the near side.
        assert!((ab.hausdorff - 2.0).abs() < 0.05, "{ab:?}");
        assert!((ab.hausdorff - ba.hausdorff).abs() < 1e-6);
        assert!(ab.mean > 0.4, "half of b's samples are on the far copy: {ab:?}");
    }

    #[test]
    fn indexed_surfaces_measure_as_surface_distance_does() {
        let (a, b) = (sphere(0.2, 32), sphere(0.3, 48));
        let want = surface_distance(&a, &b, 1000).unwrap();
        // Indexed in their own boxes (different scales) or in a shared one.
        let far = Aabb::cube(300.0);
        for (frame_a, frame_b) in [(a.bounds(), b.bounds()), (far, far), (a.bounds(), far)] {
            let (ia, ib) =
                (IndexedSurface::new(&a, &frame_a).unwrap(), IndexedSurface::new(&b, &frame_b).unwrap());
            let got = ia.distance_to(&ib, 1000).unwrap();
            assert!(
                (got.mean - want.mean).abs() < 1e-6 && (got.hausdorff - want.hausdorff).abs() < 1e-6,
                "{got:?}"
            );
        }
        // Against the exact sphere: its points and its distance.
        let exact = IndexedSurface::new(&a, &a.bounds())
            .unwrap()
            .distance_to_reference(1000, &surface_samples(&b, 1000).unwrap(), |p| (p.length() - 0.3).abs())
            .unwrap();
        assert!((exact.mean - want.mean).abs() < 1e-3, "{exact:?} vs {want:?}");
        assert!((exact.hausdorff - 0.1).abs() < 3e-3 && exact.hausdorff >= 0.1 - 1e-3, "{exact:?}");
        let empty = IndexedSurface::new(&a, &a.bounds()).unwrap().distance_to_reference(10, &[], |_| 0.0);
        assert_eq!(empty, Err(DistanceError::EmptySurface { which: "second" }));
    }

    #[test]
    fn samples_are_area_uniform() {
        // Two triangles of area 1 and 3: the counts must follow the areas.
        let mesh = TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 5.0),
                Vec3::new(3.0, 0.0, 5.0),
                Vec3::new(0.0, 2.0, 5.0),
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        )
        .unwrap();
        let points = surface_samples(&mesh, 400).unwrap();
        let on_first = points[..400].iter().filter(|p| p.z == 0.0).count();
        assert_eq!(on_first, 100);
        assert!(points[..400].iter().all(|p| p.x >= 0.0 && p.y >= 0.0));
    }

    #[test]
    fn empty_surfaces_are_errors() {
        let flat = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], vec![[0, 1, 2]]).unwrap();
        let m = sphere(0.3, 16);
        assert_eq!(surface_distance(&m, &flat, 10), Err(DistanceError::EmptySurface { which: "second" }));
        assert_eq!(
            surface_distance(&TriMesh::default(), &m, 10),
            Err(DistanceError::EmptySurface { which: "first" })
        );
    }
}
