//! Marching cubes: triangle meshes of level sets of 3D scalar fields sampled
//! on a [`Grid3<f32>`].
//!
//! # Conventions
//! - A node is **inside** when `value > iso` (strictly). A value equal to
//!   `iso` counts as *outside*, and so does NaN (any comparison with NaN is
//!   false), so NaN input never panics; it just carves "outside" holes.
//! - **One vertex per crossed grid edge** (an edge whose two nodes differ in
//!   sign), shared by all cells around that edge, placed by linear
//!   interpolation of the two node values. When a non-finite value makes the
//!   interpolation undefined the vertex goes to the edge midpoint; positions
//!   are always finite.
//! - Triangles are **counter-clockwise seen from outside** the solid: their
//!   right-hand normal points towards decreasing values.
//!
//! # Ambiguity rule and watertightness
//! The 256-case table is generated (once, on first use) from a rule on cube
//! *faces*: on every face, each maximal run of inside corners is cut off by
//! one segment, so an ambiguous face (two diagonally opposite inside corners)
//! always **separates the inside corners**. The rule is the one marching
//! squares uses ([`crate::marching_squares`]) and depends only on the four
//! corner signs of the face, so the two cells sharing a face draw the same
//! segments on it, in opposite directions. Each cell chains its face
//! segments into loops and fans every loop from an apex chosen so that no
//! fan diagonal lies in a cube face. Hence every mesh edge is either a face
//! segment (used once by each of the two cells on that face) or a diagonal
//! private to one cell (used by two triangles of its fan): when the level set
//! does not reach the grid border, the output is **closed** (every edge in
//! exactly two triangles, once in each direction) and **2-manifold**. The
//! exhaustive tests check this for all 256 cases and all 4096 configurations
//! of two face-adjacent cells.
//!
//! The rule looks at signs only (no asymptotic decider), so on ambiguous
//! faces and cells the topology may differ from that of the trilinear
//! interpolant; it is always consistent between neighbours, which is what
//! watertightness needs.
//!
//! # Degenerate input
//! Where the level set passes exactly through nodes (values equal to `iso`),
//! vertices of different edges may coincide and triangles may have zero
//! area. The connectivity is unaffected: the edge counts above still hold.
//!
//! # Grid border
//! Cells only exist between nodes, so a level set that reaches the border
//! of the grid produces an **open** surface there. Pad the grid with outside
//! values (or sample a box with a margin) for a closed mesh.
//!
//! # Cost
//! Linear in the number of nodes with a small constant: node signs are packed
//! into 64-bit row masks, so empty and full cells are skipped 64 at a time,
//! and vertex indices live in per-slab 2D arrays (no hashing). Work is split
//! into z-slabs of a fixed thickness processed in parallel with rayon; a
//! slab refers to the vertices of the plane it shares with the next slab by
//! their (deterministic) order there, so the seams carry no duplicate vertex
//! and the output is identical for any thread count. Bench:
//! `cargo bench -p isomorph-benches --bench common -- marching_cubes/torus/256`
//! (figures in `docs/EXPERIMENTS.md`).

mod sparse;
mod table;

pub use sparse::{SparseSettings, SparseStats, level_set_mesh, polygonize_near_surface};

use crate::marching_squares::crossing_parameter;
use crate::{Aabb, Field3, Grid3, GridError, TriMesh};
use glam::{UVec3, Vec3};
use rayon::prelude::*;
use std::borrow::Cow;
use table::CASES;

/// Cell layers per parallel slab (fixed so the output does not depend on the
/// number of threads).
const SLAB_LAYERS: usize = 8;

/// The triangle mesh of the level set `{value = iso}` of `grid`, oriented
/// outward (towards values below `iso`); see the [module docs](self) for the
/// inside rule, ambiguity resolution and guarantees.
///
/// A grid with fewer than two nodes along an axis has no cells and yields an
/// empty mesh. Normals are not computed (see [`TriMesh::compute_normals`]).
pub fn marching_cubes(grid: &Grid3<f32>, iso: f32) -> TriMesh {
    let plane_len = (grid.dims().x * grid.dims().y) as usize;
    let data = grid.data();
    marching_cubes_planes(grid.dims(), grid.origin(), grid.spacing(), iso, |k| {
        Cow::Borrowed(&data[k * plane_len..(k + 1) * plane_len])
    })
}

