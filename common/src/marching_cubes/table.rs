//! The 256-case triangle table, generated from the per-face rule.
//!
//! Cube corner `c` sits at `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`; case bit
//! `c` is set when corner `c` is inside. Edges: `0..4` run along x at
//! `(y, z) = (e & 1, e >> 1)`, `4..8` along y at `(x, z)`, `8..12` along z at
//! `(x, y)`, with the same bit layout relative to their base.

use crate::marching_squares::square_segments;
use std::sync::LazyLock;

/// Corners of each cube face, counter-clockwise seen from outside the cube.
pub(super) const FACES: [[u8; 4]; 6] =
    [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];

/// Most triangles one case produces: 12 crossed edges give at most 12 loop
/// vertices and a fan of 10 triangles; the bound is checked at generation.
const MAX_TRIANGLES: usize = 12;

/// Triangles (as cube edge numbers) of one corner configuration.
#[derive(Debug, Clone, Copy)]
pub(super) struct Case {
    /// Number of valid entries in `triangles`.
    pub count: u8,
    /// Triangles, counter-clockwise seen from outside the solid.
    pub triangles: [[u8; 3]; MAX_TRIANGLES],
}

/// The edge joining corners `a` and `b` (which differ in one bit).
pub(super) const fn edge_between(a: u8, b: u8) -> u8 {
    let lo = if a < b { a } else { b };
    let (x, y, z) = (lo & 1, (lo >> 1) & 1, (lo >> 2) & 1);
    match a ^ b {
        1 => y | (z << 1),
        2 => 4 + (x | (z << 1)),
        _ => 8 + (x | (y << 1)),
    }
}

/// True when cube edge `e` lies on face `f`.
pub(super) fn edge_on_face(e: u8, f: usize) -> bool {
    (0..4).any(|k| edge_between(FACES[f][k], FACES[f][(k + 1) % 4]) == e)
}

/// The directed boundary of the surface patch in a cell: `next[e]` is the
/// edge that follows crossed edge `e` (seen from outside the cube the
/// segments keep the inside corners on their left), `u8::MAX` elsewhere.
pub(super) fn boundary_successors(case: u8) -> [u8; 12] {
    let mut next = [u8::MAX; 12];
    for face in &FACES {
        let signs = (0..4).fold(0u8, |s, k| s | ((case >> face[k]) & 1) << k);
        let (segments, count) = square_segments(signs);
        for &(from, to) in &segments[..count] {
            let (from, to) = (from as usize, to as usize);
            next[edge_between(face[from], face[(from + 1) % 4]) as usize] =
                edge_between(face[to], face[(to + 1) % 4]);
        }
    }
    next
}

/// Generates one case: chain the face segments into loops and fan each loop
/// from an apex that shares no face with a vertex it is not adjacent to, so
/// that no fan diagonal lies in a cube face (the diagonals stay private to
/// the cell and the face segments are exactly what the neighbour has).
fn generate(case: u8) -> Case {
    let next = boundary_successors(case);
    let mut out = Case { count: 0, triangles: [[0; 3]; MAX_TRIANGLES] };
    let mut seen = [false; 12];
    for start in 0..12 {
        if next[start] == u8::MAX || seen[start] {
            continue;
        }
        let mut ring = [0u8; 12];
        let mut len = 0;
        let mut e = start as u8;
        while !seen[e as usize] {
            seen[e as usize] = true;
            ring[len] = e;
            len += 1;
            e = next[e as usize];
        }
        let ring = &ring[..len];
        let shares_face = |a: u8, b: u8| (0..6).any(|f| edge_on_face(a, f) && edge_on_face(b, f));
        // Such an apex exists in all 256 cases (a test checks that no fan
        // diagonal lies in a face), so the fallback is never taken.
        let apex =
            (0..len).find(|&a| (2..len - 1).all(|d| !shares_face(ring[a], ring[(a + d) % len]))).unwrap_or(0);
        // The face segments keep the inside on their left seen from outside
        // the cube, which makes the loop clockwise seen from outside the
        // solid: fan it in reverse.
        for d in 1..len - 1 {
            let tri = [ring[apex], ring[(apex + d + 1) % len], ring[(apex + d) % len]];
            out.triangles[out.count as usize] = tri;
            out.count += 1;
        }
    }
    out
}

/// All 256 cases, generated on first use.
pub(super) static CASES: LazyLock<[Case; 256]> = LazyLock::new(|| std::array::from_fn(|c| generate(c as u8)));
