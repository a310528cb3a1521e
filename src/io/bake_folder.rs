//! What `aurora bake` leaves on disk: `aurora.vdb` (both grids), `aurora.usda`
//! (a UsdVol stage pointing at it) and `bake.json` (counts, bounds, timings).
//!
//! The three files are one unit ([`crate::util::atomic_write::Unit`]): a lock on the
//! folder's `.aurora.lock` keeps two bakes from interleaving (the second
//! waits), all three are written in full to temporaries before any is
//! renamed, and `bake.json`, which names the VDB's size and content UUID, is
//! renamed last (the old one removed first). So an interrupted, failed or
//! concurrent bake leaves the previous complete set or a set without a
//! `bake.json`, never a VDB beside another bake's report, and a killed bake's
//! temporaries are removed by the next bake into that folder. Only regular
//! files are ever replaced.
//!
//! A sequence's frames (`aurora.NNNN.vdb` and `aurora.NNNN.json`) are units
//! too, staged by `crate::farm::frame_files` through [`stage_unit`] and
//! committed by `crate::farm::sequence_folder`, which keeps one bake per
//! folder. Every report names its bake's
//! [`BakeIdentity`] (`bake_identity`).

use crate::grid::Grid;
use crate::io::usd;
use crate::io::vdb::codec::Deflate;
use crate::io::vdb::write::{write_vdb_into, GridRef, MetaValue, WriteOptions};
use crate::pipeline::bake::identity::BakeIdentity;
use crate::pipeline::bake::Bake;
use crate::scene::Scene;
use crate::util::atomic_write::{AtomicError, TempFile, Unit, UnitLock};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const VDB_NAME: &str = "aurora.vdb";
pub const USDA_NAME: &str = "aurora.usda";
pub const JSON_NAME: &str = "bake.json";
/// The stem of the bake's unit lock, `.aurora.lock` in the output folder.
pub const LOCK_STEM: &str = "aurora";
/// Stem of a sequence's frame files: `aurora.NNNN.vdb`, `aurora.NNNN.json`.
pub const FRAME_STEM: &str = "aurora";

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
    #[error(transparent)]
    Output(#[from] AtomicError),
    /// A file with one of the bake's names that aurora did not write.
    #[error("{}: {why}; a bake replaces only its own files: move it away or bake into another folder", path.display())]
    NotOurs { path: PathBuf, why: String },
}

impl OutputError {
    /// True when the user's choice of output is at fault (exit status 2).
    pub fn is_input(&self) -> bool {
        match self {
            OutputError::Output(e) => e.is_input(),
            OutputError::NotOurs { .. } => true,
            OutputError::Write { .. } => false,
        }
    }
}

/// Checks, before a long bake, that `out` is (or can be made) a writable
/// folder and that none of the bake's names in it is anything but a regular
/// file; then takes the folder's bake lock (waiting for another bake into the
/// same folder to finish; `on_wait` tells the user). Hold the lock until
/// [`write_outputs_locked`] returns. If the bake fails, dropping the guard
/// removes the folder again when this call created it and it is still empty.
pub fn prepare(out: &Path, on_wait: impl FnOnce()) -> Result<BakeFolder, OutputError> {
    let created = !out.exists();
    crate::util::atomic_write::prepare_folder(out)?;
    let guard = |lock| BakeFolder { dir: out.to_path_buf(), created, lock: Some(lock) };
    let folder = guard(UnitLock::acquire(out, LOCK_STEM, on_wait)?);
    for name in [VDB_NAME, USDA_NAME, JSON_NAME] {
        crate::util::atomic_write::check_replaceable(&out.join(name))?;
    }
    check_ours(out)?;
    Ok(folder)
}

/// Refuses a folder whose bake files were not written by aurora, before
/// anything is baked (the add-on refuses such a folder too): a `bake.json`
/// that is not one of our reports (a JSON object naming `bake_identity` or
/// `aurora_version`), or, with no report, an `aurora.vdb` whose grids do
/// not carry our metadata (`aurora_scene_hash`, [`vdb_metadata`]). A VDB
/// without a report is ours when a bake was stopped between its renames,
/// and is replaced.
pub fn check_ours(out: &Path) -> Result<(), OutputError> {
    if check_report_ours(&out.join(JSON_NAME))? {
        return Ok(());
    }
    check_vdb_ours(&out.join(VDB_NAME), JSON_NAME)
}

