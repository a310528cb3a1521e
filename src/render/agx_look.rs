//! The looks Blender 5.0 ships for its AgX view (`AgX - Punchy`, the
//! contrast looks and `AgX - Greyscale`): a grade of the scene-linear colour
//! before AgX forms the picture (`agx.rs`), reproduced from their published
//! definitions in Blender's OpenColorIO configuration (`looks:` of
//! `datafiles/colormanagement/config.ocio`, Blender 5.0) and OpenColorIO 2's
//! grading operators (GradingPrimaryTransform, GradingToneTransform,
//! CDLTransform; github.com/AcademySoftwareFoundation/OpenColorIO,
//! `ops/gradingprimary`, `ops/gradingtone`), nothing of Blender's read.
//!
//! Every look grades in the config's `AgX Log` space and goes back to the
//! scene-linear colour the AgX view then takes:
//!
//! 1. Rec.709 to FilmLight E-Gamut, log2-encoded from log2(0.18) - 10 to
//!    log2(0.18) + 15 (`agx.rs`'s LUT input), then the *luminance
//!    compensation* LUT (`luminance_compensation_bt2020.cube`, 37^3,
//!    tetrahedral): each node's colour taken to Rec.2020, its negative
//!    components removed by AgX's lower guard rail (`agx::guard_rail_2020`),
//!    and back; built here from that construction (it agrees with the shipped
//!    cube to 1e-6);
//! 2. out of log, E-Gamut to Rec.2020, AgX's inset ([`crate::render::agx::INSET`])
//!    and the same log2 encoding: the `AgX Log` value `x` in about [0, 1];
//! 3. the grade of `x`:
//!    * contrast looks (GradingPrimary, log style): `y = (x - p) c + p`,
//!      `p = 0.5 + 0.5 (-0.2) = 0.4`, then saturation `s` about the Rec.709
//!      luma of `y` (weights 0.2126, 0.7152, 0.0722): [`CONTRASTS`];
//!    * `punchy`: GradingTone (log style) shadows, per channel 0.2 then
//!      master 0.35, start 0.4, pivot 0.1 (OpenColorIO's quadratic "faux
//!      cubic" through (0.1, 0.1), (0.25, y1), (0.4, 0.4) with slope m0 at its
//!      foot and 1 at its top, linear outside), then a CDL power 1.0912;
//!    * `greyscale`: out of log, the Rec.2020-in-inset luminance
//!      (0.2589, 0.6105, 0.1306) in every channel, back to log;
//! 4. out of log, the inset's inverse, Rec.2020 to Rec.709.
//!
//! Exposure is applied before the look, as in Blender.

use super::agx::{guard_rail_2020, tetrahedral, LazyLut, E_GAMUT, INSET, LUT_LOG2_MAX, LUT_LOG2_MIN};
use crate::scene::ViewTransform;
use crate::util::colour::{apply, inverse, mul, rgb_to_xyz, M3, REC2020, REC709};
use crate::util::fmath;
use std::sync::OnceLock;

/// Nodes per side of the luminance compensation LUT.
const COMP_SIZE: usize = 37;
/// GradingPrimary's log-style pivot: 0.5 + 0.5 x the config's -0.2.
const PIVOT: f64 = 0.4;
/// OpenColorIO's luma weights for saturation (Rec.709).
const LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];
/// `AgX - Greyscale`'s luminance weights (the config's matrix row).
const GREY_WEIGHTS: [f64; 3] = [0.2589235355689848, 0.6104985346066525, 0.13057792982436284];
/// `AgX - Punchy`: shadows per channel and master, start, pivot; CDL power.
const PUNCHY_SHADOWS: (f64, f64, f64, f64) = (0.2, 0.35, 0.4, 0.1);
const PUNCHY_POWER: f64 = 1.0912;

/// The contrast looks' (contrast, saturation), as the config gives them.
pub const CONTRASTS: [(ViewTransform, f64, f64); 7] = [
    (ViewTransform::AgxVeryHighContrast, 1.57, 0.9),
    (ViewTransform::AgxHighContrast, 1.4, 0.95),
    (ViewTransform::AgxMediumHighContrast, 1.2, 1.0),
    (ViewTransform::AgxBaseContrast, 1.0, 1.0),
    (ViewTransform::AgxMediumLowContrast, 0.9, 1.05),
    (ViewTransform::AgxLowContrast, 0.8, 1.1),
    (ViewTransform::AgxVeryLowContrast, 0.7, 1.15),
];

