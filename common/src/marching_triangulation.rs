//! Marching triangulation of implicit surfaces after E. Hartmann, *A
//! marching method for the triangulation of surfaces*, The Visual Computer
//! 14, 95–108, 1998 — the mesher Yang & Jüttler use for their T-spline
//! level sets (their ref. \[10\]; §1 and §4.4, Fig. 1 (c1), (f1)).
//!
//! Where marching cubes cuts a lattice and leaves slivers of every shape,
//! the marching method grows a net of **near-equilateral triangles of a
//! chosen edge length `δ`** over the surface `{value = iso}`, from a seed
//! point outwards:
//!
//! 1. **Surface point** (Hartmann §2): a point near the surface is moved onto
//!    it by Newton's method along the gradient,
//!    `x ← x − (f(x) − iso) ∇f(x) / |∇f(x)|²`, until the step is below
//!    `10⁻⁴ δ`. Every vertex is such a point, with its unit normal.
//! 2. **Start** (§3.1): a surface point `p`, its tangent plane, and six points
//!    at distance `δ` around it in that plane, projected onto the surface:
//!    a hexagon of six triangles whose boundary is the first **front
//!    polygon** (the border between the triangulated and the untriangulated
//!    part of the surface).
//! 3. **Front angles** (§3.2): at every front point `p_i` the angle `ω_i` of
//!    the untriangulated region between the directions to its front
//!    neighbours, measured in the tangent plane of `p_i`.
//! 4. **Distance check** (§3.3): before the point with the smallest front
//!    angle is expanded, the front points nearer to it than `δ` (not its
//!    neighbours, lying in its untriangulated angle and it in theirs) are
//!    looked up. The nearest one on the **same** front splits the front in
//!    two (joined by the new edge `p_i p_j`); on **another** front, the two
//!    fronts are merged into one across that edge. Neither adds triangles.
//! 5. **Expansion** (§3.2): otherwise `p_i` is expanded by
//!    `n_t = ⌊3ω_i/π⌋ + 1` triangles of angle `Δω = ω_i/n_t` at `p_i`,
//!    corrected as Hartmann does (`Δω < 0.8` and `n_t > 1`: one triangle
//!    fewer; `n_t = 1`, `Δω > 0.8` and the neighbours farther apart than
//!    `1.25 δ`: two triangles; `ω_i < 3` with a neighbour nearer than
//!    `δ/2`: one triangle). The `n_t − 1` new points sit at distance `δ`
//!    from `p_i` in its tangent plane, rotated by `kΔω` from the direction
//!    to the previous neighbour, projected onto the surface; they replace
//!    `p_i` in the front. A front of three points is closed by one triangle.
//! 6. The surface is done when no front is left. Hartmann starts from a
//!    point; to find **every component**, seed points are taken from a
//!    marching-cubes mesh on a coarse lattice (`seed_resolution` nodes along
//!    the longest edge of `bounds`), and a component is started at every
//!    such point farther than `δ` from the vertices made so far.
//!
//! Front points are kept in a priority queue by front angle and in a hash
//! grid of cell `δ` for the distance check, so the cost is
//! `O(T log T)` for `T` triangles plus a few field evaluations (value and
//! gradient) per vertex; the seed lattice costs what
//! [`level_set_mesh`] costs.
//!
//! # Output
//! Triangles are counter-clockwise seen from outside (their right-hand
//! normal points towards values below `iso`), as [`crate::marching_cubes`]
//! makes them. Every vertex is on the surface to `10⁻³ δ` (Newton's
//! tolerance), edges are about `δ` long and the triangles' angles mostly
//! between 40° and 80° (measured in the tests and `docs/EXPERIMENTS.md`).
//!
//! # Limits (not guaranteed)
//! - The surface must be smooth at the scale of `δ`: features thinner than
//!   about `δ` (or curvature radii below `δ`) make fronts collide in ways
//!   the distance check does not resolve, and the net may overlap itself
//!   there. Hartmann's adaptive step length (curvature dependent) is not
//!   implemented: `δ` is one constant.
//! - Where the surface leaves `bounds`, the front stops and the mesh is open.
//! - Components the seed lattice misses (smaller than its spacing) are
//!   missed.
//! - A projection that fails (vanishing gradient) leaves its front point
//!   unexpanded and the mesh open there; [`TriangulationStats`] counts it.

