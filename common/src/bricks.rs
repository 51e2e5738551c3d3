//! A sparse grid of fixed-size bricks: memory proportional to where values
//! are stored, not to the volume (after OpenVDB's leaf nodes, Museth 2013,
//! with a flat table in place of its tree).
//!
//! The lattice is cut into bricks of [`BRICK`]³ nodes. A brick holds values
//! only once something is written into it (allocation on write); every other
//! brick stands for a constant *background* value, one of two: the
//! `inside` or the `outside` value. Level-set state needs exactly that: real
//! values near the surface, and only the side (positive inside, negative
//! outside) everywhere else.
//!
//! Nodes are addressed like a dense x-fastest grid, by their linear index
//! `n = i + nx (j + ny k)` or by `(i, j, k)`, so code written against a
//! `[T]` indexed by node reads a [`Bricks`] the same way ([`Index`] and
//! [`IndexMut`]; a write through `IndexMut` allocates its brick).
//!
//! The brick table costs 4 bytes per brick (8 MiB at 1024³ nodes); every
//! allocated brick `512 × size_of::<T>()` bytes ([`Bricks::heap_bytes`]).

use crate::{Field3, GridError};
use glam::{UVec3, Vec3};
use rayon::prelude::*;
use std::fmt::Debug;
use std::ops::{Index, IndexMut};

/// Nodes along each edge of a brick.
pub const BRICK: u32 = 8;
/// `log2(BRICK)`.
const SHIFT: u32 = 3;
/// Nodes in one brick.
const BRICK_NODES: usize = (BRICK * BRICK * BRICK) as usize;
/// Table entry of an unallocated brick whose background is the outside value.
const OUTSIDE: u32 = u32::MAX;
/// Table entry of an unallocated brick whose background is the inside value.
const INSIDE: u32 = u32::MAX - 1;

/// A sparse grid of `dims` nodes stored in [`BRICK`]³ bricks, allocated on
/// write; an unallocated brick reads as its background, the `inside` or the
/// `outside` value.
#[derive(Debug, Clone, PartialEq)]
pub struct Bricks<T> {
    dims: UVec3,
    /// Bricks per axis.
    bricks: UVec3,
    /// Per brick (x-fastest): its slot in `data`, or [`INSIDE`] / [`OUTSIDE`].
    table: Vec<u32>,
    /// The allocated bricks, [`BRICK_NODES`] values each, nodes x-fastest
    /// within a brick.
    data: Vec<T>,
    /// Per slot: the brick it holds, or `None` for a released slot.
    owners: Vec<Option<u32>>,
    /// Released slots, reused before `data` grows.
    free: Vec<u32>,
    /// `[outside, inside]` background values.
    background: [T; 2],
}

impl<T: Copy + PartialEq> Bricks<T> {
    /// A grid of `dims` nodes whose every brick reads `outside` (mark the
    /// inside ones with [`Bricks::set_background`]).
    ///
    /// # Errors
    /// [`GridError::TooSmall`] for a zero dimension, [`GridError::TooLarge`]
    /// when the brick table alone is over the memory limit or the node
    /// count does not fit a `u32` index.
    pub fn new(dims: UVec3, outside: T, inside: T) -> Result<Self, GridError> {
        if dims.min_element() == 0 {
            return Err(GridError::TooSmall { dims, min: 1 });
        }
        let nodes = (dims.x as u64) * (dims.y as u64) * (dims.z as u64);
        let bricks = (dims + UVec3::splat(BRICK - 1)) >> SHIFT;
        let count = bricks.as_u64vec3().element_product() as usize;
        let requested = count.saturating_mul(size_of::<u32>());
        crate::grid::check_grid_bytes(dims, requested)?;
        if nodes > u64::from(u32::MAX) {
            return Err(GridError::TooLarge { dims, requested, limit: crate::memory_limit() });
        }
        Ok(Self {
            dims,
            bricks,
            table: vec![OUTSIDE; count],
            data: Vec::new(),
            owners: Vec::new(),
            free: Vec::new(),
            background: [outside, inside],
        })
    }

    /// Nodes per axis.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Number of nodes (allocated or not).
    pub fn len(&self) -> usize {
        self.dims.as_u64vec3().element_product() as usize
    }

