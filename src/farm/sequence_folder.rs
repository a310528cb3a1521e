//! A sequence folder (`aurora bake SCENE --frames SPEC --out DIR`) holds the
//! frames of one bake, whatever the shards sharing it do: a rerun keeps a
//! frame only if it is of the bake asked for, and never mixes two bakes'
//! frames in the folder or its stage.
//!
//! **Which bake.** Every frame's report names its [`BakeIdentity`] (the
//! scene's bake keys and the build). The folder names its owner in a record,
//! `DIR/.aurora.sequence.json`. The record and the stage `aurora.usda` are
//! written, and every frame is renamed into place, only under the folder's
//! lock (`.aurora.lock`, [`crate::util::atomic_write::UnitLock`], the one a single
//! bake takes), and only by the record's owner, after checking the record
//! under that lock. So at every instant the folder holds frames of the
//! record's bake only, and the stage is the owner's.
//!
//! **Opening** ([`Sequence::open`], under the lock). The record, the
//! stage's name and the folder's frames of another bake (a complete frame
//! whose report names another identity, or none, or is not a report) are
//! examined before anything is deleted or baked:
//! - a record or a report that cannot be read (an I/O error such as too
//!   many open files; for the record, also a name that is not a regular
//!   file): an I/O error ([`SequenceError::Record`], [`SequenceError::Read`];
//!   exit 1), never a verdict on whose the folder is, and nothing is
//!   deleted, `--rebake` or not; a record read but not one aurora writes:
//!   [`SequenceError::BadRecord`] (exit 2);
//! - another bake's frame, or another bake's record: refused
//!   ([`SequenceError::OtherBake`], [`SequenceError::Claimed`]; exit 2)
//!   naming the first such frame (or the record) and how to go on: a new
//!   folder, or `--rebake`;
//! - with `--rebake` ([`Sequence::open`]'s `rebake`): every frame of another
//!   bake in the folder, in the range or not, is deleted (its report first,
//!   so no instant shows a report beside another bake's VDB; only regular
//!   files are removed), and so is every frame VDB without a report (an
//!   interrupted frame, of no known bake); the record becomes this bake's
//!   and the stage is written;
//! - a frame VDB without a report that aurora did not write (its grids
//!   carry none of our metadata: `crate::io::bake_folder::check_vdb_ours`,
//!   the single bake's rule), or a frame report without its VDB that is not
//!   one of ours (`crate::io::bake_folder::check_report_ours`), is refused
//!   (exit 2) naming it, `--rebake` or not: a bake replaces or deletes only
//!   its own files;
//! - the record is this bake's: the stage is written (this run's range);
//! - no record and no other bake's frame: nothing is written yet. The folder
//!   is claimed by the first frame committed ([`Sequence::write_frame`]),
//!   so a bake that fails before its first frame (a refused scene, a full
//!   disk, a stage that cannot be written: the record is then removed
//!   again) leaves nothing that stops the next one.
//!
//! **Committing a frame** ([`Sequence::write_frame`]). The frame is staged
//! in full (temporaries), then, under the folder lock, the record is read
//! again: absent, it is claimed (record and stage written); this bake's, the
//! frame is renamed into place; another's (a concurrent bake into the same
//! folder committed first, or a `--rebake` of another scene took the folder
//! over), the frame is dropped and the bake refused. Two different scenes
//! baked into one folder at once therefore end with exactly one of them
//! refused (the one that commits second), its frames never visible.
//!
//! The record is a file of its own (not the stage, whose bytes are pinned,
//! nor a frame): a hidden name beside `.aurora.lock`, so `aurora.*.json`
//! remains the frames' reports.

use crate::farm::frame_files::{FrameState, ReportError};
use crate::io::bake_folder::{BakeReport, OutputError, FRAME_STEM, LOCK_STEM, USDA_NAME};
use crate::pipeline::bake::identity::BakeIdentity;
use crate::pipeline::bake::Bake;
use crate::scene::Scene;
use crate::util::atomic_write::{AtomicError, UnitLock};
use std::path::{Path, PathBuf};