use crate::marching_cubes::level_set_mesh;
use crate::{Aabb, Field3, MorphError, TriMesh};
use glam::Vec3;
use serde::Serialize;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::f32::consts::PI;

/// Settings of [`marching_triangulation`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangulationSettings {
    /// The step length `δ`: the target edge length of the triangles, world
    /// units (> 0).
    pub edge: f32,
    /// Lattice nodes along the longest edge of the bounds for the
    /// marching-cubes mesh that supplies one seed point per component
    /// (2–1024; default 64).
    pub seed_resolution: u32,
    /// The most triangles to make before giving up with an error (default
    /// 10 million).
    pub max_triangles: usize,
}

impl Default for TriangulationSettings {
    /// `edge` 0.02 (a hundredth of the domain `[−1, 1]³` of the T-spline
    /// crate), seeds from a 64-node lattice, at most 10⁷ triangles.
    fn default() -> Self {
        Self { edge: 0.02, seed_resolution: 64, max_triangles: 10_000_000 }
    }
}

/// What [`marching_triangulation`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[non_exhaustive]
pub struct TriangulationStats {
    /// Components started (one hexagon each).
    pub seeds: usize,
    /// Fronts split in two by the distance check.
    pub splits: usize,
    /// Pairs of fronts merged by the distance check.
    pub merges: usize,
    /// Front points left unexpanded: outside the bounds or where the
    /// projection onto the surface failed (the mesh is open there).
    pub stopped: usize,
}

/// The triangle quality figures of a mesh (angles in degrees, lengths in
/// world units), as used to compare meshers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[non_exhaustive]
pub struct TriangleQuality {
    /// The smallest angle of any triangle (degrees).
    pub min_angle: f64,
    /// The mean over the triangles of their smallest angle (degrees; 60 for
    /// equilateral triangles).
    pub mean_min_angle: f64,
    /// Share of triangles whose smallest angle is below 20°.
    pub below_20_degrees: f64,
    /// Mean edge length (world units; edges counted once per triangle).
    pub mean_edge: f64,
    /// Standard deviation of the edge lengths divided by their mean.
    pub edge_spread: f64,
}

/// The angles and edge lengths of `mesh`'s triangles (degenerate triangles
/// count with angle 0). Returns `None` for a mesh without triangles.
pub fn triangle_quality(mesh: &TriMesh) -> Option<TriangleQuality> {
    let n = mesh.triangles.len();
    if n == 0 {
        return None;
    }
    let (mut min_angle, mut sum_min, mut below) = (f64::INFINITY, 0.0, 0usize);
    let (mut sum_len, mut sum_len2) = (0.0f64, 0.0f64);
    for t in 0..n {
        let c = mesh.corners(t).map(|p| p.as_dvec3());
        let e = [c[1] - c[0], c[2] - c[1], c[0] - c[2]];
        let mut smallest = f64::INFINITY;
        for k in 0..3 {
            let (a, b) = (e[k], -e[(k + 2) % 3]);
            let denom = a.length() * b.length();
            let angle =
                if denom > 0.0 { (a.dot(b) / denom).clamp(-1.0, 1.0).acos().to_degrees() } else { 0.0 };
            smallest = smallest.min(angle);
            sum_len += e[k].length();
            sum_len2 += e[k].length_squared();
        }
        min_angle = min_angle.min(smallest);
        sum_min += smallest;
        below += usize::from(smallest < 20.0);
    }
    let edges = 3.0 * n as f64;
    let mean_edge = sum_len / edges;
    let variance = (sum_len2 / edges - mean_edge * mean_edge).max(0.0);
    Some(TriangleQuality {
        min_angle,
        mean_min_angle: sum_min / n as f64,
        below_20_degrees: below as f64 / n as f64,
        mean_edge,
        edge_spread: if mean_edge > 0.0 { variance.sqrt() / mean_edge } else { 0.0 },
    })
}