/// [`marching_cubes`] of the grid of `dims` nodes at `origin` with
/// `spacing` whose node plane `k` (the `dims.x · dims.y` values of
/// `z = k`, x-fastest) is `plane(k)`: the same mesh as [`marching_cubes`]
/// of the whole grid, while only a few planes per worker thread exist at a
/// time (memory ∝ a plane, not the volume; for grids stored sparsely, e.g.
/// a level set's band, rebuilt plane by plane).
///
/// # Panics
/// If a plane does not hold `dims.x · dims.y` values.
pub fn marching_cubes_planes<'a>(
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
    iso: f32,
    plane: impl Fn(usize) -> Cow<'a, [f32]> + Sync,
) -> TriMesh {
    if dims.min_element() < 2 {
        return TriMesh::default();
    }
    let layers = dims.z as usize - 1;
    let cases = &*CASES;
    let lattice = (origin, spacing);
    let slabs: Vec<SlabMesh> = (0..layers.div_ceil(SLAB_LAYERS))
        .into_par_iter()
        .map_init(
            || Scratch::new(dims.x as usize, dims.y as usize),
            |scratch, s| {
                let k0 = s * SLAB_LAYERS;
                let k1 = (k0 + SLAB_LAYERS).min(layers);
                scratch.run(&plane, lattice, iso, cases, k0, k1, k1 == layers)
            },
        )
        .collect();
    concatenate(slabs)
}

/// Samples `field` over `bounds` with `res` nodes along the longest edge
/// ([`Grid3::sample_box`]) and polygonizes its level set `iso` with
/// [`marching_cubes`].
///
/// The surface is open where the level set crosses the sampled box; use
/// bounds with a margin around the shape for a closed mesh.
///
/// # Errors
/// As [`Grid3::sample_box`]: [`GridError::TooSmall`] for `res < 2`,
/// [`GridError::InvalidGeometry`] for an empty or non-finite box,
/// [`GridError::TooLarge`] / [`GridError::OutOfMemory`] when the grid does
/// not fit.
pub fn polygonize<F: Field3 + ?Sized>(
    field: &F,
    bounds: &Aabb,
    res: u32,
    iso: f32,
) -> Result<TriMesh, GridError> {
    let grid = Grid3::sample_box(field, bounds, res)?;
    Ok(marching_cubes(&grid, iso))
}

/// The output of one slab: its own vertices, and triangles whose indices at
/// or above `own` refer to the next slab's first vertices.
struct SlabMesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    own: u32,
}

/// Joins slab meshes, resolving references to the next slab's vertices.
fn concatenate(slabs: Vec<SlabMesh>) -> TriMesh {
    let mut offsets = Vec::with_capacity(slabs.len() + 1);
    let mut total = 0u32;
    for s in &slabs {
        offsets.push(total);
        total += s.own;
    }
    offsets.push(total);
    let tri_total = slabs.iter().map(|s| s.triangles.len()).sum();
    let mut positions = Vec::with_capacity(total as usize);
    let mut triangles = Vec::with_capacity(tri_total);
    for (s, slab) in slabs.iter().enumerate() {
        positions.extend_from_slice(&slab.positions);
        let (own, base, next) = (slab.own, offsets[s], offsets[s + 1]);
        triangles.extend(
            slab.triangles.iter().map(|t| t.map(|v| if v < own { base + v } else { next + (v - own) })),
        );
    }
    TriMesh { positions, triangles, normals: None, colors: None }
}

/// Per-slab working memory, reused across the slabs one worker processes.
/// Index arrays are only read where the matching edge is crossed, which is
/// exactly where they were written for the current planes, so they are
/// never cleared.
struct Scratch {
    nx: usize,
    ny: usize,
    /// 64-bit words per row of sign bits.
    words: usize,
    /// Sign bits (inside = 1) of two node planes, by plane parity.
    signs: [Vec<u64>; 2],
    /// Vertex index of the x-edge starting at node `(i, j)`, by plane parity.
    x_vertex: [Vec<u32>; 2],
    /// Vertex index of the y-edge starting at node `(i, j)`, by plane parity.
    y_vertex: [Vec<u32>; 2],
    /// Vertex index of the z-edge from node `(i, j, k)` to `(i, j, k + 1)`.
    z_vertex: Vec<u32>,
}

