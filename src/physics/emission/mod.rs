//! The emission lines: their colours as the renderer sees them
//! ([`line_colour`]), the upper states' lifetimes ([`lifetime`]), and the
//! per-line grids a bake can write ([`line_table`]).

pub mod lifetime;
pub mod line_colour;
pub mod line_table;
