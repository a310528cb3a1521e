//! What `aurora bake` leaves on disk: `aurora.vdb` (both grids), `aurora.usda`
//! (a UsdVol stage pointing at it) and `bake.json` (counts, bounds, timings).
//!
//! The three files are one unit ([`crate::atomic::Unit`]): a lock on the
//! folder's `.aurora.lock` keeps two bakes from interleaving (the second
//! waits), all three are written in full to temporaries before any is
//! renamed, and `bake.json`, which names the VDB's size and content UUID, is
//! renamed last (the old one removed first). So an interrupted, failed or
//! concurrent bake leaves the previous complete set or a set without a
//! `bake.json`, never a VDB beside another bake's report, and a killed bake's
//! temporaries are removed by the next bake into that folder. Only regular
//! files are ever replaced.

use crate::bake::Bake;
use crate::scene::Scene;
use crate::usd;
use crate::atomic::{AtomicError, TempFile, Unit, UnitLock};
use crate::vdb::write::{write_vdb_into, GridRef, MetaValue, WriteOptions};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const VDB_NAME: &str = "aurora.vdb";
pub const USDA_NAME: &str = "aurora.usda";
pub const JSON_NAME: &str = "bake.json";
/// The stem of the bake's unit lock, `.aurora.lock` in the output folder.
pub const LOCK_STEM: &str = "aurora";

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
    #[error(transparent)]
    Output(#[from] AtomicError),
}

impl OutputError {
    /// True when the user's choice of output is at fault (exit status 2).
    pub fn is_input(&self) -> bool {
        matches!(self, OutputError::Output(e) if e.is_input())
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
    crate::atomic::prepare_folder(out)?;
    let guard = |lock| BakeFolder { dir: out.to_path_buf(), created, lock: Some(lock) };
    let folder = guard(UnitLock::acquire(out, LOCK_STEM, on_wait)?);
    for name in [VDB_NAME, USDA_NAME, JSON_NAME] {
        crate::atomic::check_replaceable(&out.join(name))?;
    }
    Ok(folder)
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
        ) + &self.noise_line()
            + &self.prune_line()
    }

    fn noise_line(&self) -> String {
        let n = &self.json["stats"]["noise"];
        if n.is_null() {
            return String::new();
        }
        format!(
            "\nbeams.target_noise = {}: pilot of 2 x {} beams measured {:.3} relative RMS noise; {} beams used{}, expected noise {:.3}",
            n["target"], n["pilot_beams"], n["pilot_noise"].as_f64().unwrap_or(0.0), n["beams"],
            if n["capped"].as_bool() == Some(true) { " (capped at beams.count)" } else { "" },
            n["expected_noise"].as_f64().unwrap_or(0.0)
        )
    }

    fn prune_line(&self) -> String {
        let p = &self.json["stats"]["prune"];
        if p.is_null() {
            return String::new();
        }
        format!(
            "\npruned (grid.prune = {}): {} of {} leaves, {} of {} voxels, {:.3e} of the image's light (estimated, extinction ignored)",
            p["budget"], p["leaves_removed"], p["leaves_before"], p["voxels_removed"], p["voxels_before"],
            p["removed_fraction"].as_f64().unwrap_or(0.0)
        )
    }
}

/// Grid metadata that identifies the bake inside the VDB.
pub fn vdb_metadata(scene: &Scene) -> Vec<(String, MetaValue)> {
    vec![
        ("aurora_units".into(), MetaValue::String("km".into())),
        ("aurora_seed".into(), MetaValue::Int64(scene.seed as i64)),
        ("aurora_scene_hash".into(), MetaValue::String(format!("{:016x}", scene.hash()))),
        (
            "aurora_emission_units".into(),
            MetaValue::String("linear Rec.709 radiance per km; Y = 1 for 1 kR of OI 557.7 nm per km".into()),
        ),
        ("aurora_density_units".into(), MetaValue::String("extinction per km".into())),
        // The add-on skips its own padding when this is true (blender/volume_import.py).
        ("aurora_cycles_shell".into(), MetaValue::Bool(scene.grid.cycles_shell)),
    ]
}

/// The VDB write options the scene asks for.
pub fn write_options(scene: &Scene) -> WriteOptions {
    WriteOptions {
        compression: scene.grid.compression,
        half: if scene.grid.half_emission { vec!["emission".to_string()] } else { vec![] },
        metadata: vdb_metadata(scene),
    }
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
    let vdb_path = out.join(VDB_NAME);
    let usda_path = out.join(USDA_NAME);
    let json_path = out.join(JSON_NAME);
    let mut unit = Unit::new();

    let t0 = Instant::now();
    let mut vdb_tmp = TempFile::create(&vdb_path)?;
    let stats = write_vdb_into(&mut vdb_tmp, &[GridRef::Float(&bake.density), GridRef::Vec3(&bake.emission)], &write_options(scene))
        .map_err(|e| OutputError::Write { path: vdb_path.clone(), message: e.to_string() })?;
    let vdb_seconds = t0.elapsed().as_secs_f64();
    unit.stage(vdb_tmp);

    let mut usda_tmp = TempFile::create(&usda_path)?;
    let usda = usd::usda_text(VDB_NAME, &[("density", "float"), ("emission", "float3")], 1000.0);
    use std::io::Write;
    usda_tmp
        .file()
        .write_all(usda.as_bytes())
        .map_err(|e| OutputError::Write { path: usda_path.clone(), message: e.to_string() })?;
    unit.stage(usda_tmp);

    let total: f64 = bake.stats.total_seconds() + vdb_seconds;
    let report = json!({
        "aurora_version": env!("CARGO_PKG_VERSION"),
        "scene_hash": format!("{:016x}", scene.hash()),
        "seed": scene.seed,
        "units": "km",
        "threads": rayon::current_num_threads(),
        "stats": bake.stats,
        "files": {
            "vdb": VDB_NAME,
            "vdb_bytes": stats.bytes,
            "vdb_uuid": stats.uuid,
            "vdb_write_seconds": vdb_seconds,
            "usda": USDA_NAME,
            "usda_bytes": usda.len(),
            "compression": scene.grid.compression,
            "half_emission": scene.grid.half_emission,
        },
        "total_seconds": total,
    });
    let text = serde_json::to_string_pretty(&report).expect("json serialises") + "\n";
    let mut json_tmp = TempFile::create(&json_path)?;
    json_tmp
        .file()
        .write_all(text.as_bytes())
        .map_err(|e| OutputError::Write { path: json_path.clone(), message: e.to_string() })?;
    unit.stage_manifest(json_tmp);
    unit.commit()?;
    Ok(BakeReport { vdb: vdb_path, usda: usda_path, json_path, json: report })
}
