//! The field's dip where each curtain's beams start, and the curtains whose
//! electrons cannot go down.
//!
//! A step leaves at an angle of at most `alpha_D` (`beams.alpha_d_deg`)
//! from the field line (Baranoski, Rokne, Shirley, Trondsen & Bastos 2000;
//! [`super::walk`]). Its vertical part is at most
//! `-s sin(I - alpha_D) / cos(alpha)` for a line dipping `I` below the
//! horizon, so every step descends while `I > alpha_D`; where the line lies
//! within that cone of the horizontal (`I <= alpha_D`) a beam may go up or
//! sideways for ever. With a dipole pole (`earth.magnetic_pole`,
//! `crate::physics::geomagnetic_field`) that happens near the dipole's
//! equator, a quarter of the globe (`pi R / 2`, 10007 km) from the pole.
//!
//! With a `[site]` whose beams follow IGRF-14 (`field = "igrf"`,
//! `crate::physics::site_field`) the dip is IGRF's at each sample, at the
//! beams' start altitude (`beams.top_km`), read by
//! `SiteField::angles_deg`, the function whose angles the beams follow
//! (`super::beam_field`); near the dip equator (a band some 10 degrees of
//! latitude wide across South America, Africa and Asia) that field lies
//! within the cone too.
//!
//! [`curtain_dip`] samples a curtain's start area (a straight curtain's
//! rectangle, or a path's lifted vertices widened by half the width) and
//! keeps its smallest dip, 0 where the samples straddle the (dipole's or
//! IGRF's) dip equator; [`check_field`] refuses a curtain at or inside the
//! cone.

use super::BeamError;
use crate::geometry::earth::Earth;
use crate::physics::geomagnetic_field::dipole_angles_deg;
use crate::physics::site_field::SiteField;
use crate::pipeline::footprint::curtain_path::{vertices, Lift};
use crate::scene::root::Scene;
use crate::scene::{BeamParams, Curtain, EarthParams};
use crate::util::fmath;

/// Samples along a straight curtain's length (and across, [`ACROSS`]).
const ALONG: usize = 17;
const ACROSS: usize = 3;

/// The smallest dip of the electrons' field line over a curtain's start area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurtainDip {
    /// Degrees below the horizon, in [0, 90]: 0 where the area straddles
    /// the dip equator.
    pub dip_deg: f64,
    /// The ground point `[x, y]` km where it is smallest.
    pub at: [f64; 2],
}

/// Ground points `[x, y]` km of a curtain's start area: a straight
/// curtain's rectangle at [`ALONG`] x [`ACROSS`] points (corners, edges,
/// centre), or a path's vertices lifted to the start altitude (along
/// `site`'s field when given, as the footprints are: `Lift::over`),
/// each with the four points half the width away along the axes.
pub fn start_samples(curtain: &Curtain, beams: &BeamParams, earth: &EarthParams, site: Option<&SiteField>) -> Vec<[f64; 2]> {
    if let Some(p) = &curtain.path {
        let h = 0.5 * curtain.width;
        return vertices(&Lift::over(beams, earth, site.cloned()).path(p))
            .into_iter()
            .flat_map(|[x, y]| [[x, y], [x - h, y], [x + h, y], [x, y - h], [x, y + h]])
            .collect();
    }
    let (s, c) = fmath::sin_cos(curtain.rotation_deg.to_radians());
    let mut out = Vec::with_capacity(ALONG * ACROSS);
    for i in 0..ALONG {
        for j in 0..ACROSS {
            let u = (i as f64 / (ALONG - 1) as f64 - 0.5) * curtain.length;
            let w = (j as f64 / (ACROSS - 1) as f64 - 0.5) * curtain.width;
            out.push([curtain.center[0] + u * c - w * s, curtain.center[1] + u * s + w * c]);
        }
    }
    out
}

/// The smallest dip over `curtain`'s start area: with `site` (IGRF over a
/// `[site]`, `None` when the beams follow the scene's own field) or a
/// dipole pole, the smallest `|I|` of the samples ([`start_samples`]), 0 if
/// B points down at some and up at others (the dip equator runs through
/// the curtain); `beams.b_inclination_deg` for a uniform field.
pub fn curtain_dip(curtain: &Curtain, beams: &BeamParams, earth: &EarthParams, site: Option<&SiteField>) -> CurtainDip {
    let inclination: Box<dyn Fn([f64; 2]) -> f64 + '_> = match (site, earth.magnetic_pole) {
        (Some(f), _) => Box::new(move |at| f.angles_deg(at, beams.top_km).0),
        (None, Some(pole)) if earth.radius_km > 0.0 => {
            let e = Earth::new(earth.radius_km);
            Box::new(move |at| dipole_angles_deg(&e, pole, at).0)
        }
        _ => return CurtainDip { dip_deg: beams.b_inclination_deg, at: curtain.center },
    };
    let (mut best, mut up, mut down) = (CurtainDip { dip_deg: f64::INFINITY, at: curtain.center }, false, false);
    for at in start_samples(curtain, beams, earth, site) {
        let inc = inclination(at);
        up |= inc < 0.0;
        down |= inc > 0.0;
        if inc.abs() < best.dip_deg {
            best = CurtainDip { dip_deg: inc.abs(), at };
        }
    }
    if up && down {
        best.dip_deg = 0.0;
    }
    best
}

