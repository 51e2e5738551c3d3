//! The marching loop shared by [`march`](super::march),
//! [`redistance`](super::redistance) and CSG scan conversion.
//!
//! Everything here works in *grid units*: node `(i, j, k)` sits at `(i, j, k)`
//! and distances are in voxels. Distances are marched as magnitudes on both
//! sides of the surface at once; a per-node flag byte holds the Far / Trial /
//! Known state, the side (inside or outside) and whether the node is a fixed
//! seed.

use super::heap::RadixHeap;
use super::{FastMarchingError, Update};
use crate::Grid3;
use glam::{UVec3, Vec3};
use rayon::prelude::*;

/// Not yet touched by the front.
const FAR: u8 = 0;
/// In the narrow band with a tentative distance.
const TRIAL: u8 = 1;
/// Accepted: the distance is final.
const KNOWN: u8 = 2;
/// Mask of the Far / Trial / Known state.
const STATE: u8 = 3;
/// The node lies inside (positive side).
const INSIDE: u8 = 4;
/// The node's side is known (`INSIDE` is meaningful).
const SIGNED: u8 = 8;
/// A seed: its distance is given and never updated.
const FIXED: u8 = 16;

/// One band node with its distance and, for closest-point propagation, the
/// surface point it is closest to (grid units).
#[derive(Debug, Clone, Copy)]
pub(crate) struct BandSeed {
    /// Linear node index.
    pub(crate) index: u32,
    /// Unsigned distance in voxels.
    pub(crate) distance: f32,
    /// Side of the surface, `None` when unknown (distance zero).
    pub(crate) inside: Option<bool>,
    /// Closest surface point in grid coordinates, when known.
    pub(crate) closest: Option<Vec3>,
    /// Unit surface normal at `closest` (either orientation), when known.
    pub(crate) normal: Option<Vec3>,
}

/// Radius (voxels) of the tangent disc each seed stands for. Seeds' closest
/// points sample the surface about one voxel apart, so discs of this radius
/// cover it; the disc leaves the surface by `DISC_RADIUS² κ / 2` voxels where
/// the curvature is κ (per voxel).
const DISC_RADIUS: f32 = 0.75;

/// A seed's piece of surface: its closest point and the tangent disc there.
#[derive(Debug, Clone, Copy)]
struct Surfel {
    point: Vec3,
    /// Unit normal, or zero when only the point is known.
    normal: Vec3,
}

impl Surfel {
    fn new(point: Vec3, normal: Option<Vec3>) -> Self {
        Self { point, normal: normal.map_or(Vec3::ZERO, Vec3::normalize_or_zero) }
    }

    /// Distance (voxels) from `x` to the nearest point of the tangent disc.
    ///
    /// A bare point would sample the surface too coarsely near it: a node
    /// `d` voxels away whose propagated point is off by `δ` tangentially is
    /// off by `δ² / 2d`. The disc cuts that to the disc's own deviation from
    /// the surface.
    #[inline]
    fn distance(&self, x: Vec3) -> f32 {
        let q = x - self.point;
        let tangential = q - q.dot(self.normal) * self.normal;
        let t = tangential.length();
        let slide = if t > DISC_RADIUS { tangential * (DISC_RADIUS / t) } else { tangential };
        (q - slide).length()
    }
}

/// The state of one marching run, in grid units.
pub(crate) struct Marcher {
    nx: u32,
    ny: u32,
    nz: u32,
    /// Unsigned distance in voxels (`INFINITY` until reached).
    dist: Vec<f32>,
    flags: Vec<u8>,
    /// Closest-point mode: the seed whose surface point each node uses.
    source: Vec<u32>,
    /// Closest-point mode: the seeds' surface elements.
    surfels: Vec<Surfel>,
    update: Update,
    /// Nodes farther than this (voxels) are never accepted.
    limit: f32,
    heap: RadixHeap,
}

impl Marcher {
    /// A run over `dims` nodes, every node Far. `limit` in voxels (may be
    /// infinite).
    pub(crate) fn new(dims: UVec3, update: Update, limit: f32) -> Result<Self, FastMarchingError> {
        let nodes = dims.x as u64 * dims.y as u64 * dims.z as u64;
        if nodes > u32::MAX as u64 {
            return Err(FastMarchingError::TooManyNodes(nodes));
        }
        let buffer = |fill| Grid3::new(dims, Vec3::ZERO, 1.0, fill).map(Grid3::into_data);
        let dist = buffer(f32::INFINITY)?;
        let flags = Grid3::new(dims, Vec3::ZERO, 1.0, FAR)?.into_data();
        let source = match update {
            Update::ClosestPoint => Grid3::new(dims, Vec3::ZERO, 1.0, u32::MAX)?.into_data(),
            _ => Vec::new(),
        };
        Ok(Self {
            nx: dims.x,
            ny: dims.y,
            nz: dims.z,
            dist,
            flags,
            source,
            surfels: Vec::new(),
            update,
            limit,
            heap: RadixHeap::new(),
        })
    }

