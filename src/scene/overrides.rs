//! Overrides of a scene's keys (`aurora ... --set render.width=64`): a key
//! spelled as the errors spell it (`seed`, `render.width`,
//! `curtain[1].energy_flux`, `camera.up[2]`) and a TOML value, applied in
//! order to the parsed TOML document after the file and before
//! validation, so the file's rules apply to them: unknown keys (with the
//! nearest name suggested), types, shapes and ranges. An error caused by
//! an override names the override as the user gave it (`--set KEY=VALUE`,
//! `--exposure 99`) instead of a line of the file.
//!
//! Each override is first parsed alone, as a scene holding only that key
//! (a probe: its type and shape checked by the same parser), then written
//! into the document. A table value replaces the whole table. Setting a
//! curtain's `path` removes its `center`, `length` and `rotation_deg`
//! (the path replaces them) and setting one of those removes its `path`:
//! the later wins, as for every override.

use super::root::Scene;
use super::validation::{check_shapes, SceneError};
use super::wording;
use toml::{Table, Value};

/// One override: a key path, its value, and how the user gave it.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The key as the errors spell it: `render.width`, `curtain[1].energy_flux`.
    pub key: String,
    pub value: Value,
    /// How it was given, for messages: `--set render.width=64`, `--exposure 2`.
    pub source: String,
}

/// One step of a key path: a name, with an index for an array's element.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Step {
    name: String,
    index: Option<usize>,
}

/// The keys a curtain's `path` replaces.
const STRAIGHT_KEYS: [&str; 3] = ["center", "length", "rotation_deg"];

impl Override {
    /// An override of `key` with `value`, given as `source`.
    pub fn new(key: &str, value: Value, source: &str) -> Override {
        Override { key: key.to_string(), value, source: source.to_string() }
    }

    /// `KEY=VALUE` as `--set` takes it: VALUE is TOML (`64`, `[0, 1, 0]`,
    /// `"chemistry"`); a VALUE that is not TOML is taken as text
    /// (`colour.mode=colormap`). The key's spelling is checked here, the
    /// key's existence and the value when applied.
    pub fn parse(text: &str, flag: &str) -> Result<Override, SceneError> {
        let source = format!("{flag} {}", excerpt(text));
        let bad = |message: String| SceneError::Override { given: source.clone(), message };
        // One value on one line: the rest of a second line would be read
        // as another key of the value's own table and dropped unseen.
        if let Some(at) = text.find(['\n', '\r']) {
            return Err(bad(format!(
                "takes one KEY=VALUE on one line; a line break follows `{}`: give each key its own {flag}",
                excerpt(&text[..at])
            )));
        }
        let Some((key, value)) = text.split_once('=') else {
            return Err(bad(format!("expected KEY=VALUE, e.g. {flag} render.width=64 or {flag} 'camera.up=[0, 1, 0]'")));
        };
        let key = key.trim();
        parse_key(key).map_err(bad)?;
        let value = value.trim();
        let value = match format!("v = {value}").parse::<Table>() {
            Ok(mut t) if t.len() == 1 => t.remove("v").expect("the key parsed"),
            Ok(_) => return Err(bad("takes one value; give each key its own KEY=VALUE".into())),
            Err(_) => Value::String(value.to_string()),
        };
        Ok(Override { key: key.to_string(), value, source })
    }

    /// `KEY=VALUE` with the value as TOML, as recorded in bake.json.
    pub fn record(&self) -> String {
        format!("{}={}", self.key, self.value)
    }

    /// Whether an error about `key` (as validation spells it) is this
    /// override's: the same key, or one inside it.
    fn covers(&self, key: &str) -> bool {
        key == self.key || key.strip_prefix(self.key.as_str()).is_some_and(|r| r.starts_with('.') || r.starts_with('['))
    }
}

