//! OpenVDB file I/O: a native writer (file format 224, what OpenVDB 10-12
//! write) and a reader with our own validation and decoding.
//!
//! - [`layout`]: format constants and the per-level node offset functions;
//! - [`cursor`]: the bounds-checked byte reader and its [`cursor::ParseError`];
//! - [`mantissa`]: rounding values to fewer mantissa bits (what ZIP then
//!   compresses away);
//! - [`codec`]: the compressed-values record and its writer (mask
//!   compression, ZIP, Blosc, half, rounded mantissas);
//! - [`decode`]: the record's reader (bounds-checked; ZIP and Blosc);
//! - [`fileid`]: the content-derived file UUID and its hash (XXH64);
//! - [`write`](mod@write): grids -> file bytes;
//! - [`parse`]: bounds-checked parser (validation and native decoding);
//! - [`read`]: file -> grids (our parser; a second decoder can be plugged in
//!   for the plain float grids, which the tests do with vdb-rs as an oracle);
//! - [`records`]: a file's located leaf records as a `LeafSource`, decoded on
//!   demand (the renderer's medium is built from them by `crate::app::vdb_for_render`,
//!   above this module: `vdb` knows nothing of the renderer).
//!
//! Imports point one way: layout, cursor, fileid and mantissa at the bottom; codec on
//! them, decode on codec; write on codec, parse on decode; read on parse, records on parse and decode. The write benchmark's timer
//! is not here but in `crate::app::bench::vdb_write`.
pub mod codec;
pub mod cursor;
pub mod decode;
pub mod fileid;
pub mod layout;
pub mod mantissa;
pub mod meta;
pub mod parse;
pub mod read;
pub mod records;
pub mod topology;
pub mod write;
