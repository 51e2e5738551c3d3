//! Exact signed distance to a closed triangle mesh, positive inside.
//!
//! The magnitude is the exact Euclidean distance to the nearest triangle
//! (found with [`TriangleBvh`]); the sign comes from the *angle-weighted
//! pseudonormal* of the nearest feature (face, edge or vertex; Bærentzen &
//! Aanæs, IEEE TVCG 2005), which is exact for closed, consistently oriented,
//! self-intersection-free meshes. Meshes with holes or flipped triangles get
//! a locally plausible but not guaranteed sign.

use crate::mesh::bvh::{ClosestPoint, TriangleBvh};
use crate::{Aabb, Field3, TriMesh};
use glam::Vec3;
use std::collections::HashMap;

/// Errors of [`MeshSdf::new`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SdfError {
    /// The mesh has no triangle.
    #[error("the mesh has no triangles; a distance field needs a surface")]
    EmptyMesh,
    /// The mesh failed validation.
    #[error(transparent)]
    Mesh(#[from] crate::MeshError),
}

/// Signed distance to a triangle mesh (positive inside), usable as a [`Field3`].
#[derive(Debug, Clone)]
pub struct MeshSdf {
    bvh: TriangleBvh,
    triangles: Vec<[u32; 3]>,
    face_normals: Vec<Vec3>,
    vertex_normals: Vec<Vec3>,
    edge_normals: HashMap<(u32, u32), Vec3>,
    bounds: Aabb,
}

/// Barycentric coordinates at or below this count as zero when choosing the
/// nearest feature.
const FEATURE_EPS: f32 = 1e-6;

impl MeshSdf {
    /// Builds the BVH and the pseudonormals of `mesh`.
    ///
    /// # Errors
    /// [`SdfError::EmptyMesh`] for a mesh without triangles, [`SdfError::Mesh`]
    /// for invalid indices or coordinates.
    pub fn new(mesh: &TriMesh) -> Result<Self, SdfError> {
        mesh.validate()?;
        if mesh.is_empty() {
            return Err(SdfError::EmptyMesh);
        }
        let mut face_normals = Vec::with_capacity(mesh.triangles.len());
        let mut vertex_normals = vec![Vec3::ZERO; mesh.positions.len()];
        let mut edge_normals: HashMap<(u32, u32), Vec3> =
            HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = mesh.corners(t);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            face_normals.push(n);
            for c in 0..3 {
                let (a, b) = (
                    (p[(c + 1) % 3] - p[c]).normalize_or_zero(),
                    (p[(c + 2) % 3] - p[c]).normalize_or_zero(),
                );
                let angle = a.dot(b).clamp(-1.0, 1.0).acos();
                vertex_normals[tri[c] as usize] += angle * n;
                let (u, v) = (tri[c], tri[(c + 1) % 3]);
                *edge_normals.entry((u.min(v), u.max(v))).or_insert(Vec3::ZERO) += n;
            }
        }
        Ok(Self {
            bvh: TriangleBvh::new(mesh),
            triangles: mesh.triangles.clone(),
            face_normals,
            vertex_normals,
            edge_normals,
            bounds: mesh.bounds(),
        })
    }

    /// The nearest surface point to `p`, with its triangle.
    pub fn closest(&self, p: Vec3) -> ClosestPoint {
        self.bvh.closest(p).expect("MeshSdf always has triangles")
    }

    /// Signed distance at `p` (positive inside).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        let hit = self.closest(p);
        let distance = hit.distance_squared.sqrt();
        let outward = (p - hit.point).dot(self.pseudonormal(&hit));
        if outward > 0.0 { -distance } else { distance }
    }

    /// Angle-weighted pseudonormal of the feature (vertex, edge or face)
    /// holding the closest point.
    fn pseudonormal(&self, hit: &ClosestPoint) -> Vec3 {
        let tri = self.triangles[hit.triangle as usize];
        let z = hit.barycentric.to_array().map(|b| b <= FEATURE_EPS);
        let edge = |i: usize, j: usize| {
            let (u, v) = (tri[i], tri[j]);
            self.edge_normals[&(u.min(v), u.max(v))]
        };
        match z {
            [true, true, _] => self.vertex_normals[tri[2] as usize],
            [true, _, true] => self.vertex_normals[tri[1] as usize],
            [_, true, true] => self.vertex_normals[tri[0] as usize],
            [true, false, false] => edge(1, 2),
            [false, true, false] => edge(2, 0),
            [false, false, true] => edge(0, 1),
            _ => self.face_normals[hit.triangle as usize],
        }
    }
}

impl Field3 for MeshSdf {
    fn value(&self, p: Vec3) -> f32 {
        self.signed_distance(p)
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(self.bounds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned cube `[-1, 1]³` as 12 outward triangles.
    fn cube() -> TriMesh {
        let p: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new([-1.0, 1.0][i & 1], [-1.0, 1.0][(i >> 1) & 1], [-1.0, 1.0][i >> 2]))
            .collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let tris = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        TriMesh::new(p, tris).unwrap()
    }

    #[test]
    fn cube_distances_are_exact_with_the_right_sign() {
        let sdf = MeshSdf::new(&cube()).unwrap();
        let box_sd = |p: Vec3| {
            let q = p.abs() - Vec3::ONE;
            -(q.max(Vec3::ZERO).length() + q.max_element().min(0.0))
        };
        for p in [
            Vec3::ZERO,
            Vec3::new(0.5, 0.2, -0.9),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.5, 1.5, 0.0),
            Vec3::new(2.0, 2.0, 2.0),
            Vec3::new(1.0 + 1e-4, 0.3, 0.99),
            Vec3::new(0.999, 0.999, -0.999),
        ] {
            let (got, want) = (sdf.value(p), box_sd(p));
            assert!((got - want).abs() < 1e-5, "at {p}: got {got}, want {want}");
        }
    }

    #[test]
    fn empty_mesh_is_an_error() {
        assert_eq!(MeshSdf::new(&TriMesh::default()).unwrap_err(), SdfError::EmptyMesh);
    }
}
