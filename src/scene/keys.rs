//! The scene's keys, declared once: [`KeySpec`] (a key's name, unit,
//! allowed range and description) and [`Range`] (what a key accepts). Each
//! table's file holds its table of keys beside its struct (`BEAMS_KEYS` in
//! `beams.rs`, ...); [`TABLES`] lists them in the order a scene file gives
//! them. Validation checks every key's range from here
//! ([`Range::problem`]), `aurora scene --schema` prints them
//! ([`Range::schema_into`]), and docs/scene.md and the add-on's
//! `blender/scene_keys.json` are made from them (tests/cli/schema.rs).

use super::validation::fmt_num;
use serde_json::{json, Map, Value};

/// A number's allowed interval: `[min, max]`, each end open or closed; an
/// infinite end is unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num {
    pub min: f64,
    pub max: f64,
    pub min_open: bool,
    pub max_open: bool,
}

impl Num {
    /// Any finite number.
    pub const FINITE: Num = Num { min: f64::NEG_INFINITY, max: f64::INFINITY, min_open: true, max_open: true };
    /// Any finite number > 0.
    pub const POSITIVE: Num = Num { min: 0.0, max: f64::INFINITY, min_open: true, max_open: true };
    /// `[min, max]`.
    pub const fn closed(min: f64, max: f64) -> Num {
        Num { min, max, min_open: false, max_open: false }
    }
    /// `(min, max]`.
    pub const fn open_min(min: f64, max: f64) -> Num {
        Num { min, max, min_open: true, max_open: false }
    }
    /// `[min, max)`.
    pub const fn open_max(min: f64, max: f64) -> Num {
        Num { min, max, min_open: false, max_open: true }
    }

    fn admits(&self, x: f64) -> bool {
        x.is_finite()
            && (if self.min_open { x > self.min } else { x >= self.min })
            && (if self.max_open { x < self.max } else { x <= self.max })
    }

    /// "must be in [a, b]", "must be finite" or "must be a finite number > a".
    fn says(&self) -> String {
        match (self.min.is_finite(), self.max.is_finite()) {
            (false, false) => "must be finite".into(),
            (true, false) => format!("must be a finite number {} {}", if self.min_open { ">" } else { ">=" }, fmt_num(self.min)),
            _ => format!("must be in {}", self.interval()),
        }
    }

    fn interval(&self) -> String {
        let open = if self.min_open { "(" } else { "[" };
        let close = if self.max_open { ")" } else { "]" };
        format!("{open}{}, {}{close}", fmt_num(self.min), fmt_num(self.max))
    }

    /// The schema's `min`, `max`, `min_inclusive`, `max_inclusive` (or the
    /// rule "finite" for an interval with no bound).
    fn schema_into(&self, k: &mut Map<String, Value>) {
        if !self.min.is_finite() && !self.max.is_finite() {
            k.insert("rule".into(), json!("finite"));
            return;
        }
        k.insert("min".into(), bound(self.min));
        k.insert("max".into(), bound(self.max));
        k.insert("min_inclusive".into(), json!(!self.min_open));
        k.insert("max_inclusive".into(), json!(!self.max_open));
    }
}

/// What a key accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Any value of the key's type (a switch, a seed, a path).
    Any,
    /// A number in the interval.
    Num(Num),
    /// A whole number in `[min, max]`.
    Int { min: i64, max: i64 },
    /// An array of numbers, each in `[min, max]`; `what` names them in
    /// messages ("components", "each coordinate"), `suffix` follows the
    /// range (" km").
    Each { min: f64, max: f64, what: &'static str, suffix: &'static str },
    /// 0, meaning `zero` ("a flat ground"), or a number in `[min, max]`.
    ZeroOr { min: f64, max: f64, zero: &'static str },
    /// A pair `[lo, hi]` with `min < lo <= hi <= max`.
    Span { min: f64, max: f64 },
    /// One of these whole numbers.
    Of(&'static [i64]),
    /// One of these words.
    Word(&'static [&'static str]),
    /// A number in the interval, or one of these words (`"auto"`).
    NumOrWord(Num, &'static [&'static str]),
    /// A rule over the whole value or between keys, in words; the code that
    /// checks it (`super::validation`) names the key.
    Rule(&'static str),
}

