//! Lattice index arithmetic and the up-wind finite differences of Breen &
//! Whitaker eq. 19–23, shared by both solvers.
//!
//! All solver values are in **voxel units** (distances divided by the grid
//! spacing), as the paper assumes unit spacing; the level-set equation
//! `∂φ/∂t = |∇φ| γ` keeps its time scale under that change of units.

use crate::SpeedGrid;
use isomorph_common::NodeStore;
use isomorph_common::glam::{UVec3, Vec3};
use std::ops::Index;

/// Node values (voxel units, positive inside) read by linear node index: a
/// dense slice, or a solver's [`NodeStore`] seen through [`Stored`].
pub(crate) trait Values: Index<usize, Output = f32> + Sync {
    /// The value at node `n`, whose coordinates are `c`: `self[n]`, without
    /// the divisions that recover `c` from `n` where the storage needs it.
    #[inline]
    fn at(&self, n: usize, _c: [usize; 3]) -> f32 {
        self[n]
    }
}

impl Values for [f32] {}

impl Values for Vec<f32> {}

/// A solver's embedding store ([`NodeStore`]: dense, or bricks read by
/// coordinates) as [`Values`].
pub(crate) struct Stored<'a, U>(pub(crate) &'a U);

impl<U: NodeStore<f32>> Index<usize> for Stored<'_, U> {
    type Output = f32;

    #[inline]
    fn index(&self, n: usize) -> &f32 {
        &self.0[n]
    }
}

impl<U: NodeStore<f32>> Values for Stored<'_, U> {
    #[inline]
    fn at(&self, n: usize, c: [usize; 3]) -> f32 {
        self.0.at(n, UVec3::new(c[0] as u32, c[1] as u32, c[2] as u32))
    }
}

/// An x-fastest lattice of `dims` nodes: linear indices, coordinates and the
/// six face neighbours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Lattice {
    dims: [usize; 3],
    strides: [usize; 3],
}

impl Lattice {
    /// The lattice with `dims` nodes per axis.
    pub(crate) fn new(dims: UVec3) -> Self {
        let dims = [dims.x as usize, dims.y as usize, dims.z as usize];
        Self { dims, strides: [1, dims[0], dims[0] * dims[1]] }
    }

    /// Number of nodes.
    pub(crate) fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Nodes per axis.
    pub(crate) fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Index steps between neighbours along x, y and z.
    pub(crate) fn strides(&self) -> [usize; 3] {
        self.strides
    }

    /// Integer coordinates of node `n`.
    pub(crate) fn coords(&self, n: usize) -> [usize; 3] {
        let x = n % self.dims[0];
        let yz = n / self.dims[0];
        [x, yz % self.dims[1], yz / self.dims[1]]
    }

    /// The six face neighbours of `n` in the order −x, +x, −y, +y, −z, +z;
    /// `None` past the boundary.
    pub(crate) fn neighbours(&self, n: usize) -> [Option<usize>; 6] {
        let c = self.coords(n);
        let mut out = [None; 6];
        for axis in 0..3 {
            let s = self.strides[axis];
            if c[axis] > 0 {
                out[2 * axis] = Some(n - s);
            }
            if c[axis] + 1 < self.dims[axis] {
                out[2 * axis + 1] = Some(n + s);
            }
        }
        out
    }

    /// The six face neighbours of node `n` at coordinates `c`, with their
    /// coordinates, in the order of [`Self::neighbours`].
    #[inline]
    pub(crate) fn neighbours_at(&self, n: usize, c: [usize; 3]) -> [Option<(usize, [usize; 3])>; 6] {
        let mut out = [None; 6];
        for axis in 0..3 {
            let s = self.strides[axis];
            let mut d = c;
            if c[axis] > 0 {
                d[axis] = c[axis] - 1;
                out[2 * axis] = Some((n - s, d));
            }
            if c[axis] + 1 < self.dims[axis] {
                d[axis] = c[axis] + 1;
                out[2 * axis + 1] = Some((n + s, d));
            }
        }
        out
    }

