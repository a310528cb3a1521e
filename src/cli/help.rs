//! Help texts built from the registries they describe, so that they list
//! what the program has rather than what it had when they were written:
//! the presets from [`aurora::scene::presets::PRESETS`] and the profile
//! CSV's columns from [`aurora::pipeline::altitude_profile::HEADER`], the
//! keogram's rows from [`aurora::app::keogram::ROW_DEG`].
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
zero with colour.lines = \"simple\") in photons/s; deposited_kev_s in keV/s; the *_ver_cm3_s columns are the lines' volume emission rates in photons cm^-3 s^-1, \
the footprint average (the bin's photons/s over the area of the footprint cells above footprint.threshold, named in \
the file's first line, a # comment, times the bin's height). With --out FILE.csv, FILE.columns.csv beside it holds \
each curtain's column brightness per line in rayleigh (1 R = 1e6 photons cm^-2 s^-1 in the column) and in R per \
erg cm^-2 s^-1 of its mean energy flux. docs/physics.md#altitude-profiles-against-fang-et-al-2008 \
compares them with Fang et al. (2008).",
        columns.len(),
        columns.join(", ")
    )
}

/// `aurora keogram --help`: the rows, the columns, the units and the files.
pub fn keogram_long_about() -> String {
    let row = aurora::app::keogram::ROW_DEG;
    format!(
        "A keogram of a baked sequence (aurora bake SCENE --frames SPEC --out DIR, with grid.lines for a line's grid): \
the float grid --grid traced along the magnetic meridian through the scene's camera, one column per frame of --frame \
(time left to right, frame N at [animation] time_s + (N - 1) / fps), one row every {row} degrees of scan angle from the \
magnetic north horizon (the top row) through the zenith to the magnetic south horizon. Magnetic north is \
beams.b_declination_deg, or with earth.magnetic_pole the dipole pole's azimuth at the camera, or with a [site] \
(field = \"igrf\") IGRF-14's declination at the camera. Only these rays are \
traced, through the frame's density, up to the terrain, with the air's extinction as [sky] extinction says.\n\n\
Values: a line_* grid (rayleigh per km) gives the line's column brightness in rayleigh (R), 4 pi I / 1e6. Files: \
K.exr (one channel Y, width the frames, height the rows; units and air in its header attributes aurora_units and \
aurora_air), K.png (greyscale, linear, 255 = the largest value, stated in its text chunks) and K.csv (rows: \
scan_deg, elevation_deg, azimuth_deg, then one column per frame headed by its time in seconds)."
    )
}
