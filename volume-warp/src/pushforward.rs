//! Pushing a density forward through the map (thesis §4, §5.3, §5.4), and
//! backward resampling for comparison.

use crate::table::DeformationArray;
use glam::{IVec3, UVec3, Vec3A};
use isomorph_common::Grid3;
use rayon::prelude::*;

/// How source voxels are pushed to the target.
///
/// **Box filter** (§5.4, [`Filter::Box`]): each source voxel is a unit cube of
/// constant density. Its image is approximated by the axis-aligned bounding
/// box of its six transformed face centres, each the average of two
/// neighbouring entries of the deformation mapping array (at the volume's
/// border, where one neighbour is missing, the face centre is extrapolated
/// linearly: `M[e] − (M[e+1] − M[e])/2`). For every target voxel the box
/// overlaps, the overlap volume (a fraction of the unit target voxel) is the
/// *weight*; weights and weighted values are summed per target voxel. The
/// target density is then the weighted value where the total weight is below
/// one (the uncovered part counts as empty space) and the weighted value
/// divided by the weight otherwise (overlapping boxes, and folds, average).
///
/// **Map and round** (§5.3, [`Filter::Round`]): each source voxel centre is
/// mapped and rounded to the nearest target voxel. Where several land on one
/// target voxel the thesis overwrote; we average them (the same
/// weight rule with weight 1 per voxel) so the result does not depend on
/// the order of the loop. Aliases badly, as the thesis' Fig. 6 shows.
///
/// **Backward** ([`Filter::Backward`], beyond the thesis): each target voxel
/// `y` is pulled back, `x = B⁻¹(y)` by Newton iteration from `x = y`
/// ([`crate::BSplineMap::inverse`]), and the source is sampled trilinearly at `x`
/// (zero outside the source's voxels). No holes and no blockiness where the
/// map stretches, smoother than the box filter on mild warps; but it samples
/// only one preimage, so where the map folds (not injective) it shows one
/// sheet instead of averaging, and where it compresses strongly it aliases
/// (point sampling instead of the box filter's area average). It costs one
/// Newton solve (a few map and Jacobian evaluations, direct, no table) per
/// target voxel. Measured on a sheared ball (`volume_preserving_warp_keeps_the_mass`),
/// all three filters keep the total density within 0.5 %; the identity and
/// whole-voxel translations are exact for all three.
///
/// The accumulation is parallel over fixed slabs of source z-slices. Slabs
/// whose target z-ranges are disjoint run concurrently on disjoint parts of
/// the accumulator ("waves"); the partition does not depend on the thread
/// count, so neither does the result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Filter {
    /// Map each voxel centre and round to the nearest target voxel (§5.3).
    Round,
    /// The antialiasing box filter of §5.4 (bounding box of the six
    /// transformed face centres, overlap weights).
    #[default]
    Box,
    /// Backward resampling: Newton inversion per target voxel and trilinear
    /// sampling of the source (not in the thesis; for comparison).
    Backward,
}

/// Voxel values the warp can carry: `u8` densities (0–255, material above
/// 127.5 as in the thesis) and `f32` fields (any iso level).
pub trait Density: Copy + Send + Sync + PartialEq + std::fmt::Debug + 'static {
    /// The value as `f32` (no scaling: a `u8` 200 is 200.0).
    fn to_f32(self) -> f32;
    /// Back from `f32` (`u8`: rounded and clamped to 0–255).
    fn from_f32(v: f32) -> Self;
    /// The value of empty space (0).
    const ZERO: Self;
}

impl Density for u8 {
    #[inline]
    fn to_f32(self) -> f32 {
        f32::from(self)
    }
    #[inline]
    fn from_f32(v: f32) -> Self {
        // Round half up without a libm call (the value is clamped first, so
        // the truncating cast rounds).
        (v.clamp(0.0, 255.0) + 0.5) as u8
    }
    const ZERO: Self = 0;
}

impl Density for f32 {
    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline]
    fn from_f32(v: f32) -> Self {
        v
    }
    const ZERO: Self = 0.0;
}

/// Source z-slices per accumulation slab.
const SLAB: u32 = 8;

/// Per-target-voxel sums of weights and weighted values (x-fastest over the
/// padded target).
pub(crate) type Accumulator = [[f32; 2]];

