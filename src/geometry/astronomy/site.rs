//! A place on the Earth: geodetic latitude, longitude and height on the
//! WGS 84 ellipsoid, its Earth-fixed (ITRS) position and its local frame.
//!
//! **Model.** WGS 84 (NIMA TR8350.2, 3rd ed., 2000): semi-major axis
//! `a = 6378.137 km`, flattening `f = 1 / 298.257223563`, `e^2 = f (2 - f)`.
//! A point at geodetic latitude phi, east longitude lambda and height h
//! above the ellipsoid is, with `N = a / sqrt(1 - e^2 sin^2 phi)` the prime
//! vertical's radius of curvature,
//!
//! ```text
//! x = (N + h) cos phi cos lambda
//! y = (N + h) cos phi sin lambda
//! z = (N (1 - e^2) + h) sin phi
//! ```
//!
//! (Torge and Mueller, "Geodesy", 4th ed., eq. 4.23). The local frame is
//! east, north and **up along the ellipsoid's normal** (geodetic up, the
//! direction a plumb line would hang but for the deflection of the
//! vertical, a few arcseconds): `up = (cos phi cos lambda, cos phi sin
//! lambda, sin phi)`, `east = (-sin lambda, cos lambda, 0)`, `north = up x
//! east`. The ITRS is taken as the frame the Earth's rotation carries
//! (polar motion, under 0.5 arcsecond, is neglected: `crate::geometry::astronomy::frame`).

use crate::util::fmath;
use glam::{DMat3, DVec3};
use thiserror::Error;

/// WGS 84's semi-major axis, km.
pub const WGS84_A_KM: f64 = 6378.137;
/// WGS 84's flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// Why a site was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SiteError {
    /// Latitude outside -90..90 or not finite.
    #[error("latitude {0} degrees is not in -90..90")]
    Latitude(f64),
    /// Longitude not finite.
    #[error("longitude {0} degrees is not finite")]
    Longitude(f64),
    /// Height not finite or below the Earth's centre's neighbourhood.
    #[error("height {0} km is not finite or below -100 km")]
    Height(f64),
}

/// A site: geodetic WGS 84 coordinates, east longitude positive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    pub height_km: f64,
}

impl Site {
    /// A site, its coordinates checked.
    pub fn new(latitude_deg: f64, longitude_deg: f64, height_km: f64) -> Result<Site, SiteError> {
        let site = Site { latitude_deg, longitude_deg, height_km };
        site.validate()?;
        Ok(site)
    }

    /// Checks the coordinates (a site built field by field).
    pub fn validate(&self) -> Result<(), SiteError> {
        if !(-90.0..=90.0).contains(&self.latitude_deg) {
            return Err(SiteError::Latitude(self.latitude_deg));
        }
        if !self.longitude_deg.is_finite() {
            return Err(SiteError::Longitude(self.longitude_deg));
        }
        if !(self.height_km >= -100.0 && self.height_km.is_finite()) {
            return Err(SiteError::Height(self.height_km));
        }
        Ok(())
    }

    /// The Earth-fixed (ITRS, ECEF) position, km.
    pub fn itrs_km(&self) -> DVec3 {
        let (sp, cp) = fmath::sin_cos(self.latitude_deg.to_radians());
        let (sl, cl) = fmath::sin_cos(self.longitude_deg.to_radians());
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let n = WGS84_A_KM / (1.0 - e2 * sp * sp).sqrt();
        let h = self.height_km;
        DVec3::new((n + h) * cp * cl, (n + h) * cp * sl, (n * (1.0 - e2) + h) * sp)
    }

    /// The geodetic site of the Earth-fixed point `p`, km: the inverse of
    /// [`Site::itrs_km`] by fixed-point iteration on the latitude
    /// (`tan phi = (z + e^2 N sin phi) / rho`; five rounds reach 1e-12 rad
    /// from the ground to thousands of km up). Not for points within 1 km
    /// of the Earth's centre.
    pub fn from_itrs_km(p: DVec3) -> Site {
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let rho = fmath::hypot(p.x, p.y);
        let mut phi = fmath::atan2(p.z, rho * (1.0 - e2));
        let mut n = WGS84_A_KM;
        for _ in 0..6 {
            let sp = fmath::sin(phi);
            n = WGS84_A_KM / (1.0 - e2 * sp * sp).sqrt();
            phi = fmath::atan2(p.z + e2 * n * sp, rho);
        }
        let (sp, cp) = fmath::sin_cos(phi);
        // The height along the normal, from whichever of rho and z is the better conditioned.
        let h = if cp.abs() > 0.5 { rho / cp - n } else { p.z / sp - n * (1.0 - e2) };
        Site { latitude_deg: phi.to_degrees(), longitude_deg: fmath::atan2(p.y, p.x).to_degrees(), height_km: h }
    }

