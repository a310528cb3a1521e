//! `aurora`: physically plausible aurora baked into sparse OpenVDB volumes.
//!
//! The data flows one way (see `docs/ARCHITECTURE.md`):
//! scene -> footprint -> beams -> photons -> grids -> files (vdb, usd),
//! and the renderer reads grids only.
//!
//! Lower layers (`grid`, `spectrum`, `atmosphere`, `scene`) know nothing of
//! the stages above them.

pub mod atmosphere;
pub mod bake;
pub mod bench;
pub mod beams;
pub mod footprint;
pub mod grid;
pub mod outputs;
pub mod photons;
pub mod pilot;
pub mod progress;
pub mod prune;
pub mod render;
pub mod rng;
pub mod scene;
pub mod spectrum;
pub mod starts;
pub mod usd;
pub mod vdb;
