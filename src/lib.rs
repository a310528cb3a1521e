//! `aurora`: physically plausible aurora baked into sparse OpenVDB volumes.
//!
//! The folders are the layers (`docs/ARCHITECTURE.md` draws them; the
//! layering test reads them from this tree). Data flows one way: scene ->
//! footprint -> beams -> deposits -> grids -> files, and the renderer reads
//! grids only.

pub mod app;
pub mod farm;
pub mod geometry;
pub mod grid;
pub mod io;
pub mod physics;
pub mod pipeline;
pub mod render;
pub mod scene;
pub mod util;
