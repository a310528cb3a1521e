//! The stars as light: a star's irradiance and colour ([`Star`], [`planck`],
//! [`spectrum_rgb`]) and, without a `[site]`, a statistical star field
//! ([`star_field`]); `sky.rs` draws them, `site_sky.rs` places the
//! catalogue's over a site.
//!
//! **Stars.** Isotropic directions, magnitudes from the cumulative count
//! of stars brighter than m over the whole sky,
//! `N(<m) = 4800 x 10^(0.45 (m - 6))`: the slope `d log10 N / dm ~ 0.45`
//! and about 4800 stars to m = 6 (Allen's Astrophysical Quantities, 4th
//! ed., star counts; 9110 in the Yale Bright Star Catalogue to m = 6.5,
//! against 8100 here), which holds up to m ~ 8. So star i of
//! `n = N(<m_lim)` gets `m = m_lim + log10(u) / 0.45` (`u` uniform),
//! clamped at -1.5 (Sirius). Its irradiance, in the radiance unit of the
//! volume (kR, emission per km times km) times steradians, is
//! `E = E_0 10^(-0.4 m)`, `E_0` the V-band photon flux of a magnitude-0
//! star: 3.63e-9 erg cm^-2 s^-1 A^-1 (Bessell 1979) over 880 A (the V
//! filter's width) at 3.61e-12 erg per 550 nm photon is 8.85e5 photons
//! cm^-2 s^-1, and 1 kR sr is 10^9 / (4 pi) photons cm^-2 s^-1, so
//! `E_0 = 0.0111 kR sr` (times `star_brightness`). Colours are blackbody
//! colours (Planck's law through the CIE 1931 observer, normalised to
//! luminance 1) of a temperature drawn from approximate shares of
//! naked-eye stars by spectral class (B 12 %, A 22 %, F 17 %, G 15 %,
//! K 30 %, M 4 %; Bright Star Catalogue counts, rounded).
//!

use crate::util::colour::{cie1931_xyz, gamut_map, luminance, xyz_to_rec709};
use crate::util::observer::Observer;
use glam::DVec3;
use rand::Rng;
use std::f64::consts::PI;

/// Stars brighter than magnitude 6 over the whole sky.
pub const STARS_TO_MAG_6: f64 = 4800.0;
/// `d log10 N(<m) / dm`.
pub const COUNT_SLOPE: f64 = 0.45;
/// Irradiance of a magnitude-0 star, kR sr (see the module documentation).
pub const MAG0_KR_SR: f64 = 0.0111;
/// The brightest star drawn (Sirius, V = -1.46).
pub const BRIGHTEST_MAG: f64 = -1.5;

/// Spectral classes of naked-eye stars: (share, effective temperature K).
const CLASSES: [(f64, f64); 6] = [(0.12, 15000.0), (0.22, 9000.0), (0.17, 6700.0), (0.15, 5600.0), (0.30, 4500.0), (0.04, 3400.0)];

/// One star: a direction and its irradiance per channel, kR sr.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Star {
    pub dir: DVec3,
    pub magnitude: f64,
    pub irradiance: [f64; 3],
}

/// Linear Rec.709 colour of a blackbody at `t_k` kelvin, luminance 1.
pub fn blackbody_rgb(t_k: f64) -> [f64; 3] {
    // Planck's law up to a constant: lambda^-5 / (exp(hc / (lambda k T)) - 1).
    const HC_K: f64 = 1.438_777e7; // nm K
    let mut xyz = [0.0f64; 3];
    let mut l: f64 = 380.0;
    while l <= 780.0 {
        let b = l.powi(-5) / ((HC_K / (l * t_k)).exp() - 1.0);
        let c = cie1931_xyz(l);
        for k in 0..3 {
            xyz[k] += b * c[k];
        }
        l += 5.0;
    }
    let rgb = gamut_map(xyz_to_rec709([xyz[0] / xyz[1], 1.0, xyz[2] / xyz[1]]));
    let y = luminance(rgb);
    rgb.map(|c| c / y)
}

/// Planck's law up to a constant: the spectral radiance of a blackbody at
/// `t_k` kelvin at `lambda_nm`, per nm, in arbitrary units.
pub fn planck(lambda_nm: f64, t_k: f64) -> f64 {
    const HC_K: f64 = 1.438_777e7; // nm K
    lambda_nm.powi(-5) / ((HC_K / (lambda_nm * t_k)).exp() - 1.0)
}

