//! The air between the aurora and the eye (`aurora::physics::air_extinction`, `[sky]`):
//! Rayleigh's optical depth against its derivation, the standard
//! atmosphere's pressures, Kasten & Young's air mass, the ozone table, the
//! exact slant path, and the renderer's brightness ratios against
//! `exp(-tau_c X)`.

// Channel loops index several arrays at once.
#![allow(clippy::needless_range_loop)]

use crate::common::oracle::{persp, settings};
use crate::common::update_or_check_committed;
use aurora::grid::{Grid, Transform};
use aurora::physics::air_extinction::{
    air_mass, ozone_cross_section_cm2, pressure_ratio, rayleigh_tau_sea_level, Air, Extinction, DOBSON_CM2, O3_SIGMA_CM2,
    O3_SIGMA_FIRST_NM, REFERENCE_MIX,
};
use aurora::render::{render, Volume};
use aurora::scene::{Scene, SkyParams};
use aurora::util::fmath;
use aurora::util::observer::Observer;
use aurora::util::progress::NoProgress;
use glam::{DVec3, IVec3};
use std::f64::consts::PI;

fn default_air() -> Air {
    Air::from_sky(&SkyParams::default()).expect("extinction is on by default")
}

/// Bodhaine et al. (1999) eq. (30) is their fit to the Rayleigh optical
/// depth they derive, `sigma(lambda) N`: the cross-section of their eq. (29)
/// from the refractive index of Peck & Reeves (1972, their eq. 18, scaled
/// for 360 ppm CO2 by eq. 19) and the King factor of Bates (1984) for N2,
/// O2, Ar and CO2 (eqs. 5, 6, 23), at N_s = 2.546899e19 cm^-3, times the
/// column `N = P A / (m_a g)` (eq. 3) with P = 1013.25 hPa, m_a = 28.9595 +
/// 15.0556 C_CO2 g/mol and g at 45 deg at the column's mass-weighted height
/// (5517.56 m, eqs. 10-11). Recomputed here from those equations, the fit
/// is within 1e-4 of it over 400-700 nm (measured: 9.4e-5 at 700 nm, the
/// fit's stated accuracy being of that order), and at the lines gives the
/// note's 0.27, 0.092 and 0.056.
#[test]
fn rayleigh_fit_matches_the_cross_section_times_the_column() {
    let sigma_cm2 = |lambda_nm: f64| {
        let l = lambda_nm * 1e-3;
        let il2 = fmath::powi(l, -2);
        let n300 = 1.0 + 1e-8 * (8060.51 + 2_480_990.0 / (132.274 - il2) + 17455.7 / (39.32957 - il2));
        let n = 1.0 + (n300 - 1.0) * (1.0 + 0.54 * (0.00036 - 0.0003));
        let f_n2 = 1.034 + 3.17e-4 * il2;
        let f_o2 = 1.096 + 1.385e-3 * il2 + 1.448e-4 * il2 * il2;
        let f_air = (78.084 * f_n2 + 20.946 * f_o2 + 0.934 * 1.0 + 0.036 * 1.15) / (78.084 + 20.946 + 0.934 + 0.036);
        let ns = 2.546899e19;
        let lc = l * 1e-4;
        let n2 = n * n;
        24.0 * fmath::powi(PI, 3) * fmath::powi(n2 - 1.0, 2) / (fmath::powi(lc, 4) * ns * ns * fmath::powi(n2 + 2.0, 2)) * f_air
    };
    let zc: f64 = 5517.56;
    let g = 980.6160 - 3.085462e-4 * zc + 7.254e-11 * zc * zc - 1.517e-17 * fmath::powi(zc, 3);
    let m_a = 15.0556 * 0.00036 + 28.9595;
    let column = 1.01325e6 * 6.022_136_7e23 / (m_a * g);
    for lambda in [400.0, 427.8, 500.0, 557.7, 630.0, 666.8, 700.0] {
        let want = sigma_cm2(lambda) * column;
        let got = rayleigh_tau_sea_level(lambda);
        assert!((got / want - 1.0).abs() < 1e-4, "{lambda} nm: {got} vs {want}");
    }
    for (lambda, note) in [(427.8, 0.27), (557.7, 0.092), (630.0, 0.056)] {
        assert!((rayleigh_tau_sea_level(lambda) - note).abs() < 0.005, "{lambda}");
    }
}

