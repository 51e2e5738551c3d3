//! Visibility: near clipping, projection and z-buffered triangle
//! rasterization into a buffer of [`Fragment`]s (which triangle is nearest
//! at each sample, and how far away).
//!
//! Coverage uses edge functions over each triangle's bounding box with the
//! top-left fill rule, sampled at pixel centres. Every edge is evaluated in
//! one canonical vertex order whichever triangle it belongs to, so the two
//! triangles sharing an edge see exactly opposite values: no sample on a
//! shared edge is drawn twice or missed. The depth test keeps the largest
//! `1 / depth` and breaks exact ties by triangle order, so the result does
//! not depend on the thread count.

use super::camera::{Camera, ViewBasis};
use glam::{Vec2, Vec3};
use isomorph_common::TriMesh;
use rayon::prelude::*;

/// Image rows per band; bands are rasterized in parallel.
const BAND_ROWS: usize = 16;
/// Mesh triangles per parallel task of clipping and projection.
const SETUP_CHUNK: usize = 8192;

/// The nearest surface at one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Fragment {
    /// `1 / depth` (0 where nothing was drawn; larger is nearer).
    pub(super) inv_depth: f32,
    /// Index of the mesh triangle seen here (`u32::MAX` for none).
    pub(super) triangle: u32,
}

impl Fragment {
    /// A sample where nothing is drawn.
    pub(super) const EMPTY: Fragment = Fragment { inv_depth: 0.0, triangle: u32::MAX };

    /// True when a triangle covers this sample.
    pub(super) fn is_covered(&self) -> bool {
        self.triangle != u32::MAX
    }
}

/// World → view → pixel mapping of a camera for one image size.
#[derive(Debug, Clone, Copy)]
pub(super) struct Projection {
    eye: Vec3,
    basis: ViewBasis,
    /// Pixels per unit of `lateral / depth`.
    focal: f32,
    /// Image centre in pixels.
    center: Vec2,
    /// Depth of the near clipping plane.
    near: f32,
}

impl Projection {
    /// The projection of `camera` onto a `width × height` pixel grid.
    pub(super) fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let basis = ViewBasis::new(camera.target - camera.eye, camera.up);
        let fov = if camera.fov.is_finite() { camera.fov.clamp(0.01, 3.0) } else { Camera::DEFAULT_FOV };
        let short_side = width.min(height) as f32;
        let distance = camera.eye.distance(camera.target);
        let near = if distance.is_finite() && distance > 0.0 { 1e-3 * distance } else { 1e-6 };
        Self {
            eye: camera.eye,
            basis,
            focal: 0.5 * short_side / (0.5 * fov).tan(),
            center: 0.5 * Vec2::new(width as f32, height as f32),
            near,
        }
    }

    /// The eye position.
    pub(super) fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The camera axes.
    pub(super) fn basis(&self) -> ViewBasis {
        self.basis
    }

    /// The world point at `1 / inv_depth` in front of the eye on the ray
    /// through `pixel` (fractional pixel coordinates, x right, y down).
    pub(super) fn unproject(&self, pixel: Vec2, inv_depth: f32) -> Vec3 {
        let d = (pixel - self.center) / self.focal;
        self.eye + (self.basis.forward + d.x * self.basis.right - d.y * self.basis.up) / inv_depth
    }

    /// View coordinates of a world point: right, up, depth in front of the eye.
    fn world_to_view(&self, p: Vec3) -> Vec3 {
        self.basis.coordinates(p - self.eye)
    }

    /// Coefficients `(a, b, c)` with `1 / depth = a·x + b·y + c` at pixel
    /// `(x, y)` on the plane through the view points `p`, `q`, `r`; `None`
    /// when the plane is degenerate or passes through the eye (seen edge-on).
    fn depth_plane(&self, p: Vec3, q: Vec3, r: Vec3) -> Option<Vec3> {
        // On the plane n·v = d, the ray v = t·((x − cx)/f, −(y − cy)/f, 1)
        // has 1/t = n·(…)/d; computed in f64 to keep the offset exact.
        let (p, q, r) = (p.as_dvec3(), q.as_dvec3(), r.as_dvec3());
        let n = (q - p).cross(r - p);
        let d = n.dot(p);
        let (f, c) = (f64::from(self.focal), self.center.as_dvec2());
        let (a, b) = (n.x / (f * d), -n.y / (f * d));
        let plane = glam::DVec3::new(a, b, n.z / d - a * c.x - b * c.y).as_vec3();
        (d != 0.0 && plane.is_finite()).then_some(plane)
    }

    /// Pixel position (x right, y down) of a view point in front of the eye.
    fn view_to_pixel(&self, v: Vec3) -> Vec2 {
        self.center + self.focal / v.z * Vec2::new(v.x, -v.y)
    }
}

