//! Dense voxel grids: [`Grid3`] (volumes) and [`Grid2`] (images, slices).
//!
//! Values live on *nodes*: node `(i, j, k)` sits at `origin + spacing ·
//! (i, j, k)`. Voxels are cubic (one `spacing` for all axes); resample
//! anisotropic data first. Storage is x-fastest: the linear index of `(i, j,
//! k)` is `i + nx · (j + ny · k)`, i.e. a C-order array of shape
//! `(nz, ny, nx)`.
//!
//! Every allocation is checked against a process-wide memory limit
//! ([`set_memory_limit`]) and fails with [`GridError::TooLarge`] instead of
//! aborting the process.

use crate::{Aabb, Field3};
use glam::{IVec3, UVec2, UVec3, Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Errors of grid construction and access.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GridError {
    /// The grid would need more memory than the configured limit allows.
    #[error(
        "a grid of {dims} nodes needs {}, over the memory limit of {}; lower the resolution \
         or raise the memory limit",
        Bytes(*requested),
        Bytes(*limit)
    )]
    TooLarge {
        /// Requested node counts.
        dims: UVec3,
        /// Bytes the grid would need.
        requested: usize,
        /// The limit in force.
        limit: usize,
    },
    /// The allocator refused the memory even though it is under the limit.
    #[error("could not allocate {0} bytes for a grid")]
    OutOfMemory(usize),
    /// A dimension is smaller than the operation needs.
    #[error("grid dimensions {dims} are too small: at least {min} nodes per axis are needed")]
    TooSmall {
        /// The dimensions given.
        dims: UVec3,
        /// Minimum nodes per axis.
        min: u32,
    },
    /// Spacing is not a positive finite number, or the origin is not finite.
    #[error("invalid grid geometry: spacing {spacing} must be positive and finite, origin {origin} finite")]
    InvalidGeometry {
        /// The spacing given.
        spacing: f32,
        /// The origin given.
        origin: Vec3,
    },
    /// Data length does not match the dimensions.
    #[error("data has {got} values but dimensions {dims} need {expected}")]
    DataLength {
        /// The dimensions given.
        dims: UVec3,
        /// Values needed.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// Two grids that must share a lattice do not.
    #[error("grids do not share a lattice: {0}")]
    Mismatch(String),
    /// An axis or slice index is out of range.
    #[error("slice {index} along axis {axis} is out of range (axis has {len} nodes)")]
    SliceOutOfRange {
        /// Axis 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// Requested index.
        index: u32,
        /// Nodes along that axis.
        len: u32,
    },
}

/// Default memory limit for one grid or dense system: 8 GiB.
pub const DEFAULT_MEMORY_LIMIT: usize = 8 << 30;

static MEMORY_LIMIT: AtomicUsize = AtomicUsize::new(DEFAULT_MEMORY_LIMIT);

/// Sets the largest number of bytes one grid, matrix or other allocation
/// sized by the input may take (process-wide).
pub fn set_memory_limit(bytes: usize) {
    MEMORY_LIMIT.store(bytes, Ordering::Relaxed);
}

/// The largest number of bytes one allocation sized by the input may take.
pub fn memory_limit() -> usize {
    MEMORY_LIMIT.load(Ordering::Relaxed)
}

/// A byte count printed with a binary unit (`1.5 GiB`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bytes(pub usize);

impl std::fmt::Display for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const UNITS: [&str; 6] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB"];
        let mut value = self.0 as f64;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < UNITS.len() {
            value /= 1024.0;
            unit += 1;
        }
        if unit == 0 { write!(f, "{} bytes", self.0) } else { write!(f, "{value:.1} {}", UNITS[unit]) }
    }
}

/// A computation sized by its input would need more memory than the limit
/// ([`set_memory_limit`]) allows. Raised before anything is allocated.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} needs {}, over the memory limit of {}; {advice} or raise the memory limit", Bytes(*requested), Bytes(*limit))]
pub struct MemoryLimitError {
    /// What would be allocated (e.g. "the dense RBF system of 40000 constraints").
    pub what: String,
    /// Bytes it would need (saturated at `usize::MAX`).
    pub requested: usize,
    /// The limit in force.
    pub limit: usize,
    /// Which input to lower (e.g. "use fewer points").
    pub advice: &'static str,
}

