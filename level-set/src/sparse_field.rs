//! Whitaker's sparse-field solver (Breen & Whitaker §5.2.2; Whitaker 1998)
//! with the first-order modification: the speed is sampled at the nearest
//! zero crossing, between grid points.
//!
//! # Layers
//! The active set `L0` holds the grid points next to the zero set, with
//! values in `[−½, ½]` (an active point leaves only past `±0.55`, see
//! below). Around it lie the layers `L±1` and `L±2` (positive inside). All
//! other nodes are *far*, at `±2.5` (the paper's `±(N + ½)` with `N = 2`).
//!
//! # One iteration, in the paper's order
//! 1. For each active point: a Newton step along the central-difference
//!    gradient finds the nearest zero crossing `x' = x − u ∇u / |∇u|²`; the
//!    speed is interpolated there ([`SpeedGrid`]: trilinear plus its
//!    limited second-order correction); the up-wind change (eq. 23) is
//!    computed.
//! 2. The changes are applied with one time step (the fastest front moving
//!    [`StepParams::front_step`] voxels, ½ by default (⅓ by eq. 24), and at most half a
//!    voxel of change); active points leaving `[−0.55, 0.55]` go on the
//!    status lists `S±1`. An active point does not leave upwards while a
//!    neighbour leaves downwards in the same iteration (and vice versa),
//!    which keeps the active set a boundary between inside and outside. The
//!    opposite-layer neighbours of a leaving point, which become active, get
//!    the value one unit from its new value (the one closest to zero if
//!    several).
//! 3. The status lists are processed outwards: a point moving from `L0` to
//!    `L±1` pulls its `L∓1` neighbours into `L0`, those pull their `L∓2`
//!    neighbours into `L∓1`, and those pull far points into `L∓2`.
//! 4. The layers are visited in the order `±1, ±2`; each point takes its
//!    distance from its neighbours (`L±1`: the Godunov update below; `L±2`:
//!    the paper's nearest inner neighbour plus one unit), or, with no inner
//!    neighbour, is demoted one layer outwards (from `L±2` to far). A
//!    point of `L±1` found within half a voxel of the surface joins the
//!    active set (its `L±2` neighbours move to `L±1`, their far neighbours
//!    to `L±2`).
//!
//! # Where this departs from the paper, and why
//! The paper keeps each layer "one unit from the next layer closest to the
//! active set" (the city-block distance) and samples the speed by trilinear
//! interpolation. Both put the converged surface off the target by more
//! than the grid's own floor (marching cubes of the exact distance;
//! diagnosis and figures in `docs/EXPERIMENTS.md`): city-block values
//! overestimate the distance on any front not aligned with the axes, the
//! active points' central differences read them, and the polygonized
//! surface's edges end in them; trilinear interpolation pulls a curved
//! target's zero set inwards where it is convex. Here:
//! - `L±1` values solve `|∇u| = 1` by the second-order up-wind (Godunov)
//!   update from the `L0` and same-layer neighbours ([`eikonal_update`]),
//!   exact for a planar front and second-order accurate on a curved one
//!   (`L±2`, which no active point's difference reads, keeps the paper's
//!   update);
//! - an `L±1` point closer than half a voxel joins the active set (so the
//!   point of each crossing edge nearer the surface moves with the
//!   level-set equation, not with a layer update), and an active point
//!   leaves only past `±0.55`: the margin keeps a point whose converged
//!   value lies just past `½` while its layer value lies just inside it
//!   from leaving and rejoining forever, and a point past it whose layer
//!   value would still lie within `½` stays active, held at `±0.55` (where
//!   the level-set equation and the layer update disagree by more than
//!   the margin, on a target the grid does not resolve, it would
//!   otherwise leave and rejoin every few iterations);
//! - the speed is interpolated with trilinear's second-order error term
//!   removed ([`SpeedGrid`]);
//! - no active point stays alone on its side of the surface (none of its
//!   face neighbours on it): such a one-node island is a target feature
//!   thinner than a voxel (a thin sheet or crevice sampled at one node) that
//!   the grid cannot resolve, and marching cubes would show it as a
//!   separate speck; the point goes back to its neighbours' side.
//!
//! Each iteration visits only the layer lists and their neighbours: the cost
//! grows with the surface area, not the volume.

use crate::solver::{Curvature, Solver, StepParams, StepStats, node_rate, stable_time_step};
use crate::stencil::{Lattice, Stored, Values, zero_crossing};
use crate::{BandFrame, LevelSetError, SpeedGrid};
use isomorph_common::glam::{UVec3, Vec3};
use isomorph_common::{BRICK, Bricks, Field3, Grid3, GridError, NodeStore};
use rayon::prelude::*;

/// Number of layers on each side of the active set.
const LAYERS: i8 = 2;
/// Status of far inside / outside points.
const FAR_IN: i8 = LAYERS + 1;
const FAR_OUT: i8 = -LAYERS - 1;
/// Value of far points (voxel units).
const FAR_VALUE: f32 = LAYERS as f32 + 0.5;
/// Status of an active point leaving upwards / downwards this iteration.
const ACTIVE_UP: i8 = 10;
const ACTIVE_DOWN: i8 = -10;
/// Status of a point on a status list, about to change layer.
const CHANGING: i8 = 20;
/// Bounds of the active range: a layer point closer to the surface joins
/// the active set.
const ACTIVE_MAX: f32 = 0.5;
/// An active point leaves the active set once its value is this far from
/// zero (voxels): `ACTIVE_MAX` plus a margin, so that a point whose
/// converged value lies just past `ACTIVE_MAX` while its layer value (from
/// its neighbours) lies just inside it does not leave and rejoin forever
/// (without the margin the reference case stalls short of convergence).
const LEAVE_MAX: f32 = ACTIVE_MAX + 0.05;

/// How much nearer the surface (voxels) the point beyond an `L±1` point's
/// nearest neighbour along an axis must lie for that axis's difference to
/// be fully second order; the one-sided difference is blended from first
/// to second order over `[0, ORDER_RAMP]`. Both orders are exact for a
/// planar front, so the blend is too; the alternative, a switch
/// to second order as soon as the point beyond is nearer, makes the layer
/// value jump by up to a third of a voxel as that point's value crosses
/// its neighbour's, and on a target the grid does not resolve the active
/// values and the layer values next to them then flip between two states
/// every iteration, never settling (`docs/EXPERIMENTS.md`).
const ORDER_RAMP: f32 = 0.5;