/// The U.S. Standard Atmosphere 1976 pressures at its layer bases (the
/// standard's table: 22632.06, 5474.889, 868.0187, 110.9063, 66.93887,
/// 3.956420 Pa at geopotential 11, 20, 32, 47, 51, 71 km), to the table's
/// five to seven digits, at the geometric altitudes of those geopotential
/// heights, `z = r0 H / (r0 - H)`.
#[test]
fn standard_atmosphere_pressures() {
    let r0 = 6356.766;
    for (h, p) in [(11.0, 22632.06), (20.0, 5474.889), (32.0, 868.0187), (47.0, 110.9063), (51.0, 66.93887), (71.0, 3.956420)] {
        let z = r0 * h / (r0 - h);
        let got = pressure_ratio(z) * 101_325.0;
        assert!((got / p - 1.0).abs() < 2e-5, "H {h} km: {got} Pa vs {p}");
    }
    assert_eq!(pressure_ratio(0.0), 1.0);
    assert!(pressure_ratio(150.0) < 1e-6);
}

/// Kasten & Young (1989): their formula against its defining values: 1 at
/// the zenith (0.9997: the fit's), the horizon's ray-traced 38.0868 of the
/// ISO atmosphere within the fit's own 0.5 %, 5.6 at 10 degrees, and the
/// plane-parallel `1 / sin e` at high elevations within the curvature
/// term `(H / R) cot^2 e` (H / R = 8.4 / 6371) plus 1e-3.
#[test]
fn kasten_young_air_mass() {
    assert!((air_mass(90.0) - 1.0).abs() < 5e-4);
    assert!((air_mass(0.0) / 38.0868 - 1.0).abs() < 5e-3, "{}", air_mass(0.0));
    assert!((air_mass(10.0) - 5.6).abs() < 0.05, "{}", air_mass(10.0));
    for e in [20.0f64, 30.0, 45.0, 60.0, 80.0] {
        let plane = 1.0 / fmath::sin(e.to_radians());
        let bound = 8.4 / 6371.0 / fmath::powi(fmath::tan(e.to_radians()), 2) + 1e-3;
        assert!((air_mass(e) / plane - 1.0).abs() < bound, "{e}: {} vs {plane}", air_mass(e));
    }
    // Below the horizon: the horizon's.
    assert_eq!(air_mass(-3.0), air_mass(0.0));
}

/// The ozone table read at its bin centres, linear between them, and the
/// Chappuis band's optical depths for 300 DU: 0.030 at 557.7 nm and 0.028
/// at 630.0 nm (the module doc's), peaking near 600 nm at 0.040.
#[test]
fn ozone_chappuis_band() {
    for (i, s) in O3_SIGMA_CM2.iter().enumerate() {
        assert_eq!(ozone_cross_section_cm2(O3_SIGMA_FIRST_NM + 10.0 * i as f64), *s);
    }
    let mid = ozone_cross_section_cm2(O3_SIGMA_FIRST_NM + 5.0);
    assert!((mid - 0.5 * (O3_SIGMA_CM2[0] + O3_SIGMA_CM2[1])).abs() < 1e-30);
    let air = default_air();
    let tau = |l: f64| air.depths(l).ozone;
    assert!((tau(557.7) - 0.030).abs() < 0.001, "{}", tau(557.7));
    assert!((tau(630.0) - 0.028).abs() < 0.001, "{}", tau(630.0));
    assert!((tau(605.0) - 300.0 * DOBSON_CM2 * 5.019e-21).abs() < 1e-12);
    assert!(tau(427.8) < 1e-3 && tau(350.0) == 0.0);
}

