//! `aurora scene --schema`: every scene key, its default and its allowed
//! range, as JSON. One source: defaults are `Scene::default()` (what a
//! missing table or key gives) serialised, and ranges are the checks
//! [`Scene::validate`] makes, recorded as it validates the default
//! scene (`Validator::allow`): a range changed there changes here.
use super::{
    animation::*, atmosphere::*, background::*, beams::*, camera::*, colour::*, curtain::*, earth::*, footprint::*, grid::*, photons::*,
    render::*, root::Scene, sky::*, terrain::*, validation::SceneError, volume::*,
};
use serde_json::{json, Map, Value};

/// What a key accepts (recorded by the checks in [`super::validation`]).
pub use super::validation::Allowed;

fn num(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        json!(if x > 0.0 { "inf" } else { "-inf" })
    }
}

/// Allowed values of the enum-valued keys: every key whose default is a
/// string is given a value no enum has, and the parser's own message
/// ("expected one of `a`, `b`") lists the variants. No list to keep in
/// step by hand: a variant added to an enum appears here (a test checks
/// each value parses).
pub fn enum_values() -> Vec<(String, Value)> {
    let defaults = serde_json::to_value(Scene::default()).expect("a scene serialises");
    let mut out = Vec::new();
    let Value::Object(top) = defaults else { return out };
    for (table, fields) in top {
        let fields = if table == "curtain" { serde_json::to_value(Curtain::default()).expect("serialises") } else { fields };
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
/// or "values"}}}`; `curtain` describes one `[[curtain]]` entry
/// (defaults of `Curtain::default()`), top-level keys sit under `""`.
/// Where a key inside a table that is present defaults differently from
/// a missing table (`terrain.kind`), `default_in_table` says so.
pub fn schema() -> Value {
    let scene = Scene::default();
    let checks = scene.validate_with("default", None).expect("the default scene validates");
    let defaults = serde_json::to_value(&scene).expect("a scene serialises");
    let in_table: Value = json!({
        "footprint": FootprintParams::default(), "beams": BeamParams::default(), "colour": ColourParams::default(),
        "photons": PhotonParams::default(), "grid": GridParams::default(), "camera": Camera::default(),
        "render": RenderParams::default(), "volume": VolumeParams::default(), "background": Background::default(), "sky": SkyParams::default(), "airglow": super::airglow::AirglowParams::default(),
        "terrain": Terrain::default(), "atmosphere": AtmosphereParams::default(), "animation": AnimationParams::default(),
        "earth": EarthParams::default(),
    });
    let enums = enum_values();
    let mut out = Map::new();
    let Value::Object(top) = defaults else { unreachable!() };
    for (table, value) in top {
        let (name, fields) = match (table.as_str(), value) {
            ("curtain", _) => ("curtain".to_string(), serde_json::to_value(Curtain::default()).expect("serialises")),
            (_, v @ Value::Object(_)) => (table.clone(), v),
            (_, v) => {
                let mut m = Map::new();
                m.insert(table.clone(), v);
                (String::new(), Value::Object(m))
            }
        };
        let Value::Object(fields) = fields else { continue };
        let entry = out.entry(name.clone()).or_insert_with(|| Value::Object(Map::new()));
        for (key, default) in fields {
            let full = if name.is_empty() { key.clone() } else { format!("{name}.{key}") };
            let mut k = Map::new();
            k.insert("default".into(), default.clone());
            if let Some(d) = in_table.get(&name).and_then(|t| t.get(&key)) {
                if *d != default {
                    k.insert("default_in_table".into(), d.clone());
                }
            }
            match checks.iter().find(|(c, _)| *c == full).map(|(_, a)| a) {
                Some(Allowed::Range { min, max, min_inclusive, max_inclusive }) => {
                    k.insert("min".into(), num(*min));
                    k.insert("max".into(), num(*max));
                    k.insert("min_inclusive".into(), json!(min_inclusive));
                    k.insert("max_inclusive".into(), json!(max_inclusive));
                }
                Some(Allowed::Rule(r)) => {
                    k.insert("rule".into(), json!(r));
                }
                None => {}
            }
            if let Some((_, v)) = enums.iter().find(|(e, _)| *e == full) {
                k.insert("values".into(), v.clone());
            }
            entry.as_object_mut().expect("object").insert(key, Value::Object(k));
        }
    }
    // `path` has no default (None is not written): listed with its rule.
    if let Some(Value::Object(c)) = out.get_mut("curtain") {
        let rule = checks.iter().find(|(k, _)| k == "curtain.path").map(|(_, a)| a.clone());
        let mut k = Map::new();
        k.insert("default".into(), Value::Null);
        if let Some(Allowed::Rule(r)) = rule {
            k.insert("rule".into(), json!(r));
        }
        c.insert("path".into(), Value::Object(k));
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
    use crate::scene::{schema, *};
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
                let text = format!("[{t}]\n{k} = {v}\n");
                assert!(Scene::from_toml_str(&text, "e.toml").is_ok() || t == "colour" || t == "terrain", "{text}");
            }
        }
    }
}
