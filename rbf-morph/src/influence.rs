//! Influence shapes (paper §7): three shapes at the corners of a triangle in
//! `N + 2` dimensions or four at the corners of a regular tetrahedron in
//! `N + 3`, one variational implicit through all of them, and a path through
//! the extra dimensions that chooses the blend.

use crate::RbfSettings;
use crate::error::RbfError;
use crate::interpolant::{Constraint, Interpolant};
use crate::slice::Slice3;
use crate::transform::{TransformSettings, lift, solid_constraints};
use glam::Vec3;
use isomorph_common::MorphError;
use isomorph_common::check_time;
use isomorph_common::{Aabb, Control, Frame, Morph, MorphReport, Outcome, Solid, Stages};

#[derive(Debug, Clone)]
enum Blend {
    Three(Interpolant<5>),
    Four(Interpolant<6>),
}

/// One implicit through three or four 3D shapes placed at the corners of a
/// simplex in the extra dimensions.
///
/// With three shapes the corners are the paper's `(0, 0)`, `(1, 0)` and
/// `(½, ½)`; with four, a regular tetrahedron of unit edge. Both are scaled
/// by the separation. A path from A's corner to B's that bends towards C's
/// gives a sequence from A to B that takes on some of C's character (Fig. 8).
#[derive(Debug, Clone)]
pub struct InfluenceShapes {
    blend: Blend,
    corners: Vec<Vec<f32>>,
    bounds: Aabb,
}

impl InfluenceShapes {
    /// Fits the `3 + shapes.len() − 1`-dimensional implicit through the
    /// shapes' constraints, shape `i` at [`InfluenceShapes::corner`]`(i)`.
    ///
    /// # Errors
    /// [`RbfError::InvalidInput`] unless there are 3 or 4 shapes;
    /// [`RbfError::EmptyShape`] for an empty shape; bad separation or margin
    /// and the errors of [`Interpolant::fit`].
    pub fn new(shapes: &[&[Constraint<3>]], settings: &TransformSettings) -> Result<Self, RbfError> {
        if !(settings.separation > 0.0 && settings.separation.is_finite()) {
            return Err(
                MorphError::bad_setting("separation", settings.separation, "a finite number > 0").into()
            );
        }
        if !(settings.margin >= 0.0 && settings.margin.is_finite()) {
            return Err(MorphError::bad_setting("margin", settings.margin, "a finite number ≥ 0").into());
        }
        let s = settings.separation;
        let corners: Vec<Vec<f32>> = match shapes.len() {
            3 => vec![vec![0.0, 0.0], vec![s, 0.0], vec![0.5 * s, 0.5 * s]],
            4 => {
                let h = 3.0f32.sqrt();
                vec![
                    vec![0.0, 0.0, 0.0],
                    vec![s, 0.0, 0.0],
                    vec![0.5 * s, 0.5 * h * s, 0.0],
                    vec![0.5 * s, h / 6.0 * s, (2.0f32 / 3.0).sqrt() * s],
                ]
            }
            n => return Err(RbfError::InvalidInput(format!("influence shapes need 3 or 4 shapes, got {n}"))),
        };
        const NAMES: [&str; 4] = ["first", "second", "third", "fourth"];
        for (i, cs) in shapes.iter().enumerate() {
            if cs.is_empty() {
                return Err(RbfError::EmptyShape(NAMES[i]));
            }
        }
        let blend = if shapes.len() == 3 {
            let all: Vec<Constraint<5>> =
                shapes.iter().zip(&corners).flat_map(|(cs, at)| lift(cs, at)).collect();
            Blend::Three(Interpolant::fit(&all, &settings.fit)?)
        } else {
            let all: Vec<Constraint<6>> =
                shapes.iter().zip(&corners).flat_map(|(cs, at)| lift(cs, at)).collect();
            Blend::Four(Interpolant::fit(&all, &settings.fit)?)
        };
        let pts: Vec<Vec3> =
            shapes.iter().flat_map(|cs| cs.iter().map(|c| Vec3::from_array(c.position))).collect();
        let bounds = Aabb::from_points(&pts);
        let bounds = bounds.expanded(settings.margin * bounds.diagonal());
        Ok(Self { blend, corners, bounds })
    }

