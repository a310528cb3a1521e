//! The Sun's direction in a site's sky.
//!
//! **Model.** The Sun's geometric place is Meeus' low-precision theory
//! ("Astronomical Algorithms", 2nd ed., ch. 25, 0.01 degree;
//! `earth_orbit::sun_place`), referred to the mean equinox of date. The
//! apparent longitude adds the nutation in longitude and the annual
//! aberration, `-20.4898" / R` (Meeus eq. 25.10); the apparent place is
//! then turned to the true equator
//! with the true obliquity, to the site's ITRS position by sidereal time,
//! and the site's offset (8.8" of parallax at most) is taken off
//! ([`sun_enu`]). The direction is unrefracted.

use super::earth_orbit::{sun_place, AU_KM};
use super::frame::SkyFrame;
use super::rotation::{equatorial_from_ecliptic, ARCSEC};
use crate::util::fmath;
use glam::DVec3;

/// The Sun's apparent geocentric position, km, in the true equator and
/// equinox of date of the frame's instant.
pub fn sun_apparent_tod_km(frame: &SkyFrame) -> DVec3 {
    let place = sun_place(frame.jd_tt());
    let n = frame.nutation();
    let lambda = place.longitude_deg.to_radians() + n.dpsi - 20.4898 * ARCSEC / place.distance_au;
    equatorial_from_ecliptic(lambda, 0.0, n.true_obliquity()) * place.distance_au * AU_KM
}

/// The Sun's topocentric direction in the site's east-north-up frame,
/// unrefracted.
pub fn sun_enu(frame: &SkyFrame) -> DVec3 {
    frame.enu_from_tod_topocentric(sun_apparent_tod_km(frame)).normalize()
}

/// The Sun's unrefracted elevation in the site's sky, degrees.
pub fn sun_elevation_deg(frame: &SkyFrame) -> f64 {
    fmath::asin(sun_enu(frame).z.clamp(-1.0, 1.0)).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meeus_example_25a() {
        // 1992 October 13.0 TD: true longitude 199.90988 degrees,
        // R = 0.99766 AU; apparent alpha 198.38083, delta -7.78507 (with
        // Meeus' own low-precision nutation and eps = 23.43999).
        let jde = 2_448_908.5;
        let p = sun_place(jde);
        assert!((p.longitude_deg - 199.909_88).abs() < 1e-5, "{}", p.longitude_deg);
        assert!((p.distance_au - 0.997_66).abs() < 1e-5, "{}", p.distance_au);
        let om = (125.04 - 1934.136 * (jde - 2_451_545.0) / 36_525.0_f64).to_radians();
        let lambda = (p.longitude_deg - 0.005_69 - 0.004_78 * fmath::sin(om)).to_radians();
        let v = equatorial_from_ecliptic(lambda, 0.0, 23.439_99_f64.to_radians());
        let ra = fmath::atan2(v.y, v.x).to_degrees().rem_euclid(360.0);
        let dec = fmath::asin(v.z).to_degrees();
        assert!((ra - 198.380_83).abs() < 2e-5 && (dec + 7.785_07).abs() < 2e-5, "{ra} {dec}");
    }
}
