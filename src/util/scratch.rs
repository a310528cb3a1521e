//! The unit tests' scratch folders under the system's temporary folder,
//! the FIFOs they plant there and the names they find there (compiled for
//! tests only).

use std::path::{Path, PathBuf};

/// A fresh empty folder `aurora-<group>-<pid>-<name>` under the system's
/// temporary folder (whatever was there is removed first). `group` names
/// the test module; tests running at the same time never share a folder.
pub fn folder(group: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aurora-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Makes a FIFO at `p`.
pub fn mkfifo(p: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).unwrap();
    // SAFETY: a NUL-terminated path; the result is checked.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0, "mkfifo {}", p.display());
}

/// The names in folder `d`, sorted.
pub fn file_names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}
