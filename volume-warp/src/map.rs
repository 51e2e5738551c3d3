//! The trivariate uniform cubic B-spline map `B` of thesis §5.1 and its
//! control lattice (§5.5).

use crate::WarpError;
use crate::basis::{derivatives, weights};
use glam::{Mat3, UVec3, Vec3};

/// A trivariate cubic B-spline map from the source voxel space to itself
/// (target voxel coordinates minus the target padding).
///
/// Coordinates are **source voxel coordinates**: voxel `(e, f, g)` of the
/// source volume sits at the point `(e, f, g)`. A lattice of `C = controls`
/// points per axis spans `C − 3` regions per axis; region `a` covers
/// `a·h ≤ x < (a + 1)·h` with `h = source_dims / (C − 3)` voxels per region
/// (the thesis' granularity `G` when it is an integer). The voxel at `x` has
/// spline parameter `s = x / h` (eq. 2).
///
/// Control point `m` rests at `(m − 1)·h` (§5.5: an evenly spaced lattice
/// whose end points lie outside the data). Because `Σ_i B_i(t)(a + i − 1) =
/// a + t`, the untouched lattice maps every point exactly to itself. The map
/// stores each control point as its **displacement** from that rest position
/// and evaluates `B(x) = x + Σ B_i B_j B_k D_{a+i,b+j,c+k}` — by linear
/// precision the same map as eq. 3 over the absolute positions, but the
/// identity is reproduced bit for bit and rounding scales with the
/// displacement, not with the coordinates.
///
/// Outside `[0, source_dims)` the map continues the polynomial of the nearest
/// region (needed by the boundary voxels' faces and by inversion).
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineMap {
    source_dims: UVec3,
    controls: UVec3,
    step: Vec3,
    displacement: Vec<Vec3>,
}

impl BSplineMap {
    /// The identity map of a source of `source_dims` voxels with a cubic
    /// lattice of `csize` control points per axis (the thesis' CSIZE; 9 in its
    /// examples).
    ///
    /// # Errors
    /// As [`BSplineMap::with_controls`].
    pub fn identity(source_dims: UVec3, csize: u32) -> Result<Self, WarpError> {
        Self::with_controls(source_dims, UVec3::splat(csize))
    }

    /// The identity map with `controls` control points along each axis.
    ///
    /// # Errors
    /// [`WarpError::LatticeTooSmall`] for fewer than 4 points on an axis,
    /// [`WarpError::LatticeTooFine`] for more regions than voxels on an axis
    /// (this includes a zero source dimension).
    pub fn with_controls(source_dims: UVec3, controls: UVec3) -> Result<Self, WarpError> {
        if controls.min_element() < 4 {
            return Err(WarpError::LatticeTooSmall { controls });
        }
        let regions = controls - UVec3::splat(3);
        if regions.cmpgt(source_dims).any() {
            return Err(WarpError::LatticeTooFine { controls, source_dims });
        }
        let count = controls.x as usize * controls.y as usize * controls.z as usize;
        Ok(Self {
            source_dims,
            controls,
            step: source_dims.as_vec3() / regions.as_vec3(),
            displacement: vec![Vec3::ZERO; count],
        })
    }

    /// Source voxels per axis.
    pub fn source_dims(&self) -> UVec3 {
        self.source_dims
    }

    /// Control points per axis (CSIZE).
    pub fn controls(&self) -> UVec3 {
        self.controls
    }

    /// Every control point index, x fastest.
    pub fn control_indices(&self) -> impl Iterator<Item = UVec3> + use<> {
        let c = self.controls;
        (0..c.z).flat_map(move |k| (0..c.y).flat_map(move |j| (0..c.x).map(move |i| UVec3::new(i, j, k))))
    }

