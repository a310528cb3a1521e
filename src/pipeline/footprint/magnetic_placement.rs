//! Curtains placed in magnetic coordinates: a curtain's `magnetic_path`
//! and the arcs `[oval]` lays along the auroral oval become `path`s in the
//! scene's frame, over the scene's `[site]` at its hour
//! (`utc + animation.time_s`).
//!
//! **A magnetic point to the scene.** A point `[lambda, MLT]` (corrected
//! geomagnetic latitude, magnetic local time) has the corrected geomagnetic
//! longitude of that MLT at the hour; from its apex the IGRF-14 field line
//! is followed down to [`PATH_ALTITUDE_KM`] above the WGS 84 ellipsoid
//! (`crate::physics::magnetic_coordinates`, AACGM-v2's definition). That
//! Earth-fixed point is taken into the site's east-north-up frame (the
//! scene's: origin on the ground at the site) and to the ground
//! coordinates of the curved frame (`crate::geometry::earth::Earth::to_curved`;
//! the plane's own with `earth.radius_km = 0`): a point of the path.
//! Between two given points the path is filled in straight in `(lambda,
//! MLT)` every quarter degree of arc or less (28 km), the short way round
//! the clock.
//!
//! **The oval's arcs.** With `[oval]`, straight curtain `i` of `n` follows
//! `lambda(t) = E(t) + (i + 1/2) / n (P(t) - E(t))`, with `E` and `P` the
//! oval's equatorward and poleward edges at MLT `t` (Starkov 1994,
//! `crate::physics::auroral_oval`), in the site's magnetic hemisphere,
//! centred on `oval.mlt_h` (the site's MLT if omitted), spanning the
//! curtain's `length` on the ground at 110 km (the MLT span from the
//! ground distance of a tenth of an hour at its middle), sampled at most
//! 25 km apart.
//!
//! **Whatever field the beams follow.** AACGM-v2 is defined by IGRF
//! (Shepherd 2014), so a scene whose beams follow its own field
//! (`[site] field = "scene"`) has its arcs placed where they are with
//! IGRF's: the same paths, the ground tracks of the arcs' lower borders,
//! from which its beams then rise along the scene's field
//! (`super::curtain_path::Lift::of_scene`).
//!
//! A scene with neither `[oval]` nor a `magnetic_path` is returned as it
//! is, so its bytes do not change.

use super::curtain_path::PATH_ALTITUDE_KM;
use crate::geometry::astronomy::site::Site;
use crate::geometry::astronomy::time::Utc;
use crate::geometry::earth::Earth;
use crate::physics::auroral_oval::{al_from_kp_nt, edges};
use crate::physics::magnetic_coordinates::{Cgm, CorrectedGeomagnetic};
use crate::scene::root::Scene;
use crate::util::fmath;
use glam::DVec3;

/// The longest step of a filled-in magnetic path, degrees of arc.
const FILL_STEP_DEG: f64 = 0.25;
/// The longest step between an oval arc's points, km.
const ARC_STEP_KM: f64 = 25.0;

/// Why a scene's magnetic placement was refused (the input's fault).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlacementError {
    #[error("[site] utc: {0}; magnetic coordinates need IGRF-14's years, 1900-2030")]
    Date(String),
    #[error("[site]: the site at latitude {0} deg, longitude {1} deg has no corrected geomagnetic latitude (too near the magnetic equator): [oval] cannot place arcs over it")]
    Site(f64, f64),
    #[error("{0}: the point [{1}, {2}] (latitude deg, mlt h) has no field line down to {PATH_ALTITUDE_KM} km")]
    Point(String, f64, f64),
}

impl PlacementError {
    /// Always the user's input: a site, an hour or points the model cannot place.
    pub fn is_input(&self) -> bool {
        true
    }
}

