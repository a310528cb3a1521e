//! AgX, the view transform Blender shows by default: scene-linear Rec.709
//! to sRGB display code values, built from its published construction so
//! that `aurora render`'s PNGs look like the same EXR in Blender.
//!
//! AgX is Troy Sobotka's picture formation (SB2383 configuration), in the
//! form Eary Chow tuned for Blender 4 and later (AgX_LUT_Gen, `AgXBasesRGB.py`
//! and `AgXBaseRec2020.py`). Per colour, in Rec.2020 primaries:
//!
//! 1. *lower guard rail*: negative components are removed by an offset
//!    whose brightness is taken back so that a luminance-like sum
//!    (`max(c) - Y(max(c) - c) + Y(c)`, Y with the Rec.2020 luminance
//!    weights [`Y2020`]) does not grow ([`guard_rail_2020`]);
//! 2. *inset*: [`INSET`] pulls the primaries toward white (rotated by
//!    3, -1, -2 degrees, insets 0.4, 0.22, 0.13), so that bright saturated
//!    colours desaturate toward white instead of clipping to a hue;
//! 3. *log2 encoding* of each channel between -10 and +6.5 stops around
//!    middle grey 0.18, i.e. log2(x) from [`LOG2_MIN`] = log2(0.18) - 10 =
//!    -12.47393 to [`LOG2_MAX`] = log2(0.18) + 6.5 = 4.026069, to [0, 1];
//! 4. *sigmoid* (Jed Smith's tunable sigmoid): through the fulcrum
//!    (x_p, y_p) = (10 / 16.5, 0.18^(1/2.4)) with slope s = 2.4, toe and
//!    shoulder `y = y_p + S h(s (x - x_p) / S)` with `h(t) = t / (1 + |t|^p)^(1/p)`,
//!    p = 1.5, and S chosen so the toe passes through (0, 0) and the shoulder
//!    through (1, 1): from `S h(s X / S) = Y` with X, Y the distances from the
//!    fulcrum to the end point, `S = s X / ((s X / Y)^p - 1)^(1/p)`. The
//!    result is display-encoded with a 2.4 power: y^2.4 is display-linear;
//! 5. *hue restoration*: the HSV hue becomes 60% the hue before the sigmoid
//!    plus 40% the hue after it (the per-channel curve shifts hues; this
//!    keeps 60% of the shift);
//! 6. *outset*: the inverse of [`OUTSET_INV`] (no rotation, insets 0.4, 0.22,
//!    0.04) gives back purity;
//! 7. to Rec.709, the Rec.709 lower guard rail ([`guard_rail_709`], its
//!    compensation limited by a lerp with weight `Y^0.08`), clipped to
//!    [0, 1].
//!
//! Blender evaluates this through a 57^3 3D LUT whose input is the colour in
//! FilmLight E-Gamut, log2-encoded from log2(0.18) - 10 to log2(0.18) + 15
//! (its `AllocationTransform lg2 [-12.47393, 12.5260688117]`), with
//! tetrahedral interpolation, and then encodes for the sRGB display with
//! the IEC 61966-2-1 piecewise function. [`Agx`] builds the same LUT from the
//! steps above (nothing of Blender's is read) and interpolates it the same
//! way: the LUT's interpolation, not only the formula, decides the last
//! code value of saturated colours near the log floor. The sRGB encoding is
//! [`crate::util::colour::srgb_oetf`]; the colour-space matrices come from
//! the primaries ([`crate::util::colour::rgb_to_xyz`]).
//!
//! Sources: T. J. Sobotka, AgX / SB2383-Configuration-Generation
//! (github.com/sobotka); E. Chow, AgX_LUT_Gen (github.com/EaryChow), the
//! generator of Blender's `AgX_Base_sRGB.cube`; J. Smith, tunable sigmoid
//! (desmos.com/calculator/yrysofmx8h); FilmLight, E-Gamut primaries
//! (0.8, 0.3177), (0.18, 0.9), (0.065, -0.0805), D65.

use crate::util::colour::{apply, inverse, mul, rgb_to_xyz, srgb_oetf, M3, REC2020, REC709};
use crate::util::fmath;
use std::sync::OnceLock;

/// FilmLight E-Gamut primaries, D65 white.
pub const E_GAMUT: [[f64; 2]; 4] = [[0.8, 0.3177], [0.18, 0.9], [0.065, -0.0805], [0.3127, 0.3290]];

