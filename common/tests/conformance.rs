//! The baseline runs the morph contract's conformance suite.

use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::{Aabb, Shape, Solid, marching_cubes::polygonize, models};
use isomorph_common::{BlendSettings, DistanceBlend};

#[test]
fn distance_blend_conforms() {
    let (a, b) = (Shape::sphere(0.3), models::torus());
    let (sa, sb) = (Solid::shape(a.clone()), Solid::shape(b.clone()));
    let settings = BlendSettings { resolution: 40, ..Default::default() };
    let bounds = Aabb::cube(0.5);
    let expect = Expectations {
        source: polygonize(&a, &bounds, 96, 0.0).unwrap(),
        target: polygonize(&b, &bounds, 96, 0.0).unwrap(),
        resolution: 40,
        mean_voxels: 0.1,
        hausdorff_voxels: 0.5,
        converges: true,
    };
    let got = check_morph(|c| DistanceBlend::new(&sa, &sb, &settings, c), &expect);
    println!("{got:?}");
}