/// A look's grade of the `AgX Log` value (module doc, step 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Grade {
    Contrast { contrast: f64, saturation: f64 },
    Punchy,
    Greyscale,
}

impl Grade {
    /// The grade of a view with a look; None for `standard` and plain `agx`.
    pub fn of(view: ViewTransform) -> Option<Grade> {
        match view {
            ViewTransform::Standard | ViewTransform::Agx => None,
            ViewTransform::AgxPunchy => Some(Grade::Punchy),
            ViewTransform::AgxGreyscale => Some(Grade::Greyscale),
            v => CONTRASTS.iter().find(|c| c.0 == v).map(|&(_, contrast, saturation)| Grade::Contrast { contrast, saturation }),
        }
    }

    fn grade(self, x: [f64; 3]) -> [f64; 3] {
        match self {
            Grade::Contrast { contrast, saturation } => {
                let y = x.map(|v| (v - PIVOT) * contrast + PIVOT);
                let luma = y[0] * LUMA[0] + y[1] * LUMA[1] + y[2] * LUMA[2];
                y.map(|v| luma + saturation * (v - luma))
            }
            Grade::Punchy => {
                let (per_channel, master, start, pivot) = PUNCHY_SHADOWS;
                let y = x.map(|v| shadows(v, per_channel, start, pivot));
                let y = y.map(|v| shadows(v, master, start, pivot));
                // CDL without clamping: a power of the positive values.
                y.map(|v| if v > 0.0 { fmath::powf(v, PUNCHY_POWER) } else { v })
            }
            Grade::Greyscale => {
                let lin = x.map(from_log);
                let g = lin[0] * GREY_WEIGHTS[0] + lin[1] * GREY_WEIGHTS[1] + lin[2] * GREY_WEIGHTS[2];
                [to_log(g); 3]
            }
        }
    }
}

/// OpenColorIO's GradingTone shadows (log style) of `t` with value `val`
/// below 1: the quadratic pieces from `pivot` (slope `val`) to `start`
/// (slope 1) meeting at their middle, linear outside.
fn shadows(t: f64, val: f64, start: f64, pivot: f64) -> f64 {
    let (x0, x2) = (pivot, start.max(pivot + 0.01));
    let (y0, y2) = (x0, x2);
    let x1 = x0 + (x2 - x0) * 0.5;
    let (m0, m2) = (val.max(0.01), 1.0);
    let y1 = (0.5 / (x2 - x0)) * ((2.0 * y0 + m0 * (x1 - x0)) * (x2 - x1) + (2.0 * y2 - m2 * (x2 - x1)) * (x1 - x0));
    if t < x0 {
        (t - x0) * m0 + y0
    } else if t < x1 {
        let u = (t - x0) / (x1 - x0);
        y0 * (1.0 - u * u) + y1 * u * u + m0 * (1.0 - u) * u * (x1 - x0)
    } else if t < x2 {
        let u = (t - x1) / (x2 - x1);
        y1 * (1.0 - u) * (1.0 - u) + y2 * (2.0 - u) * u + m2 * (u - 1.0) * u * (x2 - x1)
    } else {
        (t - x2) * m2 + y2
    }
}

/// The config's `lg2` allocation, `[LUT_LOG2_MIN, LUT_LOG2_MAX]` to [0, 1];
/// OpenColorIO takes the logarithm of at least the smallest normal float.
fn to_log(v: f64) -> f64 {
    (fmath::log2(v.max(f32::MIN_POSITIVE as f64)) - LUT_LOG2_MIN) / (LUT_LOG2_MAX - LUT_LOG2_MIN)
}

fn from_log(x: f64) -> f64 {
    fmath::exp2(LUT_LOG2_MIN + x * (LUT_LOG2_MAX - LUT_LOG2_MIN))
}

/// The matrices and the luminance compensation LUT the looks share.
struct Spaces {
    rec709_to_e: M3,
    e_to_2020: M3,
    rec2020_to_709: M3,
    inset_inv: M3,
    /// `COMP_SIZE`^3 nodes, red slowest, of log-encoded E-Gamut.
    compensation: LazyLut,
}

