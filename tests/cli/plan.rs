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
    // The expected peak (from a traced sample) lies under the refusal's bound.
    let (expected, bound) = (plan["expected_peak_bytes"].as_f64().unwrap(), plan["budget_bytes"].as_f64().unwrap());
    assert!(expected > 1e6 && expected <= bound, "{plan}");

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

/// One shard of a long range: the task bakes two frames but writes the
/// stage of all 40,000, about 2.6 MB, which outweighs them. The plan's
/// stage bytes, and its total, lie within 10 % of what the task then
/// writes (the stage is counted by its own writer, so it is exact; the
/// frames are the same two frames, their reports differing only in
/// timings).
#[test]
fn plan_for_a_shard_counts_the_stage_of_the_whole_range_the_task_writes() {
    let dir = scratch("plan", "shard");
    let scene = write(&dir, "scene.toml", SCENE);
    let shard = ["--frames", "1-40000", "--shard", "0/20000", "--threads", "1"];
    let o = bake_command(&scene, &dir.join("planned")).args(shard).args(["--plan", "--plan-samples", "2", "--progress", "json"]).output();
    ok(&o);
    let plan: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    assert_eq!((plan["frames"].as_u64(), plan["sequence_frames"].as_u64()), (Some(2), Some(40000)), "{plan}");
    assert_eq!(plan["shard"], serde_json::json!([0, 20000]));
    let baked = dir.join("baked");
    ok(&bake_command(&scene, &baked).args(shard).arg("-q").output());
    let stage = std::fs::metadata(baked.join("aurora.usda")).unwrap().len() as f64;
    let (planned_stage, planned_total) = (plan["stage_bytes"].as_f64().unwrap(), plan["total_bytes"].as_f64().unwrap());
    let actual = bytes_of_bake(&baked) as f64;
    println!("stage: plan {planned_stage:.0} B, bake {stage:.0} B; total: plan {planned_total:.0} B, bake {actual:.0} B");
    assert!(stage > 2e6, "the stage lists all 40,000 frames: {stage} B");
    assert!((planned_stage - stage).abs() <= 0.1 * stage, "plan's stage {planned_stage} B, the task wrote {stage} B");
    assert!((planned_total - actual).abs() <= 0.1 * actual, "plan's total {planned_total} B, the task wrote {actual} B");
    // The table says whose share it is and what the stage lists.
    let o = bake_command(&scene, &dir.join("planned")).args(shard).args(["--plan", "--plan-samples", "2", "-q"]).output();
    ok(&o);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("(2 frames) of shard 0/20000 (the sequence has 40000 frames)"), "{text}");
    assert!(text.contains("listing the sequence's 40000 frames"), "{text}");
    assert!(text.contains("(the refusal's), expected peak ") && text.contains(" at 1 threads"), "{text}");
    assert!(!dir.join("planned").exists());
}

/// `--plan` for a shard without frames blames the shard: its index and
/// count and how many frames the range has; exit 2, nothing written.
#[test]
fn plan_of_an_empty_shard_names_the_shard_and_the_range() {
    let dir = scratch("plan", "empty-shard");
    let scene = write(&dir, "scene.toml", SCENE);
    let out = dir.join("out");
    let e = refused(&bake_command(&scene, &out).args(["--frames", "1-3", "--shard", "5/8", "--plan"]).output());
    assert!(e.contains("--shard 5/8") && e.contains("range has 3 frames") && e.contains("8 shards"), "{e}");
    assert!(!out.exists());
}
