//! Scene overrides on the command line: `--set KEY=VALUE` (and render's
//! `--seed`, `--spp`, `--size`, `--exposure`) applied in command-line
//! order to the scene's TOML before validation, recorded in bake.json, the
//! bake's identity following the effective scene; bad values refused with
//! exit 2 naming the override, the key, the value and the range, nothing
//! written. Also what `aurora render` writes with `--png` alone, and its
//! refusal of a sequence folder without `--frame`.

use crate::common::{file_names, ok, refused, scratch, write, Aurora};
use crate::small_bake_toml;
use std::path::Path;

/// The small scene file with a 32 x 18 picture at 2 spp.
fn small_scene(d: &Path) -> std::path::PathBuf {
    let text = concat!(
        small_bake_toml!(),
        "[render]\nwidth = 32\nheight = 18\nspp = 2\n[camera]\nposition = [0, -120, 1]\nlook_at = [0, 0, 100]\n"
    );
    write(d, "s.toml", text)
}

/// `aurora scene FILE ARGS...`: the effective scene as TOML.
fn effective(scene: &Path, args: &[&str]) -> aurora::scene::Scene {
    let o = Aurora::new().arg("scene").arg(scene).args(args).output();
    ok(&o);
    let text = String::from_utf8(o.stdout).unwrap();
    aurora::scene::Scene::from_toml_str(&text, "stdout").unwrap()
}

fn bake_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("bake.json")).unwrap()).unwrap()
}

#[test]
fn set_applies_toml_values_in_command_line_order() {
    let d = scratch("overrides", "order");
    let scene = small_scene(&d);
    let s = effective(
        &scene,
        &["--set", "render.width=64", "--set", "camera.up=[0, 1, 0]", "--set", "colour.mode=colormap", "--set", "curtain[0].energy_flux=3"],
    );
    assert_eq!((s.render.width, s.render.height), (64, 18));
    assert_eq!(s.camera.up, [0.0, 1.0, 0.0]);
    assert_eq!(s.colour.mode, aurora::scene::ColourMode::Colormap);
    assert_eq!(s.curtains[0].energy_flux, 3.0);
    // The later wins; a preset takes overrides too, its curtains by index.
    assert_eq!(effective(&scene, &["--set", "render.width=64", "--set", "render.width=16"]).render.width, 16);
    let corona = effective(Path::new("corona"), &["--set", "curtain[1].energy_flux=7", "--set", "render.spp=3"]);
    assert_eq!((corona.curtains[1].energy_flux, corona.render.spp), (7.0, 3));
    assert_eq!(corona.curtains[0], aurora::scene::presets::by_name("corona").unwrap().curtains[0]);
}

#[test]
fn bake_records_the_overrides_and_its_identity_follows_the_effective_scene() {
    let d = scratch("overrides", "bake");
    let scene = small_scene(&d);
    let out = d.join("set");
    // --seed then --set seed: the later wins.
    ok(&Aurora::new()
        .args(["bake", scene.to_str().unwrap(), "-q", "--seed", "3", "--set", "seed=9", "--set", "curtain[0].energy_flux=3", "--out"])
        .arg(&out)
        .output());
    let j = bake_json(&out);
    assert_eq!(j["overrides"], serde_json::json!(["seed=3", "seed=9", "curtain[0].energy_flux=3"]));
    assert_eq!(j["seed"], 9);
    // The same values written into the file: the same scene, hash and identity.
    let text =
        std::fs::read_to_string(&scene).unwrap().replace("seed = 7", "seed = 9").replace("bend_km = 3.0", "bend_km = 3.0\nenergy_flux = 3");
    let edited = write(&d, "edited.toml", text);
    let plain = d.join("edited");
    ok(&Aurora::new().args(["bake", edited.to_str().unwrap(), "-q", "--out"]).arg(&plain).output());
    let k = bake_json(&plain);
    assert_eq!(k["overrides"], serde_json::json!([]));
    assert_eq!((&j["scene_hash"], &j["bake_identity"]), (&k["scene_hash"], &k["bake_identity"]));
    assert_eq!(std::fs::read(out.join("aurora.vdb")).unwrap().len(), std::fs::read(plain.join("aurora.vdb")).unwrap().len());
    // --seed after --set seed wins.
    let last = d.join("last");
    ok(&Aurora::new().args(["bake", scene.to_str().unwrap(), "-q", "--set", "seed=9", "--seed", "3", "--out"]).arg(&last).output());
    assert_eq!(bake_json(&last)["seed"], 3);
}

#[test]
fn bad_overrides_are_refused_naming_the_key_the_value_and_the_range() {
    let d = scratch("overrides", "bad");
    let scene = small_scene(&d);
    let out = d.join("out");
    let cases: [(&[&str], &[&str]); 6] = [
        (&["--set", "render.width=0"], &["--set render.width=0: render.width = 0 is out of range: must be in [1, 16384]"]),
        (&["--set", "render.width=abc"], &["--set render.width=abc", "expected a whole number, found the text \"abc\"", "[1, 16384]"]),
        (&["--set", "render.widht=64"], &["--set render.widht=64", "unknown key `widht` in [render]; did you mean `width`?"]),
        (&["--set", "rendr.width=64"], &["--set rendr.width=64", "did you mean `render`?"]),
        (&["--set", "curtain[3].energy_flux=1"], &["curtain[3]", "curtain has 1 entry, curtain[0]"]),
        (&["--set", "beams.count"], &["--set beams.count", "expected KEY=VALUE"]),
    ];
    for (args, want) in cases {
        let e = refused(&Aurora::new().args(["bake", scene.to_str().unwrap(), "--out"]).arg(&out).args(args).output());
        for w in want {
            assert!(e.contains(w), "{args:?}: no `{w}` in {e}");
        }
        assert!(!out.exists(), "{args:?}: a refused bake wrote {}", out.display());
    }
    // render's own flags are overrides too, checked by the same rules.
    let png = d.join("r.png");
    let e = refused(&Aurora::new().args(["render", scene.to_str().unwrap(), "--exposure", "99", "--png"]).arg(&png).output());
    assert!(e.contains("--exposure 99: render.exposure = 99 is out of range: must be in [-50, 50]"), "{e}");
    assert!(!png.exists());
}

