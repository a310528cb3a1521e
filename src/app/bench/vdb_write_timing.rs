//! Timing of repeated VDB writes of the same grids, for the write
//! benchmark (`examples/vdb_write_bench.rs`, runs kept under
//! `benchmarks/vdb_write/`). Not part of the writer: it only calls
//! [`crate::io::vdb::write::write_vdb`] and keeps the clock.

use crate::io::vdb::write::{write_vdb, GridRef, VdbWriteError, WriteOptions};
use std::path::Path;
use std::time::Instant;

/// Timings of repeated writes of the same grids (for benchmarks; see
/// `examples/vdb_write_bench.rs`).
#[derive(Clone, Debug)]
pub struct BenchWrite {
    /// Wall-clock seconds of each `write_vdb` call (encoding + file write).
    pub seconds: Vec<f64>,
    /// File size in bytes.
    pub bytes: u64,
}

impl BenchWrite {
    pub fn best(&self) -> f64 {
        self.seconds.iter().copied().fold(f64::INFINITY, f64::min)
    }
    pub fn median(&self) -> f64 {
        let mut s = self.seconds.clone();
        s.sort_by(f64::total_cmp);
        if s.is_empty() {
            f64::NAN
        } else {
            s[s.len() / 2]
        }
    }
}

/// Writes `grids` to `path` `repeats` times and times each write.
pub fn bench_write(path: &Path, grids: &[GridRef], opts: &WriteOptions, repeats: usize) -> Result<BenchWrite, VdbWriteError> {
    let mut seconds = Vec::with_capacity(repeats);
    let mut bytes = 0;
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        bytes = write_vdb(path, grids, opts)?.bytes;
        seconds.push(t0.elapsed().as_secs_f64());
    }
    Ok(BenchWrite { seconds, bytes })
}
