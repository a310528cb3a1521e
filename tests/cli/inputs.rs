//! Inputs that are not regular files (a FIFO, a character device, a
//! directory, a unix socket) given as the scene, the heightmap, the
//! background image or `--vdb` are refused with exit status 2, naming the
//! path and what it is, at once (never waiting on a FIFO's writer or
//! reading `/dev/zero` forever), and are left as they were: the FIFO is
//! still a FIFO, same inode, and was never opened (a writer blocked on it
//! is not woken).

use crate::common::{mkfifo, scratch, stderr, write, Aurora};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

/// A command that does not exit within this is hung (blocked on a FIFO
/// given as its scene, say). Generous: the refusals take milliseconds.
const DEADLINE: Duration = Duration::from_secs(30);

/// Runs aurora, waiting for it to exit up to [`DEADLINE`]; a child still
/// running then has blocked on its input: killed, and the test fails.
/// Returns its output and how long it ran.
fn run(args: &[std::ffi::OsString]) -> (Output, Duration) {
    let t = Instant::now();
    let o = Aurora::new().args(args).spawn().wait_within(DEADLINE);
    (o, t.elapsed())
}

/// The special files of one test: a FIFO, a character device, a directory
/// and a listening unix socket, with what aurora must call each.
struct Specials {
    fifo: PathBuf,
    sock: PathBuf,
    dir: PathBuf,
    _listener: std::os::unix::net::UnixListener,
}

impl Specials {
    fn new(d: &Path) -> Specials {
        let fifo = d.join("fifo.toml");
        mkfifo(&fifo);
        let sock = d.join("sock.toml");
        let listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
        let dir = d.join("folder.toml");
        std::fs::create_dir(&dir).unwrap();
        Specials { fifo, sock, dir, _listener: listener }
    }

    fn cases(&self) -> Vec<(PathBuf, &'static str)> {
        vec![
            (self.fifo.clone(), "is a FIFO, not a regular file"),
            (PathBuf::from("/dev/null"), "is a character device, not a regular file"),
            (PathBuf::from("/dev/zero"), "is a character device, not a regular file"),
            (self.dir.clone(), "is a directory, not a regular file"),
            (self.sock.clone(), "is a socket, not a regular file"),
        ]
    }
}

/// The FIFO's identity (inode, type, mtime), to show it untouched.
fn stamp(p: &Path) -> (u64, bool, std::time::SystemTime) {
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    let m = std::fs::symlink_metadata(p).unwrap();
    (m.ino(), m.file_type().is_fifo(), m.modified().unwrap())
}

/// A thread blocked opening `fifo` for writing: it returns only once a
/// reader opens the FIFO. `opened` says whether it has.
struct Writer {
    opened: std::sync::mpsc::Receiver<()>,
    thread: std::thread::JoinHandle<()>,
}

impl Writer {
    fn start(fifo: &Path) -> Writer {
        let (tx, rx) = std::sync::mpsc::channel();
        let p = fifo.to_path_buf();
        let thread = std::thread::spawn(move || {
            let f = std::fs::OpenOptions::new().write(true).open(&p).expect("open the FIFO for writing");
            let _ = tx.send(());
            drop(f);
        });
        Writer { opened: rx, thread }
    }

    /// Fails if a reader opened the FIFO; then opens it (non-blocking) to
    /// release the writer.
    fn finish(self, fifo: &Path) {
        assert!(self.opened.try_recv().is_err(), "{} was opened by aurora", fifo.display());
        use std::os::unix::fs::OpenOptionsExt;
        let r = std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK).open(fifo).unwrap();
        self.opened.recv_timeout(DEADLINE).expect("the writer is released");
        drop(r);
        self.thread.join().unwrap();
    }
}

/// Runs every case of `specials` through `args_for`, checking exit 2, the
/// message (the path and its kind) and that the FIFO is untouched; returns
/// the longest run.
fn refuse_all(specials: &Specials, what: &str, args_for: &dyn Fn(&Path) -> Vec<std::ffi::OsString>) -> Duration {
    // A new FIFO for every round: the last round released its writer by
    // opening the FIFO for reading, and a child spawned meanwhile by another
    // test's thread holds a copy of that descriptor until its `exec`. On the
    // same FIFO this round's writer could then find a reader and return at
    // once, as if aurora had opened it. A fresh inode has no such reader.
    std::fs::remove_file(&specials.fifo).expect("remove the last round's FIFO");
    mkfifo(&specials.fifo);
    let before = stamp(&specials.fifo);
    let writer = Writer::start(&specials.fifo);
    let mut longest = Duration::ZERO;
    for (path, kind) in specials.cases() {
        let (o, t) = run(&args_for(&path));
        longest = longest.max(t);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{what} = {}: {e}", path.display());
        assert!(e.contains(&path.display().to_string()) && e.contains(kind), "{what} = {}: {e}", path.display());
    }
    assert_eq!(stamp(&specials.fifo), before, "the FIFO changed");
    writer.finish(&specials.fifo);
    eprintln!("{what}: longest refusal {:.3} s", longest.as_secs_f64());
    longest
}

