//! The compressed-values record: how OpenVDB stores every value array (leaf
//! buffers and internal-node tile values), and its writer.
//!
//! Writer: OpenVDB `io::writeCompressedValues` with `io::MaskCompress`
//! choosing the metadata byte; the reader, `io::readCompressedValues`
//! (`openvdb/io/Compression.h`), is [`super::decode`]. Layout (file version >= 222):
//!
//! ```text
//! i8     meta                      always present
//! ValueT inactive0                 if meta in {2, 4, 5}   (full f32, rounded to half first in half mode)
//! ValueT inactive1                 if meta == 5
//! N/8    selection mask            if meta in {3, 4, 5}
//! data   count values              count = popcount(value mask) if ACTIVE_MASK and meta != 6, else N
//! ```
//!
//! `data` is `f32` (or IEEE binary16 in half mode) per component, each
//! optionally rounded to fewer mantissa bits first ([`super::mantissa`]:
//! the format is unchanged, the cleared bits only compress better); with
//! ZIP it is `i64 L` then L bytes of a zlib stream (`compress2`, level 6, or
//! with [`Deflate::Fast`] libdeflate's level 1, as valid a zlib stream for
//! every reader) if that is shorter than the raw bytes, else `-rawBytes` and
//! the raw bytes; in half mode
//! a count of 0 writes nothing at all. With BLOSC (`io::bloscToStream`) it is
//! `i64 L` then a Blosc1 frame of L bytes: LZ4 at clevel 9, byte shuffle,
//! typesize 4 (`sizeof(float)` whatever the value type, half included), one
//! block covering the whole array, one thread. Blosc never refuses: data it
//! cannot shrink are stored inside the frame (16 more bytes than raw), so the
//! `-rawBytes` form is only a fallback for an internal Blosc error, as in
//! OpenVDB. Zero values (non-half) give a 16-byte header-only frame.

use super::layout::{self, meta, COMPRESS_ACTIVE_MASK, COMPRESS_BLOSC, COMPRESS_ZIP};
use super::mantissa;
use crate::grid::VoxelValue;
use flate2::{Compress, Compression, FlushCompress, Status};
use half::f16;

/// zlib level of OpenVDB's `ZIP_COMPRESSION_LEVEL` (`Z_DEFAULT_COMPRESSION` = 6).
pub const ZIP_LEVEL: u32 = 6;

/// libdeflate level of [`Deflate::Fast`]: its fastest. On a baked field with
/// rounded mantissas its streams are within 0.5 % of level 6's size (the
/// cleared bits are Huffman coding's gain, not long matches').
pub const FAST_ZIP_LEVEL: i32 = 1;

/// Which deflate writes ZIP records. Both are zlib streams (RFC 1950/1951)
/// that OpenVDB's `io::unzipFromStream` (zlib `uncompress`) reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Deflate {
    /// zlib's `compress2` at OpenVDB's level: the bytes OpenVDB writes.
    #[default]
    OpenVdb,
    /// libdeflate at [`FAST_ZIP_LEVEL`]: on the default bake three to four
    /// times faster than zlib at level 6, for a stream 0.3 % larger (and
    /// twice as fast as zlib at level 1, for a smaller one).
    Fast,
}

/// How one grid's values are stored: half or full floats, how many mantissa
/// bits are kept ([`super::mantissa`]; the format's own width keeps all) and
/// which deflate writes ZIP records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Storage {
    pub half: bool,
    pub mantissa_bits: u32,
    pub deflate: Deflate,
}

impl Storage {
    /// Every bit of the format, OpenVDB's zlib: what OpenVDB writes.
    pub fn exact(half: bool) -> Storage {
        Storage { half, mantissa_bits: mantissa::FLOAT_MANTISSA_BITS, deflate: Deflate::OpenVdb }
    }
}

/// `x` rounded to half precision and back (OpenVDB `io::truncateRealToHalf`,
/// round to nearest even).
#[inline]
pub fn round_half(x: f32) -> f32 {
    f16::from_f32(x).to_f32()
}

/// Componentwise [`round_half`].
pub fn round_half_value<T: VoxelValue>(v: T) -> T {
    let c = v.components();
    T::from_components(&[round_half(c[0]), round_half(c[1]), round_half(c[2])])
}

