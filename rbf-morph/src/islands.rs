//! The lattice nodes of a sampled frame whose sign is in doubt, to be
//! confirmed by the exact sum.
//!
//! A fitted morph of real meshes has weights far above its values (`Σ|λ|`
//! ~1e7–1e8 for constraint values of order 1: boundary and normal
//! constraints close together), and the fast evaluators' far field, exact
//! only to a fraction of each cluster's field, errs there by up to ~0.1–0.6
//! (`docs/EXPERIMENTS.md`, issue 21). A node whose value is that close to
//! zero can take the wrong sign: the frame gets a speck (a tiny stray
//! component) or loses a thin neck. Making the far field that accurate
//! costs about as much as the direct sum, since the clusters' fields cancel
//! to the values only globally; but the doubtful nodes are few. The frame
//! ([`Slice3::polygonize_confirmed`](crate::Slice3)) measures the fast
//! error at [`PROBES`] nodes beside the surface ([`surface_probes`]), and
//! re-evaluates exactly every small sign island and the nodes within
//! [`BAND_SAFETY`] times that error of zero, nearest zero first, up to
//! [`EXACT_TERMS`] kernel terms ([`doubtful_nodes`]), before polygonizing.

use isomorph_common::Grid3;

/// Most nodes in an island that is confirmed by the exact sum.
pub(crate) const ISLAND_NODES: usize = 64;
/// Nodes beside the surface at which the fast error is measured.
pub(crate) const PROBES: usize = 512;
/// Factor on the largest measured error for the band of doubtful values.
pub(crate) const BAND_SAFETY: f32 = 2.0;
/// Most kernel terms (nodes × centres) a frame spends on the band's exact
/// sums: about 1.7 s of CPU (measured 8.5 ns per term; the 25,000-point
/// bunny → dragon morph's 48,571 centres: 4,100 nodes per frame).
pub(crate) const EXACT_TERMS: usize = 200_000_000;

/// Up to `count` nodes with a neighbour (along +x, +y or +z) on the other
/// side of `iso`, evenly spread over the lattice order.
pub(crate) fn surface_probes(grid: &Grid3<f32>, iso: f32, count: usize) -> Vec<usize> {
    let dims = grid.dims();
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let values = grid.data();
    let steps = [1, nx, nx * ny];
    let beside: Vec<usize> = (0..values.len())
        .filter(|&n| {
            let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
            let below = [i + 1 < nx, j + 1 < ny, k + 1 < dims.z as usize];
            (0..3).any(|d| below[d] && (values[n] > iso) != (values[n + steps[d]] > iso))
        })
        .collect();
    let stride = beside.len().div_ceil(count.max(1)).max(1);
    beside.into_iter().step_by(stride).collect()
}

