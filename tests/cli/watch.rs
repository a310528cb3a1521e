//! `aurora preview --watch` driven by the saves real editors make, with
//! file system events (inotify) and under the polling fallback
//! (`AURORA_WATCH=poll`): write in place in one write (nano, VS Code);
//! truncate, then the text in three writes 150 ms apart on one descriptor
//! (an editor pausing mid-save: the file sits empty, then half-written);
//! a temporary renamed onto the name, in the naming styles of JetBrains,
//! vim (`backupcopy=no`), emacs and atomic-write libraries, each with its
//! temporary written in chunks.
//!
//! Ten exposure edits must give ten exposure edits and nothing else: every
//! update the log shows (`scene PATH: text hash H`, then `wrote ...`) is of
//! a text the test finished saving, in the order saved, and none is of the
//! empty or half-written file between (which would rebake the default
//! scene: `edit (footprints)`). A file saved empty is an error in the
//! watch and the last good scene stays.
//!
//! Every wait is on the child's stderr lines with a deadline; the only
//! sleeps are the editor's pauses between chunks.

use crate::common::child::Watched;
use crate::common::small::preview_scene;
use crate::common::{refused, scratch, Aurora};
use aurora::scene::Scene;
use aurora::util::file_watch::text_hash;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Deadlines: the first picture is a bake of the small scene on a loaded
/// machine; every later wait is for an exposure edit (a re-encode, ms) or
/// an error line, after at most a 400 ms settle.
const FIRST: Duration = Duration::from_secs(300);
const EACH: Duration = Duration::from_secs(120);

/// The editor's pause between two chunks of one save.
const PAUSE: Duration = Duration::from_millis(150);

#[derive(Clone, Copy, Debug, PartialEq)]
enum Watch {
    Events,
    Poll,
}

/// How an editor saves `text` as `path`.
#[derive(Clone, Copy, Debug)]
enum Style {
    /// Truncate and write in one `write`, close.
    InPlace,
    /// Truncate, then three writes [`PAUSE`] apart (the first after a
    /// pause too: the file sits empty), on one descriptor, close.
    Chunks,
    /// JetBrains' safe write: `NAME___jb_tmp___` written, NAME renamed to
    /// `NAME___jb_old___`, the temporary renamed onto NAME, the old removed.
    JetBrains,
    /// vim with `backupcopy=no`: its `4913` writability probe, NAME renamed
    /// to the backup `NAME~`, a new NAME written, the backup removed.
    Vim,
    /// emacs' first save: the auto-save file `#NAME#`, NAME renamed to the
    /// backup `NAME~` (kept), a new NAME written, `#NAME#` removed.
    Emacs,
    /// An atomic-write library: `.NAME.tmp-N` written, renamed onto NAME.
    Atomic,
}

const RENAMES: [Style; 4] = [Style::JetBrains, Style::Vim, Style::Emacs, Style::Atomic];

/// Writes `text` to `path` on one descriptor: truncated, then three chunks
/// [`PAUSE`] apart.
fn chunks(path: &Path, text: &str) {
    let mut f = std::fs::OpenOptions::new().write(true).create(true).truncate(true).open(path).unwrap();
    let b = text.as_bytes();
    let third = b.len() / 3;
    for part in [&b[..third], &b[third..2 * third], &b[2 * third..]] {
        std::thread::sleep(PAUSE);
        f.write_all(part).unwrap();
    }
}

