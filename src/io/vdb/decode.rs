//! The compressed-values record, reader side: OpenVDB
//! `io::readCompressedValues` (`openvdb/io/Compression.h`), the inverse of
//! [`super::codec`]'s writer (the record's layout is documented there).
//! Every length is checked against the bytes that remain before anything is
//! allocated, and a record is either decoded into its slots (the inactive
//! ones rebuilt from the metadata byte, as OpenVDB does) or validated and
//! skipped; ZIP through libdeflate (the writer's library: a whole chunk at
//! once, its size known, its Adler-32 checked), Blosc through c-blosc.

use super::codec::negative;
use super::cursor::{Cursor, ParseError};
use super::layout::{self, meta, COMPRESS_ACTIVE_MASK, COMPRESS_BLOSC, COMPRESS_ZIP};
use crate::grid::VoxelValue;
use half::f16;
use std::cell::RefCell;

thread_local! {
    /// One inflater per thread, reused for every chunk it reads.
    static INFLATER: RefCell<libdeflater::Decompressor> = RefCell::new(libdeflater::Decompressor::new());
}

/// How a grid's records are decoded.
#[derive(Clone, Copy, Debug)]
pub struct RecordFormat {
    /// Per-grid compression flags.
    pub flags: u32,
    /// Stored as half floats.
    pub half: bool,
}

/// Reads (or, when `decode` is false, validates and skips) one
/// compressed-values record of `n` slots. Returns all `n` values with the
/// inactive ones rebuilt as OpenVDB does. Every length is checked against the
/// bytes that remain, so garbage never causes a large allocation.
pub fn read_values<T: VoxelValue>(
    cur: &mut Cursor,
    fmt: RecordFormat,
    n: usize,
    value_mask: &[u64],
    background: T,
    decode: bool,
) -> Result<Option<Vec<T>>, ParseError> {
    let mut scratch = Vec::new();
    if !decode {
        read_values_into::<T>(cur, fmt, n, value_mask, background, Destination::Skip { check_streams: true }, &mut scratch)?;
        return Ok(None);
    }
    let mut out = vec![background; n];
    read_values_into(cur, fmt, n, value_mask, background, Destination::Slots(&mut out), &mut scratch)?;
    Ok(Some(out))
}

/// Where [`read_values_into`] puts a record's values.
pub enum Destination<'o, T> {
    /// Into these slots, all `n` of them.
    Slots(&'o mut [T]),
    /// Nowhere: the record is only validated and skipped. Its ZIP or Blosc
    /// stream is decompressed (and dropped) only if `check_streams`, which
    /// gives the verdict decoding would give (the caller that decodes the
    /// record later may skip it: decoding checks it). Without it a
    /// stream's length must fit in the file and a Blosc header must be
    /// valid and hold the expected size, but a damaged ZIP or LZ4 payload
    /// passes.
    Skip { check_streams: bool },
}