    /// The map with every displacement multiplied by `s`: the identity for
    /// `s = 0`, this map for `s = 1`, every map in between a B-spline map
    /// too (how morphs animate a warp).
    ///
    /// # Errors
    /// [`WarpError::NonFinite`] for a non-finite `s`.
    pub fn scaled(&self, s: f32) -> Result<Self, WarpError> {
        if !s.is_finite() {
            return Err(WarpError::NonFinite { what: "displacement scale", value: Vec3::splat(s) });
        }
        let mut out = self.clone();
        out.displacement.iter_mut().for_each(|d| *d *= s);
        Ok(out)
    }

    /// Regions per axis (`controls − 3`).
    pub fn regions(&self) -> UVec3 {
        self.controls - UVec3::splat(3)
    }

    /// Voxels per region along each axis (the control point spacing `h`; the
    /// granularity `G` of thesis §5.1 when integer).
    pub fn step(&self) -> Vec3 {
        self.step
    }

    /// Linear index of control point `c` (x-fastest).
    #[inline]
    pub(crate) fn control_index(&self, c: UVec3) -> usize {
        c.x as usize + self.controls.x as usize * (c.y as usize + self.controls.y as usize * c.z as usize)
    }

    fn check_index(&self, c: UVec3) -> Result<usize, WarpError> {
        if c.cmpge(self.controls).any() {
            return Err(WarpError::ControlOutOfRange { index: c, controls: self.controls });
        }
        Ok(self.control_index(c))
    }

    /// Rest position of control point `c`: `(c − 1)·h` in source voxels.
    pub fn rest_position(&self, c: UVec3) -> Vec3 {
        (c.as_vec3() - Vec3::ONE) * self.step
    }

    /// Current position of control point `c` (source voxel units).
    ///
    /// # Errors
    /// [`WarpError::ControlOutOfRange`] for an index outside the lattice.
    pub fn control_point(&self, c: UVec3) -> Result<Vec3, WarpError> {
        let i = self.check_index(c)?;
        Ok(self.rest_position(c) + self.displacement[i])
    }

    /// Displacement of control point `c` from its rest position.
    ///
    /// # Errors
    /// [`WarpError::ControlOutOfRange`] for an index outside the lattice.
    pub fn displacement(&self, c: UVec3) -> Result<Vec3, WarpError> {
        Ok(self.displacement[self.check_index(c)?])
    }

    /// All displacements, x-fastest over the lattice.
    pub fn displacements(&self) -> &[Vec3] {
        &self.displacement
    }

    /// Moves control point `c` to `position` (source voxel units).
    ///
    /// # Errors
    /// [`WarpError::ControlOutOfRange`], or [`WarpError::NonFinite`] for a
    /// NaN or infinite position.
    pub fn set_control_point(&mut self, c: UVec3, position: Vec3) -> Result<(), WarpError> {
        self.set_displacement(c, position - self.rest_position(c))
    }

    /// Sets the displacement of control point `c` from its rest position.
    ///
    /// # Errors
    /// [`WarpError::ControlOutOfRange`], or [`WarpError::NonFinite`].
    pub fn set_displacement(&mut self, c: UVec3, displacement: Vec3) -> Result<(), WarpError> {
        let i = self.check_index(c)?;
        if !displacement.is_finite() {
            return Err(WarpError::NonFinite { what: "control point displacement", value: displacement });
        }
        self.displacement[i] = displacement;
        Ok(())
    }

    /// Region index and local parameter of the source coordinate `x` along
    /// `axis`: `a = clamp(⌊x/h⌋, 0, regions − 1)`, `t = x/h − a` (in `[0, 1)`
    /// inside the source, extrapolated outside).
    #[inline]
    pub(crate) fn locate(&self, x: f32, axis: usize) -> (u32, f32) {
        let s = x / self.step[axis];
        let last = (self.controls[axis] - 4) as f32;
        let a = s.floor().clamp(0.0, last);
        (a as u32, s - a)
    }

