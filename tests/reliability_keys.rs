//! No panic, on anything: every numeric scene key
//! and every command-line number is driven through zero, tiny, huge,
//! negative, NaN and the infinities (and, for integer keys, through the edges
//! of the integer range), the other keys kept small, and every run must end
//! with exit 0 or 2: never 101 (a panic), never a signal (an abort from a
//! failed allocation, a stack overflow), under an 8 GiB address-space cap.
//!
//! The keys are not listed by hand: they are every numeric leaf of the default
//! scene's TOML (array elements included), so a key added later is covered
//! the day it lands. Bake keys run `aurora bake`; keys of the picture
//! (`camera`, `render`, `volume`, `background`, `terrain`) run `aurora render`,
//! which bakes in memory and renders.
//!
//! A case that legitimately works longer than [`CASE_SECONDS`] is stopped by
//! the harness and passes only if it was still running (no crash) when
//! stopped; the cap makes an allocation beyond 8 GiB fail, which Rust turns
//! into an abort (a signal), so "stayed under the memory cap" is checked too.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CASE_SECONDS: u64 = 60;
/// The address-space cap, KiB (`ulimit -v`).
const CAP_KIB: u64 = 8 * 1024 * 1024;

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/test-reliability").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create test folder under target/");
    d
}

/// The base scene: one small curtain, few beams, a tiny picture, the
/// heightfield terrain kept (its keys are exercised).
fn base() -> toml::Table {
    let text = "seed = 5\n\
        [[curtain]]\nlength = 20.0\nwidth = 8.0\nbend_km = 2.0\n\
        [footprint]\nresolution = [32, 16]\nsteps = 4\npressure_iterations = 8\n\
        [beams]\ncount = 150\n\
        [grid]\nvoxel_size = 0.5\n\
        [render]\nwidth = 24\nheight = 14\nspp = 1\n\
        [terrain]\nkind = \"heightfield\"\n";
    text.parse().expect("base scene parses")
}

/// Every numeric leaf of the default scene (one curtain), as a path of keys
/// and array indices, with whether it is an integer.
fn numeric_keys() -> Vec<(Vec<String>, bool)> {
    let mut scene = aurora::scene::Scene::default();
    scene.curtains.truncate(1);
    let t = toml::Table::try_from(&scene).expect("scene serialises");
    let mut out = Vec::new();
    fn walk(v: &toml::Value, path: &mut Vec<String>, out: &mut Vec<(Vec<String>, bool)>) {
        match v {
            toml::Value::Integer(_) => out.push((path.clone(), true)),
            toml::Value::Float(_) => out.push((path.clone(), false)),
            toml::Value::Table(t) => {
                for (k, x) in t {
                    path.push(k.clone());
                    walk(x, path, out);
                    path.pop();
                }
            }
            toml::Value::Array(a) => {
                // The colour map's rows: the first row stands for all.
                for (i, x) in a.iter().enumerate().take(if path.last().map(String::as_str) == Some("colormap") { 1 } else { usize::MAX }) {
                    path.push(format!("#{i}"));
                    walk(x, path, out);
                    path.pop();
                }
            }
            _ => {}
        }
    }
    walk(&toml::Value::Table(t), &mut Vec::new(), &mut out);
    out
}

/// `table` with the value at `path` replaced (missing tables and arrays are
/// filled from the default scene).
fn set(table: &toml::Table, path: &[String], value: toml::Value) -> toml::Table {
    let mut scene = aurora::scene::Scene::default();
    scene.curtains.truncate(1);
    let defaults = toml::Table::try_from(&scene).unwrap();
    let mut t = table.clone();
    fn put(node: &mut toml::Value, default: &toml::Value, path: &[String], value: toml::Value) {
        if path.is_empty() {
            *node = value;
            return;
        }
        let (head, rest) = (&path[0], &path[1..]);
        if let Some(i) = head.strip_prefix('#') {
            let i: usize = i.parse().unwrap();
            if !matches!(node, toml::Value::Array(_)) {
                *node = default.clone();
            }
            let d = default.as_array().and_then(|a| a.get(i)).cloned().unwrap_or(toml::Value::Integer(0));
            if let toml::Value::Array(a) = node {
                if a.len() <= i {
                    *a = default.as_array().cloned().unwrap_or_default();
                }
                put(&mut a[i], &d, rest, value);
            }
        } else {
            if !matches!(node, toml::Value::Table(_)) {
                *node = toml::Value::Table(Default::default());
            }
            let d = default.get(head).cloned().unwrap_or(toml::Value::Table(Default::default()));
            let toml::Value::Table(tb) = node else { unreachable!() };
            let slot = tb.entry(head.clone()).or_insert_with(|| match &d {
                toml::Value::Table(_) => toml::Value::Table(Default::default()),
                other => other.clone(),
            });
            put(slot, &d, rest, value);
        }
    }
    let mut root = toml::Value::Table(std::mem::take(&mut t));
    put(&mut root, &toml::Value::Table(defaults), path, value);
    match root {
        toml::Value::Table(t) => t,
        _ => unreachable!(),
    }
}

