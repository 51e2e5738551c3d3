//! [`Image`]: an RGB8 pixel buffer with PNG output.

use super::RenderError;
use std::io::{BufWriter, Write};
use std::path::Path;

/// An 8-bit sRGB image, rows top to bottom, pixels left to right.
///
/// The buffer takes `3 · width · height` bytes; a side of zero gives an
/// image without pixels (which cannot be written as PNG).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    pixels: Vec<[u8; 3]>,
}

impl Image {
    /// A `width × height` image filled with `background`.
    pub fn new(width: u32, height: u32, background: [u8; 3]) -> Self {
        Self { width, height, pixels: vec![background; width as usize * height as usize] }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major from the top-left corner (`x + width · y`).
    pub fn pixels(&self) -> &[[u8; 3]] {
        &self.pixels
    }

    /// All pixels, mutable, row-major from the top-left corner.
    pub fn pixels_mut(&mut self) -> &mut [[u8; 3]] {
        &mut self.pixels
    }

    /// The pixel at column `x`, row `y` (`None` outside the image).
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        (x < self.width && y < self.height).then(|| self.pixels[self.index(x, y)])
    }

    /// Sets the pixel at column `x`, row `y`; positions outside the image are
    /// ignored, so drawing may run over the border.
    pub fn set(&mut self, x: i64, y: i64, color: [u8; 3]) {
        if (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y) {
            let i = self.index(x as u32, y as u32);
            self.pixels[i] = color;
        }
    }

    /// Fills the rectangle with top-left corner `(x, y)` and the given size,
    /// clipped to the image.
    pub fn fill_rect(&mut self, x: i64, y: i64, width: u32, height: u32, color: [u8; 3]) {
        for row in y..y + i64::from(height) {
            for col in x..x + i64::from(width) {
                self.set(col, row, color);
            }
        }
    }

    /// Copies `other` into this image with its top-left corner at `(x, y)`,
    /// clipped to this image.
    pub fn blit(&mut self, other: &Image, x: i64, y: i64) {
        for (row, line) in other.pixels.chunks_exact(other.width.max(1) as usize).enumerate() {
            for (col, &color) in line.iter().enumerate() {
                self.set(x + col as i64, y + row as i64, color);
            }
        }
    }

    /// Writes the image as an 8-bit RGB PNG file at `path`.
    ///
    /// # Errors
    /// [`RenderError::EmptyImage`] for an image with a side of zero,
    /// [`RenderError::Io`] when the file cannot be created or written,
    /// [`RenderError::Encode`] when the encoder fails.
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        if self.pixels.is_empty() {
            return Err(self.empty_error());
        }
        let file = std::fs::File::create(path)?;
        let mut out = BufWriter::new(file);
        self.write_png_to(&mut out)?;
        out.flush()?;
        Ok(())
    }

    /// Writes the image as an 8-bit RGB PNG stream to `out`.
    ///
    /// # Errors
    /// As [`Image::write_png`].
    pub fn write_png_to(&self, out: impl Write) -> Result<(), RenderError> {
        if self.pixels.is_empty() {
            return Err(self.empty_error());
        }
        let mut encoder = png::Encoder::new(out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(self.pixels.as_flattened())?;
        writer.finish()?;
        Ok(())
    }

    fn index(&self, x: u32, y: u32) -> usize {
        x as usize + self.width as usize * y as usize
    }

    fn empty_error(&self) -> RenderError {
        RenderError::EmptyImage { width: self.width, height: self.height }
    }
}

impl From<png::EncodingError> for RenderError {
    fn from(e: png::EncodingError) -> Self {
        match e {
            png::EncodingError::IoError(io) => RenderError::Io(io),
            other => RenderError::Encode(format!("PNG encoding failed: {other}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decodes a PNG stream into its size and RGB pixels.
    fn decode(bytes: &[u8]) -> (u32, u32, Vec<[u8; 3]>) {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        let pixels = buf[..info.buffer_size()].chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        (info.width, info.height, pixels)
    }

    #[test]
    fn png_round_trip_keeps_every_pixel() {
        let mut image = Image::new(7, 5, [10, 20, 30]);
        for (i, p) in image.pixels_mut().iter_mut().enumerate() {
            *p = [i as u8, (3 * i) as u8, 255 - i as u8];
        }
        let mut bytes = Vec::new();
        image.write_png_to(&mut bytes).unwrap();
        let (w, h, pixels) = decode(&bytes);
        assert_eq!((w, h), (7, 5));
        assert_eq!(pixels, image.pixels());

        let path = std::env::temp_dir().join(format!("isomorph-render-{}.png", std::process::id()));
        image.write_png(&path).unwrap();
        let from_file = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(decode(&from_file).2, image.pixels());
    }

    #[test]
    fn empty_image_is_an_error_not_a_panic() {
        let image = Image::new(0, 4, [0; 3]);
        assert!(matches!(
            image.write_png_to(Vec::new()),
            Err(RenderError::EmptyImage { width: 0, height: 4 })
        ));
    }

    #[test]
    fn drawing_is_clipped_to_the_image() {
        let mut image = Image::new(4, 3, [0; 3]);
        image.fill_rect(-2, 1, 4, 10, [9; 3]);
        let filled: Vec<bool> = image.pixels().iter().map(|p| p[0] == 9).collect();
        assert_eq!(filled, [false, false, false, false, true, true, false, false, true, true, false, false]);
        let patch = Image::new(2, 2, [5; 3]);
        image.blit(&patch, 3, 2);
        assert_eq!(image.get(3, 2), Some([5; 3]));
        assert_eq!(image.get(4, 2), None);
        assert_eq!(image.pixels().iter().filter(|p| p[0] == 5).count(), 1);
    }
}
