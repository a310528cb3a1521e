//! The scene's errors in plain words: types named as a scene's author
//! names them ("whole number", "number", "text", "list", "true or false"),
//! never Rust's; the nearest key, table or preset suggested; and the
//! messages that used to be garbled or bare: a curtain with both `path`
//! and `center`, `colour.lines` given line names, a camera looking
//! straight up with the default `up`. Each is refused with exit 2.

use crate::common::{refused, scratch, write, Aurora};

/// `aurora scene FILE` of `text`: refused, its stderr.
fn refusal(name: &str, text: &str) -> String {
    let d = scratch("messages", name);
    let f = write(&d, "s.toml", text);
    refused(&Aurora::new().arg("scene").arg(&f).output())
}

/// Every phrase of `want` is in `e`, and no Rust type name.
fn says(e: &str, want: &[&str]) {
    for w in want {
        assert!(e.contains(w), "no `{w}` in {e}");
    }
    for rust in ["usize", "f64", "u64", "a sequence", "a boolean", "wanted string or table", "invalid type", "unknown field"] {
        assert!(!e.contains(rust), "`{rust}` in {e}");
    }
}

#[test]
fn types_are_named_in_plain_words() {
    let cases: [(&str, &str, &[&str]); 6] = [
        ("width", "[render]\nwidth = 1.5\n", &["render.width: expected a whole number, found the number 1.5", "[1, 16384]"]),
        (
            "exposure",
            "[render]\nexposure = \"bright\"\n",
            &["render.exposure: expected a number of stops or \"auto\", found the text \"bright\"", "[-50, 50]"],
        ),
        ("shell", "[grid]\ncycles_shell = 1\n", &["grid.cycles_shell: expected true or false, found the whole number 1"]),
        ("lines", "[grid]\nlines = \"5577\"\n", &["grid.lines: expected a list, found the text \"5577\""]),
        ("view", "[render]\nview_transform = 3\n", &["render.view_transform: expected text, found 3", "\"standard\", \"agx\""]),
        ("flux", "[[curtain]]\nenergy_flux = [1]\n", &["curtain[0].energy_flux: expected a number, found a list"]),
    ];
    for (name, text, want) in cases {
        says(&refusal(name, text), want);
    }
}

#[test]
fn the_nearest_key_table_or_preset_is_suggested() {
    says(&refusal("key", "[[curtain]]\nenergy_flx = 3\n"), &["unknown key `energy_flx` in [[curtain]]; did you mean `energy_flux`?"]);
    says(&refusal("table", "[rendr]\nwidth = 64\n"), &["unknown table or key `rendr`; did you mean `render`?"]);
    let e = refused(&Aurora::new().args(["scene", "corona2"]).output());
    assert!(e.contains("corona2: no such file, and no preset of that name; did you mean `corona`?"), "{e}");
    // Nothing near: no guess, the known names listed.
    let e = refusal("far", "[render]\nzzzzzzzz = 1\n");
    assert!(!e.contains("did you mean") && e.contains("known: width, height, spp"), "{e}");
}

#[test]
fn a_curtain_with_path_and_center_is_told_it_takes_one() {
    let e = refusal("path", "[[curtain]]\ncenter = [0, 0]\npath = [[0, 0], [50, 10]]\n");
    says(&e, &["s.toml:3: curtain[0].path: a curtain takes either a `center` (with `length` and `rotation_deg`) or a `path`", "not both"]);
    assert!(!e.contains("out of range") && !e.contains("given"), "{e}");
}

#[test]
fn line_names_in_colour_lines_point_to_grid_lines() {
    let e = refusal("colour-lines", "[colour]\nlines = [\"5577\"]\n");
    says(
        &e,
        &[
            "colour.lines = [\"5577\"] is the line model",
            "\"chemistry\" (the default) or \"simple\"",
            "grid.lines, a list of line names (\"5577\", \"6300\", \"6364\", \"4278\", \"n2_1p\")",
        ],
    );
}

#[test]
fn a_camera_looking_straight_up_is_told_which_up_to_set() {
    let e = refusal("up", "[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 100]\n");
    says(&e, &["camera.up", "the camera looks straight up; set camera.up = [0, 1, 0]"]);
    // With that `up` the scene is good.
    let d = scratch("messages", "up-fixed");
    let f = write(&d, "s.toml", "[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 100]\nup = [0, 1, 0]\n");
    crate::common::ok(&Aurora::new().arg("scene").arg(&f).output());
    let e = refusal("along", "[camera]\nposition = [0, -100, 1]\nlook_at = [0, 0, 1]\nup = [0, 1, 0]\n");
    says(&e, &["set camera.up = [0, 0, 1]"]);
}

#[test]
fn a_folder_named_after_a_preset_does_not_hide_it() {
    // As after `aurora bake oval --out oval/`: `oval` is still the preset.
    let d = scratch("messages", "shadow");
    std::fs::create_dir_all(d.join("oval")).unwrap();
    let o = Aurora::new().args(["scene", "oval"]).current_dir(&d).output();
    let e = crate::common::ok(&o);
    assert!(e.contains("aurora: warning: oval: the preset `oval`") && e.contains("pass ./oval to mean the folder"), "{e}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("[[curtain]]"));
    let e = refused(&Aurora::new().args(["scene", "./oval"]).current_dir(&d).output());
    assert!(e.contains("./oval: cannot read"), "{e}");
}

#[test]
fn adaptive_sampling_below_its_least_spp_is_refused() {
    let d = scratch("messages", "adaptive");
    let out = d.join("a.png");
    let e = refused(&Aurora::new().args(["render", "--adaptive", "--spp", "4", "--png"]).arg(&out).output());
    says(&e, &["--adaptive with render.spp = 4", "at least 8 samples", "--spp 8"]);
    assert!(!out.exists());
}

#[test]
fn a_render_without_a_terminal_says_when_it_starts_and_how_long_it_has_left() {
    // stderr is a pipe here: indicatif draws nothing, the plain lines stand in.
    let d = scratch("messages", "log_lines");
    let png = d.join("r.png");
    let o = Aurora::new()
        .args(["render", "--set", "beams.count=300", "--set", "grid.voxel_size=2.0", "--size", "32x18", "--spp", "1", "--png"])
        .arg(&png)
        .output();
    let e = crate::common::ok(&o);
    assert!(e.contains("aurora: render: started, 18 steps (a line every 30 s with the time left)"), "{e}");
    assert!(png.is_file());
}
