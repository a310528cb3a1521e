//! Colour science shared by the bake and the renderer: the eye's response
//! to a spectrum, linear Rec.709 and its luminance, the way back into the
//! Rec.709 gamut, colour-space matrices from primaries, and the sRGB
//! encoding of a display.
//!
//! Colour space: linear Rec.709 / sRGB primaries, D65 white.
//!
//! - [`cie1931_xyz`]: the CIE 1931 2-degree colour matching functions
//!   through the multi-lobe Gaussian fit of Wyman, Sloan & Shirley, "Simple
//!   analytic approximations to the CIE XYZ color matching functions",
//!   JCGT 2(2), 2013 (their eq. 2-4); within 2 % of each function's peak of
//!   the CIE 15:2004 table.
//! - [`XYZ_TO_REC709`] and [`REC709_LUMA`]: XYZ to linear sRGB and the
//!   luminance row, as IEC 61966-2-1 prints them (4 digits).
//! - [`gamut_map`]: a colour outside Rec.709 moved toward the grey of equal
//!   luminance by the smallest step that leaves no component negative.
//! - [`rgb_to_xyz`]: the normalised primary matrix of a colour space from
//!   its primaries and white (SMPTE RP 177), full precision; with [`mul`]
//!   and [`inverse`] it converts between any two spaces ([`REC709`],
//!   [`REC2020`]).
//! - [`srgb_oetf`]: the sRGB display encoding, `12.92 x` for
//!   `x <= 0.0031308` and `1.055 x^(1/2.4) - 0.055` above
//!   (IEC 61966-2-1).
//! - [`hsv_hue_saturation`]: a colour's HSV hue and saturation, by which
//!   the tests tell a green from a yellow-green.

use crate::util::fmath;

/// A 3 x 3 matrix, rows first.
pub type M3 = [[f64; 3]; 3];

/// Rec.709 / sRGB primaries and white, CIE xy (ITU-R BT.709).
pub const REC709: [[f64; 2]; 4] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06], [0.3127, 0.3290]];
/// Rec.2020 primaries and white, CIE xy (ITU-R BT.2020).
pub const REC2020: [[f64; 2]; 4] = [[0.708, 0.292], [0.170, 0.797], [0.131, 0.046], [0.3127, 0.3290]];

/// Piecewise Gaussian of Wyman, Sloan & Shirley (2013): width `s1` left of the
/// mean, `s2` right of it.
#[inline]
fn lobe(x: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let t = (x - mu) / if x < mu { s1 } else { s2 };
    fmath::exp(-0.5 * t * t)
}

/// CIE 1931 2-degree colour matching functions (xbar, ybar, zbar) at
/// `lambda_nm`, multi-lobe fit of Wyman, Sloan & Shirley (2013), eq. 2-4.
pub fn cie1931_xyz(lambda_nm: f64) -> [f64; 3] {
    let l = lambda_nm;
    let x = 1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) - 0.065 * lobe(l, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8);
    [x, y, z]
}

/// XYZ to linear Rec.709 (sRGB primaries, D65 white), IEC 61966-2-1.
pub const XYZ_TO_REC709: M3 = [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]];

/// Luminance Y of a linear Rec.709 colour (the Y row of the inverse matrix).
pub const REC709_LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Linear Rec.709 of an XYZ colour ([`XYZ_TO_REC709`]).
pub fn xyz_to_rec709(xyz: [f64; 3]) -> [f64; 3] {
    apply(&XYZ_TO_REC709, xyz)
}

/// Luminance Y of a linear Rec.709 colour.
#[inline]
pub fn luminance(rgb: [f64; 3]) -> f64 {
    REC709_LUMA[0] * rgb[0] + REC709_LUMA[1] * rgb[1] + REC709_LUMA[2] * rgb[2]
}

/// Gamut mapping for colours outside Rec.709 (every monochromatic line is):
/// desaturate toward the white of equal luminance, `(1 - t) rgb + t (Y, Y, Y)`,
/// with the smallest `t` in [0, 1] that leaves no component negative. Y is
/// kept exactly (white has luminance Y and the map is affine), and the hue in
/// the RGB cube is kept approximately (we move along the line to grey).
/// A colour with Y <= 0 has no such white and maps to black.
pub fn gamut_map(rgb: [f64; 3]) -> [f64; 3] {
    let y = luminance(rgb);
    if y <= 0.0 {
        return [0.0; 3];
    }
    // Component c reaches 0 at t = -c / (Y - c) (Y > 0 > c).
    let t = rgb.iter().filter(|&&c| c < 0.0).map(|&c| -c / (y - c)).fold(0.0, f64::max);
    std::array::from_fn(|i| ((1.0 - t) * rgb[i] + t * y).max(0.0))
}

/// The matrix product `a b`.
pub fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The matrix `m` applied to the column `c`.
pub fn apply(m: &M3, c: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * c[0] + m[i][1] * c[1] + m[i][2] * c[2])
}

