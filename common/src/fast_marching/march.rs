//! The marching loops shared by [`march`](super::march),
//! [`redistance`](super::redistance) and CSG scan conversion.
//!
//! Everything here works in *grid units*: node `(i, j, k)` sits at `(i, j, k)`
//! and distances are in voxels. Distances are marched as magnitudes on both
//! sides of the surface at once. Each node is one 8-byte cell (distance, and
//! a tag holding the Far / Trial / Known state, the side, the seed flag and,
//! for closest-point propagation, the index of its surface element), so a
//! neighbour visit costs one memory access.
//!
//! - The Eikonal updates run Sethian's fast marching: Trial nodes in a
//!   monotone radix heap, the smallest accepted (Known) and never revisited.
//! - Closest-point propagation runs the same front in *shells* one voxel
//!   wide (a bucketed queue in the manner of Kim's group marching and
//!   Δ-stepping): the nodes of a shell are relaxed in rounds, and a node
//!   whose distance drops after it was accepted is relaxed again, so every
//!   node ends with the best surface element among its neighbours'. Each
//!   shell's queue is kept per z-slab of whole planes, in the order the
//!   nodes were reached, which is close to memory order and needs no sort; a
//!   large round is relaxed in parallel by z-slabs (even slabs together, then
//!   odd ones, so no two threads touch the same cell), each task queueing the
//!   nodes it improves by slab and shell itself.

use super::heap::RadixHeap;
use super::{FastMarchingError, Update};
use crate::grid::memory_limit;
use crate::{Grid3, GridError};
use glam::{UVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Not yet touched by the front.
const FAR: u32 = 0;
/// In the narrow band with a tentative distance.
const TRIAL: u32 = 1;
/// Accepted: final for the Eikonal updates; propagated with its current
/// distance for closest-point propagation.
const KNOWN: u32 = 2;
/// Mask of the Far / Trial / Known state.
const STATE: u32 = 3;
/// The node lies inside (positive side).
const INSIDE: u32 = 4;
/// The node's side is known (`INSIDE` is meaningful).
const SIGNED: u32 = 8;
/// A seed: its distance is given and never updated.
const FIXED: u32 = 16;
/// Bits of the tag below the surface-element index.
const FLAG_BITS: u32 = 5;
/// Mask of the flag bits.
const FLAGS: u32 = (1 << FLAG_BITS) - 1;
/// Surface-element index of a node that has none.
const NO_SOURCE: u32 = u32::MAX >> FLAG_BITS;

/// Width (voxels) of a closest-point shell.
const SHELL_WIDTH: f32 = 1.0;
/// Rounds with fewer nodes run on one thread: the front takes thousands of
/// rounds, and a fork-join per small round costs more than it saves.
const PARALLEL_MIN: usize = 8_192;
/// Thinnest z-slab (planes) of a parallel round.
const SLAB_PLANES: usize = 3;
/// Number of z-slabs a grid is cut into when its planes allow.
const SLABS: usize = 32;

/// Nodes improved by one relaxation task in one z-slab, queued for the
/// current shell (`[0]`) and the next (`[1]`).
type Improved = [Vec<u32>; 2];

/// One node: unsigned distance (voxels) and tag (`source << FLAG_BITS | flags`).
/// Stored packed in an [`AtomicU64`] (distance bits high, tag low) so that
/// slabs of a shell can be relaxed from several threads in safe code.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cell {
    dist: f32,
    tag: u32,
}

impl Cell {
    #[inline]
    fn pack(self) -> u64 {
        (u64::from(self.dist.to_bits()) << 32) | u64::from(self.tag)
    }
    #[inline]
    fn unpack(v: u64) -> Self {
        Self { dist: f32::from_bits((v >> 32) as u32), tag: v as u32 }
    }
    #[inline]
    fn flags(self) -> u32 {
        self.tag & FLAGS
    }
    #[inline]
    fn source(self) -> u32 {
        self.tag >> FLAG_BITS
    }
    #[inline]
    fn state(self) -> u32 {
        self.tag & STATE
    }
}

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
    /// The tangent disc at `closest`: unit normal (either orientation) and
    /// radius in voxels, when known.
    pub(crate) disc: Option<(Vec3, f32)>,
}

/// Largest radius (voxels) of the tangent disc a seed stands for. Seeds'
/// closest points sample the surface about one voxel apart, so discs of this
/// radius cover it; a disc leaves the surface by `radius² κ / 2` voxels where
/// the curvature is κ (per voxel), so band builders shrink it where the
/// surface bends sharply.
pub(crate) const DISC_RADIUS: f32 = 0.75;

