//! The variational-implicit morph under the morph contract: the conformance
//! suite on the reference pair with the default settings (plain and with
//! correspondences), a mesh input, and settings errors that name the field.

use isomorph_common::Field3;
use isomorph_common::conformance::{Expectations, check_morph};
use isomorph_common::glam;
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::mesh::primitives::uv_sphere;
use isomorph_common::{Aabb, Control, Morph, MorphError, Shape, Solid, models};
use isomorph_rbf::{RbfError, RbfMorph, RbfSettings, WarpedMorph, WarpedSettings};

fn reference(shape: &Shape) -> isomorph_common::TriMesh {
    polygonize(shape, &Aabb::cube(0.5), 128, 0.0).unwrap()
}

/// The suite's expectations for a morph between `a` and `b`.
fn expectations(a: &Shape, b: &Shape) -> Expectations {
    Expectations {
        source: reference(a),
        target: reference(b),
        resolution: 64,
        mean_voxels: 0.05,
        hausdorff_voxels: 0.25,
        converges: true,
    }
}

#[test]
fn rbf_conforms_with_its_defaults() {
    let (a, b) = (Shape::sphere(0.3), models::torus());
    let (sa, sb) = (Solid::shape(a.clone()), Solid::shape(b.clone()));
    let settings = RbfSettings::default();
    let expect = expectations(&a, &b);
    let got = check_morph(|c| RbfMorph::new(&sa, &sb, &settings, c), &expect);
    // Measured: mean 0.009 / Hausdorff 0.02 voxels (source), 0.014 / 0.05 (target).
    println!("{got:?}");
    let morph = RbfMorph::new(&sa, &sb, &settings, &Control::new()).unwrap();
    let report = morph.report();
    assert_eq!(report.details.get("constraints").map(|v| format!("{v:?}")), Some("Int(1600)".into()));
    assert!(report.residual.as_ref().unwrap().value < 1e-8, "{report:?}");
    // The sphere opens into the torus: one component throughout.
    for t in [0.25, 0.5, 0.75] {
        assert_eq!(morph.frame_mesh(t, 64).unwrap().connected_components(), 1, "t = {t}");
    }
}

/// A mesh input is sampled by its own vertices (no polygonization).
#[test]
fn mesh_inputs_morph() {
    let sphere = Solid::mesh(uv_sphere(glam::Vec3::ZERO, 0.3, 24, 48)).unwrap();
    let torus = Solid::shape(models::torus());
    let morph = RbfMorph::new(&sphere, &torus, &RbfSettings::default(), &Control::new()).unwrap();
    let start = morph.frame_mesh(0.0, 64).unwrap();
    let worst = start.positions.iter().map(|p| (p.length() - 0.3).abs()).fold(0.0f32, f32::max);
    assert!(worst < 0.01, "frame 0 off the sphere by {worst}");
}

#[test]
fn bad_settings_name_the_field() {
    let s = Solid::shape(Shape::sphere(0.3));
    for (bad, name) in [
        (RbfSettings { points: 2, ..Default::default() }, "points = 2"),
        (RbfSettings { separation: 0.0, ..Default::default() }, "separation = 0"),
        (RbfSettings { normal_offset: f32::NAN, ..Default::default() }, "normal_offset = NaN"),
        (RbfSettings { surface_resolution: 4, ..Default::default() }, "surface_resolution = 4"),
    ] {
        let e = RbfMorph::new(&s, &s, &bad, &Control::new()).unwrap_err();
        assert!(matches!(e, RbfError::Morph(MorphError::BadSetting { .. })), "{e}");
        assert!(e.to_string().contains(name), "{e}");
    }
}

/// Correspondences on the sphere's octant directions and the torus' tube
/// tops and bottoms.
fn sphere_torus_pairs() -> Vec<(glam::Vec3, glam::Vec3)> {
    let mut pairs = Vec::new();
    for k in 0..4 {
        let a = k as f32 * std::f32::consts::FRAC_PI_2;
        let (c, s) = (a.cos(), a.sin());
        for z in [-1.0f32, 1.0] {
            let on_sphere = glam::Vec3::new(c, s, z).normalize() * 0.3;
            pairs.push((on_sphere, glam::Vec3::new(0.3 * c, 0.3 * s, 0.12 * z)));
        }
    }
    pairs
}

