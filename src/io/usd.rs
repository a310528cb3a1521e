//! USD stage for the baked volume: `aurora.usda` beside the VDB, one
//! `UsdVol.Volume` prim whose fields are `OpenVDBAsset` prims pointing into
//! the single VDB file (Blender keeps only one file per volume; see
//! docs/guide.md, "How Cycles reads the VDB").
//!
//! A frame sequence (`aurora bake --frames`) gets one stage whose fields'
//! `filePath` is time-sampled, one sample per frame file
//! ([`usda_sequence_text`]). One writer makes both: a single bake is a
//! one-sample sequence without timing.
//!
//! Schema facts (usd-core's `usdVol/generatedSchema.usda`): `fieldClass` is a
//! token among `levelSet`, `fogVolume`, `staggered`, `unknown`;
//! `fieldDataType` a token such as `float` or `float3`; `filePath` an asset
//! path, written `./name` so it resolves against the stage's own folder; the
//! Volume links each field through a `field:<name>` relationship. The text is
//! what usd-core's `ExportToString` writes for the same stage.
//!
//! Transform: none on the prim (identity). The VDB's own grid transform
//! already maps voxel indices to world coordinates in kilometres, z up, so the
//! stage declares `metersPerUnit = 1000` and `upAxis = "Z"`.