    /// Number of shapes (3 or 4).
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Always false (there are 3 or 4 shapes).
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// The extra coordinates of shape `i`'s corner (`None` for `i ≥ len`).
    pub fn corner(&self, i: usize) -> Option<&[f32]> {
        self.corners.get(i).map(Vec::as_slice)
    }

    /// The fit report of the underlying interpolant.
    pub fn report(&self) -> &crate::FitReport {
        match &self.blend {
            Blend::Three(f) => f.report(),
            Blend::Four(f) => f.report(),
        }
    }

    /// The 3D shape at the point `at` of the extra dimensions (2 coordinates
    /// for three shapes, 3 for four).
    ///
    /// # Errors
    /// [`RbfError::SliceArity`] for the wrong number of coordinates,
    /// [`RbfError::NonFinite`] for NaN.
    pub fn slice(&self, at: &[f32]) -> Result<Slice3, RbfError> {
        let s = match &self.blend {
            Blend::Three(f) => f.slice3(at)?,
            Blend::Four(f) => f.slice3(at)?,
        };
        Ok(s.with_bounds(self.bounds))
    }

    /// A morph along the Bézier curve with control points `path` in the
    /// extra dimensions (e.g. `[corner(0), corner(2), corner(1)]`: from the
    /// first shape to the second, pulled towards the third).
    ///
    /// # Errors
    /// [`RbfError::InvalidInput`] for fewer than two control points or a
    /// control point of the wrong dimension or not finite.
    pub fn path(self, path: Vec<Vec<f32>>) -> Result<InfluencePath, RbfError> {
        let dim = self.corners[0].len();
        if path.len() < 2 || path.iter().any(|p| p.len() != dim || p.iter().any(|v| !v.is_finite())) {
            return Err(RbfError::InvalidInput(format!(
                "a path needs at least two finite control points of {dim} coordinates"
            )));
        }
        let report =
            MorphReport::new("rbf-influence", Outcome::Direct).with_detail("shapes", self.corners.len());
        Ok(InfluencePath { shapes: self, path, report })
    }
}

/// A sequence through the family of blends of [`InfluenceShapes`]: the
/// shape at `t` is the slice at the Bézier curve's point `t`.
#[derive(Debug, Clone)]
pub struct InfluencePath {
    shapes: InfluenceShapes,
    path: Vec<Vec<f32>>,
    report: MorphReport,
}

