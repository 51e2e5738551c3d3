//! Mesh metrics: area, enclosed volume, edge topology (boundary and
//! non-manifold edges), connected components, Euler characteristic and genus,
//! gathered in one [`MeshMetrics`] report.
//!
//! # Topological conventions
//! - Edges are undirected vertex-index pairs: two triangles share an edge when
//!   they share both vertex *indices* (not merely positions; weld first).
//! - A triangle with a repeated vertex index (e.g. `[4, 4, 7]`) is not a 2-cell:
//!   it has no proper edges and is skipped by every topological count (edges,
//!   faces, referenced vertices, components). Geometrically degenerate triangles
//!   with three distinct indices (zero area) count normally.
//! - Vertices that no proper triangle references are ignored: they are neither
//!   counted in the Euler characteristic nor form components of their own.
//!
//! Accumulations run in `f64`; the edge analysis sorts one packed key per
//! triangle corner (parallel sort), so a 270k-triangle mesh takes milliseconds.

use crate::TriMesh;
use glam::DVec3;
use rayon::slice::ParallelSliceMut;
use serde::Serialize;

/// Counts of the edges of a mesh by the number of triangles using them.
///
/// See the [module conventions](self) for what counts as an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[non_exhaustive]
pub struct EdgeStats {
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges used by exactly one triangle (the rim of a hole or open sheet).
    pub boundary_edges: usize,
    /// Edges used by three or more triangles (fins, T-junctions of sheets).
    pub nonmanifold_edges: usize,
    /// Edges used by exactly two triangles that traverse it in the same
    /// direction, i.e. whose windings disagree (zero for a consistently
    /// oriented mesh).
    pub misoriented_edges: usize,
}

/// The standard figures of a triangle mesh, in one serializable report.
///
/// Field names are the JSON keys of the CLI report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[non_exhaustive]
pub struct MeshMetrics {
    /// Number of vertex positions (including unreferenced ones).
    pub vertices: usize,
    /// Number of triangles (including degenerate ones).
    pub triangles: usize,
    /// Total surface area, in squared world units.
    pub area: f64,
    /// Signed enclosed volume ([`TriMesh::signed_volume`]); meaningful only for
    /// a closed mesh.
    pub volume: f64,
    /// Connected components ([`TriMesh::connected_components`]).
    pub components: usize,
    /// Components that wall in a cavity: their own signed volume is negative
    /// (their outward triangles face into an enclosed void of a solid, as
    /// marching cubes of a positive-inside field produce for an empty bubble).
    /// `components − voids` are outer shells ([`TriMesh::component_volumes`]).
    pub voids: usize,
    /// Euler characteristic V − E + F ([`TriMesh::euler_characteristic`]).
    pub euler: i64,
    /// Total genus of a closed 2-manifold ([`TriMesh::genus`]); `None` when it
    /// is undefined.
    pub genus: Option<i64>,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Edges used by three or more triangles.
    pub nonmanifold_edges: usize,
}

/// Topological counts shared by the public queries.
struct Topology {
    edges: EdgeStats,
    /// Triangles with three distinct vertex indices.
    faces: usize,
    /// Vertices referenced by such triangles.
    vertices: usize,
    components: usize,
}

impl Topology {
    fn euler(&self) -> i64 {
        self.vertices as i64 - self.edges.edges as i64 + self.faces as i64
    }

    fn genus(&self) -> Option<i64> {
        let chi = self.euler();
        let closed_manifold = self.edges.boundary_edges == 0 && self.edges.nonmanifold_edges == 0;
        // An odd χ proves a non-orientable component, whose genus this is not.
        (closed_manifold && chi % 2 == 0).then(|| self.components as i64 - chi / 2)
    }
}

/// True when the triangle has three distinct vertex indices.
#[inline]
fn is_proper([a, b, c]: [u32; 3]) -> bool {
    a != b && b != c && a != c
}

/// Packs the directed edge `from → to` (`from != to`) into a key whose upper 63
/// bits identify the undirected edge and whose lowest bit is the direction.
///
/// The undirected part is the index `hi·(hi−1)/2 + lo` of the pair `lo < hi`
/// in the lower triangle of the adjacency matrix, below 2⁶³ for all `u32`
/// indices, so sorting the keys groups the uses of each edge together.
#[inline]
fn edge_key(from: u32, to: u32) -> u64 {
    let (lo, hi) = if from < to { (from as u64, to as u64) } else { (to as u64, from as u64) };
    let pair = hi * (hi - 1) / 2 + lo;
    (pair << 1) | u64::from(from > to)
}