/// A seed's piece of surface: its closest point and the tangent disc there.
#[derive(Debug, Clone, Copy)]
struct Surfel {
    point: Vec3,
    /// Unit normal, or zero when only the point is known.
    normal: Vec3,
    /// Disc radius in voxels.
    radius: f32,
}

impl Surfel {
    fn new(point: Vec3, disc: Option<(Vec3, f32)>) -> Self {
        let (normal, radius) = disc.map_or((Vec3::ZERO, 0.0), |(n, r)| (n.normalize_or_zero(), r));
        Self { point, normal, radius }
    }

    /// Distances (voxels) from the six neighbours of `x` to the nearest
    /// point of the tangent disc, neighbour `d` being one step along axis
    /// `d / 2`, forward when `d` is odd (the order of `Marcher::neighbour`'s
    /// `(axis, forward)` pairs).
    ///
    /// A bare point would sample the surface too coarsely near it: a node
    /// `d` voxels away whose propagated point is off by `δ` tangentially is
    /// off by `δ² / 2d`. The disc cuts that to the disc's own deviation from
    /// the surface. With `q = y − point`, normal part `s = q · normal` and
    /// tangential length `t = √(|q|² − s²)`, the distance is
    /// `√(s² + max(t − radius, 0)²)`; the six neighbours share `q · normal`
    /// and `|q|²` up to one axis term, so all six cost little more than one.
    #[inline]
    fn neighbour_distances(&self, x: Vec3) -> [f32; 6] {
        let q = x - self.point;
        let (s, qq) = (q.dot(self.normal), q.length_squared());
        let (q, n) = (q.to_array(), self.normal.to_array());
        let mut out = [0.0; 6];
        for (d, o) in out.iter_mut().enumerate() {
            let (axis, sign) = (d / 2, if d % 2 == 1 { 1.0 } else { -1.0 });
            let sd = s + sign * n[axis];
            let qd = qq + sign * 2.0 * q[axis] + 1.0;
            let t = (qd - sd * sd).max(0.0).sqrt();
            let over = (t - self.radius).max(0.0);
            *o = (sd * sd + over * over).sqrt();
        }
        out
    }
}

/// The state of one marching run, in grid units.
pub(crate) struct Marcher {
    nx: u32,
    ny: u32,
    nz: u32,
    cells: Vec<AtomicU64>,
    /// Closest-point mode: the seeds' surface elements.
    surfels: Vec<Surfel>,
    update: Update,
    /// Nodes farther than this (voxels) are never accepted.
    limit: f32,
    /// Eikonal updates: the Trial nodes.
    heap: RadixHeap,
    /// Closest-point propagation: the nodes queued in each shell, by z-slab.
    shells: Vec<Vec<Vec<u32>>>,
    /// Nodes per z-slab: whole planes, at least [`SLAB_PLANES`] of them.
    slab_nodes: u32,
    /// Number of z-slabs.
    slabs: usize,
    /// Every node's side was given up front.
    sided: bool,
}

impl Marcher {
    /// A run over `dims` nodes, every node Far. `limit` in voxels (may be
    /// infinite). With `sides`, every node's side is fixed from the sign of
    /// its value there (positive inside); without, nodes take the side of
    /// the seeds that reach them.
    pub(crate) fn new(
        dims: UVec3,
        update: Update,
        limit: f32,
        sides: Option<&[f32]>,
    ) -> Result<Self, FastMarchingError> {
        let nodes = dims.x as u64 * dims.y as u64 * dims.z as u64;
        if nodes > u32::MAX as u64 {
            return Err(FastMarchingError::TooManyNodes(nodes));
        }
        let far = Cell { dist: f32::INFINITY, tag: NO_SOURCE << FLAG_BITS | FAR }.pack();
        let requested = (nodes as usize).saturating_mul(size_of::<AtomicU64>());
        if requested > memory_limit() {
            return Err(GridError::TooLarge { dims, requested, limit: memory_limit() }.into());
        }
        let cells = match sides {
            Some(values) => values
                .par_iter()
                .map(|&v| AtomicU64::new(far | u64::from(SIGNED | if v > 0.0 { INSIDE } else { 0 })))
                .collect(),
            None => (0..nodes as usize).into_par_iter().map(|_| AtomicU64::new(far)).collect(),
        };
        let thickness = SLAB_PLANES.max(dims.z as usize / SLABS).min(dims.z.max(1) as usize);
        let slab_nodes = (dims.x as usize * dims.y as usize * thickness).max(1);
        Ok(Self {
            nx: dims.x,
            ny: dims.y,
            nz: dims.z,
            cells,
            surfels: Vec::new(),
            update,
            limit,
            heap: RadixHeap::new(),
            shells: Vec::new(),
            slab_nodes: slab_nodes as u32,
            slabs: (nodes as usize).div_ceil(slab_nodes).max(1),
            sided: sides.is_some(),
        })
    }

