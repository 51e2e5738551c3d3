//! The paper's 2D example shapes as grayscale images: the X and the O of
//! Fig. 1 and 3, for the X → O transformation in tests, demos and docs.

use glam::{UVec2, Vec2};
use isomorph_common::Grid2;

/// An antialiased grayscale image (1 inside, 0 outside, mid-gray 0.5 on the
/// boundary) of a signed distance `sd` (positive inside) on `n × n` pixels
/// over `[-0.5, 0.5]²`, pixel centres as nodes.
///
/// # Panics
/// If `n` is 0.
pub fn raster(n: u32, sd: impl Fn(Vec2) -> f32) -> Grid2<f32> {
    assert!(n > 0, "raster: an image needs pixels");
    let h = 1.0 / n as f32;
    let o = Vec2::splat(-0.5 + 0.5 * h);
    let data = (0..n * n)
        .map(|k| (sd(o + h * Vec2::new((k % n) as f32, (k / n) as f32)) / h + 0.5).clamp(0.0, 1.0))
        .collect();
    Grid2::from_vec(UVec2::splat(n), o, h, data).expect("n² pixels")
}

/// The X: two crossed bars 0.66 long and 0.14 wide, on `n × n` pixels.
///
/// # Panics
/// If `n` is 0.
pub fn x_image(n: u32) -> Grid2<f32> {
    let bar = |p: Vec2, d: Vec2| {
        let along = p.dot(d).abs() - 0.33;
        let across = p.perp_dot(d).abs() - 0.07;
        -along.max(across)
    };
    let d1 = Vec2::new(1.0, 1.0).normalize();
    let d2 = Vec2::new(1.0, -1.0).normalize();
    raster(n, |p| bar(p, d1).max(bar(p, d2)))
}

/// The O: a ring of mid-radius 0.26 and width 0.18, on `n × n` pixels.
///
/// # Panics
/// If `n` is 0.
pub fn o_image(n: u32) -> Grid2<f32> {
    raster(n, |p| 0.09 - (p.length() - 0.26).abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_o_has_a_hole_and_the_x_a_centre() {
        let (x, o) = (x_image(32), o_image(32));
        let centre = |g: &Grid2<f32>| *g.get(16, 16).unwrap();
        assert_eq!(centre(&x), 1.0);
        assert_eq!(centre(&o), 0.0);
        // The ring at radius 0.26 right of the centre: pixel 16 + 0.26·32 ≈ 24.
        assert_eq!(*o.get(24, 16).unwrap(), 1.0);
        assert_eq!(*x.get(1, 16).unwrap(), 0.0);
    }
}