    /// Always false: a grid has at least one node.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Bricks per axis.
    pub fn brick_dims(&self) -> UVec3 {
        self.bricks
    }

    /// Number of bricks (allocated or not).
    pub fn brick_count(&self) -> usize {
        self.table.len()
    }

    /// Number of allocated bricks.
    pub fn allocated(&self) -> usize {
        self.owners.len() - self.free.len()
    }

    /// Heap bytes held: the brick table, the brick storage (including
    /// released bricks kept for reuse) and the slot bookkeeping.
    pub fn heap_bytes(&self) -> usize {
        self.table.capacity() * size_of::<u32>()
            + self.data.capacity() * size_of::<T>()
            + self.owners.capacity() * size_of::<Option<u32>>()
            + self.free.capacity() * size_of::<u32>()
    }

    /// The `[outside, inside]` background values.
    pub fn background_values(&self) -> [T; 2] {
        self.background
    }

    /// Integer coordinates of linear node `n` (x-fastest).
    pub fn coords(&self, n: usize) -> UVec3 {
        let n = n as u32;
        let (nx, ny) = (self.dims.x, self.dims.y);
        let yz = n / nx;
        UVec3::new(n - yz * nx, yz % ny, yz / ny)
    }

    /// Linear index (x-fastest) of node `c`.
    pub fn linear(&self, c: UVec3) -> usize {
        c.x as usize + self.dims.x as usize * (c.y as usize + self.dims.y as usize * c.z as usize)
    }

    /// The index of the brick at brick coordinates `b` (x fastest).
    #[inline]
    fn brick_index(&self, b: UVec3) -> usize {
        b.x as usize + self.bricks.x as usize * (b.y as usize + self.bricks.y as usize * b.z as usize)
    }

    /// The brick holding node `c` and the node's offset inside it.
    fn locate(&self, c: UVec3) -> (usize, usize) {
        let brick = self.brick_index(c >> SHIFT);
        let l = c & UVec3::splat(BRICK - 1);
        (brick, (l.x | (l.y << SHIFT) | (l.z << (2 * SHIFT))) as usize)
    }

    /// The brick holding linear node `n`.
    pub fn brick_of(&self, n: usize) -> usize {
        self.locate(self.coords(n)).0
    }

    /// The first node (lowest `(i, j, k)`) of `brick`.
    pub fn brick_origin(&self, brick: usize) -> UVec3 {
        origin_of(self.bricks, brick)
    }

    /// Whether `brick` holds values of its own.
    pub fn is_allocated(&self, brick: usize) -> bool {
        self.table[brick] < INSIDE
    }

    /// Whether the unallocated `brick` reads the inside value (`None` for an
    /// allocated brick).
    pub fn background_of(&self, brick: usize) -> Option<bool> {
        match self.table[brick] {
            INSIDE => Some(true),
            OUTSIDE => Some(false),
            _ => None,
        }
    }

    /// Makes the unallocated `brick` read the inside (`true`) or the
    /// outside value; an allocated brick is left as it is.
    pub fn set_background(&mut self, brick: usize, inside: bool) {
        if !self.is_allocated(brick) {
            self.table[brick] = if inside { INSIDE } else { OUTSIDE };
        }
    }

    /// The value at node `c`.
    #[inline]
    pub fn get(&self, c: UVec3) -> T {
        let (brick, local) = self.locate(c);
        *self.read(brick, local)
    }

    /// The value at node `c` if its brick holds values of its own, `None`
    /// in a background brick: one brick lookup for both questions.
    #[inline]
    pub fn stored(&self, c: UVec3) -> Option<T> {
        let (brick, local) = self.locate(c);
        let slot = self.table[brick];
        (slot < INSIDE).then(|| self.data[slot as usize * BRICK_NODES + local])
    }

    #[inline]
    fn read(&self, brick: usize, local: usize) -> &T {
        match self.table[brick] {
            INSIDE => &self.background[1],
            OUTSIDE => &self.background[0],
            slot => &self.data[slot as usize * BRICK_NODES + local],
        }
    }

    /// Sets node `c` to `value`, allocating its brick (filled with its
    /// background) if needed.
    pub fn set(&mut self, c: UVec3, value: T) {
        let (brick, local) = self.locate(c);
        *self.write(brick, local) = value;
    }

