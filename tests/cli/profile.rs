//! `aurora profile`: the CSV it promises, atomically written, and bad input
//! refused with exit status 2 naming the key.

use crate::common::{aurora, ok, refused, scratch, write};
use std::path::PathBuf;

/// A fresh folder `name` holding `s.toml`: one curtain, 60 beams, and `extra`.
fn profile_scene(name: &str, extra: &str) -> (PathBuf, PathBuf) {
    let dir = scratch("profile", name);
    let text = format!(
        "seed = 4\n[[curtain]]\nlength = 20.0\nwidth = 8.0\nbend_km = 1.0\nchar_energy_kev = 5.0\n[footprint]\nresolution = [64, 24]\n[beams]\ncount = 60\n{extra}"
    );
    let scene = write(&dir, "s.toml", text);
    (dir, scene)
}

#[test]
fn profile_writes_the_promised_csv_and_matches_stdout() {
    let (dir, scene) = profile_scene("ok", "");
    let out = dir.join("p.csv");
    ok(&aurora(&["profile", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300"), "{header}");
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    // One curtain, 0.5 km bins with centres at .25 / .75, every value finite and >= 0.
    assert!(rows.iter().all(|r| r[0] == 0.0 && r.iter().all(|x| x.is_finite() && *x >= 0.0)));
    for w in rows.windows(2) {
        assert!((w[1][1] - w[0][1] - 0.5).abs() < 1e-9);
    }
    assert!(((rows[0][1] * 4.0).round() as i64) % 2 == 1, "bin centre {}", rows[0][1]);
    // Ionization = deposited keV/s / 0.035 keV per pair, bin by bin.
    let last = header.split(',').position(|c| c == "deposited_kev_s").unwrap();
    for r in &rows {
        assert!((r[2] * 0.035 - r[last]).abs() <= 1e-5 * r[last].abs() + 1e-300, "{r:?}");
    }
    assert!(rows.iter().map(|r| r[2]).sum::<f64>() > 0.0);
    // No temporary file left beside it; stdout mode prints the same bytes.
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 2, "{names:?}");
    let r = aurora(&["profile", scene.to_str().unwrap(), "--quiet", "--threads", "1"]);
    ok(&r);
    assert_eq!(String::from_utf8(r.stdout).unwrap(), text, "stdout and --out (and thread counts) differ");
}

#[test]
fn profile_refuses_a_bad_model_name_with_exit_2() {
    let (dir, scene) = profile_scene("bad", "deposition = \"average\"\n");
    let out = dir.join("p.csv");
    let err = refused(&aurora(&["profile", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]));
    assert!(err.contains("average") && err.contains("expected") && err.contains("csda"), "{err}");
    assert!(!out.exists());
}