/// Checks that `requested` bytes for `what` fit the memory limit, before
/// allocating them; compute `requested` with saturating arithmetic so an
/// absurd size fails here instead of wrapping.
///
/// ```
/// use isomorph_common::reserve_memory;
/// assert!(reserve_memory(|| "a small table".into(), 1 << 10, "use a smaller table").is_ok());
/// let err = reserve_memory(|| "a huge table".into(), usize::MAX, "use a smaller table").unwrap_err();
/// assert!(err.to_string().contains("use a smaller table"));
/// ```
///
/// # Errors
/// [`MemoryLimitError`] naming `what`, the bytes and `advice`.
pub fn reserve_memory(
    what: impl FnOnce() -> String,
    requested: usize,
    advice: &'static str,
) -> Result<(), MemoryLimitError> {
    let limit = memory_limit();
    if requested > limit {
        return Err(MemoryLimitError { what: what(), requested, limit, advice });
    }
    Ok(())
}

/// [`GridError::TooLarge`] when `requested` bytes for a grid of `dims`
/// nodes are over the memory limit.
pub(crate) fn check_grid_bytes(dims: UVec3, requested: usize) -> Result<(), GridError> {
    let limit = memory_limit();
    if requested > limit {
        return Err(GridError::TooLarge { dims, requested, limit });
    }
    Ok(())
}

/// Allocates `len` copies of `value`, checked against the memory limit.
fn checked_vec<T: Clone>(dims: UVec3, len: usize, value: T) -> Result<Vec<T>, GridError> {
    let requested = len.saturating_mul(size_of::<T>());
    check_grid_bytes(dims, requested)?;
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| GridError::OutOfMemory(requested))?;
    v.resize(len, value);
    Ok(v)
}

/// Node count of `dims` (saturating, so absurd sizes fail the limit check).
fn node_count(dims: UVec3) -> usize {
    (dims.x as usize).saturating_mul(dims.y as usize).saturating_mul(dims.z as usize)
}

/// A dense 3D grid of values on nodes, with world placement.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid3<T> {
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
    data: Vec<T>,
}

impl<T: Clone + Send + Sync> Grid3<T> {
    /// A grid of `dims` nodes at `origin` with node `spacing`, every value `fill`.
    ///
    /// # Errors
    /// [`GridError::TooSmall`] for a zero dimension, [`GridError::InvalidGeometry`]
    /// for a non-positive or non-finite spacing, [`GridError::TooLarge`] /
    /// [`GridError::OutOfMemory`] when the memory is not available.
    pub fn new(dims: UVec3, origin: Vec3, spacing: f32, fill: T) -> Result<Self, GridError> {
        check_geometry(dims, origin, spacing, 1)?;
        let data = checked_vec(dims, node_count(dims), fill)?;
        Ok(Self { dims, origin, spacing, data })
    }

    /// A grid over existing x-fastest `data`.
    ///
    /// # Errors
    /// As [`Grid3::new`], plus [`GridError::DataLength`] when `data` does not
    /// hold exactly one value per node.
    pub fn from_vec(dims: UVec3, origin: Vec3, spacing: f32, data: Vec<T>) -> Result<Self, GridError> {
        check_geometry(dims, origin, spacing, 1)?;
        let expected = node_count(dims);
        if data.len() != expected {
            return Err(GridError::DataLength { dims, expected, got: data.len() });
        }
        Ok(Self { dims, origin, spacing, data })
    }

    /// An empty grid with the same lattice as `self`, every value `fill`.
    ///
    /// # Errors
    /// As [`Grid3::new`] (the value type may be larger).
    pub fn with_same_lattice<U: Clone + Send + Sync>(&self, fill: U) -> Result<Grid3<U>, GridError> {
        Grid3::new(self.dims, self.origin, self.spacing, fill)
    }

