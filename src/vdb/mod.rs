//! OpenVDB file I/O: a native writer (file format 224, what OpenVDB 10-12
//! write) and a reader built on vdb-rs with our own validation and decoding.
//!
//! - [`layout`]: format constants and the per-level node offset functions;
//! - [`cursor`]: the bounds-checked byte reader and its [`cursor::ParseError`];
//! - [`codec`]: the compressed-values record (mask compression, ZIP, half);
//! - [`fileid`]: the content-derived file UUID and its hash (XXH64);
//! - [`write`](mod@write): grids -> file bytes;
//! - [`parse`]: bounds-checked parser (validation and native decoding);
//! - [`read`]: file -> grids (vdb-rs where it is right, our parser elsewhere).
//!
//! Imports point one way: layout, cursor and fileid at the bottom; codec on
//! them; write and parse on codec; read on parse. The write benchmark's timer
//! is not here but in `crate::bench::vdb_write`.
pub mod codec;
pub mod cursor;
pub mod fileid;
pub mod layout;
pub mod parse;
pub mod read;
pub mod write;
