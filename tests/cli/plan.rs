//! `aurora bake --frames SPEC --plan`: the estimate of a frame range from a
//! few calibration frames (`aurora::farm::cost_plan`) against what baking the
//! range then writes.

use crate::common::small::bake_command;
use crate::common::{ok, refused, scratch, write};
use crate::small_bake_toml;
use std::path::Path;

/// The small scene, its frames 10 s apart so that the 24 frames span four
/// minutes of the closed-form motion (folds travel 3 km/s, the curtain
/// drifts 8 km over a 300 s period): their sizes differ, and the estimate
/// has something to get right.
const SCENE: &str = concat!(small_bake_toml!(), "[animation]\nfps = 0.1\n");

fn bytes_of_bake(out: &Path) -> u64 {
    std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_name().to_string_lossy().starts_with("aurora."))
        .map(|e| e.metadata().unwrap().len())
        .sum()
}

/// The plan's total bytes lie within 25 % of what the 24-frame bake writes
/// (the stage, every frame's VDB and report), it writes nothing to its
/// output folder and leaves nothing in the temporary directory.
#[test]
fn plan_bytes_are_within_a_quarter_of_the_bake() {
    let dir = scratch("plan", "bytes");
    let scene = write(&dir, "scene.toml", SCENE);
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    let planned = dir.join("planned");
    let o = bake_command(&scene, &planned).args(["--frames", "1-24", "--plan", "--progress", "json"]).env("TMPDIR", &tmp).output();
    ok(&o);
    let plan: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    assert!(!planned.exists(), "--plan wrote its output folder");
    assert_eq!(std::fs::read_dir(&tmp).unwrap().count(), 0, "the scratch folder was left behind");
    assert_eq!(plan["frames"], 24);
    let samples: Vec<i64> = plan["samples"].as_array().unwrap().iter().map(|s| s["frame"].as_i64().unwrap()).collect();
    assert_eq!(samples, vec![1, 13, 24]);
    let sizes: Vec<f64> = plan["samples"].as_array().unwrap().iter().map(|s| s["vdb_bytes"].as_f64().unwrap()).collect();
    assert!(sizes.iter().any(|&s| s != sizes[0]), "frames of a moving scene differ in size: {sizes:?}");
    let cpu = plan["cpu_per_frame_s"].as_f64().unwrap();
    assert!(cpu > 0.0 && plan["total_cpu_s"].as_f64().unwrap() >= 24.0 * cpu, "{plan}");
    assert!(plan["peak_rss_bytes"].as_f64().unwrap() > 1e6, "{plan}");

    let baked = dir.join("baked");
    ok(&bake_command(&scene, &baked).args(["--frames", "1-24", "-q"]).output());
    let actual = bytes_of_bake(&baked) as f64;
    let estimate = plan["total_bytes"].as_f64().unwrap();
    let rel = (estimate - actual).abs() / actual;
    println!("plan {estimate:.0} B, bake {actual:.0} B, relative error {rel:.3}");
    assert!(rel < 0.25, "plan {estimate} B against the bake's {actual} B ({rel:.3})");
}

/// `--plan` needs a frame range; bad sample counts are refused by name, exit 2.
#[test]
fn plan_refuses_bad_arguments() {
    let dir = scratch("plan", "args");
    let scene = write(&dir, "scene.toml", SCENE);
    for (args, needle) in [(&["--plan"][..], "--frames"), (&["--frames", "1-3", "--plan", "--plan-samples", "0"][..], "--plan-samples")] {
        let e = refused(&bake_command(&scene, &dir.join("out")).args(args).output());
        assert!(e.contains(needle), "{args:?}: {e}");
        assert!(!dir.join("out").exists());
    }
}