/// Componentwise negation (OpenVDB `math::negative`).
pub(super) fn negative<T: VoxelValue>(v: T) -> T {
    let c = v.components();
    T::from_components(&[-c[0], -c[1], -c[2]])
}

/// OpenVDB `math::isExactlyEqual`: `==` per component, so -0 equals +0.
#[inline]
fn eq<T: VoxelValue>(a: T, b: T) -> bool {
    a == b
}

/// OpenVDB `io::MaskCompress`: scans the inactive slots that are not child
/// pointers, in index order, for up to three distinct values and chooses the
/// metadata byte. Returns `(meta, [inactive0, inactive1])`.
pub fn mask_compress<T: VoxelValue>(values: &[T], value_mask: &[u64], child_mask: Option<&[u64]>, background: T) -> (u8, [T; 2]) {
    let mut inactive = [background, background];
    let mut unique = 0usize;
    'scan: for (w, &word) in value_mask.iter().enumerate() {
        // Inactive slots that are not child pointers, in index order.
        let mut bits = !word & !child_mask.map_or(0, |c| c[w]);
        while bits != 0 {
            if unique >= 3 {
                break 'scan;
            }
            let v = values[w * 64 + bits.trailing_zeros() as usize];
            bits &= bits - 1;
            let seen = (unique > 0 && eq(v, inactive[0])) || (unique > 1 && eq(v, inactive[1]));
            if !seen {
                if unique < 2 {
                    inactive[unique] = v;
                }
                unique += 1;
            }
        }
    }
    let minus_bg = negative(background);
    let m = match unique {
        0 => meta::NO_MASK_OR_INACTIVE_VALS,
        1 if eq(inactive[0], background) => meta::NO_MASK_OR_INACTIVE_VALS,
        1 if eq(inactive[0], minus_bg) => meta::NO_MASK_AND_MINUS_BG,
        1 => meta::NO_MASK_AND_ONE_INACTIVE_VAL,
        2 => {
            if !eq(inactive[0], background) && !eq(inactive[1], background) {
                meta::MASK_AND_TWO_INACTIVE_VALS
            } else if eq(inactive[1], background) {
                if eq(inactive[0], minus_bg) {
                    meta::MASK_AND_NO_INACTIVE_VALS
                } else {
                    meta::MASK_AND_ONE_INACTIVE_VAL
                }
            } else {
                // inactive[0] is the background: swap so inactive0 is the other value.
                inactive.swap(0, 1);
                if eq(inactive[0], minus_bg) {
                    meta::MASK_AND_NO_INACTIVE_VALS
                } else {
                    meta::MASK_AND_ONE_INACTIVE_VAL
                }
            }
        }
        _ => meta::NO_MASK_AND_ALL_VALS,
    };
    (m, inactive)
}

/// Writes compressed-values records with one grid's settings. Holds a reusable
/// zlib stream: `deflateReset` gives the same bytes as the fresh
/// `deflateInit` inside `compress2`, without its allocation per array (or
/// a reusable libdeflate compressor, [`Deflate::Fast`]).
pub struct Encoder {
    flags: u32,
    half: bool,
    keep: u32,
    zlib: Option<Zip>,
    blosc: bool,
    raw: Vec<u8>,
    zbuf: Vec<u8>,
    selection: Vec<u64>,
    halves: HalfScratch,
}

impl Encoder {
    /// `flags`: ZIP or BLOSC (BLOSC wins if both are set, as in OpenVDB's
    /// `writeData`), and/or ACTIVE_MASK.
    pub fn new(flags: u32, storage: Storage) -> Self {
        let blosc = flags & COMPRESS_BLOSC != 0;
        let zlib = (!blosc && flags & COMPRESS_ZIP != 0).then(|| match storage.deflate {
            Deflate::OpenVdb => Zip::Zlib(Compress::new(Compression::new(ZIP_LEVEL), true)),
            Deflate::Fast => Zip::Fast(Box::new(libdeflater::Compressor::new(
                libdeflater::CompressionLvl::new(FAST_ZIP_LEVEL).expect("a libdeflate level in 0..=12"),
            ))),
        });
        let keep = storage.mantissa_bits;
        Self {
            flags,
            half: storage.half,
            keep,
            zlib,
            blosc,
            raw: Vec::new(),
            zbuf: Vec::new(),
            selection: Vec::new(),
            halves: HalfScratch::default(),
        }
    }

