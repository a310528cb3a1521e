//! The sky over a site at an hour (`[site]`, `crate::scene::site`): the
//! catalogue's stars where they are, the Moon, and the Sun's elevation.
//!
//! **Stars.** Every star of the compiled-in Hipparcos-2 table
//! (`crate::physics::night_sky::catalogue`) down to
//! `background.limiting_magnitude` is moved by its proper motion from the
//! catalogue's epoch to the hour, placed by `crate::geometry::astronomy`
//! (precession, nutation, annual aberration, the Earth's rotation, the
//! site's WGS 84 frame) and raised by the refraction of the site's air
//! (Bennett 1982, `[site] temperature_c` and `pressure_hpa`). Its
//! irradiance is `E_0 10^(-0.4 V)` (`sky.rs`), V from the table, its
//! colour a blackbody at the temperature of its B-V (Ballesteros 2012)
//! through the scene's observer, luminance 1. Fainter than the table's
//! limit and down to the limiting magnitude, stars are drawn statistically
//! as without a site (`sky.rs`), only between the two magnitudes.
//!
//! **The Moon** (`moon.rs`): its topocentric place (Meeus 1998 ch. 47 with
//! the site's parallax), refracted, its phase angle and bright limb; the
//! disc and its light only while its centre is above the geometric horizon
//! less its radius and the refraction there, that is when any of it can be
//! up. **The Sun** is only reported: a scene whose Sun is above -12 degrees
//! (nautical twilight) gets a warning naming its elevation, for the sky has
//! no twilight yet.

use super::moon::MoonSky;
use super::stars::{spectrum_rgb, Star, MAG0_KR_SR};
use crate::geometry::astronomy::{frame::SkyFrame, moon::moon_view, refraction, site::Site, sun::sun_enu, time::Utc};
use crate::physics::night_sky::{catalogue, star_colour};
use crate::scene::SiteParams;
use crate::util::fmath;
use crate::util::observer::Observer;

/// The Sun's elevation above which a scene is warned: nautical twilight.
pub const TWILIGHT_SUN_DEG: f64 = -12.0;

/// A site at its hour: the place, the time and the air that refracts.
#[derive(Clone, Debug, PartialEq)]
pub struct SiteHour {
    pub site: Site,
    pub utc: Utc,
    pub air: refraction::Air,
}

impl SiteHour {
    /// `[site]` at the scene's time `time_s` (seconds after `utc`);
    /// the time was checked by the scene's validation.
    pub fn of(p: &SiteParams, time_s: f64) -> Result<SiteHour, String> {
        let utc = Utc::parse_rfc3339(&p.utc).map_err(|e| format!("site.utc = \"{}\": {e}", p.utc))?;
        Ok(SiteHour {
            site: Site { latitude_deg: p.latitude_deg, longitude_deg: p.longitude_deg, height_km: p.height_km },
            utc: utc.plus_seconds(time_s),
            air: refraction::Air { temperature_c: p.temperature_c, pressure_hpa: p.pressure_or_standard_hpa() },
        })
    }

    /// The rotation and motions of the sky at this hour.
    pub fn frame(&self) -> SkyFrame {
        SkyFrame::new(&self.site, self.utc)
    }

    /// The Sun's apparent (refracted) elevation, degrees.
    pub fn sun_elevation_deg(&self) -> f64 {
        let f = self.frame();
        let d = refraction::refract(sun_enu(&f), &self.air);
        fmath::asin(d.z.clamp(-1.0, 1.0)).to_degrees()
    }

    /// The warning for a Sun above [`TWILIGHT_SUN_DEG`], if any.
    pub fn twilight_warning(&self) -> Option<String> {
        let e = self.sun_elevation_deg();
        (e > TWILIGHT_SUN_DEG).then(|| {
            format!(
                "the Sun is {e:.1} degrees {} the horizon at the site at {}: above {TWILIGHT_SUN_DEG} degrees (nautical twilight) the real sky is \
                 brighter than aurora's, which has no twilight or daylight model; the picture shows the night sky",
                if e >= 0.0 { "above" } else { "below" },
                self.utc.to_rfc3339()
            )
        })
    }
}

/// The catalogue's stars at `hour` down to `limiting_magnitude`, and the
/// statistical ones between the table's limit and it (module doc),
/// `brightness` times the physical irradiance, coloured for `observer`.
pub fn site_stars(hour: &SiteHour, limiting_magnitude: f64, brightness: f64, observer: Observer, seed: u64) -> Vec<Star> {
    let frame = hour.frame();
    let mut colours = std::collections::HashMap::new();
    let mut stars: Vec<Star> = catalogue::catalogue()
        .iter()
        .take_while(|s| s.v_mag <= limiting_magnitude)
        .map(|s| {
            let dir = refraction::refract(frame.star_enu(&s.place()), &hour.air);
            // Colours by B-V to 0.01 mag, each computed once.
            let key = (s.b_minus_v * 100.0).round() as i64;
            let (colour, t) = *colours.entry(key).or_insert_with(|| {
                let t = star_colour::temperature_k(key as f64 / 100.0);
                (spectrum_rgb(observer, |l| super::stars::planck(l, t)), t)
            });
            let e = brightness * MAG0_KR_SR * fmath::powf(10f64, -0.4 * s.v_mag);
            Star { dir, magnitude: s.v_mag, irradiance: colour.map(|c| c * e), temperature_k: t }
        })
        .collect();
    if limiting_magnitude > catalogue::CATALOGUE_LIMIT_V {
        stars.extend(
            super::stars::star_field(seed, limiting_magnitude, brightness, observer)
                .into_iter()
                .filter(|s| s.magnitude > catalogue::CATALOGUE_LIMIT_V),
        );
    }
    stars
}

