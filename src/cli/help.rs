//! Help texts built from the registries they describe, so that they list
//! what the program has rather than what it had when they were written:
//! the presets from [`aurora::scene::presets::PRESETS`] and the profile
//! CSV's columns from [`aurora::pipeline::altitude_profile::HEADER`].
//! `tests/docs.rs` checks that every name reaches the help and that every
//! repository path the help names exists.

use aurora::pipeline::altitude_profile::{BIN_KM, HEADER};
use aurora::scene::presets;

/// `aurora --help`: what the program does, and the presets SCENE may name.
pub fn long_about() -> String {
    let names: Vec<&str> = presets::names().collect();
    format!(
        "Bake physically plausible aurora into sparse OpenVDB volumes (an `emission` vec3 grid and a \
`density` float grid) for Blender Cycles, Houdini or a USD pipeline, and render them with a reference raymarcher.\n\n\
SCENE is a TOML scene file or the name of a built-in preset ({}); `aurora scene --list` says what each shows, \
`aurora scene default` prints one to edit, and docs/scene.md describes every key. Units are kilometres, z up.",
        names.join(", ")
    )
}

/// `aurora profile --help`: the CSV's columns, every one, in file order.
pub fn profile_long_about() -> String {
    let columns: Vec<&str> = HEADER.split(',').collect();
    format!(
        "Altitude profiles per curtain from the bake's own beam deposits, as CSV: one row per curtain and \
{BIN_KM} km altitude bin (altitude_km is the bin's centre), {} columns:\n\n{}\n\n\
Units, each summed over the curtain: ionization in ion pairs/s (35 eV per pair); the lines (n2p_4278, oi_5577, \
oi_6300, oi_6364, n2_1p) and their sources (oi_5577_* and oi_6300_*, each line's sources summing to its column; \
zero with colour.lines = \"simple\") in photons/s; deposited_kev_s in keV/s. docs/physics.md#altitude-profiles-against-fang-et-al-2008 \
compares them with Fang et al. (2008).",
        columns.len(),
        columns.join(", ")
    )
}
