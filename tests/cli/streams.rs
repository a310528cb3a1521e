//! Standard streams that go away: a stdout whose reader has exited
//! (`aurora scene default | head -1`) ends the command quietly with
//! status 0; a stderr that is closed or broken never stops a bake nor
//! leaks its text into the files; descriptors 0-2 closed at start are
//! reopened on /dev/null before any file is opened.

use crate::common::child::Aurora;
use crate::common::{scratch, small::bake_command, write};
use crate::small_bake_toml;
use std::os::fd::{FromRawFd, OwnedFd};
use std::path::Path;
use std::process::Stdio;

/// The write end of a pipe whose read end is already closed: every write
/// to it fails with EPIPE, however little is written and however soon.
fn broken_pipe() -> Stdio {
    let mut fds = [0; 2];
    // SAFETY: pipe(2) fills the two descriptors.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0, "pipe: {}", std::io::Error::last_os_error());
    // SAFETY: both descriptors are new and owned here.
    let (read, write) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    drop(read);
    Stdio::from(write)
}

fn scene(dir: &Path) -> std::path::PathBuf {
    write(dir, "scene.toml", small_bake_toml!())
}

#[test]
fn a_closed_stdout_pipe_ends_every_printing_command_with_status_0() {
    let d = scratch("streams", "stdout");
    let s = scene(&d);
    let s = s.to_str().unwrap();
    let commands: [&[&str]; 6] = [
        &["scene", "default"],
        &["scene", "--schema"],
        &["scene", "--list"],
        &["profile", s],
        &["bake", s, "--plan", "--frames", "1-2", "--plan-samples", "1"],
        &["--help"],
    ];
    for args in commands {
        let status = Aurora::new().args(args).run_with(broken_pipe(), Stdio::null(), &[]);
        assert_eq!(status.code(), Some(0), "aurora {args:?} with its stdout's reader gone: {status}");
    }
}

/// The frames of a two-frame sequence bake run with `stderr` (and `close`
/// closed), byte for byte.
fn sequence(d: &Path, name: &str, stderr: Stdio, close: &'static [i32]) -> Vec<Vec<u8>> {
    let out = d.join(name);
    let status = bake_command(&scene(d), &out).args(["--frames", "1-2"]).run_with(Stdio::null(), stderr, close);
    assert_eq!(status.code(), Some(0), "{name}: {status}");
    (1..=2).map(|f| std::fs::read(out.join(format!("aurora.{f:04}.vdb"))).expect("frame written")).collect()
}

#[test]
fn a_closed_or_broken_stderr_never_stops_a_sequence_bake_nor_reaches_its_files() {
    let d = scratch("streams", "stderr");
    let reference = sequence(&d, "reference", Stdio::null(), &[]);
    assert_eq!(sequence(&d, "broken", broken_pipe(), &[]), reference, "stderr a pipe nobody reads");
    assert_eq!(sequence(&d, "closed", Stdio::null(), &[2]), reference, "stderr closed");
    assert_eq!(sequence(&d, "all-closed", Stdio::null(), &[0, 1, 2]), reference, "stdin, stdout and stderr closed");
}
