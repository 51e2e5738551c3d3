//! The indexed triangle mesh [`TriMesh`] and its construction errors.

use crate::Aabb;
use glam::{Affine3A, Vec3};

/// Errors of mesh construction.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle number.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A vertex position is NaN or infinite.
    #[error("vertex {0} has a non-finite coordinate")]
    NonFinite(usize),
    /// The normals array does not have one normal per vertex.
    #[error("{normals} normals given for {vertices} vertices")]
    NormalCount {
        /// Normals given.
        normals: usize,
        /// Vertices.
        vertices: usize,
    },
    /// The colour data does not have one colour per vertex.
    #[error("colour data of the wrong length: {colors} colours given for {vertices} vertices")]
    ColorCount {
        /// Colours given.
        colors: usize,
        /// Vertices.
        vertices: usize,
    },
    /// A vertex colour is NaN or infinite.
    #[error("the colour of vertex {0} is not finite")]
    NonFiniteColor(usize),
}

/// An indexed triangle mesh in world space.
///
/// Triangles are counter-clockwise seen from outside (their right-hand normal
/// points out of the solid), which is what the polygonizers produce under the
/// positive-inside convention.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Optional per-vertex unit normals (outward).
    pub normals: Option<Vec<Vec3>>,
    /// Optional per-vertex colours: sRGB red, green, blue in `[0, 1]` (PLY
    /// `red green blue`, OBJ `v x y z r g b`). Readers, writers, the
    /// renderer and the sequence exporter carry them; geometry ignores them.
    pub colors: Option<Vec<Vec3>>,
}

impl TriMesh {
    /// A mesh from positions and triangles, validated.
    ///
    /// # Errors
    /// [`MeshError::IndexOutOfRange`] for a bad index, [`MeshError::NonFinite`]
    /// for a NaN or infinite coordinate.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        let mesh = Self { positions, triangles, normals: None, colors: None };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks indices, coordinates, the normal count and the colours (one
    /// finite colour per vertex).
    ///
    /// # Errors
    /// The first problem found, as a [`MeshError`].
    pub fn validate(&self) -> Result<(), MeshError> {
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite(i));
        }
        let n = self.positions.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange { triangle: t, index, vertices: n });
            }
        }
        if let Some(normals) = &self.normals
            && normals.len() != n
        {
            return Err(MeshError::NormalCount { normals: normals.len(), vertices: n });
        }
        self.check_colors()
    }

    /// One finite colour per vertex, when there are colours.
    fn check_colors(&self) -> Result<(), MeshError> {
        let Some(colors) = &self.colors else { return Ok(()) };
        let n = self.positions.len();
        if colors.len() != n {
            return Err(MeshError::ColorCount { colors: colors.len(), vertices: n });
        }
        match colors.iter().position(|c| !c.is_finite()) {
            Some(i) => Err(MeshError::NonFiniteColor(i)),
            None => Ok(()),
        }
    }

    /// True when the mesh has no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Bounding box of the vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }

    /// A copy with every position multiplied by `s` (normals, being
    /// directions, and colours are kept).
    pub(crate) fn scaled(&self, s: f32) -> TriMesh {
        TriMesh { positions: self.positions.iter().map(|&p| p * s).collect(), ..self.clone() }
    }

    /// The mesh with per-vertex `colors` (sRGB in `[0, 1]`, see
    /// [`TriMesh::colors`]).
    ///
    /// # Errors
    /// [`MeshError::ColorCount`] unless there is one colour per vertex,
    /// [`MeshError::NonFiniteColor`] for a NaN or infinite component.
    pub fn with_colors(mut self, colors: Vec<Vec3>) -> Result<Self, MeshError> {
        self.colors = Some(colors);
        self.check_colors()?;
        Ok(self)
    }

    /// The power of two `s` that brings the largest coordinate magnitude of
    /// the vertices into `[1, 2)` (or as near as `f32` exponents allow:
    /// within `[2⁻²², 4)` for the extreme magnitudes); 1 when all
    /// coordinates are zero or the largest is infinite.
    ///
    /// Multiplying by `s` changes only exponents, so it is exact (except for
    /// results below 2⁻¹²⁶, over 2¹²⁶ times smaller than the largest, which
    /// lose bits as subnormals): computations that square or cube lengths can
    /// run in the frame `x · s`, free of overflow and underflow, and their
    /// results be scaled back exactly.
    pub(crate) fn unit_scale(&self) -> f32 {
        unit_scale(self.positions.iter().fold(0.0f32, |m, p| m.max(p.abs().max_element())))
    }

    /// The three corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Area-weighted vertex normals (unit length; zero for isolated vertices).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            let [a, b, c] = self.corners(t);
            let n = (b - a).cross(c - a); // length = 2 × area
            for &i in tri {
                acc[i as usize] += n;
            }
        }
        acc.iter().map(|n| n.normalize_or_zero()).collect()
    }

    /// Fills [`TriMesh::normals`] with [`TriMesh::vertex_normals`].
    pub fn compute_normals(&mut self) {
        self.normals = Some(self.vertex_normals());
    }

    /// Applies `map` to every position (and normals by its inverse
    /// transpose; colours stay with their vertices);
    /// a map with negative determinant also flips the triangles so that they
    /// stay outward.
    pub fn transform(&mut self, map: &Affine3A) {
        for p in &mut self.positions {
            *p = map.transform_point3(*p);
        }
        let normal_map = map.matrix3.inverse().transpose();
        if let Some(normals) = &mut self.normals {
            for n in normals.iter_mut() {
                *n = (normal_map * *n).normalize_or_zero();
            }
        }
        if map.matrix3.determinant() < 0.0 {
            for tri in &mut self.triangles {
                tri.swap(1, 2);
            }
        }
    }

    /// A transformed copy (see [`TriMesh::transform`]).
    pub fn transformed(&self, map: &Affine3A) -> Self {
        let mut m = self.clone();
        m.transform(map);
        m
    }

    /// Appends `other`'s vertices and triangles (normals and colours are
    /// kept only when both meshes have them).
    pub fn append(&mut self, other: &TriMesh) {
        let offset = self.positions.len() as u32;
        let joined = |a: Option<Vec<Vec3>>, b: &Option<Vec<Vec3>>| match (a, b) {
            (Some(mut a), Some(b)) => {
                a.extend_from_slice(b);
                Some(a)
            }
            _ => None,
        };
        self.normals = joined(self.normals.take(), &other.normals);
        self.colors = joined(self.colors.take(), &other.colors);
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + offset)));
    }
}