/// One scene key (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeySpec {
    pub name: &'static str,
    /// Unit of the value ("" for none).
    pub unit: &'static str,
    pub range: Range,
    /// What the key does, for docs/scene.md and the add-on.
    pub doc: &'static str,
    /// Why the range is what it is, said after it in messages ("" for none).
    pub note: &'static str,
}

impl KeySpec {
    pub const fn new(name: &'static str, unit: &'static str, range: Range, doc: &'static str) -> Self {
        KeySpec { name, unit, range, doc, note: "" }
    }
    pub const fn note(self, note: &'static str) -> Self {
        KeySpec { note, ..self }
    }

    /// The key's value outside its range, as (value, allowed) in the words
    /// of an error message; None when the value is allowed (or is absent,
    /// or is checked by code: [`Range::Rule`]).
    pub fn problem(&self, value: &toml::Value) -> Option<(String, String)> {
        let (shown, says) = self.range.problem(self.unit, value)?;
        Some((shown, if self.note.is_empty() { says } else { format!("{says} {}", self.note) }))
    }

    /// [`problem`](Self::problem) of a number.
    pub fn number_problem(&self, x: f64) -> Option<(String, String)> {
        self.problem(&toml::Value::Float(x))
    }
}

/// A number in a TOML value (an integer or a float).
fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// An array as Rust's `{:?}` prints one (`[0.0, 1.5]`, `[512, 128]`).
fn shown_array(a: &[toml::Value]) -> String {
    let items: Vec<String> = a
        .iter()
        .map(|v| match v {
            toml::Value::Float(x) => format!("{x:?}"),
            other => other.to_string(),
        })
        .collect();
    format!("[{}]", items.join(", "))
}

/// A bound as the per-element messages write it: `1e4` for 10000.
fn short(x: f64) -> String {
    if x != 0.0 && x.fract() == 0.0 && x.abs() >= 1e4 {
        let k = x.abs().log10().floor() as i32;
        let m = x / 10f64.powi(k);
        if m.fract() == 0.0 {
            return format!("{}e{k}", m as i64);
        }
    }
    fmt_num(x)
}

/// A bound in the schema: a number, or "inf" / "-inf".
fn bound(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        json!(if x > 0.0 { "inf" } else { "-inf" })
    }
}

fn words_quoted(words: &[&str], last: &str) -> String {
    let q: Vec<String> = words.iter().map(|w| format!("\"{w}\"")).collect();
    match q.split_last() {
        Some((l, rest)) if !rest.is_empty() => format!("{}{last}{l}", rest.join(", ")),
        _ => q.join(""),
    }
}

impl Range {
    /// The value outside this range, as (value, allowed) in words.
    pub fn problem(&self, unit: &str, value: &toml::Value) -> Option<(String, String)> {
        match *self {
            Range::Any | Range::Rule(_) => None,
            Range::Num(n) => {
                let x = number(value)?;
                (!n.admits(x)).then(|| (fmt_num(x), n.says()))
            }
            Range::Int { min, max } => {
                let x = number(value)?;
                let n = Num::closed(min as f64, max as f64);
                (!n.admits(x)).then(|| (fmt_num(x), n.says()))
            }
            Range::Each { min, max, what, suffix } => {
                let a = value.as_array()?;
                let bad = a.iter().any(|v| number(v).is_none_or(|x| !Num::closed(min, max).admits(x)));
                bad.then(|| (shown_array(a), format!("{what} must be in [{}, {}]{suffix}", short(min), short(max))))
            }
            Range::ZeroOr { min, max, .. } => {
                let x = number(value)?;
                (!(x == 0.0 || Num::closed(min, max).admits(x))).then(|| (fmt_num(x), format!("must be {}", self.rule_text(unit))))
            }
            Range::Span { min, max } => {
                let a = value.as_array()?;
                let (lo, hi) = (a.first().and_then(number)?, a.get(1).and_then(number)?);
                let ok = lo.is_finite() && hi.is_finite() && lo > min && hi >= lo && hi <= max;
                (!ok).then(|| (format!("[{}, {}]", fmt_num(lo), fmt_num(hi)), format!("must be {}", self.rule_text(""))))
            }
            Range::Of(values) => {
                let x = number(value)?;
                (!values.iter().any(|v| *v as f64 == x)).then(|| (fmt_num(x), format!("must be {}", self.rule_text(""))))
            }
            Range::Word(words) => {
                let w = value.as_str()?;
                (!words.contains(&w)).then(|| (format!("\"{w}\""), format!("must be one of {}", words_quoted(words, ", "))))
            }
            Range::NumOrWord(n, words) => match value.as_str() {
                Some(w) => {
                    (!words.contains(&w)).then(|| (format!("\"{w}\""), format!("must be a number or {}", words_quoted(words, " or "))))
                }
                None => Range::Num(n).problem(unit, value),
            },
        }
    }

