//! Above the stages, the files and the renderer: the adapter from a VDB file
//! to the renderer's medium ([`vdb_for_render`]), the live preview
//! ([`preview`]), and the speed-against-accuracy bench ([`bench`]).

pub mod bench;
pub mod preview;
pub mod vdb_for_render;