    /// Appends the record of `values` (all N slots of a node) to `out`.
    /// `child_mask` marks internal-node slots holding children (skipped by the
    /// inactive-value scan). In half mode the caller has checked that every
    /// value is within half range.
    pub fn write_values<T: VoxelValue>(
        &mut self,
        out: &mut Vec<u8>,
        values: &[T],
        value_mask: &[u64],
        child_mask: Option<&[u64]>,
        background: T,
    ) {
        let masked = self.flags & COMPRESS_ACTIVE_MASK != 0;
        let (m, inactive) =
            if masked { mask_compress(values, value_mask, child_mask, background) } else { (meta::NO_MASK_AND_ALL_VALS, [background; 2]) };
        out.push(m);
        if matches!(m, meta::NO_MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_TWO_INACTIVE_VALS) {
            let n_inactive = if m == meta::MASK_AND_TWO_INACTIVE_VALS { 2 } else { 1 };
            for &v in &inactive[..n_inactive] {
                let v = if self.half { round_half_value(v) } else { v };
                push_full(out, v);
            }
        }
        let all = m == meta::NO_MASK_AND_ALL_VALS;
        let count = if all { values.len() } else { layout::mask_count(value_mask) };
        if matches!(m, meta::MASK_AND_NO_INACTIVE_VALS | meta::MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_TWO_INACTIVE_VALS) {
            // Selection mask: bit set where an inactive slot holds inactive1.
            self.selection.clear();
            self.selection.resize(values.len() / 64, 0);
            for (n, &v) in values.iter().enumerate() {
                if !layout::mask_bit(value_mask, n) && eq(v, inactive[1]) {
                    layout::set_mask_bit(&mut self.selection, n);
                }
            }
            for w in &self.selection {
                out.extend_from_slice(&w.to_le_bytes());
            }
        }
        if self.half && count == 0 {
            // HalfWriter::write returns before writing anything, even a ZIP size.
            return;
        }
        let stored = Stored { values, mask: value_mask, all, count };
        if self.blosc {
            self.raw.clear();
            gather(&mut self.raw, stored, self.half, self.keep, &mut self.halves);
            blosc_to_stream(&self.raw, out);
            return;
        }
        match self.zlib.as_mut() {
            Some(z) => {
                self.raw.clear();
                gather(&mut self.raw, stored, self.half, self.keep, &mut self.halves);
                zip_to_stream(z, &mut self.zbuf, &self.raw, out);
            }
            None => gather(out, stored, self.half, self.keep, &mut self.halves),
        }
    }
}

/// Buffers of the half-float gather: the components as `f32`, then as
/// binary16 bit patterns.
#[derive(Default)]
struct HalfScratch {
    floats: Vec<f32>,
    bits: Vec<u16>,
}

/// The `count` values a record stores out of `values`: all of them
/// (`all`), or the active ones of `mask` in index order.
#[derive(Clone, Copy)]
struct Stored<'v, T> {
    values: &'v [T],
    mask: &'v [u64],
    all: bool,
    count: usize,
}

impl<T: VoxelValue> Stored<'_, T> {
    /// Calls `f` on the values to store, in index order.
    #[inline(always)]
    fn for_each(&self, mut f: impl FnMut(&T)) {
        if self.all {
            self.values.iter().take(self.count).for_each(f);
        } else {
            for (w, &word) in self.mask.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    f(&self.values[w * 64 + bits.trailing_zeros() as usize]);
                    bits &= bits - 1;
                }
            }
        }
    }
}

/// Appends the values to store as little-endian `f32` or binary16
/// components, each rounded to `keep` mantissa bits.
fn gather<T: VoxelValue>(dst: &mut Vec<u8>, stored: Stored<'_, T>, half: bool, keep: u32, scratch: &mut HalfScratch) {
    if half {
        gather_half(dst, stored, keep, scratch)
    } else {
        gather_float(dst, stored, keep)
    }
}