impl Spaces {
    fn get() -> &'static Spaces {
        static SPACES: OnceLock<Spaces> = OnceLock::new();
        SPACES.get_or_init(|| {
            let (x709, x2020, xe) = (rgb_to_xyz(&REC709), rgb_to_xyz(&REC2020), rgb_to_xyz(&E_GAMUT));
            let e_to_2020 = mul(&inverse(&x2020), &xe);
            let rec2020_to_e = inverse(&e_to_2020);
            let n = COMP_SIZE;
            let compensation = LazyLut::new(n, move |rgb| {
                let e = rgb.map(|i| from_log(i as f64 / (n - 1) as f64));
                let c = apply(&rec2020_to_e, guard_rail_2020(apply(&e_to_2020, e)));
                c.map(|v| to_log(v) as f32)
            });
            Spaces {
                rec709_to_e: mul(&inverse(&xe), &x709),
                e_to_2020,
                rec2020_to_709: mul(&inverse(&x709), &x2020),
                inset_inv: inverse(&INSET),
                compensation,
            }
        })
    }
}

/// Scene-linear Rec.709 `c` graded by `grade` (module doc), scene-linear
/// Rec.709 again, for the AgX view to form.
pub fn graded(grade: Grade, c: [f64; 3]) -> [f64; 3] {
    let s = Spaces::get();
    let e = apply(&s.rec709_to_e, c).map(to_log);
    let e = tetrahedral(&s.compensation, e).map(from_log);
    let x = apply(&INSET, apply(&s.e_to_2020, e)).map(to_log);
    let y = grade.grade(x).map(from_log);
    apply(&s.rec2020_to_709, apply(&s.inset_inv, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shadows curve passes through its pivot and start with slopes
    /// `val` and 1, is continuous at its middle, and leaves values above its
    /// start alone.
    #[test]
    fn the_shadows_curve_meets_its_ends_with_their_slopes() {
        let f = |t| shadows(t, 0.35, 0.4, 0.1);
        assert!((f(0.1) - 0.1).abs() < 1e-12 && (f(0.4) - 0.4).abs() < 1e-12);
        let h = 1e-7;
        assert!(((f(0.1 + h) - f(0.1)) / h - 0.35).abs() < 1e-5);
        assert!(((f(0.4) - f(0.4 - h)) / h - 1.0).abs() < 1e-5);
        assert!((f(0.25 - 1e-12) - f(0.25 + 1e-12)).abs() < 1e-9);
        assert_eq!(f(0.7), 0.7);
        // Darker in between: a darkening look.
        assert!(f(0.25) < 0.25);
    }

    /// Base Contrast (contrast 1, saturation 1) changes nothing but the
    /// compensation of colours outside Rec.2020, which a Rec.709 grey and a
    /// positive colour are not: within the LUT's float precision.
    #[test]
    fn base_contrast_leaves_a_colour_as_it_was() {
        for c in [[0.18, 0.18, 0.18], [0.5, 0.2, 0.05], [0.01, 0.3, 0.02]] {
            let g = graded(Grade::Contrast { contrast: 1.0, saturation: 1.0 }, c);
            for k in 0..3 {
                assert!((g[k] / c[k] - 1.0).abs() < 2e-4, "{c:?} -> {g:?}");
            }
        }
    }

    /// Contrast pivots at AgX Log 0.4, which is 0.18 x 2^(0.4 x 25 - 10) =
    /// 0.18: middle grey stays; a stop above it goes up by c stops.
    #[test]
    fn contrast_pivots_at_middle_grey() {
        let g = Grade::Contrast { contrast: 1.4, saturation: 1.0 };
        let m = graded(g, [0.18; 3]);
        assert!(m.iter().all(|v| (v / 0.18 - 1.0).abs() < 1e-3), "{m:?}");
        let b = graded(g, [0.36; 3]);
        assert!(b.iter().all(|v| (fmath::log2(v / 0.18) - 1.4).abs() < 1e-3), "{b:?}");
        let grey = graded(Grade::Greyscale, [0.5, 0.1, 0.02]);
        assert!((grey[0] - grey[1]).abs() < 1e-9 * grey[1] && (grey[1] - grey[2]).abs() < 1e-9 * grey[1], "{grey:?}");
    }
}
