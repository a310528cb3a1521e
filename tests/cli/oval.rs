//! `[oval]` and `magnetic_path` through the command line: the arcs placed
//! over the site (`aurora footprint` of `tromso_kp5` writes one footprint
//! per arc, `aurora scene` prints the keys as written, not the placed
//! paths); without a `[site]`, or out of range, they are refused naming
//! the key, exit 2, nothing written.

use crate::common::child::{aurora, ok, refused};
use crate::common::scratch;

#[test]
fn the_oval_places_arcs_over_the_site_and_bad_oval_keys_are_refused() {
    let d = scratch("oval", "keys");
    let fp = d.join("fp");
    ok(&aurora(&["footprint", "tromso_kp5", "--out", fp.to_str().unwrap(), "--set", "footprint.resolution=[64, 16]"]));
    for i in 0..3 {
        assert!(fp.join(format!("footprint-{i}.png")).is_file(), "footprint-{i}.png");
    }
    let printed = String::from_utf8(aurora(&["scene", "tromso_kp5"]).stdout).unwrap();
    assert!(printed.contains("[oval]\nkp = 5.0") && !printed.contains("path ="), "{printed}");

    let cases: [(&str, &[&str]); 4] = [
        ("[oval]\nkp = 5\n", &["oval", "[site]"]),
        ("[site]\nlatitude_deg = 69.65\nlongitude_deg = 18.96\nutc = \"2026-12-18T22:30:00Z\"\n[oval]\nkp = 12\n", &["oval.kp", "12", "[0, 9]"]),
        ("[[curtain]]\nmagnetic_path = [[66.0, 23.0], [66.0, 1.0]]\n", &["curtain[0].magnetic_path", "[site]"]),
        (
            "[site]\nlatitude_deg = 69.65\nlongitude_deg = 18.96\nutc = \"2026-12-18T22:30:00Z\"\n[[curtain]]\nmagnetic_path = [[66.0, 23.0], [95.0, 1.0]]\n",
            &["curtain[0].magnetic_path", "95"],
        ),
    ];
    for (text, names) in cases {
        let scene = d.join("bad.toml");
        std::fs::write(&scene, text).unwrap();
        let out = d.join("bad_fp");
        let e = refused(&aurora(&["footprint", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]));
        for n in names {
            assert!(e.contains(n), "{text}: {n} not in {e}");
        }
        assert!(!out.join("footprint-0.png").exists());
    }
}