/// The folder's owner: `DIR/.aurora.sequence.json`.
pub const RECORD_NAME: &str = ".aurora.sequence.json";

/// How to go on when the folder is another bake's (every refusal says it).
const HOW: &str = "a sequence folder holds the frames of one bake: bake into a new folder (--out), or add --rebake to delete the other bake's frames and bake these";

#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    /// The folder holds a frame of another bake.
    #[error("{}: frame {frame} ({}) is not of this bake: {why}; {HOW}", dir.display(), report.display())]
    OtherBake { dir: PathBuf, frame: i64, report: PathBuf, why: String },
    /// The folder is claimed by another bake (its record names it), without
    /// a frame of it. `taken_over`: the record changed while this run baked.
    #[error("{}: the folder belongs to another bake ({}: {why}){}; {HOW}", dir.display(), record.display(), if *taken_over { ", which took it over while this one ran: this run's frame was not written" } else { "" })]
    Claimed { dir: PathBuf, record: PathBuf, why: String, taken_over: bool },
    /// The record was read and is not one aurora writes (not JSON, or it
    /// names no bake): whose the folder is cannot be told.
    #[error("{}: the folder's ownership record {} is not one aurora writes ({why}); remove it if the folder's frames are of this bake, or add --rebake to delete any other bake's frames and bake these", dir.display(), record.display())]
    BadRecord { dir: PathBuf, record: PathBuf, why: String },
    /// The record could not be read (the OS's error, or it is not a regular
    /// file): nothing is known about the folder's owner, nothing is deleted.
    #[error("cannot read {}, the sequence folder's ownership record: {cause}", record.display())]
    Record { record: PathBuf, cause: std::io::Error },
    /// A folder listing or a frame's report could not be read.
    #[error("cannot read {}: {cause}", path.display())]
    Read { path: PathBuf, cause: std::io::Error },
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl SequenceError {
    /// True when the user's choice of folder, or what it holds, is at fault
    /// (exit status 2).
    pub fn is_input(&self) -> bool {
        match self {
            SequenceError::OtherBake { .. } | SequenceError::Claimed { .. } | SequenceError::BadRecord { .. } => true,
            SequenceError::Record { .. } | SequenceError::Read { .. } => false,
            SequenceError::Output(o) => o.is_input(),
        }
    }
}

impl From<AtomicError> for SequenceError {
    fn from(e: AtomicError) -> Self {
        SequenceError::Output(OutputError::Output(e))
    }
}

/// Who the record says owns the folder.
#[derive(Debug, PartialEq)]
enum Owner {
    Nobody,
    Bake(BakeIdentity),
    /// A record that was read and is not one (the reason).
    NotARecord(String),
}

