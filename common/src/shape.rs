//! Analytic shapes with signed distance (positive inside), CSG and placement.
//!
//! Primitives sit at the origin in their own frame; [`Shape::translated`],
//! [`Shape::rotated`], [`Shape::scaled`] and [`Shape::transformed`] place them.
//! Distances:
//!
//! | shape | value |
//! |---|---|
//! | sphere, box (rounded), torus, capped cylinder | exact signed distance |
//! | superellipsoid (Barr) | *radial* distance: exact zero set and sign; the magnitude is the distance to the surface point on the ray from the centre, an upper bound of the Euclidean distance (equal for spheres) |
//! | union / intersection / difference | `max` / `min` / `min(a, −b)`: exact zero set, exact outside a union and inside an intersection, a bound elsewhere |
//! | placed by an affine map | local value × smallest singular value of the map: exact for rigid motions and uniform scales, a lower bound of the magnitude otherwise |
//!
//! Scan conversion to exact distance volumes (closest points on the
//! evaluated CSG surface plus fast marching) builds on these values.

use crate::{Aabb, Field3};
use glam::{Affine3A, Quat, Vec2, Vec3};

/// Problems of a shape's parameters found by [`Shape::validate`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ShapeError {
    /// A size parameter is not a positive finite number.
    #[error("{path}: {name} must be positive and finite, got {value}")]
    BadParameter {
        /// Where in the CSG tree (e.g. `union[1].difference.left`).
        path: String,
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f32,
    },
    /// A union or intersection has no child.
    #[error("{0}: a union or intersection needs at least one child")]
    EmptyOperation(String),
    /// A placement map is singular or not finite.
    #[error("{0}: the placement map is singular or not finite")]
    BadTransform(String),
}

/// An analytic solid: a primitive, a CSG combination, or a placed shape.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Shape {
    /// Ball of `radius` around the origin.
    Sphere {
        /// Radius (world units).
        radius: f32,
    },
    /// Box `[-half_extents, half_extents]` with edges rounded by `rounding`
    /// (the rounded box stays inside the unrounded one).
    Cuboid {
        /// Half edge lengths.
        half_extents: Vec3,
        /// Edge rounding radius, `0 ≤ rounding ≤ min(half_extents)`.
        rounding: f32,
    },
    /// Torus around the z axis, in the xy plane.
    Torus {
        /// Distance from the origin to the tube centre (R).
        major: f32,
        /// Tube radius (r).
        minor: f32,
    },
    /// Capped cylinder along the z axis, `|z| ≤ half_height`.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Half the height.
        half_height: f32,
    },
    /// Barr superellipsoid `((|x/a1|^(2/e2) + |y/a2|^(2/e2))^(e2/e1) + |z/a3|^(2/e1)) ≤ 1`.
    Superellipsoid {
        /// Radii `(a1, a2, a3)`.
        radii: Vec3,
        /// North–south exponent ε1 (1 = round, → 0 = square, 2 = pinched).
        e1: f32,
        /// East–west exponent ε2.
        e2: f32,
    },
    /// Points inside any child (`max`).
    Union(Vec<Shape>),
    /// Points inside every child (`min`).
    Intersection(Vec<Shape>),
    /// Points inside the first and outside the second (`min(a, −b)`).
    Difference(Box<Shape>, Box<Shape>),
    /// A shape moved by an affine map.
    Placed(Box<PlacedShape>),
}

/// A shape with its local-to-world map (see [`Shape::transformed`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedShape {
    shape: Shape,
    to_world: Affine3A,
    to_local: Affine3A,
    /// Smallest singular value of the linear part: local distances × this
    /// bound world distances from below.
    distance_scale: f32,
}

impl PlacedShape {
    /// The placed shape, in its local frame.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// Local-to-world map.
    pub fn to_world(&self) -> Affine3A {
        self.to_world
    }
}

impl Shape {
    /// Ball of `radius`.
    pub fn sphere(radius: f32) -> Self {
        Shape::Sphere { radius }
    }

    /// Box of half edge lengths `half_extents`.
    pub fn cuboid(half_extents: Vec3) -> Self {
        Shape::Cuboid { half_extents, rounding: 0.0 }
    }

