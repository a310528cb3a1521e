//! USD stage for the baked volume: `aurora.usda` beside the VDB, one
//! `UsdVol.Volume` prim whose fields are `OpenVDBAsset` prims pointing into
//! the single VDB file (Blender keeps only one file per volume; see
//! docs/guide.md, "How Cycles reads the VDB").
//!
//! A frame sequence (`aurora bake --frames`) gets one stage whose fields'
//! `filePath` is time-sampled, one sample per frame file
//! ([`usda_sequence_text`]). One writer makes both: a single bake is a
//! one-sample sequence without timing. It writes line by line into a
//! buffered temporary ([`write_usda_sequence`]) or any sink
//! ([`write_usda_sequence_into`]), so a stage of ten million frames (about
//! 90 bytes a frame and field) costs its buffer in memory, not its length.
//!
//! Schema facts (usd-core's `usdVol/generatedSchema.usda`): `fieldClass` is a
//! token among `levelSet`, `fogVolume`, `staggered`, `unknown`;
//! `fieldDataType` a token such as `float` or `float3`; `filePath` an asset
//! path, written as the file's bare name, which resolves against the
//! stage's own folder whatever that folder is called ([`asset`]); the
//! Volume links each field through a `field:<name>` relationship. The text is
//! what usd-core's `ExportToString` writes for the same stage.
//!
//! Transform: none on the prim (identity). The VDB's own grid transform
//! already maps voxel indices to world coordinates in kilometres, z up, so the
//! stage declares `metersPerUnit = 1000` and `upAxis = "Z"`.

use std::io::Write;
use std::path::Path;

/// Name of the `Volume` prim (and the stage's default prim).
pub const VOLUME_PRIM: &str = "aurora";

/// Data types accepted for `fieldDataType`.
const DATA_TYPES: &[&str] = &["float", "float3", "half", "half3", "double", "double3"];

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_') && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn invalid(msg: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, msg)
}

