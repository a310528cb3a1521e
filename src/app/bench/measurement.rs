//! One point of a study: a setting, what it costs (wall time of a stage, or
//! a file's size) with the cost's unit, and its error against the study's
//! reference; the Pareto front of cost against error, and `bench.csv`.

use serde::Serialize;

/// The unit of a measurement's cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum CostUnit {
    /// Wall time of the measured stage.
    Seconds,
    /// A file's size, 10^6 bytes.
    Megabytes,
}

impl CostUnit {
    /// The unit's symbol: `s` or `MB`.
    pub fn symbol(self) -> &'static str {
        match self {
            CostUnit::Seconds => "s",
            CostUnit::Megabytes => "MB",
        }
    }

    /// What the cost is, for axis labels and table headings: `time` or `size`.
    pub fn quantity(self) -> &'static str {
        match self {
            CostUnit::Seconds => "time",
            CostUnit::Megabytes => "size",
        }
    }
}

/// One run of one method at one setting.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Measurement {
    /// What is being swept, e.g. "photon count".
    pub study: String,
    /// The curve it belongs to, e.g. "kd-tree gather".
    pub method: String,
    /// The swept parameter's name and value, e.g. ("beams", 20000).
    pub param_name: String,
    pub param: f64,
    /// The stage whose cost `cost` is, e.g. "gather", "render" or "file size".
    pub stage: String,
    /// What the setting costs, in [`Measurement::unit`]s.
    pub cost: f64,
    pub unit: CostUnit,
    /// Error against the reference (relative RMS unless `metric` says otherwise).
    pub error: f64,
    pub metric: String,
    /// This run uses the given scene's own setting for what is swept.
    pub scene_setting: bool,
}

/// Indices of the points on the Pareto front of (time, error), both to be
/// minimised: no other point is at least as good in both and better in one.
/// Returned in ascending time.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len()).filter(|&i| points[i].0.is_finite() && points[i].1.is_finite()).collect();
    idx.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1)));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The header of [`to_csv`].
pub const CSV_HEADER: &str = "study,method,param_name,param,stage,cost,unit,error,metric,scene_setting,pareto";

/// `bench.csv`: one row per measurement, plus a Pareto flag within its study.
pub fn to_csv(ms: &[Measurement]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    let on_front = front_flags(ms);
    for (m, p) in ms.iter().zip(on_front) {
        s += &format!(
            // Shortest round-trip representations: the CSV holds exactly
            // the numbers the Pareto flags were computed from.
            "{},{},{},{},{},{},{},{:e},{},{},{}\n",
            csv_field(&m.study),
            csv_field(&m.method),
            csv_field(&m.param_name),
            m.param,
            csv_field(&m.stage),
            m.cost,
            m.unit.symbol(),
            m.error,
            csv_field(&m.metric),
            m.scene_setting as u8,
            p as u8
        );
    }
    s
}

/// For each measurement, whether it is on its study's Pareto front.
pub fn front_flags(ms: &[Measurement]) -> Vec<bool> {
    let mut flags = vec![false; ms.len()];
    let mut studies: Vec<&str> = ms.iter().map(|m| m.study.as_str()).collect();
    studies.dedup();
    studies.sort();
    studies.dedup();
    for st in studies {
        let ids: Vec<usize> = (0..ms.len()).filter(|&i| ms[i].study == st).collect();
        let pts: Vec<(f64, f64)> = ids.iter().map(|&i| (ms[i].cost, ms[i].error)).collect();
        for k in pareto_front(&pts) {
            flags[ids[k]] = true;
        }
    }
    flags
}

/// A cost and its unit, as a study measures it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost(pub f64, pub CostUnit);

impl Cost {
    pub fn seconds(s: f64) -> Cost {
        Cost(s, CostUnit::Seconds)
    }

    pub fn megabytes(mb: f64) -> Cost {
        Cost(mb, CostUnit::Megabytes)
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_marks_front_per_study() {
        let m = |study: &str, s: f64, e: f64| Measurement {
            study: study.into(),
            method: "m".into(),
            param_name: "p".into(),
            param: 1.0,
            stage: "gather".into(),
            cost: s,
            unit: CostUnit::Seconds,
            error: e,
            metric: "rel".into(),
            scene_setting: false,
        };
        let ms = vec![m("a", 1.0, 1.0), m("a", 2.0, 2.0), m("b", 2.0, 2.0)];
        assert_eq!(front_flags(&ms), vec![true, false, true]);
        let csv = to_csv(&ms);
        assert_eq!(csv.lines().count(), 4);
        assert_eq!(csv.lines().next().unwrap(), CSV_HEADER);
        assert!(csv.lines().nth(2).unwrap().ends_with(",0"));
        // Numbers are written so that they read back exactly.
        let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
        assert_eq!(row[5].parse::<f64>().unwrap(), 1.0);
        assert_eq!(row[6], "s");
        assert_eq!(row[7].parse::<f64>().unwrap(), 1.0);
    }
}