    /// Node counts per axis.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// World position of node `(0, 0, 0)`.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Distance between neighbouring nodes (world units, all axes).
    pub fn spacing(&self) -> f32 {
        self.spacing
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True when the grid has no node (never, for a constructed grid).
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The values, x-fastest.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// The values, x-fastest, mutable.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consumes the grid, returning its x-fastest values.
    pub fn into_data(self) -> Vec<T> {
        self.data
    }

    /// Linear index of node `(i, j, k)` (no bounds check beyond the slice's).
    #[inline]
    pub fn index(&self, i: u32, j: u32, k: u32) -> usize {
        i as usize + self.dims.x as usize * (j as usize + self.dims.y as usize * k as usize)
    }

    /// The node `(i, j, k)` of a linear index.
    pub fn node_of(&self, index: usize) -> UVec3 {
        let nx = self.dims.x as usize;
        let ny = self.dims.y as usize;
        UVec3::new((index % nx) as u32, ((index / nx) % ny) as u32, (index / (nx * ny)) as u32)
    }

    /// Value at node `(i, j, k)`, or `None` outside the grid.
    pub fn get(&self, i: u32, j: u32, k: u32) -> Option<&T> {
        (i < self.dims.x && j < self.dims.y && k < self.dims.z).then(|| &self.data[self.index(i, j, k)])
    }

    /// Mutable value at node `(i, j, k)`, or `None` outside the grid.
    pub fn get_mut(&mut self, i: u32, j: u32, k: u32) -> Option<&mut T> {
        if i < self.dims.x && j < self.dims.y && k < self.dims.z {
            let idx = self.index(i, j, k);
            Some(&mut self.data[idx])
        } else {
            None
        }
    }

    /// World position of node `(i, j, k)`.
    #[inline]
    pub fn position(&self, i: u32, j: u32, k: u32) -> Vec3 {
        self.origin + self.spacing * Vec3::new(i as f32, j as f32, k as f32)
    }

    /// Continuous grid coordinates of world point `p` (node `(i,j,k)` ↦ `(i,j,k)`).
    #[inline]
    pub fn to_grid(&self, p: Vec3) -> Vec3 {
        (p - self.origin) / self.spacing
    }

    /// The box spanned by the nodes.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.origin, self.position(self.dims.x - 1, self.dims.y - 1, self.dims.z - 1))
    }

    /// True when `other` has the same dimensions, origin and spacing.
    pub fn same_lattice<U>(&self, other: &Grid3<U>) -> bool {
        self.dims == other.dims && self.origin == other.origin && self.spacing == other.spacing
    }

    /// Checks that `other` shares this grid's lattice.
    ///
    /// # Errors
    /// [`GridError::Mismatch`] naming what differs.
    pub fn check_same_lattice<U>(&self, other: &Grid3<U>) -> Result<(), GridError> {
        if self.same_lattice(other) {
            Ok(())
        } else {
            Err(GridError::Mismatch(format!(
                "dims {} vs {}, origin {} vs {}, spacing {} vs {}",
                self.dims, other.dims, self.origin, other.origin, self.spacing, other.spacing
            )))
        }
    }

    /// Applies `f` to every value in parallel, producing a grid on the same lattice.
    ///
    /// # Errors
    /// When the result does not fit the memory limit.
    pub fn map<U: Clone + Send + Sync + Default>(
        &self,
        f: impl Fn(&T) -> U + Sync,
    ) -> Result<Grid3<U>, GridError> {
        let mut out = self.with_same_lattice(U::default())?;
        out.data.par_iter_mut().zip(self.data.par_iter()).for_each(|(o, v)| *o = f(v));
        Ok(out)
    }

    /// The 2D slice of nodes with coordinate `index` along `axis` (0 = x, 1 = y,
    /// 2 = z). The slice's axes are the two remaining ones in order (x→(y,z),
    /// y→(x,z), z→(x,y)).
    ///
    /// # Errors
    /// [`GridError::SliceOutOfRange`] for a bad axis or index.
    pub fn slice(&self, axis: usize, index: u32) -> Result<Grid2<T>, GridError> {
        let len = if axis < 3 { self.dims[axis] } else { 0 };
        if axis >= 3 || index >= len {
            return Err(GridError::SliceOutOfRange { axis, index, len });
        }
        let (u, v) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let dims = UVec2::new(self.dims[u], self.dims[v]);
        let mut data = Vec::with_capacity(dims.x as usize * dims.y as usize);
        for b in 0..dims.y {
            for a in 0..dims.x {
                let mut n = UVec3::ZERO;
                n[axis] = index;
                n[u] = a;
                n[v] = b;
                data.push(self.data[self.index(n.x, n.y, n.z)].clone());
            }
        }
        let origin = Vec2::new(self.origin[u], self.origin[v]);
        Ok(Grid2 { dims, origin, spacing: self.spacing, data })
    }
}

fn check_geometry(dims: UVec3, origin: Vec3, spacing: f32, min: u32) -> Result<(), GridError> {
    if dims.min_element() < min {
        return Err(GridError::TooSmall { dims, min });
    }
    if !spacing.is_finite() || spacing <= 0.0 || !origin.is_finite() {
        return Err(GridError::InvalidGeometry { spacing, origin });
    }
    Ok(())
}

