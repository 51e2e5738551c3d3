//! Polygonization that evaluates the (expensive, `O(n)` per point) field
//! only near the surface: coarse-to-fine sparse blocks.
//!
//! The lattice of [`Grid3::sample_box`] is split into blocks of `block³`
//! cells and the field is evaluated at their corners. A block is *active*
//! (may hold surface) when its corners differ in sign or one is not
//! finite; otherwise:
//! - when the field bounds its values over the block ([`Field3::range`]),
//!   the block is active unless those bounds keep `iso` out. This is a
//!   proof, so such fields lose no surface: a BlobTree, exactly `−T` outside
//!   its primitives' supports, implements it;
//! - otherwise a local Lipschitz estimate `L` (the largest difference
//!   quotient along the edges of the block and its face neighbours, times a
//!   safety factor) marks it active when `L = 0` (every one of those
//!   corners has the same value: flat samples say nothing of what lies
//!   between them) or when the smallest `|f − iso|` at a corner is within
//!   `L ·` half the block diagonal.
//!
//! Active blocks are halved along each axis, their children's corners
//! evaluated in one batch per level, and tested again (with their own
//! bounds, or their own half diagonal and `L`: the parent's, or the
//! children's own edge quotients if steeper), down to single cells. Every
//! node no active block evaluated takes the (common) sign of its inactive
//! block's corners. Marching cubes on that grid then gives **exactly the
//! same mesh as the full grid** whenever no piece of surface hides entirely
//! inside an inactive block — which a sound [`Field3::range`] rules out,
//! and the Lipschitz test rules out unless the field varies faster than
//! `L` there (tested against the full grid).

use super::marching_cubes;
use crate::grid::lattice_for_box;
use crate::morph::MorphError;
use crate::{Aabb, Field3, Grid3, TriMesh};
use glam::{UVec3, Vec3};

/// Settings of [`polygonize_near_surface`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SparseSettings {
    /// Cells per block edge (default 4).
    pub block: u32,
    /// Factor (≥ 1) on the estimated local Lipschitz constant (default 1; raise
    /// it for fields with features much smaller than a block).
    pub safety: f32,
}

impl Default for SparseSettings {
    fn default() -> Self {
        Self { block: 4, safety: 1.0 }
    }
}

/// What the sparse polygonizer did.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct SparseStats {
    /// Nodes of the full lattice.
    pub nodes: usize,
    /// Nodes evaluated (the corners of the blocks of every level).
    pub evaluated: usize,
    /// Active blocks, summed over the levels.
    pub active_blocks: usize,
    /// Top-level blocks.
    pub blocks: usize,
}

