//! Marching squares: contour lines of a 2D scalar field sampled on a
//! [`Grid2<f32>`].
//!
//! # Conventions
//! - A node is **inside** when `value > iso` (strictly); a value equal to
//!   `iso` and NaN count as *outside*. A contour vertex therefore never sits
//!   on an inside node, but may sit exactly on an outside node whose value
//!   equals `iso` (zero-length segments are possible and harmless).
//! - One vertex per grid edge whose two nodes differ in sign, placed by linear
//!   interpolation of the values along the edge (midpoint when a non-finite
//!   value makes the interpolation undefined).
//! - Contours are oriented **counter-clockwise around inside regions**: walking
//!   along a polyline, the inside lies on the left (in the grid's x-right,
//!   y-up frame). Outer boundaries therefore have positive signed area and
//!   boundaries of holes negative.
//!
//! # Ambiguity rule
//! A saddle square (two diagonally opposite inside corners) always
//! **separates the inside corners**: each inside corner gets its own segment.
//! The rule depends only on the four corner signs, and it is the very same
//! rule (`square_segments`) that marching cubes applies to every cube face,
//! so 2D slices and 3D surfaces resolve saddles alike.
//!
//! # Output
//! Segments are joined into maximal polylines. A contour that closes on
//! itself is reported with `closed = true` and its first point *not* repeated
//! at the end; a contour that reaches the grid border is an open polyline
//! running from border to border. Cost is linear in the number of nodes.

use crate::Grid2;
use glam::Vec2;

/// One contour line: a sequence of points in world units.
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline2 {
    /// The vertices in order (inside on the left when walking along them).
    pub points: Vec<Vec2>,
    /// True for a closed loop (the last point joins the first, which is not
    /// repeated); false for a contour that ends on the grid border.
    pub closed: bool,
}

impl Polyline2 {
    /// Length of the polyline (including the closing segment of a loop).
    pub fn length(&self) -> f32 {
        let open: f32 = self.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        match (self.closed, self.points.first(), self.points.last()) {
            (true, Some(a), Some(b)) => open + a.distance(*b),
            _ => open,
        }
    }

    /// Signed area enclosed by a closed loop (shoelace formula): positive for
    /// a counter-clockwise loop, i.e. an outer boundary of an inside region.
    /// An open polyline is closed by its chord for this computation.
    pub fn signed_area(&self) -> f32 {
        let n = self.points.len();
        (0..n).map(|i| self.points[i].perp_dot(self.points[(i + 1) % n])).sum::<f32>() * 0.5
    }
}

/// The contour segments inside one square.
///
/// `inside` holds the corner signs, bit `k` for corner `k`, corners numbered
/// counter-clockwise (seen from the side the result is oriented for); edge `k`
/// joins corner `k` and corner `(k + 1) % 4`. Returns up to two segments
/// `(from_edge, to_edge)` and their count, directed so that the inside lies on
/// the left.
///
/// Every maximal run of consecutive inside corners yields one segment from
/// the edge where the run ends (inside → outside, counter-clockwise) back to
/// the edge where it starts (outside → inside). On a saddle square each
/// inside corner is a run of its own, so the inside corners are separated.
pub(crate) fn square_segments(inside: u8) -> ([(u8, u8); 2], usize) {
    let is_in = |k: usize| (inside >> (k % 4)) & 1 == 1;
    let mut segments = [(0, 0); 2];
    let mut count = 0;
    for exit in 0..4 {
        if is_in(exit) && !is_in(exit + 1) {
            // Walk back over the run of inside corners ending at corner `exit`.
            let mut start = exit;
            while is_in(start + 3) {
                start = (start + 3) % 4;
            }
            segments[count] = (exit as u8, ((start + 3) % 4) as u8);
            count += 1;
        }
    }
    (segments, count)
}

