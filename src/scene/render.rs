//! `[render]`: the reference renderer's image, with its defaults.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderParams {
    pub width: usize,
    pub height: usize,
    /// Samples per pixel for the stochastic parts (pixel jitter, shadow rays).
    pub spp: usize,
    /// Exposure of the PNG preview, in stops.
    pub exposure: f64,
    /// The PNG preview's view transform (the EXR stays linear).
    pub view_transform: ViewTransform,
    /// Bits per channel of the PNG: 8, or 16 for delivery (a dome master's
    /// frames: the fulldome show file format takes 8-16 bit PNG or TIFF).
    pub png_bits: u32,
    /// Shutter time, s, of the reference renderer's motion blur: each
    /// camera sample reads the fields at `p - v(p) tau`, tau uniform over
    /// [-shutter_s / 2, shutter_s / 2], as Cycles does with a velocity grid
    /// (the bake's `v`: `grid.velocity = true`). 0: no blur.
    pub shutter_s: f64,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self { width: 640, height: 360, spp: 16, exposure: 3.0, view_transform: ViewTransform::Agx, png_bits: 8, shutter_s: 0.0 }
    }
}

/// How a linear image becomes PNG code values (`crate::render::view_transform`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ViewTransform {
    /// The sRGB OETF of the linear value, clipped (Blender's "Standard").
    Standard,
    /// AgX, Blender's default view (`crate::render::agx`).
    #[default]
    Agx,
}
