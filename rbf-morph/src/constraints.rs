//! Boundary and normal constraints of a 3D shape from points with normals
//! (paper §4.2): a boundary constraint `f = 0` at each surface point and a
//! normal constraint `f = 1` a small distance inward along the normal.
//!
//! # Validated offsets
//! A normal constraint placed `k` inward from a point of a thin part (a
//! dragon's claw, a fin, the lip of a cup) can land nearer the *opposite*
//! side of the surface than its own point, or beyond it: the interpolant
//! then has to climb from 0 to 1 over a fraction of `k` between two
//! unrelated constraints, which makes the system ill-conditioned (huge,
//! cancelling weights) and puts spurious sign changes (stray bubbles) near
//! thin parts. Turk & O'Brien and FastRBF place the normal constraints at a
//! small offset on purpose; the offset must stay below the local feature
//! size. So every normal constraint is validated against all input surface
//! points of the other side (whose normals face away from its own,
//! `n_j · n_i < 0`; neighbours on the same sheet do not count, so smooth and
//! convex parts keep the offset `k`): its offset is halved (down to
//! `k / 16`) until no such point is as near to it as its own point, and a
//! normal constraint that fails even at `k / 16` is dropped (its boundary
//! constraint stays).

use crate::error::RbfError;
use crate::interpolant::Constraint;
use glam::Vec3;
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Aabb, Field3, TriMesh};
use rayon::prelude::*;

/// How far inward the normal constraint sits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalOffset {
    /// `k ·` the diagonal of the points' bounding box (the paper uses
    /// `k = 0.01` for models in a unit cube).
    RelativeToDiagonal(f32),
    /// A fixed distance in world units.
    Absolute(f32),
}

/// Which surface points become constraints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Subsample {
    /// Every point.
    #[default]
    All,
    /// `count` points at evenly spaced indices (cheap; follows the input order).
    Uniform(usize),
    /// `count` points by greedy farthest-point sampling from the first point
    /// (even coverage of the surface, `O(n · count)`).
    FarthestPoint(usize),
}

/// Settings of [`surface_constraints`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceSettings {
    /// Inward offset of the normal constraints (default `k = 0.01` of the
    /// bounding-box diagonal).
    pub offset: NormalOffset,
    /// Point selection (default all points).
    pub subsample: Subsample,
}

impl Default for SurfaceSettings {
    fn default() -> Self {
        Self { offset: NormalOffset::RelativeToDiagonal(0.01), subsample: Subsample::All }
    }
}

/// Constraints from surface `points` with **outward** `normals`: for each
/// selected point a boundary constraint (0) at the point and, after it, a
/// normal constraint (1) at `point − k_i · normal` (§4.2), where `k_i` is
/// the offset `k` halved until no point of the other side (normal facing
/// away) is as near to it as its own point (see [the module docs](self);
/// dropped below `k / 16`). Normals need
/// not be unit length.
///
/// # Errors
/// [`RbfError::InvalidInput`] when the lengths differ or a normal is zero or
/// non-finite, or the offset is not positive; [`RbfError::NonFinite`] for a
/// non-finite point; [`RbfError::EmptyShape`] for no points.
pub fn surface_constraints(
    points: &[Vec3],
    normals: &[Vec3],
    settings: &SurfaceSettings,
) -> Result<Vec<Constraint<3>>, RbfError> {
    if points.len() != normals.len() {
        return Err(RbfError::InvalidInput(format!("{} points but {} normals", points.len(), normals.len())));
    }
    if points.is_empty() {
        return Err(RbfError::EmptyShape("input"));
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(RbfError::NonFinite { index, what: "position" });
    }
    let k = match settings.offset {
        NormalOffset::RelativeToDiagonal(k) => k * Aabb::from_points(points).diagonal(),
        NormalOffset::Absolute(k) => k,
    };
    if !(k > 0.0 && k.is_finite()) {
        return Err(RbfError::InvalidInput(format!("the normal offset must be positive, got {k}")));
    }
    let chosen = select(points, settings.subsample);
    let mut units = Vec::with_capacity(chosen.len());
    for &i in &chosen {
        let n = normals[i].normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() {
            return Err(RbfError::InvalidInput(format!("normal {i} is zero or not finite")));
        }
        units.push(n);
    }
    let hash = PointHash::new(points, normals, k);
    let offsets: Vec<Option<f32>> =
        chosen.par_iter().zip(&units).map(|(&i, &n)| valid_offset(&hash, i, n, k)).collect();
    let mut out = Vec::with_capacity(2 * chosen.len());
    for ((&i, n), offset) in chosen.iter().zip(units).zip(offsets) {
        out.push(Constraint::new(points[i].to_array(), 0.0));
        if let Some(k) = offset {
            out.push(Constraint::new((points[i] - k * n).to_array(), 1.0));
        }
    }
    Ok(out)
}

