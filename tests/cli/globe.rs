//! A scene anywhere on the globe: placed by its dipole pole
//! (`earth.magnetic_pole`), its electrons go down the field line in either
//! hemisphere; where the field lies within the beams' deflection cone of
//! the horizontal (the dipole's equator) or the beams would leave their
//! footprint with most of their power, the bake is refused before anything
//! is written; a loss above 5 % is warned about and reported.

use crate::common::child::{ok, refused};
use crate::common::small::bake_command;
use crate::common::{file_names, scratch, write};
use crate::small_bake_toml;
use serde_json::Value;
use std::path::Path;
use std::time::Duration;

/// The small scene with its dipole pole `north_km` north of the origin.
/// The small scene with a dipole pole `north_km` north, and the 2014
/// walk's deflection (alpha_D 5 degrees, delta 3): the cone a field must dip
/// out of, and the walk that carries beams off a shallow field's footprint.
fn scene_with_pole(north_km: f64) -> String {
    let walk = small_bake_toml!().replace("[beams]\n", "[beams]\nalpha_d_deg = 5.0\ndelta_alpha_deg = 3.0\n");
    assert!(walk.contains("alpha_d_deg = 5.0"));
    format!("{walk}[earth]\nmagnetic_pole = [0.0, {north_km}]\n")
}

/// Address-space cap for a bake that must be refused before it allocates:
/// 4 GiB, under which the unbounded bake of a horizontal field aborted.
const CAP_KIB: u64 = 4 << 20;

/// The message of the bake of `scene` into `out` under [`CAP_KIB`], which
/// must be refused with nothing written (not even the lock).
fn refused_writing_nothing(scene: &Path, out: &Path) -> String {
    let o = bake_command(scene, out).capped(CAP_KIB).spawn().wait_within(Duration::from_secs(300));
    let e = refused(&o);
    let left = if out.exists() { file_names(out) } else { Vec::new() };
    assert!(left.is_empty(), "{}: nothing may be written, found {left:?}", scene.display());
    e
}

#[test]
fn a_field_at_the_dipole_equator_is_refused_and_nothing_is_written() {
    // A quarter of the globe from the pole (pi R / 2 = 10007.5 km) the
    // field is horizontal: refused with exit 2 naming the curtain, its dip
    // and the limit, and the output folder holds nothing, not even the
    // lock. A few km nearer, the dip (3.6 degrees at 9800 km) is still
    // within the 5-degree deflection cone: refused the same way.
    let d = scratch("globe", "equator");
    for (name, north) in [("equator", 10007.5), ("near", 9800.0)] {
        let scene = write(&d, &format!("{name}.toml"), scene_with_pole(north));
        let out = d.join(format!("out-{name}"));
        let e = refused_writing_nothing(&scene, &out);
        assert!(e.contains("curtain[0]") && e.contains("dips only") && e.contains("beams.alpha_d_deg = 5"), "{e}");
        assert!(e.contains("earth.magnetic_pole"), "{e}");
    }
}

#[test]
fn beams_that_would_leave_their_footprint_are_refused_by_the_pilot() {
    // 9700 km from the pole the field dips 5.4 degrees, just outside the
    // cone: the beams creep sideways and most leave the footprint's box
    // (the pilot deposited 26 % when measured): refused naming the pilot's
    // fraction, the dip and the limit.
    let d = scratch("globe", "pilot");
    let scene = write(&d, "shallow.toml", scene_with_pole(9700.0));
    let e = refused_writing_nothing(&scene, &d.join("out"));
    assert!(e.contains("curtain[0]: a pilot of 256") && e.contains("under the 50 %") && e.contains("dips 5."), "{e}");
}

#[test]
fn a_loss_above_five_percent_is_warned_and_reported_in_bake_json() {
    // 9400 km from the pole (dip 10.9 degrees) about 13 % of the beams
    // leave the footprint's box sideways with their power (8 % of it when
    // measured): baked, with a warning naming the curtain and the share
    // deposited, which bake.json reports for the bake and the curtain;
    // bake.json's other fields stay.
    let d = scratch("globe", "loss");
    let scene = write(&d, "loss.toml", scene_with_pole(9400.0));
    let out = d.join("out");
    let e = ok(&bake_command(&scene, &out).arg("--quiet").output());
    assert!(e.contains("aurora: warning: curtain[0]: its beams deposited"), "{e}");
    let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("bake.json")).unwrap()).unwrap();
    let st = &json["stats"]["beam_stats"];
    let f = st["deposited_fraction"].as_f64().expect("beam_stats.deposited_fraction");
    assert!(f > 0.5 && f < 0.95, "{f}");
    assert_eq!(st["curtains"][0]["deposited_fraction"].as_f64(), Some(f));
    assert_eq!(json["stats"]["deposited_fraction"].as_f64(), Some(f));
    // The fraction is the deposit over the power entering the atmosphere
    // (nothing pulses here: electron power less backscatter).
    let c = &st["curtains"][0];
    let entering = c["electron_power_w"].as_f64().unwrap() - c["backscattered_power_w"].as_f64().unwrap();
    assert!((c["deposited_power_w"].as_f64().unwrap() / entering - f).abs() < 1e-9, "{c}");
    assert!(e.contains(&format!("{:.1} %", 100.0 * f)), "the warning names the fraction: {e}");
    for key in ["electron_power_w", "deposited_power_w", "undeposited_power_w", "photons", "warnings"] {
        assert!(json["stats"].get(key).is_some() || st.get(key).is_some(), "{key} kept");
    }
    // The pole 3000 km away: everything deposited, no warning.
    let scene = write(&d, "steep.toml", scene_with_pole(3000.0));
    let e = ok(&bake_command(&scene, &d.join("steep")).arg("--quiet").output());
    assert!(!e.contains("warning"), "{e}");
}
