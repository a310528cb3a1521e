//! The physics of the bake and of what is seen, one test binary: each
//! module checks a result against a closed form, an independent model or
//! a measurement: the chemistry against NCAR GLOW (`chemistry`), the power
//! balance (`energy`), the memory budget (`budget`), the southern
//! hemisphere's mirror of the northern (`globe`), the bake's stages
//! (`pipeline`), the footprint's structure and the vortex sheet's growth
//! (`footprint`), curtains along paths (`path`), the round Earth (`earth`),
//! the lines one at a time and their red trail (`lines`, `trail`), the
//! corona's vanishing point (`corona`), the magnetic zenith of IGRF-14 over
//! a site (`magnetic_zenith`) and the presets' colours (`presets`).

#[path = "../common/mod.rs"]
mod common;

mod arcs;
mod budget;
mod chemistry;
mod corona;
mod earth;
mod energy;
mod footprint;
mod globe;
mod ibc;
mod lines;
mod magnetic_zenith;
mod path;
mod pipeline;
mod presets;
mod published;
mod trail;
mod velocity;