/// One run's view of a sequence folder (module docs).
#[derive(Debug)]
pub struct Sequence {
    dir: PathBuf,
    identity: BakeIdentity,
    frames: Vec<i64>,
    fps: f64,
    /// The per-line grids each frame holds (VDB names), listed in the stage.
    fields: Vec<(String, &'static str)>,
    /// This run has seen the record name its bake (and written the stage).
    claimed: bool,
}

impl Sequence {
    /// Opens `dir` (created if missing) for the sequence `frames` at `fps`
    /// of the bake `identity` (module docs, "Opening"), whose frames hold
    /// the grids `fields` (VDB name, USD type: `bake_folder::stage_fields`; listed in the stage).
    /// `on_wait` is called once if another process holds the folder's lock.
    pub fn open(
        dir: &Path,
        identity: BakeIdentity,
        frames: &[i64],
        fps: f64,
        fields: Vec<(String, &'static str)>,
        rebake: bool,
        on_wait: impl FnOnce(),
    ) -> Result<Sequence, SequenceError> {
        crate::util::atomic_write::prepare_folder(dir)?;
        let mut seq = Sequence { dir: dir.to_path_buf(), identity, frames: frames.to_vec(), fps, fields, claimed: false };
        let _lock = UnitLock::acquire(dir, LOCK_STEM, on_wait)?;
        // Everything that could stop this run is read and checked before
        // anything is deleted or baked: the record (a failed read stops
        // the run, exit 1), the stage's name, the frames' reports.
        let owner = seq.owner()?;
        crate::util::atomic_write::check_replaceable(&dir.join(USDA_NAME))?;
        let others = seq.other_frames()?;
        // A frame VDB without its report is an interrupted frame of ours,
        // baked again (or removed by --rebake), or a file aurora did not
        // write: refused, with or without --rebake, as a single bake
        // refuses a foreign `aurora.vdb`.
        for (vdb, report) in seq.orphan_vdbs()? {
            let report = report.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            crate::io::bake_folder::check_vdb_ours(&vdb, &report)?;
        }
        // So is a frame report without its VDB that is not a report of ours.
        for (vdb, report) in seq.frames_named("json")?.into_iter().map(|f| crate::farm::frame_files::frame_paths(dir, f)) {
            if std::fs::symlink_metadata(&vdb).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound) {
                crate::io::bake_folder::check_report_ours(&report)?;
            }
        }
        if rebake {
            for (frame, report, _) in &others {
                let (vdb, _) = crate::farm::frame_files::frame_paths(dir, *frame);
                remove_regular(report)?;
                remove_regular(&vdb)?;
            }
            for (vdb, _) in seq.orphan_vdbs()? {
                remove_regular(&vdb)?;
            }
            seq.claim()?;
            return Ok(seq);
        }
        if let Some((frame, report, why)) = others.into_iter().next() {
            return Err(SequenceError::OtherBake { dir: dir.to_path_buf(), frame, report, why });
        }
        match owner {
            Owner::Nobody => Ok(seq),
            Owner::Bake(id) if id == seq.identity => {
                seq.write_stage()?;
                seq.claimed = true;
                Ok(seq)
            }
            other => Err(seq.claimed_error(other, false)),
        }
    }

    /// The bake identity this run bakes.
    pub fn identity(&self) -> &BakeIdentity {
        &self.identity
    }

    /// Frame `frame`'s state for this bake ([`crate::farm::frame_files::frame_state`]):
    /// complete, absent, or a VDB that does not match its report.
    pub fn frame_state(&self, frame: i64) -> Result<FrameState, SequenceError> {
        crate::farm::frame_files::frame_state(&self.dir, frame, &self.identity).map_err(report_error)
    }

    /// Fails if another bake owns the folder now (a `--rebake` took it over):
    /// a cheap check without the lock before a frame's bake, so a run that
    /// lost the folder stops at once; [`Self::write_frame`] checks again
    /// under the lock.
    pub fn check_still_ours(&self) -> Result<(), SequenceError> {
        match self.owner()? {
            Owner::Nobody => Ok(()),
            Owner::Bake(id) if id == self.identity => Ok(()),
            other => Err(self.lost(other)?),
        }
    }

    /// Stages frame `frame` (`scene` at its time) and commits it if the
    /// folder is, or now becomes, this bake's (module docs, "Committing a
    /// frame"). The caller holds the frame's lock ([`crate::farm::frame_files::lock_frame`]).
    pub fn write_frame(&mut self, scene: &Scene, bake: &Bake, frame: i64) -> Result<BakeReport, SequenceError> {
        let staged = crate::farm::frame_files::stage_frame(scene, bake, &self.dir, frame, &self.identity)?;
        let _lock = UnitLock::acquire(&self.dir, LOCK_STEM, || {})?;
        match self.owner()? {
            Owner::Bake(id) if id == self.identity => {
                if !self.claimed {
                    self.write_stage()?;
                    self.claimed = true;
                }
            }
            Owner::Nobody => {
                if let Some((frame, report, why)) = self.other_frames()?.into_iter().next() {
                    return Err(SequenceError::OtherBake { dir: self.dir.clone(), frame, report, why });
                }
                self.claim()?;
            }
            other => return Err(self.lost(other)?),
        }
        Ok(staged.commit()?)
    }

    fn record_path(&self) -> PathBuf {
        self.dir.join(RECORD_NAME)
    }

