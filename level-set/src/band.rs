//! Frame storage proportional to the surface: the values of the nodes next
//! to the zero set, and the sign of every other node run-length encoded.
//!
//! Marching cubes reads values only along edges whose ends differ in sign,
//! and both ends of such an edge are band nodes here, so a frame rebuilt
//! from a [`BandFrame`] polygonizes to exactly the surface of the grid it
//! was captured from.

use crate::stencil::{Lattice, Values};
use rayon::prelude::*;

/// Value (voxel units) given to nodes away from the zero set when a frame is
/// rebuilt; its sign is the stored one.
const FAR: f32 = 1.5;

/// One saved frame of an evolution, in `O(surface)` memory.
#[derive(Debug, Clone, PartialEq)]
pub struct BandFrame {
    /// `(node, value)` for every node with a face neighbour of the other
    /// sign; values in voxel units, positive inside.
    band: Vec<(u32, f32)>,
    /// Linear node indices at which the inside/outside state flips.
    flips: Vec<u32>,
    /// Whether node 0 is inside (`value > 0`).
    first_inside: bool,
    /// Solver iterations done when the frame was captured.
    pub iteration: usize,
    /// Evolution time when the frame was captured (the `t` of eq. 17).
    pub time: f64,
}

impl BandFrame {
    /// Captures the frame of the embedding `u` (voxel units) by a scan of
    /// the whole grid (`O(volume)`; the dense solver's capture).
    pub(crate) fn capture(u: &[f32], lattice: &Lattice, iteration: usize, time: f64) -> Self {
        let plane = lattice.dims()[0] * lattice.dims()[1];
        let band: Vec<(u32, f32)> = u
            .par_chunks(plane)
            .enumerate()
            .flat_map_iter(|(k, slab)| {
                let offset = k * plane;
                slab.iter().enumerate().filter_map(move |(i, &v)| {
                    let n = offset + i;
                    lattice.on_zero_set(u, n).then_some((n as u32, v))
                })
            })
            .collect();
        let first_inside = u.first().is_some_and(|&v| v > 0.0);
        let mut flips = Vec::new();
        let mut state = first_inside;
        for (n, &v) in u.iter().enumerate() {
            if (v > 0.0) != state {
                state = !state;
                flips.push(n as u32);
            }
        }
        Self { band, flips, first_inside, iteration, time }
    }

    /// Captures the frame of the embedding `u` (voxel units) in `O(surface)`
    /// work, knowing that every node on the zero set is in one of `near`,
    /// sorted node lists (the sparse field's layers `L−1`, `L0`, `L+1`):
    /// equal to [`Self::capture`] of the same `u`.
    ///
    /// Sign flips between consecutive nodes of a row are between face
    /// neighbours, so both are band nodes; only the flips from one row's
    /// last node to the next row's first are read from the grid (a read per
    /// row).
    pub(crate) fn capture_near(
        u: &(impl Values + ?Sized),
        lattice: &Lattice,
        near: [&[u32]; 3],
        iteration: usize,
        time: f64,
    ) -> Self {
        let on_band = |list: &[u32]| -> Vec<(u32, f32)> {
            list.par_iter()
                .filter(|&&n| lattice.on_zero_set(u, n as usize))
                .map(|&n| (n, u[n as usize]))
                .collect()
        };
        let [a, b, c] = near;
        let ((a, b), c) = rayon::join(|| rayon::join(|| on_band(a), || on_band(b)), || on_band(c));
        let by_node = |e: &(u32, f32)| e.0;
        let band = merge(&merge(&a, &b, by_node), &c, by_node);
        let inside = |n: usize| u[n] > 0.0;
        let nx = lattice.dims()[0];
        // Both scans in parallel (ordered collects keep node order).
        let within: Vec<u32> = band
            .par_iter()
            .map(|&(n, _)| n as usize)
            .filter(|&n| n % nx != 0 && inside(n) != inside(n - 1))
            .map(|n| n as u32)
            .collect();
        // Row starts `(0, j, k)` (row `r = k ny + j`) against the node
        // before, `(nx − 1, j − 1, k)` or `(nx − 1, ny − 1, k − 1)`: read by
        // coordinates.
        let [_, ny, nz] = lattice.dims();
        let inside_at = |n: usize, c: [usize; 3]| u.at(n, c) > 0.0;
        let across: Vec<u32> = (1..ny * nz)
            .into_par_iter()
            .filter(|&r| {
                let (j, k) = (r % ny, r / ny);
                let before = if j > 0 { [nx - 1, j - 1, k] } else { [nx - 1, ny - 1, k - 1] };
                inside_at(r * nx, [0, j, k]) != inside_at(r * nx - 1, before)
            })
            .map(|r| (r * nx) as u32)
            .collect();
        let flips = merge(&within, &across, |&n| n);
        let first_inside = u[0] > 0.0;
        Self { band, flips, first_inside, iteration, time }
    }

    /// Writes the rebuilt embedding (voxel units) of nodes `start .. start +
    /// out.len()` into `out`: band values exact, other nodes `±1.5` with
    /// their stored sign (a part of the grid, e.g. a plane for marching
    /// cubes without the whole grid; `O(out.len() + log(surface))`).
    pub(crate) fn fill(&self, start: usize, out: &mut [f32]) {
        let end = start + out.len();
        // The flips before `start` set the side of its first node.
        let first = self.flips.partition_point(|&f| (f as usize) <= start);
        let mut inside = self.first_inside ^ (first % 2 == 1);
        let mut from = start;
        for to in self.flips[first..].iter().map(|&f| f as usize).take_while(|&f| f < end).chain([end]) {
            out[from - start..to - start].fill(if inside { FAR } else { -FAR });
            inside = !inside;
            from = to;
        }
        let band = self.band.partition_point(|e| (e.0 as usize) < start);
        for &(n, v) in self.band[band..].iter().take_while(|e| (e.0 as usize) < end) {
            out[n as usize - start] = v;
        }
    }

    /// Number of band nodes stored.
    pub fn band_len(&self) -> usize {
        self.band.len()
    }

    /// Heap bytes held by the frame.
    pub fn stored_bytes(&self) -> usize {
        self.band.len() * std::mem::size_of::<(u32, f32)>() + self.flips.len() * 4
    }
}

/// The union of two lists sorted by `node`, holding no node in common, in
/// node order.
fn merge<T: Copy>(a: &[T], b: &[T], node: impl Fn(&T) -> u32) -> Vec<T> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if node(&a[i]) <= node(&b[j]) {
            out.push(a[i]);
            i += 1;
        } else {
            out.push(b[j]);
            j += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::glam::UVec3;

    #[test]
    fn rebuild_keeps_band_values_and_all_signs() {
        let lattice = Lattice::new(UVec3::new(9, 8, 7));
        let u: Vec<f32> = (0..lattice.len())
            .map(|n| {
                let [x, y, z] = lattice.coords(n).map(|c| c as f32);
                2.6 - ((x - 4.0).powi(2) + (y - 3.5).powi(2) + (z - 3.0).powi(2)).sqrt()
            })
            .collect();
        let frame = BandFrame::capture(&u, &lattice, 3, 0.5);
        let mut back = vec![0.0; u.len()];
        frame.fill(0, &mut back);
        assert!(frame.band_len() > 20 && frame.band_len() < u.len() / 2);
        for n in 0..u.len() {
            assert_eq!(back[n] > 0.0, u[n] > 0.0, "sign of node {n}");
            if lattice.on_zero_set(&u, n) {
                assert_eq!(back[n], u[n]);
            }
        }
    }
}
