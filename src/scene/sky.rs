//! `[sky]`: the air between the aurora and the observer, with the defaults.

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
}

impl Default for SkyParams {
    fn default() -> Self {
        Self { extinction: true, ozone_du: 300.0, aerosol_optical_depth: 0.05, angstrom: 1.3, aerosol_scale_height_km: 1.2 }
    }
}
