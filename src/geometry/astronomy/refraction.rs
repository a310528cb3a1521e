//! Atmospheric refraction: how much higher a direction appears than it is.
//!
//! **Model.** Exactly skyfield's (`skyfield.earthlib.refraction` and
//! `refract`, skyfield 1.55): Bennett's formula (Bennett 1982, J. Inst.
//! Navigation 35, 255; Meeus, "Astronomical Algorithms", 2nd ed., eq. 16.4
//! with the temperature and pressure factor of ch. 16) for the refraction
//! of an *apparent* elevation h, degrees,
//!
//! ```text
//! R(h) = 0.016667 / tan(h + 7.31 / (h + 4.4)) * (0.28 P / (T + 273))
//! ```
//!
//! with P in hPa and T in C, and zero outside `-1 <= h <= 89.9` (below a
//! degree under the horizon, and at the zenith). A true elevation h0 is
//! raised by iterating `h = h0 + R(h)` from `h = h0` until a step moves it
//! by no more than 3e-5 degrees ([`refraction_deg`]). Bennett's formula is
//! good to 0.07' above the horizon for the standard air.

use crate::util::fmath;
use glam::DVec3;

/// The air refraction is computed for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Air {
    /// Temperature at the site, degrees Celsius.
    pub temperature_c: f64,
    /// Pressure at the site, hPa.
    pub pressure_hpa: f64,
}

impl Default for Air {
    /// 10 C and 1010 hPa, Meeus' standard air.
    fn default() -> Air {
        Air { temperature_c: 10.0, pressure_hpa: 1010.0 }
    }
}

/// Bennett's refraction of an apparent elevation, degrees (skyfield's
/// `earthlib.refraction`).
pub fn bennett_deg(apparent_elevation_deg: f64, air: &Air) -> f64 {
    let h = apparent_elevation_deg;
    if !(-1.0..=89.9).contains(&h) {
        return 0.0;
    }
    let r = 0.016_667 / fmath::tan((h + 7.31 / (h + 4.4)).to_radians());
    r * (0.28 * air.pressure_hpa / (air.temperature_c + 273.0))
}

/// The refraction of a true elevation, degrees: apparent minus true, by
/// skyfield's iteration (`earthlib.refract`).
pub fn refraction_deg(true_elevation_deg: f64, air: &Air) -> f64 {
    let h0 = true_elevation_deg;
    let mut h = h0;
    for _ in 0..100 {
        let next = h0 + bennett_deg(h, air);
        let step = (next - h).abs();
        h = next;
        if !(step > 3.0e-5) {
            break;
        }
    }
    h - h0
}

/// A true ENU direction raised by refraction: the same azimuth, the
/// elevation raised by [`refraction_deg`]. Unit in, unit out.
pub fn refract(enu_dir: DVec3, air: &Air) -> DVec3 {
    let el = fmath::asin(enu_dir.z.clamp(-1.0, 1.0));
    let dh = refraction_deg(el.to_degrees(), air).to_radians();
    if dh == 0.0 {
        return enu_dir;
    }
    let horizontal = DVec3::new(enu_dir.x, enu_dir.y, 0.0);
    let h_len = horizontal.length();
    if h_len == 0.0 {
        return enu_dir;
    }
    let (s, c) = fmath::sin_cos(el + dh);
    horizontal / h_len * c + DVec3::Z * s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meeus_example_16a_and_the_cut_offs() {
        // Meeus Example 16.a: an apparent elevation of 0.5 degrees is
        // refracted by 28.754' (Bennett, standard air; the air factor at
        // 10 C and 1010 hPa is 0.99929 and skyfield's 0.016667 is 1/60 to
        // 2e-5).
        let factor = 0.28 * 1010.0 / 283.0;
        let r = bennett_deg(0.5, &Air::default()) * 60.0 / factor;
        assert!((r - 28.754).abs() < 0.002, "{r}");
        assert_eq!(bennett_deg(-1.01, &Air::default()), 0.0);
        assert_eq!(bennett_deg(89.95, &Air::default()), 0.0);
        assert!(bennett_deg(-1.0, &Air::default()) > 0.0);
    }

    #[test]
    fn iteration_solves_apparent_equals_true_plus_bennett() {
        let air = Air { temperature_c: -20.0, pressure_hpa: 980.0 };
        for h0 in [-0.9, 0.0, 5.0, 10.0, 45.0, 80.0] {
            let r = refraction_deg(h0, &air);
            assert!((h0 + r - (h0 + bennett_deg(h0 + r, &air))).abs() < 1e-4, "{h0}");
        }
        // 45 degrees: about one arcminute.
        assert!((refraction_deg(45.0, &Air::default()) * 60.0 - 0.99).abs() < 0.02);
        let up = refract(DVec3::new(0.0, 1.0, 0.0), &Air::default());
        assert!((up.length() - 1.0).abs() < 1e-15 && up.z > 0.0 && up.x == 0.0);
        assert_eq!(refract(DVec3::Z, &Air::default()), DVec3::Z);
        assert_eq!(refract(DVec3::new(0.0, 0.5, -0.8).normalize(), &Air::default()).z, DVec3::new(0.0, 0.5, -0.8).normalize().z);
    }
}
