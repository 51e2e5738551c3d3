//! Procedural closed meshes (outward-oriented, counter-clockwise seen from
//! outside): test inputs, reference surfaces and quick demo shapes.

use crate::TriMesh;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// The cube `[-h, h]³`, two outward triangles per face (8 vertices).
pub fn cube(h: f32) -> TriMesh {
    let positions =
        (0..8).map(|i| Vec3::new([-h, h][i & 1], [-h, h][(i >> 1) & 1], [-h, h][(i >> 2) & 1])).collect();
    let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let triangles = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
    TriMesh { positions, triangles, ..TriMesh::default() }
}

/// A UV sphere of radius `r` about `center` with `rings` latitude bands
/// (at least 2) and `segments` longitude slices (at least 3); the poles are
/// single vertices. Smaller counts are raised to these minimums.
pub fn uv_sphere(center: Vec3, r: f32, rings: u32, segments: u32) -> TriMesh {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut positions = vec![center + Vec3::new(0.0, 0.0, r)];
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = TAU * j as f32 / segments as f32;
            let dir = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            positions.push(center + r * dir);
        }
    }
    positions.push(center - Vec3::new(0.0, 0.0, r));
    let south = positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
        triangles.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
        for i in 1..rings - 1 {
            let (a, b, c, d) = (ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1));
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    TriMesh { positions, triangles, ..TriMesh::default() }
}

/// A torus about the z axis with tube centre radius `big` and tube radius
/// `small`, `n` segments around the axis and `m` around the tube (each at
/// least 3; smaller counts are raised).
pub fn torus(big: f32, small: f32, n: u32, m: u32) -> TriMesh {
    let (n, m) = (n.max(3), m.max(3));
    let mut positions = Vec::new();
    for i in 0..n {
        let u = TAU * i as f32 / n as f32;
        for j in 0..m {
            let v = TAU * j as f32 / m as f32;
            let rho = big + small * v.cos();
            positions.push(Vec3::new(rho * u.cos(), rho * u.sin(), small * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + j % m;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    TriMesh { positions, triangles, ..TriMesh::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_are_closed_outward_and_of_their_genus() {
        for (mesh, genus) in
            [(cube(0.5), 0), (uv_sphere(Vec3::ZERO, 1.0, 12, 16), 0), (torus(1.0, 0.3, 24, 12), 1)]
        {
            mesh.validate().unwrap();
            let m = mesh.metrics();
            assert_eq!((m.boundary_edges, m.nonmanifold_edges, m.genus), (0, 0, Some(genus)));
            assert!(m.volume > 0.0, "outward oriented: {}", m.volume);
        }
    }
}