    /// Whether node `n` has a face neighbour on the other side of the zero
    /// set (inside means `u > 0`).
    pub(crate) fn on_zero_set(&self, u: &(impl Values + ?Sized), n: usize) -> bool {
        let c = self.coords(n);
        let inside = u.at(n, c) > 0.0;
        self.neighbours_at(n, c).iter().flatten().any(|&(m, d)| (u.at(m, d) > 0.0) != inside)
    }

    /// One-sided differences at `n` (eq. 19–22): `(δ⁻, δ⁺)` per axis, zero
    /// towards the outside of the grid (Neumann boundary).
    pub(crate) fn one_sided(&self, u: &(impl Values + ?Sized), n: usize) -> ([f32; 3], [f32; 3]) {
        self.one_sided_at(u, n, self.coords(n))
    }

    /// [`Self::one_sided`] of node `n` at coordinates `c`.
    fn one_sided_at(&self, u: &(impl Values + ?Sized), n: usize, c: [usize; 3]) -> ([f32; 3], [f32; 3]) {
        let nb = self.neighbours_at(n, c);
        let un = u.at(n, c);
        let mut minus = [0.0; 3];
        let mut plus = [0.0; 3];
        for axis in 0..3 {
            if let Some((m, d)) = nb[2 * axis] {
                minus[axis] = un - u.at(m, d);
            }
            if let Some((p, d)) = nb[2 * axis + 1] {
                plus[axis] = u.at(p, d) - un;
            }
        }
        (minus, plus)
    }

    /// Mean curvature `κ = ∇·(∇u/|∇u|)` at `n` (1/voxel; sum of the
    /// principal curvatures, negative on convex parts of a positive-inside
    /// embedding) from central differences over the 3×3×3 neighbourhood
    /// (clamped at the boundary), and the central gradient magnitude.
    pub(crate) fn mean_curvature(&self, u: &(impl Values + ?Sized), n: usize) -> (f32, f32) {
        let c = self.coords(n);
        let at = |d: [isize; 3]| {
            let (mut m, mut at) = (0, [0; 3]);
            for axis in 0..3 {
                at[axis] = (c[axis] as isize + d[axis]).clamp(0, self.dims[axis] as isize - 1) as usize;
                m += at[axis] * self.strides[axis];
            }
            u.at(m, at)
        };
        let e = |axis: usize, s: isize| {
            let mut d = [0isize; 3];
            d[axis] = s;
            d
        };
        let un = u.at(n, c);
        let first = |a: usize| 0.5 * (at(e(a, 1)) - at(e(a, -1)));
        let second = |a: usize| at(e(a, 1)) - 2.0 * un + at(e(a, -1));
        let mixed = |a: usize, b: usize| {
            let d = |sa: isize, sb: isize| {
                let mut d = [0isize; 3];
                d[a] = sa;
                d[b] = sb;
                at(d)
            };
            0.25 * (d(1, 1) - d(1, -1) - d(-1, 1) + d(-1, -1))
        };
        let (gx, gy, gz) = (first(0), first(1), first(2));
        let (xx, yy, zz) = (second(0), second(1), second(2));
        let (xy, xz, yz) = (mixed(0, 1), mixed(0, 2), mixed(1, 2));
        let g2 = gx * gx + gy * gy + gz * gz;
        if g2 < 1e-12 {
            return (0.0, 0.0);
        }
        let numerator = (yy + zz) * gx * gx + (xx + zz) * gy * gy + (xx + yy) * gz * gz
            - 2.0 * (gx * gy * xy + gx * gz * xz + gy * gz * yz);
        let g = g2.sqrt();
        (numerator / (g2 * g), g)
    }

    /// Central-difference gradient at `n` (one-sided at the boundary), in
    /// value units per voxel; `c` are `n`'s coordinates.
    fn central_gradient(&self, u: &(impl Values + ?Sized), n: usize, c: [usize; 3]) -> Vec3 {
        let (minus, plus) = self.one_sided_at(u, n, c);
        let g = |axis: usize| {
            let two_sided = c[axis] > 0 && c[axis] + 1 < self.dims[axis];
            let sum = minus[axis] + plus[axis];
            if two_sided { 0.5 * sum } else { sum }
        };
        Vec3::new(g(0), g(1), g(2))
    }
}

