//! The documents' relative links resolve: every `[text](target)` and
//! `![alt](target)` outside code in README.md, docs/**/*.md and
//! blender/README.md names a file or folder of the repository, and a
//! `#fragment` names a heading of the target Markdown file (GitHub's anchor
//! rule: lower case, punctuation other than `-` and `_` dropped, spaces to
//! `-`, a repeated heading numbered `-1`, `-2`, ...). Web links are not
//! followed. And every path in inline code that starts with `src/` or
//! `tools/` (`src/pipeline/beams/walk.rs`, `tools/check`) names a file or
//! folder of the repository: the documents follow the tree when it moves.

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
    let mut out = vec![root().join("README.md"), root().join("blender/README.md")];
    walk(&root().join("docs"), &mut out);
    out
}

/// The text outside fenced code blocks and inline code spans, line by line
/// (line numbers kept).
fn prose(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced || line.starts_with("    ") && !line.trim_start().starts_with(['-', '|', '*']) {
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
        out.push((i + 1, kept));
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

/// GitHub's anchors of a Markdown file's headings.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let title = line.trim_start_matches('#').trim();
        let slug: String = title
            .to_lowercase()
            .chars()
            .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
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
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        let dir = file.parent().unwrap();
        let name = file.strip_prefix(root()).unwrap().display().to_string();
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
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        let mut fenced = false;
        for (i, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("```") {
                fenced = !fenced;
                continue;
            }
            if fenced {
                continue;
            }
            for path in code_paths(line) {
                checked += 1;
                if !root().join(&path).exists() {
                    missing.push(format!("{name}:{}: `{path}`: no such file or folder", i + 1));
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
