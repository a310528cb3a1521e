//! `aurora._aurora`: the native part of the Python module `aurora`
//! (python/aurora/__init__.py wraps it in NumPy arrays). Thin: every
//! decision is the library's; this file converts arguments, runs the work
//! off the interpreter's lock and turns errors into exceptions.
//!
//! Long work ([`run`]) runs on a thread of its own while the calling thread
//! waits without the interpreter's lock and, every [`POLL`], takes it to
//! check for signals (`Python::check_signals`: Ctrl-C in a terminal or a
//! notebook's interrupt) and to hand the latest progress to the caller's
//! callback. An interrupt, or an exception raised by the callback, asks
//! the work to stop (`Progress::cancelled`): the bake stops at its next
//! chunk of beams, writes nothing, and the exception is raised; a bake
//! folder's previous files are kept, as the command line keeps them on
//! SIGINT (its files are replaced only as a whole, after a bake ends).
//!
//! Errors: the user's input (`is_input()`, the command line's exit status
//! 2) is `aurora.InputError` (a `ValueError`) with the command line's
//! message, naming the key, value and range; anything else is a
//! `RuntimeError`.

use aurora::app::render_image::{ImageRequest, RenderImageError};
use aurora::app::scene_input::SceneInputError;
use aurora::scene::{Override, Scene};
use aurora::util::progress::Progress;
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

pyo3::create_exception!(
    aurora,
    InputError,
    PyValueError,
    "The input is at fault: a scene key, value or file (the command line's exit status 2)."
);

/// How often the waiting thread checks for signals and reports progress.
const POLL: Duration = Duration::from_millis(50);

/// An error of the library as a Python exception: [`InputError`] when the
/// input is at fault, else `RuntimeError`.
fn py_err(message: String, input: bool) -> PyErr {
    if input {
        InputError::new_err(message)
    } else {
        PyRuntimeError::new_err(message)
    }
}

/// The progress of work on another thread, read by the waiting one.
#[derive(Default)]
struct Shared {
    stage: Mutex<String>,
    done: AtomicU64,
    total: AtomicU64,
    /// Bumped by every call, so the waiting thread reports only news.
    version: AtomicU64,
    cancel: AtomicBool,
}

