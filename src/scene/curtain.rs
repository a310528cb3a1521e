//! The curtains and their motion: `[[curtain]]` (where a footprint lies and
//! how hard it is driven), `[footprint]` (the fluid that shapes it) and
//! `[animation]` (closed-form motion and the red trail), each with the
//! defaults a missing table or key takes. No checks here
//! (`super::validation`).

use serde::{Deserialize, Serialize};

/// One auroral curtain: where its footprint lies and how hard it is driven.
/// Serialised through [`CurtainToml`], which leaves out `center`, `length`
/// and `rotation_deg` when `path` places the curtain.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default, into = "CurtainToml")]
pub struct Curtain {
    /// Centre of the footprint on the ground plane, km.
    pub center: [f64; 2],
    /// Length of the curtain along its axis, km.
    pub length: f64,
    /// Width of the footprint box across the axis, km (room for folds and the
    /// noise curve's bends).
    pub width: f64,
    /// Direction of the curtain's axis, degrees counter-clockwise from +x.
    pub rotation_deg: f64,
    /// Peak precipitating electron energy flux, mW/m^2 (= erg cm^-2 s^-1).
    pub energy_flux: f64,
    /// Characteristic energy E0 of the Maxwellian electron spectrum, keV.
    pub char_energy_kev: f64,
    /// Share of the energy flux carried by a soft Maxwellian component (the
    /// low-energy electrons that light the red tops above 200 km), in [0, 1].
    pub soft_fraction: f64,
    /// Characteristic energy of that soft component, keV.
    pub soft_energy_kev: f64,
    /// Share of the scene's beams given to this curtain (relative weight).
    pub beam_weight: f64,
    /// Amplitude of the low-frequency noise curve that bends the band, km.
    pub bend_km: f64,
    /// Seed offset so curtains differ.
    pub seed: u64,
    /// The ground track of the curtain's lower border (at 110 km), km: a
    /// centripetal Catmull-Rom curve through these points (`crate::pipeline::footprint::curtain_path`),
    /// instead of `center`, `length` and `rotation_deg`.
    pub path: Option<Vec<[f64; 2]>>,
}

impl Default for Curtain {
    fn default() -> Self {
        Self {
            center: [0.0, 0.0],
            length: 160.0,
            width: 40.0,
            rotation_deg: 0.0,
            energy_flux: 5.0,
            char_energy_kev: 3.0,
            soft_fraction: 0.1,
            soft_energy_kev: 0.2,
            beam_weight: 1.0,
            bend_km: 12.0,
            seed: 0,
            path: None,
        }
    }
}

/// [`Curtain`] as written: the straight placement's keys only without a path.
#[derive(Serialize)]
pub struct CurtainToml {
    #[serde(skip_serializing_if = "Option::is_none")]
    center: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    length: Option<f64>,
    width: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    rotation_deg: Option<f64>,
    energy_flux: f64,
    char_energy_kev: f64,
    soft_fraction: f64,
    soft_energy_kev: f64,
    beam_weight: f64,
    bend_km: f64,
    seed: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    path: Option<Vec<[f64; 2]>>,
}

impl From<Curtain> for CurtainToml {
    fn from(c: Curtain) -> Self {
        let straight = c.path.is_none();
        Self {
            center: straight.then_some(c.center),
            length: straight.then_some(c.length),
            width: c.width,
            rotation_deg: straight.then_some(c.rotation_deg),
            energy_flux: c.energy_flux,
            char_energy_kev: c.char_energy_kev,
            soft_fraction: c.soft_fraction,
            soft_energy_kev: c.soft_energy_kev,
            beam_weight: c.beam_weight,
            bend_km: c.bend_km,
            seed: c.seed,
            path: c.path,
        }
    }
}

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
    /// Sheet: full width at half maximum of the sheet across itself, km.
    pub sheet_thickness_km: f64,
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
            sheet_thickness_km: 0.5,
            ray_spacing_km: 3.0,
            ray_width_km: 0.4,
            ray_contrast: 10.0,
            glow: 0.2,
            uniform: false,
        }
    }
}

/// The most earlier times `animation.trail_samples` may ask for.
pub const MAX_TRAIL_SAMPLES: u32 = 16;

/// Motion in time (`crate::pipeline::motion`): closed form in t, so any frame costs
/// one bake. Speeds from the time scales observers report; every motion
/// parameter at 0 gives identical frames.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AnimationParams {
    /// Frames per second of a sequence (`aurora bake --frames`).
    pub fps: f64,
    /// Time of the bake, s; frame N of a sequence is baked at
    /// `time_s + (N - 1) / fps`.
    pub time_s: f64,
    /// Phase speed of the folds (the footprint's vortex row) along the
    /// curtain, km/s (spirals drift about 4 km/s, surges about 2 km/s).
    pub fold_speed_kms: f64,
    /// Relative swing of the fold-driving velocity (folds deepen and relax), in [0, 1).
    pub fold_breathing: f64,
    /// Period of that swing, s.
    pub fold_breathing_period_s: f64,
    /// Speed at which the bend curve travels along the curtain, km/s.
    pub bend_speed_kms: f64,
    /// Rate at which the bend curve changes shape, 1/s (its noise moves one
    /// lattice cell in 1 / rate seconds).
    pub bend_change_hz: f64,
    /// Amplitude of the curtain's drift across its axis, km (bounded: a
    /// sine of period `drift_period_s`, so curtains never leave the view).
    pub drift_km: f64,
    pub drift_period_s: f64,
    /// Speed of the rays (the start-height and colour noise) along the
    /// curtain, km/s (up to about 25 km/s).
    pub ray_speed_kms: f64,
    /// Depth of pulsating patches, in [0, 1] (0 = off): each patch's
    /// electron flux swings between (1 - pulsation) and 1 times its value.
    pub pulsation: f64,
    /// Size of a pulsating patch, km.
    pub pulsation_patch_km: f64,
    /// Range of patch periods, s (most often 6-10 s; a few s to 20 s).
    pub pulsation_period_s: [f64; 2],
    /// The red trail (`crate::pipeline::red_trail`): how many earlier times of the
    /// motion the O(1D) lines (630.0, 636.4 nm) of a bake at `time_s` sum,
    /// each weighted by the decay of O(1D) at the deposit's altitude;
    /// 0 (the default) is off: every line at `time_s`. At most
    /// [`MAX_TRAIL_SAMPLES`]; each costs one more trace of the beams (the
    /// red only).
    pub trail_samples: u32,
}

impl Default for AnimationParams {
    fn default() -> Self {
        Self {
            fps: 24.0,
            time_s: 0.0,
            fold_speed_kms: 3.0,
            fold_breathing: 0.3,
            fold_breathing_period_s: 40.0,
            bend_speed_kms: 1.0,
            bend_change_hz: 1.0 / 60.0,
            drift_km: 8.0,
            drift_period_s: 300.0,
            ray_speed_kms: 10.0,
            pulsation: 0.0,
            pulsation_patch_km: 25.0,
            pulsation_period_s: [6.0, 10.0],
            trail_samples: 0,
        }
    }
}
