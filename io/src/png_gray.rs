//! Grayscale PNG input (Turk & O'Brien §4.1: shapes drawn as images).

use glam::{UVec2, Vec2};
use isomorph_common::Grid2;
use std::path::Path;

/// Errors of PNG input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PngError {
    /// The file could not be opened or the data could not be decoded (the
    /// message says why).
    #[error("PNG input: {0}")]
    Decode(String),
    /// Decoding the image would need more memory than
    /// [`isomorph_common::memory_limit`] allows. Refused from the header's
    /// dimensions, before anything is allocated.
    #[error(
        "PNG input: a {width}×{height} image needs {requested} bytes to decode, over the memory limit of \
         {limit} bytes"
    )]
    TooLarge {
        /// Width the header claims, in pixels.
        width: u32,
        /// Height the header claims, in pixels.
        height: u32,
        /// Bytes needed: the decoded pixels plus the `f32` grid.
        requested: u128,
        /// The memory limit, in bytes.
        limit: usize,
    },
}

/// Reads a PNG as a grayscale [`Grid2`] with values in `[0, 1]` (color is
/// converted by luma `0.299 R + 0.587 G + 0.114 B`, alpha ignored, 16-bit
/// kept exact), y up (the top image row becomes the last grid row), fitted
/// into `[-0.5, 0.5]²`: pixel spacing `1 / max(width, height)`, centred.
///
/// # Errors
/// [`PngError::Decode`] when the file cannot be opened or decoded,
/// [`PngError::TooLarge`] when it would not fit the memory limit.
pub fn read_png_gray(path: &Path) -> Result<Grid2<f32>, PngError> {
    let file = std::fs::File::open(path).map_err(|e| PngError::Decode(format!("{}: {e}", path.display())))?;
    decode_png_gray(std::io::BufReader::new(file))
}

/// [`read_png_gray`] from any reader of PNG bytes.
///
/// The header is read first: an image whose decoded pixels and `f32` grid
/// together need more than [`isomorph_common::memory_limit`] bytes is
/// refused before any pixel buffer is allocated.
///
/// # Errors
/// [`PngError::Decode`] when the data cannot be decoded,
/// [`PngError::TooLarge`] when it would not fit the memory limit.
pub fn decode_png_gray<R: std::io::BufRead + std::io::Seek>(reader: R) -> Result<Grid2<f32>, PngError> {
    let img = |e: png::DecodingError| PngError::Decode(e.to_string());
    let mut decoder = png::Decoder::new(reader);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(img)?;
    let (width, height) = reader.info().size();
    let pixels = u128::from(width) * u128::from(height);
    let (color, depth) = reader.output_color_type();
    let pixel_bytes = color.samples() as u128 * if depth == png::BitDepth::Sixteen { 2 } else { 1 };
    // The decoded pixels (sub-byte depths are expanded) and the f32 grid.
    let requested = pixels * (pixel_bytes + 4);
    let limit = isomorph_common::memory_limit();
    let size = reader.output_buffer_size().filter(|_| requested <= limit as u128);
    let Some(size) = size else {
        return Err(PngError::TooLarge { width, height, requested, limit });
    };
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
        .map_err(|e| PngError::Decode(e.to_string()))
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

    /// CRC-32 (ISO-HDLC, as PNG chunks use) of `bytes`.
    fn crc32(bytes: &[u8]) -> u32 {
        !bytes.iter().fold(!0u32, |crc, &b| {
            (0..8).fold(crc ^ u32::from(b), |c, _| if c & 1 == 1 { (c >> 1) ^ 0xedb8_8320 } else { c >> 1 })
        })
    }

    /// A valid 1 × 1 gray PNG whose IHDR then claims `width` × `height`.
    fn claiming(width: u32, height: u32) -> Vec<u8> {
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, 1, 1);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            enc.write_header().unwrap().write_image_data(&[7]).unwrap();
        }
        // Signature (8), IHDR length (4), "IHDR" (4), width, height, ...,
        // then the CRC of type and data at 29.
        assert_eq!(&bytes[12..16], b"IHDR");
        assert_eq!(crc32(&bytes[12..29]).to_be_bytes(), bytes[29..33], "CRC checked on the valid file");
        bytes[16..20].copy_from_slice(&width.to_be_bytes());
        bytes[20..24].copy_from_slice(&height.to_be_bytes());
        let crc = crc32(&bytes[12..29]);
        bytes[29..33].copy_from_slice(&crc.to_be_bytes());
        bytes
    }

    #[test]
    fn huge_claimed_dimensions_are_refused_before_allocating() {
        let bytes = claiming(100_000, 100_000);
        assert!(bytes.len() < 100, "{} bytes", bytes.len());
        match decode_png_gray(std::io::Cursor::new(bytes)) {
            Err(PngError::TooLarge { width: 100_000, height: 100_000, requested, limit }) => {
                assert_eq!(requested, 100_000 * 100_000 * 5);
                assert_eq!(limit, isomorph_common::memory_limit());
            }
            other => panic!("{other:?}"),
        }
        // A plausible size gets past the check and fails on the missing data.
        assert!(matches!(decode_png_gray(std::io::Cursor::new(claiming(40, 30))), Err(PngError::Decode(_))));
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
