//! The T-mesh: an octree over the domain `D = [−1, 1]³` adapted to surface
//! samples of both shapes (paper §3.2), its anchors (one control coefficient
//! per leaf vertex) and their local knot vectors found by ray casting
//! (note §3.2–3.3).
//!
//! Coordinates inside are integers on the finest lattice: with maximum depth
//! `d` the domain has `M = 2^d` finest cells per axis, lattice coordinate `k`
//! is the point `−1 + 2k/M`. A dense `M³` table maps each finest cell to its
//! leaf, which makes point location O(1) ("an octree or equivalent").

use crate::bspline::CubicPieces;
use crate::error::{TsplineError, check_range};
use glam::DVec3;
use rayon::prelude::*;

/// Largest accepted maximum depth (`128³` finest cells in the lookup table).
pub const MAX_DEPTH: u32 = 7;

/// How the octree T-mesh is built (paper §3.2, note §3.1).
#[derive(Debug, Clone, PartialEq)]
pub struct TMeshSettings {
    /// Split a cell holding more than this many surface samples (`n_T`).
    pub max_samples_per_cell: usize,
    /// Maximum subdivision depth (the paper never exceeds 6); at most
    /// [`MAX_DEPTH`].
    pub max_depth: u32,
    /// Every cell is split at least down to this depth, so that regions
    /// between the shapes keep degrees of freedom (note §3.1).
    pub min_depth: u32,
    /// Enforce 2:1 balance between face/edge/corner neighbours (note §3.1),
    /// which keeps blending-function supports short.
    pub balance: bool,
    /// Spacing of the uniform surface samples in domain units (the domain is
    /// 2 wide); a cell crossed by a flat surface holds about
    /// `(size / spacing)²` samples.
    pub sample_spacing: f64,
}

impl Default for TMeshSettings {
    fn default() -> Self {
        Self { max_samples_per_cell: 12, max_depth: 6, min_depth: 2, balance: true, sample_spacing: 0.05 }
    }
}

impl TMeshSettings {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) naming the first bad field.
    pub fn validate(&self) -> Result<(), TsplineError> {
        check_range("max_samples_per_cell", self.max_samples_per_cell as f64, 1.0, 1e9, ">= 1")?;
        check_range("max_depth", self.max_depth as f64, 1.0, MAX_DEPTH as f64, "1..=7")?;
        check_range("min_depth", self.min_depth as f64, 0.0, self.max_depth as f64, "0..=max_depth")?;
        check_range("sample_spacing", self.sample_spacing, 1e-4, 2.0, "1e-4..=2")
    }
}

/// One leaf cell: lattice corner and edge length (finest units).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Leaf {
    pub min: [i64; 3],
    pub size: i64,
}

impl Leaf {
    fn max(&self, axis: usize) -> i64 {
        self.min[axis] + self.size
    }
}

/// One anchor: a leaf vertex with its three local knot vectors (domain units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Anchor {
    /// Lattice position.
    pub pos: [i64; 3],
    /// Knot vectors per axis, domain units, strictly increasing.
    pub knots: [[f64; 5]; 3],
    /// The univariate B-splines on those knots as polynomial pieces.
    pub pieces: [CubicPieces; 3],
}

/// The octree T-mesh with anchors, knot vectors and per-leaf lists of the
/// blending functions that do not vanish on the leaf. Fixed during the whole
/// morph; frames only differ in their coefficients.
#[derive(Debug, Clone)]
pub struct TMesh {
    depth: u32,
    /// Finest cells per axis, `2^depth`.
    res: i64,
    leaves: Vec<Leaf>,
    /// Finest cell → leaf index, x fastest.
    lookup: Vec<u32>,
    anchors: Vec<Anchor>,
    /// Per leaf: anchors whose support meets the leaf's interior (ascending).
    leaf_anchors: Vec<Vec<u32>>,
    /// Per anchor: (leaf, position in that leaf's list).
    anchor_leaves: Vec<Vec<(u32, u32)>>,
    /// Per leaf: the distinct univariate factors of its blending functions.
    leaf_factors: Vec<LeafFactors>,
}