fn os(v: &[&str]) -> Vec<std::ffi::OsString> {
    v.iter().map(|s| s.into()).collect()
}

#[test]
fn a_scene_that_is_not_a_regular_file_is_refused_at_once() {
    let d = scratch("inputs", "scene");
    let s = Specials::new(&d);
    let out = d.join("out");
    for cmd in ["bake", "render", "scene"] {
        refuse_all(&s, &format!("{cmd} SCENE"), &|p| {
            let mut a = os(&[cmd]);
            a.push(p.into());
            if cmd != "scene" {
                a.extend(os(&["--out"]));
                a.push(if cmd == "bake" { out.clone().into() } else { out.with_extension("png").into() });
            }
            a
        });
    }
    assert!(!out.exists(), "a refused bake wrote {}", out.display());
}

/// A scene of 8 x 8 pixels whose `key` (in `[table]`) names `path`.
fn scene_naming(d: &Path, name: &str, table: &str, key: &str, path: &Path) -> PathBuf {
    let extra = if table == "terrain" { "kind = \"heightfield\"\n" } else { "" };
    let text = format!(
        "[render]\nwidth = 8\nheight = 8\nspp = 1\n[beams]\ncount = 50\n[footprint]\nresolution = [32, 16]\nsteps = 2\n\
         [{table}]\n{extra}{key} = '{}'\n",
        path.display()
    );
    write(d, name, text)
}

#[test]
fn a_heightmap_or_background_image_that_is_not_a_regular_file_is_refused_before_the_bake() {
    let d = scratch("inputs", "render-inputs");
    let s = Specials::new(&d);
    let png = d.join("out.png");
    let n = std::cell::Cell::new(0);
    for (table, key) in [("terrain", "heightmap"), ("background", "image")] {
        refuse_all(&s, &format!("render: {table}.{key}"), &|p| {
            n.set(n.get() + 1);
            let scene = scene_naming(&d, &format!("scene-{}.toml", n.get()), table, key, p);
            let mut a = os(&["render"]);
            a.push(scene.into());
            a.extend(os(&["--out"]));
            a.push(png.clone().into());
            a
        });
    }
    // `aurora terrain` reads the heightmap too (no early check: the open's).
    refuse_all(&s, "terrain: terrain.heightmap", &|p| {
        n.set(n.get() + 1);
        let scene = scene_naming(&d, &format!("scene-{}.toml", n.get()), "terrain", "heightmap", p);
        let mut a = os(&["terrain"]);
        a.push(scene.into());
        a.extend(os(&["--out"]));
        a.push(d.join("t.obj").into());
        a
    });
    assert!(!png.exists());
}

#[test]
fn a_vdb_that_is_not_a_regular_file_is_refused_at_once() {
    let d = scratch("inputs", "vdb");
    let s = Specials::new(&d);
    let scene = write(&d, "small.toml", "[render]\nwidth = 8\nheight = 8\nspp = 1\n");
    let png = d.join("out.png");
    refuse_all(&s, "render --vdb", &|p| {
        let mut a = os(&["render"]);
        a.push(scene.clone().into());
        a.extend(os(&["--vdb"]));
        a.push(p.into());
        a.extend(os(&["--out"]));
        a.push(png.clone().into());
        a
    });
    assert!(!png.exists());
}

/// The library's readers refuse on their own (the render command's early
/// check aside): the terrain and the sky open through `input_file`.
#[test]
fn the_terrain_and_sky_readers_refuse_without_blocking() {
    use aurora::render::{sky::Sky, terrain::Heightfield, RenderError};
    use aurora::scene::{Background, Terrain, TerrainKind};
    let d = scratch("inputs", "library");
    let s = Specials::new(&d);
    let writer = Writer::start(&s.fifo);
    for (path, kind) in s.cases() {
        let t = Instant::now();
        let terrain = Terrain { kind: TerrainKind::Heightfield, heightmap: Some(path.display().to_string()), ..Terrain::default() };
        let e = Heightfield::from_terrain(&terrain, None).unwrap_err();
        assert!(matches!(e, RenderError::Input { key: "terrain.heightmap", .. }), "{e}");
        assert!(e.to_string().contains(kind), "{e}");
        let bg = Background { image: Some(path.display().to_string()), ..Background::default() };
        let e = Sky::new(&bg, 1, None, Default::default()).expect_err("refused");
        assert!(matches!(e, RenderError::Input { key: "background.image", .. }), "{e}");
        assert!(t.elapsed() < DEADLINE, "{}: {:?}", path.display(), t.elapsed());
    }
    writer.finish(&s.fifo);
}
