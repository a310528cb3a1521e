//! The parser's messages in plain words. serde and the TOML reader speak
//! Rust ("invalid type: floating point `1.5`, expected usize"); a scene's
//! author reads "render.width: expected a whole number, found the number
//! 1.5 (allowed: 1 to 16384)". Unknown keys, tables and presets get the
//! nearest known name by edit distance (Levenshtein 1966, with adjacent
//! transpositions counted once as in Damerau 1964): "did you mean
//! `energy_flux`?". Pure functions of the message, the key and its table
//! ([`super::tables`]), so each rewording is tested alone.

use super::tables;
use super::validation::LINE_KEYS;

/// The edit distance between `a` and `b`: insertions, deletions,
/// substitutions and swaps of two adjacent characters, each counted 1.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    d[0] = (0..=b.len()).collect();
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1).min(d[i][j - 1] + 1).min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

/// The known name nearest `word`, when near enough to be a slip: at most
/// a third of its length away (at least 1, at most 3 edits), or `word`
/// is a prefix of it or it of `word` (`curtains`, `energy`).
pub fn did_you_mean<'a>(word: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let word_l = word.to_ascii_lowercase();
    let limit = (word.chars().count() / 3).clamp(1, 3);
    known
        .into_iter()
        .map(|k| (edit_distance(&word_l, &k.to_ascii_lowercase()), k))
        .filter(|(d, k)| *d <= limit || (word.len() >= 3 && (k.starts_with(word) || word.starts_with(*k))))
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// "; did you mean `x`?" or nothing.
pub fn suggestion<'a>(word: &str, known: impl IntoIterator<Item = &'a str>) -> String {
    did_you_mean(word, known).map(|k| format!("; did you mean `{k}`?")).unwrap_or_default()
}

/// Rust's and serde's name of an expected type, in plain words.
fn plain_type(t: &str) -> String {
    let t = t.trim();
    match t {
        "usize" | "u64" | "u32" | "u16" | "u8" | "i64" | "i32" | "isize" | "an integer" | "integer" => "a whole number".into(),
        "f64" | "f32" | "a float" | "float" => "a number".into(),
        "a string" | "string" | "a borrowed string" | "char" | "a character" => "text".into(),
        "a boolean" | "bool" => "true or false".into(),
        "a sequence" | "sequence" | "an array" | "array" | "a tuple" => "a list".into(),
        "a map" | "map" | "a table" | "table" => "a table".into(),
        "string or table" => "text".into(),
        _ => {
            if let Some(n) = t.strip_prefix("an array of length ").or_else(|| t.strip_prefix("a tuple of size ")) {
                return format!("a list of {n} values");
            }
            if t.starts_with("struct ") {
                return "a table".into();
            }
            t.to_string()
        }
    }
}

/// serde's description of the value found ("floating point `1.5`"), in plain words.
fn plain_found(f: &str) -> String {
    let f = f.trim();
    let tick = |p: &str| f.strip_prefix(p).map(|r| r.trim().trim_matches('`').to_string());
    if let Some(v) = tick("floating point ") {
        return format!("the number {v}");
    }
    if let Some(v) = tick("integer ") {
        return format!("the whole number {v}");
    }
    if let Some(v) = tick("boolean ") {
        return format!("`{v}`");
    }
    if let Some(v) = f.strip_prefix("string ") {
        return format!("the text {v}");
    }
    match f {
        "sequence" => "a list".into(),
        "map" => "a table".into(),
        _ => f.to_string(),
    }
}

/// The backticked names of a list "`a`, `b` and `c`".
fn ticked(list: &str) -> Vec<&str> {
    list.split('`').skip(1).step_by(2).collect()
}

/// What the key's table ([`super::keys`]) allows for `table.key` (`key`
/// alone at the top level; `curtain` for every `[[curtain]]`), in words:
/// "must be in [1, 16384]", "must be one of ..." or "allowed: " and a
/// rule. None when no table has the key or it takes any value.
pub fn allowed(table: Option<&str>, key: &str) -> Option<String> {
    let k = tables::spec(table.unwrap_or(""), key)?;
    k.range.says(k.unit)
}

