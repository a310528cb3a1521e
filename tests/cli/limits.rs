//! The process's limits and inputs that say more than they show: a thread
//! count or a picture (render's, preview's, sky's, keogram's) too large for
//! the memory limit, a write beyond the
//! file-size limit (`ulimit -f`), a `--set` value with a second line, and
//! a farm's shard variables at the ends of a 64-bit integer. Each is
//! refused with its exit status and words, never a signal or an exit 0
//! with nothing done, and leaves no temporaries.

use crate::common::small::bake_command;
use crate::common::{aurora, file_names, refused, scratch, write, Aurora};
use std::os::unix::process::{CommandExt, ExitStatusExt};

const SMALL: &str = crate::small_bake_toml!();

fn small_scene(group: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = scratch("limits", group);
    let scene = write(&dir, "scene.toml", format!("{SMALL}[render]\nwidth = 16\nheight = 12\nspp = 1\n"));
    (dir, scene)
}

/// `--threads 1024` under a 1 GiB address-space cap: the stacks alone
/// would take half of it, so it is refused naming the count and the most
/// that fit, instead of failing to start the threads.
#[test]
fn threads_beyond_the_memory_limit_are_refused_naming_the_most_that_fit() {
    let (dir, scene) = small_scene("threads");
    let o = Aurora::new()
        .arg("render")
        .arg(&scene)
        .arg("--out")
        .arg(dir.join("a.exr"))
        .args(["--threads", "1024", "-q"])
        .capped(1 << 20)
        .output();
    let e = refused(&o);
    assert!(e.contains("--threads 1024:") && e.contains("RLIMIT_AS") && e.contains("use --threads "), "{e}");
    assert!(!dir.join("a.exr").exists());
}

/// A picture whose pixels alone exceed the memory limit is refused before
/// anything is baked or rendered, naming its size, the limit and a size
/// that fits.
#[test]
fn a_picture_too_large_for_the_memory_limit_is_refused_before_work() {
    let (dir, scene) = small_scene("picture");
    for (w, h, cap_mib) in [(16384, 4096, 512u64), (16384, 16384, 1024)] {
        let o = Aurora::new()
            .arg("render")
            .arg(&scene)
            .arg("--out")
            .arg(dir.join("a.exr"))
            .args(["--set", &format!("render.width={w}"), "--set", &format!("render.height={h}"), "-q"])
            .capped(cap_mib << 10)
            .output();
        let e = refused(&o);
        assert!(e.contains(&format!("render.width = {w}, render.height = {h}")) && e.contains("RLIMIT_AS"), "{e}");
        assert!(e.contains("render a smaller picture (at most about "), "{e}");
        assert!(!dir.join("a.exr").exists());
    }
}

/// `preview`'s, `sky`'s and `keogram`'s pictures under the same rule as
/// `render`'s: too large for a 1 GiB address-space cap, each is refused
/// before any work (exit status 2), naming the key, its value, the limit
/// and the sizes allowed, and writes nothing.
#[test]
fn preview_sky_and_keogram_pictures_too_large_for_the_memory_limit_are_refused_before_work() {
    let (dir, scene) = small_scene("pictures");
    let seq = dir.join("seq");
    std::fs::create_dir_all(&seq).unwrap();
    let (png, sky, keo) = (dir.join("p.png"), dir.join("sky.exr"), dir.join("k.exr"));
    let cases: [(Vec<&std::ffi::OsStr>, &[&str]); 3] = [
        (
            vec!["preview".as_ref(), scene.as_os_str(), "--out".as_ref(), png.as_os_str(), "--size".as_ref(), "16384x16384".as_ref()],
            &["--size 16384x16384: the picture's 268435456 pixels", "give a smaller --size (at most about "],
        ),
        (
            vec!["sky".as_ref(), scene.as_os_str(), "--out".as_ref(), sky.as_os_str(), "--width".as_ref(), "16384".as_ref()],
            &["--width 16384 (a 16384 x 8192 map): the picture's", "give a smaller --width (an even number in [8, "],
        ),
        (
            vec![
                "keogram".as_ref(),
                scene.as_os_str(),
                "--vdb".as_ref(),
                seq.as_os_str(),
                "--frame".as_ref(),
                "1-100000".as_ref(),
                "--out".as_ref(),
                keo.as_os_str(),
            ],
            &["--frame 1-100000: 100000 frames x 361 rows: the picture's", "select fewer frames (at most about "],
        ),
    ];
    for (args, words) in cases {
        let t = std::time::Instant::now();
        let e = refused(&Aurora::new().args(&args).arg("-q").capped(1 << 20).output());
        assert!(t.elapsed() < std::time::Duration::from_secs(5), "{args:?}: {:?}", t.elapsed());
        assert!(words.iter().all(|w| e.contains(w)) && e.contains("this process may use") && e.contains("RLIMIT_AS"), "{e}");
    }
    assert_eq!(file_names(&dir), vec!["scene.toml", "seq"], "nothing written");
    assert!(file_names(&seq).is_empty());
}

