//! Sidereal time: the angle of the Earth's rotation from the equinox.
//!
//! **Model.** Greenwich mean sidereal time, IAU 1982 (Aoki et al. 1982,
//! A&A 105, 359), in the form of Meeus, "Astronomical Algorithms", 2nd
//! ed., eq. 12.4, with T in Julian centuries of UT1 from J2000:
//!
//! ```text
//! GMST = 280.46061837 + 360.98564736629 (JD - 2451545) + 0.000387933 T^2
//!        - T^3 / 38710000   (degrees)
//! ```
//!
//! and Greenwich apparent sidereal time `GAST = GMST + equation of the
//! equinoxes` (`crate::geometry::astronomy::nutation`). The pair agrees
//! with IAU 2006's ERA-based GAST to a few milliarcseconds near J2000
//! (the difference is the rate of precession in right ascension,
//! 0.3" a century at most). UT1 is taken as UTC (`time`).

/// Greenwich mean sidereal time at a Julian Date in UT1, radians in
/// `[0, 2 pi)`.
pub fn gmst_rad(jd_ut1: f64) -> f64 {
    let d = jd_ut1 - 2_451_545.0;
    let t = d / 36_525.0;
    // The whole days' turns are dropped first: 360.98564736629 d =
    // 360 d + 0.98564736629 d, and 360 d is whole turns.
    let deg = 280.460_618_37 + 0.985_647_366_29 * d + 360.0 * d.fract() + 0.000_387_933 * t * t - t * t * t / 38_710_000.0;
    deg.rem_euclid(360.0).to_radians()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meeus_examples_12a_and_12b() {
        // 1987 April 10 0h UT: 13h10m46.3668s = 197.693195 degrees.
        let g = gmst_rad(2_446_895.5).to_degrees();
        assert!((g - 197.693_195).abs() < 1e-6, "{g}");
        // 1987 April 10 19h21m00s UT: 128.7378734 degrees.
        let g = gmst_rad(2_446_896.306_25).to_degrees();
        assert!((g - 128.737_873_4).abs() < 1e-6, "{g}");
        // J2000.0 (IAU 1982): 18h41m50.54841s = 280.46061837 degrees.
        assert!((gmst_rad(2_451_545.0).to_degrees() - 280.460_618_37).abs() < 1e-9);
    }
}
