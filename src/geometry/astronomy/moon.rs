//! The Moon: its geocentric place by Meeus' truncated ELP-2000/82, its
//! topocentric direction, distance and phase.
//!
//! **Model.** Meeus, "Astronomical Algorithms", 2nd ed., ch. 47: the
//! periodic terms of tables 47.A (longitude and distance, 60 terms) and
//! 47.B (latitude, 60 terms) of Chapront-Touze and Chapront's ELP-2000/82,
//! with the additive terms of Venus (A1), Jupiter (A2) and the Earth's
//! flattening (A3), the terms in M multiplied by the eccentricity factor
//! `E = 1 - 0.002516 t - 0.0000074 t^2` (E^2 for 2M). Meeus gives its
//! accuracy as 10" in longitude and 4" in latitude. The geometric longitude
//! (mean equinox of date) plus the nutation in longitude is the apparent
//! longitude; it and the latitude are turned to the true equator with the
//! true obliquity, to the Earth-fixed frame by sidereal time, and the
//! site's position taken off: the topocentric parallax, up to 1 degree,
//! is exact in vector form ([`moon_view`]).
//!
//! The **phase** is Meeus ch. 48 from the geocentric positions: the phase
//! angle i is the angle at the Moon between the Sun and the Earth, the
//! illuminated fraction `k = (1 + cos i) / 2` (eq. 48.1). The bright limb
//! points from the Moon's centre towards the Sun: the Sun's topocentric
//! direction with its part along the Moon's taken off. The angular radius
//! is that of the Moon's mean radius, 1737.4 km (IAU WGCCRE 2015), at the
//! topocentric distance.

use super::frame::SkyFrame;
use super::rotation::equatorial_from_ecliptic;
use super::sun::sun_apparent_tod_km;
use crate::util::fmath;
use glam::DVec3;

/// The Moon's mean radius, km.
pub const MOON_RADIUS_KM: f64 = 1737.4;

/// The Moon's geocentric place, ecliptic and mean equinox of date
/// (geometric: nutation not added).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoonPlace {
    /// Longitude, degrees in `[0, 360)`.
    pub longitude_deg: f64,
    /// Latitude, degrees.
    pub latitude_deg: f64,
    /// Distance between the centres of the Earth and the Moon, km.
    pub distance_km: f64,
}

/// The Moon as seen from a site.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoonView {
    /// Topocentric apparent direction, ENU unit vector, unrefracted.
    pub enu: DVec3,
    /// Topocentric distance, km (geometric: the Moon now, not 1.3 s of
    /// light time ago).
    pub distance_km: f64,
    /// The fraction of the disc that is lit, 0 (new) to 1 (full).
    pub illuminated_fraction: f64,
    /// The angle Sun-Moon-Earth, degrees.
    pub phase_angle_deg: f64,
    /// Unit vector perpendicular to `enu`, from the Moon's centre towards
    /// the Sun's side of the sky: the side that is lit.
    pub bright_limb_enu: DVec3,
    /// The apparent radius of the disc, degrees.
    pub angular_radius_deg: f64,
}

