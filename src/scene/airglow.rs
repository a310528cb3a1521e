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
    /// Zenith brightness of the OH Meinel bands of the visible red
    /// (6-1, 7-2 and 8-3, about 87 km), all three together, rayleigh.
    pub hydroxyl_r: f64,
}

impl Default for AirglowParams {
    fn default() -> Self {
        Self { on: true, scale: 1.0, green_r: 250.0, red_r: 60.0, sodium_r: 50.0, hydroxyl_r: 450.0 }
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
        "zenith brightness of the OH Meinel bands of the visible red (6-1, 7-2, 8-3 at 650-727 nm, 87 km), together",
    ),
];
