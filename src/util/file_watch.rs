//! Watching a scene file for saves (`aurora preview --watch`): the watch
//! acts on a file once a save has *ended*, never on what lies on disk in the
//! middle of one.
//!
//! Editors save in one of three ways (`tests/cli/watch.rs` drives each):
//! 1. **write in place**: open with `O_TRUNC`, write, close (nano, VS Code,
//!    vim with `backupcopy=yes`, a shell's `>`), possibly in several `write`s
//!    with pauses, so the file is empty, then half-written, for a while;
//! 2. **write a new file under the name** after renaming the old one away as
//!    a backup (vim's `file~` with `backupcopy=no`, emacs' `file~`);
//! 3. **write a temporary and rename it onto the name** (JetBrains'
//!    `file___jb_tmp___`, emacs with `file-precious-flag`, atomic-write
//!    libraries): never half-written, but missing for a moment.
//!
//! **Events (Linux).** The watcher asks inotify (inotify(7),
//! `man7.org/linux/man-pages/man7/inotify.7.html`) for the events of the file's *folder* (a watch on the file would follow the inode that 2
//! and 3 rename away), keeping those naming the file (or, for a symbolic
//! link, its target in the target's folder). A save ends with
//! `IN_CLOSE_WRITE` (1 and 2) or `IN_MOVED_TO` (3); `IN_MODIFY`, `IN_CREATE`,
//! `IN_DELETE` and `IN_MOVED_FROM` mark one in progress. The file is read
//! when the last event naming it is an end, and the read counts only if no
//! event naming it follows within [`QUIET`]: one that does means another save
//! began (the read may be torn), whose end is awaited instead. Saves that
//! ended while the caller was busy are one read, of the latest text. After
//! `IN_Q_OVERFLOW` that one save is found by polling; a watch that ends
//! (`IN_IGNORED`, `IN_MOVE_SELF`, `IN_DELETE_SELF`) turns to polling.
//!
//! **Polling** (no inotify, it fails, or `AURORA_WATCH=poll`, [`ENV`]; `auto`
//! uses events where it can): the file is read every [`POLL_TICK`] and a save
//! counts once its size, modification time and content hash have stayed the
//! same for [`SETTLE`], well above the 150 ms pauses of the tests' chunked
//! writer; a writer
//! pausing longer inside one save is seen half-way (only events know where a
//! save ends). The text at the start counts after the same settle.
//!
//! Either way a save is acted on only when its text ([`text_hash`], 64-bit
//! FNV-1a) differs from the last one acted on, so a `touch` does nothing. A
//! missing file (between the renames of 2 and 3) is no save; one that cannot
//! be read, is not a regular file (opened with `O_NONBLOCK` and checked with
//! `fstat` first, so a FIFO never blocks the watch) or is not UTF-8 is
//! reported once, until the next save that differs.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

/// The polling fallback reads the file this often.
pub const POLL_TICK: Duration = Duration::from_millis(50);

/// The polling fallback counts a save once the file's size, modification
/// time and hash have been unchanged this long.
pub const SETTLE: Duration = Duration::from_millis(400);

/// After an event-ended save is read, an event naming the file within this
/// long means the read may be torn: it is discarded and the next end
/// awaited.
pub const QUIET: Duration = Duration::from_millis(20);

/// The environment variable choosing the watch: `poll` forces the polling
/// fallback, `auto` (or unset) uses file system events where available.
pub const ENV: &str = "AURORA_WATCH";

/// Why a watch could not start, or a save could not be read.
#[derive(Debug, thiserror::Error)]
pub enum WatchError {
    #[error("{ENV}=`{value}`: unknown watch; expected `auto` (file system events where available) or `poll` (poll the file)")]
    Env { value: String },
    #[error("{}: cannot read the scene file: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: is {kind}, not a regular file: the watch reads only regular files", path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error("{}: the saved file is not UTF-8 text", path.display())]
    NotText { path: PathBuf },
}