    /// Who the record names. Only a record that was read can name a bake or
    /// be found not to be one; a failure to read it (an I/O error such as
    /// too many open files, or a name that is not a regular file: only
    /// those are ours) is an error of its own, never a verdict about the
    /// folder.
    fn owner(&self) -> Result<Owner, SequenceError> {
        let record = self.record_path();
        let failed = |cause| SequenceError::Record { record: record.clone(), cause };
        match std::fs::symlink_metadata(&record) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Owner::Nobody),
            Err(e) => return Err(failed(e)),
            Ok(m) if !m.is_file() => {
                let kind = crate::util::input_file::kind_name(m.file_type());
                return Err(failed(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("is {kind}, not a regular file"))));
            }
            Ok(_) => {}
        }
        let bytes = crate::util::input_file::read(&record).map_err(|e| failed(e.into()))?;
        Ok(match serde_json::from_slice::<serde_json::Value>(&bytes) {
            Err(e) => Owner::NotARecord(format!("not JSON: {e}")),
            Ok(j) => match BakeIdentity::from_report(&j) {
                Some(id) => Owner::Bake(id),
                None => Owner::NotARecord("it names no bake identity".into()),
            },
        })
    }

    /// The refusal when `owner`, another bake, has the folder: taken over
    /// from this run (it had claimed it), else named by the owner's first
    /// frame, or by the record when there is none.
    fn lost(&self, owner: Owner) -> Result<SequenceError, SequenceError> {
        if !self.claimed {
            if let Some((frame, report, why)) = self.other_frames()?.into_iter().next() {
                return Ok(SequenceError::OtherBake { dir: self.dir.clone(), frame, report, why });
            }
        }
        Ok(self.claimed_error(owner, self.claimed))
    }

    fn claimed_error(&self, owner: Owner, taken_over: bool) -> SequenceError {
        let why = match owner {
            Owner::Bake(id) => format!("it names {}", self.identity.difference(&id)),
            Owner::NotARecord(why) => return SequenceError::BadRecord { dir: self.dir.clone(), record: self.record_path(), why },
            Owner::Nobody => "it is gone".into(),
        };
        SequenceError::Claimed { dir: self.dir.clone(), record: self.record_path(), why, taken_over }
    }

    /// Makes the folder this bake's: the record (unless it names this bake
    /// already), then the stage. The caller holds the folder's lock. If the
    /// stage cannot be written, a record this call wrote is removed again
    /// (the folder is claimed by its first frame, which is not written).
    fn claim(&mut self) -> Result<(), SequenceError> {
        let wrote_record = self.owner()? != Owner::Bake(self.identity.clone());
        if wrote_record {
            let record = serde_json::json!({ "bake_identity": self.identity.to_json() });
            let text = serde_json::to_string_pretty(&record).expect("json serialises") + "\n";
            crate::util::atomic_write::write_atomic(&self.record_path(), text.as_bytes())?;
        }
        if let Err(e) = self.write_stage() {
            if wrote_record {
                let _ = remove_regular(&self.record_path());
            }
            return Err(e);
        }
        self.claimed = true;
        Ok(())
    }

    fn write_stage(&self) -> Result<(), SequenceError> {
        crate::farm::frame_files::write_sequence_usda(&self.dir, &self.frames, self.fps, &self.fields)?;
        Ok(())
    }

    /// The frame numbers of the folder's names `aurora.NNNN.EXT`.
    fn frames_named(&self, ext: &str) -> Result<Vec<i64>, SequenceError> {
        let failed = |cause| SequenceError::Read { path: self.dir.clone(), cause };
        let mut frames = Vec::new();
        for entry in std::fs::read_dir(&self.dir).map_err(failed)? {
            if let Some(f) = frame_of_name(&entry.map_err(failed)?.file_name().to_string_lossy(), ext) {
                frames.push(f);
            }
        }
        Ok(frames)
    }

    /// Frame VDBs without a report (with the report's path): frames
    /// interrupted between their two renames, of no known bake, or files
    /// aurora did not write ([`Self::open`] refuses those); `--rebake`
    /// removes ours with the other bake's frames (in the range they would
    /// be baked again anyway).
    fn orphan_vdbs(&self) -> Result<Vec<(PathBuf, PathBuf)>, SequenceError> {
        Ok(self
            .frames_named("vdb")?
            .into_iter()
            .map(|f| crate::farm::frame_files::frame_paths(&self.dir, f))
            .filter(|(_, report)| std::fs::symlink_metadata(report).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound))
            .collect())
    }

    /// The folder's complete frames (both files present) that are not of
    /// this bake, ascending: (frame, report path, why not).
    fn other_frames(&self) -> Result<Vec<(i64, PathBuf, String)>, SequenceError> {
        let mut out = Vec::new();
        for frame in self.frames_named("json")? {
            let (vdb, report) = crate::farm::frame_files::frame_paths(&self.dir, frame);
            if std::fs::symlink_metadata(&vdb).is_err() {
                // No VDB: not a frame (an interrupted one is baked again).
                continue;
            }
            let why = match crate::farm::frame_files::frame_identity(&report) {
                Ok(id) if id == self.identity => continue,
                Ok(id) => format!("it was baked from {}", self.identity.difference(&id)),
                Err(ReportError::NotABake { why, .. }) => why,
                Err(e) => return Err(report_error(e)),
            };
            out.push((frame, report, why));
        }
        out.sort_by_key(|o| o.0);
        Ok(out)
    }
}

