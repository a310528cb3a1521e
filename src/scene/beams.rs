//! The electrons and the world they fall through: `[beams]` (how many, how
//! they deposit, where they start), `[atmosphere]` and `[earth]`, each with
//! its defaults. No checks here (`super::validation`).

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
            alpha_d_deg: 5.0,
            delta_alpha_deg: 3.0,
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

/// The neutral atmosphere model (`crate::physics::atmosphere`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AtmosphereModel {
    /// U.S. Standard Atmosphere 1976, 50-700 km: public domain, compiled in.
    Us1976,
    /// NRLMSIS 2.1, 67 N, 20 E, 2020-01-15 00:00 UT, F10.7 = 150, Ap = 15:
    /// research, academic and non-profit use only, read from `nrlmsis21.csv`
    /// in the data folder (docs/data.md).
    Nrlmsis21,
}

/// The ambient night-time ionosphere and NO the chemistry needs
/// (`crate::physics::chemistry::ambient`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Ionosphere {
    /// Closed forms: Te = Ti = Tn, a Chapman night-time F layer, a
    /// published NO peak; compiled in.
    ClosedForm,
    /// NCAR GLOW 4.0.4's (IRI above 200 km, NOEM's NO): no sale, read from
    /// `ionosphere.csv` in the data folder (docs/data.md).
    Glow,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AtmosphereParams {
    /// `us1976` (default) or `nrlmsis21`.
    pub model: AtmosphereModel,
    /// `closed-form` (default) or `glow`.
    pub ionosphere: Ionosphere,
    /// The folder holding the tables that are not compiled in
    /// (`nrlmsis21.csv`, `ionosphere.csv`), relative to the scene file's
    /// folder; unset, the `AURORA_DATA` environment variable names it, else
    /// the source tree's `data/` of the build.
    pub data: Option<String>,
    /// The folder `data` is relative to: the scene file's, set when the
    /// scene is read from a file (not part of the scene's TOML).
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
}

impl Default for AtmosphereParams {
    fn default() -> Self {
        Self { model: AtmosphereModel::Us1976, ionosphere: Ionosphere::ClosedForm, data: None, base_dir: None }
    }
}

/// The Earth under the scene (`crate::geometry::earth`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EarthParams {
    /// Radius of the spherical Earth, km (6371, the mean radius); 0 is a
    /// flat ground where altitude is z.
    pub radius_km: f64,
    /// Ground coordinates `[x, y]` km of the geomagnetic (dipole) pole:
    /// when given the field at each beam's start follows the dipole
    /// (`crate::physics::geomagnetic_field`) and `beams.b_inclination_deg` and
    /// `b_declination_deg` are unused; none by default.
    pub magnetic_pole: Option<[f64; 2]>,
}

impl Default for EarthParams {
    fn default() -> Self {
        Self { radius_km: crate::geometry::earth::MEAN_RADIUS_KM, magnetic_pole: None }
    }
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
