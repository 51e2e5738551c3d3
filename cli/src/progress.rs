//! A terminal progress bar fed by a [`Control`]'s progress reports, and
//! Ctrl-C as cancellation.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use isomorph_common::{CancelToken, Control, MorphError};
use std::sync::OnceLock;

/// A [`Control`] on `threads` threads (all when `None`) whose progress
/// drives a bar labelled `label` on stderr (hidden when stderr is not a
/// terminal), and the bar to clear when done.
///
/// # Errors
/// A thread count the machine cannot give.
pub fn control(label: &str, threads: Option<usize>) -> Result<(Control, ProgressBar), MorphError> {
    let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{prefix:>12} [{bar:24}] {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(label.to_string());
    let shown = bar.clone();
    let mut control = Control::new().with_cancel(interrupt_token()).with_progress(move |p| {
        if let Some(f) = p.fraction {
            shown.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
        }
        shown.set_message(if p.message.is_empty() {
            p.stage.to_string()
        } else {
            format!("{}: {}", p.stage, p.message)
        });
    });
    if let Some(n) = threads {
        control = control.with_threads(n)?;
    }
    Ok((control, bar))
}

/// The process's token, cancelled by Ctrl-C (the handler is installed once;
/// every control of the run shares the token).
fn interrupt_token() -> CancelToken {
    static TOKEN: OnceLock<CancelToken> = OnceLock::new();
    TOKEN
        .get_or_init(|| {
            let token = CancelToken::new();
            let on_interrupt = token.clone();
            // Without a handler (e.g. another one is installed) Ctrl-C keeps
            // its default effect: the process ends.
            let _ = ctrlc::set_handler(move || on_interrupt.cancel());
            token
        })
        .clone()
}
