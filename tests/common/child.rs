//! The `aurora` binary as a child process. Every test runs it through
//! here, so that a child that panics (exit 101), dies of a signal or exits
//! with a status other than 0, 1 or 2 fails the test at once, with its
//! command line and stderr, whatever exit the test expected (an expected
//! failure is exit 2, the user's input refused, or 1).
//!
//! - [`aurora`]: arguments in, [`Output`] back (stdout and stderr captured);
//! - [`Aurora`]: the same built up like a `Command` (paths, variables, a
//!   working folder, an address-space cap), then run to completion
//!   ([`Aurora::output`]), started ([`Aurora::spawn`]) or watched line by
//!   line ([`Aurora::watch`]);
//! - [`Running`]: a started child, waited for ([`Running::wait`], or with a
//!   deadline [`Running::wait_within`]) or stopped on purpose
//!   ([`Running::kill`], [`Running::wait_or_kill`]): only a stop the test
//!   asks for makes a death by signal expected;
//! - [`Watched`]: a long-running child (`aurora preview --watch`) whose
//!   stderr the test waits on: a reader thread appends each line as it
//!   comes and wakes the waiters, so a wait returns as soon as its
//!   condition holds and fails at its deadline (or as soon as the child
//!   exits) with the lines so far; the test ends it with [`Watched::stop`].
//!
//! Every child runs with stdin closed and without the farm's variables
//! ([`FARM_VARS`]), so a test runs the same inside a farm job.

use std::ffi::{OsStr, OsString};
use std::io::{BufRead, Read};
use std::os::unix::process::ExitStatusExt;
use std::path::PathBuf;
use std::process::{Command, ExitStatus, Output, Stdio};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The `aurora` binary cargo built for this test run.
pub const AURORA_BIN: &str = env!("CARGO_BIN_EXE_aurora");

/// The variables `--shard auto` reads (Slurm's job array, a Kubernetes
/// Indexed Job): removed from every child; a test sets them explicitly.
pub const FARM_VARS: [&str; 5] =
    ["SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_COUNT", "SLURM_ARRAY_TASK_STEP", "JOB_COMPLETION_INDEX"];

/// `aurora ARGS...`, run to completion (stdout and stderr captured).
pub fn aurora(args: &[&str]) -> Output {
    Aurora::new().args(args).output()
}

/// Asserts that the run succeeded (exit 0); returns its stderr.
pub fn ok(o: &Output) -> String {
    let e = stderr(o);
    assert!(o.status.success(), "aurora failed ({}): {e}", o.status);
    e
}

/// Asserts that the run refused its input (exit 2); returns its stderr.
pub fn refused(o: &Output) -> String {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(2), "expected exit 2 (input refused): {e}");
    e
}

/// A process's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Fails the test if `status` is not an exit the binary gives on its own:
/// 0, 1 or 2 (a panic is 101, an abort or a crash a signal).
fn check(line: &str, status: ExitStatus, stderr: &[u8]) {
    let what = match (status.code(), status.signal()) {
        (Some(0..=2), _) => return,
        (Some(101), _) => "panicked (exit 101)".to_string(),
        (Some(c), _) => format!("exited with {c}, not 0, 1 or 2"),
        (None, Some(s)) => format!("was killed by signal {s}{}", signal_name(s)),
        (None, None) => format!("ended as {status}"),
    };
    panic!("{line} {what}; stderr:\n{}", String::from_utf8_lossy(stderr));
}

fn signal_name(s: i32) -> &'static str {
    match s {
        libc::SIGABRT => " (SIGABRT: an abort, such as a failed allocation)",
        libc::SIGSEGV => " (SIGSEGV: a crash or a stack overflow)",
        libc::SIGKILL => " (SIGKILL: killed from outside, by the OOM killer say)",
        _ => "",
    }
}

/// `aurora` and its arguments, built up like a [`Command`].
#[derive(Clone, Default)]
pub struct Aurora {
    args: Vec<OsString>,
    envs: Vec<(OsString, Option<OsString>)>,
    dir: Option<PathBuf>,
    cap_kib: Option<u64>,
}

impl Aurora {
    pub fn new() -> Aurora {
        Aurora::default()
    }

    pub fn arg(mut self, a: impl AsRef<OsStr>) -> Aurora {
        self.args.push(a.as_ref().to_owned());
        self
    }

    pub fn args<S: AsRef<OsStr>>(mut self, args: impl IntoIterator<Item = S>) -> Aurora {
        self.args.extend(args.into_iter().map(|a| a.as_ref().to_owned()));
        self
    }

    pub fn env(mut self, k: impl AsRef<OsStr>, v: impl AsRef<OsStr>) -> Aurora {
        self.envs.push((k.as_ref().to_owned(), Some(v.as_ref().to_owned())));
        self
    }

    pub fn envs<K: AsRef<OsStr>, V: AsRef<OsStr>>(self, vars: impl IntoIterator<Item = (K, V)>) -> Aurora {
        vars.into_iter().fold(self, |a, (k, v)| a.env(k, v))
    }

