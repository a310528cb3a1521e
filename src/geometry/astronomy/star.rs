//! A star's catalogue place moved to an instant: space motion and annual
//! parallax, giving its astrometric direction from the Earth (ICRS axes).
//!
//! **Model.** The catalogue entry (right ascension, declination, proper
//! motion in both, `mu_alpha* = mu_alpha cos delta`, parallax, at a Julian
//! epoch; Hipparcos-2, van Leeuwen 2007, is J1991.25 in the ICRS) is a
//! point at distance `1 / sin(parallax)` AU moving on a straight line at
//! the transverse velocity of its proper motion (the radial velocity,
//! absent from Hipparcos, taken as zero): rigorous 3-D space motion
//! (Kaplan 2005, USNO Circular 179, section 3.2; the Explanatory
//! Supplement to the Astronomical Almanac, 3rd ed., section 7.2.2.1), with
//! time in Julian years of TT. The Earth's heliocentric position
//! (`earth_orbit`) is taken off: annual parallax, 0.75" at most. A star of
//! no or negative parallax is put at a gigaparsec (parallax 1e-6 mas) as
//! skyfield does.

use super::time::Utc;
use crate::util::fmath;
use glam::DVec3;

/// Radians per milliarcsecond.
const MAS: f64 = std::f64::consts::PI / 648_000_000.0;

/// A star's catalogue place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StarPlace {
    /// Right ascension at the epoch, ICRS, degrees.
    pub ra_deg: f64,
    /// Declination at the epoch, ICRS, degrees.
    pub dec_deg: f64,
    /// Proper motion in right ascension times cos(declination), mas a year.
    pub pm_ra_cosdec_mas_yr: f64,
    /// Proper motion in declination, mas a year.
    pub pm_dec_mas_yr: f64,
    /// Parallax, mas.
    pub parallax_mas: f64,
    /// The epoch of the place, Julian year (TT): 1991.25 for Hipparcos.
    pub epoch_jyear: f64,
}

impl StarPlace {
    /// The star's position relative to the barycentre at the epoch, AU, and
    /// its velocity, AU a Julian year.
    pub fn position_velocity_au(&self) -> (DVec3, DVec3) {
        let plx = if self.parallax_mas > 0.0 { self.parallax_mas } else { 1e-6 };
        let dist = 1.0 / fmath::sin(plx * MAS);
        let (sa, ca) = fmath::sin_cos(self.ra_deg.to_radians());
        let (sd, cd) = fmath::sin_cos(self.dec_deg.to_radians());
        let unit = DVec3::new(cd * ca, cd * sa, sd);
        let east = DVec3::new(-sa, ca, 0.0);
        let north = DVec3::new(-sd * ca, -sd * sa, cd);
        // mas a year over mas of parallax is AU a year.
        let velocity = (self.pm_ra_cosdec_mas_yr * east + self.pm_dec_mas_yr * north) / plx;
        (unit * dist, velocity)
    }

    /// The star's barycentric position at a Julian Date in TT, AU.
    pub fn barycentric_au(&self, jd_tt: f64) -> DVec3 {
        let (p, v) = self.position_velocity_au();
        let years = (jd_tt - 2_451_545.0) / 365.25 - (self.epoch_jyear - 2000.0);
        p + v * years
    }

    /// The astrometric direction (ICRS axes) from an observer at
    /// `observer_au` from the barycentre, at a Julian Date in TT.
    pub fn direction_from(&self, jd_tt: f64, observer_au: DVec3) -> DVec3 {
        (self.barycentric_au(jd_tt) - observer_au).normalize()
    }

    /// The astrometric direction from the Earth's centre at an instant:
    /// space motion from the epoch and annual parallax.
    pub fn icrs_direction_at(&self, t: Utc) -> DVec3 {
        let jd_tt = t.jd_tt();
        let (earth_au, _) = super::earth_orbit::earth_position_velocity(jd_tt);
        self.direction_from(jd_tt, earth_au)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barnards_star_moves_its_proper_motion() {
        // Barnard's star (Hipparcos-2 HIP 87937): -802.8 and 10362.5 mas a
        // year, parallax 548.3 mas. After 10 years, with no radial
        // velocity, it has moved 10 x 10.3935" along the sky (to first
        // order; the second is micro-arcseconds here).
        let s = StarPlace {
            ra_deg: 269.454_022,
            dec_deg: 4.668_288,
            pm_ra_cosdec_mas_yr: -802.8,
            pm_dec_mas_yr: 10_362.5,
            parallax_mas: 548.31,
            epoch_jyear: 1991.25,
        };
        let jd0 = 2_451_545.0 - 8.75 * 365.25;
        let d0 = s.direction_from(jd0, DVec3::ZERO);
        let d1 = s.direction_from(jd0 + 3652.5, DVec3::ZERO);
        let moved_mas = d0.angle_between(d1) / MAS;
        let pm = fmath::hypot(s.pm_ra_cosdec_mas_yr, s.pm_dec_mas_yr);
        assert!((moved_mas - 10.0 * pm).abs() < 1.0, "{moved_mas}");
        // At the epoch from the barycentre: the catalogue's place.
        let dec = fmath::asin(d0.z).to_degrees();
        assert!((dec - s.dec_deg).abs() < 1e-12);
    }

    #[test]
    fn parallax_is_at_most_the_catalogues() {
        let s = StarPlace {
            ra_deg: 219.9,
            dec_deg: -60.8,
            pm_ra_cosdec_mas_yr: 0.0,
            pm_dec_mas_yr: 0.0,
            parallax_mas: 750.0,
            epoch_jyear: 2000.0,
        };
        for day in (0..365).step_by(30) {
            let t = Utc::from_jd_utc(2_461_000.5 + day as f64);
            let shift = s.icrs_direction_at(t).angle_between(s.direction_from(t.jd_tt(), DVec3::ZERO)) / MAS;
            assert!(shift < 770.0, "{shift}");
        }
    }
}
