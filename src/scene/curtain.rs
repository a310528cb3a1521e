//! `[[curtain]]`: where one curtain's footprint lies and how hard it is
//! driven, with the defaults a missing key takes.
//! [`CURTAIN_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

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
    /// The shape of the arc's electron spectrum (`crate::physics::deposition::spectrum`):
    /// `char_energy_kev` is a Maxwellian's E0, a monoenergetic beam's
    /// energy, or the accelerated spectrum's source temperature.
    pub spectrum: SpectrumShape,
    /// The field-aligned potential drop the accelerated spectrum's source
    /// falls through, kV (Evans 1974).
    pub potential_kv: f64,
    /// Peak energy flux of the filaments inside the arc, mW/m^2 (0: none;
    /// the vortex sheet only).
    pub filament_energy_flux: f64,
    /// The filaments' electrons: the arc's spectrum accelerated through
    /// this much more potential drop, kV.
    pub filament_potential_kv: f64,
    /// The ground track of the curtain's lower border (at 110 km), km: a
    /// centripetal Catmull-Rom curve through these points (`crate::pipeline::footprint::curtain_path`),
    /// instead of `center`, `length` and `rotation_deg`.
    pub path: Option<Vec<[f64; 2]>>,
    /// The same ground track in magnetic coordinates: points `[corrected
    /// geomagnetic latitude, deg; magnetic local time, h]` over the scene's
    /// `[site]` at its hour, placed as a `path` when the scene is loaded
    /// (`crate::pipeline::footprint::magnetic_placement`).
    pub magnetic_path: Option<Vec<[f64; 2]>>,
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
            spectrum: SpectrumShape::Maxwellian,
            potential_kv: 0.0,
            filament_energy_flux: 0.0,
            filament_potential_kv: 0.0,
            path: None,
            magnetic_path: None,
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
    spectrum: SpectrumShape,
    potential_kv: f64,
    filament_energy_flux: f64,
    filament_potential_kv: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    path: Option<Vec<[f64; 2]>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    magnetic_path: Option<Vec<[f64; 2]>>,
}

impl From<Curtain> for CurtainToml {
    fn from(c: Curtain) -> Self {
        let straight = c.path.is_none() && c.magnetic_path.is_none();
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
            spectrum: c.spectrum,
            potential_kv: c.potential_kv,
            filament_energy_flux: c.filament_energy_flux,
            filament_potential_kv: c.filament_potential_kv,
            path: c.path,
            magnetic_path: c.magnetic_path,
        }
    }
}

/// The shape of a curtain's electron spectrum ([`Curtain::spectrum`]).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum SpectrumShape {
    /// Number flux ~ E exp(-E / E0), E0 = `char_energy_kev`.
    Maxwellian,
    /// Every electron at `char_energy_kev`.
    Monoenergetic,
    /// A source Maxwellian of temperature `char_energy_kev` accelerated
    /// through `potential_kv` (Evans 1974).
    Accelerated,
}

/// What `curtain.path` accepts.
pub const PATH_RULE: &str = "at least 2 points [x, y] (km, each coordinate in [-1e4, 1e4]), consecutive points at least 1 m apart, \
     total length at most 1e4 km; replaces center, length and rotation_deg";

/// What `curtain.magnetic_path` accepts.
pub const MAGNETIC_PATH_RULE: &str = "at least 2 points [latitude, mlt]: corrected geomagnetic latitude in degrees, 10 to 85 \
     from the equator in the site's hemisphere (negative in the south), magnetic local time in [0, 24] h; needs [site]; replaces center, length and rotation_deg";

/// Every key of `[curtain]`: name, unit, allowed range and description (`super::keys`).
pub const CURTAIN_KEYS: &[KeySpec] = &[
    KeySpec::new("center", "km", Range::Each { min: -1e4, max: 1e4, what: "each coordinate", suffix: " km" }, "centre of the footprint on the ground plane, `[x, y]`"),
    KeySpec::new("path", "km", Range::Rule(PATH_RULE), "the curtain along a smooth curve (centripetal Catmull-Rom) through these `[x, y]` points: the ground track of its lower border (110 km), lifted up the field to the beams' start; replaces `center`, `length` and `rotation_deg` (giving both is an error)"),
    KeySpec::new("magnetic_path", "", Range::Rule(MAGNETIC_PATH_RULE), "the curtain along these `[latitude, mlt]` points in magnetic coordinates (corrected geomagnetic latitude AACGM-v2, deg; magnetic local time, h) over the `[site]` at its hour: each is traced down IGRF-14's field line to 110 km and the points joined as a `path` (giving both is an error)"),
    KeySpec::new("length", "km", Range::Num(Num::open_min(0.0, 1e4)), "length of the footprint box along the curtain's axis"),
    KeySpec::new("width", "km", Range::Num(Num::open_min(0.0, 1e4)), "width of the footprint box across the axis (room for folds and bends)"),
    KeySpec::new("rotation_deg", "deg", Range::Num(Num::FINITE), "direction of the curtain's axis, counter-clockwise from +x"),
    KeySpec::new("energy_flux", "mW/m^2", Range::Num(Num::open_min(0.0, 1e4)), "peak precipitating electron energy flux (1 mW/m^2 = 1 erg cm^-2 s^-1)"),
    KeySpec::new("char_energy_kev", "keV", Range::Num(Num::closed(0.05, 100.0)), "characteristic energy E0 of the Maxwellian electron spectrum: harder electrons reach lower"),
    KeySpec::new("soft_fraction", "", Range::Num(Num::closed(0.0, 1.0)), "share of the energy flux in a soft Maxwellian component (the electrons that light the red tops above 200 km)"),
    KeySpec::new("soft_energy_kev", "keV", Range::Num(Num::closed(0.01, 100.0)), "characteristic energy of the soft component"),
    KeySpec::new("beam_weight", "", Range::Num(Num::open_min(0.0, 1e9)), "share of the scene's beams given to this curtain (a relative weight)"),
    KeySpec::new("bend_km", "km", Range::Num(Num::closed(0.0, 1e4)), "amplitude of the noise curve that bends the band (keep it below `width / 2`)"),
    KeySpec::new("seed", "", Range::Any, "seed offset, so that curtains differ"),
    KeySpec::new("spectrum", "", Range::Word(&["maxwellian", "monoenergetic", "accelerated"]), "the arc's electron spectrum: `maxwellian` (E0 = `char_energy_kev`: soft, diffuse lower borders), `monoenergetic` (every electron at `char_energy_kev`: the sharpest lower border) or `accelerated` (a source Maxwellian of temperature `char_energy_kev` accelerated through `potential_kv`, Evans 1974: the inverted-V's peaked spectrum)"),
    KeySpec::new("potential_kv", "kV", Range::Num(Num::closed(0.0, 100.0)), "`accelerated`: the field-aligned potential drop the source falls through"),
    KeySpec::new("filament_energy_flux", "mW/m^2", Range::Num(Num::closed(0.0, 1e4)), "peak energy flux of the filaments inside the arc (0: none): `footprint.filament_count` lines of width `footprint.filament_width_km` along the vortex sheet, of harder electrons (`filament_potential_kv`); `energy_flux` is then the arc's body; the `fluid2014` footprint has no sheet to carry them and leaves them out"),
    KeySpec::new("filament_potential_kv", "kV", Range::Num(Num::closed(0.0, 100.0)), "the filaments' electrons: the arc's spectrum accelerated through this much more drop (Evans 1974)"),
];
