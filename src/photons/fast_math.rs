//! The f32 maths of the gather's inner loops: `exp(x)` for `x <= 0`, `erf`
//! by table, and integer `ceil` / `floor`. Each is deterministic (the same
//! IEEE 754 operations whatever the vector width, so the same bits) and
//! branch-free, so the loops calling them vectorise; each error bound is
//! stated here and tested against libm.
//!
//! **Rounding to nearest without a rounding instruction.** libm's `round`
//! and a saturating float-to-integer conversion both block vectorisation,
//! and x86-64's baseline has no rounding instruction. For |y| < 2^22,
//! `t = y + 1.5 * 2^23` ([`ROUND_MAGIC`]) lies in [2^23, 2^24), where consecutive
//! binary32 numbers are 1 apart (IEEE 754 binary32: 23 fraction bits), so
//! the addition rounds y to an integer (to nearest, ties to even, the
//! default rounding), `t - 1.5 * 2^23` is that integer exactly, and so is
//! the difference of t's and the constant's bit patterns (the same binade:
//! bit patterns 1 apart are values 1 apart). [`round_nearest`] is the one
//! place this is done.
//!
//! **exp.** [`exp_neg_f32`]: the range reduction `e^x = 2^(x log2 e) =
//! 2^i 2^f`, i the nearest integer and f in [-1/2, 1/2] (Cody & Waite,
//! *Software Manual for the Elementary Functions*, 1980), 2^i built
//! in the exponent bits and 2^f by its degree-6 Taylor polynomial
//! `sum_k (f ln 2)^k / k!`: truncation `(ln2 / 2)^7 / 7! = 1.2e-7` relative.
//!
//! **erf.** [`erf_lut`]: linear interpolation in a table of erf at steps h
//! = 1/1024 on [0, 4] (1 beyond: erfc(4) = 1.5e-8). Interpolation errs by
//! at most `h^2 / 8 max|erf''| = 1.2e-7` (`erf''(x) = -4x e^{-x^2} /
//! sqrt(pi)`, at most 0.97 at x = 1/sqrt 2), plus f32 rounding. The segment
//! kernel takes two per voxel and photon; a lookup costs far less than a
//! rational approximation's exponential and division (Abramowitz & Stegun
//! 7.1.26 measured slower). [`erf_lut_lanes`] is the same at 4 or 8 lanes.
//!
//! **ceil and floor.** [`ceil_i`], [`floor_i`]: truncation and a
//! correction, exact for |x| < 2^31 (`f64::ceil` is a libm call on the
//! x86-64 baseline; the gather takes six per photon and leaf).

use glam::{DVec3, IVec3};

/// `1.5 * 2^23`, the constant of [`round_nearest`] (module documentation):
/// adding it to an f32 below 2^22 in magnitude rounds it to an integer.
pub const ROUND_MAGIC: f32 = 12_582_912.0;

/// `y` rounded to the nearest integer (ties to even), as an integer and as
/// an f32, both exact, for |y| < 2^22: `t = y + 1.5 * 2^23` holds the
/// integer in its low mantissa bits (module documentation).
#[inline(always)]
pub fn round_nearest(y: f32) -> (i32, f32) {
    let t = y + ROUND_MAGIC;
    (t.to_bits() as i32 - ROUND_MAGIC.to_bits() as i32, t - ROUND_MAGIC)
}

/// exp(x) for x <= 0 in f32, deterministic and branch-free so loops
/// vectorise: `2^(x log2 e)` split into an integer power (exponent bits) and
/// 2^f for f in [-1/2, 1/2] by its degree-6 Taylor polynomial (truncation
/// ln2^7 / 7! / 2^7 = 1.2e-7 relative). Arguments below -87 return 0-ish
/// subnormal-free values (clamped at 2^-126).
#[inline(always)]
pub fn exp_neg_f32(x: f32) -> f32 {
    let y = (x * std::f32::consts::LOG2_E).max(-126.0);
    let (i_bits, yi) = round_nearest(y);
    let f = y - yi;
    const C: [f32; 7] = [1.0, std::f32::consts::LN_2, 0.240_226_5, 0.055_504_11, 0.009_618_129, 0.001_333_355_8, 0.000_154_035_3];
    let p = C[0] + f * (C[1] + f * (C[2] + f * (C[3] + f * (C[4] + f * (C[5] + f * C[6])))));
    let scale = f32::from_bits(((i_bits + 127) as u32) << 23);
    p * scale
}

/// Table steps per unit of the erf table (h = 1/1024).
const ERF_LUT_STEPS: usize = 1024;

/// Entries of the erf table: erf(k / 1024) for k = 0..=4097.
pub const ERF_LUT_LEN: usize = ERF_LUT_STEPS * 4 + 2;

/// erf on [0, 4] at steps of 1/1024, f32, for [`erf_lut`]; made once.
pub fn erf_table() -> &'static [f32; ERF_LUT_LEN] {
    static T: std::sync::OnceLock<[f32; ERF_LUT_LEN]> = std::sync::OnceLock::new();
    T.get_or_init(|| std::array::from_fn(|k| libm::erf(k as f64 / ERF_LUT_STEPS as f64) as f32))
}

/// The table cell of erf(x) and the interpolation weight in it: the cell
/// index is `|x| / h - 1/2` rounded to nearest ([`round_nearest`]: floor of
/// `|x| / h`, or one less at a cell boundary, where the weight is then 1:
/// the same value), clamped to the table, so there is no saturating
/// float-to-integer conversion and no bounds check in the inner loop.
#[inline(always)]
fn erf_cell(x: f32) -> (i32, f32) {
    let ax = (x.abs() * ERF_LUT_STEPS as f32).min((ERF_LUT_STEPS * 4) as f32);
    let k = round_nearest(ax - 0.5).0.max(0).min(ERF_LUT_LEN as i32 - 2);
    (k, ax - k as f32)
}