/// Inset matrix, Rec.2020 to Rec.2020 (SB2383 with rotate [3, -1, -2],
/// inset [0.4, 0.22, 0.13]; AgX_LUT_Gen's `inset_matrix`).
pub const INSET: [[f64; 3]; 3] = [
    [0.856627153315983, 0.0951212405381588, 0.0482516061458583],
    [0.137318972929847, 0.761241990602591, 0.101439036467562],
    [0.11189821299995, 0.0767994186031903, 0.811302368396859],
];
/// The matrix whose inverse is the outset (SB2383 with rotate [0, 0, 0],
/// inset [0.4, 0.22, 0.04]).
pub const OUTSET_INV: [[f64; 3]; 3] = [
    [0.899796955911611, 0.0871996192028351, 0.013003424885555],
    [0.11142098895748, 0.875575586156966, 0.0130034248855548],
    [0.11142098895748, 0.0871996192028349, 0.801379391839686],
];
/// Rec.2020 luminance weights from the CIE 2015 colour-matching functions
/// (AgX_LUT_Gen's, as in the LUT Blender 5.0 ships).
pub const Y2020: [f64; 3] = [0.2658180370250449, 0.59846986045365, 0.1357121025213052];

/// Middle grey.
pub const GREY: f64 = 0.18;
/// Stops below and above middle grey the sigmoid spans.
const STOPS_BELOW: f64 = 10.0;
const STOPS_ABOVE: f64 = 6.5;
/// log2 of the darkest and brightest value the log encoding spans:
/// log2(0.18) - 10 = -12.47393 and log2(0.18) + 6.5 = 4.026069.
pub const LOG2_MIN: f64 = -12.473931188332412;
pub const LOG2_MAX: f64 = 4.026068811667588;
/// Sigmoid: slope at the fulcrum, and the toe and shoulder power.
const SLOPE: f64 = 2.4;
const POWER: f64 = 1.5;
/// The display encoding inside the LUT (a pure 2.4 power, BT.1886).
const GAMMA: f64 = 2.4;
/// Hue after the sigmoid kept, as a fraction (AgX_LUT_Gen's `mix_percent`).
const HUE_MIX: f64 = 0.4;
/// The LUT: nodes per side, and its log2 input range in E-Gamut (-10 to
/// +15 stops around middle grey).
const LUT_SIZE: usize = 57;
pub const LUT_LOG2_MIN: f64 = -12.47393;
pub const LUT_LOG2_MAX: f64 = 12.5260688117;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn max3(c: [f64; 3]) -> f64 {
    c[0].max(c[1]).max(c[2])
}

fn min3(c: [f64; 3]) -> f64 {
    c[0].min(c[1]).min(c[2])
}

/// `max(c) - Y(max(c) - c) + Y(c)`: a brightness that stays positive where Y
/// of a colour with negative components does not.
fn opponent_brightness(c: [f64; 3], y: impl Fn([f64; 3]) -> f64) -> f64 {
    let m = max3(c);
    let inv = c.map(|v| m - v);
    max3(inv) - y(inv) + y(c)
}

/// Offsets `c` so that no component is negative, then scales it back so
/// that its brightness is at most what it was (step 1).
pub fn guard_rail_2020(c: [f64; 3]) -> [f64; 3] {
    let y = |v: [f64; 3]| dot(v, Y2020);
    let before = opponent_brightness(c, y);
    let offset = (-min3(c)).max(0.0);
    let o = c.map(|v| v + offset);
    let after = opponent_brightness(o, y);
    let k = if after > before { before / after } else { 1.0 };
    o.map(|v| k * v)
}

/// The Rec.709 guard rail of step 7: as [`guard_rail_2020`] with Y measured
/// in Rec.2020 and the opponent compensation mixed in only where Y is
/// small (`lerp(clamp(Y^0.08), compensated, Y)`).
fn guard_rail_709(c: [f64; 3], to2020: &M3) -> [f64; 3] {
    let y = |v: [f64; 3]| dot(apply(to2020, v), Y2020);
    let limited = |v: [f64; 3]| {
        let yv = y(v);
        let comp = opponent_brightness(v, y);
        // A negative Y has no 0.08th power: the compensation alone (the
        // generator's NaN weight, taken as weight 0).
        let w = if yv >= 0.0 { fmath::powf(yv, 0.08).clamp(0.0, 1.0) } else { 0.0 };
        (1.0 - w) * comp + w * yv
    };
    let before = limited(c);
    let offset = (-min3(c)).max(0.0);
    let o = c.map(|v| v + offset);
    let after = limited(o);
    let k = if after > before { before / after.max(1e-100) } else { 1.0 };
    o.map(|v| k * v)
}

