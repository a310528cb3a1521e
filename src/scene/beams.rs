//! `[beams]`: how many electron beams, how they deposit their energy and
//! where they start, with the defaults.
//! [`BEAMS_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

/// Electron beams traced down the geomagnetic field (Baranoski et al. 2000).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct BeamParams {
    /// Total number of beams over all curtains; with `target_noise > 0`, the
    /// most the noise target may use.
    pub count: usize,
    /// Relative RMS noise of the emission grid to aim for (0 = off: use
    /// `count`). A pilot bake measures the scene's noise and sets the beam
    /// count from it (`crate::pipeline::bake::pilot`), at most `count`.
    pub target_noise: f64,
    /// Altitude where beams start, km.
    pub top_km: f64,
    /// Amplitude of the high-frequency 1D Perlin noise on the start height, km.
    pub top_noise_km: f64,
    /// Spatial frequency of that noise along the curtain, cycles per km.
    pub top_noise_freq: f64,
    /// Upper bound of the deflection angle alpha_D, degrees, in [0, 90).
    pub alpha_d_deg: f64,
    /// Width of the deflection angle range: alpha in [alpha_D - delta, alpha_D].
    pub delta_alpha_deg: f64,
    /// Beam length L, km: steps are s = L * dt * u along B.
    pub length_km: f64,
    /// Step parameter dt; at most 1/dt deflections per beam.
    pub dt: f64,
    /// Magnetic inclination (dip) angle, degrees below the horizon (90 = vertical).
    pub b_inclination_deg: f64,
    /// Magnetic declination: azimuth of B's horizontal part, degrees from +y towards +x.
    pub b_declination_deg: f64,
    /// How a beam deposits its energy (`crate::pipeline::beams`): `expected` (the
    /// curtain's whole spectrum on every beam, Fang et al. 2010 integrated),
    /// `sampled` (one energy per beam, Fang 2010 monoenergetic) or `csda`
    /// (one energy per beam, straight-line continuous slowing down: the
    /// model before Fang, kept for comparison).
    pub deposition: Deposition,
    /// How beam starts are placed over the footprint (`crate::pipeline::beams::starts`).
    pub starts: BeamStarts,
}

impl Default for BeamParams {
    fn default() -> Self {
        Self {
            count: 8_000,
            target_noise: 0.0,
            top_km: 260.0,
            top_noise_km: 6.0,
            top_noise_freq: 0.5,
            alpha_d_deg: 0.0,
            delta_alpha_deg: 0.0,
            length_km: 400.0,
            dt: 0.0025,
            b_inclination_deg: 78.0,
            b_declination_deg: 0.0,
            deposition: Deposition::Expected,
            starts: BeamStarts::Stratified,
        }
    }
}

/// Beam energy deposition model; see [`BeamParams::deposition`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Deposition {
    Expected,
    Sampled,
    Csda,
}

/// Placement of beam starts over the footprint, in proportion to its flux.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BeamStarts {
    /// Low-discrepancy: beam i takes point i of a randomly shifted R2
    /// sequence, mapped through the footprint's flux (default).
    Stratified,
    /// Independent random points (for comparison).
    Random,
}

/// Every key of `[beams]`: name, unit, allowed range and description (`super::keys`).
pub const BEAMS_KEYS: &[KeySpec] = &[
    KeySpec::new("count", "", Range::Int { min: 1, max: 100_000_000 }, "beams over all curtains; with `target_noise`, the most it may use"),
    KeySpec::new("target_noise", "", Range::Num(Num::closed(0.0, 1.0)), "relative RMS noise of the emission grid to aim for (0 = off: use `count`): a pilot of 2 x 500 and 2 x 125 beams measures the scene's noise and sets the beam count from the law `noise^2 = a/N + b/N^1.5` fitted to them, at most `count`; `bake.json` `stats.noise` says what it measured and chose"),
    KeySpec::new("top_km", "km", Range::Num(Num::closed(80.0, 1000.0)), "altitude where beams start"),
    KeySpec::new("top_noise_km", "km", Range::Num(Num::closed(0.0, 100.0)), "amplitude of the high-frequency 1D noise on the start height"),
    KeySpec::new("top_noise_freq", "1/km", Range::Num(Num::closed(0.0, 1e3)), "spatial frequency of that noise along the curtain"),
    KeySpec::new("alpha_d_deg", "deg", Range::Num(Num::open_max(0.0, 90.0)), "upper bound alpha_D of the deflection angle; a curtain whose field dips no more than alpha_D below the horizon where its beams start is refused (its electrons could go up or sideways)").note("degrees: at 90 a beam no longer moves along B"),
    KeySpec::new("delta_alpha_deg", "deg", Range::Rule("in [0, beams.alpha_d_deg]"), "width of the deflection range: alpha is uniform in [alpha_D - delta, alpha_D]"),
    KeySpec::new("length_km", "km", Range::Num(Num::POSITIVE), "beam length L: a step is s = L dt u along B (u uniform)"),
    KeySpec::new("dt", "", Range::Num(Num::closed(1e-6, 1.0)), "step parameter: at most 1/dt deflections per beam (`csda` only: Fang beams go on until their deposition is complete)"),
    KeySpec::new("b_inclination_deg", "deg", Range::Num(Num::closed(10.0, 90.0)), "the geomagnetic field's dip below the horizon (90 = vertical); a `[site]` with `field = \"igrf\"` (its default) replaces it with IGRF-14"),
    KeySpec::new("b_declination_deg", "deg", Range::Num(Num::FINITE), "azimuth of the field's horizontal part, from +y towards +x; a `[site]` with `field = \"igrf\"` (its default) replaces it with IGRF-14"),
    KeySpec::new("deposition", "", Range::Word(&["expected", "sampled", "csda"]), "how a beam deposits its energy: `expected` (the curtain's whole spectrum on every beam, Fang et al. 2010 integrated over it), `sampled` (one energy per beam, Fang 2010 monoenergetic: the same mean, more noise) or `csda` (one energy per beam, straight-line continuous slowing down, for comparison; the `seed2014` preset uses it)"),
    KeySpec::new("starts", "", Range::Word(&["stratified", "random"]), "beam starts over the footprint, in proportion to its flux: `stratified` (beam i takes point i of a seeded R2 low-discrepancy sequence, whatever the count or thread count) or `random` (independent points, for comparison)"),
];