/// The up-wind gradient magnitude of eq. 23 for a front moving with speed of
/// sign `speed ≥ 0` under `∂φ/∂t = |∇φ| γ`.
///
/// The paper's eq. 23 is written for an embedding that is positive
/// *outside*; isomorph's fields are positive inside, which exchanges its two
/// cases: a positive speed (expansion) takes `max(δ⁺, 0)` and `min(δ⁻, 0)`.
pub(crate) fn upwind_norm(minus: [f32; 3], plus: [f32; 3], speed: f32) -> f32 {
    let mut sum = 0.0;
    for axis in 0..3 {
        let (m, p) = (minus[axis], plus[axis]);
        sum += if speed >= 0.0 {
            p.max(0.0).powi(2) + m.min(0.0).powi(2)
        } else {
            p.min(0.0).powi(2) + m.max(0.0).powi(2)
        };
    }
    sum.sqrt()
}

/// The speed at the zero crossing nearest to node `n` (the sparse field's
/// first-order modification): one Newton step along the central-difference
/// gradient, `x' = x − u ∇u / |∇u|²`, then trilinear interpolation of the
/// node speeds (same lattice).
pub(crate) fn speed_at_zero_crossing(
    lattice: &Lattice,
    u: &(impl Values + ?Sized),
    speed: &SpeedGrid,
    n: usize,
) -> f32 {
    speed.at_voxel(zero_crossing(lattice, u, n))
}

/// The zero crossing nearest to node `n` (voxel coordinates): one Newton
/// step along the central-difference gradient, `x' = x − u ∇u / |∇u|²`
/// (the node itself where the gradient vanishes).
pub(crate) fn zero_crossing(lattice: &Lattice, u: &(impl Values + ?Sized), n: usize) -> Vec3 {
    let c = lattice.coords(n);
    let grad = lattice.central_gradient(u, n, c);
    let mut x = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    let g2 = grad.length_squared();
    if g2 > 1e-12 {
        x -= u.at(n, c) * grad / g2;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbours_stop_at_the_boundary() {
        let l = Lattice::new(UVec3::new(3, 4, 5));
        assert_eq!(l.coords(l.len() - 1), [2, 3, 4]);
        let nb = l.neighbours(0);
        assert_eq!(nb, [None, Some(1), None, Some(3), None, Some(12)]);
        let last = l.neighbours(l.len() - 1);
        assert_eq!(last[1], None);
        assert_eq!(last[0], Some(l.len() - 2));
    }

    #[test]
    fn upwind_picks_the_side_the_front_comes_from() {
        // φ = −x (positive inside on the left): expanding front moves to +x
        // and must read the backward difference.
        let l = Lattice::new(UVec3::new(5, 1, 1));
        let u: Vec<f32> = vec![2.0, 1.0, 0.0, -3.0, -6.0];
        let (m, p) = l.one_sided(&u, 2);
        assert_eq!(m[0], -1.0);
        assert_eq!(p[0], -3.0);
        assert_eq!(upwind_norm(m, p, 1.0), 1.0);
        assert_eq!(upwind_norm(m, p, -1.0), 3.0);
    }

    #[test]
    fn mean_curvature_of_a_sphere_is_minus_two_over_r() {
        let l = Lattice::new(UVec3::splat(41));
        let r = 12.0;
        let u: Vec<f32> = (0..l.len())
            .map(|n| {
                let c = l.coords(n).map(|c| c as f32 - 20.0);
                r - (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
            })
            .collect();
        // A node on the sphere's surface along a diagonal-ish direction.
        let n = 20 + 27 * 41 + 29 * 41 * 41; // (20, 27, 29): |(0, 7, 9)| ≈ 11.4
        let (kappa, g) = l.mean_curvature(&u, n);
        let rho = (49.0f32 + 81.0).sqrt();
        assert!((kappa + 2.0 / rho).abs() < 0.01, "kappa {kappa} vs {}", -2.0 / rho);
        assert!((g - 1.0).abs() < 0.02);
    }
}
