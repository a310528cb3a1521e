//! `[earth]`: the ground's shape (a sphere or a flat plane) and the
//! geomagnetic pole, with the defaults.
//! [`EARTH_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Range};
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

/// Every key of `[earth]`: name, unit, allowed range and description (`super::keys`).
pub const EARTH_KEYS: &[KeySpec] = &[
    KeySpec::new("radius_km", "km", Range::ZeroOr { min: 1000.0, max: 1e5, zero: "a flat ground" }, "radius of the spherical Earth centred at `(0, 0, -radius_km)`: altitude is the distance from its centre minus the radius everywhere (atmosphere, deposition, colour, density grid, terrain); curtain positions and paths are ground distances from the origin mapped onto it (azimuthal equidistant); the field's angles are relative to the local vertical and north; 0 is a flat ground, altitude = z"),
    KeySpec::new("magnetic_pole", "km", Range::Each { min: -2e4, max: 2e4, what: "each coordinate", suffix: " km" }, "ground coordinates `[x, y]` of the geomagnetic dipole's pole: the field at each beam's start is the dipole's (dip `tan I = 2 tan(magnetic latitude)`, horizontal part toward the pole), replacing `beams.b_inclination_deg` and `b_declination_deg`; beyond the dipole's equator (more than a quarter of the globe, 10007 km, from the pole) B points up and the electrons go down along -B; needs `radius_km` > 0; a `[site]` with `field = \"igrf\"` (its default) replaces it with IGRF-14; none by default"),
];
