//! `aurora`: physically plausible aurora baked into sparse OpenVDB volumes.
//!
//! The data flows one way (see `docs/ARCHITECTURE.md`):
//! scene -> footprint -> beams -> photons -> grids -> files (vdb, usd),
//! and the renderer reads grids only.
//!
//! The bottom layer (`scene`, `rng`, `progress`, `atomic`, `memory`,
//! `atmosphere`, `spectrum`, `camera`, `grid`, `magnetic`, `deposit`) knows
//! nothing of the stages above it.

pub mod animation;
pub mod atmosphere;
pub mod atomic;
pub mod bake;
pub mod bake_identity;
pub mod beams;
pub mod bench;
pub mod budget;
pub mod camera;
pub mod chemistry;
pub mod column;
pub mod csda;
pub mod curve;
pub mod deposit;
pub mod earth;
pub mod extinction;
pub mod fang;
pub mod fang_glow;
pub mod farm_plan;
pub mod footprint;
pub mod frames;
pub mod grid;
pub mod input_file;
pub mod leaf_source;
pub mod lifetime;
pub mod lines;
pub mod magnetic;
pub mod memory;
pub mod outputs;
pub mod photons;
pub mod preview;
pub mod profile;
pub mod progress;
pub mod prune;
pub mod render;
pub mod rng;
pub mod scene;
pub mod sequence;
pub mod spectrum;
pub mod starts;
pub mod trail;
pub mod usd;
pub mod vdb;
pub mod vdb_medium;
pub mod watch;
