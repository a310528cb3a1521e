//! Outputs are ours and whole, through the binary:
//! device nodes, FIFOs and symlinks given as outputs survive; a killed bake's
//! temporaries are gone once the next bake has run; two bakes into one folder
//! never leave one's VDB beside the other's report; the output folder is
//! checked before the bake starts; the USD stage resolves its VDB in a
//! folder of any name. Device nodes and FIFOs are made in a
//! temporary folder, never the system's.

use crate::common::{aurora, file_names as names, mkfifo, ok, scratch, stderr, write, Aurora};
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn dir(name: &str) -> PathBuf {
    scratch("outputs", name)
}

/// A small, fast scene.
fn scene_file(d: &Path, seed: u64) -> PathBuf {
    write(
        d,
        &format!("small{seed}.toml"),
        format!(
            "seed = {seed}\n[[curtain]]\nlength = 8.0\nwidth = 4.0\nbend_km = 1.0\n\
             [footprint]\nresolution = [32, 16]\npressure_iterations = 10\n\
             [beams]\ncount = 300\n[grid]\nprune = 0.0\n[render]\nwidth = 32\nheight = 18\nspp = 1\n"
        ),
    )
}

/// A character device like /dev/null (1, 3), made in our own folder (root only:
/// the test suite runs as root in CI; elsewhere the FIFO and symlink cases
/// still run).
fn mknod_null(p: &Path) -> bool {
    Command::new("mknod").arg(p).args(["c", "1", "3"]).status().map(|s| s.success()).unwrap_or(false)
}

fn is_uid0() -> bool {
    Command::new("id").arg("-u").output().map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0").unwrap_or(false)
}

/// The VDB header's UUID (bytes 21..57: magic 8, version 4, library 4 + 4, flag 1).
fn vdb_uuid(p: &Path) -> String {
    let b = std::fs::read(p).expect("read vdb");
    String::from_utf8(b[21..57].to_vec()).expect("ascii uuid")
}

fn report(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).expect("read bake.json")).expect("bake.json parses")
}

