//! Resuming a sequence keeps only frames of the same bake
//! (`src/farm/sequence_folder.rs`, `src/pipeline/bake/identity.rs`): a rerun after an edit of a
//! key the bake reads is refused with exit 2 naming the first frame of the
//! other bake and how to go on, and writes nothing; an edit of a
//! render-only key (`render.exposure`, ...) or no edit keeps every frame
//! (not rebaked: same bytes, same mtimes); `--rebake` deletes the other
//! bake's frames and bakes these; a report of another build, of an older
//! aurora or one that is not a regular file is not a frame of this bake;
//! shards of two scenes baking into one folder at once end with one scene
//! refused and the folder and its stage holding the other's frames only; a
//! `--rebake` that takes a folder over from a running bake leaves only its
//! own frames.

use crate::common::small::bake_command;
use crate::common::{file_names, mkfifo, ok, refused, scratch, stderr, write, Aurora};
use crate::small_bake_toml;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant, SystemTime};

/// A small scene: about half a second a frame.
const SMALL: &str = concat!(
    small_bake_toml!(),
    r#"[animation]
fps = 24.0
ray_speed_kms = 20.0
"#
);

/// Generous: every run here takes seconds.
const DEADLINE: Duration = Duration::from_secs(300);

fn command(scene: &Path, out: &Path, extra: &[&str]) -> Aurora {
    bake_command(scene, out).args(["--threads", "1"]).args(extra)
}

/// `scene`'s `frames` baked alone into `dir/name`.
fn alone(scene: &Path, dir: &Path, name: &str, frames: &str) -> PathBuf {
    let out = dir.join(name);
    ok(&bake(scene, &out, &["--frames", frames]));
    out
}

/// A fresh folder `name` with the small scene, `a.toml`, baked: frames 1
/// to 3 in `shot`. Returns the folder, the scene and the shot.
fn three_frames(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let d = scratch("resume", name);
    let a = write(&d, "a.toml", SMALL);
    let out = alone(&a, &d, "shot", "1-3");
    (d, a, out)
}

/// A fresh folder `name` with two scenes: `a.toml`, the small scene, and
/// `b.toml`, another bake of it (another energy flux, and `edit` applied).
fn two_scenes(name: &str, edit: impl Fn(String) -> String) -> (PathBuf, PathBuf, PathBuf) {
    let d = scratch("resume", name);
    let a = write(&d, "a.toml", SMALL);
    let b = write(&d, "b.toml", edit(SMALL.replace("bend_km = 3.0", "bend_km = 3.0\nenergy_flux = 9.0")));
    (d, a, b)
}

fn bake(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    command(scene, out, extra).spawn().wait_within(DEADLINE)
}

/// Every regular file of a folder with a hash of its bytes and, but for
/// the stage (rewritten, same bytes, by every run that owns the folder),
/// its mtime.
fn snapshot(dir: &Path) -> Vec<(String, u64, Option<SystemTime>)> {
    file_names(dir)
        .into_iter()
        .filter(|n| std::fs::symlink_metadata(dir.join(n)).is_ok_and(|m| m.is_file()))
        .map(|n| {
            let p = dir.join(&n);
            let m = std::fs::metadata(&p).unwrap().modified().unwrap();
            let bytes = std::fs::read(&p).unwrap();
            (n.clone(), aurora::scene::fnv1a(&bytes), (n != "aurora.usda").then_some(m))
        })
        .collect()
}