fn gather_float<T: VoxelValue>(dst: &mut Vec<u8>, stored: Stored<'_, T>, keep: u32) {
    let stride = T::COMPONENTS * 4;
    let start = dst.len();
    dst.resize(start + stored.count * stride, 0);
    let mut slots = dst[start..].chunks_exact_mut(stride);
    stored.for_each(|v| {
        if let Some(slot) = slots.next() {
            let c = v.components();
            for k in 0..T::COMPONENTS {
                slot[4 * k..4 * k + 4].copy_from_slice(&mantissa::round_float_bits(c[k].to_bits(), keep).to_le_bytes());
            }
        }
    });
}

/// The half-float gather: the components are collected as `f32`, converted
/// to binary16 as one slice (`half`'s slice conversion uses the CPU's F16C
/// instructions where it has them, four values at a time; the rounding is
/// IEEE round-to-nearest-even either way, so the bits are those of
/// `f16::from_f32` per value), then rounded to `keep` mantissa bits.
fn gather_half<T: VoxelValue>(dst: &mut Vec<u8>, stored: Stored<'_, T>, keep: u32, s: &mut HalfScratch) {
    use half::slice::{HalfBitsSliceExt, HalfFloatSliceExt};
    s.floats.clear();
    stored.for_each(|v| s.floats.extend_from_slice(&v.components()[..T::COMPONENTS]));
    let n = s.floats.len();
    s.bits.clear();
    s.bits.resize(n, 0);
    let halves: &mut [f16] = s.bits.reinterpret_cast_mut();
    halves.convert_from_f32_slice(&s.floats);
    let start = dst.len();
    dst.resize(start + 2 * n, 0);
    for (d, &b) in dst[start..].chunks_exact_mut(2).zip(&s.bits) {
        d.copy_from_slice(&mantissa::round_half_bits(b, keep).to_le_bytes());
    }
}

/// Appends a value at full precision (`f32` per component).
pub fn push_full<T: VoxelValue>(out: &mut Vec<u8>, v: T) {
    for x in &v.components()[..T::COMPONENTS] {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

/// A ZIP record's deflate ([`Deflate`]).
enum Zip {
    Zlib(Compress),
    Fast(Box<libdeflater::Compressor>),
}

/// OpenVDB `io::zipToStream`: `i64 L` and the zlib stream when it is shorter
/// than the raw bytes, else `-rawBytes` and the raw bytes.
fn zip_to_stream(z: &mut Zip, zbuf: &mut Vec<u8>, raw: &[u8], out: &mut Vec<u8>) {
    let stream = match z {
        Zip::Zlib(z) => zlib_stream(z, zbuf, raw),
        Zip::Fast(c) => {
            zbuf.clear();
            zbuf.resize(c.zlib_compress_bound(raw.len()), 0);
            c.zlib_compress(raw, zbuf).ok().map(|n| &zbuf[..n])
        }
    };
    match stream {
        Some(z) if z.len() < raw.len() => {
            out.extend_from_slice(&(z.len() as i64).to_le_bytes());
            out.extend_from_slice(z);
        }
        _ => {
            out.extend_from_slice(&(-(raw.len() as i64)).to_le_bytes());
            out.extend_from_slice(raw);
        }
    }
}

/// zlib's `compress2` of `raw` (OpenVDB's bytes) into `zbuf`, if it ends
/// within `raw.len()` bytes.
fn zlib_stream<'z>(z: &mut Compress, zbuf: &'z mut Vec<u8>, raw: &[u8]) -> Option<&'z [u8]> {
    z.reset();
    // Only a stream shorter than the raw bytes is kept, so `raw.len()` bytes of
    // output space suffice: if deflate does not finish within them, store raw.
    zbuf.clear();
    zbuf.resize(raw.len(), 0);
    let finished = matches!(z.compress(raw, zbuf, FlushCompress::Finish), Ok(Status::StreamEnd));
    finished.then(|| &zbuf[..z.total_out() as usize])
}

