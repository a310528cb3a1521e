//! Standard streams that go away: a stdout whose reader has exited
//! (`aurora scene default | head -1`) ends the command quietly with
//! status 0; a stderr that is closed or broken never stops a bake nor
//! leaks its text into the files; descriptors 0-2 closed at start are
//! reopened on /dev/null before any file is opened; on a terminal the
//! progress bars are redrawn at least every 2 s, and the JSON progress
//! reports a stage at least every 2 s.

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

/// On a terminal every stage of a long bake (10^8 beams, one thread: a
/// chunk of beams is traced and gathered for seconds between reports)
/// shows its bar within 2 s of the start and redraws it at least every
/// 2 s: the test reads the terminal's output as it comes (events with
/// their time), over the footprints, the budget and 6 s of beams.
#[test]
fn on_a_terminal_every_stage_of_a_long_bake_shows_progress_every_two_seconds() {
    use std::io::Read;
    use std::time::{Duration, Instant};
    let dir = scratch("streams", "terminal");
    let (mut master, mut slave) = (0, 0);
    // SAFETY: openpty(3) fills the two descriptors; no name, settings or size.
    let r = unsafe { libc::openpty(&mut master, &mut slave, std::ptr::null_mut(), std::ptr::null(), std::ptr::null()) };
    assert_eq!(r, 0, "openpty: {}", std::io::Error::last_os_error());
    // SAFETY: both descriptors are new and owned here.
    let (master, slave) = unsafe { (std::fs::File::from(OwnedFd::from_raw_fd(master)), OwnedFd::from_raw_fd(slave)) };
    let mut c = std::process::Command::new(crate::common::child::AURORA_BIN);
    c.arg("bake").arg("--out").arg(dir.join("out")).args(["--set", "beams.count=100000000", "--threads", "1"]);
    c.stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::from(slave));
    for v in crate::common::child::FARM_VARS {
        c.env_remove(v);
    }
    let t0 = Instant::now();
    let mut child = c.spawn().unwrap();
    drop(c); // our copy of the terminal's other end
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut master = master;
        let mut buf = [0u8; 4096];
        // EIO once the bake has ended and its end of the terminal is closed.
        while let Ok(n @ 1..) = master.read(&mut buf) {
            if tx.send((Instant::now(), String::from_utf8_lossy(&buf[..n]).into_owned())).is_err() {
                break;
            }
        }
    });
    let (mut last, mut text, mut gaps) = (t0, String::new(), Vec::new());
    let mut beams_from = None;
    while beams_from.is_none_or(|t: Instant| last - t < Duration::from_secs(6)) {
        let Ok((t, chunk)) = rx.recv_timeout(Duration::from_secs(30)) else { break };
        gaps.push((t - last, chunk.clone()));
        last = t;
        text.push_str(&chunk);
        if beams_from.is_none() && text.contains("beams [") {
            beams_from = Some(t);
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(beams_from.is_some(), "no beams bar within 30 s of the last output: {text:?}");
    assert!(text.contains("footprints ["), "{text:?}");
    let (worst, at) = gaps.iter().max_by_key(|g| g.0).cloned().unwrap();
    assert!(worst < Duration::from_secs(2), "{worst:?} without a redraw, before {at:?}");
}

/// `--progress json` of the same long bake: every stage line follows the
/// one before it within 2 s by its own `seconds`, the beams stage's chunks
/// (seconds of tracing and gathering between reports) included; read line
/// by line as they come, over the footprints, the budget and 6 s of beams.
#[test]
fn json_progress_of_a_long_bake_reports_every_stage_every_two_seconds() {
    use std::io::BufRead;
    use std::time::Duration;
    let dir = scratch("streams", "json");
    let mut c = std::process::Command::new(crate::common::child::AURORA_BIN);
    c.arg("bake").arg("--out").arg(dir.join("out")).args(["--set", "beams.count=100000000", "--threads", "1", "--progress", "json"]);
    c.stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped());
    for v in crate::common::child::FARM_VARS {
        c.env_remove(v);
    }
    let mut child = c.spawn().unwrap();
    let err = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(err).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut lines: Vec<serde_json::Value> = Vec::new();
    let mut beams_from = None;
    while let Ok(line) = rx.recv_timeout(Duration::from_secs(30)) {
        let v: serde_json::Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"));
        let t = v["seconds"].as_f64().unwrap();
        if v["stage"] == "beams" && beams_from.is_none() {
            beams_from = Some(t);
        }
        lines.push(v);
        if beams_from.is_some_and(|b| t - b >= 6.0) {
            break;
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(beams_from.is_some_and(|b| lines.last().unwrap()["seconds"].as_f64().unwrap() - b >= 6.0), "{lines:?}");
    assert!(lines[0]["stage"] == "footprints" && lines[0]["seconds"].as_f64().unwrap() < 2.0, "{:?}", lines[0]);
    for w in lines.windows(2) {
        let gap = w[1]["seconds"].as_f64().unwrap() - w[0]["seconds"].as_f64().unwrap();
        // Within a stage (a stage's last line to the next one's start is
        // the bake between stages, the budget's check).
        if w[0]["stage"] == w[1]["stage"] {
            assert!(gap < 2.0, "{gap} s between {} and {}", w[0], w[1]);
        }
    }
}