/// The univariate factors of a leaf's blending functions: per axis the
/// distinct B-splines among its anchors (neighbouring anchors share knot
/// vectors: a uniform region has 4 per axis for 64 anchors), and for each
/// anchor of the leaf's list its index into each axis. Evaluating the
/// distinct factors once per point, instead of three per anchor, makes a
/// leaf's basis cheap.
#[derive(Debug, Clone, Default)]
pub(crate) struct LeafFactors {
    /// Distinct B-splines per axis.
    pub axes: [Vec<CubicPieces>; 3],
    /// Per anchor of the leaf (list order): its factor per axis.
    pub index: Vec<[u16; 3]>,
}

impl TMesh {
    /// Builds the T-mesh from surface samples (domain coordinates; points
    /// outside `D` are ignored) by octree subdivision of every cell holding
    /// more than `n_T` samples, then anchors and knot vectors.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) for invalid settings.
    pub fn build(samples: &[DVec3], settings: &TMeshSettings) -> Result<Self, TsplineError> {
        settings.validate()?;
        let depth = settings.max_depth;
        let res = 1i64 << depth;
        let to_lattice = |p: DVec3| -> Option<[i64; 3]> {
            let q = (p + DVec3::ONE) * 0.5 * res as f64;
            if !q.is_finite() || q.min_element() < 0.0 || q.max_element() > res as f64 {
                return None;
            }
            Some(std::array::from_fn(|a| (q[a].floor() as i64).min(res - 1)))
        };
        let cells: Vec<[i64; 3]> = samples.iter().filter_map(|&p| to_lattice(p)).collect();
        let mut leaves = Vec::new();
        subdivide(Leaf { min: [0; 3], size: res }, 0, cells, settings, &mut leaves);
        let mut lookup = build_lookup(&leaves, res);
        if settings.balance {
            (leaves, lookup) = balance(leaves, lookup, res);
        }
        Ok(Self::with_leaves(depth, res, leaves, lookup))
    }

    /// A finer T-mesh (the paper's "final refinement", §3.2): the leaves
    /// containing one of `points` (domain coordinates) are split into eight,
    /// then the tree is 2:1 balanced again. Leaves already at the maximum
    /// depth stay as they are, so the result may equal `self`; points
    /// outside the domain are ignored.
    ///
    /// The 2:1 balance of the result holds even when `self` was built
    /// without it (refinement never leaves an unbalanced tree behind).
    pub fn refined(&self, points: &[DVec3]) -> TMesh {
        let mut split: Vec<usize> = points
            .iter()
            .filter(|p| p.abs().max_element() <= 1.0)
            .map(|&p| self.locate(p))
            .filter(|&l| self.leaves[l].size > 1)
            .collect();
        split.sort_unstable();
        split.dedup();
        let leaves = split_leaves(&self.leaves, &split);
        let lookup = build_lookup(&leaves, self.res);
        let (leaves, lookup) = balance(leaves, lookup, self.res);
        Self::with_leaves(self.depth, self.res, leaves, lookup)
    }

    /// Whether neighbouring leaves (face, edge or corner) differ by at most
    /// one level.
    pub fn is_balanced(&self) -> bool {
        unbalanced(&self.leaves, &self.lookup, self.res).is_none()
    }

    /// Completes a tree from its leaves: anchors, knots, incidence lists.
    fn with_leaves(depth: u32, res: i64, leaves: Vec<Leaf>, lookup: Vec<u32>) -> TMesh {
        let mut mesh = TMesh {
            depth,
            res,
            leaves,
            lookup,
            anchors: Vec::new(),
            leaf_anchors: Vec::new(),
            anchor_leaves: Vec::new(),
            leaf_factors: Vec::new(),
        };
        mesh.build_anchors();
        mesh
    }

