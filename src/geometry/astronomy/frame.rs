//! A site's sky at an instant: the rotation from the GCRS to the site's
//! east-north-up frame, and annual aberration.
//!
//! **Model.** The classical equinox-based chain of the IAU 1976/1980/1982
//! system (Kaplan 2005, USNO Circular 179, ch. 6; SOFA's `iauPnm80`,
//! `iauGst94`), with IAU 2000's frame bias:
//!
//! ```text
//! enu = E(site) r3(GAST) N P B gcrs
//! ```
//!
//! - B: frame bias, P: IAU 1976 precession (`precession`);
//! - N: IAU 1980 nutation, truncated to its 0.001" terms (`nutation`);
//! - GAST: IAU 1982 GMST plus the equation of the equinoxes (`sidereal`),
//!   from UT1 taken as UTC (`time`): up to 0.9 s, 13" of the sky's
//!   rotation;
//! - polar motion is neglected (under 0.5", IERS Bulletin A): the
//!   terrestrial intermediate frame is the ITRS;
//! - E: the site's geodetic east, north and up (`site`).
//!
//! Directions of stars are first moved by annual aberration, `u' =
//! normalise(u + v/c)` with v the Earth's velocity (`earth_orbit`; first
//! order in v/c: the second order is 0.002"). Diurnal aberration (the
//! site's speed about the axis, 0.32" at most) and the Sun's light
//! deflection (under 0.01" more than 20 degrees from the Sun) are
//! neglected. With skyfield (IAU 2006/2000A, measured UT1, deflection,
//! diurnal aberration) as the oracle, the above sum to 15" at most, most
//! of it UT1; 1.4" is measured (`tests/sky`).

use super::earth_orbit::earth_position_velocity;
use super::nutation::{nutation, Nutation};
use super::precession::mean_of_date_from_gcrs;
use super::rotation::r3;
use super::sidereal::gmst_rad;
use super::site::Site;
use super::time::Utc;
use glam::{DMat3, DVec3};

/// The rotation of the GCRS onto a site's sky at an instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyFrame {
    site: Site,
    utc: Utc,
    jd_tt: f64,
    nutation: Nutation,
    gast_rad: f64,
    tod_from_gcrs: DMat3,
    itrs_from_tod: DMat3,
    enu_from_itrs: DMat3,
    enu_from_gcrs: DMat3,
    site_itrs_km: DVec3,
    earth_position_au: DVec3,
    earth_velocity_c: DVec3,
}

impl SkyFrame {
    /// The frame of a site at an instant.
    pub fn new(site: &Site, t: Utc) -> SkyFrame {
        let jd_tt = t.jd_tt();
        let nutation = nutation(jd_tt);
        let gast_rad = (gmst_rad(t.jd_ut1()) + nutation.equation_of_equinoxes(jd_tt)).rem_euclid(std::f64::consts::TAU);
        let tod_from_gcrs = nutation.matrix() * mean_of_date_from_gcrs(jd_tt);
        let itrs_from_tod = r3(gast_rad);
        let enu_from_itrs = site.enu_from_itrs();
        let (earth_position_au, earth_velocity_c) = earth_position_velocity(jd_tt);
        SkyFrame {
            site: *site,
            utc: t,
            jd_tt,
            nutation,
            gast_rad,
            tod_from_gcrs,
            itrs_from_tod,
            enu_from_itrs,
            enu_from_gcrs: enu_from_itrs * itrs_from_tod * tod_from_gcrs,
            site_itrs_km: site.itrs_km(),
            earth_position_au,
            earth_velocity_c,
        }
    }

    /// The apparent, unrefracted direction in the site's ENU frame of an
    /// ICRS (astrometric, barycentric or geocentric) unit direction:
    /// annual aberration, then the rotation.
    pub fn apparent_enu(&self, icrs_unit: DVec3) -> DVec3 {
        (self.enu_from_gcrs * (icrs_unit + self.earth_velocity_c).normalize()).normalize()
    }

