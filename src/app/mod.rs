//! Above the stages, the files and the renderer: the adapter from a VDB file
//! to the renderer's medium ([`vdb_for_render`]), the live preview
//! ([`preview`]), the speed-against-accuracy bench ([`bench`]),
//! keograms of a baked sequence along the magnetic meridian ([`keogram`]),
//! and the render's cost for the farm plan ([`render_cost`]).

pub mod bench;
pub mod keogram;
pub mod preview;
pub mod render_cost;
pub mod vdb_for_render;
