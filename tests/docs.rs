//! The documents' relative links resolve: every `[text](target)` and
//! `![alt](target)` outside code in README.md, docs/**/*.md,
//! blender/README.md and tools/README.md names a file or folder of the repository, and a
//! `#fragment` names a heading of the target Markdown file (GitHub's anchor
//! rule: lower case, punctuation other than `-` and `_` dropped, spaces to
//! `-`, a repeated heading numbered `-1`, `-2`, ...). Web links are not
//! followed. And every path in inline code that starts with `src/` or
//! `tools/` (`src/pipeline/beams/walk.rs`, `tools/check`) names a file or
//! folder of the repository: the documents follow the tree when it moves.
//! A reference in prose to a document or a section of one
//! (`docs/guide.md#farms`, `docs/physics.md, "The red trail"`) names an
//! existing file and heading.
//!
//! The help texts are documents too: every repository path `aurora --help`,
//! each command's `--help` and the header of `aurora scene` name exists (with
//! its heading), the presets' help names every preset of the registry, and
//! `aurora profile --help` every column of the CSV. And the README's default
//! picture records, in its PNG text chunks, the SHA-256 of the VDB it was
//! rendered from: the pinned default bake's (`benchmarks/pins/current.txt`),
//! or the picture is older than the bake and `tools/readme_pictures` remakes it.
//! The default bake's size and voxel count in README.md and docs/benchmarks.md
//! are the pinned bake's, and the README's command list names every command.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn markdown_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir).expect("read docs/").map(|e| e.unwrap().path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "md") {
                out.push(p);
            }
        }
    }
    let mut out = vec![root().join("README.md"), root().join("blender/README.md"), root().join("tools/README.md")];
    walk(&root().join("docs"), &mut out);
    out
}

/// A Markdown document: its path, its name from the repository's root, its
/// text.
struct Document {
    path: PathBuf,
    name: String,
    text: String,
}

/// The documents of [`markdown_files`], read.
fn documents() -> Vec<Document> {
    markdown_files()
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).unwrap();
            let name = path.strip_prefix(root()).unwrap().display().to_string();
            Document { path, name, text }
        })
        .collect()
}

/// The lines of `text` with their numbers (from 1), those of fenced code
/// blocks and the fences themselves blanked.
fn unfenced(text: &str) -> Vec<(usize, &str)> {
    let mut fenced = false;
    text.lines()
        .enumerate()
        .map(|(i, line)| {
            let fence = line.trim_start().starts_with("```");
            if fence {
                fenced = !fenced;
            }
            (i + 1, if fence || fenced { "" } else { line })
        })
        .collect()
}

/// The text outside fenced code blocks and inline code spans, line by line
/// (line numbers kept).
fn prose(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (number, line) in unfenced(text) {
        if line.starts_with("    ") && !line.trim_start().starts_with(['-', '|', '*']) {
            continue;
        }
        let mut kept = String::new();
        let mut in_code = false;
        for c in line.chars() {
            if c == '`' {
                in_code = !in_code;
            } else if !in_code {
                kept.push(c);
            }
        }
        out.push((number, kept));
    }
    out
}

/// Link targets `(...)` right after `]` on a line.
fn links(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let Some(end) = after.find(')') else { break };
        out.push(after[..end].trim().to_string());
        rest = &after[end..];
    }
    out
}

