//! The layering rule of `docs/ARCHITECTURE.md`, enforced: every top-level
//! module of the crate sits in one layer of [`LAYERS`], and imports only
//!
//! - modules of the layers its own layer may import ([`may_import`]):
//!   the bottom imports no other layer; the stages and the renderer only the
//!   bottom; the files the bottom and the stages; above all, everything;
//! - modules listed before it in its own layer (each layer's list is an
//!   order in which its modules are built on one another).
//!
//! The renderer so never imports a stage or a file format, a stage never
//! imports the renderer, and a file format never imports the renderer (the
//! adapter that reads a VDB into the renderer's medium sits above both). A module in no layer fails the test: a new
//! module must be placed. `main.rs` and the modules it declares (`mod x;`,
//! the binary's own) sit above everything; `lib.rs` declares the modules.
//! Import circles between top-level modules fail too.
//!
//! The graph is read from the source: every `crate::name` path in the code
//! of `src/**/*.rs` (in `use` lines and inline, `use crate::{a, b}` groups
//! included) is an edge from the file's top-level module (`src/x.rs` or
//! `src/x/...`) to `name`. Comments, string literals and `#[cfg(test)]`
//! items are skipped: a test may reach up to build its inputs (the graph is
//! the library's). [`violations`] is the one checker; it runs on the tree
//! and, with an upward import planted in each layer, on synthetic sources.

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

/// Every top-level module, by layer. Within a layer a module imports only
/// those listed before it.
const LAYERS: &[(Layer, &[&str])] = &[
    (
        Bottom,
        &[
            "input_file",
            "earth",
            "scene",
            "rng",
            "progress",
            "atomic",
            "memory",
            "atmosphere",
            "chemistry",
            "spectrum",
            "lifetime",
            "lines",
            "extinction",
            "camera",
            "grid",
            "column",
            "magnetic",
            "curve",
            "deposit",
            "watch",
            "leaf_source",
        ],
    ),
    (
        Stages,
        &[
            "frames",
            "footprint",
            "starts",
            "animation",
            "trail",
            "fang_glow",
            "fang",
            "csda",
            "beams",
            "photons",
            "prune",
            "budget",
            "bake",
            "profile",
        ],
    ),
    (Renderer, &["render"]),
    (Files, &["vdb", "usd", "bake_identity", "outputs", "sequence", "farm_plan"]),
    (Above, &["vdb_medium", "preview", "bench"]),
];

/// Whether a module of layer `from` may import a module of another layer
/// `to` (its own layer: by the order of [`LAYERS`]).
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

/// The top-level module of a file: `x` for `x.rs` and `x/...`.
fn module_of(rel: &str) -> String {
    rel.split('/').next().expect("non-empty").trim_end_matches(".rs").to_string()
}

/// The modules `main.rs` declares (`mod x;`): the binary's, above all.
fn binary_modules(files: &[(String, String)]) -> BTreeSet<String> {
    let Some((_, main)) = files.iter().find(|(rel, _)| rel == "main.rs") else { return BTreeSet::new() };
    let code = code_only(main);
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

/// Every import edge of the library as (from module, to module, file).
fn edges(files: &[(String, String)]) -> Vec<(String, String, String)> {
    let binary = binary_modules(files);
    let mut out = Vec::new();
    for (rel, text) in files {
        let module = module_of(rel);
        if module == "main" || module == "lib" || binary.contains(&module) {
            continue;
        }
        for r in crate_refs(&code_only(text)) {
            if r != module {
                out.push((module.clone(), r, rel.clone()));
            }
        }
    }
    out
}

/// module -> the modules it refers to (itself excluded).
fn graph(files: &[(String, String)]) -> BTreeMap<String, BTreeSet<String>> {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, _) in files {
        let m = module_of(rel);
        if m != "main" && m != "lib" {
            g.entry(m).or_default();
        }
    }
    for (from, to, _) in edges(files) {
        g.entry(from).or_default().insert(to);
    }
    g
}

/// A module's layer and its place in the layer's list.
fn place(module: &str) -> Option<(Layer, usize)> {
    LAYERS.iter().find_map(|(layer, ms)| ms.iter().position(|m| *m == module).map(|i| (*layer, i)))
}

