//! A field's stored values: 32-bit floats, or IEEE 754 binary16 bits when
//! every source the field is built from stores half floats (a VDB grid
//! written in half mode, as the bake writes `emission`).
//!
//! A half float read from a file is exactly an `f32` (11 significant bits,
//! exponents -24..15), so keeping its 16 bits loses nothing: every lookup
//! returns the `f32` the 32-bit store would, and renders are the same bytes.
//! It halves the medium's memory and the pages its build touches (328 MB
//! of 32-bit values on the default bake).
//!
//! The conversion is exact and cheap enough for the march's inner loop (a
//! shift and a multiplication by a power of two; no table, no branch): a
//! half's exponent and mantissa fields, shifted into an `f32`'s, are the
//! value times 2^-112 (normal and subnormal halves alike), so a
//! multiplication by 2^112 gives the value (van der Zijp 2008, "Fast half
//! float conversions", the "magic" multiplication; the tests' inverse
//! multiplies by 2^-112). The sign is carried apart. Infinities and NaN never reach a field (`check.rs` refuses them).

use crate::grid::leaf_source::{LeafError, LeafSource, LeafValues, Scratch};

/// 2^112: a half's fields shifted into an `f32`'s read as its value / 2^112.
const MAGIC: f32 = f32::from_bits((127 + 112) << 23);
/// 2^-112.
#[cfg(test)]
const INV_MAGIC: f32 = f32::from_bits((127 - 112) << 23);

/// The `f32` a finite half float's bits hold (exact).
#[inline(always)]
pub fn half_to_f32(h: u16) -> f32 {
    let h = h as u32;
    let v = f32::from_bits((h & 0x7fff) << 13) * MAGIC;
    f32::from_bits(v.to_bits() | (h & 0x8000) << 16)
}

/// The half float bits of `x`, which must be a finite half float's value
/// (an `f32` a half holds exactly: what [`half_to_f32`] returns); other
/// values are truncated, never rounded. The store copies a file's bits and
/// never converts this way: the tests' inverse of [`half_to_f32`].
#[cfg(test)]
pub fn f32_to_half(x: f32) -> u16 {
    let b = x.to_bits();
    let m = (f32::from_bits(b & 0x7fff_ffff) * INV_MAGIC).to_bits() >> 13;
    (m | (b >> 16 & 0x8000)) as u16
}

/// A field's values: channel `c` of value `i` is [`Values::get`]`(i)`.
/// Two stores are equal when they hold equal values, whatever their kind
/// (a medium from a file's half floats equals the one from its grids).
#[derive(Debug, Clone)]
pub enum Values {
    F32(Vec<f32>),
    /// Half floats' bits.
    Half(Vec<u16>),
}

impl Values {
    /// `n` zeros (fresh pages: what is never written costs no memory).
    pub fn zeros(n: usize, half: bool) -> Values {
        if half {
            Values::Half(vec![0; n])
        } else {
            Values::F32(vec![0.0; n])
        }
    }

    /// Bytes a value takes in a store of this kind.
    pub fn value_bytes(half: bool) -> usize {
        if half {
            2
        } else {
            4
        }
    }

