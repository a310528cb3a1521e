//! The emission's colour: `[colour]` (the line model and the colour mode)
//! with its defaults. No checks here (`super::validation`).

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
            noise_km: 8.0,
            noise_freq: 0.02,
            colormap: report_colormap(),
        }
    }
}

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