#[test]
fn warped_rbf_conforms() {
    let (a, b) = (Shape::sphere(0.3), models::torus());
    let (sa, sb) = (Solid::shape(a.clone()), Solid::shape(b.clone()));
    let settings = WarpedSettings { rbf: RbfSettings::default(), correspondences: sphere_torus_pairs() };
    let expect = expectations(&a, &b);
    let got = check_morph(|c| WarpedMorph::new(&sa, &sb, &settings, c), &expect);
    println!("{got:?}");
    let morph = WarpedMorph::new(&sa, &sb, &settings, &Control::new()).unwrap();
    assert_eq!(morph.report().method, "rbf-warp");
    assert_eq!(
        morph.report().details.get("correspondences").map(|v| format!("{v:?}")),
        Some("Int(8)".into())
    );
}

#[test]
fn warped_rbf_refuses_too_few_correspondences_before_work() {
    let s = Solid::shape(Shape::sphere(0.3));
    let settings =
        WarpedSettings { correspondences: sphere_torus_pairs()[..3].to_vec(), ..Default::default() };
    let e = WarpedMorph::new(&s, &s, &settings, &Control::new()).unwrap_err();
    assert!(matches!(e, RbfError::TooFewCorrespondences { got: 3, .. }), "{e}");
}

/// Two spheres apart: with the poles as correspondences the in-between
/// shapes are the sphere sliding across (one component, on the straight
/// path); the plain transformation instead shrinks one and grows the other
/// in place, so its middle frame is not the moved sphere.
#[test]
fn correspondences_make_disjoint_spheres_slide() {
    let shift = glam::Vec3::X * 0.8;
    let r = 0.25;
    let sphere = Shape::sphere(r);
    let (sa, sb) = (Solid::shape(sphere.clone()), Solid::shape(sphere.clone().translated(shift)));
    let poles = [glam::Vec3::X, -glam::Vec3::X, glam::Vec3::Y, -glam::Vec3::Y, glam::Vec3::Z, -glam::Vec3::Z];
    let rbf = RbfSettings { points: 150, ..Default::default() };
    let settings = WarpedSettings {
        rbf: rbf.clone(),
        correspondences: poles.iter().map(|&d| (d * r, d * r + shift)).collect(),
    };
    let warped = WarpedMorph::new(&sa, &sb, &settings, &Control::new()).unwrap();
    let plain = RbfMorph::new(&sa, &sb, &rbf, &Control::new()).unwrap();
    // How far the frame's surface is from the sphere moved by t · shift,
    // along the axes through its centre (where the field changes sign).
    let off = |field: &dyn Field3, t: f32| -> f32 {
        let centre = shift * t;
        poles
            .iter()
            .map(|&d| {
                let (mut lo, mut hi) = (0.0f32, 0.5f32);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if field.value(centre + d * mid) > 0.0 { lo = mid } else { hi = mid }
                }
                (lo - r).abs()
            })
            .fold(0.0, f32::max)
    };
    for t in [0.25f32, 0.5, 0.75] {
        let frame = warped.frame(t).unwrap().field;
        assert!(frame.value(shift * t) > 0.0, "t = {t}: the moved centre is outside");
        let e = off(&frame, t);
        assert!(e < 0.02, "t = {t}: the warped frame is {e} off the moved sphere");
        assert_eq!(warped.frame_mesh(t, 48).unwrap().connected_components(), 1, "t = {t}");
    }
    let e = off(&plain.frame(0.5).unwrap().field, 0.5);
    assert!(e > 0.05, "the plain middle frame is only {e} off the moved sphere");
}

/// The dense solver gives bit-identical interpolants on one and two threads
/// (faer's blocking follows a fixed task count, not the pool size).
#[test]
fn dense_fit_is_identical_for_any_thread_count() {
    use isomorph_rbf::{Constraint, FitSettings, Interpolant, Solver};
    let constraints: Vec<Constraint<4>> = (0..1600u32)
        .map(|i| {
            let c = [i % 9, (i / 9) % 9, (i / 81) % 9, i / 729]
                .map(|x| x as f32 / 9.0 + (i as f32 * 0.37).sin() * 0.01);
            Constraint::new(c, (i % 3) as f32 * 0.5)
        })
        .collect();
    let settings = FitSettings { solver: Solver::Dense, ..FitSettings::default() };
    let fit = |threads: usize| {
        let control = Control::new().with_threads(threads).unwrap();
        control.install(|| Interpolant::fit(&constraints, &settings).unwrap())
    };
    let (one, two) = (fit(1), fit(2));
    for p in [[0.31, 0.47, 0.2, 0.6], [0.9, 0.1, 0.5, 0.05]] {
        let p = p.map(f64::from);
        assert_eq!(one.value_f64(p).to_bits(), two.value_f64(p).to_bits(), "at {p:?}");
    }
}