/// The nodes whose sign is in doubt: every node of a [`small_islands`]
/// region of at most `max_nodes` nodes (with its neighbours), then the
/// nodes within `band` of `iso`, nearest first, up to `limit` nodes in all
/// (the islands are kept even beyond it); sorted, without repeats.
pub(crate) fn doubtful_nodes(
    grid: &Grid3<f32>,
    iso: f32,
    band: f32,
    max_nodes: usize,
    limit: usize,
) -> Vec<usize> {
    let mut nodes = small_islands(grid, iso, max_nodes);
    let values = grid.data();
    let mut near: Vec<usize> = (0..values.len()).filter(|&n| (values[n] - iso).abs() <= band).collect();
    near.sort_unstable_by(|&a, &b| {
        (values[a] - iso).abs().total_cmp(&(values[b] - iso).abs()).then(a.cmp(&b))
    });
    near.truncate(limit.saturating_sub(nodes.len()));
    nodes.extend(near);
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// The indices of the nodes of every 6-connected region of nodes on one
/// side of `iso` (`> iso` or not) with at most `max_nodes` nodes, plus the
/// regions' 6-neighbours; sorted, without repeats. Regions touching the
/// lattice's boundary count like the others.
pub(crate) fn small_islands(grid: &Grid3<f32>, iso: f32, max_nodes: usize) -> Vec<usize> {
    let dims = grid.dims();
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let values = grid.data();
    let inside = |n: usize| values[n] > iso;
    let neighbours = |n: usize, out: &mut Vec<usize>| {
        out.clear();
        let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
        if i > 0 {
            out.push(n - 1);
        }
        if i + 1 < nx {
            out.push(n + 1);
        }
        if j > 0 {
            out.push(n - nx);
        }
        if j + 1 < ny {
            out.push(n + nx);
        }
        if k > 0 {
            out.push(n - nx * ny);
        }
        if k + 1 < nz {
            out.push(n + nx * ny);
        }
    };
    let mut seen = vec![false; values.len()];
    let (mut region, mut stack, mut around, mut found) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for start in 0..values.len() {
        if seen[start] {
            continue;
        }
        let side = inside(start);
        seen[start] = true;
        region.clear();
        stack.push(start);
        // The whole region is marked seen; only the first `max_nodes + 1`
        // nodes are kept, enough to tell whether it is small.
        while let Some(n) = stack.pop() {
            if region.len() <= max_nodes {
                region.push(n);
            }
            neighbours(n, &mut around);
            for &m in &around {
                if !seen[m] && inside(m) == side {
                    seen[m] = true;
                    stack.push(m);
                }
            }
        }
        if region.len() <= max_nodes {
            for &n in &region {
                found.push(n);
                neighbours(n, &mut around);
                found.extend_from_slice(&around);
            }
        }
    }
    found.sort_unstable();
    found.dedup();
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::glam::{UVec3, Vec3};

    fn grid(values: impl Fn(u32, u32, u32) -> f32) -> Grid3<f32> {
        let dims = UVec3::new(12, 10, 8);
        let mut g = Grid3::new(dims, Vec3::ZERO, 1.0, 0.0f32).unwrap();
        for k in 0..dims.z {
            for j in 0..dims.y {
                for i in 0..dims.x {
                    *g.get_mut(i, j, k).unwrap() = values(i, j, k);
                }
            }
        }
        g
    }

    #[test]
    fn finds_a_small_island_and_its_neighbours_only() {
        // A big inside slab (x < 6) and a two-node inside speck at
        // (9..=10, 5, 4) in the outside; a one-node outside pocket in the
        // slab at (2, 2, 2).
        let g = grid(|i, j, k| {
            let speck = (9..=10).contains(&i) && j == 5 && k == 4;
            let pocket = (i, j, k) == (2, 2, 2);
            if (i < 6 && !pocket) || speck { 1.0 } else { -1.0 }
        });
        let found = small_islands(&g, 0.0, 4);
        let at = |i, j, k| g.index(i, j, k);
        // The speck's 2 nodes and their 10 distinct neighbours, the pocket
        // and its 6 neighbours.
        assert_eq!(found.len(), 2 + 10 + 1 + 6, "{found:?}");
        for n in
            [at(9, 5, 4), at(10, 5, 4), at(8, 5, 4), at(11, 5, 4), at(10, 5, 5), at(2, 2, 2), at(1, 2, 2)]
        {
            assert!(found.binary_search(&n).is_ok(), "node {:?} missing", g.node_of(n));
        }
        // Nothing of the slab or the outside far from both.
        assert!(found.binary_search(&at(0, 0, 0)).is_err());
        assert!(found.binary_search(&at(8, 0, 0)).is_err());
        // With islands of at most one node, only the pocket.
        assert_eq!(small_islands(&g, 0.0, 1).len(), 7);
    }

    #[test]
    fn a_lattice_without_islands_gives_nothing() {
        let g = grid(|i, _, _| if i < 6 { 1.0 } else { -1.0 });
        assert!(small_islands(&g, 0.0, ISLAND_NODES).is_empty());
    }

    #[test]
    fn doubtful_nodes_are_the_band_and_the_islands() {
        // A ramp in x crossing zero between i = 5 and 6, plus a speck.
        let g = grid(|i, j, k| if (i, j, k) == (10, 5, 4) { 0.5 } else { 5.5 - i as f32 });
        let probes = surface_probes(&g, 0.0, 1000);
        // Beside the surface: every node at i = 5 (the +x neighbour is
        // outside), the speck, and its -x, -y and -z neighbours.
        assert_eq!(probes.len(), 10 * 8 + 4, "{probes:?}");
        assert!(probes.iter().all(|&n| [5, 9, 10].contains(&g.node_of(n).x)));
        // Spread: every 9th of the 84.
        assert_eq!(surface_probes(&g, 0.0, 10).len(), 10);
        // Within 0.5 of zero: the planes i = 5 and 6 (80 nodes each); the
        // speck and its 6 neighbours.
        let doubtful = doubtful_nodes(&g, 0.0, 0.5, 4, usize::MAX);
        assert_eq!(doubtful.len(), 2 * 80 + 7);
        assert_eq!(doubtful_nodes(&g, 0.0, 0.4, 4, usize::MAX).len(), 7);
        // A limit keeps the islands and the nearest of the band: the speck's
        // 7 nodes and 20 of the band (all at |v| = 0.5; the first in order).
        let limited = doubtful_nodes(&g, 0.0, 0.5, 4, 27);
        assert_eq!(limited.len(), 27);
        assert_eq!(doubtful_nodes(&g, 0.0, 0.5, 4, 3).len(), 7);
    }
}
