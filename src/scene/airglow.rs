//! `[airglow]`: the night sky's own light, seen behind the volume by the
//! reference renderer (`crate::physics::airglow` holds the model and its
//! sources). Render-only: no stage of the bake reads it. Its keys'
//! ranges are [`AIRGLOW_KEYS`].

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AirglowParams {
    /// Draw the airglow layers behind the volume (camera rays only).
    pub on: bool,
    /// Scale on every layer's brightness.
    pub scale: f64,
    /// Zenith brightness of the OI 557.7 nm layer (about 97 km), rayleigh.
    pub green_r: f64,
    /// Zenith brightness of the OI 630.0 nm layer (about 250 km), rayleigh;
    /// OI 636.4 nm comes with it at 1 / 2.997 of it.
    pub red_r: f64,
    /// Zenith brightness of the sodium D lines (589 nm, about 92 km), rayleigh.
    pub sodium_r: f64,
    /// Zenith brightness of the OH Meinel bands from 558 to 727 nm ((7-1),
    /// (8-2), (5-0), (9-3), (6-1), (7-2), (8-3); about 87 km), together, rayleigh.
    pub hydroxyl_r: f64,
    /// Zenith brightness of the airglow continuum (about 90 km) at 550 nm, R/nm.
    pub continuum_r_per_nm: f64,
    /// Zodiacal light at 500 nm, 10^-8 W m^-2 sr^-1 um^-1 (Leinert et al. 1998's unit).
    pub zodiacal_light: f64,
    /// Integrated starlight (stars fainter than those drawn) at 500 nm, same unit.
    pub starlight: f64,
}

impl Default for AirglowParams {
    fn default() -> Self {
        Self {
            on: true,
            scale: 1.0,
            green_r: 250.0,
            red_r: 60.0,
            sodium_r: 50.0,
            hydroxyl_r: 450.0,
            // The typical dark sky of `crate::physics::night_sky::broadband`.
            continuum_r_per_nm: 1.0,
            zodiacal_light: 90.0,
            starlight: 50.0,
        }
    }
}

/// Upper bound of a layer's zenith brightness, R: ten times the brightest
/// nightglow reported for any of these emissions (a few kR of 630.0 nm in
/// a stable auroral red arc); beyond it the "airglow" is aurora.
pub const MAX_ZENITH_R: f64 = 1e4;

/// Every key of `[airglow]`: name, unit, allowed range and description (`super::keys`).
pub const AIRGLOW_KEYS: &[KeySpec] = &[
    KeySpec::new("on", "", Range::Any, "draw the airglow behind the volume (`false`: a black sky, as before it existed)"),
    KeySpec::new("scale", "", Range::Num(Num::closed(0.0, 100.0)), "scale on every layer's zenith brightness"),
    KeySpec::new("green_r", "R", Range::Num(Num::closed(0.0, MAX_ZENITH_R)), "zenith brightness of the OI 557.7 nm layer (97 km)"),
    KeySpec::new(
        "red_r",
        "R",
        Range::Num(Num::closed(0.0, MAX_ZENITH_R)),
        "zenith brightness of the OI 630.0 nm layer (250 km); OI 636.4 nm comes with it at 1 / 2.997",
    ),
    KeySpec::new("sodium_r", "R", Range::Num(Num::closed(0.0, MAX_ZENITH_R)), "zenith brightness of the sodium D lines (589 nm, 92 km)"),
    KeySpec::new(
        "hydroxyl_r",
        "R",
        Range::Num(Num::closed(0.0, MAX_ZENITH_R)),
        "zenith brightness of the OH Meinel bands from 558 to 727 nm ((7-1) 558, (8-2) 588, (5-0) 615, (9-3) 625, (6-1) 650, (7-2) 686 dimmed by the O2 B band, (8-3) 727; 87 km), together",
    ),
    KeySpec::new(
        "continuum_r_per_nm",
        "R/nm",
        Range::Num(Num::closed(0.0, 100.0)),
        "zenith brightness of the airglow continuum (NO2, 90 km) at 550 nm; yellow-green, broad across the visible (Khomich et al. 2008; Noll et al. 2012)",
    ),
    KeySpec::new(
        "zodiacal_light",
        "1e-8 W m-2 sr-1 um-1",
        Range::Num(Num::closed(0.0, 1e4)),
        "zodiacal light at 500 nm, sunlight's colour, outside the air (Leinert et al. 1998, Table 17: 77 at the ecliptic pole, 259 in the ecliptic at 90 degrees from the Sun); 90 is a dark winter sky far from the Sun",
    ),
    KeySpec::new(
        "starlight",
        "1e-8 W m-2 sr-1 um-1",
        Range::Num(Num::closed(0.0, 1e4)),
        "integrated light of the stars fainter than those drawn, at 500 nm, a G-K star's colour, outside the air (Leinert et al. 1998, sect. 6); 50 is middle to high galactic latitude",
    ),
];