/// The slant path's optical depth (`Air::tau_path`, plane-parallel exact)
/// against Simpson's rule on the extinction coefficient along the straight
/// path (2000 intervals: the fourth-order error is far below 1e-6
/// relative on these smooth profiles), rising, falling and level.
#[test]
fn slant_path_depth_is_the_integral_along_the_path() {
    let air = default_air();
    let d = air.channel_depths(Observer::default())[2];
    for (z0, z1, len) in [(0.0, 3.0, 40.0), (1.0, 0.0, 25.0), (0.3, 0.3, 60.0), (2.0, 15.0, 30.0), (0.0, 30.0, 80.0)] {
        let n = 2000;
        let f = |s: f64| air.coefficient(&d, z0 + (z1 - z0) * s / len);
        let h = len / n as f64;
        let mut sum = f(0.0) + f(len);
        for k in 1..n {
            sum += if k % 2 == 1 { 4.0 } else { 2.0 } * f(k as f64 * h);
        }
        let want = sum * h / 3.0;
        let got = air.tau_path(&d, z0, z1, len);
        assert!((got / want - 1.0).abs() < 1e-5, "{z0} -> {z1} over {len}: {got} vs {want}");
    }
}

/// The spectral transmittance of channel `c` at air mass `x` for an
/// observer at sea level, assembled here from the lines' colours, the
/// reference mix and each line's depths: `sum_i w_ic exp(-tau_i X)`.
fn channel_t(c: usize, x: f64, observer: Observer) -> f64 {
    let air = default_air();
    let colours = aurora::physics::emission::line_table::line_colours(observer);
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..aurora::physics::emission::line_table::N_LINES {
        let w = REFERENCE_MIX[i] * colours[i][c];
        let d = air.line_depths(i);
        num += w * fmath::exp(-(d.rayleigh + d.ozone + d.aerosol) * x);
        den += w;
    }
    num / den
}

/// The documented per-channel depths (docs/physics.md): first order
/// (`x -> 0`) 0.158 / 0.171 / 0.272 for the eye, 0.124 / 0.171 / 0.338
/// for the camera (its 557.7 nm has no red or blue, so red is the red
/// lines' and blue 427.8 nm's), and the eye's effective depths
/// `-ln T_c / X` at 30 and 10 degrees; a line's own depth for its grid;
/// an observer 1 km up.
#[test]
fn channel_and_line_depths() {
    let air = default_air();
    for (o, want) in [(Observer::Eye, [0.1580, 0.1707, 0.2716]), (Observer::Camera, [0.1242, 0.1707, 0.3385])] {
        let first = air.channel_depths(o).map(|d| d.rayleigh + d.ozone + d.aerosol);
        for c in 0..3 {
            assert!((first[c] - want[c]).abs() < 5e-4, "{o:?} channel {c}: {first:?}");
        }
        let ext = Extinction::for_observer_at(air, DVec3::ZERO, 0.0, DVec3::Z, None, o);
        for c in 0..3 {
            assert!((ext.effective_tau(c, 1e-9) - first[c]).abs() < 1e-6);
            for x in [1.0, 2.0, 5.6] {
                assert!((ext.effective_tau(c, x) - (-fmath::ln(channel_t(c, x, o)) / x)).abs() < 1e-12);
            }
        }
    }
    let ext = Extinction::for_observer_at(air, DVec3::ZERO, 0.0, DVec3::Z, None, Observer::Eye);
    for (e, want) in [(30.0, [0.1571, 0.1707, 0.2600]), (10.0, [0.1555, 0.1707, 0.2375])] {
        let x = air_mass(e);
        for c in 0..3 {
            let t = ext.effective_tau(c, x);
            assert!((t - want[c]).abs() < 5e-4, "{e} deg channel {c}: {t}");
            assert!((t - (-fmath::ln(channel_t(c, x, Observer::Eye)) / x)).abs() < 1e-12);
        }
    }
    // Green is 557.7 nm alone: its depth at every air mass.
    let d = air.depths(557.7);
    let t557 = d.rayleigh + d.ozone + d.aerosol;
    assert!((ext.effective_tau(1, 20.0) - t557).abs() < 1e-12);
    let green = Extinction::for_line(air, DVec3::ZERO, 0);
    let dir = DVec3::new(1.0, 0.0, 0.2).normalize();
    let x = air_mass(fmath::asin(dir.z).to_degrees());
    assert!(green.towards(dir).iter().all(|t| (t - fmath::exp(-t557 * x)).abs() < 1e-12), "{:?}", green.towards(dir));
    // An observer 1 km up sees the Rayleigh column times p(1 km) / p0.
    let up = Extinction::for_observer(air, DVec3::new(0.0, 0.0, 1.0), Some(0));
    let want = d.rayleigh * pressure_ratio(1.0) + d.ozone + d.aerosol * fmath::exp(-1.0f64 / 1.2);
    assert!((up.tau_zenith[0] - want).abs() < 1e-12);
}

