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

use super::march::{BandSeed, DISC_RADIUS};
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

/// Largest distance (voxels) a tangent disc may leave the surface.
const DISC_FLATNESS: f32 = 0.03;

/// The tangent disc at surface point `p`: the normal, and the largest radius
/// (up to [`DISC_RADIUS`]) at which the disc stays within [`DISC_FLATNESS`]
/// of the surface, estimated from the field at four rim points. Creases and
/// sharp bends get small discs, flat parts full ones.
fn tangent_disc<S: Surface + ?Sized>(surface: &S, p: Vec3) -> Option<(Vec3, f32)> {
    let (_, g) = surface.sample(p);
    let slope = g.length();
    let n = g.try_normalize()?;
    let t1 = n.any_orthonormal_vector();
    let t2 = n.cross(t1);
    let deviation = [t1, -t1, t2, -t2]
        .into_iter()
        .map(|t| surface.sample(p + DISC_RADIUS * t).0.abs() / slope)
        .fold(0.0f32, f32::max);
    let radius = if deviation <= DISC_FLATNESS {
        DISC_RADIUS
    } else {
        DISC_RADIUS * (DISC_FLATNESS / deviation).sqrt()
    };
    Some((n, radius))
}

/// A surface given as the zero set of a field, seen in grid units.
pub(crate) trait Surface: Sync {
    /// The grid's node values (positive inside), x-fastest.
    fn values(&self) -> &[f32];
    /// Node counts.
    fn dims(&self) -> UVec3;
    /// Field value and gradient (per voxel) at grid point `p`.
    fn sample(&self, p: Vec3) -> (f32, Vec3);
    /// Where on the edge from node `a` (value `va`) to its neighbour `b`
    /// (value `vb`, other side) the field crosses zero, as a fraction of the
    /// edge from `a`.
    fn edge_zero(&self, a: Vec3, b: Vec3, va: f32, vb: f32) -> f32;
}

/// Chopp's projection of node `x` onto the zero set of `surface`, starting
/// from `start`; `None` when it finds no zero within reach.
pub(crate) fn project<S: Surface + ?Sized>(surface: &S, x: Vec3, start: Vec3) -> Option<Vec3> {
    let mut p = start;
    let (mut v, mut g) = surface.sample(p);
    // The nearest iterate on the zero set: the interpolated gradient jumps
    // across cell faces, so the iteration may end up cycling between
    // zero-set points next to the answer rather than converging.
    let mut best: Option<(f32, Vec3)> = None;
    for _ in 0..MAX_ITERATIONS {
        let gg = g.length_squared();
        if gg.is_nan() || gg <= 1e-20 {
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
        (v, g) = surface.sample(p);
        if v.abs() <= RESIDUAL * g.length() && best.is_none_or(|b| reach < b.0) {
            best = Some((reach, p));
        }
        if step.length() < CONVERGED {
            break;
        }
    }
    best.map(|b| b.1)
}

/// Read access to a scalar grid in grid units; its zero set is that of the
/// trilinear interpolant.
pub(crate) struct Sampler<'a> {
    values: &'a [f32],
    dims: UVec3,
}

impl Surface for Sampler<'_> {
    fn values(&self) -> &[f32] {
        self.values
    }

    fn dims(&self) -> UVec3 {
        self.dims
    }

    fn sample(&self, p: Vec3) -> (f32, Vec3) {
        self.trilinear(p)
    }

    /// Linear interpolation: the trilinear interpolant is linear on edges.
    fn edge_zero(&self, _a: Vec3, _b: Vec3, va: f32, vb: f32) -> f32 {
        va / (va - vb)
    }
}

impl Sampler<'_> {
    #[inline]
    fn at(&self, i: u32, j: u32, k: u32) -> f32 {
        self.values[i as usize + self.dims.x as usize * (j as usize + self.dims.y as usize * k as usize)]
    }

    /// Trilinear value and its gradient at grid point `p` (clamped to the
    /// grid). The gradient is the interpolant's own, so a Newton step lands
    /// on the interpolated zero set.
    fn trilinear(&self, p: Vec3) -> (f32, Vec3) {
        let last = self.dims - UVec3::ONE;
        let p = p.clamp(Vec3::ZERO, last.as_vec3());
        // The cell's lowest corner; truncation is the floor of p ≥ 0.
        let b = p.as_uvec3().min(last.saturating_sub(UVec3::ONE));
        let w = p - b.as_vec3();
        let hi = (b + UVec3::ONE).min(last);
        let c = |x: bool, y: bool, z: bool| {
            self.at(if x { hi.x } else { b.x }, if y { hi.y } else { b.y }, if z { hi.z } else { b.z })
        };
        let (c000, c100, c010, c110) =
            (c(false, false, false), c(true, false, false), c(false, true, false), c(true, true, false));
        let (c001, c101, c011, c111) =
            (c(false, false, true), c(true, false, true), c(false, true, true), c(true, true, true));
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
}

