//! The warping session of thesis §5.3: a source volume, a B-spline map, the
//! deformation mapping array, the accumulated target, and local updates when
//! control points move.

use crate::manipulate::{Drag, Handle, solve_drag};
use crate::pushforward::{Density, Filter, Splat, resolve};
use crate::table::{CoefficientTable, DeformationArray, Evaluation, Evaluator};
use crate::{BSplineMap, WarpError};
use glam::{UVec3, Vec3};
use isomorph_common::Grid3;
use rayon::prelude::*;

/// Settings of a [`VolumeWarp`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarpSettings {
    /// Control points per axis (the thesis' CSIZE, at least 4). Default 9.
    pub csize: u32,
    /// Empty voxels added on every side of the target so that the warped
    /// shape has room to grow (the thesis' `(TSIZE − ISIZE)/2`, 4 there).
    /// Default 4.
    pub pad: u32,
    /// How the density is pushed to the target. Default [`Filter::Box`].
    pub filter: Filter,
    /// How the map is evaluated at the voxels. Default [`Evaluation::Auto`].
    pub evaluation: Evaluation,
}

impl Default for WarpSettings {
    fn default() -> Self {
        Self { csize: 9, pad: 4, filter: Filter::Box, evaluation: Evaluation::Auto }
    }
}

/// The largest [`WarpSettings::pad`]: 4096 voxels per side.
pub const MAX_PAD: u32 = 4096;

/// Newton tolerance of the backward filter, in source voxels.
const NEWTON_TOLERANCE: f32 = 1e-3;
/// Newton iteration limit of the backward filter.
const NEWTON_ITERATIONS: u32 = 20;

/// A warped volume that stays up to date as control points move.
///
/// The target grid has the source's spacing, `pad` more voxels on each side,
/// and its origin moved by `−pad · spacing`, so world positions agree: with
/// the identity map the target holds the source unchanged at the same place.
#[derive(Debug, Clone)]
pub struct VolumeWarp<T> {
    source: Grid3<T>,
    map: BSplineMap,
    table: Option<CoefficientTable>,
    deformation: DeformationArray,
    accum: Vec<[f32; 2]>,
    target: Grid3<T>,
    settings: WarpSettings,
}

