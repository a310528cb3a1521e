//! Above the stages, the files and the renderer: the adapter from a VDB file
//! to the renderer's medium ([`vdb_for_render`]), the live preview
//! ([`preview`]), the speed-against-accuracy bench ([`bench`]),
//! keograms of a baked sequence along the magnetic meridian ([`keogram`]),
//! the render's cost for the farm plan ([`render_cost`]), and what the
//! command line and the Python module share: a scene taken from a file or a
//! preset ([`scene_input`]), one image of it ([`render_image`]) and a frame
//! sequence's bake ([`bake_sequence`]).

pub mod bake_sequence;
pub mod bench;
pub mod keogram;
pub mod preview;
pub mod render_cost;
pub mod render_image;
pub mod scene_input;
pub mod vdb_for_render;