/// The Moon at `hour` when any of it can be above the horizon, with the
/// air's V extinction coefficient `k_v` (`moon.rs`).
pub fn site_moon(hour: &SiteHour, k_v: f64, observer: Observer) -> Option<MoonSky> {
    let m = moon_view(&hour.frame());
    let dir = refraction::refract(m.enu, &hour.air);
    let r = m.angular_radius_deg.to_radians();
    if dir.z < -fmath::sin(r) {
        return None;
    }
    Some(MoonSky::new(dir, m.bright_limb_enu, r, m.phase_angle_deg, m.illuminated_fraction, m.distance_km, k_v, observer))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn hour(utc: &str, time_s: f64, pressure_hpa: f64) -> SiteHour {
        let p = SiteParams {
            latitude_deg: 69.65,
            longitude_deg: 18.96,
            height_km: 0.0,
            utc: utc.into(),
            temperature_c: -10.0,
            pressure_hpa: Some(pressure_hpa),
            field: Default::default(),
        };
        SiteHour::of(&p, time_s).unwrap()
    }

    /// The sky turns about the celestial pole at the sidereal rate: an
    /// hour later every star has moved 15.041 degrees in hour angle
    /// (360 / 23.934 h), within 0.003 degrees (aberration and precession
    /// change by under an arcsecond in an hour), refraction off (no air).
    /// A model that turned the sky at the solar rate (15.000) fails by 0.04.
    #[test]
    fn an_hour_later_the_stars_have_turned_15_041_degrees_about_the_pole() {
        let (a, b) = (hour("2026-12-18T18:00:00Z", 0.0, 0.0), hour("2026-12-18T18:00:00Z", 3600.0, 0.0));
        let (sa, sb) = (site_stars(&a, 3.0, 1.0, Observer::Camera, 1), site_stars(&b, 3.0, 1.0, Observer::Camera, 1));
        assert_eq!(sa.len(), sb.len());
        assert!(sa.len() > 150, "{}", sa.len());
        let lat = 69.65f64.to_radians();
        let pole = DVec3::new(0.0, fmath::cos(lat), fmath::sin(lat));
        let east = DVec3::Z.cross(pole).normalize();
        let north_of_pole = pole.cross(east);
        let angle = |d: DVec3| {
            let p = d - pole * d.dot(pole);
            fmath::atan2(p.dot(east), p.dot(north_of_pole)).to_degrees()
        };
        for (x, y) in sa.iter().zip(&sb).filter(|(x, _)| x.dir.dot(pole).abs() < 0.9) {
            // Westward: the angle from the pole's meridian grows with the hour.
            let turn = (angle(y.dir) - angle(x.dir)).rem_euclid(360.0);
            assert!((turn - 15.041).abs() < 0.003, "{turn} for a star of magnitude {}", x.magnitude);
        }
    }

    /// Above -12 degrees the Sun is named in a warning; at night there is none.
    #[test]
    fn a_sun_above_nautical_twilight_is_warned_of() {
        let night = hour("2026-12-18T18:00:00Z", 0.0, 1010.0);
        assert!(night.sun_elevation_deg() < -25.0, "{}", night.sun_elevation_deg());
        assert!(night.twilight_warning().is_none());
        let noon = hour("2026-06-21T11:00:00Z", 0.0, 1010.0);
        let w = noon.twilight_warning().expect("a warning at midsummer noon");
        assert!(w.contains("the Sun is") && w.contains("above the horizon"), "{w}");
    }

    /// The catalogue's stars are drawn to the limiting magnitude, and the
    /// brightest is Sirius (V -1.46) when it is up or not: the list holds
    /// stars below the horizon too (the renderer hides them).
    #[test]
    fn the_catalogue_gives_the_stars_to_the_limit() {
        let h = hour("2026-12-18T18:00:00Z", 0.0, 1010.0);
        let s = site_stars(&h, 4.0, 1.0, Observer::Camera, 1);
        assert!(s.iter().all(|x| x.magnitude <= 4.0));
        assert!((s[0].magnitude + 1.46).abs() < 0.05, "{}", s[0].magnitude);
        // About 500 stars to V = 4 over the whole sky (Allen).
        assert!((400..700).contains(&s.len()), "{}", s.len());
    }
}
