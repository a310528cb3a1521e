//! `aurora profile`: the CSV it promises, atomically written, and bad input
//! refused with exit status 2 naming the key.

mod common;

use std::process::Command;

fn aurora() -> Command {
    Command::new(common::AURORA_BIN)
}

fn small_scene(extra: &str) -> String {
    format!(
        "seed = 4\n[[curtain]]\nlength = 20.0\nwidth = 8.0\nbend_km = 1.0\nchar_energy_kev = 5.0\n[footprint]\nresolution = [64, 24]\n[beams]\ncount = 60\n{extra}"
    )
}

#[test]
fn profile_writes_the_promised_csv_and_matches_stdout() {
    let dir = tempfile_dir("profile-ok");
    let scene = dir.join("s.toml");
    std::fs::write(&scene, small_scene("")).unwrap();
    let out = dir.join("p.csv");
    let r = aurora().args(["profile", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
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
    let r = aurora().args(["profile", scene.to_str().unwrap(), "--quiet", "--threads", "1"]).output().unwrap();
    assert!(r.status.success());
    assert_eq!(String::from_utf8(r.stdout).unwrap(), text, "stdout and --out (and thread counts) differ");
}

#[test]
fn profile_refuses_a_bad_model_name_with_exit_2() {
    let dir = tempfile_dir("profile-bad");
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, small_scene("deposition = \"average\"\n")).unwrap();
    let out = dir.join("p.csv");
    let r = aurora().args(["profile", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("average") && err.contains("expected") && err.contains("csda"), "{err}");
    assert!(!out.exists());
}

fn tempfile_dir(tag: &str) -> std::path::PathBuf {
    common::scratch("test-profile", tag)
}