/// Union-find root of `v` with path halving.
#[inline]
fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        let grand = parent[parent[v as usize] as usize];
        parent[v as usize] = grand;
        v = grand;
    }
    v
}

impl TriMesh {
    /// Total surface area in squared world units (degenerate triangles add 0).
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn area(&self) -> f64 {
        self.area_and_volume().0
    }

    /// Signed enclosed volume by the divergence theorem, Σ a·(b×c)/6 over the
    /// triangles, in cubed world units.
    ///
    /// Positive for a closed mesh whose triangles are counter-clockwise seen
    /// from outside (the project convention), negative when it is inside-out.
    /// For an open mesh the value depends on the origin and means nothing.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn signed_volume(&self) -> f64 {
        self.area_and_volume().1
    }

    /// Counts of edges by use: total, boundary, non-manifold and misoriented.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn edge_stats(&self) -> EdgeStats {
        self.edge_stats_inner()
    }

    /// Number of connected components: classes of triangles linked through
    /// shared vertex indices (sharing one vertex suffices). Unreferenced
    /// vertices are not components; an empty mesh has none.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn connected_components(&self) -> usize {
        self.components_and_vertices().0
    }

    /// The signed volume ([`TriMesh::signed_volume`]) of each connected
    /// component, in the order of their first triangles, in cubed world
    /// units. For a closed, outward-oriented mesh an outer shell has a
    /// positive volume and the wall of an enclosed cavity a negative one
    /// (its triangles face into the cavity), which is how
    /// [`MeshMetrics::voids`] tells them apart. Meaningless for open
    /// components.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn component_volumes(&self) -> Vec<f64> {
        let (mut parent, _, _) = self.union_find();
        let mut slot = vec![u32::MAX; self.positions.len()];
        let mut volumes = Vec::new();
        for &tri in self.triangles.iter().filter(|&&t| is_proper(t)) {
            let root = find(&mut parent, tri[0]) as usize;
            if slot[root] == u32::MAX {
                slot[root] = volumes.len() as u32;
                volumes.push(0.0);
            }
            let [a, b, c] = tri.map(|v| self.positions[v as usize].as_dvec3());
            volumes[slot[root] as usize] += a.dot(b.cross(c)) / 6.0;
        }
        volumes
    }

    /// Euler characteristic χ = V − E + F, where V counts only referenced
    /// vertices and triangles with a repeated vertex index are skipped (see
    /// the [module conventions](self)). A sphere has χ = 2, a torus χ = 0.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn euler_characteristic(&self) -> i64 {
        self.topology().euler()
    }

    /// Total genus (number of handles, summed over components) of a closed
    /// orientable 2-manifold: with C components, χ = Σ (2 − 2gᵢ) gives
    /// g = C − χ/2. A sphere has genus 0, a torus 1, two spheres 0.
    ///
    /// Returns `None` when the genus is undefined: the mesh has boundary or
    /// non-manifold edges, or χ is odd (which proves a non-orientable part).
    /// Orientability is otherwise assumed, not checked; a consistently wound
    /// mesh ([`EdgeStats::misoriented_edges`] = 0) is orientable. An empty mesh
    /// has genus 0.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn genus(&self) -> Option<i64> {
        self.topology().genus()
    }

    /// All metrics at once, sharing one edge analysis.
    ///
    /// # Panics
    /// If a triangle index is out of range (a mesh [`TriMesh::validate`] rejects).
    pub fn metrics(&self) -> MeshMetrics {
        let topo = self.topology();
        let (area, volume) = self.area_and_volume();
        MeshMetrics {
            vertices: self.positions.len(),
            triangles: self.triangles.len(),
            area,
            volume,
            components: topo.components,
            voids: self.component_volumes().iter().filter(|&&v| v < 0.0).count(),
            euler: topo.euler(),
            genus: topo.genus(),
            boundary_edges: topo.edges.boundary_edges,
            nonmanifold_edges: topo.edges.nonmanifold_edges,
        }
    }

    /// Area and signed volume in one pass, accumulated in `f64`.
    fn area_and_volume(&self) -> (f64, f64) {
        let (mut area, mut volume) = (0.0, 0.0);
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t).map(|p| p.as_dvec3());
            let cross: DVec3 = (b - a).cross(c - a);
            area += 0.5 * cross.length();
            volume += a.dot(b.cross(c)) / 6.0;
        }
        (area, volume)
    }

    fn topology(&self) -> Topology {
        let (components, vertices) = self.components_and_vertices();
        Topology {
            edges: self.edge_stats_inner(),
            faces: self.triangles.iter().filter(|&&t| is_proper(t)).count(),
            vertices,
            components,
        }
    }

    /// Sorts the directed-edge keys of all proper triangles and classifies each
    /// run of equal undirected edges by its length.
    fn edge_stats_inner(&self) -> EdgeStats {
        let n = self.positions.len();
        let mut keys: Vec<u64> = Vec::with_capacity(3 * self.triangles.len());
        for &tri @ [a, b, c] in &self.triangles {
            assert!(
                tri.iter().all(|&i| (i as usize) < n),
                "triangle {tri:?} refers to a vertex out of range ({n} vertices)"
            );
            if is_proper(tri) {
                keys.extend([edge_key(a, b), edge_key(b, c), edge_key(c, a)]);
            }
        }
        keys.par_sort_unstable();
        let mut stats = EdgeStats::default();
        let mut rest = keys.as_slice();
        while let Some(&first) = rest.first() {
            let run = rest.iter().take_while(|&&k| k >> 1 == first >> 1).count();
            stats.edges += 1;
            match run {
                1 => stats.boundary_edges += 1,
                // Sorted, so a mixed-direction pair is (…0, …1).
                2 if rest[1] == first => stats.misoriented_edges += 1,
                2 => {}
                _ => stats.nonmanifold_edges += 1,
            }
            rest = &rest[run..];
        }
        stats
    }

    /// Union-find over the proper triangles' vertices: `(components,
    /// referenced vertices)`.
    fn components_and_vertices(&self) -> (usize, usize) {
        let (_, referenced, merges) = self.union_find();
        let vertices = referenced.iter().filter(|&&r| r).count();
        (vertices - merges, vertices)
    }

    /// Union-find over the proper triangles' vertices: the parent forest,
    /// which vertices are referenced, and the number of merges.
    fn union_find(&self) -> (Vec<u32>, Vec<bool>, usize) {
        let n = self.positions.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut referenced = vec![false; n];
        let mut merges = 0;
        for &tri in self.triangles.iter().filter(|&&t| is_proper(t)) {
            for &v in &tri {
                referenced[v as usize] = true;
            }
            let root = find(&mut parent, tri[0]);
            for &v in &tri[1..] {
                let other = find(&mut parent, v);
                if other != root {
                    // Hang the other tree under `root`; path halving keeps the
                    // trees shallow without ranks.
                    parent[other as usize] = root;
                    merges += 1;
                }
            }
        }
        (parent, referenced, merges)
    }
}

