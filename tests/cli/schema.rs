//! One schema, three readers. `aurora scene --schema` (every scene key, its
//! default and its allowed range, as JSON) is the source; the Blender
//! add-on reads a committed copy (blender/scene_schema.json) and people read
//! docs/scene.md, a table per section rendered here from the same JSON plus
//! each key's unit and description, from the scene's tables of keys
//! (`aurora::scene::tables::TABLES`, which the schema's ranges and the
//! checks come from too). Both tests fail when their
//! file differs from what the binary prints:
//! - `aurora scene --schema > blender/scene_schema.json` regenerates the copy;
//! - `AURORA_UPDATE_DOCS=1 cargo test --release --test cli schema::`
//!   rewrites docs/scene.md and blender/scene_keys.json.
//!
//! A key in the schema is a row of its table of keys, with its unit and
//! description: a new key is documented the day it lands.

use crate::common::{aurora, check_committed, ok, update_or_check_committed};
use aurora::scene::tables::TABLES;
use serde_json::{Map, Value};
use std::fmt::Write as _;

/// How the files these tests generate are rewritten.
const REGENERATE: &str = "AURORA_UPDATE_DOCS=1 cargo test --release --test cli schema::";

/// What `aurora scene --schema` prints.
fn printed_schema() -> String {
    let out = aurora(&["scene", "--schema"]);
    ok(&out);
    String::from_utf8(out.stdout).expect("the schema is text")
}

#[test]
fn committed_schema_matches_the_binary() {
    let now = aurora::scene::schema::schema_json();
    check_committed("blender/scene_schema.json", &now, "aurora scene --schema > blender/scene_schema.json");
    // And the binary prints the same.
    assert_eq!(printed_schema(), now);
}

#[test]
fn scene_doc_matches_the_schema() {
    let schema: Value = serde_json::from_str(&printed_schema()).expect("the schema is JSON");
    update_or_check_committed("docs/scene.md", &scene_doc(&schema), REGENERATE);
}

/// The types the default cannot tell: a key whose default is none, or
/// one that takes a number or a word.
fn stated_type(section: &str, key: &str) -> Option<&'static str> {
    Some(match (section, key) {
        ("background", "image") | ("terrain", "heightmap") | ("atmosphere", "data") => "path",
        ("grid", "voxel_size") => "number or `\"auto\"`",
        ("grid", "lines") => "list of words",
        ("curtain", "path") => "rows of 2 numbers",
        ("curtain", "magnetic_path") => "rows of 2 numbers",
        // `[oval]`'s AL and hour: none unless given.
        ("oval", "al_nt" | "mlt_h") => "number",
        ("earth", "magnetic_pole") => "2 numbers",
        // `[site]` has no default; its required keys and the optional pressure.
        ("site", "latitude_deg" | "longitude_deg" | "pressure_hpa") => "number",
        ("site", "utc") => "string (RFC 3339)",
        _ => return None,
    })
}

/// docs/scene.md: a header, then per section a table of key, type,
/// default, range, unit and description. Deterministic: the order is
/// the tables of keys', and values print as serde_json prints them.
fn scene_doc(schema: &Value) -> String {
    let schema = schema.as_object().expect("the schema is an object");
    for section in schema.keys() {
        assert!(TABLES.iter().any(|s| s.name == section), "schema section `{section}` is no table of keys");
    }
    let mut out = String::new();
    out.push_str("# Scene keys\n\n");
    out.push_str("<!-- Generated from `aurora scene --schema` by tests/cli/schema.rs; do not edit.\n");
    let _ = write!(out, "     Regenerate: {REGENERATE} -->\n\n");
    out.push_str(
        "A scene is a TOML file. Every key is optional and takes the default below; an unknown key, a \
         value out of range or an unknown word is an error naming the file, line, key, value and allowed \
         range (exit status 2). `aurora scene default` prints the default scene with every key, \
         `aurora scene FILE` prints FILE with every default filled in, and `aurora scene --schema` prints \
         the facts of these tables as JSON (the Blender add-on reads its committed copy, \
         `blender/scene_schema.json`). Lengths are kilometres, z up, x east, y north.\n\n",
    );
    out.push_str(
        "Any key can be set on the command line without editing the file: `--set KEY=VALUE` (every \
         command that takes a scene; repeatable), the key spelled as the errors spell it (`seed`, \
         `render.width`, `curtain[1].energy_flux`, `camera.up[2]`), the value in TOML (`64`, \
         `'[0, 1, 0]'`, `\"agx\"`; a bare word is text). Overrides apply in command-line order after the \
         file and before these checks, so the same ranges apply (docs/guide.md, \"Overrides\").\n\n",
    );
    out.push_str(
        "Ranges: `[a, b]` includes both ends, `(a, b)` neither, `inf` is unbounded. A type \
         `3 numbers` is a TOML array of three numbers.\n\n",
    );
    for table in TABLES {
        let (name, about) = (&table.name, table.about);
        let Some(keys) = schema.get(*name).and_then(Value::as_object) else { continue };
        let _ = write!(out, "## {}\n\n{about}\n\n", table.heading());
        out.push_str("| key | type | default | range | unit | description |\n|---|---|---|---|---|---|\n");
        for spec in table.keys {
            let (key, unit, text) = (&spec.name, spec.unit, spec.doc);
            let entry = keys[*key].as_object().expect("a key's entry is an object");
            let row = [
                format!("`{key}`"),
                type_of(name, key, entry),
                default_of(name, entry),
                each(entry, range_of(entry)),
                unit.to_string(),
                text.to_string(),
            ];
            let _ = writeln!(out, "| {} |", row.map(|c| cell(&c)).join(" | "));
        }
        out.push('\n');
    }
    out.truncate(out.trim_end().len());
    out.push('\n');
    out
}