/// GitHub's anchor of a heading's title (without the `-N` of a repeat).
fn slug(title: &str) -> String {
    title
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// GitHub's anchors of a Markdown file's headings.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    for (_, line) in unfenced(text) {
        if !line.starts_with('#') {
            continue;
        }
        let slug = slug(line.trim_start_matches('#').trim());
        let mut anchor = slug.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{slug}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

#[test]
fn every_relative_link_in_the_documents_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for Document { path: file, name, text } in documents() {
        let dir = file.parent().unwrap();
        for (line, kept) in prose(&text) {
            for target in links(&kept) {
                if target.contains("://") || target.starts_with("mailto:") {
                    continue;
                }
                checked += 1;
                let (path, fragment) = match target.split_once('#') {
                    Some((p, f)) => (p, Some(f)),
                    None => (target.as_str(), None),
                };
                let resolved = if path.is_empty() { file.clone() } else { dir.join(path) };
                if !resolved.exists() {
                    broken.push(format!("{name}:{line}: {target}: no such file"));
                    continue;
                }
                if let Some(f) = fragment {
                    let is_md = resolved.extension().is_some_and(|e| e == "md");
                    let known = is_md && anchors(&std::fs::read_to_string(&resolved).unwrap()).contains(f);
                    if !known {
                        broken.push(format!("{name}:{line}: {target}: no heading with that anchor"));
                    }
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
    assert!(checked >= 40, "only {checked} links found: is the link parser still reading the documents?");
}

/// Paths in inline code spans (`` `src/x.rs` ``, `` `tools/check` ``, with
/// an optional `:line` or `::item` after them) on a line outside fenced
/// blocks.
fn code_paths(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (k, span) in line.split('`').enumerate() {
        if k % 2 == 0 {
            continue;
        }
        let span = span.trim();
        if !(span.starts_with("src/") || span.starts_with("tools/")) || span.contains(char::is_whitespace) {
            continue;
        }
        let path = span.split([':', '#']).next().unwrap_or(span).trim_end_matches(['.', ',', ')']);
        if path.contains(['*', '{', '<']) {
            continue; // a pattern, not a path
        }
        out.push(path.to_string());
    }
    out
}

#[test]
fn every_src_and_tools_path_in_the_documents_exists() {
    let mut missing = Vec::new();
    let mut checked = 0;
    for Document { name, text, .. } in documents() {
        for (number, line) in unfenced(&text) {
            for path in code_paths(line) {
                checked += 1;
                if !root().join(&path).exists() {
                    missing.push(format!("{name}:{number}: `{path}`: no such file or folder"));
                }
            }
        }
    }
    assert!(missing.is_empty(), "paths in the documents that do not exist:\n{}", missing.join("\n"));
    assert!(checked >= 20, "only {checked} src/ and tools/ paths found: is the parser still reading the documents?");
}

#[test]
fn code_paths_are_read_from_inline_code() {
    let got = code_paths("see `src/io/vdb/write.rs:42`, `tools/check` and `src/x/*.rs`, not src/y.rs or `cargo run`");
    assert_eq!(got, ["src/io/vdb/write.rs", "tools/check"]);
}

#[test]
fn anchors_follow_githubs_rule() {
    let a = anchors("# Speed against accuracy: `aurora bench`\n## Fang et al. 2008\n## `[[curtain]]`\n## Fang et al. 2008\n");
    let want: BTreeSet<String> =
        ["speed-against-accuracy-aurora-bench", "fang-et-al-2008", "curtain", "fang-et-al-2008-1"].map(String::from).into();
    assert_eq!(a, want);
}

/// The names at the repository's root: its top-level files and folders
/// (not hidden ones, nor the build's `target`).
fn root_entries() -> BTreeSet<String> {
    std::fs::read_dir(root())
        .expect("read the repository's root")
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.') && n != "target")
        .collect()
}

/// A reference in running text to a file of the repository, and to one of
/// its headings (as the heading's anchor).
#[derive(Debug, PartialEq)]
struct FileRef {
    path: String,
    anchor: Option<String>,
}

/// The references in `text` to files of the repository: words of path
/// characters whose first component is one of `roots` (`docs/guide.md`,
/// `blender/scene_schema.json`), each with the heading after it, written
/// as an anchor (`docs/guide.md#farms`) or quoted after a comma
/// (`docs/guide.md, "Progress as JSON"`, across a line break too).
/// Patterns (`src/*.rs`) are not references.
fn file_refs(text: &str, roots: &BTreeSet<String>) -> Vec<FileRef> {
    let is_path_char = |c: char| c.is_ascii_alphanumeric() || "_./#-*{}<>".contains(c);
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(start) = rest.find(is_path_char) {
        let after = &rest[start..];
        let len = after.find(|c: char| !is_path_char(c)).unwrap_or(after.len());
        let word = after[..len].trim_end_matches('.');
        let tail = &after[len..];
        rest = tail;
        let first = word.split(['/', '#']).next().unwrap_or("");
        if !roots.contains(first) || word.contains(['*', '{', '}', '<', '>']) {
            continue;
        }
        let (path, mut anchor) = match word.split_once('#') {
            Some((p, a)) => (p, Some(a.to_string())),
            None => (word, None),
        };
        if anchor.is_none() {
            if let Some(q) = tail.strip_prefix(", \"") {
                if let Some(end) = q.find('"') {
                    anchor = Some(slug(&q[..end].split_whitespace().collect::<Vec<_>>().join(" ")));
                }
            }
        }
        out.push(FileRef { path: path.trim_end_matches('/').to_string(), anchor });
    }
    out
}

/// What is wrong with a reference (its file or heading missing), if anything.
fn unresolved(r: &FileRef) -> Option<String> {
    let file = root().join(&r.path);
    if !file.exists() {
        return Some(format!("{}: no such file or folder", r.path));
    }
    let a = r.anchor.as_ref()?;
    let known = file.extension().is_some_and(|e| e == "md") && anchors(&std::fs::read_to_string(&file).unwrap()).contains(a);
    (!known).then(|| format!("{}#{a}: no heading with that anchor", r.path))
}

#[test]
fn file_references_are_read_with_their_headings() {
    let roots: BTreeSet<String> = ["docs", "README.md", "blender"].map(String::from).into();
    let text = "see docs/guide.md#farms, README.md and docs/physics.md, \"The red\n  trail\"; not DIR/aurora.vdb, \
                out/x.md or docs/images/*.png; blender/scene_schema.json.";
    let got = file_refs(text, &roots);
    let want = [
        FileRef { path: "docs/guide.md".into(), anchor: Some("farms".into()) },
        FileRef { path: "README.md".into(), anchor: None },
        FileRef { path: "docs/physics.md".into(), anchor: Some("the-red-trail".into()) },
        FileRef { path: "blender/scene_schema.json".into(), anchor: None },
    ];
    assert_eq!(got, want);
}

#[test]
fn every_section_reference_in_the_documents_resolves() {
    let roots = root_entries();
    let mut broken = Vec::new();
    let mut checked = 0;
    for Document { name, text, .. } in documents() {
        let outside: Vec<&str> = unfenced(&text).into_iter().map(|(_, line)| line).collect();
        // Source paths in the documents are checked above (inline code);
        // here the references to a document or a section of one.
        for r in file_refs(&outside.join("\n"), &roots) {
            if !(r.path.ends_with(".md") || r.anchor.is_some()) {
                continue;
            }
            checked += 1;
            if let Some(e) = unresolved(&r) {
                broken.push(format!("{name}: {e}"));
            }
        }
    }
    assert!(broken.is_empty(), "references in the documents that do not resolve:\n{}", broken.join("\n"));
    assert!(checked >= 40, "only {checked} references found: is the parser still reading the documents?");
}

#[allow(dead_code)]
#[path = "common/child.rs"]
mod child;

/// `aurora ARGS` run to success; its standard output.
fn aurora_stdout(args: &[&str]) -> String {
    let o = child::aurora(args);
    child::ok(&o);
    String::from_utf8(o.stdout).expect("UTF-8 output")
}

/// The commands `aurora --help` lists (not `help`).
fn commands() -> Vec<String> {
    let top = aurora_stdout(&["--help"]);
    let list = top.split("Commands:").nth(1).expect("aurora --help lists its commands");
    let names: Vec<String> = list
        .lines()
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(String::from)
        .collect();
    assert!(names.len() >= 8, "{names:?}");
    names
}

#[test]
fn every_repository_path_in_the_help_exists() {
    let roots = root_entries();
    let mut texts = vec![("aurora --help".to_string(), aurora_stdout(&["--help"]))];
    for c in commands() {
        texts.push((format!("aurora {c} --help"), aurora_stdout(&[&c, "--help"])));
    }
    let header: String = aurora_stdout(&["scene", "default"]).lines().take_while(|l| l.starts_with('#')).collect::<Vec<_>>().join("\n");
    texts.push(("aurora scene default (its header)".to_string(), header));
    let mut broken = Vec::new();
    let mut checked = 0;
    for (what, text) in &texts {
        for r in file_refs(text, &roots) {
            checked += 1;
            if let Some(e) = unresolved(&r) {
                broken.push(format!("{what}: {e}"));
            }
        }
        // "README" alone names no file: the README is README.md.
        if text.split(|c: char| !c.is_ascii_alphanumeric() && c != '.').any(|w| w == "README") {
            broken.push(format!("{what}: names README without a file (README.md) and a heading"));
        }
    }
    assert!(broken.is_empty(), "paths in the help that do not resolve:\n{}", broken.join("\n"));
    assert!(checked >= 6, "only {checked} repository paths found in the help: is the parser still reading it?");
}

#[test]
fn the_help_names_every_preset_and_every_profile_column() {
    let top = aurora_stdout(&["--help"]);
    let words = |t: &str| -> BTreeSet<String> { t.split(|c: char| !c.is_ascii_alphanumeric() && c != '_').map(String::from).collect() };
    let top_words = words(&top);
    let missing: Vec<&str> = aurora::scene::presets::names().filter(|n| !top_words.contains(*n)).collect();
    assert!(missing.is_empty(), "aurora --help does not name the presets {missing:?}");
    let profile_words = words(&aurora_stdout(&["profile", "--help"]));
    let columns: Vec<&str> = aurora::pipeline::altitude_profile::HEADER.split(',').collect();
    assert_eq!(columns.len(), 23, "{columns:?}");
    let missing: Vec<&&str> = columns.iter().filter(|c| !profile_words.contains(**c)).collect();
    assert!(missing.is_empty(), "aurora profile --help does not name the CSV's columns {missing:?}");
}

#[test]
fn the_scene_header_points_to_the_key_tables() {
    let out = aurora_stdout(&["scene", "default"]);
    let header: Vec<&str> = out.lines().take_while(|l| l.starts_with('#')).collect();
    assert!(
        header.iter().any(|l| l.contains("docs/scene.md")),
        "the header of `aurora scene` does not name docs/scene.md:\n{}",
        header.join("\n")
    );
    let tables = std::fs::read_to_string(root().join("docs/scene.md")).unwrap();
    assert!(tables.contains("`[[curtain]]`") && tables.contains("| key |"), "docs/scene.md no longer holds the key tables");
}

/// The uncompressed text chunks (tEXt, and iTXt without compression) of a
/// PNG file: (keyword, text).
fn png_text(bytes: &[u8]) -> Vec<(String, String)> {
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
    let latin1 = |b: &[u8]| b.iter().map(|&c| c as char).collect::<String>();
    let mut out = Vec::new();
    let mut pos = 8;
    while pos + 8 <= bytes.len() {
        let n = u32::from_be_bytes(bytes[pos..pos + 4].try_into().unwrap()) as usize;
        let (tag, data) = (&bytes[pos + 4..pos + 8], &bytes[pos + 8..(pos + 8 + n).min(bytes.len())]);
        pos += 12 + n;
        let Some(nul) = data.iter().position(|&c| c == 0) else { continue };
        let (key, rest) = (latin1(&data[..nul]), &data[nul + 1..]);
        match tag {
            b"tEXt" => out.push((key, latin1(rest))),
            // compression flag 0, method, language tag, translated keyword, text
            b"iTXt" if rest.first() == Some(&0) => {
                let mut parts = rest[2..].splitn(3, |&c| c == 0);
                let (_, _, text) = (parts.next(), parts.next(), parts.next().unwrap_or(&[]));
                out.push((key, String::from_utf8_lossy(text).into_owned()));
            }
            _ => {}
        }
    }
    out
}

#[test]
fn png_text_chunks_are_read() {
    let chunk = |tag: &[u8], data: &[u8]| [&(data.len() as u32).to_be_bytes()[..], tag, data, &[0u8; 4]].concat();
    let png = [
        &b"\x89PNG\r\n\x1a\n"[..],
        &chunk(b"IHDR", &[0; 13]),
        &chunk(b"tEXt", b"aurora_vdb_sha256\0abc  bake/aurora.vdb"),
        &chunk(b"iTXt", b"note\0\0\0en\0\0caf\xc3\xa9"),
        &chunk(b"IEND", b""),
    ]
    .concat();
    let want = [("aurora_vdb_sha256", "abc  bake/aurora.vdb"), ("note", "café")].map(|(k, v)| (k.to_string(), v.to_string()));
    assert_eq!(png_text(&png), want);
}

#[test]
fn the_readme_picture_of_the_default_scene_shows_the_pinned_default_bake() {
    let remake = "remake the README's pictures with `tools/readme_pictures` (docs/images/; tools/README.md)";
    let pins = std::fs::read_to_string(root().join("benchmarks/pins/current.txt")).unwrap();
    let pinned = pins.lines().find_map(|l| l.strip_suffix("  bake/aurora.vdb")).expect("benchmarks/pins/current.txt pins bake/aurora.vdb");
    let text = png_text(&std::fs::read(root().join("docs/images/default.png")).unwrap());
    let get = |k: &str| text.iter().find(|(key, _)| key == k).map(|(_, v)| v.as_str());
    let Some(vdbs) = get("aurora_vdb_sha256") else {
        panic!("docs/images/default.png records no source VDB (no aurora_vdb_sha256 text chunk): {remake}");
    };
    assert_eq!(get("aurora_command"), Some("tools/readme_pictures default"), "docs/images/default.png: {remake}");
    let lines: Vec<&str> = vdbs.lines().collect();
    assert_eq!(lines.len(), 1, "docs/images/default.png is rendered from one VDB: {vdbs}");
    let recorded = lines[0].split_whitespace().next().unwrap_or("");
    assert!(
        recorded == pinned,
        "docs/images/default.png was rendered from a VDB with SHA-256 {recorded}, but the default bake is now {pinned} \
         (benchmarks/pins/current.txt): the picture is older than the bake; {remake}"
    );
}

/// `n` with a comma between each three digits (12,573,748).
fn thousands(n: u64) -> String {
    let d = n.to_string();
    let mut out = String::new();
    for (i, c) in d.chars().enumerate() {
        if i > 0 && (d.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[test]
fn thousands_are_grouped_by_three() {
    assert_eq!(thousands(7), "7");
    assert_eq!(thousands(1_000), "1,000");
    assert_eq!(thousands(115_694_053), "115,694,053");
}

/// The default bake's bytes and active voxels in README.md and
/// docs/benchmarks.md are those of a bake made now, and that bake is the
/// pinned one (`benchmarks/pins/current.txt`): the figures follow the pins.
#[test]
fn the_default_bakes_size_in_the_documents_is_the_pinned_bakes() {
    let dir = std::env::temp_dir().join(format!("aurora-docs-figures-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    child::ok(&child::aurora(&["bake", "default", "-q", "--threads", "2", "--out", dir.to_str().unwrap()]));
    let vdb = dir.join("aurora.vdb");
    let sum = std::process::Command::new("sha256sum").arg(&vdb).output().expect("sha256sum runs");
    let sum = String::from_utf8_lossy(&sum.stdout).split_whitespace().next().unwrap_or("").to_string();
    let pins = std::fs::read_to_string(root().join("benchmarks/pins/current.txt")).unwrap();
    let pinned = pins.lines().find_map(|l| l.strip_suffix("  bake/aurora.vdb")).expect("the pins hold bake/aurora.vdb");
    assert_eq!(sum, pinned, "the default bake is not the pinned one: rerun benchmarks/pins/pin.sh");
    let bytes = std::fs::metadata(&vdb).unwrap().len();
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("bake.json")).unwrap()).unwrap();
    let voxels = report["stats"]["active_voxels"].as_u64().expect("bake.json has stats.active_voxels");
    std::fs::remove_dir_all(&dir).unwrap();
    let mb = format!("{:.1} MB", bytes as f64 / 1e6);
    for doc in ["README.md", "docs/benchmarks.md"] {
        let text = std::fs::read_to_string(root().join(doc)).unwrap();
        for want in [&mb, &thousands(bytes), &thousands(voxels)] {
            assert!(text.contains(want.as_str()), "{doc} does not give the default bake's {want} ({bytes} bytes, {voxels} active voxels)");
        }
    }
}

#[test]
fn the_readme_lists_every_command() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let section = readme.split("\n## The commands\n").nth(1).expect("README.md has \"## The commands\"");
    for c in commands() {
        assert!(section.contains(&format!("\naurora {c} ")), "README.md's command list has no `aurora {c}` line");
    }
}

#[test]
fn no_help_says_a_command_writes_a_report_it_does_not() {
    for c in commands() {
        let help = aurora_stdout(&[&c, "--help"]).split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(!help.contains("Recorded in bake.json"), "aurora {c} --help says --set is recorded in a bake.json it does not write");
    }
}
