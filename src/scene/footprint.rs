//! `[footprint]`: the vortex sheet or the 2014 report's fluid that shapes
//! each curtain's footprint, with its defaults.
//! [`FOOTPRINT_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

/// How a footprint is made (`crate::pipeline::footprint`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum FootprintModel {
    /// A vortex sheet rolled up by the Kelvin-Helmholtz instability
    /// (`crate::pipeline::footprint::sheet`), drawn with rays along it.
    Sheet,
    /// The 2014 report's sine-modulated band folded by a short stable-fluids
    /// run (Stam 1999): the `band_fraction`, `velocity_*`, `density_waves`,
    /// `steps`, `dt` and `pressure_iterations` keys.
    Fluid2014,
}

/// The footprint of each curtain: the vortex sheet (default) or the 2014
/// report's 2D stable-fluids simulation (Stam 1999).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct FootprintParams {
    /// "sheet" (a rolled-up vortex sheet) or "fluid2014" (the report's fluid).
    pub model: FootprintModel,
    /// Grid cells along and across the curtain.
    pub resolution: [usize; 2],
    /// Number of simulation steps.
    pub steps: usize,
    /// Time step in cell units (semi-Lagrangian advection is stable for any).
    pub dt: f64,
    /// Gauss-Seidel / Jacobi iterations of the pressure projection.
    pub pressure_iterations: usize,
    /// Initial band thickness as a fraction of the footprint width.
    pub band_fraction: f64,
    /// Number of sine periods of the initial velocity along the band.
    pub velocity_waves: f64,
    /// Initial velocity amplitude, cells per unit time.
    pub velocity_amplitude: f64,
    /// Number of sine periods of the initial density modulation along the band.
    pub density_waves: f64,
    /// Wavelength of the noise curve that bends the band, in curtain lengths.
    pub bend_wavelength: f64,
    /// Footprint densities below this (of a peak of 1) emit no beams.
    pub threshold: f64,
    /// Length over which the footprint fades to 0 at each end of the
    /// curtain (a smooth step), km; 0 keeps straight ends.
    pub end_fade_km: f64,
    /// Sheet: spacing of the vortex markers along it at the start, km.
    pub sheet_spacing_km: f64,
    /// Sheet: smoothing length of the vortex-blob kernel, km (the scale
    /// below which the sheet does not curl).
    pub sheet_smoothing_km: f64,
    /// Sheet: amplitude of the initial displacement spectrum (its slope at
    /// wavelengths of 200 km and more, dimensionless).
    pub sheet_amplitude: f64,
    /// Sheet: how far it rolls up: the velocity jump across it times the
    /// time integrated, km.
    pub sheet_rollup_km: f64,
    /// Sheet: Runge-Kutta steps of the roll-up.
    pub sheet_steps: usize,
    /// Sheet: full width at half maximum of the sheet across itself, km:
    /// the arc's body.
    pub sheet_thickness_km: f64,
    /// Sheet: full width at half maximum of a filament inside the arc, km
    /// (`curtain.filament_energy_flux`).
    pub filament_width_km: f64,
    /// Sheet: filaments inside each arc, parallel to its centre line.
    pub filament_count: usize,
    /// Sheet: mean spacing of the rays along it, km.
    pub ray_spacing_km: f64,
    /// Sheet: width (Gaussian sigma) of a ray along it, km.
    pub ray_width_km: f64,
    /// Sheet: brightest ray over the faintest (brightness log-uniform in
    /// [1, ray_contrast]).
    pub ray_contrast: f64,
    /// Sheet: diffuse glow between the rays, a 3 km blur of the sheet with
    /// this peak (of the sheet's 1).
    pub glow: f64,
    /// For validation: a footprint of density 1 over the whole box (no
    /// fluid, no band, no bend), so every beam carries the curtain's
    /// `energy_flux` and line yields that depend on the local flux can be
    /// compared with a one-dimensional model (NCAR GLOW) at a known flux.
    pub uniform: bool,
}

impl Default for FootprintParams {
    fn default() -> Self {
        Self {
            model: FootprintModel::Sheet,
            resolution: [512, 128],
            steps: 12,
            dt: 1.0,
            pressure_iterations: 40,
            band_fraction: 0.08,
            velocity_waves: 6.0,
            velocity_amplitude: 2.5,
            density_waves: 9.0,
            bend_wavelength: 0.6,
            threshold: 0.03,
            end_fade_km: 25.0,
            sheet_spacing_km: 0.4,
            sheet_smoothing_km: 0.8,
            sheet_amplitude: 0.05,
            sheet_rollup_km: 30.0,
            sheet_steps: 20,
            sheet_thickness_km: 8.0,
            filament_width_km: 0.1,
            filament_count: 3,
            ray_spacing_km: 3.0,
            ray_width_km: 0.4,
            ray_contrast: 10.0,
            glow: 0.0,
            uniform: false,
        }
    }
}