/// The box filter's approximate image of source voxel `(e, f, g)`: the
/// bounding box of its six transformed face centres (source voxel units,
/// before padding).
#[inline(always)]
pub(crate) fn voxel_box(m: &DeformationArray, e: u32, f: u32, g: u32) -> (Vec3A, Vec3A) {
    let dims = m.dims();
    let c = m.get(e, f, g);
    if e > 0 && f > 0 && g > 0 && e + 1 < dims.x && f + 1 < dims.y && g + 1 < dims.z {
        // Interior voxel: the six face centres are midpoints with the six
        // neighbours; min/max of the midpoints = midpoint of the min/max.
        let points = m.points();
        let n = m.index(e, f, g);
        let (sy, sz) = (dims.x as usize, dims.x as usize * dims.y as usize);
        let (xm, xp, ym, yp, zm, zp) =
            (points[n - 1], points[n + 1], points[n - sy], points[n + sy], points[n - sz], points[n + sz]);
        let lo = xm.min(xp).min(ym.min(yp)).min(zm.min(zp));
        let hi = xm.max(xp).max(ym.max(yp)).max(zm.max(zp));
        return (0.5 * (c + lo), 0.5 * (c + hi));
    }
    let mut lo = Vec3A::splat(f32::INFINITY);
    let mut hi = Vec3A::splat(f32::NEG_INFINITY);
    let p = UVec3::new(e, f, g);
    for axis in 0..3 {
        let neighbour = |d: i32| {
            let mut q = p.as_ivec3();
            q[axis] += d;
            (q[axis] >= 0 && q[axis] < dims[axis] as i32).then(|| m.get(q.x as u32, q.y as u32, q.z as u32))
        };
        let (minus, plus) = (neighbour(-1), neighbour(1));
        let face_minus = match (minus, plus) {
            (Some(n), _) => 0.5 * (c + n),
            (None, Some(n)) => c - 0.5 * (n - c),
            (None, None) => c - 0.5 * Vec3A::AXES[axis],
        };
        let face_plus = match (plus, minus) {
            (Some(n), _) => 0.5 * (c + n),
            (None, Some(n)) => c + 0.5 * (c - n),
            (None, None) => c + 0.5 * Vec3A::AXES[axis],
        };
        lo = lo.min(face_minus).min(face_plus);
        hi = hi.max(face_minus).max(face_plus);
    }
    (lo, hi)
}

/// Target voxel range `[first, last]` (inclusive, may be empty) overlapped by
/// the interval `[lo, hi]` in target coordinates, clipped to `0..n`.
#[inline]
fn cover(lo: f32, hi: f32, n: u32) -> (i32, i32) {
    let first = floor(lo + 0.5).max(0);
    let last = (-floor(-(hi + 0.5)) - 1).min(n as i32 - 1);
    (first, last)
}

/// `⌊x⌋` as an integer without a libm call (SSE2 has no rounding
/// instruction); saturates for huge `x`, which the callers clamp anyway.
#[inline]
fn floor(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(x < i as f32)
}

/// What one accumulation pass reads.
pub(crate) struct Splat<'a, T> {
    pub source: &'a [T],
    pub deformation: &'a DeformationArray,
    pub filter: Filter,
    pub pad: u32,
    pub target_dims: UVec3,
}