impl WatchError {
    /// Always the user's input: the scene file watched or the watch asked for (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// How the watcher learns of saves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// File system events where the platform gives them, else polling.
    Auto,
    /// The polling fallback.
    Poll,
}

impl Mode {
    /// The mode [`ENV`] asks for (unset: [`Mode::Auto`]).
    pub fn from_env() -> Result<Mode, WatchError> {
        match std::env::var_os(ENV) {
            None => Ok(Mode::Auto),
            Some(v) => match v.to_str() {
                Some("") | Some("auto") => Ok(Mode::Auto),
                Some("poll") => Ok(Mode::Poll),
                _ => Err(WatchError::Env { value: v.to_string_lossy().into_owned() }),
            },
        }
    }
}

/// A saved text of the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Save {
    pub text: String,
    /// [`text_hash`] of its bytes.
    pub hash: u64,
}

impl Save {
    /// True when the text holds no TOML key: only whitespace and `#`
    /// comments. Any key is optional, so such a file would be the default
    /// scene; saved while watching, it is more likely a save caught empty
    /// than a wish for the default scene, and the watch reports it.
    pub fn is_blank(&self) -> bool {
        self.text.lines().all(|l| {
            let t = l.trim();
            t.is_empty() || t.starts_with('#')
        })
    }
}

/// 64-bit FNV-1a of `bytes`: the identity of a file's text.
pub fn text_hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3))
}

/// What a read of the file found.
enum Seen {
    Missing,
    File { len: u64, modified: Option<SystemTime>, hash: u64, bytes: Vec<u8> },
    Failed(WatchError),
}

/// What the polling fallback compares from tick to tick.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Key {
    Missing,
    File { len: u64, modified: Option<SystemTime>, hash: u64 },
    Failed(String),
}

impl Seen {
    fn key(&self) -> Key {
        match self {
            Seen::Missing => Key::Missing,
            Seen::File { len, modified, hash, .. } => Key::File { len: *len, modified: *modified, hash: *hash },
            Seen::Failed(e) => Key::Failed(e.to_string()),
        }
    }
}

/// Reads `path` (following links) if it is a regular file: opened
/// non-blocking and checked with `fstat` before any read.
fn observe(path: &Path) -> Seen {
    use std::io::Read;
    let io = |source| Seen::Failed(WatchError::Io { path: path.to_path_buf(), source });
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    // Windows: an open of a file never waits on a writer (input_file's docs).
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let mut f = match options.open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Seen::Missing,
        Err(e) => return io(e),
    };
    let meta = match f.metadata() {
        Ok(m) => m,
        Err(e) => return io(e),
    };
    let t = meta.file_type();
    if !t.is_file() {
        let kind = crate::util::input_file::kind_name(t);
        return Seen::Failed(WatchError::NotRegular { path: path.to_path_buf(), kind });
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    if let Err(e) = f.read_to_end(&mut bytes) {
        return io(e);
    }
    Seen::File { len: meta.len(), modified: meta.modified().ok(), hash: text_hash(&bytes), bytes }
}

/// The polling fallback's state: the file's last key and since when it has
/// held (`done` once that key was handed on).
#[derive(Default)]
struct Poll {
    candidate: Option<(Key, Instant, bool)>,
}

impl Poll {
    /// Reads the file every [`POLL_TICK`] until a key not yet handed on has
    /// held for [`SETTLE`].
    fn settled(&mut self, path: &Path) -> Seen {
        loop {
            let seen = observe(path);
            let key = seen.key();
            match &mut self.candidate {
                Some((k, since, done)) if *k == key => {
                    if !*done && since.elapsed() >= SETTLE {
                        *done = true;
                        return seen;
                    }
                }
                _ => self.candidate = Some((key, Instant::now(), false)),
            }
            std::thread::sleep(POLL_TICK);
        }
    }
}

enum Backend {
    #[cfg(target_os = "linux")]
    Events(events::Events),
    Poll(Poll),
}

