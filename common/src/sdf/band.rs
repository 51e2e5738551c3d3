//! A mesh's signed distance in a narrow band of bricks
//! ([`MeshSdf::sample_band_bricks`]): the band bricks solved as blocks of
//! the lattice search, the signs found once per region.

use super::{LINK_MARGIN, MeshSdf, Sign};
use crate::bricks::origin_of as brick_origin;
use crate::mesh::bvh::{BlockNearest, BlockScratch, LATTICE_BLOCK, Lattice, LatticeHit};
use crate::mesh::winding::WindingNumber;
use crate::{BRICK, Bricks, GridError};
use glam::{UVec3, Vec3};
use rayon::prelude::*;

/// Nodes in one brick.
const NODES: usize = (BRICK * BRICK * BRICK) as usize;
/// `log2(BRICK)`.
const SHIFT: u32 = BRICK.trailing_zeros();

/// Local index (x-fastest) of offset `l` within a brick.
#[inline]
fn local(l: UVec3) -> usize {
    (l.x | (l.y << SHIFT) | (l.z << (2 * SHIFT))) as usize
}

/// Offset within a brick of local index `n`.
#[inline]
fn offset(n: usize) -> UVec3 {
    let n = n as u32;
    UVec3::new(n & (BRICK - 1), (n >> SHIFT) & (BRICK - 1), n >> (2 * SHIFT))
}

/// Union–find over `u32` ids (union by index, path halving).
#[derive(Debug)]
struct Sets(Vec<u32>);

impl Sets {
    fn new(len: usize) -> Self {
        Self((0..len as u32).collect())
    }

    fn find(&mut self, mut a: u32) -> u32 {
        while self.0[a as usize] != a {
            let up = self.0[self.0[a as usize] as usize];
            self.0[a as usize] = up;
            a = up;
        }
        a
    }

    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b) as usize] = a.min(b);
        }
    }
}

/// One band brick's regions: nodes linked by overlapping surface-free balls
/// within the brick, numbered from 0.
#[derive(Debug)]
struct Regions {
    /// Per node (local index), its region.
    label: Vec<u16>,
    /// Per region, a node of it (local index).
    first: Vec<u16>,
}

