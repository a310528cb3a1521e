//! The layering rule of `docs/ARCHITECTURE.md`, enforced: the crate's
//! top-level modules import one another without circles, and the bottom
//! layer imports nothing from the stages above it.
//!
//! The graph is read from the source: every `crate::name` path in the code
//! of `src/**/*.rs` (in `use` lines and inline, `use crate::{a, b}` groups
//! included) is an edge from the file's top-level module (`src/x.rs` or
//! `src/x/...`) to `name`. Comments, string literals and `#[cfg(test)]`
//! items are skipped: a test may reach up to build its inputs (the graph is
//! the library's). `main.rs` and `lib.rs` sit above everything.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The bottom layer: these know nothing of the stages above, and import
/// only one another.
const LOWER: &[&str] = &["grid", "scene", "camera", "spectrum", "atmosphere", "atomic", "input_file", "progress", "rng", "magnetic", "deposit", "watch", "leaf_source"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read src/") {
        let p = e.expect("dir entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a Rust file with comments, string and char literals blanked
/// (replaced by spaces) and every `#[cfg(test)]` item removed.
fn code_only(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c == b'r' && (b.get(i + 1) == Some(&b'"') || b.get(i + 1) == Some(&b'#')) && !ident_byte(i.checked_sub(1).map(|j| b[j])) {
            // Raw string r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&b'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&b'"') {
                out.push(c as char);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == b'"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&b'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
            out.push_str("\"\"");
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == b'\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            let end = if b.get(i + 1) == Some(&b'\\') {
                (i + 3..b.len()).find(|&j| b[j] == b'\'')
            } else if b.get(i + 2) == Some(&b'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    out.push_str("' '");
                    i = e + 1;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            // Copy one whole UTF-8 character.
            let n = src[i..].chars().next().map_or(1, char::len_utf8);
            out.push_str(&src[i..i + n]);
            i += n;
        }
    }
    strip_cfg_test(&out)
}

fn ident_byte(c: Option<u8>) -> bool {
    c.is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
}

/// Removes each `#[cfg(test)]` item: up to the end of its `{ ... }` block,
/// or its `;` if that comes first (`#[cfg(test)] use ...;`). Comments and
/// literals are already blank, so braces balance.
fn strip_cfg_test(code: &str) -> String {
    let mut s = code.to_string();
    while let Some(at) = s.find("#[cfg(test)]") {
        let rest = &s[at..];
        let semi = rest.find(';');
        let open = rest.find('{');
        let end = match (open, semi) {
            (Some(o), Some(sc)) if sc < o => at + sc + 1,
            (Some(o), _) => {
                let mut depth = 0usize;
                let mut end = s.len();
                for (k, ch) in rest[o..].char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = at + o + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (None, Some(sc)) => at + sc + 1,
            (None, None) => s.len(),
        };
        s.replace_range(at..end, "");
    }
    s
}

/// The top-level modules named after `crate::` in `code`.
fn crate_refs(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().next_back();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // `$crate::` or an identifier ending in "crate"
        }
        let t = rest.trim_start();
        if let Some(group) = t.strip_prefix('{') {
            // use crate::{a::X, b, c::{..}}: the first name of each entry,
            // the group split at its depth-0 commas.
            let mut depth = 0;
            let mut entry = String::new();
            let mut entries = Vec::new();
            for ch in group.chars() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        entries.push(std::mem::take(&mut entry));
                        continue;
                    }
                    _ => {}
                }
                entry.push(ch);
            }
            entries.push(entry);
            for e in entries {
                let name: String = e.trim().chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                if !name.is_empty() && name != "self" {
                    out.insert(name);
                }
            }
        } else {
            let name: String = t.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// module -> the modules it refers to (itself excluded).
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).expect("under src/");
        let first = rel.components().next().expect("non-empty").as_os_str().to_string_lossy().into_owned();
        let module = first.trim_end_matches(".rs").to_string();
        if module == "main" || module == "lib" {
            continue;
        }
        let text = std::fs::read_to_string(&f).expect("read a source file");
        let refs = crate_refs(&code_only(&text));
        let e = g.entry(module.clone()).or_default();
        e.extend(refs.into_iter().filter(|r| *r != module));
    }
    g
}

/// Every edge that lies on a circle, as (from, to), found by reachability.
fn circle_edges(g: &BTreeMap<String, BTreeSet<String>>) -> BTreeSet<(String, String)> {
    let reach = |from: &str, to: &str| -> bool {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.to_string()];
        while let Some(u) = stack.pop() {
            if u == to {
                return true;
            }
            if seen.insert(u.clone()) {
                stack.extend(g.get(&u).into_iter().flatten().cloned());
            }
        }
        false
    };
    let mut out = BTreeSet::new();
    for (u, vs) in g {
        for v in vs {
            if reach(v, u) {
                out.insert((u.clone(), v.clone()));
            }
        }
    }
    out
}

#[test]
fn the_parser_sees_uses_groups_and_inline_paths_but_not_comments_strings_or_tests() {
    let src = r####"
use crate::grid::{Grid, Leaf};
use crate::{atmosphere::Atmosphere, beams::{self, Photon}, spectrum};
// use crate::bake;
/* crate::pilot */
const S: &str = "crate::render";
const R: &str = r#"crate::outputs"#;
const C: char = '{';
fn f<'a>(x: &'a str) -> &'a str { crate::camera::f(x) }
#[cfg(test)]
mod tests {
    use crate::bench;
    fn g() { let _ = "}"; let _ = '}'; }
}
#[cfg(test)]
use crate::frames;
fn h() { crate::vdb::read(); }
"####;
    let refs = crate_refs(&code_only(src));
    let want: BTreeSet<String> =
        ["grid", "atmosphere", "beams", "spectrum", "camera", "vdb"].iter().map(|s| s.to_string()).collect();
    assert_eq!(refs, want);
}

#[test]
fn a_circle_is_found() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    g.entry("c".into()).or_default().insert("d".into());
    let c = circle_edges(&g);
    assert_eq!(c.len(), 3, "{c:?}");
    assert!(!c.contains(&("c".into(), "d".into())));
}

#[test]
fn modules_import_each_other_without_circles() {
    let g = graph();
    assert!(g.len() > 15 && g.contains_key("bake") && g["vdb"].contains("grid"), "the graph was not read: {g:?}");
    let circles = circle_edges(&g);
    assert!(circles.is_empty(), "import circles (module -> module on a circle): {circles:?}\nthe graph: {g:#?}");
}

#[test]
fn the_bottom_layer_imports_nothing_from_above() {
    let g = graph();
    let mut bad = Vec::new();
    for low in LOWER {
        let deps = g.get(*low).unwrap_or_else(|| panic!("no module `{low}` in src/: update LOWER"));
        for d in deps {
            if !LOWER.contains(&d.as_str()) {
                bad.push(format!("{low} -> {d}"));
            }
        }
    }
    assert!(bad.is_empty(), "lower layers reach up: {bad:?} (lower: {LOWER:?})");
}
