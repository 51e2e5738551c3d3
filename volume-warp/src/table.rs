//! Rapid evaluation of the B-spline map (thesis §5.2) and the deformation
//! mapping array.

use crate::basis::{weight_poly, weights};
use crate::{BSplineMap, WarpError};
use glam::{UVec3, Vec3, Vec3A, Vec4};
use isomorph_common::GridError;
use rayon::prelude::*;

/// The precomputed basis-weight products of eq. 4: for each of the `G³`
/// parameter triples `(ē, f̄, ḡ)`, the 64 weights `c[i][j][k]` with `i`
/// fastest.
///
/// When the source size is an integer multiple `G` of the region count along
/// each axis, the voxel `(e, f, g)` of region `(a, b, c)` always has the local
/// parameters `(ē/G, f̄/G, ḡ/G)` with `ē = e mod G`. The products of basis
/// weights therefore take only `G³` distinct sets of 64 values, precomputed
/// once as
///
/// `c[ē][f̄][ḡ][i][j][k] = Σ_{p,q,r} b_ip (ē/G)^p · b_jq (f̄/G)^q · b_kr (ḡ/G)^r`   (eq. 4)
///
/// ([`CoefficientTable`]), after which each voxel's image is one 64-term dot
/// product with the 64 control points of its region (eq. 5). The 64 entries
/// of a voxel are contiguous, and a region's 64 control displacements are
/// gathered once into three contiguous arrays, so the dot products vectorize.
///
/// [`DeformationArray`] holds `B` at every source voxel centre (the thesis'
/// deformation mapping array), filled by the table ([`Evaluation::Table`]) or
/// by direct basis evaluation ([`Evaluation::Direct`], any source size).
#[derive(Debug, Clone, PartialEq)]
pub struct CoefficientTable {
    granularity: UVec3,
    entries: Vec<[f32; 64]>,
}

impl CoefficientTable {
    /// The table for `map`'s lattice (it depends only on the lattice, not on
    /// the control point positions, so it survives every edit).
    ///
    /// # Errors
    /// [`WarpError::NotTableable`] when a source dimension is not an integer
    /// multiple of the region count along that axis; [`MorphError::Grid`](isomorph_common::MorphError::Grid)
    /// ([`GridError::TooLarge`]) when the table's `G³ · 64` weights (256
    /// bytes per entry) exceed the process-wide grid memory limit.
    pub fn new(map: &BSplineMap) -> Result<Self, WarpError> {
        let dims = map.source_dims();
        let regions = map.regions();
        if (dims % regions).cmpne(UVec3::ZERO).any() {
            return Err(WarpError::NotTableable { source_dims: dims, regions });
        }
        let g = dims / regions;
        let count = g.as_u64vec3().element_product();
        let requested = usize::try_from(count).unwrap_or(usize::MAX).saturating_mul(size_of::<[f32; 64]>());
        let limit = isomorph_common::memory_limit();
        if requested > limit {
            return Err(GridError::TooLarge { dims: g, requested, limit }.into());
        }
        // Per-axis basis values B_i(ē/G) summed from the polynomial
        // coefficients b_ip (the inner sums of eq. 4; the triple sum over
        // p, q, r factors into these three).
        let axis = |n: u32| -> Vec<[f64; 4]> {
            (0..n)
                .map(|e| {
                    let t = f64::from(e) / f64::from(n);
                    std::array::from_fn(|i| weight_poly(i, t))
                })
                .collect()
        };
        let (bx, by, bz) = (axis(g.x), axis(g.y), axis(g.z));
        let mut entries = Vec::with_capacity(g.x as usize * g.y as usize * g.z as usize);
        for wz in &bz {
            for wy in &by {
                for wx in &bx {
                    entries.push(std::array::from_fn(|n| (wx[n & 3] * wy[(n >> 2) & 3] * wz[n >> 4]) as f32));
                }
            }
        }
        Ok(Self { granularity: g, entries })
    }

    /// The granularity `G` per axis (source voxels per region).
    pub fn granularity(&self) -> UVec3 {
        self.granularity
    }

    /// The 64 weights `c[ē][f̄][ḡ][·][·][·]` (`i` fastest).
    pub fn entry(&self, e_bar: u32, f_bar: u32, g_bar: u32) -> &[f32; 64] {
        let g = self.granularity;
        &self.entries[e_bar as usize + g.x as usize * (f_bar as usize + g.y as usize * g_bar as usize)]
    }
}