fn report(dir: &Path, frame: i64) -> serde_json::Value {
    let p = dir.join(format!("aurora.{frame:04}.json"));
    serde_json::from_slice(&std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}

/// The frame numbers a folder holds (reports), ascending.
fn frames_in(dir: &Path) -> Vec<i64> {
    file_names(dir).iter().filter_map(|n| n.strip_prefix("aurora.")?.strip_suffix(".json")?.parse().ok()).collect()
}

/// The folder holds exactly `reference`'s frames (same VDB bytes, reports
/// naming the same bake) and its stage, and nothing else but the record.
fn same_bake_as(dir: &Path, reference: &Path) {
    assert_eq!(frames_in(dir), frames_in(reference), "{}", dir.display());
    for f in frames_in(reference) {
        let vdb = format!("aurora.{f:04}.vdb");
        assert!(std::fs::read(dir.join(&vdb)).unwrap() == std::fs::read(reference.join(&vdb)).unwrap(), "{vdb} differs");
        assert_eq!(report(dir, f)["bake_identity"], report(reference, f)["bake_identity"], "frame {f}");
    }
    assert_eq!(std::fs::read_to_string(dir.join("aurora.usda")).unwrap(), std::fs::read_to_string(reference.join("aurora.usda")).unwrap());
    let mut names = file_names(reference);
    names.sort();
    assert_eq!(file_names(dir), names, "{}: other files", dir.display());
}

#[test]
fn a_bake_key_edit_is_refused_and_a_render_only_edit_or_none_keeps_the_frames() {
    let (d, a, out) = three_frames("edits");
    let id = report(&out, 1)["bake_identity"].clone();
    assert!(id["scene"].is_string() && id["build"].is_string(), "{id}");
    for f in 2..=3 {
        assert_eq!(report(&out, f)["bake_identity"], id);
    }
    let before = snapshot(&out);
    assert_eq!(
        before.iter().map(|b| b.0.as_str()).collect::<Vec<_>>(),
        [
            ".aurora.sequence.json",
            "aurora.0001.json",
            "aurora.0001.vdb",
            "aurora.0002.json",
            "aurora.0002.vdb",
            "aurora.0003.json",
            "aurora.0003.vdb",
            "aurora.usda"
        ]
    );

    // The same scene, and the same scene spelled otherwise: kept.
    let respelled = write(
        &d,
        "a2.toml",
        format!("# the same scene\n{}", SMALL.replace("count = 400", "count = 400 # beams").replace("fps = 24.0", "fps = 24")),
    );
    for scene in [&a, &respelled] {
        let e = ok(&bake(scene, &out, &["--frames", "1-3"]));
        assert!(e.contains("0 frames baked, 3 already complete"), "{e}");
        assert_eq!(snapshot(&out), before, "{}: a frame was rebaked", scene.display());
    }
    // Render-only keys: kept.
    let render_only = format!(
        "{SMALL}[render]\nexposure = 5.0\nspp = 3\n[volume]\nemission_scale = 4.0\ndensity_scale = 0.5\n\
         [terrain]\nkind = \"plane\"\n[background]\nstars = true\nradiance = [0.1, 0.1, 0.1]\n"
    );
    let r = write(&d, "render-only.toml", &render_only);
    let e = ok(&bake(&r, &out, &["--frames", "1-3"]));
    assert!(e.contains("0 frames baked, 3 already complete"), "{e}");
    assert_eq!(snapshot(&out), before, "a render-only edit rebaked a frame");

    // Keys the bake reads: refused before any work, naming frame 1 and the
    // ways on; nothing in the folder changes.
    let edits: Vec<(&str, String, Vec<&str>)> = vec![
        ("energy_flux", SMALL.replace("bend_km = 3.0", "bend_km = 3.0\nenergy_flux = 9.0"), vec![]),
        ("render.width (pruning)", format!("{SMALL}[render]\nwidth = 320\n"), vec![]),
        ("camera.fov_deg", format!("{SMALL}[camera]\nfov_deg = 60.0\n"), vec![]),
        ("animation.fps", SMALL.replace("fps = 24.0", "fps = 25.0"), vec![]),
        ("--seed", SMALL.to_string(), vec!["--seed", "8"]),
        ("a frame of the range only", SMALL.replace("count = 400", "count = 401"), vec![]),
    ];
    for (i, (what, text, extra)) in edits.into_iter().enumerate() {
        let s = write(&d, &format!("edit-{i}.toml"), &text);
        let frames = if what == "a frame of the range only" { "3" } else { "1-3" };
        let t = Instant::now();
        let mut args = vec!["--frames", frames];
        args.extend(extra);
        let e = refused(&bake(&s, &out, &args));
        assert!(e.contains("frame 1 (") && e.contains("aurora.0001.json") && e.contains("another scene"), "{what}: {e}");
        assert!(e.contains("new folder") && e.contains("--rebake"), "{what}: {e}");
        assert!(t.elapsed() < Duration::from_secs(30), "{what}: refused after {:?}", t.elapsed());
        assert_eq!(snapshot(&out), before, "{what}: the folder changed");
    }
}

#[test]
fn rebake_replaces_every_frame_of_the_other_bake_and_keeps_its_own() {
    let (d, a, b) = two_scenes("rebake", |b| b);
    let reference = alone(&b, &d, "b-alone", "1-2");
    let out = alone(&a, &d, "shot", "1-3");
    // A frame VDB of ours without its report (interrupted between the renames).
    std::fs::copy(out.join("aurora.0001.vdb"), out.join("aurora.0009.vdb")).unwrap();
    // Frames 1 and 2 rebaked, frame 3 (out of the range) and the lone VDB deleted.
    let e = ok(&bake(&b, &out, &["--frames", "1-2", "--rebake"]));
    assert!(e.contains("2 frames baked, 0 already complete"), "{e}");
    same_bake_as(&out, &reference);
    // --rebake keeps this bake's own frames.
    let before = snapshot(&out);
    let e = ok(&bake(&b, &out, &["--frames", "1-2", "--rebake"]));
    assert!(e.contains("0 frames baked, 2 already complete"), "{e}");
    assert_eq!(snapshot(&out), before);
    // And the first scene is refused now.
    let e = refused(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("aurora.0001.json"), "{e}");
    assert_eq!(snapshot(&out), before);
}

#[test]
fn reports_of_another_build_an_older_aurora_or_not_regular_files_are_not_frames_of_this_bake() {
    let (_, a, out) = three_frames("reports");
    let path = |f: i64| out.join(format!("aurora.{f:04}.json"));
    // Frame 2 of another build (as a binary built from other source writes it).
    let mut r = report(&out, 2);
    r["bake_identity"]["build"] = "0123456789abcdef".into();
    std::fs::write(path(2), serde_json::to_string_pretty(&r).unwrap()).unwrap();
    let e = refused(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("frame 2 (") && e.contains("another build"), "{e}");
    // Frame 2 of an aurora from before bake identities.
    r.as_object_mut().unwrap().remove("bake_identity");
    std::fs::write(path(2), serde_json::to_string_pretty(&r).unwrap()).unwrap();
    let e = refused(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("frame 2 (") && e.contains("older aurora"), "{e}");
    // --rebake deletes it and bakes frame 2 again, byte for byte as before.
    let vdb2 = std::fs::read(out.join("aurora.0002.vdb")).unwrap();
    let e = ok(&bake(&a, &out, &["--frames", "1-3", "--rebake"]));
    assert!(e.contains("1 frames baked, 2 already complete"), "{e}");
    assert!(std::fs::read(out.join("aurora.0002.vdb")).unwrap() == vdb2, "frame 2 rebaked differs");
    // A FIFO in a report's place is refused without waiting on it, and
    // --rebake does not remove it (only a regular file is).
    std::fs::remove_file(path(3)).unwrap();
    mkfifo(&path(3));
    let e = refused(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("frame 3 (") && e.contains("is a FIFO, not a regular file"), "{e}");
    let e = refused(&bake(&a, &out, &["--frames", "1-3", "--rebake"]));
    assert!(e.contains("is a FIFO, not a regular file"), "{e}");
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(path(3)).unwrap().file_type().is_fifo());
}

