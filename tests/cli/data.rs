//! The tables that are not compiled in (docs/data.md): NRLMSIS 2.1 and
//! GLOW's ionosphere are read from the data folder a scene names
//! (`[atmosphere] data`, relative to the scene file, then `AURORA_DATA`,
//! then the source tree's `data/`); the default reads no file, and the
//! binary holds neither table.

use crate::common::child::AURORA_BIN;
use crate::common::small::bake_command;
use crate::common::{file_names, ok, refused, repo_root, scratch, write, Aurora};
use crate::small_bake_toml;
use std::path::PathBuf;

/// A row of each restrictive table, as it stands in the file (NRLMSIS 2.1
/// at 50.5 km, GLOW's ionosphere at its second altitude).
const NRLMSIS_ROW: &str = "50.5,6.22167e-07,1.01069e+16,2.71023e+15,5.13424e+07";
const GLOW_ROW: &str = "74.784,225.812,225.812,1661.96,2.23783e+08";

/// The small scene with `atmosphere`'s lines as its [atmosphere] table.
fn scene_text(atmosphere: &str) -> String {
    format!("{}\n[atmosphere]\n{atmosphere}", small_bake_toml!())
}

/// In a fresh folder `name`: an empty data folder `empty`, and the bake of
/// the small scene with `atmosphere` as its [atmosphere] table into `out`
/// with `AURORA_DATA` naming the empty folder (the caller runs it); returns
/// (folder, empty data folder, output, bake).
fn bake_with_empty_data(name: &str, atmosphere: &str) -> (PathBuf, PathBuf, PathBuf, Aurora) {
    let d = scratch("data", name);
    let empty = d.join("empty");
    std::fs::create_dir(&empty).unwrap();
    let scene = write(&d, "s.toml", scene_text(atmosphere));
    let out = d.join("out");
    let bake = bake_command(&scene, &out).env("AURORA_DATA", &empty);
    (d, empty, out, bake)
}

fn holds(haystack: &[u8], needle: &str) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle.as_bytes())
}

#[test]
fn the_binary_holds_no_restrictive_table_and_holds_the_standard_atmosphere() {
    let nrlmsis = std::fs::read_to_string(repo_root().join("data/nrlmsis21.csv")).unwrap();
    let glow = std::fs::read_to_string(repo_root().join("data/ionosphere.csv")).unwrap();
    assert!(nrlmsis.contains(NRLMSIS_ROW) && glow.contains(GLOW_ROW), "the rows searched for are the files' own");
    let bin = std::fs::read(AURORA_BIN).unwrap();
    assert!(!holds(&bin, NRLMSIS_ROW), "the binary holds NRLMSIS 2.1's table");
    assert!(!holds(&bin, GLOW_ROW), "the binary holds GLOW's ionosphere");
    let us1976 = std::fs::read_to_string(repo_root().join("data/us1976.csv")).unwrap();
    let row = us1976.lines().find(|l| l.starts_with("100.0,")).unwrap();
    assert!(holds(&bin, row), "the binary holds the U.S. Standard Atmosphere");
}

#[test]
fn the_default_bakes_with_an_empty_data_folder() {
    let (_, _, out, bake) = bake_with_empty_data("default_empty", "");
    ok(&bake.arg("--quiet").output());
    assert!(file_names(&out).contains(&"aurora.vdb".to_string()), "{:?}", file_names(&out));
}

#[test]
fn a_missing_table_is_refused_naming_the_file_its_terms_and_where_to_put_it() {
    // Through AURORA_DATA: the folder it names.
    let (d, empty, out, bake) = bake_with_empty_data("missing", "model = \"nrlmsis21\"\n");
    let e = refused(&bake.output());
    for want in
        ["nrlmsis21.csv", "model = \"nrlmsis21\"", "non-profit", "AURORA_DATA", "[atmosphere] data", "us1976", &empty.display().to_string()]
    {
        assert!(e.contains(want), "{want}: {e}");
    }
    assert!(!out.exists(), "nothing is written");
    // Through [atmosphere] data, relative to the scene file; GLOW's table too.
    let scene = write(&d, "g.toml", scene_text("ionosphere = \"glow\"\ndata = \"tables\"\n"));
    let e = refused(&Aurora::new().arg("scene").arg(&scene).current_dir(repo_root()).output());
    assert!(e.contains("ionosphere.csv") && e.contains("no sale") && e.contains("closed-form"), "{e}");
    assert!(e.contains(&d.join("tables").display().to_string()), "{e}");
}

#[test]
fn the_data_key_finds_the_tables_beside_the_scene_and_they_change_the_bake() {
    let d = scratch("data", "found");
    let tables = d.join("tables");
    std::fs::create_dir(&tables).unwrap();
    for f in ["nrlmsis21.csv", "ionosphere.csv"] {
        std::fs::copy(repo_root().join("data").join(f), tables.join(f)).unwrap();
    }
    let scene = write(&d, "s.toml", scene_text("model = \"nrlmsis21\"\nionosphere = \"glow\"\ndata = \"tables\"\n"));
    // Found from another working folder, with AURORA_DATA pointing elsewhere.
    let empty = d.join("empty");
    std::fs::create_dir(&empty).unwrap();
    let bake = |scene: &std::path::Path, out: &str| {
        ok(&bake_command(scene, &d.join(out)).env("AURORA_DATA", &empty).current_dir(&empty).arg("--quiet").output());
        std::fs::read(d.join(out).join("aurora.vdb")).unwrap()
    };
    let validated = bake(&scene, "validated");
    let default = bake(&write(&d, "default.toml", scene_text("")), "default");
    assert_ne!(validated, default, "the tables are read and used");
    // A damaged table is refused naming its line.
    std::fs::write(tables.join("ionosphere.csv"), "altitude_km,te_k,ti_k,ne_cm3,no_cm3\n80,200,200,1000,1e8\n90,x,200,1000,1e8\n").unwrap();
    let e = refused(&bake_command(&scene, &d.join("damaged")).env("AURORA_DATA", &empty).output());
    assert!(e.contains("ionosphere.csv:3:") && e.contains("'x' is not a number"), "{e}");
}
