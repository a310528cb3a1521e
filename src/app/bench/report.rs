//! What `aurora bench` leaves behind: `bench.csv` (every measurement),
//! `bench.json` (machine, date, plan, reduced scene, per-study references and
//! best settings), one chart per study (`<study>.png` and `.svg`), and the
//! summary table printed on stdout.

use super::chart;
use super::harness::{Study, StudyPlan};
use super::measurement::{front_flags, Measurement};
use crate::util::atomic_write::write_atomic;
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The machine a bench ran on.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Machine {
    /// Logical CPUs available to the process.
    pub nproc: usize,
    /// `model name` from /proc/cpuinfo ("unknown" elsewhere).
    pub model_name: String,
    /// rayon worker threads used.
    pub threads: usize,
    /// /proc/loadavg at the start and end (the machine may be shared).
    pub loadavg_start: String,
    pub loadavg_end: String,
}

impl Machine {
    pub fn probe() -> Machine {
        let model_name = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| {
                t.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split_once(':')).map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Machine {
            nproc: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            model_name,
            threads: rayon::current_num_threads(),
            loadavg_start: loadavg(),
            loadavg_end: String::new(),
        }
    }
}

/// /proc/loadavg's first three fields, or "unknown".
pub fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|t| t.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".into())
}

/// UTC date and time of `t` as ("YYYY-MM-DD", "YYYY-MM-DDTHH:MM:SSZ").
pub fn utc_date(t: std::time::SystemTime) -> (String, String) {
    let secs = t.duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs() as i64).unwrap_or(0);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let (y, m, d) = civil_from_days(days);
    let date = format!("{y:04}-{m:02}-{d:02}");
    let full = format!("{date}T{:02}:{:02}:{:02}Z", rem / 3600, rem / 60 % 60, rem % 60);
    (date, full)
}

/// Proleptic Gregorian (year, month, day) of a day count since 1970-01-01
/// (H. Hinnant, "chrono-Compatible Low-Level Date Algorithms", civil_from_days).
pub fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (if m <= 2 { y + 1 } else { y }, m, d)
}

/// A whole bench run.
#[derive(Clone, Debug)]
pub struct BenchRun {
    pub machine: Machine,
    /// ("YYYY-MM-DD", ISO date-time), UTC, at the start.
    pub date: (String, String),
    pub wall_seconds: f64,
    pub plan: StudyPlan,
    /// The scene argument, the reduced scene (TOML) and what was changed.
    pub scene_name: String,
    pub reduced_toml: String,
    pub reduction: Vec<String>,
    pub studies: Vec<Study>,
    /// The full scene's throughput as a sequence: two frames of a ten-minute
    /// range at the scene's fps baked and written ([`crate::farm::cost_plan`]).
    pub throughput: crate::farm::cost_plan::CostPlan,
}

impl BenchRun {
    /// Every measurement, study by study.
    pub fn measurements(&self) -> Vec<Measurement> {
        self.studies.iter().flat_map(|s| s.measurements.iter().cloned()).collect()
    }
}

fn point(m: &Measurement) -> Value {
    json!({
        "method": m.method,
        m.param_name.clone(): m.param,
        "cost": m.cost,
        "unit": m.unit.symbol(),
        "error": m.error,
    })
}

/// The per-study summary of `bench.json`: the Pareto front, the scene's own
/// setting and whether it is on the front, the most accurate setting, and
/// the fastest setting at least as accurate as the scene's.
pub fn study_json(st: &Study) -> Value {
    let ms = &st.measurements;
    let flags = front_flags(ms);
    let front: Vec<Value> = ms.iter().zip(&flags).filter(|(_, &f)| f).map(|(m, _)| point(m)).collect();
    let scene = ms.iter().zip(&flags).find(|(m, _)| m.scene_setting);
    let most_accurate = ms.iter().min_by(|a, b| a.error.total_cmp(&b.error).then(a.cost.total_cmp(&b.cost)));
    let as_good = scene.and_then(|(s, _)| ms.iter().filter(|m| m.error <= s.error).min_by(|a, b| a.cost.total_cmp(&b.cost)));
    json!({
        "study": st.name,
        "timed_stage": st.stage,
        "metric": st.metric,
        "reference": st.reference,
        "reference_cost": st.reference_cost,
        "unit": st.unit.symbol(),
        "notes": st.notes,
        "pareto_front": front,
        "scene_setting": scene.map(|(m, _)| point(m)),
        "scene_setting_on_front": scene.map(|(_, &f)| f),
        "most_accurate": most_accurate.map(point),
        "fastest_at_least_as_accurate_as_scene": as_good.map(point),
    })
}

/// `bench.json`.
pub fn to_json(run: &BenchRun) -> Value {
    json!({
        "aurora_version": env!("CARGO_PKG_VERSION"),
        "date": run.date.0,
        "started_utc": run.date.1,
        "wall_seconds": run.wall_seconds,
        "machine": run.machine,
        "scene": run.scene_name,
        "reduced_scene_changes": run.reduction,
        "reduced_scene_toml": run.reduced_toml,
        "plan": run.plan,
        "studies": run.studies.iter().map(study_json).collect::<Vec<_>>(),
        "throughput": throughput_json(&run.throughput),
    })
}

/// Frames per hour (one task on this machine's threads, and per CPU-hour)
/// and bytes per frame of the full scene.
pub fn throughput_json(p: &crate::farm::cost_plan::CostPlan) -> Value {
    json!({
        "frames_per_hour": frames_per_hour(p.wall_per_frame_s),
        "frames_per_cpu_hour": frames_per_hour(p.cpu_per_frame_s),
        "bytes_per_frame": p.bytes_per_frame,
        "wall_per_frame_s": p.wall_per_frame_s,
        "cpu_per_frame_s": p.cpu_per_frame_s,
        "setup_cpu_s": p.setup_cpu_s,
        "peak_rss_bytes": p.peak_rss_bytes,
        "threads": p.threads,
        "plan": p.json(),
    })
}