/// Meshes shared by the tests of the mesh modules: the Stanford bunny read
/// by a minimal OBJ reader (the real reader lives in `isomorph-io`) and the
/// procedural meshes of [`crate::mesh::primitives`].
#[cfg(test)]
pub(crate) mod test_meshes {
    use crate::TriMesh;
    use glam::Vec3;

    pub(crate) use crate::mesh::primitives::{cube, torus, uv_sphere};

    /// Reads the `v` and `f` lines of an OBJ file (triangles only, 1-based
    /// indices, `i/j/k` corner syntax reduced to the position index).
    pub(crate) fn read_obj(path: &str) -> TriMesh {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for line in text.lines() {
            let mut words = line.split_whitespace();
            match words.next() {
                Some("v") => {
                    let c: Vec<f32> = words.take(3).map(|w| w.parse().unwrap()).collect();
                    positions.push(Vec3::new(c[0], c[1], c[2]));
                }
                Some("f") => {
                    let c: Vec<u32> =
                        words.map(|w| w.split('/').next().unwrap().parse::<u32>().unwrap() - 1).collect();
                    assert_eq!(c.len(), 3, "only triangles are supported");
                    triangles.push([c[0], c[1], c[2]]);
                }
                _ => {}
            }
        }
        TriMesh::new(positions, triangles).unwrap()
    }

    /// The Stanford bunny of the repository's test data.
    pub(crate) fn bunny() -> TriMesh {
        read_obj(concat!(env!("CARGO_MANIFEST_DIR"), "/../data/bunny.obj"))
    }
}

