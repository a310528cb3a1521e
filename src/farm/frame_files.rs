//! A sequence's frame files: `aurora.NNNN.vdb` and its report
//! `aurora.NNNN.json`, each frame one atomic unit
//! ([`crate::util::atomic_write::Unit`]) staged here through the bake
//! folder's writer ([`crate::io::bake_folder::stage_unit`]) and committed by
//! [`crate::farm::sequence_folder`]; whether a frame is complete for a bake
//! ([`frame_state`]: its report names the bake and its VDB is the file the
//! report records, by size and header UUID); and the sequence's
//! time-sampled USD stage, streamed ([`write_sequence_usda`]).

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

/// Whether frame `frame` of a sequence folder is done ([`frame_state`]).
#[derive(Clone, Debug, PartialEq)]
pub enum FrameState {
    /// Both files in place, the report naming this bake, the VDB the one
    /// the report describes (its size and header UUID).
    Complete,
    /// Not (yet) a frame of this bake: no report, a report of another bake
    /// or none (`crate::farm::sequence_folder` decides about those), or an
    /// interrupted frame: baked (again) without comment.
    Absent,
    /// The report names this bake but its VDB is not the file it describes
    /// (missing, cut short, another frame's): baked again, the reason said.
    Mismatch(String),
}

/// Why a frame report names no bake, or could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Reading failed (the OS's error): says nothing about whose it is.
    #[error("cannot read {}: {cause}", path.display())]
    Unreadable { path: PathBuf, cause: std::io::Error },
    /// Read (or refused unread: not a regular file), and not a report of a
    /// bake: the reason.
    #[error("{why}")]
    NotABake { path: PathBuf, why: String },
}

impl ReportError {
    /// A report that is not one is the folder's content, the user's to
    /// sort out (exit 2); a failed read is not (exit 1).
    pub fn is_input(&self) -> bool {
        matches!(self, ReportError::NotABake { .. })
    }
}

/// Frame `frame`'s state for the bake `identity`. A frame is complete when
/// both its final names exist, its report names `identity`
/// (`crate::farm::sequence_folder` keeps one bake per folder), and its VDB
/// is the one the report records: the same size in bytes and the same UUID
/// in its header (the writer's content UUID, `crate::io::vdb::write`; a
/// truncated file, or another frame's, differs in one or both). Final
/// names only ever appear by rename (temporaries are `.NAME.tmpPID`), and
/// the report is renamed last, so a frame interrupted anywhere is baked
/// again. Err: a file could not be read (an I/O error, not a verdict).
pub fn frame_state(out: &Path, frame: i64, identity: &BakeIdentity) -> Result<FrameState, ReportError> {
    let (vdb, json) = frame_paths(out, frame);
    let report = match read_report(&json) {
        Ok(r) => r,
        Err(ReportError::NotABake { .. }) => return Ok(FrameState::Absent),
        Err(ReportError::Unreadable { cause, .. }) if cause.kind() == std::io::ErrorKind::NotFound => return Ok(FrameState::Absent),
        Err(e) => return Err(e),
    };
    if BakeIdentity::from_report(&report).is_none_or(|id| id != *identity) {
        return Ok(FrameState::Absent);
    }
    let name = vdb.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let (Some(bytes), Some(uuid)) = (report["files"]["vdb_bytes"].as_u64(), report["files"]["vdb_uuid"].as_str()) else {
        return Ok(FrameState::Mismatch(format!("{} records no VDB size and UUID", json.display())));
    };
    let unreadable = |cause| ReportError::Unreadable { path: vdb.clone(), cause };
    let len = match std::fs::symlink_metadata(&vdb) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(FrameState::Mismatch(format!("{name} is missing"))),
        Err(e) => return Err(unreadable(e)),
        Ok(m) if !m.is_file() => {
            let kind = crate::util::input_file::kind_name(m.file_type());
            return Ok(FrameState::Mismatch(format!("{name} is {kind}, not a regular file")));
        }
        Ok(m) => m.len(),
    };
    if len != bytes {
        return Ok(FrameState::Mismatch(format!("{name} is {len} bytes, its report records {bytes}")));
    }
    match vdb_header(&vdb) {
        Ok(h) if h.uuid == uuid => Ok(FrameState::Complete),
        Ok(h) => Ok(FrameState::Mismatch(format!("{name} has UUID {}, its report records {uuid}", h.uuid))),
        Err(VdbHeaderError::NotVdb(why)) => Ok(FrameState::Mismatch(format!("{name}: {why}"))),
        Err(VdbHeaderError::Unreadable(source)) => Err(unreadable(source)),
    }
}