    /// The cell of node `n`.
    #[inline]
    fn cell(&self, n: u32) -> Cell {
        Cell::unpack(self.cells[n as usize].load(Relaxed))
    }

    /// Overwrites the cell of node `n` (no other thread may touch it meanwhile).
    #[inline]
    fn set(&self, n: u32, cell: Cell) {
        self.cells[n as usize].store(cell.pack(), Relaxed);
    }

    /// Adds a seed (its distance stays as given).
    ///
    /// # Errors
    /// [`FastMarchingError::MissingClosestPoint`] in closest-point mode when
    /// the seed has no surface point (`seed_number` names it),
    /// [`FastMarchingError::TooManySeeds`] past 2²⁷ − 1 seeds.
    pub(crate) fn add_seed(&mut self, seed: BandSeed, seed_number: usize) -> Result<(), FastMarchingError> {
        let cell = self.cell(seed.index);
        if seed.distance > cell.dist {
            return Ok(()); // A node seeded twice keeps the nearer value.
        }
        let mut flags = (cell.flags() & !STATE) | TRIAL | FIXED;
        if let Some(inside) = seed.inside {
            flags = (flags & !INSIDE) | SIGNED | if inside { INSIDE } else { 0 };
        }
        let mut source = cell.source();
        if self.update == Update::ClosestPoint {
            let cp = seed.closest.ok_or(FastMarchingError::MissingClosestPoint(seed_number))?;
            source = self.surfels.len() as u32;
            if source >= NO_SOURCE {
                return Err(FastMarchingError::TooManySeeds(source as usize + 1));
            }
            self.surfels.push(Surfel::new(cp, seed.disc));
            self.enqueue(seed.index, seed.distance, 0);
        } else {
            self.heap.push(seed.distance, seed.index);
        }
        self.set(seed.index, Cell { dist: seed.distance, tag: source << FLAG_BITS | flags });
        Ok(())
    }

    /// Grid coordinates of linear index `n`.
    #[inline]
    fn coords(&self, n: u32) -> [u32; 3] {
        let row = n / self.nx;
        [n - row * self.nx, row % self.ny, row / self.ny]
    }

    /// The neighbour of `n` (coordinates `c`) one step along `axis`, if any.
    #[inline]
    fn neighbour(&self, n: u32, c: [u32; 3], axis: usize, forward: bool) -> Option<u32> {
        let dims = [self.nx, self.ny, self.nz];
        let stride = [1, self.nx, self.nx * self.ny][axis];
        if forward {
            (c[axis] + 1 < dims[axis]).then(|| n + stride)
        } else {
            (c[axis] > 0).then(|| n - stride)
        }
    }

    /// Runs the front until every reachable node within the limit is Known.
    pub(crate) fn run(&mut self) {
        match self.update {
            Update::ClosestPoint => self.run_shells(),
            Update::FirstOrder | Update::SecondOrder => self.run_heap(),
        }
    }

    /// Queues `n` (distance `d`) in its shell, or in shell `current` if the
    /// front already passed it.
    #[inline]
    fn enqueue(&mut self, n: u32, d: f32, current: usize) {
        let shell = ((d / SHELL_WIDTH) as usize).max(current);
        if shell >= self.shells.len() {
            let slabs = self.slabs;
            self.shells.resize_with(shell + 1, || vec![Vec::new(); slabs]);
        }
        self.shells[shell][(n / self.slab_nodes) as usize].push(n);
    }

