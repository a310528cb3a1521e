//! Random streams and seeded noise for the bake.
//!
//! Every random stream is derived from the scene seed and a few indices
//! (curtain seed, beam index, purpose tag) through a splitmix64 hash, so a
//! stream never depends on which thread runs it or in which order: the bake is
//! byte-identical whatever the thread count.
//!
//! splitmix64 is Steele, Lea & Flood, "Fast splittable pseudorandom number
//! generators", OOPSLA 2014 (the finaliser also used by `java.util.SplittableRandom`).

use noise::{NoiseFn, Perlin};
use rand_pcg::Pcg64Mcg;

/// Purpose tags: one per kind of stream, so streams of different stages never
/// coincide even for equal indices.
pub mod tag {
    pub const FOOTPRINT_VELOCITY: u64 = 0x1001;
    pub const FOOTPRINT_BEND: u64 = 0x1002;
    pub const FOOTPRINT_FILAMENTS: u64 = 0x1003;
    pub const BEAM: u64 = 0x2001;
    pub const BEAM_TOP_NOISE: u64 = 0x2002;
    pub const COLOUR_NOISE: u64 = 0x2003;
    pub const BEAM_STARTS: u64 = 0x2004;
    pub const RADIUS_NOISE: u64 = 0x3001;
    pub const PULSATION: u64 = 0x4001;
}

/// The splitmix64 finaliser of `x + golden gamma`: a bijection on u64 with
/// good avalanche, used to hash seeds, never as a generator itself.
#[inline]
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Hashes a sequence of integers (scene seed, curtain seed, index, tag...)
/// into one 64-bit seed. Order matters: (1, 2) and (2, 1) differ.
pub fn stream_seed(parts: &[u64]) -> u64 {
    let mut h: u64 = 0x243F_6A88_85A3_08D3; // pi's fraction: any fixed start works
    for &p in parts {
        h = splitmix64(h ^ p);
    }
    h
}

/// A PCG generator (128-bit MCG, XSL-RR output) seeded from `parts`.
pub fn rng(parts: &[u64]) -> Pcg64Mcg {
    let a = stream_seed(parts);
    let b = splitmix64(a ^ 0x5851_F42D_4C95_7F2D);
    // An MCG needs an odd state; the low bit is forced.
    Pcg64Mcg::new(((a as u128) << 64) | (b as u128) | 1)
}

/// Perlin noise whose permutation table is seeded from `parts`.
pub fn perlin(parts: &[u64]) -> Perlin {
    Perlin::new(stream_seed(parts) as u32)
}

/// 1D Perlin noise in [-1, 1]: a line through the 2D noise at a fixed,
/// non-integer y. (The crate's own 1D Perlin truncates towards zero instead of
/// flooring, which breaks continuity at negative coordinates.)
#[inline]
pub fn noise1(p: &Perlin, x: f64) -> f64 {
    noise2(p, x, NOISE1_Y)
}

/// The y at which [`noise1`] reads the 2D noise: a motion that moves along
/// y from here starts from the 1D noise.
pub const NOISE1_Y: f64 = 0.371_9;

/// 2D Perlin noise in [-1, 1].
///
/// The noise crate's Perlin hashes lattice corners by `corner & 0xff`, so it
/// is periodic with period 256 in each coordinate; its `floor` to `isize`
/// panics for coordinates beyond `isize` (a huge `voxel_size`, a tiny
/// `bend_wavelength` or `mountain_scale`) and for NaN. Coordinates of
/// magnitude 2^31 or more are moved by a multiple of 256 into [0, 256):
/// `x - 256 floor(x / 256)` is exact there (the result is a multiple of
/// ulp(x) and smaller than |x|), and so is the crate's own `x - floor(x)`, so
/// the value is the one the crate would give without the overflow; smaller
/// coordinates pass unchanged (bit for bit the crate's noise); a non-finite
/// coordinate gives 0.
#[inline]
pub fn noise2(p: &Perlin, x: f64, y: f64) -> f64 {
    p.get([wrap_period(x), wrap_period(y)])
}

/// The Perlin lattice period of the noise crate's permutation table.
const PERLIN_PERIOD: f64 = 256.0;

/// Below this magnitude coordinates pass unchanged.
const WRAP_FROM: f64 = 2_147_483_648.0;

#[inline]
fn wrap_period(x: f64) -> f64 {
    if !x.is_finite() {
        0.0
    } else if x.abs() < WRAP_FROM {
        x
    } else {
        x - PERLIN_PERIOD * (x / PERLIN_PERIOD).floor()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::fmath;
    use rand::Rng;

    #[test]
    fn noise_is_periodic_exactly_and_total_on_any_input() {
        let p = perlin(&[3]);
        for i in 0..1000 {
            let (x, y) = (i as f64 * 0.731 - 300.0, i as f64 * -0.277 + 11.0);
            // Unwrapped crate value where it does not panic.
            assert_eq!(noise2(&p, x, y), p.get([x, y]), "at ({x}, {y})");
            // Far coordinates equal their wrapped selves (the period is exact).
            let far = fmath::powi(2f64, 32); // a multiple of 256 whose ulp (2^-20) keeps x + far exact
            let (xf, yf) = ((x * 64.0).round() / 64.0, (y * 64.0).round() / 64.0);
            assert_eq!(noise2(&p, xf + far, yf - far), noise2(&p, xf, yf), "at ({xf}, {yf})");
        }
        for x in [1e20, -1e300, f64::MAX, f64::MIN_POSITIVE, -1e-300, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let v = noise2(&p, x, 0.5);
            assert!(v.is_finite() && (-1.0..=1.0).contains(&v), "{x} -> {v}");
            assert!(noise1(&p, x).is_finite());
        }
    }

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let mut a = rng(&[1, 2, 3]);
        let mut b = rng(&[1, 2, 3]);
        let mut c = rng(&[1, 3, 2]);
        let xa: Vec<u64> = (0..8).map(|_| a.random()).collect();
        let xb: Vec<u64> = (0..8).map(|_| b.random()).collect();
        let xc: Vec<u64> = (0..8).map(|_| c.random()).collect();
        assert_eq!(xa, xb);
        assert_ne!(xa, xc);
    }

    #[test]
    fn noise1_is_continuous_across_zero_and_bounded() {
        let p = perlin(&[7]);
        // Continuity: a step of 1e-6 changes the value by at most the
        // gradient bound (|grad| <= a few units per lattice cell) times 1e-6.
        for &x in &[-1.0, -0.5, 0.0, 0.5, 1.0] {
            let d = (noise1(&p, x + 1e-6) - noise1(&p, x - 1e-6)).abs();
            assert!(d < 1e-4, "jump {d} at {x}");
        }
        for i in 0..10_000 {
            let v = noise1(&p, i as f64 * 0.0137 - 50.0);
            assert!((-1.0..=1.0).contains(&v));
        }
    }
}
