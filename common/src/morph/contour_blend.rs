//! The 2D naive baseline: linear interpolation of two 2D shapes' signed
//! distances ([`ContourBlend`]), the top row of Turk & O'Brien's Figs. 2–3
//! that the variational transformation is compared with.

use super::{MorphError, Side, check, check_time};
use crate::Grid2;
use crate::control::Control;
use crate::marching_squares::{Polyline2, marching_squares};
use glam::{UVec2, Vec2};
use rayon::prelude::*;

/// Two 2D shapes given as images (inside above a level) morphed by
/// `d(t) = (1 − t) d_A + t d_B`, with `d_A`, `d_B` their exact signed
/// distances (positive inside, world units) to the images' contours,
/// sampled once on one lattice over both images' boxes. In-between shapes
/// shrink, pinch and pop rather than travel: it is the comparison, not a
/// method.
///
/// ```
/// use isomorph_common::{Control, ContourBlend, Grid2};
/// use isomorph_common::glam::{UVec2, Vec2};
///
/// // Two discs of radius 6 pixels, 10 pixels apart, as 0–1 images.
/// let disc = |c: Vec2| {
///     let data = (0..32 * 32).map(|i| {
///         let p = Vec2::new((i % 32) as f32, (i / 32) as f32);
///         (0.5 + 0.25 * (6.0 - p.distance(c))).clamp(0.0, 1.0)
///     });
///     Grid2::from_vec(UVec2::splat(32), Vec2::ZERO, 1.0, data.collect()).unwrap()
/// };
/// let blend = ContourBlend::new(&disc(Vec2::new(11.0, 16.0)), &disc(Vec2::new(21.0, 16.0)), 0.5, 64, &Control::new())?;
/// // Half-way the shape is the ellipse |p − a| + |p − b| < 12: it has lost
/// // almost half its area instead of moving (a disc has 113 px², it 62).
/// let middle = blend.frame_grid(0.5)?;
/// let inside = middle.data().iter().filter(|&&v| v > 0.0).count();
/// let start = blend.frame_grid(0.0)?.data().iter().filter(|&&v| v > 0.0).count();
/// assert!(3 * inside < 2 * start);
/// # Ok::<(), isomorph_common::MorphError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ContourBlend {
    a: Grid2<f32>,
    b: Grid2<f32>,
}

impl ContourBlend {
    /// The blend of images `a` and `b` (any lattices; inside where a value is
    /// above `level`), their distances sampled with `res` nodes (2–4096)
    /// along the longer edge of the union of their boxes.
    ///
    /// Cost: every node against every contour segment, in parallel.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] for `res` or a non-finite `level`,
    /// [`MorphError::EmptyShape`] when an image has no contour at `level`,
    /// [`MorphError::Cancelled`].
    pub fn new(
        a: &Grid2<f32>,
        b: &Grid2<f32>,
        level: f32,
        res: u32,
        control: &Control,
    ) -> Result<Self, MorphError> {
        check::count("resolution", u64::from(res), 2, 4096)?;
        if !level.is_finite() {
            return Err(MorphError::bad_setting("level", format!("{level}"), "a finite value"));
        }
        let (lo_a, hi_a) = corners(a);
        let (lo_b, hi_b) = corners(b);
        let (lo, hi) = (lo_a.min(lo_b), hi_a.max(hi_b));
        let size = hi - lo;
        let spacing = size.max_element() / (res - 1) as f32;
        let dims = (size / spacing).ceil().as_uvec2() + UVec2::ONE;
        control.progress("distance images", Some(0.0), String::new);
        let da = signed_distance(a, level, Side::Source, dims, lo, spacing, control)?;
        control.progress("distance images", Some(0.5), String::new);
        let db = signed_distance(b, level, Side::Target, dims, lo, spacing, control)?;
        Ok(Self { a: da, b: db })
    }

    /// The shape at `t` on the blend's lattice: `(1 − t) d_A + t d_B`,
    /// positive inside, surface at 0.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`] for NaN or `t ∉ [0, 1]`.
    pub fn frame_grid(&self, t: f32) -> Result<Grid2<f32>, MorphError> {
        let t = check_time(t)?;
        let data = self.a.data().iter().zip(self.b.data()).map(|(a, b)| (1.0 - t) * a + t * b).collect();
        Ok(Grid2::from_vec(self.a.dims(), self.a.origin(), self.a.spacing(), data)?)
    }

    /// The contours of the shape at `t` (counter-clockwise around inside).
    ///
    /// # Errors
    /// As [`ContourBlend::frame_grid`].
    pub fn contours(&self, t: f32) -> Result<Vec<Polyline2>, MorphError> {
        Ok(marching_squares(&self.frame_grid(t)?, 0.0))
    }
}

/// Lowest and highest node positions of `grid`.
fn corners(grid: &Grid2<f32>) -> (Vec2, Vec2) {
    let d = grid.dims();
    (grid.origin(), grid.position(d.x.saturating_sub(1), d.y.saturating_sub(1)))
}