/// Halvings of the normal offset tried before a normal constraint is
/// dropped (down to `k / 16`).
const OFFSET_HALVINGS: u32 = 4;

/// The largest of `k, k/2, …, k/16` at which no point of the other side
/// (normal facing away from `n`) is as near to `points[i] − k_i · n` as
/// `points[i]`, or `None`.
fn valid_offset(hash: &PointHash<'_>, i: usize, n: Vec3, k: f32) -> Option<f32> {
    let origin = hash.points[i];
    (0..=OFFSET_HALVINGS).map(|h| k / (1u32 << h) as f32).find(|&k| {
        let q = origin - k * n;
        let own = q.distance_squared(origin);
        !hash.any_within(q, own.sqrt(), |p, normal| normal.dot(n) < 0.0 && q.distance_squared(p) <= own)
    })
}

/// Points bucketed in cubic cells of side `cell` (a uniform spatial hash),
/// for queries within a radius of at most `cell`.
struct PointHash<'a> {
    points: &'a [Vec3],
    normals: &'a [Vec3],
    cell: f32,
    buckets: std::collections::HashMap<[i32; 3], Vec<u32>>,
}

impl<'a> PointHash<'a> {
    fn new(points: &'a [Vec3], normals: &'a [Vec3], cell: f32) -> Self {
        let mut buckets = std::collections::HashMap::<[i32; 3], Vec<u32>>::new();
        for (j, &p) in points.iter().enumerate() {
            buckets.entry(Self::key(p, cell)).or_default().push(j as u32);
        }
        Self { points, normals, cell, buckets }
    }

    fn key(p: Vec3, cell: f32) -> [i32; 3] {
        (p / cell).floor().as_ivec3().to_array()
    }

    /// Whether `test(point, normal)` holds for a point within `radius` (≤
    /// the cell side) of `q` or in a cell touching that ball.
    fn any_within(&self, q: Vec3, radius: f32, test: impl Fn(Vec3, Vec3) -> bool) -> bool {
        let (lo, hi) =
            (Self::key(q - Vec3::splat(radius), self.cell), Self::key(q + Vec3::splat(radius), self.cell));
        (lo[2]..=hi[2]).any(|z| {
            (lo[1]..=hi[1]).any(|y| {
                (lo[0]..=hi[0]).any(|x| {
                    self.buckets.get(&[x, y, z]).is_some_and(|b| {
                        b.iter().any(|&j| test(self.points[j as usize], self.normals[j as usize]))
                    })
                })
            })
        })
    }
}

/// Constraints from the vertices of `mesh` and its area-weighted vertex
/// normals (triangles counter-clockwise seen from outside).
///
/// # Errors
/// As [`surface_constraints`]; a vertex without any triangle has a zero
/// normal and is an [`RbfError::InvalidInput`].
pub fn mesh_constraints(mesh: &TriMesh, settings: &SurfaceSettings) -> Result<Vec<Constraint<3>>, RbfError> {
    let normals = mesh.vertex_normals();
    surface_constraints(&mesh.positions, &normals, settings)
}

/// Constraints of the zero level set of a field (positive inside): the
/// surface polygonized with `res` nodes along the longest edge of `bounds`,
/// its vertices with the field's outward normals `−∇f/|∇f|`.
///
/// # Errors
/// Grid errors of the polygonizer, [`RbfError::EmptyShape`] when the field
/// has no surface in `bounds`, and those of [`surface_constraints`].
pub fn field_constraints<F: Field3 + ?Sized>(
    field: &F,
    bounds: &Aabb,
    res: u32,
    settings: &SurfaceSettings,
) -> Result<Vec<Constraint<3>>, RbfError> {
    let mesh = polygonize(field, bounds, res, 0.0)?;
    if mesh.positions.is_empty() {
        return Err(RbfError::EmptyShape("field"));
    }
    let normals: Vec<Vec3> = mesh.positions.par_iter().map(|&p| -field.gradient(p)).collect();
    surface_constraints(&mesh.positions, &normals, settings)
}

