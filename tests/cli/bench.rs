//! `aurora bench --quick` end to end: the files exist and parse, the Pareto
//! flags agree with the numbers in the CSV, and each study's error moves the
//! way the method's analysis says it must (more beams or samples: less
//! noise; smaller voxels or steps: less discretisation error). Errors are
//! deterministic (fixed seeds), so these orderings are properties of the
//! code, not of a lucky run; times are never asserted.

use crate::common::{scratch, Aurora};
use serde_json::Value;
use std::collections::BTreeMap;

/// One CSV row, by column name.
type Row = BTreeMap<String, String>;

/// RFC 4180 subset: comma-separated, fields with commas or quotes quoted,
/// "" for a quote inside.
fn parse_csv_line(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            (c, _) => cur.push(c),
        }
    }
    out.push(cur);
    out
}

fn num(r: &Row, k: &str) -> f64 {
    r[k].parse::<f64>().unwrap_or_else(|e| panic!("column {k} = {:?}: {e}", r[k]))
}

/// The rows of `study` and `method`, sorted by the swept parameter, as
/// (param, error).
fn curve(rows: &[Row], study: &str, method: &str) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> =
        rows.iter().filter(|r| r["study"] == study && r["method"] == method).map(|r| (num(r, "param"), num(r, "error"))).collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(v.len() >= 2, "{study} / {method}: {v:?}");
    v
}

fn strictly_decreasing(what: &str, c: &[(f64, f64)]) {
    for w in c.windows(2) {
        assert!(w[1].1 < w[0].1, "{what}: error must fall as the parameter grows: {c:?}");
    }
}

fn strictly_increasing(what: &str, c: &[(f64, f64)]) {
    for w in c.windows(2) {
        assert!(w[1].1 > w[0].1, "{what}: error must grow with the parameter: {c:?}");
    }
}

