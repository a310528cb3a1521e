//! The f32 maths of the gather's inner loops: `exp(x)` for `x <= 0`, `erf`
//! by a rational function, and integer `ceil` / `floor`. Each is deterministic (the same
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
//! **erf.** [`erf_rational`]: `erf(x) ~ x P(x^2) / Q(x^2)` on |x| <= 4
//! (1 beyond: erfc(4) = 1.5e-8), P of degree 6 and Q of degree 5 in x^2,
//! odd like erf. The coefficients are a near-minimax fit on [0, 4]
//! (weighted linear least squares on 4,000 Chebyshev nodes, reweighted
//! toward equal ripple; `tools/reference/fit_erf.py` refits them): 1.5e-9 in f64,
//! 4e-7 after Horner's rule in f32 (tested against libm). The segment
//! kernel takes two per voxel and photon, as their difference
//! ([`erf_diff`]) over one common denominator. Straight-line arithmetic
//! with one division vectorises whole; a table lookup (linear
//! interpolation at steps of 1/1024) needed 16 scalar reads per 8-lane
//! row and made the default bake's gather 1.13x slower, Abramowitz &
//! Stegun 7.1.26 an exponential and a division per erf.
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

/// The coefficients of [`erf_rational`]: `erf(x) ~ x P(x^2) / Q(x^2)`,
/// P of degree 6 and Q of degree 5 in x^2 (Q's constant term 1). The fit's
/// P(0) rounds to the f32 of 2 / sqrt(pi), erf's slope at 0.
const ERF_P: [f32; 7] =
    [std::f32::consts::FRAC_2_SQRT_PI, 0.184_710_37, 0.054_332_614, 0.003_839_532, 0.000_382_692_93, 4.780_557e-6, -1.366_687_5e-8];
const ERF_Q: [f32; 6] = [1.0, 0.497_028_86, 0.113_826_334, 0.015_453_524, 0.001_309_580_5, 6.400_944e-5];

/// erf in f32 by a rational function of x^2 on |x| <= 4 (1 beyond, to
/// erfc(4) = 1.5e-8): `x P(x^2) / Q(x^2)`, straight-line arithmetic so a
/// loop over lanes vectorises whole (no table reads).
#[inline(always)]
pub fn erf_rational(x: f32) -> f32 {
    let (n, q) = erf_fraction(x);
    n / q
}

/// The numerator `x P(x^2)` and denominator `Q(x^2)` of [`erf_rational`],
/// x clamped to [-4, 4]. Both are odd or even like erf's parts, so no sign
/// handling is needed.
#[inline(always)]
fn erf_fraction(x: f32) -> (f32, f32) {
    let x = x.clamp(-4.0, 4.0);
    let t = x * x;
    (x * erf_p(t), erf_q(t))
}

/// [`erf_rational`]'s numerator polynomial P(t), Horner's rule.
#[inline(always)]
fn erf_p(t: f32) -> f32 {
    let c = ERF_P;
    c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * (c[5] + t * c[6])))))
}

/// [`erf_rational`]'s denominator polynomial Q(t), Horner's rule.
#[inline(always)]
fn erf_q(t: f32) -> f32 {
    let c = ERF_Q;
    c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))))
}

/// `erf(a) - erf(b)`, the segment kernel's along factor, by
/// [`erf_rational`]'s rational function over one common denominator:
/// `(a P(a^2) Q(b^2) - b P(b^2) Q(a^2)) / (Q(a^2) Q(b^2))`, one division
/// instead of two ([`erf_fraction`]'s parts). Q is below 260 there, a product of
/// two below 6.8e4: no overflow. Both numerator terms are within a few
/// roundings of `erf Q(a^2) Q(b^2)`, so the difference errs by a few
/// 2^-24 of the larger |erf|, as two separate quotients would. Meant for
/// `a >= b` (the segment's start side minus its end side): where both lie
/// near the clamp that rounding could make the difference a few 1e-7 below
/// zero, so it is floored at 0 (the kernel is never negative).
#[inline(always)]
pub fn erf_diff(a: f32, b: f32) -> f32 {
    let ((na, qa), (nb, qb)) = (erf_fraction(a), erf_fraction(b));
    ((na * qb - nb * qa) / (qa * qb)).max(0.0)
}

/// [`erf_diff`] at N lanes (4 or 8: half or whole z-rows): straight-line
/// arithmetic, so the loop vectorises whole; the same operations per lane,
/// so the same values.
#[inline(always)]
pub fn erf_diff_lanes<const N: usize>(a: &[f32; N], b: &[f32; N]) -> [f32; N] {
    let mut v = [0.0f32; N];
    for j in 0..N {
        v[j] = erf_diff(a[j], b[j]);
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
    use crate::util::fmath;
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
            let want = fmath::exp(x as f64);
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
        let mut r = crate::util::rng::rng(&[5]);
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
        let mut rng = crate::util::rng::rng(&[9]);
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
    fn rational_erf_matches_libm() {
        // The fit's f64 error is 1.5e-9; Horner's rule in f32 (13 roundings
        // of values below 1.2 after the quotient's scaling) adds up to about
        // 4e-7: 6e-7 leaves room.
        let mut worst = 0.0f64;
        for i in -200_000..=200_000 {
            let x = 6.0 * i as f64 / 200_000.0;
            let want = libm::erf(x as f32 as f64);
            worst = worst.max((erf_rational(x as f32) as f64 - want).abs());
        }
        assert!(worst < 6e-7, "worst error {worst}");
    }

    #[test]
    fn erf_difference_matches_libm_and_keeps_its_sign() {
        // The along factor's arguments: a = s / (sqrt2 r), b = a - lambda /
        // sqrt2, lambda >= 0.004. The common denominator's error is that of
        // two separate quotients: a few 2^-24 of the larger |erf|.
        let mut r = crate::util::rng::rng(&[11]);
        let mut worst = 0.0f64;
        for k in 0..400_000 {
            let a: f32 = r.random_range(-6.0..6.0);
            let gap: f32 = if k % 2 == 0 { r.random_range(0.0028..0.05) } else { r.random_range(0.0028..12.0) };
            let b = a - gap;
            let want = libm::erf(a as f64) - libm::erf(b as f64);
            let got = erf_diff(a, b) as f64;
            worst = worst.max((got - want).abs());
            assert!(got >= 0.0, "erf({a}) - erf({b}) = {got} < 0");
        }
        assert!(worst < 1e-6, "worst error {worst}");
        // The lanes are the scalar function, bit for bit; -0 and the clamp.
        let a: [f32; 8] = std::array::from_fn(|j| -4.5 + 1.3 * j as f32);
        let b = a.map(|x| x - 0.7);
        let lanes = erf_diff_lanes(&a, &b);
        for j in 0..8 {
            assert_eq!(lanes[j].to_bits(), erf_diff(a[j], b[j]).to_bits());
        }
        assert_eq!(erf_diff(9.0, 5.0), 0.0);
        assert_eq!(erf_rational(7.5), erf_rational(4.0));
        assert_eq!(erf_rational(-0.3), -erf_rational(0.3));
    }
}