    /// `B(x)` by direct basis evaluation (eq. 3): locate the region, evaluate
    /// the 12 basis values, blend the 64 control points.
    pub fn eval(&self, x: Vec3) -> Vec3 {
        let (a, tx) = self.locate(x.x, 0);
        let (b, ty) = self.locate(x.y, 1);
        let (c, tz) = self.locate(x.z, 2);
        let (wx, wy, wz) = (weights(tx), weights(ty), weights(tz));
        x + self.blend(UVec3::new(a, b, c), &wx, &wy, &wz)
    }

    /// `Σ wx_i wy_j wz_k D_{a+i, b+j, c+k}` over the region at `corner`.
    #[inline]
    fn blend(&self, corner: UVec3, wx: &[f32; 4], wy: &[f32; 4], wz: &[f32; 4]) -> Vec3 {
        let (cx, cy) = (self.controls.x as usize, self.controls.y as usize);
        let base = self.control_index(corner);
        let mut sum = Vec3::ZERO;
        for (k, &wk) in wz.iter().enumerate() {
            for (j, &wj) in wy.iter().enumerate() {
                let row = base + cx * (j + cy * k);
                let wjk = wj * wk;
                for (i, &wi) in wx.iter().enumerate() {
                    sum += (wi * wjk) * self.displacement[row + i];
                }
            }
        }
        sum
    }

    /// The Jacobian matrix `∂B/∂x` at `x` (columns are the derivatives along
    /// x, y and z), from the basis derivatives.
    pub fn jacobian(&self, x: Vec3) -> Mat3 {
        let (a, tx) = self.locate(x.x, 0);
        let (b, ty) = self.locate(x.y, 1);
        let (c, tz) = self.locate(x.z, 2);
        let (wx, wy, wz) = (weights(tx), weights(ty), weights(tz));
        let inv = self.step.recip();
        let (dx, dy, dz) = (derivatives(tx), derivatives(ty), derivatives(tz));
        let corner = UVec3::new(a, b, c);
        Mat3::from_cols(
            Vec3::X + inv.x * self.blend(corner, &dx, &wy, &wz),
            Vec3::Y + inv.y * self.blend(corner, &wx, &dy, &wz),
            Vec3::Z + inv.z * self.blend(corner, &wx, &wy, &dz),
        )
    }