/// [`read_values`] writing straight into `dest` ([`Destination`]), with no
/// allocation beyond `scratch` (reused for decompression): stored values
/// are converted from the file's bytes, or from the decompressed bytes, in
/// place.
pub fn read_values_into<T: VoxelValue>(
    cur: &mut Cursor,
    fmt: RecordFormat,
    n: usize,
    value_mask: &[u64],
    background: T,
    dest: Destination<'_, T>,
    scratch: &mut Vec<u8>,
) -> Result<(), ParseError> {
    let (out, check_streams) = match dest {
        Destination::Slots(out) => (Some(out), true),
        Destination::Skip { check_streams } => (None, check_streams),
    };
    let m = cur.u8()?;
    if m > meta::NO_MASK_AND_ALL_VALS {
        return Err(cur.err(format!("invalid value-array metadata byte {m} (expected 0..6)")));
    }
    let mut inactive0 = if m == meta::NO_MASK_OR_INACTIVE_VALS { background } else { negative(background) };
    let mut inactive1 = background;
    if matches!(m, meta::NO_MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_TWO_INACTIVE_VALS) {
        inactive0 = read_full(cur)?;
        if m == meta::MASK_AND_TWO_INACTIVE_VALS {
            inactive1 = read_full(cur)?;
        }
    }
    // Selection mask as stored bytes: bit i is byte i >> 3, bit i & 7.
    let selection: Option<&[u8]> =
        if matches!(m, meta::MASK_AND_NO_INACTIVE_VALS | meta::MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_TWO_INACTIVE_VALS) {
            Some(cur.bytes(n / 8)?)
        } else {
            None
        };
    let masked = fmt.flags & COMPRESS_ACTIVE_MASK != 0 && m != meta::NO_MASK_AND_ALL_VALS;
    let count = if masked { layout::mask_count(value_mask) } else { n };
    let comp = T::COMPONENTS;
    let elem = if fmt.half { 2 } else { 4 } * comp;
    let nbytes = count * elem;
    let decode = out.is_some();
    let raw: Option<&[u8]> = if fmt.half && count == 0 {
        Some(&[])
    } else if fmt.flags & COMPRESS_BLOSC != 0 {
        read_chunk(cur, Codec::Blosc, nbytes, decode, decode || check_streams, scratch)?
    } else if fmt.flags & COMPRESS_ZIP != 0 {
        read_chunk(cur, Codec::Zip, nbytes, decode, decode || check_streams, scratch)?
    } else {
        Some(cur.bytes(nbytes)?)
    };
    let (Some(out), Some(raw)) = (out, raw) else { return Ok(()) };
    debug_assert_eq!(out.len(), n);
    debug_assert_eq!(raw.len(), count * elem);
    let scatter = Scatter { value_mask, selection, inactive: [inactive0, inactive1], full: !masked || count == n };
    if fmt.half {
        scatter.run(
            out,
            raw.chunks_exact(elem).map(|chunk| {
                let mut c = [0f32; 3];
                for (j, x) in c[..comp].iter_mut().enumerate() {
                    *x = f16::from_bits(u16::from_le_bytes([chunk[2 * j], chunk[2 * j + 1]])).to_f32();
                }
                T::from_components(&c)
            }),
        );
    } else {
        scatter.run(
            out,
            raw.chunks_exact(elem).map(|chunk| {
                let mut c = [0f32; 3];
                for (x, b) in c[..comp].iter_mut().zip(chunk.chunks_exact(4)) {
                    *x = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                }
                T::from_components(&c)
            }),
        );
    }
    Ok(())
}

/// Where the decoded values of a record go: every slot in order (`full`),
/// or the active slots (value mask) in order, the others rebuilt from the
/// selection mask (bit set -> `inactive[1]`, clear -> `inactive[0]`).
struct Scatter<'m, T> {
    value_mask: &'m [u64],
    selection: Option<&'m [u8]>,
    inactive: [T; 2],
    full: bool,
}

impl<T: VoxelValue> Scatter<'_, T> {
    #[inline]
    fn run(&self, out: &mut [T], mut values: impl Iterator<Item = T>) {
        if self.full {
            for (o, v) in out.iter_mut().zip(values) {
                *o = v;
            }
            return;
        }
        match self.selection {
            None => out.fill(self.inactive[0]),
            Some(s) => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = self.inactive[usize::from(s[i >> 3] >> (i & 7) & 1)];
                }
            }
        }
        // The record holds exactly one value per active slot (`count`).
        for (w, &word) in self.value_mask.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let i = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if let (Some(o), Some(v)) = (out.get_mut(i), values.next()) {
                    *o = v;
                }
            }
        }
    }
}

/// A value stored at full precision.
fn read_full<T: VoxelValue>(cur: &mut Cursor) -> Result<T, ParseError> {
    let mut c = [0f32; 3];
    for x in c[..T::COMPONENTS].iter_mut() {
        *x = cur.f32()?;
    }
    Ok(T::from_components(&c))
}

/// The length prefix of a compressed chunk (`i64 L`), shared by ZIP and
/// Blosc: L <= 0 means the data were stored raw, -L bytes, which must be
/// exactly `nbytes`; L > 0 is the compressed stream's length.
enum ChunkLen<'a> {
    Stored(&'a [u8]),
    Compressed(i64),
}