/// Checks what goes into the text: prim names must be USD identifiers, the
/// asset path a file name beside the stage ([`asset`]) without `@`, a
/// backslash or a line break, data types must be known.
fn check(vdb_file_name: &str, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<(), std::io::Error> {
    if vdb_file_name.is_empty() || vdb_file_name.contains(['@', '\n', '\r', '/', '\\']) || matches!(vdb_file_name, "." | "..") {
        return Err(invalid(format!(
            "VDB file name `{vdb_file_name}` must be a file name beside the stage (no folder, `@`, backslash or line break)"
        )));
    }
    for (i, (name, ty)) in fields.iter().enumerate() {
        if !is_identifier(name) || fields[..i].iter().any(|(n, _)| n == name) {
            return Err(invalid(format!("field name `{name}` is not a unique USD identifier")));
        }
        if !DATA_TYPES.contains(ty) {
            return Err(invalid(format!("field `{name}`: data type `{ty}` is not one of {DATA_TYPES:?}")));
        }
    }
    if !(meters_per_unit.is_finite() && meters_per_unit > 0.0) {
        return Err(invalid(format!("metersPerUnit {meters_per_unit} must be positive")));
    }
    Ok(())
}

/// What the fields' `filePath` holds. A single bake is a one-sample
/// sequence without timing: one file for every time, `filePath` a plain
/// asset and no time codes on the stage.
#[derive(Clone, Copy)]
enum Samples<'a> {
    /// A single bake: the VDB's name relative to the stage.
    Single(&'a str),
    /// A sequence.
    Sequence(Sequence<'a>),
}

/// A frame sequence's time samples: its frames, ascending; each frame's VDB
/// file name relative to the stage, made when its line is written (nothing
/// is kept per frame); its fps.
#[derive(Clone, Copy)]
pub struct Sequence<'a> {
    pub frames: &'a [i64],
    pub name: &'a dyn Fn(i64) -> String,
    pub fps: f64,
}

/// The asset path of the file `name` beside the stage: the bare name,
/// which USD's resolver anchors to the stage's own folder. Not `./name`:
/// the resolver normalises an anchored `./` or `../` path with the stage's
/// folder, and a backslash anywhere in that folder's path (a legal
/// character in a POSIX name) is taken for a separator there, so the path
/// no longer resolves; the bare name resolves in any folder (`@`, spaces,
/// quotes, colons and backslashes in its path included: tested with
/// usd-core). The folder's path is never written into the stage.
fn asset(name: &str) -> &str {
    name
}

/// The one writer of stage text (single bake and sequence), line by line
/// into `w`: what it holds at any time is one line, however many frames
/// the sequence has (callers buffer `w`). Stage metadata in the order
/// usd-core's `ExportToString` sorts it.
fn write_stage(w: &mut dyn Write, samples: Samples<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> std::io::Result<()> {
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(w, "    defaultPrim = \"{VOLUME_PRIM}\"")?;
    match samples {
        Samples::Single(file) => {
            writeln!(w, "    doc = \"Aurora volume written by {}; fields in {}\"", crate::io::vdb::write::CREATOR, asset(file))?;
        }
        Samples::Sequence(Sequence { frames, fps, .. }) => {
            let (first, last) = (frames.first().map_or(0, |f| *f), frames.last().map_or(0, |f| *f));
            writeln!(
                w,
                "    doc = \"Aurora volume sequence written by {}: frames {first} to {last}, {} files\"",
                crate::io::vdb::write::CREATOR,
                frames.len()
            )?;
            writeln!(w, "    endTimeCode = {last}")?;
            writeln!(w, "    framesPerSecond = {}", fmt_number(fps))?;
        }
    }
    writeln!(w, "    metersPerUnit = {}", fmt_number(meters_per_unit))?;
    if let Samples::Sequence(Sequence { frames, fps, .. }) = samples {
        writeln!(w, "    startTimeCode = {}", frames.first().map_or(0, |f| *f))?;
        writeln!(w, "    timeCodesPerSecond = {}", fmt_number(fps))?;
    }
    writeln!(w, "    upAxis = \"Z\"")?;
    writeln!(w, ")")?;
    writeln!(w)?;
    writeln!(w, "def Volume \"{VOLUME_PRIM}\"")?;
    writeln!(w, "{{")?;
    for (name, _) in fields {
        writeln!(w, "    custom rel field:{name} = </{VOLUME_PRIM}/{name}>")?;
    }
    for (name, ty) in fields {
        writeln!(w)?;
        writeln!(w, "    def OpenVDBAsset \"{name}\"")?;
        writeln!(w, "    {{")?;
        writeln!(w, "        token fieldClass = \"fogVolume\"")?;
        writeln!(w, "        token fieldDataType = \"{ty}\"")?;
        writeln!(w, "        token fieldName = \"{name}\"")?;
        match samples {
            Samples::Single(file) => writeln!(w, "        asset filePath = @{}@", asset(file))?,
            Samples::Sequence(Sequence { frames, name, .. }) => {
                writeln!(w, "        asset filePath.timeSamples = {{")?;
                for &f in frames {
                    writeln!(w, "            {f}: @{}@,", asset(&name(f)))?;
                }
                writeln!(w, "        }}")?;
            }
        }
        writeln!(w, "    }}")?;
    }
    writeln!(w, "}}")
}

/// Checks every input of [`write_stage`] before a byte is written: frames
/// non-empty and ascending, fps finite and positive, and each file name,
/// field and unit as [`check`] wants them.
fn check_samples(samples: Samples<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<(), std::io::Error> {
    match samples {
        Samples::Single(file) => check(file, fields, meters_per_unit),
        Samples::Sequence(Sequence { frames, name, fps }) => {
            if frames.is_empty() || frames.windows(2).any(|w| w[1] <= w[0]) {
                return Err(invalid("a sequence needs at least one frame, in ascending order".into()));
            }
            if !(fps.is_finite() && fps > 0.0) {
                return Err(invalid(format!("fps {fps} must be positive")));
            }
            check("x", fields, meters_per_unit)?;
            frames.iter().try_for_each(|&f| check(&name(f), &[], meters_per_unit))
        }
    }
}

/// The text of a stage in memory (for small stages and tests: a sequence's
/// stage is written by [`write_usda_sequence`] or
/// [`write_usda_sequence_into`] without holding its text).
fn stage_text(samples: Samples<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> String {
    let mut bytes = Vec::new();
    write_stage(&mut bytes, samples, fields, meters_per_unit).expect("writing into memory cannot fail");
    String::from_utf8(bytes).expect("the stage is UTF-8")
}

/// Writes `samples`' stage to `path` atomically: streamed through a
/// buffered writer into a temporary beside it, then renamed (a failure
/// removes the temporary).
fn write_file(path: &Path, samples: Samples<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<(), std::io::Error> {
    check_samples(samples, fields, meters_per_unit)?;
    let mut tmp = crate::util::atomic_write::TempFile::create(path)?;
    let mut w = std::io::BufWriter::with_capacity(STREAM_BUFFER, tmp.file());
    write_stage(&mut w, samples, fields, meters_per_unit)?;
    w.flush()?;
    drop(w);
    tmp.commit().map_err(Into::into)
}

/// The buffer between the stage writer and its file, bytes: what a stage
/// costs in memory, whatever its length.
pub const STREAM_BUFFER: usize = 64 * 1024;

/// The stage text of a single bake. `vdb_file_name` is relative to the
/// stage's folder; `fields` are (grid name, data type: `"float"` |
/// `"float3"`). Call [`write_usda`] to have the inputs validated.
pub fn usda_text(vdb_file_name: &str, fields: &[(&str, &str)], meters_per_unit: f64) -> String {
    stage_text(Samples::Single(vdb_file_name), fields, meters_per_unit)
}

/// The stage of a frame sequence: the same prims, each field's `filePath`
/// time-sampled, one sample per frame of `seq` (its `frames` ascending,
/// `name(frame)` its VDB file name relative to the stage); `startTimeCode`
/// and `endTimeCode` are the first and last frame, `timeCodesPerSecond` and
/// `framesPerSecond` the sequence's fps. USD has no `####` substitution:
/// every frame is listed (openusd.org, UsdVol OpenVDBAsset). In memory, for
/// short sequences; [`write_usda_sequence`] streams a sequence of any length.
pub fn usda_sequence_text(seq: Sequence<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> String {
    stage_text(Samples::Sequence(seq), fields, meters_per_unit)
}

/// Writes a sequence's stage (see [`usda_sequence_text`]) into `w`, line by
/// line, after checking its inputs (frames non-empty and ascending, fps
/// finite and positive): nothing is written when they are refused, and no
/// more than one line is held whatever the number of frames.
pub fn write_usda_sequence_into(
    w: &mut dyn Write,
    seq: Sequence<'_>,
    fields: &[(&str, &str)],
    meters_per_unit: f64,
) -> Result<(), std::io::Error> {
    let samples = Samples::Sequence(seq);
    check_samples(samples, fields, meters_per_unit)?;
    write_stage(w, samples, fields, meters_per_unit)
}

/// Writes a sequence stage to `path` atomically (see [`usda_sequence_text`]):
/// streamed to a temporary through a [`STREAM_BUFFER`]-byte buffer, then
/// renamed, so its memory does not grow with the number of frames.
pub fn write_usda_sequence(path: &Path, seq: Sequence<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<(), std::io::Error> {
    write_file(path, Samples::Sequence(seq), fields, meters_per_unit)
}

/// A number as USD writes it: integers without a decimal point.
fn fmt_number(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}

/// Writes the stage of a single bake atomically (temporary file in the same
/// folder, then rename).
pub fn write_usda(path: &Path, vdb_file_name: &str, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<(), std::io::Error> {
    write_file(path, Samples::Single(vdb_file_name), fields, meters_per_unit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_matches_usd_core_export() {
        let t = usda_text("aurora.vdb", &[("density", "float"), ("emission", "float3")], 1000.0);
        // The body, exactly as usd-core's ExportToString writes it.
        let body = r#"def Volume "aurora"
{
    custom rel field:density = </aurora/density>
    custom rel field:emission = </aurora/emission>

    def OpenVDBAsset "density"
    {
        token fieldClass = "fogVolume"
        token fieldDataType = "float"
        token fieldName = "density"
        asset filePath = @aurora.vdb@
    }

    def OpenVDBAsset "emission"
    {
        token fieldClass = "fogVolume"
        token fieldDataType = "float3"
        token fieldName = "emission"
        asset filePath = @aurora.vdb@
    }
}
"#;
        assert!(t.ends_with(body), "{t}");
        assert!(t.starts_with("#usda 1.0\n(\n    defaultPrim = \"aurora\"\n"));
        assert!(t.contains("    metersPerUnit = 1000\n    upAxis = \"Z\"\n)"));
        assert_eq!(fmt_number(0.01), "0.01");
    }

    fn name(f: i64) -> String {
        format!("aurora.{f:04}.vdb")
    }

    fn seq<'a>(frames: &'a [i64], name: &'a dyn Fn(i64) -> String, fps: f64) -> Sequence<'a> {
        Sequence { frames, name, fps }
    }

    #[test]
    fn sequence_lists_every_frame_as_a_time_sample() {
        let frames = [1, 2, 3];
        let t = usda_sequence_text(seq(&frames, &name, 24.0), &[("density", "float")], 1000.0);
        assert!(t.contains("    endTimeCode = 3\n    framesPerSecond = 24\n    metersPerUnit = 1000\n    startTimeCode = 1\n    timeCodesPerSecond = 24\n"), "{t}");
        assert!(t.contains("        asset filePath.timeSamples = {\n            1: @aurora.0001.vdb@,\n            2: @aurora.0002.vdb@,\n            3: @aurora.0003.vdb@,\n        }\n"), "{t}");
        let p = std::env::temp_dir().join("aurora-usd-seq-never-written.usda");
        let fields = [("density", "float")];
        assert!(write_usda_sequence(&p, seq(&[], &name, 24.0), &fields, 1000.0).is_err());
        assert!(write_usda_sequence(&p, seq(&[2, 1], &name, 24.0), &fields, 1000.0).is_err());
        assert!(write_usda_sequence(&p, seq(&frames, &name, 0.0), &fields, 1000.0).is_err());
        assert!(write_usda_sequence(&p, seq(&frames, &|_| "a@b.vdb".into(), 24.0), &fields, 1000.0).is_err());
        assert!(!p.exists());
        // Refused inputs write nothing into a sink either.
        let mut sink = Vec::new();
        assert!(write_usda_sequence_into(&mut sink, seq(&[2, 1], &name, 24.0), &fields, 1000.0).is_err());
        assert!(sink.is_empty());
    }

    #[test]
    fn bad_inputs_are_refused() {
        let p = std::env::temp_dir().join("aurora-usd-test-never-written.usda");
        assert!(write_usda(&p, "a@b.vdb", &[("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "/abs/a.vdb", &[("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "./a.vdb", &[("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a\\b.vdb", &[("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("1density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("density", "float"), ("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("density", "vec3")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("density", "float")], 0.0).is_err());
        assert!(!p.exists());
    }
}
