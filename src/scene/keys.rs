//! The scene's keys, declared once: [`KeySpec`] (a key's name, unit,
//! allowed range and description) and [`Range`] (what a key accepts). Each
//! table's file holds its table of keys beside its struct (`BEAMS_KEYS` in
//! `beams.rs`, ...); `super::tables::TABLES` lists them in the order a
//! scene file gives them. Validation checks every key's range from here
//! ([`Range::problem`]), `aurora scene --schema` prints them
//! ([`Range::schema_into`]), and docs/scene.md and the add-on's
//! `blender/scene_keys.json` are made from them (tests/cli/schema.rs).

use crate::util::fmath;
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
        let k = fmath::log10(x.abs()).floor() as i32;
        let m = x / fmath::powi(10f64, k);
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

/// Items as a list in words: "a, b or c" (`last` before the last: " or ",
/// or ", " for a plain list).
fn listed(items: &[String], last: &str) -> String {
    match items.split_last() {
        Some((l, rest)) if !rest.is_empty() => format!("{}{last}{l}", rest.join(", ")),
        _ => items.join(""),
    }
}

fn words_quoted(words: &[&str], last: &str) -> String {
    listed(&words.iter().map(|w| format!("\"{w}\"")).collect::<Vec<_>>(), last)
}

impl Range {
    /// The value outside this range, as (value, allowed) in words
    /// ([`says`](Self::says)); None when it is inside, absent from the
    /// value's type or checked by code ([`Range::Rule`]).
    pub fn problem(&self, unit: &str, value: &toml::Value) -> Option<(String, String)> {
        let (shown, ok) = match *self {
            Range::Any | Range::Rule(_) => return None,
            Range::Num(n) => {
                let x = number(value)?;
                (fmt_num(x), n.admits(x))
            }
            Range::Int { min, max } => {
                let x = number(value)?;
                (fmt_num(x), Num::closed(min as f64, max as f64).admits(x))
            }
            Range::Each { min, max, .. } => {
                let a = value.as_array()?;
                (shown_array(a), a.iter().all(|v| number(v).is_some_and(|x| Num::closed(min, max).admits(x))))
            }
            Range::ZeroOr { min, max, .. } => {
                let x = number(value)?;
                (fmt_num(x), x == 0.0 || Num::closed(min, max).admits(x))
            }
            Range::Span { min, max } => {
                let a = value.as_array()?;
                let (lo, hi) = (a.first().and_then(number)?, a.get(1).and_then(number)?);
                (format!("[{}, {}]", fmt_num(lo), fmt_num(hi)), lo.is_finite() && hi.is_finite() && lo > min && hi >= lo && hi <= max)
            }
            Range::Of(values) => {
                let x = number(value)?;
                (fmt_num(x), values.iter().any(|v| *v as f64 == x))
            }
            Range::Word(words) => {
                let w = value.as_str()?;
                (format!("\"{w}\""), words.contains(&w))
            }
            // A number is held to its interval, in the interval's words.
            Range::NumOrWord(n, words) => match value.as_str() {
                Some(w) => (format!("\"{w}\""), words.contains(&w)),
                None => return Range::Num(n).problem(unit, value),
            },
        };
        if ok {
            None
        } else {
            Some((shown, self.says(unit)?))
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
            Range::Rule(r) => format!("allowed: {r}"),
            Range::ZeroOr { .. } | Range::Span { .. } | Range::Of(_) | Range::NumOrWord(..) => format!("must be {}", self.rule_text(unit)),
        })
    }

    /// The range in words for the schema's `rule` (`unit` is the key's).
    fn rule_text(&self, unit: &str) -> String {
        let unit_after = |u: &str| if u.is_empty() { String::new() } else { format!(" {u}") };
        match *self {
            Range::ZeroOr { min, max, zero } => format!("0 ({zero}) or in [{}, {}]{}", fmt_num(min), fmt_num(max), unit_after(unit)),
            Range::Span { min, max } => format!("[min, max] with {} < min <= max <= {}", fmt_num(min), fmt_num(max)),
            Range::Of(values) => listed(&values.iter().map(|v| v.to_string()).collect::<Vec<_>>(), " or "),
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

/// A number as messages write it: whole numbers without a point.
pub fn fmt_num(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}