fn rgb_to_hsv(c: [f64; 3]) -> [f64; 3] {
    let (mx, mn) = (max3(c), min3(c));
    let d = mx - mn;
    let s = if mx > 0.0 { d / mx } else { 0.0 };
    if d <= 0.0 {
        return [0.0, s, mx];
    }
    let h = if mx == c[0] {
        (c[1] - c[2]) / d
    } else if mx == c[1] {
        2.0 + (c[2] - c[0]) / d
    } else {
        4.0 + (c[0] - c[1]) / d
    };
    [(h / 6.0).rem_euclid(1.0), s, mx]
}

fn hsv_to_rgb([h, s, v]: [f64; 3]) -> [f64; 3] {
    let i = (h * 6.0).floor();
    let f = h * 6.0 - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match (i as i64).rem_euclid(6) {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    }
}

/// The sigmoid of step 4, on the log-encoded value x (0 at -10 stops, 1 at
/// +6.5 stops), returning the 2.4-power display encoding.
pub fn sigmoid(x: f64) -> f64 {
    let x_p = STOPS_BELOW / (STOPS_BELOW + STOPS_ABOVE);
    let y_p = fmath::powf(GREY, 1.0 / GAMMA);
    let scale = |dx: f64, dy: f64| SLOPE * dx / fmath::powf(fmath::powf(SLOPE * dx / dy, POWER) - 1.0, 1.0 / POWER);
    let s = if x < x_p { scale(x_p, y_p) } else { scale(1.0 - x_p, 1.0 - y_p) };
    let t = SLOPE * (x - x_p) / s;
    y_p + s * t / fmath::powf(1.0 + fmath::powf(t.abs(), POWER), 1.0 / POWER)
}

/// AgX as Blender's LUT holds it: Rec.2020 (any sign) to 2.4-encoded
/// Rec.709 in [0, 1] (steps 1-7).
fn formed(c2020: [f64; 3], to709: &M3, to2020_from_709: &M3, outset: &M3) -> [f64; 3] {
    let c = apply(&INSET, guard_rail_2020(c2020));
    let hue_before = rgb_to_hsv(c)[0];
    let y = c.map(|v| {
        let x = (fmath::log2(v) - LOG2_MIN) / (LOG2_MAX - LOG2_MIN);
        // Below -10 stops (and at 0) the curve has no value: black, as the
        // generator's NaN nodes are written as 0.
        let e = sigmoid(x);
        if x.is_finite() && e > 0.0 {
            fmath::powf(e, GAMMA)
        } else {
            0.0
        }
    });
    let [hue_after, s, v] = rgb_to_hsv(y);
    let h = (1.0 - HUE_MIX) * hue_before + HUE_MIX * hue_after;
    let c = apply(to709, apply(outset, hsv_to_rgb([h, s, v])));
    guard_rail_709(c, to2020_from_709).map(|v| if v > 0.0 { fmath::powf(v, 1.0 / GAMMA).min(1.0) } else { 0.0 })
}

/// A `size`^3 LUT (red slowest, blue fastest) whose nodes are computed
/// when first read: a small picture reads a few hundred of the 185,193
/// nodes of the AgX LUT, and building them all cost a 16x9 render a
/// twentieth of a second. Each node is a pure function of its index, so the
/// values never depend on which pixel, thread or order read it first.
pub struct LazyLut {
    size: usize,
    nodes: Vec<OnceLock<[f32; 3]>>,
    node: Box<dyn Fn([usize; 3]) -> [f32; 3] + Send + Sync>,
}

impl LazyLut {
    pub fn new(size: usize, node: impl Fn([usize; 3]) -> [f32; 3] + Send + Sync + 'static) -> LazyLut {
        LazyLut { size, nodes: (0..size * size * size).map(|_| OnceLock::new()).collect(), node: Box::new(node) }
    }

