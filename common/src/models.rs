//! Built-in demo and test models, all inside the box `[-0.5, 0.5]³`, y up.
//!
//! The Breen & Whitaker models (ball, "C", mug, chain) are CSG of
//! superellipsoids, cylinders and tori as in the paper's Figs. 4 and 16; their
//! exact proportions are not given in the paper, so these are our own.

use crate::Landmarks;
use crate::shape::Shape;
use glam::{Quat, Vec3};
use std::f32::consts::FRAC_PI_2;

/// Names accepted by [`by_name`], in display order.
pub const NAMES: [&str; 9] =
    ["sphere", "torus", "ball", "c-shape", "mug", "chain", "cube", "holed-cube", "apple"];

/// The built-in model called `name` (see [`NAMES`]), or `None`.
pub fn by_name(name: &str) -> Option<Shape> {
    Some(match name {
        "sphere" => sphere(),
        "torus" => torus(),
        "ball" => ball(),
        "c-shape" | "c" => c_shape(),
        "mug" => mug(),
        "chain" => chain(),
        "cube" => cube(),
        "holed-cube" => holed_cube(),
        "apple" => apple(),
        _ => return None,
    })
}

/// The reference sphere: radius 0.3 at the origin.
pub fn sphere() -> Shape {
    Shape::sphere(0.3)
}

/// The reference torus: R = 0.3, r = 0.12 around the z axis (in the xy plane).
pub fn torus() -> Shape {
    Shape::torus(0.3, 0.12)
}

/// A rounded cube of half edge 0.3.
pub fn cube() -> Shape {
    Shape::rounded_cuboid(Vec3::splat(0.3), 0.04)
}

/// Yang & Jüttler's Example 2 target (Fig. 5): a cube of half edge 0.3
/// with three cylindrical holes of radius 0.08, one along each axis, offset
/// from the centre so that they do not meet (three crossing holes would
/// make genus 5): genus 3.
pub fn holed_cube() -> Shape {
    let drill =
        |rotation: Quat, offset: Vec3| Shape::cylinder(0.08, 0.5).rotated(rotation).translated(offset);
    Shape::cuboid(Vec3::splat(0.3))
        .subtract(drill(Quat::IDENTITY, Vec3::new(0.12, -0.12, 0.0)))
        .subtract(drill(Quat::from_rotation_y(FRAC_PI_2), Vec3::new(0.0, 0.12, -0.12)))
        .subtract(drill(Quat::from_rotation_x(FRAC_PI_2), Vec3::new(-0.12, 0.0, 0.12)))
}

/// Yang & Jüttler's Example 3 source (Fig. 7, apple → teapot): an apple
/// upright along y, a flattened ellipsoid (half width 0.3, half height
/// 0.26) with a spherical dimple at the top (radius 0.1) and a shallower one
/// at the bottom, and a stem (radius 0.02) rising from the top dimple to
/// y = 0.36. Genus 0.
pub fn apple() -> Shape {
    let body = Shape::superellipsoid(Vec3::new(0.3, 0.26, 0.3), 1.0, 1.0);
    let top = Shape::sphere(0.1).translated(Vec3::new(0.0, 0.3, 0.0));
    let bottom = Shape::sphere(0.07).translated(Vec3::new(0.0, -0.3, 0.0));
    let stem = Shape::cylinder(0.02, 0.08)
        .rotated(Quat::from_rotation_x(-FRAC_PI_2))
        .translated(Vec3::new(0.0, 0.28, 0.0));
    body.subtract(top).subtract(bottom).union(stem)
}

/// Breen's ball (Fig. 4): a small sphere lying mostly inside the left half of
/// the [`c_shape`], protruding from it.
pub fn ball() -> Shape {
    Shape::sphere(0.17).translated(Vec3::new(-0.2, 0.0, 0.0))
}

/// Breen's "C" (Fig. 4): a thick ring open towards +x (a superellipsoid disk
/// minus a superellipsoid hole and a box), with bulbous superellipsoid
/// terminals at both ends of the opening, like a typeset C. Standing in the xy
/// plane, z is its thickness.
pub fn c_shape() -> Shape {
    let disk = Shape::superellipsoid(Vec3::new(0.4, 0.4, 0.1), 0.5, 1.0);
    let hole = Shape::superellipsoid(Vec3::new(0.2, 0.2, 0.3), 0.3, 1.0);
    let opening = Shape::cuboid(Vec3::new(0.25, 0.12, 0.3)).translated(Vec3::new(0.3, 0.0, 0.0));
    let ring = disk.subtract(hole).subtract(opening);
    let terminal = |y: f32| {
        Shape::superellipsoid(Vec3::new(0.1, 0.1, 0.13), 0.6, 1.0).translated(Vec3::new(0.27, y, 0.0))
    };
    ring.union(terminal(0.2)).union(terminal(-0.2))
}

/// Breen's mug (Fig. 16): a cylindrical body with a torus handle, hollowed by a
/// second cylinder; upright along y.
pub fn mug() -> Shape {
    let upright = Quat::from_rotation_x(-FRAC_PI_2);
    let body = Shape::cylinder(0.25, 0.3);
    let handle = Shape::torus(0.14, 0.045)
        .rotated(Quat::from_rotation_x(FRAC_PI_2))
        .translated(Vec3::new(0.27, 0.0, 0.0));
    let cavity = Shape::cylinder(0.2, 0.3).translated(Vec3::new(0.0, 0.0, 0.06));
    body.union(handle).subtract(cavity).rotated(upright)
}