/// Refuses a report (`bake.json`, a sequence's `aurora.NNNN.json`) that
/// aurora did not write: one that is not a JSON object naming
/// `bake_identity` or `aurora_version`. The one rule for both; Ok(false)
/// when there is none (or the name is not a regular file, which is never
/// read here: the writers refuse to replace it), Ok(true) when it is ours;
/// one that cannot be read is an I/O error (exit status 1).
pub fn check_report_ours(json: &Path) -> Result<bool, OutputError> {
    use crate::util::input_file::InputFileError;
    match crate::util::input_file::read(json) {
        Err(InputFileError::NotRegular { .. }) => Ok(false),
        Err(InputFileError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(OutputError::Write { path: json.to_path_buf(), message: e.reason() }),
        Ok(bytes) => {
            let ours = serde_json::from_slice::<serde_json::Value>(&bytes)
                .ok()
                .is_some_and(|v| v.get("bake_identity").is_some() || v.get("aurora_version").is_some());
            if ours {
                Ok(true)
            } else {
                Err(OutputError::NotOurs { path: json.to_path_buf(), why: "is not the report of an aurora bake".into() })
            }
        }
    }
}

/// Refuses a VDB without its report (`report`, the name it would have
/// beside it) that aurora did not write: one whose grids carry no
/// `aurora_scene_hash` ([`vdb_metadata`]), or that is not a VDB at all.
/// The one rule for a single bake's `aurora.vdb` ([`check_ours`]) and a
/// sequence's `aurora.NNNN.vdb` (`crate::farm::sequence_folder`). A missing
/// file is fine, and so is a name that is not a regular file (never read
/// here: the writers refuse to replace it); one that cannot be read is an
/// I/O error (exit status 1).
pub fn check_vdb_ours(vdb: &Path, report: &str) -> Result<(), OutputError> {
    if std::fs::metadata(vdb).is_ok_and(|m| !m.is_file()) {
        return Ok(());
    }
    let bytes = match crate::io::vdb::records::FileBytes::open(vdb) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(OutputError::Write { path: vdb.to_path_buf(), message: e.to_string() }),
    };
    let ours = crate::io::vdb::parse::list_grids(bytes.bytes())
        .ok()
        .is_some_and(|grids| grids.iter().any(|g| g.metadata.iter().any(|(k, _)| k == "aurora_scene_hash")));
    if ours {
        Ok(())
    } else {
        Err(OutputError::NotOurs {
            path: vdb.to_path_buf(),
            why: format!("has no {report} beside it and is not a VDB aurora wrote (its grids carry no aurora_scene_hash)"),
        })
    }
}

/// A bake's output folder, locked (see [`prepare`]).
#[derive(Debug)]
pub struct BakeFolder {
    dir: PathBuf,
    created: bool,
    lock: Option<UnitLock>,
}

