//! No panic, on anything (issue: hardening, part 1): every numeric scene key
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
    let cases = std::sync::Mutex::new(cases.into_iter().enumerate().collect::<Vec<_>>());
    let failures = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let Some((i, (label, args))) = cases.lock().unwrap().pop() else { break };
                let work = d.join(format!("case{i}"));
                std::fs::create_dir_all(&work).unwrap();
                let a: Vec<&str> = args.iter().map(String::as_str).collect();
                let (outcome, err) = run_capped(&a, &work);
                let ok = matches!(outcome, Outcome::Exit(0) | Outcome::Exit(2) | Outcome::Cut);
                if !ok {
                    let tail: String = err.lines().filter(|l| !l.starts_with("  ")).take(6).collect::<Vec<_>>().join(" | ");
                    failures.lock().unwrap().push(format!("{label}: {outcome:?}: {tail}"));
                }
                // An error must say what is wrong, in words.
                if matches!(outcome, Outcome::Exit(2)) && !err.contains("error") {
                    failures.lock().unwrap().push(format!("{label}: exit 2 without an error message"));
                }
                let _ = std::fs::remove_dir_all(&work);
            });
        }
    });
    failures.into_inner().unwrap()
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
    let values = ["0", "1", "-1", "2", "1e9", "1000000000", "9223372036854775807", "9223372036854775808", "18446744073709551616", "nan", "inf", "", "x"];
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
            cases.push((format!("{cmd} {flag} {v:?}"), vec![cmd.into(), s.clone(), flag.into(), v.into(), "--out".into(), out.into(), "-q".into()]));
        }
    }
    let n = cases.len();
    let failures = run_all(cases, &d);
    assert!(failures.is_empty(), "{} of {n} cases failed:\n{}", failures.len(), failures.join("\n"));
}