/// The key a message is about: its table (None at the top level) and name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct At<'a> {
    pub table: Option<&'a str>,
    /// Which `[[curtain]]`, counted from 0.
    pub index: Option<usize>,
    pub key: Option<&'a str>,
}

impl At<'_> {
    fn dotted(&self) -> Option<String> {
        let key = self.key?;
        Some(match (self.table, self.index) {
            (Some(t), Some(i)) => format!("{t}[{i}].{key}"),
            (Some(t), None) => format!("{t}.{key}"),
            (None, _) => key.to_string(),
        })
    }
    fn table_words(&self) -> String {
        match self.table {
            Some("curtain") => " in [[curtain]]".into(),
            Some(t) => format!(" in [{t}]"),
            None => String::new(),
        }
    }
}

/// The TOML reader's or serde's `message` about the key `at` (whose value
/// reads `source` in the file, when known), in plain words.
pub fn plain(message: &str, at: At<'_>, source: Option<&str>) -> String {
    let m = message.trim();
    // `colour.lines` is the line model; the lines written are `grid.lines`.
    if (at.table, at.key) == (Some("colour"), Some("lines")) && !m.contains("unknown variant") {
        let names = LINE_KEYS.map(|k| format!("\"{k}\"")).join(", ");
        return format!(
            "colour.lines{} is the line model, one name as text: \"chemistry\" (the default) or \"simple\"; the emission lines \
             written as grids of their own are chosen by grid.lines, a list of line names ({names}), e.g. grid.lines = [\"5577\"]",
            source.map(|s| format!(" = {s}")).unwrap_or_default()
        );
    }
    if let Some(rest) = m.strip_prefix("unknown field `") {
        let (word, expected) = rest.split_once('`').unwrap_or((rest, ""));
        let known = ticked(expected);
        let is_root = known.contains(&"curtain") && known.contains(&"render");
        let what = if is_root { "table or key" } else { "key" };
        let hint = suggestion(word, known.iter().copied());
        return format!("unknown {what} `{word}`{}{hint} (known: {})", at.table_words(), known.join(", "));
    }
    if let Some(rest) = m.strip_prefix("unknown variant `") {
        let (word, expected) = rest.split_once('`').unwrap_or((rest, ""));
        let known = ticked(expected);
        let hint = suggestion(word, known.iter().copied());
        let key = at.dotted().map(|k| format!("{k} = ")).unwrap_or_default();
        return format!(
            "{key}\"{word}\"{hint} (expected one of {})",
            known.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ")
        );
    }
    let range = at.key.and_then(|k| allowed(at.table, k)).map(|a| format!(" ({a})")).unwrap_or_default();
    let key = at.dotted().map(|k| format!("{k}: ")).unwrap_or_default();
    if let Some(rest) = m.strip_prefix("invalid type: ") {
        if let Some((found, expected)) = rest.rsplit_once(", expected ") {
            return format!("{key}expected {}, found {}{range}", plain_type(expected), plain_found(found));
        }
    }
    if let Some(rest) = m.strip_prefix("invalid value: ") {
        if let Some((found, expected)) = rest.rsplit_once(", expected ") {
            let unsigned = ["usize", "u64", "u32", "u16", "u8"].contains(&expected.trim());
            let expected = if unsigned { "a whole number, 0 or more".to_string() } else { plain_type(expected) };
            return format!("{key}expected {expected}, found {}{range}", plain_found(found));
        }
    }
    if let Some(rest) = m.strip_prefix("missing field `") {
        let word = rest.split('`').next().unwrap_or(rest);
        // The reader points at the table's header, not into it: the only
        // required keys are `[site]`'s.
        let in_table = at.table.or(["latitude_deg", "longitude_deg", "utc"].contains(&word).then_some("site"));
        let table = in_table.map(|t| format!("[{t}]")).unwrap_or_else(|| "this table".into());
        let required = if in_table == Some("site") { " (a [site] gives latitude_deg, longitude_deg and utc; docs/scene.md)" } else { "" };
        return format!("{table} needs the key `{word}`{required}");
    }
    if m == "duplicate key" {
        return match at.dotted() {
            Some(k) => format!("{k} is given twice; give each key once"),
            None => "this table is given twice; give each table once (merge the two)".into(),
        };
    }
    if m == "wanted string or table" {
        let found = source.map(|s| format!(", found {s}")).unwrap_or_default();
        return format!("{key}expected text{found}{range}");
    }
    if let Some(rest) = m.strip_prefix("invalid length ") {
        if let Some((n, expected)) = rest.split_once(", expected ") {
            return format!("{key}expected {}, found {n} values{range}", plain_type(expected));
        }
    }
    m.to_string()
}