/// Linear Rec.709 colour of the spectrum `s` (per nm, 380-780 nm by 5 nm)
/// as `observer` records it, brought into its gamut
/// (`Observer::in_gamut`), luminance 1.
pub fn spectrum_rgb(observer: Observer, s: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut rgb = [0.0f64; 3];
    let mut l: f64 = 380.0;
    while l <= 780.0 {
        let b = s(l);
        let c = observer.rgb(l);
        for k in 0..3 {
            rgb[k] += b * c[k];
        }
        l += 5.0;
    }
    let rgb = observer.in_gamut(rgb);
    let y = luminance(rgb);
    rgb.map(|c| c / y)
}

/// The star field of `seed` down to `limiting_magnitude` (module
/// documentation), `brightness` times the physical irradiance.
pub fn star_field(seed: u64, limiting_magnitude: f64, brightness: f64) -> Vec<Star> {
    let n = (STARS_TO_MAG_6 * 10f64.powf(COUNT_SLOPE * (limiting_magnitude - 6.0))).round() as usize;
    let colours: Vec<[f64; 3]> = CLASSES.iter().map(|&(_, t)| blackbody_rgb(t)).collect();
    let mut rng = crate::util::rng::rng(&[seed, 0x5354_4152_5300]);
    (0..n)
        .map(|_| {
            // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
            let z: f64 = rng.random::<f64>() * 2.0 - 1.0;
            let phi = rng.random::<f64>() * 2.0 * PI;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let u: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
            let m = (limiting_magnitude + u.log10() / COUNT_SLOPE).max(BRIGHTEST_MAG);
            let mut pick: f64 = rng.random::<f64>();
            let mut class = CLASSES.len() - 1;
            for (i, (share, _)) in CLASSES.iter().enumerate() {
                if pick < *share {
                    class = i;
                    break;
                }
                pick -= share;
            }
            let e = brightness * MAG0_KR_SR * 10f64.powf(-0.4 * m);
            Star { dir: DVec3::new(s * phi.cos(), s * phi.sin(), z), magnitude: m, irradiance: colours[class].map(|c| c * e) }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The drawn magnitudes follow log10 N(<m) = const + 0.45 m: counts
    /// brighter than m_lim - 1 and m_lim - 2 are 10^-0.45 and 10^-0.9 of
    /// the total, within 4 Poisson standard deviations.
    #[test]
    fn magnitudes_follow_the_star_counts() {
        let stars = star_field(3, 7.0, 1.0);
        let n = stars.len() as f64;
        assert!((n / (STARS_TO_MAG_6 * 10f64.powf(0.45)) - 1.0).abs() < 1e-3, "{n}");
        for dm in [1.0, 2.0] {
            let k = stars.iter().filter(|s| s.magnitude < 7.0 - dm).count() as f64;
            let want = n * 10f64.powf(-0.45 * dm);
            assert!((k - want).abs() < 4.0 * want.sqrt(), "dm {dm}: {k} vs {want}");
        }
        // Isotropic: as many in each hemisphere, within 4 sigma.
        let up = stars.iter().filter(|s| s.dir.z > 0.0).count() as f64;
        assert!((up - n / 2.0).abs() < 4.0 * (n / 4.0).sqrt());
        // Deterministic per seed.
        assert_eq!(star_field(3, 7.0, 1.0), stars);
        assert_ne!(star_field(4, 7.0, 1.0), stars);
    }

    #[test]
    fn blackbody_colours_run_from_red_to_blue() {
        let cool = blackbody_rgb(3400.0);
        let sun = blackbody_rgb(5800.0);
        let hot = blackbody_rgb(15000.0);
        assert!(cool[0] > cool[2] && hot[2] > hot[0], "{cool:?} {hot:?}");
        // Near white around the sun's temperature (D65 is 6504 K).
        assert!((sun[0] / sun[2] - 1.0).abs() < 0.35, "{sun:?}");
        for c in [cool, sun, hot] {
            assert!((luminance(c) - 1.0).abs() < 1e-9);
        }
    }
}