    #[inline]
    fn write(&mut self, brick: usize, local: usize) -> &mut T {
        let slot = self.allocate(brick);
        &mut self.data[slot * BRICK_NODES + local]
    }

    /// Allocates `brick` (filled with its background value) if it is not,
    /// and returns its slot.
    fn allocate(&mut self, brick: usize) -> usize {
        let entry = self.table[brick];
        if entry < INSIDE {
            return entry as usize;
        }
        let fill = self.background[usize::from(entry == INSIDE)];
        let slot = match self.free.pop() {
            Some(slot) => {
                let s = slot as usize;
                self.data[s * BRICK_NODES..(s + 1) * BRICK_NODES].fill(fill);
                self.owners[s] = Some(brick as u32);
                s
            }
            None => {
                self.data.resize(self.data.len() + BRICK_NODES, fill);
                self.owners.push(Some(brick as u32));
                self.owners.len() - 1
            }
        };
        self.table[brick] = slot as u32;
        slot
    }

    /// The values of allocated `brick`, nodes x-fastest within it (`None`
    /// when it is not allocated). Nodes of an edge brick past the grid's
    /// dims hold the background they were allocated with.
    pub fn brick_values(&self, brick: usize) -> Option<&[T]> {
        self.is_allocated(brick).then(|| {
            let s = self.table[brick] as usize;
            &self.data[s * BRICK_NODES..(s + 1) * BRICK_NODES]
        })
    }

    /// Copies the values of the `N³` nodes `first + (i, j, k)`, `i, j, k <
    /// N`, into `out` (x fastest), one brick lookup per brick they span
    /// rather than per node: `true` when all their bricks are allocated,
    /// `false` (and `out` partly written) when one is not.
    ///
    /// # Panics
    /// If the box reaches past the grid's dims, or `out` does not hold `N³`
    /// values.
    pub fn stored_cube<const N: usize>(&self, first: UVec3, out: &mut [T]) -> bool {
        assert_eq!(out.len(), N * N * N, "stored_cube: one value per node");
        let last = first + UVec3::splat(N as u32 - 1);
        assert!(last.cmplt(self.dims).all(), "stored_cube: {first} + {N}³ reaches past {}", self.dims);
        let (lo, hi) = (first >> SHIFT, last >> SHIFT);
        for bz in lo.z..=hi.z {
            for by in lo.y..=hi.y {
                for bx in lo.x..=hi.x {
                    let brick = UVec3::new(bx, by, bz);
                    let Some(values) = self.brick_values(self.brick_index(brick)) else { return false };
                    // The box's nodes in this brick.
                    let from = first.max(brick << SHIFT);
                    let to = last.min((brick << SHIFT) + UVec3::splat(BRICK - 1));
                    for z in from.z..=to.z {
                        for y in from.y..=to.y {
                            let row =
                                ((y & (BRICK - 1)) << SHIFT | (z & (BRICK - 1)) << (2 * SHIFT)) as usize;
                            let at = ((y - first.y) as usize + N * (z - first.z) as usize) * N;
                            for x in from.x..=to.x {
                                out[at + (x - first.x) as usize] = values[row + (x & (BRICK - 1)) as usize];
                            }
                        }
                    }
                }
            }
        }
        true
    }

    /// Allocates `brick` if needed and sets its values (nodes x-fastest
    /// within the brick; `BRICK³` of them, including any past the grid's
    /// dims in an edge brick).
    ///
    /// # Panics
    /// If `values` does not hold `BRICK³` values.
    pub fn fill_brick(&mut self, brick: usize, values: &[T]) {
        let slot = self.allocate(brick);
        self.data[slot * BRICK_NODES..(slot + 1) * BRICK_NODES].copy_from_slice(values);
    }