/// Table 47.A: multiples of D, M, M', F; the coefficients of sin (longitude,
/// 1e-6 degree) and cos (distance, 0.001 km).
#[rustfmt::skip]
const LONGITUDE_DISTANCE: [([i8; 4], f64, f64); 60] = [
    ([0, 0, 1, 0], 6288774.0, -20905355.0),
    ([2, 0, -1, 0], 1274027.0, -3699111.0),
    ([2, 0, 0, 0], 658314.0, -2955968.0),
    ([0, 0, 2, 0], 213618.0, -569925.0),
    ([0, 1, 0, 0], -185116.0, 48888.0),
    ([0, 0, 0, 2], -114332.0, -3149.0),
    ([2, 0, -2, 0], 58793.0, 246158.0),
    ([2, -1, -1, 0], 57066.0, -152138.0),
    ([2, 0, 1, 0], 53322.0, -170733.0),
    ([2, -1, 0, 0], 45758.0, -204586.0),
    ([0, 1, -1, 0], -40923.0, -129620.0),
    ([1, 0, 0, 0], -34720.0, 108743.0),
    ([0, 1, 1, 0], -30383.0, 104755.0),
    ([2, 0, 0, -2], 15327.0, 10321.0),
    ([0, 0, 1, 2], -12528.0, 0.0),
    ([0, 0, 1, -2], 10980.0, 79661.0),
    ([4, 0, -1, 0], 10675.0, -34782.0),
    ([0, 0, 3, 0], 10034.0, -23210.0),
    ([4, 0, -2, 0], 8548.0, -21636.0),
    ([2, 1, -1, 0], -7888.0, 24208.0),
    ([2, 1, 0, 0], -6766.0, 30824.0),
    ([1, 0, -1, 0], -5163.0, -8379.0),
    ([1, 1, 0, 0], 4987.0, -16675.0),
    ([2, -1, 1, 0], 4036.0, -12831.0),
    ([2, 0, 2, 0], 3994.0, -10445.0),
    ([4, 0, 0, 0], 3861.0, -11650.0),
    ([2, 0, -3, 0], 3665.0, 14403.0),
    ([0, 1, -2, 0], -2689.0, -7003.0),
    ([2, 0, -1, 2], -2602.0, 0.0),
    ([2, -1, -2, 0], 2390.0, 10056.0),
    ([1, 0, 1, 0], -2348.0, 6322.0),
    ([2, -2, 0, 0], 2236.0, -9884.0),
    ([0, 1, 2, 0], -2120.0, 5751.0),
    ([0, 2, 0, 0], -2069.0, 0.0),
    ([2, -2, -1, 0], 2048.0, -4950.0),
    ([2, 0, 1, -2], -1773.0, 4130.0),
    ([2, 0, 0, 2], -1595.0, 0.0),
    ([4, -1, -1, 0], 1215.0, -3958.0),
    ([0, 0, 2, 2], -1110.0, 0.0),
    ([3, 0, -1, 0], -892.0, 3258.0),
    ([2, 1, 1, 0], -810.0, 2616.0),
    ([4, -1, -2, 0], 759.0, -1897.0),
    ([0, 2, -1, 0], -713.0, -2117.0),
    ([2, 2, -1, 0], -700.0, 2354.0),
    ([2, 1, -2, 0], 691.0, 0.0),
    ([2, -1, 0, -2], 596.0, 0.0),
    ([4, 0, 1, 0], 549.0, -1423.0),
    ([0, 0, 4, 0], 537.0, -1117.0),
    ([4, -1, 0, 0], 520.0, -1571.0),
    ([1, 0, -2, 0], -487.0, -1739.0),
    ([2, 1, 0, -2], -399.0, 0.0),
    ([0, 0, 2, -2], -381.0, -4421.0),
    ([1, 1, 1, 0], 351.0, 0.0),
    ([3, 0, -2, 0], -340.0, 0.0),
    ([4, 0, -3, 0], 330.0, 0.0),
    ([2, -1, 2, 0], 327.0, 0.0),
    ([0, 2, 1, 0], -323.0, 1165.0),
    ([1, 1, -1, 0], 299.0, 0.0),
    ([2, 0, 3, 0], 294.0, 0.0),
    ([2, 0, -1, -2], 0.0, 8752.0),
];

