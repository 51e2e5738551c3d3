//! Constraints of a 2D shape from a grayscale image (paper §4.1).

use crate::error::RbfError;
use crate::interpolant::Constraint;
use glam::Vec2;
use isomorph_common::Grid2;
use isomorph_common::MorphError;

/// Boundary and normal constraints of the shape in `image` (node values,
/// bright = inside), with the boundary at level `mid` (0.5 for images read
/// by `isomorph_io::png_gray::read_png_gray`).
///
/// White (high) pixels are inside, black outside. Between every pixel and its
/// east and north neighbour whose values straddle the mid-gray `m`, a
/// boundary constraint (0) is placed where the linearly interpolated image
/// equals `m`; the image gradient there (central differences at the two
/// pixels, interpolated linearly) gives the inward direction, and a normal
/// constraint (1) is placed one pixel width along it.
///
/// # Errors
/// [`RbfError::EmptyShape`] when no pair of neighbouring pixels straddles
/// `mid` (a blank image); [`RbfError::NonFinite`] for a NaN pixel (index in
/// x-fastest order) or `mid`.
pub fn image_constraints(image: &Grid2<f32>, mid: f32) -> Result<Vec<Constraint<2>>, RbfError> {
    if !mid.is_finite() {
        return Err(MorphError::bad_setting("mid", mid, "a finite number").into());
    }
    if let Some(index) = image.data().iter().position(|v| !v.is_finite()) {
        return Err(RbfError::NonFinite { index, what: "value" });
    }
    let (w, h) = (image.dims().x, image.dims().y);
    let h_px = image.spacing();
    let at = |i: u32, j: u32| image.data()[(i + w * j) as usize];
    // Central differences (one-sided at the border), in value per world unit.
    let grad = |i: u32, j: u32| {
        let (i0, i1) = (i.saturating_sub(1), (i + 1).min(w - 1));
        let (j0, j1) = (j.saturating_sub(1), (j + 1).min(h - 1));
        let gx = if i1 > i0 { (at(i1, j) - at(i0, j)) / ((i1 - i0) as f32 * h_px) } else { 0.0 };
        let gy = if j1 > j0 { (at(i, j1) - at(i, j0)) / ((j1 - j0) as f32 * h_px) } else { 0.0 };
        Vec2::new(gx, gy)
    };
    let mut out = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let a = at(i, j);
            for (di, dj) in [(1u32, 0u32), (0, 1)] {
                let (ni, nj) = (i + di, j + dj);
                if ni >= w || nj >= h {
                    continue;
                }
                let b = at(ni, nj);
                if !((a < mid && b > mid) || (a > mid && b < mid)) {
                    continue;
                }
                let s = (mid - a) / (b - a);
                let pa = image.position(i, j);
                let p = pa + s * (image.position(ni, nj) - pa);
                let g = (1.0 - s) * grad(i, j) + s * grad(ni, nj);
                // Inward = towards brighter pixels; fall back to the pixel pair.
                let dir = g.try_normalize().unwrap_or_else(|| {
                    let d = Vec2::new(di as f32, dj as f32);
                    if b > a { d } else { -d }
                });
                out.push(Constraint::new(p.to_array(), 0.0));
                out.push(Constraint::new((p + h_px * dir).to_array(), 1.0));
            }
        }
    }
    if out.is_empty() {
        return Err(RbfError::EmptyShape("image"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::UVec2;

    /// A disk of radius `r` (pixels) in an `n × n` image, antialiased.
    fn disk(n: u32, r: f32) -> Grid2<f32> {
        let c = (n - 1) as f32 / 2.0;
        let data = (0..n * n)
            .map(|k| {
                let p = Vec2::new((k % n) as f32, (k / n) as f32) - Vec2::splat(c);
                (r - p.length() + 0.5).clamp(0.0, 1.0)
            })
            .collect();
        Grid2::from_vec(UVec2::splat(n), Vec2::ZERO, 1.0, data).unwrap()
    }

    #[test]
    fn disk_constraints_lie_on_the_circle_with_inward_normals() {
        let img = disk(32, 10.0);
        let cs = image_constraints(&img, 0.5).unwrap();
        assert!(cs.len() > 100, "{}", cs.len());
        let c = Vec2::splat(15.5);
        for pair in cs.chunks(2) {
            let b = Vec2::from_array(pair[0].position) - c;
            let n = Vec2::from_array(pair[1].position) - c;
            assert!((b.length() - 10.0).abs() < 0.1, "boundary at radius {}", b.length());
            assert!(
                (b.length() - n.length() - 1.0).abs() < 0.1,
                "normal constraint {} inside",
                b.length() - n.length()
            );
        }
    }

    #[test]
    fn blank_image_is_an_error() {
        let blank = Grid2::from_vec(UVec2::splat(4), Vec2::ZERO, 1.0, vec![0.0; 16]).unwrap();
        assert!(matches!(image_constraints(&blank, 0.5), Err(RbfError::EmptyShape("image"))));
    }
}
