//! `aurora` under an address-space cap (`ulimit -v`, where an allocation
//! beyond the cap fails and Rust turns it into an abort, a signal): no
//! panic and no signal, on anything. Its own test binary: the children run
//! two at a time, as many as the machines have cores.
//!
//! Every numeric scene key and every command-line number is driven through
//! zero, tiny, huge, negative, NaN and the infinities (and, for integer
//! keys, through the edges of the integer range), the other keys kept
//! small, and 200 random valid scenes are baked and rendered: every run
//! must end with exit 0 or 2 under an 8 GiB cap, never 101 (a panic),
//! never a signal (an abort from a failed allocation, a stack overflow).
//! And a VDB whose leaves would not fit under a 1 GiB cap is refused
//! before they are read.
//!
//! The keys are not listed by hand: they are every numeric leaf of the default
//! scene's TOML (array elements included), so a key added later is covered
//! the day it lands. Bake keys run `aurora bake`; keys of the picture
//! (`camera`, `render`, `volume`, `background`, `terrain`) run `aurora render`,
//! which bakes in memory and renders.
//!
//! A case that legitimately works longer than [`CASE_SECONDS`] is stopped by
//! the harness and passes only if it was still running (no crash) when
//! stopped; the cap makes an allocation beyond 8 GiB fail, so "stayed under
//! the memory cap" is checked too.

use aurora::util::fmath;

mod common;

use aurora::grid::{Grid, Transform};
use common::{aurora, ok, refused, render_foreign_vdb, scratch, write, Aurora};
use glam::{DVec3, IVec3};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

const CASE_SECONDS: u64 = 60;
/// The address-space cap, KiB (`ulimit -v`).
const CAP_KIB: u64 = 8 * 1024 * 1024;

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

/// How a capped run ended: its exit status, or `None` if it was still
/// running (not crashed) when the harness stopped it after
/// [`CASE_SECONDS`]; and its stderr. A panic or a signal fails the test
/// at once (`common::child`).
fn run_capped(args: &[&str], cwd: &Path) -> (Option<i32>, String) {
    let run = Aurora::new().args(args).current_dir(cwd).capped(CAP_KIB).spawn();
    match run.wait_or_kill(Duration::from_secs(CASE_SECONDS)) {
        Some(o) => (o.status.code(), common::stderr(&o)),
        None => (None, String::new()),
    }
}

/// Sets its flag when the thread holding it panics, so the other workers
/// stop taking cases.
struct StopOnPanic<'a>(&'a AtomicBool);

impl Drop for StopOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

fn is_picture_key(path: &[String]) -> bool {
    matches!(path[0].as_str(), "camera" | "render" | "volume" | "background" | "terrain")
}

/// `aurora CMD SCENE ARGS... --out OUT -q`, as owned strings.
fn command_line(cmd: &str, scene: &Path, args: &[&str], out: &str) -> Vec<String> {
    let scene = scene.to_str().expect("a UTF-8 path");
    [cmd, scene].iter().chain(args).chain(&["--out", out, "-q"]).map(|a| a.to_string()).collect()
}

