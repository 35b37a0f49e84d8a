//! Progress of one stage shared by the threads that do its work, with cancellation: long
//! loops ask [`StageProgress::stopped`] between small work items (an atomic load, plus
//! [`Progress::cancelled`]) and report finished items with [`StageProgress::advance`].

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Receives progress; return `false` to cancel the render.
pub trait Progress: Sync {
    fn update(&self, stage: &str, fraction: f64) -> bool;
    /// True once the render should stop. Long loops ask between small work items, so it
    /// must be cheap (the Python binding's is an atomic load). Default: only `update`
    /// cancels.
    fn cancelled(&self) -> bool {
        false
    }
}

/// No progress reporting.
pub struct Silent;
impl Progress for Silent {
    fn update(&self, _: &str, _: f64) -> bool {
        true
    }
}

/// A stage of `total` work items reported to a [`Progress`] under `name`.
pub struct StageProgress<'a> {
    progress: &'a dyn Progress,
    name: &'a str,
    total: u64,
    done: AtomicU64,
    stop: AtomicBool,
}

impl<'a> StageProgress<'a> {
    /// Starts the stage, reporting it at 0 (so that the stage shows before its first
    /// item, which may take long, is done).
    pub fn new(progress: &'a dyn Progress, name: &'a str, total: u64) -> Self {
        let stage = StageProgress {
            progress,
            name,
            total: total.max(1),
            done: AtomicU64::new(0),
            stop: AtomicBool::new(false),
        };
        stage.advance(0);
        stage
    }

    /// Counts `n` more finished items and reports the fraction done; a `false` from the
    /// progress receiver stops the stage.
    pub fn advance(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        let fraction = (done as f64 / self.total as f64).min(1.0);
        if !self.progress.update(self.name, fraction) {
            self.stop.store(true, Ordering::Relaxed);
        }
    }

    /// Asks the stage to stop (e.g. when it ran out of memory).
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    /// True once the stage should stop: cheap enough to ask per pixel or per photon path.
    #[inline]
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || self.progress.cancelled()
    }

    /// `Err(Cancelled)` when the stage was stopped.
    pub fn finish(&self) -> Result<()> {
        if self.stopped() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }
}

/// `Err(Cancelled)` when `progress` asks to stop: for the seams between stages.
pub fn check(progress: &dyn Progress) -> Result<()> {
    if progress.cancelled() {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}