impl Drop for BakeFolder {
    fn drop(&mut self) {
        drop(self.lock.take());
        if self.created {
            // Fails, harmlessly, unless the folder is empty.
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}

/// What was written, and the report that went into `bake.json`.
pub struct BakeReport {
    pub vdb: PathBuf,
    pub usda: PathBuf,
    pub json_path: PathBuf,
    pub json: serde_json::Value,
}

impl BakeReport {
    /// A few lines for the terminal.
    pub fn summary(&self) -> String {
        let j = &self.json;
        format!(
            "wrote {} ({} bytes), {} and {}\n{} beams, {} photons, {} active voxels in {} leaves (+{} shell voxels for Cycles), voxel {} km, bake {:.2} s",
            self.vdb.display(),
            j["files"]["vdb_bytes"],
            self.usda.display(),
            self.json_path.display(),
            j["stats"]["beams"],
            j["stats"]["photons"],
            j["stats"]["active_voxels"],
            j["stats"]["leaves"],
            j["stats"]["shell_voxels"],
            j["stats"]["voxel_size_km"],
            j["total_seconds"].as_f64().unwrap_or(0.0),
        ) + &self.stats_line("noise", noise_line)
            + &self.stats_line("prune", prune_line)
    }

    /// The summary's line on `stats.<key>` as `line` words it; none when
    /// the bake has no such record.
    fn stats_line(&self, key: &str, line: fn(&serde_json::Value) -> String) -> String {
        let record = &self.json["stats"][key];
        if record.is_null() {
            String::new()
        } else {
            line(record)
        }
    }
}

/// The summary's line on the noise target's pilot (`stats.noise`).
fn noise_line(n: &serde_json::Value) -> String {
    format!(
        "\nbeams.target_noise = {}: pilot of 2 x {} beams measured {:.3} relative RMS noise; {} beams used{}, expected noise {:.3}",
        n["target"],
        n["pilot_beams"],
        n["pilot_noise"].as_f64().unwrap_or(0.0),
        n["beams"],
        if n["capped"].as_bool() == Some(true) { " (capped at beams.count)" } else { "" },
        n["expected_noise"].as_f64().unwrap_or(0.0)
    )
}

/// The summary's line on what the pruning removed (`stats.prune`).
fn prune_line(p: &serde_json::Value) -> String {
    format!(
        "\npruned (grid.prune = {}): {} of {} leaves, {} of {} voxels, {:.3e} of the image's light (estimated, extinction ignored)",
        p["budget"],
        p["leaves_removed"],
        p["leaves_before"],
        p["voxels_removed"],
        p["voxels_before"],
        p["removed_fraction"].as_f64().unwrap_or(0.0)
    )
}

/// The grid metadata naming the observer whose colours `emission` holds
/// (`[colour] observer`), written when it is not the default (the camera).
pub const OBSERVER_KEY: &str = "aurora_observer";

/// Grid metadata that identifies the bake inside the VDB.
pub fn vdb_metadata(scene: &Scene) -> Vec<(String, MetaValue)> {
    let mut m = vec![
        ("aurora_units".into(), MetaValue::String("km".into())),
        ("aurora_seed".into(), MetaValue::Int64(scene.seed as i64)),
        ("aurora_scene_hash".into(), MetaValue::String(format!("{:016x}", scene.hash()))),
        ("aurora_emission_units".into(), MetaValue::String("linear Rec.709 radiance per km; Y = 1 for 1 kR of OI 557.7 nm per km".into())),
        ("aurora_density_units".into(), MetaValue::String("extinction per km".into())),
        // The add-on skips its own padding when this is true (blender/volume_import.py).
        ("aurora_cycles_shell".into(), MetaValue::Bool(scene.grid.cycles_shell)),
    ];
    if scene.colour.observer != crate::util::observer::Observer::default() {
        // Only for another observer than the default, so the default file is
        // unchanged: a bake of ours without the key holds the default's colours.
        m.push((OBSERVER_KEY.into(), MetaValue::String(scene.colour.observer.name().into())));
    }
    if !scene.grid.lines.is_empty() {
        // Only with per-line grids, so the default file is unchanged.
        let units = "line_NAME grids: volume emission rate in rayleigh per km (10 photons cm^-3 s^-1), no colour noise, not pruned";
        m.push(("aurora_line_units".into(), MetaValue::String(units.into())));
    }
    if scene.grid.velocity {
        // Only with the velocity grid, so the default file is unchanged.
        let units = "v: the emission pattern's velocity in km/s (1 unit = 1 km), a central difference over t +- dt";
        m.push(("aurora_velocity_units".into(), MetaValue::String(units.into())));
        m.push(("aurora_velocity_fps".into(), MetaValue::Double(scene.animation.fps)));
        m.push(("aurora_velocity_dt_s".into(), MetaValue::Double(crate::pipeline::bake::velocity::dt_s(&scene.animation))));
    }
    m
}

/// The VDB write options the scene asks for, for `density` and
/// `emission` (the high column's grids follow their fine grids:
/// [`with_high_column`]): half floats, mantissa bits, and libdeflate for
/// ZIP (a valid zlib stream, three to four times faster to write than
/// OpenVDB's zlib at level 6).
pub fn write_options(scene: &Scene) -> WriteOptions {
    // The velocity grid `v`, when written, is stored as the emission is.
    let v = scene.grid.velocity.then_some(crate::pipeline::bake::velocity::GRID_NAME);
    let half = [(scene.grid.half_density, Some("density")), (scene.grid.half_emission, Some("emission")), (scene.grid.half_emission, v)]
        .into_iter()
        .filter_map(|(on, name)| name.filter(|_| on))
        .map(|name| name.to_string())
        .collect();
    let mantissa_bits = ["density", "emission"].into_iter().chain(v).map(|g| (g.to_string(), scene.grid.mantissa_bits)).collect();
    WriteOptions { compression: scene.grid.compression, half, mantissa_bits, deflate: Deflate::Fast, metadata: vdb_metadata(scene) }
}

/// `options` without the half-float requests for grids whose values do
/// not fit a half (|x| > 65504): those are stored as full floats (the bake
/// warns, `crate::pipeline::bake::finish`), so a half-float default never refuses a
/// valid scene. Returns the names dropped.
pub fn fit_half(mut options: WriteOptions, grids: &[GridRef<'_>]) -> (WriteOptions, Vec<String>) {
    let max = half::f16::MAX.to_f32();
    let too_big = |g: &GridRef<'_>| match g {
        GridRef::Float(g) => g.iter_active().any(|(_, v)| v.abs() > max),
        GridRef::Vec3(g) => g.iter_active().any(|(_, v)| v.iter().any(|x| x.abs() > max)),
    };
    let dropped: Vec<String> =
        grids.iter().filter(|g| options.half.iter().any(|h| h == g.name()) && too_big(g)).map(|g| g.name().to_string()).collect();
    options.half.retain(|h| !dropped.contains(h));
    (options, dropped)
}

/// `options` for a file that also holds the high column: `NAME_high` is
/// stored as `NAME` is (half floats, mantissa bits), for the grids the
/// column splits (`density`, `emission`; the velocity `v` stays whole).
pub fn with_high_column(mut options: WriteOptions) -> WriteOptions {
    let high = |n: &str| format!("{n}{}", crate::grid::high_column::HIGH_SUFFIX);
    let split = |n: &str| n == "density" || n == "emission";
    let half: Vec<String> = options.half.iter().filter(|n| split(n)).map(|n| high(n)).collect();
    let bits: Vec<(String, u32)> = options.mantissa_bits.iter().filter(|(n, _)| split(n)).map(|(n, b)| (high(n), *b)).collect();
    options.half.extend(half);
    options.mantissa_bits.extend(bits);
    options
}

/// Whether the scene's files store the high column in grids of their own
/// (`grid.high_voxel_factor > 1`, [`crate::grid::high_column`]).
pub fn has_high_column(scene: &Scene) -> bool {
    scene.grid.high_voxel_factor > 1
}

/// The fields a USD stage lists for the scene's files: `density`,
/// `emission`, the high column's grids when stored apart, and the
/// per-line grids, each with its USD data type.
pub fn stage_fields(scene: &Scene) -> Vec<(String, &'static str)> {
    let mut f = vec![("density".to_string(), "float"), ("emission".to_string(), "float3")];
    if has_high_column(scene) {
        f.push((format!("density{}", crate::grid::high_column::HIGH_SUFFIX), "float"));
        f.push((format!("emission{}", crate::grid::high_column::HIGH_SUFFIX), "float3"));
    }
    f.extend(scene.grid.lines.iter().map(|k| (crate::physics::emission::line_table::grid_name(k), "float")));
    if scene.grid.velocity {
        f.push((crate::pipeline::bake::velocity::GRID_NAME.to_string(), "float3"));
    }
    f
}

/// The high column's grids of a bake (`density_high`, `emission_high`)
/// and the fine grids that go with them ([`crate::grid::high_column::split`]), when
/// the scene stores it apart; with `grid.cycles_shell` each grid gets its
/// own shell (the bake's grids already carry theirs).
pub struct HighColumn {
    pub column: crate::grid::high_column::Column,
    pub density: Grid<f32>,
    pub emission: Grid<[f32; 3]>,
    pub density_high: Grid<f32>,
    pub emission_high: Grid<[f32; 3]>,
}

/// [`HighColumn`] of `bake` for `scene` (None without one).
pub fn high_column(scene: &Scene, bake: &Bake) -> Option<HighColumn> {
    if !has_high_column(scene) {
        return None;
    }
    let col = crate::grid::high_column::Column::new(
        scene.grid.high_above_km,
        scene.grid.high_voxel_factor as i32,
        bake.emission.transform.voxel_size,
    );
    let earth = crate::geometry::earth::Earth::new(scene.earth.radius_km);
    let ((density, mut density_high), (emission, mut emission_high)) = rayon::join(
        || crate::grid::high_column::split(&bake.density, &col, &earth),
        || crate::grid::high_column::split(&bake.emission, &col, &earth),
    );
    if scene.grid.cycles_shell {
        emission_high.dilate_active();
        density_high.dilate_active();
    }
    Some(HighColumn { column: col, density, emission, density_high, emission_high })
}

/// Writes the three files into `out` as one unit (see the module docs).
/// Takes the folder's lock itself: a caller that already holds it (from
/// [`prepare`], taken before a long bake) calls [`write_outputs_locked`].
pub fn write_outputs(scene: &Scene, bake: &Bake, out: &Path) -> Result<BakeReport, OutputError> {
    let _lock = prepare(out, || {})?;
    write_outputs_locked(scene, bake, out)
}

/// [`write_outputs`] for a caller that holds the folder's lock from [`prepare`].
pub fn write_outputs_locked(scene: &Scene, bake: &Bake, out: &Path) -> Result<BakeReport, OutputError> {
    let fields = stage_fields(scene);
    let fields: Vec<(&str, &str)> = fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let usda = usd::usda_text(VDB_NAME, &fields, 1000.0);
    let usda_len = usda.len();
    let files = UnitFiles {
        vdb: out.join(VDB_NAME),
        vdb_name: VDB_NAME.to_string(),
        usda: Some((out.join(USDA_NAME), usda)),
        json: out.join(JSON_NAME),
        options: write_options(scene),
        high: high_column(scene, bake),
    };
    let mut report = unit_report(scene, bake, &BakeIdentity::of(scene));
    let staged = stage_unit(bake, files, |mut vdb_files, vdb_seconds| {
        vdb_files["usda_bytes"] = json!(usda_len);
        report["files"] = vdb_files;
        report["total_seconds"] = json!(bake.stats.total_seconds() + vdb_seconds);
        report
    })?;
    staged.commit()
}

/// What one output unit holds: the VDB (its path, its name in the report,
/// the write options), an optional USD stage with its text, and the report.
pub(crate) struct UnitFiles {
    pub(crate) vdb: PathBuf,
    pub(crate) vdb_name: String,
    pub(crate) usda: Option<(PathBuf, String)>,
    pub(crate) json: PathBuf,
    pub(crate) options: WriteOptions,
    /// The grids split at the high column, when the scene stores it apart.
    pub(crate) high: Option<HighColumn>,
}

/// The report's keys common to a bake and a frame (the rest is added by the
/// caller). `identity` is the bake's ([`BakeIdentity`]; a frame's is its
/// sequence's, the same for every frame).
pub(crate) fn unit_report(scene: &Scene, bake: &Bake, identity: &BakeIdentity) -> serde_json::Value {
    let mut report = json!({
        "aurora_version": env!("CARGO_PKG_VERSION"),
        "bake_identity": identity.to_json(),
        "scene_hash": format!("{:016x}", scene.hash()),
        "seed": scene.seed,
        "overrides": scene.overrides,
        "units": "km",
        "threads": rayon::current_num_threads(),
        "stats": bake.stats,
    });
    if bake.velocity.is_some() {
        // Only with the velocity grid, so the default report is unchanged.
        report["velocity"] = json!({
            "grid": crate::pipeline::bake::velocity::GRID_NAME,
            "units": "km/s",
            "fps": scene.animation.fps,
            "dt_s": crate::pipeline::bake::velocity::dt_s(&scene.animation),
            "method": "central difference of the closed-form motion over t +- dt, luminance-weighted per voxel",
        });
    }
    report
}

/// An output unit written in full to temporaries, not yet visible: its
/// files appear by [`StagedUnit::commit`]; dropped, they are removed.
pub struct StagedUnit {
    unit: Unit,
    report: BakeReport,
}

impl StagedUnit {
    /// Renames the unit's files into place, the report last.
    pub fn commit(self) -> Result<BakeReport, OutputError> {
        self.unit.commit()?;
        Ok(self.report)
    }
}

/// Stages one output unit: the VDB, then the USD stage if any, then the
/// report (the manifest, renamed last by [`StagedUnit::commit`]). `report`
/// receives the `files` object (VDB name, bytes, UUID and write time, the
/// stage's name, compression, half floats) and the VDB write time, and
/// returns the whole report.
pub(crate) fn stage_unit(
    bake: &Bake,
    files: UnitFiles,
    report: impl FnOnce(serde_json::Value, f64) -> serde_json::Value,
) -> Result<StagedUnit, OutputError> {
    use std::io::Write;
    let UnitFiles { vdb: vdb_path, vdb_name, usda, json: json_path, options, high } = files;
    let mut unit = Unit::new();
    let t0 = Instant::now();
    let mut vdb_tmp = TempFile::create(&vdb_path)?;
    let options = if high.is_some() { with_high_column(options) } else { options };
    let mut grids = match &high {
        Some(h) => {
            vec![GridRef::Float(&h.density), GridRef::Vec3(&h.emission), GridRef::Float(&h.density_high), GridRef::Vec3(&h.emission_high)]
        }
        None => vec![GridRef::Float(&bake.density), GridRef::Vec3(&bake.emission)],
    };
    grids.extend(bake.lines.iter().map(GridRef::Float));
    // The velocity on the emission's voxels, whole (not split at a high column).
    grids.extend(bake.velocity.iter().map(GridRef::Vec3));
    let (options, full_float) = fit_half(options, &grids);
    let stats = write_vdb_into(&mut vdb_tmp, &grids, &options)
        .map_err(|e| OutputError::Write { path: vdb_path.clone(), message: e.to_string() })?;
    let vdb_seconds = t0.elapsed().as_secs_f64();
    unit.stage(vdb_tmp);
    let usda_path = match usda {
        Some((path, text)) => {
            let mut tmp = TempFile::create(&path)?;
            tmp.file().write_all(text.as_bytes()).map_err(|e| OutputError::Write { path: path.clone(), message: e.to_string() })?;
            unit.stage(tmp);
            path
        }
        None => vdb_path.with_file_name(USDA_NAME),
    };
    let vdb_files = json!({
        "vdb": vdb_name,
        "vdb_bytes": stats.bytes,
        "vdb_uuid": stats.uuid,
        "vdb_write_seconds": vdb_seconds,
        "usda": USDA_NAME,
        "compression": options.compression,
        "half_emission": options.half.iter().any(|g| g == "emission"),
        "half_density": options.half.iter().any(|g| g == "density"),
        "mantissa_bits": options.mantissa_bits.iter().find(|(g, _)| g == "emission").map(|(_, b)| *b),
        "full_float_beyond_half_range": full_float,
        "high_column": high.as_ref().map(|h| json!({
            "above_km": h.column.above_km,
            "band_km": h.column.band_km,
            "voxel_km": h.emission_high.transform.voxel_size,
            "voxels": h.emission.active_voxel_count(),
            "high_voxels": h.emission_high.active_voxel_count(),
        })),
    });
    let report = report(vdb_files, vdb_seconds);
    let text = serde_json::to_string_pretty(&report).expect("json serialises") + "\n";
    let mut json_tmp = TempFile::create(&json_path)?;
    json_tmp.file().write_all(text.as_bytes()).map_err(|e| OutputError::Write { path: json_path.clone(), message: e.to_string() })?;
    unit.stage_manifest(json_tmp);
    Ok(StagedUnit { unit, report: BakeReport { vdb: vdb_path, usda: usda_path, json_path, json: report } })
}