/// Two scenes (another flux, another frame range and fps, so their stages
/// differ too), each in two shards, all four started at once into one
/// folder: the scene whose frame is committed first owns the folder, both
/// shards of the other are refused with exit 2, and the folder and its
/// stage are exactly the first scene's bake.
#[test]
fn concurrent_shards_of_two_scenes_into_one_folder_end_with_one_bake() {
    let (d, a, b) = two_scenes("concurrent", |b| b.replace("fps = 24.0", "fps = 30.0"));
    let (ra, rb) = (alone(&a, &d, "a-alone", "1-4"), alone(&b, &d, "b-alone", "1-3"));
    let out = d.join("shot");
    let start = |scene: &Path, frames: &str, shard: &str| command(scene, &out, &["--frames", frames, "--shard", shard]).spawn();
    let children = [start(&a, "1-4", "0/2"), start(&b, "1-3", "0/2"), start(&a, "1-4", "1/2"), start(&b, "1-3", "1/2")];
    let outs: Vec<Output> = children.into_iter().map(|c| c.wait_within(DEADLINE)).collect();
    let codes: Vec<Option<i32>> = outs.iter().map(|o| o.status.code()).collect();
    let logs: String = outs.iter().map(|o| format!("{:?}: {}\n", o.status.code(), stderr(o))).collect();
    let (winner, loser) = match (codes[0], codes[2], codes[1], codes[3]) {
        (Some(0), Some(0), Some(2), Some(2)) => (&ra, [&outs[1], &outs[3]]),
        (Some(2), Some(2), Some(0), Some(0)) => (&rb, [&outs[0], &outs[2]]),
        _ => panic!("expected one scene's shards to succeed and the other's refused: {codes:?}\n{logs}"),
    };
    for o in loser {
        let e = stderr(o);
        assert!(e.contains("not of this bake") || e.contains("belongs to another bake"), "{e}");
    }
    same_bake_as(&out, winner);
    let record: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join(".aurora.sequence.json")).unwrap()).unwrap();
    assert_eq!(record["bake_identity"], report(winner, 1)["bake_identity"]);
    eprintln!("owner: {}", winner.display());
}