/// Hartmann's marching triangulation of `field`'s level set `iso` inside
/// `bounds` (see the [module docs](self)): near-equilateral triangles of
/// edge length `settings.edge`, oriented outward.
///
/// # Errors
/// [`MorphError::BadSetting`] for a non-positive or non-finite `edge`, a
/// `seed_resolution` outside 2–1024, or when more than `max_triangles`
/// would be made; [`MorphError::Grid`] when the seed lattice is too large
/// or `bounds` is empty.
///
/// # Example
/// ```
/// use glam::Vec3;
/// use isomorph_common::Aabb;
/// use isomorph_common::marching_triangulation::{TriangulationSettings, marching_triangulation};
///
/// let ball = |p: Vec3| 0.5 - p.length(); // positive inside
/// let settings = TriangulationSettings { edge: 0.1, ..Default::default() };
/// let (mesh, _) = marching_triangulation(&ball, &Aabb::cube(1.0), 0.0, &settings)?;
/// assert_eq!(mesh.edge_stats().boundary_edges, 0); // closed
/// assert_eq!(mesh.genus(), Some(0));
/// assert!(mesh.positions.iter().all(|p| (p.length() - 0.5).abs() < 1e-4));
/// # Ok::<(), isomorph_common::MorphError>(())
/// ```
pub fn marching_triangulation<F: Field3 + ?Sized>(
    field: &F,
    bounds: &Aabb,
    iso: f32,
    settings: &TriangulationSettings,
) -> Result<(TriMesh, TriangulationStats), MorphError> {
    if !(settings.edge > 0.0 && settings.edge.is_finite()) {
        return Err(MorphError::bad_setting("edge", settings.edge, "a finite length > 0"));
    }
    if !(2..=1024).contains(&settings.seed_resolution) {
        return Err(MorphError::bad_setting("seed_resolution", settings.seed_resolution, "2..=1024"));
    }
    let seeds = level_set_mesh(field, bounds, settings.seed_resolution, iso)?;
    let mut net = Net::new(field, iso, bounds.expanded(0.5 * settings.edge), settings);
    for &candidate in &seeds.positions {
        if net.near_vertex(candidate) {
            continue;
        }
        if let Some((p, n)) = net.surface_point(candidate)
            && !net.near_vertex(p)
        {
            net.start(p, n)?;
            net.march()?;
        }
    }
    let mesh = TriMesh::new(net.positions, net.triangles)?;
    Ok((mesh, net.stats))
}

/// Integer cell of a hash grid of cell size `cell`.
fn cell_of(p: Vec3, cell: f32) -> (i32, i32, i32) {
    let c = (p / cell).floor();
    (c.x as i32, c.y as i32, c.z as i32)
}

/// The 27 cells around `p`'s cell.
fn cells_around(p: Vec3, cell: f32) -> impl Iterator<Item = (i32, i32, i32)> {
    let (x, y, z) = cell_of(p, cell);
    (-1..=1).flat_map(move |dx| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| (x + dx, y + dy, z + dz))))
}

/// One point of a front polygon (fronts are doubly linked cycles).
#[derive(Debug, Clone, Copy)]
struct Entry {
    vertex: u32,
    prev: u32,
    next: u32,
    front: u32,
    /// The front angle `ω` (radians, in `[0, 2π)`).
    angle: f32,
    /// Bumped whenever the angle changes (stale queue items are skipped).
    version: u32,
    alive: bool,
}

/// The growing net: mesh, fronts and their search structures.
struct Net<'a, F: ?Sized> {
    field: &'a F,
    iso: f32,
    bounds: Aabb,
    delta: f32,
    max_triangles: usize,
    positions: Vec<Vec3>,
    /// Outward unit normal per vertex.
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    entries: Vec<Entry>,
    /// Live entries per front.
    front_sizes: Vec<usize>,
    /// Smallest front angle first: (angle bits, entry, version).
    queue: BinaryHeap<Reverse<(u32, u32, u32)>>,
    /// Front entries by cell of size `δ`.
    entry_grid: HashMap<(i32, i32, i32), Vec<u32>>,
    /// Mesh vertices by cell of size `δ`.
    vertex_grid: HashMap<(i32, i32, i32), Vec<u32>>,
    stats: TriangulationStats,
}