/// Under `ulimit -f` a write past the limit fails with EFBIG (SIGXFSZ is
/// ignored): exit status 1 naming the error, and the bake's temporaries,
/// lock and new folder are gone.
#[test]
fn a_write_beyond_the_file_size_limit_is_an_error_that_leaves_nothing() {
    let (dir, scene) = small_scene("fsize");
    let out = dir.join("out");
    let mut c = std::process::Command::new(crate::common::child::AURORA_BIN);
    c.arg("bake").arg(&scene).arg("--out").arg(&out).arg("-q").stdin(std::process::Stdio::null());
    for v in crate::common::child::FARM_VARS {
        c.env_remove(v);
    }
    // SAFETY: setrlimit is async-signal-safe, as pre_exec requires.
    unsafe {
        c.pre_exec(|| {
            let lim = libc::rlimit { rlim_cur: 4096, rlim_max: 4096 };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let o = c.output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.signal(), None, "killed by a signal: {e}");
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("File too large"), "{e}");
    // Nothing left: the folder the bake created is removed with its lock.
    assert!(!out.exists() || file_names(&out).is_empty(), "{:?}", file_names(&out));
}

/// `--set` takes one KEY=VALUE on one line: a second line (which TOML would
/// read as another key and drop) is refused naming the first.
#[test]
fn a_set_value_with_a_second_line_is_refused() {
    let (dir, scene) = small_scene("set");
    let s = scene.to_str().unwrap();
    let out = dir.join("a.exr");
    let o = aurora(&["render", s, "--out", out.to_str().unwrap(), "--set", "render.width=64\nspp = 3", "-q"]);
    let e = refused(&o);
    assert!(e.contains("takes one KEY=VALUE on one line") && e.contains("a line break follows `render.width=64`"), "{e}");
    assert!(!out.exists());
}

/// `--shard auto` under Slurm variables at the ends of a 64-bit integer is
/// refused (exit 2) naming them, never run as a shard that bakes nothing.
#[test]
fn shard_auto_refuses_variables_at_the_ends_of_a_64_bit_integer() {
    let (dir, scene) = small_scene("shard");
    let (max, min) = (i64::MAX.to_string(), i64::MIN.to_string());
    let (max, min) = (max.as_str(), min.as_str());
    for (id, lo, count) in [(max, min, "4"), (max, "0", max)] {
        let out = dir.join("seq");
        let vars = [("SLURM_ARRAY_TASK_ID", id), ("SLURM_ARRAY_TASK_MIN", lo), ("SLURM_ARRAY_TASK_COUNT", count)];
        let o = bake_command(&scene, &out).args(["--frames", "1-4", "--shard", "auto", "-q"]).envs(vars).output();
        let e = refused(&o);
        assert!(e.contains("--shard `auto`: SLURM_ARRAY_TASK_"), "{e}");
        assert!(!out.join("aurora.0001.vdb").exists());
    }
}

/// An output name of 250 bytes is written (its temporary's name is cut to
/// fit the file system's 255 bytes); one of 256 bytes is refused before
/// anything is rendered, naming the limit.
#[test]
fn output_names_up_to_the_file_systems_limit_are_written_and_longer_ones_refused_first() {
    let (dir, scene) = small_scene("names");
    let long = dir.join(format!("{}.exr", "n".repeat(246)));
    let o = Aurora::new().arg("render").arg(&scene).arg("--out").arg(&long).arg("-q").output();
    crate::common::ok(&o);
    assert!(long.is_file());
    let too_long = dir.join(format!("{}.exr", "n".repeat(252)));
    let e = refused(&Aurora::new().arg("render").arg(&scene).arg("--out").arg(&too_long).arg("-q").output());
    assert!(e.contains("a name of 256 bytes, longer than the 255 bytes a file name may have"), "{e}");
    let mut names = file_names(&dir);
    names.retain(|n| n != "scene.toml");
    assert_eq!(names, vec![long.file_name().unwrap().to_string_lossy().into_owned()], "no temporaries left");
}