/// A mesh vertex in view coordinates and in pixels (the latter meaningful
/// only in front of the eye).
#[derive(Debug, Clone, Copy)]
struct Vertex {
    view: Vec3,
    pixel: Vec2,
}

/// A projected triangle, counter-clockwise on screen (positive area with y
/// down), ready to rasterize.
#[derive(Debug, Clone, Copy)]
struct ScreenTriangle {
    pixel: [Vec2; 3],
    /// `1 / depth` at pixel `(x, y)` is `depth_plane · (x, y, 1)`: it is
    /// affine in screen space, and taken from the whole mesh triangle's plane
    /// so that clipping costs no precision.
    depth_plane: Vec3,
    triangle: u32,
}

/// Rasterizes `mesh` seen through `projection` into a `width × height`
/// buffer of fragments (row-major from the top-left). Triangles with an
/// out-of-range index or a non-finite corner are skipped, as are triangles
/// behind the near plane (partly visible ones are clipped) and those of zero
/// projected area.
pub(super) fn rasterize(mesh: &TriMesh, projection: &Projection, width: u32, height: u32) -> Vec<Fragment> {
    let (width, height) = (width as usize, height as usize);
    let mut fragments = vec![Fragment::EMPTY; width * height];
    if fragments.is_empty() {
        return fragments;
    }
    let vertices: Vec<Vertex> = mesh
        .positions
        .par_iter()
        .map(|&p| {
            let view = projection.world_to_view(p);
            Vertex { view, pixel: projection.view_to_pixel(view) }
        })
        .collect();
    let triangles = mesh
        .triangles
        .par_chunks(SETUP_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut out = Vec::with_capacity(chunk.len());
            for (i, tri) in chunk.iter().enumerate() {
                let t = (c * SETUP_CHUNK + i) as u32;
                out.extend(setup(&vertices, t, tri, projection, width, height).into_iter().flatten());
            }
            out
        })
        .collect::<Vec<Vec<ScreenTriangle>>>()
        .concat();

    let band_count = height.div_ceil(BAND_ROWS);
    let mut bands: Vec<Vec<u32>> = vec![Vec::new(); band_count];
    for (i, tri) in triangles.iter().enumerate() {
        let (lo, hi) = row_range(tri, height);
        if lo <= hi {
            for band in &mut bands[lo / BAND_ROWS..=hi / BAND_ROWS] {
                band.push(i as u32);
            }
        }
    }

    fragments.par_chunks_mut(width * BAND_ROWS).zip(bands.par_iter()).enumerate().for_each(
        |(b, (rows, band))| {
            let first_row = b * BAND_ROWS;
            let last_row = first_row + rows.len() / width - 1;
            for &i in band {
                draw(&triangles[i as usize], rows, width, first_row, last_row);
            }
        },
    );
    fragments
}

