//! `aurora bench`: speed against accuracy for every method choice.
pub mod chart;
pub mod metrics;