/// Indices of the selected points.
fn select(points: &[Vec3], subsample: Subsample) -> Vec<usize> {
    let n = points.len();
    match subsample {
        Subsample::All => (0..n).collect(),
        Subsample::Uniform(count) if count >= n => (0..n).collect(),
        Subsample::Uniform(count) => (0..count).map(|i| i * n / count).collect(),
        Subsample::FarthestPoint(count) if count >= n => (0..n).collect(),
        Subsample::FarthestPoint(count) => farthest_points(points, count),
    }
}

/// Greedy farthest-point sampling of `count < points.len()` points.
fn farthest_points(points: &[Vec3], count: usize) -> Vec<usize> {
    let mut chosen = Vec::with_capacity(count);
    if count == 0 {
        return chosen;
    }
    let mut dist = vec![f32::INFINITY; points.len()];
    let mut next = 0usize;
    for _ in 0..count {
        chosen.push(next);
        let c = points[next];
        next = dist
            .par_iter_mut()
            .zip(points.par_iter())
            .enumerate()
            .map(|(i, (d, p))| {
                *d = d.min(p.distance_squared(c));
                (i, *d)
            })
            .reduce(
                || (0, f32::NEG_INFINITY),
                |a, b| if b.1 > a.1 || (b.1 == a.1 && b.0 < a.0) { b } else { a },
            )
            .0;
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::Shape;

    #[test]
    fn sphere_constraints_sit_on_and_inside_the_surface() {
        let settings =
            SurfaceSettings { offset: NormalOffset::Absolute(0.01), subsample: Subsample::FarthestPoint(50) };
        let cs = field_constraints(&Shape::sphere(0.3), &Aabb::cube(0.5), 20, &settings).unwrap();
        assert_eq!(cs.len(), 100);
        for pair in cs.chunks(2) {
            let b = Vec3::from_array(pair[0].position);
            let n = Vec3::from_array(pair[1].position);
            assert_eq!((pair[0].value, pair[1].value), (0.0, 1.0));
            assert!((b.length() - 0.3).abs() < 0.01, "{b}");
            assert!((b.length() - n.length() - 0.01).abs() < 1e-3, "{b} {n}");
        }
        // Farthest-point samples spread out: no two boundary points closer than
        // a fraction of the even spacing on the sphere.
        let min = cs
            .iter()
            .step_by(2)
            .enumerate()
            .flat_map(|(i, a)| cs.iter().step_by(2).skip(i + 1).map(move |b| (a, b)))
            .map(|(a, b)| Vec3::from_array(a.position).distance(Vec3::from_array(b.position)))
            .fold(f32::INFINITY, f32::min);
        assert!(min > 0.05, "closest pair {min}");
    }

    #[test]
    fn uniform_subsample_and_errors() {
        let pts = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        let nrm = vec![Vec3::X; 4];
        let s = SurfaceSettings { subsample: Subsample::Uniform(2), ..Default::default() };
        let cs = surface_constraints(&pts, &nrm, &s).unwrap();
        assert_eq!(cs.len(), 4);
        assert_eq!(cs[2].position, [0.0, 0.0, 1.0]);
        let d = Aabb::from_points(&pts).diagonal() * 0.01;
        assert!((cs[1].position[0] - (1.0 - d)).abs() < 1e-6);
        assert!(matches!(surface_constraints(&pts, &nrm[..3], &s), Err(RbfError::InvalidInput(_))));
        let zero = vec![Vec3::ZERO; 4];
        assert!(matches!(surface_constraints(&pts, &zero, &s), Err(RbfError::InvalidInput(_))));
        assert!(matches!(surface_constraints(&[], &[], &s), Err(RbfError::EmptyShape(_))));
        let far = |p: Vec3| -1.0 - p.length();
        assert!(matches!(field_constraints(&far, &Aabb::cube(0.5), 8, &s), Err(RbfError::EmptyShape(_))));
    }
}