    /// A uniform T-mesh: every cell at `depth` (a tensor-product tricubic
    /// B-spline space; the interior knot vectors are uniform).
    ///
    /// # Errors
    /// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) for `depth` outside `1..=MAX_DEPTH`.
    pub fn uniform(depth: u32) -> Result<Self, TsplineError> {
        let settings =
            TMeshSettings { min_depth: depth, max_depth: depth, balance: false, ..TMeshSettings::default() };
        Self::build(&[], &settings)
    }

    /// Number of leaf cells.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    /// Number of anchors = control coefficients `n`.
    pub fn anchor_count(&self) -> usize {
        self.anchors.len()
    }

    /// Maximum depth (the lookup table's resolution is `2^depth`).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Edge length of the smallest leaf, domain units.
    pub fn finest_cell(&self) -> f64 {
        let s = self.leaves.iter().map(|l| l.size).min().unwrap_or(self.res);
        self.lattice_len(s)
    }

    /// Edge lengths of all leaves, domain units (for statistics).
    pub fn leaf_sizes(&self) -> Vec<f64> {
        self.leaves.iter().map(|l| self.lattice_len(l.size)).collect()
    }

    /// The position (domain units) of anchor `i`.
    ///
    /// # Panics
    /// If `i >= anchor_count()`.
    pub fn anchor_position(&self, i: usize) -> DVec3 {
        let p = self.anchors[i].pos;
        DVec3::new(self.coord(p[0]), self.coord(p[1]), self.coord(p[2]))
    }

    /// The knot vectors (x, y, z; domain units) of anchor `i`.
    ///
    /// # Panics
    /// If `i >= anchor_count()`.
    pub fn anchor_knots(&self, i: usize) -> [[f64; 5]; 3] {
        self.anchors[i].knots
    }

    /// Mean number of blending functions that are non-zero on a leaf.
    pub fn mean_support(&self) -> f64 {
        let total: usize = self.leaf_anchors.iter().map(Vec::len).sum();
        total as f64 / self.leaves.len().max(1) as f64
    }

    pub(crate) fn anchors(&self) -> &[Anchor] {
        &self.anchors
    }

    pub(crate) fn leaf_anchors(&self, leaf: usize) -> &[u32] {
        &self.leaf_anchors[leaf]
    }

    pub(crate) fn anchor_leaves(&self, anchor: usize) -> &[(u32, u32)] {
        &self.anchor_leaves[anchor]
    }

    pub(crate) fn leaf_factors(&self, leaf: usize) -> &LeafFactors {
        &self.leaf_factors[leaf]
    }

    /// Finest lattice cells per axis.
    pub(crate) fn resolution(&self) -> i64 {
        self.res
    }

    /// Domain coordinate of lattice coordinate `k`.
    pub(crate) fn coord(&self, k: i64) -> f64 {
        -1.0 + 2.0 * k as f64 / self.res as f64
    }

    /// The number of finest lattice cells (`res³`), indexed as
    /// [`TMesh::leaf_cells`] does.
    pub(crate) fn finest_cells(&self) -> usize {
        (self.res * self.res * self.res) as usize
    }

    /// The centre (domain units) of finest lattice cell `cell` (indexed as
    /// [`TMesh::leaf_cells`] does).
    pub(crate) fn finest_cell_centre(&self, cell: usize) -> DVec3 {
        let (res, cell) = (self.res, cell as i64);
        let centre = |k: i64| 0.5 * (self.coord(k) + self.coord(k + 1));
        DVec3::new(centre(cell % res), centre((cell / res) % res), centre(cell / (res * res)))
    }

    fn lattice_len(&self, k: i64) -> f64 {
        2.0 * k as f64 / self.res as f64
    }

    /// Domain box of a leaf.
    pub(crate) fn leaf_box(&self, leaf: usize) -> (DVec3, DVec3) {
        let l = self.leaves[leaf];
        let lo = DVec3::new(self.coord(l.min[0]), self.coord(l.min[1]), self.coord(l.min[2]));
        (lo, lo + DVec3::splat(self.lattice_len(l.size)))
    }

