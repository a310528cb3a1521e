//! The emission's colour: `[colour]` (the line model and the colour mode)
//! with its defaults.
//! [`COLOUR_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

/// Whose colours (`observer`): "camera" (default) or "eye" (CIE 1931).
pub use crate::util::observer::Observer;

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ColourMode {
    /// Emission lines OI 557.7, OI 630.0, N2+ 427.8 through CIE 1931.
    Physical,
    /// Artist colour map: altitude -> RGB table.
    Colormap,
}

/// The line model of `mode = "physical"`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LineModel {
    /// The ion and excited-state chemistry (`crate::physics::chemistry`), driven by
    /// the local ionization rate at each deposit (default).
    Chemistry,
    /// The altitude-only parameterisation (`spectrum::EmissionModel`).
    Simple,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ColourParams {
    pub mode: ColourMode,
    /// Line model of the physical colours: "chemistry" or "simple".
    pub lines: LineModel,
    /// Whose colours the lines get: "camera" (a digital camera at daylight
    /// white balance, as photographs record aurora) or "eye" (the CIE 1931
    /// observer). The bake writes that observer's RGB; the renderer's air
    /// weighs its channels for it (`crate::util::observer`).
    pub observer: Observer,
    /// The camera observer's white balance, K (`crate::util::white_balance`):
    /// the PNG shows the linear image through it, as exposure; the EXR
    /// stays at the camera table's daylight balance. The eye has none.
    pub white_balance_k: f64,
    /// Amplitude of the low-frequency 1D noise on the altitude used for colour, km.
    pub noise_km: f64,
    /// Spatial frequency of that noise, cycles per km (along the curtain).
    pub noise_freq: f64,
    /// Artist colour map: rows of [altitude_km, r, g, b] (linear Rec.709, per
    /// unit deposited power), ascending altitude. Used when mode = "colormap".
    pub colormap: Vec<[f64; 4]>,
}

impl Default for ColourParams {
    fn default() -> Self {
        Self {
            mode: ColourMode::Physical,
            lines: LineModel::Chemistry,
            observer: Observer::Camera,
            white_balance_k: DEFAULT_WHITE_BALANCE_K,
            noise_km: 8.0,
            noise_freq: 0.02,
            colormap: report_colormap(),
        }
    }
}

/// The default white balance, K: within the 3200-4000 K aurora
/// photographers set (docs/colour.md).
pub const DEFAULT_WHITE_BALANCE_K: f64 = 3200.0;

/// The report's hand-tuned look as an artist colour map: green low,
/// fading through yellow to red and violet high up (altitude in km).
pub fn report_colormap() -> Vec<[f64; 4]> {
    vec![
        [95.0, 0.05, 0.6, 0.25],
        [110.0, 0.1, 1.0, 0.35],
        [150.0, 0.25, 0.9, 0.3],
        [190.0, 0.7, 0.4, 0.2],
        [240.0, 0.9, 0.15, 0.25],
        [300.0, 0.5, 0.05, 0.4],
    ]
}

/// Every key of `[colour]`: name, unit, allowed range and description (`super::keys`).
pub const COLOUR_KEYS: &[KeySpec] = &[
    KeySpec::new("mode", "", Range::Word(&["physical", "colormap"]), "`physical` (the emission lines through the observer's colour response, `observer`) or `colormap` (the `colormap` table)"),
    KeySpec::new("observer", "", Range::Word(&["camera", "eye"]), "whose colours the lines get: `camera` (a digital camera, the Nikon D5100 measured by Darrodi et al. 2015, at daylight white balance with a ColorChecker-fitted matrix: 557.7 nm a saturated green, as photographs show it) or `eye` (the CIE 1931 observer: 557.7 nm yellow-green); the bake writes its RGB and the air's channels are weighed for it (docs/colour.md)"),
    KeySpec::new("white_balance_k", "K", Range::Num(Num::closed(1500.0, 20000.0)), "the camera's white balance: a grey lit by a Planckian at this temperature comes out grey (von Kries on the camera's raw response, then its matrix; docs/colour.md); the PNG shows the linear image through it, the EXR stays at daylight balance; the `eye` observer has none. 3200 K: a camera's Tungsten preset, the low end of the 3200-4000 K aurora photographers set"),
    KeySpec::new("lines", "", Range::Word(&["chemistry", "simple"]), "the line model of `mode = \"physical\"`: `chemistry` (steady-state ion and excited-state chemistry driven by the local ionization rate, after NCAR GLOW's; docs/physics.md) or `simple` (yields in proportion to mole fractions, one quencher per state: the older rule of thumb)"),
    KeySpec::new("noise_km", "km", Range::Num(Num::closed(0.0, 200.0)), "amplitude of the low-frequency noise on the altitude used for colour (not intensity)"),
    KeySpec::new("noise_freq", "1/km", Range::Num(Num::closed(0.0, 1e3)), "spatial frequency of that noise along the curtain"),
    KeySpec::new("colormap", "km, linear Rec.709", Range::Rule("rows of [altitude_km, r, g, b], at least 2, altitudes ascending, colours >= 0 (mode = \"colormap\")"), "rows `[altitude_km, r, g, b]` (colour per unit deposited power), altitudes ascending, used when `mode = \"colormap\"`; the default is the 2014 report's look"),
];