fn read_chunk_len<'a>(cur: &mut Cursor<'a>, nbytes: usize) -> Result<ChunkLen<'a>, ParseError> {
    let at = cur.pos();
    let len = cur.i64()?;
    if len > 0 {
        return Ok(ChunkLen::Compressed(len));
    }
    if len.unsigned_abs() != nbytes as u64 {
        return Err(cur.err_at(at, format!("expected a {nbytes}-byte uncompressed chunk, found {}", len.unsigned_abs())));
    }
    Ok(ChunkLen::Stored(cur.bytes(nbytes)?))
}

/// A compressed chunk's codec, from the grid's compression flags.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Codec {
    Zip,
    Blosc,
}

/// One compressed chunk of `nbytes` uncompressed bytes: OpenVDB
/// `io::unzipFromStream` or `io::bloscFromStream`. Stored chunks come back
/// as the file's bytes; a stream is expanded into `scratch` when `expand`
/// is set, and returned when `decode` is.
///
/// ZIP: the decompressed size must be exactly `nbytes`. The stream is
/// inflated even when only validating: vdb-rs reads just the first `nbytes`
/// of a stream and never reaches its Adler-32 checksum, so a damaged stream
/// would otherwise pass unnoticed. OpenVDB's `uncompress` checks the whole
/// stream.
///
/// Blosc: the header is validated (`blosc_cbuffer_validate`: its compressed
/// size must equal the chunk length) before the C decompressor sees the
/// bytes, so it never reads out of bounds; Blosc1 frames carry no checksum,
/// so running the decompressor is the only check of the LZ4 payload.
fn read_chunk<'a, 's>(
    cur: &mut Cursor<'a>,
    codec: Codec,
    nbytes: usize,
    decode: bool,
    expand: bool,
    scratch: &'s mut Vec<u8>,
) -> Result<Option<&'s [u8]>, ParseError>
where
    'a: 's,
{
    let at = cur.pos();
    let len = match read_chunk_len(cur, nbytes)? {
        ChunkLen::Stored(raw) => return Ok(decode.then_some(raw)),
        ChunkLen::Compressed(len) => len,
    };
    let stream = cur.bytes_len(len as u64)?;
    if codec == Codec::Blosc {
        blosc_validate(cur, at, stream, nbytes)?;
    }
    if !expand {
        return Ok(None);
    }
    if codec == Codec::Blosc && nbytes == 0 {
        return Ok(decode.then_some(&[]));
    }
    scratch.clear();
    scratch.resize(nbytes, 0);
    match codec {
        Codec::Blosc => blosc_decompress(cur, at, stream, scratch)?,
        Codec::Zip => match INFLATER.with(|z| z.borrow_mut().zlib_decompress(stream, scratch)) {
            Ok(got) if got == nbytes => {}
            Ok(_) | Err(libdeflater::DecompressionError::InsufficientSpace) => {
                return Err(cur.err_at(at, format!("zip chunk does not decompress to exactly {nbytes} bytes")))
            }
            Err(e) => return Err(cur.err_at(at, format!("corrupt zip chunk: {e}"))),
        },
    }
    Ok(decode.then_some(&scratch[..]))
}

/// Checks a Blosc frame's header: valid, and `nbytes` once decompressed.
fn blosc_validate(cur: &Cursor, at: usize, frame: &[u8], nbytes: usize) -> Result<(), ParseError> {
    let mut header_nbytes: usize = 0;
    // SAFETY: `blosc_cbuffer_validate` reads at most `frame.len()` bytes of the
    // frame (it first checks `cbytes >= BLOSC_MIN_HEADER_LENGTH`).
    let ok = unsafe { blosc_src::blosc_cbuffer_validate(frame.as_ptr().cast(), frame.len(), &mut header_nbytes) };
    if ok != 0 {
        return Err(cur.err_at(at, "invalid Blosc chunk header".to_string()));
    }
    if header_nbytes != nbytes {
        return Err(cur.err_at(at, format!("Blosc chunk holds {header_nbytes} bytes, expected {nbytes}")));
    }
    Ok(())
}

/// Decompresses a validated Blosc `frame` (whose header says `dst.len()`
/// bytes) into `dst`.
fn blosc_decompress(cur: &Cursor, at: usize, frame: &[u8], dst: &mut [u8]) -> Result<(), ParseError> {
    let nbytes = dst.len();
    // SAFETY: the frame was validated (its header's cbytes equals the slice
    // length), and blosc writes at most `destsize` = `dst.len()` bytes.
    let got = unsafe { blosc_src::blosc_decompress_ctx(frame.as_ptr().cast(), dst.as_mut_ptr().cast(), nbytes, 1) };
    if got != nbytes as i32 {
        return Err(cur.err_at(at, format!("corrupt Blosc chunk (decompressed {got} of {nbytes} bytes)")));
    }
    Ok(())
}