    /// An approximate inverse: the `x` with `B(x) = y`, by damped Newton
    /// iteration from `x = y`, or `None` when it does not converge to
    /// `tolerance` voxels within `max_iterations` (a fold or a point outside
    /// the image). For an injective map the answer is the unique preimage.
    pub fn inverse(&self, y: Vec3, tolerance: f32, max_iterations: u32) -> Option<Vec3> {
        let mut x = y;
        let mut r = self.eval(x) - y;
        for _ in 0..max_iterations {
            let err = r.length();
            if err <= tolerance {
                return Some(x);
            }
            let j = self.jacobian(x);
            let det = j.determinant();
            if !det.is_finite() || det.abs() < 1e-12 {
                return None;
            }
            let dx = j.inverse() * r;
            // Halve the step until the residual decreases (at most 8 times).
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..8 {
                let xn = x - lambda * dx;
                let rn = self.eval(xn) - y;
                if rn.length() < err {
                    x = xn;
                    r = rn;
                    accepted = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                return None;
            }
        }
        (r.length() <= tolerance).then_some(x)
    }

    /// The control points whose support contains the source point `x`: the
    /// corner of the 4×4×4 block of the region containing `x`.
    pub fn support_corner(&self, x: Vec3) -> UVec3 {
        UVec3::new(self.locate(x.x, 0).0, self.locate(x.y, 1).0, self.locate(x.z, 2).0)
    }

    /// The 64 basis weight products at `x`, ordered like the control points
    /// of [`BSplineMap::support_corner`]`(x) + (i, j, k)` with `i` fastest.
    pub fn weights_at(&self, x: Vec3) -> [f32; 64] {
        let (wx, wy, wz) =
            (weights(self.locate(x.x, 0).1), weights(self.locate(x.y, 1).1), weights(self.locate(x.z, 2).1));
        let mut out = [0.0; 64];
        for (n, w) in out.iter_mut().enumerate() {
            *w = wx[n & 3] * wy[(n >> 2) & 3] * wz[n >> 4];
        }
        out
    }

    /// The source voxels (half-open box `[lo, hi)`) whose map value depends
    /// on control point `c`: the regions `c − 3 ≤ a ≤ c` per axis (§5.3),
    /// clamped to the source.
    pub fn influence_box(&self, c: UVec3) -> (UVec3, UVec3) {
        let regions = self.regions();
        let lo_region = c.saturating_sub(UVec3::splat(3)).min(regions);
        let hi_region = (c + UVec3::ONE).min(regions);
        (self.region_start(lo_region), self.region_start(hi_region))
    }

    /// First source voxel of region `r` along each axis (voxel `e` lies in
    /// region `⌊e/h⌋`, clamped to the last region).
    pub(crate) fn region_start(&self, r: UVec3) -> UVec3 {
        let mut out = UVec3::ZERO;
        for axis in 0..3 {
            out[axis] = if r[axis] >= self.regions()[axis] {
                self.source_dims[axis]
            } else {
                // Smallest voxel e with ⌊e / h⌋ ≥ r (robust to rounding of e/h).
                let mut e = ((r[axis] as f32) * self.step[axis]).ceil() as u32;
                while e > 0 && self.locate((e - 1) as f32, axis).0 >= r[axis] {
                    e -= 1;
                }
                while e < self.source_dims[axis] && self.locate(e as f32, axis).0 < r[axis] {
                    e += 1;
                }
                e
            };
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 40) as f32) / (1u64 << 24) as f32
    }