impl<T: Density> Splat<'_, T> {
    /// Adds `sign ×` the contributions of the source voxels in `[lo, hi)` to
    /// `accum`. Returns the (inclusive) target voxel box it touched, if any.
    pub fn run(&self, accum: &mut Accumulator, lo: UVec3, hi: UVec3, sign: f32) -> Option<(UVec3, UVec3)> {
        let hi = hi.min(self.deformation.dims());
        if lo.cmpge(hi).any() {
            return None;
        }
        // Pass 1: target box of every slab.
        let slabs: Vec<(u32, u32)> =
            (lo.z..hi.z).step_by(SLAB as usize).map(|z| (z, (z + SLAB).min(hi.z))).collect();
        let ranges: Vec<Option<(IVec3, IVec3)>> =
            slabs.par_iter().map(|&(z0, z1)| self.target_range(lo, hi, z0, z1)).collect();
        // Greedy waves of slabs with disjoint target z-ranges.
        let mut waves: Vec<Vec<usize>> = Vec::new();
        for (n, range) in ranges.iter().enumerate() {
            let Some((a, b)) = range else { continue };
            let fits = |wave: &Vec<usize>| {
                wave.iter().all(|&m| {
                    let (c, d) = ranges[m].expect("only non-empty slabs are queued");
                    b.z < c.z || d.z < a.z
                })
            };
            match waves.iter_mut().find(|w| fits(w)) {
                Some(w) => w.push(n),
                None => waves.push(vec![n]),
            }
        }
        let layer = self.target_dims.x as usize * self.target_dims.y as usize;
        for mut wave in waves {
            wave.sort_by_key(|&n| ranges[n].expect("queued").0.z);
            let mut rest: &mut Accumulator = accum;
            let mut consumed = 0usize;
            let mut jobs = Vec::with_capacity(wave.len());
            for &n in &wave {
                let (a, b) = ranges[n].expect("queued");
                let start = a.z as usize * layer;
                let end = (b.z as usize + 1) * layer;
                let (_, tail) = std::mem::take(&mut rest).split_at_mut(start - consumed);
                let (part, tail) = tail.split_at_mut(end - start);
                rest = tail;
                consumed = end;
                jobs.push((n, part));
            }
            jobs.into_par_iter().for_each(|(n, part)| {
                let (z0, z1) = slabs[n];
                let zbase = ranges[n].expect("queued").0.z;
                self.accumulate(part, zbase, lo, hi, z0, z1, sign);
            });
        }
        let mut touched: Option<(IVec3, IVec3)> = None;
        for (a, b) in ranges.into_iter().flatten() {
            touched = Some(match touched {
                None => (a, b),
                Some((c, d)) => (a.min(c), b.max(d)),
            });
        }
        touched.map(|(a, b)| (a.as_uvec3(), b.as_uvec3()))
    }

    /// Inclusive target voxel box touched by the source slab `z0..z1` (of
    /// the source box `[lo, hi)`). Every interior face centre is a midpoint
    /// of two mapped voxel centres of the slab grown by one voxel, so the
    /// bounds of those centres bound it; only voxels on the volume's border
    /// (extrapolated faces) need their boxes computed.
    fn target_range(&self, lo: UVec3, hi: UVec3, z0: u32, z1: u32) -> Option<(IVec3, IVec3)> {
        let m = self.deformation;
        let dims = m.dims();
        let round = self.filter == Filter::Round;
        let (glo, ghi) = if round {
            (UVec3::new(lo.x, lo.y, z0), UVec3::new(hi.x, hi.y, z1))
        } else {
            (
                UVec3::new(lo.x, lo.y, z0).saturating_sub(UVec3::ONE),
                (UVec3::new(hi.x, hi.y, z1) + UVec3::ONE).min(dims),
            )
        };
        let mut bmin = Vec3A::splat(f32::INFINITY);
        let mut bmax = Vec3A::splat(f32::NEG_INFINITY);
        for g in glo.z..ghi.z {
            for f in glo.y..ghi.y {
                let row = m.index(glo.x, f, g);
                for &p in &m.points()[row..row + (ghi.x - glo.x) as usize] {
                    bmin = bmin.min(p);
                    bmax = bmax.max(p);
                }
            }
        }
        if !round {
            let border = |e: u32, f: u32, g: u32| {
                e == 0 || f == 0 || g == 0 || e + 1 == dims.x || f + 1 == dims.y || g + 1 == dims.z
            };
            for g in z0..z1 {
                for f in lo.y..hi.y {
                    let whole_row = g == 0 || f == 0 || g + 1 == dims.z || f + 1 == dims.y;
                    let mut visit = |e: u32| {
                        if border(e, f, g) {
                            let (a, b) = voxel_box(m, e, f, g);
                            bmin = bmin.min(a);
                            bmax = bmax.max(b);
                        }
                    };
                    if whole_row {
                        (lo.x..hi.x).for_each(&mut visit);
                    } else {
                        visit(lo.x);
                        visit(hi.x - 1);
                    }
                }
            }
        }
        let pad = Vec3A::splat(self.pad as f32);
        let (bmin, bmax) = (bmin + pad, bmax + pad);
        let mut first = IVec3::ZERO;
        let mut last = IVec3::ZERO;
        for axis in 0..3 {
            (first[axis], last[axis]) = if round {
                (
                    floor(bmin[axis] + 0.5).max(0),
                    floor(bmax[axis] + 0.5).min(self.target_dims[axis] as i32 - 1),
                )
            } else {
                // One voxel more at the top: the 2 × 2 × 2 fast path of
                // `accumulate` writes (zero weights) to voxel `q + 1` even
                // when a box ends in voxel `q`.
                let (first, last) = cover(bmin[axis], bmax[axis], self.target_dims[axis]);
                (first, (last + 1).min(self.target_dims[axis] as i32 - 1))
            };
        }
        first.cmple(last).all().then_some((first, last))
    }

    /// Accumulates the slab `z0..z1` of the source box into `part`, the
    /// accumulator's z-layers from `zbase` on.
    #[allow(clippy::too_many_arguments)]
    fn accumulate(
        &self,
        part: &mut Accumulator,
        zbase: i32,
        lo: UVec3,
        hi: UVec3,
        z0: u32,
        z1: u32,
        sign: f32,
    ) {
        let dims = self.deformation.dims();
        let points = self.deformation.points();
        let mut target = Target::new(part, zbase, self.target_dims, sign);
        let pad = Vec3A::splat(self.pad as f32);
        for g in z0..z1 {
            for f in lo.y..hi.y {
                let row = self.deformation.index(0, f, g);
                let values = &self.source[row..row + dims.x as usize];
                if self.filter == Filter::Round {
                    for e in lo.x..hi.x {
                        target.add_point(points[row + e as usize] + pad, values[e as usize].to_f32());
                    }
                    continue;
                }
                // Interior voxels of interior rows: the six face centres are
                // midpoints with the six neighbours (min/max of the midpoints
                // = midpoint of the min/max), read from seven row slices
                // without index arithmetic; the rest take `voxel_box`.
                let interior_row = f > 0 && g > 0 && f + 1 < dims.y && g + 1 < dims.z;
                let (a, b) = if interior_row {
                    (lo.x.max(1), hi.x.min(dims.x - 1).max(lo.x.max(1)))
                } else {
                    (hi.x, hi.x)
                };
                for e in (lo.x..a).chain(b..hi.x) {
                    let (blo, bhi) = voxel_box(self.deformation, e, f, g);
                    target.add_box(blo + pad, bhi + pad, values[e as usize].to_f32());
                }
                if a < b {
                    let (sy, sz) = (dims.x as usize, dims.x as usize * dims.y as usize);
                    let (a, b) = (row + a as usize, row + b as usize);
                    let centre = &points[a..b];
                    let n = centre.len();
                    let (xm, xp) = (&points[a - 1..b - 1][..n], &points[a + 1..b + 1][..n]);
                    let (ym, yp) = (&points[a - sy..b - sy][..n], &points[a + sy..b + sy][..n]);
                    let (zm, zp) = (&points[a - sz..b - sz][..n], &points[a + sz..b + sz][..n]);
                    let values = &self.source[a..b][..n];
                    for i in 0..n {
                        let lo = xm[i].min(xp[i]).min(ym[i].min(yp[i])).min(zm[i].min(zp[i]));
                        let hi = xm[i].max(xp[i]).max(ym[i].max(yp[i])).max(zm[i].max(zp[i]));
                        let c = centre[i];
                        target.add_box(0.5 * (c + lo) + pad, 0.5 * (c + hi) + pad, values[i].to_f32());
                    }
                }
            }
        }
    }
}