/// A frame report's JSON: Err says why there is none (not a regular file,
/// not JSON), or that it could not be read.
fn read_report(report: &Path) -> Result<serde_json::Value, ReportError> {
    let bytes = crate::util::input_file::read(report).map_err(|e| match e {
        crate::util::input_file::InputFileError::Io { path, source } => ReportError::Unreadable { path, cause: source },
        other => ReportError::NotABake { path: report.to_path_buf(), why: other.reason() },
    })?;
    serde_json::from_slice(&bytes).map_err(|e| ReportError::NotABake { path: report.to_path_buf(), why: format!("not a JSON report: {e}") })
}

/// The bake identity a frame report names; Err says why there is none (the
/// file is not a regular file, is not JSON, names none) or that it could
/// not be read.
pub fn frame_identity(report: &Path) -> Result<BakeIdentity, ReportError> {
    BakeIdentity::from_report(&read_report(report)?).ok_or_else(|| ReportError::NotABake {
        path: report.to_path_buf(),
        why: "it names no bake identity (written by an older aurora)".to_string(),
    })
}

/// What a VDB file's fixed header says (OpenVDB `Archive::readHeader`,
/// `crate::io::vdb::write`'s steps 1 to 6): the file format version and
/// the UUID.
#[derive(Clone, Debug, PartialEq)]
pub struct VdbHeader {
    pub file_version: u32,
    pub uuid: String,
}

/// Why [`vdb_header`] found no header.
#[derive(Debug)]
pub enum VdbHeaderError {
    /// The file could not be opened or read (the OS's error).
    Unreadable(std::io::Error),
    /// Read, but not a VDB file aurora reads: why.
    NotVdb(String),
}

