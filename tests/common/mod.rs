//! Shared helpers of the integration tests (`mod common;`): the `aurora`
//! binary and its stderr (a long-running child's, line by line: `child`), scratch folders under `target/`, test grids, and
//! the external reference tools (pyopenvdb, vdb_print, bpy, usd-core), which
//! must be installed by `tools/setup`: a missing tool is a test failure,
//! never a skip.
#![allow(dead_code)]

use aurora::grid::{Grid, Transform};
use glam::{DVec3, IVec3};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub mod child;
pub mod damaged;
mod openvdb_tool;
pub mod small;
pub mod vdbrs;

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `aurora` binary cargo built for this test run.
pub const AURORA_BIN: &str = env!("CARGO_BIN_EXE_aurora");

/// `aurora ARGS...`, run to completion (stdout and stderr captured).
pub fn aurora(args: &[&str]) -> Output {
    Command::new(AURORA_BIN).args(args).output().expect("run aurora")
}

/// A process's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh empty folder `target/<group>/<name>` (whatever was there is
/// removed first). `group` names the test file's corner of `target/`.
pub fn scratch(group: &str, name: &str) -> PathBuf {
    let d = repo_root().join("target").join(group).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create a test folder under target/");
    d
}

/// The names in folder `d`, sorted (none if it does not exist).
pub fn file_names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .map(|rd| rd.map(|e| e.expect("dir entry").file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

/// A fresh empty folder `target/test-vdb/<name>`.
pub fn temp_dir(name: &str) -> PathBuf {
    scratch("test-vdb", name)
}

/// Debian's Python, which sees pyopenvdb.
pub fn system_python() -> PathBuf {
    let p = PathBuf::from("/usr/bin/python3");
    assert!(p.exists(), "/usr/bin/python3 is missing: run tools/setup");
    p
}

/// The project venv's Python (bpy, usd-core): `$AURORA_PYTHON` or `<repo>/.venv/bin/python`.
pub fn venv_python() -> PathBuf {
    let p = std::env::var_os("AURORA_PYTHON").map(PathBuf::from).unwrap_or_else(|| repo_root().join(".venv/bin/python"));
    assert!(p.exists(), "{} is missing: run tools/setup (or set AURORA_PYTHON)", p.display());
    p
}

/// Runs `python tools/probes/SCRIPT args...` and parses its stdout as JSON; any failure
/// (missing module, non-zero exit, bad JSON) fails the test with the output.
pub fn run_json(python: &Path, script: &str, args: &[&str]) -> Value {
    let out = Command::new(python)
        .arg(repo_root().join("tools/probes").join(script))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}; run tools/setup", python.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{script} failed ({}); run tools/setup if a module is missing\nstdout: {stdout}\nstderr: {stderr}",
        out.status
    );
    // bpy may print its own lines; the JSON is the last line.
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{') || l.starts_with('['))
        .unwrap_or_else(|| panic!("{script} printed no JSON\nstdout: {stdout}\nstderr: {stderr}"));
    serde_json::from_str(line).unwrap_or_else(|e| panic!("{script}: bad JSON ({e}): {line}"))
}

/// `vdb_print -l FILE` must exit 0 *and* print no error (it exits 0 even after ERROR).
pub fn vdb_print_ok(file: &Path) -> String {
    let out =
        Command::new("vdb_print").arg("-l").arg(file).output().unwrap_or_else(|e| panic!("cannot run vdb_print: {e}; run tools/setup"));
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "vdb_print -l {} failed: {text}", file.display());
    assert!(!text.to_lowercase().contains("error"), "vdb_print -l {} reported an error:\n{text}", file.display());
    text
}

/// A density grid with every structural case: negative coordinates, several
/// root children (including negative ones), a fully active leaf, isolated
/// single voxels, a leaf straddling zero, and values of varied magnitude.
pub fn test_density() -> Grid<f32> {
    let mut g = Grid::new("density", 0.0f32, Transform::new(0.125, DVec3::new(-3.0, 1.5, 100.25)));
    // Fully active leaf at (16..24, -8..0, 32..40).
    for n in 0..512 {
        let p = IVec3::new(16, -8, 32) + aurora::grid::offset_to_local(n);
        g.set(p, 0.001 * n as f32 + 1e-7);
    }
    // Single voxels across root children (4096 apart), negative ones included.
    let singles = [
        IVec3::new(-1, -1, -1),
        IVec3::new(-4097, 5, 9),
        IVec3::new(4096, -4096, 0),
        IVec3::new(8191, 8191, -8192),
        IVec3::new(0, 0, 0),
        IVec3::new(-100000, 3, 70000),
        IVec3::new(127, 128, -129),
    ];
    for (i, &p) in singles.iter().enumerate() {
        g.set(p, (i as f32 + 1.0) * 1.7e-3);
    }
    // A small curtain-like sheet with a smooth profile, crossing x = 0.
    for i in -12..12 {
        for j in -3..3 {
            for k in 0..20 {
                let v = (-(k as f32) / 6.0).exp() * (1.0 + 0.1 * (i as f32 * 0.7).sin());
                g.set(IVec3::new(i, j, k + 200), v);
            }
        }
    }
    g
}

/// An emission grid with distinct components and negative coordinates.
pub fn test_emission() -> Grid<[f32; 3]> {
    let mut g = Grid::new("emission", [0.0f32; 3], Transform::new(0.125, DVec3::new(-3.0, 1.5, 100.25)));
    for n in 0..512 {
        let p = IVec3::new(-8, -8, -8) + aurora::grid::offset_to_local(n);
        g.set(p, [0.5 + n as f32, -(n as f32) * 0.01, 1.0 / (n as f32 + 1.0)]);
    }
    for i in -10..10 {
        for k in 0..30 {
            let t = k as f32 / 30.0;
            g.set(IVec3::new(i * 3, 4100, k - 15), [0.1 * t, 0.8 * (1.0 - t), 3e-4 * (i as f32).abs()]);
        }
    }
    g.set(IVec3::new(-5000, 12, 7), [123.0, 0.0, 1e-6]);
    g
}

/// OpenVDB's own writer (`benchmarks/vdb_write/openvdb_write_bench.cpp`), compiled into
/// `target/` on first use and whenever the source is newer.
pub fn openvdb_write_tool() -> PathBuf {
    openvdb_tool::build(&repo_root()).unwrap_or_else(|e| panic!("{e}"))
}

/// Two short curtains with unequal beam weights (so the apportioned counts
/// differ), few beams, coarse voxels: a bake in about a second. The
/// integration tests' one small scene (tests/pipeline.rs, tests/preview_cli.rs,
/// tests/budget.rs).
pub fn small_scene() -> aurora::scene::Scene {
    use aurora::scene::{Curtain, Scene, VoxelSize};
    let mut s = Scene {
        curtains: vec![
            Curtain { length: 40.0, width: 16.0, bend_km: 3.0, ..Curtain::default() },
            Curtain { center: [30.0, 20.0], length: 30.0, width: 14.0, beam_weight: 0.5, seed: 7, ..Curtain::default() },
        ],
        ..Scene::default()
    };
    s.footprint.resolution = [128, 48];
    s.beams.count = 301;
    s.photons.radius_km = 1.0;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s
}