/// Which slots [`read_stored_f32`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredSlots {
    /// Every slot, in index order.
    All,
    /// The active slots only (value mask), in index order.
    Active,
}

/// Decodes the values a record *stores*, as `comps` f32 components a
/// slot, into `out`, without rebuilding the inactive slots: the active
/// slots alone when the record holds only those (an active-mask record),
/// else every slot. Checks what [`read_values_into`] checks. A Blosc frame
/// of full floats is decompressed straight into `out`'s memory (on a
/// little-endian machine its bytes are the floats); other encodings go
/// through `scratch`.
pub fn read_stored_f32(
    cur: &mut Cursor,
    fmt: RecordFormat,
    n: usize,
    value_mask: &[u64],
    comps: usize,
    out: &mut Vec<f32>,
    scratch: &mut Vec<u8>,
) -> Result<StoredSlots, ParseError> {
    let (slots, floats) = stored_header(cur, fmt, n, value_mask, comps)?;
    out.clear();
    out.resize(floats, 0.0);
    if fmt.half && floats == 0 {
        return Ok(slots);
    }
    let nbytes = floats * if fmt.half { 2 } else { 4 };
    if fmt.flags & COMPRESS_BLOSC != 0 && !fmt.half && cfg!(target_endian = "little") {
        let at = cur.pos();
        let frame = match read_chunk_len(cur, nbytes)? {
            ChunkLen::Stored(raw) => {
                le_floats(raw, out);
                return Ok(slots);
            }
            ChunkLen::Compressed(len) => cur.bytes_len(len as u64)?,
        };
        blosc_validate(cur, at, frame, nbytes)?;
        if nbytes > 0 {
            // SAFETY: `out` holds `floats` f32s = `nbytes` initialised bytes,
            // and any bit pattern is a valid f32.
            let dst = unsafe { std::slice::from_raw_parts_mut(out.as_mut_ptr().cast::<u8>(), nbytes) };
            blosc_decompress(cur, at, frame, dst)?;
        }
        return Ok(slots);
    }
    let raw = stored_bytes(cur, fmt, nbytes, scratch)?;
    if fmt.half {
        halves_to_f32(raw, out);
    } else {
        le_floats(raw, out);
    }
    Ok(slots)
}

/// A stored-values record's header, passed over: which slots it stores and
/// how many components (`comps` a slot) follow.
fn stored_header(
    cur: &mut Cursor,
    fmt: RecordFormat,
    n: usize,
    value_mask: &[u64],
    comps: usize,
) -> Result<(StoredSlots, usize), ParseError> {
    let m = cur.u8()?;
    if m > meta::NO_MASK_AND_ALL_VALS {
        return Err(cur.err(format!("invalid value-array metadata byte {m} (expected 0..6)")));
    }
    let n_inactive = match m {
        meta::NO_MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_ONE_INACTIVE_VAL => 1,
        meta::MASK_AND_TWO_INACTIVE_VALS => 2,
        _ => 0,
    };
    cur.bytes(n_inactive * 4 * comps)?;
    if matches!(m, meta::MASK_AND_NO_INACTIVE_VALS | meta::MASK_AND_ONE_INACTIVE_VAL | meta::MASK_AND_TWO_INACTIVE_VALS) {
        cur.bytes(n / 8)?;
    }
    let masked = fmt.flags & COMPRESS_ACTIVE_MASK != 0 && m != meta::NO_MASK_AND_ALL_VALS;
    let count = if masked { layout::mask_count(value_mask) } else { n };
    let slots = if count == n { StoredSlots::All } else { StoredSlots::Active };
    Ok((slots, count * comps))
}

