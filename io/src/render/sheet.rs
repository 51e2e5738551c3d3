//! Contact sheets: frames tiled in a grid, each labelled underneath, with an
//! optional title line.

use super::{Image, text_size};

/// Layout and colours of a contact sheet; [`ContactSheet::compose`] draws it.
///
/// Frames are placed left to right, top to bottom, each centred in a cell as
/// large as the largest frame, with its label centred below it in the
/// built-in font (cut to the cell width).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ContactSheet {
    /// Frames per row; 0 picks a near-square grid (`⌈√n⌉` columns).
    pub columns: u32,
    /// Pixels between cells and around the sheet.
    pub gap: u32,
    /// Image pixels per font pixel of the labels (glyphs are 5 × 7 font
    /// pixels); 0 picks 2 for cells at least 200 pixels wide, else 1. The
    /// title is one step larger.
    pub label_scale: u32,
    /// Text across the top of the sheet, if any.
    pub title: Option<String>,
    /// sRGB colour between and around the frames.
    pub background: [u8; 3],
    /// sRGB colour of labels and title.
    pub text_color: [u8; 3],
}

impl Default for ContactSheet {
    /// Automatic columns and label size, 8-pixel gaps, no title, dark text
    /// on light grey.
    fn default() -> Self {
        Self {
            columns: 0,
            gap: 8,
            label_scale: 0,
            title: None,
            background: [226, 226, 222],
            text_color: [32, 32, 36],
        }
    }
}

impl ContactSheet {
    /// Draws `frames` (image and label) onto one sheet. No frames give a
    /// sheet with just the title and margins (0 × 0 without title and gap).
    pub fn compose(&self, frames: &[(Image, String)]) -> Image {
        let n = frames.len() as u32;
        let columns = match self.columns {
            0 => (1..=n).find(|c| c * c >= n).unwrap_or(1),
            c => c,
        }
        .clamp(1, n.max(1));
        let rows = n.div_ceil(columns);
        let used_columns = columns.min(n);
        let cell_width = frames.iter().map(|(f, _)| f.width()).max().unwrap_or(0);
        let cell_height = frames.iter().map(|(f, _)| f.height()).max().unwrap_or(0);
        let scale = match self.label_scale {
            0 if cell_width >= 200 => 2,
            0 => 1,
            s => s,
        };
        let gap = self.gap;
        // Label band under each frame: a little space, then one text line.
        let label_height = 3 * scale + text_size("0", scale).1;
        let row_height = cell_height + label_height + gap;
        let title_scale = scale + 1;
        let title = self.title.as_deref().filter(|t| !t.is_empty());
        let (title_width, title_height) = title.map_or((0, 0), |t| text_size(t, title_scale));
        // Space the title takes: below it and on either side of it.
        let (title_band, title_span) = match title {
            Some(_) => (title_height + gap, title_width + 2 * gap),
            None => (0, 0),
        };

        let width = (gap + used_columns * (cell_width + gap)).max(title_span);
        let height = gap + title_band + rows * row_height;
        let mut sheet = Image::new(width, height, self.background);
        if let Some(t) = title {
            let x = (width - title_width) / 2;
            sheet.draw_text(i64::from(x), i64::from(gap), t, title_scale, self.text_color);
        }
        for (i, (frame, label)) in frames.iter().enumerate() {
            let (col, row) = (i as u32 % columns, i as u32 / columns);
            let cell_x = gap + col * (cell_width + gap);
            let cell_y = gap + title_band + row * row_height;
            let frame_x = cell_x + (cell_width - frame.width()) / 2;
            sheet.blit(frame, i64::from(frame_x), i64::from(cell_y));
            let label = fit_text(label, cell_width, scale);
            let label_width = text_size(label, scale).0;
            let label_x = cell_x + (cell_width - label_width) / 2;
            let label_y = cell_y + cell_height + 3 * scale;
            sheet.draw_text(i64::from(label_x), i64::from(label_y), label, scale, self.text_color);
        }
        sheet
    }
}