/// Where byte `offset` of a scene's TOML `text` lies: the table whose
/// section holds it (and which `[[curtain]]`), the key of its line and the
/// value's text. A plain text scan, as [`super::validation::find_key_line`]:
/// enough to name the key of a parser's message.
pub fn locate(text: &str, offset: usize) -> (Option<String>, Option<usize>, Option<String>, Option<String>) {
    let offset = offset.min(text.len());
    let start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    let line = text[start..end].trim();
    let (mut table, mut index) = (None, None);
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    for raw in text[..start].lines() {
        let l = raw.trim();
        if let Some(rest) = l.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let c = counts.entry(name.clone()).or_insert(0);
            (table, index) = (Some(name), Some(*c));
            *c += 1;
        } else if let Some(rest) = l.strip_prefix('[') {
            (table, index) = (Some(rest.split(']').next().unwrap_or("").trim().to_string()), None);
        }
    }
    if line.starts_with('[') {
        return (None, None, None, None);
    }
    match line.split_once('=') {
        Some((k, v)) => (table, index, Some(k.trim().trim_matches('"').to_string()), Some(v.trim().to_string())),
        None => (table, index, None, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_counts_slips() {
        assert_eq!(edit_distance("energy_flx", "energy_flux"), 1);
        assert_eq!(edit_distance("rendr", "render"), 1);
        assert_eq!(edit_distance("corona2", "corona"), 1);
        assert_eq!(edit_distance("widht", "width"), 1, "a swap is one edit");
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(did_you_mean("widht", ["width", "height", "spp"]), Some("width"));
        assert_eq!(did_you_mean("curtains", ["curtain", "camera"]), Some("curtain"));
        assert_eq!(did_you_mean("zzz", ["width", "height"]), None);
    }

    #[test]
    fn rust_type_names_become_plain_words() {
        let at = At { index: None, table: Some("render"), key: Some("width") };
        let m = plain("invalid type: floating point `1.5`, expected usize", at, None);
        assert_eq!(m, "render.width: expected a whole number, found the number 1.5 (must be in [1, 16384])");
        let at = At { index: None, table: Some("grid"), key: Some("cycles_shell") };
        assert!(
            plain("invalid type: integer `1`, expected a boolean", at, None).contains("expected true or false, found the whole number 1")
        );
        let at = At { index: None, table: Some("render"), key: Some("exposure") };
        assert!(plain("invalid type: string \"x\", expected f64", at, None).contains("expected a number, found the text \"x\""));
        let at = At { index: None, table: Some("camera"), key: Some("up") };
        assert!(plain("invalid type: string \"x\", expected an array of length 3", at, None).contains("expected a list of 3 values"));
        let seed = At { index: None, table: None, key: Some("seed") };
        assert_eq!(
            plain("invalid value: integer `-1`, expected u64", seed, None),
            "seed: expected a whole number, 0 or more, found the whole number -1"
        );
        assert_eq!(plain("duplicate key", at, None), "camera.up is given twice; give each key once");
        for rust in ["usize", "f64", "a string", "a sequence", "a boolean", "struct RenderParams"] {
            let m = plain(&format!("invalid type: map, expected {rust}"), At { index: None, table: None, key: Some("seed") }, None);
            assert!(!m.contains(rust), "{m}");
        }
    }
}