/// A stored-values record's `nbytes` of values, decompressed (into
/// `scratch`) or read where they lie; checked as [`read_values_into`]
/// checks them.
fn stored_bytes<'a, 's>(cur: &mut Cursor<'a>, fmt: RecordFormat, nbytes: usize, scratch: &'s mut Vec<u8>) -> Result<&'s [u8], ParseError>
where
    'a: 's,
{
    Ok(if fmt.flags & COMPRESS_BLOSC != 0 {
        read_chunk(cur, Codec::Blosc, nbytes, true, true, scratch)?.unwrap_or(&[])
    } else if fmt.flags & COMPRESS_ZIP != 0 {
        read_chunk(cur, Codec::Zip, nbytes, true, true, scratch)?.unwrap_or(&[])
    } else {
        cur.bytes(nbytes)?
    })
}

/// [`read_stored_f32`] for a half-float record (`fmt.half`), its values
/// left as the halves' bits (no conversion): what a store of half floats
/// copies. The same checks.
pub fn read_stored_half(
    cur: &mut Cursor,
    fmt: RecordFormat,
    n: usize,
    value_mask: &[u64],
    comps: usize,
    out: &mut Vec<u16>,
    scratch: &mut Vec<u8>,
) -> Result<StoredSlots, ParseError> {
    debug_assert!(fmt.half);
    let (slots, halves) = stored_header(cur, fmt, n, value_mask, comps)?;
    out.clear();
    out.resize(halves, 0);
    if halves == 0 {
        return Ok(slots);
    }
    let raw = stored_bytes(cur, fmt, halves * 2, scratch)?;
    for (o, b) in out.iter_mut().zip(raw.chunks_exact(2)) {
        *o = u16::from_le_bytes([b[0], b[1]]);
    }
    Ok(slots)
}

/// Little-endian half floats from `raw` into `out` (as many as fit both),
/// in bulk (the `half` crate's slice conversion: F16C where the CPU has
/// it) when the bytes are aligned halves, else one at a time; both exact.
fn halves_to_f32(raw: &[u8], out: &mut [f32]) {
    use half::slice::HalfFloatSliceExt;
    let n = out.len().min(raw.len() / 2);
    match bytemuck::try_cast_slice::<u8, f16>(&raw[..2 * n]) {
        Ok(h) if cfg!(target_endian = "little") => h.convert_to_f32_slice(&mut out[..n]),
        _ => {
            for (o, b) in out.iter_mut().zip(raw.chunks_exact(2)) {
                *o = f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32();
            }
        }
    }
}

/// Little-endian f32s from `raw` into `out` (as many as fit both).
fn le_floats(raw: &[u8], out: &mut [f32]) {
    for (o, b) in out.iter_mut().zip(raw.chunks_exact(4)) {
        *o = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::{Compress, Compression, FlushCompress};

    /// Malformed records are errors: bad meta byte, truncated data, wrong zip
    /// sizes, a zip stream that decodes to the wrong length.
    #[test]
    fn malformed_records_are_errors() {
        let mask = vec![u64::MAX; 8];
        let fmt = |flags| RecordFormat { flags, half: false };
        let try_read = |b: &[u8], flags| read_values::<f32>(&mut Cursor::new(b), fmt(flags), 512, &mask, 0.0, true);
        assert!(try_read(&[7], 2).is_err());
        assert!(try_read(&[0, 1, 2, 3], 2).is_err());
        let mut b = vec![0u8];
        b.extend_from_slice(&(-100i64).to_le_bytes());
        b.extend_from_slice(&[0; 100]);
        assert!(try_read(&b, 3).is_err());
        let mut b = vec![0u8];
        b.extend_from_slice(&(i64::MAX).to_le_bytes());
        assert!(try_read(&b, 3).is_err());
        // A valid zlib stream of the wrong length.
        let mut z = Compress::new(Compression::new(6), true);
        let mut s = vec![0u8; 100];
        z.compress(&[0u8; 16], &mut s, FlushCompress::Finish).unwrap();
        s.truncate(z.total_out() as usize);
        let mut b = vec![0u8];
        b.extend_from_slice(&(s.len() as i64).to_le_bytes());
        b.extend_from_slice(&s);
        assert!(try_read(&b, 3).is_err());
        // Garbage where a Blosc frame should be.
        let mut b = vec![0u8];
        b.extend_from_slice(&20i64.to_le_bytes());
        b.extend_from_slice(&[0xAB; 20]);
        assert!(try_read(&b, 6).is_err());
    }
}
