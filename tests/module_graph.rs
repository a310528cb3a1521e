//! The layering rule of `docs/ARCHITECTURE.md`, read from the tree: the
//! top-level folders of `src/` are the layers ([`LAYERS`]), and a file
//! imports only
//!
//! - folders of the layers its own layer may import ([`may_import`]): the
//!   bottom imports no other layer; the stages and the renderer only the
//!   bottom; the files the bottom and the stages; above all, everything;
//! - folders of an earlier tier of its own layer (each layer's tiers are an
//!   order in which its folders are built on one another), and folders of
//!   its own tier (peers: `scene` is plain data that `geometry`'s camera
//!   reads, and the presets place the oval with `geometry`'s Earth).
//!
//! Inside a folder the rule is that files import each other without
//! circles: the graph is between files, not only between folders. A file at
//! the top of `src/` (besides `lib.rs` and `main.rs`) or a folder in no
//! layer fails: a new folder must be placed. `main.rs` and the modules it
//! declares (`mod cli;`) are the binary's, above everything.
//!
//! The graph is read from the source: every path that starts with `crate::`,
//! `super::` or `self::`, and every path that starts with a child module the
//! file declares (`mod x;` then `x::f()`), in `use` lines (groups included)
//! and inline, is resolved to the deepest file it names (`crate::a::b::C`
//! is `a/b.rs` or `a/b/mod.rs`; an item of a `mod.rs` is that file).
//! Comments, string literals and `#[cfg(test)]` items are skipped: a test
//! may reach up to build its inputs (the graph is the library's).
//! [`violations`] and [`file_circles`] are the checkers; they run on the
//! tree and on synthetic trees with an upward import or a circle planted.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A layer of `docs/ARCHITECTURE.md`, lowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layer {
    Bottom,
    Stages,
    Renderer,
    Files,
    Above,
}
use Layer::*;

/// Every top-level folder of `src/`, by layer and tier. Within a layer a
/// folder imports the folders of earlier tiers and of its own.
const LAYERS: &[(Layer, &[&[&str]])] = &[
    (Bottom, &[&["util"], &["scene", "geometry"], &["physics"], &["grid"]]),
    (Stages, &[&["pipeline"]]),
    (Renderer, &[&["render"]]),
    (Files, &[&["io"], &["farm"]]),
    (Above, &[&["app"]]),
];

/// At most this many entries at the top of `src/` besides `lib.rs` and
/// `main.rs`: the layers and the binary's `cli/`.
const MAX_TOP_ENTRIES: usize = 12;

/// Whether a file of layer `from` may import a file of another layer `to`.
fn may_import(from: Layer, to: Layer) -> bool {
    match from {
        Bottom => false,
        Stages | Renderer => to == Bottom,
        Files => matches!(to, Bottom | Stages),
        Above => true,
    }
}

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

/// The paths in `code` that start with `crate::`, `super::`, `self::` or
/// one of `children` (the modules the file declares), each as its segments
/// from that root on (`crate::a::{b, c::D}` gives `[crate, a, b]` and
/// `[crate, a, c, D]`).
fn paths(code: &str, children: &BTreeSet<String>) -> Vec<Vec<String>> {
    let b = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let after_path = i >= 2 && &b[i - 2..i] == b"::";
        let starts_word = !ident_byte(i.checked_sub(1).map(|j| b[j])) && !after_path;
        if starts_word && (b[i].is_ascii_alphabetic() || b[i] == b'_') {
            let word: String = code[i..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            let after = i + word.len();
            let rooted = matches!(word.as_str(), "crate" | "super" | "self") || children.contains(&word);
            if rooted && code[after..].starts_with("::") {
                let (found, end) = expand(&code[i..]);
                out.extend(found);
                i += end.max(1);
                continue;
            }
            i = after;
            continue;
        }
        i += 1;
    }
    out
}

