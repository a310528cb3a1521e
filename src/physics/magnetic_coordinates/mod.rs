//! Corrected geomagnetic coordinates and magnetic local time: AACGM-v2
//! (Shepherd 2014, "Altitude-adjusted corrected geomagnetic coordinates:
//! Definition and functional approximations", J. Geophys. Res. Space
//! Physics 119, 7501, doi 10.1002/2014JA020264), by tracing IGRF-14
//! (`crate::physics::igrf`) field lines.
//!
//! **The dipole frame.** IGRF's degree-1 term is a centred dipole; its axis
//! `z` points to the north geomagnetic pole ([`Igrf::dipole_north`]),
//! `y = Z_geo x z / |...|`, `x = y x z` (the geographic north pole lies at
//! dipole longitude 180 degrees).
//!
//! **A point's coordinates.** From the point (geocentric, radius `r0`) the
//! IGRF field line is followed towards the dipole equator (against B in
//! the north, along B in the south) by fourth-order Runge-Kutta steps of
//! [`STEP_FRACTION`] of the radius, the last step bisected onto the plane
//! `z = 0`: that point is the field line's apex, at `L` Earth radii
//! (`R_E = 6371.2 km`, IGRF's). The dipole field line with that apex,
//! `r = L cos^2(lambda)`, meets the ground `r = R_E` at
//!
//! ```text
//! lambda = +-acos(sqrt(1 / L))      (sign: the point's dipole hemisphere)
//! ```
//!
//! the corrected geomagnetic latitude, and the apex's dipole longitude is
//! the corrected geomagnetic longitude. A field line that comes back below
//! `r0` before it reaches the dipole equator, or whose apex lies below
//! `r0`, has no coordinates (AACGM-v2 leaves them undefined: low
//! latitudes high up).
//!
//! **The inverse.** From `(lambda, phi)`: the dipole equator's point at
//! `L = 1 / cos^2(lambda)` and longitude `phi`, followed along the IGRF
//! field line into the hemisphere of `lambda` down to a geocentric radius
//! ([`CorrectedGeomagnetic::to_itrs`], AACGM-v2's own inverse) or to a
//! geodetic height ([`CorrectedGeomagnetic::to_geodetic`]).
//!
//! **Magnetic local time.** `MLT = 12 h + (phi - phi_ref) / 15 deg`, with
//! `phi_ref` the corrected geomagnetic longitude of the subsolar point at
//! [`MLT_REFERENCE_HEIGHT_KM`] (AACGM-v2 v2.4's definition; the Sun's
//! place from `crate::geometry::astronomy::sun`). AACGM-v2 takes that
//! longitude from its coefficients, which interpolate through the low
//! latitudes where tracing leaves it undefined; here it is traced, and
//! where undefined (the subsolar point is within 23.4 degrees of the
//! equator) interpolated linearly in latitude between the nearest traced
//! points north and south on its meridian, half a degree apart.
//!
//! **Checked** against aacgmv2 2.7.1 (`tests/data/aacgm_oracle.csv`, made by
//! `tools/reference/aacgm_oval_table.py`): the tests in
//! `magnetic_coordinates/tests.rs` state the tolerances.

use crate::geometry::astronomy::frame::SkyFrame;
use crate::geometry::astronomy::rotation::r3;
use crate::geometry::astronomy::site::Site;
use crate::geometry::astronomy::sun::sun_apparent_tod_km;
use crate::geometry::astronomy::time::Utc;
use crate::physics::igrf::{Igrf, IgrfError, REFERENCE_RADIUS_KM};
use crate::util::fmath;
use glam::DVec3;

/// A tracing step, as a fraction of the geocentric radius (32 km at the
/// ground: a field line's radius of curvature there is over 2000 km).
pub const STEP_FRACTION: f64 = 0.005;
/// The subsolar point's height for magnetic local time's reference
/// longitude, km (AACGM-v2's).
pub const MLT_REFERENCE_HEIGHT_KM: f64 = 700.0;
/// The most steps of one trace (from 89 degrees it takes about 2000).
const MAX_STEPS: usize = 100_000;
/// Bisections of the last step (2^-48 of a step of at most thousands of km).
const BISECTIONS: usize = 48;