fn save(path: &Path, text: &str, style: Style, n: usize) {
    let dir = path.parent().unwrap();
    let name = path.file_name().unwrap().to_str().unwrap();
    let beside = |s: String| dir.join(s);
    match style {
        Style::InPlace => std::fs::write(path, text).unwrap(),
        Style::Chunks => chunks(path, text),
        Style::JetBrains => {
            let (tmp, old) = (beside(format!("{name}___jb_tmp___")), beside(format!("{name}___jb_old___")));
            chunks(&tmp, text);
            std::fs::rename(path, &old).unwrap();
            std::fs::rename(&tmp, path).unwrap();
            std::fs::remove_file(&old).unwrap();
        }
        Style::Vim => {
            let probe = beside("4913".into());
            std::fs::write(&probe, b"").unwrap();
            std::fs::remove_file(&probe).unwrap();
            let backup = beside(format!("{name}~"));
            std::fs::rename(path, &backup).unwrap();
            chunks(path, text);
            std::fs::remove_file(&backup).unwrap();
        }
        Style::Emacs => {
            let autosave = beside(format!("#{name}#"));
            std::fs::write(&autosave, text).unwrap();
            std::fs::rename(path, beside(format!("{name}~"))).unwrap();
            chunks(path, text);
            std::fs::remove_file(&autosave).unwrap();
        }
        Style::Atomic => {
            let tmp = beside(format!(".{name}.tmp-{n}"));
            chunks(&tmp, text);
            std::fs::rename(&tmp, path).unwrap();
        }
    }
}

/// A watch of a fresh copy of the small scene, past its first picture.
struct Session {
    child: Watched,
    scene: Scene,
    path: PathBuf,
    png: PathBuf,
    /// The hash of every text saved, in order (the first: the start).
    saved: Vec<u64>,
}

fn start(name: &str, watch: Watch) -> Session {
    let dir = scratch("watch", name);
    let path = dir.join("scene.toml");
    let png = dir.join("p.png");
    let scene = preview_scene();
    let text = scene.to_toml();
    std::fs::write(&path, &text).unwrap();
    let cmd = Aurora::new()
        .args(["preview", path.to_str().unwrap(), "--watch", "--size", "32x18", "--spp", "1", "--threads", "2", "--out"])
        .arg(&png);
    let child = match watch {
        Watch::Events => cmd.env_remove(aurora::util::file_watch::ENV),
        Watch::Poll => cmd.env(aurora::util::file_watch::ENV, "poll"),
    }
    .watch();
    let text_so_far = child.wait_for("the first picture", FIRST, |t| pictures(t) >= 1);
    let first = text_so_far.lines().next().unwrap();
    let how = match watch {
        Watch::Events => "(inotify: ".to_string(),
        Watch::Poll => {
            format!(
                "(polling every 50 ms (AURORA_WATCH=poll): a save counts once unchanged for {} ms",
                aurora::util::file_watch::SETTLE.as_millis()
            )
        }
    };
    assert!(first.starts_with("watching ") && first.contains(&how), "{first}");
    Session { child, scene, path, png, saved: vec![text_hash(text.as_bytes())] }
}

fn pictures(text: &str) -> usize {
    text.lines().filter(|l| l.starts_with("wrote ")).count()
}

/// The text hashes of the saves the watch acted on, in order.
fn acted(text: &str) -> Vec<u64> {
    text.lines()
        .filter_map(|l| l.strip_prefix("scene ").and_then(|r| r.split_once(": text hash ")))
        .map(|(_, r)| u64::from_str_radix(&r[..16], 16).unwrap_or_else(|e| panic!("{e}: {r}")))
        .collect()
}

