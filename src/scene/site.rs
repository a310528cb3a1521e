//! `[site]`: where on the Earth and when the scene is, for the real sky
//! over it (the stars of a catalogue, the Moon, the Sun:
//! `crate::geometry::astronomy`). Without `[site]` the scene is the local
//! frame it always was, with a statistical star field and no Moon.
//! [`SITE_KEYS`]: each key's unit, allowed range and description.
//!
//! With a site, the scene's frame is the site's: its origin on the ground
//! at the site, x east, y north and z along the WGS 84 ellipsoid's normal
//! there (the direction a plumb line and a camera's level give; the round
//! Earth of `[earth]` is the sphere tangent to it at the origin). The hour
//! of a picture is `utc + animation.time_s`: frame N of a sequence is at
//! `utc + time_s + (N - 1) / fps`, so the sky turns with the frames.
//!
//! **The field.** With a site the beams follow the Earth's field, IGRF-14
//! at the hour (`field = "igrf"`, the default:
//! `crate::physics::site_field`), which replaces `beams.b_inclination_deg`,
//! `b_declination_deg` and `earth.magnetic_pole`; `field = "scene"` keeps
//! those keys' field under the site's sky.

use super::keys::{KeySpec, Num, Range};
use crate::util::fmath;
use serde::{Deserialize, Serialize};

/// The site and the hour (module documentation).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SiteParams {
    /// Geodetic latitude (WGS 84), degrees north.
    pub latitude_deg: f64,
    /// Longitude, degrees east.
    pub longitude_deg: f64,
    /// The ground's height above the WGS 84 ellipsoid at the site, km.
    #[serde(default)]
    pub height_km: f64,
    /// The hour of the scene's time 0, RFC 3339 (`2026-12-07T22:00:00Z`).
    pub utc: String,
    /// The air's temperature at the site, for refraction, degrees Celsius.
    #[serde(default = "default_temperature_c")]
    pub temperature_c: f64,
    /// The air's pressure at the site, for refraction, hPa; none: the
    /// standard pressure at the site's height, `1010 exp(-height / 9.1 km)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_hpa: Option<f64>,
    /// The field the beams follow (module documentation).
    #[serde(default)]
    pub field: SiteField,
}

/// Which field the beams of a scene with a site follow.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SiteField {
    /// IGRF-14 at the site and the hour.
    #[default]
    Igrf,
    /// The scene's own: `beams.b_inclination_deg` and `b_declination_deg`,
    /// or the dipole of `earth.magnetic_pole`.
    Scene,
}

fn default_temperature_c() -> f64 {
    -10.0
}

impl SiteParams {
    /// The pressure refraction is computed with, hPa (`pressure_hpa`, or
    /// the standard pressure at `height_km`: the same rule skyfield applies).
    pub fn pressure_or_standard_hpa(&self) -> f64 {
        self.pressure_hpa.unwrap_or_else(|| 1010.0 * fmath::exp(-self.height_km / 9.1))
    }
}

/// Every key of `[site]`: name, unit, allowed range and description (`super::keys`).
pub const SITE_KEYS: &[KeySpec] = &[
    KeySpec::new("latitude_deg", "deg", Range::Num(Num::closed(-90.0, 90.0)), "geodetic latitude of the site (WGS 84), north positive; required in `[site]`"),
    KeySpec::new("longitude_deg", "deg", Range::Num(Num::closed(-180.0, 360.0)), "longitude of the site, east positive; required in `[site]`"),
    KeySpec::new("height_km", "km", Range::Num(Num::closed(-0.5, 9.0)), "the ground's height above the WGS 84 ellipsoid at the site (the Moon's parallax, the standard pressure)"),
    KeySpec::new(
        "utc",
        "",
        Range::Rule("an RFC 3339 time between 1900 and 2100, such as \"2026-12-07T22:00:00Z\" or \"2026-12-07T23:00:00+01:00\""),
        "the hour of the scene's time 0: a picture is at `utc + animation.time_s`, frame N of a sequence at `utc + time_s + (N - 1) / fps`; required in `[site]`",
    ),
    KeySpec::new("temperature_c", "C", Range::Num(Num::closed(-90.0, 60.0)), "the air's temperature at the site, for the refraction of the stars, the Moon and the Sun (Bennett 1982)"),
    KeySpec::new("pressure_hpa", "hPa", Range::Num(Num::closed(0.0, 1100.0)), "the air's pressure at the site, for refraction; omitted: the standard pressure at `height_km`, 1010 exp(-height_km / 9.1) hPa"),
    KeySpec::new(
        "field",
        "",
        Range::Word(&["igrf", "scene"]),
        "the field the beams follow: `igrf` (the Earth's, IGRF-14 at the site and `utc`, 1900-2030; it replaces `beams.b_inclination_deg`, `b_declination_deg` and `earth.magnetic_pole`) or `scene` (those keys' field, as without a site)",
    ),
];