/// Every key of `[footprint]`: name, unit, allowed range and description (`super::keys`).
pub const FOOTPRINT_KEYS: &[KeySpec] = &[
    KeySpec::new("model", "", Range::Word(&["sheet", "fluid2014"]), "`sheet`: a vortex sheet rolled up by the Kelvin-Helmholtz instability, with rays along it; `fluid2014`: the 2014 report's band folded by a stable fluid (the `steps` to `density_waves` keys)"),
    KeySpec::new("resolution", "cells", Range::Each { min: 8.0, max: 4096.0, what: "each side", suffix: "" }, "grid across the curtain and least cells along it (the sheet's cells are at most as long as wide)"),
    KeySpec::new("steps", "", Range::Int { min: 0, max: 10_000 }, "fluid2014: simulation steps"),
    KeySpec::new("dt", "cells", Range::Num(Num::open_min(0.0, 1e6)), "fluid2014: time step (semi-Lagrangian advection: stable for any `dt`)"),
    KeySpec::new("pressure_iterations", "", Range::Int { min: 0, max: 10_000 }, "fluid2014: iterations of the pressure projection"),
    KeySpec::new("band_fraction", "", Range::Num(Num::open_min(0.0, 1.0)), "fluid2014: initial band thickness, as a fraction of the footprint width"),
    KeySpec::new("velocity_waves", "", Range::Num(Num::closed(0.0, 1e3)), "fluid2014: sine periods of the initial velocity along the band"),
    KeySpec::new("velocity_amplitude", "cells per unit time", Range::Num(Num::closed(0.0, 1e6)), "fluid2014: amplitude of the initial velocity"),
    KeySpec::new("density_waves", "", Range::Num(Num::closed(0.0, 1e3)), "fluid2014: sine periods of the initial density modulation along the band"),
    KeySpec::new("bend_wavelength", "curtain lengths", Range::Num(Num::open_min(0.0, 1e3)), "wavelength of the noise curve that bends the band"),
    KeySpec::new("threshold", "", Range::Num(Num::open_min(0.0, 1.0)), "footprint density (of a peak of 1) below which no beam starts"),
    KeySpec::new("end_fade_km", "km", Range::Num(Num::closed(0.0, 1e4)), "length over which the footprint fades to 0 at each end of the curtain (0: straight ends)"),
    KeySpec::new("sheet_spacing_km", "km", Range::Num(Num::closed(0.01, 10.0)), "sheet: spacing of its vortex markers at the start"),
    KeySpec::new("sheet_smoothing_km", "km", Range::Num(Num::closed(0.01, 100.0)), "sheet: smoothing length of the vortex-blob kernel (no curls below it)"),
    KeySpec::new("sheet_amplitude", "", Range::Num(Num::closed(0.0, 1.0)), "sheet: amplitude of the initial displacement spectrum (its slope at 200 km wavelengths and more)"),
    KeySpec::new("sheet_rollup_km", "km", Range::Num(Num::closed(0.0, 1e3)), "sheet: how far it rolls up (the shear across it times the time)"),
    KeySpec::new("sheet_steps", "", Range::Int { min: 1, max: 10_000 }, "sheet: Runge-Kutta steps of the roll-up"),
    KeySpec::new("sheet_thickness_km", "km", Range::Num(Num::closed(0.01, 100.0)), "sheet: full width at half maximum across it"),
    KeySpec::new("filament_width_km", "km", Range::Num(Num::closed(0.01, 10.0)), "sheet: full width at half maximum of a filament inside the arc (observed 0.05-0.2 km; `curtain.filament_energy_flux`)"),
    KeySpec::new("filament_count", "", Range::Int { min: 1, max: 16 }, "sheet: filaments inside each arc, parallel to its centre line within its half maximum"),
    KeySpec::new("ray_spacing_km", "km", Range::Num(Num::closed(0.1, 1e4)), "sheet: mean spacing of the rays along it (irregular)"),
    KeySpec::new("ray_width_km", "km", Range::Num(Num::closed(0.01, 100.0)), "sheet: width of a ray along it (Gaussian sigma)"),
    KeySpec::new("ray_contrast", "", Range::Num(Num::closed(1.0, 1e3)), "sheet: brightest ray over the faintest (log-uniform between)"),
    KeySpec::new("glow", "", Range::Num(Num::closed(0.0, 100.0)), "sheet: diffuse glow between the rays, a 3 km blur of the sheet, of its peak"),
    KeySpec::new("uniform", "", Range::Any, "for validation only: density 1 over the whole footprint box (no fluid, no band, no bend), so every beam carries the curtain's `energy_flux`; `tests/python/test_glow.py` compares such a curtain with NCAR GLOW"),
];