    pub fn env_remove(mut self, k: impl AsRef<OsStr>) -> Aurora {
        self.envs.push((k.as_ref().to_owned(), None));
        self
    }

    pub fn current_dir(mut self, d: impl Into<PathBuf>) -> Aurora {
        self.dir = Some(d.into());
        self
    }

    /// Runs it under an address-space cap of `kib` KiB (`ulimit -v` in a
    /// shell that then execs it): an allocation beyond the cap fails, which
    /// Rust turns into an abort, a signal.
    pub fn capped(mut self, kib: u64) -> Aurora {
        self.cap_kib = Some(kib);
        self
    }

    /// The command line, for messages.
    fn line(&self) -> String {
        let mut s = String::from("aurora");
        for a in &self.args {
            s.push(' ');
            s.push_str(&a.to_string_lossy());
        }
        if let Some(k) = self.cap_kib {
            s.push_str(&format!(" (under ulimit -v {k})"));
        }
        s
    }

    fn command(&self) -> Command {
        let mut c = match self.cap_kib {
            Some(kib) => {
                let mut c = Command::new("sh");
                c.arg("-c").arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\"")).arg(AURORA_BIN);
                c
            }
            None => Command::new(AURORA_BIN),
        };
        c.args(&self.args).stdin(Stdio::null());
        for v in FARM_VARS {
            c.env_remove(v);
        }
        for (k, v) in &self.envs {
            match v {
                Some(v) => c.env(k, v),
                None => c.env_remove(k),
            };
        }
        if let Some(d) = &self.dir {
            c.current_dir(d);
        }
        c
    }

    /// Runs it to completion, stdout and stderr captured.
    pub fn output(self) -> Output {
        let o = self.command().output().unwrap_or_else(|e| panic!("cannot run {}: {e}", self.line()));
        check(&self.line(), o.status, &o.stderr);
        o
    }

    /// Runs it to completion with the standard streams as given (a pipe
    /// whose reader has gone, say) and `close` (of 0, 1, 2) closed in the
    /// child before it starts; its exit is checked as [`Aurora::output`]
    /// checks it (stderr is not captured: the message names the command).
    pub fn run_with(self, stdout: Stdio, stderr: Stdio, close: &'static [i32]) -> ExitStatus {
        use std::os::unix::process::CommandExt;
        let mut c = self.command();
        c.stdout(stdout).stderr(stderr);
        // SAFETY: close(2) is async-signal-safe, as pre_exec requires.
        unsafe {
            c.pre_exec(move || {
                for &fd in close {
                    libc::close(fd);
                }
                Ok(())
            });
        }
        let status = c.status().unwrap_or_else(|e| panic!("cannot run {}: {e}", self.line()));
        check(&self.line(), status, b"(not captured)");
        status
    }

    /// Starts it with stderr piped and stdout as given.
    fn start(&self, stdout: Stdio) -> std::process::Child {
        self.command().stdout(stdout).stderr(Stdio::piped()).spawn().unwrap_or_else(|e| panic!("cannot start {}: {e}", self.line()))
    }

    /// Starts it, stdout and stderr read as it writes them.
    pub fn spawn(self) -> Running {
        let mut child = self.start(Stdio::piped());
        let out = drain(child.stdout.take().expect("piped stdout"));
        let err = drain(child.stderr.take().expect("piped stderr"));
        Running { child, line: self.line(), out: Some(out), err: Some(err), output: None }
    }

    /// Starts it with stdout discarded and stderr read line by line.
    pub fn watch(self) -> Watched {
        let mut child = self.start(Stdio::null());
        let stderr = child.stderr.take().expect("piped stderr");
        let log: Log = Arc::new((Mutex::new((Vec::new(), false)), Condvar::new()));
        let l = log.clone();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                l.0.lock().unwrap().0.push(line);
                l.1.notify_all();
            }
            l.0.lock().unwrap().1 = true;
            l.1.notify_all();
        });
        Watched { child: Mutex::new(child), line: self.line(), log, stopped: false }
    }
}

/// A thread reading a pipe to its end.
fn drain(mut r: impl Read + Send + 'static) -> JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = r.read_to_end(&mut b);
        b
    })
}

/// A started `aurora`. Dropped while it runs (a test failing on the way),
/// it is killed; a test that passes must have waited for it or stopped it.
pub struct Running {
    child: std::process::Child,
    line: String,
    out: Option<JoinHandle<Vec<u8>>>,
    err: Option<JoinHandle<Vec<u8>>>,
    /// What it wrote, once it has exited.
    output: Option<Output>,
}

impl Running {
    /// What it wrote, once it has exited with `status`.
    fn collect(&mut self, status: ExitStatus) -> Output {
        if let Some(o) = &self.output {
            return o.clone();
        }
        let stdout = self.out.take().expect("stdout reader").join().expect("stdout reader");
        let stderr = self.err.take().expect("stderr reader").join().expect("stderr reader");
        let o = Output { status, stdout, stderr };
        self.output = Some(o.clone());
        o
    }

