//! Output files that are ours and whole.
//!
//! Every file `aurora` writes goes through this module, under three rules:
//!
//! 1. **Only a regular file of ours, or a new name, is ever replaced.** Before
//!    anything is written, and again just before the final rename, the
//!    destination is examined with `lstat` (no link is followed): it must be
//!    absent or a regular file. A symlink, a directory, a device node, a FIFO
//!    or a socket is refused with [`AtomicError::NotRegular`]. (A rename over
//!    a device node does not write through it but replaces its directory entry:
//!    as root, `--out /dev/full` would replace the system's `/dev/full`.)
//! 2. **A file appears whole or not at all.** Bytes go to a temporary name in
//!    the destination's folder, `.<name>.tmp<pid>-<n>.<host>` (the name cut so
//!    that it fits the file system's 255 bytes), created with
//!    `O_EXCL` (so nothing planted at that name is written through), and are
//!    renamed over the destination at the end. On any error, or when a
//!    [`TempFile`] is dropped uncommitted, the temporary is removed.
//! 3. **A killed writer's temporaries are removed by the next writer, and
//!    only then.** A writer holds an exclusive advisory lock (`flock`) on its
//!    temporary while it exists. A later writer of the same name removes every
//!    `.<name>.tmp*` whose lock it can take: the kernel drops a lock when its
//!    process dies, so a free lock means the owner is gone; a live writer's
//!    temporary is never touched.
//!
//! Files that belong together (a bake's VDB, USD stage and report) form an
//! [`Unit`]: a lock per unit serialises writers ([`UnitLock`]; a second
//! writer of the same unit waits), every member is staged as a temporary
//! first (where a full disk or an interrupt strikes), and only then are they
//! renamed, the unit's *manifest* (its report, which names the other members
//! and their sizes and hashes) last. The old manifest is removed before the
//! first rename, so at every instant the folder holds either the previous
//! complete set (manifest present and matching), or a set without a manifest
//! (incomplete, for the microseconds of the renames or after a crash between
//! them), never a manifest beside another bake's members.
//!
//! Like OpenVDB, nothing is `fsync`ed: durability across a power loss is the
//! file system's business.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why an output could not be written.
#[derive(Debug, thiserror::Error)]
pub enum AtomicError {
    /// The destination exists and is not a regular file.
    #[error("{}: is {kind}, not a regular file: refusing to replace it (give a new file name, or the path of a regular file to overwrite)", path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    /// The output folder exists and is not a folder, or cannot be created or written.
    #[error("output folder {}: {message}", path.display())]
    Folder { path: PathBuf, message: String },
    /// The destination's name is longer than the file system takes.
    #[error("{}: a name of {bytes} bytes, longer than the {NAME_MAX} bytes a file name may have: give a shorter name", path.display())]
    NameTooLong { path: PathBuf, bytes: usize },
    /// An I/O error while writing or renaming.
    #[error("cannot write {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
}

impl AtomicError {
    /// True when the error is the user's choice of output (exit status 2):
    /// a destination that is not ours to replace, or a folder that is not one.
    pub fn is_input(&self) -> bool {
        matches!(self, AtomicError::NotRegular { .. } | AtomicError::Folder { .. } | AtomicError::NameTooLong { .. })
    }
}