impl MeshSdf {
    /// The exact signed distance (world units, positive inside) on the
    /// lattice of `dims` nodes at `origin` with `spacing`, in the bricks
    /// that come within `band` of the surface, and the side elsewhere:
    /// [`Bricks::sample_band`] for a mesh (the sparse level set's source).
    ///
    /// Each brick is one block of the lattice search
    /// ([`TriangleBvh::nearest_in_block`](crate::mesh::bvh::TriangleBvh::nearest_in_block)):
    /// one tree query at its centre, then, when a node may lie within
    /// `band`, exact distances at all its nodes, bitwise those of
    /// [`MeshSdf::sample_lattice`] on the whole lattice. Signs as there:
    /// with the winding-number test on a closed mesh they are found once
    /// per region — nodes and far bricks (each with the surface-free ball
    /// about its centre) whose surface-free balls overlap share a sign, as
    /// OpenVDB floods signs between band voxels — and by the inside test at
    /// every band node and far-brick centre otherwise. Unallocated bricks
    /// read `±band`. Work ∝ the bricks plus the band's nodes.
    ///
    /// # Errors
    /// As [`Bricks::new`].
    pub fn sample_band_bricks(
        &self,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
        band: f32,
    ) -> Result<Bricks<f32>, GridError> {
        let mut grid = Bricks::new(dims, -band, band)?;
        let world = Lattice { dims, origin, step: Vec3::splat(spacing) };
        let finite = origin.is_finite() && spacing.is_finite() && band.is_finite();
        let Some(lattice) = self.local_lattice(&world).filter(|_| finite) else {
            return Bricks::sample_band_by_points(self, dims, origin, spacing, band);
        };
        debug_assert_eq!(BRICK, LATTICE_BLOCK, "a brick is a block of the lattice search");
        let bricks = grid.brick_dims();
        let max = band * self.scale;
        // Every brick: its centre's distance, and its nodes' nearest
        // triangles when one may lie within the band.
        let blocks: Vec<(BlockNearest, Vec<LatticeHit>)> = (0..grid.brick_count())
            .into_par_iter()
            .map_init(BlockScratch::default, |scratch, brick| {
                let lo = brick_origin(bricks, brick);
                let mut hits = Vec::new();
                let found = self.bvh.nearest_in_block(&lattice, lo, max, scratch, |i, j, k, hit| {
                    if hits.is_empty() {
                        hits.resize(NODES, LatticeHit::NONE);
                    }
                    hits[local(UVec3::new(i, j, k) - lo)] = hit;
                });
                (found.expect("MeshSdf always has triangles; bricks lie in the lattice"), hits)
            })
            .collect();
        let near: Vec<usize> = (0..blocks.len()).filter(|&b| !blocks[b].1.is_empty()).collect();
        grid.allocate_all(&near);
        let last = dims - UVec3::ONE;
        // Per slot, per node: inside.
        let mut inside = vec![false; grid.slots() * NODES];
        let far_inside: Vec<bool> = match &self.sign {
            Sign::Winding(wn) if self.closed => self.flood_signs(wn, &lattice, &grid, &blocks, &mut inside),
            _ => {
                inside.par_chunks_mut(NODES).zip(&near).for_each(|(inside, &brick)| {
                    let lo = brick_origin(bricks, brick);
                    for (n, out) in inside.iter_mut().enumerate() {
                        let c = (lo + offset(n)).min(last);
                        let p = lattice.position(c.x, c.y, c.z);
                        *out = self.inside_at(p, &blocks[brick].1[local(c - lo)]);
                    }
                });
                blocks
                    .par_iter()
                    .map(|(block, hits)| hits.is_empty() && self.is_inside_local(block.center))
                    .collect()
            }
        };
        for (brick, (_, hits)) in blocks.iter().enumerate() {
            if hits.is_empty() {
                grid.set_background(brick, far_inside[brick]);
            }
        }
        // Values: signed, in world units; nodes past the lattice (edge
        // bricks) repeat the border node they clamp to.
        let unit = self.unit();
        let slots: Vec<Option<usize>> = (0..blocks.len()).map(|b| grid.slot_of(b)).collect();
        grid.par_for_each_brick(|brick, values| {
            let lo = brick_origin(bricks, brick);
            let slot = slots[brick].expect("allocated");
            let (hits, inside) = (&blocks[brick].1, &inside[slot * NODES..(slot + 1) * NODES]);
            for (n, v) in values.iter_mut().enumerate() {
                let m = local((lo + offset(n)).min(last) - lo);
                let d = hits[m].distance * unit;
                *v = if inside[m] { d } else { -d };
            }
        });
        Ok(grid)
    }

    /// The inside test at local point `p` whose nearest triangle is `hit`
    /// (the pseudonormal side, or the winding number).
    fn inside_at(&self, p: Vec3, hit: &LatticeHit) -> bool {
        match &self.sign {
            Sign::Winding(wn) => wn.is_inside(p),
            Sign::Pseudonormal(normals) => {
                self.bvh.closest_point_of(p, hit).is_some_and(|c| Self::pseudonormal_inside(normals, p, &c))
            }
        }
    }