/// The steps of `key`: names of letters, digits and `_`, each with an
/// optional `[index]`, joined by dots.
/// At most [`EXCERPT_CHARS`] characters of `text`, for a message: a longer
/// text is cut there and its length in bytes said.
fn excerpt(text: &str) -> String {
    match text.char_indices().nth(EXCERPT_CHARS) {
        None => text.to_string(),
        Some((at, _)) => format!("{}... ({} bytes)", &text[..at], text.len()),
    }
}

/// The most characters of a given text a message quotes: a line's worth.
const EXCERPT_CHARS: usize = 80;

fn parse_key(key: &str) -> Result<Vec<Step>, String> {
    let bad = || format!("`{key}` is not a key: write it as the errors do, e.g. render.width, curtain[1].energy_flux or seed");
    if key.is_empty() {
        return Err(bad());
    }
    key.split('.')
        .map(|part| {
            let (name, index) = match part.split_once('[') {
                Some((n, rest)) => {
                    let i = rest.strip_suffix(']').and_then(|i| i.parse::<usize>().ok()).ok_or_else(bad)?;
                    (n, Some(i))
                }
                None => (part, None),
            };
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(bad());
            }
            Ok(Step { name: name.to_string(), index })
        })
        .collect()
}

/// The probe of an override: a document holding only the path to the
/// value. An intermediate array element is a one-element array of its
/// table; a last step's element is the whole array `target` it changes.
fn probe(steps: &[Step], value: &Value, target: Option<&Vec<Value>>) -> Table {
    let mut v = value.clone();
    for (k, step) in steps.iter().enumerate().rev() {
        if step.index.is_some() {
            v = match (k + 1 == steps.len(), target) {
                (true, Some(all)) => Value::Array(all.clone()),
                _ => Value::Array(vec![v]),
            };
        }
        let mut t = Table::new();
        t.insert(step.name.clone(), v);
        v = Value::Table(t);
    }
    match v {
        Value::Table(t) => with_required_keys(t),
        _ => unreachable!("a path has at least one step"),
    }
}

/// A probe with the keys a table requires filled in where it omits them
/// (`[site]`'s, from the `tromso` preset's site), so that it tests only the
/// key it sets: `--set site.utc=...` alone is no incomplete `[site]`.
fn with_required_keys(mut probe: Table) -> Table {
    if let Some(Value::Table(site)) = probe.get_mut("site") {
        let example = Table::try_from(super::presets::sites::tromso_site()).expect("a site serialises to a table");
        for (k, v) in example {
            site.entry(k).or_insert(v);
        }
    }
    probe
}

/// Parses a probe as a scene (shapes and types, no ranges): the message
/// of the first problem, in plain words.
fn check_probe(doc: &Table) -> Result<(), String> {
    let text = toml::to_string(doc).map_err(|e| e.to_string())?;
    if let Err(e) = check_shapes(&text, "") {
        return Err(match e {
            SceneError::Invalid(errors) => {
                errors.iter().map(|r| format!("{} = {}: {}", r.key, r.value, r.allowed)).collect::<Vec<_>>().join("; ")
            }
            other => other.to_string(),
        });
    }
    toml::from_str::<Scene>(&text).map(|_| ()).map_err(|e| {
        let (table, index, key, source) = e.span().map_or((None, None, None, None), |s| wording::locate(&text, s.start));
        let at = wording::At { table: table.as_deref(), index: index.map(|_| 0), key: key.as_deref() };
        wording::plain(e.message(), at, source.as_deref())
    })
}

/// Applies `overrides` in order to `doc`, a scene's TOML document (a
/// missing `[[curtain]]` list is the default scene's, so its elements can
/// be set). The first that does not fit is an error naming it.
pub fn apply(doc: &mut Table, overrides: &[Override]) -> Result<(), SceneError> {
    for o in overrides {
        apply_one(doc, o).map_err(|message| SceneError::Override { given: o.source.clone(), message })?;
    }
    Ok(())
}