/// A report that could not be read is an I/O error (exit 1); one that is
/// not a report is the folder's content ([`SequenceError::OtherBake`] says
/// so where it is found).
fn report_error(e: ReportError) -> SequenceError {
    match e {
        ReportError::Unreadable { path, cause } => SequenceError::Read { path, cause },
        ReportError::NotABake { path, why } => {
            SequenceError::Read { path, cause: std::io::Error::new(std::io::ErrorKind::InvalidData, why) }
        }
    }
}

/// Removes `path` if it is a regular file (only those are ours to remove);
/// gone already is fine.
fn remove_regular(path: &Path) -> Result<(), SequenceError> {
    crate::util::atomic_write::check_replaceable(path)?;
    match std::fs::remove_file(path) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(source) => Err(AtomicError::Io { path: path.to_path_buf(), source }.into()),
    }
}

/// The frame number of a frame file's name (`aurora.NNNN.EXT`, at least
/// four digits, as `crate::farm::frame_range::frame_file_name` writes it), if it is one.
fn frame_of_name(name: &str, ext: &str) -> Option<i64> {
    let digits = name.strip_prefix(FRAME_STEM)?.strip_prefix('.')?.strip_suffix(ext)?.strip_suffix('.')?;
    if digits.len() < 4 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let frame = digits.parse().ok()?;
    (crate::farm::frame_range::frame_file_name(FRAME_STEM, frame, ext) == name).then_some(frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A claim whose stage cannot be written (a directory in its place,
    /// put there after the folder was opened) takes the record back: the
    /// folder holds what it held before, nothing of this bake.
    #[test]
    fn a_claim_whose_stage_cannot_be_written_leaves_no_record() {
        let dir = crate::util::scratch::folder("claim", "stage");
        let scene = Scene::default();
        let fields = crate::io::bake_folder::stage_fields(&scene);
        let mut seq = Sequence::open(&dir, BakeIdentity::of(&scene), &[1, 2], 24.0, fields, false, || {}).unwrap();
        std::fs::create_dir(dir.join(USDA_NAME)).unwrap();
        let e = seq.claim().unwrap_err();
        assert!(e.to_string().contains("aurora.usda") && e.is_input(), "{e}");
        assert_eq!(crate::util::scratch::file_names(&dir), [USDA_NAME]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn frame_reports_are_recognised_by_name() {
        assert_eq!(frame_of_name("aurora.0001.json", "json"), Some(1));
        assert_eq!(frame_of_name("aurora.12345.json", "json"), Some(12345));
        assert_eq!(frame_of_name("aurora.0007.vdb", "vdb"), Some(7));
        for n in [
            "aurora.001.json",
            "aurora.0001.vdb",
            "bake.json",
            ".aurora.sequence.json",
            "aurora.00a1.json",
            "aurora.00001.json",
            "aurora.0001xjson",
        ] {
            assert_eq!(frame_of_name(n, "json"), None, "{n}");
        }
    }
}