    /// The allocated bricks (brick index), in slot order.
    pub fn allocated_bricks(&self) -> impl Iterator<Item = usize> + '_ {
        self.owners.iter().filter_map(|o| o.map(|b| b as usize))
    }

    /// Releases every allocated brick whose values all equal one of the
    /// two background values (which it then reads: no value changes), e.g.
    /// the bricks a moving level-set band has left; their storage is kept
    /// for the next allocation. Returns how many were released. Work ∝ the
    /// allocated bricks.
    pub fn release_uniform(&mut self) -> usize
    where
        T: Send + Sync,
    {
        let background = self.background;
        let uniform: Vec<(usize, bool)> = self
            .data
            .par_chunks(BRICK_NODES)
            .zip(self.owners.par_iter())
            .filter_map(|(values, owner)| {
                let brick = owner.map(|b| b as usize)?;
                let first = values[0];
                let side =
                    [false, true].into_iter().find(|&inside| first == background[usize::from(inside)])?;
                values.iter().all(|&v| v == first).then_some((brick, side))
            })
            .collect();
        for &(brick, inside) in &uniform {
            self.release(brick, inside);
        }
        uniform.len()
    }

    /// Releases allocated `brick`, which then reads the inside (`true`) or
    /// outside value; its storage is kept for the next allocation.
    pub fn release(&mut self, brick: usize, inside: bool) {
        let entry = self.table[brick];
        if entry < INSIDE {
            self.owners[entry as usize] = None;
            self.free.push(entry);
        }
        self.table[brick] = if inside { INSIDE } else { OUTSIDE };
    }
}

impl<T: Copy + PartialEq> Index<usize> for Bricks<T> {
    type Output = T;

    /// The value at linear node `n` (x-fastest).
    #[inline]
    fn index(&self, n: usize) -> &T {
        let (brick, local) = self.locate(self.coords(n));
        self.read(brick, local)
    }
}

impl<T: Copy + PartialEq> IndexMut<usize> for Bricks<T> {
    /// The value at linear node `n`, allocating its brick (filled with its
    /// background) if needed.
    #[inline]
    fn index_mut(&mut self, n: usize) -> &mut T {
        let (brick, local) = self.locate(self.coords(n));
        self.write(brick, local)
    }
}

impl<T: Copy + PartialEq + Send + Sync> Bricks<T> {
    /// Allocates the bricks `list` (ascending brick indices get ascending
    /// slots), each filled with its background.
    pub(crate) fn allocate_all(&mut self, list: &[usize]) {
        self.data.reserve_exact(list.len() * BRICK_NODES);
        self.owners.reserve_exact(list.len());
        for &brick in list {
            self.allocate(brick);
        }
    }

    /// Calls `f(brick, values)` for every allocated brick, in parallel.
    pub(crate) fn par_for_each_brick(&mut self, f: impl Fn(usize, &mut [T]) + Sync + Send) {
        let Bricks { data, owners, .. } = self;
        data.par_chunks_mut(BRICK_NODES).zip(owners.par_iter()).for_each(|(chunk, owner)| {
            if let Some(brick) = owner {
                f(*brick as usize, chunk);
            }
        });
    }

    /// The slot of allocated `brick` (its index among [`Bricks::brick_values`]'s
    /// storage), `None` when it is not allocated.
    pub(crate) fn slot_of(&self, brick: usize) -> Option<usize> {
        self.is_allocated(brick).then(|| self.table[brick] as usize)
    }

    /// Number of slots (allocated or released).
    pub(crate) fn slots(&self) -> usize {
        self.owners.len()
    }
}