    /// Signs of a closed mesh's band (into `inside`, per slot and node) and
    /// far bricks (returned, per brick) by regions of overlapping
    /// surface-free balls, one winding number per region. Two points whose
    /// balls overlap lie in one connected surface-free set, where the
    /// winding number of a closed mesh is constant (see the [module
    /// docs](super)).
    fn flood_signs(
        &self,
        wn: &WindingNumber,
        lattice: &Lattice,
        grid: &Bricks<f32>,
        blocks: &[(BlockNearest, Vec<LatticeHit>)],
        inside: &mut [bool],
    ) -> Vec<bool> {
        let (bricks, count, dims) = (grid.brick_dims(), blocks.len(), lattice.dims);
        let last = dims - UVec3::ONE;
        // Link limits, as `propagate_signs`: the step plus rounding.
        let reach = lattice.origin.abs().max(lattice.position(last.x, last.y, last.z).abs()).max_element();
        let slack = 4.0 * f32::EPSILON * reach + f32::MIN_POSITIVE;
        let limits = lattice.step.abs() * (1.0 + LINK_MARGIN) + Vec3::splat(slack);
        let overlap = |a: f32, b: f32, gap: f32| a + b > gap * (1.0 + LINK_MARGIN) + slack;
        let in_lattice = |c: UVec3| c.cmple(last).all();
        // Regions within each band brick.
        let slots: Vec<usize> = (0..count).filter(|&b| !blocks[b].1.is_empty()).collect();
        let regions: Vec<Regions> = slots
            .par_iter()
            .map(|&brick| {
                let (lo, hits) = (brick_origin(bricks, brick), &blocks[brick].1);
                let mut sets = Sets::new(NODES);
                for n in 0..NODES {
                    let c = lo + offset(n);
                    if !in_lattice(c) {
                        continue;
                    }
                    for axis in 0..3 {
                        let step = UVec3::AXES[axis];
                        let (l, e) = (offset(n) + step, c + step);
                        if l[axis] < BRICK
                            && in_lattice(e)
                            && hits[n].distance + hits[local(l)].distance > limits[axis]
                        {
                            sets.union(n as u32, local(l) as u32);
                        }
                    }
                }
                let mut label = vec![u16::MAX; NODES];
                let mut first = Vec::new();
                for n in 0..NODES {
                    if in_lattice(lo + offset(n)) {
                        let root = sets.find(n as u32) as usize;
                        if label[root] == u16::MAX {
                            label[root] = first.len() as u16;
                            first.push(root as u16);
                        }
                        label[n] = label[root];
                    }
                }
                Regions { label, first }
            })
            .collect();
        // Ids: far bricks by brick index, then each band brick's regions.
        let mut base = vec![0u32; count];
        let mut next = count as u32;
        for (&brick, r) in slots.iter().zip(&regions) {
            base[brick] = next;
            next += r.first.len() as u32;
        }
        let slot_of: Vec<Option<usize>> = (0..count).map(|b| grid.slot_of(b)).collect();
        let id = |brick: usize, n: usize| base[brick] + u32::from(regions[slot_of[brick].unwrap()].label[n]);
        let mut sets = Sets::new(next as usize);
        let strides = [1, bricks.x as usize, bricks.x as usize * bricks.y as usize];
        for brick in 0..count {
            let lo = brick_origin(bricks, brick);
            for axis in 0..3 {
                if lo[axis] / BRICK + 1 >= bricks[axis] {
                    continue;
                }
                let other = brick + strides[axis];
                let (a, b) = (&blocks[brick], &blocks[other]);
                match (a.1.is_empty(), b.1.is_empty()) {
                    (true, true) => {
                        if overlap(a.0.distance, b.0.distance, (a.0.center - b.0.center).length()) {
                            sets.union(brick as u32, other as u32);
                        }
                    }
                    (far_a, _) => {
                        // The face between them: nodes of `brick` at offset
                        // BRICK − 1 along `axis`, of `other` at 0.
                        for u in 0..BRICK {
                            for v in 0..BRICK {
                                let mut l = UVec3::ZERO;
                                l[(axis + 1) % 3] = u;
                                l[(axis + 2) % 3] = v;
                                let (mut la, lb) = (l, l);
                                la[axis] = BRICK - 1;
                                let (ca, cb) = (lo + la, lo + la + UVec3::AXES[axis]);
                                if !in_lattice(cb) {
                                    continue;
                                }
                                let (na, nb) = (local(la), local(lb));
                                if far_a {
                                    let p = lattice.position(cb.x, cb.y, cb.z);
                                    if overlap(b.1[nb].distance, a.0.distance, (p - a.0.center).length()) {
                                        sets.union(brick as u32, id(other, nb));
                                    }
                                } else if b.1.is_empty() {
                                    let p = lattice.position(ca.x, ca.y, ca.z);
                                    if overlap(a.1[na].distance, b.0.distance, (p - b.0.center).length()) {
                                        sets.union(id(brick, na), other as u32);
                                    }
                                } else if a.1[na].distance + b.1[nb].distance > limits[axis] {
                                    sets.union(id(brick, na), id(other, nb));
                                }
                            }
                        }
                    }
                }
            }
        }
        // One winding number per region, at a point of it.
        let roots: Vec<u32> = (0..next).map(|i| sets.find(i)).collect();
        let point = |i: u32| -> Vec3 {
            let i = i as usize;
            if i < count {
                return blocks[i].0.center;
            }
            let k = slots.partition_point(|&b| base[b] as usize <= i) - 1;
            let (brick, r) = (slots[k], &regions[k]);
            let c = brick_origin(bricks, brick) + offset(usize::from(r.first[i - base[brick] as usize]));
            lattice.position(c.x, c.y, c.z)
        };
        let own: Vec<u32> = (0..next).filter(|&i| roots[i as usize] == i).collect();
        let signs: Vec<bool> = own.par_iter().map(|&i| wn.is_inside(point(i))).collect();
        let mut root_inside = vec![false; next as usize];
        for (&i, &s) in own.iter().zip(&signs) {
            root_inside[i as usize] = s;
        }
        inside.par_chunks_mut(NODES).zip(&slots).zip(&regions).for_each(|((inside, &brick), r)| {
            for (out, &label) in inside.iter_mut().zip(&r.label) {
                if label != u16::MAX {
                    *out = root_inside[roots[(base[brick] + u32::from(label)) as usize] as usize];
                }
            }
        });
        (0..count).map(|b| root_inside[roots[b] as usize]).collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::grid::lattice_for_box;
    use crate::mesh::bvh::Lattice;
    use crate::mesh::metrics::test_meshes::{bunny, cube, read_obj, torus};
    use crate::sdf::{MeshSdf, SdfSettings, SignMode};
    use crate::{Aabb, Bricks};
    use glam::{Affine3A, Quat, Vec3};

    /// The band bricks of a mesh hold the dense lattice sample's values
    /// bitwise at every node within the band, and every node reads the
    /// dense sample's side, in both sign modes: on a closed mesh (the bunny:
    /// signs flooded by region), an open one (the teapot: the winding number
    /// at every band node), a tube under two voxels across and a tilted
    /// sheet a fifth of a voxel thick (closed: the regions on its two sides
    /// must stay apart). The per-point path agrees on every side (on the
    /// open mesh with the winding number only).
    #[test]
    fn band_bricks_equal_the_dense_sample_near_the_surface() {
        let teapot = read_obj(concat!(env!("CARGO_MANIFEST_DIR"), "/../data/teapot.obj"));
        let tilt = Affine3A::from_quat(Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.2, 0.1));
        let sheet = cube(1.0).transformed(&(tilt * Affine3A::from_scale(Vec3::new(1.0, 0.004, 1.0))));
        let cases = [
            ("bunny", bunny(), 61),
            ("teapot", teapot, 53),
            ("thin torus", torus(1.0, 0.03, 64, 12), 59),
            ("sheet", sheet, 57),
        ];
        for (name, mesh, res) in cases {
            let closed = name != "teapot";
            for sign in [SignMode::WindingNumber, SignMode::Pseudonormal] {
                let sdf = MeshSdf::with_settings(&mesh, SdfSettings::default().with_sign(sign)).unwrap();
                assert_eq!(sdf.is_closed(), closed, "{name}");
                // A cube about the mesh, so that thin meshes have far bricks too.
                let (b, pad) = (mesh.bounds(), 0.2 * mesh.bounds().size().max_element());
                let half = Vec3::splat(0.5 * b.size().max_element() + pad);
                let bounds = Aabb::new(b.center() - half, b.center() + half);
                let (dims, origin, h) = lattice_for_box(&bounds, res).unwrap();
                let band = 3.0 * h;
                let dense = sdf.sample_lattice(&Lattice { dims, origin, step: Vec3::splat(h) });
                let sparse = sdf.sample_band_bricks(dims, origin, h, band).unwrap();
                let by_points = Bricks::sample_band_by_points(&sdf, dims, origin, h, band).unwrap();
                let (mut in_band, mut inside) = (0, 0);
                for (n, &d) in dense.iter().enumerate() {
                    let got = sparse[n];
                    assert_eq!(got > 0.0, d > 0.0, "{name}, {sign:?}: side of node {n}: {got} vs {d}");
                    // (An open mesh's pseudonormal side is only locally
                    // plausible: far from it, one centre per brick may differ.)
                    if closed || sign == SignMode::WindingNumber {
                        assert_eq!(by_points[n] > 0.0, d > 0.0, "{name}, {sign:?}: per point, node {n}");
                    }
                    if d.abs() <= band {
                        in_band += 1;
                        assert_eq!(got.to_bits(), d.to_bits(), "{name}, {sign:?}: node {n}: {got} vs {d}");
                        assert!(
                            (by_points[n] - d).abs() <= 1e-5 * h,
                            "{name}, {sign:?}: per point, node {n}"
                        );
                    }
                    inside += usize::from(d > 0.0);
                }
                assert!(in_band > 2000 && inside > 0, "{name}: {in_band} band nodes, {inside} inside");
                assert!(
                    sparse.allocated() * 2 < sparse.brick_count(),
                    "{name}: {} of {} bricks",
                    sparse.allocated(),
                    sparse.brick_count()
                );
            }
        }
    }
}