    /// Closest-point propagation, one shell at a time (see the module docs).
    fn run_shells(&mut self) {
        let mut shell = 0;
        // The lists being relaxed; their buffers are reused round to round.
        let mut round: Vec<Vec<u32>> = vec![Vec::new(); self.slabs];
        while shell < self.shells.len() {
            let queued: usize = self.shells[shell].iter().map(Vec::len).sum();
            if queued == 0 {
                shell += 1;
                continue;
            }
            // Relax the shell's nodes slab by slab; nodes re-queued into
            // this shell are relaxed in a further round.
            std::mem::swap(&mut round, &mut self.shells[shell]);
            let improved = if queued >= PARALLEL_MIN && self.slabs >= 4 {
                self.relax_slabs(&round, shell)
            } else {
                let mut out = vec![Improved::default(); self.slabs];
                for slab in &round {
                    self.relax_all(slab, shell, &mut out);
                }
                vec![out]
            };
            round.iter_mut().for_each(Vec::clear);
            if self.shells.len() < shell + 2 {
                self.shells.push(vec![Vec::new(); self.slabs]);
            }
            for (slab, lists) in improved.into_iter().flat_map(|task| task.into_iter().enumerate()) {
                for (offset, list) in lists.into_iter().enumerate() {
                    if !list.is_empty() {
                        self.shells[shell + offset][slab].extend_from_slice(&list);
                    }
                }
            }
        }
    }

    /// Relaxes the z-slabs' lists in parallel: the even slabs together, then
    /// the odd ones. A node only touches its own and the two neighbouring
    /// planes, and slabs are at least [`SLAB_PLANES`] thick, so slabs running
    /// together never touch the same cell and plain loads and stores suffice.
    fn relax_slabs(&self, slabs: &[Vec<u32>], shell: usize) -> Vec<Vec<Improved>> {
        let mut improved = Vec::with_capacity(slabs.len());
        for parity in 0..2 {
            let part: Vec<Vec<Improved>> = slabs
                .par_iter()
                .skip(parity)
                .step_by(2)
                .filter(|slab| !slab.is_empty())
                .map(|slab| {
                    let mut out = vec![Improved::default(); self.slabs];
                    self.relax_all(slab, shell, &mut out);
                    out
                })
                .collect();
            improved.extend(part);
        }
        improved
    }

    /// Relaxes the nodes of `list` in order during shell `shell`.
    fn relax_all(&self, list: &[u32], shell: usize, out: &mut [Improved]) {
        for &n in list {
            self.relax(n, shell, out);
        }
    }

    /// Accepts node `n` during shell `shell` and offers its surface element
    /// to its neighbours; improved neighbours are queued in `out` by their
    /// slab. Callers make sure no other thread touches the same cells
    /// meanwhile.
    fn relax(&self, n: u32, shell: usize, out: &mut [Improved]) {
        let cell = self.cell(n);
        if cell.state() == KNOWN || cell.dist > self.limit {
            return;
        }
        self.set(n, Cell { tag: (cell.tag & !STATE) | KNOWN, ..cell });
        let surfel = self.surfels[cell.source() as usize];
        let c = self.coords(n);
        let x = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        // Load all six neighbours first so that their cache misses overlap.
        let mut targets = [None; 6];
        for (d, t) in targets.iter_mut().enumerate() {
            *t = self.neighbour(n, c, d / 2, d % 2 == 1).map(|m| (m, self.cell(m)));
        }
        let distances = surfel.neighbour_distances(x);
        for (target, dist) in targets.into_iter().zip(distances) {
            let Some((m, nb)) = target else { continue };
            if nb.flags() & FIXED != 0 || nb.source() == cell.source() {
                continue;
            }
            if dist >= nb.dist {
                continue;
            }
            let mut flags = (nb.flags() & !STATE) | TRIAL;
            if flags & SIGNED == 0 && cell.flags() & SIGNED != 0 {
                flags |= SIGNED | (cell.flags() & INSIDE);
            }
            self.set(m, Cell { dist, tag: cell.source() << FLAG_BITS | flags });
            // The new distance is at most one voxel more than this node's,
            // which is below the end of this shell: it belongs to this shell
            // or the next (rounding errors go to the next as well).
            let next = usize::from((dist / SHELL_WIDTH) as usize > shell);
            out[(m / self.slab_nodes) as usize][next].push(m);
        }
    }

