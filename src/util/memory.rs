//! How much memory this process may use: the smallest of the limits that can
//! stop it. A machine-level fact read at run time, so it lives at the bottom
//! layer and is consulted by the bake's memory budget ([`crate::pipeline::memory::budget`]),
//! never by scene validation (a scene is valid or not whatever machine reads
//! it).
//!
//! The limits, each optional:
//! - `RLIMIT_AS` (address space; `ulimit -v`, `prlimit --as`): read from
//!   `/proc/self/limits`, "Max address space", soft limit;
//! - the cgroup's memory limit: cgroup v2 `memory.max` of the process's own
//!   cgroup (from `/proc/self/cgroup`), or v1 `memory.limit_in_bytes`;
//! - `MemAvailable` from `/proc/meminfo` (what the kernel can hand out
//!   without swapping).
//!
//! When none can be read (not Linux), 24 GiB is assumed.

use std::path::Path;

/// The limit that bounds this process, and where it comes from.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryLimit {
    pub bytes: f64,
    /// "RLIMIT_AS", "cgroup memory.max", "MemAvailable" or "assumed".
    pub source: &'static str,
}

impl std::fmt::Display for MemoryLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", gib(self.bytes), self.source)
    }
}

/// Bytes as GiB with two decimals, e.g. "7.50 GiB".
pub fn gib(bytes: f64) -> String {
    format!("{:.2} GiB", bytes / (1u64 << 30) as f64)
}

/// The smallest readable limit on this process's memory.
pub fn available() -> MemoryLimit {
    smallest(&[
        (mem_available(), "MemAvailable"),
        (cgroup_limit(), "cgroup memory limit"),
        (rlimit_as(), "RLIMIT_AS"),
        #[cfg(windows)]
        (windows_available(), "available physical memory"),
    ])
}