impl Scratch {
    fn new(nx: usize, ny: usize) -> Self {
        let words = nx.div_ceil(64);
        Self {
            nx,
            ny,
            words,
            signs: [vec![0; words * ny], vec![0; words * ny]],
            x_vertex: [vec![0; nx * ny], vec![0; nx * ny]],
            y_vertex: [vec![0; nx * ny], vec![0; nx * ny]],
            z_vertex: vec![0; nx * ny],
        }
    }

    /// Polygonizes cell layers `k0..k1`. Vertices are numbered in a fixed
    /// order: plane `k0`, then per layer its z-edges and the next plane, so
    /// the vertices of plane `k1` are the first ones of the next slab.
    #[allow(clippy::too_many_arguments)]
    fn run<'a>(
        &mut self,
        plane: &(impl Fn(usize) -> Cow<'a, [f32]> + Sync),
        lattice: (Vec3, f32),
        iso: f32,
        cases: &[table::Case; 256],
        k0: usize,
        k1: usize,
        last: bool,
    ) -> SlabMesh {
        let mut out = SlabMesh { positions: Vec::new(), triangles: Vec::new(), own: 0 };
        let plane_len = self.nx * self.ny;
        let get = |k: usize| {
            let values = plane(k);
            assert_eq!(values.len(), plane_len, "marching_cubes_planes: plane {k} has the wrong length");
            values
        };
        let mut below = get(k0);
        self.compute_signs(&below, iso, k0 & 1);
        self.emit_plane_vertices(lattice, &below, iso, k0, &mut out.positions);
        for k in k0..k1 {
            let above = get(k + 1);
            self.compute_signs(&above, iso, (k + 1) & 1);
            self.emit_z_vertices(lattice, &below, &above, iso, k, &mut out.positions);
            if k + 1 == k1 && !last {
                out.own = out.positions.len() as u32;
            }
            self.emit_plane_vertices(lattice, &above, iso, k + 1, &mut out.positions);
            self.emit_triangles(cases, k, &mut out.triangles);
            below = above;
        }
        if last {
            out.own = out.positions.len() as u32;
        }
        out.positions.truncate(out.own as usize);
        out
    }

    /// Packs `value > iso` of one plane into row bit masks.
    fn compute_signs(&mut self, values: &[f32], iso: f32, slot: usize) {
        let words = self.words;
        for (row, bits) in values.chunks_exact(self.nx).zip(self.signs[slot].chunks_exact_mut(words)) {
            for (chunk, word) in row.chunks(64).zip(bits.iter_mut()) {
                // Bytes first: this shape vectorizes well (about 1.6× faster).
                *word = chunk.chunks(8).enumerate().fold(0u64, |w, (k, eight)| {
                    let byte = eight.iter().enumerate().fold(0u8, |b, (n, &v)| b | (((v > iso) as u8) << n));
                    w | ((byte as u64) << (8 * k))
                });
            }
        }
    }

    /// Creates the vertices of the crossed x- and y-edges of plane `k`.
    fn emit_plane_vertices(
        &mut self,
        (origin, h): (Vec3, f32),
        values: &[f32],
        iso: f32,
        k: usize,
        positions: &mut Vec<Vec3>,
    ) {
        let (nx, ny, words) = (self.nx, self.ny, self.words);
        let signs = &self.signs[k & 1];
        let (x_vertex, y_vertex) = (&mut self.x_vertex[k & 1], &mut self.y_vertex[k & 1]);
        for j in 0..ny {
            let row = &signs[j * words..(j + 1) * words];
            let base = origin + h * Vec3::new(0.0, j as f32, k as f32);
            for w in 0..words {
                // x-edge i crosses when bits i and i + 1 differ (i < nx - 1).
                let mut crossed = (row[w] ^ shifted(row, w)) & cell_mask(nx, w);
                while crossed != 0 {
                    let i = w * 64 + crossed.trailing_zeros() as usize;
                    crossed &= crossed - 1;
                    let n = j * nx + i;
                    let t = crossing_parameter(values[n], values[n + 1], iso);
                    x_vertex[n] = positions.len() as u32;
                    positions.push(base + Vec3::new(h * (i as f32 + t), 0.0, 0.0));
                }
            }
            if j + 1 < ny {
                let up = &signs[(j + 1) * words..(j + 2) * words];
                for w in 0..words {
                    let mut crossed = row[w] ^ up[w];
                    while crossed != 0 {
                        let i = w * 64 + crossed.trailing_zeros() as usize;
                        crossed &= crossed - 1;
                        let n = j * nx + i;
                        let t = crossing_parameter(values[n], values[n + nx], iso);
                        y_vertex[n] = positions.len() as u32;
                        positions.push(base + Vec3::new(h * i as f32, h * t, 0.0));
                    }
                }
            }
        }
    }