#[test]
fn quick_bench_writes_consistent_csv_json_and_charts() {
    let out = scratch("bench", "quick");
    // At the beam density the default had before its arcs grew from 1140
    // to 1900 km (8000 beams then, 13,333 now): its 8000 beams give the
    // reduced 40 km chunk 133 beams, so noisy that the gather-radius
    // curve still falls at its largest radius (no interior minimum).
    let run = Aurora::new().args(["bench", "default", "--quick", "--quiet", "--set", "beams.count=13333", "--out"]).arg(&out).output();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "status {:?}\nstdout:\n{stdout}\nstderr:\n{}", run.status, String::from_utf8_lossy(&run.stderr));
    // The summary table names every study.
    let studies = [
        "photon count",
        "gather radius",
        "gather method",
        "voxel size",
        "primary-ray integration",
        "pruning",
        "storage (scene camera)",
        "storage (dome master)",
        "shadow rays",
        "animation flicker",
    ];
    for st in studies {
        assert!(stdout.contains(&format!("== {st} ")), "summary lacks {st}:\n{stdout}");
    }
    // Frames per hour and bytes per frame of the full default scene: two
    // frames of a ten-minute range at the scene's fps, baked and written.
    assert!(stdout.contains("== throughput of the full scene"), "{stdout}");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("bench.json")).unwrap()).unwrap();
    let t = &json["throughput"];
    assert!(t["frames_per_hour"].as_f64().unwrap() > 0.0 && t["frames_per_cpu_hour"].as_f64().unwrap() > 0.0, "{t}");
    // The default frame is some 40-60 MB: 20-500 MB bounds a real write.
    let b = t["bytes_per_frame"].as_f64().unwrap();
    assert!((2e7..5e8).contains(&b), "bytes per frame {b}");
    let frames: Vec<i64> = t["plan"]["samples"].as_array().unwrap().iter().map(|s| s["frame"].as_i64().unwrap()).collect();
    assert_eq!(frames, vec![1, 14400], "ten minutes at the default 24 fps");

    // --- bench.csv
    let text = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    let mut lines = text.lines();
    let header = parse_csv_line(lines.next().expect("header"));
    assert_eq!(header, aurora::app::bench::measurement::CSV_HEADER.split(',').collect::<Vec<_>>());
    let rows: Vec<Row> = lines
        .map(|l| {
            let f = parse_csv_line(l);
            assert_eq!(f.len(), header.len(), "{l}");
            header.iter().cloned().zip(f).collect()
        })
        .collect();
    for r in &rows {
        let (s, e) = (num(r, "cost"), num(r, "error"));
        assert!(s > 0.0 && s.is_finite() && e >= 0.0 && e.is_finite(), "{r:?}");
        assert!(["0", "1"].contains(&r["pareto"].as_str()) && ["0", "1"].contains(&r["scene_setting"].as_str()));
    }
    for st in studies {
        let sel: Vec<&Row> = rows.iter().filter(|r| r["study"] == st).collect();
        assert!(sel.len() >= 3, "{st}: {} rows", sel.len());
        // Pareto flags: a flagged point is dominated by no other; an
        // unflagged one is dominated (or repeats an earlier flagged point).
        let pts: Vec<(f64, f64)> = sel.iter().map(|r| (num(r, "cost"), num(r, "error"))).collect();
        for (i, r) in sel.iter().enumerate() {
            let dominated =
                pts.iter().enumerate().any(|(j, q)| j != i && q.0 <= pts[i].0 && q.1 <= pts[i].1 && (q.0 < pts[i].0 || q.1 < pts[i].1));
            let duplicate = pts[..i].iter().any(|q| *q == pts[i]);
            assert_eq!(r["pareto"] == "1", !dominated && !duplicate, "{st}: {r:?}");
        }
        assert!(sel.iter().any(|r| r["pareto"] == "1"), "{st}: empty front");
        assert_eq!(sel.iter().filter(|r| r["scene_setting"] == "1").count(), 1, "{st}: one scene setting");
        let stage = &sel[0]["stage"];
        assert!(sel.iter().all(|r| &r["stage"] == stage), "{st}: one timed stage");
    }

    // --- the expected trends
    strictly_decreasing("photon count", &curve(&rows, "photon count", "splat, r = 0.35 km"));
    for m in ["kd-tree (kiddo)", "splat"] {
        strictly_decreasing(&format!("gather method / {m}"), &curve(&rows, "gather method", m));
        strictly_increasing(&format!("voxel size / {m}"), &curve(&rows, "voxel size", m));
    }
    // report2014 is an average, not a density: far from the density
    // reference at every photon count, and no better with more photons
    // (its expectation is not the density), unlike the kd-tree.
    let kd = curve(&rows, "gather method", "kd-tree (kiddo)");
    let avg = curve(&rows, "gather method", "report2014 (average)");
    assert!(avg.last().unwrap().1 > 1.5 * kd.last().unwrap().1, "{avg:?} vs {kd:?}");
    let fixed = curve(&rows, "primary-ray integration", "fixed step");
    strictly_increasing("fixed step", &fixed);
    let exact: Vec<&Row> = rows.iter().filter(|r| r["method"].starts_with("exact")).collect();
    assert_eq!(exact.len(), 1);
    assert_eq!(num(exact[0], "error"), 0.0, "exact is the reference");
    // Pruning: a larger budget drops more light, so the image error grows;
    // the unpruned bake is the reference (error 0).
    strictly_increasing("pruning", &curve(&rows, "pruning", "contribution pruning"));
    let unpruned: Vec<&Row> = rows.iter().filter(|r| r["method"] == "unpruned").collect();
    assert_eq!(unpruned.len(), 1);
    assert_eq!(num(unpruned[0], "error"), 0.0, "unpruned is the reference");
    for m in ["shadow rays per hit (spp 1)", "pixel samples (1 shadow ray each)"] {
        strictly_decreasing(m, &curve(&rows, "shadow rays", m));
    }
    // Radius: noise at the small end, blur at the large end, both worse than
    // the best radius in between (with the quick bench's few beams that
    // lies above the scene's 0.35 km, where the noise is smaller).
    let radius: Vec<&Row> = rows.iter().filter(|r| r["study"] == "gather radius").collect();
    let at = |want: f64| num(radius.iter().find(|r| (num(r, "param") - want).abs() < 1e-9).unwrap(), "error");
    let scene_r = num(radius.iter().find(|r| r["scene_setting"] == "1").unwrap(), "param");
    let rs: Vec<f64> = radius.iter().map(|r| num(r, "param")).collect();
    let (rmin, rmax) = (rs.iter().cloned().fold(f64::MAX, f64::min), rs.iter().cloned().fold(f64::MIN, f64::max));
    let best = radius.iter().map(|r| num(r, "error")).fold(f64::MAX, f64::min);
    assert!(scene_r > rmin && scene_r < rmax, "the scene's radius lies inside the sweep: {radius:?}");
    assert!(at(rmin) > best && at(rmax) > best, "radius curve has no interior minimum: {radius:?}");

    // One gather setting, one time: the scene's own gather (N beams,
    // r, v) appears in three gather-timed studies with the same seconds.
    let scene_gather: Vec<f64> = rows
        .iter()
        .filter(|r| r["scene_setting"] == "1" && ["gather radius", "gather method", "voxel size"].contains(&r["study"].as_str()))
        .map(|r| num(r, "cost"))
        .collect();
    assert_eq!(scene_gather.len(), 3);
    assert!(scene_gather.iter().all(|&t| t == scene_gather[0]), "{scene_gather:?}");
    // The photon-count study adds the beam trace to the same gather.
    let pc = rows.iter().find(|r| r["study"] == "photon count" && r["scene_setting"] == "1").unwrap();
    assert!(num(pc, "cost") > scene_gather[0], "beams + gather > gather");

    // --- charts
    for st in studies {
        let stem = aurora::app::bench::report::slug(st);
        let png = std::fs::File::open(out.join(format!("{stem}.png"))).expect("png chart");
        let mut reader = png::Decoder::new(std::io::BufReader::new(png)).read_info().expect("png parses");
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).expect("png decodes");
        assert_eq!((info.width, info.height), (900, 600));
        // Not blank: some pixels are not white.
        assert!(buf.iter().any(|&b| b < 200), "{stem}.png is blank");
        let svg = std::fs::read_to_string(out.join(format!("{stem}.svg"))).expect("svg chart");
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "{stem}.svg");
        // The storage studies chart a file's size, not a time.
        let against = if st.starts_with("storage") { "size" } else { "time" };
        assert!(svg.contains(&format!("{st}: {against} against error")) && svg.contains("Pareto front"), "{stem}.svg");
    }

    // --- bench.json
    let j: Value = serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).expect("bench.json")).expect("json");
    assert!(j["machine"]["nproc"].as_u64().unwrap() >= 1);
    assert!(!j["machine"]["model_name"].as_str().unwrap().is_empty());
    let date = j["date"].as_str().unwrap();
    assert!(date.len() == 10 && date.as_bytes()[4] == b'-' && date.as_bytes()[7] == b'-', "{date}");
    assert_eq!(j["plan"]["quick"], Value::Bool(true));
    let js = j["studies"].as_array().unwrap();
    assert_eq!(js.len(), studies.len());
    for s in js {
        let name = s["study"].as_str().unwrap();
        let front = s["pareto_front"].as_array().unwrap();
        let csv_front = rows.iter().filter(|r| r["study"] == name && r["pareto"] == "1").count();
        assert_eq!(front.len(), csv_front, "{name}");
        let scene_row = rows.iter().find(|r| r["study"] == name && r["scene_setting"] == "1").unwrap();
        assert_eq!(s["scene_setting_on_front"].as_bool().unwrap(), scene_row["pareto"] == "1", "{name}");
        assert!(s["most_accurate"]["error"].as_f64().is_some() && s["reference"].as_str().is_some(), "{name}");
        // The fastest setting at least as accurate as the scene's is no
        // slower and no less accurate than it.
        let best = &s["fastest_at_least_as_accurate_as_scene"];
        assert!(best["cost"].as_f64().unwrap() <= num(scene_row, "cost"));
        assert!(best["error"].as_f64().unwrap() <= num(scene_row, "error"));
    }
}
