//! Axis-aligned bounding boxes in world space.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// An axis-aligned box `[min, max]` in world units.
///
/// A box with `min > max` on any axis is *empty*; [`Aabb::EMPTY`] is the
/// identity of [`Aabb::union`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (contains nothing; union identity).
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// The box `[min, max]` (corners taken as given).
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The cube `[-half, half]³` centred on the origin.
    pub fn cube(half: f32) -> Self {
        Self::new(Vec3::splat(-half), Vec3::splat(half))
    }

    /// The smallest box containing all `points` ([`Aabb::EMPTY`] if none).
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.including(p))
    }

    /// True when the box contains no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Edge lengths (zero for an empty box).
    pub fn size(&self) -> Vec3 {
        if self.is_empty() { Vec3::ZERO } else { self.max - self.min }
    }

    /// Centre point.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Length of the main diagonal (zero for an empty box).
    pub fn diagonal(&self) -> f32 {
        self.size().length()
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The box grown to contain `p`.
    pub fn including(&self, p: Vec3) -> Self {
        Self::new(self.min.min(p), self.max.max(p))
    }

    /// Smallest box containing both boxes.
    pub fn union(&self, other: &Aabb) -> Self {
        Self::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// Overlap of both boxes (possibly empty).
    pub fn intersection(&self, other: &Aabb) -> Self {
        Self::new(self.min.max(other.min), self.max.min(other.max))
    }

    /// The box grown by `margin` world units on every side.
    pub fn expanded(&self, margin: f32) -> Self {
        Self::new(self.min - Vec3::splat(margin), self.max + Vec3::splat(margin))
    }

    /// The box grown by `fraction` of its own extent on every side, per axis
    /// (`0.1` pads 10 % per side, as the distance-volume tools use).
    pub fn padded(&self, fraction: f32) -> Self {
        let pad = self.size() * fraction;
        Self::new(self.min - pad, self.max + pad)
    }

    /// Squared Euclidean distance from `p` to the box (zero inside).
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.length_squared()
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// The box containing the image of this box under an affine map.
    pub fn transformed(&self, map: &glam::Affine3A) -> Self {
        if self.is_empty() {
            return *self;
        }
        let corners = self.corners().map(|c| map.transform_point3(c));
        Self::from_points(&corners)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_and_intersection() {
        let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let b = Aabb::new(Vec3::splat(0.5), Vec3::splat(2.0));
        assert_eq!(a.union(&b), Aabb::new(Vec3::ZERO, Vec3::splat(2.0)));
        assert_eq!(a.intersection(&b), Aabb::new(Vec3::splat(0.5), Vec3::ONE));
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.union(&a), a);
        let far = Aabb::new(Vec3::splat(3.0), Vec3::splat(4.0));
        assert!(a.intersection(&far).is_empty());
    }

    #[test]
    fn distance_to_box() {
        let a = Aabb::cube(1.0);
        assert_eq!(a.distance_squared(Vec3::ZERO), 0.0);
        assert_eq!(a.distance_squared(Vec3::new(3.0, 0.0, 0.0)), 4.0);
        assert_eq!(a.distance_squared(Vec3::new(2.0, 2.0, 0.0)), 2.0);
    }

    #[test]
    fn padding_is_per_axis_fraction() {
        let a = Aabb::new(Vec3::ZERO, Vec3::new(10.0, 1.0, 2.0)).padded(0.1);
        assert_eq!(a.min, Vec3::new(-1.0, -0.1, -0.2));
        assert_eq!(a.max, Vec3::new(11.0, 1.1, 2.2));
    }
}