    /// Box with rounded edges.
    pub fn rounded_cuboid(half_extents: Vec3, rounding: f32) -> Self {
        Shape::Cuboid { half_extents, rounding }
    }

    /// Torus in the xy plane: tube centre at distance `major`, tube radius `minor`.
    pub fn torus(major: f32, minor: f32) -> Self {
        Shape::Torus { major, minor }
    }

    /// Capped cylinder along z.
    pub fn cylinder(radius: f32, half_height: f32) -> Self {
        Shape::Cylinder { radius, half_height }
    }

    /// Barr superellipsoid with radii and exponents ε1 (north–south), ε2 (east–west).
    pub fn superellipsoid(radii: Vec3, e1: f32, e2: f32) -> Self {
        Shape::Superellipsoid { radii, e1, e2 }
    }

    /// Union with `other`.
    pub fn union(self, other: Shape) -> Self {
        match self {
            Shape::Union(mut v) => {
                v.push(other);
                Shape::Union(v)
            }
            s => Shape::Union(vec![s, other]),
        }
    }

    /// Intersection with `other`.
    pub fn intersect(self, other: Shape) -> Self {
        match self {
            Shape::Intersection(mut v) => {
                v.push(other);
                Shape::Intersection(v)
            }
            s => Shape::Intersection(vec![s, other]),
        }
    }

    /// This shape minus `other`.
    pub fn subtract(self, other: Shape) -> Self {
        Shape::Difference(Box::new(self), Box::new(other))
    }

    /// The shape moved by `map` (applied after any earlier placement).
    ///
    /// A singular map is kept and reported by [`Shape::validate`].
    pub fn transformed(self, map: Affine3A) -> Self {
        let (shape, to_world) = match self {
            Shape::Placed(p) => (p.shape, map * p.to_world),
            s => (s, map),
        };
        let to_local = to_world.inverse();
        let distance_scale = smallest_singular_value(&to_world);
        Shape::Placed(Box::new(PlacedShape { shape, to_world, to_local, distance_scale }))
    }

    /// The shape moved by `offset`.
    pub fn translated(self, offset: Vec3) -> Self {
        self.transformed(Affine3A::from_translation(offset))
    }

    /// The shape rotated about the origin.
    pub fn rotated(self, rotation: Quat) -> Self {
        self.transformed(Affine3A::from_quat(rotation))
    }

    /// The shape scaled uniformly about the origin.
    pub fn scaled(self, factor: f32) -> Self {
        self.transformed(Affine3A::from_scale(Vec3::splat(factor)))
    }

    /// Checks every parameter of the tree.
    ///
    /// # Errors
    /// The first problem found, with its path in the tree.
    pub fn validate(&self) -> Result<(), ShapeError> {
        self.validate_at("shape")
    }

