//! The `aurora` binary end to end: a small scene baked, read back, rendered;
//! byte-identical output whatever the thread count; bad input refused with
//! exit status 2, a message naming file, key, value and range, and nothing
//! written.

use crate::common::{aurora as run, ok, refused, scratch, stderr, write};
use crate::small_bake_toml;
use aurora::util::fmath;

/// A scene small enough to bake in about a second.
const SMALL: &str = concat!(
    small_bake_toml!(),
    r#"[camera]
position = [0.0, -120.0, 20.0]
look_at = [0.0, 0.0, 120.0]
fov_deg = 60.0
[render]
width = 48
height = 32
spp = 2
[terrain]
kind = "plane"
"#
);

#[test]
fn bake_writes_vdb_usda_and_report_that_agree() {
    let dir = scratch("end_to_end", "bake");
    let scene = write(&dir, "small.toml", SMALL);
    let out = dir.join("out");
    ok(&run(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]));

    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("bake.json")).unwrap()).unwrap();
    let stats = &report["stats"];
    assert_eq!(stats["beams"], 400);
    assert!(stats["photons"].as_u64().unwrap() > 400, "every beam deposits photons");
    // Default pruning (grid.prune = 0.001) reported and consistent; no noise target.
    let pr = &stats["prune"];
    assert_eq!(pr["budget"], 0.001);
    let removed = pr["removed_fraction"].as_f64().unwrap();
    assert!(removed > 0.0 && removed <= 0.001, "{pr}");
    assert_eq!(pr["voxels_before"].as_u64().unwrap() - pr["voxels_removed"].as_u64().unwrap(), stats["active_voxels"].as_u64().unwrap());
    assert_eq!(pr["leaves_before"].as_u64().unwrap() - pr["leaves_removed"].as_u64().unwrap(), stats["leaves"].as_u64().unwrap());
    assert!(stats["noise"].is_null());
    assert_eq!(stats["voxel_size_km"], 1.0);
    assert_eq!(report["units"], "km");
    assert_eq!(report["seed"], 7);

    let file = aurora::io::vdb::read::read_vdb(&out.join("aurora.vdb")).unwrap();
    // By default the file holds the aurora's voxels, no Cycles shell, one
    // grid per field (the high column apart is `grid.high_voxel_factor > 1`:
    // tests/vdb/openvdb.rs, aurora::grid::high_column).
    assert!(report["files"]["high_column"].is_null(), "{}", report["files"]);
    assert!(file.vec3("emission_high").is_none() && file.float("density_high").is_none());
    assert_eq!(stats["shell_voxels"], 0);
    assert_eq!(stats["file_voxels"], stats["active_voxels"]);
    let fine = file.vec3("emission").expect("emission grid");
    let e = fine;
    let d = file.float("density").expect("density grid");
    assert_eq!(e.active_voxel_count(), stats["file_voxels"].as_u64().unwrap());
    // The density lives on the aurora's own voxels only: no fog box.
    assert!(d.active_voxel_count() <= e.active_voxel_count());
    for (ijk, _) in d.iter_active() {
        assert!(e.is_active(ijk), "density outside the aurora at {ijk}");
    }
    assert!(e.first_non_finite().is_none() && d.first_non_finite().is_none());
    // The stored peak is the bake's rounded to the kept mantissa bits (5 by
    // default, after the half float's 10): within half a unit in the last
    // kept place, 2^-(bits+1) relative, plus the half's own 2^-11.
    assert_eq!(report["files"]["mantissa_bits"], 5);
    assert_eq!(report["files"]["compression"], "zip-active-mask");
    let peak = fine.iter_active().map(|(_, v)| v[1]).fold(0.0f32, f32::max);
    let bound = fmath::powi(2f64, -6) + fmath::powi(2f64, -11);
    assert!((peak as f64 - stats["peak_emission"][1].as_f64().unwrap()).abs() <= bound * peak as f64);

    let usda = std::fs::read_to_string(out.join("aurora.usda")).unwrap();
    assert!(usda.contains("@aurora.vdb@") && usda.contains("metersPerUnit = 1000"), "{usda}");
    // No temporary files are left behind.
    let names: Vec<String> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert_eq!(names.len(), 3, "{names:?}");

    // Render the baked file with the reference renderer.
    let exr = dir.join("r.exr");
    let png = dir.join("r.png");
    ok(&run(&[
        "render",
        scene.to_str().unwrap(),
        "--vdb",
        out.join("aurora.vdb").to_str().unwrap(),
        "--out",
        exr.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--quiet",
    ]));
    let img = aurora::render::image_file::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (48, 32));
    assert!(img.pixels.iter().flatten().all(|c| c.is_finite()));
    assert!(img.pixels.iter().any(|p| p[1] > 0.0), "the aurora is in view");
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