impl<'a, F: Field3 + ?Sized> Net<'a, F> {
    fn new(field: &'a F, iso: f32, bounds: Aabb, settings: &TriangulationSettings) -> Self {
        Self {
            field,
            iso,
            bounds,
            delta: settings.edge,
            max_triangles: settings.max_triangles,
            positions: Vec::new(),
            normals: Vec::new(),
            triangles: Vec::new(),
            entries: Vec::new(),
            front_sizes: Vec::new(),
            queue: BinaryHeap::new(),
            entry_grid: HashMap::new(),
            vertex_grid: HashMap::new(),
            stats: TriangulationStats::default(),
        }
    }

    /// Hartmann's surface point: Newton's method along the gradient from
    /// `start`; the point and its outward unit normal, or `None` where the
    /// gradient vanishes or the iteration does not settle.
    fn surface_point(&self, start: Vec3) -> Option<(Vec3, Vec3)> {
        let tolerance = 1e-4 * self.delta;
        let mut x = start;
        for _ in 0..20 {
            let g = self.field.gradient(x);
            let gg = g.length_squared();
            if !(gg > 1e-20 && gg.is_finite()) {
                return None;
            }
            let step = g * ((self.field.value(x) - self.iso) / gg);
            x -= step;
            if !x.is_finite() || (x - start).length() > 2.0 * self.delta {
                return None;
            }
            if step.length() < tolerance {
                let n = -self.field.gradient(x).normalize_or_zero();
                return (n != Vec3::ZERO).then_some((x, n));
            }
        }
        None
    }

    /// True when a mesh vertex lies within `δ` of `p`.
    fn near_vertex(&self, p: Vec3) -> bool {
        let r2 = self.delta * self.delta;
        cells_around(p, self.delta).any(|c| {
            self.vertex_grid
                .get(&c)
                .is_some_and(|vs| vs.iter().any(|&v| self.positions[v as usize].distance_squared(p) < r2))
        })
    }

    fn add_vertex(&mut self, p: Vec3, n: Vec3) -> u32 {
        let v = self.positions.len() as u32;
        self.positions.push(p);
        self.normals.push(n);
        self.vertex_grid.entry(cell_of(p, self.delta)).or_default().push(v);
        v
    }

    fn add_triangle(&mut self, t: [u32; 3]) -> Result<(), MorphError> {
        if self.triangles.len() >= self.max_triangles {
            return Err(MorphError::bad_setting(
                "max_triangles",
                self.max_triangles,
                "more triangles for this surface and edge length (or a longer edge)",
            ));
        }
        self.triangles.push(t);
        Ok(())
    }

    fn add_entry(&mut self, vertex: u32, front: u32) -> u32 {
        let e = self.entries.len() as u32;
        let entry = Entry { vertex, prev: e, next: e, front, angle: 0.0, version: 0, alive: true };
        self.entries.push(entry);
        self.entry_grid.entry(cell_of(self.positions[vertex as usize], self.delta)).or_default().push(e);
        e
    }

    fn link(&mut self, a: u32, b: u32) {
        self.entries[a as usize].next = b;
        self.entries[b as usize].prev = a;
    }

    fn kill(&mut self, e: u32) {
        let entry = &mut self.entries[e as usize];
        entry.alive = false;
        self.front_sizes[entry.front as usize] -= 1;
    }

    fn pos(&self, e: u32) -> Vec3 {
        self.positions[self.entries[e as usize].vertex as usize]
    }

    /// The tangent-plane direction from entry `e`'s point to `q` (not unit).
    fn tangent(&self, e: u32, q: Vec3) -> Vec3 {
        let v = self.entries[e as usize].vertex as usize;
        let (p, n) = (self.positions[v], self.normals[v]);
        let d = q - p;
        d - n * n.dot(d)
    }

    /// The counter-clockwise angle about entry `e`'s normal from its
    /// previous neighbour's direction to `q`'s, in `[0, 2π)`.
    fn angle_to(&self, e: u32, q: Vec3) -> f32 {
        let entry = self.entries[e as usize];
        let n = self.normals[entry.vertex as usize];
        let u = self.tangent(e, self.pos(entry.prev));
        let w = self.tangent(e, q);
        let a = n.dot(u.cross(w)).atan2(u.dot(w));
        if a < 0.0 { a + 2.0 * PI } else { a }
    }