impl Bricks<f32> {
    /// Samples the signed distance `field` (world units, positive inside)
    /// on the lattice of `dims` nodes at `origin` with `spacing`, only in
    /// the bricks that come within `band` (world units) of its zero set: a
    /// narrow band, and the side elsewhere (unallocated bricks read
    /// `±band`, their nodes being farther than that).
    ///
    /// The field chooses how ([`Field3::band_bricks`]): by default one value
    /// per brick and one per band node ([`Bricks::sample_band_by_points`]);
    /// a triangle mesh's distance ([`MeshSdf`](crate::sdf::MeshSdf)) solves
    /// the band bricks as blocks of its lattice search and finds the signs
    /// once per region. Either way the nodes within `band` of the surface
    /// get the values a dense sample of `field` gets, and every other node
    /// the right side.
    ///
    /// # Errors
    /// As [`Bricks::new`].
    pub fn sample_band<F: Field3 + ?Sized>(
        field: &F,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<Self, GridError> {
        field.band_bricks(dims, origin, spacing, band)
    }

    /// [`Bricks::sample_band`] through single values: the default of
    /// [`Field3::band_bricks`], for any field.
    ///
    /// Each brick is judged by one value at its centre: with `|d|` over
    /// `band` plus the brick's half diagonal, no node of the brick lies
    /// within `band` of the surface, nor on the other side. That holds for
    /// any field whose value changes by at most the distance moved (an
    /// exact distance, or a bound such as a CSG of exact distances); the
    /// nodes sampled get exactly the values a dense sample of `field` gets.
    /// The work is one value per brick plus a full brick per band brick:
    /// proportional to the surface, not the volume.
    ///
    /// # Errors
    /// As [`Bricks::new`].
    pub fn sample_band_by_points<F: Field3 + ?Sized>(
        field: &F,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<Self, GridError> {
        let mut grid = Bricks::new(dims, -band, band)?;
        let last = dims - UVec3::ONE;
        let bricks = grid.bricks;
        // Per brick: `None` near the surface, or the side of a far brick.
        let sides: Vec<Option<bool>> = (0..grid.brick_count())
            .into_par_iter()
            .map(|brick| {
                let first = origin_of(bricks, brick);
                let extent = ((first + UVec3::splat(BRICK - 1)).min(last) - first).as_vec3();
                let d = field.value(origin + spacing * (first.as_vec3() + 0.5 * extent));
                (d.abs() > band + 0.5 * spacing * extent.length()).then_some(d > 0.0)
            })
            .collect();
        let near = sides.iter().filter(|s| s.is_none()).count();
        grid.data.reserve_exact(near * BRICK_NODES);
        grid.owners.reserve_exact(near);
        for (brick, side) in sides.into_iter().enumerate() {
            match side {
                Some(inside) => grid.set_background(brick, inside),
                None => {
                    grid.allocate(brick);
                }
            }
        }
        // The band bricks, row by row as `Grid3::fill_from` samples them.
        let Bricks { data, owners, .. } = &mut grid;
        data.par_chunks_mut(BRICK_NODES).zip(owners.par_iter()).for_each(|(chunk, owner)| {
            let Some(brick) = owner.map(|b| b as usize) else { return };
            let first = origin_of(bricks, brick);
            let mut points = [Vec3::ZERO; BRICK as usize];
            for (row, out) in chunk.chunks_mut(BRICK as usize).enumerate() {
                // Nodes past the lattice (edge bricks) are sampled at its border.
                let j = (first.y + row as u32 % BRICK).min(last.y);
                let k = (first.z + row as u32 / BRICK).min(last.z);
                let yz = origin + spacing * Vec3::new(0.0, j as f32, k as f32);
                for (i, p) in points.iter_mut().enumerate() {
                    let x = (first.x + i as u32).min(last.x);
                    *p = yz + Vec3::new(spacing * x as f32, 0.0, 0.0);
                }
                field.values(&points, out);
            }
        });
        Ok(grid)
    }
}

/// The first node of `brick` among `bricks` bricks per axis.
pub(crate) fn origin_of(bricks: UVec3, brick: usize) -> UVec3 {
    let (bx, by) = (bricks.x as usize, bricks.y as usize);
    UVec3::new((brick % bx) as u32, ((brick / bx) % by) as u32, (brick / (bx * by)) as u32) << SHIFT
}

/// Per-node storage of an x-fastest lattice, addressed by linear node
/// index: dense (`Vec<T>`, a value per node) or sparse ([`Bricks`], values
/// only near a given set of nodes). Lets an algorithm written against node
/// indices (a sparse-field level set) run on either, with equal results.
pub trait NodeStore<T>: IndexMut<usize, Output = T> + Clone + Debug + Send + Sync {
    /// A store of `dims` nodes in which node `n` reads `values[1]` (inside)
    /// when `is_inside(n)`, `values[0]` (outside) otherwise. A sparse store
    /// allocates only the bricks within `reach` nodes (per axis) of a node
    /// of `near` (linear indices) and gives every other brick the side of
    /// its first node: the caller guarantees such bricks lie on one side.
    ///
    /// # Errors
    /// [`GridError::TooSmall`] for a zero dimension, [`GridError::TooLarge`]
    /// over the memory limit.
    fn by_side(
        dims: UVec3,
        is_inside: impl Fn(usize) -> bool + Sync,
        near: &[u32],
        reach: u32,
        values: [T; 2],
    ) -> Result<Self, GridError>
    where
        Self: Sized;

    /// Heap bytes held.
    fn heap_bytes(&self) -> usize;

    /// The value at node `n`, whose coordinates are `c`: `self[n]`, read
    /// without recovering `c` from `n` (two integer divisions a brick
    /// lookup otherwise needs; for a solver's inner loops).
    #[inline]
    fn at(&self, n: usize, _c: UVec3) -> T
    where
        T: Copy,
    {
        self[n]
    }

    /// Drops what reads as a background value anyway (a sparse store's
    /// uniform bricks, [`Bricks::release_uniform`]; nothing for a dense
    /// one, the default); every node keeps its value. Returns the bricks
    /// released.
    fn release_uniform(&mut self) -> usize {
        0
    }
}

impl<T: Copy + Debug + Send + Sync> NodeStore<T> for Vec<T> {
    fn by_side(
        dims: UVec3,
        is_inside: impl Fn(usize) -> bool + Sync,
        _near: &[u32],
        _reach: u32,
        values: [T; 2],
    ) -> Result<Self, GridError> {
        if dims.min_element() == 0 {
            return Err(GridError::TooSmall { dims, min: 1 });
        }
        let len = dims.as_u64vec3().element_product() as usize;
        crate::grid::check_grid_bytes(dims, len.saturating_mul(size_of::<T>()))?;
        Ok((0..len).into_par_iter().map(|n| values[usize::from(is_inside(n))]).collect())
    }

    fn heap_bytes(&self) -> usize {
        self.capacity() * size_of::<T>()
    }
}

impl<T: Copy + PartialEq + Debug + Send + Sync> NodeStore<T> for Bricks<T> {
    #[inline]
    fn at(&self, _n: usize, c: UVec3) -> T {
        self.get(c)
    }

    fn by_side(
        dims: UVec3,
        is_inside: impl Fn(usize) -> bool + Sync,
        near: &[u32],
        reach: u32,
        values: [T; 2],
    ) -> Result<Self, GridError> {
        let mut grid = Bricks::new(dims, values[0], values[1])?;
        let mut marked = vec![false; grid.brick_count()];
        let last = dims - UVec3::ONE;
        let (bx, by) = (grid.bricks.x as usize, grid.bricks.y as usize);
        for &n in near {
            let c = grid.coords(n as usize);
            let lo = c.saturating_sub(UVec3::splat(reach)) >> SHIFT;
            let hi = (c + UVec3::splat(reach)).min(last) >> SHIFT;
            for k in lo.z..=hi.z {
                for j in lo.y..=hi.y {
                    for i in lo.x..=hi.x {
                        marked[i as usize + bx * (j as usize + by * k as usize)] = true;
                    }
                }
            }
        }
        let count = marked.iter().filter(|&&m| m).count();
        grid.data.reserve_exact(count * BRICK_NODES);
        grid.owners.reserve_exact(count);
        for (brick, &keep) in marked.iter().enumerate() {
            if keep {
                grid.allocate(brick);
            } else {
                let first = grid.linear(grid.brick_origin(brick));
                grid.set_background(brick, is_inside(first));
            }
        }
        // Every node of an allocated brick by its own side, bricks in parallel.
        let (bricks, nx, nxy) = (grid.bricks, dims.x as usize, dims.x as usize * dims.y as usize);
        let Bricks { data, owners, .. } = &mut grid;
        data.par_chunks_mut(BRICK_NODES).zip(owners.par_iter()).for_each(|(chunk, owner)| {
            let Some(brick) = owner.map(|b| b as usize) else { return };
            let origin = origin_of(bricks, brick);
            for (local, v) in chunk.iter_mut().enumerate() {
                let l = local as u32;
                let c = origin + UVec3::new(l & (BRICK - 1), (l >> SHIFT) & (BRICK - 1), l >> (2 * SHIFT));
                if c.cmple(last).all() {
                    let n = c.x as usize + nx * c.y as usize + nxy * c.z as usize;
                    *v = values[usize::from(is_inside(n))];
                }
            }
        });
        Ok(grid)
    }

    fn heap_bytes(&self) -> usize {
        Bricks::heap_bytes(self)
    }

    fn release_uniform(&mut self) -> usize {
        Bricks::release_uniform(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `stored` reads an allocated brick's values (its background fill
    /// included) and nothing in a background brick, whichever side it is.
    #[test]
    fn stored_is_none_only_in_background_bricks() {
        let mut grid = Bricks::new(UVec3::new(20, 9, 17), -1.0f32, 1.0).unwrap();
        let (set, same_brick, other) = (UVec3::new(12, 3, 5), UVec3::new(13, 2, 7), UVec3::new(2, 3, 5));
        let inside = grid.brick_of(grid.linear(other));
        grid.set_background(inside, true);
        assert_eq!((grid.stored(set), grid.stored(other)), (None, None));
        grid.set(set, 0.25);
        assert_eq!(grid.stored(set), Some(0.25));
        assert_eq!(grid.stored(same_brick), Some(-1.0));
        assert_eq!((grid.stored(other), grid.get(other)), (None, 1.0));
    }

    /// A 4³ box of nodes copied brick by brick is every node's own value,
    /// wherever the box sits across brick faces; a box touching a
    /// background brick reports it.
    #[test]
    fn stored_cubes_are_the_nodes_values() {
        let dims = UVec3::new(21, 19, 18);
        let mut grid = Bricks::new(dims, -1.0f32, 1.0).unwrap();
        let value = |c: UVec3| (c.x + 100 * c.y + 10_000 * c.z) as f32;
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x.min(16) {
                    grid.set(UVec3::new(x, y, z), value(UVec3::new(x, y, z)));
                }
            }
        }
        let mut out = [0.0f32; 64];
        for first in [UVec3::ZERO, UVec3::new(5, 6, 7), UVec3::new(6, 13, 14), UVec3::new(12, 2, 5)] {
            assert!(grid.stored_cube::<4>(first, &mut out), "{first}");
            for (n, &v) in out.iter().enumerate() {
                let c = first + UVec3::new(n as u32 % 4, (n as u32 / 4) % 4, n as u32 / 16);
                assert_eq!(v, value(c), "{first} + {c}");
            }
        }
        // Nodes x = 16.. lie in bricks never written.
        assert!(!grid.stored_cube::<4>(UVec3::new(14, 0, 0), &mut out));
    }

    /// Random writes into a bricked and a dense grid of odd dims (edge
    /// bricks cut by the border) read back equal everywhere, through both
    /// addressings; only the written bricks are allocated.
    #[test]
    fn reads_equal_a_dense_grid() {
        let dims = UVec3::new(21, 17, 30);
        let mut sparse = Bricks::new(dims, -2.5f32, 2.5).unwrap();
        let len = sparse.len();
        let mut dense = vec![-2.5f32; len];
        // Bricks with z ≥ 2 (nodes z ≥ 16) are inside.
        for b in 0..sparse.brick_count() {
            if sparse.brick_origin(b).z >= 16 {
                sparse.set_background(b, true);
            }
        }
        for (n, v) in dense.iter_mut().enumerate() {
            if sparse.coords(n).z >= 16 {
                *v = 2.5;
            }
        }
        let mut state = 12345u64;
        let mut touched = std::collections::HashSet::new();
        for step in 0..3000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            // Writes clustered in a slab, as a band would be.
            let n = ((state >> 33) as usize) % (len / 3) + len / 3;
            let v = step as f32 * 0.001 - 1.0;
            dense[n] = v;
            if step % 2 == 0 {
                sparse[n] = v;
            } else {
                sparse.set(sparse.coords(n), v);
            }
            touched.insert(sparse.brick_of(n));
        }
        for (n, &v) in dense.iter().enumerate() {
            let c = sparse.coords(n);
            assert_eq!(sparse.linear(c), n);
            assert_eq!(sparse[n], v, "node {c}");
            assert_eq!(sparse.get(c), v, "node {c}");
        }
        assert_eq!(sparse.allocated(), touched.len());
        assert!(sparse.allocated() < sparse.brick_count());
        let mut listed: Vec<usize> = sparse.allocated_bricks().collect();
        listed.sort_unstable();
        let mut expected: Vec<usize> = touched.into_iter().collect();
        expected.sort_unstable();
        assert_eq!(listed, expected);
    }

    /// A released brick reads its new background, and its storage is
    /// reused by the next allocation (filled with that brick's background,
    /// not the old values).
    #[test]
    fn release_and_reuse() {
        let mut g = Bricks::new(UVec3::splat(16), 0u8, 1).unwrap();
        g[0] = 7;
        let first = g.brick_of(0);
        g.release(first, true);
        let bytes = g.heap_bytes();
        assert_eq!(g[0], 1);
        assert_eq!(g.allocated(), 0);
        assert_eq!(g.background_of(first), Some(true));
        let far = g.linear(UVec3::new(15, 15, 15));
        g[far] = 9;
        assert_eq!(g.heap_bytes(), bytes, "the released slot is reused");
        assert_eq!(g.brick_values(g.brick_of(far)).unwrap().iter().filter(|&&v| v == 0).count(), 511);
        assert_eq!(g[0], 1);
        assert_eq!(g[far], 9);
        assert_eq!(g.brick_origin(g.brick_of(far)), UVec3::splat(8));
    }

    /// Built by side around a sphere's surface nodes, the bricked store reads
    /// as the dense one at every node while allocating a fraction of the
    /// bricks.
    #[test]
    fn by_side_equals_the_dense_store() {
        let dims = UVec3::new(64, 61, 70);
        let r = |n: usize| {
            let c =
                Bricks::new(dims, 0u8, 0).unwrap().coords(n).as_vec3() - glam::Vec3::new(30.0, 27.0, 33.0);
            c.length() - 12.0
        };
        let near: Vec<u32> = (0..(64 * 61 * 70)).filter(|&n| r(n).abs() < 1.0).map(|n| n as u32).collect();
        let inside = |n: usize| r(n) < 0.0;
        let dense = <Vec<i8> as NodeStore<i8>>::by_side(dims, inside, &near, 3, [-3, 3]).unwrap();
        let sparse = <Bricks<i8> as NodeStore<i8>>::by_side(dims, inside, &near, 3, [-3, 3]).unwrap();
        assert!((0..dense.len()).all(|n| dense[n] == sparse[n]));
        assert!(sparse.allocated() < sparse.brick_count() / 3, "{} bricks", sparse.allocated());
        assert!(NodeStore::heap_bytes(&sparse) < NodeStore::heap_bytes(&dense));
    }

    /// The narrow band of a sphere's distance holds the dense sample's
    /// values bitwise at every node within the band, the right side at
    /// every other node, in a fraction of the bricks.
    #[test]
    fn sample_band_equals_the_dense_sample_near_the_surface() {
        let sphere = crate::Shape::sphere(0.3);
        let (dims, origin, h) = (UVec3::new(70, 64, 67), Vec3::splat(-0.5), 1.0 / 63.0);
        let dense = crate::Grid3::sample(&sphere, dims, origin, h).unwrap();
        let band = 3.0 * h;
        let sparse = Bricks::sample_band(&sphere, dims, origin, h, band).unwrap();
        for (n, &d) in dense.data().iter().enumerate() {
            let got = sparse[n];
            assert_eq!(got > 0.0, d > 0.0, "side of node {n}");
            assert!(d.abs() > band || got == d, "node {n}: {got} vs {d}");
        }
        assert!(sparse.allocated() * 3 < sparse.brick_count(), "{} bricks", sparse.allocated());
    }

    /// Only bricks holding one background value everywhere are released,
    /// and every node reads as before.
    #[test]
    fn uniform_bricks_are_released_without_changing_a_value() {
        let mut g = Bricks::new(UVec3::new(20, 16, 9), -2i8, 2).unwrap();
        let (a, b, c) =
            (g.linear(UVec3::new(1, 1, 1)), g.linear(UVec3::new(9, 1, 1)), g.linear(UVec3::new(17, 9, 1)));
        g[a] = 0; // stays: a value of its own
        g[b] = 2; // released as inside: all of it reads 2 only if the rest does too
        g[c] = -2; // released as outside
        let brick_b = g.brick_of(b);
        g.fill_brick(brick_b, &[2; 512]);
        let before: Vec<i8> = (0..g.len()).map(|n| g[n]).collect();
        assert_eq!(g.release_uniform(), 2);
        assert_eq!(g.allocated(), 1);
        assert_eq!(g.background_of(brick_b), Some(true));
        assert_eq!(g.background_of(g.brick_of(c)), Some(false));
        assert!((0..g.len()).all(|n| g[n] == before[n]));
    }

    #[test]
    fn empty_grids_are_refused() {
        assert!(Bricks::new(UVec3::new(4, 0, 4), 0.0f32, 1.0).is_err());
        assert!(Bricks::new(UVec3::splat(2048), 0.0f32, 1.0).is_err());
    }
}
