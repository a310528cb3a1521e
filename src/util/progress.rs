//! Progress reporting for long stages, without tying the library to a
//! terminal: the CLI implements [`Progress`] with indicatif bars, hosts that
//! run the binary (the Blender add-on, a Houdini HDA) read
//! [`JsonProgress`]'s lines, tests and library users pass [`NoProgress`].
//!
//! The JSON lines (`aurora bake --progress json`, documented in
//! docs/guide.md, "Progress as JSON"): one object per line,
//! `{"stage": S, "done": D, "total": T, "seconds": X}` with `total` 0 when
//! the amount of work is unknown and `seconds` the time since the run began;
//! `{"warning": M, "seconds": X}` and `{"error": M, "status": N,
//! "seconds": X}` for warnings and the error that ends the run (N its exit
//! status). A stage reports when it starts (`done` 0), each time it crosses
//! another percent of `total` (at most 101 such lines a stage, so a host is
//! never flooded), every [`JsonProgress::BETWEEN_PERCENTS`] at most between
//! them (a stage whose percent takes minutes still says where it is, also
//! when no work is reported meanwhile: [`JsonProgress::tick`]), every
//! [`JsonProgress::HEARTBEAT`] at most while `total` is unknown, and when it
//! finishes (`done` = `total`).

use serde_json::json;
use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Receives progress of a stage. Implementations must be cheap and
/// thread-safe: `inc` is called from worker threads.
pub trait Progress: Sync {
    /// A new stage begins with `total` units of work (0 if unknown).
    fn start(&self, stage: &str, total: u64);
    /// `n` more units are done.
    fn inc(&self, n: u64);
    /// The current stage is done.
    fn finish(&self);
    /// Whether the caller has asked the work to stop (a host's interrupt):
    /// the bake asks between chunks of beams and returns
    /// `BeamError::Cancelled` instead of a result. Never, by default.
    fn cancelled(&self) -> bool {
        false
    }
}

/// Ignores all progress.
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _stage: &str, _total: u64) {}
    fn inc(&self, _n: u64) {}
    fn finish(&self) {}
}

/// Progress as JSON objects, one per line, on a writer (the CLI: stderr).
pub struct JsonProgress<W: Write + Send> {
    out: Mutex<Writer<W>>,
    t0: Instant,
    done: AtomicU64,
    total: AtomicU64,
    /// The last percent reported (total known), or heartbeat count.
    reported: AtomicU64,
}

struct Writer<W> {
    w: W,
    stage: String,
    last: Instant,
    /// A stage has started and not finished ([`JsonProgress::tick`]).
    active: bool,
}

impl<W: Write + Send> JsonProgress<W> {
    /// Seconds between lines of a stage whose total is unknown.
    pub const HEARTBEAT: Duration = Duration::from_millis(250);
    /// Seconds after which a stage whose next percent has not come yet
    /// reports where it is (within 2 s of its start, however long a
    /// percent takes).
    pub const BETWEEN_PERCENTS: Duration = Duration::from_secs(1);

    pub fn new(w: W) -> Self {
        let now = Instant::now();
        Self {
            out: Mutex::new(Writer { w, stage: String::new(), last: now, active: false }),
            t0: now,
            done: AtomicU64::new(0),
            total: AtomicU64::new(0),
            reported: AtomicU64::new(0),
        }
    }

    fn seconds(&self) -> f64 {
        // Millisecond resolution: enough for a status bar, short lines.
        (self.t0.elapsed().as_secs_f64() * 1e3).round() / 1e3
    }

    fn line(w: &mut Writer<W>, value: serde_json::Value) {
        // A host that stopped reading is no reason to fail the bake.
        let _ = writeln!(w.w, "{value}").and_then(|_| w.w.flush());
    }

