//! The bake's stages, each a function from plain data to plain data:
//! scene -> footprint -> beam starts -> beams -> deposits -> photons ->
//! grids, with the closed-form motion and the red trail that make a
//! sequence, the pruning and the memory budget, the bake that composes them,
//! and the altitude profile read from the same deposits.

pub mod altitude_profile;
pub mod bake;
pub mod beams;
pub mod columns;
pub mod deposit;
pub mod footprint;
pub mod memory;
pub mod motion;
pub mod photons;
pub mod plan;
pub mod prune;
pub mod red_trail;
pub mod voxel;
