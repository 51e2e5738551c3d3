//! Progress bars for long exports.

use indicatif::{ProgressBar, ProgressStyle};
use isomorph_common::export::ExportProgress;

/// A progress bar over `frames` frames, labelled `label`, and the export
/// callback that drives it.
pub struct FrameBar {
    bar: ProgressBar,
}

impl FrameBar {
    /// A bar for an export of `frames` frames.
    pub fn new(label: &str, frames: usize) -> Self {
        let bar = ProgressBar::new(frames as u64);
        bar.set_style(
            ProgressStyle::with_template("{prefix:>12} [{bar:30}] {pos}/{len} frames {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(label.to_string());
        Self { bar }
    }

    /// The callback for `export_sequence`.
    pub fn update(&self, p: ExportProgress) -> bool {
        match p {
            ExportProgress::Frame { done, .. } => self.bar.set_position(done as u64),
            ExportProgress::ContactSheet => self.bar.set_message("contact sheet"),
            ExportProgress::Endpoints => self.bar.set_message("endpoint distances"),
            _ => {}
        }
        true
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