    /// Recomputes entry `e`'s front angle and queues it (unless its point
    /// is outside the bounds: the front stops there).
    fn update(&mut self, e: u32) {
        let next = self.pos(self.entries[e as usize].next);
        let angle = self.angle_to(e, next);
        let entry = &mut self.entries[e as usize];
        entry.angle = angle;
        entry.version += 1;
        let (version, inside) = (entry.version, self.bounds.contains(self.pos(e)));
        if inside {
            self.queue.push(Reverse((angle.to_bits(), e, version)));
        } else {
            self.stats.stopped += 1;
        }
    }

    /// §3.1: the hexagon around the surface point `p` (normal `n`).
    fn start(&mut self, p: Vec3, n: Vec3) -> Result<(), MorphError> {
        let t1 = n.any_orthonormal_vector();
        let t2 = n.cross(t1);
        let mut ring = Vec::with_capacity(6);
        for k in 0..6 {
            let angle = k as f32 * PI / 3.0;
            let q = p + self.delta * (t1 * angle.cos() + t2 * angle.sin());
            match self.surface_point(q) {
                Some(point) => ring.push(point),
                None => return Ok(()), // not smooth here: the next seed point may be
            }
        }
        self.stats.seeds += 1;
        let centre = self.add_vertex(p, n);
        let ring: Vec<u32> = ring.into_iter().map(|(q, m)| self.add_vertex(q, m)).collect();
        let front = self.front_sizes.len() as u32;
        self.front_sizes.push(6);
        let entries: Vec<u32> = ring.iter().map(|&v| self.add_entry(v, front)).collect();
        for k in 0..6 {
            self.add_triangle([centre, ring[k], ring[(k + 1) % 6]])?;
            self.link(entries[k], entries[(k + 1) % 6]);
        }
        for e in entries {
            self.update(e);
        }
        Ok(())
    }

    /// Runs steps 3–5 until every front is closed (or stopped).
    fn march(&mut self) -> Result<(), MorphError> {
        while let Some(Reverse((_, e, version))) = self.queue.pop() {
            let entry = self.entries[e as usize];
            if !entry.alive || entry.version != version {
                continue;
            }
            if self.front_sizes[entry.front as usize] == 3 {
                self.close(e)?;
            } else if let Some(other) = self.nearest_front_point(e) {
                if self.entries[other as usize].front == entry.front {
                    self.split(e, other);
                } else {
                    self.merge(e, other);
                }
            } else {
                self.expand(e)?;
            }
        }
        Ok(())
    }

    /// Closes the three-point front of `e` with one triangle.
    fn close(&mut self, e: u32) -> Result<(), MorphError> {
        let Entry { vertex, prev, next, .. } = self.entries[e as usize];
        let (a, b) = (self.entries[prev as usize].vertex, self.entries[next as usize].vertex);
        self.add_triangle([vertex, a, b])?;
        for x in [e, prev, next] {
            self.kill(x);
        }
        Ok(())
    }

    /// §3.3: the nearest front point within `δ` of `e` that may be joined to
    /// it: not `e`'s point or its neighbours' (nor next to another copy of
    /// `e`'s point), inside `e`'s front angle, with `e` inside its own.
    fn nearest_front_point(&mut self, e: u32) -> Option<u32> {
        let entry = self.entries[e as usize];
        let p = self.pos(e);
        let excluded = [
            entry.vertex,
            self.entries[entry.prev as usize].vertex,
            self.entries[entry.next as usize].vertex,
        ];
        let r2 = self.delta * self.delta;
        let mut best: Option<(f32, u32)> = None;
        for c in cells_around(p, self.delta) {
            let Some(list) = self.entry_grid.get_mut(&c) else { continue };
            list.retain(|&x| self.entries[x as usize].alive);
            for &x in list.iter() {
                let other = self.entries[x as usize];
                let q = self.positions[other.vertex as usize];
                let d2 = q.distance_squared(p);
                let neighbours = [
                    other.vertex,
                    self.entries[other.prev as usize].vertex,
                    self.entries[other.next as usize].vertex,
                ];
                if d2 >= r2 || neighbours.iter().any(|v| excluded.contains(v)) {
                    continue;
                }
                if best.is_none_or(|(b, _)| d2 < b) {
                    best = Some((d2, x));
                }
            }
        }
        let (_, x) = best?;
        let q = self.pos(x);
        (self.angle_to(e, q) < entry.angle && self.angle_to(x, p) < self.entries[x as usize].angle)
            .then_some(x)
    }