/// A PNG's width and height, from its header.
fn png_size(p: &Path) -> (u32, u32) {
    let b = std::fs::read(p).unwrap();
    (u32::from_be_bytes(b[16..20].try_into().unwrap()), u32::from_be_bytes(b[20..24].try_into().unwrap()))
}

#[test]
fn render_size_exposure_and_spp_are_overrides_and_png_alone_writes_only_the_png() {
    let d = scratch("overrides", "render");
    small_scene(&d);
    let render = |args: &[&str]| ok(&Aurora::new().current_dir(&d).args(["render", "s.toml", "--threads", "2"]).args(args).output());
    // --png alone: the one image written.
    let e = render(&["--size", "20x10", "--spp", "1", "--set", "render.spp=3", "--exposure", "-1", "--png", "a.png"]);
    assert_eq!(file_names(&d), ["a.png", "s.toml"], "{e}");
    assert_eq!(png_size(&d.join("a.png")), (20, 10));
    // The later of --spp and --set render.spp wins: 20 x 10 x 3 rays.
    assert!(e.contains("600 primary rays"), "{e}");
    // --exposure is render.exposure, --size is render.width and height.
    render(&[
        "--set",
        "render.width=20",
        "--set",
        "render.height=10",
        "--set",
        "render.spp=3",
        "--set",
        "render.exposure=-1",
        "--png",
        "b.png",
    ]);
    assert_eq!(std::fs::read(d.join("a.png")).unwrap(), std::fs::read(d.join("b.png")).unwrap());
    // With --out too, both.
    render(&["--spp", "1", "--out", "c.exr", "--png", "c.png"]);
    assert_eq!(file_names(&d), ["a.png", "b.png", "c.exr", "c.png", "s.toml"]);
}

/// The shadow rays a render reports ("N shadow samples").
fn shadow_samples(summary: &str) -> u64 {
    let line = summary.lines().find(|l| l.contains("shadow samples")).unwrap_or_else(|| panic!("no shadow samples in {summary}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "shadow").unwrap();
    words[at - 1].trim_start_matches(',').parse().unwrap_or_else(|_| panic!("{line}"))
}

#[test]
fn shadow_samples_is_a_render_key_and_the_flag_overrides_it() {
    let d = scratch("overrides", "shadow");
    small_scene(&d);
    // Looking at the horizon: the lower half of the picture is the lit ground.
    let render = |args: &[&str]| {
        ok(&Aurora::new()
            .current_dir(&d)
            .args(["render", "s.toml", "--threads", "2", "--set", "camera.look_at=[0, 0, 1]", "--set", "terrain.kind=\"plane\""])
            .args(args)
            .output())
    };
    let by_key = shadow_samples(&render(&["--shadow-samples", "2", "--set", "render.shadow_samples=5", "--png", "a.png"]));
    let by_flag = shadow_samples(&render(&["--set", "render.shadow_samples=5", "--shadow-samples", "2", "--png", "b.png"]));
    let one = shadow_samples(&render(&["--png", "c.png"]));
    // Every terrain hit draws the key's count per sample: the same hits, 5, 2 and 1 rays each.
    assert!(one > 0, "the ground is in the picture");
    assert_eq!((by_key, by_flag), (5 * one, 2 * one));
    let s = effective(&d.join("s.toml"), &["--set", "render.shadow_samples=7"]);
    assert_eq!(s.render.shadow_samples, 7);
    assert_eq!(aurora::scene::presets::by_name("default").unwrap().render.shadow_samples, 8);
    let e =
        refused(&Aurora::new().current_dir(&d).args(["render", "s.toml", "--set", "render.shadow_samples=0", "--png", "z.png"]).output());
    assert!(e.contains("render.shadow_samples") && e.contains('0') && e.contains("4096"), "{e}");
}

#[test]
fn a_sequence_folder_without_frame_is_refused_naming_its_frames() {
    let d = scratch("overrides", "sequence");
    let scene = small_scene(&d);
    let seq = d.join("seq");
    ok(&Aurora::new().args(["bake", scene.to_str().unwrap(), "-q", "--frames", "2-4", "--out"]).arg(&seq).output());
    let png = d.join("x.png");
    let e = refused(&Aurora::new().args(["render", scene.to_str().unwrap(), "--vdb"]).arg(&seq).arg("--png").arg(&png).output());
    let s = seq.display();
    assert!(e.contains(&format!("--vdb {s}: is a sequence folder (3 frames, 2-4); pass --frame N")) && e.contains("--frame 2-4"), "{e}");
    let empty = d.join("empty");
    std::fs::create_dir(&empty).unwrap();
    let e = refused(&Aurora::new().args(["render", scene.to_str().unwrap(), "--vdb"]).arg(&empty).arg("--png").arg(&png).output());
    assert!(e.contains("is a directory, not a regular file, and holds no frames (aurora.NNNN.vdb)"), "{e}");
    assert!(!png.exists());
}