    /// What the range allows, in the words of a message ("must be in
    /// [1, 16384]", "must be one of ...", "allowed: " and a rule); None for
    /// [`Range::Any`].
    pub fn says(&self, unit: &str) -> Option<String> {
        Some(match *self {
            Range::Any => return None,
            Range::Num(n) => n.says(),
            Range::Int { min, max } => Num::closed(min as f64, max as f64).says(),
            Range::Each { min, max, what, suffix } => format!("{what} must be in [{}, {}]{suffix}", short(min), short(max)),
            Range::Word(words) => format!("must be one of {}", words_quoted(words, ", ")),
            _ => format!("allowed: {}", self.rule_text(unit)),
        })
    }

    /// The range in words for the schema's `rule` (`unit` is the key's).
    fn rule_text(&self, unit: &str) -> String {
        let unit_after = |u: &str| if u.is_empty() { String::new() } else { format!(" {u}") };
        match *self {
            Range::ZeroOr { min, max, zero } => format!("0 ({zero}) or in [{}, {}]{}", fmt_num(min), fmt_num(max), unit_after(unit)),
            Range::Span { min, max } => format!("[min, max] with {} < min <= max <= {}", fmt_num(min), fmt_num(max)),
            Range::Of(values) => {
                let v: Vec<String> = values.iter().map(|v| v.to_string()).collect();
                match v.split_last() {
                    Some((l, rest)) if !rest.is_empty() => format!("{} or {l}", rest.join(", ")),
                    _ => v.join(""),
                }
            }
            Range::NumOrWord(n, words) => {
                let of = if unit.is_empty() { String::new() } else { format!(" of {unit}") };
                let num = match n.says().strip_prefix("must be a finite number ") {
                    Some(cmp) => format!("a number{of} {cmp}"),
                    None => format!("a number{of} {}", n.says().trim_start_matches("must be ")),
                };
                format!("{num}, or {}", words_quoted(words, " or "))
            }
            Range::Rule(r) => r.to_string(),
            _ => String::new(),
        }
    }

    /// The range's fields in a key's schema entry (`unit` is the key's).
    pub fn schema_into(&self, unit: &str, k: &mut Map<String, Value>) {
        match *self {
            Range::Any => {}
            Range::Num(n) => n.schema_into(k),
            Range::Int { min, max } => Num::closed(min as f64, max as f64).schema_into(k),
            Range::Each { min, max, .. } => Num::closed(min, max).schema_into(k),
            Range::Word(words) => {
                k.insert("values".into(), json!(words));
            }
            _ => {
                k.insert("rule".into(), json!(self.rule_text(unit)));
            }
        }
    }
}

/// One table of the scene: its name (`""` for the top level, `curtain`
/// for each `[[curtain]]`), its keys and what it is.
#[derive(Clone, Copy, Debug)]
pub struct Table {
    pub name: &'static str,
    pub keys: &'static [KeySpec],
    /// What the table is, for docs/scene.md.
    pub about: &'static str,
}

