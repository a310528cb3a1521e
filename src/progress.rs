//! Progress reporting for long stages, without tying the library to a
//! terminal: the CLI implements [`Progress`] with indicatif bars, tests and
//! library users pass [`NoProgress`].

/// Receives progress of a stage. Implementations must be cheap and
/// thread-safe: `inc` is called from worker threads.
pub trait Progress: Sync {
    /// A new stage begins with `total` units of work (0 if unknown).
    fn start(&self, stage: &str, total: u64);
    /// `n` more units are done.
    fn inc(&self, n: u64);
    /// The current stage is done.
    fn finish(&self);
}

/// Ignores all progress.
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _stage: &str, _total: u64) {}
    fn inc(&self, _n: u64) {}
    fn finish(&self) {}
}