/// How the map is evaluated at the voxels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Evaluation {
    /// [`Evaluation::Separable`], the fastest (it serves any source size).
    #[default]
    Auto,
    /// The precomputed table of §5.2 and the 64-term dot product of eq. 5
    /// per voxel (fails with [`WarpError::NotTableable`] when the source is
    /// not an integer multiple of the region count).
    Table,
    /// The tensor-product factorization of eq. 4–5 (beyond the thesis):
    /// the same weight products `wx_i · wy_j · wz_k`, but the 64-term sum
    /// contracted one axis at a time, z and y once per row of a region and
    /// x per voxel (4 terms per voxel instead of 64). Any source size.
    Separable,
    /// Direct basis evaluation per voxel (eq. 3).
    Direct,
}

/// The evaluation [`DeformationArray::update`] runs: an [`Evaluation`]
/// resolved, carrying the table it needs.
#[derive(Debug, Clone, Copy)]
pub enum Evaluator<'a> {
    /// The §5.2 table (it must belong to the map's lattice).
    Table(&'a CoefficientTable),
    /// The tensor-product factorization ([`Evaluation::Separable`]).
    Separable,
    /// Direct basis evaluation (eq. 3).
    Direct,
}

impl<'a> Evaluator<'a> {
    /// Resolves `evaluation`; `table` must be given exactly for
    /// [`Evaluation::Table`] (otherwise it is ignored).
    pub fn new(evaluation: Evaluation, table: Option<&'a CoefficientTable>) -> Self {
        match (evaluation, table) {
            (Evaluation::Direct, _) => Self::Direct,
            (Evaluation::Table, Some(table)) => Self::Table(table),
            _ => Self::Separable,
        }
    }
}

/// The deformation mapping array: `B(e, f, g)` for every source voxel
/// centre, in source voxel coordinates, x-fastest (16-byte [`Vec3A`]s, so
/// the pushforward's loads and min/max are single SIMD instructions).
#[derive(Debug, Clone, PartialEq)]
pub struct DeformationArray {
    dims: UVec3,
    points: Vec<Vec3A>,
}

impl DeformationArray {
    /// The identity array (every voxel maps to itself) for `dims` voxels.
    ///
    /// # Errors
    /// [`MorphError::Grid`](isomorph_common::MorphError::Grid) when the array does not fit the memory limit.
    pub fn identity(dims: UVec3) -> Result<Self, WarpError> {
        let grid = isomorph_common::Grid3::new(dims, Vec3::ZERO, 1.0, Vec3A::ZERO)?;
        let mut points = grid.into_data();
        let (nx, ny) = (dims.x as usize, dims.y as usize);
        points.par_iter_mut().enumerate().for_each(|(n, p)| {
            *p = Vec3A::new((n % nx) as f32, ((n / nx) % ny) as f32, (n / (nx * ny)) as f32);
        });
        Ok(Self { dims, points })
    }

    /// `map` evaluated at every source voxel.
    ///
    /// # Errors
    /// [`WarpError::NotTableable`] for [`Evaluation::Table`] on a size the
    /// table cannot serve, [`MorphError::Grid`](isomorph_common::MorphError::Grid) for memory.
    pub fn compute(map: &BSplineMap, evaluation: Evaluation) -> Result<Self, WarpError> {
        let mut out = Self::identity(map.source_dims())?;
        let table = match evaluation {
            Evaluation::Table => Some(CoefficientTable::new(map)?),
            _ => None,
        };
        out.update(map, Evaluator::new(evaluation, table.as_ref()), UVec3::ZERO, map.source_dims());
        Ok(out)
    }

    /// Source voxels per axis.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// The mapped points, x-fastest.
    pub fn points(&self) -> &[Vec3A] {
        &self.points
    }

    /// The image of voxel `(e, f, g)`.
    #[inline]
    pub fn get(&self, e: u32, f: u32, g: u32) -> Vec3A {
        self.points[self.index(e, f, g)]
    }

