//! Progress on stderr: an indicatif bar per stage, behind the library's
//! [`Progress`] trait (or none with --quiet).
//!
//! A bar is drawn when its stage starts and then redrawn every [`TICK`]
//! by indicatif's ticker, not only when work is reported: a stage whose
//! units come seconds apart (a chunk of beams traced, then gathered) or
//! never (a spinner) still shows its elapsed time move, as the JSON lines
//! report every second.

use aurora::util::progress::{NoProgress, Progress};
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::Mutex;
use std::time::Duration;

/// How often a bar is redrawn whether or not work was reported.
pub const TICK: Duration = Duration::from_millis(500);

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
        pb.enable_steady_tick(TICK);
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