/// A watch on one scene file: [`Watcher::next_save`] blocks until a save
/// of another text than the last has ended (see the module documentation).
pub struct Watcher {
    path: PathBuf,
    backend: Backend,
    /// Why the watcher polls (empty with events).
    why_poll: String,
    /// The hash of the last text handed on, and the last failure reported
    /// since.
    last_text: Option<u64>,
    last_failure: Option<String>,
}

impl Watcher {
    /// A watch on `path` in the mode [`ENV`] asks for.
    pub fn new(path: &Path) -> Result<Watcher, WatchError> {
        Ok(Watcher::with_mode(path, Mode::from_env()?))
    }

    /// A watch on `path` in `mode`; [`Mode::Auto`] polls where events are
    /// unavailable (the reason is in [`Watcher::describe`]).
    pub fn with_mode(path: &Path, mode: Mode) -> Watcher {
        let (backend, why_poll) = match mode {
            Mode::Poll => (Backend::Poll(Poll::default()), format!("{ENV}=poll")),
            Mode::Auto => Self::events(path),
        };
        Watcher { path: path.to_path_buf(), backend, why_poll, last_text: None, last_failure: None }
    }

    #[cfg(target_os = "linux")]
    fn events(path: &Path) -> (Backend, String) {
        match events::Events::new(path) {
            Ok(e) => (Backend::Events(e), String::new()),
            Err(e) => (Backend::Poll(Poll::default()), format!("inotify unavailable: {e}")),
        }
    }

    #[cfg(not(target_os = "linux"))]
    fn events(_: &Path) -> (Backend, String) {
        (Backend::Poll(Poll::default()), "no file system events on this platform".to_string())
    }

    /// How saves are seen, for the terminal.
    pub fn describe(&self) -> String {
        match &self.backend {
            #[cfg(target_os = "linux")]
            Backend::Events(_) => "inotify: a save counts when it ends (a close after writing, a rename onto the name)".to_string(),
            Backend::Poll(_) => format!(
                "polling every {} ms ({}): a save counts once unchanged for {} ms",
                POLL_TICK.as_millis(),
                self.why_poll,
                SETTLE.as_millis()
            ),
        }
    }

    /// True when the watch polls.
    pub fn polls(&self) -> bool {
        matches!(self.backend, Backend::Poll(_))
    }

    /// Blocks until a save whose text differs from the last one handed on
    /// has ended (the first call: the text at the start), or a read fails
    /// otherwise than the last failure did.
    pub fn next_save(&mut self) -> Result<Save, WatchError> {
        loop {
            let seen = match &mut self.backend {
                #[cfg(target_os = "linux")]
                Backend::Events(ev) => match ev.next_end(&self.path) {
                    Ok(events::End::Read(seen)) => seen,
                    Ok(events::End::Overflow) => Poll::default().settled(&self.path),
                    Ok(events::End::Lost) | Err(_) => {
                        self.why_poll = "the folder's watch ended".to_string();
                        self.backend = Backend::Poll(Poll::default());
                        continue;
                    }
                },
                Backend::Poll(p) => p.settled(&self.path),
            };
            match seen {
                Seen::Missing => {}
                Seen::File { hash, .. } if self.last_text == Some(hash) => self.last_failure = None,
                Seen::File { hash, bytes, .. } => {
                    self.last_text = Some(hash);
                    self.last_failure = None;
                    return match String::from_utf8(bytes) {
                        Ok(text) => Ok(Save { text, hash }),
                        Err(_) => Err(WatchError::NotText { path: self.path.clone() }),
                    };
                }
                Seen::Failed(e) => {
                    let msg = e.to_string();
                    if self.last_failure.as_ref() != Some(&msg) {
                        self.last_failure = Some(msg);
                        return Err(e);
                    }
                }
            }
        }
    }