/// The inverse of `m` (cofactors over the determinant).
pub fn inverse(m: &M3) -> M3 {
    let c = |i: usize, j: usize| {
        m[(i + 1) % 3][(j + 1) % 3] * m[(i + 2) % 3][(j + 2) % 3] - m[(i + 1) % 3][(j + 2) % 3] * m[(i + 2) % 3][(j + 1) % 3]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    std::array::from_fn(|i| std::array::from_fn(|j| c(j, i) / det))
}

/// RGB to XYZ of a colour space from its primaries and white (the
/// normalised primary matrix, SMPTE RP 177).
pub fn rgb_to_xyz(p: &[[f64; 2]; 4]) -> M3 {
    let xyz = |[x, y]: [f64; 2]| [x / y, 1.0, (1.0 - x - y) / y];
    let cols = [xyz(p[0]), xyz(p[1]), xyz(p[2])];
    let prim: M3 = std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i]));
    let s = apply(&inverse(&prim), xyz(p[3]));
    std::array::from_fn(|i| std::array::from_fn(|j| prim[i][j] * s[j]))
}

/// The sRGB OETF (IEC 61966-2-1) of a linear value.
pub fn srgb_oetf(x: f64) -> f64 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * fmath::powf(x, 1.0 / 2.4) - 0.055
    }
}

