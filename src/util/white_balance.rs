//! The camera's white balance (`[colour] white_balance_k`): what a raw
//! converter does to a camera's picture to make a grey lit by a Planckian
//! illuminant of temperature `T` come out grey.
//!
//! **Model.** The camera observer's table (`crate::util::observer`) is the
//! Nikon D5100's raw response `r(lambda)` balanced for daylight D55,
//! `diag(1 / d)`, then taken to Rec.709 by the ColorChecker-fitted matrix
//! `M`: `c(lambda) = s M diag(1 / d) r(lambda)`. Balancing for an
//! illuminant `P` instead is von Kries in the camera's raw space, each raw
//! channel divided by its response to `P`, `U_P = M^-1 sum c(lambda)
//! P(lambda)` (the same raw response up to the D55 gains, which cancel),
//! then the same matrix:
//!
//! `W(T) = k N M diag(1 / U_T) M^-1`, applied to the table's linear Rec.709,
//!
//! with `P = B_T`, Planck's spectrum at `T`, summed at every nm of the
//! table (380-780 nm). `N = diag(1 / (M 1))` scales each row of `M` to sum
//! to 1, as raw converters normalise their camera matrix (dcraw's
//! `cam_xyz_coeff`), so the balanced grey is exactly grey: `M`'s rows sum
//! to 0.985-0.998. `k` keeps the grey's luminance as the table records it,
//! so a white balance changes colours, not the exposure of a grey. A grey
//! under `B_T` then renders `(Y, Y, Y)` at `white_balance_k = T`.
//! Photographers of aurora set 3200-4000 K or leave it on auto
//! (docs/colour.md); the daylight table is `W` near 5500 K up to `N`.
//!
//! Only the camera has a white balance: the eye's colours are
//! colorimetric (D65 white) and are left as they are.

use crate::util::colour::luminance;
use crate::util::fmath;
use crate::util::observer::{camera_matrix, Observer, CAMERA_RANGE_NM};

/// The second radiation constant, nm K.
const HC_K_NM: f64 = 1.438_777e7;
/// The white balance's allowed range, K (the key's range).
pub const WHITE_BALANCE_RANGE_K: (f64, f64) = (1500.0, 20000.0);

/// Planck's spectral radiance at `t_k` up to a constant (energy per nm).
pub fn planck(lambda_nm: f64, t_k: f64) -> f64 {
    fmath::powi(lambda_nm, -5) / (fmath::exp(HC_K_NM / (lambda_nm * t_k)) - 1.0)
}

/// The camera's linear Rec.709 of a grey lit by the spectrum `p` (energy
/// per nm), summed at every nm of the table, at its daylight balance.
pub fn camera_rgb_of(p: impl Fn(f64) -> f64) -> [f64; 3] {
    let (a, b) = (CAMERA_RANGE_NM.0 as u32, CAMERA_RANGE_NM.1 as u32);
    let mut rgb = [0.0; 3];
    for l in a..=b {
        let (l, c) = (l as f64, Observer::Camera.rgb(l as f64));
        for k in 0..3 {
            rgb[k] += p(l) * c[k];
        }
    }
    rgb
}

/// The inverse of a 3x3 matrix (rows), by cofactors; None if singular.
fn inverse(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |r: usize, k: usize| {
        let (r1, r2, k1, k2) = ((r + 1) % 3, (r + 2) % 3, (k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    if det.abs() < 1e-12 {
        return None;
    }
    Some(std::array::from_fn(|i| std::array::from_fn(|j| c(j, i) / det)))
}

fn mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// `m` times the column `v`.
pub fn apply(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// `W(T)` of the module doc: the matrix that takes the camera's daylight
/// Rec.709 to its Rec.709 at white balance `t_k` (K, in
/// [`WHITE_BALANCE_RANGE_K`]).
pub fn camera_white_balance(t_k: f64) -> [[f64; 3]; 3] {
    let m = camera_matrix();
    let m_inv = inverse(m).expect("the camera matrix is invertible");
    let grey = camera_rgb_of(|l| planck(l, t_k));
    let u = apply(&m_inv, grey);
    let gains = [[1.0 / u[0], 0.0, 0.0], [0.0, 1.0 / u[1], 0.0], [0.0, 0.0, 1.0 / u[2]]];
    let rows: [f64; 3] = std::array::from_fn(|i| m[i].iter().sum());
    let n = [[1.0 / rows[0], 0.0, 0.0], [0.0, 1.0 / rows[1], 0.0], [0.0, 0.0, 1.0 / rows[2]]];
    let k = luminance(grey);
    mul(mul(mul(n, m), gains), m_inv).map(|r| r.map(|x| x * k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::colour::hsv_hue_saturation;

    /// A grey lit by a Planckian at T renders grey at `white_balance_k =
    /// T` (to rounding: the construction is exact) with its luminance kept;
    /// balanced for another temperature it is not: 1000 K off leaves a
    /// colour cast of several percent, warm under a lower white balance.
    #[test]
    fn a_grey_under_a_planckian_is_grey_at_its_temperature() {
        for t in [2500.0, 3200.0, 3800.0, 5500.0, 6500.0, 10000.0] {
            let grey = camera_rgb_of(|l| planck(l, t));
            let out = apply(&camera_white_balance(t), grey);
            let y = luminance(grey);
            for c in out {
                assert!((c / y - 1.0).abs() < 1e-9, "{t} K: {out:?} (Y {y})");
            }
            let off = apply(&camera_white_balance(t + 1000.0), grey);
            let (h, s) = hsv_hue_saturation(off);
            assert!(s > 0.04 && !(90.0..300.0).contains(&h), "{t} K seen at {} K: hue {h}, saturation {s}", t + 1000.0);
        }
    }

    /// Without its white balance the camera records a 3500 K grey orange
    /// (the daylight table), as a camera left on daylight does under
    /// tungsten light.
    #[test]
    fn daylight_balance_sees_a_warm_light_orange() {
        let grey = camera_rgb_of(|l| planck(l, 3500.0));
        let (h, s) = hsv_hue_saturation(grey);
        assert!((15.0..50.0).contains(&h) && s > 0.3, "hue {h} saturation {s}");
        assert!(inverse([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]).is_none());
    }
}
