//! Sequences on a farm: frame ranges and shards ([`frame_range`]), the
//! sequence folder and its ownership ([`sequence_folder`]), and the cost
//! plan behind `--plan` ([`cost_plan`]).

pub mod cost_plan;
pub mod frame_files;
pub mod frame_range;
pub mod sequence_folder;