/// Contours of `grid` at level `iso` (see the [module docs](self) for the
/// inside rule, orientation and saddle resolution).
///
/// Polylines come in a deterministic order: first the open ones (in order of
/// their starting edge), then the closed loops. A grid with fewer than two
/// nodes along an axis has no cells and yields no contour.
pub fn marching_squares(grid: &Grid2<f32>, iso: f32) -> Vec<Polyline2> {
    let (nx, ny) = (grid.dims().x as usize, grid.dims().y as usize);
    if nx < 2 || ny < 2 {
        return Vec::new();
    }
    let data = grid.data();
    let inside = |i: usize, j: usize| data[i + nx * j] > iso;
    // Vertex ids: x-edge (i, j) ↦ i + nx·j, y-edge (i, j) ↦ nx·ny + i + nx·j.
    let y_base = nx * ny;
    let point = |id: usize| -> Vec2 {
        let (along_x, local) = if id < y_base { (true, id) } else { (false, id - y_base) };
        let (i, j) = (local % nx, local / nx);
        let (di, dj) = if along_x { (1, 0) } else { (0, 1) };
        let t = crossing_parameter(data[i + nx * j], data[i + di + nx * (j + dj)], iso);
        let base = Vec2::new(i as f32, j as f32);
        let offset = if along_x { Vec2::new(t, 0.0) } else { Vec2::new(0.0, t) };
        grid.origin() + grid.spacing() * (base + offset)
    };
    const NONE: usize = usize::MAX;
    let mut next = vec![NONE; 2 * nx * ny];
    let mut has_prev = vec![false; 2 * nx * ny];
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let signs = corners.iter().enumerate().fold(0u8, |s, (k, &(a, b))| s | (inside(a, b) as u8) << k);
            let edge_id = |e: u8| match e {
                0 => i + nx * j,
                1 => y_base + (i + 1) + nx * j,
                2 => i + nx * (j + 1),
                _ => y_base + i + nx * j,
            };
            let (segments, count) = square_segments(signs);
            for &(from, to) in &segments[..count] {
                let (a, b) = (edge_id(from), edge_id(to));
                next[a] = b;
                has_prev[b] = true;
            }
        }
    }
    let mut visited = vec![false; 2 * nx * ny];
    let mut lines = Vec::new();
    let mut trace = |start: usize, closed: bool, visited: &mut [bool]| {
        let mut points = Vec::new();
        let mut v = start;
        loop {
            visited[v] = true;
            points.push(point(v));
            v = next[v];
            if v == NONE || v == start {
                break;
            }
        }
        lines.push(Polyline2 { points, closed });
    };
    for start in 0..next.len() {
        if next[start] != NONE && !has_prev[start] {
            trace(start, false, &mut visited);
        }
    }
    for start in 0..next.len() {
        if next[start] != NONE && !visited[start] {
            trace(start, true, &mut visited);
        }
    }
    lines
}

