//! A sequence's frame files: `aurora.NNNN.vdb` and its report
//! `aurora.NNNN.json`, each frame one atomic unit
//! ([`crate::util::atomic_write::Unit`]) staged here through the bake
//! folder's writer ([`crate::io::bake_folder::stage_unit`]) and committed by
//! [`crate::farm::sequence_folder`]; whether a frame is complete for a bake
//! ([`frame_complete`]); and the sequence's time-sampled USD stage.

use crate::farm::frame_range::frame_file_name;
use crate::io::bake_folder::{
    high_column, stage_unit, unit_report, write_options, OutputError, StagedUnit, UnitFiles, FRAME_STEM, USDA_NAME,
};
use crate::io::usd;
use crate::io::vdb::write::MetaValue;
use crate::pipeline::bake::identity::BakeIdentity;
use crate::pipeline::bake::Bake;
use crate::scene::Scene;
use crate::util::atomic_write::UnitLock;
use serde_json::json;
use std::path::{Path, PathBuf};

/// The frame files of a sequence: `DIR/aurora.NNNN.vdb` and its report
/// `DIR/aurora.NNNN.json`.
pub fn frame_paths(out: &Path, frame: i64) -> (PathBuf, PathBuf) {
    (out.join(frame_file_name(FRAME_STEM, frame, "vdb")), out.join(frame_file_name(FRAME_STEM, frame, "json")))
}

/// A frame is complete when both its final names exist and its report
/// names `identity` (`crate::farm::sequence_folder` keeps one bake per folder). Final
/// names only ever appear by rename (temporaries are `.NAME.tmpPID`), and
/// the report is renamed last, so a frame interrupted anywhere is baked
/// again.
pub fn frame_complete(out: &Path, frame: i64, identity: &BakeIdentity) -> bool {
    let (vdb, json) = frame_paths(out, frame);
    vdb.is_file() && frame_identity(&json).is_ok_and(|id| id == *identity)
}

/// The bake identity a frame report names; Err says why there is none (the
/// file is not a regular file, cannot be read, is not JSON, names none).
pub fn frame_identity(report: &Path) -> Result<BakeIdentity, String> {
    let bytes = crate::util::input_file::read(report).map_err(|e| e.reason())?;
    let json: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| format!("not a JSON report: {e}"))?;
    BakeIdentity::from_report(&json).ok_or_else(|| "it names no bake identity (written by an older aurora)".to_string())
}

/// Writes the sequence stage `DIR/aurora.usda` listing every frame of the
/// range (whichever shard bakes it): the same bytes from every shard, written
/// to a temporary name and renamed, so it is never half-written and any
/// shard may rewrite it.
/// The stage lists `fields` (VDB grid name, USD data type: [`stage_fields`]).
pub fn write_sequence_usda(out: &Path, frames: &[i64], fps: f64, fields: &[(String, &'static str)]) -> Result<PathBuf, OutputError> {
    crate::util::atomic_write::prepare_folder(out)?;
    let list: Vec<(i64, String)> = frames.iter().map(|&f| (f, frame_file_name(FRAME_STEM, f, "vdb"))).collect();
    let path = out.join(USDA_NAME);
    let err = |e: std::io::Error| OutputError::Write { path: path.clone(), message: e.to_string() };
    let fields: Vec<(&str, &str)> = fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let text = usd::usda_sequence_checked(&list, &fields, 1000.0, fps).map_err(err)?;
    crate::util::atomic_write::write_atomic(&path, text.as_bytes())?;
    Ok(path)
}

/// Takes frame `frame`'s lock (`.aurora.NNNN.lock`), waiting while another
/// process (a shard sharing the folder) bakes it. Hold it while baking and
/// writing the frame; check [`frame_complete`] again once it is held.
pub fn lock_frame(out: &Path, frame: i64, on_wait: impl FnOnce()) -> Result<UnitLock, OutputError> {
    let stem = frame_file_name(FRAME_STEM, frame, "");
    Ok(UnitLock::acquire(out, stem.trim_end_matches('.'), on_wait)?)
}

/// Stages frame `frame` of a sequence as one unit: the VDB (with
/// `aurora_frame` and `aurora_time_s` metadata), then its report, renamed
/// last (see [`frame_complete`]) by [`StagedUnit::commit`], naming the VDB's
/// size and UUID and the sequence's `identity`. `scene` is the scene at that
/// frame's time. The caller holds [`lock_frame`]; `crate::farm::sequence_folder` commits
/// it once the folder is known to be this bake's.
pub fn stage_frame(scene: &Scene, bake: &Bake, out: &Path, frame: i64, identity: &BakeIdentity) -> Result<StagedUnit, OutputError> {
    crate::util::atomic_write::prepare_folder(out)?;
    let (vdb, json) = frame_paths(out, frame);
    let mut options = write_options(scene);
    options.metadata.push(("aurora_frame".into(), MetaValue::Int64(frame)));
    options.metadata.push(("aurora_time_s".into(), MetaValue::String(format!("{}", scene.animation.time_s))));
    let vdb_name = frame_file_name(FRAME_STEM, frame, "vdb");
    let files = UnitFiles { vdb, vdb_name, usda: None, json, options, high: high_column(scene, bake) };
    let mut report = unit_report(scene, bake, identity);
    report["frame"] = json!(frame);
    report["time_s"] = json!(scene.animation.time_s);
    report["fps"] = json!(scene.animation.fps);
    stage_unit(bake, files, |vdb_files, vdb_seconds| {
        report["files"] = vdb_files;
        report["total_seconds"] = json!(bake.stats.total_seconds() + vdb_seconds);
        report
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::bake_folder::stage_fields;

    /// Eight writers (one process, as containers that are all PID 1 look to
    /// a shared folder) write the stage 40 times each at once: every write
    /// succeeds, the stage is whole, no temporary is left.
    #[test]
    fn concurrent_stage_writers_never_fail_or_leave_temporaries() {
        let dir = std::env::temp_dir().join(format!("aurora-shared-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let frames: Vec<i64> = (1..=500).collect();
        std::thread::scope(|s| {
            for _ in 0..8 {
                s.spawn(|| {
                    for _ in 0..40 {
                        write_sequence_usda(&dir, &frames, 24.0, &stage_fields(&Scene::default())).unwrap();
                    }
                });
            }
        });
        let text = std::fs::read_to_string(dir.join(USDA_NAME)).unwrap();
        assert!(text.ends_with("}\n") && text.contains("500: @./aurora.0500.vdb@"));
        let names: Vec<String> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        assert_eq!(names, [USDA_NAME]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
