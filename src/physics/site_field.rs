//! The Earth's field over a scene with a site: IGRF-14 (`crate::physics::igrf`)
//! at the site's hour, at the Earth-fixed point each scene point lies over.
//!
//! **The mapping.** The scene's frame is the site's (`crate::scene::site`):
//! origin on the ground at the site, x east, y north, z along the WGS 84
//! ellipsoid's normal. It is laid rigidly on the Earth: the scene point
//! `p` is the Earth-fixed (ITRS) point
//!
//! ```text
//! X(p) = X_site + p_x e + p_y n + p_z u
//! ```
//!
//! with `X_site` the site's ITRS position (at its height) and `e`, `n`, `u`
//! its east, north and up (`crate::geometry::astronomy::site::Site`). A
//! point of the curved frame, ground coordinates and altitude `(x, y, h)`,
//! is first placed in the scene frame on the round Earth of `[earth]`
//! (`crate::geometry::earth::Earth::to_scene`): the sphere tangent to the
//! ellipsoid at the site. Sphere and ellipsoid part by
//! `d^2 / 2 (1/R - 1/R_ellipsoid)`, under 0.3 km at d = 1000 km from the
//! site, so a point's altitude is its height within that.
//!
//! **The angles.** IGRF's B at `X(p)` (`Igrf::field_itrs`), rotated into
//! the scene frame, is read in the local frame of the ground point `(x, y)`
//! (`Earth::local_frame`: east, north, up on the scene's sphere): the dip
//! `I = atan2(-B_up, |B_h|)` and the declination `D = atan2(B_e, B_n)` make
//! the beams' frame as the dipole's do
//! (`crate::physics::geomagnetic_field::MagneticField::dipole`): `b = B`
//! where B points down, `-B` where it points up (the southern hemisphere).

use crate::geometry::astronomy::site::Site;
use crate::geometry::astronomy::time::Utc;
use crate::geometry::earth::Earth;
use crate::physics::geomagnetic_field::MagneticField;
use crate::physics::igrf::Igrf;
use crate::scene::root::Scene;
use crate::scene::site::SiteField as SiteFieldChoice;
use crate::util::fmath;
use glam::DVec3;

/// IGRF at a site's hour over the scene's frame (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct SiteField {
    igrf: Igrf,
    earth: Earth,
    origin_itrs: DVec3,
    axes: [DVec3; 3],
}

impl SiteField {
    /// The field `igrf` over the scene of `site` on `earth`.
    pub fn new(igrf: Igrf, site: &Site, earth: Earth) -> Self {
        SiteField { igrf, earth, origin_itrs: site.itrs_km(), axes: site.basis() }
    }

    /// IGRF-14 over the scene's site at its hour (`utc + animation.time_s`),
    /// when the scene has a `[site]` whose `field` is `igrf`; `None` for the
    /// scene's own field. The scene is a validated one (its `utc` parses and
    /// lies in IGRF-14's years).
    pub fn of_scene(scene: &Scene) -> Option<SiteField> {
        let p = scene.site.as_ref().filter(|p| p.field == SiteFieldChoice::Igrf)?;
        let t = Utc::parse_rfc3339(&p.utc).ok()?.plus_seconds(scene.animation.time_s);
        let igrf = Igrf::at(t).ok()?;
        let site = Site::new(p.latitude_deg, p.longitude_deg, p.height_km).ok()?;
        Some(SiteField::new(igrf, &site, Earth::new(scene.earth.radius_km)))
    }

    /// The ITRS point of the scene point `p` (module doc).
    pub fn itrs_of(&self, p: DVec3) -> DVec3 {
        let [e, n, u] = self.axes;
        self.origin_itrs + p.x * e + p.y * n + p.z * u
    }

    /// B, nT, in the scene's frame at the scene point `p`.
    pub fn b_scene(&self, p: DVec3) -> DVec3 {
        let b = self.igrf.field_itrs(self.itrs_of(p));
        let [e, n, u] = self.axes;
        DVec3::new(b.dot(e), b.dot(n), b.dot(u))
    }