    #[test]
    fn identity_lattice_maps_every_point_to_itself_exactly() {
        let map = BSplineMap::identity(UVec3::new(20, 17, 12), 7).unwrap();
        let mut seed = 1;
        for _ in 0..500 {
            let x = Vec3::new(
                lcg(&mut seed) * 24.0 - 2.0,
                lcg(&mut seed) * 20.0 - 2.0,
                lcg(&mut seed) * 14.0 - 1.0,
            );
            assert_eq!(map.eval(x), x);
            let j = map.jacobian(x);
            assert!((j.determinant() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn absolute_control_points_reproduce_eq_3() {
        // Eq. 3 blends absolute positions P = rest + D; the displacement form
        // must give the same point.
        let mut map = BSplineMap::identity(UVec3::splat(12), 6).unwrap();
        let mut seed = 7;
        for k in 0..6 {
            for j in 0..6 {
                for i in 0..6 {
                    let d = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) - 0.5;
                    map.set_displacement(UVec3::new(i, j, k), 3.0 * d).unwrap();
                }
            }
        }
        let x = Vec3::new(5.3, 7.9, 2.2);
        let corner = map.support_corner(x);
        let w = map.weights_at(x);
        let mut eq3 = Vec3::ZERO;
        for (n, &wn) in w.iter().enumerate() {
            let c = corner + UVec3::new(n as u32 & 3, (n as u32 >> 2) & 3, n as u32 >> 4);
            eq3 += wn * map.control_point(c).unwrap();
        }
        let got = map.eval(x);
        assert!((got - eq3).length() < 1e-4, "eq. 3 {eq3} vs displacement form {got}");
    }

    #[test]
    fn affine_lattice_gives_the_affine_map() {
        let dims = UVec3::new(16, 12, 20);
        let mut map = BSplineMap::with_controls(dims, UVec3::new(8, 7, 9)).unwrap();
        let a =
            Mat3::from_cols(Vec3::new(1.1, 0.2, -0.1), Vec3::new(0.05, 0.9, 0.3), Vec3::new(-0.2, 0.1, 1.2));
        let t = Vec3::new(1.5, -2.0, 0.75);
        let affine = |p: Vec3| a * p + t;
        let c = map.controls();
        for k in 0..c.z {
            for j in 0..c.y {
                for i in 0..c.x {
                    let idx = UVec3::new(i, j, k);
                    let rest = map.rest_position(idx);
                    map.set_control_point(idx, affine(rest)).unwrap();
                }
            }
        }
        let mut seed = 3;
        for _ in 0..300 {
            let x = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * dims.as_vec3();
            let got = map.eval(x);
            assert!((got - affine(x)).length() < 1e-4, "B({x}) = {got}, affine {}", affine(x));
            let jac = map.jacobian(x);
            assert!((jac - a).abs_diff_eq(Mat3::ZERO, 1e-4), "Jacobian {jac} vs {a}");
        }
    }

    #[test]
    fn jacobian_matches_finite_differences_and_inverse_round_trips() {
        let mut map = BSplineMap::identity(UVec3::splat(18), 9).unwrap();
        let mut seed = 11;
        for n in 0..map.displacements().len() as u32 {
            let c = UVec3::new(n % 9, (n / 9) % 9, n / 81);
            let d = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) - 0.5;
            map.set_displacement(c, 1.2 * d).unwrap();
        }
        let x = Vec3::new(7.3, 4.1, 12.6);
        let j = map.jacobian(x);
        let h = 1e-2;
        for axis in 0..3 {
            let e = Vec3::AXES[axis] * h;
            let fd = (map.eval(x + e) - map.eval(x - e)) / (2.0 * h);
            assert!((fd - j.col(axis)).length() < 1e-3, "axis {axis}: {fd} vs {}", j.col(axis));
        }
        let y = map.eval(x);
        let back = map.inverse(y, 1e-4, 30).expect("Newton converges on a mild warp");
        assert!((back - x).length() < 1e-3, "inverse {back} vs {x}");
    }

    #[test]
    fn influence_box_covers_exactly_the_voxels_that_change() {
        let dims = UVec3::new(13, 12, 9);
        let base = BSplineMap::with_controls(dims, UVec3::new(7, 6, 5)).unwrap();
        for c in [UVec3::new(0, 0, 0), UVec3::new(3, 2, 1), UVec3::new(6, 5, 4), UVec3::new(5, 1, 2)] {
            let mut moved = base.clone();
            moved.set_displacement(c, Vec3::new(0.7, -0.4, 0.3)).unwrap();
            let (lo, hi) = base.influence_box(c);
            for z in 0..dims.z {
                for y in 0..dims.y {
                    for x in 0..dims.x {
                        let p = UVec3::new(x, y, z);
                        let inside = p.cmpge(lo).all() && p.cmplt(hi).all();
                        let changed = moved.eval(p.as_vec3()) != p.as_vec3();
                        assert!(!changed || inside, "control {c}: voxel {p} changed outside [{lo}, {hi})");
                    }
                }
            }
        }
    }

    #[test]
    fn bad_lattices_are_typed_errors() {
        assert!(matches!(BSplineMap::identity(UVec3::splat(10), 3), Err(WarpError::LatticeTooSmall { .. })));
        assert!(matches!(
            BSplineMap::identity(UVec3::new(10, 2, 10), 9),
            Err(WarpError::LatticeTooFine { .. })
        ));
        let mut map = BSplineMap::identity(UVec3::splat(10), 5).unwrap();
        assert!(matches!(
            map.set_displacement(UVec3::new(5, 0, 0), Vec3::ONE),
            Err(WarpError::ControlOutOfRange { .. })
        ));
        assert!(matches!(
            map.set_control_point(UVec3::ONE, Vec3::new(f32::NAN, 0.0, 0.0)),
            Err(WarpError::NonFinite { .. })
        ));
    }
}