fn float_values() -> Vec<toml::Value> {
    [0.0, 1e-300, -1e-300, 1e-22, 1e20, 1e300, -1.0, -1e300, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, f64::MAX]
        .into_iter()
        .map(toml::Value::Float)
        .collect()
}

fn integer_values() -> Vec<toml::Value> {
    let mut v: Vec<toml::Value> = [0i64, 1, -1, 1_000_000_000, i64::MAX, i64::MIN].into_iter().map(toml::Value::Integer).collect();
    // A float where an integer belongs is a type error (exit 2), never a panic.
    v.push(toml::Value::Float(f64::NAN));
    v.push(toml::Value::Float(0.5));
    v
}

#[derive(Debug)]
enum Outcome {
    Exit(i32),
    Signal(i32),
    /// Still running (not crashed) when the harness stopped it.
    Cut,
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::Exit(c) => write!(f, "exit {c}"),
            Outcome::Signal(s) => write!(f, "killed by signal {s}{}", if *s == 6 { " (abort: a panic under the cap?)" } else { "" }),
            Outcome::Cut => write!(f, "still running at the cut"),
        }
    }
}

/// Runs aurora under the address-space cap, stopping it after `CASE_SECONDS`.
fn run_capped(args: &[&str], cwd: &Path) -> (Outcome, String) {
    use std::os::unix::process::ExitStatusExt;
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("ulimit -v {CAP_KIB} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_aurora"))
        .args(args)
        .current_dir(cwd)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("spawn sh");
    let t = Instant::now();
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        use std::io::Read;
        let _ = stderr.read_to_string(&mut s);
        s
    });
    loop {
        if let Some(st) = child.try_wait().expect("wait") {
            let err = reader.join().unwrap();
            return match (st.code(), st.signal()) {
                (Some(c), _) => (Outcome::Exit(c), err),
                (None, Some(s)) => (Outcome::Signal(s), err),
                _ => (Outcome::Exit(-1), err),
            };
        }
        if t.elapsed() > Duration::from_secs(CASE_SECONDS) {
            let _ = child.kill();
            let _ = child.wait();
            return (Outcome::Cut, reader.join().unwrap());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn is_picture_key(path: &[String]) -> bool {
    matches!(path[0].as_str(), "camera" | "render" | "volume" | "background" | "terrain")
}

/// Runs `cases` two at a time (the machines have 2 cores) and returns the failures.
fn run_all(cases: Vec<(String, Vec<String>)>, d: &Path) -> Vec<String> {
    run_all_counting(cases, d).0
}

/// [`run_all`], also counting the runs that succeeded (exit 0).
fn run_all_counting(cases: Vec<(String, Vec<String>)>, d: &Path) -> (Vec<String>, usize) {
    let cases = std::sync::Mutex::new(cases.into_iter().enumerate().collect::<Vec<_>>());
    let failures = std::sync::Mutex::new(Vec::new());
    let succeeded = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let Some((i, (label, args))) = cases.lock().unwrap().pop() else { break };
                let work = d.join(format!("case{i}"));
                std::fs::create_dir_all(&work).unwrap();
                let a: Vec<&str> = args.iter().map(String::as_str).collect();
                let (outcome, err) = run_capped(&a, &work);
                let ok = matches!(outcome, Outcome::Exit(0) | Outcome::Exit(2) | Outcome::Cut);
                if matches!(outcome, Outcome::Exit(0)) {
                    succeeded.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
                if !ok {
                    let tail: String = err.lines().filter(|l| !l.starts_with("  ")).take(6).collect::<Vec<_>>().join(" | ");
                    failures.lock().unwrap().push(format!("{label}: {outcome}: {tail}"));
                }
                // An error must say what is wrong, in words.
                if matches!(outcome, Outcome::Exit(2)) && !err.contains("error") {
                    failures.lock().unwrap().push(format!("{label}: exit 2 without an error message"));
                }
                let _ = std::fs::remove_dir_all(&work);
            });
        }
    });
    (failures.into_inner().unwrap(), succeeded.into_inner())
}