    /// Fixes every node's side from `values` (positive inside).
    pub(crate) fn set_sides(&mut self, values: &[f32]) {
        self.flags.par_iter_mut().zip(values.par_iter()).for_each(|(f, &v)| {
            *f = SIGNED | if v > 0.0 { INSIDE } else { 0 };
        });
    }

    /// Adds a seed (its distance stays as given).
    ///
    /// # Errors
    /// [`FastMarchingError::MissingClosestPoint`] in closest-point mode when
    /// the seed has no surface point; `seed_number` names it.
    pub(crate) fn add_seed(&mut self, seed: BandSeed, seed_number: usize) -> Result<(), FastMarchingError> {
        let n = seed.index as usize;
        let mut f = (self.flags[n] & !STATE) | TRIAL | FIXED;
        if let Some(inside) = seed.inside {
            f = (f & !INSIDE) | SIGNED | if inside { INSIDE } else { 0 };
        }
        self.flags[n] = f;
        if self.update == Update::ClosestPoint {
            let cp = seed.closest.ok_or(FastMarchingError::MissingClosestPoint(seed_number))?;
            // A node seeded twice keeps the closer surface point.
            if seed.distance > self.dist[n] {
                return Ok(());
            }
            self.source[n] = self.surfels.len() as u32;
            self.surfels.push(Surfel::new(cp, seed.normal));
        }
        self.dist[n] = self.dist[n].min(seed.distance);
        self.heap.push(seed.distance, seed.index);
        Ok(())
    }

    /// Grid coordinates of linear index `n`.
    #[inline]
    fn coords(&self, n: u32) -> [u32; 3] {
        let row = n / self.nx;
        [n - row * self.nx, row % self.ny, row / self.ny]
    }

    /// Runs the front until every reachable node within the limit is Known.
    pub(crate) fn run(&mut self) {
        let strides = [1u32, self.nx, self.nx * self.ny];
        let dims = [self.nx, self.ny, self.nz];
        while let Some(n) = self.heap.pop() {
            let nu = n as usize;
            let f = self.flags[nu];
            if f & STATE == KNOWN || self.dist[nu] > self.limit {
                continue;
            }
            self.flags[nu] = (f & !STATE) | KNOWN;
            let c = self.coords(n);
            for axis in 0..3 {
                for forward in [false, true] {
                    let m = if forward {
                        if c[axis] + 1 >= dims[axis] {
                            continue;
                        }
                        n + strides[axis]
                    } else {
                        if c[axis] == 0 {
                            continue;
                        }
                        n - strides[axis]
                    };
                    let mu = m as usize;
                    let fm = self.flags[mu];
                    if fm & STATE == KNOWN || fm & FIXED != 0 {
                        continue;
                    }
                    let mut fm = (fm & !STATE) | TRIAL;
                    if fm & SIGNED == 0 && f & SIGNED != 0 {
                        fm |= SIGNED | (f & INSIDE);
                    }
                    self.flags[mu] = fm;
                    let candidate = match self.update {
                        Update::ClosestPoint => {
                            let s = self.source[nu];
                            if self.source[mu] == s {
                                continue;
                            }
                            let mut mc = c;
                            mc[axis] = if forward { c[axis] + 1 } else { c[axis] - 1 };
                            let p = Vec3::new(mc[0] as f32, mc[1] as f32, mc[2] as f32);
                            let d = self.surfels[s as usize].distance(p);
                            if d < self.dist[mu] {
                                self.source[mu] = s;
                            }
                            d
                        }
                        Update::FirstOrder | Update::SecondOrder => {
                            let mut mc = c;
                            mc[axis] = if forward { c[axis] + 1 } else { c[axis] - 1 };
                            self.eikonal(m, mc, strides, dims)
                        }
                    };
                    if candidate < self.dist[mu] {
                        self.dist[mu] = candidate;
                        self.heap.push(candidate, m);
                    }
                }
            }
        }
    }

    /// True when Known node `m` may serve as an upwind neighbour of a node
    /// with flags `fn_`: same side, or either side unknown, or on the surface.
    #[inline]
    fn usable(&self, m: usize, fn_: u8) -> bool {
        let fm = self.flags[m];
        fm & STATE == KNOWN
            && (self.dist[m] == 0.0
                || fm & fn_ & SIGNED == 0
                || (fm & INSIDE) == (fn_ & INSIDE))
    }

