//! `aurora bake --frames`: every frame's bytes are the same baked alone, in a
//! range, in any shard (I/N, Slurm's and Kubernetes' variables); frames
//! move; with every motion parameter at zero they do not; a rerun skips
//! complete frames and never takes a temporary file for one; the stage lists
//! every frame of the range whichever shard wrote it; bad ranges and shards
//! exit 2 naming the offending text.

use crate::common::small::{bake_command, baked_frames};
use crate::common::{file_names, ok, refused, scratch, write, Aurora};
use crate::small_bake_toml;
use std::path::{Path, PathBuf};
use std::process::Output;

/// A small scene (about a second a frame) whose motion is fast enough that
/// consecutive frames differ at its 1 km voxels.
const SMALL: &str = concat!(
    small_bake_toml!(),
    r#"[animation]
fps = 24.0
ray_speed_kms = 20.0
pulsation = 0.5
"#
);

const STILL: &str = r#"
fold_speed_kms = 0.0
fold_breathing = 0.0
bend_speed_kms = 0.0
bend_change_hz = 0.0
drift_km = 0.0
ray_speed_kms = 0.0
pulsation = 0.0
"#;

fn bake(scene: &Path, out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Output {
    bake_command(scene, out).arg("-q").args(extra).envs(env.iter().copied()).output()
}

/// [`SMALL`] with a 16 x 12 render, its frames `frames` baked into a fresh
/// folder `name`: (folder, scene, sequence folder).
fn baked_for_render(name: &str, frames: &str) -> (PathBuf, PathBuf, PathBuf) {
    baked_frames("frames", name, &format!("{SMALL}[render]\nwidth = 16\nheight = 12\nspp = 1\n"), frames)
}

fn read(dir: &Path, frame: i64) -> Vec<u8> {
    std::fs::read(dir.join(format!("aurora.{frame:04}.vdb"))).unwrap_or_else(|e| panic!("frame {frame} in {}: {e}", dir.display()))
}

#[test]
fn frames_are_identical_alone_in_a_range_and_in_any_shard() {
    let dir = scratch("frames", "shards");
    let scene = write(&dir, "small.toml", SMALL);

    let range = dir.join("range");
    ok(&bake(&scene, &range, &["--frames", "1-4", "--threads", "2"], &[]));
    let frames: Vec<Vec<u8>> = (1..=4).map(|f| read(&range, f)).collect();
    for i in 0..4 {
        for j in 0..i {
            assert_ne!(frames[i], frames[j], "frames {} and {} are equal: nothing moved", j + 1, i + 1);
        }
        assert!(dir.join("range").join(format!("aurora.{:04}.json", i + 1)).is_file());
    }
    let usda = std::fs::read_to_string(range.join("aurora.usda")).unwrap();

    // Two shards into one folder, one thread each.
    let sharded = dir.join("sharded");
    ok(&bake(&scene, &sharded, &["--frames", "1-4", "--shard", "1/2", "--threads", "1"], &[]));
    assert!(!sharded.join("aurora.0001.vdb").exists() && sharded.join("aurora.0002.vdb").exists());
    // The stage lists every frame already, whichever shard wrote it.
    assert_eq!(std::fs::read_to_string(sharded.join("aurora.usda")).unwrap(), usda);
    ok(&bake(&scene, &sharded, &["--frames", "1-4", "--shard", "0/2", "--threads", "1"], &[]));
    // Slurm's array variables (task 7 of 5..8 is shard 2 of 4: frame 3) and
    // a Kubernetes Indexed Job's index (shard 3 of 4: frame 4).
    let slurm = dir.join("slurm");
    let vars =
        [("SLURM_ARRAY_TASK_ID", "7"), ("SLURM_ARRAY_TASK_MIN", "5"), ("SLURM_ARRAY_TASK_COUNT", "4"), ("SLURM_ARRAY_TASK_STEP", "1")];
    ok(&bake(&scene, &slurm, &["--frames", "1-4", "--shard", "auto"], &vars));
    ok(&bake(&scene, &slurm, &["--frames", "1-4", "--shard", "auto/4"], &[("JOB_COMPLETION_INDEX", "3")]));
    assert_eq!(
        file_names(&slurm),
        [".aurora.sequence.json", "aurora.0003.json", "aurora.0003.vdb", "aurora.0004.json", "aurora.0004.vdb", "aurora.usda"]
    );
    // Frame 3 alone.
    let alone = dir.join("alone");
    ok(&bake(&scene, &alone, &["--frames", "3"], &[]));
    for f in 1..=4 {
        assert_eq!(read(&sharded, f), frames[f as usize - 1], "frame {f}: shards 0/2 + 1/2 differ from the range");
    }
    assert_eq!(read(&slurm, 3), frames[2]);
    assert_eq!(read(&slurm, 4), frames[3]);
    assert_eq!(read(&alone, 3), frames[2], "frame 3 alone differs from frame 3 of the range");
}

#[test]
fn rerun_skips_complete_frames_and_ignores_temporaries() {
    let dir = scratch("frames", "rerun");
    let scene = write(&dir, "small.toml", SMALL);
    let out = dir.join("out");
    ok(&bake(&scene, &out, &["--frames", "1-2"], &[]));
    let f1 = out.join("aurora.0001.vdb");
    let mtime = std::fs::metadata(&f1).unwrap().modified().unwrap();
    let good2 = read(&out, 2);
    // Frame 2 interrupted between its renames: its VDB (of another frame,
    // ours) is there, its report is not.
    std::fs::remove_file(out.join("aurora.0002.json")).unwrap();
    std::fs::copy(&f1, out.join("aurora.0002.vdb")).unwrap();
    // Frame 3: only a temporary (as a killed writer leaves it).
    std::fs::write(out.join(".aurora.0003.vdb.tmp999999"), b"half").unwrap();
    let msg = ok(&bake_command(&scene, &out).args(["--frames", "1-3"]).output());
    assert!(msg.contains("2 frames baked, 1 already complete"), "{msg}");
    assert_eq!(std::fs::metadata(&f1).unwrap().modified().unwrap(), mtime, "frame 1 was rebaked");
    assert_eq!(read(&out, 2), good2, "the interrupted frame 2 was not rebaked");
    assert!(read(&out, 3).len() > 1000);
    assert!(out.join("aurora.0003.json").is_file());
}

#[test]
fn motion_off_gives_identical_grids() {
    let dir = scratch("frames", "still");
    let scene = write(&dir, "still.toml", format!("{SMALL}{STILL}").replace("ray_speed_kms = 20.0\npulsation = 0.5\n", ""));
    let out = dir.join("out");
    ok(&bake(&scene, &out, &["--frames", "1-2"], &[]));
    // The files differ only in their frame metadata (aurora_frame,
    // aurora_time_s, the frame's scene hash, the content UUID): compare the
    // grids, voxel by voxel.
    let grids = |f: i64| {
        let file = aurora::io::vdb::read::read_vdb(&out.join(format!("aurora.{f:04}.vdb"))).unwrap();
        let (d, e) = aurora::app::vdb_for_render::render_grids(file).unwrap();
        let (d, e) = (d.unwrap(), e.unwrap());
        (d.iter_active().collect::<Vec<_>>(), e.iter_active().collect::<Vec<_>>())
    };
    let (d1, e1) = grids(1);
    let (d2, e2) = grids(2);
    assert!(!e1.is_empty());
    assert!(d1 == d2 && e1 == e2, "frames 1 and 2 differ with every motion parameter at zero");
}

#[test]
fn bad_ranges_and_shards_exit_2_naming_the_text() {
    let dir = scratch("frames", "bad");
    let out = dir.join("out");
    for (args, needle) in [
        (vec!["--frames", "1-x"], "`1-x`"),
        (vec!["--frames", "5-1"], "runs backwards"),
        (vec!["--frames", "-3-2"], "negative"),
        (vec!["--frames", "1-4", "--shard", "4/4"], "`4/4`"),
        (vec!["--frames", "1-4", "--shard", "auto"], "SLURM_ARRAY_TASK_ID is not set"),
    ] {
        let msg = refused(&bake(Path::new("default"), &out, &args, &[]));
        assert!(msg.contains(needle), "{args:?}: {msg}");
    }
    let o = bake(
        Path::new("default"),
        &out,
        &["--frames", "1-4", "--shard", "auto"],
        &[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_MIN", "1"), ("SLURM_ARRAY_TASK_COUNT", "2"), ("SLURM_ARRAY_TASK_STEP", "2")],
    );
    assert!(refused(&o).contains("stepped"));
    assert!(!out.exists(), "a refused bake wrote {}", out.display());
}

#[test]
fn render_frame_renders_one_frame_or_a_range_of_a_sequence_folder() {
    let (dir, scene, out) = baked_for_render("render", "1-2");
    let img = dir.join("f.exr");
    let render = |frames: &str| Aurora::new().arg("render").arg(&scene).arg("--vdb").arg(&out).args(["--frame", frames, "--out"]).arg(&img);
    ok(&render("1-2").arg("--png").arg(dir.join("f.png")).arg("-q").output());
    for f in ["f.0001.exr", "f.0002.exr", "f.0001.png", "f.0002.png"] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    assert_ne!(std::fs::read(dir.join("f.0001.exr")).unwrap(), std::fs::read(dir.join("f.0002.exr")).unwrap());
    // A frame the folder does not hold is an input error naming the file.
    assert!(refused(&render("7").arg("-q").output()).contains("aurora.0007.vdb"));
}

#[test]
fn red_trail_frames_are_identical_alone_and_in_shards() {
    // With the red trail each frame traces its own earlier times of the
    // closed-form motion: frame 3 alone, in a range and in a shard (one
    // thread against two) are the same bytes, and the trail changes them.
    let dir = scratch("frames", "trail");
    let scene = write(&dir, "trail.toml", format!("{SMALL}trail_samples = 2\n"));
    let range = dir.join("range");
    ok(&bake(&scene, &range, &["--frames", "2-3", "--threads", "2"], &[]));
    let sharded = dir.join("sharded");
    ok(&bake(&scene, &sharded, &["--frames", "2-3", "--shard", "1/2", "--threads", "1"], &[]));
    let alone = dir.join("alone");
    ok(&bake(&scene, &alone, &["--frames", "3", "--threads", "1"], &[]));
    assert_eq!(read(&sharded, 3), read(&range, 3), "frame 3 of shard 1/2 differs from the range's");
    assert_eq!(read(&alone, 3), read(&range, 3), "frame 3 alone differs from the range's");
    let plain_scene = write(&dir, "plain.toml", SMALL);
    let plain = dir.join("plain");
    ok(&bake(&plain_scene, &plain, &["--frames", "3"], &[]));
    assert_ne!(read(&plain, 3), read(&range, 3), "the trail changed nothing");
}

/// `render --frame A-B` checks every frame it needs before the first is
/// rendered: a frame missing from the folder, or one whose VDB is not a
/// VDB (a file cut to nothing, another file in its place), exits 2 naming
/// that frame's file, and no image, preview or temporary is written.
#[test]
fn render_frame_with_a_missing_or_damaged_frame_writes_nothing() {
    let (dir, scene, seq) = baked_for_render("render-missing", "1,3");
    let images = dir.join("images");
    std::fs::create_dir(&images).unwrap();
    let render = |frames: &str| {
        Aurora::new()
            .arg("render")
            .arg(&scene)
            .arg("--vdb")
            .arg(&seq)
            .args(["--frame", frames, "--out"])
            .arg(images.join("f.exr"))
            .arg("--png")
            .arg(images.join("f.png"))
            .arg("-q")
            .output()
    };
    let e = refused(&render("1-3"));
    assert_eq!(file_names(&images), Vec::<String>::new(), "written before the missing frame was found");
    assert!(e.contains("frame 2") && e.contains("aurora.0002.vdb") && e.contains("does not exist"), "{e}");
    std::fs::write(seq.join("aurora.0002.vdb"), b"").unwrap();
    let e = refused(&render("1-3"));
    assert!(e.contains("aurora.0002.vdb") && e.contains("not a VDB file"), "{e}");
    std::fs::copy(seq.join("aurora.usda"), seq.join("aurora.0002.vdb")).unwrap();
    let e = refused(&render("1-3"));
    assert!(e.contains("aurora.0002.vdb") && e.contains("magic number"), "{e}");
    assert_eq!(file_names(&images), Vec::<String>::new());
    // The frames that are there render.
    ok(&render("3"));
    assert_eq!(file_names(&images), ["f.0003.exr", "f.0003.png"]);
}