    /// Number of source cells (between 2×2×2 neighbouring voxel centres)
    /// where the sampled map folds: the determinant of its forward
    /// differences along x, y and z is not positive. Zero for an injective,
    /// orientation-preserving warp at the voxel scale; a positive count means
    /// the control points fold space there (the box filter then averages the
    /// overlapping images, see the crate docs).
    pub fn folded_cells(&self) -> usize {
        let d = self.dims;
        if d.min_element() < 2 {
            return 0;
        }
        (0..d.z - 1)
            .into_par_iter()
            .map(|g| {
                let mut count = 0;
                for f in 0..d.y - 1 {
                    for e in 0..d.x - 1 {
                        let c = self.get(e, f, g);
                        let jx = self.get(e + 1, f, g) - c;
                        let jy = self.get(e, f + 1, g) - c;
                        let jz = self.get(e, f, g + 1) - c;
                        if jx.dot(jy.cross(jz)) <= 0.0 {
                            count += 1;
                        }
                    }
                }
                count
            })
            .sum()
    }

    #[inline]
    pub(crate) fn index(&self, e: u32, f: u32, g: u32) -> usize {
        e as usize + self.dims.x as usize * (f as usize + self.dims.y as usize * g as usize)
    }

    /// Re-evaluates `map` on the source voxels of the box `[lo, hi)` with
    /// `evaluator`. Parallel over z-slices.
    pub fn update(&mut self, map: &BSplineMap, evaluator: Evaluator<'_>, lo: UVec3, hi: UVec3) {
        let hi = hi.min(self.dims);
        if lo.cmpge(hi).any() {
            return;
        }
        let (nx, ny) = (self.dims.x as usize, self.dims.y as usize);
        let slab = nx * ny;
        let slices = self.points[lo.z as usize * slab..hi.z as usize * slab].par_chunks_mut(slab);
        match evaluator {
            Evaluator::Table(table) => slices.enumerate().for_each(|(dz, slice)| {
                table_slice(map, table, slice, lo.z + dz as u32, lo, hi, nx);
            }),
            Evaluator::Separable => {
                // Region and basis weights of every x of the box, once.
                let xs: Vec<(u32, [f32; 4])> = (lo.x..hi.x)
                    .map(|e| {
                        let (a, t) = map.locate(e as f32, 0);
                        (a, weights(t))
                    })
                    .collect();
                slices.enumerate().for_each(|(dz, slice)| {
                    separable_slice(map, &xs, slice, lo.z + dz as u32, lo, hi, nx);
                });
            }
            Evaluator::Direct => slices.enumerate().for_each(|(dz, slice)| {
                let g = lo.z + dz as u32;
                for f in lo.y..hi.y {
                    for e in lo.x..hi.x {
                        slice[e as usize + nx * f as usize] =
                            map.eval(Vec3::new(e as f32, f as f32, g as f32)).into();
                    }
                }
            }),
        }
    }
}

/// One z-slice `g` of the separable path. Per row `f`: the displacements
/// blended along z and y, `S_m = Σ_{j,k} wy_j wz_k D_{m, b+j, c+k}`, for every
/// control column `m` the row's regions use; then per voxel the 4-term sum
/// `Σ_i wx_i S_{a+i}` (`xs` holds each voxel's region `a` and `wx`).
fn separable_slice(
    map: &BSplineMap,
    xs: &[(u32, [f32; 4])],
    slice: &mut [Vec3A],
    g: u32,
    lo: UVec3,
    hi: UVec3,
    nx: usize,
) {
    let controls = map.controls();
    let (cx, cy) = (controls.x as usize, controls.y as usize);
    let disp = map.displacements();
    let (c, tz) = map.locate(g as f32, 2);
    let wz = weights(tz);
    let (first, last) = (xs[0].0 as usize, xs[xs.len() - 1].0 as usize + 4);
    let mut columns = vec![Vec3A::ZERO; last - first];
    for f in lo.y..hi.y {
        let (b, ty) = map.locate(f as f32, 1);
        let wy = weights(ty);
        columns.fill(Vec3A::ZERO);
        for (k, &wk) in wz.iter().enumerate() {
            for (j, &wj) in wy.iter().enumerate() {
                let w = wj * wk;
                let row = cx * (b as usize + j + cy * (c as usize + k));
                for (sum, &d) in columns.iter_mut().zip(&disp[row + first..row + last]) {
                    *sum += w * Vec3A::from(d);
                }
            }
        }
        let out = &mut slice[nx * f as usize + lo.x as usize..nx * f as usize + hi.x as usize];
        for ((p, &(a, wx)), e) in out.iter_mut().zip(xs).zip(lo.x..) {
            let s = &columns[a as usize - first..a as usize - first + 4];
            *p = Vec3A::new(e as f32, f as f32, g as f32)
                + (wx[0] * s[0] + wx[1] * s[1] + (wx[2] * s[2] + wx[3] * s[3]));
        }
    }
}