/// Corrected geomagnetic latitude and longitude, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cgm {
    pub lat_deg: f64,
    pub lon_deg: f64,
}

/// IGRF-14 at an instant with its dipole frame and magnetic local time's
/// reference longitude (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct CorrectedGeomagnetic {
    igrf: Igrf,
    /// The dipole frame's x, y, z in the ITRS.
    axes: [DVec3; 3],
    /// The subsolar point's corrected geomagnetic longitude, degrees.
    reference_lon_deg: f64,
}

impl CorrectedGeomagnetic {
    /// The coordinates at instant `t` (IGRF-14's span, 1900-2030).
    pub fn at(t: Utc) -> Result<Self, IgrfError> {
        Ok(Self::new(Igrf::at(t)?, t))
    }

    /// The coordinates of the model `igrf`, magnetic local time at `t`.
    pub fn new(igrf: Igrf, t: Utc) -> Self {
        let z = igrf.dipole_north();
        let y = DVec3::Z.cross(z).normalize();
        let x = y.cross(z);
        let mut c = CorrectedGeomagnetic { igrf, axes: [x, y, z], reference_lon_deg: 0.0 };
        c.reference_lon_deg = c.subsolar_reference_lon_deg(t);
        c
    }

    /// The ITRS point `p` in the dipole frame.
    pub fn dipole_of(&self, p: DVec3) -> DVec3 {
        let [x, y, z] = self.axes;
        DVec3::new(p.dot(x), p.dot(y), p.dot(z))
    }

    fn itrs_of_dipole(&self, m: DVec3) -> DVec3 {
        let [x, y, z] = self.axes;
        m.x * x + m.y * y + m.z * z
    }

    /// One Runge-Kutta step of `h` km along `sign` B / |B|.
    fn step(&self, p: DVec3, h: f64, sign: f64) -> DVec3 {
        let f = |q: DVec3| sign * self.igrf.field_itrs(q).normalize();
        let k1 = f(p);
        let k2 = f(p + 0.5 * h * k1);
        let k3 = f(p + 0.5 * h * k2);
        let k4 = f(p + h * k3);
        p + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    }

