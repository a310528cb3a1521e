//! Display encoding: how a linear Rec.709 pixel becomes the 8- or 16-bit
//! sRGB code values of a PNG, through the view transform
//! (`render.view_transform`), at `2^exposure` times the linear value.
//!
//! * `standard`, Blender's "Standard": per RGB channel
//!   `v = clamp(sRGB_OETF(x), 0, 1)`, with the sRGB OETF of IEC 61966-2-1
//!   ([`crate::util::colour::srgb_oetf`]).
//! * `agx` (the default), Blender's AgX view for an sRGB display
//!   ([`Agx`]);
//! * `agx_punchy`, `agx_high_contrast`, ...: AgX after one of the looks
//!   Blender 5.0 ships for it ([`crate::render::agx_look`]), applied to
//!   the exposed linear value.
//!
//! Either is quantised as `round(255 v)` (`round(65535 v)` for a 16-bit
//! PNG, a dome master's delivery depth), no dither; a NaN (and with AgX an
//! infinite) channel is black. Alpha is not encoded.

use super::agx::Agx;
use super::agx_look::{graded, Grade};
use crate::scene::ViewTransform;
use crate::util::colour::srgb_oetf;
use crate::util::fmath;

/// The standard display transform of one linear channel value (module doc).
pub fn display_u8(linear: f32, exposure: f64) -> u8 {
    to_u8(srgb_oetf(linear as f64 * fmath::exp2(exposure)))
}

fn to_u8(v: f64) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (v * 255.0).round() as u8
}

/// One pixel's RGB code values through `view` at `exposure` (module doc).
pub fn display_rgb(p: [f32; 4], exposure: f64, view: ViewTransform) -> [u8; 3] {
    display_unit(p, exposure, view).map(to_u8)
}

/// One pixel's 16-bit RGB code values through `view` at `exposure`.
pub fn display_rgb16(p: [f32; 4], exposure: f64, view: ViewTransform) -> [u16; 3] {
    display_unit(p, exposure, view).map(|v| {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        (v * 65535.0).round() as u16
    })
}

/// One pixel's display values in [0, 1] before quantising (NaN possible
/// with the standard transform; the quantisers make it black).
fn display_unit(p: [f32; 4], exposure: f64, view: ViewTransform) -> [f64; 3] {
    let k = fmath::exp2(exposure);
    match view {
        ViewTransform::Standard => [0, 1, 2].map(|c| srgb_oetf(p[c] as f64 * k)),
        agx => {
            // A NaN or infinite pixel is black, as in the standard transform.
            let c = [0, 1, 2].map(|i| if p[i].is_finite() { p[i] as f64 * k } else { 0.0 });
            match Grade::of(agx) {
                Some(g) => Agx::get().display(graded(g, c)),
                None => Agx::get().display(c),
            }
        }
    }
}