    fn report(&self, w: &mut Writer<W>) {
        let (done, total) = (self.done.load(Ordering::Relaxed), self.total.load(Ordering::Relaxed));
        let done = if total > 0 { done.min(total) } else { done };
        w.last = Instant::now();
        Self::line(w, json!({"stage": w.stage, "done": done, "total": total, "seconds": self.seconds()}));
    }

    /// A warning line.
    pub fn warning(&self, message: &str) {
        let mut w = self.out.lock().expect("progress lock");
        Self::line(&mut w, json!({"warning": message, "seconds": self.seconds()}));
    }

    /// The error line that ends a run with exit status `status`.
    pub fn error(&self, message: &str, status: i32) {
        let mut w = self.out.lock().expect("progress lock");
        Self::line(&mut w, json!({"error": message, "status": status, "seconds": self.seconds()}));
    }

    /// A stage line with explicit counts (a sequence's frames done).
    pub fn step(&self, stage: &str, done: u64, total: u64) {
        let mut w = self.out.lock().expect("progress lock");
        Self::line(&mut w, json!({"stage": stage, "done": done, "total": total, "seconds": self.seconds()}));
    }

    /// Reports where the running stage is if it has said nothing for
    /// [`Self::BETWEEN_PERCENTS`] ([`Self::HEARTBEAT`] while its total is
    /// unknown): for a ticker thread to call, so that a stage whose work
    /// comes in chunks seconds apart (no `inc` meanwhile) still reports
    /// every second. Nothing between stages.
    pub fn tick(&self) {
        let every = if self.total.load(Ordering::Relaxed) > 0 { Self::BETWEEN_PERCENTS } else { Self::HEARTBEAT };
        if let Ok(mut w) = self.out.try_lock() {
            if w.active && w.last.elapsed() >= every {
                self.report(&mut w);
            }
        }
    }

    /// The writer back (tests read what was written).
    pub fn into_inner(self) -> W {
        self.out.into_inner().expect("progress lock").w
    }
}

impl<W: Write + Send> Progress for JsonProgress<W> {
    fn start(&self, stage: &str, total: u64) {
        let mut w = self.out.lock().expect("progress lock");
        w.stage = stage.to_string();
        w.active = true;
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
        self.reported.store(0, Ordering::Relaxed);
        self.report(&mut w);
    }

    fn inc(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        let total = self.total.load(Ordering::Relaxed);
        // `None`: the total is unknown (0).
        if let Some(pct) = (done.min(total) * 100).checked_div(total) {
            let last = self.reported.load(Ordering::Relaxed);
            // One thread wins each new percent; the others go on working.
            if pct > last && self.reported.compare_exchange(last, pct, Ordering::Relaxed, Ordering::Relaxed).is_ok() {
                if let Ok(mut w) = self.out.lock() {
                    self.report(&mut w);
                }
            } else if let Ok(mut w) = self.out.try_lock() {
                // A stage whose percent takes long (a bake of 10^8 beams)
                // still says where it is.
                if w.last.elapsed() >= Self::BETWEEN_PERCENTS {
                    self.report(&mut w);
                }
            }
        } else if let Ok(mut w) = self.out.try_lock() {
            if w.last.elapsed() >= Self::HEARTBEAT {
                self.report(&mut w);
            }
        }
    }

