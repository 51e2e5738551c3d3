//! Redistancing's initial band: the nodes next to a sign change, with the
//! distance to (and closest point on) the grid's interpolated zero set.
//!
//! Each band node `x` is projected onto the zero set of the trilinear
//! interpolant with Chopp's iteration (Chopp 2001, *Some improvements of the
//! fast marching method*, §3): alternately a Newton step onto `φ = 0` and a
//! step that makes `x − p` parallel to the normal, using the trilinearly
//! interpolated central-difference gradient. The result is checked (on the
//! zero set, within two voxels) and compared with the crossings of the
//! node's grid edges — points of the same zero set, where the trilinear
//! interpolant is linear — and the nearest of these is kept. The zero set is
//! therefore kept to interpolation accuracy, and band distances are exact for
//! planes and second-order accurate for curved surfaces.

use super::march::BandSeed;
use glam::{UVec3, Vec3};
use rayon::prelude::*;

/// Most Chopp iterations per node.
const MAX_ITERATIONS: usize = 12;
/// Step size (voxels) under which the iteration has converged.
const CONVERGED: f32 = 1e-4;
/// Largest accepted residual of the projected point, in voxels (`|φ| / |∇φ|`).
const RESIDUAL: f32 = 1e-3;
/// Farthest accepted projection (voxels): band nodes lie within one voxel of
/// the zero set, so anything farther went astray.
const MAX_REACH: f32 = 2.0;

/// Read access to a scalar grid in grid units.
struct Sampler<'a> {
    values: &'a [f32],
    dims: UVec3,
}

impl Sampler<'_> {
    #[inline]
    fn at(&self, i: u32, j: u32, k: u32) -> f32 {
        self.values[i as usize + self.dims.x as usize * (j as usize + self.dims.y as usize * k as usize)]
    }

    /// Central-difference gradient at a node (one-sided at the boundary).
    fn node_gradient(&self, n: UVec3) -> Vec3 {
        let mut g = Vec3::ZERO;
        for axis in 0..3 {
            let (mut lo, mut hi) = (n, n);
            lo[axis] = n[axis].saturating_sub(1);
            hi[axis] = (n[axis] + 1).min(self.dims[axis] - 1);
            if hi[axis] > lo[axis] {
                g[axis] = (self.at(hi.x, hi.y, hi.z) - self.at(lo.x, lo.y, lo.z)) / (hi[axis] - lo[axis]) as f32;
            }
        }
        g
    }

    /// Trilinear value and interpolated gradient at grid point `p` (clamped
    /// to the grid).
    fn sample(&self, p: Vec3) -> (f32, Vec3) {
        let max = (self.dims - UVec3::ONE).as_vec3();
        let p = p.clamp(Vec3::ZERO, max);
        let base = p.floor().min((max - Vec3::ONE).max(Vec3::ZERO));
        let w = p - base;
        let b = base.as_uvec3();
        let (mut v, mut g) = (0.0, Vec3::ZERO);
        for corner in 0..8u32 {
            let d = UVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
            let n = (b + d).min(self.dims - UVec3::ONE);
            let wt = Vec3::select(d.cmpeq(UVec3::ONE), w, Vec3::ONE - w);
            let weight = wt.x * wt.y * wt.z;
            v += weight * self.at(n.x, n.y, n.z);
            g += weight * self.node_gradient(n);
        }
        (v, g)
    }

    /// Chopp's projection of node `x` onto the zero set; `None` when it does
    /// not converge to a nearby zero.
    fn project(&self, x: Vec3) -> Option<Vec3> {
        let mut p = x;
        for _ in 0..MAX_ITERATIONS {
            let (v, g) = self.sample(p);
            let gg = g.length_squared();
            if !(gg > 1e-20) {
                return None;
            }
            let newton = -v * g / gg;
            let q = x - p;
            let tangential = q - q.dot(g) * g / gg;
            let step = newton + tangential;
            p += step;
            if (p - x).length() > MAX_REACH {
                return None;
            }
            if step.length() < CONVERGED {
                let (v, g) = self.sample(p);
                return (v.abs() <= RESIDUAL * g.length()).then_some(p);
            }
        }
        None
    }
}

/// The band of `values` (positive inside) on a `dims` lattice: every node
/// with a 6-neighbour on the other side (`> 0` vs `≤ 0`) and every node with
/// value exactly zero, with its distance (voxels) to the interpolated zero
/// set, its side and its closest point there (grid units).
pub(crate) fn interface_seeds(values: &[f32], dims: UVec3) -> Vec<BandSeed> {
    let sampler = Sampler { values, dims };
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let rows = ny * dims.z as usize;
    (0..rows)
        .into_par_iter()
        .flat_map_iter(|row| {
            let (j, k) = ((row % ny) as u32, (row / ny) as u32);
            let sampler = &sampler;
            (0..dims.x).filter_map(move |i| {
                let index = i as usize + nx * row;
                let v = values[index];
                let x = Vec3::new(i as f32, j as f32, k as f32);
                let inside = v > 0.0;
                if v == 0.0 {
                    let normal = sampler.sample(x).1.try_normalize();
                    return Some(BandSeed { index: index as u32, distance: 0.0, inside: None, closest: Some(x), normal });
                }
                // Crossings of the node's grid edges: exact zero-set points.
                let mut best: Option<(f32, Vec3)> = None;
                let n = UVec3::new(i, j, k);
                for axis in 0..3 {
                    for forward in [false, true] {
                        let mut m = n;
                        if forward {
                            if n[axis] + 1 >= dims[axis] {
                                continue;
                            }
                            m[axis] += 1;
                        } else {
                            if n[axis] == 0 {
                                continue;
                            }
                            m[axis] -= 1;
                        }
                        let w = sampler.at(m.x, m.y, m.z);
                        if (w > 0.0) == inside {
                            continue;
                        }
                        let t = v / (v - w);
                        if best.is_none_or(|b| t < b.0) {
                            best = Some((t, x + t * (m.as_vec3() - x)));
                        }
                    }
                }
                let (mut distance, mut closest) = best?;
                if let Some(p) = sampler.project(x) {
                    let d = (p - x).length();
                    if d < distance {
                        (distance, closest) = (d, p);
                    }
                }
                let normal = (x - closest).try_normalize().or_else(|| sampler.sample(closest).1.try_normalize());
                Some(BandSeed { index: index as u32, distance, inside: Some(inside), closest: Some(closest), normal })
            })
        })
        .collect()
}
