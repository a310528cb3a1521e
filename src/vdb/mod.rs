//! OpenVDB file I/O.
pub mod read;
pub mod write;