use std::fmt::Write as _;
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
/// asset path must not contain `@` or line breaks, data types must be known.
fn check(vdb_file_name: &str, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<(), std::io::Error> {
    if vdb_file_name.is_empty() || vdb_file_name.contains(['@', '\n', '\r']) || Path::new(vdb_file_name).is_absolute() {
        return Err(invalid(format!("VDB file name `{vdb_file_name}` must be a non-empty relative path without `@`")));
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

/// What the fields' `filePath` holds: the frames' VDB files (frame number,
/// file name relative to the stage) and, for a sequence, its fps. A single
/// bake is a one-sample sequence without timing: one file for every time,
/// `filePath` a plain asset and no time codes on the stage.
struct Samples<'a> {
    frames: Vec<(i64, &'a str)>,
    /// `None`: a single bake (exactly one frame, untimed).
    fps: Option<f64>,
}

/// `./name` unless the name already starts at `.` or `..`, so the path
/// resolves against the stage's own folder.
fn asset(name: &str) -> String {
    if name.starts_with("./") || name.starts_with("../") {
        name.to_string()
    } else {
        format!("./{name}")
    }
}

/// The one writer of stage text (single bake and sequence). Stage metadata
/// in the order usd-core's `ExportToString` sorts it.
fn stage_text(samples: &Samples<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> String {
    let frames = &samples.frames;
    let (first, last) = (frames.first().map_or(0, |f| f.0), frames.last().map_or(0, |f| f.0));
    let mut s = String::new();
    let _ = writeln!(s, "#usda 1.0");
    let _ = writeln!(s, "(");
    let _ = writeln!(s, "    defaultPrim = \"{VOLUME_PRIM}\"");
    match samples.fps {
        None => {
            let _ = writeln!(
                s,
                "    doc = \"Aurora volume written by {}; fields in {}\"",
                crate::io::vdb::write::CREATOR,
                asset(frames.first().map_or("", |f| f.1))
            );
        }
        Some(fps) => {
            let _ = writeln!(
                s,
                "    doc = \"Aurora volume sequence written by {}: frames {first} to {last}, {} files\"",
                crate::io::vdb::write::CREATOR,
                frames.len()
            );
            let _ = writeln!(s, "    endTimeCode = {last}");
            let _ = writeln!(s, "    framesPerSecond = {}", fmt_number(fps));
        }
    }
    let _ = writeln!(s, "    metersPerUnit = {}", fmt_number(meters_per_unit));
    if let Some(fps) = samples.fps {
        let _ = writeln!(s, "    startTimeCode = {first}");
        let _ = writeln!(s, "    timeCodesPerSecond = {}", fmt_number(fps));
    }
    let _ = writeln!(s, "    upAxis = \"Z\"");
    let _ = writeln!(s, ")");
    let _ = writeln!(s);
    let _ = writeln!(s, "def Volume \"{VOLUME_PRIM}\"");
    let _ = writeln!(s, "{{");
    for (name, _) in fields {
        let _ = writeln!(s, "    custom rel field:{name} = </{VOLUME_PRIM}/{name}>");
    }
    for (name, ty) in fields {
        let _ = writeln!(s);
        let _ = writeln!(s, "    def OpenVDBAsset \"{name}\"");
        let _ = writeln!(s, "    {{");
        let _ = writeln!(s, "        token fieldClass = \"fogVolume\"");
        let _ = writeln!(s, "        token fieldDataType = \"{ty}\"");
        let _ = writeln!(s, "        token fieldName = \"{name}\"");
        match samples.fps {
            None => {
                let _ = writeln!(s, "        asset filePath = @{}@", asset(frames.first().map_or("", |f| f.1)));
            }
            Some(_) => {
                let _ = writeln!(s, "        asset filePath.timeSamples = {{");
                for (f, file) in frames {
                    let _ = writeln!(s, "            {f}: @{}@,", asset(file));
                }
                let _ = writeln!(s, "        }}");
            }
        }
        let _ = writeln!(s, "    }}");
    }
    let _ = writeln!(s, "}}");
    s
}

/// [`stage_text`] after checking every input: frames non-empty and
/// ascending (a single bake: exactly one), fps finite and positive, and
/// each file name, field and unit as [`check`] wants them.
fn stage_checked(samples: &Samples<'_>, fields: &[(&str, &str)], meters_per_unit: f64) -> Result<String, std::io::Error> {
    let frames = &samples.frames;
    if frames.is_empty() || frames.windows(2).any(|w| w[1].0 <= w[0].0) || (samples.fps.is_none() && frames.len() != 1) {
        return Err(invalid("a sequence needs at least one frame, in ascending order".into()));
    }
    if let Some(fps) = samples.fps {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(invalid(format!("fps {fps} must be positive")));
        }
    }
    for (_, name) in frames {
        check(name, fields, meters_per_unit)?;
    }
    Ok(stage_text(samples, fields, meters_per_unit))
}

fn single(vdb_file_name: &str) -> Samples<'_> {
    Samples { frames: vec![(0, vdb_file_name)], fps: None }
}

fn sequence(frames: &[(i64, String)], fps: f64) -> Samples<'_> {
    Samples { frames: frames.iter().map(|(f, n)| (*f, n.as_str())).collect(), fps: Some(fps) }
}

/// The stage text of a single bake. `vdb_file_name` is relative to the
/// stage's folder; `fields` are (grid name, data type: `"float"` |
/// `"float3"`). Call [`write_usda`] to have the inputs validated.
pub fn usda_text(vdb_file_name: &str, fields: &[(&str, &str)], meters_per_unit: f64) -> String {
    stage_text(&single(vdb_file_name), fields, meters_per_unit)
}

/// The stage of a frame sequence: the same prims, each field's `filePath`
/// time-sampled, one sample per frame (`frames`: (frame number, VDB file
/// name relative to the stage)); `startTimeCode` and `endTimeCode` are the
/// first and last frame, `timeCodesPerSecond` and `framesPerSecond` the
/// sequence's fps. USD has no `####` substitution: every frame is listed
/// (openusd.org, UsdVol OpenVDBAsset). Call [`write_usda_sequence`] to
/// have the inputs validated.
pub fn usda_sequence_text(frames: &[(i64, String)], fields: &[(&str, &str)], meters_per_unit: f64, fps: f64) -> String {
    stage_text(&sequence(frames, fps), fields, meters_per_unit)
}

/// Writes a sequence stage atomically (see [`usda_sequence_text`]); frames
/// must be non-empty and ascending, fps finite and positive.
pub fn write_usda_sequence(
    path: &Path,
    frames: &[(i64, String)],
    fields: &[(&str, &str)],
    meters_per_unit: f64,
    fps: f64,
) -> Result<(), std::io::Error> {
    let text = usda_sequence_checked(frames, fields, meters_per_unit, fps)?;
    crate::util::atomic_write::write_atomic(path, text.as_bytes()).map_err(Into::into)
}

/// [`usda_sequence_text`] after checking its inputs as
/// [`write_usda_sequence`] does.
pub fn usda_sequence_checked(
    frames: &[(i64, String)],
    fields: &[(&str, &str)],
    meters_per_unit: f64,
    fps: f64,
) -> Result<String, std::io::Error> {
    stage_checked(&sequence(frames, fps), fields, meters_per_unit)
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
    let text = stage_checked(&single(vdb_file_name), fields, meters_per_unit)?;
    crate::util::atomic_write::write_atomic(path, text.as_bytes()).map_err(Into::into)
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
        asset filePath = @./aurora.vdb@
    }

    def OpenVDBAsset "emission"
    {
        token fieldClass = "fogVolume"
        token fieldDataType = "float3"
        token fieldName = "emission"
        asset filePath = @./aurora.vdb@
    }
}
"#;
        assert!(t.ends_with(body), "{t}");
        assert!(t.starts_with("#usda 1.0\n(\n    defaultPrim = \"aurora\"\n"));
        assert!(t.contains("    metersPerUnit = 1000\n    upAxis = \"Z\"\n)"));
        assert_eq!(fmt_number(0.01), "0.01");
    }

    #[test]
    fn sequence_lists_every_frame_as_a_time_sample() {
        let frames: Vec<(i64, String)> = [1, 2, 3].iter().map(|&f| (f, format!("aurora.{f:04}.vdb"))).collect();
        let t = usda_sequence_text(&frames, &[("density", "float")], 1000.0, 24.0);
        assert!(t.contains("    endTimeCode = 3\n    framesPerSecond = 24\n    metersPerUnit = 1000\n    startTimeCode = 1\n    timeCodesPerSecond = 24\n"), "{t}");
        assert!(t.contains("        asset filePath.timeSamples = {\n            1: @./aurora.0001.vdb@,\n            2: @./aurora.0002.vdb@,\n            3: @./aurora.0003.vdb@,\n        }\n"), "{t}");
        let p = std::env::temp_dir().join("aurora-usd-seq-never-written.usda");
        assert!(write_usda_sequence(&p, &[], &[("density", "float")], 1000.0, 24.0).is_err());
        assert!(write_usda_sequence(&p, &[(2, "a.vdb".into()), (1, "b.vdb".into())], &[("density", "float")], 1000.0, 24.0).is_err());
        assert!(write_usda_sequence(&p, &frames, &[("density", "float")], 1000.0, 0.0).is_err());
        assert!(!p.exists());
    }

    #[test]
    fn bad_inputs_are_refused() {
        let p = std::env::temp_dir().join("aurora-usd-test-never-written.usda");
        assert!(write_usda(&p, "a@b.vdb", &[("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "/abs/a.vdb", &[("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("1density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("density", "float"), ("density", "float")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("density", "vec3")], 1000.0).is_err());
        assert!(write_usda(&p, "a.vdb", &[("density", "float")], 0.0).is_err());
        assert!(!p.exists());
    }
}