impl Table {
    /// The table's heading in docs/scene.md: "Top level", "`[[curtain]]`", "`[beams]`".
    pub fn heading(&self) -> String {
        match self.name {
            "" => "Top level".into(),
            "curtain" => "`[[curtain]]`".into(),
            name => format!("`[{name}]`"),
        }
    }
}

/// Every table, in the order a scene file gives them (and docs/scene.md).
pub const TABLES: &[Table] = &[
    Table {
        name: "",
        keys: super::root::ROOT_KEYS,
        about: "Keys outside any table.",
    },
    Table {
        name: "curtain",
        keys: super::curtain::CURTAIN_KEYS,
        about: "One table per auroral curtain: where its footprint lies and how hard it is driven. A scene without any `[[curtain]]` has the default scene's three; the defaults below are those of one table that omits a key.",
    },
    Table {
        name: "footprint",
        keys: super::footprint::FOOTPRINT_KEYS,
        about: "The 2D stable-fluids simulation (Stam 1999) that makes each curtain's footprint, bent along a low-frequency noise curve.",
    },
    Table {
        name: "beams",
        keys: super::beams::BEAMS_KEYS,
        about: "Electron beams traced down the geomagnetic field with random deflections (Baranoski et al. 2000), depositing energy by Fang et al. (2010).",
    },
    Table {
        name: "atmosphere",
        keys: super::atmosphere::ATMOSPHERE_KEYS,
        about: "The neutral atmosphere the electrons deposit their energy in, and the ambient night ionosphere the chemistry needs. The default is compiled in and free to sell with; `nrlmsis21` and `glow` are the data the physics was validated on, whose terms forbid commercial use or sale, read from a data folder ([data.md](data.md)).",
    },
    Table {
        name: "earth",
        keys: super::earth::EARTH_KEYS,
        about: "The ground's shape: a sphere (curtain positions and paths are ground distances from the origin, azimuthal equidistant) or a flat plane.",
    },
    Table {
        name: "colour",
        keys: super::colour::COLOUR_KEYS,
        about: "How deposited energy becomes colour.",
    },
    Table {
        name: "photons",
        keys: super::photons::PHOTONS_KEYS,
        about: "Volumetric photon mapping: a Gaussian-kernel density estimate of the emission.",
    },
    Table {
        name: "grid",
        keys: super::grid::GRID_KEYS,
        about: "The sparse grids written to the VDB.",
    },
    Table {
        name: "camera",
        keys: super::camera::CAMERA_KEYS,
        about: "The camera of `aurora render` and of the Blender scene; pruning and the automatic voxel size follow it.",
    },
    Table {
        name: "render",
        keys: super::render::RENDER_KEYS,
        about: "The reference renderer's image.",
    },
    Table {
        name: "volume",
        keys: super::volume::VOLUME_KEYS,
        about: "The volume material, as `aurora render` and the add-on's Cycles material apply it.",
    },
    Table {
        name: "background",
        keys: super::background::BACKGROUND_KEYS,
        about: "What is seen behind the volume.",
    },
    Table {
        name: "sky",
        keys: super::sky::SKY_KEYS,
        about: "The air between the aurora and the observer: Rayleigh scattering, ozone and aerosol dim and redden what is seen through the lower atmosphere (docs/physics.md, \"The air between the aurora and the eye\").",
    },
    Table {
        name: "airglow",
        keys: super::airglow::AIRGLOW_KEYS,
        about: "The night sky's own light, drawn by `aurora render` behind the volume (camera rays only, dimmed by the air, hidden by the terrain) and by Cycles through `aurora sky`'s map: Gaussian layers in spherical shells (docs/physics.md, \"Airglow\"). Render-only: the bake never reads it.",
    },
    Table {
        name: "terrain",
        keys: super::terrain::TERRAIN_KEYS,
        about: "The ground, lit by the aurora only (emissive shadow rays).",
    },
    Table {
        name: "animation",
        keys: super::animation::ANIMATION_KEYS,
        about: "Motion in time, closed form in t, so any frame costs one bake; every motion key at 0 gives identical frames.",
    },
];

