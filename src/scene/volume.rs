//! `[volume]`: the volume material's scales, with the defaults.
//! [`VOLUME_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct VolumeParams {
    /// extinction = density_scale * density grid.
    pub density_scale: f64,
    /// emitted radiance per unit length = emission_scale * emission grid.
    pub emission_scale: f64,
}

impl Default for VolumeParams {
    fn default() -> Self {
        Self { density_scale: 1.0, emission_scale: 1.0 }
    }
}

/// Every key of `[volume]`: name, unit, allowed range and description (`super::keys`).
pub const VOLUME_KEYS: &[KeySpec] = &[
    KeySpec::new("density_scale", "", Range::Num(Num::closed(0.0, 1e9)), "extinction = `density_scale` x the `density` grid"),
    KeySpec::new(
        "emission_scale",
        "",
        Range::Num(Num::closed(0.0, 1e9)),
        "emitted radiance per km = `emission_scale` x the `emission` grid",
    ),
];