#[test]
fn same_seed_gives_byte_identical_vdb_for_any_thread_count() {
    let dir = scratch("end_to_end", "determinism");
    let scene = write(&dir, "small.toml", SMALL);
    let mut files = Vec::new();
    for threads in ["1", "2", "3"] {
        let out = dir.join(format!("t{threads}"));
        ok(&run(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--threads", threads, "-q"]));
        files.push(std::fs::read(out.join("aurora.vdb")).unwrap());
    }
    assert!(files[0] == files[1] && files[1] == files[2], "aurora.vdb differs between thread counts");
    // A different seed changes the bake.
    let out = dir.join("seed8");
    ok(&run(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--seed", "8", "-q"]));
    assert_ne!(std::fs::read(out.join("aurora.vdb")).unwrap(), files[0]);
}

/// Each bad scene: (TOML, words the message must contain).
#[test]
fn bad_input_exits_2_names_the_problem_and_writes_nothing() {
    let dir = scratch("end_to_end", "bad");
    let cases: &[(&str, &[&str])] = &[
        ("[beams\ncount = 3\n", &["bad.toml", "line 1"]),
        ("[beams]\ncount = 3\nbogus_key = 1\n", &["bad.toml", "bogus_key", "line 3"]),
        ("[beams]\nalpha_d_deg = 90.0\n", &["bad.toml:2", "beams.alpha_d_deg = 90", "[0, 90)"]),
        ("[beams]\ncount = 0\n", &["bad.toml:2", "beams.count = 0", "[1, "]),
        ("[photons]\nradius_km = -0.5\n", &["bad.toml:2", "photons.radius_km = -0.5", "> 0"]),
        ("[grid]\nvoxel_size = 0.0\n", &["bad.toml:2", "grid.voxel_size = 0", "> 0"]),
        // Memory is a bake-time check (the scene is valid on any machine): no line number;
        // the share of the limit that counts, and a larger voxel that fits.
        ("[grid]\nvoxel_size = 0.001\n", &["grid.voxel_size = 0.001", "GiB", "80 %", "brings it under: grid.voxel_size = "]),
    ];
    for (toml, words) in cases {
        let scene = write(&dir, "bad.toml", toml);
        let out = dir.join("never");
        let o = run(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{toml:?}: {}", stderr(&o));
        let msg = stderr(&o);
        for w in *words {
            assert!(msg.contains(w), "{toml:?}: message lacks {w:?}: {msg}");
        }
        assert!(!out.exists(), "{toml:?}: output folder was created");
    }
    // A missing scene file, and a VDB that is not one.
    let e = refused(&run(&["bake", dir.join("missing.toml").to_str().unwrap(), "--out", dir.join("never").to_str().unwrap()]));
    assert!(e.contains("missing.toml"));
    let junk = write(&dir, "junk.vdb", b"not a vdb at all");
    let exr = dir.join("x.exr");
    let e = refused(&run(&["render", "default", "--vdb", junk.to_str().unwrap(), "--out", exr.to_str().unwrap()]));
    assert!(e.contains("junk.vdb"), "{e}");
    assert!(!exr.exists());
}

#[test]
fn printed_presets_parse_back_to_themselves() {
    for name in aurora::scene::presets::names() {
        let o = run(&["scene", name]);
        ok(&o);
        let text = String::from_utf8(o.stdout).unwrap();
        let parsed = aurora::scene::Scene::from_toml_str(&text, name).unwrap();
        assert_eq!(parsed, aurora::scene::presets::by_name(name).unwrap());
    }
}

#[test]
fn footprint_and_terrain_commands_write_files() {
    let dir = scratch("end_to_end", "fp");
    let scene = write(&dir, "small.toml", SMALL.replace("kind = \"plane\"", "kind = \"heightfield\""));
    ok(&run(&["footprint", scene.to_str().unwrap(), "--out", dir.to_str().unwrap()]));
    let png = std::fs::read(dir.join("footprint-0.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let obj = dir.join("t.obj");
    ok(&run(&["terrain", scene.to_str().unwrap(), "--out", obj.to_str().unwrap()]));
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.lines().filter(|l| l.starts_with("v ")).count() > 100);
    assert!(text.lines().any(|l| l.starts_with("f ")));
}

#[test]
fn target_noise_sets_the_beam_count_and_prune_zero_keeps_every_leaf() {
    let dir = scratch("end_to_end", "noise");
    let text =
        SMALL.replace("count = 400", "count = 100000\ntarget_noise = 0.4").replace("voxel_size = 1.0", "voxel_size = 1.0\nprune = 0.0");
    let scene = write(&dir, "noise.toml", text);
    let out = dir.join("out");
    let e = ok(&run(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]));
    assert!(e.contains("beams.target_noise = 0.4"), "{e}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("bake.json")).unwrap()).unwrap();
    let stats = &report["stats"];
    let n = &stats["noise"];
    // The count is the pilot's fitted law a / N + b / N^2 = target^2
    // (aurora::pilot), rounded up, and the bake used it; its a and b come
    // from the reported noise at m and m / 4 beams.
    let (m, noise_m) = (n["pilot_beams"].as_f64().unwrap(), n["pilot_noise"].as_f64().unwrap());
    let noise_q = n["quarter_noise"].as_f64().unwrap();
    let (a, b) = aurora::pipeline::bake::pilot::fit_law((m as usize / 4) as f64, noise_q, m, noise_m);
    assert_eq!((a, b), (n["law_a"].as_f64().unwrap(), n["law_b"].as_f64().unwrap()));
    let want = aurora::pipeline::bake::pilot::beams_for_law(a, b, 0.4).ceil() as u64;
    assert_eq!(n["beams"].as_u64().unwrap(), want, "{n}");
    assert_eq!(stats["beams"].as_u64().unwrap(), want);
    assert_eq!(n["capped"], false);
    assert!(stats["prune"].is_null(), "prune = 0 stores every leaf");
    // A target beyond beams.count: capped, with a warning naming both keys.
    assert!(want > 5, "{n}");
    let capped = write(&dir, "capped.toml", std::fs::read_to_string(&scene).unwrap().replace("count = 100000", "count = 5"));
    let e = ok(&run(&["bake", capped.to_str().unwrap(), "--out", dir.join("out2").to_str().unwrap(), "-q"]));
    assert!(e.contains("beams.target_noise = 0.4") && e.contains("capped at beams.count = 5"), "{e}");
}