/// The power of two `s` with `magnitude · s` in `[1, 2)`, within the
/// normal `f32` exponents `[2⁻¹²⁶, 2¹²⁷]`; 1 for a zero or non-finite
/// `magnitude`.
pub(crate) fn unit_scale(magnitude: f32) -> f32 {
    if !(magnitude.is_finite() && magnitude > 0.0) {
        return 1.0;
    }
    // A normal `magnitude` with biased exponent `e` lies in [2^(e−127), 2^(e−126)):
    // `s = 2^(127−e)` has biased exponent 254 − e (kept normal); subnormals have e = 0.
    let biased = (magnitude.to_bits() >> 23) as i32;
    f32::from_bits(((254 - biased).clamp(1, 254) as u32) << 23)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A unit right tetrahedron, outward oriented.
    pub(crate) fn tetrahedron() -> TriMesh {
        TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn validation_catches_bad_input() {
        assert!(matches!(
            TriMesh::new(vec![Vec3::ZERO], vec![[0, 0, 1]]),
            Err(MeshError::IndexOutOfRange { index: 1, .. })
        ));
        assert!(matches!(TriMesh::new(vec![Vec3::NAN], vec![]), Err(MeshError::NonFinite(0))));
        let short = tetrahedron().with_colors(vec![Vec3::ONE; 3]);
        assert_eq!(short, Err(MeshError::ColorCount { colors: 3, vertices: 4 }));
        assert!(short.unwrap_err().to_string().contains("colour data of the wrong length"));
        let nan =
            tetrahedron().with_colors(vec![Vec3::ONE, Vec3::ONE, Vec3::new(0.0, f32::NAN, 0.0), Vec3::ONE]);
        assert_eq!(nan, Err(MeshError::NonFiniteColor(2)));
        let mut long = tetrahedron();
        long.colors = Some(vec![Vec3::ZERO; 5]);
        assert_eq!(long.validate(), Err(MeshError::ColorCount { colors: 5, vertices: 4 }));
    }

    #[test]
    fn colors_follow_their_vertices() {
        let colors = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        let t = tetrahedron().with_colors(colors.clone()).unwrap();
        let m = t.transformed(&Affine3A::from_scale(Vec3::new(-1.0, 2.0, 1.0)));
        assert_eq!(m.colors.as_ref(), Some(&colors));
        let mut both = t.clone();
        both.append(&t);
        assert_eq!(both.colors.as_ref().map(Vec::len), Some(8));
        assert_eq!(both.colors.as_ref().unwrap()[4..], colors[..]);
        let mut one = t.clone();
        one.append(&tetrahedron());
        assert_eq!(one.colors, None, "colours of only one part are dropped");
        assert_eq!(t.scaled(4.0).colors, t.colors);
    }

    #[test]
    fn unit_scale_is_a_power_of_two_bringing_magnitudes_near_one() {
        for m in [1.0f32, 1.5, 0.75, 3e-7, 1e13, 1e30, 3.3e38, f32::MAX, 1e-38, 1e-40, 1e-45] {
            let s = unit_scale(m);
            assert_eq!(s.to_bits() & 0x7f_ffff, 0, "{m}: {s} is not a power of two");
            let scaled = m * s;
            assert!((2f32.powi(-22)..4.0).contains(&scaled), "{m} · {s} = {scaled}");
            if (1e-37..1.7e38).contains(&m) {
                assert!((1.0..2.0).contains(&scaled), "{m} · {s} = {scaled}");
            }
        }
        for m in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(unit_scale(m), 1.0);
        }
        let mut t = tetrahedron();
        t.positions.iter_mut().for_each(|p| *p *= -3e20);
        assert_eq!(t.unit_scale(), unit_scale(3e20));
    }

    #[test]
    fn mirror_keeps_outward_orientation() {
        let t = tetrahedron();
        let n0 = t.vertex_normals()[0];
        assert!(n0.dot(Vec3::ONE) < 0.0, "normal at origin points away from the body");
        let m = t.transformed(&Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        let n0m = m.vertex_normals()[0];
        assert!(n0m.dot(Vec3::new(-1.0, 1.0, 1.0)) < 0.0);
    }
}
