//! Mantissa rounding: keeping only the significand bits a value can
//! vouch for, so that the zeros left behind compress.
//!
//! A binary floating-point number is `x = (1 + m / 2^p) 2^e` with a `p`-bit
//! mantissa `m` (p = 10 for a half float, 23 for a float). Rounding it to
//! `k < p` bits keeps the nearest number of the form `(1 + j / 2^k) 2^e`:
//! add half of the last kept place to the bit pattern and clear the
//! `p - k` bits below it, ties to the even `j` (IEEE 754's rounding,
//! applied at bit `k`). A carry out of the mantissa steps into the next
//! binade, which is the correct result because the encoding is monotone in
//! its bit pattern. The relative error of a normal number is then at most
//! `2^-(k+1)`, and, for values that are not on the grid of kept values
//! already, it is spread evenly on both sides (no bias on average).
//! Subnormals are rounded at the same bit, so their absolute step is that of
//! the smallest normal binade. A value that would round up to infinity is
//! cut (rounded toward zero) instead, so the result is always finite when
//! the input is.
//!
//! This is the "bit rounding" of Klöwer et al. (2021), "Compressing
//! atmospheric data into its real information content", Nature
//! Computational Science 1, 713-724, who round to the bits that carry
//! information and leave the rest to a lossless coder, and it refines
//! Zender (2016), "Bit Grooming", Geoscientific Model Development 9,
//! 3199-3211, whose alternate shaving and setting is replaced by
//! round-to-nearest. Why it pays here: a baked field's low mantissa bits are
//! photon noise (a voxel's emission is a sum of a few kernel deposits), so a
//! coder sees them as random; cleared, they cost deflate's Huffman stage
//! almost nothing (RFC 1951). A renderer sums many voxels per pixel, so the
//! per-voxel errors, independent and unbiased, average down along the ray:
//! `aurora bench`'s storage study measures the picture against the bits
//! kept.

/// Significand bits of a half float (IEEE binary16).
pub const HALF_MANTISSA_BITS: u32 = 10;
/// Significand bits of a float (IEEE binary32).
pub const FLOAT_MANTISSA_BITS: u32 = 23;

/// The binary16 bit pattern `bits` rounded to `keep` mantissa bits (module
/// docs); `keep >= 10` returns it unchanged. NaN and infinity are returned
/// unchanged (the writer refuses them before).
#[inline]
pub fn round_half_bits(bits: u16, keep: u32) -> u16 {
    round_bits(bits as u32, keep, HALF_MANTISSA_BITS, 0x7c00) as u16
}

/// The binary32 bit pattern `bits` rounded to `keep` mantissa bits (module
/// docs); `keep >= 23` returns it unchanged.
#[inline]
pub fn round_float_bits(bits: u32, keep: u32) -> u32 {
    round_bits(bits, keep, FLOAT_MANTISSA_BITS, 0x7f80_0000)
}

/// `x` rounded to `keep` mantissa bits, as [`round_float_bits`].
#[inline]
pub fn round_float(x: f32, keep: u32) -> f32 {
    f32::from_bits(round_float_bits(x.to_bits(), keep))
}