    fn finish(&self) {
        let mut w = self.out.lock().expect("progress lock");
        w.active = false;
        let total = self.total.load(Ordering::Relaxed);
        if total > 0 {
            self.done.store(total, Ordering::Relaxed);
        }
        self.report(&mut w);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(p: JsonProgress<Vec<u8>>) -> Vec<serde_json::Value> {
        let text = String::from_utf8(p.into_inner()).expect("utf-8");
        text.lines().map(|l| serde_json::from_str(l).expect("every line is one JSON object")).collect()
    }

    #[test]
    fn a_stage_reports_start_each_percent_and_finish() {
        let p = JsonProgress::new(Vec::new());
        p.start("beams", 1000);
        for _ in 0..1000 {
            p.inc(1);
        }
        p.finish();
        let l = lines(p);
        // start + 100 percents + finish.
        assert_eq!(l.len(), 102);
        assert_eq!(l[0]["stage"], "beams");
        assert_eq!(l[0]["done"], 0);
        assert_eq!(l[0]["total"], 1000);
        assert_eq!(l[1]["done"], 10);
        assert_eq!(l[101]["done"], 1000);
        let done: Vec<u64> = l.iter().map(|v| v["done"].as_u64().unwrap()).collect();
        assert!(done.windows(2).all(|w| w[0] <= w[1]), "done never goes back");
        let secs: Vec<f64> = l.iter().map(|v| v["seconds"].as_f64().unwrap()).collect();
        assert!(secs.windows(2).all(|w| w[0] <= w[1]) && secs[0] >= 0.0);
    }

    #[test]
    fn threads_cannot_flood_it_and_done_never_exceeds_total() {
        let p = JsonProgress::new(Vec::new());
        p.start("photons", 5000);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| {
                    for _ in 0..2000 {
                        p.inc(1);
                    }
                });
            }
        });
        p.finish();
        let l = lines(p);
        // At most one line per percent, plus start and finish.
        assert!(l.len() <= 102, "{} lines", l.len());
        assert!(l.iter().all(|v| v["done"].as_u64().unwrap() <= 5000));
        assert_eq!(l.last().unwrap()["done"], 5000);
    }

    /// A stage whose first percent takes long (10^12 units) reports where it
    /// is within 2 s of its start, not only at the percent.
    #[test]
    fn a_slow_percent_still_reports_within_two_seconds() {
        let p = JsonProgress::new(Vec::new());
        p.start("beams", 1_000_000_000_000);
        let t = Instant::now();
        // Work goes on (one beam an inc) until the stage has said more
        // than its start: the wait is on that line, bounded.
        let mut n = 0u64;
        while p.out.lock().unwrap().w.iter().filter(|&&b| b == b'\n').count() < 2 && t.elapsed() < Duration::from_secs(10) {
            p.inc(1);
            n += 1;
        }
        let seen = t.elapsed();
        assert!(seen < Duration::from_secs(2), "{seen:?}");
        assert!(n < 10_000_000_000, "the percent was not reached: {n} beams");
        let l = lines(p);
        assert_eq!(l.len(), 2);
        assert!(l[1]["done"].as_u64().unwrap() > 0 && l[1]["total"] == 1_000_000_000_000u64);
    }

    /// A stage that reports no work says where it is on a tick once a
    /// second has passed, not before, and nothing once it has finished.
    #[test]
    fn a_tick_reports_a_silent_stage_after_a_second_and_nothing_between_stages() {
        let p = JsonProgress::new(Vec::new());
        p.start("beams", 100);
        p.tick();
        p.out.lock().unwrap().last -= JsonProgress::<Vec<u8>>::BETWEEN_PERCENTS;
        p.tick();
        p.finish();
        p.out.lock().unwrap().last -= JsonProgress::<Vec<u8>>::BETWEEN_PERCENTS;
        p.tick();
        let l = lines(p);
        assert_eq!(l.iter().map(|v| v["done"].as_u64().unwrap()).collect::<Vec<_>>(), [0, 0, 100], "{l:?}");
    }

    #[test]
    fn warnings_errors_and_steps_are_objects_too() {
        let p = JsonProgress::new(Vec::new());
        p.warning("under-resolved \"kernel\"");
        p.step("frame", 1, 3);
        p.error("scene.toml: beams.count = 0 must be in [1, 1e8]", 2);
        let l = lines(p);
        assert_eq!(l[0]["warning"], "under-resolved \"kernel\"");
        assert_eq!((l[1]["stage"].as_str(), l[1]["done"].as_u64(), l[1]["total"].as_u64()), (Some("frame"), Some(1), Some(3)));
        assert_eq!(l[2]["status"], 2);
        assert!(l[2]["error"].as_str().unwrap().contains("beams.count"));
    }
}