/// The mesh of `field`'s level set `iso` on the lattice of
/// [`Grid3::sample_box`]`(bounds, res)`, evaluating the field only near the
/// surface (see [`crate::marching_cubes`]).
///
/// # Errors
/// [`MorphError::Grid`] for a bad box, `res < 2` or a lattice too large;
/// [`MorphError::BadSetting`] for `block < 1` or a safety factor below 1.
pub fn polygonize_near_surface<F: Field3 + ?Sized>(
    field: &F,
    bounds: &Aabb,
    res: u32,
    iso: f32,
    settings: &SparseSettings,
) -> Result<(TriMesh, SparseStats), MorphError> {
    if settings.block < 1 {
        return Err(MorphError::bad_setting("block", settings.block, "at least 1 cell"));
    }
    if !(settings.safety >= 1.0 && settings.safety.is_finite()) {
        return Err(MorphError::bad_setting("safety", settings.safety, "a finite number ≥ 1"));
    }
    let (dims, origin, h) = lattice_for_box(bounds, res)?;
    let mut grid = Grid3::new(dims, origin, h, 0.0f32)?;
    let mut sampler =
        Sampler { field, grid: &mut grid, evaluated: vec![false; dims.element_product() as usize], count: 0 };
    // The top-level blocks and their corners.
    let b = settings.block;
    let nb = (dims - UVec3::ONE + UVec3::splat(b - 1)) / b;
    let top: Vec<Block> = (0..nb.element_product())
        .map(|n| {
            let a = UVec3::new(n % nb.x, (n / nb.x) % nb.y, n / (nb.x * nb.y));
            Block { lo: a * b, hi: ((a + UVec3::ONE) * b).min(dims - UVec3::ONE), lipschitz: 0.0 }
        })
        .collect();
    sampler.evaluate(top.iter().flat_map(Block::corners));
    // Local Lipschitz estimate of a top-level block: the steepest difference
    // quotient along its 12 edges, then the largest over the block and its
    // face neighbours.
    let own: Vec<f32> = top.iter().map(|block| block.steepest(sampler.grid)).collect();
    let mut level: Vec<Block> = top
        .iter()
        .enumerate()
        .map(|(n, block)| {
            let a = UVec3::new(n as u32 % nb.x, (n as u32 / nb.x) % nb.y, n as u32 / (nb.x * nb.y));
            let mut l = own[n];
            for axis in 0..3 {
                for step in [-1i64, 1] {
                    let c = i64::from(a[axis]) + step;
                    if c >= 0 && c < i64::from(nb[axis]) {
                        let mut m = a;
                        m[axis] = c as u32;
                        l = l.max(own[(m.x + nb.x * (m.y + nb.y * m.z)) as usize]);
                    }
                }
            }
            Block { lipschitz: settings.safety * l, ..*block }
        })
        .collect();
    // Coarse to fine: a block with a sign change among its corners, or a
    // corner within `L ·` half its diagonal of the level, is split in eight
    // (down to single cells); every other block has no surface and its
    // nodes take its corners' common sign.
    let (mut active_blocks, mut inactive) = (0, Vec::new());
    while !level.is_empty() {
        let mut next = Vec::new();
        for block in level {
            if !block.active(field, sampler.grid, iso) {
                inactive.push(block);
                continue;
            }
            active_blocks += 1;
            next.extend(block.children());
        }
        sampler.evaluate(next.iter().flat_map(Block::corners));
        for child in &mut next {
            child.lipschitz = child.lipschitz.max(settings.safety * child.steepest(sampler.grid));
        }
        level = next;
    }
    for block in &inactive {
        let fill = sampler.grid.get(block.lo.x, block.lo.y, block.lo.z).copied().unwrap_or(iso);
        for k in block.lo.z..=block.hi.z {
            for j in block.lo.y..=block.hi.y {
                for i in block.lo.x..=block.hi.x {
                    let n = sampler.grid.index(i, j, k);
                    if !sampler.evaluated[n] {
                        sampler.grid.data_mut()[n] = fill;
                    }
                }
            }
        }
    }
    let stats =
        SparseStats { nodes: sampler.grid.len(), evaluated: sampler.count, active_blocks, blocks: top.len() };
    Ok((marching_cubes(&grid, iso), stats))
}

/// A box of cells `[lo, hi]` (inclusive node range) of the lattice, with
/// the Lipschitz bound (times the safety factor) its test uses.
#[derive(Debug, Clone, Copy)]
struct Block {
    lo: UVec3,
    hi: UVec3,
    lipschitz: f32,
}

impl Block {
    /// The eight corner nodes.
    fn corners(&self) -> impl Iterator<Item = UVec3> + use<> {
        let (lo, hi) = (self.lo, self.hi);
        (0..8u32).map(move |q| {
            UVec3::new(pick(lo.x, hi.x, q & 1), pick(lo.y, hi.y, q & 2), pick(lo.z, hi.z, q & 4))
        })
    }

    /// The steepest difference quotient along the 12 edges (corners must be
    /// evaluated).
    fn steepest(&self, grid: &Grid3<f32>) -> f32 {
        let v = |c: UVec3| *grid.get(c.x, c.y, c.z).expect("corner inside the lattice");
        let mut l = 0.0f32;
        for c in self.corners() {
            for axis in 0..3 {
                if c[axis] == self.lo[axis] && self.hi[axis] > self.lo[axis] {
                    let mut d = c;
                    d[axis] = self.hi[axis];
                    let len = (self.hi[axis] - self.lo[axis]) as f32 * grid.spacing();
                    l = l.max((v(d) - v(c)).abs() / len);
                }
            }
        }
        l
    }

    /// Whether the surface may pass through: a sign change among the corners
    /// or a non-finite value (for a single cell, whose nodes are all
    /// evaluated, nothing else); otherwise, when the field bounds its values
    /// over the block ([`Field3::range`]), whether those bounds let the iso
    /// value in; otherwise a Lipschitz estimate of zero (corners of the
    /// block and its neighbours all equal: flat samples prove nothing, the
    /// surface may still pass between them) or a corner within `L ·` half
    /// the diagonal.
    fn active<F: Field3 + ?Sized>(&self, field: &F, grid: &Grid3<f32>, iso: f32) -> bool {
        let (mut inside, mut nearest) = (0, f32::INFINITY);
        for c in self.corners() {
            let v = *grid.get(c.x, c.y, c.z).expect("corner inside the lattice") - iso;
            if !v.is_finite() {
                return true;
            }
            inside += usize::from(v > 0.0);
            nearest = nearest.min(v.abs());
        }
        if inside != 0 && inside != 8 {
            return true;
        }
        if (self.hi - self.lo).max_element() <= 1 {
            // A single cell: all its nodes are evaluated, nothing to refine.
            return false;
        }
        let h = grid.spacing();
        // A hair of margin: the nodes' positions are rounded.
        let region = Aabb::new(grid.origin() + self.lo.as_vec3() * h, grid.origin() + self.hi.as_vec3() * h)
            .expanded(1e-4 * h);
        if let Some([lo, hi]) = field.range(&region) {
            // No node crosses when all are at most `iso` (outside) or all
            // above it (inside); NaN bounds keep the block.
            return !(hi <= iso || lo > iso);
        }
        if self.lipschitz == 0.0 {
            return true;
        }
        nearest <= 0.5 * self.lipschitz * ((self.hi - self.lo).as_vec3() * h).length()
    }