/// The default of [`Field3::values_on_lattice`]: `field` at every node of
/// the lattice of `dims` nodes at `origin + spacing·(i, j, k)` into `out`
/// (`i` fastest), one batched [`Field3::values`] call per row of `dims.x`
/// nodes, rows in parallel.
///
/// # Panics
/// If `out` does not hold `dims.x · dims.y · dims.z` values.
pub fn values_by_rows<F: Field3 + ?Sized>(
    field: &F,
    dims: UVec3,
    origin: Vec3,
    spacing: f32,
    out: &mut [f32],
) {
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    assert_eq!(out.len(), nx * ny * dims.z as usize, "values_by_rows: out does not match the lattice");
    let h = spacing;
    out.par_chunks_mut(nx.max(1)).enumerate().for_each_init(
        || vec![Vec3::ZERO; nx],
        |points, (row, out)| {
            let (j, k) = (row % ny, row / ny);
            let yz = origin + h * Vec3::new(0.0, j as f32, k as f32);
            for (i, p) in points.iter_mut().enumerate() {
                *p = yz + Vec3::new(h * i as f32, 0.0, 0.0);
            }
            field.values(points, out);
        },
    );
}

/// Node placement of a grid that covers a box: `res` nodes along the longest
/// edge, cubic voxels, the box centred in the lattice.
///
/// Returns `(dims, origin, spacing)`.
///
/// # Errors
/// [`GridError::TooSmall`] for `res < 2`, [`GridError::InvalidGeometry`] for an
/// empty or non-finite box.
pub fn lattice_for_box(bounds: &Aabb, res: u32) -> Result<(UVec3, Vec3, f32), GridError> {
    if res < 2 {
        return Err(GridError::TooSmall { dims: UVec3::splat(res), min: 2 });
    }
    let size = bounds.size();
    let spacing = size.max_element() / (res - 1) as f32;
    if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() || spacing <= 0.0 {
        return Err(GridError::InvalidGeometry { spacing, origin: bounds.min });
    }
    let cells = (size / spacing).ceil().max(Vec3::ONE);
    let dims = (cells.as_uvec3() + UVec3::ONE).min(UVec3::splat(res)).max(UVec3::splat(2));
    let span = (dims - UVec3::ONE).as_vec3() * spacing;
    let origin = bounds.center() - 0.5 * span;
    Ok((dims, origin, spacing))
}

impl Grid3<f32> {
    /// Samples `field` on `dims` nodes in parallel (z-slabs over rayon, one
    /// batched [`Field3::values`] call per row).
    ///
    /// # Errors
    /// As [`Grid3::new`].
    pub fn sample<F: Field3 + ?Sized>(
        field: &F,
        dims: UVec3,
        origin: Vec3,
        spacing: f32,
    ) -> Result<Self, GridError> {
        let mut grid = Grid3::new(dims, origin, spacing, 0.0f32)?;
        grid.fill_from(field);
        Ok(grid)
    }

    /// Samples `field` over `bounds` with `res` nodes along the longest edge
    /// (see [`lattice_for_box`]).
    ///
    /// # Errors
    /// As [`lattice_for_box`] and [`Grid3::new`].
    pub fn sample_box<F: Field3 + ?Sized>(field: &F, bounds: &Aabb, res: u32) -> Result<Self, GridError> {
        let (dims, origin, spacing) = lattice_for_box(bounds, res)?;
        Self::sample(field, dims, origin, spacing)
    }

    /// Overwrites every node with `field`'s value there, in parallel
    /// ([`Field3::values_on_lattice`]).
    pub fn fill_from<F: Field3 + ?Sized>(&mut self, field: &F) {
        field.values_on_lattice(self.dims, self.origin, self.spacing, &mut self.data);
    }

    /// Trilinear interpolation at world point `p`; points outside the grid
    /// are clamped to its boundary. Exact at nodes.
    pub fn trilinear(&self, p: Vec3) -> f32 {
        let (base, w) = self.cell_and_weights(p);
        trilinear_blend(
            |i, j, k| self.data[self.index(base.x + i as u32, base.y + j as u32, base.z + k as u32)],
            w,
        )
    }