impl InfluencePath {
    /// The point of the curve at `t` (de Casteljau).
    pub fn point(&self, t: f32) -> Vec<f32> {
        let mut pts = self.path.clone();
        while pts.len() > 1 {
            pts = pts
                .windows(2)
                .map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| a + t * (b - a)).collect())
                .collect();
        }
        pts.swap_remove(0)
    }

    /// The shapes the path runs through.
    pub fn shapes(&self) -> &InfluenceShapes {
        &self.shapes
    }

    /// The morph from `source` to `target` under the influence of one or
    /// two more solids (§7, Fig. 8): all of them sampled as
    /// [`RbfMorph::new`](crate::RbfMorph::new) samples its two, one implicit
    /// through the three (five dimensions) or four (six) shapes at the
    /// corners of a triangle or tetrahedron, and the path from the source's
    /// corner to the target's, a Bézier curve pulled towards the influence
    /// shapes' corners (control points source, influences, target).
    ///
    /// # Errors
    /// [`RbfError::InvalidInput`] unless there are one or two influence
    /// solids; [`MorphError::BadSetting`], [`MorphError::Cancelled`], the
    /// solids' conversion errors and those of [`InfluenceShapes::new`].
    pub fn from_solids(
        source: &Solid,
        target: &Solid,
        influences: &[Solid],
        settings: &RbfSettings,
        control: &Control,
    ) -> Result<Self, RbfError> {
        settings.validate()?;
        if !(1..=2).contains(&influences.len()) {
            return Err(RbfError::InvalidInput(format!(
                "one or two influence shapes, not {}",
                influences.len()
            )));
        }
        let mut warnings = isomorph_common::validate_inputs(source, target, control)?;
        for influence in influences {
            warnings.extend(isomorph_common::validate_inputs(influence, target, control)?);
        }
        control.install(|| {
            let mut stages = Stages::start();
            let solids: Vec<&Solid> = [source, target].into_iter().chain(influences).collect();
            let share = 1.0 / solids.len() as f32;
            let constraints = solids
                .iter()
                .enumerate()
                .map(|(i, solid)| solid_constraints(solid, settings, i as f32 * share, control))
                .collect::<Result<Vec<_>, _>>()?;
            stages.lap("constraints");
            let total: usize = constraints.iter().map(Vec::len).sum();
            control.progress("fit", None, || format!("{total} constraints in {}D", 3 + solids.len() - 1));
            let refs: Vec<&[Constraint<3>]> = constraints.iter().map(Vec::as_slice).collect();
            let shapes = InfluenceShapes::new(&refs, &settings.transform())?;
            control.check()?;
            stages.lap("fit");
            // Source, the influences in order, target.
            let order = [0].into_iter().chain(2..solids.len()).chain([1]);
            let path = order.map(|i| shapes.corners[i].clone()).collect();
            let mut morph = shapes.path(path)?;
            morph.report = morph.report.with_stages(stages).with_warnings(warnings);
            Ok(morph)
        })
    }
}

impl Morph for InfluencePath {
    type Field = Slice3;
    type Error = RbfError;