    /// The upwind Eikonal update `|∇u| = 1` at node `m` (coordinates `c`) from
    /// its Known neighbours: per axis the smaller upwind neighbour, with
    /// Sethian's second-order one-sided difference `(3u − 4a₁ + a₂) / 2` when
    /// the setting asks for it and the second node out is Known and no larger;
    /// the quadratic is solved with 1, 2 or 3 axes, adding axes while the
    /// solution exceeds their neighbour value.
    fn eikonal(&self, m: u32, c: [u32; 3], strides: [u32; 3], dims: [u32; 3]) -> f32 {
        let fm = self.flags[m as usize];
        let second = self.update == Update::SecondOrder;
        // (upwind value a₁, centre b, weight c) per axis.
        let mut terms = [(f32::INFINITY, 0.0f32, 0.0f32); 3];
        for axis in 0..3 {
            let s = strides[axis];
            for forward in [false, true] {
                let (m1, m2) = if forward {
                    if c[axis] + 1 >= dims[axis] {
                        continue;
                    }
                    (m + s, (c[axis] + 2 < dims[axis]).then(|| m + 2 * s))
                } else {
                    if c[axis] == 0 {
                        continue;
                    }
                    (m - s, (c[axis] >= 2).then(|| m - 2 * s))
                };
                if !self.usable(m1 as usize, fm) {
                    continue;
                }
                let a1 = self.dist[m1 as usize];
                if a1 >= terms[axis].0 {
                    continue;
                }
                terms[axis] = (a1, a1, 1.0);
                if second && let Some(m2) = m2 {
                    let a2 = self.dist[m2 as usize];
                    if self.usable(m2 as usize, fm) && a2 <= a1 {
                        terms[axis] = (a1, (4.0 * a1 - a2) / 3.0, 2.25);
                    }
                }
            }
        }
        terms.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let (mut qa, mut qb, mut qc) = (0.0f32, 0.0f32, 0.0f32);
        let mut u = f32::INFINITY;
        for (a1, b, w) in terms {
            if a1 == f32::INFINITY || u <= a1 {
                break;
            }
            let (na, nb, nc) = (qa + w, qb + w * b, qc + w * b * b);
            let disc = nb * nb - na * (nc - 1.0);
            if disc < 0.0 {
                break;
            }
            (qa, qb, qc) = (na, nb, nc);
            u = (nb + disc.sqrt()) / na;
        }
        u
    }

    /// Gives nodes of unknown side the side of a neighbouring region (flood
    /// fill from the nodes whose side is known); nodes with no known side
    /// anywhere stay outside.
    fn flood_sides(&mut self) {
        if self.flags.par_iter().all(|f| f & SIGNED != 0) {
            return;
        }
        let strides = [1u32, self.nx, self.nx * self.ny];
        let dims = [self.nx, self.ny, self.nz];
        let mut stack: Vec<u32> = (0..self.flags.len() as u32)
            .filter(|&n| self.flags[n as usize] & SIGNED != 0)
            .collect();
        while let Some(n) = stack.pop() {
            let f = self.flags[n as usize];
            let c = self.coords(n);
            for axis in 0..3 {
                let neighbours = [
                    (c[axis] > 0).then(|| n - strides[axis]),
                    (c[axis] + 1 < dims[axis]).then(|| n + strides[axis]),
                ];
                for m in neighbours.into_iter().flatten() {
                    let fm = &mut self.flags[m as usize];
                    if *fm & SIGNED == 0 {
                        *fm |= SIGNED | (f & INSIDE);
                        stack.push(m);
                    }
                }
            }
        }
    }

    /// The signed result in world units: `±distance · spacing`, positive
    /// inside; nodes never accepted get `±max_distance`.
    pub(crate) fn finish(mut self, origin: Vec3, spacing: f32, max_distance: f32) -> Result<Grid3<f32>, FastMarchingError> {
        self.flood_sides();
        let limit = self.limit;
        let mut dist = std::mem::take(&mut self.dist);
        dist.par_iter_mut().zip(self.flags.par_iter()).for_each(|(d, &f)| {
            let magnitude = if f & STATE == KNOWN && *d <= limit { *d * spacing } else { max_distance };
            *d = if f & INSIDE != 0 { magnitude } else { -magnitude };
        });
        Ok(Grid3::from_vec(UVec3::new(self.nx, self.ny, self.nz), origin, spacing, dist)?)
    }
}
impl Marcher {
    pub(crate) fn debug(&self, n: u32, c: Vec3) {
        let x = Vec3::new((n % self.nx) as f32, ((n / self.nx) % self.ny) as f32, (n / self.nx / self.ny) as f32);
        let s = self.source[n as usize];
        println!("node {x} dist {} flags {} src {} cp {} |cp-c| {} exact {}", self.dist[n as usize], self.flags[n as usize], s, self.surfels[s as usize].point, (self.surfels[s as usize].point-c).length(), 10.0 - (x-c).length());
        for d in [1u32, self.nx, self.nx*self.ny] {
            for m in [n - d, n + d] {
                let x = Vec3::new((m % self.nx) as f32, ((m / self.nx) % self.ny) as f32, (m / self.nx / self.ny) as f32);
                let s = self.source[m as usize];
                println!("  nb {x} dist {} flags {} src {} cp {} exact {}", self.dist[m as usize], self.flags[m as usize], s, self.surfels[s as usize].point,  10.0 - (x-c).length());
            }
        }
    }
}
