//! OpenVDB file I/O: a native writer (file format 224, what OpenVDB 10-12
//! write) and a reader built on vdb-rs with our own validation and decoding.
//!
//! - [`layout`]: format constants and the per-level node offset functions;
//! - [`codec`]: the compressed-values record (mask compression, ZIP, half);
//! - [`write`](mod@write): grids -> file bytes;
//! - [`parse`]: bounds-checked parser (validation and native decoding);
//! - [`read`]: file -> grids (vdb-rs where it is right, our parser elsewhere).
pub mod codec;
pub mod layout;
pub mod parse;
pub mod read;
pub mod write;
