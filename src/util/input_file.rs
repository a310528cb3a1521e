//! Input files that are ours to read: every file a user names (a scene,
//! a heightmap, a background image, a `--vdb`) is opened here, and only a
//! regular file is read.
//!
//! Anything else is refused with [`InputFileError::NotRegular`] before
//! anything could block on it or change it: a FIFO (opening it for reading
//! waits for a writer, forever; reading it would also take the bytes another
//! reader was meant to get), a character or block device (`/dev/zero` never
//! ends; opening a tape or a serial line has effects of its own), a socket
//! or a directory. The check is made twice:
//!
//! 1. `stat` of the path (a symbolic link is followed: a link to a regular
//!    file is a regular file): anything but a regular file is refused
//!    without being opened, so a FIFO's writer is never woken and a device
//!    never opened.
//! 2. Between that `stat` and the `open`, the name may be replaced (a race
//!    no check of a path can close). So the file is opened with
//!    `O_NONBLOCK` (the open of a FIFO returns at once instead of waiting
//!    for a writer) and `O_NOCTTY` (a terminal never becomes the process's
//!    controlling terminal), the *descriptor* is examined with `fstat`, and
//!    anything but a regular file is refused and closed unread. Only then is
//!    `O_NONBLOCK` cleared (`fcntl`), so the reads are ordinary blocking
//!    reads (for a regular file the flag changes nothing anyway; POSIX,
//!    `open(2)`: "O_NONBLOCK ... for other file types the behaviour is
//!    unspecified", Linux ignores it for regular files).
//!
//! The path of a sequence folder (`render --vdb DIR --frame N`) is not an
//! input file: it is the folder the frame names are looked up in.

use std::fs::{File, FileType};
use std::path::{Path, PathBuf};

/// Why an input file was not read.
#[derive(Debug, thiserror::Error)]
pub enum InputFileError {
    /// The path names something other than a regular file.
    #[error("{}: is {kind}, not a regular file", path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    /// The file could not be opened, examined or read.
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
}

impl InputFileError {
    /// The user's input (exit status 2) but for a file that changed size
    /// while it was read ([`is_input_io`]).
    pub fn is_input(&self) -> bool {
        match self {
            InputFileError::NotRegular { .. } => true,
            InputFileError::Io { source, .. } => is_input_io(source),
        }
    }
}

impl InputFileError {
    /// The reason without the path, for error types that name the path
    /// themselves: "is a FIFO, not a regular file", or the I/O error.
    pub fn reason(&self) -> String {
        match self {
            InputFileError::NotRegular { kind, .. } => format!("is {kind}, not a regular file"),
            InputFileError::Io { source, .. } => source.to_string(),
        }
    }
}

/// For callers whose error type holds an `std::io::Error` beside the path:
/// the I/O error itself, or the refusal as an error of kind `InvalidInput`
/// whose message is [`InputFileError::reason`] (no path: the caller names it).
impl From<InputFileError> for std::io::Error {
    fn from(e: InputFileError) -> Self {
        match e {
            InputFileError::Io { source, .. } => source,
            other => std::io::Error::new(std::io::ErrorKind::InvalidInput, other.reason()),
        }
    }
}

/// What a file type is, as the messages of this module and of
/// [`crate::util::atomic_write`] say it: "regular", "a FIFO", "a directory", ...
/// (Windows knows the first three.)
pub fn kind_name(t: FileType) -> &'static str {
    #[cfg(unix)]
    use std::os::unix::fs::FileTypeExt;
    let kinds = [
        (FileType::is_file as fn(&FileType) -> bool, "regular"),
        (FileType::is_symlink, "a symbolic link"),
        (FileType::is_dir, "a directory"),
        #[cfg(unix)]
        (FileType::is_char_device, "a character device"),
        #[cfg(unix)]
        (FileType::is_block_device, "a block device"),
        #[cfg(unix)]
        (FileType::is_fifo, "a FIFO"),
        #[cfg(unix)]
        (FileType::is_socket, "a socket"),
    ];
    kinds.iter().find(|(is, _)| is(&t)).map_or("not a regular file", |(_, name)| name)
}