/// Table 47.B: multiples of D, M, M', F; the coefficient of sin (latitude,
/// 1e-6 degree).
#[rustfmt::skip]
const LATITUDE: [([i8; 4], f64); 60] = [
    ([0, 0, 0, 1], 5128122.0),
    ([0, 0, 1, 1], 280602.0),
    ([0, 0, 1, -1], 277693.0),
    ([2, 0, 0, -1], 173237.0),
    ([2, 0, -1, 1], 55413.0),
    ([2, 0, -1, -1], 46271.0),
    ([2, 0, 0, 1], 32573.0),
    ([0, 0, 2, 1], 17198.0),
    ([2, 0, 1, -1], 9266.0),
    ([0, 0, 2, -1], 8822.0),
    ([2, -1, 0, -1], 8216.0),
    ([2, 0, -2, -1], 4324.0),
    ([2, 0, 1, 1], 4200.0),
    ([2, 1, 0, -1], -3359.0),
    ([2, -1, -1, 1], 2463.0),
    ([2, -1, 0, 1], 2211.0),
    ([2, -1, -1, -1], 2065.0),
    ([0, 1, -1, -1], -1870.0),
    ([4, 0, -1, -1], 1828.0),
    ([0, 1, 0, 1], -1794.0),
    ([0, 0, 0, 3], -1749.0),
    ([0, 1, -1, 1], -1565.0),
    ([1, 0, 0, 1], -1491.0),
    ([0, 1, 1, 1], -1475.0),
    ([0, 1, 1, -1], -1410.0),
    ([0, 1, 0, -1], -1344.0),
    ([1, 0, 0, -1], -1335.0),
    ([0, 0, 3, 1], 1107.0),
    ([4, 0, 0, -1], 1021.0),
    ([4, 0, -1, 1], 833.0),
    ([0, 0, 1, -3], 777.0),
    ([4, 0, -2, 1], 671.0),
    ([2, 0, 0, -3], 607.0),
    ([2, 0, 2, -1], 596.0),
    ([2, -1, 1, -1], 491.0),
    ([2, 0, -2, 1], -451.0),
    ([0, 0, 3, -1], 439.0),
    ([2, 0, 2, 1], 422.0),
    ([2, 0, -3, -1], 421.0),
    ([2, 1, -1, 1], -366.0),
    ([2, 1, 0, 1], -351.0),
    ([4, 0, 0, 1], 331.0),
    ([2, -1, 1, 1], 315.0),
    ([2, -2, 0, -1], 302.0),
    ([0, 0, 1, 3], -283.0),
    ([2, 1, 1, -1], -229.0),
    ([1, 1, 0, -1], 223.0),
    ([1, 1, 0, 1], 223.0),
    ([0, 1, -2, -1], -220.0),
    ([2, 1, -1, -1], -220.0),
    ([1, 0, 1, 1], -185.0),
    ([2, -1, -2, -1], 181.0),
    ([0, 1, 2, 1], -177.0),
    ([4, 0, -2, -1], 176.0),
    ([4, -1, -1, -1], 166.0),
    ([1, 0, 1, -1], -164.0),
    ([4, 0, 1, -1], 132.0),
    ([1, 0, -1, -1], -119.0),
    ([4, -1, 0, -1], 115.0),
    ([2, -2, 0, 1], 107.0),
];

/// The Moon's geometric place at a Julian Date in TT (Meeus ch. 47).
pub fn moon_place(jd_tt: f64) -> MoonPlace {
    let t = (jd_tt - 2_451_545.0) / 36_525.0;
    let (t2, t3, t4) = (t * t, t * t * t, t * t * t * t);
    let lp = 218.316_447_7 + 481_267.881_234_21 * t - 0.001_578_6 * t2 + t3 / 538_841.0 - t4 / 65_194_000.0;
    let d = 297.850_192_1 + 445_267.111_403_4 * t - 0.001_881_9 * t2 + t3 / 545_868.0 - t4 / 113_065_000.0;
    let m = 357.529_109_2 + 35_999.050_290_9 * t - 0.000_153_6 * t2 + t3 / 24_490_000.0;
    let mp = 134.963_396_4 + 477_198.867_505_5 * t + 0.008_741_4 * t2 + t3 / 69_699.0 - t4 / 14_712_000.0;
    let f = 93.272_095_0 + 483_202.017_523_3 * t - 0.003_653_9 * t2 - t3 / 3_526_000.0 + t4 / 863_310_000.0;
    let a1 = 119.75 + 131.849 * t;
    let a2 = 53.09 + 479_264.290 * t;
    let a3 = 313.45 + 481_266.484 * t;
    let e = 1.0 - 0.002_516 * t - 0.000_007_4 * t2;
    let sin = |deg: f64| fmath::sin(deg.rem_euclid(360.0).to_radians());
    let cos = |deg: f64| fmath::cos(deg.rem_euclid(360.0).to_radians());
    let factor = |k: i8| match k.abs() {
        1 => e,
        2 => e * e,
        _ => 1.0,
    };
    let args = [d, m, mp, f];
    let argument = |k: &[i8; 4]| k.iter().zip(args).map(|(&k, a)| k as f64 * a).sum::<f64>();
    let (mut sl, mut sr) = (0.0, 0.0);
    for (k, l, r) in &LONGITUDE_DISTANCE {
        let (arg, fe) = (argument(k), factor(k[1]));
        sl += l * fe * sin(arg);
        sr += r * fe * cos(arg);
    }
    let mut sb = 0.0;
    for (k, b) in &LATITUDE {
        sb += b * factor(k[1]) * sin(argument(k));
    }
    sl += 3958.0 * sin(a1) + 1962.0 * sin(lp - f) + 318.0 * sin(a2);
    sb += -2235.0 * sin(lp) + 382.0 * sin(a3) + 175.0 * sin(a1 - f) + 175.0 * sin(a1 + f) + 127.0 * sin(lp - mp) - 115.0 * sin(lp + mp);
    MoonPlace { longitude_deg: (lp + sl * 1e-6).rem_euclid(360.0), latitude_deg: sb * 1e-6, distance_km: 385_000.56 + sr * 1e-3 }
}

