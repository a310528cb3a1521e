//! Helpers the benchmark examples share (`mod common;`); not every example
//! uses every one.
#![allow(dead_code)]

/// CPU time of this process (user + system, all threads), seconds, from
/// /proc/self/stat (clock ticks of 1/100 s); 0 where unavailable.
pub fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which may hold spaces) end with ')'.
    let rest = stat.rsplit_once(')').map(|x| x.1).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after ')'.
    (tick(11) + tick(12)) / 100.0
}

/// The load averages over 1, 5 and 15 minutes, as /proc/loadavg prints
/// them; empty where unavailable.
pub fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg").map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" ")).unwrap_or_default()
}