/// Towards a point far above the layer, the slant path (plane-parallel,
/// `1 / sin e`) and the air-mass law agree where the air mass is nearly
/// plane-parallel (within 1 % of transmittance at 30 degrees and above).
#[test]
fn slant_path_and_air_mass_agree_high_in_the_sky() {
    let ext = Extinction::for_observer(default_air(), DVec3::ZERO, None);
    for e in [30.0f64, 60.0, 90.0] {
        let dir = DVec3::new(fmath::cos(e.to_radians()), 0.0, fmath::sin(e.to_radians()));
        let p = dir * (150.0 / dir.z);
        let (a, b) = (ext.along(DVec3::ZERO, p), ext.towards(dir));
        for c in 0..3 {
            assert!((a[c] / b[c] - 1.0).abs() < 0.01, "{e}: {a:?} vs {b:?}");
        }
    }
}

/// A uniform emitting slab 100-110 km up, seen at 10, 30 and 90 degrees
/// elevation through a 0.5-degree view (odd size, one sample at each pixel
/// centre: the centre pixel looks exactly at the elevation): the ratio of
/// each channel with extinction on to off is `exp(-tau_c X)` with `X`
/// Kasten & Young's and `tau_c` the channel's effective depth at that air
/// mass (`-ln T_c(X) / X`, `T_c` the lines' sum of exponentials assembled
/// in [`channel_t`]), within 1 % (the done-when's tolerance; the pixel
/// values are f32, so the centre pixel's ratio is good to 1e-6). Over the
/// whole 5 x 5 image the ratio of sums is within 1 % too (the elevation
/// varies by 0.25 degree about the centre: 0.4 % of X at 10 degrees, to
/// first order cancelling).
#[test]
fn a_curtain_dims_as_exp_minus_tau_x() {
    let voxel = 1.0;
    let mut ratios = [[0.0; 3]; 3];
    for (k, elev) in [10.0f64, 30.0, 90.0].into_iter().enumerate() {
        // The slab where the view meets 105 km, a few km around it.
        let dir = DVec3::new(fmath::cos(elev.to_radians()), 0.0, fmath::sin(elev.to_radians()));
        let hit = dir * (105.0 / dir.z);
        let mut e = Grid::new("emission", [0.0f32; 3], Transform::new(voxel, DVec3::ZERO));
        let reach = 4 + (1.5 / fmath::tan(elev.to_radians())) as i32;
        for x in -reach..=reach {
            for y in -4..=4 {
                for z in 100..=110 {
                    e.set(IVec3::new(hit.x.round() as i32 + x, y, z), [0.6, 1.0, 0.3]);
                }
            }
        }
        let up = if elev == 90.0 { [1.0, 0.0, 0.0] } else { [0.0, 0.0, 1.0] };
        let mut s = settings(persp([0.0, 0.0, 0.0], (dir * 10.0).to_array(), up, 0.5), 5, 5, 1);
        let off = render(&s, &Volume { density: None, emission: Some(&e) }, &NoProgress).unwrap();
        s.sky = SkyParams::default();
        let on = render(&s, &Volume { density: None, emission: Some(&e) }, &NoProgress).unwrap();
        let x = air_mass(elev);
        let (pc, pn) = (off.pixel(2, 2), on.pixel(2, 2));
        for c in 0..3 {
            assert!(pc[c] > 0.0, "the slab is in view");
            let tau_c = -fmath::ln(channel_t(c, x, s.observer)) / x;
            let want = fmath::exp(-tau_c * x);
            let got = pn[c] as f64 / pc[c] as f64;
            assert!((got / want - 1.0).abs() < 0.01, "{elev} deg, channel {c}: {got} vs {want}");
            let sum = |img: &aurora::render::Image| img.pixels.iter().map(|p| p[c] as f64).sum::<f64>();
            let whole = sum(&on) / sum(&off);
            assert!((whole / want - 1.0).abs() < 0.01, "{elev} deg, channel {c}, whole image: {whole} vs {want}");
            ratios[k][c] = got;
        }
    }
    // The curtain near the horizon is dimmer and redder than overhead.
    assert!(ratios[0][0] < ratios[2][0] && ratios[0][2] / ratios[0][0] < ratios[2][2] / ratios[2][0]);
}