/// One z-slice `g` of the table path: region by region along y and x, gather
/// the region's 64 control displacements (eq. 5's `P_{a+i,b+j,c+k}`) into
/// structure-of-arrays form, then one 64-term dot product per voxel.
fn table_slice(
    map: &BSplineMap,
    table: &CoefficientTable,
    slice: &mut [Vec3A],
    g: u32,
    lo: UVec3,
    hi: UVec3,
    nx: usize,
) {
    let gran = table.granularity();
    let controls = map.controls();
    let disp = map.displacements();
    let (c, g_bar) = (g / gran.z, g % gran.z);
    let mut dx = [Vec4::ZERO; 16];
    let mut dy = [Vec4::ZERO; 16];
    let mut dz = [Vec4::ZERO; 16];
    let mut b = lo.y / gran.y;
    while b * gran.y < hi.y {
        let f_range = (b * gran.y).max(lo.y)..((b + 1) * gran.y).min(hi.y);
        let mut a = lo.x / gran.x;
        while a * gran.x < hi.x {
            let e_range = (a * gran.x).max(lo.x)..((a + 1) * gran.x).min(hi.x);
            // The region's 64 control displacements, four per SIMD lane group.
            for n in 0..64 {
                let idx = (a + (n as u32 & 3)) as usize
                    + controls.x as usize
                        * ((b + ((n as u32 >> 2) & 3)) as usize
                            + controls.y as usize * (c + (n as u32 >> 4)) as usize);
                dx[n / 4][n % 4] = disp[idx].x;
                dy[n / 4][n % 4] = disp[idx].y;
                dz[n / 4][n % 4] = disp[idx].z;
            }
            for f in f_range.clone() {
                let row = nx * f as usize;
                for e in e_range.clone() {
                    let w = table.entry(e - a * gran.x, f - b * gran.y, g_bar);
                    let (mut sx, mut sy, mut sz) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
                    for (l, w4) in w.chunks_exact(4).enumerate() {
                        let w4 = Vec4::from_slice(w4);
                        sx += w4 * dx[l];
                        sy += w4 * dy[l];
                        sz += w4 * dz[l];
                    }
                    slice[row + e as usize] = Vec3A::new(e as f32, f as f32, g as f32)
                        + Vec3A::new(sx.element_sum(), sy.element_sum(), sz.element_sum());
                }
            }
            a += 1;
        }
        b += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_over_the_memory_limit_is_refused_before_allocation() {
        // One region over 1024³ voxels: 2³⁰ entries of 256 bytes.
        let map = BSplineMap::with_controls(UVec3::splat(1024), UVec3::splat(4)).unwrap();
        match CoefficientTable::new(&map) {
            Err(WarpError::Morph(isomorph_common::MorphError::Grid(GridError::TooLarge {
                requested,
                ..
            }))) => assert_eq!(requested, 256 << 30),
            other => panic!("expected TooLarge, got {other:?}"),
        }
    }

    fn random_map(dims: UVec3, controls: UVec3, amplitude: f32, seed: u64) -> BSplineMap {
        let mut map = BSplineMap::with_controls(dims, controls).unwrap();
        let mut s = seed;
        let mut r = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32 - 0.5
        };
        for k in 0..controls.z {
            for j in 0..controls.y {
                for i in 0..controls.x {
                    map.set_displacement(UVec3::new(i, j, k), amplitude * Vec3::new(r(), r(), r())).unwrap();
                }
            }
        }
        map
    }

    #[test]
    fn table_entries_are_the_basis_products() {
        let map = BSplineMap::with_controls(UVec3::new(12, 10, 8), UVec3::new(7, 8, 5)).unwrap();
        let table = CoefficientTable::new(&map).unwrap();
        assert_eq!(table.granularity(), UVec3::new(3, 2, 4));
        for (e, f, g) in [(0, 0, 0), (2, 1, 3), (1, 0, 2)] {
            let x = Vec3::new(e as f32, f as f32, g as f32);
            let direct = map.weights_at(x);
            let entry = table.entry(e, f, g);
            for n in 0..64 {
                assert!(
                    (direct[n] - entry[n]).abs() < 1e-7,
                    "({e},{f},{g})[{n}]: {} vs {}",
                    direct[n],
                    entry[n]
                );
            }
            assert!((entry.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn table_and_direct_evaluation_agree() {
        let dims = UVec3::new(24, 18, 30);
        let map = random_map(dims, UVec3::new(7, 9, 8), 4.0, 5);
        let direct = DeformationArray::compute(&map, Evaluation::Direct).unwrap();
        for evaluation in [Evaluation::Table, Evaluation::Separable] {
            let fast = DeformationArray::compute(&map, evaluation).unwrap();
            let worst = fast
                .points()
                .iter()
                .zip(direct.points())
                .map(|(a, b)| (*a - *b).abs().max_element())
                .fold(0.0, f32::max);
            assert!(worst < 1e-5, "{evaluation:?} vs direct: worst difference {worst} voxels");
        }
        let p = UVec3::new(13, 5, 22);
        assert_eq!(Vec3::from(direct.get(p.x, p.y, p.z)), map.eval(p.as_vec3()));
    }

    #[test]
    fn identity_array_is_exact_on_both_paths() {
        let map = BSplineMap::identity(UVec3::splat(12), 7).unwrap();
        let id = DeformationArray::identity(map.source_dims()).unwrap();
        for evaluation in [Evaluation::Table, Evaluation::Separable, Evaluation::Direct] {
            assert_eq!(DeformationArray::compute(&map, evaluation).unwrap(), id);
        }
    }

    #[test]
    fn partial_update_equals_full_compute() {
        let dims = UVec3::new(16, 16, 12);
        let mut map = random_map(dims, UVec3::new(7, 7, 7), 2.0, 9);
        let mut array = DeformationArray::compute(&map, Evaluation::Table).unwrap();
        let table = CoefficientTable::new(&map).unwrap();
        let c = UVec3::new(3, 4, 2);
        map.set_displacement(c, Vec3::new(1.5, -2.0, 0.5)).unwrap();
        let (lo, hi) = map.influence_box(c);
        array.update(&map, Evaluator::Table(&table), lo, hi);
        assert_eq!(array, DeformationArray::compute(&map, Evaluation::Table).unwrap());
    }

    #[test]
    fn separable_partial_update_equals_full_compute_on_any_size() {
        // 17 × 13 × 11 voxels: not a multiple of the region counts.
        let dims = UVec3::new(17, 13, 11);
        let mut map = random_map(dims, UVec3::new(7, 6, 5), 2.0, 3);
        assert!(CoefficientTable::new(&map).is_err());
        let mut array = DeformationArray::compute(&map, Evaluation::Separable).unwrap();
        let c = UVec3::new(4, 2, 3);
        map.set_displacement(c, Vec3::new(-1.0, 2.5, 0.75)).unwrap();
        let (lo, hi) = map.influence_box(c);
        array.update(&map, Evaluator::Separable, lo, hi);
        assert_eq!(array, DeformationArray::compute(&map, Evaluation::Separable).unwrap());
    }

    #[test]
    fn folds_are_counted() {
        let dims = UVec3::splat(12);
        let mut map = BSplineMap::identity(dims, 7).unwrap();
        assert_eq!(DeformationArray::compute(&map, Evaluation::Auto).unwrap().folded_cells(), 0);
        // Pull one control point through its neighbours: space folds over.
        map.set_displacement(UVec3::new(3, 3, 3), Vec3::new(12.0, 0.0, 0.0)).unwrap();
        assert!(DeformationArray::compute(&map, Evaluation::Auto).unwrap().folded_cells() > 0);
        // A mild move keeps the map injective.
        map.set_displacement(UVec3::new(3, 3, 3), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert_eq!(DeformationArray::compute(&map, Evaluation::Auto).unwrap().folded_cells(), 0);
    }

    #[test]
    fn table_refuses_sizes_that_are_not_multiples() {
        let map = BSplineMap::identity(UVec3::splat(10), 7).unwrap();
        assert!(matches!(CoefficientTable::new(&map), Err(WarpError::NotTableable { .. })));
        assert!(DeformationArray::compute(&map, Evaluation::Auto).is_ok());
    }
}
