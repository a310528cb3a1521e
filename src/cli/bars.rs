//! Progress on stderr: an indicatif bar per stage, behind the library's
//! [`Progress`] trait (or none with --quiet).
//!
//! A bar is drawn when its stage starts and then redrawn every [`TICK`]
//! by indicatif's ticker, not only when work is reported: a stage whose
//! units come seconds apart (a chunk of beams traced, then gathered) or
//! never (a spinner) still shows its elapsed time move, as the JSON lines
//! report every second.
//!
//! Without a terminal on stderr (a farm's log, a pipe) indicatif draws
//! nothing; [`Bars::with_log_lines`] then writes plain lines instead: one
//! when a stage with a known size starts, and one every [`LOG_EVERY`] with
//! the share done and the time left, so a long render's log shows its
//! estimate.

use aurora::util::progress::{NoProgress, Progress};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How often a bar is redrawn whether or not work was reported.
pub const TICK: Duration = Duration::from_millis(500);

/// How often a stage's plain line is written without a terminal.
pub const LOG_EVERY: Duration = Duration::from_secs(30);

/// A stage reported as plain lines: its name, size, units done, start and
/// the time of its last line.
struct LogStage {
    stage: String,
    total: u64,
    done: u64,
    started: Instant,
    last: Instant,
}

/// indicatif progress bars on stderr, one per stage.
pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
    hidden: bool,
    log: Option<Mutex<Option<LogStage>>>,
}

impl Bars {
    pub fn new(hidden: bool) -> Self {
        Self { bar: Mutex::new(None), hidden, log: None }
    }

    /// As [`new`](Self::new), and plain lines in place of the bars when
    /// stderr is not a terminal.
    pub fn with_log_lines(hidden: bool) -> Self {
        let log = (!hidden && !std::io::stderr().is_terminal()).then(|| Mutex::new(None));
        Self { bar: Mutex::new(None), hidden, log }
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
        if let Some(log) = &self.log {
            let mut log = log.lock().expect("progress lock");
            *log = (total > 0).then(|| {
                eprintln!("aurora: {stage}: started, {total} steps (a line every {} s with the time left)", LOG_EVERY.as_secs());
                LogStage { stage: stage.to_string(), total, done: 0, started: Instant::now(), last: Instant::now() }
            });
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
        if let Some(log) = &self.log {
            if let Some(l) = log.lock().expect("progress lock").as_mut() {
                l.done += n;
                if l.last.elapsed() >= LOG_EVERY {
                    l.last = Instant::now();
                    eprintln!("aurora: {}", log_line(&l.stage, l.done, l.total, l.started.elapsed()));
                }
            }
            return;
        }
        if let Some(b) = self.bar.lock().expect("progress lock").as_ref() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(log) = &self.log {
            log.lock().expect("progress lock").take();
            return;
        }
        if let Some(b) = self.bar.lock().expect("progress lock").take() {
            b.finish_and_clear();
        }
    }
}

/// A stage's plain line: the share done, the time spent and the time left
/// at the rate so far.
fn log_line(stage: &str, done: u64, total: u64, elapsed: Duration) -> String {
    let share = done.min(total) as f64 / total.max(1) as f64;
    let spent = elapsed.as_secs_f64();
    let left =
        if share > 0.0 { format!("about {} left", clock(spent * (1.0 - share) / share)) } else { "time left not known yet".to_string() };
    format!("{stage}: {:.0}% after {}, {left}", 100.0 * share, clock(spent))
}

/// Seconds as `H:MM:SS`.
fn clock(s: f64) -> String {
    let s = s.round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_log_line_gives_the_share_done_and_the_time_left() {
        assert_eq!(log_line("render", 250, 1000, Duration::from_secs(90)), "render: 25% after 0:01:30, about 0:04:30 left");
        assert_eq!(log_line("render", 0, 1000, Duration::from_secs(30)), "render: 0% after 0:00:30, time left not known yet");
        assert_eq!(clock(3725.0), "1:02:05");
    }
}