fn apply_one(doc: &mut Table, o: &Override) -> Result<(), String> {
    let steps = parse_key(&o.key)?;
    let defaults = Table::try_from(Scene::default()).expect("a scene serialises to a table");
    // Walk to the table holding the last step, creating missing tables.
    let mut here: &mut Table = doc;
    let mut defaults_here = Some(&defaults);
    let (last, path) = steps.split_last().expect("a key has a step");
    if last.index.is_none() {
        // Unknown keys and tables, types and shapes, before the document changes.
        check_probe(&probe(&steps, &o.value, None))?;
    }
    let mut spelled = String::new();
    for step in path {
        spelled += &step.name;
        let default = defaults_here.and_then(|d| d.get(&step.name));
        if !here.contains_key(&step.name) {
            let fresh = match (default, step.index) {
                (Some(Value::Array(a)), Some(_)) => Value::Array(a.clone()),
                _ => Value::Table(Table::new()),
            };
            here.insert(step.name.clone(), fresh);
        }
        let slot = here.get_mut(&step.name).expect("inserted above");
        let next = match (slot, step.index) {
            (Value::Table(t), None) => t,
            (Value::Array(a), Some(i)) => {
                let n = a.len();
                match a.get_mut(i) {
                    Some(Value::Table(t)) => t,
                    Some(_) => return Err(format!("{spelled}[{i}] is not a table")),
                    None => return Err(out_of_bounds(&spelled, i, n)),
                }
            }
            (Value::Array(_), None) => return Err(format!("{spelled} is a list: name an element, e.g. {spelled}[0]")),
            (_, _) => {
                // Not a table here: the probe words what it is.
                check_probe(&probe(&steps, &o.value, None))?;
                return Err(format!("{spelled} is not a table"));
            }
        };
        if let Some(i) = step.index {
            spelled += &format!("[{i}]");
        }
        spelled += ".";
        here = next;
        defaults_here = match default {
            Some(Value::Table(t)) => Some(t),
            Some(Value::Array(a)) => a.first().and_then(Value::as_table),
            _ => None,
        };
    }
    spelled += &last.name;
    // The whole array a last `[i]` changes, for its probe.
    let target = match last.index {
        Some(i) => match here.get(&last.name).or_else(|| defaults_here.and_then(|d| d.get(&last.name))) {
            Some(Value::Array(a)) if i < a.len() => {
                let mut a = a.clone();
                a[i] = o.value.clone();
                Some(a)
            }
            Some(Value::Array(a)) => return Err(out_of_bounds(&spelled, i, a.len())),
            Some(_) => return Err(format!("{spelled} is not a list")),
            None => return Err(format!("{spelled} has no default list: set the whole list, {spelled}=[...]")),
        },
        None => None,
    };
    if target.is_some() {
        check_probe(&probe(&steps, &o.value, target.as_ref()))?;
    }
    match (last.index, target) {
        (Some(_), Some(a)) => {
            here.insert(last.name.clone(), Value::Array(a));
        }
        _ => {
            here.insert(last.name.clone(), o.value.clone());
        }
    }
    // In a curtain, a path and a straight placement exclude each other.
    if path.last().is_some_and(|s| s.name == "curtain" && s.index.is_some()) {
        if last.name == "path" {
            STRAIGHT_KEYS.iter().for_each(|k| drop(here.remove(*k)));
        } else if STRAIGHT_KEYS.contains(&last.name.as_str()) {
            here.remove("path");
        }
    }
    Ok(())
}

fn out_of_bounds(spelled: &str, i: usize, n: usize) -> String {
    match n {
        0 => format!("{spelled}[{i}]: {spelled} is empty"),
        1 => format!("{spelled}[{i}]: {spelled} has 1 entry, {spelled}[0]"),
        _ => format!("{spelled}[{i}]: {spelled} has {n} entries, {spelled}[0] to {spelled}[{}]", n - 1),
    }
}