/// The sparse-field level-set solver, with its per-node embedding `U` and
/// layer status `S` kept in a [`NodeStore`]: by default sparse
/// ([`Bricks`]: values only in the bricks the band occupies or has
/// crossed, the far side elsewhere, so memory grows with the surface), or
/// dense (`Vec`, a value per node; the same results).
#[derive(Debug, Clone)]
pub struct SparseFieldSolver<U = Bricks<f32>, S = Bricks<i8>> {
    lattice: Lattice,
    u: U,
    status: S,
    /// Layer lists `L−2 … L+2` at index `ℓ + 2`; entries whose status no
    /// longer matches are dropped at the end of each iteration.
    layers: [Vec<u32>; 5],
    /// Length of each layer list's prefix that is sorted by node index
    /// (entries pushed since the last [`Self::compact`] follow it).
    sorted: [usize; 5],
    /// Per active point: `(change rate, distance-term speed, target
    /// distance at the zero crossing)` of the current step.
    rates: Vec<(f32, f32, f32)>,
    /// Per point of the layer list being updated: its distance from the
    /// surface, `None` without an inner neighbour.
    distances: Vec<Option<f32>>,
    /// Per active point: its nearest zero crossing (voxel coordinates) in
    /// the current step.
    crossings: Vec<Vec3>,
    /// Per active point: its value before the current step.
    before: Vec<f32>,
    /// Per active point: whether it leaves the active set this step
    /// (`±1`, towards `L±1`) or stays (`0`).
    leaving: Vec<i8>,
}

fn slot(layer: i8) -> usize {
    (layer + LAYERS) as usize
}

impl SparseFieldSolver {
    /// Builds the active set and layers from the source's signed distance
    /// grid (world units, positive inside), with the embedding and status
    /// in bricks: see [`Self::with_storage`].
    ///
    /// # Errors
    /// As [`Self::with_storage`].
    pub fn new(source: &Grid3<f32>) -> Result<Self, LevelSetError> {
        Self::with_storage(source)
    }

    /// Builds the active set and layers from the source's signed distance
    /// `field` (world units, positive inside; changing by at most the
    /// distance moved, as an exact distance does) on the lattice of `dims`
    /// nodes at `origin` with `spacing`, without a dense grid: the field is
    /// sampled in a narrow band of bricks ([`Bricks::sample_band`]) and
    /// only its side is kept elsewhere. The result equals
    /// [`Self::with_storage`] of the dense sample of `field`.
    ///
    /// # Errors
    /// [`LevelSetError::NonFinite`] for a NaN or infinite value in the band,
    /// [`MorphError::Grid`](isomorph_common::MorphError::Grid) for fewer than 3 nodes per axis, a node
    /// count over `u32`, or over the memory limit, [`LevelSetError::NoSurface`]
    /// without a sign change.
    pub fn from_field<F: Field3 + ?Sized>(
        field: &F,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
    ) -> Result<Self, LevelSetError> {
        if dims.min_element() < 3 {
            return Err(GridError::TooSmall { dims, min: 3 }.into());
        }
        let band = Bricks::sample_band(field, dims, origin, spacing, Self::band_width(spacing))?;
        Self::from_band(&band, spacing)
    }

    /// Half-width (world units) of the narrow band [`Self::from_band`]
    /// needs on a lattice of `spacing`: the layers lie within `LAYERS + 1`
    /// voxels of the surface, plus one voxel for rounding.
    pub fn band_width(spacing: f32) -> f32 {
        (f32::from(LAYERS) + 2.0) * spacing
    }

    /// [`Self::from_field`] from the field's narrow band already sampled
    /// (world units, [`Bricks::sample_band`] with at least
    /// [`Self::band_width`]), so the caller can keep it.
    ///
    /// # Errors
    /// As [`Self::from_field`].
    pub fn from_band(band: &Bricks<f32>, spacing: f32) -> Result<Self, LevelSetError> {
        let dims = band.dims();
        if dims.min_element() < 3 {
            return Err(GridError::TooSmall { dims, min: 3 }.into());
        }
        let side = BRICK as usize;
        for brick in band.allocated_bricks() {
            let first = band.brick_origin(brick);
            for (l, v) in band.brick_values(brick).unwrap_or_default().iter().enumerate() {
                let c = first
                    + UVec3::new((l % side) as u32, ((l / side) % side) as u32, (l / (side * side)) as u32);
                if !v.is_finite() && c.cmplt(dims).all() {
                    return Err(LevelSetError::NonFinite { what: "source", node: band.linear(c) });
                }
            }
        }
        let inv_h = 1.0 / spacing;
        Self::build(dims, |n| band[n] * inv_h)
    }
}

/// The active set of the values `value(n)` (voxel units, positive inside):
/// for every lattice edge the zero set crosses, the end closer to it, and
/// every node within [`ACTIVE_MAX`] of it.
fn active_nodes(lattice: &Lattice, value: &(impl Fn(usize) -> f32 + Sync)) -> Vec<u32> {
    (0..lattice.len())
        .into_par_iter()
        .filter(|&n| {
            let (un, inside) = (value(n), value(n) > 0.0);
            lattice.neighbours(n).iter().flatten().any(|&m| {
                let um = value(m);
                (um > 0.0) != inside && (un.abs() <= um.abs() || un.abs() <= ACTIVE_MAX)
            })
        })
        .map(|n| n as u32)
        .collect()
}

/// The nodes of `value` (voxel units, positive inside) that share a side
/// with none of their face neighbours, sorted, each with its value mirrored
/// to their side. Each such node or one of its neighbours is in `active`
/// (of every edge the zero set crosses, the end nearer to it is), so only
/// those are looked at.
fn one_node_islands(
    lattice: &Lattice,
    value: &(impl Fn(usize) -> f32 + Sync),
    active: &[u32],
) -> Vec<(usize, f32)> {
    let mut near: Vec<usize> = active
        .par_iter()
        .flat_map_iter(|&n| {
            let n = n as usize;
            std::iter::once(n).chain(lattice.neighbours(n).into_iter().flatten())
        })
        .collect();
    near.par_sort_unstable();
    near.dedup();
    near.into_par_iter()
        .filter_map(|n| {
            let inside = value(n) > 0.0;
            let alone = lattice.neighbours(n).into_iter().flatten().all(|m| (value(m) > 0.0) != inside);
            alone.then(|| (n, if inside { -value(n) } else { (-value(n)).max(f32::MIN_POSITIVE) }))
        })
        .collect()
}

impl<U: NodeStore<f32>, S: NodeStore<i8>> SparseFieldSolver<U, S> {
    /// Builds the active set and layers from the source's signed distance
    /// grid (world units, positive inside), keeping the embedding in `U`
    /// and the status in `S`.
    ///
    /// The active set is, for every grid edge the zero set crosses, the end
    /// closer to it (and every node within half a voxel of it); values are
    /// clamped to `[−½, ½]`, and the layers are then filled as in step 4.
    /// A sparse store holds values only in the bricks within two nodes of
    /// the active set; every other brick lies on one side of the surface.
    ///
    /// # Errors
    /// [`LevelSetError::NonFinite`], [`MorphError::Grid`](isomorph_common::MorphError::Grid) (fewer than 3 nodes per axis, or over the memory limit),
    /// [`LevelSetError::NoSurface`] for a source without a sign change.
    pub fn with_storage(source: &Grid3<f32>) -> Result<Self, LevelSetError> {
        crate::check_source(source, 0)?;
        let (d, inv_h) = (source.data(), 1.0 / source.spacing());
        Self::build(source.dims(), |n| d[n] * inv_h)
    }

