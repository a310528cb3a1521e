//! The frame rotations of the IAU/SOFA conventions.
//!
//! **Model.** `r1(a)`, `r2(a)`, `r3(a)` rotate the *frame* by `a` radians
//! anticlockwise about its x, y and z axes, seen from the axis' tip; a
//! vector's components in the new frame are `r * v` (SOFA's `iauRx`,
//! `iauRy`, `iauRz`; Kaplan 2005, "The IAU Resolutions on Astronomical
//! Reference Systems...", USNO Circular 179, section 6). Each is the active
//! rotation by `-a`.

use crate::util::fmath;
use glam::{DMat3, DVec3};

/// The frame rotation about x by `a` radians.
pub fn r1(a: f64) -> DMat3 {
    DMat3::from_rotation_x(-a)
}

/// The frame rotation about y by `a` radians.
pub fn r2(a: f64) -> DMat3 {
    DMat3::from_rotation_y(-a)
}

/// The frame rotation about z by `a` radians.
pub fn r3(a: f64) -> DMat3 {
    DMat3::from_rotation_z(-a)
}

/// Radians per arcsecond.
pub const ARCSEC: f64 = std::f64::consts::PI / 648_000.0;

/// The unit vector of an ecliptic longitude and latitude (radians) in the
/// equatorial frame of an obliquity (radians).
pub fn equatorial_from_ecliptic(longitude: f64, latitude: f64, obliquity: f64) -> DVec3 {
    let (sl, cl) = fmath::sin_cos(longitude);
    let (sb, cb) = fmath::sin_cos(latitude);
    let (se, ce) = fmath::sin_cos(obliquity);
    let (x, y, z) = (cb * cl, cb * sl, sb);
    DVec3::new(x, y * ce - z * se, y * se + z * ce)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rotation_moves_the_axis_backwards() {
        // Rotating the frame by +90 degrees about z: the old x axis is at
        // -y in the new frame.
        let v = r3(std::f64::consts::FRAC_PI_2) * DVec3::X;
        assert!((v - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-15);
        let v = r1(std::f64::consts::FRAC_PI_2) * DVec3::Y;
        assert!((v - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-15);
        let v = r2(std::f64::consts::FRAC_PI_2) * DVec3::Z;
        assert!((v - DVec3::new(-1.0, 0.0, 0.0)).length() < 1e-15);
    }
}