/// The fixed header of the VDB file at `path` (the first 57 bytes: magic,
/// file version, library version, offsets flag, UUID), checked as the
/// reader checks it (`crate::io::vdb::parse`): the magic number, a file
/// version the reader handles, grid offsets present. Only a regular file
/// is opened (`crate::util::input_file`).
pub fn vdb_header(path: &Path) -> Result<VdbHeader, VdbHeaderError> {
    use crate::io::vdb::layout::{MAGIC, MAX_READ_VERSION, MIN_READ_VERSION, UUID_LEN};
    use std::io::Read;
    let mut file = crate::util::input_file::open(path).map_err(|e| match e {
        crate::util::input_file::InputFileError::Io { source, .. } => VdbHeaderError::Unreadable(source),
        other => VdbHeaderError::NotVdb(other.reason()),
    })?;
    let mut h = [0u8; 21 + UUID_LEN];
    let mut got = 0;
    while got < h.len() {
        match file.read(&mut h[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(VdbHeaderError::Unreadable(e)),
        }
    }
    if got < h.len() {
        return Err(VdbHeaderError::NotVdb(format!("not a VDB file: {got} bytes, shorter than a VDB header ({} bytes)", h.len())));
    }
    let magic = i64::from_le_bytes(h[0..8].try_into().expect("8 bytes"));
    if magic != MAGIC {
        return Err(VdbHeaderError::NotVdb(format!("not a VDB file: magic number {magic:#x}, expected {MAGIC:#x}")));
    }
    let file_version = u32::from_le_bytes(h[8..12].try_into().expect("4 bytes"));
    if !(MIN_READ_VERSION..=MAX_READ_VERSION).contains(&file_version) {
        return Err(VdbHeaderError::NotVdb(format!(
            "unsupported VDB file format version {file_version} (this reader handles {MIN_READ_VERSION}..={MAX_READ_VERSION})"
        )));
    }
    if h[20] != 1 {
        return Err(VdbHeaderError::NotVdb(format!("has-grid-offsets flag is {}: streamed archives are not supported", h[20])));
    }
    Ok(VdbHeader { file_version, uuid: String::from_utf8_lossy(&h[21..]).into_owned() })
}

/// Writes the sequence stage `DIR/aurora.usda` listing every frame of the
/// range (whichever shard bakes it): the same bytes from every shard,
/// streamed to a temporary name and renamed, so it is never half-written,
/// any shard may rewrite it, and its memory does not grow with the range.
/// The stage lists `fields` (VDB grid name, USD data type: [`stage_fields`]).
pub fn write_sequence_usda(out: &Path, frames: &[i64], fps: f64, fields: &[(String, &'static str)]) -> Result<PathBuf, OutputError> {
    crate::util::atomic_write::prepare_folder(out)?;
    let path = out.join(USDA_NAME);
    // Refused as the user's (exit 2) when the name is not a regular file.
    crate::util::atomic_write::check_replaceable(&path)?;
    let fields: Vec<(&str, &str)> = fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    usd::write_usda_sequence(&path, usd::Sequence { frames, name: &stage_vdb_name, fps }, &fields, 1000.0)
        .map_err(|e| OutputError::Write { path: path.clone(), message: e.to_string() })?;
    Ok(path)
}

/// The bytes of the sequence stage [`write_sequence_usda`] writes for
/// `frames`, counted as it is written into a sink that keeps none of them.
pub fn sequence_usda_bytes(frames: &[i64], fps: f64, fields: &[(String, &'static str)]) -> Result<u64, std::io::Error> {
    let fields: Vec<(&str, &str)> = fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let mut sink = std::io::BufWriter::with_capacity(usd::STREAM_BUFFER, ByteCount(0));
    usd::write_usda_sequence_into(&mut sink, usd::Sequence { frames, name: &stage_vdb_name, fps }, &fields, 1000.0)?;
    Ok(sink.into_inner().map_err(|e| e.into_error())?.0)
}

/// A frame's VDB name as the stage lists it (relative to the stage).
fn stage_vdb_name(frame: i64) -> String {
    frame_file_name(FRAME_STEM, frame, "vdb")
}

/// A sink that counts the bytes written into it.
struct ByteCount(u64);

impl std::io::Write for ByteCount {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0 += buf.len() as u64;
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Takes frame `frame`'s lock (`.aurora.NNNN.lock`), waiting while another
/// process (a shard sharing the folder) bakes it. Hold it while baking and
/// writing the frame; check [`frame_state`] again once it is held.
pub fn lock_frame(out: &Path, frame: i64, on_wait: impl FnOnce()) -> Result<UnitLock, OutputError> {
    let stem = frame_file_name(FRAME_STEM, frame, "");
    Ok(UnitLock::acquire(out, stem.trim_end_matches('.'), on_wait)?)
}

/// Stages frame `frame` of a sequence as one unit: the VDB (with
/// `aurora_frame` and `aurora_time_s` metadata), then its report, renamed
/// last (see [`frame_state`]) by [`StagedUnit::commit`], naming the VDB's
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
        let dir = crate::util::scratch::folder("shared", "stage");
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
        assert!(text.ends_with("}\n") && text.contains("500: @aurora.0500.vdb@"));
        assert_eq!(crate::util::scratch::file_names(&dir), [USDA_NAME]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
