//! Constraints of a 2D shape from a grayscale image (paper §4.1).
//!
//! White (high) pixels are inside, black outside. Between every pixel and its
//! east and north neighbour whose values straddle the mid-gray `m`, a
//! boundary constraint (0) is placed where the linearly interpolated image
//! equals `m`; the image gradient there (central differences at the two
//! pixels, interpolated linearly) gives the inward direction, and a normal
//! constraint (1) is placed one pixel width along it.

use crate::error::RbfError;
use crate::interpolant::Constraint;
use glam::{UVec2, Vec2};
use isomorph_common::Grid2;
use std::path::Path;

/// Boundary and normal constraints of the shape in `image` (node values,
/// bright = inside), with the boundary at level `mid` (0.5 for images read
/// by [`read_png_gray`]).
///
/// # Errors
/// [`RbfError::EmptyShape`] when no pair of neighbouring pixels straddles
/// `mid` (a blank image); [`RbfError::NonFinite`] for a NaN pixel (index in
/// x-fastest order) or `mid`.
pub fn image_constraints(image: &Grid2<f32>, mid: f32) -> Result<Vec<Constraint<2>>, RbfError> {
    if !mid.is_finite() {
        return Err(RbfError::InvalidSetting("the mid-gray level must be finite"));
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

/// Reads a PNG as a grayscale [`Grid2`] with values in `[0, 1]` (color is
/// converted by luma `0.299 R + 0.587 G + 0.114 B`, alpha ignored, 16-bit
/// kept exact), y up (the top image row becomes the last grid row), fitted
/// into `[-0.5, 0.5]²`: pixel spacing `1 / max(width, height)`, centred.
///
/// # Errors
/// [`RbfError::Image`] when the file cannot be opened or decoded.
pub fn read_png_gray(path: &Path) -> Result<Grid2<f32>, RbfError> {
    let file = std::fs::File::open(path).map_err(|e| RbfError::Image(format!("{}: {e}", path.display())))?;
    decode_png_gray(std::io::BufReader::new(file))
}

/// [`read_png_gray`] from any reader of PNG bytes.
///
/// # Errors
/// [`RbfError::Image`] when the data cannot be decoded.
pub fn decode_png_gray<R: std::io::BufRead + std::io::Seek>(reader: R) -> Result<Grid2<f32>, RbfError> {
    let img = |e: png::DecodingError| RbfError::Image(e.to_string());
    let mut decoder = png::Decoder::new(reader);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(img)?;
    let size = reader.output_buffer_size().ok_or_else(|| RbfError::Image("image too large".into()))?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(img)?;
    let (w, h) = (info.width as usize, info.height as usize);
    let channels = info.color_type.samples();
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let bytes = if sixteen { 2 } else { 1 };
    let sample = |px: usize, c: usize| -> f32 {
        let k = (px * channels + c) * bytes;
        if sixteen {
            f32::from(u16::from_be_bytes([buf[k], buf[k + 1]])) / 65535.0
        } else {
            f32::from(buf[k]) / 255.0
        }
    };
    let mut data = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let px = y * w + x;
            let v = if channels >= 3 {
                0.299 * sample(px, 0) + 0.587 * sample(px, 1) + 0.114 * sample(px, 2)
            } else {
                sample(px, 0)
            };
            data[x + w * (h - 1 - y)] = v;
        }
    }
    let spacing = 1.0 / w.max(h) as f32;
    let origin = -0.5 * spacing * Vec2::new((w - 1) as f32, (h - 1) as f32);
    Grid2::from_vec(UVec2::new(w as u32, h as u32), origin, spacing, data).map_err(RbfError::from)
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn blank_image_and_png_errors() {
        let blank = Grid2::from_vec(UVec2::splat(4), Vec2::ZERO, 1.0, vec![0.0; 16]).unwrap();
        assert!(matches!(image_constraints(&blank, 0.5), Err(RbfError::EmptyShape("image"))));
        assert!(matches!(
            decode_png_gray(std::io::Cursor::new(b"not a png".to_vec())),
            Err(RbfError::Image(_))
        ));
        assert!(matches!(read_png_gray(Path::new("/nonexistent.png")), Err(RbfError::Image(_))));
    }

    #[test]
    fn png_roundtrip_is_y_up_and_centred() {
        // 3 × 2 gray image: top row white, bottom row black.
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, 3, 2);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().unwrap();
            w.write_image_data(&[255, 255, 255, 0, 0, 0]).unwrap();
        }
        let g = decode_png_gray(std::io::Cursor::new(bytes)).unwrap();
        assert_eq!(g.dims(), UVec2::new(3, 2));
        assert_eq!(g.data(), &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        assert!((g.spacing() - 1.0 / 3.0).abs() < 1e-7);
        assert!((g.position(1, 0).x).abs() < 1e-7);
        let cs = image_constraints(&g, 0.5).unwrap();
        // Three vertical crossings; normals point up (towards white).
        assert_eq!(cs.len(), 6);
        assert!(cs[1].position[1] > cs[0].position[1]);
    }
}