/// For callers whose error type holds an `std::io::Error`: the I/O error
/// itself, or the refusal as an error of kind `InvalidInput`.
impl From<AtomicError> for std::io::Error {
    fn from(e: AtomicError) -> Self {
        match e {
            AtomicError::Io { source, .. } => source,
            other => std::io::Error::new(std::io::ErrorKind::InvalidInput, other.to_string()),
        }
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> AtomicError + '_ {
    move |source| AtomicError::Io { path: path.to_path_buf(), source }
}

/// What kind of thing sits at `path`, without following a final symlink;
/// `None` when nothing does.
fn kind_at(path: &Path) -> std::io::Result<Option<&'static str>> {
    match std::fs::symlink_metadata(path) {
        Ok(m) => Ok(Some(crate::util::input_file::kind_name(m.file_type()))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Ok when `path` may be replaced: nothing is there, or a regular file.
pub fn check_replaceable(path: &Path) -> Result<(), AtomicError> {
    if let Some(n) = path.file_name().filter(|n| n.len() > NAME_MAX) {
        return Err(AtomicError::NameTooLong { path: path.to_path_buf(), bytes: n.len() });
    }
    match kind_at(path).map_err(io_err(path))? {
        None | Some("regular") => Ok(()),
        Some(kind) => Err(AtomicError::NotRegular { path: path.to_path_buf(), kind }),
    }
}

/// Creates `dir` if missing and checks that it is a folder we can write in
/// (a probe file is created and removed), before any long work starts.
pub fn prepare_folder(dir: &Path) -> Result<(), AtomicError> {
    let folder = |message: String| AtomicError::Folder { path: dir.to_path_buf(), message };
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(folder("exists and is not a folder".into())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::create_dir_all(dir).map_err(|e| folder(format!("cannot create it: {e}")))?
        }
        Err(e) => return Err(folder(e.to_string())),
    }
    let probe = dir.join(format!(".aurora-write-probe{}-{}", std::process::id(), next_serial()));
    let f = OpenOptions::new().write(true).create_new(true).open(&probe).map_err(|e| folder(format!("not writable: {e}")))?;
    drop(f);
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// `.HOST` for temporary names, so writers on several hosts sharing a folder
/// (farm shards in containers that all run as PID 1) never pick one name.
fn host_tag() -> String {
    static TAG: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TAG.get_or_init(|| {
        let h = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .or_else(|_| std::env::var("HOSTNAME"))
            .or_else(|_| std::env::var("COMPUTERNAME"))
            .unwrap_or_default();
        let h: String = h.trim().chars().filter(|c| c.is_ascii_alphanumeric() || *c == '-').take(64).collect();
        if h.is_empty() {
            String::new()
        } else {
            format!(".{h}")
        }
    })
    .clone()
}

static SERIAL: AtomicU64 = AtomicU64::new(0);

fn next_serial() -> u64 {
    SERIAL.fetch_add(1, Ordering::Relaxed)
}

fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn file_name(path: &Path) -> Result<String, AtomicError> {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| AtomicError::Io { path: path.to_path_buf(), source: std::io::Error::other("the path has no file name") })
}

/// The longest file name most file systems take (`NAME_MAX`), bytes.
const NAME_MAX: usize = 255;

/// The most bytes a temporary's name adds after its stem: `.tmp` and the
/// unique part (a 32-bit pid, `-`, a 64-bit serial, the host tag of at most
/// 65 bytes).
const TEMP_SUFFIX_MAX: usize = 4 + 10 + 1 + 20 + 65;

/// `name` as it appears in its temporaries' names: whole, or cut (at a
/// character's boundary) so that `.<stem>.tmp<unique>` fits in
/// [`NAME_MAX`] bytes. An output whose own name fits is never lost to its
/// temporary's (names of up to 255 bytes); two names sharing a long start
/// share a stem, which costs nothing: a sweep removes only the temporaries
/// no live writer holds locked.
fn temp_stem(name: &str) -> &str {
    let room = NAME_MAX - 1 - TEMP_SUFFIX_MAX;
    if name.len() <= room {
        return name;
    }
    let mut end = room;
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name[..end]
}

/// The prefix of every temporary of `name`: `.<name>.tmp` (the name cut by
/// [`temp_stem`]).
fn temp_prefix(name: &str) -> String {
    format!(".{}.tmp", temp_stem(name))
}

/// The prefix of a temporary in the instant between its creation and its lock.
fn fresh_prefix(name: &str) -> String {
    format!(".{}.new", temp_stem(name))
}

/// A `.new` file older than this was left by a writer that died between
/// creating and locking it (microseconds): it is swept too.
const FRESH_GRACE: std::time::Duration = std::time::Duration::from_secs(60);

/// Removes the temporaries of `path` (`.<name>.tmp*` beside it) whose owner is
/// gone (their lock is free). Returns how many were removed. Temporaries of a
/// live writer (locked) are left alone; so is anything that is not a regular
/// file.
pub fn sweep_stale(path: &Path) -> Result<usize, AtomicError> {
    let dir = folder_of(path);
    let name = file_name(path)?;
    let (prefix, fresh) = (temp_prefix(&name), fresh_prefix(&name));
    let entries = match std::fs::read_dir(&dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(AtomicError::Io { path: dir, source: e }),
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let entry_name = entry.file_name().to_string_lossy().into_owned();
        let p = entry.path();
        if entry_name.starts_with(&fresh) {
            let old = std::fs::symlink_metadata(&p).ok().and_then(|m| m.modified().ok()).and_then(|t| t.elapsed().ok());
            if old.is_none_or(|age| age <= FRESH_GRACE) {
                continue;
            }
        } else if !entry_name.starts_with(&prefix) {
            continue;
        }
        if kind_at(&p).ok().flatten() != Some("regular") {
            continue;
        }
        let Ok(f) = OpenOptions::new().read(true).open(&p) else { continue };
        if f.try_lock().is_ok() {
            // Free lock: the writer died (or finished and failed to clean up).
            if std::fs::remove_file(&p).is_ok() {
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// A temporary file beside its destination, locked while it exists; renamed
/// over the destination by [`TempFile::commit`], removed if dropped first.
#[derive(Debug)]
pub struct TempFile {
    tmp: PathBuf,
    dest: PathBuf,
    file: Option<File>,
}

impl TempFile {
    /// Checks that `dest` may be replaced, removes its stale temporaries and
    /// creates a new, locked temporary for it.
    pub fn create(dest: &Path) -> Result<Self, AtomicError> {
        check_replaceable(dest)?;
        sweep_stale(dest)?;
        let name = file_name(dest)?;
        let unique = format!("{}-{}{}", std::process::id(), next_serial(), host_tag());
        let tmp = folder_of(dest).join(format!("{}{unique}", temp_prefix(&name)));
        // Created and locked under a name sweepers ignore, then renamed to the
        // temporary name: a sweeper never sees an unlocked live temporary.
        let fresh = folder_of(dest).join(format!("{}{unique}", fresh_prefix(&name)));
        let file = OpenOptions::new().read(true).write(true).create_new(true).open(&fresh).map_err(io_err(&fresh))?;
        if let Err(e) = file.lock().and_then(|_| std::fs::rename(&fresh, &tmp)) {
            let _ = std::fs::remove_file(&fresh);
            return Err(AtomicError::Io { path: tmp, source: e });
        }
        Ok(Self { tmp, dest: dest.to_path_buf(), file: Some(file) })
    }

    /// The open temporary, to write into.
    pub fn file(&mut self) -> &mut File {
        self.file.as_mut().expect("an uncommitted TempFile holds its file")
    }

    /// The temporary's path (for error messages of writers that take a path).
    pub fn temp_path(&self) -> &Path {
        &self.tmp
    }

    /// The destination.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Renames the temporary over the destination, after checking once more
    /// that the destination is absent or a regular file.
    pub fn commit(mut self) -> Result<(), AtomicError> {
        if let Some(mut f) = self.file.take() {
            f.flush().map_err(io_err(&self.tmp))?;
            // Keep the lock (the open file) until the rename is done.
            check_replaceable(&self.dest)?;
            std::fs::rename(&self.tmp, &self.dest).map_err(io_err(&self.dest))?;
            drop(f);
        }
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Writes `bytes` to `path` through a locked temporary and a rename: readers
/// never see a half-written file, and only a regular file is replaced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), AtomicError> {
    let mut t = TempFile::create(path)?;
    t.file().write_all(bytes).map_err(io_err(path))?;
    t.commit()
}

/// An exclusive lock on one output unit: `.<stem>.lock` in the output folder
/// (for example `.aurora.lock` for a bake, `.aurora.0001.lock` for frame 1 of
/// a sequence, so shards can share a folder). Released when dropped or when
/// the process dies.
///
/// The lock file is removed on release, so finished folders hold only their
/// outputs. That is safe because a waiter, once it holds the lock, checks that
/// the name still refers to the file it locked (same device and inode) and
/// starts over otherwise: the holder unlinks before it unlocks, so a waiter
/// that wins the old file sees it gone.
#[derive(Debug)]
pub struct UnitLock {
    path: PathBuf,
    file: Option<File>,
    /// Its slot in [`HELD`], if one was free.
    slot: Option<usize>,
}

/// How many held locks [`remove_held_locks`] knows at once (a bake holds
/// one; a sequence one per frame it commits, one at a time).
const HELD_SLOTS: usize = 16;

/// The paths of the locks this process holds, as C strings, for
/// [`remove_held_locks`], which a signal handler calls: only atomic loads
/// there. A path is never freed (a few bytes per lock taken), so a handler
/// running beside a release never reads freed memory.
static HELD: [std::sync::atomic::AtomicPtr<std::ffi::c_char>; HELD_SLOTS] =
    [const { std::sync::atomic::AtomicPtr::new(std::ptr::null_mut()) }; HELD_SLOTS];

/// Windows: no signal handler removes locks there (`cli::out`), so none is
/// recorded.
#[cfg(not(unix))]
fn hold(_path: &Path) -> Option<usize> {
    None
}

#[cfg(unix)]
fn hold(path: &Path) -> Option<usize> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?.into_raw();
    let slot = HELD.iter().position(|s| s.compare_exchange(std::ptr::null_mut(), c, Ordering::SeqCst, Ordering::SeqCst).is_ok());
    if slot.is_none() {
        // SAFETY: `c` came from `into_raw` above and was not shared.
        drop(unsafe { std::ffi::CString::from_raw(c) });
    }
    slot
}

/// Removes the lock files this process holds: for a handler of SIGINT or
/// SIGTERM, so that an interrupted bake leaves no `.aurora.lock` behind
/// (the kernel drops the locks themselves when the process ends). Only
/// async-signal-safe calls: atomic loads and `unlink`.
pub fn remove_held_locks() {
    #[cfg(unix)]
    for s in &HELD {
        let p = s.load(Ordering::SeqCst);
        if !p.is_null() {
            // SAFETY: `p` is a NUL-terminated path that is never freed.
            unsafe { libc::unlink(p) };
        }
    }
}

/// Whether two metadata are of one file: device and inode on Unix. On
/// Windows stable Rust's std gives neither, and the lock's path still
/// being there is taken as the same file: a lock removed and made anew by
/// another writer between the two looks is not told apart there.
#[cfg(unix)]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

#[cfg(not(unix))]
fn same_file(_: &std::fs::Metadata, _: &std::fs::Metadata) -> bool {
    true
}

impl UnitLock {
    /// Takes the lock, waiting while another writer holds it; `on_wait` is
    /// called once if it has to wait (to tell the user).
    pub fn acquire(dir: &Path, stem: &str, on_wait: impl FnOnce()) -> Result<Self, AtomicError> {
        let path = dir.join(format!(".{stem}.lock"));
        let mut on_wait = Some(on_wait);
        loop {
            check_replaceable(&path)?;
            let file = OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(io_err(&path))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    if let Some(f) = on_wait.take() {
                        f();
                    }
                    file.lock().map_err(io_err(&path))?;
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(AtomicError::Io { path, source: e }),
            }
            let held = file.metadata().map_err(io_err(&path))?;
            match std::fs::symlink_metadata(&path) {
                Ok(now) if same_file(&now, &held) => {
                    let slot = hold(&path);
                    return Ok(Self { path, file: Some(file), slot });
                }
                // The previous holder removed it: lock the new one.
                _ => continue,
            }
        }
    }
}

impl Drop for UnitLock {
    fn drop(&mut self) {
        if let Some(f) = self.file.take() {
            if let Some(i) = self.slot.take() {
                // The path is left allocated (see `HELD`).
                HELD[i].store(std::ptr::null_mut(), Ordering::SeqCst);
            }
            let _ = std::fs::remove_file(&self.path);
            drop(f);
        }
    }
}

/// Files that become visible together: staged as temporaries, then renamed,
/// the manifest last (see the module docs).
#[derive(Debug, Default)]
pub struct Unit {
    members: Vec<TempFile>,
    manifest: Option<TempFile>,
}

impl Unit {
    pub fn new() -> Self {
        Self::default()
    }

    /// Stages a member (written in full before anything is renamed).
    pub fn stage(&mut self, file: TempFile) {
        self.members.push(file);
    }

    /// Stages the manifest, renamed last.
    pub fn stage_manifest(&mut self, file: TempFile) {
        self.manifest = Some(file);
    }

    /// Makes the unit visible: the old manifest removed, the members renamed,
    /// then the new manifest. Every destination is checked before the first
    /// rename, so a refusal changes nothing.
    pub fn commit(mut self) -> Result<(), AtomicError> {
        for t in self.members.iter().chain(self.manifest.iter()) {
            check_replaceable(t.dest())?;
        }
        if let Some(m) = &self.manifest {
            match std::fs::remove_file(m.dest()) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(AtomicError::Io { path: m.dest().to_path_buf(), source: e }),
            }
        }
        for t in self.members.drain(..) {
            t.commit()?;
        }
        if let Some(m) = self.manifest.take() {
            m.commit()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::scratch::{folder, mkfifo};

    #[test]
    fn writes_new_and_replaces_regular() {
        let d = folder("atomic", "regular");
        let p = d.join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        // Nothing else left in the folder.
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    }

    #[test]
    fn refuses_symlink_fifo_directory() {
        let d = folder("atomic", "refuse");
        let target = d.join("target.txt");
        std::fs::write(&target, b"keep").unwrap();
        let link = d.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write_atomic(&link, b"x").unwrap_err();
        assert!(matches!(e, AtomicError::NotRegular { kind: "a symbolic link", .. }), "{e}");
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");

        let fifo = d.join("fifo");
        mkfifo(&fifo);
        let e = write_atomic(&fifo, b"x").unwrap_err();
        assert!(matches!(e, AtomicError::NotRegular { kind: "a FIFO", .. }), "{e}");
        assert!(e.is_input());

        let sub = d.join("sub");
        std::fs::create_dir(&sub).unwrap();
        assert!(matches!(write_atomic(&sub, b"x").unwrap_err(), AtomicError::NotRegular { kind: "a directory", .. }));
        // No temporaries left behind by the refusals.
        let names: Vec<_> = std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 4, "{names:?}");
    }

    /// Outputs with names of up to 255 bytes (ASCII and multi-byte) are
    /// written: their temporaries' names fit the file system's limit.
    #[test]
    fn names_up_to_the_file_systems_limit_are_written() {
        let d = crate::util::scratch::folder("atomic", "long-names");
        for name in ["a".repeat(255), format!("{}.exr", "b".repeat(251)), format!("{}.png", "é".repeat(125)), "c".repeat(150)] {
            assert!(name.len() <= 255);
            let dest = d.join(&name);
            let mut t = TempFile::create(&dest).unwrap_or_else(|e| panic!("{} bytes: {e}", name.len()));
            assert!(t.temp_path().file_name().unwrap().len() <= 255);
            t.file().write_all(b"x").unwrap();
            t.commit().unwrap();
            assert_eq!(std::fs::read(&dest).unwrap(), b"x");
        }
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 4, "no temporaries left");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn dropped_temp_is_removed_and_stale_temps_swept_only_when_unlocked() {
        let d = folder("atomic", "sweep");
        let p = d.join("out.vdb");
        {
            let mut t = TempFile::create(&p).unwrap();
            t.file().write_all(b"partial").unwrap();
        }
        assert!(!d.join("out.vdb").exists());
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);

        // A live writer's temporary (locked) survives a sweep.
        let mut live = TempFile::create(&p).unwrap();
        live.file().write_all(b"live").unwrap();
        assert_eq!(sweep_stale(&p).unwrap(), 0);
        assert!(live.temp_path().exists());
        // A dead writer's (unlocked) temporary is swept.
        let stale = d.join(".out.vdb.tmp999999-0");
        std::fs::write(&stale, b"stale").unwrap();
        assert_eq!(sweep_stale(&p).unwrap(), 1);
        assert!(!stale.exists());
        live.commit().unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"live");
    }

    #[test]
    fn unit_commits_manifest_last_and_refusal_changes_nothing() {
        let d = folder("atomic", "unit");
        let (a, m) = (d.join("a.bin"), d.join("manifest.json"));
        std::fs::write(&a, b"old a").unwrap();
        std::fs::write(&m, b"old manifest").unwrap();
        let mut u = Unit::new();
        let mut ta = TempFile::create(&a).unwrap();
        ta.file().write_all(b"new a").unwrap();
        u.stage(ta);
        let mut tm = TempFile::create(&m).unwrap();
        tm.file().write_all(b"new manifest").unwrap();
        u.stage_manifest(tm);
        u.commit().unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        assert_eq!(std::fs::read(&m).unwrap(), b"new manifest");

        // A member whose destination turned into a FIFO after staging: nothing renamed.
        let b = d.join("b.bin");
        let mut u = Unit::new();
        let mut ta = TempFile::create(&a).unwrap();
        ta.file().write_all(b"newer a").unwrap();
        u.stage(ta);
        let tb = TempFile::create(&b).unwrap();
        u.stage(tb);
        mkfifo(&b);
        assert!(u.commit().is_err());
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        assert_eq!(std::fs::read(&m).unwrap(), b"new manifest");
    }

    #[test]
    fn unit_lock_is_exclusive() {
        let d = folder("atomic", "lock");
        let l1 = UnitLock::acquire(&d, "aurora", || panic!("must not wait")).unwrap();
        let f = OpenOptions::new().read(true).open(d.join(".aurora.lock")).unwrap();
        assert!(f.try_lock().is_err(), "the unit lock is held");
        // A second writer waits until the first releases.
        let (tx, rx) = std::sync::mpsc::channel();
        let d2 = d.clone();
        let waiter = std::thread::spawn(move || {
            let l2 = UnitLock::acquire(&d2, "aurora", || tx.send("waiting").unwrap()).unwrap();
            drop(l2);
        });
        assert_eq!(rx.recv_timeout(std::time::Duration::from_secs(120)).unwrap(), "waiting");
        drop(l1);
        waiter.join().unwrap();
        // Released and removed: the folder is empty again.
        assert!(!d.join(".aurora.lock").exists());
    }

    #[test]
    fn prepare_folder_refuses_a_file() {
        let d = folder("atomic", "folder");
        let f = d.join("file");
        std::fs::write(&f, b"").unwrap();
        assert!(matches!(prepare_folder(&f), Err(AtomicError::Folder { .. })));
        prepare_folder(&d.join("new/deeper")).unwrap();
        assert!(d.join("new/deeper").is_dir());
    }
}