/// `extinction = false` renders as if `[sky]` were absent from the
/// renderer whatever its other keys: the same bits with the aerosol,
/// ozone and Angstrom keys at other values.
#[test]
fn extinction_off_ignores_the_other_sky_keys() {
    let mut scene = Scene::default();
    scene.render.width = 24;
    scene.render.height = 16;
    let mut e = Grid::new("emission", [0.0f32; 3], Transform::new(2.0, DVec3::ZERO));
    for x in -10..10 {
        for z in 45..55 {
            e.set(IVec3::new(x, 10, z), [1.0, 0.8, 0.2]);
        }
    }
    let mut s = settings(scene.camera.clone(), 24, 16, 2);
    let a = render(&s, &Volume { density: None, emission: Some(&e) }, &NoProgress).unwrap();
    s.sky = SkyParams {
        extinction: false,
        ozone_du: 500.0,
        aerosol_optical_depth: 1.0,
        angstrom: 0.0,
        aerosol_scale_height_km: 5.0,
        scattering: true,
    };
    let b = render(&s, &Volume { density: None, emission: Some(&e) }, &NoProgress).unwrap();
    assert!(a.pixels.iter().any(|p| p[1] > 0.0));
    assert_eq!(a.pixels, b.pixels);
    s.sky.extinction = true;
    let c = render(&s, &Volume { density: None, emission: Some(&e) }, &NoProgress).unwrap();
    assert_ne!(a.pixels, c.pixels);
}

/// `blender/extinction.json`: what the add-on needs to apply the same air
/// in Cycles (blender/air.py): per line its sea-level Rayleigh depth, its
/// ozone depth per Dobson unit and the wavelengths its aerosol depth is
/// averaged over; each channel's weights over the lines for each observer
/// (`[colour] observer`: "camera", "eye"); and, as the add-on's test
/// oracle, the transmittance per channel at a few elevations for the
/// default sky at two observer altitudes, for each observer. Regenerated
/// with `AURORA_UPDATE_DOCS=1 cargo test --release --test render air_extinction::`.
#[test]
fn committed_addon_table_matches_the_library() {
    use aurora::physics::emission::line_colour::{LINES, N2_1P, N2_1P_BANDS_NM};
    use serde_json::{json, Value};
    let air = default_air();
    let per_du = Air { ozone_du: 1.0, ..air };
    let lines: Vec<Value> = (0..aurora::physics::emission::line_table::N_LINES)
        .map(|i| {
            let d = per_du.line_depths(i);
            let wl: Vec<f64> = if LINES[i] == N2_1P { N2_1P_BANDS_NM.to_vec() } else { vec![LINES[i].lambda_nm] };
            json!({"name": LINES[i].name, "rayleigh": d.rayleigh, "ozone_per_du": d.ozone, "aerosol_wavelengths_nm": wl})
        })
        .collect();
    let mut checks = Vec::new();
    for o in Observer::ALL {
        for z in [0.0, 1.0] {
            let at = DVec3::new(0.0, 0.0, z);
            let ext = Extinction::for_observer_at(air, at, z, DVec3::Z, None, o);
            for e in [90.0f64, 30.0, 10.0, 2.0] {
                let dir = DVec3::new(fmath::cos(e.to_radians()), 0.0, fmath::sin(e.to_radians()));
                checks.push(json!({"observer": o.name(), "observer_km": z, "elevation_deg": e, "transmittance": ext.towards(dir)}));
            }
        }
    }
    let weights: serde_json::Map<String, Value> =
        Observer::ALL.iter().map(|o| (o.name().to_string(), json!(aurora::physics::air_extinction::channel_weights(*o)))).collect();
    let doc = json!({
        "reference_mix": REFERENCE_MIX,
        "weights": weights,
        "lines": lines,
        "checks": checks,
    });
    let text = serde_json::to_string_pretty(&doc).expect("serialises") + "\n";
    update_or_check_committed("blender/extinction.json", &text, "AURORA_UPDATE_DOCS=1 cargo test --release --test render air_extinction::");
}