    /// Creates the vertices of the crossed z-edges between planes `k` and `k + 1`.
    fn emit_z_vertices(
        &mut self,
        (origin, h): (Vec3, f32),
        below: &[f32],
        above: &[f32],
        iso: f32,
        k: usize,
        positions: &mut Vec<Vec3>,
    ) {
        let (nx, words) = (self.nx, self.words);
        let (lo, hi) = (&self.signs[k & 1], &self.signs[(k + 1) & 1]);
        for j in 0..self.ny {
            let base = origin + h * Vec3::new(0.0, j as f32, k as f32);
            for w in 0..words {
                let mut crossed = lo[j * words + w] ^ hi[j * words + w];
                while crossed != 0 {
                    let i = w * 64 + crossed.trailing_zeros() as usize;
                    crossed &= crossed - 1;
                    let n = j * nx + i;
                    let t = crossing_parameter(below[n], above[n], iso);
                    self.z_vertex[n] = positions.len() as u32;
                    positions.push(base + Vec3::new(h * i as f32, 0.0, h * t));
                }
            }
        }
    }

    /// Emits the triangles of the mixed cells of layer `k`.
    fn emit_triangles(&self, cases: &[table::Case; 256], k: usize, triangles: &mut Vec<[u32; 3]>) {
        let (nx, words) = (self.nx, self.words);
        let (lo, hi) = (&self.signs[k & 1], &self.signs[(k + 1) & 1]);
        let (x_vertex, y_vertex) = (&self.x_vertex, &self.y_vertex);
        for j in 0..self.ny - 1 {
            let rows = [
                &lo[j * words..(j + 1) * words],
                &lo[(j + 1) * words..(j + 2) * words],
                &hi[j * words..(j + 1) * words],
                &hi[(j + 1) * words..(j + 2) * words],
            ];
            for w in 0..words {
                let all = rows.iter().fold(!0u64, |a, r| a & r[w]);
                let any = rows.iter().fold(0u64, |a, r| a | r[w]);
                let all_next = rows.iter().fold(!0u64, |a, r| a & r.get(w + 1).copied().unwrap_or(0));
                let any_next = rows.iter().fold(0u64, |a, r| a | r.get(w + 1).copied().unwrap_or(0));
                let full = all & ((all >> 1) | (all_next << 63));
                let empty = !any & !((any >> 1) | (any_next << 63));
                let mut mixed = !(full | empty) & cell_mask(nx, w);
                while mixed != 0 {
                    let i = w * 64 + mixed.trailing_zeros() as usize;
                    mixed &= mixed - 1;
                    let case = rows.iter().enumerate().fold(0usize, |c, (r, row)| {
                        c | (bit(row, i) << (2 * r)) | (bit(row, i + 1) << (2 * r + 1))
                    });
                    let vertex = |e: u8| -> u32 {
                        let (a, b) = ((e & 1) as usize, ((e >> 1) & 1) as usize);
                        match e {
                            0..4 => x_vertex[(k + b) & 1][(j + a) * nx + i],
                            4..8 => y_vertex[(k + b) & 1][j * nx + i + a],
                            _ => self.z_vertex[(j + b) * nx + i + a],
                        }
                    };
                    let c = &cases[case];
                    triangles.extend(c.triangles[..c.count as usize].iter().map(|t| t.map(vertex)));
                }
            }
        }
    }
}

/// Bit `i` of a row mask.
#[inline]
fn bit(row: &[u64], i: usize) -> usize {
    ((row[i / 64] >> (i % 64)) & 1) as usize
}

/// Word `w` of a row mask shifted down by one bit (bit `i` holds bit `i + 1`).
#[inline]
fn shifted(row: &[u64], w: usize) -> u64 {
    (row[w] >> 1) | (row.get(w + 1).copied().unwrap_or(0) << 63)
}

/// Mask of the bits of word `w` that are cells or x-edges, i.e. `i < nx - 1`.
#[inline]
fn cell_mask(nx: usize, w: usize) -> u64 {
    let valid = (nx - 1).saturating_sub(w * 64);
    if valid >= 64 { !0 } else { (1u64 << valid) - 1 }
}

#[cfg(test)]
mod tests;
