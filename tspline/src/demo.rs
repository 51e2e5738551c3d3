//! The paper's example shapes that the shared models do not have, built from
//! the shared CSG primitives or as parametric meshes.

use crate::evolution::Speed;
use crate::morph::TsplineSettings;
use glam::{DVec3, Vec2, Vec3};
use isomorph_common::{Shape, TriMesh};
use std::f32::consts::TAU;

/// The settings that morph a sphere of radius 0.3 into Example 2's target
/// (Fig. 5, genus 3: [`isomorph_common::models::holed_cube`])
/// (tested in `tests/sphere_holed_cube.rs`, benched as
/// `morph/sphere_holed_cube`): a uniform depth-3 T-mesh (729 coefficients;
/// the paper used 651), a margin of half the shapes' size (the cube's faces
/// stay away from the domain boundary), [`Speed::Robust`] (the paper's
/// eq. 8 stalls this growth) and a step of a quarter of a depth-3 cell
/// (0.0625 domain units). With the default half cell, one step carries the
/// surface across the holes' mouths and leaves six lens-shaped caps outside
/// the cube's faces for one level set; at a quarter cell every level set has
/// one outer piece (the holes open from inside: one level set holds a
/// cavity, which the metrics report as a void).
pub fn holed_cube_settings() -> TsplineSettings {
    let mut s = TsplineSettings::default();
    s.tmesh.max_depth = 3;
    s.margin = 0.5;
    s.evolve.speed = Speed::Robust { v_max: 0.2, beta_cells: 0.25 };
    s.evolve.step = Some(0.25 * 2.0 / 8.0);
    s.evolve.max_steps = 60;
    s
}

/// The settings of the paper's Example 1, the bunny morphing into a
/// [`petal_torus`] (Fig. 1; tested in `tests/tests/tspline_example1.rs`):
/// the paper's speed (eq. 8, [`Speed::Paper`]), a T-mesh of depth at most
/// 5 with at most 60 surface samples per cell (`n_T`), so that the thin
/// ears get depth-5 cells and the rest stays coarser (1327 coefficients
/// for the bunny and the petal torus at the test's sizes; the paper used
/// 2449), a stall window of 40 steps (eq. 8's curvature term on depth-5
/// cells makes the first steps short, `Δτ` about 0.005) and at most 200
/// steps. Measured: converged in 77 steps, one component in every level
/// set, genus 0 → 1. At depth 4 the ears are about one cell thick and a
/// sliver of an ear's tip pinches off for a level set or two.
pub fn example1_settings() -> TsplineSettings {
    let mut s = TsplineSettings::default();
    s.tmesh.max_depth = 5;
    s.tmesh.max_samples_per_cell = 60;
    s.evolve.speed = Speed::Paper;
    s.evolve.stall_steps = 40;
    s.evolve.max_steps = 200;
    s
}