    /// The solver for the source values `value(n)` (voxel units, positive
    /// inside) on a lattice of `dims` nodes (at least 3 per axis).
    ///
    /// The source starts free of one-node islands, as every step keeps it
    /// ([`Self::dissolve_islands`]): a node that none of its face neighbours
    /// shares a side with (a source feature thinner than a voxel sampled at
    /// one node, which marching cubes would show as a separate speck in the
    /// first frame) takes their side, its value mirrored; unless that would
    /// leave no surface at all (a source smaller than a voxel).
    fn build(dims: UVec3, value: impl Fn(usize) -> f32 + Sync) -> Result<Self, LevelSetError> {
        let lattice = Lattice::new(dims);
        let mut active = active_nodes(&lattice, &value);
        if active.is_empty() {
            return Err(LevelSetError::NoSurface("source"));
        }
        let mut islands = one_node_islands(&lattice, &value, &active);
        if !islands.is_empty() {
            let mirrored = |n: usize| match islands.binary_search_by_key(&n, |i| i.0) {
                Ok(k) => islands[k].1,
                Err(_) => value(n),
            };
            let without = active_nodes(&lattice, &mirrored);
            if without.is_empty() {
                islands.clear();
            } else {
                active = without;
            }
        }
        let value = |n: usize| match islands.binary_search_by_key(&n, |i| i.0) {
            Ok(k) => islands[k].1,
            Err(_) => value(n),
        };
        let inside = |n: usize| value(n) > 0.0;
        let reach = LAYERS as u32;
        let mut u = U::by_side(dims, inside, &active, reach, [-FAR_VALUE, FAR_VALUE])?;
        let mut status = S::by_side(dims, inside, &active, reach, [FAR_OUT, FAR_IN])?;
        for &n in &active {
            status[n as usize] = 0;
            u[n as usize] = value(n as usize).clamp(-ACTIVE_MAX, ACTIVE_MAX);
        }
        let mut solver = Self {
            lattice,
            u,
            status,
            layers: Default::default(),
            sorted: [0; 5],
            rates: Vec::new(),
            distances: Vec::new(),
            crossings: Vec::new(),
            before: Vec::new(),
            leaving: Vec::new(),
        };
        solver.layers[slot(0)] = active;
        // Grow the layers outwards from the active set, with the source's values.
        for layer in 1..=LAYERS {
            for side in [1i8, -1] {
                let inner = side * (layer - 1);
                let far = if side > 0 { FAR_IN } else { FAR_OUT };
                let mut grown = Vec::new();
                for &n in &solver.layers[slot(inner)] {
                    for m in solver.lattice.neighbours(n as usize).into_iter().flatten() {
                        if solver.status[m] == far {
                            solver.status[m] = side * layer;
                            solver.u[m] = value(m);
                            grown.push(m as u32);
                        }
                    }
                }
                solver.layers[slot(side * layer)] = grown;
            }
        }
        solver.propagate_layer_values();
        solver.compact();
        Ok(solver)
    }

    /// Number of points in the active set `L0`.
    pub fn active_len(&self) -> usize {
        self.layers[slot(0)].len()
    }

    /// Number of points in layer `ℓ ∈ [−2, 2]`.
    pub fn layer_len(&self, layer: i8) -> usize {
        self.layers[slot(layer.clamp(-LAYERS, LAYERS))].len()
    }

    /// Step 1: change rate of every active point, with the speed sampled at
    /// its nearest zero crossing; with `capture`, the state before the step
    /// is captured meanwhile (both only read the embedding), so that the
    /// capture's serial parts overlap the rates' parallel work.
    fn compute_rates(
        &mut self,
        speed: &SpeedGrid,
        curvature: Option<Curvature>,
        capture: Option<(usize, f64)>,
    ) -> Option<BandFrame> {
        let Self { lattice, u, layers, crossings, rates, .. } = self;
        let (lattice, u, h) = (&*lattice, &Stored(&*u), speed.spacing());
        let frame = || capture.map(|(iteration, time)| capture_layers(u, lattice, layers, iteration, time));
        let rates = || {
            let active = &layers[slot(0)];
            active.par_iter().map(|&n| zero_crossing(lattice, u, n as usize)).collect_into_vec(crossings);
            // A lazy speed fills the bricks the crossings read, then is read without locking per point.
            speed.prepare(crossings);
            let speeds = speed.reader();
            active
                .par_iter()
                .zip(&*crossings)
                .map(|(&n, &x)| {
                    let n = n as usize;
                    let d = speeds.at_voxel(x);
                    let (rate, gamma) = node_rate(lattice, u, n, d, h, curvature);
                    (rate, gamma, d)
                })
                .collect_into_vec(rates);
        };
        rayon::join(frame, rates).0
    }