#[test]
fn every_numeric_scene_key_at_its_extremes_exits_0_or_2() {
    let d = dir("keys");
    let keys = numeric_keys();
    assert!(keys.len() > 60, "only {} numeric keys found", keys.len());
    let base = base();
    let mut cases = Vec::new();
    for (path, integer) in &keys {
        let values = if *integer { integer_values() } else { float_values() };
        for v in values {
            let scene = set(&base, path, v.clone());
            let file = d.join(format!("{}-{}.toml", path.join("."), cases.len()));
            std::fs::write(&file, toml::to_string(&scene).expect("scene prints")).unwrap();
            let f = file.to_str().unwrap().to_string();
            let args = if is_picture_key(path) {
                vec!["render".into(), f, "--out".into(), "x.exr".into(), "-q".into(), "--threads".into(), "1".into()]
            } else {
                vec!["bake".into(), f, "--out".into(), "out".into(), "-q".into(), "--threads".into(), "1".into()]
            };
            cases.push((format!("{} = {v}", path.join(".")), args));
        }
    }
    let n = cases.len();
    let failures = run_all(cases, &d);
    assert!(failures.is_empty(), "{} of {n} cases failed:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn every_command_line_number_at_its_extremes_exits_0_or_2() {
    let d = dir("flags");
    let scene = d.join("small.toml");
    std::fs::write(&scene, toml::to_string(&base()).unwrap()).unwrap();
    let s = scene.to_str().unwrap().to_string();
    let values = [
        "0",
        "1",
        "-1",
        "2",
        "1e9",
        "1000000000",
        "9223372036854775807",
        "9223372036854775808",
        "18446744073709551616",
        "nan",
        "inf",
        "",
        "x",
    ];
    let mut cases = Vec::new();
    for v in values {
        for (cmd, flag) in [
            ("bake", "--seed"),
            ("bake", "--threads"),
            ("render", "--seed"),
            ("render", "--spp"),
            ("render", "--shadow-samples"),
            ("render", "--threads"),
        ] {
            let out = if cmd == "bake" { "out" } else { "x.exr" };
            cases.push((
                format!("{cmd} {flag} {v:?}"),
                vec![cmd.into(), s.clone(), flag.into(), v.into(), "--out".into(), out.into(), "-q".into()],
            ));
        }
    }
    let n = cases.len();
    let failures = run_all(cases, &d);
    assert!(failures.is_empty(), "{} of {n} cases failed:\n{}", failures.len(), failures.join("\n"));
}

/// The soak: 200 seeded random scenes, every
/// numeric key drawn from its valid range as `aurora scene --schema` states
/// it (uniform, or log-uniform over a range wider than 100x; open ranges
/// within a decade of the default), the sizes capped (beams, footprint and
/// image resolution, steps) so the soak takes minutes, each baked and
/// rendered under the 8 GiB cap: exit 0 or 2, never a panic or a signal.
#[test]
fn soak_200_random_valid_scenes() {
    use rand::{Rng, SeedableRng};
    let d = dir("soak");
    let out = Command::new(env!("CARGO_BIN_EXE_aurora")).args(["scene", "--schema"]).output().expect("schema");
    assert!(out.status.success());
    let schema: serde_json::Value = serde_json::from_slice(&out.stdout).expect("schema is JSON");
    // Size caps: (table, key, largest value drawn).
    let caps: &[(&str, &str, f64)] = &[
        ("beams", "count", 300.0),
        ("beams", "dt", 1.0),
        ("footprint", "steps", 8.0),
        ("footprint", "pressure_iterations", 20.0),
        ("render", "width", 32.0),
        ("render", "height", 24.0),
        ("render", "spp", 2.0),
        ("curtain", "length", 60.0),
        ("curtain", "width", 30.0),
        ("photons", "radius_km", 2.0),
        ("photons", "cutoff", 3.0),
        ("terrain", "mountain_height", 10.0),
    ];
    let floors: &[(&str, &str, f64)] = &[("beams", "dt", 0.002), ("grid", "voxel_size", 0.25), ("photons", "radius_km", 0.2)];
    let mut r = rand_pcg::Pcg64Mcg::seed_from_u64(20261129);
    let mut cases = Vec::new();
    for i in 0..200 {
        let mut t = toml::Table::new();
        for (table, keys) in schema.as_object().unwrap() {
            if table.is_empty() {
                continue;
            }
            let mut tt = toml::Table::new();
            for (key, k) in keys.as_object().unwrap() {
                let (Some(lo), Some(hi), Some(def)) = (k["min"].as_f64(), k.get("max"), k["default"].as_f64()) else { continue };
                let hi = hi.as_f64().unwrap_or(f64::INFINITY);
                let cap = caps.iter().find(|c| c.0 == table && c.1 == key).map(|c| c.2).unwrap_or(f64::INFINITY);
                let floor = floors.iter().find(|c| c.0 == table && c.1 == key).map(|c| c.2).unwrap_or(f64::NEG_INFINITY);
                let (mut a, mut b) = (lo, hi.min(cap));
                if !b.is_finite() {
                    b = if def > 0.0 { def * 10.0 } else { lo.abs().max(1.0) * 10.0 };
                    a = a.max(if def > 0.0 { def / 10.0 } else { lo });
                }
                a = a.max(floor);
                if !(b >= a) {
                    continue;
                }
                // Mostly near the default (a scene someone would write), sometimes anywhere.
                let x = if def != 0.0 && r.random::<f64>() < 0.7 {
                    (def * 10f64.powf(r.random::<f64>() - 0.5)).clamp(a, b)
                } else if a > 0.0 && b / a > 100.0 {
                    (a.ln() + r.random::<f64>() * (b.ln() - a.ln())).exp()
                } else {
                    a + r.random::<f64>() * (b - a)
                };
                let v = if k["default"].is_i64() || k["default"].is_u64() {
                    toml::Value::Integer(x.round().max(lo.ceil()) as i64)
                } else {
                    toml::Value::Float(x)
                };
                tt.insert(key.clone(), v);
            }
            if table == "curtain" {
                t.insert("curtain".into(), toml::Value::Array(vec![toml::Value::Table(tt)]));
            } else {
                t.insert(table.clone(), toml::Value::Table(tt));
            }
        }
        // Small footprints whatever was drawn.
        if let Some(toml::Value::Table(f)) = t.get_mut("footprint") {
            f.insert(
                "resolution".into(),
                toml::Value::Array(vec![toml::Value::Integer(r.random_range(8..=48)), toml::Value::Integer(r.random_range(8..=24))]),
            );
        }
        // Rules across keys: the bend within the width, delta alpha within alpha_D.
        if let Some(toml::Value::Array(cs)) = t.get_mut("curtain") {
            if let Some(toml::Value::Table(c)) = cs.get_mut(0) {
                let w = c.get("width").and_then(|v| v.as_float()).unwrap_or(40.0);
                let b = c.get("bend_km").and_then(|v| v.as_float()).unwrap_or(0.0);
                c.insert("bend_km".into(), toml::Value::Float(b.min(0.4 * w)));
            }
        }
        if let Some(toml::Value::Table(b)) = t.get_mut("beams") {
            let a = b.get("alpha_d_deg").and_then(|v| v.as_float()).unwrap_or(5.0);
            let da = b.get("delta_alpha_deg").and_then(|v| v.as_float()).unwrap_or(0.0);
            b.insert("delta_alpha_deg".into(), toml::Value::Float(da.min(a)));
        }
        t.insert("seed".into(), toml::Value::Integer(i));
        let file = d.join(format!("soak{i}.toml"));
        std::fs::write(&file, toml::to_string(&t).unwrap()).unwrap();
        let f = file.to_str().unwrap().to_string();
        cases.push((
            format!("soak{i}"),
            vec!["render".into(), f, "--out".into(), "x.png".into(), "-q".into(), "--threads".into(), "1".into()],
        ));
    }
    let (failures, succeeded) = run_all_counting(cases, &d);
    assert!(failures.is_empty(), "{} of 200 scenes failed:\n{}", failures.len(), failures.join("\n"));
    // Most scenes drawn from valid ranges bake and render: a soak that is
    // all refusals exercises nothing.
    // (Measured: 71 of 200 render; the rest are refused with exit 2 for
    // combinations no single range forbids, such as a footprint the fluid
    // empties, a threshold above the footprint's peak, a first step longer
    // than the atmosphere, or a grid beyond the memory budget.)
    assert!(succeeded >= 50, "only {succeeded} of 200 soak scenes rendered");
}
