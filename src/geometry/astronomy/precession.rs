//! Frame bias and precession: from the GCRS (ICRS axes) to the mean
//! equator and equinox of date, and the mean obliquity of the ecliptic.
//!
//! **Model.** The frame bias of IAU 2000 (IERS Conventions 2003, section
//! 5.5.2; SOFA `iauBi00`): `da0 = -14.6 mas`, `dpsi = -41.775 mas`,
//! `deps = -6.8192 mas`, `B = r1(-deps) r2(dpsi sin eps0) r3(da0)`. Then the
//! IAU 1976 precession (Lieske et al. 1977, A&A 58, 1; SOFA `iauPrec76`
//! from J2000): with t in Julian centuries of TT from J2000,
//!
//! ```text
//! zeta  = 2306.2181" t + 0.30188" t^2 + 0.017998" t^3
//! z     = 2306.2181" t + 1.09468" t^2 + 0.018203" t^3
//! theta = 2004.3109" t - 0.42665" t^2 - 0.041833" t^3
//! P = r3(-z) r2(theta) r3(-zeta)
//! ```
//!
//! It differs from IAU 2006 by its rate in longitude, `-0.3"` a century,
//! 0.1 arcsecond at 2030. The mean obliquity is IAU 1980's (Lieske 1979;
//! Meeus, eq. 22.2): `eps0 = 84381.448" - 46.8150" t - 0.00059" t^2 +
//! 0.001813" t^3`.

use super::rotation::{r1, r2, r3, ARCSEC};
use crate::util::fmath;
use glam::DMat3;

/// Julian centuries of TT from J2000.
pub fn centuries_tt(jd_tt: f64) -> f64 {
    (jd_tt - 2_451_545.0) / 36_525.0
}

/// The mean obliquity of the ecliptic of date (IAU 1980), radians.
pub fn mean_obliquity_rad(jd_tt: f64) -> f64 {
    let t = centuries_tt(jd_tt);
    (84_381.448 + t * (-46.8150 + t * (-0.00059 + t * 0.001_813))) * ARCSEC
}

/// The frame bias from the GCRS to the mean J2000 frame (IAU 2000).
pub fn frame_bias() -> DMat3 {
    let eps0 = 84_381.448 * ARCSEC;
    r1(0.006_819_2 * ARCSEC) * r2(-0.041_775 * ARCSEC * fmath::sin(eps0)) * r3(-0.0146 * ARCSEC)
}

/// The IAU 1976 precession from the mean J2000 frame to the mean frame of
/// date.
pub fn precession_1976(jd_tt: f64) -> DMat3 {
    let t = centuries_tt(jd_tt);
    let zeta = t * (2306.2181 + t * (0.30188 + t * 0.017_998)) * ARCSEC;
    let z = t * (2306.2181 + t * (1.09468 + t * 0.018_203)) * ARCSEC;
    let theta = t * (2004.3109 + t * (-0.42665 - t * 0.041_833)) * ARCSEC;
    r3(-z) * r2(theta) * r3(-zeta)
}

/// Bias then precession: from the GCRS to the mean frame of date.
pub fn mean_of_date_from_gcrs(jd_tt: f64) -> DMat3 {
    precession_1976(jd_tt) * frame_bias()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn meeus_example_21b_theta_persei() {
        // Meeus Example 21.b: theta Persei at J2000, alpha 2h44m11.986s,
        // delta +49d13'42.48", proper motion +0.03425 s and -0.0895" a
        // year, to 2028 Nov 13.19 TD (JDE 2462088.69): alpha 2h46m11.331s,
        // delta +49d20'54.54".
        let jde: f64 = 2_462_088.69;
        let years = (jde - 2_451_545.0) / 365.25;
        let a = (41.049_941_7 + 0.034_25 * 15.0 * years / 3600.0).to_radians();
        let d = (49.228_466_7 - 0.0895 * years / 3600.0).to_radians();
        let v = DVec3::new(fmath::cos(d) * fmath::cos(a), fmath::cos(d) * fmath::sin(a), fmath::sin(d));
        let p = precession_1976(jde) * v;
        let ra = fmath::atan2(p.y, p.x).to_degrees();
        let dec = fmath::asin(p.z).to_degrees();
        let (ra_want, dec_want) = (41.547_212_5, 49.348_483_3);
        assert!((ra - ra_want).abs() < 1e-5 && (dec - dec_want).abs() < 1e-5, "{ra} {dec}");
    }

    #[test]
    fn bias_is_tens_of_milliarcseconds() {
        let b = frame_bias();
        let moved = (b * DVec3::X - DVec3::X).length() / ARCSEC;
        assert!(moved > 0.01 && moved < 0.05, "{moved}");
        // Meeus Example 22.a: 1987 April 10 0h TD, eps0 = 23d26'27.407".
        assert!((mean_obliquity_rad(2_446_895.5) / ARCSEC - 84_387.407).abs() < 0.001);
    }
}