#[cfg(test)]
mod tests {
    use super::test_meshes::*;
    use super::*;
    use crate::mesh::trimesh::tests::tetrahedron;
    use glam::Vec3;
    use std::f64::consts::PI;

    #[track_caller]
    fn assert_rel(got: f64, expected: f64, tol: f64) {
        let diff = (got - expected).abs();
        assert!(diff <= tol * expected.abs(), "expected {expected}, got {got}, difference {diff}");
    }

    /// Checks every topological figure of `m` against the expected values.
    #[track_caller]
    fn assert_topology(m: &TriMesh, components: usize, euler: i64, genus: Option<i64>) {
        let metrics = m.metrics();
        assert_eq!(
            (metrics.components, metrics.euler, metrics.genus),
            (components, euler, genus),
            "(components, χ, genus)"
        );
        assert_eq!(m.connected_components(), components);
        assert_eq!(m.euler_characteristic(), euler);
        assert_eq!(m.genus(), genus);
    }

    #[test]
    fn tetrahedron_figures() {
        let t = tetrahedron();
        let m = t.metrics();
        assert_rel(m.volume, 1.0 / 6.0, 1e-12);
        assert_rel(m.area, 1.5 + 3f64.sqrt() / 2.0, 1e-7);
        assert_eq!(t.edge_stats(), EdgeStats { edges: 6, ..EdgeStats::default() });
        assert_topology(&t, 1, 2, Some(0));
    }

    #[test]
    fn cube_figures_and_inside_out_volume() {
        let mut c = cube(1.0);
        assert_rel(c.area(), 24.0, 1e-12);
        assert_rel(c.signed_volume(), 8.0, 1e-12);
        assert_eq!(c.edge_stats().edges, 18);
        assert_topology(&c, 1, 2, Some(0));
        c.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        assert_rel(c.signed_volume(), -8.0, 1e-12);
        assert_eq!(c.edge_stats().misoriented_edges, 0, "flipping all keeps consistency");
        c.triangles[0].swap(1, 2);
        assert_eq!(c.edge_stats().misoriented_edges, 3, "one flipped triangle disagrees on 3 edges");
    }