    fn method(&self) -> &'static str {
        "rbf-influence"
    }

    fn frame(&self, t: f32) -> Result<Frame<Slice3>, RbfError> {
        let t = check_time(t)?;
        Ok(Frame { field: self.shapes.slice(&self.point(t))?, iso: 0.0, transform: glam::Affine3A::IDENTITY })
    }

    fn field_bounds(&self) -> Aabb {
        self.shapes.bounds
    }

    fn world_bounds(&self) -> Aabb {
        self.shapes.bounds
    }

    fn report(&self) -> &MorphReport {
        &self.report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::{NormalOffset, Subsample, SurfaceSettings, field_constraints};
    use isomorph_common::marching_cubes::polygonize;
    use isomorph_common::mesh::distance::surface_distance;
    use isomorph_common::{Field3, Shape};

    fn shapes() -> Vec<Shape> {
        vec![
            Shape::sphere(0.3),
            Shape::torus(0.3, 0.12),
            Shape::rounded_cuboid(Vec3::splat(0.25), 0.05),
            Shape::cylinder(0.2, 0.3),
        ]
    }

    #[test]
    fn each_shape_is_reproduced_at_its_corner() {
        let s = SurfaceSettings {
            offset: NormalOffset::Absolute(0.01),
            subsample: Subsample::FarthestPoint(120),
        };
        let all: Vec<Vec<Constraint<3>>> =
            shapes().iter().map(|sh| field_constraints(sh, &Aabb::cube(0.5), 28, &s).unwrap()).collect();
        for count in [3usize, 4] {
            let refs: Vec<&[Constraint<3>]> = all[..count].iter().map(Vec::as_slice).collect();
            let inf = InfluenceShapes::new(&refs, &TransformSettings::default()).unwrap();
            assert_eq!(inf.len(), count);
            assert!(inf.report().max_residual.unwrap() < 1e-8);
            for (i, shape) in shapes()[..count].iter().enumerate() {
                let slice = inf.slice(inf.corner(i).unwrap()).unwrap();
                let worst = all[i]
                    .iter()
                    .step_by(2)
                    .map(|c| slice.value(Vec3::from_array(c.position)).abs())
                    .fold(0.0, f32::max);
                // The f64 fit is exact (residual above); the f32 slice is within
                // 5e-3 of the unit value, 5e-5 world units where |∇f| ≈ 100.
                assert!(worst < 5e-3, "{count} shapes, shape {i}: boundary value {worst}");
                let got = polygonize(&slice, &Aabb::cube(0.55), 40, 0.0).unwrap();
                let want = polygonize(shape, &Aabb::cube(0.55), 80, 0.0).unwrap();
                let d = surface_distance(&got, &want, 3000).unwrap();
                assert!(d.mean < 0.012, "{count} shapes, shape {i}: {d:?}");
            }
        }
    }

    #[test]
    fn path_runs_from_first_to_second_and_checks_input() {
        let s =
            SurfaceSettings { offset: NormalOffset::Absolute(0.01), subsample: Subsample::FarthestPoint(40) };
        let all: Vec<Vec<Constraint<3>>> =
            shapes()[..3].iter().map(|sh| field_constraints(sh, &Aabb::cube(0.5), 16, &s).unwrap()).collect();
        let refs: Vec<&[Constraint<3>]> = all.iter().map(Vec::as_slice).collect();
        let inf = InfluenceShapes::new(&refs, &TransformSettings::default()).unwrap();
        let (a, b, c) = (
            inf.corner(0).unwrap().to_vec(),
            inf.corner(1).unwrap().to_vec(),
            inf.corner(2).unwrap().to_vec(),
        );
        assert!(inf.clone().path(vec![a.clone()]).is_err());
        assert!(inf.clone().path(vec![a.clone(), vec![1.0]]).is_err());
        let path = inf.path(vec![a.clone(), c, b.clone()]).unwrap();
        assert_eq!(path.point(0.0), a);
        assert_eq!(path.point(1.0), b);
        assert!(path.point(0.5)[1] > 0.0, "the path bends towards the third shape");
        assert!(path.frame(0.5).unwrap().field.value(Vec3::new(0.0, 0.0, 0.2)).is_finite());
        assert!(matches!(path.frame(2.0), Err(RbfError::Morph(MorphError::InvalidTime(_)))));
        let two: Vec<&[Constraint<3>]> = refs[..2].to_vec();
        assert!(matches!(
            InfluenceShapes::new(&two, &TransformSettings::default()),
            Err(RbfError::InvalidInput(_))
        ));
    }

    #[test]
    fn an_influence_solid_pulls_the_in_betweens_towards_it() {
        let control = Control::new();
        let (sphere, torus) = (Solid::shape(Shape::sphere(0.3)), Solid::shape(Shape::torus(0.3, 0.12)));
        let cube = Solid::shape(Shape::rounded_cuboid(Vec3::splat(0.3), 0.04));
        let settings = RbfSettings { points: 150, ..Default::default() };
        let pulled =
            InfluencePath::from_solids(&sphere, &torus, std::slice::from_ref(&cube), &settings, &control)
                .unwrap();
        let plain = crate::RbfMorph::new(&sphere, &torus, &settings, &control).unwrap();
        let cube_surface = cube.surface(48, &control).unwrap().into_owned();
        let to_cube = |m: &dyn Fn(f32) -> isomorph_common::TriMesh| {
            surface_distance(&m(0.5), &cube_surface, 2000).unwrap().mean
        };
        let with = to_cube(&|t| pulled.frame_mesh(t, 48).unwrap());
        let without = to_cube(&|t| plain.frame_mesh(t, 48).unwrap());
        assert!(with < 0.8 * without, "mid-way {with} from the cube with its influence, {without} without");
        // The ends are still the source and the target.
        for (t, end) in [(0.0, &sphere), (1.0, &torus)] {
            let d = surface_distance(
                &pulled.frame_mesh(t, 48).unwrap(),
                &end.surface(48, &control).unwrap(),
                2000,
            );
            assert!(d.unwrap().mean < 0.01, "t = {t}");
        }
        let none = InfluencePath::from_solids(&sphere, &torus, &[], &settings, &control).unwrap_err();
        assert!(none.to_string().contains("one or two influence shapes"), "{none}");
    }
}