/// Example 1's target (Fig. 1): a "petal torus", a torus in the xy plane
/// whose tube radius varies with the angle around the z axis,
/// `r(θ) = minor · (1 + amplitude · cos(petals · θ))`, as a closed,
/// outward-oriented mesh with `segments` × `segments / 2` quads.
pub fn petal_torus(major: f32, minor: f32, amplitude: f32, petals: u32, segments: u32) -> TriMesh {
    let (nu, nv) = (segments.max(8), (segments / 2).max(6));
    let mut positions = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let theta = TAU * i as f32 / nu as f32;
        let r = minor * (1.0 + amplitude * (petals as f32 * theta).cos());
        let (s, c) = theta.sin_cos();
        for j in 0..nv {
            let phi = TAU * j as f32 / nv as f32;
            let rho = major + r * phi.cos();
            positions.push(Vec3::new(rho * c, rho * s, r * phi.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + j % nv;
    let mut triangles = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh { positions, triangles, ..TriMesh::default() }
}

/// Half thickness along z of the extruded letters [`letter_t`] and
/// [`letter_c`] (world units).
pub const LETTER_HALF_DEPTH: f32 = 0.1;

/// The source of the paper's Fig. 2–3: a letter "T" lying on its side
/// ("├"), extruded to `|z| ≤ LETTER_HALF_DEPTH` (world units): a vertical
/// bar `x ∈ [−0.45, −0.3]`, `|y| ≤ 0.3` and a horizontal bar
/// `x ∈ [−0.3, 0.33]`, `|y| ≤ 0.07` pointing right. The horizontal bar
/// crosses the inside of [`letter_c`] and ends in the C's opening.
pub fn letter_t() -> Shape {
    let z = LETTER_HALF_DEPTH;
    extruded_bar(Vec2::new(-0.45, -0.3), Vec2::new(-0.3, 0.3), z).union(extruded_bar(
        Vec2::new(-0.3, -0.07),
        Vec2::new(0.33, 0.07),
        z,
    ))
}

/// The target of the paper's Fig. 2–3: a round letter "C", the annulus
/// `0.32 ≤ r ≤ 0.45` about the z axis without the opening `x > 0`,
/// `|y| < 0.2`, extruded to `|z| ≤ LETTER_HALF_DEPTH` (world units). Its left
/// arc overlaps the "T"'s vertical bar. The "T"'s horizontal bar lies outside
/// the "C": 0.25 from it at the C's centre, 0.11–0.13 where it passes between
/// the C's ends, so the distance speed cuts the bar in its middle (Fig. 2).
pub fn letter_c() -> Shape {
    let z = LETTER_HALF_DEPTH;
    let opening = Shape::cuboid(Vec3::new(0.25, 0.2, 2.0 * z)).translated(Vec3::new(0.25, 0.0, 0.0));
    Shape::cylinder(0.45, z).subtract(Shape::cylinder(0.32, 2.0 * z)).subtract(opening)
}

/// Half thickness along z of the extruded corners [`corner_source`] and
/// [`corner_target`] (world units).
pub const CORNER_HALF_DEPTH: f32 = 0.25;

/// The axis-aligned bar `lo ≤ (x, y) ≤ hi`, `|z| ≤ half_depth` (world units).
fn extruded_bar(lo: Vec2, hi: Vec2, half_depth: f32) -> Shape {
    let centre = (0.5 * (lo + hi)).extend(0.0);
    Shape::cuboid((0.5 * (hi - lo)).extend(half_depth)).translated(centre)
}

/// The source of the paper's Fig. 2–3 as its text describes it: a "┌"
/// extruded to `|z| ≤ CORNER_HALF_DEPTH` (world units): a horizontal bar
/// `x ∈ [−0.45, 0.45]`, `y ∈ [−0.05, 0.1]` and a vertical bar
/// `x ∈ [−0.45, −0.3]`, `y ∈ [−0.45, 0.1]` hanging from its left end. It
/// sits below [`corner_target`]'s horizontal bar (a gap of 0.2) and
/// overlaps the target only where its horizontal bar ends in the target's
/// right bar (`x ∈ [0.3, 0.45]`).
pub fn corner_source() -> Shape {
    let z = CORNER_HALF_DEPTH;
    extruded_bar(Vec2::new(-0.45, -0.05), Vec2::new(0.45, 0.1), z).union(extruded_bar(
        Vec2::new(-0.45, -0.45),
        Vec2::new(-0.3, 0.1),
        z,
    ))
}

/// The target of the paper's Fig. 2–3 as its text describes it: a "┐"
/// extruded to `|z| ≤ CORNER_HALF_DEPTH` (world units): a horizontal bar
/// `x ∈ [−0.45, 0.45]`, `y ∈ [0.3, 0.45]` and a vertical bar
/// `x ∈ [0.3, 0.45]`, `y ∈ [−0.45, 0.45]` hanging from its right end.
/// [`corner_source`]'s horizontal bar lies 0.2 below its horizontal bar
/// (uniformly, up to its right bar), [`corner_source`]'s vertical bar 0.2
/// to 0.55 below it.
pub fn corner_target() -> Shape {
    let z = CORNER_HALF_DEPTH;
    extruded_bar(Vec2::new(-0.45, 0.3), Vec2::new(0.45, 0.45), z).union(extruded_bar(
        Vec2::new(0.3, -0.45),
        Vec2::new(0.45, 0.45),
        z,
    ))
}

/// `n` nearly uniform points on the sphere of radius `r` about `center`
/// (Fibonacci spiral), e.g. to build a [`crate::TMesh`] in domain units.
pub fn sphere_samples(n: usize, r: f64, center: DVec3) -> Vec<DVec3> {
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let phi = i as f64 * 2.399_963_229_728_653;
            center + r * DVec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::Aabb;
    use isomorph_common::marching_cubes::polygonize;

    #[test]
    fn holed_cube_has_genus_three() {
        let m = polygonize(&isomorph_common::models::holed_cube(), &Aabb::cube(0.5), 48, 0.0).unwrap();
        assert_eq!(m.genus(), Some(3));
        assert_eq!(m.connected_components(), 1);
    }

    /// `shape` polygonizes to one genus-0 surface.
    fn assert_single_genus_zero_solid(shape: &Shape) {
        let m = polygonize(shape, &Aabb::cube(0.5), 48, 0.0).unwrap();
        assert_eq!((m.connected_components(), m.genus()), (1, Some(0)));
    }

    #[test]
    fn letters_overlap_and_are_single_genus_zero_solids() {
        let (t, c) = (letter_t(), letter_c());
        assert_single_genus_zero_solid(&t);
        assert_single_genus_zero_solid(&c);
        // The T's vertical bar lies in the C's left arc; its horizontal bar
        // (centre, between the C's ends) lies outside the C.
        assert!(c.distance(Vec3::new(-0.38, 0.0, 0.0)) > 0.0);
        // (CSG distances are bounds: the points avoid the cut's faces.)
        assert!(c.distance(Vec3::new(-0.05, 0.07, 0.0)) < -0.15);
        assert!(c.distance(Vec3::new(0.3, 0.07, 0.0)) < -0.1);
    }

    #[test]
    fn corners_overlap_only_at_the_source_bar_end() {
        let (a, b) = (corner_source(), corner_target());
        assert_single_genus_zero_solid(&a);
        assert_single_genus_zero_solid(&b);
        // The source's horizontal bar ends inside the target's vertical bar.
        let end = Vec3::new(0.38, 0.02, 0.0);
        assert!(a.distance(end) > 0.0 && b.distance(end) > 0.0);
        // Its corner and its bar's middle lie 0.2 or more outside the target.
        assert!(b.distance(Vec3::new(-0.38, 0.02, 0.0)) < -0.19);
        assert!(b.distance(Vec3::new(0.0, 0.02, 0.0)) < -0.19);
        assert!(b.distance(Vec3::new(-0.38, -0.4, 0.0)) < -0.5);
    }

    #[test]
    fn petal_torus_is_a_closed_outward_torus() {
        let m = petal_torus(0.3, 0.1, 0.4, 5, 64);
        assert_eq!(m.genus(), Some(1));
        assert!(m.signed_volume() > 0.0, "outward orientation");
    }
}