/// Runs `cases` (a label and a command line each) two at a time (the
/// machines have 2 cores), each in a folder of its own under `d`: every
/// one must exit 0 or 2 (an error in words), or still run at the cut.
/// Returns how many succeeded (exit 0).
fn all_exit_0_or_2(cases: Vec<(String, Vec<String>)>, d: &Path) -> usize {
    let n = cases.len();
    let cases = std::sync::Mutex::new(cases.into_iter().enumerate().collect::<Vec<_>>());
    let failures = std::sync::Mutex::new(Vec::new());
    let succeeded = AtomicUsize::new(0);
    let times = std::sync::Mutex::new(Vec::new());
    let stop = AtomicBool::new(false);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                let _stop = StopOnPanic(&stop);
                while !stop.load(Ordering::Relaxed) {
                    let Some((i, (label, args))) = cases.lock().unwrap().pop() else { break };
                    let work = d.join(format!("case{i}"));
                    std::fs::create_dir_all(&work).unwrap();
                    let a: Vec<&str> = args.iter().map(String::as_str).collect();
                    let started = std::time::Instant::now();
                    let (code, err) = run_capped(&a, &work);
                    times.lock().unwrap().push((started.elapsed().as_secs_f64(), label.clone()));
                    if code == Some(0) {
                        succeeded.fetch_add(1, Ordering::Relaxed);
                    }
                    if !matches!(code, Some(0) | Some(2) | None) {
                        let tail: String = err.lines().filter(|l| !l.starts_with("  ")).take(6).collect::<Vec<_>>().join(" | ");
                        failures.lock().unwrap().push(format!("{label}: exit {}: {tail}", code.unwrap_or(-1)));
                    }
                    // An error must say what is wrong, in words.
                    if code == Some(2) && !err.contains("error") {
                        failures.lock().unwrap().push(format!("{label}: exit 2 without an error message"));
                    }
                    let _ = std::fs::remove_dir_all(&work);
                }
            });
        }
    });
    // The slowest cases, for whoever wonders where the minutes go
    // (`cargo test --release --test capped -- --nocapture`).
    let mut times = times.into_inner().unwrap();
    times.sort_by(|a, b| b.0.total_cmp(&a.0));
    let total: f64 = times.iter().map(|t| t.0).sum();
    eprintln!("{n} cases, {total:.0} s of children; slowest:");
    for (t, label) in times.iter().take(8) {
        eprintln!("  {t:6.1} s  {label}");
    }
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{} of {n} cases failed:\n{}", failures.len(), failures.join("\n"));
    succeeded.into_inner()
}

#[test]
fn every_numeric_scene_key_at_its_extremes_exits_0_or_2() {
    let d = scratch("capped", "keys");
    let keys = numeric_keys();
    assert!(keys.len() > 60, "only {} numeric keys found", keys.len());
    let base = base();
    let mut cases = Vec::new();
    for (path, integer) in &keys {
        let values = if *integer { integer_values() } else { float_values() };
        for v in values {
            let scene = set(&base, path, v.clone());
            let file = write(&d, &format!("{}-{}.toml", path.join("."), cases.len()), toml::to_string(&scene).expect("scene prints"));
            let (cmd, out) = if is_picture_key(path) { ("render", "x.exr") } else { ("bake", "out") };
            cases.push((format!("{} = {v}", path.join(".")), command_line(cmd, &file, &["--threads", "1"], out)));
        }
    }
    all_exit_0_or_2(cases, &d);
}

