//! The bake's memory, known before it is spent, from the plan the bake
//! runs (`crate::pipeline::plan::BakePlan`) and nothing else: the bake and
//! its estimate read the same footprints, field, kernel and chunks.
//!
//! - [`reach`]: how far beams and deposits go (the highest deposit, the
//!   lowest stop, the steps a beam takes, its walk's spread, the world box);
//! - [`leaves`]: the leaves the grids can hold, counted from bands of
//!   field lines through the beams' starts;
//! - [`budget`]: the estimate, an upper bound term by term, each term
//!   naming the scene key that drives it;
//! - [`refusal`]: a bake whose estimate exceeds the usable share of this
//!   process's limit refused, naming the changes that would fit.
//!
//! The bake checks after building its plan (whose footprints cost some
//! MB: 0.002-0.004 GiB for the presets) and before it traces any beam
//! (`crate::pipeline::bake::check_memory`). Nothing here calls the bake.

pub mod budget;
pub mod expected;
pub mod leaves;
pub mod reach;
pub mod refusal;
