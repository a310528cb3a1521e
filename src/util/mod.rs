//! The machine and the process, no physics: seeded random numbers, progress
//! reporting, memory limits, reading input files, atomic writes, watching
//! files for changes.

pub mod atomic_write;
pub mod file_watch;
pub mod input_file;
pub mod memory;
pub mod progress;
pub mod rng;