/// Clips mesh triangle `t` against the near plane and projects it: zero, one
/// or two screen triangles.
fn setup(
    vertices: &[Vertex],
    t: u32,
    tri: &[u32; 3],
    projection: &Projection,
    width: usize,
    height: usize,
) -> [Option<ScreenTriangle>; 2] {
    let corners = [0, 1, 2].map(|k| vertices.get(tri[k] as usize).copied());
    let [Some(u), Some(v), Some(w)] = corners else { return [None, None] };
    let (a, b, c) = (u.view, v.view, w.view);
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return [None, None];
    }
    let Some(depth_plane) = projection.depth_plane(a, b, c) else { return [None, None] };
    let near = projection.near;
    if a.z >= near && b.z >= near && c.z >= near {
        return [screen_triangle([u.pixel, v.pixel, w.pixel], depth_plane, t, width, height), None];
    }
    let input = [a, b, c];
    // Sutherland–Hodgman against depth ≥ near: a triangle becomes at most a quad.
    let mut clipped = [a; 4];
    let mut n = 0;
    for k in 0..3 {
        let (p, q) = (input[k], input[(k + 1) % 3]);
        let (p_in, q_in) = (p.z >= near, q.z >= near);
        if p_in {
            clipped[n] = p;
            n += 1;
        }
        if p_in != q_in {
            clipped[n] = p.lerp(q, (near - p.z) / (q.z - p.z));
            n += 1;
        }
    }
    let project = |k: [usize; 3]| {
        let corners = k.map(|i| projection.view_to_pixel(clipped[i]));
        screen_triangle(corners, depth_plane, t, width, height)
    };
    match n {
        3 => [project([0, 1, 2]), None],
        4 => [project([0, 1, 2]), project([0, 2, 3])],
        _ => [None, None],
    }
}

/// A projected triangle with its corners in pixels; `None` when it has no
/// area or misses the image.
fn screen_triangle(
    pixel: [Vec2; 3],
    depth_plane: Vec3,
    triangle: u32,
    width: usize,
    height: usize,
) -> Option<ScreenTriangle> {
    let mut tri = ScreenTriangle { pixel, depth_plane, triangle };
    let [p0, p1, p2] = tri.pixel;
    let area = (p1 - p0).perp_dot(p2 - p0);
    if !area.is_finite() || area == 0.0 {
        return None;
    }
    if area < 0.0 {
        tri.pixel.swap(1, 2);
    }
    let (min, max) = bounding_box(&tri);
    let on_image =
        max.x >= 0.0 && max.y >= 0.0 && min.x <= width as f32 && min.y <= height as f32 && min.is_finite();
    on_image.then_some(tri)
}

fn bounding_box(tri: &ScreenTriangle) -> (Vec2, Vec2) {
    let [a, b, c] = tri.pixel;
    (a.min(b).min(c), a.max(b).max(c))
}

/// First and last pixel row whose centre may lie in the triangle, clamped to
/// the image (first > last when none).
fn row_range(tri: &ScreenTriangle, height: usize) -> (usize, usize) {
    let (min, max) = bounding_box(tri);
    pixel_range(min.y, max.y, height)
}

/// Pixels `i` with centre `i + 0.5` in `[lo, hi]`, clamped to `0..len`.
fn pixel_range(lo: f32, hi: f32, len: usize) -> (usize, usize) {
    let first = (lo - 0.5).ceil().max(0.0) as usize;
    let last = ((hi - 0.5).floor().min(len as f32 - 1.0)).max(0.0) as usize;
    (first, last)
}

/// One triangle edge, evaluated in a canonical vertex order so that the
/// triangle on its other side sees exactly the negated value.
#[derive(Debug, Clone, Copy)]
struct Edge {
    from: Vec2,
    to: Vec2,
    /// +1 or −1: the triangle's edge runs `to → from`.
    sign: f32,
    /// Samples exactly on the edge belong to the triangle (top-left rule).
    owns_boundary: bool,
}

impl Edge {
    /// The edge `a → b` of a triangle that lies on its positive side.
    fn new(a: Vec2, b: Vec2) -> Self {
        let d = b - a;
        // With y down and the interior on the positive side, a top edge is
        // horizontal running right, a left edge runs up.
        let owns_boundary = d.y < 0.0 || (d.y == 0.0 && d.x > 0.0);
        if (a.x, a.y) <= (b.x, b.y) {
            Self { from: a, to: b, sign: 1.0, owns_boundary }
        } else {
            Self { from: b, to: a, sign: -1.0, owns_boundary }
        }
    }

    /// Twice the signed area of the triangle (edge, p): positive inside.
    #[inline]
    fn eval(&self, p: Vec2) -> f32 {
        self.sign * (self.to - self.from).perp_dot(p - self.from)
    }

    #[inline]
    fn covers(&self, value: f32) -> bool {
        value > 0.0 || (value == 0.0 && self.owns_boundary)
    }
}

