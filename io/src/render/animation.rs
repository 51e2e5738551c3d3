//! Animated previews: rendered frames as a looping GIF that plays forward
//! and back (the `gif` crate encodes; NeuQuant picks each frame's palette).

use super::{Image, RenderError};
use std::io::Write;
use std::path::Path;

/// Writes `frames` (all of one size) to `path` as a GIF that loops forever,
/// playing forward and then back (the end frames once per loop), each frame
/// shown for `delay` hundredths of a second.
///
/// # Errors
/// [`RenderError::EmptyImage`] for no frames, an empty frame or one wider
/// or higher than 65535 pixels; [`RenderError::Encode`] for frames of
/// different sizes; [`RenderError::Io`].
pub fn write_gif(frames: &[Image], delay: u16, path: impl AsRef<Path>) -> Result<(), RenderError> {
    let file = std::fs::File::create(path)?;
    let mut out = std::io::BufWriter::new(file);
    write_gif_to(frames, delay, &mut out)?;
    out.flush()?;
    Ok(())
}

/// [`write_gif`] into any writer.
///
/// ```
/// use isomorph_io::render::{Image, write_gif_to};
///
/// let frames: Vec<Image> = (0..3u8).map(|i| Image::new(8, 8, [80 * i, 0, 0])).collect();
/// let mut bytes = Vec::new();
/// write_gif_to(&frames, 10, &mut bytes)?;
/// assert_eq!(&bytes[..6], b"GIF89a");
/// # Ok::<(), isomorph_io::render::RenderError>(())
/// ```
///
/// # Errors
/// As [`write_gif`].
pub fn write_gif_to(frames: &[Image], delay: u16, out: impl Write) -> Result<(), RenderError> {
    let Some(first) = frames.first() else {
        return Err(RenderError::EmptyImage { width: 0, height: 0 });
    };
    let (width, height) = (first.width(), first.height());
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(RenderError::EmptyImage { width, height });
    };
    if w == 0 || h == 0 {
        return Err(RenderError::EmptyImage { width, height });
    }
    if let Some(other) = frames.iter().find(|f| (f.width(), f.height()) != (width, height)) {
        return Err(RenderError::Encode(format!(
            "GIF frames differ in size: {width}×{height} and {}×{}",
            other.width(),
            other.height()
        )));
    }
    let encode = |e: gif::EncodingError| RenderError::Encode(format!("GIF encoding failed: {e}"));
    let mut encoder = gif::Encoder::new(out, w, h, &[]).map_err(encode)?;
    encoder.set_repeat(gif::Repeat::Infinite).map_err(encode)?;
    // Forward, then back without repeating the two ends.
    let back = frames.iter().rev().skip(1).take(frames.len().saturating_sub(2));
    for image in frames.iter().chain(back) {
        let rgb: Vec<u8> = image.pixels().iter().flatten().copied().collect();
        let mut frame = gif::Frame::from_rgb_speed(w, h, &rgb, 10);
        frame.delay = delay;
        encoder.write_frame(&frame).map_err(encode)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_play_forward_and_back() {
        let frames: Vec<Image> = (0..4u8).map(|i| Image::new(6, 5, [60 * i, 30, 200])).collect();
        let mut bytes = Vec::new();
        write_gif_to(&frames, 7, &mut bytes).unwrap();
        let mut decoder = gif::DecodeOptions::new();
        decoder.set_color_output(gif::ColorOutput::RGBA);
        let mut reader = decoder.read_info(bytes.as_slice()).unwrap();
        let mut reds = Vec::new();
        while let Some(frame) = reader.read_next_frame().unwrap() {
            assert_eq!((frame.width, frame.height, frame.delay), (6, 5, 7));
            reds.push(frame.buffer[0]);
        }
        assert_eq!(reds, [0, 60, 120, 180, 120, 60]);
    }

    #[test]
    fn bad_frames_are_errors() {
        assert!(matches!(write_gif_to(&[], 5, Vec::new()), Err(RenderError::EmptyImage { .. })));
        let mixed = [Image::new(4, 4, [0; 3]), Image::new(5, 4, [0; 3])];
        assert!(matches!(write_gif_to(&mixed, 5, Vec::new()), Err(RenderError::Encode(_))));
        let wide = [Image::new(70_000, 1, [0; 3])];
        assert!(matches!(write_gif_to(&wide, 5, Vec::new()), Err(RenderError::EmptyImage { .. })));
    }
}