/// Checks, without opening it, that `path` is a regular file (a symbolic
/// link to one counts): step 1 of the module docs, for callers that want
/// to refuse a bad input before long work and open it later with [`open`].
pub fn check(path: &Path) -> Result<(), InputFileError> {
    let m = std::fs::metadata(path).map_err(|source| InputFileError::Io { path: path.to_path_buf(), source })?;
    if m.is_file() {
        Ok(())
    } else {
        Err(InputFileError::NotRegular { path: path.to_path_buf(), kind: kind_name(m.file_type()) })
    }
}

/// Opens `path` for reading if it is a regular file (module docs): the
/// returned file reads as usual (blocking).
pub fn open(path: &Path) -> Result<File, InputFileError> {
    check(path)?;
    open_descriptor_checked(path)
}

/// Step 2 of the module docs: open without blocking, `fstat` the
/// descriptor, refuse anything but a regular file, clear `O_NONBLOCK`.
#[cfg(unix)]
fn open_descriptor_checked(path: &Path) -> Result<File, InputFileError> {
    use std::os::fd::AsRawFd;
    use std::os::unix::fs::OpenOptionsExt;
    let io = |source| InputFileError::Io { path: path.to_path_buf(), source };
    let file = std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY).open(path).map_err(io)?;
    let t = file.metadata().map_err(io)?.file_type();
    if !t.is_file() {
        return Err(InputFileError::NotRegular { path: path.to_path_buf(), kind: kind_name(t) });
    }
    let fd = file.as_raw_fd();
    // SAFETY: F_GETFL / F_SETFL on a descriptor this function owns; the
    // results are checked.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) } < 0 {
        return Err(io(std::io::Error::last_os_error()));
    }
    Ok(file)
}

/// Step 2 on Windows: an open of a file does not wait on a writer there
/// (a named pipe is not a path of the file system), so the file is opened
/// as usual and refused unless its handle's metadata says regular.
#[cfg(not(unix))]
fn open_descriptor_checked(path: &Path) -> Result<File, InputFileError> {
    let io = |source| InputFileError::Io { path: path.to_path_buf(), source };
    let file = File::open(path).map_err(io)?;
    let t = file.metadata().map_err(io)?.file_type();
    if !t.is_file() {
        return Err(InputFileError::NotRegular { path: path.to_path_buf(), kind: kind_name(t) });
    }
    Ok(file)
}

/// A file that was not the length it had when opened by the end of its
/// read: another process truncated, rewrote or extended it meanwhile. An
/// I/O failure (exit status 1), not the user's input: the same command
/// run again on the file, once written, reads it ([`is_input_io`]).
#[derive(Debug, thiserror::Error)]
#[error("the file changed size while it was read ({opened} bytes when opened, {read} read): another process is writing it")]
pub struct ChangedSize {
    pub opened: u64,
    pub read: u64,
}

/// Whether an I/O error met reading a file the user named is the user's
/// input (exit status 2: the file is missing, unreadable, not a regular
/// file) rather than a failure of the machine or of another process
/// (exit status 1: the file changed size while it was read, [`ChangedSize`]).
pub fn is_input_io(e: &std::io::Error) -> bool {
    !e.get_ref().is_some_and(|x| x.is::<ChangedSize>())
}

/// The `len` bytes of `file` (its size when opened, the length check): the
/// buffer is reserved without aborting when memory is short (an error of
/// kind `OutOfMemory`), and a file that is not `len` bytes long by the end
/// of the read (it was truncated or grew meanwhile) is an error of kind
/// `InvalidData` holding a [`ChangedSize`].
pub fn read_exactly(file: &File, len: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let want = usize::try_from(len)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::OutOfMemory, format!("{len} bytes do not fit in memory")))?;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(want)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::OutOfMemory, format!("cannot hold the file's {len} bytes in memory")))?;
    // One byte more than expected: a file that grew is found too.
    file.take(len.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 != len {
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, ChangedSize { opened: len, read: bytes.len() as u64 }));
    }
    Ok(bytes)
}