    /// The halves along every axis more than one cell long (up to eight
    /// children), or none for a single cell.
    fn children(&self) -> Vec<Block> {
        let size = self.hi - self.lo;
        if size.max_element() <= 1 {
            return Vec::new();
        }
        let halves = |axis: usize| -> Vec<(u32, u32)> {
            let (lo, hi) = (self.lo[axis], self.hi[axis]);
            if hi - lo <= 1 {
                vec![(lo, hi)]
            } else {
                let mid = lo + (hi - lo).div_ceil(2);
                vec![(lo, mid), (mid, hi)]
            }
        };
        let (xs, ys, zs) = (halves(0), halves(1), halves(2));
        let mut out = Vec::with_capacity(8);
        for &(z0, z1) in &zs {
            for &(y0, y1) in &ys {
                for &(x0, x1) in &xs {
                    let (lo, hi) = (UVec3::new(x0, y0, z0), UVec3::new(x1, y1, z1));
                    out.push(Block { lo, hi, lipschitz: self.lipschitz });
                }
            }
        }
        out
    }
}

/// `a` when `bit` is clear, else `b`.
fn pick(a: u32, b: u32, bit: u32) -> u32 {
    if bit == 0 { a } else { b }
}

/// Batch evaluation of lattice nodes, each at most once.
struct Sampler<'a, F: ?Sized> {
    field: &'a F,
    grid: &'a mut Grid3<f32>,
    evaluated: Vec<bool>,
    count: usize,
}

impl<F: Field3 + ?Sized> Sampler<'_, F> {
    /// Evaluates the nodes among `nodes` not evaluated yet, in one batch (at
    /// the positions `Grid3::fill_from` uses, so values match a full sample
    /// bit for bit).
    fn evaluate(&mut self, nodes: impl Iterator<Item = UVec3>) {
        let (origin, h) = (self.grid.origin(), self.grid.spacing());
        let mut todo = Vec::new();
        for c in nodes {
            let n = self.grid.index(c.x, c.y, c.z);
            if !self.evaluated[n] {
                self.evaluated[n] = true;
                todo.push(n);
            }
        }
        let pts: Vec<Vec3> = todo
            .iter()
            .map(|&n| {
                let c = self.grid.node_of(n);
                origin + h * Vec3::new(0.0, c.y as f32, c.z as f32) + Vec3::new(h * c.x as f32, 0.0, 0.0)
            })
            .collect();
        let mut vals = vec![0.0f32; pts.len()];
        self.field.values(&pts, &mut vals);
        for (&n, &v) in todo.iter().zip(&vals) {
            self.grid.data_mut()[n] = v;
        }
        self.count += todo.len();
    }
}

