//! What the integration test binaries share (`#[path = "../common/mod.rs"]
//! mod common;`): the `aurora` binary as a child process (`child`), the
//! small scenes they bake (`small`), scratch folders, test grids and the
//! files of every compression mode, damaged files (`damaged`), the vdb-rs
//! oracle (`vdbrs`), the renderer's independent oracles (`oracle`), the
//! committed files generated from the code, and the external reference
//! tools (pyopenvdb, vdb_print, bpy, usd-core, OpenVDB's own writer), which
//! must be installed by `tools/setup`: a missing tool is a test failure,
//! never a skip.
#![allow(dead_code, unused_imports)]

use aurora::grid::{Grid, Transform, VoxelValue};
use aurora::io::vdb::codec::round_half_value;
use aurora::io::vdb::write::{write_vdb, GridRef, MetaValue, WriteOptions};
use aurora::scene::Compression;
use aurora::util::fmath;
use glam::{DVec3, IVec3};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

pub mod child;
pub mod damaged;
mod openvdb_tool;
pub mod oracle;
pub mod small;
pub mod vdbrs;

pub use child::{aurora, ok, refused, stderr, Aurora};

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh empty folder `<group>/<name>` under cargo's scratch folder for
/// integration tests (`target/tmp`; whatever was there is removed first).
/// `group` names the test module; tests running at the same time never
/// share a folder.
pub fn scratch(group: &str, name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(group).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create a test folder under target/tmp");
    d
}

/// A path `<group>/<name>/<name>` in a fresh folder of its own (a test's
/// files never share a folder with another test's, which runs at the same
/// time).
pub fn scratch_file(group: &str, name: &str) -> PathBuf {
    scratch(group, name).join(name)
}

/// Writes `contents` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap_or_else(|e| panic!("write {}: {e}", p.display()));
    p
}

/// `f` run on a thread pool of its own with `threads` threads.
pub fn with_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool").install(f)
}

/// Makes a FIFO at `p`.
pub fn mkfifo(p: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).unwrap();
    // SAFETY: a NUL-terminated path; the result is checked.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0, "mkfifo {}: {}", p.display(), std::io::Error::last_os_error());
}