    /// Step 2: applies the changes; returns the two status lists `S+1`, `S−1`
    /// and the RMS statistics.
    ///
    /// A point past `±LEAVE_MAX` leaves the active set only if it would stay
    /// out: if its distance as a layer point (step 4, from its neighbours'
    /// new values) is under `ACTIVE_MAX`, step 4 would take it straight back
    /// with that distance, and where the level-set equation and the layer
    /// update disagree by more than the margin (a target the grid does not
    /// resolve, whose residual speed keeps pushing the point out) it would
    /// leave and rejoin forever, the RMS change never settling. Such a point
    /// stays active, held at `±LEAVE_MAX`.
    fn apply_rates(&mut self, dt: f32) -> (Vec<u32>, Vec<u32>, StepStats) {
        let (mut up, mut down) = (Vec::new(), Vec::new());
        let (mut sum_change, mut sum_dist) = (0.0f64, 0.0f64);
        let active = std::mem::take(&mut self.layers[slot(0)]);
        // The new values first: whether a point may leave reads its neighbours'.
        let mut before = std::mem::take(&mut self.before);
        let u = &self.u;
        active.par_iter().map(|&n| u[n as usize]).collect_into_vec(&mut before);
        for (&n, &(rate, _, _)) in active.iter().zip(&self.rates) {
            self.u[n as usize] += dt * rate;
        }
        self.dissolve_islands(&active, &before);
        let mut leaving = std::mem::take(&mut self.leaving);
        let solver = &*self;
        active
            .par_iter()
            .map(|&n| {
                let new = solver.u[n as usize];
                let direction: i8 = if new > LEAVE_MAX {
                    1
                } else if new < -LEAVE_MAX {
                    -1
                } else {
                    return 0;
                };
                match solver.layer_distance(n as usize, direction) {
                    Some(v) if v < ACTIVE_MAX => 0,
                    _ => direction,
                }
            })
            .collect_into_vec(&mut leaving);
        for ((&n, &(_, _, distance)), (&old, &direction)) in
            active.iter().zip(&self.rates).zip(before.iter().zip(&leaving))
        {
            let n = n as usize;
            let new = self.u[n];
            sum_dist += f64::from(distance * distance);
            if direction == 0 {
                let kept = new.clamp(-LEAVE_MAX, LEAVE_MAX);
                sum_change += f64::from((kept - old).powi(2));
                self.u[n] = kept;
                continue;
            }
            let (opposite_move, opposite_layer, mine) =
                if direction > 0 { (ACTIVE_DOWN, -1, ACTIVE_UP) } else { (ACTIVE_UP, 1, ACTIVE_DOWN) };
            let neighbours = self.lattice.neighbours(n);
            if neighbours.iter().flatten().any(|&m| self.status[m] == opposite_move) {
                self.u[n] = old;
                continue;
            }
            let handed = new - f32::from(direction);
            for m in neighbours.into_iter().flatten() {
                if self.status[m] == opposite_layer
                    && (self.u[m].abs() > ACTIVE_MAX || handed.abs() < self.u[m].abs())
                {
                    self.u[m] = handed;
                }
            }
            self.status[n] = mine;
            if direction > 0 {
                up.push(n as u32)
            } else {
                down.push(n as u32)
            }
            sum_change += f64::from((new - old).powi(2));
        }
        self.layers[slot(0)] = active;
        (self.before, self.leaving) = (before, leaving);
        let count = self.rates.len().max(1) as f64;
        let stats = StepStats {
            dt,
            rms_change: (sum_change / count).sqrt() as f32,
            rms_distance: (sum_dist / count).sqrt() as f32,
            surface_nodes: self.rates.len(),
        };
        (up, down, stats)
    }

    /// Keeps the embedding free of one-node islands after step 2's update
    /// (`active` sorted, `before` its values before the step): an active
    /// point that none of its face neighbours shares a side with encloses a
    /// component smaller than a voxel, which marching cubes would show as a
    /// separate speck. Such points appear where the target has a feature
    /// thinner than a voxel (a thin sheet or crevice sampled at one node):
    /// the front passing it leaves the node behind, or the node crosses
    /// alone. A point that crossed zero this step goes back to its old
    /// value; a point its neighbours left takes their side (its value
    /// mirrored). Only points that crossed and their active neighbours can
    /// be alone, so the work is ∝ the crossings.
    fn dissolve_islands(&mut self, active: &[u32], before: &[f32]) {
        let (u, lattice, status) = (&self.u, &self.lattice, &self.status);
        let inside = |n: usize| u[n] > 0.0;
        let alone = |n: usize| lattice.neighbours(n).into_iter().flatten().all(|m| inside(m) != inside(n));
        // The crossings and their active neighbours (status `0`: the active
        // list holds exactly those nodes) that are alone; few, so their old
        // values are looked up afterwards.
        let mut lonely: Vec<usize> = active
            .par_iter()
            .zip(before)
            .filter(|&(&n, &old)| (old > 0.0) != inside(n as usize))
            .flat_map_iter(|(&n, _)| {
                let n = n as usize;
                let around = lattice.neighbours(n).into_iter().flatten().filter(|&m| status[m] == 0);
                std::iter::once(n).chain(around).filter(|&m| alone(m))
            })
            .collect();
        if lonely.is_empty() {
            return;
        }
        lonely.sort_unstable();
        lonely.dedup();
        let moves: Vec<(usize, f32)> = lonely
            .into_iter()
            .filter_map(|n| {
                let old = before[active.binary_search(&(n as u32)).ok()?];
                Some(match ((old > 0.0) != inside(n), u[n] > 0.0) {
                    (true, _) => (n, old),
                    (false, true) => (n, -u[n]),
                    (false, false) => (n, (-u[n]).max(f32::MIN_POSITIVE)),
                })
            })
            .collect();
        for (n, v) in moves {
            self.u[n] = v;
        }
    }

    /// Moves every point of `input` to `to`, and puts its neighbours of
    /// status `search` on the returned list (the paper's step 4).
    fn process_status_list(&mut self, input: &[u32], to: i8, search: i8) -> Vec<u32> {
        let mut output = Vec::new();
        for &n in input {
            let n = n as usize;
            self.status[n] = to;
            self.layers[slot(to)].push(n as u32);
            for m in self.lattice.neighbours(n).into_iter().flatten() {
                if self.status[m] == search {
                    self.status[m] = CHANGING;
                    output.push(m as u32);
                }
            }
        }
        output
    }

    /// Step 3: the status lists, outwards from the active set.
    fn process_status_lists(&mut self, up: &[u32], down: &[u32]) {
        // Upwards: L0 → L+1 pulls L−1 → L0, which pulls L−2 → L−1, which pulls far → L−2.
        let mut up = self.process_status_list(up, 1, -1);
        let mut down = self.process_status_list(down, -1, 1);
        for layer in 0..LAYERS {
            let (up_to, down_to) = (-layer, layer);
            let (up_search, down_search) =
                if layer + 1 == LAYERS { (FAR_OUT, FAR_IN) } else { (-layer - 2, layer + 2) };
            up = self.process_status_list(&up, up_to, up_search);
            down = self.process_status_list(&down, down_to, down_search);
        }
        for &n in &up {
            self.status[n as usize] = -LAYERS;
            self.layers[slot(-LAYERS)].push(n);
        }
        for &n in &down {
            self.status[n as usize] = LAYERS;
            self.layers[slot(LAYERS)].push(n);
        }
    }

    /// Step 4: values of `L±1` then `L±2` from their inner neighbours;
    /// points without one are demoted outwards.
    fn propagate_layer_values(&mut self) {
        for layer in 1..=LAYERS {
            for side in [1i8, -1] {
                let this = side * layer;
                let mut list = std::mem::take(&mut self.layers[slot(this)]);
                // `list` grows while it is visited: a promotion pulls points
                // in, which the next round visits.
                let mut start = 0;
                while start < list.len() {
                    // A Jacobi sweep: every distance from the values before it.
                    let mut distances = std::mem::take(&mut self.distances);
                    let solver = &*self;
                    list[start..]
                        .par_iter()
                        .map(|&n| {
                            let n = n as usize;
                            if solver.status[n] == this { solver.layer_distance(n, this) } else { None }
                        })
                        .collect_into_vec(&mut distances);
                    let end = list.len();
                    for (k, &distance) in (start..end).zip(&distances) {
                        let n = list[k] as usize;
                        if self.status[n] == this {
                            self.settle(n, this, distance, &mut list);
                        }
                    }
                    self.distances = distances;
                    start = end;
                }
                // Keep the list (stale entries are dropped in `compact`).
                list.append(&mut self.layers[slot(this)]);
                self.layers[slot(this)] = list;
            }
        }
    }

