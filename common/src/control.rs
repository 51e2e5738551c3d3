//! How a long operation is driven: progress reports, cancellation and the
//! threads it may use ([`Control`]).
//!
//! Every morph constructor (`XxxMorph::new(source, target, &settings,
//! &control)`) and the sequence exporter take a [`Control`]. Long loops call
//! [`Control::check`] between units of work (an iteration, a block of grid
//! nodes, a stage), so a cancelled run returns
//! [`MorphError::Cancelled`](crate::MorphError::Cancelled) within a fraction
//! of a second; [`Control::install`] runs work on the chosen thread pool, so
//! every `rayon` loop inside honours the thread count. Results never depend
//! on the thread count.
//!
//! ```
//! use isomorph_common::{CancelToken, Control};
//! use std::sync::{Arc, Mutex};
//!
//! let token = CancelToken::new();
//! let seen = Arc::new(Mutex::new(Vec::new()));
//! let log = seen.clone();
//! let control = Control::new()
//!     .with_threads(1)?
//!     .with_cancel(token.clone())
//!     .with_progress(move |p| log.lock().unwrap().push(p.stage.to_string()));
//! control.progress("fit", Some(0.5), || "half way".into());
//! assert_eq!(seen.lock().unwrap().as_slice(), ["fit"]);
//! assert!(control.check().is_ok());
//! token.cancel();
//! assert!(control.check().is_err());
//! assert_eq!(control.install(rayon::current_num_threads), 1);
//! # Ok::<(), isomorph_common::MorphError>(())
//! ```

use crate::MorphError;
use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// One progress report: which stage runs, how far it is (when known) and a
/// short human-readable message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress<'a> {
    /// The stage, e.g. `"distance volumes"`, `"evolution"`, `"fit"`, `"frames"`.
    pub stage: &'a str,
    /// Fraction of the stage done, in `[0, 1]`, when it is known.
    pub fraction: Option<f32>,
    /// A short message (iteration, residual, ...); may be empty.
    pub message: &'a str,
}

/// A shared flag that asks a running operation to stop. Clones share the
/// flag: keep one, hand one to [`Control::with_cancel`], call
/// [`CancelToken::cancel`] from anywhere (another thread, a signal handler, a
/// progress callback).
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token that is not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every operation holding this token to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`CancelToken::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// The progress callback's type.
type ProgressFn = dyn Fn(&Progress<'_>) + Send + Sync;

/// Progress callback, cancellation token and thread pool of a long
/// operation (see the [crate docs](crate)). `Control::default()` reports
/// nothing, is never cancelled and uses rayon's global pool.
#[derive(Clone, Default)]
pub struct Control {
    progress: Option<Arc<ProgressFn>>,
    cancel: CancelToken,
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl fmt::Debug for Control {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Control")
            .field("progress", &self.progress.is_some())
            .field("cancelled", &self.cancel.is_cancelled())
            .field("threads", &self.threads())
            .finish()
    }
}

impl Control {
    /// No progress reports, not cancelled, rayon's global pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// This control reporting progress to `callback`. The callback runs on
    /// the working thread (sometimes a pool thread): keep it short.
    pub fn with_progress(mut self, callback: impl Fn(&Progress<'_>) + Send + Sync + 'static) -> Self {
        self.progress = Some(Arc::new(callback));
        self
    }

    /// This control stopping when `token` is cancelled.
    pub fn with_cancel(mut self, token: CancelToken) -> Self {
        self.cancel = token;
        self
    }

    /// This control running parallel work on a dedicated pool of `threads`
    /// threads (`0`: rayon's global pool, sized by the machine or
    /// `RAYON_NUM_THREADS`).
    ///
    /// # Errors
    /// [`MorphError::BadSetting`] when the pool cannot be built (the system
    /// refuses the threads).
    pub fn with_threads(mut self, threads: usize) -> Result<Self, MorphError> {
        self.pool = match threads {
            0 => None,
            n => Some(Arc::new(rayon::ThreadPoolBuilder::new().num_threads(n).build().map_err(|e| {
                MorphError::BadSetting {
                    name: "threads",
                    value: n.to_string(),
                    expected: format!("a number of threads the system can start ({e})"),
                }
            })?)),
        };
        Ok(self)
    }

    /// The number of threads parallel work runs on.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or_else(rayon::current_num_threads, |p| p.current_num_threads())
    }

    /// The cancellation token (clone it to cancel from elsewhere).
    pub fn cancel_token(&self) -> &CancelToken {
        &self.cancel
    }

    /// Whether the operation should stop.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    /// `Ok` to go on, [`MorphError::Cancelled`] once cancelled.
    ///
    /// # Errors
    /// [`MorphError::Cancelled`].
    pub fn check(&self) -> Result<(), MorphError> {
        if self.is_cancelled() { Err(MorphError::Cancelled) } else { Ok(()) }
    }

    /// Whether a progress callback is installed (to skip formatting
    /// messages nobody reads).
    pub fn reports_progress(&self) -> bool {
        self.progress.is_some()
    }

    /// Reports progress of `stage`; `message` is only built when a callback
    /// is installed.
    pub fn progress(&self, stage: &str, fraction: Option<f32>, message: impl FnOnce() -> String) {
        if let Some(callback) = &self.progress {
            let message = message();
            callback(&Progress { stage, fraction: fraction.map(|f| f.clamp(0.0, 1.0)), message: &message });
        }
    }

    /// Runs `work` on this control's thread pool (or on the caller's pool
    /// when none was chosen: the global one from outside any pool), so that
    /// every rayon loop inside uses it. `work` itself runs on one of the
    /// pool's threads: its loops then split work among the pool's threads
    /// directly, where a loop started from outside the pool hands its work
    /// over and sleeps until woken, which costs tens of microseconds per
    /// loop (a tenth of the level-set command's evolution, whose iterations
    /// run some fifteen loops each).
    pub fn install<R: Send>(&self, work: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some(pool) => pool.install(work),
            None if rayon::current_thread_index().is_some() => work(),
            None => rayon::scope(|_| work()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn threads_are_honoured_and_progress_is_lazy() {
        let two = Control::new().with_threads(2).unwrap();
        assert_eq!(
            two.install(|| (0..64).into_par_iter().map(|_| rayon::current_num_threads()).max()),
            Some(2)
        );
        let quiet = Control::new();
        // Without a pool of its own, work still runs on a pool thread (the global pool's).
        assert!(quiet.install(rayon::current_thread_index).is_some());
        assert_eq!(quiet.install(rayon::current_num_threads), rayon::current_num_threads());
        quiet.progress("x", None, || unreachable!("no callback: the message is not built"));
        assert!(!quiet.reports_progress());
        let fractions = Arc::new(std::sync::Mutex::new(Vec::new()));
        let f = fractions.clone();
        let loud = Control::new().with_progress(move |p| f.lock().unwrap().push(p.fraction));
        loud.progress("x", Some(1.5), String::new);
        assert_eq!(fractions.lock().unwrap().as_slice(), [Some(1.0)]);
    }
}
