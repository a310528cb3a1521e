//! The standard streams, made safe to lose. In this binary `print!`,
//! `println!`, `eprint!` and `eprintln!` are the macros below, which shadow
//! std's for every module under `cli` (declared first in `cli/mod.rs`):
//!
//! - stdout is the product (a scene, a CSV, a plan): when its reader has
//!   gone (`aurora scene default | head -1`), the process ends at once,
//!   quietly, with status 0, as ripgrep and coreutils do; any other write
//!   error ends it with a message and status 1. std's `print!` would panic
//!   (exit 101).
//! - stderr is for people: a write that fails (a closed pipe, a full
//!   disk) is dropped, so losing the terminal never stops a bake.
//!
//! [`reopen_closed_descriptors`] runs first in `main`: a process started
//! with descriptor 0, 1 or 2 closed would otherwise hand that number to the
//! next file it opens, and text meant for stderr would land in a VDB's
//! temporary.

use std::io::Write;

/// Writes `args` to stdout (see the module doc for what a failure does).
pub fn stdout(args: std::fmt::Arguments) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|_| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(super::exit::SUCCESS);
        }
        stderr(format_args!("aurora: error: writing to stdout: {e}\n"));
        std::process::exit(super::exit::FAILURE);
    }
}

/// Writes `args` to stderr, dropping it if stderr cannot take it.
pub fn stderr(args: std::fmt::Arguments) {
    let mut err = std::io::stderr().lock();
    let _ = err.write_fmt(args).and_then(|_| err.flush());
}

/// Ignores SIGXFSZ, the signal a write past `RLIMIT_FSIZE` (`ulimit -f`)
/// raises, whose default action kills the process and leaves its
/// temporaries behind. Ignored, the write fails with `EFBIG` instead: an I/O
/// error like a full disk (exit status 1), whose staged files are removed
/// as any failed write's are (`aurora::util::atomic_write`).
///
/// Windows has no such signal (nor `ulimit -f`): nothing to do there.
#[cfg(unix)]
pub fn ignore_file_size_signal() {
    // SAFETY: setting a signal's disposition to SIG_IGN installs no handler;
    // it is done first in `main`, before any thread is started.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

/// On SIGINT (Ctrl-C) or SIGTERM: the held locks' files are removed
/// (`aurora::util::atomic_write::remove_held_locks`), stderr says the run
/// was interrupted, and the signal is raised again with its default action,
/// so the process ends as interrupted processes do (a shell sees the
/// signal). Temporaries are left to the next run into the folder, which
/// removes them.
///
/// Windows: not installed. Ctrl-C ends the process at once; the lock
/// files stay, and the next run into the folder takes them (a lock is the
/// file's lock, which the system drops with the process, not the file).
#[cfg(unix)]
pub fn on_interrupt_remove_locks() {
    extern "C" fn handler(sig: libc::c_int) {
        aurora::util::atomic_write::remove_held_locks();
        let msg = b"\naurora: interrupted before finishing\n";
        // SAFETY: write(2), signal(2) and raise(3) are async-signal-safe.
        unsafe {
            libc::write(2, msg.as_ptr().cast(), msg.len());
            libc::signal(sig, libc::SIG_DFL);
            libc::raise(sig);
        }
    }
    for sig in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: the handler makes only async-signal-safe calls.
        unsafe {
            libc::signal(sig, handler as extern "C" fn(libc::c_int) as libc::sighandler_t);
        }
    }
}

/// Opens /dev/null on each of descriptors 0, 1 and 2 that is closed.
/// Windows: nothing to do; a process without a standard handle reads and
/// writes it as an empty source and a sink (Rust's standard library).
#[cfg(unix)]
pub fn reopen_closed_descriptors() {
    for fd in 0..=2 {
        // SAFETY: fcntl(F_GETFD) only queries the descriptor table.
        let closed = unsafe { libc::fcntl(fd, libc::F_GETFD) } == -1 && std::io::Error::last_os_error().raw_os_error() == Some(libc::EBADF);
        if closed {
            // open(2) returns the lowest free descriptor: this one, as the
            // lower ones are open by now.
            // SAFETY: a NUL-terminated path and plain flags.
            let got = unsafe { libc::open(c"/dev/null".as_ptr(), libc::O_RDWR) };
            if got != fd && got >= 0 {
                // SAFETY: dup2 onto the closed descriptor, then drop the extra one.
                unsafe {
                    libc::dup2(got, fd);
                    libc::close(got);
                }
            }
        }
    }
}

/// See the Unix version: Windows has no SIGXFSZ.
#[cfg(not(unix))]
pub fn ignore_file_size_signal() {}

/// See the Unix version: not installed on Windows.
#[cfg(not(unix))]
pub fn on_interrupt_remove_locks() {}

/// See the Unix version: nothing to do on Windows.
#[cfg(not(unix))]
pub fn reopen_closed_descriptors() {}

macro_rules! print {
    ($($t:tt)*) => { $crate::cli::out::stdout(format_args!($($t)*)) };
}

macro_rules! println {
    () => { $crate::cli::out::stdout(format_args!("\n")) };
    ($($t:tt)*) => { $crate::cli::out::stdout(format_args!("{}\n", format_args!($($t)*))) };
}

// Unused today; defined so that a future eprint! is the safe one too.
#[allow(unused_macros)]
macro_rules! eprint {
    ($($t:tt)*) => { $crate::cli::out::stderr(format_args!($($t)*)) };
}

macro_rules! eprintln {
    () => { $crate::cli::out::stderr(format_args!("\n")) };
    ($($t:tt)*) => { $crate::cli::out::stderr(format_args!("{}\n", format_args!($($t)*))) };
}
