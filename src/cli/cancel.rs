//! `aurora bake --cancel-file PATH`: a host program's way to stop a bake
//! that works alike on every platform. Windows has no SIGINT one process
//! can send another (a console's Ctrl-C reaches its whole group, and
//! `TerminateProcess` gives the baker no say), so the Blender add-on asks
//! for the stop by creating a file instead (blender/bake_job.py).
//!
//! A thread looks for PATH every [`POLL`] (already there at the start
//! counts). Once it is there the run ends as an interrupted one does
//! (`out::on_interrupt_remove_locks`): the held locks' files are removed
//! (on Unix; on Windows the lock file stays and the next run into the
//! folder takes it, as after Ctrl-C), stderr says why (the JSON object
//! `{"error", "status", "seconds"}` with `--progress json`), and the process
//! exits with [`super::exit::CANCELLED`]. Nothing the bake had not renamed
//! into place is seen: the previous bake in the folder stays whole, its
//! units renamed manifest-last (`aurora::util::atomic_write`), and the
//! temporaries left behind are removed by the next run into the folder.

use aurora::util::progress::JsonProgress;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// How often the file is looked for: a stat call 20 times a second costs
/// nothing beside a bake, and a person's cancel is seen within a frame of
/// Blender's status bar.
pub const POLL: Duration = Duration::from_millis(50);

/// Starts the thread that ends the process once `path` exists; `json` is
/// the bake's JSON progress, whose writer the error line goes through so it
/// never splits another line.
pub fn watch(path: PathBuf, json: Option<Arc<JsonProgress<std::io::Stderr>>>) {
    std::thread::spawn(move || {
        while std::fs::symlink_metadata(&path).is_err() {
            std::thread::sleep(POLL);
        }
        aurora::util::atomic_write::remove_held_locks();
        let status = super::exit::CANCELLED;
        let message = format!("cancelled: {} appeared (--cancel-file)", path.display());
        match json {
            Some(p) => p.error(&message, status),
            None => eprintln!("aurora: {message}"),
        }
        std::process::exit(status);
    });
}
