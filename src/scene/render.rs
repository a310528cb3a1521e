//! `[render]`: the reference renderer's image, with its defaults.
//! [`RENDER_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default, from = "RenderKeys", into = "RenderKeys")]
pub struct RenderParams {
    pub width: usize,
    pub height: usize,
    /// Samples per pixel for the stochastic parts (pixel jitter, shadow rays).
    pub spp: usize,
    /// Emissive shadow rays per terrain hit and pixel sample
    /// (`crate::render::shadow`).
    pub shadow_samples: usize,
    /// Exposure of the PNG preview, in stops (unused when `auto_exposure`).
    pub exposure: f64,
    /// `exposure = "auto"`: the PNG's exposure is metered from the image
    /// (`crate::render::develop`).
    pub auto_exposure: bool,
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
        Self {
            width: 640,
            height: 360,
            spp: 16,
            shadow_samples: 1,
            exposure: 3.0,
            auto_exposure: false,
            view_transform: ViewTransform::Agx,
            png_bits: 8,
            shutter_s: 0.0,
        }
    }
}

/// `render.exposure` as the file writes it: stops, or the word "auto".
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum ExposureKey {
    Stops(f64),
    Word(AutoWord),
}

impl<'de> Deserialize<'de> for ExposureKey {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = ExposureKey;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number of stops or \"auto\"")
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> Result<ExposureKey, E> {
                Ok(ExposureKey::Stops(x))
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> Result<ExposureKey, E> {
                Ok(ExposureKey::Stops(x as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, x: u64) -> Result<ExposureKey, E> {
                Ok(ExposureKey::Stops(x as f64))
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<ExposureKey, E> {
                if s == "auto" {
                    Ok(ExposureKey::Word(AutoWord::Auto))
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(s), &self))
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// The one word `render.exposure` takes.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AutoWord {
    Auto,
}

/// `[render]` as the file holds it (`exposure` a number or "auto").
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderKeys {
    pub width: usize,
    pub height: usize,
    pub spp: usize,
    pub shadow_samples: usize,
    pub exposure: ExposureKey,
    pub view_transform: ViewTransform,
    pub png_bits: u32,
    pub shutter_s: f64,
}

impl Default for RenderKeys {
    fn default() -> Self {
        RenderParams::default().into()
    }
}

impl From<RenderParams> for RenderKeys {
    fn from(r: RenderParams) -> Self {
        let exposure = if r.auto_exposure { ExposureKey::Word(AutoWord::Auto) } else { ExposureKey::Stops(r.exposure) };
        Self {
            width: r.width,
            height: r.height,
            spp: r.spp,
            shadow_samples: r.shadow_samples,
            exposure,
            view_transform: r.view_transform,
            png_bits: r.png_bits,
            shutter_s: r.shutter_s,
        }
    }
}

impl From<RenderKeys> for RenderParams {
    fn from(k: RenderKeys) -> Self {
        let (exposure, auto_exposure) = match k.exposure {
            ExposureKey::Stops(ev) => (ev, false),
            ExposureKey::Word(AutoWord::Auto) => (0.0, true),
        };
        Self {
            width: k.width,
            height: k.height,
            spp: k.spp,
            shadow_samples: k.shadow_samples,
            exposure,
            auto_exposure,
            view_transform: k.view_transform,
            png_bits: k.png_bits,
            shutter_s: k.shutter_s,
        }
    }
}

/// How a linear image becomes PNG code values (`crate::render::view_transform`):
/// Standard, AgX, or AgX with one of the looks Blender 5.0 ships for it
/// (`crate::render::agx_look`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum ViewTransform {
    /// The sRGB OETF of the linear value, clipped (Blender's "Standard").
    Standard,
    /// AgX, Blender's default view (`crate::render::agx`).
    #[default]
    Agx,
    AgxPunchy,
    AgxGreyscale,
    AgxVeryHighContrast,
    AgxHighContrast,
    AgxMediumHighContrast,
    AgxBaseContrast,
    AgxMediumLowContrast,
    AgxLowContrast,
    AgxVeryLowContrast,
}

/// Every `render.view_transform` word, as the key's range lists them.
pub const VIEW_TRANSFORM_WORDS: &[&str] = &[
    "standard",
    "agx",
    "agx_punchy",
    "agx_greyscale",
    "agx_very_high_contrast",
    "agx_high_contrast",
    "agx_medium_high_contrast",
    "agx_base_contrast",
    "agx_medium_low_contrast",
    "agx_low_contrast",
    "agx_very_low_contrast",
];

impl ViewTransform {
    /// Blender's view transform and look of the same picture
    /// (`scene.view_settings.view_transform`, `.look`).
    pub fn blender(self) -> (&'static str, &'static str) {
        let look = match self {
            ViewTransform::Standard => return ("Standard", "None"),
            ViewTransform::Agx => "None",
            ViewTransform::AgxPunchy => "AgX - Punchy",
            ViewTransform::AgxGreyscale => "AgX - Greyscale",
            ViewTransform::AgxVeryHighContrast => "AgX - Very High Contrast",
            ViewTransform::AgxHighContrast => "AgX - High Contrast",
            ViewTransform::AgxMediumHighContrast => "AgX - Medium High Contrast",
            ViewTransform::AgxBaseContrast => "AgX - Base Contrast",
            ViewTransform::AgxMediumLowContrast => "AgX - Medium Low Contrast",
            ViewTransform::AgxLowContrast => "AgX - Low Contrast",
            ViewTransform::AgxVeryLowContrast => "AgX - Very Low Contrast",
        };
        ("AgX", look)
    }
}

/// Largest `render.width` and `render.height` (the one image-size limit:
/// the scene, the camera and the renderer all check this).
pub const MAX_IMAGE_SIDE: usize = 16384;

/// Largest `render.spp` (also the `--spp` flag's).
pub const MAX_SPP: u64 = 65_536;

/// Largest `render.shadow_samples` (also the `--shadow-samples` flag's).
pub const MAX_SHADOW_SAMPLES: u64 = 4_096;

/// Largest `render.shutter_s`, s: ten seconds of motion in one picture,
/// far beyond a frame (the aurora's fastest rays cross 250 km in it).
pub const MAX_SHUTTER_S: f64 = 10.0;

/// Every key of `[render]`: name, unit, allowed range and description (`super::keys`).
pub const RENDER_KEYS: &[KeySpec] = &[
    KeySpec::new("width", "px", Range::Int { min: 1, max: MAX_IMAGE_SIDE as i64 }, "image width"),
    KeySpec::new("height", "px", Range::Int { min: 1, max: MAX_IMAGE_SIDE as i64 }, "image height (row 0 is the top)"),
    KeySpec::new("spp", "", Range::Int { min: 1, max: MAX_SPP as i64 }, "samples per pixel (pixel positions and shadow rays): 1 samples pixel centres; more average the pixel square (box filter) at stratified antithetic positions"),
    KeySpec::new("shadow_samples", "", Range::Int { min: 1, max: MAX_SHADOW_SAMPLES as i64 }, "emissive shadow rays per terrain hit and pixel sample: the aurora's light on the ground is estimated from `spp` x this many rays a pixel; more makes lit terrain smooth at less cost than more `spp` (a photographer's view: 8)"),
    KeySpec::new("exposure", "stops", Range::NumOrWord(Num::closed(-50.0, 50.0), &["auto"]), "PNG only: the view transform of 2^exposure x the (white-balanced) linear image; `\"auto\"` meters it as a camera's highlight-weighted meter does (docs/colour.md, \"Exposure\"): the EV used is printed and recorded in the PNG and the EXR"),
    KeySpec::new("png_bits", "bits", Range::Of(&[8, 16]), "PNG only: bits per channel, 8 or 16 (16 for delivery: dome masters, whose faint sky gradients band at 8)"),
    KeySpec::new("view_transform", "", Range::Word(VIEW_TRANSFORM_WORDS), "PNG only: `agx` (Blender's default AgX view for an sRGB display, built from its published construction), `agx_` and a look Blender 5.0 ships for AgX (`agx_punchy`: AgX - Punchy, `agx_high_contrast`: AgX - High Contrast, ...; graded as its colour management grades them), or `standard` (the sRGB OETF, clipped: Blender's Standard); the EXR stays linear"),
    KeySpec::new("shutter_s", "s", Range::Num(Num::closed(0.0, MAX_SHUTTER_S)), "motion blur of `aurora render`: each camera sample reads the fields at `p - v(p) tau`, tau uniform over the shutter centred on the frame, as Cycles does; needs the bake's `v` (`grid.velocity = true`); 0 is sharp"),
];