    /// Gives point `n` of layer `this ≠ 0` its `distance` from the surface:
    /// promoted to the active set within half a voxel (`L±1` only; its
    /// outer neighbours move one layer inwards, those of `L±1` onto
    /// `pulled`), demoted one layer outwards without an inner neighbour.
    fn settle(&mut self, n: usize, this: i8, distance: Option<f32>, pulled: &mut Vec<u32>) {
        let side = this.signum();
        let far = if side > 0 { FAR_IN } else { FAR_OUT };
        // A promotion earlier in this sweep may have given `n` an inner neighbour.
        let distance = distance.or_else(|| self.layer_distance(n, this));
        match distance {
            Some(v) if this.abs() == 1 && v < ACTIVE_MAX => {
                self.status[n] = 0;
                self.u[n] = f32::from(side) * v;
                self.layers[slot(0)].push(n as u32);
                let outer = this + side;
                for m in self.lattice.neighbours(n).into_iter().flatten() {
                    if self.status[m] != outer {
                        continue;
                    }
                    self.status[m] = this;
                    pulled.push(m as u32);
                    for k in self.lattice.neighbours(m).into_iter().flatten() {
                        if self.status[k] == far {
                            self.status[k] = outer;
                            self.layers[slot(outer)].push(k as u32);
                        }
                    }
                }
            }
            Some(v) => self.u[n] = f32::from(side) * v,
            None if this.abs() == LAYERS => {
                self.status[n] = far;
                self.u[n] = f32::from(side) * FAR_VALUE;
            }
            None => {
                self.status[n] = this + side;
                self.layers[slot(this + side)].push(n as u32);
            }
        }
    }

    /// The distance (voxels, positive away from the surface) of node `n`
    /// of layer `layer ≠ 0`; `None` without an inner-layer neighbour.
    ///
    /// `L±1`, whose values the active points' differences and the
    /// polygonized surface read: the up-wind (Godunov) solution of
    /// `|∇u| = 1` ([`eikonal_update`]) from, per axis, the neighbour nearest
    /// the surface among those of `L0` and of `n`'s own layer, blended
    /// towards second order as the next point on along the axis (in the
    /// band) lies nearer still ([`ORDER_RAMP`]). Own-layer neighbours carry the values of the last iteration
    /// (a Jacobi sweep, converged once the front stops): without them, a
    /// point whose nearest `L0` neighbours lie along one or two axes only
    /// would be given its distance along those axes, too far by up to
    /// `√3 − 1` voxels on a diagonal front.
    ///
    /// `L±2`: the paper's nearest inner neighbour plus one unit. No
    /// difference of an active point reads these values (face neighbours'
    /// layers differ by at most one), and a point moving into `L±1` is
    /// updated there; the cheaper update keeps the cost per iteration close
    /// to the paper's.
    fn layer_distance(&self, n: usize, layer: i8) -> Option<f32> {
        let side = f32::from(layer.signum());
        let inner = layer - layer.signum();
        let c = self.lattice.coords(n);
        // Reads by coordinates: a brick lookup without dividing `m`.
        let status =
            |m: usize, c: [usize; 3]| self.status.at(m, UVec3::new(c[0] as u32, c[1] as u32, c[2] as u32));
        let value = |m: usize, c: [usize; 3]| self.u.at(m, UVec3::new(c[0] as u32, c[1] as u32, c[2] as u32));
        if layer.abs() > 1 {
            let nearest = self
                .lattice
                .neighbours_at(n, c)
                .into_iter()
                .flatten()
                .filter(|&(m, d)| status(m, d) == inner);
            return nearest.map(|(m, d)| side * value(m, d)).reduce(f32::min).map(|v| v + 1.0);
        }
        let (dims, strides) = (self.lattice.dims(), self.lattice.strides());
        let mut axes = [(f32::INFINITY, 1.0f32); 3];
        let mut reached = false;
        for axis in 0..3 {
            let (s, at, len) = (strides[axis], c[axis], dims[axis]);
            // The nearer of the two neighbours along the axis, and whether
            // it lies towards +axis.
            let mut nearest: Option<(usize, bool)> = None;
            let lines = [(at >= 1).then(|| (n - s, false)), (at + 1 < len).then(|| (n + s, true))];
            let moved = |up: bool, by: usize| {
                let mut d = c;
                d[axis] = if up { at + by } else { at - by };
                d
            };
            for (m, up) in lines.into_iter().flatten() {
                let d = moved(up, 1);
                let state = status(m, d);
                if state != inner && state != layer {
                    continue;
                }
                reached |= state == inner;
                let near = side * value(m, d);
                if near < axes[axis].0 {
                    axes[axis].0 = near;
                    nearest = Some((m, up));
                }
            }
            // Towards second order as the point beyond is nearer still:
            // c (v − a) = (v − u₁) + ½ w (v − 2u₁ + u₂), w ∈ [0, 1].
            let Some((m, up)) = nearest else { continue };
            let beyond = if up {
                (at + 2 < len).then(|| (m + s, moved(true, 2)))
            } else {
                (at >= 2).then(|| (m - s, moved(false, 2)))
            };
            let near = axes[axis].0;
            if let Some(b) = beyond
                .filter(|&(k, d)| (-LAYERS..=LAYERS).contains(&status(k, d)))
                .map(|(k, d)| side * value(k, d))
            {
                let w = ((near - b) / ORDER_RAMP).clamp(0.0, 1.0);
                let c = 1.0 + 0.5 * w;
                axes[axis] = (((1.0 + w) * near - 0.5 * w * b) / c, c);
            }
        }
        reached.then(|| eikonal_update(axes))
    }

    /// Drops list entries whose status moved on, and keeps every list
    /// sorted by node index (the entries pushed during the iteration are
    /// sorted and merged in, duplicates dropped): the next iteration then
    /// sweeps memory in order instead of jumping about the grid, which is
    /// what keeps the cost per point flat once the grid outgrows the cache.
    /// The five lists are compacted in parallel (each on its own).
    fn compact(&mut self) {
        let status = &self.status;
        self.layers.par_iter_mut().zip(self.sorted.par_iter_mut()).enumerate().for_each(
            |(i, (list, sorted))| {
                let layer = i as i8 - LAYERS;
                let keep = |n: &u32| status[*n as usize] == layer;
                let split = (*sorted).min(list.len());
                let mut fresh: Vec<u32> = list.drain(split..).filter(keep).collect();
                list.retain(keep);
                if !fresh.is_empty() {
                    fresh.sort_unstable();
                    *list = merge_sorted(list, &fresh);
                }
                *sorted = list.len();
            },
        );
    }
}