    /// Without blocking: whether a save of another text than `hash` has
    /// ended since the last [`Watcher::next_save`] (with polling: whether
    /// the file holds another text now, perhaps mid-save). The save is
    /// still handed on by the next `next_save`.
    pub fn changed_since(&mut self, hash: u64) -> bool {
        match &mut self.backend {
            #[cfg(target_os = "linux")]
            Backend::Events(ev) => {
                if !ev.ended_now() {
                    return false;
                }
            }
            Backend::Poll(_) => {}
        }
        matches!(observe(&self.path), Seen::File { hash: h, .. } if h != hash)
    }
}

#[cfg(target_os = "linux")]
mod events {
    //! The inotify side of [`super::Watcher`].

    use super::{observe, Seen, QUIET};
    use std::ffi::{CString, OsStr, OsString};
    use std::io;
    use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
    use std::os::unix::ffi::OsStrExt;
    use std::path::Path;
    use std::time::Duration;

    /// Events that end a save of a name.
    const END: u32 = libc::IN_CLOSE_WRITE | libc::IN_MOVED_TO;
    /// Events of a save in progress (or of the name going away).
    const CHANGE: u32 = libc::IN_MODIFY | libc::IN_CREATE | libc::IN_DELETE | libc::IN_MOVED_FROM;
    /// The watch itself ended.
    const GONE: u32 = libc::IN_IGNORED | libc::IN_DELETE_SELF | libc::IN_MOVE_SELF;

    /// What [`Events::next_end`] found.
    pub enum End {
        /// A save ended and no other began within [`QUIET`] of its read.
        Read(Seen),
        /// Events were lost: the caller settles the file by polling.
        Overflow,
        /// A folder's watch ended: the caller polls from now on.
        Lost,
    }

    pub struct Events {
        fd: OwnedFd,
        /// (watch descriptor, name in that folder) of the file.
        names: Vec<(i32, OsString)>,
        /// The last event naming the file was an end / a change.
        ended: bool,
        dirty: bool,
        overflow: bool,
        lost: bool,
    }

