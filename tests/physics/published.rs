//! The lines against published measurements and models beyond GLOW, each
//! test citing its source and its tolerance: the O(1D) doublet's ratio,
//! the red's altitude and the 427.8 nm brightness per ion pair and per
//! unit energy flux. docs/physics.md, "The lines against published
//! values", tables the comparisons.

use aurora::pipeline::altitude_profile::{profile, CurtainProfile};
use aurora::scene::Scene;
use aurora::util::progress::NoProgress;

/// One straight 40 x 16 km curtain of Maxwellian electrons of `e0` keV
/// (no soft component), 1 erg cm^-2 s^-1 on every beam (uniform
/// footprint), on the validated atmosphere (NRLMSIS 2.1 with GLOW's
/// ionosphere), the air's density off.
fn scene(e0: f64) -> Scene {
    let text = format!(
        "seed = 3\n[[curtain]]\nlength = 40.0\nwidth = 16.0\nbend_km = 0.0\nenergy_flux = 1.0\nchar_energy_kev = {e0}\nsoft_fraction = 0.0\n\
         [footprint]\nresolution = [64, 32]\nuniform = true\n[beams]\ncount = 400\n[grid]\ndensity_a = 0.0\n\
         [atmosphere]\nmodel = \"nrlmsis21\"\nionosphere = \"glow\"\n"
    );
    Scene::from_toml_str(&text, "published.toml").unwrap()
}

/// The curtain's profile and the electron power into the atmosphere, erg/s.
fn run(e0: f64) -> (CurtainProfile, f64) {
    let p = profile(&scene(e0), &NoProgress).unwrap();
    let erg_s = p.beam_stats.power.electron_power_w * 1e7;
    (p.curtains.into_iter().next().unwrap(), erg_s)
}

/// Profile columns: ion pairs (0), 427.8 (1), 630.0 (3), 636.4 nm (4).
const ION: usize = 0;
const BLUE: usize = 1;
const RED: usize = 3;
const RED2: usize = 4;

/// The column of `col`, photons/s.
fn column(p: &CurtainProfile, col: usize) -> f64 {
    p.bins.iter().map(|b| b[col]).sum()
}

/// The column-weighted mean altitude of `col`, km.
fn centroid(p: &CurtainProfile, col: usize) -> f64 {
    p.bins.iter().enumerate().map(|(i, b)| b[col] * p.centre(i)).sum::<f64>() / column(p, col)
}

#[test]
fn the_red_doublet_leaves_the_bake_at_storey_and_zeippens_ratio() {
    // Sharpee & Slanger (2006, J. Phys. Chem. A 110, 6707) measured the
    // 630.0 / 636.4 nm photon ratio 2.997 +- 0.016 in nightglow, as
    // Storey & Zeippen's (2000) coefficients give; both lines come from
    // O(1D), so the ratio holds at every altitude and in the columns.
    // Within 1 % (the measurement's 0.5 % twice); GLOW's old pair gave 3.16.
    let (p, _) = run(3.0);
    let r = column(&p, RED) / column(&p, RED2);
    assert!((r / 2.997 - 1.0).abs() < 0.01, "630.0 / 636.4 = {r}");
}

#[test]
fn the_red_centroid_lies_within_15_km_of_glows() {
    // GLOW 4.0.4's 630.0 nm centroids (nightglow subtracted, same place,
    // time and atmosphere): 241 / 229 / 218 / 212 km at E0 = 0.5 / 1 / 3 /
    // 10 keV. Its electron density switches to IRI at 200 km, which moves
    // its centroid by a few km; 15 km is half the 20-35 km the red sat
    // too high before the chemistry and the topside were modelled.
    for (e0, glow) in [(0.5, 241.0), (1.0, 229.0), (3.0, 218.0), (10.0, 212.0)] {
        let (p, _) = run(e0);
        let c = centroid(&p, RED);
        assert!((c - glow).abs() < 15.0, "E0 {e0} keV: 630.0 nm centroid {c:.1} km, GLOW {glow} km");
    }
}

