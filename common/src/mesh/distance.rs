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

use super::bvh::TriangleBvh;
use crate::TriMesh;
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
    a.validate()?;
    b.validate()?;
    let scale = a.unit_scale().min(b.unit_scale());
    let (a, b) = (&a.scaled(scale), &b.scaled(scale));
    let points_a = surface_samples(a, samples).ok_or(DistanceError::EmptySurface { which: "first" })?;
    let points_b = surface_samples(b, samples).ok_or(DistanceError::EmptySurface { which: "second" })?;
    let (sum_ab, sq_ab, max_ab) = one_sided(&points_a, &TriangleBvh::new(b));
    let (sum_ba, sq_ba, max_ba) = one_sided(&points_b, &TriangleBvh::new(a));
    let n = (points_a.len() + points_b.len()) as f64;
    let unit = 1.0 / f64::from(scale);
    Ok(SurfaceDistance {
        mean: ((sum_ab + sum_ba) / n * unit) as f32,
        rms: (((sq_ab + sq_ba) / n).sqrt() * unit) as f32,
        hausdorff: (max_ab.max(max_ba) * unit) as f32,
    })
}

/// Sum, sum of squares and maximum of the distances from `points` to `bvh`.
fn one_sided(points: &[Vec3], bvh: &TriangleBvh) -> (f64, f64, f64) {
    let mut closest = vec![None; points.len()];
    bvh.closest_many(points, &mut closest);
    closest
        .par_iter()
        .map(|c| c.map_or(0.0, |c| f64::from(c.distance_squared.max(0.0)).sqrt()))
        .fold(|| (0.0, 0.0, 0.0f64), |(s, q, m), d| (s + d, q + d * d, m.max(d)))
        .reduce(|| (0.0, 0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1, x.2.max(y.2)))
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
