//! Nutation in longitude and obliquity, and the rotation from the mean to
//! the true equator and equinox of date.
//!
//! **Model.** The IAU 1980 theory of nutation (Wahr 1981; Seidelmann 1982)
//! truncated to its 34 largest terms, those of 0.0011" and more (Meeus,
//! "Astronomical Algorithms", 2nd ed., ch. 22, table 22.A, whose first
//! rows these are): the terms left out sum to under 0.01". With the
//! fundamental arguments of Meeus (22.x) in degrees, t in Julian centuries
//! of TT from J2000,
//!
//! ```text
//! D  = 297.85036 + 445267.111480 t - 0.0019142 t^2 + t^3 / 189474
//! M  = 357.52772 +  35999.050340 t - 0.0001603 t^2 - t^3 / 300000
//! M' = 134.96298 + 477198.867398 t + 0.0086972 t^2 + t^3 / 56250
//! F  =  93.27191 + 483202.017538 t - 0.0036825 t^2 + t^3 / 327270
//! O  = 125.04452 -   1934.136261 t + 0.0020708 t^2 + t^3 / 450000
//! dpsi = sum (S + S' t) sin(arg),  deps = sum (C + C' t) cos(arg)
//! ```
//!
//! in units of 0.0001". IAU 2000A differs from this by under 0.05" in the
//! 2020s: well under this module's 1-arcsecond budget. The rotation from
//! the mean to the true frame of date is `N = r1(-(eps0 + deps)) r3(-dpsi)
//! r1(eps0)` (SOFA `iauNumat`).

use super::precession::{centuries_tt, mean_obliquity_rad};
use super::rotation::{r1, r3, ARCSEC};
use crate::util::fmath;
use glam::DMat3;

/// Nutation at an instant, radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nutation {
    /// Nutation in longitude.
    pub dpsi: f64,
    /// Nutation in obliquity.
    pub deps: f64,
    /// The mean obliquity of the ecliptic of date.
    pub mean_obliquity: f64,
}

/// Multiples of D, M, M', F, Omega; sine coefficient and its rate, cosine
/// coefficient and its rate (0.0001" and 0.0001" a century).
const TERMS: &[([i8; 5], f64, f64, f64, f64)] = &[
    ([0, 0, 0, 0, 1], -171_996.0, -174.2, 92_025.0, 8.9),
    ([-2, 0, 0, 2, 2], -13_187.0, -1.6, 5736.0, -3.1),
    ([0, 0, 0, 2, 2], -2274.0, -0.2, 977.0, -0.5),
    ([0, 0, 0, 0, 2], 2062.0, 0.2, -895.0, 0.5),
    ([0, 1, 0, 0, 0], 1426.0, -3.4, 54.0, -0.1),
    ([0, 0, 1, 0, 0], 712.0, 0.1, -7.0, 0.0),
    ([-2, 1, 0, 2, 2], -517.0, 1.2, 224.0, -0.6),
    ([0, 0, 0, 2, 1], -386.0, -0.4, 200.0, 0.0),
    ([0, 0, 1, 2, 2], -301.0, 0.0, 129.0, -0.1),
    ([-2, -1, 0, 2, 2], 217.0, -0.5, -95.0, 0.3),
    ([-2, 0, 1, 0, 0], -158.0, 0.0, 0.0, 0.0),
    ([-2, 0, 0, 2, 1], 129.0, 0.1, -70.0, 0.0),
    ([0, 0, -1, 2, 2], 123.0, 0.0, -53.0, 0.0),
    ([2, 0, 0, 0, 0], 63.0, 0.0, 0.0, 0.0),
    ([0, 0, 1, 0, 1], 63.0, 0.1, -33.0, 0.0),
    ([2, 0, -1, 2, 2], -59.0, 0.0, 26.0, 0.0),
    ([0, 0, -1, 0, 1], -58.0, -0.1, 32.0, 0.0),
    ([0, 0, 1, 2, 1], -51.0, 0.0, 27.0, 0.0),
    ([-2, 0, 2, 0, 0], 48.0, 0.0, 0.0, 0.0),
    ([0, 0, -2, 2, 1], 46.0, 0.0, -24.0, 0.0),
    ([2, 0, 0, 2, 2], -38.0, 0.0, 16.0, 0.0),
    ([0, 0, 2, 2, 2], -31.0, 0.0, 13.0, 0.0),
    ([0, 0, 2, 0, 0], 29.0, 0.0, 0.0, 0.0),
    ([-2, 0, 1, 2, 2], 29.0, 0.0, -12.0, 0.0),
    ([0, 0, 0, 2, 0], 26.0, 0.0, 0.0, 0.0),
    ([-2, 0, 0, 2, 0], -22.0, 0.0, 0.0, 0.0),
    ([0, 0, -1, 2, 1], 21.0, 0.0, -10.0, 0.0),
    ([0, 2, 0, 0, 0], 17.0, -0.1, 0.0, 0.0),
    ([2, 0, -1, 0, 1], 16.0, 0.0, -8.0, 0.0),
    ([-2, 2, 0, 2, 2], -16.0, 0.1, 7.0, 0.0),
    ([0, 1, 0, 0, 1], -15.0, 0.0, 9.0, 0.0),
    ([-2, 0, 1, 0, 1], -13.0, 0.0, 7.0, 0.0),
    ([0, -1, 0, 0, 1], -12.0, 0.0, 6.0, 0.0),
    ([0, 0, 2, -2, 0], 11.0, 0.0, 0.0, 0.0),
];

