//! Affine maps split into translation · rotation · stretch, and their
//! interpolation over time (Breen & Whitaker eq. 25–26, Yang & Jüttler eq. 11).
//!
//! A map `x ↦ M x + c` with `det M > 0` is decomposed by the polar
//! decomposition `M = R S` (`R` a rotation, `S` symmetric positive definite:
//! the *stretch*, which is `diag(scale)` when `M` has no shear). Interpolation
//! lerps the translation and the stretch and slerps the rotation, so a pure
//! rotation turns at constant speed, a pure scale changes linearly, and both
//! endpoints are reproduced.

use glam::{Affine3A, Mat3, Quat, Vec3};

/// Why a map cannot be decomposed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TransformError {
    /// The linear part is singular (or nearly: smallest singular value ≤ 1e-12
    /// of the largest) or not finite.
    #[error("the affine map is singular or not finite")]
    Singular,
    /// The map mirrors space (`det < 0`); mirrors cannot be reached continuously
    /// from the identity, so they cannot be interpolated.
    #[error("the affine map is a reflection (negative determinant); it cannot be interpolated")]
    Reflection,
}

/// An affine map as translation · rotation · stretch: `x ↦ t + R (S x)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AffineParts {
    /// Translation (world units).
    pub translation: Vec3,
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Symmetric positive definite stretch applied before the rotation.
    pub stretch: Mat3,
}

impl AffineParts {
    /// The identity map.
    pub const IDENTITY: AffineParts =
        AffineParts { translation: Vec3::ZERO, rotation: Quat::IDENTITY, stretch: Mat3::IDENTITY };

    /// Polar decomposition of `map`.
    ///
    /// # Errors
    /// [`TransformError::Singular`] or [`TransformError::Reflection`].
    pub fn from_affine(map: &Affine3A) -> Result<Self, TransformError> {
        if !map.is_finite() {
            return Err(TransformError::Singular);
        }
        let m = map.matrix3;
        let cols = [m.x_axis, m.y_axis, m.z_axis];
        let mat = nalgebra::Matrix3::from_fn(|r, c| cols[c][r] as f64);
        let svd = mat.svd(true, true);
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
            return Err(TransformError::Singular);
        };
        let (smax, smin) = (svd.singular_values.max(), svd.singular_values.min());
        if smin.is_nan() || smin <= smax * 1e-12 {
            return Err(TransformError::Singular);
        }
        if mat.determinant() < 0.0 {
            return Err(TransformError::Reflection);
        }
        let rot = u * v_t;
        let stretch = v_t.transpose() * nalgebra::Matrix3::from_diagonal(&svd.singular_values) * v_t;
        let to_glam = |a: &nalgebra::Matrix3<f64>| {
            Mat3::from_cols_array(&std::array::from_fn(|i| a[(i % 3, i / 3)] as f32))
        };
        let rotation = Quat::from_mat3(&to_glam(&rot)).normalize();
        let s = to_glam(&stretch);
        // Symmetrize away rounding.
        let stretch = Mat3::from_cols_array(&std::array::from_fn(|i| {
            let (r, c) = (i % 3, i / 3);
            0.5 * (s.col(c)[r] + s.col(r)[c])
        }));
        Ok(Self { translation: Vec3::from(map.translation), rotation, stretch })
    }

    /// The map `x ↦ t + R S x`.
    pub fn to_affine(&self) -> Affine3A {
        Affine3A::from_mat3_translation(Mat3::from_quat(self.rotation) * self.stretch, self.translation)
    }

    /// The diagonal of the stretch: per-axis scale when the map has no shear.
    pub fn scale(&self) -> Vec3 {
        Vec3::new(self.stretch.x_axis.x, self.stretch.y_axis.y, self.stretch.z_axis.z)
    }

    /// Interpolation at `t ∈ [0, 1]`: translation and stretch linearly,
    /// rotation by spherical linear interpolation (shortest arc).
    pub fn lerp(&self, other: &AffineParts, t: f32) -> AffineParts {
        AffineParts {
            translation: self.translation.lerp(other.translation, t),
            rotation: self.rotation.slerp(other.rotation, t).normalize(),
            stretch: self.stretch * (1.0 - t) + other.stretch * t,
        }
    }
}

/// A time-dependent affine map `T(x, t)` between two maps, as Breen's eq. 25
/// uses to place each frame: `at(0)` is the start map, `at(1)` the end map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AffinePath {
    start: AffineParts,
    end: AffineParts,
}

