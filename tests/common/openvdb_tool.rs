//! OpenVDB's own writer (`benchmarks/vdb_write/openvdb_write_bench.cpp`), compiled into
//! `target/` on first use and whenever the source is newer, and the names
//! it gives the compression modes. Shared by the integration tests
//! (`tests/common`) and `examples/vdb_write_bench.rs` (which includes this
//! file by path).

use aurora::scene::Compression;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The compiled tool's path under `root` (the crate's folder), building it
/// if missing or stale. Errors say what failed and to run `tools/setup`.
pub fn build(root: &Path) -> Result<PathBuf, String> {
    let src = root.join("benchmarks/vdb_write/openvdb_write_bench.cpp");
    let bin = root.join("target/openvdb_write_bench");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified());
    let stale = match (modified(&src), modified(&bin)) {
        (Ok(s), Ok(b)) => s > b,
        _ => true,
    };
    if stale {
        // Compile to a private name, then rename: concurrent users never see a partial binary.
        let tmp = bin.with_extension(format!("tmp{}", std::process::id()));
        let out = Command::new("g++")
            .args(["-O2", "-std=c++17"])
            .arg(&src)
            .arg("-o")
            .arg(&tmp)
            .args(["-lopenvdb", "-ltbb", "-lImath-3_1", "-lpthread"])
            .output()
            .map_err(|e| format!("cannot run g++: {e}; run tools/setup"))?;
        if !out.status.success() {
            return Err(format!(
                "compiling {} failed (run tools/setup for libopenvdb-dev and libboost-dev):\n{}",
                src.display(),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        std::fs::rename(&tmp, &bin).map_err(|e| format!("cannot install {}: {e}", bin.display()))?;
    }
    Ok(bin)
}

/// The tool's name of a compression mode (its third argument).
pub fn mode_name(c: Compression) -> &'static str {
    match c {
        Compression::None => "none",
        Compression::Zip => "zip",
        Compression::ActiveMask => "active-mask",
        Compression::ZipActiveMask => "zip+active-mask",
        Compression::Blosc => "blosc",
        Compression::BloscActiveMask => "blosc+active-mask",
    }
}