/// The whole of a regular file's bytes.
pub fn read(path: &Path) -> Result<Vec<u8>, InputFileError> {
    use std::io::Read;
    let mut file = open(path)?;
    let mut bytes = Vec::with_capacity(file.metadata().map(|m| m.len() as usize).unwrap_or(0));
    file.read_to_end(&mut bytes).map_err(|source| InputFileError::Io { path: path.to_path_buf(), source })?;
    Ok(bytes)
}

/// A regular file's text (UTF-8).
pub fn read_to_string(path: &Path) -> Result<String, InputFileError> {
    String::from_utf8(read(path)?).map_err(|e| InputFileError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::scratch::{folder, mkfifo};
    use std::time::{Duration, Instant};

    #[test]
    fn a_regular_file_and_a_link_to_one_read_as_usual() {
        let d = folder("input-file", "regular");
        let p = d.join("a.txt");
        std::fs::write(&p, "hello").unwrap();
        assert_eq!(read_to_string(&p).unwrap(), "hello");
        let l = d.join("link.txt");
        std::os::unix::fs::symlink(&p, &l).unwrap();
        assert_eq!(read(&l).unwrap(), b"hello");
        // O_NONBLOCK is cleared on the descriptor handed back.
        use std::os::fd::AsRawFd;
        let f = open(&p).unwrap();
        let flags = unsafe { libc::fcntl(f.as_raw_fd(), libc::F_GETFL) };
        assert_eq!(flags & libc::O_NONBLOCK, 0);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Both steps refuse each kind, the second (the descriptor's `fstat`,
    /// the race's guard) without blocking on a FIFO that has no writer.
    #[test]
    fn fifos_devices_directories_and_sockets_are_refused_by_both_checks_without_blocking() {
        let d = folder("input-file", "special");
        let fifo = d.join("fifo");
        mkfifo(&fifo);
        let sock = d.join("sock");
        let _listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
        let link = d.join("link-to-fifo");
        std::os::unix::fs::symlink(&fifo, &link).unwrap();
        let cases: [(&Path, &str); 5] = [
            (&fifo, "a FIFO"),
            (&link, "a FIFO"),
            (Path::new("/dev/zero"), "a character device"),
            (&d, "a directory"),
            (&sock, "a socket"),
        ];
        for (p, kind) in cases {
            let t = Instant::now();
            match read(p) {
                Err(InputFileError::NotRegular { kind: k, .. }) => assert_eq!(k, kind, "{}", p.display()),
                other => panic!("{}: {other:?}", p.display()),
            }
            // The descriptor check alone (as if the name had been swapped
            // after the stat). A socket cannot be opened at all (ENXIO).
            match open_descriptor_checked(p) {
                Err(InputFileError::NotRegular { kind: k, .. }) => assert_eq!(k, kind, "{}", p.display()),
                Err(InputFileError::Io { source, .. }) if kind == "a socket" => {
                    assert_eq!(source.raw_os_error(), Some(libc::ENXIO))
                }
                other => panic!("{}: {other:?}", p.display()),
            }
            // Generous: a blocked open would never return at all.
            assert!(t.elapsed() < Duration::from_secs(5), "{}: {:?}", p.display(), t.elapsed());
        }
        let e = read(&fifo).unwrap_err();
        assert_eq!(e.to_string(), format!("{}: is a FIFO, not a regular file", fifo.display()));
        assert_eq!(std::io::Error::from(e).to_string(), "is a FIFO, not a regular file");
        assert!(matches!(read(&d.join("missing")), Err(InputFileError::Io { .. })));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
