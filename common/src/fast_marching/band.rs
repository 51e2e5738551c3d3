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
/// Farthest accepted projection (voxels): band nodes of the first layer lie
/// within one voxel of the zero set and those of the second within two, so
/// anything farther went astray.
const MAX_REACH: f32 = 2.5;

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

    /// Trilinear value and its gradient at grid point `p` (clamped to the
    /// grid). The gradient is the interpolant's own, so a Newton step lands
    /// on the interpolated zero set.
    fn sample(&self, p: Vec3) -> (f32, Vec3) {
        let max = (self.dims - UVec3::ONE).as_vec3();
        let p = p.clamp(Vec3::ZERO, max);
        let base = p.floor().min((max - Vec3::ONE).max(Vec3::ZERO));
        let w = p - base;
        let b = base.as_uvec3();
        let hi = (b + UVec3::ONE).min(self.dims - UVec3::ONE);
        let c = |x: bool, y: bool, z: bool| {
            self.at(if x { hi.x } else { b.x }, if y { hi.y } else { b.y }, if z { hi.z } else { b.z })
        };
        let (c000, c100, c010, c110) = (c(false, false, false), c(true, false, false), c(false, true, false), c(true, true, false));
        let (c001, c101, c011, c111) = (c(false, false, true), c(true, false, true), c(false, true, true), c(true, true, true));
        // Interpolate along x, then y, then z, keeping the partial derivatives.
        let x00 = c000 + w.x * (c100 - c000);
        let x10 = c010 + w.x * (c110 - c010);
        let x01 = c001 + w.x * (c101 - c001);
        let x11 = c011 + w.x * (c111 - c011);
        let y0 = x00 + w.y * (x10 - x00);
        let y1 = x01 + w.y * (x11 - x01);
        let value = y0 + w.z * (y1 - y0);
        let dx0 = (c100 - c000) + w.y * ((c110 - c010) - (c100 - c000));
        let dx1 = (c101 - c001) + w.y * ((c111 - c011) - (c101 - c001));
        let gx = dx0 + w.z * (dx1 - dx0);
        let gy = (x10 - x00) + w.z * ((x11 - x01) - (x10 - x00));
        let gz = y1 - y0;
        (value, Vec3::new(gx, gy, gz))
    }

    /// Chopp's projection of node `x` onto the zero set, starting from
    /// `start`; `None` when it does not converge to a nearby zero.
    fn project(&self, x: Vec3, start: Vec3) -> Option<Vec3> {
        let mut p = start;
        let (mut v, mut g) = self.sample(p);
        // The nearest iterate on the zero set: the interpolated gradient jumps
        // across cell faces, so the iteration may end up cycling between
        // zero-set points next to the answer rather than converging.
        let mut best: Option<(f32, Vec3)> = None;
        for _ in 0..MAX_ITERATIONS {
            let gg = g.length_squared();
            if !(gg > 1e-20) {
                break;
            }
            let newton = -v * g / gg;
            let q = x - p;
            let tangential = q - q.dot(g) * g / gg;
            let step = newton + tangential;
            p += step;
            let reach = (p - x).length();
            if reach > MAX_REACH {
                break;
            }
            (v, g) = self.sample(p);
            if v.abs() <= RESIDUAL * g.length() && best.is_none_or(|b| reach < b.0) {
                best = Some((reach, p));
            }
            if step.length() < CONVERGED {
                break;
            }
        }
        best.map(|b| b.1)
    }
}

/// The band of `values` (positive inside) on a `dims` lattice: every node
/// with a 6-neighbour on the other side (`> 0` vs `≤ 0`) and every node with
/// value exactly zero, with its distance (voxels) to the interpolated zero
/// set, its side and its closest point there (grid units).
pub(crate) fn interface_seeds(values: &[f32], dims: UVec3) -> Vec<BandSeed> {
    let sampler = Sampler { values, dims };
    let mut seeds = crossing_seeds(&sampler);
    let second = second_layer(&sampler, &seeds);
    seeds.extend(second);
    seeds
}

/// The 6-neighbours of node `n` inside the grid.
fn neighbours(n: UVec3, dims: UVec3) -> impl Iterator<Item = UVec3> {
    (0..6).filter_map(move |d| {
        let (axis, forward) = (d / 2, d % 2 == 1);
        let mut m = n;
        if forward {
            (n[axis] + 1 < dims[axis]).then(|| {
                m[axis] += 1;
                m
            })
        } else {
            (n[axis] > 0).then(|| {
                m[axis] -= 1;
                m
            })
        }
    })
}

/// The second layer: nodes next to the first band layer, projected with
/// Chopp's iteration started from their nearest neighbour's closest point.
/// Exact distances one layer further out keep closest-point propagation
/// from sampling the surface too coarsely right next to it.
fn second_layer(sampler: &Sampler<'_>, first: &[BandSeed]) -> Vec<BandSeed> {
    let dims = sampler.dims;
    let linear = |n: UVec3| n.x + dims.x * (n.y + dims.y * n.z);
    let node = |index: u32| {
        let row = index / dims.x;
        UVec3::new(index % dims.x, row % dims.y, row / dims.y)
    };
    let find = |index: u32| first.binary_search_by_key(&index, |s| s.index).ok().map(|i| &first[i]);
    let mut candidates: Vec<u32> = first
        .par_iter()
        .flat_map_iter(|s| neighbours(node(s.index), dims).map(linear).filter(|&m| find(m).is_none()))
        .collect();
    candidates.par_sort_unstable();
    candidates.dedup();
    candidates
        .into_par_iter()
        .filter_map(|index| {
            let n = node(index);
            let x = n.as_vec3();
            let start = neighbours(n, dims)
                .filter_map(|m| find(linear(m)).and_then(|s| s.closest))
                .min_by(|a, b| (*a - x).length_squared().total_cmp(&(*b - x).length_squared()))?;
            let p = sampler.project(x, start)?;
            let v = sampler.values[index as usize];
            let normal = sampler.sample(p).1.try_normalize();
            let distance = (p - x).length();
            // The projection must not be worse than the start point.
            (distance <= (start - x).length() + 1e-3).then_some(BandSeed {
                index,
                distance,
                inside: Some(v > 0.0),
                closest: Some(p),
                normal,
            })
        })
        .collect()
}

/// The first band layer: nodes with a sign change to a neighbour, and zero nodes.
fn crossing_seeds(sampler: &Sampler<'_>) -> Vec<BandSeed> {
    let (values, dims) = (sampler.values, sampler.dims);
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let rows = ny * dims.z as usize;
    (0..rows)
        .into_par_iter()
        .flat_map_iter(|row| {
            let (j, k) = ((row % ny) as u32, (row / ny) as u32);
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
                if let Some(p) = sampler.project(x, x) {
                    let d = (p - x).length();
                    if d < distance {
                        (distance, closest) = (d, p);
                    }
                }
                let normal = sampler.sample(closest).1.try_normalize();
                Some(BandSeed { index: index as u32, distance, inside: Some(inside), closest: Some(closest), normal })
            })
        })
        .collect()
}