    /// East, north and up (the ellipsoid's normal) in the ITRS.
    pub fn basis(&self) -> [DVec3; 3] {
        let (sp, cp) = fmath::sin_cos(self.latitude_deg.to_radians());
        let (sl, cl) = fmath::sin_cos(self.longitude_deg.to_radians());
        let east = DVec3::new(-sl, cl, 0.0);
        let up = DVec3::new(cp * cl, cp * sl, sp);
        [east, up.cross(east), up]
    }

    /// The rotation from the ITRS to the site's east-north-up frame (its
    /// rows are [`Site::basis`]).
    pub fn enu_from_itrs(&self) -> DMat3 {
        let [e, n, u] = self.basis();
        DMat3::from_cols(e, n, u).transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_geodetic_site_of_an_itrs_point_is_the_inverse() {
        for &(lat, lon, h) in
            &[(69.65, 18.96, 110.0), (-77.85, 166.67, 0.0), (0.3, -30.0, 800.0), (89.9, 10.0, 2.0), (-45.0, 200.0, 35_000.0)]
        {
            let s = Site::from_itrs_km(Site::new(lat, lon, h).unwrap().itrs_km());
            let lon_back = (s.longitude_deg - lon).rem_euclid(360.0);
            assert!(
                (s.latitude_deg - lat).abs() < 1e-9 && lon_back.min(360.0 - lon_back) < 1e-9 && (s.height_km - h).abs() < 1e-6,
                "{s:?}"
            );
        }
    }

    #[test]
    fn ecef_of_known_points() {
        let equator = Site::new(0.0, 0.0, 0.0).unwrap().itrs_km();
        assert!((equator - DVec3::new(WGS84_A_KM, 0.0, 0.0)).length() < 1e-9);
        // The pole: b = a (1 - f) = 6356.752314 km.
        let pole = Site::new(90.0, 0.0, 1.0).unwrap().itrs_km();
        assert!((pole.z - 6_357.752_314).abs() < 1e-6, "{pole}");
        // 45 N: geocentric latitude 44.8076 degrees (geodetic - 0.1924).
        let p = Site::new(45.0, 10.0, 0.0).unwrap().itrs_km();
        let geocentric = fmath::atan(p.z / (p.x * p.x + p.y * p.y).sqrt()).to_degrees();
        assert!((geocentric - 44.807_576).abs() < 1e-5, "{geocentric}");
    }

    #[test]
    fn basis_is_right_handed_and_up_is_the_normal() {
        let s = Site::new(69.65, 18.96, 0.1).unwrap();
        let [e, n, u] = s.basis();
        assert!((e.cross(n) - u).length() < 1e-12);
        // Up is the ellipsoid's normal: the gradient of x^2/a^2 + z^2/b^2.
        let p = Site { height_km: 0.0, ..s }.itrs_km();
        let b = WGS84_A_KM * (1.0 - WGS84_F);
        let normal = DVec3::new(p.x / fmath::powi(WGS84_A_KM, 2), p.y / fmath::powi(WGS84_A_KM, 2), p.z / (b * b)).normalize();
        assert!((normal - u).length() < 1e-12);
        // Up from the site is 0.1 km above the ellipsoid's point.
        assert!(((s.itrs_km() - p) - 0.1 * u).length() < 1e-9);
        assert!((s.enu_from_itrs() * u - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn refusals() {
        assert!(Site::new(91.0, 0.0, 0.0).is_err());
        assert!(Site::new(f64::NAN, 0.0, 0.0).is_err());
        assert!(Site::new(0.0, f64::INFINITY, 0.0).is_err());
        assert!(Site::new(0.0, 0.0, -200.0).is_err());
    }
}