    /// The finest lattice cell `[x, y, z]` containing `p` (clamped into the
    /// domain; index `(z · res + y) · res + x`).
    pub(crate) fn cell_of(&self, p: DVec3) -> [i64; 3] {
        let q = (p + DVec3::ONE) * 0.5 * self.res as f64;
        let idx = |v: f64| -> i64 { if v.is_nan() { 0 } else { (v.floor() as i64).clamp(0, self.res - 1) } };
        [idx(q.x), idx(q.y), idx(q.z)]
    }

    /// The indices `(z · res + y) · res + x` of the finest lattice cells
    /// that leaf `leaf` covers.
    pub(crate) fn leaf_cells(&self, leaf: usize) -> impl Iterator<Item = usize> + '_ {
        let l = self.leaves[leaf];
        let res = self.res;
        (l.min[2]..l.min[2] + l.size).flat_map(move |z| {
            (l.min[1]..l.min[1] + l.size).flat_map(move |y| {
                (l.min[0]..l.min[0] + l.size).map(move |x| ((z * res + y) * res + x) as usize)
            })
        })
    }

    /// The leaf containing `p` (clamped into the domain; half-open cells,
    /// the upper domain faces belong to the last cells).
    pub(crate) fn locate(&self, p: DVec3) -> usize {
        self.lookup_cell(self.cell_of(p))
    }

    fn lookup_cell(&self, c: [i64; 3]) -> usize {
        self.lookup[((c[2] * self.res + c[1]) * self.res + c[0]) as usize] as usize
    }

    /// Anchors at every leaf vertex (hanging ones included), their knots by
    /// ray casting, and the leaf ↔ anchor incidence lists.
    fn build_anchors(&mut self) {
        let mut positions: Vec<[i64; 3]> = self
            .leaves
            .iter()
            .flat_map(|l| {
                (0..8).map(move |c| {
                    std::array::from_fn(|a| l.min[a] + if c >> a & 1 == 1 { l.size } else { 0 })
                })
            })
            .collect();
        positions.sort_unstable_by_key(|p| [p[2], p[1], p[0]]);
        positions.dedup();
        let anchors: Vec<Anchor> = positions
            .par_iter()
            .map(|&pos| {
                let knots = std::array::from_fn(|axis| {
                    let k = self.knot_vector(pos, axis);
                    k.map(|v| self.coord(v))
                });
                Anchor { pos, knots, pieces: knots.map(|k| CubicPieces::new(&k)) }
            })
            .collect();
        self.anchors = anchors;
        // Leaf → anchors whose open support box meets the open leaf. Anchors
        // are bucketed on a coarse grid of their support boxes first.
        let bins = 8i64.min(self.res);
        let bin_size = self.res / bins;
        let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); (bins * bins * bins) as usize];
        let to_bin = |v: f64, up: bool| -> i64 {
            let k = (v + 1.0) * 0.5 * self.res as f64 / bin_size as f64;
            let b = if up { k.ceil() as i64 - 1 } else { k.floor() as i64 };
            b.clamp(0, bins - 1)
        };
        for (i, a) in self.anchors.iter().enumerate() {
            let lo: [i64; 3] = std::array::from_fn(|ax| to_bin(a.knots[ax][0], false));
            let hi: [i64; 3] = std::array::from_fn(|ax| to_bin(a.knots[ax][4], true));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        buckets[((z * bins + y) * bins + x) as usize].push(i as u32);
                    }
                }
            }
        }
        let leaf_anchors: Vec<Vec<u32>> = (0..self.leaves.len())
            .into_par_iter()
            .map(|li| {
                let (lo, hi) = self.leaf_box(li);
                let l = self.leaves[li];
                let blo: [i64; 3] = std::array::from_fn(|a| l.min[a] / bin_size);
                let bhi: [i64; 3] = std::array::from_fn(|a| ((l.max(a) - 1) / bin_size).min(bins - 1));
                let mut list = Vec::new();
                for z in blo[2]..=bhi[2] {
                    for y in blo[1]..=bhi[1] {
                        for x in blo[0]..=bhi[0] {
                            for &i in &buckets[((z * bins + y) * bins + x) as usize] {
                                let k = &self.anchors[i as usize].knots;
                                if (0..3).all(|a| k[a][0] < hi[a] && k[a][4] > lo[a]) {
                                    list.push(i);
                                }
                            }
                        }
                    }
                }
                list.sort_unstable();
                list.dedup();
                list
            })
            .collect();
        let mut anchor_leaves = vec![Vec::new(); self.anchors.len()];
        for (li, list) in leaf_anchors.iter().enumerate() {
            for (pos, &a) in list.iter().enumerate() {
                anchor_leaves[a as usize].push((li as u32, pos as u32));
            }
        }
        self.leaf_factors = leaf_anchors
            .par_iter()
            .map(|list| {
                let mut f = LeafFactors::default();
                for &i in list {
                    let a = &self.anchors[i as usize];
                    let index = std::array::from_fn(|axis| {
                        let distinct = &mut f.axes[axis];
                        let at = distinct.iter().position(|pc| *pc == a.pieces[axis]).unwrap_or_else(|| {
                            distinct.push(a.pieces[axis]);
                            distinct.len() - 1
                        });
                        u16::try_from(at).expect("fewer than 2^16 knot vectors per leaf")
                    });
                    f.index.push(index);
                }
                f
            })
            .collect();
        self.leaf_anchors = leaf_anchors;
        self.anchor_leaves = anchor_leaves;
    }

    /// Sederberg's ray casting in 3D (note §3.3): the two nearest face
    /// planes perpendicular to `axis` met by rays from `pos` in ±axis, with
    /// the last spacing repeated outside the domain.
    fn knot_vector(&self, pos: [i64; 3], axis: usize) -> [i64; 5] {
        let s = pos[axis];
        let fwd1 = self.next_knot(pos, axis, true);
        let back1 = self.next_knot(pos, axis, false);
        let (k3, k1) = match (fwd1, back1) {
            (Some(f), Some(b)) => (f, b),
            (Some(f), None) => (f, s - (f - s)),
            (None, Some(b)) => (s + (s - b), b),
            (None, None) => (s + self.res, s - self.res),
        };
        let along = |from: i64, forward: bool, step: i64| -> i64 {
            let mut p = pos;
            p[axis] = from;
            let inside = (0..=self.res).contains(&from);
            match inside.then(|| self.next_knot(p, axis, forward)).flatten() {
                Some(k) => k,
                None if forward => from + step,
                None => from - step,
            }
        };
        let k4 = along(k3, true, k3 - s);
        let k0 = along(k1, false, s - k1);
        [k0, k1, s, k3, k4]
    }

    /// The next face plane perpendicular to `axis` that the ray from `pos`
    /// in direction ±axis meets (lattice units), or `None` when the ray
    /// leaves the domain first.
    fn next_knot(&self, pos: [i64; 3], axis: usize, forward: bool) -> Option<i64> {
        let s = pos[axis];
        let cell = if forward { s } else { s - 1 };
        if cell < 0 || cell >= self.res {
            return None;
        }
        let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut best: Option<i64> = None;
        for d1 in [pos[a1] - 1, pos[a1]] {
            for d2 in [pos[a2] - 1, pos[a2]] {
                if d1 < 0 || d1 >= self.res || d2 < 0 || d2 >= self.res {
                    continue;
                }
                let mut c = [0i64; 3];
                c[axis] = cell;
                c[a1] = d1;
                c[a2] = d2;
                let leaf = self.leaves[self.lookup_cell(c)];
                let k = if forward { leaf.max(axis) } else { leaf.min[axis] };
                best = Some(match best {
                    None => k,
                    Some(b) if forward => b.min(k),
                    Some(b) => b.max(k),
                });
            }
        }
        best
    }
}