    /// Node `(r, g, b)`.
    #[inline]
    pub fn at(&self, r: usize, g: usize, b: usize) -> [f32; 3] {
        *self.nodes[(r * self.size + g) * self.size + b].get_or_init(|| (self.node)([r, g, b]))
    }
}

/// Tetrahedral interpolation (OpenColorIO's `interpolation: tetrahedral`)
/// of the LUT `lut` at `p`, each component clamped to [0, 1].
pub fn tetrahedral(lut: &LazyLut, p: [f64; 3]) -> [f64; 3] {
    let size = lut.size;
    let last = (size - 1) as f64;
    let q = p.map(|v| v.clamp(0.0, 1.0) * last);
    let i = q.map(|v| (v.floor() as usize).min(size - 2));
    let [fr, fg, fb] = [q[0] - i[0] as f64, q[1] - i[1] as f64, q[2] - i[2] as f64];
    let c = |a: usize, b: usize, d: usize| lut.at(i[0] + a, i[1] + b, i[2] + d).map(f64::from);
    // The tetrahedron containing (fr, fg, fb): weights along the path
    // from corner 000 to 111 through the two corners it passes.
    let (w, k1, k2) = if fr > fg {
        if fg > fb {
            ([1.0 - fr, fr - fg, fg - fb, fb], c(1, 0, 0), c(1, 1, 0))
        } else if fr > fb {
            ([1.0 - fr, fr - fb, fb - fg, fg], c(1, 0, 0), c(1, 0, 1))
        } else {
            ([1.0 - fb, fb - fr, fr - fg, fg], c(0, 0, 1), c(1, 0, 1))
        }
    } else if fb > fg {
        ([1.0 - fb, fb - fg, fg - fr, fr], c(0, 0, 1), c(0, 1, 1))
    } else if fb > fr {
        ([1.0 - fg, fg - fb, fb - fr, fr], c(0, 1, 0), c(0, 1, 1))
    } else {
        ([1.0 - fg, fg - fr, fr - fb, fb], c(0, 1, 0), c(1, 1, 0))
    };
    let (c0, c3) = (c(0, 0, 0), c(1, 1, 1));
    std::array::from_fn(|j| w[0] * c0[j] + w[1] * k1[j] + w[2] * k2[j] + w[3] * c3[j])
}

/// The AgX view transform for an sRGB display.
pub struct Agx {
    /// Rec.709 to FilmLight E-Gamut.
    to_e_gamut: M3,
    /// `LUT_SIZE`^3 nodes of 2.4-encoded Rec.709.
    lut: LazyLut,
}