/// A slab's part of the accumulator, and the sign of the pass (`+1` adds
/// contributions, `−1` removes them for a local update).
struct Target<'a> {
    part: &'a mut Accumulator,
    zbase: i32,
    dims: UVec3,
    /// The largest voxel index along each axis at which a 2 × 2 × 2 block
    /// may start (`dims − 2`), as floats.
    last_block: Vec3A,
    sign: f32,
}

impl<'a> Target<'a> {
    fn new(part: &'a mut Accumulator, zbase: i32, dims: UVec3, sign: f32) -> Self {
        let last_block = (dims.saturating_sub(UVec3::splat(2))).as_vec3a();
        Self { part, zbase, dims, last_block, sign }
    }

    /// Index into `part` of target voxel `(x, y, z)`.
    #[inline(always)]
    fn cell(&self, x: usize, y: usize, z: i32) -> usize {
        let z = z - self.zbase;
        debug_assert!(z >= 0 && (z as usize + 1) * (self.dims.x * self.dims.y) as usize <= self.part.len());
        x + self.dims.x as usize * (y + self.dims.y as usize * z as usize)
    }

    /// Map and round (§5.3): the voxel centre's image `p` (target voxel
    /// coordinates) rounded to the nearest target voxel, weight one.
    #[inline]
    fn add_point(&mut self, p: Vec3A, v: f32) {
        let q = p + 0.5;
        let qi = IVec3::new(floor(q.x), floor(q.y), floor(q.z));
        if qi.cmpge(IVec3::ZERO).all() && qi.cmplt(self.dims.as_ivec3()).all() {
            let n = self.cell(qi.x as usize, qi.y as usize, qi.z);
            let cell = &mut self.part[n];
            cell[0] += self.sign;
            cell[1] += self.sign * v;
        }
    }