/// The up-wind (Godunov) solution `v` of `|∇u| = 1` at a node from one
/// `(a, c)` per axis: the one-sided difference along the axis is
/// `c (v − a)` (first order: `a` the nearest neighbour's distance, `c = 1`;
/// second order: `a = (4 u₁ − u₂)/3` from the next two points, `c = 3/2`;
/// a blend `c = 1 + w/2`, `a = ((1 + w) u₁ − (w/2) u₂)/c` in between; `a`
/// infinite for an axis without one). `v` is the largest root of
/// `Σ c² max(v − a, 0)² = 1`. Exact for a planar front, where the paper's
/// city-block update (nearest neighbour plus one) overestimates the
/// distance by up to `√3 − 1` voxels along a diagonal.
fn eikonal_update(mut axes: [(f32, f32); 3]) -> f32 {
    // Sorted by `a` (three compare-and-swaps).
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if axes[j].0 < axes[i].0 {
            axes.swap(i, j);
        }
    }
    let (a0, c0) = axes[0];
    let mut v = a0 + 1.0 / c0;
    let (mut sum_w, mut sum_wa, mut sum_waa) = (c0 * c0, c0 * c0 * a0, c0 * c0 * a0 * a0);
    for &(a, c) in &axes[1..] {
        if v <= a {
            break;
        }
        let w = c * c;
        sum_w += w;
        sum_wa += w * a;
        sum_waa += w * a * a;
        // Root of sum_w v² − 2 sum_wa v + sum_waa − 1 = 0.
        let disc = sum_wa * sum_wa - sum_w * (sum_waa - 1.0);
        v = (sum_wa + disc.max(0.0).sqrt()) / sum_w;
    }
    v
}

/// The sorted union of two sorted lists, without duplicates.
fn merge_sorted(a: &[u32], b: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let next = a[i].min(b[j]);
        i += usize::from(a[i] == next);
        j += usize::from(b[j] == next);
        out.push(next);
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out.dedup();
    out
}

impl<U: NodeStore<f32>, S: NodeStore<i8>> Solver for SparseFieldSolver<U, S> {
    /// The embedding and status stores, the layer lists and the
    /// per-iteration buffers.
    fn heap_bytes(&self) -> usize {
        let lists: usize = self.layers.iter().map(Vec::capacity).sum();
        self.u.heap_bytes()
            + self.status.heap_bytes()
            + lists * size_of::<u32>()
            + self.rates.capacity() * size_of::<(f32, f32, f32)>()
            + self.distances.capacity() * size_of::<Option<f32>>()
            + self.crossings.capacity() * size_of::<Vec3>()
            + self.before.capacity() * size_of::<f32>()
            + self.leaving.capacity()
    }

    fn step(&mut self, speed: &SpeedGrid, params: &StepParams) -> StepStats {
        self.step_after_capture(speed, params, None).0
    }

    fn step_after_capture(
        &mut self,
        speed: &SpeedGrid,
        params: &StepParams,
        capture: Option<(usize, f64)>,
    ) -> (StepStats, Option<BandFrame>) {
        let frame = self.compute_rates(speed, params.curvature, capture);
        let (max_rate, max_gamma) = self
            .rates
            .par_iter()
            .map(|r| (r.0.abs(), r.1.abs()))
            .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
        let mut dt = stable_time_step(max_gamma, params);
        if max_rate > 0.0 {
            dt = dt.min(ACTIVE_MAX / max_rate);
        }
        let (up, down, stats) = self.apply_rates(dt);
        self.process_status_lists(&up, &down);
        self.propagate_layer_values();
        self.compact();
        (stats, frame)
    }

    fn release(&mut self) -> usize {
        self.u.release_uniform() + self.status.release_uniform()
    }

    fn capture(&self, iteration: usize, time: f64) -> BandFrame {
        capture_layers(&Stored(&self.u), &self.lattice, &self.layers, iteration, time)
    }
}