fn children(leaf: &Leaf) -> [Leaf; 8] {
    let h = leaf.size / 2;
    std::array::from_fn(|c| Leaf {
        min: std::array::from_fn(|a| leaf.min[a] + if c >> a & 1 == 1 { h } else { 0 }),
        size: h,
    })
}

fn subdivide(leaf: Leaf, depth: u32, cells: Vec<[i64; 3]>, settings: &TMeshSettings, out: &mut Vec<Leaf>) {
    let split = depth < settings.max_depth
        && (depth < settings.min_depth || cells.len() > settings.max_samples_per_cell);
    if !split {
        out.push(leaf);
        return;
    }
    let h = leaf.size / 2;
    let mut parts: [Vec<[i64; 3]>; 8] = Default::default();
    for c in cells {
        let o = (0..3).fold(0, |o, a| o | (usize::from(c[a] >= leaf.min[a] + h) << a));
        parts[o].push(c);
    }
    for (child, part) in children(&leaf).into_iter().zip(parts) {
        subdivide(child, depth + 1, part, settings, out);
    }
}

/// `leaves` with the leaves at the sorted indices `split` replaced by their
/// eight children.
fn split_leaves(leaves: &[Leaf], split: &[usize]) -> Vec<Leaf> {
    let mut next = Vec::with_capacity(leaves.len() + 7 * split.len());
    for (i, leaf) in leaves.iter().enumerate() {
        if split.binary_search(&i).is_ok() {
            next.extend(children(leaf));
        } else {
            next.push(*leaf);
        }
    }
    next
}