/// Every breach of the layering rule in `files`: modules in no layer
/// (and layer entries with no module), and every import the rule forbids,
/// as "from -> to (file): why".
fn violations(files: &[(String, String)]) -> Vec<String> {
    let binary = binary_modules(files);
    let modules: BTreeSet<String> =
        files.iter().map(|(rel, _)| module_of(rel)).filter(|m| m != "main" && m != "lib" && !binary.contains(m)).collect();
    let mut bad = Vec::new();
    for m in &modules {
        if place(m).is_none() {
            bad.push(format!("module `{m}` is in no layer: place it in LAYERS and docs/ARCHITECTURE.md"));
        }
    }
    for (_, ms) in LAYERS {
        for m in *ms {
            if !modules.contains(*m) {
                bad.push(format!("LAYERS lists `{m}`, which is not a module of src/"));
            }
        }
    }
    for (from, to, file) in edges(files) {
        let (Some((lf, i)), Some((lt, j))) = (place(&from), place(&to)) else { continue };
        let allowed = if lf == lt { j < i } else { may_import(lf, lt) };
        if !allowed {
            let why = if lf == lt {
                format!("`{to}` is listed after `{from}` in the {lf:?} layer")
            } else {
                format!("the {lf:?} layer may not import the {lt:?} layer")
            };
            bad.push(format!("{from} -> {to} ({file}): {why}"));
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
    let want: BTreeSet<String> = ["grid", "atmosphere", "beams", "spectrum", "camera", "vdb"].iter().map(|s| s.to_string()).collect();
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

/// The size rule of `docs/ARCHITECTURE.md`: a file of `src/` that grows past
/// [`MAX_LINES`] lines is doing more than one job and is split.
const MAX_LINES: usize = 1000;

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
fn modules_import_each_other_without_circles() {
    let g = graph(&tree());
    assert!(g.len() > 15 && g.contains_key("bake") && g["vdb"].contains("grid"), "the graph was not read: {g:?}");
    let circles = circle_edges(&g);
    assert!(circles.is_empty(), "import circles (module -> module on a circle): {circles:?}\nthe graph: {g:#?}");
}

#[test]
fn every_module_is_in_a_layer_and_imports_only_what_its_layer_may() {
    let files = tree();
    assert!(edges(&files).len() > 40, "the edges were not read");
    let bad = violations(&files);
    assert!(bad.is_empty(), "the layering of docs/ARCHITECTURE.md is broken:\n{}", bad.join("\n"));
}

/// A clean synthetic tree: one file per module of [`LAYERS`], each
/// importing only what the rule allows (the adapter importing a file
/// format and the renderer).
fn synthetic() -> Vec<(String, String)> {
    let mut files: BTreeMap<String, String> = BTreeMap::new();
    for (_, ms) in LAYERS {
        for m in *ms {
            files.insert(format!("{m}.rs"), String::new());
        }
    }
    for dir in ["vdb", "render", "bench"] {
        files.remove(&format!("{dir}.rs"));
    }
    let with = [
        ("lib.rs", ""),
        ("main.rs", "mod cli;\n"),
        ("cli/mod.rs", "use crate::anything;\n"),
        ("spectrum.rs", "use crate::atmosphere::Atmosphere;\n"),
        ("profile.rs", "use crate::{bake, beams::BeamStats};\n"),
        ("render/mod.rs", "fn f() { crate::camera::CameraModel::new(); }\n"),
        ("vdb/mod.rs", "use crate::grid::Grid;\n"),
        ("vdb/read.rs", "use crate::bake::Bake;\n"),
        ("vdb_medium.rs", "use crate::render::medium::Medium;\nuse crate::vdb::read;\n"),
        ("outputs.rs", "use crate::{frames, usd, vdb};\n"),
        ("bench/mod.rs", "use crate::{preview, render, outputs};\n"),
    ];
    for (rel, text) in with {
        files.insert(rel.to_string(), text.to_string());
    }
    files.into_iter().collect()
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
    let cases: &[(&str, &str, &str)] = &[
        // The bottom: onto a stage, and onto a bottom module listed after it.
        ("grid.rs", "use crate::bake::Bake;\n", "grid -> bake (grid.rs)"),
        ("scene.rs", "fn f() { crate::camera::x(); }\n", "scene -> camera (scene.rs)"),
        // The stages: onto the files, the renderer, and a later stage.
        ("beams.rs", "use crate::outputs;\n", "beams -> outputs (beams.rs)"),
        ("bake.rs", "use crate::render::Prepared;\n", "bake -> render (bake.rs)"),
        ("footprint.rs", "use crate::{rng, beams::Photon};\n", "footprint -> beams (footprint.rs)"),
        // The renderer: onto a file format and onto a stage.
        ("render/mod.rs", "use crate::vdb::read;\n", "render -> vdb (render/mod.rs)"),
        ("render/mod.rs", "use crate::photons::GatherInput;\n", "render -> photons (render/mod.rs)"),
        // The files: onto the layer above, onto the renderer (the reader
        // too: the adapter is above), and onto a later file module.
        ("usd.rs", "use crate::preview;\n", "usd -> preview (usd.rs)"),
        ("vdb/write.rs", "use crate::render::medium::Medium;\n", "vdb -> render (vdb/write.rs)"),
        ("vdb/read.rs", "use crate::render::medium::Medium;\n", "vdb -> render (vdb/read.rs)"),
        ("vdb/mod.rs", "use crate::outputs::write;\n", "vdb -> outputs (vdb/mod.rs)"),
        // Above all: onto a module listed after it.
        ("preview.rs", "use crate::bench::Study;\n", "preview -> bench (preview.rs)"),
        ("vdb_medium.rs", "use crate::preview;\n", "vdb_medium -> preview (vdb_medium.rs)"),
    ];
    for (rel, line, want) in cases {
        let got = violations(&planted(rel, line));
        assert!(got.len() == 1 && got[0].starts_with(want), "planted `{}` in {rel}: want `{want}`, got {got:?}", line.trim());
    }
    // A module placed in no layer.
    let got = violations(&planted("newthing.rs", ""));
    assert!(got.len() == 1 && got[0].contains("`newthing` is in no layer"), "{got:?}");
    // A layer entry whose module is gone.
    let mut files = synthetic();
    files.retain(|(rel, _)| rel != "deposit.rs");
    let got = violations(&files);
    assert!(got.len() == 1 && got[0].contains("lists `deposit`"), "{got:?}");
}
