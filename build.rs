//! Exports `AURORA_BUILD_HASH`: a hash of the source the binary is built
//! from, the build part of a bake's identity (`src/pipeline/bake/identity.rs`). The
//! crate's version is the same on every commit, so it cannot tell two builds
//! apart; the git revision is not always there (a source tarball) and does
//! not see uncommitted edits. So the bytes are hashed: every `.rs` file under
//! `src/`, every file under `data/` (the atmosphere table and the reference
//! data compiled in with `include_str!`), `Cargo.toml` and `Cargo.lock` (the
//! dependencies' versions), each with its path, in sorted order. About 1.5 MB
//! read once per change: milliseconds.
//!
//! Cargo reruns this script when anything under `src/` or `data/` changes
//! (a `rerun-if-changed` directory is scanned recursively), or either
//! manifest, or the script itself.

use std::path::{Path, PathBuf};

fn files(dir: &Path, keep: &dyn Fn(&Path) -> bool, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        match e.file_type() {
            Ok(t) if t.is_dir() => files(&p, keep, out),
            Ok(t) if t.is_file() && keep(&p) => out.push(p),
            _ => {}
        }
    }
}

/// FNV-1a, 64 bit (as `aurora::scene::fnv1a`), continued from `h`.
fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

fn main() {
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    for p in ["src", "data", "Cargo.toml", "Cargo.lock", "build.rs"] {
        println!("cargo:rerun-if-changed={p}");
    }
    let mut list = Vec::new();
    files(&root.join("src"), &|p| p.extension().is_some_and(|e| e == "rs"), &mut list);
    files(&root.join("data"), &|_| true, &mut list);
    list.extend(["Cargo.toml", "Cargo.lock"].map(|n| root.join(n)).into_iter().filter(|p| p.is_file()));
    let mut named: Vec<(String, PathBuf)> =
        list.into_iter().map(|p| (p.strip_prefix(&root).unwrap_or(&p).to_string_lossy().replace('\\', "/"), p)).collect();
    named.sort();
    let mut h = 0xcbf29ce484222325u64;
    for (name, path) in &named {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("build.rs: cannot read {}: {e}", path.display()));
        h = fnv1a(h, name.as_bytes());
        h = fnv1a(h, &[0]);
        h = fnv1a(h, &(bytes.len() as u64).to_le_bytes());
        h = fnv1a(h, &bytes);
    }
    println!("cargo:rustc-env=AURORA_BUILD_HASH={h:016x}");
}
