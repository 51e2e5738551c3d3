//! Grayscale PNG input (Turk & O'Brien §4.1: shapes drawn as images).

use glam::{UVec2, Vec2};
use isomorph_common::Grid2;
use std::path::Path;

/// A PNG file could not be opened or decoded (the message says why).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("PNG input: {0}")]
pub struct PngError(pub String);

/// Reads a PNG as a grayscale [`Grid2`] with values in `[0, 1]` (color is
/// converted by luma `0.299 R + 0.587 G + 0.114 B`, alpha ignored, 16-bit
/// kept exact), y up (the top image row becomes the last grid row), fitted
/// into `[-0.5, 0.5]²`: pixel spacing `1 / max(width, height)`, centred.
///
/// # Errors
/// [`PngError`] when the file cannot be opened or decoded.
pub fn read_png_gray(path: &Path) -> Result<Grid2<f32>, PngError> {
    let file = std::fs::File::open(path).map_err(|e| PngError(format!("{}: {e}", path.display())))?;
    decode_png_gray(std::io::BufReader::new(file))
}

/// [`read_png_gray`] from any reader of PNG bytes.
///
/// # Errors
/// [`PngError`] when the data cannot be decoded.
pub fn decode_png_gray<R: std::io::BufRead + std::io::Seek>(reader: R) -> Result<Grid2<f32>, PngError> {
    let img = |e: png::DecodingError| PngError(e.to_string());
    let mut decoder = png::Decoder::new(reader);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(img)?;
    let size = reader.output_buffer_size().ok_or_else(|| PngError("image too large".into()))?;
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
    Grid2::from_vec(UVec2::new(w as u32, h as u32), origin, spacing, data)
        .map_err(|e| PngError(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_files_are_errors() {
        assert!(decode_png_gray(std::io::Cursor::new(b"not a png".to_vec())).is_err());
        let e = read_png_gray(Path::new("/nonexistent.png")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent.png"), "{e}");
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
    }
}
