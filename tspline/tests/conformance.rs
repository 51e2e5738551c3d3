//! The T-spline morph under the morph contract: the conformance suite on
//! the reference pair with the default settings, and its settings errors.

use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::{Control, MorphError, Shape, Solid, models};
use isomorph_tspline::{TsplineError, TsplineMorph, TsplineSettings};

#[test]
fn tspline_conforms_with_its_defaults() {
    let (sa, sb) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(models::torus()));
    let settings = TsplineSettings::default();
    let control = Control::new();
    // The projection frames start and end on the inputs' surfaces (marching
    // cubes of their distance volumes at the settings' resolution).
    let res = settings.surface_resolution;
    let expect = Expectations {
        source: sa.surface(res, &control).unwrap().into_owned(),
        target: sb.surface(res, &control).unwrap().into_owned(),
        resolution: 64,
        mean_voxels: 0.01,
        hausdorff_voxels: 0.01,
        converges: true,
    };
    let got = check_morph(|c| TsplineMorph::new(&sa, &sb, &settings, c), &expect);
    println!("{got:?}");
}

#[test]
fn bad_settings_name_the_field() {
    let (sa, sb) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(models::torus()));
    let mut bad = TsplineSettings::default();
    bad.tmesh.max_depth = 9;
    let e = TsplineMorph::new(&sa, &sb, &bad, &Control::new()).unwrap_err();
    assert!(matches!(e, TsplineError::Morph(MorphError::BadSetting { name: "max_depth", .. })), "{e}");
    let bad = TsplineSettings { surface_resolution: 2, ..Default::default() };
    let e = TsplineMorph::new(&sa, &sb, &bad, &Control::new()).unwrap_err();
    assert!(e.to_string().contains("surface_resolution = 2"), "{e}");
}