/// The smallest of these readings (each a limit in bytes, if it could be
/// read, and where it comes from); 24 GiB "assumed" when none is a finite
/// positive number. Readings are taken once by the caller, so the answer is
/// at most each of them even while `MemAvailable` moves.
pub fn smallest(readings: &[(Option<f64>, &'static str)]) -> MemoryLimit {
    readings
        .iter()
        .filter_map(|&(bytes, source)| bytes.filter(|b| b.is_finite() && *b > 0.0).map(|bytes| MemoryLimit { bytes, source }))
        .min_by(|a, b| a.bytes.total_cmp(&b.bytes))
        .unwrap_or(MemoryLimit { bytes: 24.0 * (1u64 << 30) as f64, source: "assumed" })
}

/// Windows' available physical memory (`GlobalMemoryStatusEx`, kernel32),
/// in bytes: what `MemAvailable` is on Linux. Job-object limits are not read.
#[cfg(windows)]
fn windows_available() -> Option<f64> {
    /// MEMORYSTATUSEX.
    #[repr(C)]
    struct Status {
        length: u32,
        load: u32,
        total_phys: u64,
        avail_phys: u64,
        rest: [u64; 5],
    }
    #[link(name = "kernel32")]
    extern "system" {
        fn GlobalMemoryStatusEx(status: *mut Status) -> i32;
    }
    let mut s = Status { length: std::mem::size_of::<Status>() as u32, load: 0, total_phys: 0, avail_phys: 0, rest: [0; 5] };
    // SAFETY: a plain out-struct we own, its length set as the call asks.
    (unsafe { GlobalMemoryStatusEx(&mut s) } != 0).then_some(s.avail_phys as f64)
}

fn read(path: impl AsRef<Path>) -> Option<String> {
    std::fs::read_to_string(path).ok()
}

/// `MemAvailable` in bytes.
pub fn mem_available() -> Option<f64> {
    parse_meminfo(&read("/proc/meminfo")?, "MemAvailable:")
}

fn parse_meminfo(text: &str, key: &str) -> Option<f64> {
    let l = text.lines().find(|l| l.starts_with(key))?;
    Some(l.split_whitespace().nth(1)?.parse::<f64>().ok()? * 1024.0)
}

/// The soft `RLIMIT_AS` in bytes, if finite.
pub fn rlimit_as() -> Option<f64> {
    parse_limits(&read("/proc/self/limits")?)
}

fn parse_limits(text: &str) -> Option<f64> {
    let l = text.lines().find(|l| l.starts_with("Max address space"))?;
    let soft = l.trim_start_matches("Max address space").split_whitespace().next()?;
    soft.parse::<f64>().ok()
}

/// The cgroup memory limit in bytes, if one is set (v2 `memory.max`, or v1).
pub fn cgroup_limit() -> Option<f64> {
    let own = read("/proc/self/cgroup").unwrap_or_default();
    for line in own.lines() {
        // v2: "0::/path"; v1 memory controller: "N:memory:/path".
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        let path = path.trim_start_matches('/');
        let candidates: Vec<String> = if controllers.is_empty() {
            vec![format!("/sys/fs/cgroup/{path}/memory.max"), "/sys/fs/cgroup/memory.max".into()]
        } else if controllers.split(',').any(|c| c == "memory") {
            vec![format!("/sys/fs/cgroup/memory/{path}/memory.limit_in_bytes"), "/sys/fs/cgroup/memory/memory.limit_in_bytes".into()]
        } else {
            continue;
        };
        for c in candidates {
            if let Some(v) = read(&c).and_then(|t| parse_cgroup_value(&t)) {
                return Some(v);
            }
        }
    }
    None
}

/// Tunes glibc's allocator for the bake, which allocates and frees a few
/// large buffers (photons, bins, VDB batches) and many leaves from its
/// threads, then exits:
/// - one arena (`M_ARENA_MAX`): the threads' leaves share the main heap,
///   which grows by `brk`, instead of per-thread heaps that grow by
///   `mprotect` and shrink by `madvise` (pages faulted in again at the next
///   leaf); peak memory falls too (744 MB against 788 MB for the default
///   bake, whose threads allocate little at once);
/// - no trimming (`M_TRIM_THRESHOLD`) and 64 MiB of padding on each heap
///   extension (`M_TOP_PAD`): freed memory stays mapped for the next stage
///   instead of going back to the kernel and being faulted in again;
/// - a fixed `mmap` threshold of 32 MiB (`M_MMAP_THRESHOLD`, the largest
///   glibc allows; setting it stops glibc's own adjustment): only the
///   largest buffers get their own mapping, returned when freed.
///
/// The bake's system time falls from 0.9-1.2 s to 0.55-0.65 s (page faults,
/// `mprotect`); results do not depend on it. Returns whether every setting
/// was taken; a no-op returning false off glibc.
pub fn tune_allocator() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let settings =
            [(libc::M_ARENA_MAX, 1), (libc::M_TRIM_THRESHOLD, i32::MAX), (libc::M_TOP_PAD, 64 << 20), (libc::M_MMAP_THRESHOLD, 32 << 20)];
        // SAFETY: mallopt only changes glibc's allocator parameters (it takes
        // the arena lock itself); these values are within its documented
        // ranges, and no memory is handed out or freed by the call.
        settings.iter().all(|&(param, value)| unsafe { libc::mallopt(param, value) } == 1)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

fn parse_cgroup_value(text: &str) -> Option<f64> {
    let t = text.trim();
    if t == "max" {
        return None;
    }
    let v: f64 = t.parse().ok()?;
    // cgroup v1 reports "no limit" as a huge page-aligned number.
    (v < 1e18).then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_kernels_formats() {
        assert_eq!(parse_meminfo("MemTotal: 100 kB\nMemAvailable:   2048 kB\n", "MemAvailable:"), Some(2048.0 * 1024.0));
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max address space         8589934592           unlimited            bytes     \n";
        assert_eq!(parse_limits(limits), Some(8589934592.0));
        let unl = "Max address space         unlimited            unlimited            bytes     \n";
        assert_eq!(parse_limits(unl), None);
        assert_eq!(parse_cgroup_value("max\n"), None);
        assert_eq!(parse_cgroup_value("1073741824\n"), Some(1073741824.0));
        assert_eq!(parse_cgroup_value("9223372036854771712"), None);
    }

    #[test]
    fn the_tuned_allocator_gives_the_same_values() {
        // The settings are taken on glibc; allocations after them, large
        // (beyond the mmap threshold) and small, hold what was written, as
        // before them.
        let fill = || -> (Vec<u64>, Vec<Box<[f32; 512]>>) {
            let big: Vec<u64> = (0..(40u64 << 20) / 8).map(|i| i * 2654435761).collect();
            let small = (0..1000).map(|i| Box::new([i as f32; 512])).collect();
            (big, small)
        };
        let before = fill();
        let tuned = tune_allocator();
        assert_eq!(tuned, cfg!(all(target_os = "linux", target_env = "gnu")));
        let after = fill();
        assert!(before == after);
    }

    #[test]
    fn the_smallest_readable_limit_wins_and_none_is_assumed() {
        let gib = |g: f64| g * (1u64 << 30) as f64;
        let m = smallest(&[(Some(gib(20.0)), "MemAvailable"), (Some(gib(8.0)), "cgroup memory limit"), (Some(gib(12.0)), "RLIMIT_AS")]);
        assert_eq!(m, MemoryLimit { bytes: gib(8.0), source: "cgroup memory limit" });
        // Unreadable, zero, negative and non-finite readings are no limits;
        // a limit above the assumed 24 GiB still wins when it is the only one.
        let m = smallest(&[
            (None, "MemAvailable"),
            (Some(0.0), "cgroup memory limit"),
            (Some(f64::INFINITY), "RLIMIT_AS"),
            (Some(gib(64.0)), "x"),
        ]);
        assert_eq!(m, MemoryLimit { bytes: gib(64.0), source: "x" });
        assert_eq!(smallest(&[(None, "MemAvailable"), (Some(-1.0), "RLIMIT_AS")]), MemoryLimit { bytes: gib(24.0), source: "assumed" });
    }

    #[test]
    fn this_machines_limit_is_positive_and_named() {
        // The live readings move (MemAvailable) between calls, so only what
        // cannot move is asserted here; the choice is the test above.
        let a = available();
        assert!(a.bytes.is_finite() && a.bytes > 0.0);
        assert!(["MemAvailable", "cgroup memory limit", "RLIMIT_AS", "available physical memory", "assumed"].contains(&a.source));
    }
}
