//! A bake never replaces a file it did not write: a folder holding a
//! hand-made `bake.json` (not one of our reports) or, without a report, an
//! `aurora.vdb` that is not ours, is refused before anything is baked
//! (exit status 2, naming the file), and the file is left as it was; so is
//! a sequence's folder holding a frame VDB without its report that is not
//! ours, or a frame report without its VDB that is not one of ours.

use crate::common::small::bake_command;
use crate::common::{file_names, ok, refused, scratch, write};
use aurora::grid::{Grid, Transform};
use aurora::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
use glam::{DVec3, IVec3};

const SMALL: &str = crate::small_bake_toml!();

/// A VDB of another program: a valid file whose grids carry none of our
/// metadata.
fn foreign_vdb() -> Vec<u8> {
    let mut d = Grid::new("density", 0.0f32, Transform::new(0.5, DVec3::ZERO));
    d.set(IVec3::new(1, 2, 3), 1.0);
    write_vdb_bytes(&[GridRef::Float(&d)], &WriteOptions { metadata: vec![], ..Default::default() }).unwrap()
}

#[test]
fn a_bake_refuses_a_folder_holding_files_it_did_not_write() {
    let dir = scratch("foreign", "files");
    let scene = write(&dir, "scene.toml", SMALL);
    let cases: [(&str, Vec<u8>, &str); 4] = [
        ("bake.json", b"{\"mine\": true}\n".to_vec(), "is not the report of an aurora bake"),
        ("bake.json", b"my notes\n".to_vec(), "is not the report of an aurora bake"),
        ("aurora.vdb", foreign_vdb(), "has no bake.json beside it and is not a VDB aurora wrote"),
        ("aurora.vdb", b"not a volume".to_vec(), "has no bake.json beside it and is not a VDB aurora wrote"),
    ];
    for (i, (name, bytes, why)) in cases.iter().enumerate() {
        let out = dir.join(format!("out{i}"));
        std::fs::create_dir_all(&out).unwrap();
        let p = write(&out, name, bytes);
        let e = refused(&bake_command(&scene, &out).arg("-q").output());
        assert!(e.contains(&format!("{}: {why}", p.display())) && e.contains("a bake replaces only its own files"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), *bytes, "{name} left as it was");
        assert_eq!(file_names(&out), vec![name.to_string()], "nothing written beside it");
    }
    // Our own files are replaced: a full bake, and its VDB alone (a bake
    // stopped before its report was renamed into place).
    let out = dir.join("ours");
    ok(&bake_command(&scene, &out).arg("-q").output());
    ok(&bake_command(&scene, &out).arg("-q").output());
    std::fs::remove_file(out.join("bake.json")).unwrap();
    ok(&bake_command(&scene, &out).arg("-q").output());
    assert_eq!(file_names(&out), vec!["aurora.usda", "aurora.vdb", "bake.json"]);
}

/// A sequence bake's frame names under the same rule: a hand-made
/// `aurora.0001.vdb` without its report, or a frame report without its VDB
/// that is not one of ours, is refused before anything is baked, with or
/// without `--rebake`, naming the file; an interrupted frame of ours (its
/// report gone) is baked again.
#[test]
fn a_sequence_bake_refuses_a_frame_vdb_it_did_not_write() {
    let dir = scratch("foreign", "frames");
    let scene = write(&dir, "scene.toml", SMALL);
    let vdb_why = "has no aurora.0001.json beside it and is not a VDB aurora wrote";
    let json_why = "is not the report of an aurora bake";
    let cases: [(&str, Vec<u8>, &[&str], &str); 5] = [
        ("aurora.0001.vdb", foreign_vdb(), &[], vdb_why),
        ("aurora.0001.vdb", b"not a volume".to_vec(), &[], vdb_why),
        ("aurora.0001.vdb", foreign_vdb(), &["--rebake"], vdb_why),
        ("aurora.0001.json", b"{\"mine\": true}\n".to_vec(), &[], json_why),
        ("aurora.0002.json", b"my notes\n".to_vec(), &["--rebake"], json_why),
    ];
    for (i, (name, bytes, flags, why)) in cases.iter().enumerate() {
        let out = dir.join(format!("seq{i}"));
        std::fs::create_dir_all(&out).unwrap();
        let p = write(&out, name, bytes);
        let o = bake_command(&scene, &out).args(["--frames", "1-2", "-q"]).args(*flags).output();
        let e = refused(&o);
        assert!(e.contains(&format!("{}: {why}", p.display())) && e.contains("a bake replaces only its own files"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), *bytes, "left as it was");
        assert_eq!(file_names(&out), vec![name.to_string()], "nothing written beside it");
    }
    // A frame of ours whose report is gone (a bake stopped between the
    // frame's renames) is baked again.
    let out = dir.join("ours");
    ok(&bake_command(&scene, &out).args(["--frames", "1-2", "-q"]).output());
    std::fs::remove_file(out.join("aurora.0001.json")).unwrap();
    ok(&bake_command(&scene, &out).args(["--frames", "1-2", "-q"]).output());
    assert!(out.join("aurora.0001.json").is_file());
}

/// Ctrl-C (SIGINT) during a bake: stderr says it was interrupted, the
/// process ends by the signal as an interrupted one does, and the folder's
/// `.aurora.lock` is gone; the next bake finds nothing of it.
#[test]
fn an_interrupted_bake_says_so_and_removes_its_lock() {
    use std::os::unix::process::ExitStatusExt;
    use std::time::{Duration, Instant};
    let dir = scratch("foreign", "interrupted");
    let out = dir.join("out");
    // The default scene bakes for many seconds: the signal comes mid-bake.
    let mut c = std::process::Command::new(crate::common::child::AURORA_BIN);
    c.arg("bake").arg("--out").arg(&out).args(["-q", "--threads", "2"]);
    c.stdin(std::process::Stdio::null()).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped());
    for v in crate::common::child::FARM_VARS {
        c.env_remove(v);
    }
    let mut child = c.spawn().unwrap();
    let lock = out.join(".aurora.lock");
    let t = Instant::now();
    // Until the bake holds the lock (a lock of ours on it would block).
    let held = || std::fs::File::open(&lock).is_ok_and(|f| matches!(f.try_lock(), Err(std::fs::TryLockError::WouldBlock)));
    while !held() && child.try_wait().unwrap().is_none() && t.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(held(), "the bake took no lock");
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let o = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.signal(), Some(libc::SIGINT), "{e}");
    assert!(e.contains("aurora: interrupted before finishing"), "{e}");
    assert!(!lock.exists(), "{:?}", file_names(&out));
    assert!(!file_names(&out).contains(&"bake.json".to_string()));
}
