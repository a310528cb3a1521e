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
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
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
    assert_eq!(names.len(), 3, "{names:?}");
    assert!(dir.join("p.columns.csv").is_file(), "{names:?}");
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

/// Rows of a CSV without its `#` lines: the header's names and the numbers.
fn read_csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap().split(',').map(str::to_string).collect();
    (header, lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect())
}

fn col(header: &[String], name: &str) -> usize {
    header.iter().position(|c| c == name).unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// A uniform curtain of Maxwellian electrons of E0 = 1, 3 and 5 keV at 5 erg
/// cm^-2 s^-1 on the atmosphere the chemistry was checked on (NRLMSIS 2.1
/// and GLOW's ionosphere, docs/data.md): the columns file's brightness in
/// rayleigh is the integral of the profile's volume emission rates (to the
/// CSV's 7 digits, so 1 % holds with room), the energy flux is the scene's
/// (a uniform footprint has its peak flux everywhere), and 557.7 nm gives
/// 1.1-1.45 kR per erg cm^-2 s^-1, the published yield for E0 <= 5 keV
/// (Rees & Luckey 1974; GLOW: 1268 R at 3 keV). 2000 beams: the column's
/// sampling error is under 1 %.
#[test]
fn profile_columns_in_rayleigh_integrate_the_volume_emission_rates() {
    for e0 in [1.0, 3.0, 5.0] {
        let extra = "[atmosphere]\nmodel = \"nrlmsis21\"\nionosphere = \"glow\"\n";
        let dir = scratch("profile", &format!("columns_{e0}"));
        let text = format!(
            "seed = 4\n[[curtain]]\nlength = 40.0\nwidth = 16.0\nbend_km = 0.0\nenergy_flux = 5.0\nchar_energy_kev = {e0}\n\
soft_fraction = 0.0\n[footprint]\nresolution = [64, 24]\nuniform = true\n[beams]\ncount = 2000\n{extra}"
        );
        let scene = write(&dir, "s.toml", text);
        let out = dir.join("p.csv");
        ok(&aurora(&["profile", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]));
        let first = std::fs::read_to_string(&out).unwrap();
        assert!(first.starts_with("# footprint area per curtain, km^2: 6.400000e2 "), "{}", first.lines().next().unwrap());
        let (h, rows) = read_csv(&out);
        let (ch, crow) = read_csv(&dir.join("p.columns.csv"));
        assert_eq!(crow.len(), 1);
        let c = &crow[0];
        assert!((c[col(&ch, "footprint_area_km2")] - 640.0).abs() < 1e-6);
        assert!((c[col(&ch, "energy_flux_erg_cm2_s")] / 5.0 - 1.0).abs() < 1e-6, "{c:?}");
        for line in ["n2p_4278", "oi_5577", "oi_6300", "oi_6364", "n2_1p"] {
            let ver = col(&h, &format!("{line}_ver_cm3_s"));
            // photons cm^-3 s^-1 times 0.5 km = 5e4 cm, over 1e6 per rayleigh.
            let integral: f64 = rows.iter().map(|r| r[ver] * 5e4 / 1e6).sum();
            let column = c[col(&ch, &format!("{line}_r"))];
            assert!(column > 0.0 && (column / integral - 1.0).abs() < 0.01, "{line}: column {column} R, integral {integral} R");
            // The rate is the bin's photons over 640 km^2 times 0.5 km.
            let photons = col(&h, line);
            for r in &rows {
                assert!((r[ver] - r[photons] / (640.0 * 1e10 * 5e4)).abs() <= 1e-5 * r[ver] + 1e-300, "{line}: {r:?}");
            }
        }
        let green = c[col(&ch, "oi_5577_r_per_erg")];
        assert!((1100.0..=1450.0).contains(&green), "E0 = {e0} keV: 557.7 nm {green:.0} R per erg cm^-2 s^-1");
        assert!((green * 5.0 / c[col(&ch, "oi_5577_r")] - 1.0).abs() < 1e-5);
    }
}