/// `image`'s signed distance to its contour at `level` on the lattice
/// `dims`, `origin`, `spacing`: the exact distance to the contour's
/// segments, positive where the image (bilinear, clamped at its border) is
/// above `level`.
fn signed_distance(
    image: &Grid2<f32>,
    level: f32,
    side: Side,
    dims: UVec2,
    origin: Vec2,
    spacing: f32,
    control: &Control,
) -> Result<Grid2<f32>, MorphError> {
    let segments: Vec<(Vec2, Vec2)> = marching_squares(image, level)
        .iter()
        .flat_map(|line| {
            let ends = line.points.last().zip(line.points.first());
            let closing = ends.filter(|_| line.closed).map(|(&last, &first)| (last, first));
            line.points.windows(2).map(|w| (w[0], w[1])).chain(closing)
        })
        .collect();
    if segments.is_empty() {
        return Err(MorphError::EmptyShape {
            side,
            detail: format!("the image has no contour at level {level}"),
        });
    }
    let width = dims.x as usize;
    let mut data = vec![0.0f32; width * dims.y as usize];
    control.install(|| {
        data.par_chunks_mut(width).enumerate().try_for_each(|(j, row)| {
            control.check()?;
            for (i, value) in row.iter_mut().enumerate() {
                let p = origin + spacing * Vec2::new(i as f32, j as f32);
                let d2 =
                    segments.iter().map(|&(a, b)| segment_distance_squared(p, a, b)).fold(f32::MAX, f32::min);
                *value = if bilinear(image, p) > level { d2.sqrt() } else { -d2.sqrt() };
            }
            Ok::<(), MorphError>(())
        })
    })?;
    Ok(Grid2::from_vec(dims, origin, spacing, data)?)
}

/// Squared distance from `p` to the segment `a`–`b`.
fn segment_distance_squared(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let ab = b - a;
    let s = if ab == Vec2::ZERO { 0.0 } else { ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) };
    (a + s * ab).distance_squared(p)
}

/// Bilinear value of `image` at `p`, clamped to its border.
fn bilinear(image: &Grid2<f32>, p: Vec2) -> f32 {
    let max = (image.dims() - UVec2::ONE).as_vec2();
    let g = ((p - image.origin()) / image.spacing()).clamp(Vec2::ZERO, max);
    let base = g.floor().min((max - Vec2::ONE).max(Vec2::ZERO));
    let w = g - base;
    let (i, j) = (base.x as u32, base.y as u32);
    let at = |di: u32, dj: u32| {
        image.get((i + di).min(max.x as u32), (j + dj).min(max.y as u32)).copied().unwrap_or(0.0)
    };
    let bottom = at(0, 0) + w.x * (at(1, 0) - at(0, 0));
    let top = at(0, 1) + w.x * (at(1, 1) - at(0, 1));
    bottom + w.y * (top - bottom)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(n: u32, c: Vec2, r: f32) -> Grid2<f32> {
        let data = (0..n * n)
            .map(|i| {
                let p = Vec2::new((i % n) as f32, (i / n) as f32);
                (0.5 + 0.25 * (r - p.distance(c))).clamp(0.0, 1.0)
            })
            .collect();
        Grid2::from_vec(UVec2::splat(n), Vec2::ZERO, 1.0, data).unwrap()
    }

    #[test]
    fn endpoints_are_the_inputs_distances() {
        let (a, b) = (disc(40, Vec2::new(12.0, 20.0), 7.0), disc(40, Vec2::new(27.0, 20.0), 5.0));
        let blend = ContourBlend::new(&a, &b, 0.5, 40, &Control::new()).unwrap();
        let (start, end) = (blend.frame_grid(0.0).unwrap(), blend.frame_grid(1.0).unwrap());
        for (j, i) in [(20u32, 12u32), (20, 27), (5, 5), (20, 19)] {
            let p = start.position(i, j);
            let (da, db) = (7.0 - p.distance(Vec2::new(12.0, 20.0)), 5.0 - p.distance(Vec2::new(27.0, 20.0)));
            assert!(
                (start.get(i, j).unwrap() - da).abs() < 0.1,
                "start at {p}: {} vs {da}",
                start.get(i, j).unwrap()
            );
            assert!(
                (end.get(i, j).unwrap() - db).abs() < 0.1,
                "end at {p}: {} vs {db}",
                end.get(i, j).unwrap()
            );
        }
        // Disjoint discs: the middle frame splits into two pieces or
        // vanishes in between, the artefact the paper shows.
        let middle = blend.contours(0.5).unwrap();
        assert!(middle.len() != 1, "{} contours half-way", middle.len());
    }

    #[test]
    fn bad_input_is_an_error() {
        let a = disc(16, Vec2::splat(8.0), 4.0);
        let blank = Grid2::from_vec(UVec2::splat(16), Vec2::ZERO, 1.0, vec![0.0; 256]).unwrap();
        let err = ContourBlend::new(&a, &blank, 0.5, 32, &Control::new()).unwrap_err();
        assert!(matches!(err, MorphError::EmptyShape { side: Side::Target, .. }), "{err}");
        assert!(matches!(
            ContourBlend::new(&a, &a, 0.5, 1, &Control::new()),
            Err(MorphError::BadSetting { .. })
        ));
        let blend = ContourBlend::new(&a, &a, 0.5, 32, &Control::new()).unwrap();
        assert!(matches!(blend.frame_grid(f32::NAN), Err(MorphError::InvalidTime(_))));
    }
}