    /// Lower corner node of the cell containing `p` (clamped) and the local
    /// weights in `[0, 1]³`. Axes with a single node use weight 0.
    fn cell_and_weights(&self, p: Vec3) -> (UVec3, Vec3) {
        let g = self.to_grid(p);
        let max_cell = self.dims.saturating_sub(UVec3::splat(2)).as_vec3();
        let g = g.clamp(Vec3::ZERO, (self.dims - UVec3::ONE).as_vec3());
        let base = g.floor().min(max_cell);
        let mut w = g - base;
        let single = self.dims.cmpeq(UVec3::ONE);
        w = Vec3::select(single, Vec3::ZERO, w);
        let mut b = base.as_uvec3();
        b = UVec3::select(single, UVec3::ZERO, b);
        (b, w)
    }

    /// Central-difference gradient at node `(i, j, k)` (one-sided at the
    /// boundary), in value units per world unit.
    pub fn node_gradient(&self, i: u32, j: u32, k: u32) -> Vec3 {
        let n = IVec3::new(i as i32, j as i32, k as i32);
        let max = self.dims.as_ivec3() - IVec3::ONE;
        let mut g = Vec3::ZERO;
        for axis in 0..3 {
            let mut lo = n;
            let mut hi = n;
            lo[axis] = (n[axis] - 1).max(0);
            hi[axis] = (n[axis] + 1).min(max[axis]);
            let steps = (hi[axis] - lo[axis]) as f32;
            if steps > 0.0 {
                let v = |q: IVec3| self.data[self.index(q.x as u32, q.y as u32, q.z as u32)];
                g[axis] = (v(hi) - v(lo)) / (steps * self.spacing);
            }
        }
        g
    }
}

impl Field3 for Grid3<f32> {
    fn value(&self, p: Vec3) -> f32 {
        self.trilinear(p)
    }

    /// Trilinear interpolation of the central-difference node gradients.
    fn gradient(&self, p: Vec3) -> Vec3 {
        let (b, w) = self.cell_and_weights(p);
        let mut g = Vec3::ZERO;
        for corner in 0..8u32 {
            let d = UVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
            let wt = Vec3::select(d.cmpeq(UVec3::ONE), w, Vec3::ONE - w);
            let n = (b + d).min(self.dims - UVec3::ONE);
            g += wt.x * wt.y * wt.z * self.node_gradient(n.x, n.y, n.z);
        }
        g
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(Grid3::bounds(self))
    }
}

/// A dense 2D grid of values on nodes (images, slices, 2D shapes): node `(i,
/// j)` at `origin + spacing · (i, j)`, x-fastest storage.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid2<T> {
    dims: UVec2,
    origin: Vec2,
    spacing: f32,
    data: Vec<T>,
}

impl<T: Clone> Grid2<T> {
    /// A grid over existing x-fastest `data`.
    ///
    /// # Errors
    /// [`GridError::DataLength`] when `data` does not hold one value per node,
    /// [`GridError::InvalidGeometry`] for a bad spacing or origin,
    /// [`GridError::TooSmall`] for a zero dimension.
    pub fn from_vec(dims: UVec2, origin: Vec2, spacing: f32, data: Vec<T>) -> Result<Self, GridError> {
        let d3 = dims.extend(1);
        check_geometry(d3, origin.extend(0.0), spacing, 1)?;
        let expected = dims.x as usize * dims.y as usize;
        if data.len() != expected {
            return Err(GridError::DataLength { dims: d3, expected, got: data.len() });
        }
        Ok(Self { dims, origin, spacing, data })
    }

    /// Node counts per axis.
    pub fn dims(&self) -> UVec2 {
        self.dims
    }

    /// World position of node `(0, 0)`.
    pub fn origin(&self) -> Vec2 {
        self.origin
    }

    /// Distance between neighbouring nodes.
    pub fn spacing(&self) -> f32 {
        self.spacing
    }

    /// The values, x-fastest.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// Value at node `(i, j)`, or `None` outside.
    pub fn get(&self, i: u32, j: u32) -> Option<&T> {
        (i < self.dims.x && j < self.dims.y)
            .then(|| &self.data[i as usize + self.dims.x as usize * j as usize])
    }

    /// World position of node `(i, j)`.
    pub fn position(&self, i: u32, j: u32) -> Vec2 {
        self.origin + self.spacing * Vec2::new(i as f32, j as f32)
    }
}