    /// The rotation from the GCRS to the site's ENU frame.
    pub fn enu_from_gcrs_matrix(&self) -> DMat3 {
        self.enu_from_gcrs
    }

    /// The rotation from the GCRS to the true equator and equinox of date.
    pub fn tod_from_gcrs_matrix(&self) -> DMat3 {
        self.tod_from_gcrs
    }

    /// A geocentric position in the true equator and equinox of date (km)
    /// as seen from the site: in its ENU frame, km, the site's offset from
    /// the Earth's centre taken off (the parallax).
    pub fn enu_from_tod_topocentric(&self, geocentric_tod_km: DVec3) -> DVec3 {
        self.enu_from_itrs * (self.itrs_from_tod * geocentric_tod_km - self.site_itrs_km)
    }

    /// The instant.
    pub fn utc(&self) -> Utc {
        self.utc
    }

    /// The site.
    pub fn site(&self) -> &Site {
        &self.site
    }

    /// The instant's Julian Date in TT.
    pub fn jd_tt(&self) -> f64 {
        self.jd_tt
    }

    /// The nutation at the instant.
    pub fn nutation(&self) -> Nutation {
        self.nutation
    }

    /// Greenwich apparent sidereal time, radians in `[0, 2 pi)`.
    pub fn gast_rad(&self) -> f64 {
        self.gast_rad
    }

    /// The Earth's heliocentric position, AU, ICRS axes.
    pub fn earth_position_au(&self) -> DVec3 {
        self.earth_position_au
    }

    /// A catalogue star's apparent direction in the site's frame
    /// (unrefracted): its place at the instant seen from the Earth's
    /// centre (`StarPlace::icrs_direction_at` with the Earth computed once
    /// for the frame), then [`Self::apparent_enu`].
    pub fn star_enu(&self, star: &super::star::StarPlace) -> DVec3 {
        self.apparent_enu(star.direction_from(self.jd_tt, self.earth_position_au))
    }

    /// The Earth's heliocentric velocity over c, ICRS axes.
    pub fn earth_velocity_c(&self) -> DVec3 {
        self.earth_velocity_c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::astronomy::horizontal::separation_deg;
    use crate::util::fmath;

    fn tromso() -> (Site, Utc) {
        let site = Site::new(69.65, 18.96, 0.1).unwrap();
        (site, Utc::parse_rfc3339("2026-12-07T22:00:00Z").unwrap())
    }

    #[test]
    fn the_celestial_pole_stands_at_the_latitude() {
        // The true pole of date, seen from the site, is due north at an
        // elevation of the geodetic latitude.
        let (site, t) = tromso();
        let f = SkyFrame::new(&site, t);
        let pole_gcrs = f.tod_from_gcrs_matrix().transpose() * DVec3::Z;
        let enu = f.enu_from_gcrs_matrix() * pole_gcrs;
        let el = fmath::asin(enu.z).to_degrees();
        assert!((el - site.latitude_deg).abs() < 1e-9, "{el}");
        assert!(enu.x.abs() < 1e-12, "{enu}");
        let m = f.enu_from_gcrs_matrix();
        assert!((m * m.transpose() - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-14));
    }

    #[test]
    fn aberration_is_at_most_the_constant() {
        let (site, t) = tromso();
        let f = SkyFrame::new(&site, t);
        let v = f.earth_velocity_c();
        let perpendicular = v.normalize().any_orthonormal_vector();
        let sep = |a, b| separation_deg(a, b).to_radians();
        let moved = sep(f.apparent_enu(perpendicular), f.enu_from_gcrs_matrix() * perpendicular);
        assert!((moved - fmath::atan(v.length())).abs() < 1e-11, "{moved}");
        assert!(sep(f.apparent_enu(v.normalize()), f.enu_from_gcrs_matrix() * v.normalize()) < 1e-11);
    }
}