/// Rounds the mantissa of a sign-magnitude pattern with `p` mantissa bits
/// and exponent field `exp_mask` to `keep` bits, ties to even, never to
/// infinity.
#[inline(always)]
fn round_bits(bits: u32, keep: u32, p: u32, exp_mask: u32) -> u32 {
    if keep >= p || bits & exp_mask == exp_mask {
        return bits;
    }
    let drop = p - keep;
    let cleared = !((1u32 << drop) - 1);
    let lsb = (bits >> drop) & 1;
    // Half of the last kept place, less one unless the kept part is odd:
    // ties go to even.
    let rounded = (bits + ((1u32 << (drop - 1)) - 1) + lsb) & cleared;
    if rounded & exp_mask == exp_mask {
        bits & cleared
    } else {
        rounded
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::fmath;
    use half::f16;

    /// The oracle: the nearest number with `keep` mantissa bits, found in
    /// f64 from the definition (the kept values of `x`'s binade and the
    /// next one up), ties to the even last kept bit.
    fn nearest(x: f64, keep: u32, min_normal_exp: i32) -> f64 {
        if x == 0.0 {
            return x;
        }
        let e = (fmath::log2(x.abs()).floor() as i32).max(min_normal_exp);
        let step = fmath::powi(2f64, e - keep as i32);
        let j = x / step;
        let lo = j.floor();
        let frac = j - lo;
        let pick = if frac > 0.5 || (frac == 0.5 && lo % 2.0 != 0.0) { lo + 1.0 } else { lo };
        pick * step
    }

    #[test]
    fn every_half_matches_the_oracle_for_every_kept_width() {
        for keep in 1..HALF_MANTISSA_BITS {
            for b in 0u16..=u16::MAX {
                let x = f16::from_bits(b);
                if !x.is_finite() {
                    assert_eq!(round_half_bits(b, keep), b);
                    continue;
                }
                let got = f16::from_bits(round_half_bits(b, keep));
                assert!(got.is_finite(), "{x} at {keep} bits became {got}");
                let want = nearest(x.to_f64(), keep, -14);
                if want.abs() > f16::MAX.to_f64() {
                    // Rounds past the largest half: cut instead.
                    assert_eq!(got.to_bits(), b & !((1 << (HALF_MANTISSA_BITS - keep)) - 1), "{x} at {keep}");
                } else {
                    assert_eq!(got.to_f64(), want, "{x} (bits {b:#06x}) at {keep} bits");
                }
            }
        }
    }

    #[test]
    fn the_scene_key_ends_at_a_full_float() {
        assert_eq!(crate::scene::grid::MAX_MANTISSA_BITS, FLOAT_MANTISSA_BITS);
    }

    #[test]
    fn keeping_every_bit_changes_nothing() {
        for b in [0u16, 1, 0x3c00, 0x3c01, 0x7bff, 0x8001, 0xfbff] {
            assert_eq!(round_half_bits(b, HALF_MANTISSA_BITS), b);
        }
        for x in [0.0f32, 1.0, 1.0 + f32::EPSILON, f32::MAX, -3.7e-30] {
            assert_eq!(round_float(x, FLOAT_MANTISSA_BITS), x);
        }
    }

    #[test]
    fn floats_match_the_oracle_and_the_error_bound() {
        // A deterministic spread over many binades, both signs, subnormals.
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..200_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let x = f32::from_bits((s >> 32) as u32);
            if !x.is_finite() {
                continue;
            }
            for keep in [1, 3, 5, 8, 12, 22] {
                let got = round_float(x, keep);
                assert!(got.is_finite());
                let want = nearest(x as f64, keep, -126);
                if want.abs() <= f32::MAX as f64 {
                    assert_eq!(got as f64, want, "{x:e} at {keep} bits");
                }
                if x.is_normal() && got.is_normal() {
                    let rel = ((got as f64 - x as f64) / x as f64).abs();
                    assert!(rel <= fmath::powi(2f64, -(keep as i32 + 1)), "{x:e} at {keep}: {rel:e}");
                }
            }
        }
    }

    #[test]
    fn the_rounding_is_unbiased_over_a_smooth_spread() {
        // Values spread evenly over a binade: the mean of the rounding
        // errors is zero to within the sampling noise.
        let keep = 5;
        let n = 100_000;
        let mean: f64 = (0..n)
            .map(|i| {
                let x = 1.0 + (i as f64 + 0.37) / n as f64;
                let x = x as f32;
                (round_float(x, keep) - x) as f64
            })
            .sum::<f64>()
            / n as f64;
        // Step 2^-5. Cutting the bits (rounding toward zero) would give a
        // mean of -step/2; rounding to nearest gives 0 up to the spread's
        // discreteness and f32's own rounding (a few 1e-6 here).
        let step = fmath::powi(2f64, -(keep as i32));
        assert!(mean.abs() < 1e-3 * step, "{mean:e}");
    }
}