/// Blosc level of OpenVDB's `bloscCompress` (0..9, 9 = most effort).
pub const BLOSC_LEVEL: i32 = 9;
/// Blosc type size of OpenVDB's `bloscCompress`: `sizeof(float)` for every
/// value type (a vec3s is shuffled as three floats, a half array as pairs).
pub const BLOSC_TYPESIZE: usize = 4;

/// OpenVDB `io::bloscToStream`: `i64 L` and the Blosc frame
/// (`blosc_compress_ctx(9, shuffle, 4, n, .., "lz4", blocksize n, 1 thread)`),
/// or, only if Blosc reports an error, `-rawBytes` and the raw bytes.
/// Appends straight into `out`: the frame is compressed in place after the
/// 8-byte length, which is patched afterwards.
fn blosc_to_stream(raw: &[u8], out: &mut Vec<u8>) {
    let at = out.len();
    let cap = raw.len() + blosc_src::BLOSC_MAX_OVERHEAD as usize;
    out.resize(at + 8 + cap, 0);
    // SAFETY: `raw` and the destination are disjoint; blosc writes at most
    // `destsize` = `cap` bytes, all inside `out[at + 8..]`. The compressor
    // name is a NUL-terminated constant.
    let got = unsafe {
        blosc_src::blosc_compress_ctx(
            BLOSC_LEVEL,
            blosc_src::BLOSC_SHUFFLE as i32,
            BLOSC_TYPESIZE,
            raw.len(),
            raw.as_ptr().cast(),
            out[at + 8..].as_mut_ptr().cast(),
            cap,
            blosc_src::BLOSC_LZ4_COMPNAME.as_ptr().cast(),
            raw.len(),
            1,
        )
    };
    if got > 0 {
        out.truncate(at + 8 + got as usize);
        out[at..at + 8].copy_from_slice(&(got as i64).to_le_bytes());
    } else {
        out.truncate(at);
        out.extend_from_slice(&(-(raw.len() as i64)).to_le_bytes());
        out.extend_from_slice(raw);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::vdb::cursor::Cursor;
    use crate::io::vdb::decode::{read_values, RecordFormat};

    fn record<T: VoxelValue>(flags: u32, half: bool, values: &[T], mask: &[u64], child: Option<&[u64]>, bg: T) -> Vec<u8> {
        let mut out = Vec::new();
        Encoder::new(flags, Storage::exact(half)).write_values(&mut out, values, mask, child, bg);
        out
    }

    fn decode<T: VoxelValue>(bytes: &[u8], flags: u32, half: bool, n: usize, mask: &[u64], bg: T) -> Vec<T> {
        let mut cur = Cursor::new(bytes);
        let v = read_values(&mut cur, RecordFormat { flags, half }, n, mask, bg, true).unwrap().unwrap();
        assert_eq!(cur.pos(), bytes.len(), "record fully consumed");
        v
    }

    /// A 512-slot leaf whose inactive slots hold `inactive(n)` and whose active
    /// slots (every 3rd) hold distinct values.
    fn leaf(inactive: impl Fn(usize) -> f32) -> (Vec<f32>, Vec<u64>) {
        let mut mask = vec![0u64; 8];
        let values: Vec<f32> = (0..512)
            .map(|n| {
                if n % 3 == 0 {
                    layout::set_mask_bit(&mut mask, n);
                    1.0 + n as f32 * 0.25
                } else {
                    inactive(n)
                }
            })
            .collect();
        (values, mask)
    }

    /// All seven metadata cases of `MaskCompress`, with the bytes the notes
    /// give for each (meta byte, stored inactive values, selection mask), and
    /// an exact round trip through the reader in every compression mode.
    #[test]
    fn mask_compress_cases_and_round_trip() {
        let bg = 2.0f32;
        type Case = (u8, Box<dyn Fn(usize) -> f32>);
        let cases: Vec<Case> = vec![
            (0, Box::new(|_| 2.0)),
            (1, Box::new(|_| -2.0)),
            (2, Box::new(|_| 5.0)),
            (3, Box::new(|n| if n % 2 == 0 { -2.0 } else { 2.0 })),
            (4, Box::new(|n| if n % 2 == 0 { 2.0 } else { 7.0 })),
            (5, Box::new(|n| if n % 2 == 0 { 7.0 } else { 8.0 })),
            (6, Box::new(|n| n as f32)),
        ];
        for (want, f) in &cases {
            let (values, mask) = leaf(f);
            let (m, inactive) = mask_compress(&values, &mask, None, bg);
            assert_eq!(m, *want);
            match m {
                2 => assert_eq!(inactive[0], 5.0),
                4 => assert_eq!(inactive, [7.0, 2.0]),
                5 => assert_eq!(inactive, [8.0, 7.0]),
                _ => {}
            }
            for flags in 0..4 {
                let bytes = record(flags, false, &values, &mask, None, bg);
                let expect_meta = if flags & COMPRESS_ACTIVE_MASK != 0 { *want } else { 6 };
                assert_eq!(bytes[0], expect_meta);
                assert_eq!(decode(&bytes, flags, false, 512, &mask, bg), values, "meta {m} flags {flags}");
            }
        }
    }

    /// With every inactive slot at the background, mask mode stores exactly
    /// the active values after a 0 byte; ZIP of nothing is 8 zero bytes and
    /// half mode with nothing to store writes nothing.
    #[test]
    fn fog_volume_records_are_minimal() {
        let (values, mask) = leaf(|_| 0.0);
        let active: Vec<u8> = layout::mask_ones(&mask).flat_map(|n| values[n].to_le_bytes()).collect();
        let bytes = record(COMPRESS_ACTIVE_MASK, false, &values, &mask, None, 0.0);
        assert_eq!(bytes[0], 0);
        assert_eq!(&bytes[1..], &active[..]);
        let empty = vec![0u64; 8];
        let zeros = vec![0f32; 512];
        assert_eq!(record(3, false, &zeros, &empty, None, 0.0), vec![0u8; 9]);
        assert_eq!(record(2, true, &zeros, &empty, None, 0.0), vec![0u8]);
        assert_eq!(record(3, true, &zeros, &empty, None, 0.0), vec![0u8]);
        // A fully active leaf is meta 0 with all 512 values.
        let full = vec![u64::MAX; 8];
        let bytes = record(2, false, &values, &full, None, 0.0);
        assert_eq!(bytes.len(), 1 + 512 * 4);
        assert_eq!(decode(&bytes, 2, false, 512, &full, 0.0f32), values);
    }

    /// ZIP output is exactly zlib's `compress2` at level 6: the stream for a
    /// known input, checked against Python's `zlib.compress(data, 6)`.
    #[test]
    fn zip_matches_zlib_compress2() {
        let raw: Vec<u8> = (0..64u32).flat_map(|i| (i as f32 * 0.5).to_le_bytes()).collect();
        let mut z = Zip::Zlib(Compress::new(Compression::new(ZIP_LEVEL), true));
        let mut out = Vec::new();
        zip_to_stream(&mut z, &mut Vec::new(), &raw, &mut out);
        // python3 -c "import zlib,struct;d=b''.join(struct.pack('<f',i*0.5) for i in range(64));print(zlib.compress(d,6).hex())"
        let expect = hex("789c1dc31114c2001400c08f61180ec3306bb3300cc3300c0741100441100441100441100c8220088220088220088220e85ef7de45fc3522720b238d484ced983b76eedac293375f461651b26cc5c4aa35eba6366dd9b663d79e7d73070e1d3976e2d49973172e5db976e3d69d857b0f1e3d79f6e2d59b771f3e7df9f6e337fb01b26c332e");
        let zlen = i64::from_le_bytes(out[..8].try_into().unwrap());
        assert_eq!(zlen as usize, out.len() - 8);
        assert_eq!(hex_str(&out[8..]), hex_str(&expect));
        // Incompressible data is stored raw with a negative length.
        let noise: Vec<u8> = (0..256u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
        let mut out = Vec::new();
        zip_to_stream(&mut z, &mut Vec::new(), &noise, &mut out);
        assert_eq!(i64::from_le_bytes(out[..8].try_into().unwrap()), -256);
        assert_eq!(&out[8..], &noise[..]);
    }

    /// Rounded mantissas and libdeflate: every compression mode decodes to
    /// the values rounded as `mantissa::round_*` says (the format is
    /// OpenVDB's; only the stored bits change), and the fast deflate's
    /// stream is a zlib stream our reader (zlib `uncompress`) decodes.
    #[test]
    fn rounded_mantissas_decode_to_the_rounded_values_in_every_mode() {
        let mut s = 12345u32;
        let values: Vec<f32> = (0..512)
            .map(|i| {
                s = s.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                if i % 7 == 0 {
                    0.0
                } else {
                    (s >> 8) as f32 / (1u32 << 24) as f32 * 3.0
                }
            })
            .collect();
        let mask = vec![u64::MAX; 8];
        for flags in [0, COMPRESS_ZIP, COMPRESS_BLOSC, COMPRESS_ZIP | COMPRESS_ACTIVE_MASK] {
            for half in [false, true] {
                for deflate in [Deflate::OpenVdb, Deflate::Fast] {
                    let keep = 5;
                    let st = Storage { half, mantissa_bits: keep, deflate };
                    let mut out = Vec::new();
                    Encoder::new(flags, st).write_values(&mut out, &values, &mask, None, 0.0f32);
                    let back = decode(&out, flags, half, 512, &mask, 0.0f32);
                    let want: Vec<f32> = values
                        .iter()
                        .map(|&v| {
                            if half {
                                f16::from_bits(mantissa::round_half_bits(f16::from_f32(v).to_bits(), keep)).to_f32()
                            } else {
                                mantissa::round_float(v, keep)
                            }
                        })
                        .collect();
                    assert_eq!(back, want, "flags {flags} half {half} {deflate:?}");
                    // Zeros stay exact zeros (the background never moves).
                    assert!(back.iter().step_by(7).all(|&x| x == 0.0));
                }
            }
        }
    }

    /// Blosc records: an empty non-half array is an 8-byte length plus a
    /// 16-byte header-only frame (the 24 bytes per empty internal array the
    /// notes measured in pyopenvdb's files); half with nothing to store writes
    /// nothing; a smooth leaf shrinks; every case reads back exactly, float
    /// and vec3, full and half; incompressible data stay inside a frame.
    #[test]
    fn blosc_records() {
        let flags = COMPRESS_BLOSC | COMPRESS_ACTIVE_MASK;
        let empty = vec![0u64; 8];
        let zeros = vec![0f32; 512];
        let b = record(flags, false, &zeros, &empty, None, 0.0);
        assert_eq!(b.len(), 1 + 8 + 16);
        assert_eq!(i64::from_le_bytes(b[1..9].try_into().unwrap()), 16);
        assert_eq!(record(flags, true, &zeros, &empty, None, 0.0), vec![0u8]);
        let full = vec![u64::MAX; 8];
        let smooth: Vec<f32> = (0..512).map(|n| 1.0 + (n / 64) as f32 * 0.5).collect();
        let b = record(flags, false, &smooth, &full, None, 0.0);
        assert!(b.len() < 1 + 8 + 512 * 4 / 4, "smooth leaf compresses: {} bytes", b.len());
        assert_eq!(decode(&b, flags, false, 512, &full, 0.0f32), smooth);
        for f in [COMPRESS_BLOSC, flags] {
            let (values, mask) = leaf(|n| if n % 2 == 0 { 7.0 } else { 8.0 });
            for half in [false, true] {
                let b = record(f, half, &values, &mask, None, 2.0);
                let want: Vec<f32> = values.iter().map(|&v| if half { round_half(v) } else { v }).collect();
                assert_eq!(decode(&b, f, half, 512, &mask, 2.0f32), want, "flags {f} half {half}");
            }
            let vecs: Vec<[f32; 3]> = (0..512).map(|n| [n as f32, -(n as f32), 0.25]).collect();
            let b = record(f, false, &vecs, &full, None, [0.0; 3]);
            assert_eq!(decode(&b, f, false, 512, &full, [0.0f32; 3]), vecs);
        }
        let noise: Vec<f32> = (0..512u32).map(|i| f32::from_bits(0x3f80_0000 | (i.wrapping_mul(2654435761) >> 9))).collect();
        let b = record(flags, false, &noise, &full, None, 0.0);
        let len = i64::from_le_bytes(b[1..9].try_into().unwrap());
        assert!(len > 0 && len <= 512 * 4 + 16, "stored in a frame, {len} bytes");
        assert_eq!(decode(&b, flags, false, 512, &full, 0.0f32), noise);
    }

    /// The slice conversion of the half-float gather gives, bit for bit, the
    /// per-value `f16::from_f32` then mantissa rounding: over normal,
    /// subnormal, tie, signed-zero and near-overflow values, for vec3 and
    /// float, every mask shape, and every kept width.
    #[test]
    fn half_gather_matches_per_value_conversion() {
        use rand::RngCore;
        let mut r = crate::util::rng::rng(&[0x2545_f491]);
        let mut next = || r.next_u32();
        let specials = [0.0f32, -0.0, 1.0, -2.5, 65504.0, -65504.0, 65519.0, 6.1e-5, 5.96e-8, 2.98e-8, 1.0e-7, 2049.0, 2051.0, 1.0009766];
        let mut floats: Vec<f32> = specials.to_vec();
        while floats.len() < 3 * 512 {
            let r = next();
            // Exponents spanning the half range, subnormals included.
            let x = f32::from_bits((r & 0x807f_ffff) | ((103 + (r >> 23) % 40) << 23));
            floats.push(x);
        }
        let vecs: Vec<[f32; 3]> = floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let mut sparse = vec![0u64; 8];
        for n in (0..512).filter(|n| n % 3 != 1) {
            layout::set_mask_bit(&mut sparse, n);
        }
        for keep in [1, 5, 9, 10] {
            for (mask, all) in [(vec![u64::MAX; 8], true), (sparse.clone(), false)] {
                let count = if all { 512 } else { layout::mask_count(&mask) };
                let want = |xs: &mut dyn Iterator<Item = f32>| -> Vec<u8> {
                    xs.flat_map(|x| mantissa::round_half_bits(f16::from_f32(x).to_bits(), keep).to_le_bytes()).collect()
                };
                let mut got = Vec::new();
                gather(&mut got, Stored { values: &vecs, mask: &mask, all, count }, true, keep, &mut HalfScratch::default());
                let stored = layout::mask_ones(&mask).flat_map(|n| vecs[n]);
                assert_eq!(got, want(&mut stored.into_iter()), "vec3 keep {keep} all {all}");
                let mut got = Vec::new();
                gather(&mut got, Stored { values: &floats[..512], mask: &mask, all, count }, true, keep, &mut HalfScratch::default());
                assert_eq!(got, want(&mut layout::mask_ones(&mask).map(|n| floats[n])), "float keep {keep} all {all}");
            }
        }
    }

    fn hex(s: &str) -> Vec<u8> {
        (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap()).collect()
    }
    fn hex_str(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    /// Half mode: data are binary16, stored inactive values are rounded but
    /// kept as f32, and vec3 values keep x y z order.
    #[test]
    fn half_records() {
        let mut mask = vec![0u64; 8];
        layout::set_mask_bit(&mut mask, 3);
        let mut values = vec![[0.1f32, 0.2, 0.3]; 512];
        values[3] = [1.0, -2.5, 65504.0];
        let bytes = record(COMPRESS_ACTIVE_MASK, true, &values, &mask, None, [0.0; 3]);
        let r = round_half(0.1);
        assert_eq!(bytes[0], 2);
        assert_eq!(&bytes[1..5], &r.to_le_bytes());
        assert_eq!(bytes.len(), 1 + 12 + 6);
        assert_eq!(&bytes[13..], &[0x00, 0x3c, 0x00, 0xc1, 0xff, 0x7b]);
        let back = decode(&bytes, 2, true, 512, &mask, [0.0f32; 3]);
        assert_eq!(back[3], [1.0, -2.5, 65504.0]);
        assert_eq!(back[0], [round_half(0.1), round_half(0.2), round_half(0.3)]);
        // Round to nearest even: 2049 lies halfway between 2048 and 2050.
        assert_eq!(round_half(2049.0), 2048.0);
        assert_eq!(round_half(2051.0), 2052.0);
    }
}
