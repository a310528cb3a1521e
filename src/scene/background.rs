//! `[background]`: what is seen behind the volume (constant radiance, an
//! image, the stars), with the defaults.
//! [`BACKGROUND_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Background {
    /// Constant radiance behind the volume where no terrain is hit.
    pub radiance: [f64; 3],
    /// Optional equirectangular linear EXR of sky radiance, added to
    /// `radiance` (path relative to the scene file; mapped as Blender's
    /// Environment Texture: centre towards +x, top row the zenith).
    pub image: Option<String>,
    /// A procedural star field (`crate::render::sky`), from the scene seed.
    pub stars: bool,
    /// Faintest star drawn, visual magnitude (6: the naked eye's limit).
    pub limiting_magnitude: f64,
    /// Scale on the stars' physical irradiance.
    pub star_brightness: f64,
}

impl Default for Background {
    fn default() -> Self {
        Self { radiance: [0.0, 0.0, 0.0], image: None, stars: true, limiting_magnitude: 6.0, star_brightness: 1.0 }
    }
}

/// Every key of `[background]`: name, unit, allowed range and description (`super::keys`).
pub const BACKGROUND_KEYS: &[KeySpec] = &[
    KeySpec::new("radiance", "linear Rec.709", Range::Each { min: 0.0, max: 1e9, what: "components", suffix: "" }, "constant radiance seen behind the volume where no terrain is hit (it does not light the terrain)"),
    KeySpec::new("image", "", Range::Any, "an equirectangular linear EXR of sky radiance added to `radiance` (relative to the scene file; mapped as Blender's Environment Texture: centre towards +x, top row the zenith); the add-on sets it as the World"),
    KeySpec::new("stars", "", Range::Any, "a procedural star field (`aurora render` only): the real sky's counts per magnitude (Hipparcos), V-band flux, colours by temperature from the catalogue's B-V; each star drawn as a reference 14 mm f/2.8 lens draws it (a 2.5 arcminute core and a faint halo, sized in angle) keeping its flux; none in orthographic views; Cycles gets them through `aurora sky`"),
    KeySpec::new("limiting_magnitude", "mag", Range::Num(Num::closed(-1.5, 8.0)), "faintest star drawn (6: the naked eye's limit)"),
    KeySpec::new("star_brightness", "", Range::Num(Num::closed(0.0, 1e6)), "scale on the stars' physical irradiance"),
];
