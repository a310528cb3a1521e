//! The README's quick start, as a newcomer types it on a fresh clone: the
//! first line of its block (`cargo install --locked --path .`) installs `aurora`,
//! and every other line is an `aurora` command run by the shell, in an
//! empty folder, with the installed `bin/` first on PATH. The commands are
//! read from README.md, so the test follows the README when it changes.
//!
//! The install goes to a scratch root (`--root`) and builds in this run's
//! own target folder (`CARGO_TARGET_DIR`), offline (the one word added to
//! the README's line) and from Cargo.lock (the README's `--locked`: without it
//! cargo resolves newer dependencies and rebuilds them all):
//! after `cargo build --release` (as tools/check runs it) it compiles
//! nothing, takes a fraction of a second and leaves the target folder's
//! `aurora`, which the other tests run, as it was (Cargo.toml asks for the
//! dev-dependencies' features, so that a test build and a plain build are
//! one build). The commands then take what a default bake and render take.

use crate::common;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The lines of the first fenced block after README.md's "## Quick start"
/// heading.
fn quick_start_block(readme: &str) -> Vec<String> {
    let section = readme.split("\n## Quick start\n").nth(1).expect("README.md has a \"## Quick start\" section");
    let section = section.split("\n## ").next().unwrap();
    let fence = section.find("```").expect("the quick start has a fenced block");
    let body = &section[fence..];
    let body = &body[body.find('\n').unwrap() + 1..];
    let end = body.find("```").expect("the quick start's block is closed");
    body[..end].lines().map(str::trim).filter(|l| !l.is_empty()).map(String::from).collect()
}

/// The words of a shell line before its comment.
fn words(line: &str) -> Vec<&str> {
    line.split(" #").next().unwrap().split_whitespace().collect()
}

/// The files a command line says it writes: the values of `--out` and
/// `--png`, and the target of `>`.
fn outputs(line: &str) -> Vec<String> {
    let w = words(line);
    w.windows(2).filter(|p| matches!(p[0], "--out" | "--png" | ">")).map(|p| p[1].to_string()).collect()
}

/// The cargo target folder of this run: the folder above the profile
/// folder holding the `aurora` binary, and that profile's name.
fn target_dir() -> (PathBuf, String) {
    let exe = Path::new(common::child::AURORA_BIN);
    let profile_dir = exe.parent().unwrap();
    let profile = profile_dir.file_name().unwrap().to_string_lossy().into_owned();
    (profile_dir.parent().unwrap().to_path_buf(), profile)
}

#[test]
fn the_block_is_read_from_the_readme() {
    let readme = "# x\n\n## Quick start\n\ntext\n\n```sh\ncargo install --path .   # here\n\naurora scene default > my.toml\n```\n\n## Next\n```sh\naurora no\n```\n";
    assert_eq!(quick_start_block(readme), ["cargo install --path .   # here", "aurora scene default > my.toml"]);
    assert_eq!(words("cargo install --path .   # here"), ["cargo", "install", "--path", "."]);
    assert_eq!(outputs("aurora render a.toml --vdb o/a.vdb --out f.exr --png f.png  # x"), ["f.exr", "f.png"]);
    assert_eq!(outputs("aurora scene default > my.toml"), ["my.toml"]);
}

#[test]
fn the_readme_quick_start_runs_as_written_after_its_install_line() {
    let readme = std::fs::read_to_string(common::repo_root().join("README.md")).unwrap();
    let block = quick_start_block(&readme);
    let (install, commands) = block.split_first().expect("the quick start is not empty");
    assert_eq!(
        words(install),
        ["cargo", "install", "--locked", "--path", "."],
        "the quick start begins with its install line, from Cargo.lock"
    );
    assert!(commands.len() >= 3, "{commands:?}");

    let d = common::scratch("quick_start", "fresh_clone");
    let (root, work) = (d.join("root"), d.join("work"));
    std::fs::create_dir_all(&work).unwrap();
    let (target, profile) = target_dir();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut c = Command::new(&cargo);
    c.args(&words(install)[1..]).arg("--root").arg(&root).arg("--offline");
    if profile == "debug" {
        c.arg("--debug");
    }
    let o = c.current_dir(common::repo_root()).env("CARGO_TARGET_DIR", &target).stdin(std::process::Stdio::null()).output().unwrap();
    assert!(o.status.success(), "{install}: {}\n{}", o.status, String::from_utf8_lossy(&o.stderr));
    let bin = root.join("bin");
    assert!(bin.join("aurora").is_file(), "cargo install put no aurora in {}", bin.display());

    let path =
        std::env::join_paths(std::iter::once(bin.clone()).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())))
            .unwrap();
    let sh = |line: &str| {
        Command::new("sh").arg("-c").arg(line).current_dir(&work).env("PATH", &path).stdin(std::process::Stdio::null()).output().unwrap()
    };
    let found = sh("command -v aurora");
    assert_eq!(String::from_utf8_lossy(&found.stdout).trim(), bin.join("aurora").to_str().unwrap(), "another aurora comes first on PATH");
    for line in commands {
        assert_eq!(words(line).first(), Some(&"aurora"), "a quick-start line that is not an aurora command: {line}");
        let o = sh(line);
        assert!(o.status.success(), "{line}: {}\n{}", o.status, String::from_utf8_lossy(&o.stderr));
        for f in outputs(line) {
            let p = work.join(&f);
            let size = std::fs::metadata(&p).map(|m| if m.is_dir() { 1 } else { m.len() }).unwrap_or(0);
            assert!(size > 0, "{line}: wrote no {f}");
        }
    }
}