/// The scene with its magnetic placements made (module doc).
pub fn place(scene: &Scene) -> Result<Scene, PlacementError> {
    let wanted = scene.oval.is_some() || scene.curtains.iter().any(|c| c.magnetic_path.is_some());
    let Some(site) = scene.site.as_ref().filter(|_| wanted) else {
        return Ok(scene.clone());
    };
    let t = Utc::parse_rfc3339(&site.utc).map_err(|e| PlacementError::Date(e.to_string()))?.plus_seconds(scene.animation.time_s);
    let cgm = CorrectedGeomagnetic::at(t).map_err(|e| PlacementError::Date(e.to_string()))?;
    let ground = Site { latitude_deg: site.latitude_deg, longitude_deg: site.longitude_deg, height_km: site.height_km };
    let frame = Frame { cgm: &cgm, origin: ground.itrs_km(), enu: ground.basis(), earth: Earth::new(scene.earth.radius_km) };
    let mut out = scene.clone();
    for (i, c) in out.curtains.iter_mut().enumerate() {
        if let Some(m) = c.magnetic_path.take() {
            c.path = Some(frame.path(&fill(&m), &format!("curtain[{i}].magnetic_path"))?);
        }
    }
    if let Some(oval) = &scene.oval {
        let here = cgm
            .from_geodetic(site.latitude_deg, site.longitude_deg, PATH_ALTITUDE_KM)
            .ok_or(PlacementError::Site(site.latitude_deg, site.longitude_deg))?;
        let hemisphere = if here.lat_deg < 0.0 { -1.0 } else { 1.0 };
        let middle = oval.mlt_h.unwrap_or_else(|| cgm.mlt_h(here.lon_deg));
        let al = oval.al_nt.unwrap_or_else(|| al_from_kp_nt(oval.kp));
        let straight: Vec<usize> = (0..out.curtains.len()).filter(|&i| out.curtains[i].path.is_none()).collect();
        let n = straight.len();
        for (k, &i) in straight.iter().enumerate() {
            let f = (k as f64 + 0.5) / n as f64;
            let lat = |mlt: f64| {
                let e = edges(mlt.rem_euclid(24.0), al);
                hemisphere * (e.equatorward_deg + f * (e.poleward_deg - e.equatorward_deg))
            };
            let what = format!("curtain[{i}] along [oval]");
            // Ground km (the curved frame's, at 110 km) per hour of MLT at the arc's middle.
            let dt = 0.1;
            let (a, b) = (frame.itrs(lat(middle), middle, &what)?, frame.itrs(lat(middle + dt), middle + dt, &what)?);
            let km_per_h = (a - b).length() * crate::geometry::earth::MEAN_RADIUS_KM / a.length() / dt;
            let length = out.curtains[i].length;
            let span = length / km_per_h;
            // An odd count: the middle is a point.
            let count = 2 * ((0.5 * length / ARC_STEP_KM).ceil() as usize).max(2) + 1;
            let points: Vec<[f64; 2]> = (0..count)
                .map(|j| {
                    let mlt = middle - 0.5 * span + span * j as f64 / (count - 1) as f64;
                    [lat(mlt), mlt.rem_euclid(24.0)]
                })
                .collect();
            out.curtains[i].path = Some(frame.path(&points, &what)?);
        }
    }
    Ok(out)
}

/// The magnetic path filled in (module doc).
fn fill(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = vec![points[0]];
    for w in points.windows(2) {
        let [a, b] = [w[0], w[1]];
        let mut dm = b[1] - a[1];
        if dm > 12.0 {
            dm -= 24.0;
        } else if dm < -12.0 {
            dm += 24.0;
        }
        let cos = fmath::cos(a[0].to_radians()).max(fmath::cos(b[0].to_radians()));
        let steps = (((b[0] - a[0]).abs().max(dm.abs() * 15.0 * cos) / FILL_STEP_DEG).ceil() as usize).max(1);
        for s in 1..=steps {
            let f = s as f64 / steps as f64;
            out.push([a[0] + f * (b[0] - a[0]), (a[1] + f * dm).rem_euclid(24.0)]);
        }
    }
    out
}

/// The site's frame for placing magnetic points.
struct Frame<'a> {
    cgm: &'a CorrectedGeomagnetic,
    origin: DVec3,
    enu: [DVec3; 3],
    earth: Earth,
}

