//! Frame ranges on the command line: `--frames`/`--frame` and `--shard`
//! turned into frame numbers, and the file name of one frame of an output.

use super::exit::InputError;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// The frames of SPEC (exit 2 on bad syntax or a negative frame) and the
/// share `--shard` gives this process.
pub fn frame_selection(spec: &str, shard: Option<&str>) -> Result<(Vec<i64>, Vec<i64>)> {
    let s = selection(spec, shard)?;
    Ok((s.frames, s.mine))
}

/// A frame range and this process's share of it.
pub struct Selection {
    /// Every frame of SPEC, ascending.
    pub frames: Vec<i64>,
    /// The frames `--shard` gives this process (all of them without one).
    pub mine: Vec<i64>,
    /// The shard, (index, count), when one was given.
    pub shard: Option<(u64, u64)>,
}

/// [`frame_selection`], with the shard it resolved.
pub fn selection(spec: &str, shard: Option<&str>) -> Result<Selection> {
    let frames = aurora::farm::frame_range::parse_range(spec).map_err(|e| InputError(e.to_string()))?;
    if let Some(f) = frames.iter().find(|&&f| f < 0) {
        return Err(InputError(format!(
            "--frames `{spec}`: frame {f} is negative; frame files are named by frame number (aurora.0001.vdb), so frames must be >= 0"
        ))
        .into());
    }
    let shard = match shard {
        None => None,
        Some(t) => Some(
            aurora::farm::frame_range::Shard::parse(t)
                .and_then(|s| s.resolve(|k| std::env::var(k).ok()))
                .map_err(|e| InputError(e.to_string()))?,
        ),
    };
    let (i, n) = shard.unwrap_or((0, 1));
    let mine = aurora::farm::frame_range::select(&frames, i, n);
    Ok(Selection { frames, mine, shard })
}

/// `name.ext` -> `name.NNNN.ext` (the frame before the extension); a file
/// name holding a run of `#` gets the frame there instead, zero-padded to
/// the run's length: `show_#####.png` -> `show_00001.png`, the names a
/// fulldome show file's frames take (checked first by [`frame_pattern`]).
pub fn frame_name(path: &Path, frame: i64) -> PathBuf {
    let name = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if let Some((start, len)) = hash_run(&name) {
        return path.with_file_name(format!("{}{frame:0len$}{}", &name[..start], &name[start + len..]));
    }
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "frame".into());
    let ext = path.extension().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(aurora::farm::frame_range::frame_file_name(&stem, frame, &ext))
}

/// The byte offset and length of the run of `#` in a file name, if any.
fn hash_run(name: &str) -> Option<(usize, usize)> {
    let start = name.find('#')?;
    let len = name[start..].bytes().take_while(|&b| b == b'#').count();
    Some((start, len))
}

/// Checks an output name against the frames it will be written for: a name
/// with a `#` run numbers frames, so it needs `--frame` (`frames` None
/// without), one run only, and enough `#` for the largest frame (a wider
/// number would break the sequence's sort order and its reader's pattern).
/// `flag` names the option in the message.
pub fn frame_pattern(flag: &str, path: &Path, frames: Option<&[i64]>) -> Result<(), InputError> {
    let name = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let Some((start, len)) = hash_run(&name) else { return Ok(()) };
    if name[start + len..].contains('#') {
        return Err(InputError(format!(
            "{flag} {}: more than one run of # in the name; one run (show_#####.png) takes the frame number",
            path.display()
        )));
    }
    let Some(frames) = frames else {
        return Err(InputError(format!("{flag} {}: a run of # takes a frame number; give --frame with a sequence folder", path.display())));
    };
    if let Some(&widest) = frames.iter().max() {
        let digits = widest.to_string().len();
        if digits > len {
            return Err(InputError(format!(
                "{flag} {}: frame {widest} has {digits} digits but the name has {len} #; give at least {digits}",
                path.display()
            )));
        }
    }
    Ok(())
}
