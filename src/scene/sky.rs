//! `[sky]`: the air between the aurora and the observer, with the defaults.
//! [`SKY_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

/// The air between the aurora and the observer (`crate::physics::air_extinction`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SkyParams {
    /// Dim and redden what is seen through the lower atmosphere (Rayleigh,
    /// ozone, aerosol along each camera ray); false: no air.
    pub extinction: bool,
    /// Ozone column, Dobson units.
    pub ozone_du: f64,
    /// Aerosol optical depth at 550 nm, at sea level.
    pub aerosol_optical_depth: f64,
    /// Angstrom exponent of the aerosol's optical depth.
    pub angstrom: f64,
    /// Scale height of the aerosol's density, km.
    pub aerosol_scale_height_km: f64,
    /// The air scatters the night sky's own light into every sight line
    /// and the sky lights the ground (`crate::render::airglow`); false:
    /// the sky is only dimmed by the air and lights nothing.
    pub scattering: bool,
}

impl Default for SkyParams {
    fn default() -> Self {
        Self {
            extinction: true,
            ozone_du: 300.0,
            aerosol_optical_depth: 0.05,
            angstrom: 1.3,
            aerosol_scale_height_km: 1.2,
            scattering: true,
        }
    }
}

/// Every key of `[sky]`: name, unit, allowed range and description (`super::keys`).
pub const SKY_KEYS: &[KeySpec] = &[
    KeySpec::new("extinction", "", Range::Any, "dim and redden the volume, the terrain's light and the stars through the air (Rayleigh by Bodhaine et al. 1999 with the observer's pressure, ozone's Chappuis band, aerosol; Kasten & Young's air mass); `false`: no air, the images of the renderer without it"),
    KeySpec::new("ozone_du", "DU", Range::Num(Num::closed(0.0, 1000.0)), "ozone column (Chappuis band, Serdyuchenko et al. 2014 cross-sections); 300 is the global mean"),
    KeySpec::new("aerosol_optical_depth", "", Range::Num(Num::closed(0.0, 5.0)), "aerosol optical depth at 550 nm at sea level (0.05: clean Arctic winter air)"),
    KeySpec::new("angstrom", "", Range::Num(Num::closed(-1.0, 4.0)), "Angstrom exponent: the aerosol's depth goes as (lambda / 550 nm)^-angstrom"),
    KeySpec::new("scattering", "", Range::Any, "the night sky's light (airglow, zodiacal light, starlight) scattered once by the air into every sight line, so the sky brightens toward the horizon as photographs show instead of fading with the extinction, and lighting the ground (docs/physics.md, \"The sky's light in the air and on the ground\"); needs `extinction`; `false`: the sky is only dimmed and lights nothing"),
    KeySpec::new("aerosol_scale_height_km", "km", Range::Num(Num::closed(0.1, 20.0)), "scale height of the aerosol's density (the column above the observer falls as exp(-altitude / it))"),
];
