//! A long-running `aurora` child (`aurora preview --watch`) whose stderr the
//! test waits on: a reader thread appends each line as it comes and wakes
//! the waiters, so a wait returns as soon as its condition holds and fails
//! at its deadline (or as soon as the child's stderr closes) with the lines
//! so far. The child is killed however the test ends.

use std::io::BufRead;
use std::process::{Command, Stdio};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// The lines read so far, and whether stderr has closed.
type Shared = Arc<(Mutex<(Vec<String>, bool)>, Condvar)>;

pub struct Child {
    child: Mutex<std::process::Child>,
    log: Shared,
}

impl Child {
    /// Spawns `cmd` with stdout discarded and stderr read line by line.
    pub fn spawn(cmd: &mut Command) -> Child {
        let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("spawn aurora");
        let stderr = child.stderr.take().expect("piped stderr");
        let log: Shared = Arc::new((Mutex::new((Vec::new(), false)), Condvar::new()));
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
        Child { child: Mutex::new(child), log }
    }

    /// The stderr so far, one line per line.
    pub fn text(&self) -> String {
        join(&self.log.0.lock().unwrap().0)
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
            assert!(!g.1, "the child's stderr closed before {what}; stderr:\n{text}");
            let left = deadline.checked_sub(t.elapsed());
            let Some(left) = left.filter(|l| !l.is_zero()) else {
                panic!("timed out after {deadline:?} waiting for {what}; stderr so far:\n{text}")
            };
            g = self.log.1.wait_timeout(g, left).unwrap().0;
        }
    }

    /// True while the child runs.
    pub fn running(&self) -> bool {
        self.child.lock().unwrap().try_wait().expect("try_wait").is_none()
    }
}

impl Drop for Child {
    fn drop(&mut self) {
        let c = self.child.get_mut().unwrap_or_else(|e| e.into_inner());
        let _ = c.kill();
        let _ = c.wait();
    }
}

fn join(lines: &[String]) -> String {
    let mut s = lines.join("\n");
    if !s.is_empty() {
        s.push('\n');
    }
    s
}