/// Splits leaves until neighbours differ by at most one level; returns the
/// leaves and their lookup table.
fn balance(mut leaves: Vec<Leaf>, mut lookup: Vec<u32>, res: i64) -> (Vec<Leaf>, Vec<u32>) {
    while let Some(split) = unbalanced(&leaves, &lookup, res) {
        leaves = split_leaves(&leaves, &split);
        lookup = build_lookup(&leaves, res);
    }
    (leaves, lookup)
}

fn build_lookup(leaves: &[Leaf], res: i64) -> Vec<u32> {
    let mut lookup = vec![0u32; (res * res * res) as usize];
    for (i, l) in leaves.iter().enumerate() {
        for z in l.min[2]..l.max(2) {
            for y in l.min[1]..l.max(1) {
                let row = ((z * res + y) * res) as usize;
                lookup[row + l.min[0] as usize..row + l.max(0) as usize].fill(i as u32);
            }
        }
    }
    lookup
}

/// Leaves (sorted indices) with a neighbour (face, edge or corner) less than
/// half their size, or `None` when the tree is 2:1 balanced.
fn unbalanced(leaves: &[Leaf], lookup: &[u32], res: i64) -> Option<Vec<usize>> {
    let split: Vec<usize> = (0..leaves.len())
        .into_par_iter()
        .filter(|&i| {
            let l = leaves[i];
            if l.size <= 2 {
                return false;
            }
            // Scan the one-cell-thick shell around the leaf.
            let lo: [i64; 3] = std::array::from_fn(|a| (l.min[a] - 1).max(0));
            let hi: [i64; 3] = std::array::from_fn(|a| (l.max(a) + 1).min(res));
            for z in lo[2]..hi[2] {
                for y in lo[1]..hi[1] {
                    for x in lo[0]..hi[0] {
                        let c = [x, y, z];
                        if (0..3).all(|a| c[a] >= l.min[a] && c[a] < l.max(a)) {
                            continue;
                        }
                        let n = leaves[lookup[((z * res + y) * res + x) as usize] as usize];
                        if 2 * n.size < l.size {
                            return true;
                        }
                    }
                }
            }
            false
        })
        .collect();
    (!split.is_empty()).then_some(split)
}