    impl Events {
        /// Watches the folder of `path` (and, when `path` is a symbolic
        /// link, the folder of its target).
        pub fn new(path: &Path) -> io::Result<Events> {
            // SAFETY: a plain system call; the descriptor is owned below.
            let fd = unsafe { libc::inotify_init1(libc::IN_CLOEXEC | libc::IN_NONBLOCK) };
            if fd < 0 {
                return Err(io::Error::last_os_error());
            }
            // SAFETY: `fd` is a fresh descriptor nothing else owns.
            let fd = unsafe { OwnedFd::from_raw_fd(fd) };
            let mut places = vec![path.to_path_buf()];
            if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
                places.push(std::fs::canonicalize(path)?);
            }
            let mut names = Vec::new();
            for p in places {
                let name = p.file_name().ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "no file name"))?.to_os_string();
                let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
                let c = CString::new(dir.as_os_str().as_bytes()).map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
                let mask = END | CHANGE | libc::IN_DELETE_SELF | libc::IN_MOVE_SELF | libc::IN_ONLYDIR | libc::IN_EXCL_UNLINK;
                // SAFETY: `c` is a NUL-terminated path that outlives the call.
                let wd = unsafe { libc::inotify_add_watch(fd.as_raw_fd(), c.as_ptr(), mask) };
                if wd < 0 {
                    return Err(io::Error::last_os_error());
                }
                names.push((wd, name));
            }
            // The text at the start is read as if a save had just ended: a
            // save under way then is awaited.
            Ok(Events { fd, names, ended: true, dirty: false, overflow: false, lost: false })
        }

        /// Blocks until a save of the file has ended (see the module
        /// documentation) and returns its read.
        pub fn next_end(&mut self, path: &Path) -> io::Result<End> {
            loop {
                if self.lost {
                    return Ok(End::Lost);
                }
                if self.overflow {
                    (self.overflow, self.ended, self.dirty) = (false, false, false);
                    return Ok(End::Overflow);
                }
                if self.ended && !self.dirty {
                    let seen = observe(path);
                    if self.drain(Some(QUIET))? {
                        continue;
                    }
                    self.ended = false;
                    return Ok(End::Read(seen));
                }
                self.drain(None)?;
            }
        }

        /// Takes the events queued now; true when the last event naming the
        /// file ended a save (or events were lost).
        pub fn ended_now(&mut self) -> bool {
            let _ = self.drain(Some(Duration::ZERO));
            self.overflow || (self.ended && !self.dirty)
        }

        /// Waits up to `timeout` (None: for ever) for events and takes all
        /// that are queued; true when one named the file, was an overflow
        /// or ended a watch.
        fn drain(&mut self, timeout: Option<Duration>) -> io::Result<bool> {
            let ms = timeout.map_or(-1, |d| d.as_millis().min(i32::MAX as u128) as libc::c_int);
            let mut pfd = libc::pollfd { fd: self.fd.as_raw_fd(), events: libc::POLLIN, revents: 0 };
            loop {
                // SAFETY: one valid pollfd.
                let r = unsafe { libc::poll(&mut pfd, 1, ms) };
                if r >= 0 {
                    if r == 0 {
                        return Ok(false);
                    }
                    break;
                }
                let e = io::Error::last_os_error();
                if e.kind() != io::ErrorKind::Interrupted {
                    return Err(e);
                }
            }
            let mut any = false;
            // Room for many events (each at most 16 + NAME_MAX + 1 bytes).
            let mut buf = [0u8; 16 * 1024];
            loop {
                // SAFETY: `buf` is writable for its whole length.
                let n = unsafe { libc::read(self.fd.as_raw_fd(), buf.as_mut_ptr().cast(), buf.len()) };
                if n < 0 {
                    let e = io::Error::last_os_error();
                    match e.kind() {
                        io::ErrorKind::Interrupted => continue,
                        io::ErrorKind::WouldBlock => break,
                        _ => return Err(e),
                    }
                }
                if n == 0 {
                    break;
                }
                any |= self.take(&buf[..n as usize]);
            }
            Ok(any)
        }

        /// Notes a read's events (`struct inotify_event`: wd, mask, cookie,
        /// len, then `len` bytes of NUL-padded name).
        fn take(&mut self, mut bytes: &[u8]) -> bool {
            let word = |b: &[u8], i: usize| u32::from_ne_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
            let mut any = false;
            while bytes.len() >= 16 {
                let (wd, mask, len) = (word(bytes, 0) as i32, word(bytes, 4), word(bytes, 12) as usize);
                let raw = &bytes[16..(16 + len).min(bytes.len())];
                let name = OsStr::from_bytes(&raw[..raw.iter().position(|&b| b == 0).unwrap_or(raw.len())]);
                bytes = &bytes[(16 + len).min(bytes.len())..];
                if mask & libc::IN_Q_OVERFLOW != 0 {
                    self.overflow = true;
                    any = true;
                } else if mask & GONE != 0 && self.names.iter().any(|(w, _)| *w == wd) {
                    self.lost = true;
                    any = true;
                } else if self.names.iter().any(|(w, n)| *w == wd && n == name) {
                    if mask & END != 0 {
                        (self.ended, self.dirty) = (true, false);
                    } else if mask & CHANGE != 0 {
                        self.dirty = true;
                    }
                    any = true;
                }
            }
            any
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::scratch::{folder, mkfifo};
    use std::io::Write;
    use std::sync::mpsc;

    /// A watcher on its own thread, handing on its saves (the test waits on
    /// them with a deadline, so a watcher that never wakes fails instead of
    /// hanging).
    fn spawn(path: &Path, mode: Mode) -> (mpsc::Receiver<Result<Save, String>>, bool) {
        let (tx, rx) = mpsc::channel();
        let mut w = Watcher::with_mode(path, mode);
        let polls = w.polls();
        std::thread::spawn(move || loop {
            if tx.send(w.next_save().map_err(|e| e.to_string())).is_err() {
                break;
            }
        });
        (rx, polls)
    }

    fn next(rx: &mpsc::Receiver<Result<Save, String>>) -> Result<Save, String> {
        rx.recv_timeout(Duration::from_secs(60)).expect("a save within 60 s")
    }

    /// One descriptor: truncate, then the text in three writes 150 ms
    /// apart (an editor pausing), then close.
    fn chunked(path: &Path, text: &str) {
        let mut f = std::fs::OpenOptions::new().write(true).create(true).truncate(true).open(path).unwrap();
        let b = text.as_bytes();
        let third = b.len() / 3;
        for part in [&b[..third], &b[third..2 * third], &b[2 * third..]] {
            std::thread::sleep(Duration::from_millis(150));
            f.write_all(part).unwrap();
        }
    }

    /// Each save style hands on the whole saved text, once per text: the
    /// first text, a chunked write in place, a rewrite of the same text
    /// (nothing), a temporary renamed onto the name, a rename away then a
    /// new file, an empty save; with events and by polling.
    fn saves_are_whole(mode: Mode, name: &str) {
        let d = folder("watch-test", name);
        let p = d.join("scene.toml");
        let texts: Vec<String> = (0..5).map(|i| format!("seed = {i}\n# {}\n", "x".repeat(40 + i))).collect();
        std::fs::write(&p, &texts[0]).unwrap();
        let (rx, polls) = spawn(&p, mode);
        assert_eq!(polls, mode == Mode::Poll || cfg!(not(target_os = "linux")));
        assert_eq!(next(&rx).unwrap().text, texts[0]);
        chunked(&p, &texts[1]);
        assert_eq!(next(&rx).unwrap().text, texts[1]);
        // The same text again is no save: the next one handed on is the
        // temporary renamed into place.
        chunked(&p, &texts[1]);
        let tmp = d.join("scene.toml___jb_tmp___");
        chunked(&tmp, &texts[2]);
        std::fs::rename(&tmp, &p).unwrap();
        assert_eq!(next(&rx).unwrap().text, texts[2]);
        std::fs::rename(&p, d.join("scene.toml~")).unwrap();
        chunked(&d.join("scene.toml"), &texts[3]);
        assert_eq!(next(&rx).unwrap().text, texts[3]);
        std::fs::write(&p, "").unwrap();
        let s = next(&rx).unwrap();
        assert!(s.text.is_empty() && s.is_blank());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn saves_are_whole_with_events() {
        saves_are_whole(Mode::Auto, "events");
    }

    #[test]
    fn saves_are_whole_when_polling() {
        saves_are_whole(Mode::Poll, "poll");
    }

    /// A FIFO put in the file's place is reported (once), never read; the
    /// next regular save is handed on.
    #[test]
    fn a_fifo_in_its_place_is_refused_without_blocking() {
        let d = folder("watch-test", "fifo");
        let p = d.join("scene.toml");
        std::fs::write(&p, "seed = 1\n").unwrap();
        let (rx, _) = spawn(&p, Mode::Auto);
        assert_eq!(next(&rx).unwrap().text, "seed = 1\n");
        let fifo = d.join("fifo");
        mkfifo(&fifo);
        std::fs::rename(&fifo, &p).unwrap();
        let e = next(&rx).unwrap_err();
        assert!(e.contains("a FIFO"), "{e}");
        std::fs::remove_file(&p).unwrap();
        std::fs::write(&p, "seed = 2\n").unwrap();
        assert_eq!(next(&rx).unwrap().text, "seed = 2\n");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn blank_means_whitespace_and_comments_only() {
        let s = |t: &str| Save { text: t.to_string(), hash: text_hash(t.as_bytes()) };
        assert!(s("").is_blank() && s(" \n\t\n").is_blank() && s("# a scene\n  # more\n").is_blank());
        assert!(!s("seed = 1\n").is_blank() && !s("[render]\n").is_blank() && !s("# c\nseed = 1 # c\n").is_blank());
        // FNV-1a 64 test vectors.
        assert_eq!(text_hash(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(text_hash(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