/// The HSV (hexcone) hue in degrees, in `[0, 360)`, and the saturation of
/// an RGB colour with non-negative components; a grey has hue and
/// saturation 0.
pub fn hsv_hue_saturation(c: [f64; 3]) -> (f64, f64) {
    let [r, g, b] = c;
    let (mx, mn) = (r.max(g).max(b), r.min(g).min(b));
    if mx == mn {
        return (0.0, 0.0);
    }
    let h = if mx == r {
        60.0 * ((g - b) / (mx - mn))
    } else if mx == g {
        60.0 * ((b - r) / (mx - mn) + 2.0)
    } else {
        60.0 * ((r - g) / (mx - mn) + 4.0)
    };
    (h.rem_euclid(360.0), (mx - mn) / mx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cmf_fit_matches_cie_table_values() {
        // CIE 1931 2-degree table values. The multi-lobe fit is an
        // approximation (largest error here: xbar(440) 0.359 vs 0.348, 1 % of
        // the peak); allow 2 % of each function's peak (1.06, 1.0, 1.78).
        let cases = [
            (555.0, 1, 1.0000),
            (600.0, 0, 1.0622),
            (450.0, 2, 1.7721),
            (630.0, 1, 0.2650),
            (440.0, 0, 0.3483),
            (500.0, 1, 0.3230),
            (650.0, 0, 0.2835),
        ];
        let peak = [1.0622, 1.0, 1.7721];
        for (l, k, want) in cases {
            let got = cie1931_xyz(l)[k];
            assert!((got - want).abs() < 0.02 * peak[k], "{l} nm component {k}: {got} vs {want}");
        }
    }

    #[test]
    fn cmf_fit_follows_the_cie_table_across_the_visible() {
        // CIE 1931 2-degree table (CIE 15:2004, table T.4), 10 nm steps.
        // Same 2 %-of-peak tolerance as above (the fit's largest deviation on
        // these rows is about 1 % of the peak).
        #[rustfmt::skip]
        let table = [
            (400.0, 0.01431, 0.000396, 0.06785), (420.0, 0.13438, 0.0040, 0.64560),
            (460.0, 0.29080, 0.06000, 1.66920), (470.0, 0.19536, 0.09098, 1.28764),
            (480.0, 0.09564, 0.13902, 0.81295), (490.0, 0.03201, 0.20802, 0.46518),
            (510.0, 0.00930, 0.50300, 0.15820), (520.0, 0.06327, 0.71000, 0.07825),
            (530.0, 0.16550, 0.86200, 0.04216), (540.0, 0.29040, 0.95400, 0.02030),
            (550.0, 0.43345, 0.99495, 0.00875), (560.0, 0.59450, 0.99500, 0.00390),
            (570.0, 0.76210, 0.95200, 0.00210), (580.0, 0.91630, 0.87000, 0.00165),
            (590.0, 1.02630, 0.75700, 0.00110), (610.0, 1.00260, 0.50300, 0.00034),
            (620.0, 0.85445, 0.38100, 0.00019), (640.0, 0.44790, 0.17500, 0.00002),
            (660.0, 0.16490, 0.06100, 0.0), (680.0, 0.04677, 0.01700, 0.0),
            (700.0, 0.01136, 0.00410, 0.0),
        ];
        let peak = [1.0622, 1.0, 1.7826];
        for (l, x, y, z) in table {
            let got = cie1931_xyz(l);
            for (k, want) in [x, y, z].into_iter().enumerate() {
                assert!((got[k] - want).abs() < 0.02 * peak[k], "{l} nm component {k}: {} vs {want}", got[k]);
            }
        }
        // Equal-energy white: the three functions have equal integrals
        // (CIE 1931 normalisation, 106.86 nm each); the fit keeps them within
        // 0.1 % (1 nm sums, 360-830 nm): allow 0.5 %.
        let int = (360..=830).fold([0.0; 3], |a, l| {
            let c = cie1931_xyz(l as f64);
            [a[0] + c[0], a[1] + c[1], a[2] + c[2]]
        });
        for (k, v) in int.iter().enumerate() {
            assert!((v / 106.86 - 1.0).abs() < 0.005, "integral {k}: {v}");
        }
    }

    #[test]
    fn white_maps_to_equal_rgb_and_luma_row_matches_y() {
        // D65 white point XYZ (0.95047, 1, 1.08883) -> (1, 1, 1) to the
        // matrix's 4-digit precision.
        let w = xyz_to_rec709([0.95047, 1.0, 1.08883]);
        for c in w {
            assert!((c - 1.0).abs() < 1e-3, "{w:?}");
        }
        let xyz = [0.3, 0.5, 0.2];
        assert!((luminance(xyz_to_rec709(xyz)) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn the_printed_matrix_is_the_one_the_primaries_give() {
        // IEC 61966-2-1's 4-digit XYZ to Rec.709 matrix and luminance row
        // against the normalised primary matrix of the Rec.709 primaries.
        let to_xyz = rgb_to_xyz(&REC709);
        let m = inverse(&to_xyz);
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - XYZ_TO_REC709[i][j]).abs() < 1e-3, "{m:?}");
            }
            assert!((to_xyz[1][i] - REC709_LUMA[i]).abs() < 1e-4, "{to_xyz:?}");
        }
    }

    #[test]
    fn rec709_to_rec2020_is_the_published_matrix() {
        // ITU-R BT.2087, to its 4 digits.
        let m = mul(&inverse(&rgb_to_xyz(&REC2020)), &rgb_to_xyz(&REC709));
        let want = [[0.6274, 0.3293, 0.0433], [0.0691, 0.9195, 0.0114], [0.0164, 0.0880, 0.8956]];
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - want[i][j]).abs() < 1e-4, "{m:?}");
            }
        }
    }

    #[test]
    fn gamut_map_keeps_luminance_and_clears_negatives() {
        for l in [427.8, 450.0, 500.0, 557.7, 630.0, 700.0] {
            let raw = xyz_to_rec709(cie1931_xyz(l));
            let m = gamut_map(raw);
            assert!(m.iter().all(|&c| c >= 0.0), "{l}: {m:?}");
            // Affine map toward (Y, Y, Y): Y is kept to rounding.
            assert!((luminance(m) - luminance(raw)).abs() < 1e-12 * (1.0 + luminance(raw).abs()), "{l}");
            // Minimal: some component sits at exactly zero when raw was out of gamut.
            if raw.iter().any(|&c| c < 0.0) {
                assert!(m.iter().any(|&c| c.abs() < 1e-12), "{l}: {m:?}");
            }
        }
        let inside = [0.2, 0.5, 0.1];
        assert_eq!(gamut_map(inside), inside);
    }

    #[test]
    fn gamut_map_moves_along_the_line_to_grey_by_the_smallest_step() {
        // raw = (-0.1, 0.5, 0.2): Y = 0.35078, t = 0.1 / (Y + 0.1), and the
        // result minus grey is (1 - t) times raw minus grey.
        let raw = [-0.1, 0.5, 0.2];
        let y = 0.2126 * -0.1 + 0.7152 * 0.5 + 0.0722 * 0.2;
        let t = 0.1 / (y + 0.1);
        let m = gamut_map(raw);
        for k in 0..3 {
            assert!((m[k] - y - (1.0 - t) * (raw[k] - y)).abs() < 1e-15, "{m:?}");
        }
        assert!(m[0].abs() < 1e-16);
        // Two negative components: the more negative one decides.
        let m = gamut_map([-0.3, 1.0, -0.05]);
        assert!(m[0].abs() < 1e-15 && m[2] > 0.0, "{m:?}");
        // Negative luminance: no white to move to, black.
        assert_eq!(gamut_map([0.2, -0.2, 0.0]), [0.0; 3]);
    }

    #[test]
    fn the_srgb_curve_is_continuous_at_its_knee_and_ends_at_one() {
        let k = 0.003_130_8;
        assert!((srgb_oetf(k) - (1.055 * fmath::powf(k, 1.0 / 2.4) - 0.055)).abs() < 1e-6);
        assert_eq!(srgb_oetf(0.0), 0.0);
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-12);
        // Middle grey 0.18 encodes to 0.4614 (118 of 255).
        assert!((srgb_oetf(0.18) - 0.4614).abs() < 1e-4);
    }
}
