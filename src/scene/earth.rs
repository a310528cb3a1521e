//! `[earth]`: the ground's shape (a sphere or a flat plane) and the
//! geomagnetic pole, with the defaults.

use serde::{Deserialize, Serialize};

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