impl Progress for Shared {
    fn start(&self, stage: &str, total: u64) {
        *self.stage.lock().expect("progress lock") = stage.to_string();
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
        self.version.fetch_add(1, Ordering::Relaxed);
    }
    fn inc(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
        self.version.fetch_add(1, Ordering::Relaxed);
    }
    fn finish(&self) {
        let total = self.total.load(Ordering::Relaxed);
        self.done.store(total, Ordering::Relaxed);
        self.version.fetch_add(1, Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// Runs `work` on a thread of its own (module doc), `callback(stage, done,
/// total)` told of its progress; an interrupt or the callback's exception
/// cancels it and is raised once it has stopped.
fn run<T: Send>(py: Python<'_>, callback: Option<&Bound<'_, PyAny>>, work: impl FnOnce(&Shared) -> T + Send) -> PyResult<T> {
    let shared = Shared::default();
    let slot: (Mutex<Option<T>>, Condvar) = (Mutex::new(None), Condvar::new());
    let mut raised: Option<PyErr> = None;
    let out = std::thread::scope(|s| {
        let (shared, slot) = (&shared, &slot);
        let worker = s.spawn(move || {
            let v = work(shared);
            *slot.0.lock().expect("result lock") = Some(v);
            slot.1.notify_all();
        });
        let mut seen = 0u64;
        loop {
            let got = py.detach(|| {
                let guard = slot.0.lock().unwrap_or_else(|e| e.into_inner());
                let (mut guard, _) = slot.1.wait_timeout_while(guard, POLL, |v| v.is_none()).unwrap_or_else(|e| e.into_inner());
                guard.take()
            });
            if let Some(v) = got {
                return Some(v);
            }
            if worker.is_finished() {
                break;
            }
            if raised.is_some() {
                continue;
            }
            if let Err(e) = py.check_signals() {
                shared.cancel.store(true, Ordering::Relaxed);
                raised = Some(e);
                continue;
            }
            let version = shared.version.load(Ordering::Relaxed);
            if let (Some(cb), true) = (callback, version != seen) {
                seen = version;
                let stage = shared.stage.lock().expect("progress lock").clone();
                let (done, total) = (shared.done.load(Ordering::Relaxed), shared.total.load(Ordering::Relaxed));
                let done = if total > 0 { done.min(total) } else { done };
                if let Err(e) = cb.call1((stage, done, total)) {
                    shared.cancel.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
        }
        // The worker has ended: with its result (stored after the last
        // wait), or having panicked (joined here, so the panic becomes the
        // RuntimeError below rather than the scope's).
        let _ = worker.join();
        let v = slot.0.lock().unwrap_or_else(|e| e.into_inner()).take();
        v
    });
    match (raised, out) {
        (Some(e), _) => Err(e),
        (None, Some(v)) => Ok(v),
        (None, None) => Err(PyRuntimeError::new_err("the work's thread ended without a result (a panic: see stderr)")),
    }
}

/// A stopped bake: the interrupt (or the callback's exception) is raised
/// by [`run`]; this is its message if the work stopped on its own.
fn cancelled() -> PyErr {
    PyKeyboardInterrupt::new_err("cancelled before finishing")
}

/// A Python value as TOML, for an override: bool, int, float, str, and
/// lists and dicts of them.
fn to_toml(v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        return Ok(toml::Value::Array(v.try_iter()?.map(|x| to_toml(&x?)).collect::<PyResult<_>>()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            t.insert(k.extract::<String>()?, to_toml(&x)?);
        }
        return Ok(toml::Value::Table(t));
    }
    // NumPy scalars and the like: as their float.
    if let Ok(x) = v.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    Err(PyValueError::new_err(format!("{}: a scene value is a bool, int, float, str, or a list or dict of them", v.repr()?)))
}

fn scene_error(e: SceneInputError) -> PyErr {
    py_err(e.to_string(), e.is_input())
}

/// A scene: a preset or a scene file, with overrides applied in order
/// (`Scene.set`), validated as the command line validates it.
#[pyclass(module = "aurora._aurora", name = "Scene")]
#[derive(Clone)]
struct PyScene {
    /// The preset name or file path.
    #[pyo3(get)]
    source: String,
    overrides: Vec<Override>,
    scene: Scene,
    /// What taking the scene warned of.
    #[pyo3(get)]
    warnings: Vec<String>,
}

#[pymethods]
impl PyScene {
    /// The scene `source` names: a preset (`aurora scene --list`) or a TOML file.
    #[new]
    fn new(source: &str) -> PyResult<PyScene> {
        let input = aurora::app::scene_input::load(source, &[]).map_err(scene_error)?;
        Ok(PyScene { source: source.to_string(), overrides: Vec::new(), scene: input.scene, warnings: input.warnings })
    }

    /// Sets a key as `--set KEY=VALUE` does (`curtain[0].energy_flux`,
    /// `render.width`): the later override wins, and the whole scene is
    /// validated again; a bad key or value raises `InputError` naming the
    /// key, value and allowed range, and leaves the scene as it was.
    fn set(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = to_toml(value)?;
        let o = Override::parse(&format!("{key}={v}"), "Scene.set").map_err(|e| py_err(e.to_string(), e.is_input()))?;
        let mut overrides = self.overrides.clone();
        overrides.push(o);
        let input = aurora::app::scene_input::load(&self.source, &overrides).map_err(scene_error)?;
        self.overrides = overrides;
        self.scene = input.scene;
        self.warnings = input.warnings;
        Ok(())
    }

    /// The scene as TOML with every default filled in (`aurora scene`).
    fn to_toml(&self) -> String {
        self.scene.to_toml()
    }

    /// The overrides applied, as `KEY=VALUE` (as a bake records them).
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.overrides.iter().map(Override::record).collect()
    }

    /// The scene's `[site]` latitude and longitude, degrees, or None.
    #[getter]
    fn site(&self) -> Option<(f64, f64)> {
        self.scene.site.as_ref().map(|s| (s.latitude_deg, s.longitude_deg))
    }

    /// The image size, (width, height) pixels.
    #[getter]
    fn size(&self) -> (usize, usize) {
        (self.scene.render.width, self.scene.render.height)
    }

    /// Each frame's time, s (`animation.time_s + (N - 1) / fps`).
    fn frame_time(&self, frame: i64) -> f64 {
        aurora::pipeline::motion::frame_time(&self.scene.animation, frame)
    }

    fn __repr__(&self) -> String {
        format!("Scene({:?}, overrides={:?})", self.source, self.overrides())
    }
}

/// `aurora profile`'s tables: (header, units, rows as little-endian f64
/// bytes, row count, the columns CSV's header, its rows' bytes, the
/// footprint areas in km^2, the electron power accounting in W).
#[pyfunction]
#[pyo3(signature = (scene, progress=None))]
fn profile<'py>(py: Python<'py>, scene: &PyScene, progress: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use aurora::pipeline::altitude_profile as ap;
    let s = scene.scene.clone();
    let p = run(py, progress, move |pr| ap::profile(&s, pr))?.map_err(|e| {
        if matches!(e, aurora::pipeline::beams::BeamError::Cancelled) {
            cancelled()
        } else {
            py_err(e.to_string(), e.is_input())
        }
    })?;
    let header: Vec<&str> = ap::HEADER.split(',').collect();
    let units: Vec<&str> = header.iter().map(|c| ap::unit(c)).collect();
    let rows = ap::rows(&p);
    let flat: Vec<u8> = rows.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let cols = ap::columns(&p);
    let col_header: Vec<&str> = ap::COLUMNS_HEADER.split(',').collect();
    let col_rows: Vec<u8> = cols
        .iter()
        .enumerate()
        .flat_map(|(i, c)| {
            let mut r = vec![i as f64, c.area_km2, c.energy_flux_erg_cm2_s];
            r.extend(c.rayleigh.iter().chain(c.rayleigh_per_erg.iter()));
            r
        })
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let d = PyDict::new(py);
    d.set_item("header", header)?;
    d.set_item("units", units)?;
    d.set_item("rows", PyBytes::new(py, &flat))?;
    d.set_item("row_count", rows.len())?;
    d.set_item("columns_header", col_header)?;
    d.set_item("columns_rows", PyBytes::new(py, &col_rows))?;
    d.set_item("area_km2", p.curtains.iter().map(|c| c.area_km2).collect::<Vec<_>>())?;
    let w = &p.beam_stats.power;
    d.set_item(
        "power_w",
        [
            ("electron", w.electron_power_w),
            ("deposited", w.deposited_power_w),
            ("backscattered", w.backscattered_power_w),
            ("above_top", w.above_top_power_w),
            ("undeposited", w.undeposited_power_w),
        ]
        .into_py_dict(py)?,
    )?;
    Ok(d)
}

/// A list of pairs as a dict.
trait IntoDict {
    fn into_py_dict<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>>;
}

impl<const N: usize> IntoDict for [(&str, f64); N] {
    fn into_py_dict<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in self {
            d.set_item(k, v)?;
        }
        Ok(d)
    }
}

/// The Python side of a sequence's report: progress to the waiting
/// thread, warnings kept.
struct SequenceSay<'a> {
    shared: &'a Shared,
    warnings: Mutex<Vec<String>>,
}

impl aurora::app::bake_sequence::SequenceReport for SequenceSay<'_> {
    fn progress(&self) -> &dyn Progress {
        self.shared
    }
    fn say(&self, _line: &dyn Fn() -> String) {}
    fn warnings(&self, warnings: &[String]) {
        self.warnings.lock().expect("warnings lock").extend_from_slice(warnings);
    }
    fn frames(&self, _done: usize, _total: usize) {}
}

