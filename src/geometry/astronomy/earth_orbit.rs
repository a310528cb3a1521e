//! The Earth's orbit: the Sun's geocentric place, and the Earth's
//! heliocentric place and velocity for annual parallax and aberration.
//!
//! **Model.** The Sun's low-precision theory, Meeus, "Astronomical
//! Algorithms", 2nd ed., ch. 25 (0.01 degree), with t in Julian centuries
//! of TT from J2000:
//!
//! ```text
//! L0 = 280.46646 + 36000.76983 t + 0.0003032 t^2     (mean longitude)
//! M  = 357.52911 + 35999.05029 t - 0.0001537 t^2     (mean anomaly)
//! e  = 0.016708634 - 0.000042037 t - 0.0000001267 t^2
//! C  = (1.914602 - 0.004817 t - 0.000014 t^2) sin M
//!      + (0.019993 - 0.000101 t) sin 2M + 0.000289 sin 3M
//! true longitude = L0 + C,   R = 1.000001018 (1 - e^2) / (1 + e cos(M + C))  AU
//! ```
//!
//! referred to the mean equinox of date ([`sun_place`]). It is a Keplerian
//! ellipse, read the other way round: the Earth is at `-R` along the Sun's geometric
//! longitude, and its velocity in the ecliptic plane is (Smart, "Textbook
//! on Spherical Astronomy", 6th ed., section 108; Meeus eq. 23.2's vector
//! form)
//!
//! ```text
//! v / c = kappa (sin L - e sin w, -cos L + e cos w, 0)
//! ```
//!
//! with `L` the Sun's true longitude, `e` the orbit's eccentricity, `w =
//! 102.93735 + 1.71946 t` degrees the longitude of the Earth's perihelion
//! and `kappa = 20.49552"` the constant of aberration. Longitudes are moved
//! from the equinox of date to J2000 by the general precession, `-5029.0966"
//! t`, and the ecliptic turned to the ICRS equator with `eps0 = 84381.448"`
//! (the frame bias, 0.02", neglected). The Sun's own motion about the
//! barycentre (0.013 km/s, 0.01") and the ellipse's perturbations are left
//! out: the aberration is good to a few hundredths of an arcsecond, the
//! parallax (0.75" at most, alpha Centauri) to its hundredth.

use super::rotation::{equatorial_from_ecliptic, ARCSEC};
use crate::util::fmath;
use glam::DVec3;

/// The astronomical unit, km (IAU 2012).
pub const AU_KM: f64 = 149_597_870.7;

/// The Sun's geometric geocentric place, ecliptic and mean equinox of date.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPlace {
    /// The true (geometric) longitude, degrees in `[0, 360)`.
    pub longitude_deg: f64,
    /// The distance from the Earth's centre, AU.
    pub distance_au: f64,
}

/// The Sun's geometric place at a Julian Date in TT (Meeus ch. 25).
pub fn sun_place(jd_tt: f64) -> SunPlace {
    let t = (jd_tt - 2_451_545.0) / 36_525.0;
    let l0 = 280.466_46 + 36_000.769_83 * t + 0.000_303_2 * t * t;
    let m = (357.529_11 + 35_999.050_29 * t - 0.000_153_7 * t * t).to_radians();
    let e = 0.016_708_634 - 0.000_042_037 * t - 0.000_000_126_7 * t * t;
    let c = (1.914_602 - 0.004_817 * t - 0.000_014 * t * t) * fmath::sin(m)
        + (0.019_993 - 0.000_101 * t) * fmath::sin(2.0 * m)
        + 0.000_289 * fmath::sin(3.0 * m);
    let nu = m + c.to_radians();
    SunPlace { longitude_deg: (l0 + c).rem_euclid(360.0), distance_au: 1.000_001_018 * (1.0 - e * e) / (1.0 + e * fmath::cos(nu)) }
}

/// The constant of aberration, radians (the Earth's mean orbital speed
/// over c).
pub const ABERRATION_CONSTANT: f64 = 20.495_52 * ARCSEC;

/// The Earth's heliocentric position (AU) and velocity (in units of c),
/// ICRS axes, at a Julian Date in TT.
pub fn earth_position_velocity(jd_tt: f64) -> (DVec3, DVec3) {
    let t = (jd_tt - 2_451_545.0) / 36_525.0;
    let place = sun_place(jd_tt);
    let to_j2000 = -5029.0966 * t * ARCSEC;
    let l = place.longitude_deg.to_radians() + to_j2000;
    let w = (102.937_35 + 1.719_46 * t).to_radians() + to_j2000;
    let e = 0.016_708_634 - 0.000_042_037 * t;
    let eps0 = 84_381.448 * ARCSEC;
    let position = -equatorial_from_ecliptic(l, 0.0, eps0) * place.distance_au;
    let v_ecl = DVec3::new(fmath::sin(l) - e * fmath::sin(w), -fmath::cos(l) + e * fmath::cos(w), 0.0) * ABERRATION_CONSTANT;
    let (se, ce) = fmath::sin_cos(eps0);
    let velocity = DVec3::new(v_ecl.x, v_ecl.y * ce - v_ecl.z * se, v_ecl.y * se + v_ecl.z * ce);
    (position, velocity)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_is_the_position_rate() {
        // The velocity agrees with the position's finite difference (AU a
        // day over c's 173.1446 AU a day) to 0.5 % (the series' terms of
        // order e^2 and the Sun's mean-longitude rate).
        let jd = 2_461_380.5;
        let h = 0.05;
        let (p0, v) = earth_position_velocity(jd);
        let (pm, _) = earth_position_velocity(jd - h);
        let (pp, _) = earth_position_velocity(jd + h);
        let rate = (pp - pm) / (2.0 * h) / 173.144_632_7;
        assert!((rate - v).length() < 5e-3 * v.length(), "{rate} {v}");
        // Perpendicular to the position, nearly, and the right size.
        assert!((p0.length() - 1.0).abs() < 0.02);
        assert!((v.length() / ARCSEC - 20.5).abs() < 0.4);
    }
}