    /// Follows the field line from `p` along `sign` B while `inside` holds,
    /// and returns the point where it stops holding (the last step
    /// bisected), or `None` when `valid` fails first or the trace runs out
    /// of steps.
    fn trace(&self, p: DVec3, sign: f64, inside: impl Fn(DVec3) -> bool, valid: impl Fn(DVec3) -> bool) -> Option<DVec3> {
        let mut q = p;
        for _ in 0..MAX_STEPS {
            let h = STEP_FRACTION * q.length();
            let next = self.step(q, h, sign);
            if inside(next) {
                if !valid(next) {
                    return None;
                }
                q = next;
                continue;
            }
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if inside(self.step(q, h * mid, sign)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Some(self.step(q, h * 0.5 * (lo + hi), sign));
        }
        None
    }

    /// The corrected geomagnetic coordinates of the Earth-fixed point `p`,
    /// km (module doc); `None` where AACGM-v2 has none.
    pub fn from_itrs(&self, p: DVec3) -> Option<Cgm> {
        let r0 = p.length();
        let z0 = self.dipole_of(p).z;
        let hemisphere = if z0 >= 0.0 { 1.0 } else { -1.0 };
        let apex =
            if z0 == 0.0 { p } else { self.trace(p, -hemisphere, |q| self.dipole_of(q).z * hemisphere > 0.0, |q| q.length() >= r0)? };
        let l = apex.length() / REFERENCE_RADIUS_KM;
        if apex.length() < r0 {
            return None;
        }
        let m = self.dipole_of(apex);
        Some(Cgm {
            lat_deg: hemisphere * fmath::acos((1.0 / l).sqrt().clamp(0.0, 1.0)).to_degrees(),
            lon_deg: fmath::atan2(m.y, m.x).to_degrees(),
        })
    }

    /// The corrected geomagnetic coordinates of a geodetic (WGS 84) place.
    pub fn from_geodetic(&self, latitude_deg: f64, longitude_deg: f64, height_km: f64) -> Option<Cgm> {
        let site = Site { latitude_deg, longitude_deg, height_km };
        self.from_itrs(site.itrs_km())
    }

    /// The dipole equator's point of the coordinates and the direction
    /// (the sign of B) that leads into their hemisphere; `None` within a
    /// millidegree of a pole.
    fn apex_of(&self, c: Cgm) -> Option<(DVec3, f64)> {
        if !(c.lat_deg.abs() < 89.999) {
            return None;
        }
        let l = 1.0 / fmath::powi(fmath::cos(c.lat_deg.to_radians()), 2);
        let (s, co) = fmath::sin_cos(c.lon_deg.to_radians());
        let apex = self.itrs_of_dipole(DVec3::new(l * REFERENCE_RADIUS_KM * co, l * REFERENCE_RADIUS_KM * s, 0.0));
        Some((apex, if c.lat_deg >= 0.0 { 1.0 } else { -1.0 }))
    }

    /// The Earth-fixed point of the coordinates `c` at geocentric radius
    /// `radius_km` (AACGM-v2's inverse; module doc); `None` where the apex
    /// lies below that radius.
    pub fn to_itrs(&self, c: Cgm, radius_km: f64) -> Option<DVec3> {
        let (apex, sign) = self.apex_of(c)?;
        if apex.length() < radius_km {
            return None;
        }
        self.trace(apex, sign, |q| q.length() > radius_km, |_| true)
    }

    /// The geodetic place of the coordinates `c` at height `height_km`
    /// above the WGS 84 ellipsoid; `None` where the apex lies below it.
    pub fn to_geodetic(&self, c: Cgm, height_km: f64) -> Option<Site> {
        let (apex, sign) = self.apex_of(c)?;
        let above = |q: DVec3| Site::from_itrs_km(q).height_km > height_km;
        if !above(apex) {
            return None;
        }
        self.trace(apex, sign, above, |_| true).map(Site::from_itrs_km)
    }

    /// Magnetic local time, hours in [0, 24), of corrected geomagnetic
    /// longitude `lon_deg` (module doc).
    pub fn mlt_h(&self, lon_deg: f64) -> f64 {
        (12.0 + (lon_deg - self.reference_lon_deg) / 15.0).rem_euclid(24.0)
    }

    /// The corrected geomagnetic longitude, degrees, at magnetic local time
    /// `mlt_h`.
    pub fn lon_at_mlt_deg(&self, mlt_h: f64) -> f64 {
        ((mlt_h - 12.0) * 15.0 + self.reference_lon_deg + 180.0).rem_euclid(360.0) - 180.0
    }

    /// The subsolar point's corrected geomagnetic longitude at
    /// [`MLT_REFERENCE_HEIGHT_KM`], or its dipole longitude where that is
    /// undefined (module doc).
    fn subsolar_reference_lon_deg(&self, t: Utc) -> f64 {
        let frame = SkyFrame::new(&Site { latitude_deg: 0.0, longitude_deg: 0.0, height_km: 0.0 }, t);
        let sun = (r3(frame.gast_rad()) * sun_apparent_tod_km(&frame)).normalize();
        let (lat, lon) = (fmath::asin(sun.z).to_degrees(), fmath::atan2(sun.y, sun.x).to_degrees());
        let at = |lat: f64| self.from_geodetic(lat, lon, MLT_REFERENCE_HEIGHT_KM).map(|c| c.lon_deg);
        if let Some(l) = at(lat) {
            return l;
        }
        // Undefined: interpolated along the meridian between the nearest
        // defined points north and south (module doc).
        let nearest = |dir: f64| (1..=180).map(|k| lat + dir * 0.5 * k as f64).find_map(|l| at(l).map(|m| (l, m)));
        match (nearest(1.0), nearest(-1.0)) {
            (Some((ln, mn)), Some((ls, ms))) => {
                let d = (mn - ms + 180.0).rem_euclid(360.0) - 180.0;
                ms + d * (lat - ls) / (ln - ls)
            }
            _ => {
                let m = self.dipole_of(Site { latitude_deg: lat, longitude_deg: lon, height_km: MLT_REFERENCE_HEIGHT_KM }.itrs_km());
                fmath::atan2(m.y, m.x).to_degrees()
            }
        }
    }
}

#[cfg(test)]
mod tests;