/// Rasterizes one triangle into the band `rows` (image rows `first_row ..=
/// last_row`), keeping the nearest fragment per sample.
fn draw(tri: &ScreenTriangle, rows: &mut [Fragment], width: usize, first_row: usize, last_row: usize) {
    let [p0, p1, p2] = tri.pixel;
    let edges = [Edge::new(p1, p2), Edge::new(p2, p0), Edge::new(p0, p1)];
    let (min, max) = bounding_box(tri);
    let (x0, x1) = pixel_range(min.x, max.x, width);
    let (y0, y1) = pixel_range(min.y, max.y, last_row + 1);
    for y in y0.max(first_row)..=y1 {
        let row = &mut rows[(y - first_row) * width..][..width];
        for (x, fragment) in (x0..).zip(row.iter_mut().take(x1 + 1).skip(x0)) {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let e = edges.map(|edge| edge.eval(p));
            if !(edges[0].covers(e[0]) && edges[1].covers(e[1]) && edges[2].covers(e[2])) {
                continue;
            }
            let depth = tri.depth_plane.dot(p.extend(1.0));
            if depth > fragment.inv_depth {
                *fragment = Fragment { inv_depth: depth, triangle: tri.triangle };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A camera on +z looking at the origin, 2 units away, whose image spans
    /// `[-1, 1]²` at depth 2 on a `size²` pixel image.
    fn front_projection(size: u32) -> Projection {
        let camera = Camera {
            eye: Vec3::new(0.0, 0.0, 2.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov: 2.0 * 0.5f32.atan(),
        };
        Projection::new(&camera, size, size)
    }

    fn covered(fragments: &[Fragment]) -> usize {
        fragments.iter().filter(|f| f.is_covered()).count()
    }

    /// Twice the signed area of (a, b, p) in exact f64 arithmetic (inputs
    /// are multiples of 1/2 pixel), positive when p is left of a → b with y up.
    fn cross(a: Vec2, b: Vec2, p: Vec2) -> f64 {
        let (a, b, p) = (a.as_dvec2(), b.as_dvec2(), p.as_dvec2());
        (b - a).perp_dot(p - a)
    }

    proptest! {
        /// A fan of triangles around a centre tiles a star-shaped polygon:
        /// every sample strictly inside is drawn exactly once, none outside.
        /// Corners snap to half pixels, so edges and corners run through
        /// sample points and the fill rule decides.
        #[test]
        fn fans_are_drawn_watertight(
            center in (-20i32..20, -20i32..20),
            radii in proptest::collection::vec(12i32..56, 3..10),
            phase in 0.0f32..std::f32::consts::TAU,
        ) {
            let size = 64;
            let projection = front_projection(size);
            // World (x, y) at depth 2 maps to pixel (32 + 32x, 32 − 32y):
            // multiples of 1/64 land on half pixels exactly.
            let snap = |v: f32| (v * 64.0).round() / 64.0;
            let c = Vec2::new(center.0 as f32, center.1 as f32) / 64.0;
            let n = radii.len();
            let mut positions = vec![c.extend(0.0)];
            for (i, &r) in radii.iter().enumerate() {
                let a = phase + i as f32 * std::f32::consts::TAU / n as f32;
                let p = c + r as f32 / 64.0 * Vec2::new(a.cos(), a.sin());
                positions.push(Vec3::new(snap(p.x), snap(p.y), 0.0));
            }
            let triangles: Vec<[u32; 3]> = (0..n as u32).map(|i| [0, 1 + i, 1 + (i + 1) % n as u32]).collect();
            let fan = TriMesh::new(positions.clone(), triangles.clone()).unwrap();
            let fragments = rasterize(&fan, &projection, size, size);
            let separate: usize = triangles
                .iter()
                .map(|&t| covered(&rasterize(&TriMesh::new(positions.clone(), vec![t]).unwrap(), &projection, size, size)))
                .sum();
            prop_assert_eq!(separate, covered(&fragments), "a sample was drawn by two triangles");

            let pixel: Vec<Vec2> = positions.iter().map(|p| 32.0 + 32.0 * Vec2::new(p.x, -p.y)).collect();
            for (i, f) in fragments.iter().enumerate() {
                let s = Vec2::new((i % 64) as f32 + 0.5, (i / 64) as f32 + 0.5);
                // Screen y runs down, so counter-clockwise triangles have
                // negative `cross`; inside means all three ≤ 0.
                let in_closed = triangles.iter().any(|t| {
                    let [a, b, c] = t.map(|k| pixel[k as usize]);
                    cross(a, b, s) <= 0.0 && cross(b, c, s) <= 0.0 && cross(c, a, s) <= 0.0
                });
                let on_outline = (1..=n).any(|k| {
                    let (a, b) = (pixel[k], pixel[1 + k % n]);
                    cross(a, b, s) == 0.0 && s.cmpge(a.min(b)).all() && s.cmple(a.max(b)).all()
                });
                if in_closed && !on_outline {
                    prop_assert!(f.is_covered(), "gap at interior sample {}", s);
                } else if !in_closed {
                    prop_assert!(!f.is_covered(), "sample {} outside the polygon drawn", s);
                }
            }
        }
    }

    #[test]
    fn axis_aligned_squares_tile_without_gaps_or_overlap() {
        // Two rectangles sharing a vertical edge through a column of pixel
        // centres (x = 1/64 maps to 32.5), with their top edges on a row of
        // centres (y = 0.265625 maps to 23.5). World units map to 32 pixels.
        let size = 64;
        let projection = front_projection(size);
        let (shared, top, bottom) = (1.0 / 64.0, 0.265625, -0.5);
        let quad = |x0: f32, x1: f32| {
            TriMesh::new(
                vec![
                    Vec3::new(x0, bottom, 0.0),
                    Vec3::new(x1, bottom, 0.0),
                    Vec3::new(x1, top, 0.0),
                    Vec3::new(x0, top, 0.0),
                ],
                vec![[0, 1, 2], [0, 2, 3]],
            )
            .unwrap()
        };
        let (left, right) = (quad(-0.5, shared), quad(shared, 0.5));
        let mut both = left.clone();
        both.append(&right);
        let count = |m: &TriMesh| covered(&rasterize(m, &projection, size, size));
        // Columns 16..=31 and 32..=47 (the shared centre column belongs to the
        // right one, whose edge there is a left edge), rows 23..=47 (the top
        // edge owns its row of centres).
        assert_eq!(count(&left), 16 * 25);
        assert_eq!(count(&right), 16 * 25);
        assert_eq!(count(&both), 2 * 16 * 25);
    }

    #[test]
    fn triangles_crossing_the_eye_plane_are_clipped_not_dropped() {
        // A long floor strip running from behind the camera to far ahead.
        let size = 32;
        let projection = front_projection(size);
        let floor = TriMesh::new(
            vec![
                Vec3::new(-1.0, -0.5, 5.0),
                Vec3::new(1.0, -0.5, 5.0),
                Vec3::new(1.0, -0.5, -50.0),
                Vec3::new(-1.0, -0.5, -50.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        let fragments = rasterize(&floor, &projection, size, size);
        // The bottom rows see the floor right below the eye, the top half never.
        let rows = |range: std::ops::Range<usize>| covered(&fragments[range.start * 32..range.end * 32]);
        assert_eq!(rows(28..32), 4 * 32);
        assert_eq!(rows(0..16), 0);
        // Every seen point lies on the floor, in front of the eye.
        for (i, f) in fragments.iter().enumerate().filter(|(_, f)| f.is_covered()) {
            let pixel = Vec2::new((i % 32) as f32 + 0.5, (i / 32) as f32 + 0.5);
            let p = projection.unproject(pixel, f.inv_depth);
            let depth = 1.0 / f.inv_depth;
            assert!((p.y + 0.5).abs() < 1e-5 * depth && p.z < 2.0, "seen point {p} is not on the floor");
        }
    }

    #[test]
    fn bad_triangles_are_skipped() {
        let projection = front_projection(16);
        let mesh = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::NAN, Vec3::INFINITY],
            triangles: vec![[0, 1, 9], [0, 1, 3], [0, 4, 2], [0, 0, 1], [0, 1, 2]],
            normals: None,
            colors: None,
        };
        let fragments = rasterize(&mesh, &projection, 16, 16);
        assert!(fragments.iter().filter(|f| f.is_covered()).all(|f| f.triangle == 4));
        assert!(covered(&fragments) > 0);
        assert!(rasterize(&mesh, &projection, 0, 16).is_empty());
    }
}