impl AffinePath {
    /// The path from `start` to `end`.
    ///
    /// # Errors
    /// When either map is singular or a reflection.
    pub fn new(start: &Affine3A, end: &Affine3A) -> Result<Self, TransformError> {
        Ok(Self { start: AffineParts::from_affine(start)?, end: AffineParts::from_affine(end)? })
    }

    /// The path from the identity to `end` (Breen's `T(x, α)`).
    ///
    /// # Errors
    /// When `end` is singular or a reflection.
    pub fn from_identity(end: &Affine3A) -> Result<Self, TransformError> {
        Self::new(&Affine3A::IDENTITY, end)
    }

    /// The map at time `t` (clamped to `[0, 1]`; the endpoints are reproduced).
    pub fn at(&self, t: f32) -> Affine3A {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        self.start.lerp(&self.end, t).to_affine()
    }

    /// The decomposed start and end maps.
    pub fn parts(&self) -> (AffineParts, AffineParts) {
        (self.start, self.end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f32::consts::FRAC_PI_2;

    fn close(a: &Affine3A, b: &Affine3A, tol: f32) -> bool {
        a.abs_diff_eq(*b, tol)
    }

    #[test]
    fn rotation_and_scale_interpolate_as_parts() {
        let end = Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 3.0, 4.0),
            Quat::from_rotation_z(FRAC_PI_2),
            Vec3::new(1.0, 0.0, -2.0),
        );
        let path = AffinePath::from_identity(&end).unwrap();
        assert!(close(&path.at(0.0), &Affine3A::IDENTITY, 1e-6));
        assert!(close(&path.at(1.0), &end, 1e-5));
        let mid = AffineParts::from_affine(&path.at(0.5)).unwrap();
        assert!(mid.rotation.abs_diff_eq(Quat::from_rotation_z(FRAC_PI_2 / 2.0), 1e-5));
        assert!(mid.scale().abs_diff_eq(Vec3::new(1.5, 2.0, 2.5), 1e-5));
        assert!(mid.translation.abs_diff_eq(Vec3::new(0.5, 0.0, -1.0), 1e-6));
    }

    #[test]
    fn bad_maps_are_errors() {
        let flat = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(AffineParts::from_affine(&flat), Err(TransformError::Singular));
        let mirror = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        assert_eq!(AffineParts::from_affine(&mirror), Err(TransformError::Reflection));
        let nan = Affine3A::from_translation(Vec3::NAN);
        assert_eq!(AffineParts::from_affine(&nan), Err(TransformError::Singular));
        let path = AffinePath::from_identity(&Affine3A::from_translation(Vec3::X)).unwrap();
        assert!(close(&path.at(f32::NAN), &Affine3A::IDENTITY, 0.0));
        assert!(close(&path.at(7.0), &Affine3A::from_translation(Vec3::X), 1e-6));
    }

    proptest! {
        /// Decomposition reproduces any orientation-preserving map, sheared or not,
        /// and interpolation hits both endpoints.
        #[test]
        fn decomposition_roundtrips(
            axis in (-1.0f32..1.0, -1.0f32..1.0, 0.1f32..1.0),
            angle in -3.0f32..3.0,
            scale in (0.2f32..3.0, 0.2f32..3.0, 0.2f32..3.0),
            shear in -0.5f32..0.5,
            offset in (-5.0f32..5.0, -5.0f32..5.0, -5.0f32..5.0),
        ) {
            let rot = Quat::from_axis_angle(Vec3::from(axis).normalize(), angle);
            let sheared = Mat3::from_cols(Vec3::X, Vec3::new(shear, 1.0, 0.0), Vec3::Z);
            let m = Mat3::from_quat(rot) * Mat3::from_diagonal(Vec3::from(scale)) * sheared;
            let map = Affine3A::from_mat3_translation(m, Vec3::from(offset));
            let parts = AffineParts::from_affine(&map).unwrap();
            prop_assert!(close(&parts.to_affine(), &map, 1e-4), "{:?} vs {:?}", parts.to_affine(), map);
            let path = AffinePath::from_identity(&map).unwrap();
            prop_assert!(close(&path.at(1.0), &map, 1e-4));
            prop_assert!(close(&path.at(0.0), &Affine3A::IDENTITY, 1e-6));
            // Every in-between map stays orientation preserving and non-singular.
            prop_assert!(path.at(0.5).matrix3.determinant() > 0.0);
        }
    }
}
