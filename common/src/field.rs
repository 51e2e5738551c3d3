//! Scalar fields in 3D: the one interface every shape representation shares.

use crate::Aabb;
use glam::{UVec3, Vec3};

/// Step (world units) of the default central-difference [`Field3::gradient`].
pub const GRADIENT_STEP: f32 = 1e-3;

/// A scalar field over world space, **positive inside**, zero on the surface
/// and negative outside (fields with another iso level say so in their docs).
///
/// Closures `Fn(Vec3) -> f32 + Sync` are fields; grids, analytic shapes and
/// every method's frames implement it too.
///
/// ```
/// use glam::Vec3;
/// use isomorph_common::Field3;
///
/// let ball = |p: Vec3| 0.5 - p.length(); // signed distance, positive inside
/// assert!(ball.value(Vec3::ZERO) > 0.0);
/// let g = ball.gradient(Vec3::new(0.25, 0.0, 0.0));
/// assert!((g - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-2); // points inward
/// ```
pub trait Field3: Sync {
    /// The field value at `p` (world units for distance fields).
    fn value(&self, p: Vec3) -> f32;

    /// The gradient at `p`; it points *into* the shape (towards larger
    /// values). The default uses central differences with step
    /// [`GRADIENT_STEP`]; implementations with an analytic gradient override it.
    fn gradient(&self, p: Vec3) -> Vec3 {
        let h = GRADIENT_STEP;
        let dx = self.value(p + Vec3::X * h) - self.value(p - Vec3::X * h);
        let dy = self.value(p + Vec3::Y * h) - self.value(p - Vec3::Y * h);
        let dz = self.value(p + Vec3::Z * h) - self.value(p - Vec3::Z * h);
        Vec3::new(dx, dy, dz) / (2.0 * h)
    }

    /// Evaluates the field at every point of `points` into `out`.
    ///
    /// Override this for speed (vectorized or shared-setup evaluation); the
    /// hot loops of the library (grid fill, polygonizers) call it in batches.
    ///
    /// # Panics
    /// If `points` and `out` differ in length.
    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "values: points and out differ in length");
        for (o, &p) in out.iter_mut().zip(points) {
            *o = self.value(p);
        }
    }

    /// A box outside of which the field is known to be negative (no surface),
    /// when the field has one.
    fn bounds(&self) -> Option<Aabb> {
        None
    }

    /// Bounds `[lo, hi]` on the field's values over the closed box `region`
    /// (every `value(p)` with `p` in `region` satisfies `lo ≤ value(p) ≤ hi`),
    /// when the field can prove them cheaply; `None` (the default) when it
    /// cannot. The sparse polygonizer
    /// ([`polygonize_near_surface`](crate::marching_cubes::polygonize_near_surface))
    /// skips a block with no further evaluation when these bounds keep the
    /// iso value out, and otherwise refines it: a field whose slope its
    /// samples cannot estimate (flat outside a compact support, such as a
    /// BlobTree) should implement this so that no surface is lost.
    ///
    /// The bounds must be *sound* (they may be loose, never too tight); an
    /// empty `region` may return anything.
    fn range(&self, region: &Aabb) -> Option<[f32; 2]> {
        let _ = region;
        None
    }

    /// Evaluates the field at every node of the lattice of `dims` nodes at
    /// `origin + spacing·(i, j, k)` into `out`, `i` fastest then `j`, `k`
    /// (the layout of [`Grid3`](crate::Grid3)).
    ///
    /// The default calls [`Field3::values`] once per row of `dims.x` nodes,
    /// rows in parallel ([`values_by_rows`](crate::values_by_rows));
    /// fields that can share work across a whole lattice (e.g. a fast
    /// summation over many centres) override it.
    ///
    /// # Panics
    /// If `out` does not hold `dims.x · dims.y · dims.z` values.
    fn values_on_lattice(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        crate::grid::values_by_rows(self, dims, origin, spacing, out);
    }

    /// This field sampled in a narrow band of bricks: what
    /// [`Bricks::sample_band`](crate::Bricks::sample_band) returns (see
    /// there; meaningful for fields whose value changes by at most the
    /// distance moved, such as exact signed distances, in world units).
    /// The default evaluates one value per brick and every node of the
    /// band bricks ([`Bricks::sample_band_by_points`](crate::Bricks::sample_band_by_points));
    /// fields that can share work over a brick (a mesh's lattice search)
    /// override it.
    ///
    /// # Errors
    /// As [`Bricks::new`](crate::Bricks::new).
    fn band_bricks(
        &self,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<crate::Bricks<f32>, crate::GridError> {
        crate::Bricks::sample_band_by_points(self, dims, origin, spacing, band)
    }
}

impl<F> Field3 for F
where
    F: Fn(Vec3) -> f32 + Sync,
{
    fn value(&self, p: Vec3) -> f32 {
        self(p)
    }
}

impl Field3 for Box<dyn Field3 + '_> {
    fn value(&self, p: Vec3) -> f32 {
        (**self).value(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        (**self).gradient(p)
    }
    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        (**self).values(points, out)
    }
    fn values_on_lattice(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        (**self).values_on_lattice(dims, origin, spacing, out)
    }
    fn band_bricks(
        &self,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<crate::Bricks<f32>, crate::GridError> {
        (**self).band_bricks(dims, origin, spacing, band)
    }
    fn bounds(&self) -> Option<Aabb> {
        (**self).bounds()
    }
    fn range(&self, region: &Aabb) -> Option<[f32; 2]> {
        (**self).range(region)
    }
}

/// A field with a stated bounding box: wraps a closure (or any field) so that
/// [`Field3::bounds`] reports `bounds`.
#[derive(Debug, Clone)]
pub struct Bounded<F> {
    /// The wrapped field.
    pub field: F,
    /// The box reported by [`Field3::bounds`].
    pub bounds: Aabb,
}

impl<F: Field3> Field3 for Bounded<F> {
    fn value(&self, p: Vec3) -> f32 {
        self.field.value(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.field.gradient(p)
    }
    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        self.field.values(points, out)
    }
    fn values_on_lattice(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        self.field.values_on_lattice(dims, origin, spacing, out)
    }
    fn band_bricks(
        &self,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<crate::Bricks<f32>, crate::GridError> {
        self.field.band_bricks(dims, origin, spacing, band)
    }
    fn bounds(&self) -> Option<Aabb> {
        Some(self.bounds)
    }
    fn range(&self, region: &Aabb) -> Option<[f32; 2]> {
        self.field.range(region)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closure_batch_matches_pointwise() {
        let f = |p: Vec3| p.x * 2.0 - p.y;
        let pts = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 3.0, 0.0)];
        let mut out = [0.0; 3];
        f.values(&pts, &mut out);
        assert_eq!(out, [0.0, 2.0, -1.0]);
        let g = f.gradient(Vec3::ZERO);
        assert!((g - Vec3::new(2.0, -1.0, 0.0)).length() < 1e-3, "{g}");
    }

    #[test]
    fn boxed_and_bounded_fields_forward() {
        let b: Box<dyn Field3> = Box::new(|p: Vec3| 1.0 - p.length());
        assert_eq!(b.value(Vec3::ZERO), 1.0);
        let bounded = Bounded { field: b, bounds: Aabb::cube(1.0) };
        assert_eq!(bounded.bounds(), Some(Aabb::cube(1.0)));
        assert_eq!(bounded.value(Vec3::X), 0.0);
    }
}
