//! Lighting of visible fragments: a key light from the upper left, a weak
//! fill light from the right, ambient light and a Blinn–Phong highlight, all
//! fixed relative to the camera so that every view is lit alike. Shading is
//! computed in linear RGB and encoded as sRGB.

use super::raster::{Fragment, Projection};
use super::{RenderSettings, Shading};
use glam::{Vec2, Vec3};
use isomorph_common::TriMesh;

/// Light reaching every surface regardless of orientation.
const AMBIENT: f32 = 0.12;
/// Strength of the key light.
const KEY: f32 = 0.85;
/// Strength of the fill light.
const FILL: f32 = 0.3;
/// Strength of the highlight of the key light.
const SPECULAR: f32 = 0.25;
/// Blinn–Phong exponent (larger: smaller, sharper highlight).
const SHININESS: f32 = 48.0;

/// Shades fragments of one mesh for one camera.
pub(super) struct Shader<'a> {
    mesh: &'a TriMesh,
    /// Unit vertex normals for smooth shading; `None` for flat shading.
    normals: Option<Vec<Vec3>>,
    projection: Projection,
    /// Unit directions towards the key and the fill light.
    key: Vec3,
    fill: Vec3,
    /// Linear albedo of front and back faces.
    front: Vec3,
    back: Vec3,
    /// Linear albedo of the front faces per vertex, from the mesh's
    /// colours (when there is one per vertex); replaces `front`.
    vertex_front: Option<Vec<Vec3>>,
}

impl<'a> Shader<'a> {
    pub(super) fn new(mesh: &'a TriMesh, settings: &RenderSettings, projection: &Projection) -> Self {
        let normals = match settings.shading {
            Shading::Flat => None,
            Shading::Smooth => smooth_normals(mesh),
        };
        let b = projection.basis();
        // Light directions in view axes: right, up, towards the viewer.
        let world = |x: f32, y: f32, z: f32| (x * b.right + y * b.up - z * b.forward).normalize();
        Self {
            mesh,
            normals,
            projection: *projection,
            key: world(-0.45, 0.75, 0.55),
            fill: world(0.8, -0.1, 0.5),
            front: srgb_to_linear(settings.color),
            back: srgb_to_linear(settings.back_color),
            vertex_front: mesh
                .colors
                .as_ref()
                .filter(|c| c.len() == mesh.positions.len())
                .map(|c| c.iter().map(|&c| unit_srgb_to_linear(c)).collect()),
        }
    }

    /// Linear RGB radiance of a covered fragment seen at `sample` (in
    /// fractional pixels of the sample grid).
    pub(super) fn shade(&self, fragment: &Fragment, sample: Vec2) -> Vec3 {
        let tri = self.mesh.triangles[fragment.triangle as usize];
        let [a, b, c] = tri.map(|i| self.mesh.positions[i as usize]);
        let point = self.projection.unproject(sample, fragment.inv_depth);
        let weights = barycentric(point, a, b, c);
        let to_eye = (self.projection.eye() - point).normalize_or(Vec3::Z);
        let mut face = (b - a).cross(c - a).normalize_or(to_eye);
        let mut normal = self
            .normals
            .as_ref()
            .map(|n| {
                let [na, nb, nc] = tri.map(|i| n[i as usize]);
                weights.x * na + weights.y * nb + weights.z * nc
            })
            .and_then(Vec3::try_normalize)
            .unwrap_or(face);
        // Two-sided: the back of a surface is lit as if it faced the viewer,
        // in its own colour.
        let is_front = face.dot(to_eye) >= 0.0;
        if !is_front {
            face = -face;
            normal = -normal;
        }
        // Interpolated normals may turn away from the viewer near the
        // silhouette; tilt them back so that they still catch light.
        let facing = normal.dot(to_eye);
        if facing < 0.0 {
            normal = (normal - 1.01 * facing * to_eye).normalize_or(face);
        }
        let lambert = |light: Vec3| normal.dot(light).max(0.0);
        let diffuse = AMBIENT + KEY * lambert(self.key) + FILL * lambert(self.fill);
        let albedo = match &self.vertex_front {
            _ if !is_front => self.back,
            Some(colors) => {
                let [ca, cb, cc] = tri.map(|i| colors[i as usize]);
                weights.x * ca + weights.y * cb + weights.z * cc
            }
            None => self.front,
        };
        let half = (self.key + to_eye).normalize_or(to_eye);
        let highlight = if is_front { SPECULAR * normal.dot(half).max(0.0).powf(SHININESS) } else { 0.0 };
        albedo * diffuse + Vec3::splat(highlight)
    }
}

/// Barycentric weights of `p` (projected onto the plane of triangle `abc`),
/// clamped into the triangle: samples on an edge may fall a rounding error
/// outside.
fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (ab.dot(ab), ab.dot(ac), ac.dot(ac));
    let (d20, d21) = (ap.dot(ab), ap.dot(ac));
    let denom = d00 * d11 - d01 * d01;
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    let weights = Vec3::new(1.0 - v - w, v, w).max(Vec3::ZERO);
    let sum = weights.element_sum();
    if sum.is_finite() && sum > 0.0 { weights / sum } else { Vec3::splat(1.0 / 3.0) }
}

/// Unit vertex normals for smooth shading: the mesh's own when it has one per
/// vertex, else area-weighted ones; `None` (flat shading) when a triangle
/// index is out of range.
fn smooth_normals(mesh: &TriMesh) -> Option<Vec<Vec3>> {
    let n = mesh.positions.len();
    match &mesh.normals {
        Some(normals) if normals.len() == n => Some(normals.clone()),
        _ => mesh.triangles.iter().flatten().all(|&i| (i as usize) < n).then(|| mesh.vertex_normals()),
    }
}

/// An 8-bit sRGB colour in linear RGB `[0, 1]`.
pub(super) fn srgb_to_linear(color: [u8; 3]) -> Vec3 {
    unit_srgb_to_linear(Vec3::from(color.map(f32::from)) / 255.0)
}

/// An sRGB colour with components in `[0, 1]` (clamped; NaN as 0) in
/// linear RGB.
fn unit_srgb_to_linear(color: Vec3) -> Vec3 {
    Vec3::from(color.to_array().map(|c| {
        let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    }))
}

/// A linear RGB colour (clamped to `[0, 1]`) in 8-bit sRGB.
pub(super) fn linear_to_srgb(color: Vec3) -> [u8; 3] {
    color.to_array().map(|c| {
        let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
        (255.0 * s).round() as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_weights_reproduce_the_point() {
        let (a, b, c) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 0.0, 3.0));
        let w = Vec3::new(0.2, 0.3, 0.5);
        let p = w.x * a + w.y * b + w.z * c;
        assert!(barycentric(p, a, b, c).abs_diff_eq(w, 1e-6));
        // Off the plane: projected; outside: clamped; degenerate: centroid.
        let normal = (b - a).cross(c - a).normalize();
        assert!(barycentric(p + 0.1 * normal, a, b, c).abs_diff_eq(w, 1e-5));
        assert_eq!(barycentric(2.0 * a, a, b, c), Vec3::X);
        assert_eq!(barycentric(a, a, a, a), Vec3::splat(1.0 / 3.0));
    }

    #[test]
    fn srgb_round_trip_is_exact_on_every_byte() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear([c, c, c])), [c, c, c]);
        }
        assert_eq!(linear_to_srgb(Vec3::new(f32::NAN, 2.0, -1.0)), [0, 255, 0]);
    }
}