/// Expands the path at the start of `s` (`a::b::{c, d::{e}}`) into its
/// leaf paths; returns them and the bytes read.
fn expand(s: &str) -> (Vec<Vec<String>>, usize) {
    let mut segs = Vec::new();
    let mut i = 0;
    loop {
        let rest = &s[i..];
        let t = rest.trim_start();
        i += rest.len() - t.len();
        if let Some(inner) = t.strip_prefix('{') {
            // A group: split at depth-0 commas, expand each entry.
            let mut depth = 0;
            let mut end = inner.len();
            let mut starts = vec![0];
            for (k, ch) in inner.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        end = k;
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => starts.push(k + 1),
                    _ => {}
                }
            }
            let mut out = Vec::new();
            for (n, &st) in starts.iter().enumerate() {
                let stop = starts.get(n + 1).map_or(end, |&x| x - 1);
                let entry = &inner[st..stop];
                if entry.trim().is_empty() {
                    continue;
                }
                for sub in expand(entry).0 {
                    let mut p = segs.clone();
                    if sub.first().is_some_and(|w| w == "self") {
                        p.extend(sub.into_iter().skip(1));
                    } else {
                        p.extend(sub);
                    }
                    out.push(p);
                }
            }
            return (out, i + 1 + end + 1);
        }
        let word: String = t.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        if word.is_empty() {
            return (vec![segs], i);
        }
        i += word.len();
        segs.push(word);
        if s[i..].starts_with("::") {
            i += 2;
        } else {
            return (vec![segs], i);
        }
    }
}

/// The modules a file declares (`mod x;`, `pub mod x;`, `pub(crate) mod x;`).
fn declared_children(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for part in code.split(';') {
        let words: Vec<&str> = part.split_whitespace().collect();
        if let [.., m, name] = words[..] {
            if m == "mod" && name.chars().all(|c| c.is_alphanumeric() || c == '_') {
                out.insert(name.to_string());
            }
        }
    }
    out
}

/// A file's module folder: where its children live (`a/b.rs` -> `a/b`,
/// `a/mod.rs` -> `a`, `lib.rs` -> ``).
fn own_dir(rel: &str) -> String {
    if rel == "lib.rs" || rel == "main.rs" {
        return String::new();
    }
    match rel.strip_suffix("/mod.rs") {
        Some(d) => d.to_string(),
        None => rel.trim_end_matches(".rs").to_string(),
    }
}

/// The parent of a module folder (`a/b` -> `a`, `a` -> ``).
fn parent_dir(dir: &str) -> String {
    dir.rsplit_once('/').map_or(String::new(), |(p, _)| p.to_string())
}

/// The file of the module whose folder is `dir`.
fn module_file(dir: &str, files: &BTreeSet<String>) -> Option<String> {
    if dir.is_empty() {
        return Some("lib.rs".to_string());
    }
    [format!("{dir}.rs"), format!("{dir}/mod.rs")].into_iter().find(|f| files.contains(f))
}

/// The deepest file that the path `segs`, written in file `rel`, names.
fn resolve(rel: &str, segs: &[String], files: &BTreeSet<String>) -> Option<String> {
    let mut dir = own_dir(rel);
    let mut rest = segs;
    match segs.first().map(String::as_str) {
        Some("crate") => {
            dir = String::new();
            rest = &segs[1..];
        }
        Some("self") => rest = &segs[1..],
        _ => {}
    }
    while rest.first().is_some_and(|s| s == "super") {
        dir = parent_dir(&dir);
        rest = &rest[1..];
    }
    let mut found = module_file(&dir, files);
    for seg in rest {
        let child = if dir.is_empty() { seg.clone() } else { format!("{dir}/{seg}") };
        match module_file(&child, files) {
            Some(f) => found = Some(f),
            // A folder without its own file (a synthetic tree's) stands for
            // its `mod.rs`.
            None if files.iter().any(|f| f.starts_with(&format!("{child}/"))) => found = Some(format!("{child}/mod.rs")),
            None => break,
        }
        dir = child;
    }
    found
}

/// Every `.rs` file under `src/`, as (path relative to `src/`, text).
fn tree() -> Vec<(String, String)> {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|f| {
            let rel = f.strip_prefix(&src).expect("under src/").to_string_lossy().replace('\\', "/");
            (rel, std::fs::read_to_string(&f).expect("read a source file"))
        })
        .collect()
}

/// The top-level entry of `src/` a file belongs to: `x` for `x.rs` and `x/...`.
fn folder_of(rel: &str) -> String {
    rel.split('/').next().expect("non-empty").trim_end_matches(".rs").to_string()
}

/// Whether a file is the binary's (`main.rs` and the modules it declares)
/// or `lib.rs`: outside the library's graph.
fn outside(rel: &str, binary: &BTreeSet<String>) -> bool {
    rel == "lib.rs" || rel == "main.rs" || binary.contains(&folder_of(rel))
}