fn is_cancelled(e: &aurora::pipeline::bake::BakeError) -> bool {
    matches!(e, aurora::pipeline::bake::BakeError::Beams(aurora::pipeline::beams::BeamError::Cancelled))
}

/// `aurora bake SCENE --out DIR`: aurora.vdb, aurora.usda and bake.json in
/// `out`, replaced as a unit only when the bake has finished; with
/// `frames`, `aurora bake --frames` (a sequence folder, frames already
/// complete kept). Returns the summary and the warnings.
#[pyfunction]
#[pyo3(signature = (scene, out, frames=None, progress=None))]
fn bake(
    py: Python<'_>,
    scene: &PyScene,
    out: PathBuf,
    frames: Option<Vec<i64>>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<(String, Vec<String>)> {
    let s = scene.scene.clone();
    let out2 = out.clone();
    // (message, input, cancelled)
    type Failed = (String, bool, bool);
    let r = run(py, progress, move |pr| -> Result<(String, Vec<String>), Failed> {
        let err = |m: String, input: bool| (m, input, false);
        if let Some(frames) = frames {
            let say = SequenceSay { shared: pr, warnings: Mutex::new(Vec::new()) };
            let n = aurora::app::bake_sequence::bake_frames(&s, &out2, &frames, &frames, false, &say).map_err(|e| match e {
                aurora::app::bake_sequence::SequenceBakeError::Bake(b) if is_cancelled(&b) => (String::new(), false, true),
                e => err(e.to_string(), e.is_input()),
            })?;
            let summary = format!("{} frames baked, {} already complete, into {}", n.baked, n.skipped, out2.display());
            return Ok((summary, say.warnings.into_inner().expect("warnings lock")));
        }
        let _lock = aurora::io::bake_folder::prepare(&out2, || {}).map_err(|e| err(e.to_string(), e.is_input()))?;
        let b = match aurora::pipeline::bake::bake(&s, pr) {
            Ok(b) => b,
            Err(e) if is_cancelled(&e) => return Err((String::new(), false, true)),
            Err(e) => return Err(err(e.to_string(), e.is_input())),
        };
        let report = aurora::io::bake_folder::write_outputs_locked(&s, &b, &out2).map_err(|e| err(e.to_string(), e.is_input()))?;
        Ok((report.summary(), b.stats.warnings.clone()))
    })?;
    r.map_err(|(m, input, stopped)| if stopped { cancelled() } else { py_err(m, input) })
}

/// A render's answer: RGBA f32 bytes, width, height, a grey image's
/// units and air (or None), the bake's warnings.
type RenderOut<'py> = (Bound<'py, PyBytes>, usize, usize, Option<(String, String)>, Vec<String>);