fn frames_per_hour(seconds: f64) -> f64 {
    if seconds > 0.0 {
        3600.0 / seconds
    } else {
        0.0
    }
}

/// The throughput lines of the summary.
pub fn throughput_summary(p: &crate::farm::cost_plan::CostPlan) -> String {
    format!(
        "\n== throughput of the full scene as a sequence (frames {} and {} of {}-{}, baked and written)\n   {:.0} frames per hour on {} threads ({:.2} s a frame), {:.0} frames per CPU-hour ({:.2} CPU-s a frame; {}), {} a frame, peak {}\n",
        p.samples.first().map_or(0, |s| s.frame),
        p.samples.last().map_or(0, |s| s.frame),
        p.first,
        p.last,
        frames_per_hour(p.wall_per_frame_s),
        p.threads,
        p.wall_per_frame_s,
        frames_per_hour(p.cpu_per_frame_s),
        p.cpu_per_frame_s,
        p.setup_words(),
        crate::farm::cost_plan::human_bytes(p.bytes_per_frame),
        crate::util::memory::gib(p.peak_rss_bytes),
    )
}

/// The table printed on stdout: one block per study, one line per
/// measurement (`F` = on the Pareto front, `*` = the scene's own setting).
pub fn summary(run: &BenchRun) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "aurora bench: {} ({}), {} threads of {} CPUs ({}), {:.0} s",
        run.date.1, run.scene_name, run.machine.threads, run.machine.nproc, run.machine.model_name, run.wall_seconds
    );
    for st in &run.studies {
        let flags = front_flags(&st.measurements);
        let (what, unit) = (st.unit.quantity(), st.unit.symbol());
        let col = match st.unit {
            super::measurement::CostUnit::Seconds => "seconds",
            super::measurement::CostUnit::Megabytes => unit,
        };
        let _ = writeln!(s, "\n== {} ({what}: {}; error: {})", st.name, st.stage, st.metric);
        let _ = writeln!(s, "   reference: {} ({:.2} {unit})", st.reference, st.reference_cost);
        let _ = writeln!(s, "   {:<44} {:>12} {:>10} {:>11}  front scene", "method", "param", col, "error");
        for (m, f) in st.measurements.iter().zip(&flags) {
            let _ = writeln!(
                s,
                "   {:<44} {:>12} {:>10.4} {:>11.4e}  {:^5} {:^5}",
                m.method,
                format!("{}={}", short(&m.param_name), m.param),
                m.cost,
                m.error,
                if *f { "F" } else { "" },
                if m.scene_setting { "*" } else { "" }
            );
        }
        let j = study_json(st);
        if let Some(on) = j["scene_setting_on_front"].as_bool() {
            let _ = writeln!(s, "   scene setting on the Pareto front: {}", if on { "yes" } else { "no" });
        }
    }
    s + &throughput_summary(&run.throughput)
}

fn short(name: &str) -> &str {
    match name {
        "radius_km" => "r",
        "voxel_km" => "v",
        "step_km" => "h",
        other => other,
    }
}

/// A file-name stem for a study: lowercase, words joined by '-'.
pub fn slug(study: &str) -> String {
    let mut out = String::new();
    for c in study.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') && !out.is_empty() {
            out.push('-');
        }
    }
    out.trim_end_matches('-').to_string()
}

/// A bench output could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error(transparent)]
    Chart(#[from] chart::ChartError),
}

impl ReportError {
    /// Never the user's input: writing the report or drawing a chart failed (exit status 1).
    pub fn is_input(&self) -> bool {
        false
    }
}

/// Writes `bench.csv`, `bench.json` and a PNG and an SVG chart per study into
/// `dir` (created if missing), each through a temporary name and a rename.
/// Returns the paths written.
pub fn write(run: &BenchRun, dir: &Path) -> Result<Vec<PathBuf>, ReportError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ReportError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let mut written = Vec::new();
    let ms = run.measurements();
    let csv = dir.join("bench.csv");
    write_atomic(&csv, super::measurement::to_csv(&ms).as_bytes()).map_err(|e| io(&csv)(e.into()))?;
    written.push(csv);
    for st in &run.studies {
        let name = slug(&st.name);
        let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
        chart::draw_study(&ms, &st.name, &tmp)?;
        for ext in ["png", "svg"] {
            let to = dir.join(format!("{name}.{ext}"));
            std::fs::rename(tmp.with_extension(ext), &to).map_err(io(&to))?;
            written.push(to);
        }
    }
    let json_path = dir.join("bench.json");
    let text = serde_json::to_string_pretty(&to_json(run)).expect("bench json serialises") + "\n";
    write_atomic(&json_path, text.as_bytes()).map_err(|e| io(&json_path)(e.into()))?;
    written.push(json_path);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates_match_known_days() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        // 2000-02-29 (a leap day of a century leap year) is day 11016.
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        // 2024-03-01 is day 19783.
        assert_eq!(civil_from_days(19_783), (2024, 3, 1));
        let t = std::time::UNIX_EPOCH + std::time::Duration::from_secs(19_783 * 86_400 + 3_723);
        assert_eq!(utc_date(t), ("2024-03-01".into(), "2024-03-01T01:02:03Z".into()));
    }

    #[test]
    fn slugs_are_file_names() {
        assert_eq!(slug("primary-ray integration"), "primary-ray-integration");
        assert_eq!(slug("photon count"), "photon-count");
    }
}
