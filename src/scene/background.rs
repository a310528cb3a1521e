//! `[background]`: what is seen behind the volume (constant radiance, an
//! image, the stars), with the defaults.

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
