//! A frame sequence baked into one folder (`aurora bake --frames`, and the
//! Python module's `bake(..., frames=...)`): this process's share of the
//! frames, resumed frame by frame. A frame already complete for this bake
//! is skipped, one whose VDB is not the file its report records (size,
//! header UUID: `crate::farm::frame_files::frame_state`) is baked again
//! with a warning, one another process is baking is waited for
//! (`crate::farm::sequence_folder`, `crate::farm::frame_files::lock_frame`).
//! Frame `N` is the scene at `animation.time_s + (N - 1) / fps`
//! (`crate::pipeline::motion::at_frame`); one plan is carried from frame to
//! frame, as only the time changes.

use crate::farm::frame_files::FrameState;
use crate::farm::sequence_folder::{Sequence, SequenceError};
use crate::io::bake_folder::OutputError;
use crate::pipeline::bake::BakeError;
use crate::scene::Scene;
use crate::util::progress::Progress;
use std::path::Path;

/// Where a sequence's bake says what it does: the bake's progress, lines
/// for a person, warnings, and the frames done.
pub trait SequenceReport {
    fn progress(&self) -> &dyn Progress;
    /// A line for a person (built only if it is shown).
    fn say(&self, line: &dyn Fn() -> String);
    fn warnings(&self, warnings: &[String]);
    /// `done` of `total` frames of this share are complete.
    fn frames(&self, done: usize, total: usize);
}

/// Why a sequence could not be baked: the folder, a frame's files, or a bake.
#[derive(Debug, thiserror::Error)]
pub enum SequenceBakeError {
    #[error(transparent)]
    Sequence(#[from] SequenceError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Bake(#[from] BakeError),
}

impl SequenceBakeError {
    /// As the error inside says (exit status 2 for the user's input).
    pub fn is_input(&self) -> bool {
        match self {
            SequenceBakeError::Sequence(e) => e.is_input(),
            SequenceBakeError::Output(e) => e.is_input(),
            SequenceBakeError::Bake(e) => e.is_input(),
        }
    }
}

/// What a sequence's bake did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SequenceTally {
    pub baked: usize,
    pub skipped: usize,
    pub mismatched: usize,
}

/// Bakes this process's share `mine` of the sequence `frames` into `out`
/// (a folder of one bake: `crate::farm::sequence_folder`; `rebake` deletes another's).
pub fn bake_frames(
    scene: &Scene,
    out: &Path,
    frames: &[i64],
    mine: &[i64],
    rebake: bool,
    say: &dyn SequenceReport,
) -> Result<SequenceTally, SequenceBakeError> {
    let progress = say.progress();
    let identity = crate::pipeline::bake::identity::BakeIdentity::of(scene);
    let fields = crate::io::bake_folder::stage_fields(scene);
    let mut seq = Sequence::open(out, identity, frames, scene.animation.fps, fields, rebake, || {
        say.say(&|| format!("aurora: another bake is writing to {}; waiting", out.display()))
    })?;
    say.frames(0, mine.len());
    let mut n = SequenceTally::default();
    let mut plan: Option<crate::pipeline::plan::BakePlan> = None;
    for &f in mine {
        if seq.frame_state(f)? == FrameState::Complete {
            n.skipped += 1;
            say.frames(n.baked + n.skipped, mine.len());
            continue;
        }
        seq.check_still_ours()?;
        // One writer per frame: a shard that finds another baking it waits,
        // then finds it complete.
        let _lock =
            crate::farm::frame_files::lock_frame(out, f, || say.say(&|| format!("frame {f}: another process is baking it; waiting")))?;
        match seq.frame_state(f)? {
            FrameState::Complete => {
                n.skipped += 1;
                say.frames(n.baked + n.skipped, mine.len());
                continue;
            }
            FrameState::Mismatch(why) => {
                n.mismatched += 1;
                say.warnings(&[format!("frame {f}: {why}; baking it again")]);
            }
            FrameState::Absent => {}
        }
        let at = Scene { animation: crate::pipeline::motion::at_frame(&scene.animation, f), ..scene.clone() };
        let (bake, p) = crate::pipeline::bake::bake_reusing(&at, plan.as_ref(), progress)?;
        plan = Some(p);
        say.warnings(&bake.stats.warnings);
        let report = seq.write_frame(&at, &bake, f)?;
        n.baked += 1;
        say.say(&|| format!("frame {f} (t = {:.4} s): {}", at.animation.time_s, report.vdb.display()));
        say.frames(n.baked + n.skipped, mine.len());
    }
    if n.mismatched > 0 {
        say.warnings(&[format!(
            "{} frames baked again: their VDB was not the file their report records (its size in bytes and header UUID)",
            n.mismatched
        )]);
    }
    Ok(n)
}