    /// Splits the front of `e` and `x` along the new edge `e x`: one front
    /// runs `e … x`, the other `x' … e'` (copies of both points).
    fn split(&mut self, e: u32, x: u32) {
        self.stats.splits += 1;
        let front = self.entries[e as usize].front;
        let (pe, nx) = (self.entries[e as usize].prev, self.entries[x as usize].next);
        let new_front = self.front_sizes.len() as u32;
        self.front_sizes.push(0);
        let e2 = self.add_entry(self.entries[e as usize].vertex, new_front);
        let x2 = self.add_entry(self.entries[x as usize].vertex, new_front);
        self.link(x, e);
        self.link(x2, nx);
        self.link(pe, e2);
        self.link(e2, x2);
        // Relabel the second front (x2 … pe, e2).
        let mut size = 0;
        let mut k = x2;
        loop {
            self.entries[k as usize].front = new_front;
            size += 1;
            k = self.entries[k as usize].next;
            if k == x2 {
                break;
            }
        }
        self.front_sizes[new_front as usize] = size;
        self.front_sizes[front as usize] = self.front_sizes[front as usize] + 2 - size;
        for k in [e, x, e2, x2] {
            self.update(k);
        }
    }

    /// Merges the front of `x` into that of `e` across the new edge `e x`:
    /// `… e, x, …(x's front)…, x', e', …`.
    fn merge(&mut self, e: u32, x: u32) {
        self.stats.merges += 1;
        let (front, gone) = (self.entries[e as usize].front, self.entries[x as usize].front);
        let (ne, px) = (self.entries[e as usize].next, self.entries[x as usize].prev);
        let e2 = self.add_entry(self.entries[e as usize].vertex, front);
        let x2 = self.add_entry(self.entries[x as usize].vertex, front);
        self.link(e, x);
        self.link(px, x2);
        self.link(x2, e2);
        self.link(e2, ne);
        let mut k = x;
        while k != x2 {
            self.entries[k as usize].front = front;
            k = self.entries[k as usize].next;
        }
        self.front_sizes[front as usize] += self.front_sizes[gone as usize] + 2;
        self.front_sizes[gone as usize] = 0;
        for k in [e, x, e2, x2] {
            self.update(k);
        }
    }

