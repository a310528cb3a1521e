//! What the PNG shows of the linear image before the view transform, as a
//! camera develops its raw picture: the white balance, then the exposure,
//! fixed or metered ([`develop`]). The EXR stays the linear image at the
//! camera table's daylight balance; the PNG is the view transform of
//! `2^EV W x`.
//!
//! **White balance.** `W` is the camera's `W(T)` at `[colour]
//! white_balance_k` (`crate::util::white_balance`: von Kries on its raw
//! response to a Planckian at T, then its matrix) for the camera observer,
//! the identity for the eye. Light adds, so `W` on the image is `W` on
//! every light in it: the aurora, the sky, the stars, the lit ground.
//!
//! **Metering** (`render.exposure = "auto"`). A centre-weighted highlight
//! meter, as cameras offer for bright subjects on dark ground (a stage, the
//! Moon, an aurora): the luminance of each white-balanced pixel, weighted 3
//! inside the centre 60 % of the frame's width and height and 1 outside,
//! and the weighted [`METER_PERCENTILE`] of it placed at [`METER_TARGET`]
//! of the linear scale: `EV = log2(METER_TARGET / L_p)`. An average meter
//! (mean luminance to 18 % grey) would make a night sky grey and burn the
//! aurora white; a spot meter would depend on where the aurora is. The
//! percentile is high enough that the few pixels of bright stars do not
//! set it (stars cover under 0.5 % of a frame of the default's field) and
//! low enough that the aurora's bright core does. AgX maps 0.5 of linear to
//! about 0.7 of display: the core stays below white, its colour kept. A
//! black image meters EV 0. The EV is clamped to the key's range,
//! [-50, 50].

use super::image::Image;
use crate::scene::{ColourParams, Observer, RenderParams};
use crate::util::colour::luminance;
use crate::util::fmath;
use crate::util::white_balance::{apply, camera_white_balance};

/// The luminance percentile the meter reads (module doc).
pub const METER_PERCENTILE: f64 = 0.995;
/// Where the meter puts that luminance, linear (module doc).
pub const METER_TARGET: f64 = 0.5;
/// Weight of the centre of the frame in the meter.
pub const CENTRE_WEIGHT: f64 = 3.0;
/// The centre's share of the frame's width and height.
pub const CENTRE_SHARE: f64 = 0.6;

/// How an image was developed: the white balance (None for the eye) and
/// the EV, metered or the scene's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Developed {
    pub white_balance_k: Option<f64>,
    pub exposure_ev: f64,
    pub metered: bool,
}

impl Developed {
    /// The text the PNG and the EXR record: (key, value).
    pub fn metadata(&self) -> Vec<(String, String)> {
        let how = if self.metered { "metered (render.exposure = \"auto\": centre-weighted highlight meter)" } else { "render.exposure" };
        let mut v = vec![("aurora_exposure_ev".to_string(), format!("{:.4} ({how})", self.exposure_ev))];
        let wb = match self.white_balance_k {
            Some(k) => format!("{k} K (camera observer; the EXR is at daylight balance)"),
            None => "none (eye observer)".to_string(),
        };
        v.push(("aurora_white_balance".to_string(), wb));
        v
    }
}

/// The white balance matrix of `colour` (module doc).
pub fn white_balance_matrix(colour: &ColourParams) -> Option<[[f64; 3]; 3]> {
    (colour.observer == Observer::Camera).then(|| camera_white_balance(colour.white_balance_k))
}

/// The white-balanced linear image the PNG shows (before its exposure),
/// and how it is developed (module doc). Alpha is kept.
pub fn develop(image: &Image, colour: &ColourParams, render: &RenderParams) -> (Image, Developed) {
    let w = white_balance_matrix(colour);
    let pixels = match &w {
        Some(m) => image
            .pixels
            .iter()
            .map(|p| {
                let c = apply(m, [p[0] as f64, p[1] as f64, p[2] as f64]);
                [c[0] as f32, c[1] as f32, c[2] as f32, p[3]]
            })
            .collect(),
        None => image.pixels.clone(),
    };
    let out = Image { width: image.width, height: image.height, pixels, stats: image.stats.clone() };
    let exposure_ev = if render.auto_exposure { meter(&out) } else { render.exposure };
    let d = Developed { white_balance_k: w.map(|_| colour.white_balance_k), exposure_ev, metered: render.auto_exposure };
    (out, d)
}

/// The metered EV of a (white-balanced) image (module doc).
pub fn meter(image: &Image) -> f64 {
    let (w, h) = (image.width as f64, image.height as f64);
    let (x0, x1) = (0.5 * (1.0 - CENTRE_SHARE) * w, 0.5 * (1.0 + CENTRE_SHARE) * w);
    let (y0, y1) = (0.5 * (1.0 - CENTRE_SHARE) * h, 0.5 * (1.0 + CENTRE_SHARE) * h);
    let mut lw: Vec<(f64, f64)> = image
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let l = luminance([p[0] as f64, p[1] as f64, p[2] as f64]);
            let (x, y) = ((i % image.width) as f64 + 0.5, (i / image.width) as f64 + 0.5);
            let centre = (x0..x1).contains(&x) && (y0..y1).contains(&y);
            (if l.is_finite() { l.max(0.0) } else { 0.0 }, if centre { CENTRE_WEIGHT } else { 1.0 })
        })
        .collect();
    lw.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = lw.iter().map(|x| x.1).sum();
    let mut acc = 0.0;
    let mut lp = 0.0;
    for &(l, wt) in &lw {
        acc += wt;
        lp = l;
        if acc >= METER_PERCENTILE * total {
            break;
        }
    }
    if lp <= 0.0 {
        return 0.0;
    }
    fmath::log2(METER_TARGET / lp).clamp(-50.0, 50.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::image::RenderStats;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Image {
        let pixels = (0..w * h).map(|i| [f(i % w, i / w); 3].into_iter().chain([1.0]).collect::<Vec<_>>().try_into().unwrap()).collect();
        Image { width: w, height: h, pixels, stats: RenderStats::default() }
    }

    /// A dark frame with a bright patch: the meter puts the patch at the
    /// target, whatever the frame's size; a few bright pixels (stars) do not
    /// move it; a black frame meters 0.
    #[test]
    fn the_meter_exposes_for_the_highlights() {
        for (w, h) in [(100, 60), (640, 360)] {
            // 1 % of the frame at 4.0 in the centre, the rest 0.01.
            let img = image(w, h, |x, y| if x * 10 / w == 5 && y * 10 / h == 5 { 4.0 } else { 0.01 });
            let ev = meter(&img);
            assert!((ev - fmath::log2(METER_TARGET / 4.0)).abs() < 1e-9, "{w}x{h}: {ev}");
        }
        let stars = image(200, 100, |x, y| if (x * 7 + y * 13) % 997 == 0 { 100.0 } else { 0.02 });
        assert!((meter(&stars) - fmath::log2(METER_TARGET / 0.02)).abs() < 1e-6, "{}", meter(&stars));
        assert_eq!(meter(&image(10, 10, |_, _| 0.0)), 0.0);
    }
}