impl Agx {
    /// The transform (its LUT's nodes computed once per process, when first read).
    pub fn get() -> &'static Agx {
        static AGX: OnceLock<Agx> = OnceLock::new();
        AGX.get_or_init(Agx::build)
    }

    fn build() -> Agx {
        let xyz709 = rgb_to_xyz(&REC709);
        let xyz2020 = rgb_to_xyz(&REC2020);
        let xyz_e = rgb_to_xyz(&E_GAMUT);
        let to709 = mul(&inverse(&xyz709), &xyz2020);
        let to2020_from_709 = mul(&inverse(&xyz2020), &xyz709);
        let e_to2020 = mul(&inverse(&xyz2020), &xyz_e);
        let outset = inverse(&OUTSET_INV);
        let n = LUT_SIZE;
        let node = move |i: usize| fmath::exp2(LUT_LOG2_MIN + (LUT_LOG2_MAX - LUT_LOG2_MIN) * i as f64 / (n - 1) as f64);
        let lut = LazyLut::new(n, move |rgb| {
            let c = apply(&e_to2020, rgb.map(node));
            formed(c, &to709, &to2020_from_709, &outset).map(|v| v as f32)
        });
        Agx { to_e_gamut: mul(&inverse(&xyz_e), &xyz709), lut }
    }

    /// Scene-linear Rec.709 to sRGB display code values in [0, 1].
    pub fn display(&self, linear: [f64; 3]) -> [f64; 3] {
        let e = apply(&self.to_e_gamut, linear);
        let span = LUT_LOG2_MAX - LUT_LOG2_MIN;
        // Non-positive components sit at the LUT's floor (log2 of 0 is -inf).
        let p = e.map(|v| if v > 0.0 { (fmath::log2(v) - LUT_LOG2_MIN) / span } else { 0.0 });
        tetrahedral(&self.lut, p).map(|v| srgb_oetf(fmath::powf(v.max(0.0), GAMMA).min(1.0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_range_is_ten_stops_below_and_six_and_a_half_above_middle_grey() {
        assert!((LOG2_MIN - (fmath::log2(GREY) - 10.0)).abs() < 1e-12);
        assert!((LOG2_MAX - (fmath::log2(GREY) + 6.5)).abs() < 1e-12);
        // Blender's published numbers (to their 7 digits).
        assert!((LOG2_MIN + 12.47393).abs() < 1e-5 && (LOG2_MAX - 4.026069).abs() < 1e-6);
    }

    #[test]
    fn the_sigmoid_passes_through_its_ends_and_fulcrum_with_slope_2_4() {
        let x_p = 10.0 / 16.5;
        assert!(sigmoid(0.0).abs() < 1e-12);
        assert!((sigmoid(1.0) - 1.0).abs() < 1e-12);
        assert!((sigmoid(x_p) - fmath::powf(GREY, 1.0 / 2.4)).abs() < 1e-12);
        let h = 1e-6;
        assert!(((sigmoid(x_p + h) - sigmoid(x_p - h)) / (2.0 * h) - 2.4).abs() < 1e-4);
        let mut last = -1.0;
        for i in 0..=1000 {
            let y = sigmoid(i as f64 / 1000.0);
            assert!(y > last, "monotonic");
            last = y;
        }
    }

    #[test]
    fn middle_grey_stays_middle_grey_and_greys_stay_grey() {
        // Inset and outset rows sum to 1 and the guard rails and hue mix
        // leave greys alone: 0.18 forms to display-linear 0.18, sRGB 0.4614.
        let to709 = mul(&inverse(&rgb_to_xyz(&REC709)), &rgb_to_xyz(&REC2020));
        let to2020 = inverse(&to709);
        let f = formed([GREY; 3], &to709, &to2020, &inverse(&OUTSET_INV));
        for v in f {
            assert!((fmath::powf(v, 2.4) - GREY).abs() < 1e-9, "{f:?}");
        }
        let d = Agx::get().display([GREY; 3]);
        for v in d {
            assert!((v - srgb_oetf(GREY)).abs() < 2e-3, "{d:?}");
        }
        for stops in [-8.0, -3.0, 0.0, 2.0, 5.0] {
            let d = Agx::get().display([GREY * fmath::exp2(stops); 3]);
            assert!((d[0] - d[1]).abs() < 1e-4 && (d[1] - d[2]).abs() < 1e-4, "{stops}: {d:?}");
        }
    }

    #[test]
    fn black_is_black_and_bright_light_reaches_white_without_clipping_hue() {
        // Black sits at the LUT's floor node, 2^-12.47 below middle grey's log range: code value 0.
        assert!(Agx::get().display([0.0; 3]).iter().all(|&v| v < 1e-6));
        // +6.5 stops above middle grey is the top of the curve: white.
        let w = Agx::get().display([GREY * fmath::powf(2f64, 6.5); 3]);
        assert!(w.iter().all(|&v| v > 0.99), "{w:?}");
        // A very bright pure green goes toward white, keeping green ahead.
        let g = Agx::get().display([0.0, 50.0, 0.0]);
        assert!(g[1] > 0.95 && g[0] > 0.5 && g[2] > 0.4 && g[1] > g[0] && g[1] > g[2], "{g:?}");
    }

    #[test]
    fn inset_and_outset_keep_white() {
        for row in INSET.iter().chain(OUTSET_INV.iter()) {
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn guard_rails_leave_positive_colours_alone_and_remove_negatives() {
        let c = [0.2, 0.5, 0.01];
        assert_eq!(guard_rail_2020(c), c);
        let g = guard_rail_2020([-0.1, 0.5, 0.2]);
        assert!(g.iter().all(|&v| v >= 0.0), "{g:?}");
        let to2020 = mul(&inverse(&rgb_to_xyz(&REC2020)), &rgb_to_xyz(&REC709));
        assert_eq!(guard_rail_709(c, &to2020), c);
        assert!(guard_rail_709([0.3, -0.05, 0.1], &to2020).iter().all(|&v| v >= 0.0));
    }
}
