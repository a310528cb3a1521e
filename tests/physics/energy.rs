//! The power balance in `bake.json`: for the default scene the
//! deposited power plus the backscatter Fang's parameterisation states
//! matches the electron power within 1 %, per curtain and in total, and
//! the grid holds the deposit above the beams' start (the soft spectrum's
//! share above `beams.top_km`, deposited along the field line above it).

use crate::common::small::coarse;
use crate::common::{aurora, ok, scratch, write};
use aurora::scene::Scene;

#[test]
fn default_scene_deposits_the_electron_power_less_backscatter_within_one_percent() {
    let dir = scratch("energy", "default");
    // The default scene; fewer beams and coarser voxels only to bake fast:
    // each beam's split of its power is a fixed function of its curtain's
    // spectrum and start altitude, whatever the count.
    let default = Scene::load("default").unwrap();
    let mut s = coarse(default.clone(), default.footprint.resolution, 600);
    s.beams.target_noise = 0.0;
    let top = s.beams.top_km + s.beams.top_noise_km;
    let scene = write(&dir, "scene.toml", s.to_toml());
    let out = dir.join("out");
    ok(&aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("bake.json")).unwrap()).unwrap();
    let st = &report["stats"]["beam_stats"];
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k} in {v}"));
    let mut rows: Vec<&serde_json::Value> = st["curtains"].as_array().unwrap().iter().collect();
    assert_eq!(rows.len(), s.curtains.len());
    rows.push(st);
    for c in rows {
        let e = f(c, "electron_power_w");
        let (dep, back, above, undep) =
            (f(c, "deposited_power_w"), f(c, "backscattered_power_w"), f(c, "above_top_power_w"), f(c, "undeposited_power_w"));
        eprintln!(
            "electron {e:.4e} W: deposited {:.2} %, backscattered {:.2} %, above the top {:.3} %, undeposited {:.3} %",
            100.0 * dep / e,
            100.0 * back / e,
            100.0 * above / e,
            100.0 * undep / e
        );
        assert!(e > 0.0);
        assert!(((dep + back + above + undep) / e - 1.0).abs() < 1e-9, "the four add up: {c}");
        assert!(((dep + back) / e - 1.0).abs() < 0.01, "deposited + backscattered within 1 % of the electron power: {c}");
        // The rest above the deposit's top is at most ABOVE_START_TOL of
        // the spectrum's deposition, or what lies above the atmosphere
        // table's 700 km top (the soft part's tail; measured 3.6e-5 of the
        // electron power): under 1e-4.
        assert!(above <= aurora::pipeline::beams::walk::ABOVE_START_TOL * e || above <= 1e-4 * e, "{c}");
    }
    // The grid reaches above the beams' start: the above-start deposit is in it.
    let z_max = report["stats"]["world_bbox"][1][2].as_f64().unwrap();
    assert!(z_max > top + 50.0, "grid top {z_max} km, beams start at most at {top} km");
}