/// The Moon's apparent geocentric position, km, true equator and equinox
/// of date of the frame's instant.
pub fn moon_apparent_tod_km(frame: &SkyFrame) -> DVec3 {
    let place = moon_place(frame.jd_tt());
    let n = frame.nutation();
    let lambda = place.longitude_deg.to_radians() + n.dpsi;
    equatorial_from_ecliptic(lambda, place.latitude_deg.to_radians(), n.true_obliquity()) * place.distance_km
}

/// The phase angle (Sun-Moon-Earth), radians, of the geocentric positions
/// of the Moon and the Sun (any one frame).
pub fn phase_angle_rad(moon_km: DVec3, sun_km: DVec3) -> f64 {
    (sun_km - moon_km).angle_between(-moon_km)
}

/// The illuminated fraction of a phase angle, radians (Meeus eq. 48.1).
pub fn illuminated_fraction(phase_angle_rad: f64) -> f64 {
    0.5 * (1.0 + fmath::cos(phase_angle_rad))
}

/// The Moon seen from the frame's site at its instant.
pub fn moon_view(frame: &SkyFrame) -> MoonView {
    let moon_tod = moon_apparent_tod_km(frame);
    let sun_tod = sun_apparent_tod_km(frame);
    let topo = frame.enu_from_tod_topocentric(moon_tod);
    let distance_km = topo.length();
    let enu = topo / distance_km;
    let sun_enu = frame.enu_from_tod_topocentric(sun_tod).normalize();
    let bright = sun_enu - sun_enu.dot(enu) * enu;
    let bright_limb_enu = if bright.length() > 1e-12 { bright.normalize() } else { enu.any_orthonormal_vector() };
    let i = phase_angle_rad(moon_tod, sun_tod);
    MoonView {
        enu,
        distance_km,
        illuminated_fraction: illuminated_fraction(i),
        phase_angle_deg: i.to_degrees(),
        bright_limb_enu,
        angular_radius_deg: fmath::asin(MOON_RADIUS_KM / distance_km).to_degrees(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meeus_example_47a() {
        // 1992 April 12 0h TD: lambda 133.162655, beta -3.229126,
        // distance 368409.7 km.
        let p = moon_place(2_448_724.5);
        assert!((p.longitude_deg - 133.162_655).abs() < 2e-6, "{}", p.longitude_deg);
        assert!((p.latitude_deg + 3.229_126).abs() < 2e-6, "{}", p.latitude_deg);
        assert!((p.distance_km - 368_409.7).abs() < 0.1, "{}", p.distance_km);
    }

    #[test]
    fn meeus_example_48a() {
        // 1992 April 12 0h TD: the Sun (Meeus' ch. 25 higher accuracy)
        // at lambda0 22.33978 (apparent), R = 1.002 481 AU, and the Moon
        // of Example 47.a: i = 69.0756 degrees, k = 0.6786. With the Sun
        // of ch. 25's lower accuracy the fraction agrees to 0.0005.
        use super::super::earth_orbit::{sun_place, AU_KM};
        let jde = 2_448_724.5;
        let m = moon_place(jde);
        let s = sun_place(jde);
        let moon = equatorial_from_ecliptic(m.longitude_deg.to_radians(), m.latitude_deg.to_radians(), 0.409) * m.distance_km;
        let sun = equatorial_from_ecliptic(s.longitude_deg.to_radians(), 0.0, 0.409) * s.distance_au * AU_KM;
        let i = phase_angle_rad(moon, sun);
        assert!((illuminated_fraction(i) - 0.6786).abs() < 5e-4, "{}", illuminated_fraction(i));
        assert!((i.to_degrees() - 69.0756).abs() < 0.05, "{}", i.to_degrees());
    }
}
