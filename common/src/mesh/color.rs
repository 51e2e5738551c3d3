//! Surface colours looked up at the closest surface point
//! ([`ColorLookup`]), to carry the inputs' vertex colours onto the frames of
//! a morph (Breen & Whitaker Fig. 13).

use super::bvh::TriangleBvh;
use crate::TriMesh;
use glam::Vec3;

/// The colour of a surface anywhere in space: the colour at the surface
/// point closest to the query, interpolated barycentrically from the
/// closest triangle's vertex colours (sRGB components in `[0, 1]`, as
/// [`TriMesh::colors`]). A surface without vertex colours, or without
/// triangles, has one colour everywhere.
///
/// Queries run on a copy of the mesh scaled by a power of two (exact) that
/// brings its coordinates near 1, so any mesh scale works.
#[derive(Debug, Clone)]
pub struct ColorLookup(Lookup);

#[derive(Debug, Clone)]
enum Lookup {
    Uniform(Vec3),
    Surface { bvh: TriangleBvh, triangles: Vec<[u32; 3]>, colors: Vec<Vec3>, scale: f32 },
}

impl ColorLookup {
    /// Looks colours up on `mesh`, or gives `uniform` everywhere when the
    /// mesh has no colours or no triangles.
    ///
    /// # Errors
    /// [`MeshError`](crate::MeshError) when the mesh does not validate
    /// (e.g. colour data of the wrong length).
    pub fn new(mesh: &TriMesh, uniform: Vec3) -> Result<Self, crate::MeshError> {
        mesh.validate()?;
        Ok(Self(match &mesh.colors {
            Some(colors) if !mesh.is_empty() => {
                let scale = mesh.unit_scale();
                Lookup::Surface {
                    bvh: TriangleBvh::new(&mesh.scaled(scale)),
                    triangles: mesh.triangles.clone(),
                    colors: colors.clone(),
                    scale,
                }
            }
            _ => Lookup::Uniform(uniform),
        }))
    }

    /// One colour everywhere.
    pub fn uniform(color: Vec3) -> Self {
        Self(Lookup::Uniform(color))
    }

    /// True when the colour is the same everywhere.
    pub fn is_uniform(&self) -> bool {
        matches!(self.0, Lookup::Uniform(_))
    }

    /// The colour at the surface point closest to each of `points`, written
    /// to the same position of `out`; parallel, and independent of the
    /// thread count. A non-finite point gets the colour of the first vertex.
    ///
    /// # Panics
    /// If `out` and `points` differ in length.
    pub fn colors_at(&self, points: &[Vec3], out: &mut [Vec3]) {
        assert_eq!(points.len(), out.len(), "colors_at: one output slot per point");
        match &self.0 {
            Lookup::Uniform(color) => out.fill(*color),
            Lookup::Surface { bvh, triangles, colors, scale } => {
                let scaled: Vec<Vec3> = points.iter().map(|&p| p * *scale).collect();
                let mut closest = vec![None; points.len()];
                bvh.closest_many(&scaled, &mut closest);
                for (o, c) in out.iter_mut().zip(closest) {
                    *o = match c {
                        Some(c) => {
                            let [a, b, d] = triangles[c.triangle as usize].map(|i| colors[i as usize]);
                            a * c.barycentric.x + b * c.barycentric.y + d * c.barycentric.z
                        }
                        None => colors[0],
                    };
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::primitives::uv_sphere;

    /// A colour that varies linearly over space, in `[0, 1]` on the unit ball.
    fn paint(p: Vec3) -> Vec3 {
        p * 0.5 + Vec3::splat(0.5)
    }

    #[test]
    fn vertices_get_their_own_colour_and_points_off_the_surface_the_nearest() {
        for scale in [1.0, 3e-6, 2e5] {
            let mut sphere = uv_sphere(Vec3::ZERO, 1.0, 48, 96);
            let colors = sphere.positions.iter().map(|&p| paint(p)).collect();
            sphere = sphere.with_colors(colors).unwrap();
            let lookup = ColorLookup::new(
                &sphere.transformed(&glam::Affine3A::from_scale(Vec3::splat(scale))),
                Vec3::ZERO,
            )
            .unwrap();
            assert!(!lookup.is_uniform());
            let at: Vec<Vec3> = sphere.positions.iter().map(|&p| p * scale).collect();
            let mut out = vec![Vec3::ZERO; at.len()];
            lookup.colors_at(&at, &mut out);
            for (got, expected) in out.iter().zip(sphere.colors.as_ref().unwrap()) {
                assert!((*got - *expected).abs().max_element() < 1e-5, "scale {scale}: {got} vs {expected}");
            }
            // Points 30 % out along a direction take the colour where the
            // direction meets the sphere (linear paint: exact up to the
            // facets' flatness, a few thousandths here).
            let dirs = [Vec3::new(0.3, 0.8, -0.5), Vec3::new(-0.9, 0.1, 0.2), Vec3::Z];
            let out_points: Vec<Vec3> = dirs.iter().map(|d| d.normalize() * 1.3 * scale).collect();
            let mut out = vec![Vec3::ZERO; 3];
            lookup.colors_at(&out_points, &mut out);
            for (got, d) in out.iter().zip(dirs) {
                let expected = paint(d.normalize());
                assert!((*got - expected).abs().max_element() < 0.01, "scale {scale}: {got} vs {expected}");
            }
        }
    }

    #[test]
    fn uncoloured_or_empty_surfaces_are_uniform_and_bad_colours_are_errors() {
        let grey = Vec3::splat(0.7);
        let plain = ColorLookup::new(&uv_sphere(Vec3::ZERO, 1.0, 4, 8), grey).unwrap();
        assert!(plain.is_uniform());
        let mut out = [Vec3::ZERO; 2];
        plain.colors_at(&[Vec3::ZERO, Vec3::X], &mut out);
        assert_eq!(out, [grey; 2]);
        let mut short = uv_sphere(Vec3::ZERO, 1.0, 4, 8);
        short.colors = Some(vec![grey; 3]);
        assert!(matches!(
            ColorLookup::new(&short, grey),
            Err(crate::MeshError::ColorCount { colors: 3, .. })
        ));
    }
}