#[test]
fn blue_per_ion_pair_is_glows_and_its_excess_per_erg_is_the_deposit() {
    // 427.8 nm per erg cm^-2 s^-1: ours 271-297 R from 1 to 10 keV, GLOW
    // 231-271 R, Rees & Luckey (1974, J. Geophys. Res. 79, 5181) about
    // 213 R. Per ion pair ours is GLOW's (0.0151 / 0.0166 / 0.0171 photons
    // at 1 / 3 / 10 keV from GLOW's columns): within 5 %, the spread of
    // GLOW's own yield over Q. The excess per erg is in the ion pairs:
    // ours deposit 0.975-0.99 of the incident energy, GLOW 0.77-0.83 (1 minus
    // its upward energy flux at the top) at 31-33 eV per ion pair, so ours
    // makes 1.10-1.15 times GLOW's 1.53 / 1.59 / 1.59e10 ion pairs per erg
    // (at 35 eV each, the most an erg can make is 1.78e10).
    for (e0, glow_blue_per_ion, glow_ions_per_erg) in [(1.0, 0.01512, 1.528e10), (3.0, 0.01664, 1.589e10), (10.0, 0.01712, 1.585e10)] {
        let (p, erg) = run(e0);
        let ions = column(&p, ION);
        let per_ion = column(&p, BLUE) / ions;
        assert!((per_ion / glow_blue_per_ion - 1.0).abs() < 0.05, "E0 {e0}: 427.8 per ion pair {per_ion:.5}, GLOW {glow_blue_per_ion}");
        let ratio = ions / erg / glow_ions_per_erg;
        assert!(
            (1.05..1.20).contains(&ratio) && ions / erg <= 6.2415e11 / 35.0,
            "E0 {e0}: ion pairs per erg {:.3e}, {ratio:.3} of GLOW's",
            ions / erg
        );
    }
}

/// Profile column of the N2 1P bands.
const FIRST_POSITIVE: usize = 5;

/// The 1P over 427.8 nm photons of the bins whose centres lie in `range`, km.
fn first_positive_over_blue(p: &CurtainProfile, range: std::ops::Range<f64>) -> f64 {
    let (mut red, mut blue) = (0.0, 0.0);
    for (i, b) in p.bins.iter().enumerate() {
        if range.contains(&p.centre(i)) {
            red += b[FIRST_POSITIVE];
            blue += b[BLUE];
        }
    }
    red / blue
}

#[test]
fn the_first_positive_gains_half_on_427_8_below_100_km_under_hard_electrons() {
    // Type-B aurora: the lower border of hard aurora shows the N2 1PG about
    // 50 % brighter relative to N2+ 1NG than normal aurora (a five-channel
    // photometer in type-B red aurora, Can. J. Phys.; Vallance Jones 1974,
    // "Aurora"). "About 50 %" is one figure over many events: 1.3-1.7. Above
    // 110 km the 1P keeps its unquenched R_1P = 1 photon per 427.8 nm photon
    // within 5 % (the collisional cascade is under 10 % on there); the old
    // line model gave exactly 1 at every altitude.
    for e0 in [10.0, 20.0] {
        let (p, _) = run(e0);
        let (low, high) = (first_positive_over_blue(&p, 0.0..100.0), first_positive_over_blue(&p, 110.0..1000.0));
        let gain = low / high;
        assert!((1.3..1.7).contains(&gain), "E0 {e0} keV: 1P / 427.8 below 100 km {low:.3}, above 110 km {high:.3}, gain {gain:.3}");
        assert!((high - 1.0).abs() < 0.05, "E0 {e0} keV: 1P / 427.8 above 110 km {high:.3}");
    }
    // A soft spectrum's aurora lies above 110 km: its 1P column stays R_1P's.
    let (p, _) = run(1.0);
    let all = column(&p, FIRST_POSITIVE) / column(&p, BLUE);
    assert!((all - 1.0).abs() < 0.05, "E0 1 keV: 1P / 427.8 column {all:.3}");
}