/// Where the level `iso` crosses an edge from value `a` to value `b` with
/// exactly one of them inside: the fraction of the way from `a` to `b`, in
/// `[0, 1]`; `0.5` when a non-finite value leaves it undefined.
#[inline]
pub(crate) fn crossing_parameter(a: f32, b: f32, iso: f32) -> f32 {
    let t = (iso - a) / (b - a);
    if t.is_nan() { 0.5 } else { t.clamp(0.0, 1.0) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::UVec2;
    use std::f32::consts::PI;

    fn sample(n: u32, origin: Vec2, h: f32, f: impl Fn(Vec2) -> f32) -> Grid2<f32> {
        let mut data = Vec::new();
        for j in 0..n {
            for i in 0..n {
                data.push(f(origin + h * Vec2::new(i as f32, j as f32)));
            }
        }
        Grid2::from_vec(UVec2::splat(n), origin, h, data).unwrap()
    }

    #[test]
    fn square_rule_separates_saddle_corners_and_keeps_inside_left() {
        // One inside corner 0: from edge 0 (leaving it) to edge 3 (entering it).
        assert_eq!(square_segments(0b0001), ([(0, 3), (0, 0)], 1));
        // Saddle 0 & 2: each corner gets its own segment.
        let (s, n) = square_segments(0b0101);
        assert_eq!((n, s), (2, [(0, 3), (2, 1)]));
        assert_eq!(square_segments(0b0000).1, 0);
        assert_eq!(square_segments(0b1111).1, 0);
        // Every edge with a sign change is used exactly once as start or end.
        for case in 0u8..16 {
            let (s, n) = square_segments(case);
            let mut uses = [0; 4];
            for &(a, b) in &s[..n] {
                uses[a as usize] += 1;
                uses[b as usize] += 1;
            }
            for (e, &u) in uses.iter().enumerate() {
                let crossing = ((case >> e) ^ (case >> ((e + 1) % 4))) & 1 == 1;
                assert_eq!(u, crossing as i32, "case {case:04b} edge {e}");
            }
        }
    }

    #[test]
    fn circle_is_one_counter_clockwise_loop() {
        let r = 0.7;
        let g = sample(65, Vec2::splat(-1.0), 2.0 / 64.0, |p| r - p.length());
        let lines = marching_squares(&g, 0.0);
        assert_eq!(lines.len(), 1);
        let l = &lines[0];
        assert!(l.closed);
        let len = l.length();
        assert!((len - 2.0 * PI * r).abs() < 0.01 * 2.0 * PI * r, "length {len}");
        let area = l.signed_area();
        assert!((area - PI * r * r).abs() < 0.01 * PI * r * r, "area {area}");
        for p in &l.points {
            assert!((p.length() - r).abs() < 1e-3, "point {p} off the circle");
        }
    }

    #[test]
    fn annulus_has_two_loops_of_opposite_orientation() {
        let g = sample(81, Vec2::splat(-1.0), 2.0 / 80.0, |p| 0.2 - (p.length() - 0.6).abs());
        let lines = marching_squares(&g, 0.0);
        assert_eq!(lines.len(), 2);
        let mut areas: Vec<f32> = lines.iter().map(|l| l.signed_area()).collect();
        assert!(lines.iter().all(|l| l.closed));
        areas.sort_by(f32::total_cmp);
        assert!((areas[0] + PI * 0.16).abs() < 0.02, "hole {areas:?}");
        assert!((areas[1] - PI * 0.64).abs() < 0.02, "outer {areas:?}");
    }

    #[test]
    fn contours_touching_the_border_are_open() {
        // Half-plane x < 0.3 inside, plus a disc fully inside the grid.
        let g = sample(41, Vec2::splat(-1.0), 0.05, |p| {
            (0.3 - p.x).max(0.2 - (p - Vec2::new(0.6, 0.0)).length())
        });
        let lines = marching_squares(&g, 0.0);
        let open: Vec<_> = lines.iter().filter(|l| !l.closed).collect();
        assert_eq!((lines.len(), open.len()), (2, 1));
        let line = open[0];
        let (a, b) = (line.points[0], *line.points.last().unwrap());
        // Inside (x < 0.3) on the left: the line runs upward (towards +y).
        assert!((a.y + 1.0).abs() < 1e-5 && (b.y - 1.0).abs() < 1e-5, "{a} -> {b}");
        assert!(line.points.iter().all(|p| (p.x - 0.3).abs() < 1e-5));
    }

    #[test]
    fn saddle_separates_inside_corners_and_nan_is_outside() {
        let data = vec![1.0, -1.0, -1.0, 1.0];
        let g = Grid2::from_vec(UVec2::splat(2), Vec2::ZERO, 1.0, data).unwrap();
        let lines = marching_squares(&g, 0.0);
        assert_eq!(lines.len(), 2);
        assert!(lines.iter().all(|l| !l.closed && l.points.len() == 2));
        let nan =
            Grid2::from_vec(UVec2::splat(2), Vec2::ZERO, 1.0, vec![1.0, f32::NAN, f32::NAN, 1.0]).unwrap();
        let lines = marching_squares(&nan, 0.0);
        assert_eq!(lines.len(), 2);
        assert!(lines.iter().flat_map(|l| &l.points).all(|p| p.is_finite()));
    }
}
