//! The machine and the process: seeded random numbers, progress
//! reporting, memory limits, reading input files, atomic writes, watching
//! files for changes; and the colour science the bake and the renderer
//! share (`colour.rs`) and the observers whose colours they use
//! (`observer.rs`: the eye, a camera) with the camera's white balance
//! (`white_balance.rs`); and the transcendental functions, one
//! implementation on every platform (`fmath.rs`).

pub mod atomic_write;
pub mod colour;
pub mod file_watch;
pub mod fmath;
pub mod input_file;
pub mod memory;
pub mod observer;
pub mod progress;
pub mod rng;
#[cfg(test)]
pub mod scratch;
pub mod white_balance;