    /// §3.2: expands the front at `e` by `n_t` triangles.
    fn expand(&mut self, e: u32) -> Result<(), MorphError> {
        let Entry { vertex, prev, next, angle, front, .. } = self.entries[e as usize];
        let (p, a, b) = (self.pos(e), self.pos(prev), self.pos(next));
        let delta = self.delta;
        let mut nt = (3.0 * angle / PI) as usize + 1;
        let mut dw = angle / nt as f32;
        if dw < 0.8 && nt > 1 {
            nt -= 1;
            dw = angle / nt as f32;
        }
        if nt == 1 && dw > 0.8 && a.distance(b) > 1.25 * delta {
            nt = 2;
            dw = angle / 2.0;
        }
        if angle < 3.0 && (p.distance(a) <= 0.5 * delta || p.distance(b) <= 0.5 * delta) {
            nt = 1;
        }
        let (va, vb) = (self.entries[prev as usize].vertex, self.entries[next as usize].vertex);
        if nt == 1 {
            self.add_triangle([vertex, va, vb])?;
            self.kill(e);
            self.link(prev, next);
            self.update(prev);
            self.update(next);
            return Ok(());
        }
        let n = self.normals[vertex as usize];
        let u = self.tangent(e, a).normalize_or_zero();
        let w = n.cross(u);
        let mut new_points = Vec::with_capacity(nt - 1);
        for k in 1..nt {
            let phi = k as f32 * dw;
            match self.surface_point(p + delta * (u * phi.cos() + w * phi.sin())) {
                Some(point) => new_points.push(point),
                None => {
                    // Not smooth here: leave the front point unexpanded.
                    self.stats.stopped += 1;
                    return Ok(());
                }
            }
        }
        let mut fan = vec![va];
        let mut chain = vec![prev];
        for (q, m) in new_points {
            let v = self.add_vertex(q, m);
            fan.push(v);
            chain.push(self.add_entry(v, front));
        }
        fan.push(vb);
        chain.push(next);
        for pair in fan.windows(2) {
            self.add_triangle([vertex, pair[0], pair[1]])?;
        }
        self.kill(e);
        self.front_sizes[front as usize] += nt - 1;
        for pair in chain.windows(2) {
            self.link(pair[0], pair[1]);
        }
        for k in chain {
            self.update(k);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::marching_cubes::polygonize;
    use crate::{Shape, models};

    fn check_closed_on_surface(field: &dyn Field3, mesh: &TriMesh, delta: f32) {
        let stats = mesh.edge_stats();
        assert_eq!(stats.boundary_edges, 0, "{stats:?}");
        assert_eq!(stats.nonmanifold_edges, 0, "{stats:?}");
        assert_eq!(stats.misoriented_edges, 0, "{stats:?}");
        let worst = mesh.positions.iter().map(|&p| field.value(p).abs()).fold(0.0, f32::max);
        assert!(worst < 1e-3 * delta, "a vertex is {worst} off the surface");
    }

    #[test]
    fn sphere_is_closed_genus_0_and_far_better_shaped_than_marching_cubes() {
        let ball = Shape::sphere(0.5);
        let delta = 0.05;
        let settings = TriangulationSettings { edge: delta, ..Default::default() };
        let (mesh, stats) = marching_triangulation(&ball, &Aabb::cube(0.7), 0.0, &settings).unwrap();
        check_closed_on_surface(&ball, &mesh, delta);
        assert_eq!(mesh.genus(), Some(0));
        assert_eq!(stats.seeds, 1);
        assert!(mesh.signed_volume() > 0.0, "outward");
        let q = triangle_quality(&mesh).unwrap();
        let mc = triangle_quality(&polygonize(&ball, &Aabb::cube(0.7), 40, 0.0).unwrap()).unwrap();
        assert!((q.mean_edge - f64::from(delta)).abs() < 0.15 * f64::from(delta), "{q:?}");
        assert!(q.mean_min_angle > 45.0 && q.edge_spread < 0.2, "{q:?}");
        assert!(
            q.min_angle > 3.0 * mc.min_angle && q.mean_min_angle > mc.mean_min_angle + 10.0,
            "{q:?} {mc:?}"
        );
        assert!(q.edge_spread < 0.5 * mc.edge_spread, "{q:?} {mc:?}");
    }

    #[test]
    fn torus_and_two_balls_keep_their_topology() {
        let torus = models::torus();
        let delta = 0.03;
        let settings = TriangulationSettings { edge: delta, ..Default::default() };
        let (mesh, _) = marching_triangulation(&torus, &Aabb::cube(1.0), 0.0, &settings).unwrap();
        check_closed_on_surface(&torus, &mesh, delta);
        assert_eq!(mesh.genus(), Some(1));
        assert_eq!(mesh.connected_components(), 1);
        let balls =
            Shape::sphere(0.3).translated(Vec3::X * -0.5).union(Shape::sphere(0.2).translated(Vec3::X * 0.5));
        let (mesh, stats) = marching_triangulation(&balls, &Aabb::cube(1.0), 0.0, &settings).unwrap();
        check_closed_on_surface(&balls, &mesh, delta);
        assert_eq!((mesh.connected_components(), stats.seeds), (2, 2));
        assert!(
            marching_triangulation(
                &balls,
                &Aabb::cube(1.0),
                0.0,
                &TriangulationSettings { edge: 0.0, ..settings }
            )
            .is_err()
        );
    }
}