/// The frame of embedding `u` from its layer lists: every node on the zero
/// set is in `L−1`, `L0` or `L+1` (positive nodes are in `L0` or above,
/// negative ones in `L0` or below, and face neighbours' layers differ by at
/// most one).
fn capture_layers(
    u: &(impl Values + ?Sized),
    lattice: &Lattice,
    layers: &[Vec<u32>; 5],
    iteration: usize,
    time: f64,
) -> BandFrame {
    let near = [&layers[slot(-1)][..], &layers[slot(0)], &layers[slot(1)]];
    BandFrame::capture_near(u, lattice, near, iteration, time)
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::glam::Vec3;
    use isomorph_common::mesh::primitives;
    use isomorph_common::{Aabb, Control, Field3, Shape, Solid};
    use std::ops::Index;

    /// The values of a store at every node.
    fn dense<T: Copy>(store: &impl Index<usize, Output = T>, len: usize) -> Vec<T> {
        (0..len).map(|n| store[n]).collect()
    }

    /// The bricked solver's frames are bitwise those of the dense one at
    /// every iteration (analytic sphere → torus at 32³ and 48³, and meshes:
    /// a polygonal sphere into a polygonal torus at 40³), and so are its
    /// embedding and status at every node at the end.
    #[test]
    fn bricked_storage_equals_dense_storage() {
        let control = Control::new();
        let mesh_case = || {
            let (from, to) = (
                Solid::mesh(primitives::uv_sphere(Vec3::new(0.02, -0.01, 0.0), 0.3, 24, 32)).unwrap(),
                Solid::mesh(primitives::torus(0.3, 0.12, 48, 24)).unwrap(),
            );
            let bounds = Aabb::cube(0.5);
            let source = from.distance_volume(&bounds, 40, &control).unwrap();
            let target = to.distance_volume(&bounds, 40, &control).unwrap();
            (source, SpeedGrid::from_grid(&target, crate::Response::Identity).unwrap())
        };
        let analytic = |n: u32| {
            let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), n).unwrap();
            let speed =
                SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, crate::Response::Identity)
                    .unwrap();
            (source, speed)
        };
        for (source, speed) in [analytic(32), analytic(48), mesh_case()] {
            let mut bricked = SparseFieldSolver::new(&source).unwrap();
            let mut flat = SparseFieldSolver::<Vec<f32>, Vec<i8>>::with_storage(&source).unwrap();
            let params = StepParams::default();
            for i in 0..150 {
                if i > 0 {
                    assert_eq!(bricked.step(&speed, &params), flat.step(&speed, &params), "iteration {i}");
                }
                assert_eq!(bricked.capture(i, 0.0), flat.capture(i, 0.0), "iteration {i}");
            }
            let len = source.len();
            assert_eq!(dense(&bricked.u, len), flat.u);
            assert_eq!(dense(&bricked.status, len), flat.status);
        }
    }

    /// A lazy speed (bricks computed where the band goes) gives the frames
    /// of the speed sampled at every node, bitwise, at every iteration, while
    /// storing a part of it.
    #[test]
    fn lazy_speed_equals_the_sampled_speed() {
        let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 48).unwrap();
        let torus = Shape::torus(0.3, 0.12);
        let sampled = SpeedGrid::sample(&source, &torus, |x| x, crate::Response::Identity).unwrap();
        let inv_h = 1.0 / source.spacing();
        let sampler: crate::SpeedSampler = std::sync::Arc::new(move |x| torus.value(x) * inv_h);
        let lazy = SpeedGrid::lazy(source.dims(), source.origin(), source.spacing(), sampler).unwrap();
        assert_eq!(lazy.max_abs(), sampled.max_abs());
        let (mut a, mut b) =
            (SparseFieldSolver::new(&source).unwrap(), SparseFieldSolver::new(&source).unwrap());
        let params = StepParams::default();
        for i in 1..150 {
            assert_eq!(a.step(&sampled, &params), b.step(&lazy, &params), "iteration {i}");
            assert_eq!(a.capture(i, 0.0), b.capture(i, 0.0), "iteration {i}");
        }
        assert!(lazy.heap_bytes() < sampled.heap_bytes(), "{} bytes", lazy.heap_bytes());
        assert!((0..source.len()).all(|n| lazy.node_value(n) == sampled.node_value(n)));
    }

    /// Built from the analytic field in a narrow band, without a dense
    /// grid, the solver is the one built from the dense sample: equal
    /// frames at every iteration.
    #[test]
    fn from_field_equals_the_dense_source() {
        let sphere = Shape::sphere(0.3);
        let source = Grid3::sample_box(&sphere, &Aabb::cube(0.5), 56).unwrap();
        let speed =
            SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, crate::Response::Identity).unwrap();
        let mut dense = SparseFieldSolver::new(&source).unwrap();
        let mut band =
            SparseFieldSolver::from_field(&sphere, source.dims(), source.origin(), source.spacing()).unwrap();
        let params = StepParams::default();
        for i in 0..100 {
            if i > 0 {
                assert_eq!(dense.step(&speed, &params), band.step(&speed, &params), "iteration {i}");
            }
            assert_eq!(dense.capture(i, 0.0), band.capture(i, 0.0), "iteration {i}");
        }
        let outside = Shape::sphere(0.1).translated(Vec3::splat(2.0));
        let none = SparseFieldSolver::from_field(&outside, source.dims(), source.origin(), source.spacing());
        assert!(matches!(none, Err(LevelSetError::NoSurface("source"))));
    }

    /// At 256³ the bricked state of the reference case's source (layer lists
    /// included) takes under a fifth of the dense arrays' 5 bytes per node.
    #[test]
    fn bricked_state_is_far_under_dense_at_256() {
        let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 256).unwrap();
        let solver = SparseFieldSolver::new(&source).unwrap();
        let dense_bytes = 5 * source.len();
        assert!(
            solver.heap_bytes() * 5 < dense_bytes,
            "{} bytes bricked against {dense_bytes} dense",
            solver.heap_bytes()
        );
    }

    /// A planar front `u = d − n·x` (unit `n`, positive components): from
    /// its exact values one step (first order) or two steps (second order)
    /// towards the surface along every axis, the update returns `d` exactly.
    #[test]
    fn eikonal_update_is_exact_for_a_planar_front() {
        for n in [[1.0f32, 0.0, 0.0], [0.6, 0.8, 0.0], [0.48, 0.6, 0.64], [0.2, 0.3, 0.93]] {
            let norm = n.iter().map(|c| c * c).sum::<f32>().sqrt();
            let n = n.map(|c| c / norm);
            for d in [0.6f32, 0.9, 1.3] {
                let unused = |c: f32| if c > 0.0 { 0.0 } else { f32::INFINITY };
                let first = n.map(|c| (d - c + unused(c), 1.0));
                let second = n.map(|c| (((4.0 * (d - c)) - (d - 2.0 * c)) / 3.0 + unused(c), 1.5));
                for (axes, order) in [(first, "first"), (second, "second")] {
                    let v = eikonal_update(axes);
                    assert!((v - d).abs() < 1e-5, "{order} order, normal {n:?}: {v} for {d}");
                }
            }
        }
        // With one axis only, the update is the paper's: the neighbour plus one unit.
        assert!(
            (eikonal_update([(0.3, 1.0), (f32::INFINITY, 1.0), (f32::INFINITY, 1.0)]) - 1.3).abs() < 1e-6
        );
    }

    /// On a sphere (radius 20 voxels) the second-order update from the exact
    /// distances of the band is within 0.005 voxel of the true distance at
    /// every point of `L±1`, where the paper's city-block values are up to
    /// 0.4 voxel off; the active points are left at their exact distances.
    #[test]
    fn layer_values_are_the_distance_to_a_curved_surface() {
        let (n, r) = (48u32, 20.0f32);
        let centre = 23.7f32;
        let exact = |c: [usize; 3]| r - c.map(|c| (c as f32 - centre).powi(2)).iter().sum::<f32>().sqrt();
        let grid = Grid3::from_vec(
            isomorph_common::glam::UVec3::splat(n),
            isomorph_common::glam::Vec3::ZERO,
            1.0,
            (0..n * n * n)
                .map(|i| exact(Lattice::new(isomorph_common::glam::UVec3::splat(n)).coords(i as usize)))
                .collect(),
        )
        .unwrap();
        let mut solver = SparseFieldSolver::new(&grid).unwrap();
        for &node in &solver.layers[slot(0)] {
            solver.u[node as usize] = exact(solver.lattice.coords(node as usize));
        }
        // Two sweeps: the own-layer neighbours settle from the first.
        solver.propagate_layer_values();
        solver.propagate_layer_values();
        for layer in [-1i8, 1] {
            let worst = solver.layers[slot(layer)]
                .iter()
                .filter(|&&m| solver.status[m as usize] == layer)
                .map(|&m| (solver.u[m as usize] - exact(solver.lattice.coords(m as usize))).abs())
                .fold(0.0f32, f32::max);
            assert!(worst < 0.005, "layer {layer}: {worst} voxel off the distance");
        }
    }

    /// A target feature thinner than a voxel, sampled at one node (a ball
    /// of 0.4 voxel about a node outside the target's body), would be left
    /// behind by the shrinking front as a one-node island, which marching
    /// cubes shows as a separate speck; the island is dissolved, and the
    /// converged surface is the body's one component.
    #[test]
    fn no_one_node_island_is_left_behind() {
        let n = 32u32;
        let bounds = Aabb::cube(0.5);
        let source = Grid3::sample_box(&Shape::sphere(0.35), &bounds, n).unwrap();
        let h = source.spacing();
        let node = UVec3::new(24, 16, 16);
        let speck = source.position(node.x, node.y, node.z);
        assert!(speck.length() > 0.2 + 2.0 * h && speck.length() < 0.35 - 2.0 * h, "{speck}");
        let body = Shape::sphere(0.2);
        let sheet = diagonal_sheet(speck, h);
        let target = move |p: Vec3| body.value(p).max(sheet(p));
        let speed = SpeedGrid::sample(&source, &target, |x| x, crate::Response::Identity).unwrap();
        let at = |u: &Bricks<f32>| u[source.index(node.x, node.y, node.z)];
        assert!(speed.node_value(source.index(node.x, node.y, node.z)) > 0.25, "the speck's node is inside");
        let mut solver = SparseFieldSolver::new(&source).unwrap();
        for _ in 0..200 {
            solver.step(&speed, &StepParams::default());
        }
        assert!(at(&solver.u) <= 0.0, "the speck's node is outside: {}", at(&solver.u));
        assert_eq!(surface_components(&solver, &source), 1);
    }

    /// A disc of a sheet 0.6 voxel (of `h`) thick through `centre`, across
    /// the lattice's diagonal (positive inside): the face neighbours of a
    /// node at `centre` lie 0.58 voxel from the mid-plane (outside), and
    /// the sheet's nodes touch along edges only.
    fn diagonal_sheet(centre: Vec3, h: f32) -> impl Fn(Vec3) -> f32 + Copy {
        let normal = Vec3::ONE.normalize();
        move |p: Vec3| (0.3 * h - normal.dot(p - centre).abs()).min(2.0 * h - (p - centre).length())
    }

    /// Components of the zero set of `solver`'s values (in voxels) on the
    /// lattice of `like`, by marching cubes.
    fn surface_components(solver: &SparseFieldSolver, like: &Grid3<f32>) -> usize {
        let h = like.spacing();
        let u: Vec<f32> = dense(&solver.u, like.len()).iter().map(|v| v * h).collect();
        let grid = Grid3::from_vec(like.dims(), like.origin(), h, u).unwrap();
        isomorph_common::marching_cubes::marching_cubes(&grid, 0.0).metrics().components
    }

    /// A source feature thinner than a voxel, sampled at single nodes (the
    /// same diagonal sheet, now in the source outside its body: its nodes
    /// touch along edges only), starts on the body's side, so the first frame is the body's one component; a source
    /// smaller than a voxel (one node inside) is kept rather than lost.
    #[test]
    fn the_source_starts_without_one_node_islands() {
        let n = 32u32;
        let bounds = Aabb::cube(0.5);
        let probe = Grid3::sample_box(&Shape::sphere(0.2), &bounds, n).unwrap();
        let h = probe.spacing();
        let node = UVec3::new(24, 16, 16);
        let speck = probe.position(node.x, node.y, node.z);
        let sheet = diagonal_sheet(speck, h);
        let body = Shape::sphere(0.2);
        let source = Grid3::sample_box(&move |p: Vec3| body.value(p).max(sheet(p)), &bounds, n).unwrap();
        let index = source.index(node.x, node.y, node.z);
        assert!(source.data()[index] > 0.0, "the sheet's node is inside the source");
        let raw = isomorph_common::marching_cubes::marching_cubes(&source, 0.0);
        assert!(raw.metrics().components > 1, "the sampled source has specks");
        let solver = SparseFieldSolver::new(&source).unwrap();
        assert!(solver.u[index] <= 0.0, "the speck's node starts outside: {}", solver.u[index]);
        assert_eq!(surface_components(&solver, &source), 1);
        let mut dot = vec![-h; source.len()];
        dot[index] = 0.5 * h;
        let dot = Grid3::from_vec(source.dims(), source.origin(), h, dot).unwrap();
        let solver = SparseFieldSolver::new(&dot).unwrap();
        assert!(solver.u[index] > 0.0 && solver.active_len() > 0);
    }

    #[test]
    fn merge_keeps_order_and_drops_duplicates() {
        assert_eq!(merge_sorted(&[1, 4, 9], &[2, 4, 4, 10]), vec![1, 2, 4, 9, 10]);
        assert_eq!(merge_sorted(&[], &[3, 3]), vec![3]);
        assert_eq!(merge_sorted(&[7], &[]), vec![7]);
    }

    /// The capture from the layer lists equals the scan of the whole grid at
    /// every iteration: growth, shrinking, splitting and merging surfaces.
    #[test]
    fn capture_from_the_layers_equals_the_full_scan() {
        use isomorph_common::glam::Vec3;
        use isomorph_common::models;
        let two = Shape::sphere(0.15)
            .translated(Vec3::new(-0.22, 0.0, 0.0))
            .union(Shape::sphere(0.15).translated(Vec3::new(0.22, 0.0, 0.0)));
        let cases = [
            (Shape::sphere(0.3), Shape::torus(0.3, 0.12), 28),
            (models::ball(), models::c_shape(), 30),
            (models::mug(), models::chain(), 26),
            // Splits in two, and the reverse merges.
            (Shape::cuboid(Vec3::new(0.4, 0.08, 0.08)), two.clone(), 27),
            (two, Shape::cuboid(Vec3::new(0.4, 0.1, 0.1)), 25),
        ];
        for (from, to, n) in cases {
            let source = Grid3::sample_box(&from, &Aabb::cube(0.5), n).unwrap();
            let speed = SpeedGrid::sample(&source, &to, |x| x, crate::Response::Identity).unwrap();
            let mut solver = SparseFieldSolver::new(&source).unwrap();
            for i in 0..120 {
                if i > 0 {
                    solver.step(&speed, &StepParams::default());
                }
                let fast = solver.capture(i, 0.5);
                let u = dense(&solver.u, solver.lattice.len());
                assert_eq!(fast, BandFrame::capture(&u, &solver.lattice, i, 0.5), "iteration {i}");
            }
        }
    }

    #[test]
    fn layer_lists_stay_sorted_unique_and_consistent_with_status() {
        let source = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 32).unwrap();
        let speed =
            SpeedGrid::sample(&source, &Shape::torus(0.3, 0.12), |x| x, crate::Response::Identity).unwrap();
        let mut solver = SparseFieldSolver::new(&source).unwrap();
        for _ in 0..20 {
            solver.step(&speed, &StepParams::default());
            for layer in -LAYERS..=LAYERS {
                let list = &solver.layers[slot(layer)];
                assert!(list.windows(2).all(|w| w[0] < w[1]), "layer {layer} not strictly sorted");
                assert!(list.iter().all(|&n| solver.status[n as usize] == layer));
            }
            // Every node of a layer status is on its list.
            let on_lists: usize = solver.layers.iter().map(Vec::len).sum();
            let with_status =
                (0..solver.lattice.len()).filter(|&n| (-LAYERS..=LAYERS).contains(&solver.status[n])).count();
            assert_eq!(on_lists, with_status);
        }
    }
}