/// Every import edge of the library between two different files, as
/// (from file, to file).
fn file_edges(files: &[(String, String)]) -> BTreeSet<(String, String)> {
    let names: BTreeSet<String> = files.iter().map(|(r, _)| r.clone()).collect();
    let binary = files.iter().find(|(r, _)| r == "main.rs").map_or(BTreeSet::new(), |(_, t)| declared_children(&code_only(t)));
    let mut out = BTreeSet::new();
    for (rel, text) in files {
        if outside(rel, &binary) {
            continue;
        }
        let code = code_only(text);
        let children = declared_children(&code);
        for p in paths(&code, &children) {
            if let Some(to) = resolve(rel, &p, &names) {
                if to != *rel && to != "lib.rs" {
                    out.insert((rel.clone(), to));
                }
            }
        }
    }
    out
}

/// A folder's layer and its tier in the layer.
fn place(folder: &str) -> Option<(Layer, usize)> {
    LAYERS.iter().find_map(|(layer, tiers)| tiers.iter().position(|t| t.contains(&folder)).map(|i| (*layer, i)))
}

/// Every breach of the layering rule in `files`: top-level entries in no
/// layer (and layer entries with no folder), and every import the rule
/// forbids, as "from -> to (file): why".
fn violations(files: &[(String, String)]) -> Vec<String> {
    let binary = files.iter().find(|(r, _)| r == "main.rs").map_or(BTreeSet::new(), |(_, t)| declared_children(&code_only(t)));
    let folders: BTreeSet<String> = files.iter().filter(|(r, _)| !outside(r, &binary)).map(|(r, _)| folder_of(r)).collect();
    let mut bad = Vec::new();
    for f in &folders {
        if place(f).is_none() {
            bad.push(format!("`src/{f}` is in no layer: place it in LAYERS and docs/ARCHITECTURE.md"));
        }
    }
    for (_, tiers) in LAYERS {
        for m in tiers.iter().flat_map(|t| t.iter()) {
            if !folders.contains(*m) {
                bad.push(format!("LAYERS lists `{m}`, which is not a folder of src/"));
            }
        }
    }
    for (from_file, to_file) in file_edges(files) {
        let (from, to) = (folder_of(&from_file), folder_of(&to_file));
        if from == to {
            continue;
        }
        let (Some((lf, i)), Some((lt, j))) = (place(&from), place(&to)) else { continue };
        let allowed = if lf == lt { j <= i } else { may_import(lf, lt) };
        if !allowed {
            let why = if lf == lt {
                format!("`{to}` is in a later tier than `{from}` in the {lf:?} layer")
            } else {
                format!("the {lf:?} layer may not import the {lt:?} layer")
            };
            bad.push(format!("{from} -> {to} ({from_file} -> {to_file}): {why}"));
        }
    }
    bad
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

/// The file-to-file edges of `files` that lie on an import circle.
fn file_circles(files: &[(String, String)]) -> BTreeSet<(String, String)> {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (from, to) in file_edges(files) {
        g.entry(from).or_default().insert(to);
    }
    circle_edges(&g)
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn the_parser_sees_uses_groups_children_and_inline_paths_but_not_comments_strings_or_tests() {
    let src = r####"
mod kid;
use crate::grid::{Grid, leaf::Leaf};
use crate::{physics::atmosphere::Atmosphere, pipeline::beams::{self, Photon}};
use super::sibling::Thing;
// use crate::pipeline::bake;
/* crate::pilot */
const S: &str = "crate::render";
const R: &str = r#"crate::io"#;
const C: char = '{';
fn f<'a>(x: &'a str) -> &'a str { crate::geometry::camera::f(x) }
fn k() { kid::go(); other::stop(); }
#[cfg(test)]
mod tests {
    use crate::app::bench;
    fn g() { let _ = "}"; let _ = '}'; }
}
#[cfg(test)]
use crate::farm;
fn h() { crate::io::vdb::read(); }
"####;
    let code = code_only(src);
    let got: BTreeSet<Vec<String>> = paths(&code, &declared_children(&code)).into_iter().collect();
    let want: BTreeSet<Vec<String>> = [
        &["crate", "grid", "Grid"][..],
        &["crate", "grid", "leaf", "Leaf"],
        &["crate", "physics", "atmosphere", "Atmosphere"],
        &["crate", "pipeline", "beams"],
        &["crate", "pipeline", "beams", "Photon"],
        &["super", "sibling", "Thing"],
        &["crate", "geometry", "camera", "f"],
        &["kid", "go"],
        &["crate", "io", "vdb", "read"],
    ]
    .iter()
    .map(|p| strings(p))
    .collect();
    assert_eq!(got, want);
}

#[test]
fn paths_resolve_to_the_deepest_file_they_name() {
    let files: BTreeSet<String> =
        ["lib.rs", "a/mod.rs", "a/b.rs", "a/c/mod.rs", "a/c/d.rs", "e.rs"].iter().map(|s| s.to_string()).collect();
    let r = |rel: &str, p: &[&str]| resolve(rel, &strings(p), &files);
    assert_eq!(r("e.rs", &["crate", "a", "b", "X"]).as_deref(), Some("a/b.rs"));
    assert_eq!(r("e.rs", &["crate", "a", "X"]).as_deref(), Some("a/mod.rs"));
    assert_eq!(r("a/b.rs", &["super", "c", "d", "f"]).as_deref(), Some("a/c/d.rs"));
    assert_eq!(r("a/c/d.rs", &["super", "Y"]).as_deref(), Some("a/c/mod.rs"));
    assert_eq!(r("a/c/d.rs", &["super", "super", "b"]).as_deref(), Some("a/b.rs"));
    assert_eq!(r("a/c/mod.rs", &["d", "g"]).as_deref(), Some("a/c/d.rs"));
    assert_eq!(r("a/c/mod.rs", &["self", "d"]).as_deref(), Some("a/c/d.rs"));
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

/// The size rule of `docs/ARCHITECTURE.md`: a file of `src/` that grows past
/// [`MAX_LINES`] lines is doing more than one job and is split.
const MAX_LINES: usize = 800;

#[test]
fn no_source_file_is_over_the_line_limit() {
    let long: Vec<String> = tree()
        .iter()
        .filter(|(_, text)| text.lines().count() > MAX_LINES)
        .map(|(rel, text)| format!("src/{rel}: {} lines", text.lines().count()))
        .collect();
    assert!(long.is_empty(), "over {MAX_LINES} lines (split by job): {long:?}");
}

#[test]
fn the_top_of_src_is_the_layers() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut entries: Vec<String> = std::fs::read_dir(&src)
        .expect("read src/")
        .map(|e| e.expect("dir entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n != "lib.rs" && n != "main.rs")
        .collect();
    entries.sort();
    assert!(entries.len() <= MAX_TOP_ENTRIES, "src/ has {} entries besides lib.rs and main.rs: {entries:?}", entries.len());
    let loose: Vec<&String> = entries.iter().filter(|n| n.ends_with(".rs")).collect();
    assert!(loose.is_empty(), "files at the top of src/ (each belongs in a layer's folder): {loose:?}");
}

#[test]
fn files_import_each_other_without_circles() {
    let files = tree();
    let edges = file_edges(&files);
    assert!(
        edges.len() > 200 && edges.contains(&("io/vdb/write.rs".to_string(), "grid/mod.rs".to_string())),
        "the graph was not read: {} edges",
        edges.len()
    );
    let circles = file_circles(&files);
    assert!(circles.is_empty(), "import circles (file -> file on a circle): {circles:#?}");
}

#[test]
fn every_folder_is_in_a_layer_and_imports_only_what_its_layer_may() {
    let bad = violations(&tree());
    assert!(bad.is_empty(), "the layering of docs/ARCHITECTURE.md is broken:\n{}", bad.join("\n"));
}

/// A clean synthetic tree: a file or two per folder of [`LAYERS`], each
/// importing only what the rule allows (the adapter importing a file
/// format and the renderer).
fn synthetic() -> Vec<(String, String)> {
    let with = [
        ("lib.rs", ""),
        ("main.rs", "mod cli;\n"),
        ("cli/mod.rs", "use crate::anything;\n"),
        ("util/mod.rs", "pub mod rng;\n"),
        ("util/rng.rs", ""),
        ("scene/mod.rs", "use crate::util::rng::Pcg;\n"),
        ("geometry/camera.rs", "use crate::scene::Scene;\n"),
        ("physics/mod.rs", "pub mod atmosphere;\npub mod emission;\n"),
        ("physics/atmosphere.rs", "use crate::scene::Scene;\n"),
        ("physics/emission/mod.rs", "mod line_colour;\npub use line_colour::ColourTable;\n"),
        ("physics/emission/line_colour.rs", "use crate::physics::atmosphere::Atmosphere;\n"),
        ("grid/mod.rs", "use crate::geometry::camera;\n"),
        ("pipeline/bake/mod.rs", "use crate::{grid, physics::emission::ColourTable};\nmod plan;\n"),
        ("pipeline/bake/plan.rs", "use crate::pipeline::beams::BeamStats;\n"),
        ("pipeline/beams/mod.rs", "use crate::util::rng;\n"),
        ("render/mod.rs", "fn f() { crate::geometry::camera::CameraModel::new(); }\n"),
        ("io/vdb/mod.rs", "use crate::grid::Grid;\n"),
        ("io/bake_folder.rs", "use crate::io::vdb;\n"),
        ("io/vdb/read.rs", "use crate::pipeline::bake::Bake;\n"),
        ("farm/sequence_folder.rs", "use crate::io::vdb;\n"),
        ("app/vdb_for_render.rs", "use crate::render::medium::Medium;\nuse crate::io::vdb::read;\n"),
        ("app/bench/mod.rs", "use crate::{app::preview, render, farm};\n"),
        ("app/preview.rs", ""),
    ];
    with.iter().map(|(r, t)| (r.to_string(), t.to_string())).collect()
}

/// Plants `line` in the file `rel` of the synthetic tree.
fn planted(rel: &str, line: &str) -> Vec<(String, String)> {
    let mut files = synthetic();
    match files.iter_mut().find(|(r, _)| r == rel) {
        Some((_, text)) => text.push_str(line),
        None => files.push((rel.to_string(), line.to_string())),
    }
    files
}

#[test]
fn the_checker_reports_an_upward_import_planted_in_each_layer() {
    let clean = violations(&synthetic());
    assert!(clean.is_empty(), "the clean synthetic tree: {clean:?}");
    assert!(file_circles(&synthetic()).is_empty());
    let cases: &[(&str, &str, &str)] = &[
        // The bottom: onto a stage, and onto a bottom folder listed after it.
        ("grid/mod.rs", "use crate::pipeline::bake::Bake;\n", "grid -> pipeline"),
        ("scene/mod.rs", "fn f() { crate::physics::atmosphere::x(); }\n", "scene -> physics"),
        ("util/rng.rs", "use crate::scene::Scene;\n", "util -> scene"),
        ("physics/atmosphere.rs", "use crate::grid::Grid;\n", "physics -> grid"),
        // The stages: onto the files and the renderer.
        ("pipeline/beams/mod.rs", "use crate::io::bake_folder;\n", "pipeline -> io"),
        ("pipeline/bake/mod.rs", "use crate::render::Prepared;\n", "pipeline -> render"),
        // The renderer: onto a file format and onto a stage.
        ("render/mod.rs", "use crate::io::vdb::read;\n", "render -> io"),
        ("render/mod.rs", "use crate::pipeline::photons::GatherInput;\n", "render -> pipeline"),
        // The files: onto the layer above, onto the renderer, and onto a
        // later folder of their own layer.
        ("io/vdb/mod.rs", "use crate::app::preview;\n", "io -> app"),
        ("io/vdb/read.rs", "use crate::render::medium::Medium;\n", "io -> render"),
        ("io/vdb/mod.rs", "use crate::farm::sequence_folder;\n", "io -> farm"),
    ];
    for (rel, line, want) in cases {
        let got = violations(&planted(rel, line));
        assert!(got.len() == 1 && got[0].starts_with(want), "planted `{}` in {rel}: want `{want}`, got {got:?}", line.trim());
    }
    // A file at the top, and a folder placed in no layer.
    let got = violations(&planted("newthing.rs", ""));
    assert!(got.len() == 1 && got[0].contains("`src/newthing` is in no layer"), "{got:?}");
    let got = violations(&planted("extra/mod.rs", ""));
    assert!(got.len() == 1 && got[0].contains("`src/extra` is in no layer"), "{got:?}");
    // A layer entry whose folder is gone.
    let mut files = synthetic();
    files.retain(|(rel, _)| !rel.starts_with("geometry/"));
    let got = violations(&files);
    assert!(got.iter().any(|b| b.contains("lists `geometry`")), "{got:?}");
}

#[test]
fn the_checker_reports_a_circle_planted_between_files() {
    // Two files of one folder that import each other, through `super::`.
    let files = planted("pipeline/beams/walk.rs", "use super::emit::deposit;\n");
    let files = {
        let mut f = files;
        f.push(("pipeline/beams/emit.rs".to_string(), "use super::walk::step;\n".to_string()));
        f
    };
    let c = file_circles(&files);
    assert!(
        c.contains(&("pipeline/beams/walk.rs".to_string(), "pipeline/beams/emit.rs".to_string()))
            && c.contains(&("pipeline/beams/emit.rs".to_string(), "pipeline/beams/walk.rs".to_string())),
        "{c:?}"
    );
    // A parent and its child: the child uses the parent's item, the parent
    // calls into the child by its declared name.
    let files = planted("physics/emission/line_colour.rs", "use super::Helper;\n");
    let c = file_circles(&files);
    assert!(c.contains(&("physics/emission/line_colour.rs".to_string(), "physics/emission/mod.rs".to_string())), "{c:?}");
    // Three files in a ring across folders of one layer is a layering
    // breach as well as a circle.
    let files = planted("util/rng.rs", "use crate::scene::Scene;\n");
    assert!(!file_circles(&files).is_empty());
}

/// The bake (`pipeline/bake/`) composes the stages below it in
/// `pipeline/`; nothing below calls back up into it. Every edge from a file
/// of `pipeline/` outside `pipeline/bake/` into `pipeline/bake/`.
fn bake_upcalls(files: &[(String, String)]) -> Vec<(String, String)> {
    file_edges(files)
        .into_iter()
        .filter(|(from, to)| from.starts_with("pipeline/") && !from.starts_with("pipeline/bake/") && to.starts_with("pipeline/bake/"))
        .collect()
}

#[test]
fn nothing_in_the_pipeline_below_the_bake_calls_up_into_it() {
    let up = bake_upcalls(&tree());
    assert!(up.is_empty(), "files below the bake import it (docs/ARCHITECTURE.md): {up:#?}");
    // The checker sees one planted: the memory budget reaching for the
    // bake's trace.
    let planted = planted("pipeline/memory/budget.rs", "use crate::pipeline::bake::trace::for_each_chunk;\n");
    let found = bake_upcalls(&planted);
    assert!(
        found.iter().any(|(from, to)| from == "pipeline/memory/budget.rs" && to.starts_with("pipeline/bake/")),
        "a planted upward call is not found: {found:?}"
    );
}

/// Where each piece of the bake's boundary lives (docs/ARCHITECTURE.md):
/// a file, and a definition that appears there and nowhere else in `src/`.
const BAKE_HOMES: &[(&str, &str)] = &[
    ("pipeline/plan.rs", "pub struct BakePlan "),
    ("pipeline/plan.rs", "pub const BEAM_CHUNK"),
    ("pipeline/plan.rs", "pub fn chunks("),
    ("pipeline/plan.rs", "pub const DEPOSIT_PILOT_BEAMS"),
    ("pipeline/beams/mod.rs", "pub fn beam_field("),
    ("pipeline/bake/trace.rs", "pub fn for_each_chunk("),
    ("pipeline/bake/gather.rs", "pub fn trace_and_gather("),
    ("pipeline/bake/finish.rs", "pub fn finish(\n    plan: &BakePlan"),
    ("pipeline/memory/budget.rs", "pub fn estimate(plan: &BakePlan"),
    ("pipeline/memory/leaves.rs", "pub fn band_leaves("),
    ("pipeline/memory/reach.rs", "pub fn world_bounds(plan: &BakePlan"),
    ("pipeline/memory/refusal.rs", "pub fn check(plan: &BakePlan"),
];

/// Every breach of [`BAKE_HOMES`] in `files`: a home that is missing or
/// lacks its definition, or a definition found in another file.
fn scattered(files: &[(String, String)]) -> Vec<String> {
    let mut bad = Vec::new();
    for (home, def) in BAKE_HOMES {
        let holders: Vec<&String> = files.iter().filter(|(_, t)| code_only(t).contains(def)).map(|(r, _)| r).collect();
        if holders.len() != 1 || holders[0] != home {
            bad.push(format!("`{def}` should be in {home} alone, found in {holders:?}"));
        }
    }
    // The memory module is one folder, not siblings by name prefix.
    bad.extend(
        files
            .iter()
            .filter(|(r, _)| r.starts_with("pipeline/memory_"))
            .map(|(r, _)| format!("{r}: the memory module lives in pipeline/memory/")),
    );
    bad
}

#[test]
fn the_plan_trace_gather_finish_and_memory_each_live_in_one_named_place() {
    let bad = scattered(&tree());
    assert!(bad.is_empty(), "the bake's boundary scattered:\n{}", bad.join("\n"));
    // The checker sees a second home and a sibling planted.
    let mut files = tree();
    files.push(("pipeline/bake/chunked.rs".to_string(), "pub fn trace_and_gather() {}\n".to_string()));
    files.push(("pipeline/memory_reach.rs".to_string(), String::new()));
    let bad = scattered(&files);
    assert_eq!(bad.len(), 2, "{bad:#?}");
}