/// The longest prefix of `text` that fits in `width` pixels at `scale`.
fn fit_text(text: &str, width: u32, scale: u32) -> &str {
    let end = text
        .char_indices()
        .map(|(i, c)| i + c.len_utf8())
        .take_while(|&end| text_size(&text[..end], scale).0 <= width)
        .last()
        .unwrap_or(0);
    &text[..end]
}

/// Tiles `frames` (image and label, e.g. `"t = 0.25"`) into a grid of
/// `columns` frames per row (0: near-square) with the default
/// [`ContactSheet`] layout.
pub fn contact_sheet(frames: &[(Image, String)], columns: u32) -> Image {
    ContactSheet { columns, ..ContactSheet::default() }.compose(frames)
}

/// [`contact_sheet`] with a `title` line across the top.
pub fn contact_sheet_titled(frames: &[(Image, String)], columns: u32, title: &str) -> Image {
    ContactSheet { columns, title: Some(title.to_owned()), ..ContactSheet::default() }.compose(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(n: usize, size: u32) -> Vec<(Image, String)> {
        (0..n)
            .map(|i| {
                let t = i as f32 / (n - 1).max(1) as f32;
                (Image::new(size, size, [200, 0, 0]), format!("t = {t:.2}"))
            })
            .collect()
    }

    fn count(image: &Image, color: [u8; 3]) -> usize {
        image.pixels().iter().filter(|&&p| p == color).count()
    }

    #[test]
    fn grid_dimensions_follow_the_layout() {
        let layout = ContactSheet::default();
        let text = layout.text_color;
        let sheet = contact_sheet(&frames(5, 40), 3);
        // 3 columns × 2 rows of 40-pixel cells, 8-pixel gaps, labels of 7
        // font pixels at scale 1 plus 3 pixels of space.
        assert_eq!(sheet.width(), 8 + 3 * (40 + 8));
        assert_eq!(sheet.height(), 8 + 2 * (40 + 10 + 8));
        assert_eq!(count(&sheet, [200, 0, 0]), 5 * 40 * 40, "every frame pixel is copied");
        assert!(count(&sheet, text) > 5 * 20, "labels are drawn");
        // Labels sit right below their frames.
        let label_rows = 8 + 40 + 3..8 + 40 + 10;
        let below_first = (0..sheet.width())
            .flat_map(|x| label_rows.clone().map(move |y| (x, y)))
            .filter(|&(x, y)| sheet.get(x, y) == Some(text))
            .count();
        assert!(below_first > 3 * 20);

        let auto = contact_sheet(&frames(10, 40), 0);
        assert_eq!(auto.width(), 8 + 4 * 48, "10 frames: 4 columns");
        assert_eq!(contact_sheet(&frames(2, 40), 10).width(), 8 + 2 * 48, "no empty columns");
    }

    #[test]
    fn title_adds_a_line_and_empty_input_is_fine() {
        let plain = contact_sheet(&frames(4, 240), 2);
        let titled = contact_sheet_titled(&frames(4, 240), 2, "sphere -> torus");
        // Labels at scale 2 (cells ≥ 200 px), the title at scale 3: 21 + 8 pixels.
        assert_eq!(plain.height(), 8 + 2 * (240 + 6 + 14 + 8));
        assert_eq!(titled.height(), plain.height() + 21 + 8);
        assert_eq!(titled.width(), plain.width());
        let text = ContactSheet::default().text_color;
        assert!(count(&titled, text) > count(&plain, text) + 200);

        let empty = contact_sheet(&[], 3);
        assert_eq!((empty.width(), empty.height()), (8, 8));
        let wide_title = contact_sheet_titled(&[], 0, "title");
        assert_eq!(wide_title.width(), text_size("title", 2).0 + 16);
    }

    #[test]
    fn long_labels_are_cut_to_the_cell() {
        let mut f = frames(1, 30);
        f[0].1 = "a label much wider than thirty pixels".into();
        let sheet = contact_sheet(&f, 1);
        assert_eq!(sheet.width(), 30 + 16);
        assert_eq!(fit_text(&f[0].1, 30, 1), "a lab");
        assert_eq!(fit_text("é→x", 100, 1), "é→x");
        assert_eq!(fit_text("abc", 0, 1), "");
    }
}