#[test]
fn render_never_replaces_a_device_fifo_or_symlink() {
    let d = dir("render-special");
    let scene = scene_file(&d, 1);
    let scene = scene.to_str().unwrap();
    let fifo = d.join("fifo.exr");
    mkfifo(&fifo);
    let keep = d.join("keep.exr");
    std::fs::write(&keep, b"not ours to replace").unwrap();
    let link = d.join("link.exr");
    std::os::unix::fs::symlink(&keep, &link).unwrap();
    let mut cases = vec![(fifo.clone(), "a FIFO"), (link.clone(), "a symbolic link")];
    let dev = d.join("null.exr");
    if mknod_null(&dev) {
        cases.push((dev.clone(), "a character device"));
    } else {
        assert!(!is_uid0(), "mknod failed as root");
    }
    for (out, kind) in &cases {
        let o = aurora(&["render", scene, "--out", out.to_str().unwrap(), "-q"]);
        assert_eq!(o.status.code(), Some(2), "{}: {}", out.display(), stderr(&o));
        assert!(stderr(&o).contains(kind), "{}", stderr(&o));
        // --png too.
        let o = aurora(&["render", scene, "--out", d.join("ok.exr").to_str().unwrap(), "--png", out.to_str().unwrap(), "-q"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    }
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read(&keep).unwrap(), b"not ours to replace");
    if dev.exists() {
        assert!(std::fs::symlink_metadata(&dev).unwrap().file_type().is_char_device());
    }
    // The refusals came before rendering: nothing else was written.
    let left: Vec<_> = names(&d).into_iter().filter(|n| n.starts_with('.')).collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
    assert!(!d.join("ok.exr").exists());
}

#[test]
fn render_format_follows_the_extension() {
    let d = dir("render-format");
    let scene = scene_file(&d, 1);
    let scene = scene.to_str().unwrap();
    let o = aurora(&["render", scene, "--out", d.join("x.tiff").to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--out") && stderr(&o).contains(".exr"), "{}", stderr(&o));
    let o = aurora(&["render", scene, "--out", d.join("a.exr").to_str().unwrap(), "--png", d.join("b.jpg").to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // --out x.png is honoured: a PNG, not EXR bytes.
    let png = d.join("x.png");
    let o = aurora(&["render", scene, "--out", png.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(&std::fs::read(&png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
    let exr = d.join("x.EXR");
    let o = aurora(&["render", scene, "--out", exr.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(&std::fs::read(&exr).unwrap()[..4], &[0x76, 0x2f, 0x31, 0x01]);
}

#[test]
fn bake_refuses_special_files_in_its_folder_before_baking() {
    let d = dir("bake-special");
    let scene = scene_file(&d, 1);
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    mkfifo(&out.join("bake.json"));
    let t = Instant::now();
    let o = aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("bake.json") && stderr(&o).contains("FIFO"), "{}", stderr(&o));
    assert!(t.elapsed() < Duration::from_secs(5));
    assert_eq!(names(&out), vec!["bake.json"], "nothing written beside the FIFO");

    // A file where the folder should be.
    let notdir = d.join("file");
    std::fs::write(&notdir, b"x").unwrap();
    let o = aurora(&["bake", scene.to_str().unwrap(), "--out", notdir.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a folder"), "{}", stderr(&o));

    // A symlinked aurora.vdb is refused too, and survives.
    let out2 = d.join("out2");
    std::fs::create_dir(&out2).unwrap();
    std::os::unix::fs::symlink(&notdir, out2.join("aurora.vdb")).unwrap();
    let o = aurora(&["bake", scene.to_str().unwrap(), "--out", out2.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(out2.join("aurora.vdb")).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read(&notdir).unwrap(), b"x");
}

#[test]
fn a_killed_bake_leaves_nothing_once_the_next_bake_has_run() {
    let d = dir("killed");
    let out = d.join("out");
    // The default scene writes ~90 MB: long enough to be caught mid-write.
    let mut child = Aurora::new().args(["bake", "--out", out.to_str().unwrap(), "-q", "--threads", "2"]).spawn();
    let t = Instant::now();
    let mut caught = false;
    while t.elapsed() < Duration::from_secs(300) && child.running() {
        if names(&out).iter().any(|n| n.starts_with(".aurora.vdb.tmp")) {
            caught = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    // Killed on purpose, mid-write (a bake that ended first is checked).
    child.kill();
    assert!(caught, "the bake finished (or failed) before its VDB temporary was seen");
    let before = names(&out);
    assert!(before.iter().any(|n| n.starts_with(".aurora.vdb.tmp")), "{before:?}");
    assert!(!before.contains(&"bake.json".to_string()), "no report for a killed bake: {before:?}");

    let scene = scene_file(&d, 2);
    ok(&aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]));
    assert_eq!(names(&out), vec!["aurora.usda", "aurora.vdb", "bake.json"]);
    let r = report(&out.join("bake.json"));
    assert_eq!(r["files"]["vdb_uuid"].as_str().unwrap(), vdb_uuid(&out.join("aurora.vdb")));
}

#[test]
fn two_bakes_into_one_folder_leave_one_consistent_set() {
    let d = dir("concurrent");
    let out = d.join("out");
    let (s1, s2) = (scene_file(&d, 11), scene_file(&d, 12));
    let spawn = |s: &Path| Aurora::new().args(["bake", s.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]).spawn();
    for _ in 0..3 {
        let (a, b) = (spawn(&s1), spawn(&s2));
        let (oa, ob) = (a.wait(), b.wait());
        assert!(oa.status.success() && ob.status.success(), "{}\n{}", stderr(&oa), stderr(&ob));
        assert_eq!(names(&out), vec!["aurora.usda", "aurora.vdb", "bake.json"]);
        let r = report(&out.join("bake.json"));
        let seed = r["seed"].as_u64().unwrap();
        assert!(seed == 11 || seed == 12);
        assert_eq!(r["files"]["vdb_uuid"].as_str().unwrap(), vdb_uuid(&out.join("aurora.vdb")), "VDB and report from different bakes");
        assert_eq!(r["files"]["vdb_bytes"].as_u64().unwrap(), std::fs::metadata(out.join("aurora.vdb")).unwrap().len());
    }
}

#[test]
fn a_failed_bake_leaves_no_folder_it_created() {
    // A bake that fails after the folder was prepared: 2 m voxels, refused
    // by the memory budget (terabytes on any machine) inside the bake. (Many
    // beams no longer do: a bake's memory does not grow with the beams.)
    let d = dir("failed");
    let p = d.join("huge.toml");
    std::fs::write(&p, "[[curtain]]\nlength = 8.0\nwidth = 4.0\nbend_km = 1.0\n[grid]\nvoxel_size = 0.002\n").unwrap();
    let out = d.join("new-folder");
    let o = aurora(&["bake", p.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!out.exists(), "the failed bake left {:?}", names(&out));
    // Into an existing folder with a previous set: the set survives untouched.
    let kept = d.join("kept");
    let ok = scene_file(&d, 5);
    assert!(aurora(&["bake", ok.to_str().unwrap(), "--out", kept.to_str().unwrap(), "-q"]).status.success());
    let before: Vec<Vec<u8>> = ["aurora.vdb", "aurora.usda", "bake.json"].iter().map(|n| std::fs::read(kept.join(n)).unwrap()).collect();
    let o = aurora(&["bake", p.to_str().unwrap(), "--out", kept.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let after: Vec<Vec<u8>> = ["aurora.vdb", "aurora.usda", "bake.json"].iter().map(|n| std::fs::read(kept.join(n)).unwrap()).collect();
    assert!(before == after, "the previous set changed");
    assert_eq!(names(&kept), vec!["aurora.usda", "aurora.vdb", "bake.json"]);
}

/// An output whose folder cannot take a file is refused before anything
/// is baked or rendered (exit 2, the folder named; a failure after the
/// render would be the writer's, exit 1), and nothing is written: not
/// the EXR when only the preview's folder is bad. The cases fail for root
/// too: a folder that does not exist, and a "folder" that is a regular
/// file.
#[test]
fn render_into_a_folder_it_cannot_write_fails_before_rendering_and_writes_nothing() {
    let d = dir("render-folder");
    let scene = scene_file(&d, 1);
    let scene = scene.to_str().unwrap();
    let file = write(&d, "file.txt", "a regular file");
    let good = d.join("good.exr");
    let cases = [
        (d.join("missing/x.exr"), None, "does not exist"),
        (file.join("x.exr"), None, "not a folder"),
        (good.clone(), Some(file.join("x.png")), "not a folder"),
        (good.clone(), Some(d.join("missing/x.png")), "does not exist"),
    ];
    for (out, png, why) in &cases {
        let mut c = Aurora::new().args(["render", scene, "-q", "--out"]).arg(out);
        if let Some(p) = png {
            c = c.arg("--png").arg(p);
        }
        let o = c.output();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{}: {e}", out.display());
        assert!(e.contains("output folder") && e.contains(why), "{e}");
        assert!(!good.exists(), "{} written before the preview's folder was refused", good.display());
    }
    assert_eq!(names(&d), ["file.txt", "small1.toml"]);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "a regular file");
}

/// The stage's asset paths resolve whatever the output folder is called:
/// usd-core opens `aurora.usda` baked into folders named with a backslash,
/// `@`, `@@@`, a space and a colon, and resolves every field to the VDB
/// beside it; a sequence's stage in a folder named with a backslash
/// resolves every frame's time sample to that frame's VDB.
#[test]
fn the_stage_resolves_its_vdb_in_folders_named_with_characters_usd_treats_specially() {
    let d = dir("usd-names");
    let scene = write(&d, "scene.toml", crate::small_bake_toml!());
    let py = crate::common::venv_python();
    let same = |a: &str, b: &Path| !a.is_empty() && std::fs::canonicalize(a).ok() == std::fs::canonicalize(b).ok();
    for name in ["a\\b", "c@d", "e@@@f", "g h:i"] {
        let out = d.join(name);
        ok(&crate::common::small::bake_command(&scene, &out).arg("-q").output());
        let u = crate::common::run_json(&py, "usd_probe.py", &[out.join("aurora.usda").to_str().unwrap()]);
        for f in ["density", "emission"] {
            let r = u["volumes"][0]["fields"][f]["resolved_path"].as_str().unwrap_or("");
            assert!(same(r, &out.join("aurora.vdb")), "{name}: {f} resolves to `{r}`: {u}");
        }
    }
    let out = d.join("s\\q");
    ok(&crate::common::small::bake_command(&scene, &out).args(["--frames", "1-2", "-q"]).output());
    let script =
        "import sys\nfrom pxr import Usd\ns = Usd.Stage.Open(sys.argv[1])\na = s.GetPrimAtPath('/aurora/density').GetAttribute('filePath')\n\
                  print('\\n'.join(a.Get(t).resolvedPath for t in a.GetTimeSamples()))";
    let got = crate::common::python(&py, &["-c", script, out.join("aurora.usda").to_str().unwrap()]);
    let got: Vec<&str> = got.lines().collect();
    assert_eq!(got.len(), 2, "{got:?}");
    for (r, f) in got.iter().zip(["aurora.0001.vdb", "aurora.0002.vdb"]) {
        assert!(same(r, &out.join(f)), "{f} resolves to `{r}`");
    }
}