/// A table cell: pipes escaped, never empty.
fn cell(s: &str) -> String {
    if s.is_empty() {
        "-".into()
    } else {
        s.replace('|', "\\|")
    }
}

fn type_of(section: &str, key: &str, entry: &Map<String, Value>) -> String {
    if let Some(t) = stated_type(section, key) {
        return t.to_string();
    }
    let d = &entry["default"];
    match d {
        Value::Bool(_) => "bool".into(),
        Value::Number(n) if n.is_u64() || n.is_i64() => "integer".into(),
        Value::Number(_) => "number".into(),
        Value::String(_) if entry.contains_key("values") => "word".into(),
        Value::String(_) => "string".into(),
        Value::Array(items) => match items.first() {
            Some(Value::Array(row)) => format!("rows of {} numbers", row.len()),
            Some(Value::Number(n)) if n.is_u64() || n.is_i64() => format!("{} integers", items.len()),
            _ => format!("{} numbers", items.len()),
        },
        other => panic!("`{section}.{key}`: no type for a default of {other}; add it to `stated_type` (tests/cli/schema.rs)"),
    }
}

/// A value as TOML writes it: words quoted, arrays inline, none as `none`.
fn toml_value(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::String(s) => format!("\"{s}\""),
        Value::Array(items) => format!("[{}]", items.iter().map(toml_value).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

fn default_of(section: &str, entry: &Map<String, Value>) -> String {
    // A key with no default but an example (`[site]`'s required keys).
    if let (Value::Null, Some(t)) = (&entry["default"], entry.get("default_in_table")) {
        return format!("required in `[{section}]` (for example `{}`)", toml_value(t));
    }
    let mut s = format!("`{}`", toml_value(&entry["default"]));
    if let Some(t) = entry.get("default_in_table") {
        let _ = write!(s, " (`{}` in a written `[{section}]` table)", toml_value(t));
    }
    s
}

/// An array's range is each element's: "each in [0.0, 1.0]".
fn each(entry: &Map<String, Value>, range: String) -> String {
    if entry["default"].is_array() && entry.contains_key("min") && !entry.contains_key("rule") {
        format!("each in {range}")
    } else {
        range
    }
}

fn range_of(entry: &Map<String, Value>) -> String {
    if let Some(Value::Array(values)) = entry.get("values") {
        return values.iter().map(|v| format!("`{}`", toml_value(v))).collect::<Vec<_>>().join(", ");
    }
    if let Some(Value::String(rule)) = entry.get("rule") {
        return rule.clone();
    }
    let bound = |k: &str| entry.get(k).map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_string));
    match (bound("min"), bound("max")) {
        (Some(lo), Some(hi)) => {
            let open = if entry.get("min_inclusive") == Some(&Value::Bool(true)) { '[' } else { '(' };
            let close = if entry.get("max_inclusive") == Some(&Value::Bool(true)) { ']' } else { ')' };
            format!("{open}{lo}, {hi}{close}")
        }
        _ => String::new(),
    }
}

/// `blender/scene_keys.json`: each key's unit and description from
/// its table of keys, `{section: {key: {"unit", "description"}}}`, which the add-on's
/// panel shows beside the schema's defaults and ranges. Regenerated with
/// the docs (`AURORA_UPDATE_DOCS=1`).
#[test]
fn committed_key_docs_match_the_table() {
    let mut out = Map::new();
    for (section, key, unit, description) in TABLES.iter().flat_map(|t| t.keys.iter().map(|k| (t.name, k.name, k.unit, k.doc))) {
        let entry = out.entry(section.to_string()).or_insert_with(|| Value::Object(Map::new()));
        let mut k = Map::new();
        k.insert("unit".into(), Value::String(unit.to_string()));
        k.insert("description".into(), Value::String(description.to_string()));
        entry.as_object_mut().expect("object").insert(key.to_string(), Value::Object(k));
    }
    let text = serde_json::to_string_pretty(&Value::Object(out)).expect("serialises") + "\n";
    update_or_check_committed("blender/scene_keys.json", &text, REGENERATE);
}