/// A map from lattice position to anchor index (tests and diagnostics).
#[cfg(test)]
pub(crate) fn anchor_index(mesh: &TMesh) -> std::collections::HashMap<[i64; 3], usize> {
    mesh.anchors.iter().enumerate().map(|(i, a)| (a.pos, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mesh_has_uniform_interior_knots() {
        let m = TMesh::uniform(3).unwrap();
        assert_eq!(m.leaf_count(), 512);
        assert_eq!(m.anchor_count(), 9 * 9 * 9);
        let idx = anchor_index(&m);
        let i = idx[&[4, 4, 4]];
        let h = 0.25;
        for axis in 0..3 {
            let k = m.anchor_knots(i)[axis];
            for (j, v) in k.iter().enumerate() {
                assert!((v - (j as f64 - 2.0) * h).abs() < 1e-12, "{k:?}");
            }
        }
        // Boundary anchors extend with the last spacing.
        let k = m.anchor_knots(idx[&[0, 4, 4]])[0];
        assert!((k[0] + 1.5).abs() < 1e-12 && (k[4] + 0.5).abs() < 1e-12, "{k:?}");
        // 4³ blending functions on an interior leaf, fewer at the border.
        assert_eq!(m.leaf_anchors(m.locate(DVec3::splat(0.1))).len(), 64);
        assert_eq!(m.leaf_anchors(m.locate(DVec3::splat(-0.99))).len(), 27);
    }

    #[test]
    fn refined_mesh_knots_are_strictly_increasing_and_symmetric() {
        // Samples on a sphere: an adapted, mirror-symmetric octree.
        let mut pts = Vec::new();
        for i in 0..2000 {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / 2000.0;
            let r = (1.0 - z * z).sqrt();
            let phi = i as f64 * 2.399_963;
            let p = DVec3::new(r * phi.cos(), r * phi.sin(), z) * 0.5;
            pts.push(p);
            pts.push(DVec3::new(-p.x, p.y, p.z));
        }
        let m = TMesh::build(&pts, &TMeshSettings { max_depth: 5, ..Default::default() }).unwrap();
        assert!(m.leaf_count() > 64);
        let idx = anchor_index(&m);
        for (i, a) in m.anchors().iter().enumerate() {
            for k in a.knots {
                assert!(k.windows(2).all(|w| w[0] < w[1]), "anchor {i}: {k:?}");
            }
            // Mirror in x: the mirrored anchor exists and has mirrored knots
            // (when the tree itself is mirror symmetric at that anchor).
            let r = m.resolution();
            let mirror = [r - a.pos[0], a.pos[1], a.pos[2]];
            if let Some(&j) = idx.get(&mirror) {
                let kx = m.anchors()[j].knots[0];
                for (t, k) in kx.iter().enumerate() {
                    assert!((k + a.knots[0][4 - t]).abs() < 1e-12);
                }
            }
        }
        // Balanced: neighbours differ by at most one level.
        assert!(m.is_balanced());
    }

    #[test]
    fn refinement_splits_the_leaves_at_the_points_and_keeps_the_balance() {
        let coarse =
            TMesh::build(&[], &TMeshSettings { max_depth: 4, min_depth: 1, ..Default::default() }).unwrap();
        assert_eq!(coarse.leaf_count(), 8);
        let p = DVec3::new(0.3, 0.3, 0.3);
        let once = coarse.refined(&[p]);
        assert_eq!(once.leaf_count(), 15);
        assert!(once.leaf_sizes()[once.locate(p)] < coarse.leaf_sizes()[coarse.locate(p)]);
        // Refining the same corner twice more forces balancing splits around it.
        let deep = once.refined(&[p]).refined(&[p]);
        assert!((deep.leaf_sizes()[deep.locate(p)] - 0.125).abs() < 1e-12);
        assert!(deep.is_balanced());
        assert!(deep.leaf_count() > 15 + 7 + 7, "balancing split neighbours: {}", deep.leaf_count());
        // At the maximum depth nothing changes; outside points are ignored.
        let finest = TMesh::uniform(2).unwrap().refined(&[p]);
        assert_eq!(finest.leaf_count(), 64);
        assert_eq!(coarse.refined(&[DVec3::splat(3.0)]).leaf_count(), 8);
    }

    #[test]
    fn bad_settings_are_errors() {
        let s = TMeshSettings { max_depth: 9, ..Default::default() };
        assert!(matches!(
            TMesh::build(&[], &s),
            Err(TsplineError::Morph(isomorph_common::MorphError::BadSetting { name: "max_depth", .. }))
        ));
        let s = TMeshSettings { sample_spacing: f64::NAN, ..Default::default() };
        assert!(TMesh::build(&[], &s).is_err());
    }
}