/// Ten exposure edits saved in `styles` (in turn): each gives one update, an
/// exposure edit of the text saved; no other update, no error.
fn ten_exposure_edits(name: &str, watch: Watch, styles: &[Style]) {
    let mut s = start(name, watch);
    for i in 0..10 {
        s.scene.render.exposure = 3.0 + 0.25 * (i + 1) as f64;
        let text = s.scene.to_toml();
        s.saved.push(text_hash(text.as_bytes()));
        save(&s.path, &text, styles[i % styles.len()], i);
        s.child.wait_for(&format!("edit {} ({:?})", i + 1, styles[i % styles.len()]), EACH, |t| pictures(t) >= i + 2);
    }
    let text = s.child.text();
    assert_eq!(acted(&text), s.saved, "the watch acted on other texts than those saved, or not once each:\n{text}");
    let wrote: Vec<&str> = text.lines().filter(|l| l.starts_with("wrote ")).collect();
    assert_eq!(wrote.len(), 11, "{text}");
    assert!(wrote[0].contains("edit (first)"), "{text}");
    for w in &wrote[1..] {
        assert!(w.contains("edit (exposure)"), "an exposure edit became another edit: {w}\n{text}");
    }
    assert!(!text.contains("aurora: error"), "{text}");
    assert_eq!(&std::fs::read(&s.png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
    s.child.stop();
}

/// Two tests of `check`: `$events` with file system events, `$poll` under
/// the polling fallback, each in a folder named after it.
macro_rules! with_events_and_polling {
    ($events:ident, $poll:ident, $check:expr) => {
        #[test]
        fn $events() {
            ($check)(stringify!($events), Watch::Events);
        }

        #[test]
        fn $poll() {
            ($check)(stringify!($poll), Watch::Poll);
        }
    };
}

with_events_and_polling!(
    exposure_edits_written_in_place_stay_exposure_edits,
    exposure_edits_written_in_place_stay_exposure_edits_when_polling,
    |name, watch| ten_exposure_edits(name, watch, &[Style::InPlace])
);

with_events_and_polling!(
    exposure_edits_truncated_then_written_in_chunks_stay_exposure_edits,
    exposure_edits_truncated_then_written_in_chunks_stay_exposure_edits_when_polling,
    |name, watch| ten_exposure_edits(name, watch, &[Style::Chunks])
);

with_events_and_polling!(
    exposure_edits_saved_by_temporary_and_rename_stay_exposure_edits,
    exposure_edits_saved_by_temporary_and_rename_stay_exposure_edits_when_polling,
    |name, watch| ten_exposure_edits(name, watch, &RENAMES)
);

/// A file saved empty, then with comments only, is an error each time and
/// leaves the picture; the next good save is diffed against the last good
/// scene (an exposure edit, not a first bake or a rebake).
fn an_empty_save_is_an_error(name: &str, watch: Watch) {
    let mut s = start(name, watch);
    let before = std::fs::read(&s.png).unwrap();
    let errors = |t: &str| t.lines().filter(|l| l.starts_with("aurora: error:")).count();
    save(&s.path, "", Style::InPlace, 0);
    let text = s.child.wait_for("the empty save's error", EACH, |t| errors(t) >= 1);
    let e = text.lines().find(|l| l.starts_with("aurora: error:")).unwrap();
    assert!(e.contains("scene.toml: the saved scene file is empty"), "{e}");
    save(&s.path, "# a scene, soon\n\n   \n", Style::Chunks, 1);
    s.child.wait_for("the comment-only save's error", EACH, |t| errors(t) >= 2);
    assert_eq!(std::fs::read(&s.png).unwrap(), before, "an empty save must not touch the picture");
    s.scene.render.exposure += 1.0;
    save(&s.path, &s.scene.to_toml(), Style::Chunks, 2);
    let text = s.child.wait_for("the good save's picture", EACH, |t| pictures(t) >= 2);
    let last = text.lines().rfind(|l| l.starts_with("wrote ")).unwrap();
    assert!(last.contains("edit (exposure)"), "{text}");
    assert_eq!(pictures(&text), 2, "{text}");
    assert_eq!(acted(&text).len(), 4, "{text}");
    assert_ne!(std::fs::read(&s.png).unwrap(), before);
    s.child.stop();
}

with_events_and_polling!(
    an_empty_save_is_an_error_and_the_last_good_scene_stays,
    an_empty_save_is_an_error_and_the_last_good_scene_stays_when_polling,
    an_empty_save_is_an_error
);

#[test]
fn an_unknown_watch_mode_exits_2_naming_the_variable() {
    let dir = scratch("watch", "env");
    let path = dir.join("scene.toml");
    std::fs::write(&path, preview_scene().to_toml()).unwrap();
    let e =
        refused(&Aurora::new().args(["preview", path.to_str().unwrap(), "--watch"]).env(aurora::util::file_watch::ENV, "fast").output());
    assert!(e.contains("AURORA_WATCH=`fast`") && e.contains("`poll`"), "{e}");
}