/// The trilinear blend of a cell's eight corner values `corner(i, j, k)`
/// (`i, j, k ∈ {0, 1}` along x, y, z) at the weights `w ∈ [0, 1]³`:
/// lerps along x, then y, then z (the order fixes the rounding, so every
/// caller interpolates bit for bit alike).
#[inline]
pub fn trilinear_blend(corner: impl Fn(usize, usize, usize) -> f32, w: Vec3) -> f32 {
    let c = corner;
    let x00 = c(0, 0, 0) + w.x * (c(1, 0, 0) - c(0, 0, 0));
    let x10 = c(0, 1, 0) + w.x * (c(1, 1, 0) - c(0, 1, 0));
    let x01 = c(0, 0, 1) + w.x * (c(1, 0, 1) - c(0, 0, 1));
    let x11 = c(0, 1, 1) + w.x * (c(1, 1, 1) - c(0, 1, 1));
    let y0 = x00 + w.y * (x10 - x00);
    let y1 = x01 + w.y * (x11 - x01);
    y0 + w.z * (y1 - y0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ramp() -> Grid3<f32> {
        let f = |p: Vec3| 1.0 + 2.0 * p.x - 3.0 * p.y + 0.5 * p.z;
        Grid3::sample(&f, UVec3::new(5, 6, 7), Vec3::new(-1.0, -2.0, 0.5), 0.25).unwrap()
    }

    #[test]
    fn index_roundtrip_and_positions() {
        let g = ramp();
        for idx in [0, 1, 5, 29, 100, g.len() - 1] {
            let n = g.node_of(idx);
            assert_eq!(g.index(n.x, n.y, n.z), idx);
        }
        assert_eq!(g.position(4, 5, 6), Vec3::new(0.0, -0.75, 2.0));
        assert_eq!(g.bounds().max, Vec3::new(0.0, -0.75, 2.0));
    }

    #[test]
    fn trilinear_reproduces_affine_fields_and_clamps() {
        let g = ramp();
        let f = |p: Vec3| 1.0 + 2.0 * p.x - 3.0 * p.y + 0.5 * p.z;
        for p in [Vec3::new(-0.6, -1.3, 1.1), Vec3::new(-0.01, -0.8, 1.99)] {
            assert!((g.value(p) - f(p)).abs() < 1e-5, "at {p}: {} vs {}", g.value(p), f(p));
            assert!((g.gradient(p) - Vec3::new(2.0, -3.0, 0.5)).length() < 1e-4);
        }
        let outside = Vec3::new(10.0, -1.5, 1.0);
        assert_eq!(g.value(outside), f(Vec3::new(0.0, -1.5, 1.0)));
    }

    #[test]
    fn memory_limit_is_an_error_not_an_abort() {
        let err = Grid3::new(UVec3::splat(100_000), Vec3::ZERO, 1.0, 0.0f32).unwrap_err();
        assert!(matches!(err, GridError::TooLarge { .. }), "{err}");
        assert!(Grid3::new(UVec3::new(0, 1, 1), Vec3::ZERO, 1.0, 0u8).is_err());
        assert!(Grid3::new(UVec3::ONE, Vec3::ZERO, f32::NAN, 0u8).is_err());
        assert!(Grid3::from_vec(UVec3::splat(2), Vec3::ZERO, 1.0, vec![0u8; 7]).is_err());
    }

    #[test]
    fn slices_pick_the_right_nodes() {
        let g = ramp();
        let s = g.slice(1, 2).unwrap();
        assert_eq!(s.dims(), UVec2::new(5, 7));
        assert_eq!(*s.get(3, 4).unwrap(), *g.get(3, 2, 4).unwrap());
        assert!(g.slice(2, 7).is_err());
        assert!(g.slice(3, 0).is_err());
    }

    #[test]
    fn lattice_for_box_covers_the_box() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 0.5));
        let (dims, origin, h) = lattice_for_box(&b, 65).unwrap();
        assert_eq!(dims.x, 65);
        assert!((h - 2.0 / 64.0).abs() < 1e-7);
        let max = origin + (dims - UVec3::ONE).as_vec3() * h;
        assert!(origin.cmple(b.min + 1e-6).all() && max.cmpge(b.max - 1e-6).all());
    }

    proptest! {
        #[test]
        fn sampling_is_exact_at_nodes(i in 0u32..5, j in 0u32..6, k in 0u32..7) {
            let g = ramp();
            let p = g.position(i, j, k);
            prop_assert_eq!(g.value(p), *g.get(i, j, k).unwrap());
        }
    }
}
