//! Progress on stderr: an indicatif bar per stage, behind the library's
//! [`Progress`] trait (or none with --quiet).

use aurora::util::progress::{NoProgress, Progress};
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::Mutex;

/// indicatif progress bars on stderr, one per stage.
pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
    hidden: bool,
}

impl Bars {
    pub fn new(hidden: bool) -> Self {
        Self { bar: Mutex::new(None), hidden }
    }

    /// The progress a stage reports to: these bars, or nothing when quiet.
    pub fn progress(&self) -> &dyn Progress {
        if self.hidden {
            &NoProgress
        } else {
            self
        }
    }
}

impl Progress for Bars {
    fn start(&self, stage: &str, total: u64) {
        if self.hidden {
            return;
        }
        let pb = if total > 0 {
            ProgressBar::new(total).with_style(
                ProgressStyle::with_template("{prefix:>12} [{bar:30}] {percent:>3}% {elapsed_precise} eta {eta}")
                    .expect("valid template")
                    .progress_chars("=> "),
            )
        } else {
            ProgressBar::new_spinner()
        };
        pb.set_prefix(stage.to_string());
        if let Some(old) = self.bar.lock().expect("progress lock").replace(pb) {
            old.finish_and_clear();
        }
    }
    fn inc(&self, n: u64) {
        if let Some(b) = self.bar.lock().expect("progress lock").as_ref() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().expect("progress lock").take() {
            b.finish_and_clear();
        }
    }
}