/// One image (`aurora render`): the scene baked in memory or the VDB
/// `vdb` (with `frame`, the sequence folder's frame), or with `grid` one
/// float grid alone; returns (RGBA f32 bytes, width, height, the grey
/// image's units or None, the bake's warnings).
#[pyfunction]
#[pyo3(signature = (scene, vdb=None, grid=None, frame=None, progress=None))]
fn render<'py>(
    py: Python<'py>,
    scene: &PyScene,
    vdb: Option<PathBuf>,
    grid: Option<String>,
    frame: Option<i64>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<RenderOut<'py>> {
    let s = scene.scene.clone();
    let dir = aurora::app::scene_input::scene_dir(&scene.source);
    let vdb = match (vdb, frame) {
        (Some(seq), Some(f)) => Some(aurora::farm::frame_files::frame_paths(&seq, f).0),
        (v, _) => v,
    };
    let g = grid.clone();
    let r = run(py, progress, move |pr| {
        let req = ImageRequest { scene: &s, dir, vdb: vdb.as_deref(), frame, grid: g.as_deref(), adaptive: false };
        aurora::app::render_image::render(&req, pr)
    })?;
    let r = r.map_err(|e| match e {
        RenderImageError::Bake(b) if is_cancelled(&b) => cancelled(),
        e => py_err(e.to_string(), e.is_input()),
    })?;
    let img = &r.image;
    let bytes: Vec<u8> = img.pixels.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let meta = grid.map(|g| {
        let m = aurora::app::render_image::grey_metadata(&scene.scene, &g);
        (m.units, m.air)
    });
    Ok((PyBytes::new(py, &bytes), img.width, img.height, meta, r.warnings))
}

/// `aurora keogram`: the grid `grid` of the sequence folder `seq`'s
/// `frames` along the magnetic meridian; returns a dict of the values
/// (f32 bytes, rows x frames), the rows' scan angle, elevation and
/// azimuth, the frames, their times and the units.
#[pyfunction]
#[pyo3(signature = (scene, seq, frames, grid="line_5577".to_string(), progress=None))]
fn keogram<'py>(
    py: Python<'py>,
    scene: &PyScene,
    seq: PathBuf,
    frames: Vec<i64>,
    grid: String,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = scene.scene.clone();
    let g = grid.clone();
    let k = run(py, progress, move |pr| aurora::app::keogram::keogram(&s, &seq, &frames, &g, pr))?
        .map_err(|e| py_err(e.to_string(), e.is_input()))?;
    let meta = aurora::app::render_image::grey_metadata(&scene.scene, &grid);
    let d = PyDict::new(py);
    let values: Vec<u8> = k.values.iter().flat_map(|x| x.to_le_bytes()).collect();
    d.set_item("values", PyBytes::new(py, &values))?;
    d.set_item("scan_deg", k.rows.iter().map(|r| r.scan_deg).collect::<Vec<_>>())?;
    d.set_item("elevation_deg", k.rows.iter().map(|r| r.elevation_deg).collect::<Vec<_>>())?;
    d.set_item("azimuth_deg", k.rows.iter().map(|r| r.azimuth_deg).collect::<Vec<_>>())?;
    d.set_item("frames", k.frames.clone())?;
    d.set_item("times_s", k.times_s.clone())?;
    d.set_item("units", meta.units)?;
    d.set_item("air", meta.air)?;
    d.set_item("grid", k.grid.clone())?;
    Ok(d)
}