/// The names in folder `d`, sorted (none if it does not exist).
pub fn file_names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .map(|rd| rd.map(|e| e.expect("dir entry").file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    v.sort();
    v
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

/// Runs `python ARGS...` and returns its stdout; any failure (missing
/// module, non-zero exit) fails the test with its output.
pub fn python(python: &Path, args: &[&str]) -> String {
    let out = Command::new(python).args(args).output().unwrap_or_else(|e| panic!("cannot run {}: {e}; run tools/setup", python.display()));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{} {} failed ({}); run tools/setup if a module is missing\nstdout: {stdout}\nstderr: {}",
        python.display(),
        args.first().unwrap_or(&""),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// Runs `python tools/probes/SCRIPT ARGS...` and parses its stdout as JSON; any
/// failure (missing module, non-zero exit, bad JSON) fails the test with
/// the output.
pub fn run_json(py: &Path, script: &str, args: &[&str]) -> Value {
    let path = repo_root().join("tools/probes").join(script);
    let mut all = vec![path.to_str().expect("a UTF-8 path")];
    all.extend_from_slice(args);
    let stdout = python(py, &all);
    // bpy may print its own lines; the JSON is the last line.
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{') || l.starts_with('['))
        .unwrap_or_else(|| panic!("{script} printed no JSON\nstdout: {stdout}"));
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

/// OpenVDB's own writer (`benchmarks/vdb_write/openvdb_write_bench.cpp`), compiled into
/// `target/` on first use and whenever the source is newer.
pub fn openvdb_write_tool() -> PathBuf {
    openvdb_tool::build(&repo_root()).unwrap_or_else(|e| panic!("{e}"))
}

/// The mode names of OpenVDB's writer tool (`--help` of
/// `benchmarks/vdb_write/openvdb_write_bench.cpp`).
pub use openvdb_tool::mode_name;

/// The committed file `rel` (from the repository root) must hold `now`;
/// else the test fails naming the first line that differs and
/// `regenerate`, the command that rewrites it.
pub fn check_committed(rel: &str, now: &str, regenerate: &str) {
    let committed = std::fs::read_to_string(repo_root().join(rel)).unwrap_or_default();
    if committed != now {
        let line =
            committed.lines().zip(now.lines()).position(|(a, b)| a != b).unwrap_or(committed.lines().count().min(now.lines().count()));
        panic!("{rel} is stale (first difference at line {}): regenerate it with\n    {regenerate}", line + 1);
    }
}

/// [`check_committed`] for a file the tests themselves generate: with
/// `AURORA_UPDATE_DOCS` set, the test writes `now` to it instead.
pub fn update_or_check_committed(rel: &str, now: &str, regenerate: &str) {
    if std::env::var_os("AURORA_UPDATE_DOCS").is_some() {
        std::fs::write(repo_root().join(rel), now).unwrap_or_else(|e| panic!("write {rel}: {e}"));
        return;
    }
    check_committed(rel, now, regenerate);
}

/// The writer's compression modes: every value the scene's
/// `grid.compression` accepts, in the schema's order
/// (`aurora::scene::schema`).
pub fn modes() -> Vec<Compression> {
    let schema = aurora::scene::schema::schema();
    let values = schema["grid"]["compression"]["values"].as_array().expect("grid.compression's values in the schema");
    values.iter().map(|v| serde_json::from_value(v.clone()).unwrap_or_else(|e| panic!("compression {v}: {e}"))).collect()
}

/// The writer's options in every mode, full and half floats (`density` and
/// `emission` stored as half in the latter), each with `metadata`: (mode,
/// half, options).
pub fn every_mode(metadata: &[(String, MetaValue)]) -> Vec<(Compression, bool, WriteOptions)> {
    modes()
        .into_iter()
        .flat_map(|compression| {
            [false, true].map(|half| {
                let opts = WriteOptions {
                    compression,
                    half: if half { vec!["density".into(), "emission".into()] } else { vec![] },
                    metadata: metadata.to_vec(),
                    ..Default::default()
                };
                (compression, half, opts)
            })
        })
        .collect()
}

/// `e` written as a foreign VDB, `dir/foreign.vdb`, and `aurora render` of
/// it (not yet run) in an 8 x 8 view from 50 km south of (0, 0, 100), the
/// scene's tables followed by `extra`, to `dir/out.exr` (removed first):
/// the command and the image's path.
pub fn render_foreign_vdb(dir: &Path, e: &Grid<[f32; 3]>, extra: &str) -> (Aurora, PathBuf) {
    let vdb = dir.join("foreign.vdb");
    write_vdb(&vdb, &[GridRef::Vec3(e)], &WriteOptions::default()).unwrap();
    let scene = write(
        dir,
        "s.toml",
        format!("[camera]\nposition = [0, -50, 100]\nlook_at = [0, 0, 100]\n[render]\nwidth = 8\nheight = 8\nspp = 1\n{extra}"),
    );
    let img = dir.join("out.exr");
    let _ = std::fs::remove_file(&img);
    (Aurora::new().arg("render").arg(&scene).arg("--vdb").arg(&vdb).arg("--out").arg(&img).arg("-q"), img)
}

/// The grid with every value rounded to half precision (what half storage
/// keeps).
pub fn rounded<T: VoxelValue>(g: &Grid<T>) -> Grid<T> {
    let mut r = Grid::new(g.name.clone(), g.background, g.transform);
    for leaf in g.leaves() {
        let mut l = leaf.clone();
        for v in l.values.iter_mut() {
            *v = round_half_value(*v);
        }
        r.insert_leaf(l);
    }
    r
}

/// The writer tests' grids: [`test_density`] and [`test_emission`].
pub fn test_grids() -> (Grid<f32>, Grid<[f32; 3]>) {
    (test_density(), test_emission())
}

/// A density grid with every structural case: negative coordinates, several
/// root children (including negative ones), a fully active leaf, isolated
/// single voxels, a leaf straddling zero, and values of varied magnitude.
fn test_density() -> Grid<f32> {
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
                let v = fmath::exp(-(k as f32) / 6.0) * (1.0 + 0.1 * fmath::sin(i as f32 * 0.7));
                g.set(IVec3::new(i, j, k + 200), v);
            }
        }
    }
    g
}

/// An emission grid with distinct components and negative coordinates.
fn test_emission() -> Grid<[f32; 3]> {
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