impl Frame<'_> {
    /// The Earth-fixed point of `[lat, mlt]` at [`PATH_ALTITUDE_KM`].
    fn itrs(&self, lat: f64, mlt: f64, what: &str) -> Result<DVec3, PlacementError> {
        let c = Cgm { lat_deg: lat, lon_deg: self.cgm.lon_at_mlt_deg(mlt) };
        self.cgm.to_geodetic(c, PATH_ALTITUDE_KM).map(|s| s.itrs_km()).ok_or_else(|| PlacementError::Point(what.to_string(), lat, mlt))
    }

    /// The ground coordinates of the curved frame under each point.
    fn path(&self, points: &[[f64; 2]], what: &str) -> Result<Vec<[f64; 2]>, PlacementError> {
        points
            .iter()
            .map(|&[lat, mlt]| {
                let d = self.itrs(lat, mlt, what)? - self.origin;
                let [e, n, u] = self.enu;
                let q = self.earth.to_curved(DVec3::new(d.dot(e), d.dot(n), d.dot(u)));
                // Rounded to millimetres: the TOML a bake records stays readable.
                Ok([(q.x * 1e6).round() / 1e6, (q.y * 1e6).round() / 1e6])
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::presets;

    /// The corrected geomagnetic coordinates of a placed path's point at 110 km.
    fn cgm_of(scene: &Scene, cgm: &CorrectedGeomagnetic, q: [f64; 2]) -> Cgm {
        let site = scene.site.as_ref().unwrap();
        let g = Site { latitude_deg: site.latitude_deg, longitude_deg: site.longitude_deg, height_km: site.height_km };
        let p = Earth::new(scene.earth.radius_km).to_scene(DVec3::new(q[0], q[1], PATH_ALTITUDE_KM));
        let [e, n, u] = g.basis();
        cgm.from_itrs(g.itrs_km() + p.x * e + p.y * n + p.z * u).unwrap()
    }

    #[test]
    fn scenes_without_magnetic_keys_are_unchanged() {
        for name in ["default", "oval", "tromso"] {
            let s = presets::by_name(name).unwrap();
            assert_eq!(place(&s).unwrap(), s, "{name}");
        }
    }

    #[test]
    fn the_oval_arcs_lie_between_starkovs_edges_at_their_magnetic_local_time() {
        let mut s = presets::by_name("tromso").unwrap();
        s.oval = Some(crate::scene::oval::OvalParams { kp: 5.0, al_nt: None, mlt_h: Some(0.0) });
        // `[oval]` places straight curtains (the default's follow paths of their own).
        for c in &mut s.curtains {
            c.path = None;
            c.length = 400.0;
        }
        let placed = place(&s).unwrap();
        placed.validate("placed", None).unwrap();
        let t = Utc::parse_rfc3339(&s.site.as_ref().unwrap().utc).unwrap();
        let cgm = CorrectedGeomagnetic::at(t).unwrap();
        let al = al_from_kp_nt(5.0);
        for (i, c) in placed.curtains.iter().enumerate() {
            let path = c.path.as_ref().unwrap();
            let f = (i as f64 + 0.5) / 3.0;
            for &q in path {
                let m = cgm_of(&s, &cgm, q);
                let mlt = cgm.mlt_h(m.lon_deg);
                let e = edges(mlt, al);
                let want = e.equatorward_deg + f * (e.poleward_deg - e.equatorward_deg);
                // The field line traced back up: within 0.01 degree.
                assert!((m.lat_deg - want).abs() < 0.01, "curtain {i}: {m:?} at {mlt} h, want {want}");
                assert!(m.lat_deg > e.equatorward_deg && m.lat_deg < e.poleward_deg);
            }
            // Its middle at magnetic midnight, its length the curtain's.
            let mid = cgm_of(&s, &cgm, path[path.len() / 2]);
            let mlt = cgm.mlt_h(mid.lon_deg);
            assert!(mlt.min(24.0 - mlt) < 0.01, "{mlt}");
            let len: f64 = path.windows(2).map(|w| Earth::new(s.earth.radius_km).ground_distance_km(w[0], w[1])).sum();
            assert!((len / c.length - 1.0).abs() < 0.05, "curtain {i}: {len} km of {}", c.length);
        }
    }

    #[test]
    fn a_magnetic_path_is_placed_where_its_points_say() {
        let mut s = presets::by_name("tromso").unwrap();
        s.curtains.truncate(1);
        s.curtains[0].magnetic_path = Some(vec![[66.0, 19.0], [66.5, 20.0]]);
        let placed = place(&s).unwrap();
        assert!(placed.curtains[0].magnetic_path.is_none());
        let path = placed.curtains[0].path.as_ref().unwrap();
        let cgm = CorrectedGeomagnetic::at(Utc::parse_rfc3339(&s.site.as_ref().unwrap().utc).unwrap()).unwrap();
        let first = cgm_of(&s, &cgm, path[0]);
        let last = cgm_of(&s, &cgm, *path.last().unwrap());
        assert!((first.lat_deg - 66.0).abs() < 0.01 && (cgm.mlt_h(first.lon_deg) - 19.0).abs() < 0.01, "{first:?}");
        assert!((last.lat_deg - 66.5).abs() < 0.01 && (cgm.mlt_h(last.lon_deg) - 20.0).abs() < 0.01, "{last:?}");
        // One hour of MLT at 66 degrees is about 680 km at 110 km: the
        // points are filled in every 28 km or less.
        assert!(path.len() > 20, "{}", path.len());
    }

    #[test]
    fn the_arcs_are_placed_by_aacgm_whatever_field_the_beams_follow() {
        use crate::pipeline::footprint::curtain_path::Lift;
        use crate::scene::site::SiteField;
        let igrf = presets::by_name("tromso_kp5").unwrap();
        let mut own = igrf.clone();
        own.site.as_mut().unwrap().field = SiteField::Scene;
        let (a, b) = (place(&igrf).unwrap(), place(&own).unwrap());
        for (x, y) in a.curtains.iter().zip(&b.curtains) {
            assert!(x.path.is_some() && x.path == y.path);
        }
        // The beams rise from the same paths along each scene's own field.
        assert_eq!(Lift::of_scene(&b), Lift::of(&b.beams, &b.earth));
        assert!(matches!(Lift::of_scene(&a), Lift::Site { .. }));
    }
}