/// The nutation at a Julian Date in TT.
pub fn nutation(jd_tt: f64) -> Nutation {
    let t = centuries_tt(jd_tt);
    let t2 = t * t;
    let t3 = t2 * t;
    let args = [
        297.850_36 + 445_267.111_480 * t - 0.001_914_2 * t2 + t3 / 189_474.0,
        357.527_72 + 35_999.050_340 * t - 0.000_160_3 * t2 - t3 / 300_000.0,
        134.962_98 + 477_198.867_398 * t + 0.008_697_2 * t2 + t3 / 56_250.0,
        93.271_91 + 483_202.017_538 * t - 0.003_682_5 * t2 + t3 / 327_270.0,
        125.044_52 - 1_934.136_261 * t + 0.002_070_8 * t2 + t3 / 450_000.0,
    ]
    .map(|a: f64| a.rem_euclid(360.0).to_radians());
    let (mut dpsi, mut deps) = (0.0, 0.0);
    for (k, s, st, c, ct) in TERMS {
        let arg: f64 = k.iter().zip(args).map(|(&k, a)| k as f64 * a).sum();
        dpsi += (s + st * t) * fmath::sin(arg);
        deps += (c + ct * t) * fmath::cos(arg);
    }
    Nutation { dpsi: dpsi * 1e-4 * ARCSEC, deps: deps * 1e-4 * ARCSEC, mean_obliquity: mean_obliquity_rad(jd_tt) }
}

impl Nutation {
    /// The true obliquity of the ecliptic of date, radians.
    pub fn true_obliquity(&self) -> f64 {
        self.mean_obliquity + self.deps
    }

    /// The rotation from the mean to the true equator and equinox of date.
    pub fn matrix(&self) -> DMat3 {
        r1(-self.true_obliquity()) * r3(-self.dpsi) * r1(self.mean_obliquity)
    }

    /// The equation of the equinoxes (IAU 1994, with its two small terms
    /// in the Moon's node): GAST - GMST, radians.
    pub fn equation_of_equinoxes(&self, jd_tt: f64) -> f64 {
        let t = centuries_tt(jd_tt);
        let om = (125.044_52 - 1_934.136_261 * t).to_radians();
        self.dpsi * fmath::cos(self.mean_obliquity) + (0.002_64 * fmath::sin(om) + 0.000_063 * fmath::sin(2.0 * om)) * ARCSEC
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meeus_example_22a() {
        // 1987 April 10 0h TD: dpsi = -3.788", deps = +9.443",
        // eps = 23d26'36.850".
        let n = nutation(2_446_895.5);
        assert!((n.dpsi / ARCSEC + 3.788).abs() < 0.002, "{}", n.dpsi / ARCSEC);
        assert!((n.deps / ARCSEC - 9.443).abs() < 0.002, "{}", n.deps / ARCSEC);
        assert!((n.true_obliquity() / ARCSEC - 84_396.850).abs() < 0.002);
    }

    #[test]
    fn matrix_moves_the_equinox_by_dpsi_along_the_ecliptic() {
        use glam::DVec3;
        let n = nutation(2_461_000.5);
        let moved = n.matrix() * DVec3::X;
        // The mean equinox seen in the true frame: longitude +dpsi (a
        // fixed direction's apparent longitude is its mean one plus dpsi).
        let ra = fmath::atan2(moved.y, moved.x);
        assert!((ra - n.dpsi * fmath::cos(n.true_obliquity())).abs() < 1e-3 * ARCSEC, "{ra}");
    }
}