    fn validate_at(&self, path: &str) -> Result<(), ShapeError> {
        let positive = |name: &'static str, value: f32| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ShapeError::BadParameter { path: path.to_string(), name, value })
            }
        };
        match self {
            Shape::Sphere { radius } => positive("radius", *radius),
            Shape::Cuboid { half_extents, rounding } => {
                positive("half_extents", half_extents.min_element())?;
                if !(rounding.is_finite() && *rounding >= 0.0 && *rounding <= half_extents.min_element()) {
                    return Err(ShapeError::BadParameter {
                        path: path.into(),
                        name: "rounding",
                        value: *rounding,
                    });
                }
                Ok(())
            }
            Shape::Torus { major, minor } => {
                positive("major", *major)?;
                positive("minor", *minor)
            }
            Shape::Cylinder { radius, half_height } => {
                positive("radius", *radius)?;
                positive("half_height", *half_height)
            }
            Shape::Superellipsoid { radii, e1, e2 } => {
                positive("radii", radii.min_element())?;
                positive("e1", *e1)?;
                positive("e2", *e2)
            }
            Shape::Union(children) | Shape::Intersection(children) => {
                let op = if matches!(self, Shape::Union(_)) { "union" } else { "intersection" };
                if children.is_empty() {
                    return Err(ShapeError::EmptyOperation(path.into()));
                }
                children.iter().enumerate().try_for_each(|(i, c)| c.validate_at(&format!("{path}.{op}[{i}]")))
            }
            Shape::Difference(a, b) => {
                a.validate_at(&format!("{path}.difference.left"))?;
                b.validate_at(&format!("{path}.difference.right"))
            }
            Shape::Placed(p) => {
                let finite = p.to_world.is_finite() && p.to_local.is_finite();
                if !finite || p.distance_scale.is_nan() || p.distance_scale <= 0.0 {
                    return Err(ShapeError::BadTransform(path.into()));
                }
                p.shape.validate_at(&format!("{path}.placed"))
            }
        }
    }

    /// Signed distance (positive inside) at `p`; see the module docs for
    /// which shapes are exact.
    pub fn distance(&self, p: Vec3) -> f32 {
        match self {
            Shape::Sphere { radius } => radius - p.length(),
            Shape::Cuboid { half_extents, rounding } => {
                let q = p.abs() - (*half_extents - Vec3::splat(*rounding));
                let outside = q.max(Vec3::ZERO).length() + q.max_element().min(0.0);
                rounding - outside
            }
            Shape::Torus { major, minor } => {
                let q = Vec2::new(Vec2::new(p.x, p.y).length() - major, p.z);
                minor - q.length()
            }
            Shape::Cylinder { radius, half_height } => {
                let d = Vec2::new(Vec2::new(p.x, p.y).length() - radius, p.z.abs() - half_height);
                -(d.max_element().min(0.0) + d.max(Vec2::ZERO).length())
            }
            Shape::Superellipsoid { radii, e1, e2 } => superellipsoid_radial_distance(p, *radii, *e1, *e2),
            Shape::Union(c) => c.iter().map(|s| s.distance(p)).fold(f32::NEG_INFINITY, f32::max),
            Shape::Intersection(c) => c.iter().map(|s| s.distance(p)).fold(f32::INFINITY, f32::min),
            Shape::Difference(a, b) => a.distance(p).min(-b.distance(p)),
            Shape::Placed(pl) => pl.distance_scale * pl.shape.distance(pl.to_local.transform_point3(p)),
        }
    }

    /// Whether [`Shape::distance`] is the exact Euclidean signed distance
    /// everywhere: sphere, box, torus and cylinder primitives, also when
    /// placed by a rigid motion or a uniform scale. Superellipsoids and CSG
    /// give only bounds away from the surface; convert those with
    /// [`crate::scan_conversion::scan_convert`] when true distances matter.
    pub fn is_exact_distance(&self) -> bool {
        match self {
            Shape::Sphere { .. } | Shape::Cuboid { .. } | Shape::Torus { .. } | Shape::Cylinder { .. } => {
                true
            }
            Shape::Superellipsoid { .. }
            | Shape::Union(_)
            | Shape::Intersection(_)
            | Shape::Difference(..) => false,
            Shape::Placed(pl) => {
                let m = pl.to_world.matrix3;
                let lengths = [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()];
                let uniform = lengths.iter().all(|l| (l - lengths[0]).abs() <= 1e-5 * lengths[0]);
                let orthogonal = m.x_axis.dot(m.y_axis).abs()
                    + m.x_axis.dot(m.z_axis).abs()
                    + m.y_axis.dot(m.z_axis).abs()
                    <= 1e-5 * lengths[0] * lengths[0];
                uniform && orthogonal && pl.shape.is_exact_distance()
            }
        }
    }

    /// A box containing the shape (tight for primitives, conservative for CSG).
    pub fn aabb(&self) -> Aabb {
        match self {
            Shape::Sphere { radius } => Aabb::cube(*radius),
            Shape::Cuboid { half_extents, .. } => Aabb::new(-*half_extents, *half_extents),
            Shape::Torus { major, minor } => {
                let e = Vec3::new(major + minor, major + minor, *minor);
                Aabb::new(-e, e)
            }
            Shape::Cylinder { radius, half_height } => {
                let e = Vec3::new(*radius, *radius, *half_height);
                Aabb::new(-e, e)
            }
            Shape::Superellipsoid { radii, .. } => Aabb::new(-*radii, *radii),
            Shape::Union(c) => c.iter().fold(Aabb::EMPTY, |b, s| b.union(&s.aabb())),
            Shape::Intersection(c) => {
                c.iter().map(Shape::aabb).reduce(|a, b| a.intersection(&b)).unwrap_or(Aabb::EMPTY)
            }
            Shape::Difference(a, _) => a.aabb(),
            Shape::Placed(p) => p.shape.aabb().transformed(&p.to_world),
        }
    }
}