    #[test]
    fn sphere_is_genus_zero_and_approaches_analytic_figures() {
        let s = uv_sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 64, 128);
        let m = s.metrics();
        assert_eq!((m.boundary_edges, m.nonmanifold_edges), (0, 0));
        assert_topology(&s, 1, 2, Some(0));
        assert_rel(m.area, 4.0 * PI * 4.0, 2e-3);
        assert_rel(m.volume, 4.0 / 3.0 * PI * 8.0, 3e-3);
        assert_eq!(s.edge_stats().misoriented_edges, 0);
    }

    #[test]
    fn torus_is_genus_one() {
        let t = torus(3.0, 1.0, 96, 48);
        assert_topology(&t, 1, 0, Some(1));
        let m = t.metrics();
        assert_rel(m.area, 4.0 * PI * PI * 3.0, 2e-3);
        // The inscribed polygons lose sin(2π/m)·m/2π (0.29 %) of the tube's
        // cross-section and 0.07 % around the axis.
        assert_rel(m.volume, 2.0 * PI * PI * 3.0, 5e-3);
    }

    #[test]
    fn disjoint_shapes_add_components_and_genera() {
        let mut two = uv_sphere(Vec3::ZERO, 1.0, 8, 12);
        two.append(&uv_sphere(Vec3::new(5.0, 0.0, 0.0), 1.0, 8, 12));
        assert_topology(&two, 2, 4, Some(0));
        two.append(&torus(3.0, 1.0, 12, 8));
        two.append(&torus(3.0, 1.0, 12, 8));
        assert_topology(&two, 4, 4, Some(2));
    }

    #[test]
    fn cavity_walls_are_voids_and_shells_are_not() {
        // A hollow ball: the outer sphere outward, the inner one inside-out
        // (its triangles face into the cavity), and a separate outer ball.
        let mut m = uv_sphere(Vec3::ZERO, 2.0, 16, 24);
        let mut wall = uv_sphere(Vec3::ZERO, 1.0, 16, 24);
        wall.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        m.append(&wall);
        m.append(&uv_sphere(Vec3::new(9.0, 0.0, 0.0), 0.5, 8, 12));
        let v = m.component_volumes();
        assert_eq!(v.len(), 3);
        assert!(v[0] > 30.0 && v[1] < -3.0 && v[2] > 0.3, "{v:?}");
        assert_rel(v.iter().sum(), m.signed_volume(), 1e-9);
        let metrics = m.metrics();
        assert_eq!((metrics.components, metrics.voids), (3, 1));
    }

    #[test]
    fn open_mesh_counts_boundary_and_has_no_genus() {
        let mut s = uv_sphere(Vec3::ZERO, 1.0, 8, 12);
        // Removing the 12 triangles around the north pole opens a 12-edge hole
        // and leaves the pole unreferenced: a disc, χ = 1.
        s.triangles.retain(|t| !t.contains(&0));
        let m = s.metrics();
        assert_eq!((m.boundary_edges, m.nonmanifold_edges), (12, 0));
        assert_topology(&s, 1, 1, None);
        assert_eq!(m.vertices, s.positions.len(), "vertices counts positions, referenced or not");
    }

    #[test]
    fn fin_is_non_manifold() {
        let mut c = cube(1.0);
        // A fin glued to the cube's edge between vertices 0 and 4.
        c.positions.push(Vec3::new(-3.0, -3.0, 0.0));
        c.triangles.push([0, 4, 8]);
        let stats = c.edge_stats();
        assert_eq!((stats.boundary_edges, stats.nonmanifold_edges), (2, 1));
        assert_topology(&c, 1, 2, None);
    }

    #[test]
    fn degenerate_and_unreferenced_elements_are_skipped() {
        let mut t = tetrahedron();
        t.positions.push(Vec3::splat(9.0)); // unreferenced
        t.triangles.push([1, 1, 2]); // repeated index
        t.triangles.push([0, 0, 0]);
        let m = t.metrics();
        assert_eq!((m.vertices, m.triangles), (5, 6));
        assert_eq!(t.edge_stats(), EdgeStats { edges: 6, ..EdgeStats::default() });
        assert_topology(&t, 1, 2, Some(0));
    }

    #[test]
    fn empty_mesh_has_zero_everything() {
        let e = TriMesh::default();
        let m = e.metrics();
        assert_eq!((m.area, m.volume, m.components, m.euler, m.genus), (0.0, 0.0, 0, 0, Some(0)));
        assert_eq!(m.boundary_edges + m.nonmanifold_edges, 0);
    }

    #[test]
    fn odd_euler_characteristic_has_no_genus() {
        // Two tetrahedra sharing only a vertex: closed by edges, χ = 3, one
        // component; a pinched surface, not a 2-manifold the formula fits.
        let mut t = tetrahedron();
        let mut u = tetrahedron();
        u.transform(&glam::Affine3A::from_scale(Vec3::splat(-1.0)));
        t.append(&u);
        let n = t.positions.len() as u32;
        t.triangles.iter_mut().flatten().for_each(|v| *v = if *v == n / 2 { 0 } else { *v });
        assert_eq!(t.connected_components(), 1);
        assert_eq!(t.euler_characteristic(), 3);
        assert_eq!(t.genus(), None);
    }

    #[test]
    fn bunny_matches_reference_figures() {
        let b = bunny();
        let m = b.metrics();
        assert_eq!((m.vertices, m.triangles), (1839, 3674));
        assert_rel(m.area, 218.68927, 1e-4);
        assert_rel(m.volume, 194.28837, 1e-4);
        assert_eq!((m.boundary_edges, m.nonmanifold_edges, m.components), (0, 0, 1));
        assert_eq!(b.edge_stats().edges, 5511);
        assert_eq!(b.edge_stats().misoriented_edges, 0);
        assert_eq!((m.euler, m.genus), (2, Some(0)));
        let json = serde_json::to_value(m).unwrap();
        for key in ["vertices", "triangles", "area", "volume", "components", "euler", "genus"] {
            assert!(json.get(key).is_some(), "JSON key {key} missing");
        }
        assert!(json.get("boundary_edges").is_some() && json.get("nonmanifold_edges").is_some());
    }

    /// A large mesh for timing the edge analysis (release build).
    #[test]
    #[ignore = "timing helper"]
    fn metrics_timing() {
        let t = torus(3.0, 1.0, 600, 225); // 270k triangles
        let start = std::time::Instant::now();
        let m = t.metrics();
        println!("metrics of {} triangles: {:?} ({m:?})", t.triangles.len(), start.elapsed());
        assert_eq!(m.genus, Some(1));
    }
}