    /// Its output if it has exited (checked as [`Aurora::output`] checks).
    fn exited(&mut self) -> Option<Output> {
        if let Some(o) = &self.output {
            return Some(o.clone());
        }
        let status = self.child.try_wait().unwrap_or_else(|e| panic!("wait for {}: {e}", self.line))?;
        let o = self.collect(status);
        check(&self.line, o.status, &o.stderr);
        Some(o)
    }

    /// Whether it is still running (a crash fails the test here).
    pub fn running(&mut self) -> bool {
        self.exited().is_none()
    }

    /// Waits for it to exit.
    pub fn wait(mut self) -> Output {
        let status = self.child.wait().unwrap_or_else(|e| panic!("wait for {}: {e}", self.line));
        let o = self.collect(status);
        check(&self.line, o.status, &o.stderr);
        o
    }

    /// Waits for it to exit; still running after `deadline`, it has hung:
    /// killed, and the test fails.
    pub fn wait_within(mut self, deadline: Duration) -> Output {
        let t = Instant::now();
        loop {
            if let Some(o) = self.exited() {
                return o;
            }
            if t.elapsed() > deadline {
                let o = self.kill();
                panic!("{} still running after {deadline:?}; stderr:\n{}", self.line, stderr(&o));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Waits up to `limit`, then stops it on purpose: `None` if it was
    /// still running then (a run allowed to go on longer than the test
    /// waits), else its output.
    pub fn wait_or_kill(mut self, limit: Duration) -> Option<Output> {
        let t = Instant::now();
        while t.elapsed() <= limit {
            if let Some(o) = self.exited() {
                return Some(o);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let _ = self.kill();
        None
    }

    /// Stops it on purpose (SIGKILL) and returns what it wrote. Had it
    /// already exited on its own, its exit is checked as any other.
    pub fn kill(&mut self) -> Output {
        if let Some(o) = self.exited() {
            return o;
        }
        let _ = self.child.kill();
        let status = self.child.wait().unwrap_or_else(|e| panic!("wait for {}: {e}", self.line));
        let o = self.collect(status);
        if status.signal() != Some(libc::SIGKILL) {
            check(&self.line, o.status, &o.stderr);
        }
        o
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if self.output.is_some() {
            return;
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        if !std::thread::panicking() {
            panic!("{} was left running: wait for it or kill it", self.line);
        }
    }
}

/// The stderr lines read so far, and whether stderr has closed.
type Log = Arc<(Mutex<(Vec<String>, bool)>, Condvar)>;

/// A long-running `aurora` whose stderr the test waits on (module docs).
pub struct Watched {
    child: Mutex<std::process::Child>,
    line: String,
    log: Log,
    stopped: bool,
}

impl Watched {
    /// The stderr so far, one line per line.
    pub fn text(&self) -> String {
        join(&self.log.0.lock().unwrap().0)
    }

    /// Fails the test if it has exited by a crash (as [`Aurora::output`]
    /// checks); whether it has exited.
    fn exited(&self) -> bool {
        let status = self.child.lock().unwrap().try_wait().expect("try_wait");
        if let Some(s) = status {
            check(&self.line, s, self.text().as_bytes());
        }
        status.is_some()
    }

    /// Waits until `cond` holds on the stderr so far and returns it; fails
    /// after `deadline`, or once stderr closes without `cond` holding.
    pub fn wait_for(&self, what: &str, deadline: Duration, cond: impl Fn(&str) -> bool) -> String {
        let t = Instant::now();
        let mut g = self.log.0.lock().unwrap();
        loop {
            let text = join(&g.0);
            if cond(&text) {
                return text;
            }
            if g.1 {
                drop(g);
                // The child's end: a crash is named as such.
                let exit = self.child.lock().unwrap().wait().expect("wait for the child");
                check(&self.line, exit, text.as_bytes());
                panic!("{} exited ({exit}) before {what}; stderr:\n{text}", self.line);
            }
            let left = deadline.checked_sub(t.elapsed());
            let Some(left) = left.filter(|l| !l.is_zero()) else {
                panic!("timed out after {deadline:?} waiting for {what}; stderr so far:\n{text}")
            };
            g = self.log.1.wait_timeout(g, left).unwrap().0;
        }
    }

    /// True while the child runs (a crash fails the test here).
    pub fn running(&self) -> bool {
        !self.exited()
    }

    /// Stops it on purpose (SIGKILL), once the test is done with it; it
    /// must still be running then.
    pub fn stop(mut self) {
        assert!(self.running(), "{} exited before the test stopped it; stderr:\n{}", self.line, self.text());
        self.stopped = true;
    }
}

impl Drop for Watched {
    fn drop(&mut self) {
        let c = self.child.get_mut().unwrap_or_else(|e| e.into_inner());
        let _ = c.kill();
        let _ = c.wait();
        if !self.stopped && !std::thread::panicking() {
            panic!("{} was left running: stop it", self.line);
        }
    }
}

fn join(lines: &[String]) -> String {
    let mut s = lines.join("\n");
    if !s.is_empty() {
        s.push('\n');
    }
    s
}