/// The keogram's rows' directions for the scene's camera (scan angle,
/// elevation, azimuth, and the unit direction in the scene frame).
#[pyfunction]
fn meridian(scene: &PyScene) -> Vec<(f64, f64, f64, [f64; 3])> {
    aurora::app::keogram::meridian(&scene.scene).iter().map(|r| (r.scan_deg, r.elevation_deg, r.azimuth_deg, r.dir.to_array())).collect()
}

/// The skymap of the scene's camera at `altitude_km` (its `[site]`'s
/// latitude and longitude as the origin, or `origin`): a dict of f64 bytes
/// (height x width) for azimuth, elevation, latitude and longitude.
#[pyfunction]
#[pyo3(signature = (scene, altitude_km, origin=None))]
fn skymap<'py>(py: Python<'py>, scene: &PyScene, altitude_km: f64, origin: Option<(f64, f64)>) -> PyResult<Bound<'py, PyDict>> {
    let s = &scene.scene;
    let origin = match (origin, &s.site) {
        (Some(o), _) => [o.0, o.1],
        (None, Some(site)) => [site.latitude_deg, site.longitude_deg],
        (None, None) => {
            return Err(InputError::new_err(
                "the scene has no [site]: give the origin's latitude and longitude (origin=(lat, lon)) or a [site] (site.latitude_deg, site.longitude_deg)",
            ))
        }
    };
    let cam = aurora::geometry::camera::CameraModel::new(&s.camera, s.render.width, s.render.height)
        .map_err(|e| py_err(e.to_string(), e.is_input()))?;
    let m = aurora::geometry::imager_skymap::skymap(&cam, s.earth.radius_km, origin, altitude_km)
        .map_err(|e| InputError::new_err(e.to_string()))?;
    let bytes = |v: &[f64]| PyBytes::new(py, &v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
    let d = PyDict::new(py);
    d.set_item("az", bytes(&m.azimuth_deg))?;
    d.set_item("el", bytes(&m.elevation_deg))?;
    d.set_item("lat", bytes(&m.latitude_deg))?;
    d.set_item("lon", bytes(&m.longitude_deg))?;
    d.set_item("alt", m.altitude_km)?;
    d.set_item("width", m.width)?;
    d.set_item("height", m.height)?;
    d.set_item("origin", (origin[0], origin[1]))?;
    Ok(d)
}

/// The frame numbers of a range in Open Job Description syntax
/// (`1-10`, `1,3,7-20:2`), as `--frames` reads it.
#[pyfunction]
fn frame_range(spec: &str) -> PyResult<Vec<i64>> {
    aurora::farm::frame_range::parse_range(spec).map_err(|e| py_err(e.to_string(), e.is_input()))
}

/// A sequence folder's frame `frame`: its VDB's path.
#[pyfunction]
fn frame_vdb(seq: PathBuf, frame: i64) -> PathBuf {
    aurora::farm::frame_files::frame_paths(Path::new(&seq), frame).0
}

/// The presets' names and what each shows.
#[pyfunction]
fn presets() -> String {
    aurora::scene::presets::list()
}

#[pymodule]
fn _aurora(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add_class::<PyScene>()?;
    m.add_function(wrap_pyfunction!(profile, m)?)?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(keogram, m)?)?;
    m.add_function(wrap_pyfunction!(meridian, m)?)?;
    m.add_function(wrap_pyfunction!(skymap, m)?)?;
    m.add_function(wrap_pyfunction!(frame_range, m)?)?;
    m.add_function(wrap_pyfunction!(frame_vdb, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    Ok(())
}