#[test]
fn every_command_line_number_at_its_extremes_exits_0_or_2() {
    let d = scratch("capped", "flags");
    let scene = write(&d, "small.toml", toml::to_string(&base()).unwrap());
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
            cases.push((format!("{cmd} {flag} {v:?}"), command_line(cmd, &scene, &[flag, v], out)));
        }
    }
    all_exit_0_or_2(cases, &d);
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
    let d = scratch("capped", "soak");
    let out = aurora(&["scene", "--schema"]);
    ok(&out);
    let schema: serde_json::Value = serde_json::from_slice(&out.stdout).expect("schema is JSON");
    // The largest value drawn (sizes kept small) and the smallest, per key.
    // No shutter: the motion-blurred march can take minutes on a scene the
    // plain one renders in seconds, and the blur has its own tests. The
    // vortex sheet's size is its markers (period over `sheet_spacing_km`)
    // times its steps, each step O(markers x window): drawn freely it made
    // four scenes of 200 run past the cut (measured: 861 steps at 0.024 km
    // spacing, 8133 steps, a 572 km roll-up).
    let caps: toml::Table = "beams = { count = 300, dt = 1.0 }
        footprint = { steps = 8, pressure_iterations = 20, sheet_steps = 200, sheet_rollup_km = 30.0 }
        render = { width = 32, height = 24, spp = 2, shutter_s = 0.0 }
        curtain = { length = 60.0, width = 30.0 }
        photons = { radius_km = 2.0, cutoff = 3.0 }
        terrain = { mountain_height = 10.0 }"
        .parse()
        .unwrap();
    let floors: toml::Table =
        "beams.dt = 0.002\ngrid.voxel_size = 0.25\nphotons.radius_km = 0.2\nfootprint.sheet_spacing_km = 0.05".parse().unwrap();
    let bound = |t: &toml::Table, table: &str, key: &str| {
        let v = t.get(table)?.get(key)?;
        v.as_float().or(v.as_integer().map(|i| i as f64))
    };
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
                let cap = bound(&caps, table, key).unwrap_or(f64::INFINITY);
                let floor = bound(&floors, table, key).unwrap_or(f64::NEG_INFINITY);
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
                    (def * fmath::powf(10f64, r.random::<f64>() - 0.5)).clamp(a, b)
                } else if a > 0.0 && b / a > 100.0 {
                    fmath::exp(fmath::ln(a) + r.random::<f64>() * (fmath::ln(b) - fmath::ln(a)))
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
            // A table whose required keys have no default (`[site]`): their
            // examples, and the table in half the scenes.
            let required: Vec<(&String, &serde_json::Value)> =
                keys.as_object().unwrap().iter().filter(|(_, k)| k["default"].is_null() && k.get("default_in_table").is_some()).collect();
            if !required.is_empty() {
                if r.random::<f64>() < 0.5 {
                    continue;
                }
                for (key, k) in required {
                    let v = &k["default_in_table"];
                    tt.insert(
                        key.clone(),
                        v.as_str().map(|s| toml::Value::String(s.into())).unwrap_or_else(|| toml::Value::Float(v.as_f64().unwrap())),
                    );
                }
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
        // `[oval]` places the arcs over a `[site]`: without one it is
        // refused (exit 2), so it comes only with a site.
        if !t.contains_key("site") {
            t.remove("oval");
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
        // A shutter blurs along the velocity grid, which the bake then writes.
        let shutter = t.get("render").and_then(|r| r.get("shutter_s")).and_then(|v| v.as_float()).unwrap_or(0.0);
        if shutter > 0.0 {
            if let Some(toml::Value::Table(g)) = t.get_mut("grid") {
                g.insert("velocity".into(), toml::Value::Boolean(true));
            }
        }
        t.insert("seed".into(), toml::Value::Integer(i));
        let file = write(&d, &format!("soak{i}.toml"), toml::to_string(&t).unwrap());
        cases.push((format!("soak{i}"), command_line("render", &file, &["--threads", "1"], "x.png")));
    }
    let succeeded = all_exit_0_or_2(cases, &d);
    // Most scenes drawn from valid ranges bake and render: a soak that is
    // all refusals exercises nothing.
    // (Measured: 71 of 200 render; the rest are refused with exit 2 for
    // combinations no single range forbids, such as a footprint the fluid
    // empties, a threshold above the footprint's peak, a first step longer
    // than the atmosphere, or a grid beyond the memory budget.)
    assert!(succeeded >= 50, "only {succeeded} of 200 soak scenes rendered");
}

#[test]
fn a_vdb_whose_leaves_would_not_fit_in_memory_is_refused_before_they_are_read() {
    // 150,000 leaves of one voxel each: a small file, but the renderer's
    // medium holds every leaf as a dense block (512 voxels x 3 channels x 4
    // bytes = 6 KiB): about 0.92 GB. Under a 1 GiB address-space cap the
    // allocation would fail, which Rust turns into an abort; the medium's
    // size is checked first against 3/4 of the limit
    // (render::medium::build::MEDIUM_MEMORY_FRACTION; crate::util::memory::available
    // reads RLIMIT_AS): exit 2 naming the leaves and the limit, no image.
    let d = scratch("capped", "too-many-leaves");
    let tr = Transform::new(1.0, DVec3::ZERO);
    let mut e: Grid<[f32; 3]> = Grid::new("emission", [0.0; 3], tr);
    for i in 0..400 {
        for j in 0..375 {
            e.set(IVec3::new(8 * i, 8 * j, 100), [1.0, 1.0, 1.0]);
        }
    }
    assert_eq!(e.leaf_count(), 150_000);
    let (render, img) = render_foreign_vdb(&d, &e, "");
    let m = refused(&render.capped(1024 * 1024).output());
    assert!(m.contains("150000 leaves") && m.contains("RLIMIT_AS"), "{m}");
    assert!(!img.exists());
}