impl<T: Density> VolumeWarp<T> {
    /// Sets up the identity warp of `source` and computes the target (equal
    /// to the source, padded).
    ///
    /// # Errors
    /// Lattice errors of [`BSplineMap::identity`], [`WarpError::NonFiniteDensity`]
    /// for a NaN in an `f32` source, [`WarpError::NotTableable`] for
    /// [`Evaluation::Table`] on a size the table cannot serve, and
    /// [`MorphError::Grid`](isomorph_common::MorphError::Grid) when the target does not fit the memory limit,
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) for a `pad` above [`MAX_PAD`].
    pub fn new(source: Grid3<T>, settings: WarpSettings) -> Result<Self, WarpError> {
        let map = BSplineMap::identity(source.dims(), settings.csize)?;
        Self::with_map(source, map, settings)
    }

    /// Sets up the warp of `source` by `map` (whose lattice sets the control
    /// count; `settings.csize` is ignored) and computes the target.
    ///
    /// # Errors
    /// As [`VolumeWarp::new`], plus [`WarpError::Mismatch`] when the map was
    /// built for other source dimensions.
    pub fn with_map(source: Grid3<T>, map: BSplineMap, settings: WarpSettings) -> Result<Self, WarpError> {
        if map.source_dims() != source.dims() {
            return Err(WarpError::Mismatch(format!(
                "map built for {} source voxels, source has {}",
                map.source_dims(),
                source.dims()
            )));
        }
        if let Some(n) = source.data().iter().position(|v| !v.to_f32().is_finite()) {
            return Err(WarpError::NonFiniteDensity(n));
        }
        let table = match settings.evaluation {
            Evaluation::Table => Some(CoefficientTable::new(&map)?),
            _ => None,
        };
        let deformation = DeformationArray::identity(source.dims())?;
        let pad = settings.pad;
        isomorph_common::check::count("pad", u64::from(pad), 0, u64::from(MAX_PAD))?;
        let dims = source.dims().saturating_add(UVec3::splat(2 * pad));
        let origin = source.origin() - Vec3::splat(pad as f32 * source.spacing());
        let target = Grid3::new(dims, origin, source.spacing(), T::ZERO)?;
        let accum = if settings.filter == Filter::Backward {
            Vec::new()
        } else {
            target.with_same_lattice([0.0f32; 2])?.into_data()
        };
        let mut warp = Self { source, map, table, deformation, accum, target, settings };
        warp.recompute();
        Ok(warp)
    }

    /// The source volume.
    pub fn source(&self) -> &Grid3<T> {
        &self.source
    }

    /// The current map.
    pub fn map(&self) -> &BSplineMap {
        &self.map
    }

    /// The warped volume (padded target).
    pub fn target(&self) -> &Grid3<T> {
        &self.target
    }

    /// The deformation mapping array (image of every source voxel centre, in
    /// source voxel coordinates; add `pad` for target voxel coordinates).
    pub fn deformation(&self) -> &DeformationArray {
        &self.deformation
    }

    /// The settings in force.
    pub fn settings(&self) -> &WarpSettings {
        &self.settings
    }

    /// Consumes the session, returning the warped volume.
    pub fn into_target(self) -> Grid3<T> {
        self.target
    }

    /// Replaces the whole map and recomputes everything.
    ///
    /// # Errors
    /// [`WarpError::Mismatch`] when `map` has another source size or lattice.
    pub fn set_map(&mut self, map: BSplineMap) -> Result<(), WarpError> {
        if map.source_dims() != self.map.source_dims() || map.controls() != self.map.controls() {
            return Err(WarpError::Mismatch(format!(
                "new map has {} controls over {} voxels, the warp {} over {}",
                map.controls(),
                map.source_dims(),
                self.map.controls(),
                self.map.source_dims()
            )));
        }
        self.map = map;
        self.recompute();
        Ok(())
    }

    /// Recomputes the deformation array and the whole target from scratch.
    fn recompute(&mut self) {
        let dims = self.source.dims();
        self.deformation.update(
            &self.map,
            Evaluator::new(self.settings.evaluation, self.table.as_ref()),
            UVec3::ZERO,
            dims,
        );
        let all = (UVec3::ZERO, self.target.dims() - UVec3::ONE);
        if self.settings.filter == Filter::Backward {
            self.backward(all.0, all.1);
        } else {
            self.accum.par_iter_mut().for_each(|c| *c = [0.0; 2]);
            self.splat(UVec3::ZERO, dims, 1.0);
            resolve(&self.accum, &mut self.target, all.0, all.1);
        }
    }

    fn splat(&mut self, lo: UVec3, hi: UVec3, sign: f32) -> Option<(UVec3, UVec3)> {
        let splat = Splat {
            source: self.source.data(),
            deformation: &self.deformation,
            filter: self.settings.filter,
            pad: self.settings.pad,
            target_dims: self.target.dims(),
        };
        splat.run(&mut self.accum, lo, hi, sign)
    }

    /// Moves control points to new positions (source voxel units) and
    /// updates the target locally (thesis §5.3 main loop): only the regions
    /// `i − 3 ≤ a ≤ i` (per axis) of each moved point `i` are re-mapped; their
    /// old contribution is subtracted from the accumulated weights and
    /// weighted values, the new one added, and the touched target voxels
    /// renormalized. (The thesis zeroed the old footprint instead, an
    /// approximation; subtracting keeps the result equal to a full
    /// recompute up to float rounding.) The backward filter recomputes the
    /// target voxels in the old and new images of the affected regions.
    ///
    /// Moves are applied one after the other, each with its own local
    /// update. Returns the number of source voxels re-mapped.
    ///
    /// # Errors
    /// [`WarpError::ControlOutOfRange`] or [`WarpError::NonFinite`] for a bad
    /// move; the warp is left unchanged then.
    pub fn move_control_points(&mut self, moves: &[(UVec3, Vec3)]) -> Result<usize, WarpError> {
        let mut check = self.map.clone();
        for &(c, p) in moves {
            check.set_control_point(c, p)?;
        }
        // One local update per moved point: far-apart points do not re-map
        // everything in between, and overlapping updates compose exactly.
        Ok(moves.iter().map(|&(c, p)| self.move_one(c, p)).sum())
    }

    /// The local update for one validated control point move.
    fn move_one(&mut self, c: UVec3, position: Vec3) -> usize {
        let (lo, hi) = self.map.influence_box(c);
        let moved =
            |map: &mut BSplineMap| map.set_control_point(c, position).expect("validated by the caller");
        if lo.cmpge(hi).any() {
            moved(&mut self.map);
            return 0;
        }
        // Source voxels whose box uses a changed map value: one voxel more
        // on each side (their face centres average with the changed voxel).
        let dims = self.source.dims();
        let (slo, shi) = (lo.saturating_sub(UVec3::ONE), (hi + UVec3::ONE).min(dims));
        if self.settings.filter == Filter::Backward {
            let old = self.image_box(slo, shi);
            moved(&mut self.map);
            self.deformation.update(
                &self.map,
                Evaluator::new(self.settings.evaluation, self.table.as_ref()),
                lo,
                hi,
            );
            let new = self.image_box(slo, shi);
            if let Some((a, b)) = union(old, new) {
                self.backward(a, b);
            }
        } else {
            let old = self.splat(slo, shi, -1.0);
            moved(&mut self.map);
            self.deformation.update(
                &self.map,
                Evaluator::new(self.settings.evaluation, self.table.as_ref()),
                lo,
                hi,
            );
            let new = self.splat(slo, shi, 1.0);
            if let Some((a, b)) = union(old, new) {
                resolve(&self.accum, &mut self.target, a, b);
            }
        }
        let n = hi - lo;
        n.x as usize * n.y as usize * n.z as usize
    }

    /// Direct manipulation (thesis §6): moves the control points by the
    /// minimum-norm change that sends each handle's source point to its goal
    /// ([`solve_drag`]), optionally only those within `influence` voxels of a
    /// handle, and updates the target locally.
    ///
    /// # Errors
    /// As [`solve_drag`].
    pub fn drag(&mut self, handles: &[Handle], influence: Option<f32>) -> Result<Drag, WarpError> {
        let drag = solve_drag(&self.map, handles, influence)?;
        self.move_control_points(&drag.moves)?;
        Ok(drag)
    }

    /// Inclusive target voxel box containing the image of the source voxels
    /// `[lo, hi)`, one voxel of margin.
    fn image_box(&self, lo: UVec3, hi: UVec3) -> Option<(UVec3, UVec3)> {
        let (mut a, mut b) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for g in lo.z..hi.z {
            for f in lo.y..hi.y {
                for e in lo.x..hi.x {
                    let p = Vec3::from(self.deformation.get(e, f, g));
                    a = a.min(p);
                    b = b.max(p);
                }
            }
        }
        let pad = Vec3::splat(self.settings.pad as f32);
        let max = (self.target.dims() - UVec3::ONE).as_vec3();
        let (a, b) = ((a + pad - 1.0).floor().max(Vec3::ZERO), (b + pad + 1.0).ceil().min(max));
        a.cmple(b).all().then(|| (a.as_uvec3(), b.as_uvec3()))
    }

    /// Backward resampling of the inclusive target box `[lo, hi]`.
    fn backward(&mut self, lo: UVec3, hi: UVec3) {
        let dims = self.target.dims();
        let layer = dims.x as usize * dims.y as usize;
        let pad = Vec3::splat(self.settings.pad as f32);
        let (map, source) = (&self.map, &self.source);
        let sdims = source.dims();
        let upper = sdims.as_vec3() - 0.5;
        let sample = |x: Vec3| -> f32 {
            if x.cmplt(Vec3::splat(-0.5)).any() || x.cmpgt(upper).any() {
                return 0.0;
            }
            let g = x.clamp(Vec3::ZERO, (sdims - UVec3::ONE).as_vec3());
            let base = g.floor().min((sdims.saturating_sub(UVec3::splat(2))).as_vec3());
            let w = g - base;
            let b = base.as_uvec3();
            let v = |d: UVec3| {
                let n = (b + d).min(sdims - UVec3::ONE);
                source.get(n.x, n.y, n.z).map_or(0.0, |v| v.to_f32())
            };
            let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
            let x00 = lerp(v(UVec3::new(0, 0, 0)), v(UVec3::new(1, 0, 0)), w.x);
            let x10 = lerp(v(UVec3::new(0, 1, 0)), v(UVec3::new(1, 1, 0)), w.x);
            let x01 = lerp(v(UVec3::new(0, 0, 1)), v(UVec3::new(1, 0, 1)), w.x);
            let x11 = lerp(v(UVec3::new(0, 1, 1)), v(UVec3::new(1, 1, 1)), w.x);
            lerp(lerp(x00, x10, w.y), lerp(x01, x11, w.y), w.z)
        };
        self.target.data_mut()[lo.z as usize * layer..(hi.z as usize + 1) * layer]
            .par_chunks_mut(layer)
            .enumerate()
            .for_each(|(dz, out)| {
                let z = lo.z + dz as u32;
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let goal = Vec3::new(x as f32, y as f32, z as f32) - pad;
                        let value =
                            map.inverse(goal, NEWTON_TOLERANCE, NEWTON_ITERATIONS).map_or(0.0, sample);
                        out[x as usize + y as usize * dims.x as usize] = T::from_f32(value);
                    }
                }
            });
    }
}