    #[inline(always)]
    pub fn get(&self, i: usize) -> f32 {
        match self {
            Values::F32(v) => v[i],
            Values::Half(v) => half_to_f32(v[i]),
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Values::F32(v) => v.len(),
            Values::Half(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn is_half(&self) -> bool {
        matches!(self, Values::Half(_))
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.len() * Values::value_bytes(self.is_half())
    }

    /// Every value, in order.
    pub fn iter(&self) -> impl Iterator<Item = f32> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    /// Hints the cache to load value `i` (nothing if out of range).
    #[inline(always)]
    pub fn prefetch(&self, i: usize) {
        match self {
            Values::F32(v) => prefetch_at(v, i),
            Values::Half(v) => prefetch_at(v, i),
        }
    }
}

impl PartialEq for Values {
    fn eq(&self, other: &Values) -> bool {
        match (self, other) {
            (Values::F32(a), Values::F32(b)) => a == b,
            (Values::Half(a), Values::Half(b)) => a == b,
            _ => self.len() == other.len() && self.iter().eq(other.iter()),
        }
    }
}

/// Hints the CPU to load the cache line holding `values[i]` (a no-op off
/// x86-64 and for an index past the end). It changes no result.
#[inline(always)]
fn prefetch_at<T>(values: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if i < values.len() {
        // SAFETY: a prefetch never faults and reads nothing into the program;
        // the pointer is inside `values` anyway.
        #[allow(unused_unsafe)]
        unsafe {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            _mm_prefetch::<_MM_HINT_T0>(values.as_ptr().add(i) as *const i8);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (values, i);
}

/// A value as a source gives it and a block of the store holds it: an
/// `f32`, or a half float's bits. The build reads, checks and copies
/// values of one kind, without converting them.
pub trait Stored: Copy + Send + Sync + std::fmt::Debug {
    /// The leaf's values from `src` in this kind.
    fn leaf_values<'s>(src: &'s dyn LeafSource, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s, Self>, LeafError>;
    fn to_f32(self) -> f32;
    /// All bits zero (+0.0).
    fn is_zero_bits(self) -> bool;
    /// Zero of either sign.
    fn is_zero(self) -> bool;
    /// Finite and >= 0 (-0.0 included): what the renderer accepts.
    fn is_valid(self) -> bool;
    /// The bits without the sign: for valid values, ordered as the values.
    fn magnitude(self) -> u32;
    /// The value of magnitude bits [`Stored::magnitude`] gave.
    fn from_magnitude(m: u32) -> f32;
}

impl Stored for f32 {
    fn leaf_values<'s>(src: &'s dyn LeafSource, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s, f32>, LeafError> {
        src.values(i, scratch)
    }
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline(always)]
    fn is_zero_bits(self) -> bool {
        self.to_bits() == 0
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self == 0.0
    }
    #[inline(always)]
    fn is_valid(self) -> bool {
        let b = self.to_bits();
        b < 0x7f80_0000 || b == 0x8000_0000
    }
    #[inline(always)]
    fn magnitude(self) -> u32 {
        self.to_bits() & 0x7fff_ffff
    }
    fn from_magnitude(m: u32) -> f32 {
        f32::from_bits(m)
    }
}

impl Stored for u16 {
    fn leaf_values<'s>(src: &'s dyn LeafSource, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s, u16>, LeafError> {
        src.values_half(i, scratch)
    }
    #[inline(always)]
    fn to_f32(self) -> f32 {
        half_to_f32(self)
    }
    #[inline(always)]
    fn is_zero_bits(self) -> bool {
        self == 0
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self & 0x7fff == 0
    }
    #[inline(always)]
    fn is_valid(self) -> bool {
        self < 0x7c00 || self == 0x8000
    }
    #[inline(always)]
    fn magnitude(self) -> u32 {
        (self & 0x7fff) as u32
    }
    fn from_magnitude(m: u32) -> f32 {
        half_to_f32(m as u16)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use half::f16;

    /// Every finite half, against the `half` crate: the value is exact, and
    /// back to bits is the same bits (both zeros' signs included).
    #[test]
    fn every_finite_half_converts_exactly_both_ways() {
        let mut n = 0;
        for h in 0..=u16::MAX {
            let want = f16::from_bits(h);
            if !want.is_finite() {
                continue;
            }
            let x = half_to_f32(h);
            assert_eq!(x.to_bits(), want.to_f32().to_bits(), "{h:#06x}");
            assert_eq!(f32_to_half(x), h, "{h:#06x} -> {x:e}");
            n += 1;
        }
        assert_eq!(n, 63488, "every finite half: 2 * 31 exponents * 1024 mantissas");
    }

    /// The checks on a half's bits agree with its value's, for every half.
    #[test]
    fn the_checks_on_half_bits_are_the_checks_on_their_values() {
        for h in 0..=u16::MAX {
            let x = f16::from_bits(h).to_f32();
            assert_eq!(h.is_valid(), x.is_valid(), "{h:#06x}");
            assert_eq!(h.is_zero(), x.is_zero(), "{h:#06x}");
            if h.is_valid() {
                assert_eq!(u16::from_magnitude(h.magnitude()), f32::from_magnitude(x.magnitude()), "{h:#06x}");
            }
        }
    }

    /// A half store reads back what a 32-bit store of the same (half) values does.
    #[test]
    fn the_two_stores_read_the_same_values() {
        let xs: Vec<f32> = [0.0, 6.0e-8, 6.1e-5, 0.5, 1.0, 2.71, 65504.0].iter().map(|&x| f16::from_f32(x).to_f32()).collect();
        let a = Values::F32(xs.clone());
        let b = Values::Half(xs.iter().map(|&x| f32_to_half(x)).collect());
        assert!(a.iter().eq(b.iter()) && a == b);
        assert!(a != Values::Half(vec![0; 7]));
        assert_eq!((a.bytes(), b.bytes()), (28, 14));
    }
}
