//! A bounds-checked read position in a byte slice ([`Cursor`]) and the
//! error it reports ([`ParseError`]: what is wrong and at which byte). The
//! bottom of the reading side: [`super::codec`] decodes value records and
//! [`super::parse`] walks whole files with it, so neither needs the other's
//! module for its reads.

use glam::{DVec3, IVec3};

/// What is wrong, and at which byte offset of the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("at byte {offset}: {message}")]
pub struct ParseError {
    pub offset: u64,
    pub message: String,
}

impl ParseError {
    /// Always the user's input: the bytes of the file given (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// A read position in a byte slice; every read checks the bytes left.
pub struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }
    pub fn pos(&self) -> usize {
        self.pos
    }
    /// All the bytes (not only those left).
    pub fn data(&self) -> &'a [u8] {
        self.data
    }
    pub fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
    /// An error at the current position.
    pub fn err(&self, message: String) -> ParseError {
        self.err_at(self.pos, message)
    }
    pub fn err_at(&self, at: usize, message: String) -> ParseError {
        ParseError { offset: at as u64, message }
    }
    /// Moves to absolute offset `pos`, which must lie within the data.
    pub fn seek(&mut self, pos: u64) -> Result<(), ParseError> {
        if pos > self.data.len() as u64 {
            return Err(self.err(format!("offset {pos} is past the end of the file ({} bytes)", self.data.len())));
        }
        self.pos = pos as usize;
        Ok(())
    }
    pub fn bytes(&mut self, n: usize) -> Result<&'a [u8], ParseError> {
        if n > self.remaining() {
            return Err(self.err(format!("truncated: needs {n} more bytes, {} left", self.remaining())));
        }
        let b = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(b)
    }
    /// `n` bytes where `n` came from the file as a 64-bit length.
    pub fn bytes_len(&mut self, n: u64) -> Result<&'a [u8], ParseError> {
        if n > self.remaining() as u64 {
            return Err(self.err(format!("truncated: chunk of {n} bytes, {} left", self.remaining())));
        }
        self.bytes(n as usize)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], ParseError> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.bytes(N)?);
        Ok(a)
    }
    pub fn u8(&mut self) -> Result<u8, ParseError> {
        Ok(self.array::<1>()?[0])
    }
    pub fn u32(&mut self) -> Result<u32, ParseError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub fn i32(&mut self) -> Result<i32, ParseError> {
        Ok(i32::from_le_bytes(self.array()?))
    }
    pub fn i64(&mut self) -> Result<i64, ParseError> {
        Ok(i64::from_le_bytes(self.array()?))
    }
    pub fn f32(&mut self) -> Result<f32, ParseError> {
        Ok(f32::from_le_bytes(self.array()?))
    }
    pub fn f64(&mut self) -> Result<f64, ParseError> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    pub fn ivec3(&mut self) -> Result<IVec3, ParseError> {
        Ok(IVec3::new(self.i32()?, self.i32()?, self.i32()?))
    }
    pub fn dvec3(&mut self) -> Result<DVec3, ParseError> {
        Ok(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    /// `count` little-endian `u64` words (a node mask).
    pub fn u64s(&mut self, count: usize) -> Result<Vec<u64>, ParseError> {
        let b = self.bytes(count * 8)?;
        Ok(b.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().expect("8-byte chunk"))).collect())
    }
    /// OpenVDB string: `u32` length, then the bytes (no NUL).
    pub fn string_bytes(&mut self) -> Result<&'a [u8], ParseError> {
        let at = self.pos;
        let len = self.u32()? as usize;
        if len > self.remaining() {
            return Err(self.err_at(at, format!("string length {len} exceeds the {} bytes left", self.remaining())));
        }
        self.bytes(len)
    }
    pub fn string(&mut self) -> Result<String, ParseError> {
        Ok(String::from_utf8_lossy(self.string_bytes()?).into_owned())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cursor_checks_bounds() {
        let data = [1u8, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f];
        let mut c = Cursor::new(&data);
        assert_eq!(c.u32().unwrap(), 1);
        assert!(c.string().is_err(), "length 2^31-1 exceeds the data");
        let mut c = Cursor::new(&data);
        assert!(c.seek(9).is_err());
        assert!(c.bytes_len(u64::MAX).is_err());
        assert!(c.u64s(2).is_err());
    }
}