/// The mesh of `field`'s level set `iso` over `bounds` (grown by a hair so
/// that a surface on the box is still closed) with `res` nodes along the
/// longest edge, polygonized near the surface with the default settings.
///
/// # Errors
/// As [`polygonize_near_surface`].
pub fn level_set_mesh<F: Field3 + ?Sized>(
    field: &F,
    bounds: &Aabb,
    res: u32,
    iso: f32,
) -> Result<TriMesh, MorphError> {
    Ok(polygonize_near_surface(field, &bounds.expanded(1e-4), res, iso, &SparseSettings::default())?.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::marching_cubes::polygonize;
    use crate::{Shape, models};

    #[test]
    fn same_mesh_as_the_full_grid_with_fewer_evaluations() {
        // Exact distances, a CSG bound and a field far from a distance.
        let torus = models::torus();
        let c = models::c_shape();
        let squashed = |p: Vec3| (0.3 - p.length()) * (1.0 + 4.0 * p.x * p.x);
        let box_ = Aabb::cube(0.5);
        let fields: [&dyn Field3; 3] = [&torus, &c, &squashed];
        for field in fields {
            let full = polygonize(field, &box_, 40, 0.0).unwrap();
            let (sparse, stats) =
                polygonize_near_surface(field, &box_, 40, 0.0, &SparseSettings::default()).unwrap();
            assert_eq!(sparse.positions, full.positions);
            assert_eq!(sparse.triangles, full.triangles);
            assert!(!full.triangles.is_empty());
            assert!(stats.evaluated * 10 < stats.nodes * 6, "{stats:?}");
        }
        let f = |p: Vec3| 0.3 - p.length();
        assert!(polygonize_near_surface(&f, &Aabb::cube(0.5), 1, 0.0, &SparseSettings::default()).is_err());
        let bad = SparseSettings { block: 0, ..Default::default() };
        assert!(matches!(
            polygonize_near_surface(&f, &Aabb::cube(0.5), 8, 0.0, &bad),
            Err(MorphError::BadSetting { name: "block", .. })
        ));
        let sphere = level_set_mesh(&Shape::sphere(0.3), &box_, 32, 0.0).unwrap();
        assert_eq!(sphere.genus(), Some(0));
    }

    /// A compactly supported bump `(1 − r²/R²)³ − ½` around `centre`: flat
    /// (exactly `−½`) at distance ≥ `R`, like a BlobTree primitive.
    fn bump(centre: Vec3, radius: f32) -> impl Fn(Vec3) -> f32 + Sync {
        move |p: Vec3| {
            let x = (p - centre).length_squared() / (radius * radius);
            if x >= 1.0 { -0.5 } else { (1.0 - x).powi(3) - 0.5 }
        }
    }

    /// The bump with its exact value bounds over a box (the kernel is
    /// monotone in the distance to the centre).
    struct BoundedBump(Vec3, f32);

    impl Field3 for BoundedBump {
        fn value(&self, p: Vec3) -> f32 {
            bump(self.0, self.1)(p)
        }
        fn range(&self, region: &Aabb) -> Option<[f32; 2]> {
            let near = self.0.clamp(region.min, region.max);
            let far = Vec3::select((self.0 - region.min).cmpgt(region.max - self.0), region.min, region.max);
            Some([self.value(far), self.value(near)])
        }
    }

    /// Every triple of `xs` (the top-level block corners of a cubic lattice).
    fn triples(xs: &[f32]) -> Vec<(&f32, &f32, &f32)> {
        xs.iter().flat_map(|x| xs.iter().flat_map(move |y| xs.iter().map(move |z| (x, y, z)))).collect()
    }

    /// Regression (BlobMorph of `pierced_sphere` at res 16 came out empty):
    /// a surface whose field is flat at every top-level block corner was
    /// skipped, because the Lipschitz estimate from those corners is zero.
    /// The bump's support (radius 0.45 around `(−0.2)³`) holds no block
    /// corner (the nearest, `(−0.467)³` or `(0.067)³`, are 0.46 away).
    #[test]
    fn a_field_flat_at_every_block_corner_keeps_its_surface() {
        let (box_, res, centre, radius) = (Aabb::cube(1.0), 16, Vec3::splat(-0.2), 0.45);
        let (dims, origin, h) = lattice_for_box(&box_, res).unwrap();
        let at = |i: u32| origin.x + h * i.min(dims.x - 1) as f32;
        let corners: Vec<f32> = (0..=dims.x).step_by(4).map(at).collect();
        for (&x, &y, &z) in triples(&corners) {
            assert!(Vec3::new(x, y, z).distance(centre) > radius, "the test's premise");
        }
        let full = polygonize(&bump(centre, radius), &box_, res, 0.0).unwrap();
        assert!(!full.triangles.is_empty());
        assert_eq!(full.connected_components(), 1);
        assert_eq!(full.genus(), Some(0));
        // Without bounds from the field: flat samples are refined, not skipped.
        let (sparse, _) =
            polygonize_near_surface(&bump(centre, radius), &box_, res, 0.0, &SparseSettings::default())
                .unwrap();
        assert_eq!(sparse.triangles.len(), full.triangles.len());
        assert_eq!(sparse.positions, full.positions);
        assert_eq!(sparse.triangles, full.triangles);
        // With the field's own bounds: the same mesh, from far fewer values.
        let (bounded, stats) = polygonize_near_surface(
            &BoundedBump(centre, radius),
            &box_,
            res,
            0.0,
            &SparseSettings::default(),
        )
        .unwrap();
        assert_eq!(bounded.positions, full.positions);
        assert_eq!(bounded.triangles, full.triangles);
        assert!(stats.evaluated * 4 < stats.nodes, "{stats:?}");
        // The same through the boxed form the morphs' frames take.
        let boxed: crate::DynField = Box::new(BoundedBump(centre, radius));
        assert_eq!(level_set_mesh(&boxed, &box_, res, 0.0).unwrap().connected_components(), 1);
    }
}