/// Breen's chain (Fig. 16): three linked tori along x, the end links in the xy
/// plane and the middle one in the xz plane, each passing through its
/// neighbour's hole without touching.
pub fn chain() -> Shape {
    let link = |i: i32| {
        let t = Shape::torus(0.14, 0.035);
        let t = if i == 0 { t.rotated(Quat::from_rotation_x(FRAC_PI_2)) } else { t };
        t.translated(Vec3::new(0.19 * i as f32, 0.0, 0.0))
    };
    link(-1).union(link(0)).union(link(1))
}

/// Radius of [`finned_ball`]'s ball.
pub const FIN_BALL_RADIUS: f32 = 0.25;

/// A ball (radius [`FIN_BALL_RADIUS`]) with a fin reaching to x = 0.58,
/// turned by `angle` (radians) about z: `finned_ball(0.0)` →
/// `finned_ball(π/2)` is a part that should travel a quarter circle, the
/// kind of morph Breen & Whitaker's landmarks exist for (§6.2, the dart's
/// fins becoming the X-29's wings).
pub fn finned_ball(angle: f32) -> Shape {
    let fin = Shape::rounded_cuboid(Vec3::new(0.2, 0.06, 0.06), 0.03).translated(Vec3::new(0.38, 0.0, 0.0));
    Shape::sphere(FIN_BALL_RADIUS).union(fin).rotated(Quat::from_rotation_z(angle))
}

/// Landmarks for `finned_ball(0.0)` → `finned_ball(π/2)`: the fin's tip and
/// a point on its side go round with it, four points of the ball stay.
pub fn fin_turn_landmarks() -> Landmarks {
    let turn = Quat::from_rotation_z(FRAC_PI_2);
    let r = FIN_BALL_RADIUS;
    let moving = [Vec3::new(0.58, 0.0, 0.0), Vec3::new(0.4, 0.06, 0.0)];
    let fixed =
        [Vec3::new(0.0, 0.0, r), Vec3::new(0.0, 0.0, -r), Vec3::new(-r, 0.0, 0.0), Vec3::new(0.0, -r, 0.0)];
    let pairs: Vec<(Vec3, Vec3)> =
        moving.iter().map(|&p| (p, turn * p)).chain(fixed.iter().map(|&p| (p, p))).collect();
    Landmarks::new(&pairs).expect("four ball points off the fin's plane and two fin points")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Aabb;

    #[test]
    fn every_model_is_valid_and_fits_the_unit_box() {
        let unit = Aabb::cube(0.5);
        for name in NAMES {
            let s = by_name(name).unwrap();
            s.validate().unwrap();
            let b = s.aabb();
            assert!(unit.contains(b.min) && unit.contains(b.max), "{name} bounds {b:?}");
        }
        assert!(by_name("teapot").is_none());
    }

    #[test]
    fn models_have_their_features() {
        let c = c_shape();
        assert!(c.distance(Vec3::ZERO) < 0.0, "the C has a hole");
        assert!(c.distance(Vec3::new(-0.3, 0.0, 0.0)) > 0.0, "left side is solid");
        assert!(c.distance(Vec3::new(0.3, 0.0, 0.0)) < 0.0, "open towards +x");
        assert!(c.distance(Vec3::new(0.27, 0.2, 0.0)) > 0.0, "terminal");
        let ball = ball();
        assert!(ball.distance(Vec3::new(-0.3, 0.0, 0.0)) > 0.0, "ball overlaps the C");
        let mug = mug();
        assert!(mug.distance(Vec3::new(0.0, 0.1, 0.0)) < 0.0, "hollow");
        assert!(mug.distance(Vec3::new(0.0, -0.27, 0.0)) > 0.0, "floor");
        assert!(mug.distance(Vec3::new(0.41, 0.0, 0.0)) > 0.0, "handle");
        assert!(mug.distance(Vec3::new(0.32, 0.0, 0.0)) < 0.0, "hole of the handle");
        let apple = apple();
        assert!(apple.distance(Vec3::ZERO) > 0.0, "solid");
        assert!(apple.distance(Vec3::new(0.0, 0.23, 0.05)) < 0.0, "top dimple");
        assert!(apple.distance(Vec3::new(0.0, -0.245, 0.03)) < 0.0, "bottom dimple");
        assert!(apple.distance(Vec3::new(0.0, 0.33, 0.0)) > 0.0, "stem");
        assert!(apple.distance(Vec3::new(0.0, 0.37, 0.0)) < 0.0, "stem top");
        let chain = chain();
        assert!(chain.distance(Vec3::new(-0.19, 0.14, 0.0)) > 0.0, "left link");
        assert!(chain.distance(Vec3::new(0.0, 0.0, 0.14)) > 0.0, "middle link");
        assert!(chain.distance(Vec3::ZERO) < 0.0);
        // The links interlock without touching: along the x axis the surface
        // alternates between the three links with gaps.
        let links_on_axis = (0..=200)
            .map(|i| chain.distance(Vec3::new(-0.5 + i as f32 * 0.005, 0.0, 0.0)) > 0.0)
            .collect::<Vec<_>>()
            .windows(2)
            .filter(|w| !w[0] && w[1])
            .count();
        assert_eq!(links_on_axis, 6, "six tube crossings of the x axis");
    }
}