/// The smallest dip over every curtain's start area, degrees (90 without
/// curtains).
pub fn min_dip_deg(curtains: &[Curtain], beams: &BeamParams, earth: &EarthParams, site: Option<&SiteField>) -> f64 {
    curtains.iter().map(|c| curtain_dip(c, beams, earth, site).dip_deg).fold(90.0, f64::min)
}

/// [`check_field`] on a validated scene's curtains, with IGRF over its
/// `[site]` when its beams follow it (`SiteField::of_scene`, the field
/// `super::site_field` gives the trace).
pub fn check_scene_field(scene: &Scene) -> Result<(), BeamError> {
    check_field(&scene.curtains, &scene.beams, &scene.earth, SiteField::of_scene(scene).as_ref())
}

/// Refuses the first curtain whose field line at its start lies within the
/// beams' deflection cone of the horizontal (`dip <= beams.alpha_d_deg`),
/// naming it, its dip and the limit ([`BeamError::FieldInCone`]); `site`
/// as in [`curtain_dip`].
pub fn check_field(curtains: &[Curtain], beams: &BeamParams, earth: &EarthParams, site: Option<&SiteField>) -> Result<(), BeamError> {
    for (i, c) in curtains.iter().enumerate() {
        let d = curtain_dip(c, beams, earth, site);
        if !(d.dip_deg > beams.alpha_d_deg) {
            let fix = match (site, earth.magnetic_pole) {
                (Some(_), _) => "the site's field, IGRF-14 at [site] utc, is this flat near the dip equator: choose a site farther from it, lower beams.alpha_d_deg, or set site.field = \"scene\" with beams.b_inclination_deg".to_string(),
                (None, Some(pole)) => format!(
                    "the dipole pole earth.magnetic_pole = [{}, {}] is {:.0} km away, its equator (dip 0) {:.0} km from it: move the pole nearer the curtain, or lower beams.alpha_d_deg",
                    pole[0],
                    pole[1],
                    Earth::new(earth.radius_km).central_angle(d.at, pole) * earth.radius_km,
                    std::f64::consts::FRAC_PI_2 * earth.radius_km
                ),
                (None, None) => "raise beams.b_inclination_deg or lower beams.alpha_d_deg".to_string(),
            };
            return Err(BeamError::FieldInCone { curtain: i, dip_deg: d.dip_deg, at: d.at, alpha_d_deg: beams.alpha_d_deg, fix });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::earth::MEAN_RADIUS_KM;

    fn earth(pole: Option<[f64; 2]>) -> EarthParams {
        EarthParams { radius_km: MEAN_RADIUS_KM, magnetic_pole: pole }
    }

    #[test]
    fn the_dip_is_the_smallest_over_the_start_area() {
        let b = BeamParams::default();
        let c = Curtain { center: [0.0, 0.0], length: 200.0, width: 0.0, rotation_deg: 90.0, ..Curtain::default() };
        // A uniform field: its inclination.
        assert_eq!(curtain_dip(&c, &b, &earth(None), None).dip_deg, 78.0);
        // The pole 3000 km north, the curtain along y: the far end (100 km
        // farther, magnetic latitude 90 - 3100 / R rad) dips least.
        let d = curtain_dip(&c, &b, &earth(Some([0.0, 3000.0])), None);
        let lat = 90.0 - (3100.0 / MEAN_RADIUS_KM).to_degrees();
        let want = fmath::atan(2.0 * fmath::tan(lat.to_radians())).to_degrees();
        assert!((d.dip_deg - want).abs() < 1e-6 && (d.at[1] + 100.0).abs() < 1e-9, "{d:?} vs {want}");
        // Across the dipole's equator: 0.
        let q = std::f64::consts::FRAC_PI_2 * MEAN_RADIUS_KM;
        assert_eq!(curtain_dip(&c, &b, &earth(Some([0.0, q + 10.0])), None).dip_deg, 0.0);
    }

    #[test]
    fn a_field_within_the_deflection_cone_is_refused_naming_the_curtain_and_the_dip() {
        let b = BeamParams { alpha_d_deg: 5.0, delta_alpha_deg: 3.0, ..BeamParams::default() };
        let c = vec![Curtain::default(), Curtain { center: [0.0, 0.0], ..Curtain::default() }];
        check_field(&c, &b, &earth(Some([0.0, 2000.0])), None).unwrap();
        // At the dipole's equator: refused.
        let q = std::f64::consts::FRAC_PI_2 * MEAN_RADIUS_KM;
        let e = check_field(&c, &b, &earth(Some([0.0, q])), None).unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("curtain[0]") && m.contains("beams.alpha_d_deg = 5") && m.contains("earth.magnetic_pole"), "{m}");
        assert!(e.is_input());
        // A uniform field: the dip against alpha_D.
        let b = BeamParams { alpha_d_deg: 30.0, b_inclination_deg: 30.0, delta_alpha_deg: 3.0, ..BeamParams::default() };
        let m = check_field(&c, &b, &earth(None), None).unwrap_err().to_string();
        assert!(m.contains("dips only 30.00 degrees") && m.contains("raise beams.b_inclination_deg"), "{m}");
    }

    /// IGRF-14's dip, degrees, `height_km` above a site at an hour,
    /// computed from the model and the site's WGS 84 frame alone.
    fn igrf_dip_deg(p: &crate::scene::site::SiteParams, height_km: f64) -> f64 {
        use crate::geometry::astronomy::{site::Site, time::Utc};
        let site = Site::new(p.latitude_deg, p.longitude_deg, p.height_km).unwrap();
        let b = crate::physics::igrf::Igrf::at(Utc::parse_rfc3339(&p.utc).unwrap())
            .unwrap()
            .field_itrs(site.itrs_km() + height_km * site.basis()[2]);
        let [e, n, u] = site.basis();
        fmath::atan2(-b.dot(u), fmath::hypot(b.dot(e), b.dot(n))).to_degrees()
    }

    /// A scene over `site` with one small straight curtain over it (2 km
    /// square: its start area's dip differs from its centre's by under
    /// 0.02 degree even at the dip equator, where dI/dlatitude is 2).
    fn site_scene(latitude_deg: f64, longitude_deg: f64, utc: &str) -> Scene {
        let mut s = crate::scene::presets::by_name("tromso").unwrap();
        let p = s.site.as_mut().unwrap();
        (p.latitude_deg, p.longitude_deg, p.utc) = (latitude_deg, longitude_deg, utc.to_string());
        s.curtains = vec![Curtain { center: [0.0, 0.0], length: 2.0, width: 2.0, bend_km: 0.5, path: None, ..Curtain::default() }];
        s
    }

    #[test]
    fn a_site_near_the_dip_equator_is_refused_by_the_dip_of_igrf() {
        // Off Brazil's coast, 3 N 45 W, mid-2025: IGRF-14's dip equator
        // runs here (12 S on this meridian it dips 27 degrees south).
        let mut s = site_scene(3.0, -45.0, "2025-07-01T00:00:00Z");
        (s.beams.alpha_d_deg, s.beams.delta_alpha_deg) = (5.0, 3.0);
        s.validate("s", None).unwrap();
        let want = igrf_dip_deg(s.site.as_ref().unwrap(), s.beams.top_km);
        assert!(want.abs() < s.beams.alpha_d_deg, "IGRF dips {want} degrees here");
        // The scene's own field (78 degrees) alone passes.
        check_field(&s.curtains, &s.beams, &s.earth, None).unwrap();
        let e = check_scene_field(&s).unwrap_err();
        let m = e.to_string();
        let BeamError::FieldInCone { curtain: 0, dip_deg, .. } = e else { panic!("{m}") };
        assert!((dip_deg - want.abs()).abs() < 0.05, "{dip_deg} vs IGRF's {want}");
        assert!(m.starts_with("curtain[0]") && m.contains(&format!("dips only {dip_deg:.2} degrees")) && m.contains("IGRF-14"), "{m}");
        // With the scene's field instead of IGRF's, the scene is baked.
        s.site.as_mut().unwrap().field = crate::scene::site::SiteField::Scene;
        check_scene_field(&s).unwrap();
    }

    #[test]
    fn a_high_latitude_site_is_accepted_by_its_steep_igrf_field() {
        // Tromso: IGRF dips 78.5 degrees; the scene's own 10-degree field
        // within alpha_D = 20 would be refused.
        let mut s = site_scene(69.65, 18.96, "2026-12-18T18:00:00Z");
        (s.beams.b_inclination_deg, s.beams.alpha_d_deg, s.beams.delta_alpha_deg) = (10.0, 20.0, 3.0);
        s.validate("s", None).unwrap();
        let want = igrf_dip_deg(s.site.as_ref().unwrap(), s.beams.top_km);
        let site = SiteField::of_scene(&s).unwrap();
        let d = curtain_dip(&s.curtains[0], &s.beams, &s.earth, Some(&site)).dip_deg;
        assert!((d - want).abs() < 0.05 && want > 78.0, "{d} vs IGRF's {want}");
        check_scene_field(&s).unwrap();
        s.site.as_mut().unwrap().field = crate::scene::site::SiteField::Scene;
        let m = check_scene_field(&s).unwrap_err().to_string();
        assert!(m.contains("dips only 10.00 degrees") && m.contains("raise beams.b_inclination_deg"), "{m}");
    }
}