    /// IGRF's inclination (of B itself: negative where it points up) and
    /// declination, degrees, at the curved frame's point `(x, y, h)`, in
    /// the local frame of `(x, y)`.
    pub fn angles_deg(&self, at: [f64; 2], altitude_km: f64) -> (f64, f64) {
        let b = self.b_scene(self.earth.to_scene(DVec3::new(at[0], at[1], altitude_km)));
        let [east, north, up] = self.earth.local_frame(at[0], at[1]);
        let (be, bn, bu) = (b.dot(east), b.dot(north), b.dot(up));
        let inc = fmath::atan2(-bu, fmath::hypot(be, bn)).to_degrees();
        (inc, fmath::atan2(be, bn).to_degrees())
    }

    /// The beams' field at the curved frame's point `(x, y, h)`: along B
    /// where it points down, along -B where it points up.
    pub fn field(&self, at: [f64; 2], altitude_km: f64) -> MagneticField {
        let (inc, dec) = self.angles_deg(at, altitude_km);
        if inc < 0.0 {
            MagneticField::new(-inc, dec + 180.0)
        } else {
            MagneticField::new(inc, dec)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::astronomy::time::Utc;
    use crate::geometry::earth::MEAN_RADIUS_KM;

    fn tromso() -> (Igrf, Site) {
        let igrf = Igrf::at(Utc::parse_rfc3339("2026-12-18T18:00:00Z").unwrap()).unwrap();
        (igrf, Site::new(69.65, 18.96, 0.0).unwrap())
    }

    #[test]
    fn at_the_origin_the_field_is_igrf_in_the_sites_east_north_up() {
        let (igrf, site) = tromso();
        let f = SiteField::new(igrf.clone(), &site, Earth::new(MEAN_RADIUS_KM));
        let [e, n, u] = site.basis();
        let up_110 = site.itrs_km() + 110.0 * u;
        let b = igrf.field_itrs(up_110);
        let want = DVec3::new(b.dot(e), b.dot(n), b.dot(u)).normalize();
        let got = f.field([0.0, 0.0], 110.0).b;
        assert!(got.angle_between(want).to_degrees() < 1e-9, "{got} {want}");
        // Tromso in 2026: dip 78.5 degrees, declination 11.3 degrees east.
        let (inc, dec) = f.angles_deg([0.0, 0.0], 0.0);
        assert!(inc > 78.0 && inc < 79.0 && dec > 10.0 && dec < 12.5, "{inc} {dec}");
    }

    #[test]
    fn the_southern_hemisphere_goes_down_along_minus_b() {
        let igrf = Igrf::at(Utc::parse_rfc3339("2026-07-01T12:00:00Z").unwrap()).unwrap();
        let site = Site::new(-77.85, 166.67, 0.0).unwrap();
        let f = SiteField::new(igrf, &site, Earth::new(MEAN_RADIUS_KM));
        let (inc, _) = f.angles_deg([0.0, 0.0], 110.0);
        assert!(inc < -75.0, "{inc}");
        let m = f.field([0.0, 0.0], 110.0);
        assert!(m.b.z < 0.0 && (m.dip_deg() + inc).abs() < 1e-9, "{:?} {inc}", m.b);
    }

    #[test]
    fn a_ground_point_far_away_is_read_in_its_own_local_frame() {
        // 800 km north of Tromso, the field read at the mapped point equals
        // IGRF at the geodetic place a local frame there would give within
        // the sphere's difference from the ellipsoid (module doc).
        let (igrf, site) = tromso();
        let f = SiteField::new(igrf.clone(), &site, Earth::new(MEAN_RADIUS_KM));
        let x = f.itrs_of(Earth::new(MEAN_RADIUS_KM).to_scene(DVec3::new(0.0, 800.0, 0.0)));
        let lat = fmath::atan2(x.z, fmath::hypot(x.x, x.y)).to_degrees();
        // 800 km is 7.2 degrees of arc: the point is near 76.8 N geocentric.
        assert!((lat - (69.65 - 0.19 + 7.19)).abs() < 0.1, "{lat}");
        let (inc, _) = f.angles_deg([0.0, 800.0], 0.0);
        assert!(inc > 80.0 && inc < 84.0, "{inc}");
    }
}