/// The band of grid `values` (positive inside) on a `dims` lattice, measured
/// to the zero set of their trilinear interpolant (see [`interface_seeds`]).
pub(crate) fn grid_seeds(values: &[f32], dims: UVec3) -> Vec<BandSeed> {
    interface_seeds(&Sampler { values, dims })
}

/// The band of `surface`'s node values: every node with a 6-neighbour on the
/// other side (`> 0` vs `≤ 0`), every node with value exactly zero, and the
/// nodes next to those (second layer), each with its distance (voxels) to
/// the zero set, its side and its closest point there (grid units).
pub(crate) fn interface_seeds<S: Surface + ?Sized>(surface: &S) -> Vec<BandSeed> {
    let mut seeds = crossing_seeds(surface);
    let second = second_layer(surface, &seeds);
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
fn second_layer<S: Surface + ?Sized>(surface: &S, first: &[BandSeed]) -> Vec<BandSeed> {
    let dims = surface.dims();
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
            let p = project(surface, x, start)?;
            let v = surface.values()[index as usize];
            let disc = tangent_disc(surface, p);
            let distance = (p - x).length();
            // The projection must not be worse than the start point.
            (distance <= (start - x).length() + 1e-3).then_some(BandSeed {
                index,
                distance,
                inside: Some(v > 0.0),
                closest: Some(p),
                disc,
            })
        })
        .collect()
}

/// True when no node of `row` (index `j + ny · k`) is in the band: all its
/// values are nonzero and on one side, and so are those of the (up to four)
/// rows next to it. Most rows are, and this test costs a few instructions a
/// node.
fn far_row(values: &[f32], dims: UVec3, row: usize) -> bool {
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let line = |r: usize| &values[r * nx..(r + 1) * nx];
    let inside = values[row * nx] > 0.0;
    let same = |r: usize| line(r).iter().fold(true, |all, &v| all & ((v > 0.0) == inside));
    let (j, k) = (row % ny, row / ny);
    line(row).iter().fold(true, |all, &v| all & (v != 0.0))
        && same(row)
        && (j == 0 || same(row - 1))
        && (j + 1 == ny || same(row + 1))
        && (k == 0 || same(row - ny))
        && (k + 1 == nz || same(row + ny))
}

/// True when node `n` (linear `index`) has a 6-neighbour on the other side
/// (`> 0` vs `≤ 0`): the quick test that keeps the scan of the whole grid cheap.
#[inline]
fn has_crossing(values: &[f32], dims: UVec3, index: usize, n: UVec3) -> bool {
    let inside = values[index] > 0.0;
    let (row, plane) = (dims.x as usize, dims.x as usize * dims.y as usize);
    let differs = |m: usize| (values[m] > 0.0) != inside;
    (n.x > 0 && differs(index - 1))
        || (n.x + 1 < dims.x && differs(index + 1))
        || (n.y > 0 && differs(index - row))
        || (n.y + 1 < dims.y && differs(index + row))
        || (n.z > 0 && differs(index - plane))
        || (n.z + 1 < dims.z && differs(index + plane))
}

/// The first band layer: nodes with a sign change to a neighbour, and zero nodes.
fn crossing_seeds<S: Surface + ?Sized>(surface: &S) -> Vec<BandSeed> {
    let (values, dims) = (surface.values(), surface.dims());
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let rows = ny * dims.z as usize;
    (0..rows)
        .into_par_iter()
        .flat_map_iter(|row| {
            let (j, k) = ((row % ny) as u32, (row / ny) as u32);
            let span = if far_row(values, dims, row) { 0..0 } else { 0..dims.x };
            span.filter_map(move |i| {
                let index = i as usize + nx * row;
                let v = values[index];
                let x = Vec3::new(i as f32, j as f32, k as f32);
                let inside = v > 0.0;
                if v == 0.0 {
                    let disc = tangent_disc(surface, x);
                    return Some(BandSeed {
                        index: index as u32,
                        distance: 0.0,
                        inside: None,
                        closest: Some(x),
                        disc,
                    });
                }
                if !has_crossing(values, dims, index, UVec3::new(i, j, k)) {
                    return None;
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
                        let w = values[m.x as usize + nx * (m.y as usize + ny * m.z as usize)];
                        if (w > 0.0) == inside {
                            continue;
                        }
                        let t = surface.edge_zero(x, m.as_vec3(), v, w);
                        if best.is_none_or(|b| t < b.0) {
                            best = Some((t, x + t * (m.as_vec3() - x)));
                        }
                    }
                }
                let (mut distance, mut closest) = best?;
                if let Some(p) = project(surface, x, x) {
                    let d = (p - x).length();
                    if d < distance {
                        (distance, closest) = (d, p);
                    }
                }
                let disc = tangent_disc(surface, closest);
                Some(BandSeed {
                    index: index as u32,
                    distance,
                    inside: Some(inside),
                    closest: Some(closest),
                    disc,
                })
            })
        })
        .collect()
}