/// Moves the validation errors an override caused from the file's lines
/// to the override (the last that covers the key wins).
pub fn relocate(e: SceneError, overrides: &[Override]) -> SceneError {
    match e {
        SceneError::Invalid(mut errors) => {
            for r in &mut errors {
                if let Some(o) = overrides.iter().rev().find(|o| o.covers(&r.key)) {
                    r.file = o.source.clone();
                    r.line = None;
                }
            }
            SceneError::Invalid(errors)
        }
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(text: &str) -> Override {
        Override::parse(text, "--set").unwrap()
    }

    #[test]
    fn values_are_toml_and_bare_words_text() {
        assert_eq!(set("render.width=64").value, Value::Integer(64));
        assert_eq!(set("camera.up=[0,1,0]").record(), "camera.up=[0, 1, 0]");
        assert_eq!(set("colour.mode=\"chemistry\"").value, Value::String("chemistry".into()));
        assert_eq!(set("colour.mode=colormap").value, Value::String("colormap".into()));
        for bad in ["render.width", "=3", "render..width=3", "curtain[x].energy_flux=1", "render width=3"] {
            let e = Override::parse(bad, "--set").unwrap_err().to_string();
            assert!(e.starts_with(&format!("--set {bad}: ")), "{e}");
        }
    }

    /// A value with a line break (a second key hidden on the next line)
    /// is refused, not taken with the second line dropped; a long value is
    /// quoted by its first line's worth.
    #[test]
    fn one_value_on_one_line() {
        for text in ["render.width=64\nspp = 3", "render.width=64\r\nrender.spp=3", "render.width=\n64"] {
            let e = Override::parse(text, "--set").unwrap_err().to_string();
            assert!(e.contains("takes one KEY=VALUE on one line"), "{e}");
            assert!(e.contains("a line break follows `render.width="), "{e}");
        }
        let long = format!("colour.mode={}", "x".repeat(10_000_000));
        let e = Override::parse(&format!("{long}\n"), "--set").unwrap_err().to_string();
        assert!(e.len() < 400 && e.contains("(10000012 bytes)"), "{}", &e[..e.len().min(400)]);
        assert_eq!(set("render.width=64 # a comment").value, Value::Integer(64));
    }

    #[test]
    fn overrides_apply_in_order_to_the_document() {
        let mut doc: Table = "[render]\nwidth = 8\n".parse().unwrap();
        let list = [set("render.width=64"), set("render.height=32"), set("curtain[1].energy_flux=3"), set("render.width=16")];
        apply(&mut doc, &list).unwrap();
        let s: Scene = toml::from_str(&toml::to_string(&doc).unwrap()).unwrap();
        assert_eq!((s.render.width, s.render.height), (16, 32));
        assert_eq!(s.curtains.len(), Scene::default().curtains.len());
        assert_eq!(s.curtains[1].energy_flux, 3.0);
        assert_eq!(s.curtains[0], Scene::default().curtains[0]);
        apply(&mut doc, &[set("camera.up[1]=1"), set("camera.up[2]=0")]).unwrap();
        let s: Scene = toml::from_str(&toml::to_string(&doc).unwrap()).unwrap();
        assert_eq!(s.camera.up, [0.0, 1.0, 0.0]);
        // A path replaces the straight placement.
        apply(&mut doc, &[set("curtain[0].center=[1, 2]"), set("curtain[0].path=[[0, 0], [10, 0]]")]).unwrap();
        let text = toml::to_string(&doc).unwrap();
        check_shapes(&text, "t").unwrap();
    }

    #[test]
    fn an_override_that_does_not_fit_names_itself() {
        let mut doc = Table::new();
        let cases = [
            ("render.widht=64", "unknown key `widht` in [render]; did you mean `width`?"),
            ("rendr.width=64", "did you mean `render`?"),
            ("curtain[0].energy_flx=3", "did you mean `energy_flux`?"),
            ("render.width=abc", "expected a whole number, found the text \"abc\""),
            ("curtain[7].energy_flux=3", "curtain has 3 entries, curtain[0] to curtain[2]"),
            ("camera.up=[0, 1]", "must have exactly 3 values"),
        ];
        for (text, want) in cases {
            let e = apply(&mut doc, &[set(text)]).unwrap_err().to_string();
            assert!(e.starts_with(&format!("--set {text}: ")) && e.contains(want), "{text}: {e}");
        }
    }
}
