//! [`Camera`]: a perspective pinhole camera and automatic framing.

use glam::Vec3;
use isomorph_common::Aabb;

/// A perspective pinhole camera in world space.
///
/// The field of view spans the *shorter* side of the image, so a camera that
/// frames a box frames it at any aspect ratio. Degenerate values (eye on the
/// target, `up` along the view, a non-finite or out-of-range field of view)
/// are repaired when rendering rather than rejected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Position of the eye (centre of projection).
    pub eye: Vec3,
    /// Point the camera looks at; it appears at the image centre.
    pub target: Vec3,
    /// Approximate up direction; it appears vertical in the image.
    pub up: Vec3,
    /// Field of view across the shorter image side, in radians (clamped to
    /// `[0.01, 3.0]` when rendering).
    pub fov: f32,
}

impl Camera {
    /// The default field of view: 30° (mild perspective).
    pub const DEFAULT_FOV: f32 = std::f32::consts::PI / 6.0;

    /// The default side to look from: front-right and above, for +y up
    /// shapes (the built-in shapes and the bunny); a three-quarter view that
    /// shows three faces of a cube.
    pub const DEFAULT_VIEW_DIR: Vec3 = Vec3::new(1.0, 0.8, 1.4);

    /// Fraction of the half-image the framed box may fill (the rest is margin).
    const FILL: f32 = 0.9;

    /// A camera at `eye` looking at `target` with +y up and the default field
    /// of view.
    pub fn look_at(eye: Vec3, target: Vec3) -> Self {
        Self { eye, target, up: Vec3::Y, fov: Self::DEFAULT_FOV }
    }

    /// A camera that looks at the centre of `bounds` from the direction
    /// `view_dir` (pointing from the box *towards the eye*, need not be unit)
    /// with +y up, as close as it can while every corner of the box stays
    /// inside the image with a margin of about 5 % on each side.
    ///
    /// An empty or non-finite box is replaced by the unit cube `[-0.5, 0.5]³`,
    /// a flat or point-like one is thickened; a zero or non-finite `view_dir`
    /// falls back to [`Camera::DEFAULT_VIEW_DIR`].
    pub fn fit(bounds: &Aabb, view_dir: Vec3) -> Self {
        let bounds = if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            Aabb::cube(0.5)
        } else {
            // A point or a sheet still needs some depth to frame.
            let thickness = (bounds.diagonal() * 1e-3).max(1e-6);
            let pad = (Vec3::splat(thickness) - bounds.size()).max(Vec3::ZERO) * 0.5;
            Aabb::new(bounds.min - pad, bounds.max + pad)
        };
        let back = view_dir.normalize_or(Self::DEFAULT_VIEW_DIR.normalize());
        let basis = ViewBasis::new(-back, Vec3::Y);
        let center = bounds.center();
        let tan_half = (0.5 * Self::DEFAULT_FOV).tan() * Self::FILL;
        // A corner at lateral offset (x, y) and height z towards the eye is
        // inside the image when max(|x|, |y|) ≤ tan_half · (distance − z).
        let distance = bounds
            .corners()
            .iter()
            .map(|&c| {
                let v = basis.coordinates(c - center);
                -v.z + v.x.abs().max(v.y.abs()) / tan_half
            })
            .fold(0.0, f32::max);
        Self { eye: center + back * distance, target: center, up: Vec3::Y, fov: Self::DEFAULT_FOV }
    }

    /// [`Camera::fit`] from [`Camera::DEFAULT_VIEW_DIR`].
    pub fn fit_default(bounds: &Aabb) -> Self {
        Self::fit(bounds, Self::DEFAULT_VIEW_DIR)
    }
}

/// Orthonormal camera axes: `right`, `up`, and `forward` (the view direction).
#[derive(Debug, Clone, Copy)]
pub(super) struct ViewBasis {
    pub(super) right: Vec3,
    pub(super) up: Vec3,
    pub(super) forward: Vec3,
}

impl ViewBasis {
    /// Axes for looking along `forward` with `up` vertical; a degenerate
    /// `forward` becomes −z and an `up` along `forward` is replaced by
    /// another perpendicular direction.
    pub(super) fn new(forward: Vec3, up: Vec3) -> Self {
        let forward = forward.normalize_or(Vec3::NEG_Z);
        let right = forward.cross(up).try_normalize().unwrap_or_else(|| forward.any_orthonormal_vector());
        Self { right, up: right.cross(forward), forward }
    }

    /// Components of `v` along `right`, `up` and `forward`.
    pub(super) fn coordinates(self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;
    use proptest::prelude::*;

    /// Projects `p` with `camera` to normalized image coordinates in
    /// `[-1, 1]` across the shorter side.
    fn project(camera: &Camera, p: Vec3) -> Vec2 {
        let basis = ViewBasis::new(camera.target - camera.eye, camera.up);
        let v = basis.coordinates(p - camera.eye);
        v.truncate() / (v.z * (0.5 * camera.fov).tan())
    }

    proptest! {
        #[test]
        fn fit_keeps_every_corner_inside_with_a_small_margin(
            min in proptest::array::uniform3(-100.0f32..100.0),
            size in proptest::array::uniform3(0.01f32..50.0),
            dir in proptest::array::uniform3(-1.0f32..1.0),
        ) {
            let bounds = Aabb::new(Vec3::from(min), Vec3::from(min) + Vec3::from(size));
            let camera = Camera::fit(&bounds, Vec3::from(dir));
            let extent = bounds
                .corners()
                .iter()
                .map(|&c| project(&camera, c).abs().max_element())
                .fold(0.0, f32::max);
            prop_assert!(extent <= Camera::FILL + 1e-4, "corner outside the image: {}", extent);
            prop_assert!(extent > 0.75 * Camera::FILL, "box too small in the image: {}", extent);
        }
    }

    #[test]
    fn fit_repairs_degenerate_input() {
        let camera = Camera::fit(&Aabb::EMPTY, Vec3::NAN);
        assert!(camera.eye.is_finite() && camera.target == Vec3::ZERO);
        let point = Aabb::new(Vec3::ONE, Vec3::ONE);
        let camera = Camera::fit(&point, Vec3::ZERO);
        assert!(camera.eye.is_finite() && camera.eye.distance(Vec3::ONE) > 0.0);
    }

    #[test]
    fn basis_is_orthonormal_even_looking_straight_down() {
        for forward in [Vec3::NEG_Y, Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO] {
            let b = ViewBasis::new(forward, Vec3::Y);
            for (u, v) in [(b.right, b.up), (b.up, b.forward), (b.forward, b.right)] {
                assert!(u.dot(v).abs() < 1e-6);
                assert!((u.length() - 1.0).abs() < 1e-6);
            }
        }
    }
}