    /// Sethian's fast marching with the Eikonal update.
    fn run_heap(&mut self) {
        while let Some(n) = self.heap.pop() {
            let cell = self.cell(n);
            if cell.state() == KNOWN || cell.dist > self.limit {
                continue;
            }
            self.set(n, Cell { tag: (cell.tag & !STATE) | KNOWN, ..cell });
            let c = self.coords(n);
            for axis in 0..3 {
                for forward in [false, true] {
                    let Some(m) = self.neighbour(n, c, axis, forward) else { continue };
                    let nb = self.cell(m);
                    if nb.state() == KNOWN || nb.flags() & FIXED != 0 {
                        continue;
                    }
                    let mut flags = (nb.flags() & !STATE) | TRIAL;
                    if flags & SIGNED == 0 && cell.flags() & SIGNED != 0 {
                        flags |= SIGNED | (cell.flags() & INSIDE);
                    }
                    self.set(m, Cell { tag: (nb.tag & !FLAGS) | flags, ..nb });
                    let mut mc = c;
                    mc[axis] = if forward { c[axis] + 1 } else { c[axis] - 1 };
                    let u = self.eikonal(m, mc);
                    if u < nb.dist {
                        self.set(m, Cell { dist: u, tag: (nb.tag & !FLAGS) | flags });
                        self.heap.push(u, m);
                    }
                }
            }
        }
    }

    /// True when Known node `m` may serve as an upwind neighbour of a node
    /// with flags `own`: same side, or either side unknown, or on the surface.
    #[inline]
    fn usable(&self, m: u32, own: u32) -> bool {
        let c = self.cell(m);
        let f = c.flags();
        c.state() == KNOWN && (c.dist == 0.0 || f & own & SIGNED == 0 || (f & INSIDE) == (own & INSIDE))
    }

    /// The upwind Eikonal update `|∇u| = 1` at node `m` (coordinates `c`) from
    /// its Known neighbours: per axis the smaller upwind neighbour, with
    /// Sethian's second-order one-sided difference `(3u − 4a₁ + a₂) / 2` when
    /// the setting asks for it and the second node out is Known and no larger;
    /// the quadratic is solved with 1, 2 or 3 axes, adding axes while the
    /// solution exceeds their neighbour value.
    fn eikonal(&self, m: u32, c: [u32; 3]) -> f32 {
        let own = self.cell(m).flags();
        let second = self.update == Update::SecondOrder;
        // (upwind value a₁, centre b, weight w) per axis.
        let mut terms = [(f32::INFINITY, 0.0f32, 0.0f32); 3];
        for (axis, term) in terms.iter_mut().enumerate() {
            for forward in [false, true] {
                let Some(m1) = self.neighbour(m, c, axis, forward) else { continue };
                if !self.usable(m1, own) {
                    continue;
                }
                let a1 = self.cell(m1).dist;
                if a1 >= term.0 {
                    continue;
                }
                *term = (a1, a1, 1.0);
                let mut c1 = c;
                c1[axis] = if forward { c[axis] + 1 } else { c[axis] - 1 };
                if second && let Some(m2) = self.neighbour(m1, c1, axis, forward) {
                    let a2 = self.cell(m2).dist;
                    if self.usable(m2, own) && a2 <= a1 {
                        *term = (a1, (4.0 * a1 - a2) / 3.0, 2.25);
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
        if self.sided || self.cells.par_iter().all(|c| Cell::unpack(c.load(Relaxed)).flags() & SIGNED != 0) {
            return;
        }
        let mut stack: Vec<u32> =
            (0..self.cells.len() as u32).filter(|&n| self.cell(n).flags() & SIGNED != 0).collect();
        while let Some(n) = stack.pop() {
            let side = self.cell(n).flags() & INSIDE;
            let c = self.coords(n);
            for axis in 0..3 {
                for forward in [false, true] {
                    let Some(m) = self.neighbour(n, c, axis, forward) else { continue };
                    let nb = self.cell(m);
                    if nb.tag & SIGNED == 0 {
                        self.set(m, Cell { tag: nb.tag | SIGNED | side, ..nb });
                        stack.push(m);
                    }
                }
            }
        }
    }

    /// The signed result in world units: `±distance · spacing`, positive
    /// inside; nodes never accepted get `±unreached`.
    pub(crate) fn finish(
        mut self,
        origin: Vec3,
        spacing: f32,
        unreached: f32,
    ) -> Result<Grid3<f32>, FastMarchingError> {
        self.flood_sides();
        let limit = self.limit;
        let dims = UVec3::new(self.nx, self.ny, self.nz);
        let mut out = Grid3::new(dims, origin, spacing, 0.0f32)?;
        out.data_mut().par_iter_mut().zip(self.cells.par_iter()).for_each(|(o, c)| {
            let c = Cell::unpack(c.load(Relaxed));
            let magnitude = if c.state() == KNOWN && c.dist <= limit { c.dist * spacing } else { unreached };
            *o = if c.flags() & INSIDE != 0 { magnitude } else { -magnitude };
        });
        Ok(out)
    }
}