/// The key `name` of table `table` (`""` for the top level).
pub fn spec(table: &str, name: &str) -> Option<&'static KeySpec> {
    TABLES.iter().find(|t| t.name == table)?.keys.iter().find(|k| k.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::*;

    #[test]
    fn every_field_has_one_key_and_every_key_a_field() {
        let defaults = serde_json::to_value(Scene::default()).unwrap();
        for t in TABLES {
            let fields = match t.name {
                "" => defaults.as_object().unwrap().iter().filter(|(_, v)| !v.is_object()).map(|(k, _)| k.clone()).collect::<Vec<_>>(),
                "curtain" => {
                    let mut f: Vec<String> =
                        serde_json::to_value(Curtain::default()).unwrap().as_object().unwrap().keys().cloned().collect();
                    f.push("path".into());
                    f.retain(|k| k != "curtain");
                    f
                }
                name => defaults[name].as_object().unwrap().keys().cloned().collect(),
            };
            let fields: Vec<String> = fields.into_iter().filter(|k| k != "curtain").collect();
            for f in &fields {
                assert_eq!(t.keys.iter().filter(|k| k.name == f).count(), 1, "{}.{f}: no key or two", t.name);
            }
            for k in t.keys {
                assert!(fields.iter().any(|f| f == k.name), "{}.{}: no such field", t.name, k.name);
            }
        }
    }

    #[test]
    fn words_are_the_parsers() {
        // Each Word range lists exactly the words the parser takes, in its order.
        let parsed = schema::enum_values();
        for t in TABLES {
            for k in t.keys {
                if let Range::Word(words) = k.range {
                    let key = format!("{}.{}", t.name, k.name);
                    let p = parsed.iter().find(|(e, _)| *e == key).unwrap_or_else(|| panic!("{key}: the parser lists no words"));
                    assert_eq!(p.1, json!(words), "{key}");
                }
            }
        }
        assert!(grid::GRID_KEYS
            .iter()
            .any(|k| matches!(k.range, Range::Rule(r) if validation::LINE_KEYS.iter().all(|l| r.contains(&format!("\"{l}\""))))));
    }

    #[test]
    fn ranges_say_what_they_allow() {
        let k = spec("beams", "alpha_d_deg").unwrap();
        assert_eq!(
            k.number_problem(95.0).unwrap(),
            ("95".into(), "must be in [0, 90) degrees: at 90 a beam no longer moves along B".into())
        );
        assert!(k.number_problem(45.0).is_none());
        let v = toml::Value::Array(vec![toml::Value::Float(2e4), toml::Value::Float(0.0)]);
        assert_eq!(spec("curtain", "center").unwrap().problem(&v).unwrap().1, "each coordinate must be in [-1e4, 1e4] km");
        assert_eq!(
            spec("earth", "radius_km").unwrap().number_problem(10.0).unwrap().1,
            "must be 0 (a flat ground) or in [1000, 100000] km"
        );
        let voxel = spec("grid", "voxel_size").unwrap();
        assert!(voxel.problem(&toml::Value::String("auto".into())).is_none());
        assert_eq!(voxel.number_problem(0.0).unwrap().1, "must be a finite number > 0");
        let mut k = Map::new();
        voxel.range.schema_into(voxel.unit, &mut k);
        assert_eq!(k["rule"], "a number of km > 0, or \"auto\"");
        // A key that takes a number or a word needs no code of its own.
        let exposure = KeySpec::new("exposure", "stops", Range::NumOrWord(Num::closed(-50.0, 50.0), &["auto"]), "");
        assert!(exposure.problem(&toml::Value::String("auto".into())).is_none());
        assert_eq!(exposure.number_problem(99.0).unwrap().1, "must be in [-50, 50]");
        assert!(exposure.problem(&toml::Value::String("dim".into())).unwrap().1.contains("\"auto\""));
    }
}
