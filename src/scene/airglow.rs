//! `[airglow]`: the night sky's own light, seen behind the volume by the
//! reference renderer (`crate::physics::airglow` holds the model and its
//! sources). Render-only: no stage of the bake reads it. No checks here
//! beyond [`AirglowParams::ranges`], which `super::validation` applies.

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

impl AirglowParams {
    /// Each numeric key with its allowed range `[lo, hi]` (inclusive).
    pub fn ranges(&self) -> [(&'static str, f64, f64, f64); 5] {
        [
            ("scale", self.scale, 0.0, 100.0),
            ("green_r", self.green_r, 0.0, MAX_ZENITH_R),
            ("red_r", self.red_r, 0.0, MAX_ZENITH_R),
            ("sodium_r", self.sodium_r, 0.0, MAX_ZENITH_R),
            ("hydroxyl_r", self.hydroxyl_r, 0.0, MAX_ZENITH_R),
        ]
    }
}