/// A `--rebake` of another scene while a bake runs into the folder: the
/// folder ends with the new bake's frames only (the running bake is refused
/// at its next frame, or had finished and its frames were deleted).
#[test]
fn a_rebake_that_takes_a_folder_over_from_a_running_bake_leaves_only_its_own_frames() {
    let (d, a, b) = two_scenes("takeover", |b| b);
    let rb = alone(&b, &d, "b-alone", "1-2");
    let out = d.join("shot");
    let running = command(&a, &out, &["--frames", "1-8"]).spawn();
    // The event: the running bake's first frame is in place.
    let t = Instant::now();
    while !out.join("aurora.0001.json").exists() {
        assert!(t.elapsed() < DEADLINE, "the running bake wrote no frame in {DEADLINE:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
    let e = ok(&bake(&b, &out, &["--frames", "1-2", "--rebake"]));
    let first = running.wait_within(DEADLINE);
    match first.status.code() {
        Some(2) => assert!(stderr(&first).contains("took it over"), "{}", stderr(&first)),
        Some(0) => {}
        other => panic!("the running bake exited {other:?}: {}", stderr(&first)),
    }
    same_bake_as(&out, &rb);
    eprintln!("running bake: exit {:?}; rebake: {}", first.status.code(), e.lines().last().unwrap_or(""));
}

/// Asserts that the run failed on its own account (exit 1, not the
/// input's); returns its stderr.
fn failed(o: &Output) -> String {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "expected exit 1 (an I/O error): {e}");
    e
}

/// A resume checks each kept frame's VDB against its report (size, header
/// UUID): a VDB cut in half, two frames' VDBs swapped, and a VDB of the
/// right size whose UUID is not the report's are baked again, each said
/// on stderr with the count, and the folder ends byte for byte as a clean
/// bake of the same frames.
#[test]
fn a_truncated_swapped_or_foreign_frame_is_baked_again_and_matches_a_clean_bake() {
    let (d, a, out) = three_frames("verify");
    let clean = alone(&a, &d, "clean", "1-3");
    let vdb = |f: i64| out.join(format!("aurora.{f:04}.vdb"));
    let bytes1 = std::fs::read(vdb(1)).unwrap();
    std::fs::write(vdb(1), &bytes1[..bytes1.len() / 2]).unwrap();
    let (two, three) = (std::fs::read(vdb(2)).unwrap(), std::fs::read(vdb(3)).unwrap());
    assert_ne!(two, three);
    std::fs::write(vdb(2), &three).unwrap();
    std::fs::write(vdb(3), &two).unwrap();
    let e = ok(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("3 frames baked, 0 already complete"), "{e}");
    assert!(e.contains(&format!("frame 1: aurora.0001.vdb is {} bytes, its report records {}", bytes1.len() / 2, bytes1.len())), "{e}");
    for f in 2..=3 {
        assert!(e.contains(&format!("frame {f}: aurora.{f:04}.vdb ")) && e.contains("baking it again"), "{e}");
    }
    assert!(e.contains("3 frames baked again"), "{e}");
    same_bake_as(&out, &clean);

    // The same size, another UUID (a file of another bake written over
    // this one's, or a bit flipped in the header): caught by the UUID.
    let mut b2 = std::fs::read(vdb(2)).unwrap();
    b2[21] = if b2[21] == b'0' { b'1' } else { b'0' };
    std::fs::write(vdb(2), &b2).unwrap();
    let e = ok(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("1 frames baked, 2 already complete") && e.contains("frame 2: aurora.0002.vdb has UUID"), "{e}");
    assert!(e.contains("1 frames baked again"), "{e}");
    same_bake_as(&out, &clean);
    // And a folder that matches its reports is kept as it is.
    let before = snapshot(&out);
    let e = ok(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("0 frames baked, 3 already complete") && !e.contains("again"), "{e}");
    assert_eq!(snapshot(&out), before);
}

/// `scene` baked into `out` with at most `files` open file descriptors
/// (`ulimit -n`, which binds root too).
fn bake_with_open_files(scene: &Path, out: &Path, files: u32, extra: &[&str]) -> Output {
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -n {files} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_aurora"))
        .arg("bake")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--threads", "1"])
        .args(extra)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("sh runs");
    assert!(matches!(o.status.code(), Some(0..=2) | Some(127)), "ulimit -n {files}: {:?}: {}", o.status, stderr(&o));
    o
}

/// A failure to read the ownership record because the process has too
/// many files open (the smallest `ulimit -n` under which the binary
/// starts at all leaves it no descriptor for the record) is an I/O error,
/// exit 1, naming the record and the OS's reason; with --rebake of another
/// scene it deletes nothing (the frames' reports could not be read either:
/// they are not another bake's).
#[test]
fn too_many_open_files_reading_the_record_is_an_io_error_that_deletes_nothing() {
    let (d, _, out) = three_frames("open-files");
    let b = write(&d, "b.toml", SMALL.replace("bend_km = 3.0", "bend_km = 3.0\nenergy_flux = 9.0"));
    let before = snapshot(&out);
    let mut hit = false;
    for files in 3..=16 {
        let o = bake_with_open_files(&b, &out, files, &["--frames", "1-3", "--rebake"]);
        let e = stderr(&o);
        assert!(!e.contains("belongs to another bake") && !e.contains("not of this bake"), "ulimit -n {files}: {e}");
        if o.status.code() == Some(1) && e.contains(".aurora.sequence.json") {
            assert!(e.contains("Too many open files"), "{e}");
            assert_eq!(snapshot(&out), before, "ulimit -n {files}: the folder changed");
            hit = true;
            break;
        }
        // Failed earlier (the loader, the scene file, the lock): it must
        // have changed nothing either.
        assert_ne!(o.status.code(), Some(0), "ulimit -n {files}: the bake ran: {e}");
        assert_eq!(snapshot(&out), before, "ulimit -n {files}: the folder changed: {e}");
    }
    assert!(hit, "no ulimit -n from 3 to 16 made the record's read fail");
}

/// An ownership record that is not a regular file (a directory, a symbolic
/// link: only a regular file is ours) cannot be read: exit 1, the record's
/// path and the reason, never "belongs to another bake"; and with --rebake
/// of another scene nothing is deleted.
#[test]
fn an_unreadable_ownership_record_is_an_io_error_and_deletes_nothing() {
    let (d, a, out) = three_frames("record");
    let b = write(&d, "b.toml", SMALL.replace("bend_km = 3.0", "bend_km = 3.0\nenergy_flux = 9.0"));
    let record = out.join(".aurora.sequence.json");
    let good = std::fs::read(&record).unwrap();
    std::fs::remove_file(&record).unwrap();
    std::fs::create_dir(&record).unwrap();
    let before = snapshot(&out);
    for (scene, extra) in [(&a, &[][..]), (&b, &["--rebake"][..])] {
        let mut args = vec!["--frames", "1-3"];
        args.extend(extra);
        let e = failed(&bake(scene, &out, &args));
        assert!(e.contains("cannot read") && e.contains(".aurora.sequence.json") && e.contains("is a directory"), "{e}");
        assert!(!e.contains("belongs to another bake") && !e.contains("--rebake"), "{e}");
        assert_eq!(snapshot(&out), before, "{}: the folder changed", scene.display());
    }
    std::fs::remove_dir(&record).unwrap();
    std::os::unix::fs::symlink(".aurora.sequence.json", &record).unwrap();
    let e = failed(&bake(&b, &out, &["--frames", "1-3", "--rebake"]));
    assert!(e.contains(".aurora.sequence.json") && e.contains("symbolic link"), "{e}");
    assert!(!e.contains("belongs to another bake"), "{e}");
    for f in 1..=3 {
        assert!(out.join(format!("aurora.{f:04}.vdb")).is_file() && out.join(format!("aurora.{f:04}.json")).is_file(), "frame {f} deleted");
    }
    // A record that is read and is not one aurora writes is the folder's
    // content (exit 2), and says so rather than name another bake.
    std::fs::remove_file(&record).unwrap();
    std::fs::write(&record, b"{ not json").unwrap();
    let e = refused(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("not one aurora writes") && e.contains("not JSON") && !e.contains("belongs to another bake"), "{e}");
    // Restored, the folder resumes as before.
    std::fs::write(&record, good).unwrap();
    let e = ok(&bake(&a, &out, &["--frames", "1-3"]));
    assert!(e.contains("0 frames baked, 3 already complete"), "{e}");
}