    /// The box filter (§5.4): adds the box `[lo, hi]` (target voxel
    /// coordinates) of a source voxel of value `v` to every target voxel it
    /// overlaps, weighted by the overlap volume.
    #[inline(always)]
    fn add_box(&mut self, lo: Vec3A, hi: Vec3A, v: f32) {
        let sign = self.sign;
        let sv = sign * v;
        // The common case, branch-free in SIMD: a box within 2 × 2 × 2
        // target voxels, `q` and `q + 1` per axis (voxel `q` spans
        // `[q − ½, q + ½]`), split at `m = q + ½`; the overlaps are
        // `min(m, hi) − lo` and `max(hi − m, 0)` (zero when the box ends in
        // voxel `q`; the slab's range includes `q + 1` then, see
        // `target_range`).
        let start = lo + 0.5;
        let q = floor_small(start);
        let m = q + 0.5;
        let (w_lo, w_hi) = (m.min(hi) - lo, (hi - m).max(Vec3A::ZERO));
        if (w_hi.cmple(Vec3A::ONE) & start.cmpge(Vec3A::ZERO) & q.cmple(self.last_block)).all() {
            let wx = [[sign * w_lo.x, sv * w_lo.x], [sign * w_hi.x, sv * w_hi.x]];
            let base = self.cell(small_index(q.x), small_index(q.y), small_index(q.z) as i32);
            let (tx, layer) = (self.dims.x as usize, (self.dims.x * self.dims.y) as usize);
            // The four rows of two cells, at these offsets in one block.
            let block = &mut self.part[base..base + layer + tx + 2];
            let rows = [
                (0, w_lo.y * w_lo.z),
                (tx, w_hi.y * w_lo.z),
                (layer, w_lo.y * w_hi.z),
                (layer + tx, w_hi.y * w_hi.z),
            ];
            for (offset, wyz) in rows {
                for (cell, w) in block[offset..offset + 2].iter_mut().zip(&wx) {
                    cell[0] += wyz * w[0];
                    cell[1] += wyz * w[1];
                }
            }
            return;
        }
        // General boxes (strong stretching, or at the target's border).
        let (x0, x1) = cover(lo.x, hi.x, self.dims.x);
        let (y0, y1) = cover(lo.y, hi.y, self.dims.y);
        let (z0, z1) = cover(lo.z, hi.z, self.dims.z);
        let overlap = |q: i32, l: f32, h: f32| (h.min(q as f32 + 0.5) - l.max(q as f32 - 0.5)).max(0.0);
        for qz in z0..=z1 {
            let wz = overlap(qz, lo.z, hi.z);
            for qy in y0..=y1 {
                let wyz = wz * overlap(qy, lo.y, hi.y);
                let row = self.cell(0, qy as usize, qz);
                for qx in x0..=x1 {
                    let w = wyz * overlap(qx, lo.x, hi.x);
                    let cell = &mut self.part[row + qx as usize];
                    cell[0] += sign * w;
                    cell[1] += sv * w;
                }
            }
        }
    }
}

/// `⌊x⌋` per lane for `x` in `[0, 2²²)` (other lanes give garbage that
/// the caller rejects): rounding to nearest by adding and subtracting 2²³,
/// then one down where that rounded up. Five SIMD instructions instead of
/// the general `floor`.
#[inline(always)]
fn floor_small(x: Vec3A) -> Vec3A {
    const MAGIC: Vec3A = Vec3A::splat(8_388_608.0);
    let r = (x + MAGIC) - MAGIC;
    Vec3A::select(r.cmpgt(x), r - Vec3A::ONE, r)
}

/// An integer-valued float in `[0, 2²³)` as an index, without the
/// saturating checks of `as`: adding 2²³ puts the integer in the low
/// mantissa bits.
#[inline(always)]
fn small_index(x: f32) -> usize {
    debug_assert!((0.0..8_388_608.0).contains(&x) && x.fract() == 0.0);
    ((x + 8_388_608.0).to_bits() - 0x4B00_0000) as usize
}

/// Writes the normalized density (§5.4's last loop) of the target voxels in
/// the inclusive box `[lo, hi]` from the accumulator.
pub(crate) fn resolve<T: Density>(accum: &Accumulator, target: &mut Grid3<T>, lo: UVec3, hi: UVec3) {
    let dims = target.dims();
    let layer = dims.x as usize * dims.y as usize;
    let (lo, hi) = (lo.min(dims - UVec3::ONE), hi.min(dims - UVec3::ONE));
    target.data_mut()[lo.z as usize * layer..(hi.z as usize + 1) * layer]
        .par_chunks_mut(layer)
        .zip(accum[lo.z as usize * layer..(hi.z as usize + 1) * layer].par_chunks(layer))
        .for_each(|(out, acc)| {
            for y in lo.y..=hi.y {
                let row = y as usize * dims.x as usize;
                for x in lo.x..=hi.x {
                    let [w, wv] = acc[row + x as usize];
                    out[row + x as usize] = T::from_f32(if w < 1.0 { wv } else { wv / w });
                }
            }
        });
}