/// erf in f32 by linear interpolation in [`erf_table`] (module
/// documentation: error at most 1.2e-7 plus f32 rounding).
#[inline(always)]
pub fn erf_lut(table: &[f32; ERF_LUT_LEN], x: f32) -> f32 {
    let (k, f) = erf_cell(x);
    let k = (k as usize).min(ERF_LUT_LEN - 2);
    let v = table[k] + f * (table[k + 1] - table[k]);
    v.copysign(x)
}

/// [`erf_lut`] at N arguments (4 or 8: half or whole z-rows), staged so
/// the index and interpolation arithmetic vectorise (only the 2N table
/// reads are scalar); the same operations per lane, so the same values.
#[inline(always)]
pub fn erf_lut_lanes<const N: usize>(table: &[f32; ERF_LUT_LEN], x: &[f32; N]) -> [f32; N] {
    let (mut k, mut f) = ([0usize; N], [0.0f32; N]);
    for j in 0..N {
        let (kj, fj) = erf_cell(x[j]);
        k[j] = kj as usize;
        f[j] = fj;
    }
    let (mut a, mut b) = ([0.0f32; N], [0.0f32; N]);
    for j in 0..N {
        let kj = k[j].min(ERF_LUT_LEN - 2);
        (a[j], b[j]) = (table[kj], table[kj + 1]);
    }
    let mut v = [0.0f32; N];
    for j in 0..N {
        v[j] = (a[j] + f[j] * (b[j] - a[j])).copysign(x[j]);
    }
    v
}

/// `ceil` per component as integers, by truncation and a correction
/// (x86-64's baseline has no rounding instruction, so `f64::ceil` is a libm
/// call; the gather takes six per photon and leaf). Exact for |x| < 2^31;
/// NaN gives 0, as `as` does.
#[inline(always)]
pub fn ceil_i(v: DVec3) -> IVec3 {
    let c = |x: f64| {
        let i = x as i32;
        i + ((i as f64) < x) as i32
    };
    IVec3::new(c(v.x), c(v.y), c(v.z))
}

/// `floor` per component as integers (see [`ceil_i`]).
#[inline(always)]
pub fn floor_i(v: DVec3) -> IVec3 {
    let f = |x: f64| {
        let i = x as i32;
        i - ((i as f64) > x) as i32
    };
    IVec3::new(f(v.x), f(v.y), f(v.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn fast_exp_matches_std_exp() {
        // Relative error budget: polynomial 1.2e-7 + f32 rounding of the
        // product chain (~6 operations x 2^-24 = 3.6e-7) + the argument's
        // own rounding, |x| 2^-24 <= 1.1e-6 at x = -18 (c = 6).
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = -18.0f32 * i as f32 / 200_000.0;
            let got = exp_neg_f32(x) as f64;
            let want = (x as f64).exp();
            worst = worst.max((got / want - 1.0).abs());
        }
        assert!(worst < 1.5e-6, "worst relative error {worst}");
        assert_eq!(exp_neg_f32(0.0), 1.0);
        assert!(exp_neg_f32(-200.0) >= 0.0 && exp_neg_f32(-200.0) < 1e-37);
    }

    #[test]
    fn rounding_by_the_magic_constant_is_round_half_even() {
        // Every quarter on [-2^12, 2^12] (ties included) and random values
        // up to 2^22: the integer and the f32 are f32::round_ties_even's.
        let mut r = crate::rng::rng(&[5]);
        let quarters = (-(1 << 14)..=(1 << 14)).map(|k| k as f32 * 0.25);
        let random = (0..100_000).map(|_| r.random_range(-4_194_303.0f32..4_194_303.0));
        for y in quarters.chain(random) {
            let (i, f) = round_nearest(y);
            assert_eq!(f, y.round_ties_even(), "{y}");
            assert_eq!(i as f32, f, "{y}");
        }
    }

    #[test]
    fn integer_ceil_and_floor_match_libm() {
        let mut rng = crate::rng::rng(&[9]);
        for k in 0..100_000 {
            let x: f64 = match k % 3 {
                0 => rng.random_range(-1e6..1e6),
                1 => (rng.random_range(-100..100) as f64) * 0.5,
                _ => rng.random_range(-3.0..3.0),
            };
            let v = DVec3::new(x, -x, x * 0.25);
            assert_eq!(ceil_i(v), v.ceil().as_ivec3(), "{v}");
            assert_eq!(floor_i(v), v.floor().as_ivec3(), "{v}");
        }
    }

    #[test]
    fn erf_table_matches_libm() {
        // h^2 / 8 max|erf''| = 1.2e-7, f32 storage and interpolation 1.2e-7.
        let t = erf_table();
        for i in -100_000..=100_000 {
            let x = 6.0 * i as f64 / 100_000.0;
            let err = (erf_lut(t, x as f32) as f64 - libm::erf(x as f32 as f64)).abs();
            assert!(err < 2.5e-7, "erf({x}): error {err}");
        }
        // The lanes are the scalar lookup, bit for bit.
        let x: [f32; 8] = std::array::from_fn(|j| -4.5 + 1.3 * j as f32);
        assert_eq!(erf_lut_lanes(t, &x), x.map(|x| erf_lut(t, x)));
    }
}