/// Barr's inside-outside function turned into the distance along the ray from
/// the centre: `|p_s| − |p|` where `p_s = p · F(p)^(−ε1/2)` is on the surface.
fn superellipsoid_radial_distance(p: Vec3, radii: Vec3, e1: f32, e2: f32) -> f32 {
    let q = (p / radii).abs().as_dvec3();
    let (e1, e2) = (e1 as f64, e2 as f64);
    let xy = q.x.powf(2.0 / e2) + q.y.powf(2.0 / e2);
    let f = xy.powf(e2 / e1) + q.z.powf(2.0 / e1);
    let r = p.as_dvec3().length();
    if f <= 0.0 || r == 0.0 {
        // At the centre the nearest surface point lies along the shortest axis.
        return radii.min_element();
    }
    (r * f.powf(-e1 / 2.0) - r) as f32
}

/// Smallest singular value of the linear part of `map` (its weakest stretch).
fn smallest_singular_value(map: &Affine3A) -> f32 {
    let m = map.matrix3;
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let mat = nalgebra::Matrix3::from_fn(|r, c| cols[c][r] as f64);
    let sv = mat.singular_values();
    sv.min() as f32
}

impl Field3 for Shape {
    fn value(&self, p: Vec3) -> f32 {
        self.distance(p)
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(self.aabb())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;
    use std::f32::consts::FRAC_PI_2;

    #[test]
    fn primitive_distances_match_closed_forms() {
        let s = Shape::sphere(0.5);
        assert_relative_eq!(s.distance(Vec3::new(0.0, 2.0, 0.0)), -1.5);
        let b = Shape::cuboid(Vec3::new(1.0, 2.0, 3.0));
        assert_relative_eq!(b.distance(Vec3::ZERO), 1.0);
        assert_relative_eq!(b.distance(Vec3::new(4.0, 6.0, 0.0)), -5.0);
        let t = Shape::torus(0.3, 0.12);
        assert_relative_eq!(t.distance(Vec3::new(0.3, 0.0, 0.0)), 0.12);
        assert_relative_eq!(t.distance(Vec3::ZERO), -0.18);
        let c = Shape::cylinder(0.5, 1.0);
        assert_relative_eq!(c.distance(Vec3::new(0.0, 0.0, 0.8)), 0.2, epsilon = 1e-6);
        assert_relative_eq!(c.distance(Vec3::new(1.5, 0.0, 2.0)), -2f32.sqrt(), epsilon = 1e-6);
        let r = Shape::rounded_cuboid(Vec3::ONE, 0.25);
        assert_relative_eq!(r.distance(Vec3::new(2.0, 0.0, 0.0)), -1.0);
        let corner = Vec3::splat(0.75) + Vec3::splat(0.25 / 3f32.sqrt());
        assert!(r.distance(corner).abs() < 1e-6);
    }

    #[test]
    fn round_superellipsoid_is_a_sphere_and_signs_are_right() {
        let s = Shape::superellipsoid(Vec3::splat(0.4), 1.0, 1.0);
        for p in [Vec3::new(0.1, 0.2, -0.05), Vec3::new(0.0, 0.9, 0.3), Vec3::new(-0.3, 0.0, 0.0)] {
            assert_relative_eq!(s.distance(p), 0.4 - p.length(), epsilon = 1e-6);
        }
        let boxy = Shape::superellipsoid(Vec3::new(0.5, 0.3, 0.2), 0.2, 0.2);
        assert!(boxy.distance(Vec3::new(0.45, 0.25, 0.15)) > 0.0);
        assert!(boxy.distance(Vec3::new(0.55, 0.0, 0.0)) < 0.0);
        assert_relative_eq!(boxy.distance(Vec3::ZERO), 0.2);
    }

    #[test]
    fn csg_combines_with_min_and_max() {
        let a = Shape::sphere(1.0);
        let b = Shape::sphere(0.5).translated(Vec3::X);
        let p = Vec3::new(1.2, 0.0, 0.0);
        assert_relative_eq!(a.clone().union(b.clone()).distance(p), 0.3, epsilon = 1e-6);
        assert_relative_eq!(a.clone().intersect(b.clone()).distance(p), -0.2, epsilon = 1e-6);
        let d = a.subtract(b);
        assert_relative_eq!(d.distance(Vec3::new(0.4, 0.0, 0.0)), 0.1, epsilon = 1e-6);
        assert_relative_eq!(d.distance(Vec3::new(0.8, 0.0, 0.0)), -0.3, epsilon = 1e-6);
    }

    #[test]
    fn placement_scales_distances() {
        let s = Shape::sphere(1.0).scaled(2.0).translated(Vec3::Z);
        assert_relative_eq!(s.distance(Vec3::new(0.0, 0.0, 4.0)), -1.0, epsilon = 1e-6);
        let r = Shape::cylinder(0.1, 1.0).rotated(Quat::from_rotation_x(FRAC_PI_2));
        assert!(r.distance(Vec3::new(0.0, 0.9, 0.0)) > 0.0, "cylinder now along y");
        let aabb = r.aabb();
        assert!((aabb.max.y - 1.0).abs() < 1e-6 && (aabb.max.z - 0.1).abs() < 1e-6);
        // Anisotropic scale: the value bounds the true distance from below.
        let e = Shape::sphere(1.0).transformed(Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)));
        assert_relative_eq!(e.distance(Vec3::new(3.0, 0.0, 0.0)), -0.5, epsilon = 1e-6);
    }

    #[test]
    fn validation_names_the_bad_node() {
        let bad = Shape::sphere(1.0).union(Shape::torus(0.3, -0.1));
        match bad.validate() {
            Err(ShapeError::BadParameter { path, name, .. }) => {
                assert_eq!(path, "shape.union[1]");
                assert_eq!(name, "minor");
            }
            other => panic!("expected a bad parameter, got {other:?}"),
        }
        assert!(Shape::Union(vec![]).validate().is_err());
        assert!(Shape::sphere(1.0).scaled(0.0).validate().is_err());
        assert!(Shape::sphere(1.0).scaled(2.0).validate().is_ok());
    }

    proptest! {
        /// Exact primitives are 1-Lipschitz and their value is zero only on the
        /// surface: moving by δ changes the value by at most δ.
        #[test]
        fn exactness_flag_follows_the_table(
            r in 0.1f32..1.0, s in 0.5f32..2.0, stretch in 1.1f32..2.0
        ) {
            let sphere = Shape::sphere(r);
            prop_assert!(sphere.is_exact_distance());
            prop_assert!(sphere.clone().translated(Vec3::X).is_exact_distance());
            prop_assert!(sphere.clone().scaled(s).rotated(Quat::from_rotation_x(s)).is_exact_distance());
            let stretched = sphere.clone().transformed(Affine3A::from_scale(Vec3::new(stretch, 1.0, 1.0)));
            prop_assert!(!stretched.is_exact_distance());
            prop_assert!(!sphere.union(Shape::torus(r, r / 3.0)).is_exact_distance());
        }

        #[test]
        fn exact_primitives_are_one_lipschitz(
            x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0,
            dx in -0.1f32..0.1, dy in -0.1f32..0.1, dz in -0.1f32..0.1,
        ) {
            let p = Vec3::new(x, y, z);
            let d = Vec3::new(dx, dy, dz);
            for s in [
                Shape::sphere(0.4),
                Shape::rounded_cuboid(Vec3::new(0.3, 0.5, 0.2), 0.05),
                Shape::torus(0.3, 0.12),
                Shape::cylinder(0.3, 0.4),
            ] {
                prop_assert!((s.distance(p + d) - s.distance(p)).abs() <= d.length() * 1.0001 + 1e-6);
            }
        }
    }
}