fn union(a: Option<(UVec3, UVec3)>, b: Option<(UVec3, UVec3)>) -> Option<(UVec3, UVec3)> {
    match (a, b) {
        (Some((a, b)), Some((c, d))) => Some((a.min(c), b.max(d))),
        (x, None) | (None, x) => x,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A blobby u8 density: a ball of radius `r` voxels around `c`, smooth
    /// over about 2 voxels.
    fn ball(dims: UVec3, c: Vec3, r: f32) -> Grid3<u8> {
        let mut g = Grid3::new(dims, Vec3::ZERO, 1.0, 0u8).unwrap();
        for n in 0..g.len() {
            let p = g.node_of(n).as_vec3();
            let d = r - (p - c).length();
            g.data_mut()[n] = (127.5 + 64.0 * d).clamp(0.0, 255.0) as u8;
        }
        g
    }

    fn noise(dims: UVec3, seed: u64) -> Grid3<f32> {
        let mut s = seed;
        let data = (0..dims.x * dims.y * dims.z)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((s >> 40) as f32) / (1u64 << 24) as f32
            })
            .collect();
        Grid3::from_vec(dims, Vec3::ZERO, 1.0, data).unwrap()
    }

    #[test]
    fn a_pad_that_would_wrap_is_a_bad_setting() {
        let source = Grid3::new(UVec3::splat(8), Vec3::ZERO, 1.0, 0u8).unwrap();
        let err = VolumeWarp::new(source, settings(4, u32::MAX, Filter::Box)).err().unwrap();
        assert!(
            matches!(err, WarpError::Morph(isomorph_common::MorphError::BadSetting { name: "pad", .. })),
            "{err}"
        );
    }

    fn settings(csize: u32, pad: u32, filter: Filter) -> WarpSettings {
        WarpSettings { csize, pad, filter, evaluation: Evaluation::Auto }
    }

    /// Target value at source voxel `p` shifted by `shift` (and the padding).
    fn at<T: Density>(w: &VolumeWarp<T>, p: UVec3, shift: IVec3) -> T {
        let q = (p.as_ivec3() + shift + IVec3::splat(w.settings().pad as i32)).as_uvec3();
        *w.target().get(q.x, q.y, q.z).unwrap()
    }

    use glam::IVec3;

    fn translate_all(map: &mut BSplineMap, d: Vec3) {
        let c = map.controls();
        for k in 0..c.z {
            for j in 0..c.y {
                for i in 0..c.x {
                    map.set_displacement(UVec3::new(i, j, k), d).unwrap();
                }
            }
        }
    }

    #[test]
    fn identity_warp_reproduces_u8_and_f32_for_every_filter() {
        let dims = UVec3::new(14, 12, 10);
        let dens = ball(dims, Vec3::new(6.5, 5.0, 4.5), 3.5);
        let field = noise(dims, 3);
        for filter in [Filter::Box, Filter::Round, Filter::Backward] {
            let wu = VolumeWarp::new(dens.clone(), settings(5, 2, filter)).unwrap();
            let wf = VolumeWarp::new(field.clone(), settings(5, 2, filter)).unwrap();
            for n in 0..dens.len() {
                let p = dens.node_of(n);
                assert_eq!(at(&wu, p, IVec3::ZERO), dens.data()[n], "{filter:?} u8 at {p}");
                assert_eq!(at(&wf, p, IVec3::ZERO), field.data()[n], "{filter:?} f32 at {p}");
            }
            let inside: u64 = dens.data().iter().map(|&v| u64::from(v)).sum();
            let total: u64 = wu.target().data().iter().map(|&v| u64::from(v)).sum();
            assert_eq!(inside, total, "{filter:?}: the padding must stay empty");
            assert_eq!(wu.target().origin(), Vec3::splat(-2.0));
        }
    }

    #[test]
    fn whole_voxel_translation_shifts_exactly() {
        let dims = UVec3::new(16, 12, 12);
        let dens = ball(dims, Vec3::new(7.0, 6.0, 5.5), 3.0);
        let field = noise(dims, 5);
        let shift = IVec3::new(2, -1, 1);
        let mut map = BSplineMap::identity(dims, 6).unwrap();
        translate_all(&mut map, shift.as_vec3());
        for filter in [Filter::Box, Filter::Round, Filter::Backward] {
            let wu = VolumeWarp::with_map(dens.clone(), map.clone(), settings(6, 3, filter)).unwrap();
            let wf = VolumeWarp::with_map(field.clone(), map.clone(), settings(6, 3, filter)).unwrap();
            for n in 0..dens.len() {
                let p = dens.node_of(n);
                assert_eq!(at(&wu, p, shift), dens.data()[n], "{filter:?} u8 at {p}");
                let (got, want) = (at(&wf, p, shift), field.data()[n]);
                assert!((got - want).abs() < 1e-5, "{filter:?} f32 at {p}: expected {want}, got {got}");
            }
        }
    }

    #[test]
    fn half_voxel_translation_averages_neighbours_with_the_box_filter() {
        // Each source box straddles two target voxels with weight 1/2 each.
        let dims = UVec3::new(12, 8, 8);
        let field = noise(dims, 9);
        let mut map = BSplineMap::identity(dims, 6).unwrap();
        translate_all(&mut map, Vec3::new(0.5, 0.0, 0.0));
        let w = VolumeWarp::with_map(field.clone(), map, settings(6, 1, Filter::Box)).unwrap();
        for n in 0..field.len() {
            let p = field.node_of(n);
            if p.x == 0 {
                continue;
            }
            let want = 0.5 * (field.data()[n] + field.data()[n - 1]);
            let got = at(&w, p, IVec3::ZERO);
            assert!((got - want).abs() < 1e-5, "at {p}: expected {want}, got {got}");
        }
        // The first voxel is half covered: weight 1/2 keeps half its value.
        let got = at(&w, UVec3::new(0, 3, 3), IVec3::ZERO);
        let want = 0.5 * field.get(0, 3, 3).unwrap();
        assert!((got - want).abs() < 1e-5, "half-covered voxel: expected {want}, got {got}");
    }

    #[test]
    fn volume_preserving_warp_keeps_the_mass() {
        // x' = x + s(y): a sheared ball, Jacobian determinant exactly 1.
        let dims = UVec3::splat(32);
        let dens = ball(dims, Vec3::splat(15.5), 8.0);
        let mut map = BSplineMap::identity(dims, 8).unwrap();
        let c = map.controls();
        for k in 0..c.z {
            for j in 0..c.y {
                for i in 0..c.x {
                    let d = Vec3::new(3.0 * (j as f32 * 1.3).sin(), 0.0, 0.0);
                    map.set_displacement(UVec3::new(i, j, k), d).unwrap();
                }
            }
        }
        let mass = |g: &Grid3<u8>| g.data().iter().map(|&v| f64::from(v)).sum::<f64>();
        for (filter, tolerance) in [(Filter::Box, 0.005), (Filter::Backward, 0.005), (Filter::Round, 0.005)] {
            let w = VolumeWarp::with_map(dens.clone(), map.clone(), settings(8, 6, filter)).unwrap();
            let ratio = mass(w.target()) / mass(&dens);
            assert!((ratio - 1.0).abs() < tolerance, "{filter:?}: mass ratio {ratio}");
        }
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let small = noise(UVec3::splat(5), 1);
        assert!(matches!(
            VolumeWarp::new(small, WarpSettings::default()),
            Err(WarpError::LatticeTooFine { .. })
        ));
        let mut field = noise(UVec3::splat(8), 1);
        field.data_mut()[17] = f32::NAN;
        assert!(matches!(
            VolumeWarp::new(field, settings(5, 1, Filter::Box)),
            Err(WarpError::NonFiniteDensity(17))
        ));
        let map = BSplineMap::identity(UVec3::splat(9), 5).unwrap();
        assert!(matches!(
            VolumeWarp::with_map(noise(UVec3::splat(8), 1), map, settings(5, 1, Filter::Box)),
            Err(WarpError::Mismatch(_))
        ));
        let mut w = VolumeWarp::new(noise(UVec3::splat(8), 1), settings(5, 1, Filter::Box)).unwrap();
        let before = w.target().clone();
        let bad = [(UVec3::ONE, Vec3::ONE), (UVec3::new(9, 0, 0), Vec3::ONE)];
        assert!(matches!(w.move_control_points(&bad), Err(WarpError::ControlOutOfRange { .. })));
        assert_eq!(w.target(), &before, "a failed move leaves the warp unchanged");
    }

    #[test]
    fn dragging_a_volume_point_moves_its_density() {
        // Drag the centre of a small ball 3 voxels along x: the ball's peak
        // follows, and the result equals a full warp by the solved map.
        let dims = UVec3::splat(24);
        let dens = ball(dims, Vec3::new(10.0, 12.0, 12.0), 2.5);
        let mut w = VolumeWarp::new(dens.clone(), settings(7, 2, Filter::Box)).unwrap();
        let handle = Handle { point: Vec3::new(10.0, 12.0, 12.0), goal: Vec3::new(13.0, 12.0, 12.0) };
        let drag = w.drag(&[handle], None).unwrap();
        assert!(drag.residual < 1e-3);
        assert!((w.map().eval(handle.point) - handle.goal).length() < 1e-3);
        let moved = at(&w, UVec3::new(13, 12, 12), IVec3::ZERO);
        assert!(moved > 200, "density at the goal {moved}");
        let full = VolumeWarp::with_map(dens, w.map().clone(), settings(7, 2, Filter::Box)).unwrap();
        for (a, b) in w.target().data().iter().zip(full.target().data()) {
            assert!(a.abs_diff(*b) <= 1, "local {a} vs full {b}");
        }
    }

    fn check_local_update(filter: Filter, moves: &[(UVec3, Vec3)], seed: u64) {
        let dims = UVec3::new(24, 20, 16);
        let field = noise(dims, seed);
        let mut local = VolumeWarp::new(field.clone(), settings(7, 3, filter)).unwrap();
        // A first, global edit so the local update starts from a warped state.
        let mut map = local.map().clone();
        map.set_displacement(UVec3::new(3, 3, 3), Vec3::new(1.0, 0.5, -0.5)).unwrap();
        local.set_map(map).unwrap();
        let touched = local.move_control_points(moves).unwrap();
        // Each move re-maps at most 4×4×4 regions of 6×5×4 voxels.
        assert!(touched <= moves.len() * 24 * 20 * 16, "re-mapped {touched} voxels");
        let full = VolumeWarp::with_map(field, local.map().clone(), settings(7, 3, filter)).unwrap();
        for (n, (a, b)) in local.target().data().iter().zip(full.target().data()).enumerate() {
            assert!((a - b).abs() < 1e-4, "{filter:?} target voxel {n}: local {a}, full {b}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]
        #[test]
        fn local_update_equals_full_recompute(
            c in (0u32..7, 0u32..7, 0u32..7),
            d in (-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0),
            c2 in (0u32..7, 0u32..7, 0u32..7),
            filter in prop_oneof![Just(Filter::Box), Just(Filter::Round), Just(Filter::Backward)],
            seed in 0u64..1000,
        ) {
            let map = BSplineMap::identity(UVec3::new(24, 20, 16), 7).unwrap();
            let (c, c2) = (UVec3::new(c.0, c.1, c.2), UVec3::new(c2.0, c2.1, c2.2));
            let moves = [
                (c, map.rest_position(c) + Vec3::new(d.0, d.1, d.2)),
                (c2, map.rest_position(c2) - 0.5 * Vec3::new(d.2, d.0, d.1)),
            ];
            check_local_update(filter, &moves, seed);
        }
    }
}
