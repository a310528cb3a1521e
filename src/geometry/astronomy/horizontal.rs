//! Horizontal coordinates: azimuth and elevation of a direction in a
//! site's east-north-up frame, and back.
//!
//! **Model.** Azimuth is measured from north through east (0 north, 90
//! east), in `[0, 360)`; elevation from the horizontal plane, positive up
//! (Meeus, "Astronomical Algorithms", 2nd ed., ch. 13, with azimuth from
//! north as navigators and skyfield count it, not Meeus' from south):
//! for a unit vector `(x, y, z)`, `az = atan2(x, y)`, `el = asin(z)`.

use crate::util::fmath;
use glam::DVec3;

/// Azimuth (from north through east, `[0, 360)`) and elevation of an ENU
/// direction, degrees; the vector need not be unit.
pub fn az_el_deg(enu: DVec3) -> (f64, f64) {
    let horizontal = fmath::hypot(enu.x, enu.y);
    let az = fmath::atan2(enu.x, enu.y).to_degrees().rem_euclid(360.0);
    (if az >= 360.0 { 0.0 } else { az }, fmath::atan2(enu.z, horizontal).to_degrees())
}

/// The unit ENU vector of an azimuth and elevation, degrees.
pub fn enu_from_az_el_deg(az_deg: f64, el_deg: f64) -> DVec3 {
    let (sa, ca) = fmath::sin_cos(az_deg.to_radians());
    let (se, ce) = fmath::sin_cos(el_deg.to_radians());
    DVec3::new(ce * sa, ce * ca, se)
}

/// The angle between two directions, degrees (robust for small angles:
/// `atan2(|a x b|, a . b)`).
pub fn separation_deg(a: DVec3, b: DVec3) -> f64 {
    fmath::atan2(a.cross(b).length(), a.dot(b)).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cardinal_points_and_round_trip() {
        assert_eq!(az_el_deg(DVec3::Y), (0.0, 0.0));
        assert!((az_el_deg(DVec3::X).0 - 90.0).abs() < 1e-12);
        assert!((az_el_deg(-DVec3::X).0 - 270.0).abs() < 1e-12);
        assert!((az_el_deg(DVec3::Z).1 - 90.0).abs() < 1e-12);
        for (az, el) in [(10.0, 20.0), (200.0, -5.0), (359.5, 80.0)] {
            let v = enu_from_az_el_deg(az, el);
            let (a, e) = az_el_deg(v * 3.0);
            assert!((a - az).abs() < 1e-9 && (e - el).abs() < 1e-9, "{a} {e}");
        }
        let s = separation_deg(enu_from_az_el_deg(0.0, 0.0), enu_from_az_el_deg(0.0, 1e-6));
        assert!((s - 1e-6).abs() < 1e-15);
    }
}
