//! `aurora scene --schema`: every scene key, its default and its allowed
//! range, as JSON. One source: defaults are `Scene::default()` (what a
//! missing table or key gives) serialised, and ranges are the keys' tables
//! ([`super::keys`]) that [`Scene::validate`] checks: a range changed there
//! changes here.
use super::tables::TABLES;
use super::{
    animation::*, atmosphere::*, background::*, beams::*, camera::*, colour::*, curtain::*, earth::*, footprint::*, grid::*, photons::*,
    render::*, root::Scene, sky::*, terrain::*, validation::SceneError, volume::*,
};
use serde_json::{json, Map, Value};

/// The words the parser takes for each enum-valued key: every key whose
/// default is a string is given a value no enum has, and the parser's own
/// message ("expected one of `a`, `b`") lists the variants. The keys'
/// `Range::Word` lists are checked against it (`super::keys`), so a variant
/// added to an enum and not to its key fails a test.
pub fn enum_values() -> Vec<(String, Value)> {
    let defaults = serde_json::to_value(Scene::default()).expect("a scene serialises");
    let mut out = Vec::new();
    let Value::Object(mut top) = defaults else { return out };
    // No site by default: the preset's, for its words.
    top.insert("site".into(), serde_json::to_value(super::presets::sites::tromso_site()).expect("serialises"));
    for (table, fields) in top {
        let fields = match table.as_str() {
            "curtain" => serde_json::to_value(Curtain::default()).expect("serialises"),
            _ => fields,
        };
        let Value::Object(fields) = fields else { continue };
        for (key, d) in fields {
            if !d.is_string() {
                continue;
            }
            let header = if table == "curtain" { "[[curtain]]".to_string() } else { format!("[{table}]") };
            let text = format!("{header}\n{key} = \"not a variant\"\n");
            let Err(SceneError::Parse { message, .. }) = Scene::from_toml_str(&text, "enum") else { continue };
            let Some(list) = message.split("expected one of ").nth(1).or_else(|| message.split("expected ").nth(1)) else { continue };
            let values: Vec<Value> = list.split('`').enumerate().filter(|(i, _)| i % 2 == 1).map(|(_, v)| json!(v)).collect();
            if !values.is_empty() {
                out.push((format!("{table}.{key}"), Value::Array(values)));
            }
        }
    }
    out
}

/// The schema: `{table: {key: {"default": .., "min"/"max"/.. or "rule"
/// or "values"}}}`, one entry per key of [`TABLES`] (its range from
/// [`super::keys::Range::schema_into`]); `curtain` describes one
/// `[[curtain]]` entry (defaults of `Curtain::default()`), top-level keys
/// sit under `""`. Where a key inside a table that is present defaults
/// differently from a missing table (`terrain.kind`), `default_in_table`
/// says so; for `[site]`, whose required keys have no default, it is the
/// `tromso` preset's site, the example the add-on's panel starts from.
/// The defaults of a `[site]` table that gives only its required keys
/// (serde's, the one source), the required keys themselves left out.
fn site_defaults() -> Value {
    const REQUIRED: [&str; 3] = ["latitude_deg", "longitude_deg", "utc"];
    let minimal: super::site::SiteParams =
        toml::from_str("latitude_deg = 0\nlongitude_deg = 0\nutc = \"\"").expect("the required keys alone");
    let mut v = serde_json::to_value(minimal).expect("serialises");
    for k in REQUIRED {
        v.as_object_mut().expect("a table").remove(k);
    }
    v
}

pub fn schema() -> Value {
    let defaults = serde_json::to_value(Scene::default()).expect("a scene serialises");
    let in_table: Value = json!({
        "footprint": FootprintParams::default(), "beams": BeamParams::default(), "colour": ColourParams::default(),
        "photons": PhotonParams::default(), "grid": GridParams::default(), "camera": Camera::default(),
        "render": RenderParams::default(), "volume": VolumeParams::default(), "background": Background::default(), "sky": SkyParams::default(), "airglow": super::airglow::AirglowParams::default(),
        "terrain": Terrain::default(), "atmosphere": AtmosphereParams::default(), "animation": AnimationParams::default(),
        "earth": EarthParams::default(),
        // `[site]` has no default (its required keys have none): the example
        // the add-on's panel starts from.
        "site": super::presets::sites::tromso_site(),
        "oval": super::oval::OvalParams::default(),
    });
    let curtain = serde_json::to_value(Curtain::default()).expect("serialises");
    let site = site_defaults();
    let oval = serde_json::to_value(super::oval::OvalParams::default()).expect("serialises");
    let mut out = Map::new();
    for table in TABLES {
        let fields = match table.name {
            "" => &defaults,
            "curtain" => &curtain,
            "site" => &site,
            "oval" => &oval,
            name => &defaults[name],
        };
        let mut keys = Map::new();
        for spec in table.keys {
            let default = fields.get(spec.name).cloned().unwrap_or(Value::Null);
            let mut k = Map::new();
            if let Some(d) = in_table.get(table.name).and_then(|t| t.get(spec.name)) {
                if *d != default {
                    k.insert("default_in_table".into(), d.clone());
                }
            }
            k.insert("default".into(), default);
            spec.range.schema_into(spec.unit, &mut k);
            keys.insert(spec.name.into(), Value::Object(k));
        }
        out.insert(table.name.into(), Value::Object(keys));
    }
    Value::Object(out)
}

/// The schema as `aurora scene --schema` prints it (sorted keys, two
/// spaces, trailing newline).
pub fn schema_json() -> String {
    serde_json::to_string_pretty(&schema()).expect("serialises") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::schema;
    #[test]
    fn schema_has_every_key_with_default_and_range() {
        let s = schema::schema();
        assert_eq!(s["camera"]["fov_deg"]["default"], 75.0);
        assert!(s["camera"]["fov_deg"]["rule"].as_str().unwrap().contains("360"));
        assert_eq!(s["render"]["width"]["max"], MAX_IMAGE_SIDE as f64);
        assert_eq!(s["grid"]["prune"]["max"], MAX_PRUNE);
        assert_eq!(s["curtain"]["char_energy_kev"]["min"], 0.05);
        assert_eq!(s["terrain"]["kind"]["default"], "heightfield");
        assert_eq!(s["terrain"]["kind"]["default_in_table"], "none");
        assert_eq!(s[""]["seed"]["default"], 2014);
        // Every numeric key has a range or a rule, and every enum value parses.
        for (table, keys) in s.as_object().unwrap() {
            for (key, k) in keys.as_object().unwrap() {
                let d = &k["default"];
                if d.is_number() && key != "seed" && key != "count" || d.is_array() {
                    assert!(k.get("min").is_some() || k.get("rule").is_some() || table.is_empty(), "{table}.{key} has no range");
                }
            }
        }
        for (key, values) in schema::enum_values() {
            let (t, k) = key.split_once('.').unwrap();
            for v in values.as_array().unwrap() {
                let text = if t == "curtain" { format!("[[{t}]]\n{k} = {v}\n") } else { format!("[{t}]\n{k} = {v}\n") };
                assert!(Scene::from_toml_str(&text, "e.toml").is_ok() || t == "colour" || t == "terrain" || t == "site", "{text}");
            }
        }
    }
}
