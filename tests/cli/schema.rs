//! One schema, three readers. `aurora scene --schema` (every scene key, its
//! default and its allowed range, as JSON) is the source; the Blender
//! add-on reads a committed copy (blender/scene_schema.json) and people read
//! docs/scene.md, a table per section rendered here from the same JSON plus
//! each key's unit and description ([`KEYS`]). Both tests fail when their
//! file differs from what the binary prints:
//! - `aurora scene --schema > blender/scene_schema.json` regenerates the copy;
//! - `AURORA_UPDATE_DOCS=1 cargo test --release --test cli schema::`
//!   rewrites docs/scene.md and blender/scene_keys.json.
//!
//! A key in the schema without a row in [`KEYS`], or a row naming no key,
//! fails the docs test: a new key is documented the day it lands.

use crate::common::{aurora, check_committed, ok, update_or_check_committed};
use serde_json::{Map, Value};
use std::fmt::Write as _;

/// How the files these tests generate are rewritten.
const REGENERATE: &str = "AURORA_UPDATE_DOCS=1 cargo test --release --test cli schema::";

/// What `aurora scene --schema` prints.
fn printed_schema() -> String {
    let out = aurora(&["scene", "--schema"]);
    ok(&out);
    String::from_utf8(out.stdout).expect("the schema is text")
}

#[test]
fn committed_schema_matches_the_binary() {
    let now = aurora::scene::schema::schema_json();
    check_committed("blender/scene_schema.json", &now, "aurora scene --schema > blender/scene_schema.json");
    // And the binary prints the same.
    assert_eq!(printed_schema(), now);
}

#[test]
fn scene_doc_matches_the_schema() {
    let schema: Value = serde_json::from_str(&printed_schema()).expect("the schema is JSON");
    update_or_check_committed("docs/scene.md", &scene_doc(&schema), REGENERATE);
}

/// The sections in the order a scene file gives them: schema name (`""`
/// for the top level), heading, and what the section is.
const SECTIONS: &[(&str, &str, &str)] = &[
    ("", "Top level", "Keys outside any table."),
    ("curtain", "`[[curtain]]`", "One table per auroral curtain: where its footprint lies and how hard it is driven. A scene without any `[[curtain]]` has the default scene's three; the defaults below are those of one table that omits a key."),
    ("footprint", "`[footprint]`", "The 2D stable-fluids simulation (Stam 1999) that makes each curtain's footprint, bent along a low-frequency noise curve."),
    ("beams", "`[beams]`", "Electron beams traced down the geomagnetic field with random deflections (Baranoski et al. 2000), depositing energy by Fang et al. (2010)."),
    ("atmosphere", "`[atmosphere]`", "The neutral atmosphere the electrons deposit their energy in, and the ambient night ionosphere the chemistry needs. The default is compiled in and free to sell with; `nrlmsis21` and `glow` are the data the physics was validated on, whose terms forbid commercial use or sale, read from a data folder ([data.md](data.md))."),
    ("earth", "`[earth]`", "The ground's shape: a sphere (curtain positions and paths are ground distances from the origin, azimuthal equidistant) or a flat plane."),
    ("colour", "`[colour]`", "How deposited energy becomes colour."),
    ("photons", "`[photons]`", "Volumetric photon mapping: a Gaussian-kernel density estimate of the emission."),
    ("grid", "`[grid]`", "The sparse grids written to the VDB."),
    ("camera", "`[camera]`", "The camera of `aurora render` and of the Blender scene; pruning and the automatic voxel size follow it."),
    ("render", "`[render]`", "The reference renderer's image."),
    ("volume", "`[volume]`", "The volume material, as `aurora render` and the add-on's Cycles material apply it."),
    ("background", "`[background]`", "What is seen behind the volume."),
    ("sky", "`[sky]`", "The air between the aurora and the observer: Rayleigh scattering, ozone and aerosol dim and redden what is seen through the lower atmosphere (docs/physics.md, \"The air between the aurora and the eye\")."),
    ("airglow", "`[airglow]`", "The night sky's own light, drawn by `aurora render` behind the volume (camera rays only, dimmed by the air, hidden by the terrain) and by Cycles through `aurora sky`'s map: Gaussian layers in spherical shells (docs/physics.md, \"Airglow\"). Render-only: the bake never reads it."),
    ("terrain", "`[terrain]`", "The ground, lit by the aurora only (emissive shadow rays)."),
    ("animation", "`[animation]`", "Motion in time, closed form in t, so any frame costs one bake; every motion key at 0 gives identical frames."),
];

/// Every key: section, key, unit (`""`: none), description. The order
/// within a section is the table's.
const KEYS: &[(&str, &str, &str, &str)] = &[
    ("", "seed", "", "master seed: every random stream is derived from it and an index"),
    ("curtain", "center", "km", "centre of the footprint on the ground plane, `[x, y]`"),
    ("curtain", "path", "km", "the curtain along a smooth curve (centripetal Catmull-Rom) through these `[x, y]` points: the ground track of its lower border (110 km), lifted up the field to the beams' start; replaces `center`, `length` and `rotation_deg` (giving both is an error)"),
    ("curtain", "length", "km", "length of the footprint box along the curtain's axis"),
    ("curtain", "width", "km", "width of the footprint box across the axis (room for folds and bends)"),
    ("curtain", "rotation_deg", "deg", "direction of the curtain's axis, counter-clockwise from +x"),
    ("curtain", "energy_flux", "mW/m^2", "peak precipitating electron energy flux (1 mW/m^2 = 1 erg cm^-2 s^-1)"),
    ("curtain", "char_energy_kev", "keV", "characteristic energy E0 of the Maxwellian electron spectrum: harder electrons reach lower"),
    ("curtain", "soft_fraction", "", "share of the energy flux in a soft Maxwellian component (the electrons that light the red tops above 200 km)"),
    ("curtain", "soft_energy_kev", "keV", "characteristic energy of the soft component"),
    ("curtain", "beam_weight", "", "share of the scene's beams given to this curtain (a relative weight)"),
    ("curtain", "bend_km", "km", "amplitude of the noise curve that bends the band (keep it below `width / 2`)"),
    ("curtain", "seed", "", "seed offset, so that curtains differ"),
    ("footprint", "model", "", "`sheet`: a vortex sheet rolled up by the Kelvin-Helmholtz instability, with rays along it; `fluid2014`: the 2014 report's band folded by a stable fluid (the `steps` to `density_waves` keys)"),
    ("footprint", "resolution", "cells", "grid across the curtain and least cells along it (the sheet's cells are at most as long as wide)"),
    ("footprint", "steps", "", "fluid2014: simulation steps"),
    ("footprint", "dt", "cells", "fluid2014: time step (semi-Lagrangian advection: stable for any `dt`)"),
    ("footprint", "pressure_iterations", "", "fluid2014: iterations of the pressure projection"),
    ("footprint", "band_fraction", "", "fluid2014: initial band thickness, as a fraction of the footprint width"),
    ("footprint", "velocity_waves", "", "fluid2014: sine periods of the initial velocity along the band"),
    ("footprint", "velocity_amplitude", "cells per unit time", "fluid2014: amplitude of the initial velocity"),
    ("footprint", "density_waves", "", "fluid2014: sine periods of the initial density modulation along the band"),
    ("footprint", "bend_wavelength", "curtain lengths", "wavelength of the noise curve that bends the band"),
    ("footprint", "threshold", "", "footprint density (of a peak of 1) below which no beam starts"),
    ("footprint", "end_fade_km", "km", "length over which the footprint fades to 0 at each end of the curtain (0: straight ends)"),
    ("footprint", "sheet_spacing_km", "km", "sheet: spacing of its vortex markers at the start"),
    ("footprint", "sheet_smoothing_km", "km", "sheet: smoothing length of the vortex-blob kernel (no curls below it)"),
    ("footprint", "sheet_amplitude", "", "sheet: amplitude of the initial displacement spectrum (its slope at 200 km wavelengths and more)"),
    ("footprint", "sheet_rollup_km", "km", "sheet: how far it rolls up (the shear across it times the time)"),
    ("footprint", "sheet_steps", "", "sheet: Runge-Kutta steps of the roll-up"),
    ("footprint", "sheet_thickness_km", "km", "sheet: full width at half maximum across it"),
    ("footprint", "ray_spacing_km", "km", "sheet: mean spacing of the rays along it (irregular)"),
    ("footprint", "ray_width_km", "km", "sheet: width of a ray along it (Gaussian sigma)"),
    ("footprint", "ray_contrast", "", "sheet: brightest ray over the faintest (log-uniform between)"),
    ("footprint", "glow", "", "sheet: diffuse glow between the rays, a 3 km blur of the sheet, of its peak"),
    ("footprint", "uniform", "", "for validation only: density 1 over the whole footprint box (no fluid, no band, no bend), so every beam carries the curtain's `energy_flux`; `tests/python/test_glow.py` compares such a curtain with NCAR GLOW"),
    ("beams", "count", "", "beams over all curtains; with `target_noise`, the most it may use"),
    ("beams", "target_noise", "", "relative RMS noise of the emission grid to aim for (0 = off: use `count`): a pilot of 2 x 500 and 2 x 125 beams measures the scene's noise and sets the beam count from the law `noise^2 = a/N + b/N^1.5` fitted to them, at most `count`; `bake.json` `stats.noise` says what it measured and chose"),
    ("beams", "top_km", "km", "altitude where beams start"),
    ("beams", "top_noise_km", "km", "amplitude of the high-frequency 1D noise on the start height"),
    ("beams", "top_noise_freq", "1/km", "spatial frequency of that noise along the curtain"),
    ("beams", "alpha_d_deg", "deg", "upper bound alpha_D of the deflection angle; a curtain whose field dips no more than alpha_D below the horizon where its beams start is refused (its electrons could go up or sideways)"),
    ("beams", "delta_alpha_deg", "deg", "width of the deflection range: alpha is uniform in [alpha_D - delta, alpha_D]"),
    ("beams", "length_km", "km", "beam length L: a step is s = L dt u along B (u uniform)"),
    ("beams", "dt", "", "step parameter: at most 1/dt deflections per beam (`csda` only: Fang beams go on until their deposition is complete)"),
    ("beams", "b_inclination_deg", "deg", "the geomagnetic field's dip below the horizon (90 = vertical)"),
    ("beams", "b_declination_deg", "deg", "azimuth of the field's horizontal part, from +y towards +x"),
    ("beams", "deposition", "", "how a beam deposits its energy: `expected` (the curtain's whole spectrum on every beam, Fang et al. 2010 integrated over it), `sampled` (one energy per beam, Fang 2010 monoenergetic: the same mean, more noise) or `csda` (one energy per beam, straight-line continuous slowing down, for comparison; the `seed2014` preset uses it)"),
    ("beams", "starts", "", "beam starts over the footprint, in proportion to its flux: `stratified` (beam i takes point i of a seeded R2 low-discrepancy sequence, whatever the count or thread count) or `random` (independent points, for comparison)"),
    ("atmosphere", "model", "", "the neutral atmosphere: `us1976` (U.S. Standard Atmosphere 1976, 50-700 km, public domain, compiled in: `data/us1976.csv` from `tools/reference/ussa1976_table.py`) or `nrlmsis21` (NRLMSIS 2.1 at 67 N 20 E, 2020-01-15 00 UT, F10.7 150, Ap 15, made by `tools/reference/msis_table.py`; research, academic and non-profit use only, so read from `nrlmsis21.csv` in the data folder, never compiled in; docs/data.md)"),
    ("atmosphere", "ionosphere", "", "the ambient night ionosphere and NO the chemistry needs: `closed-form` (Te = Ti = Tn, Chapman F and E layers, SNOE's NO peak; compiled in; `src/physics/chemistry/ambient.rs`) or `glow` (NCAR GLOW 4.0.4's IRI ionosphere and NOEM NO at the NRLMSIS table's place and time, the data the chemistry was validated on; GLOW's licence forbids sale, so read from `ionosphere.csv` in the data folder; docs/data.md)"),
    ("atmosphere", "data", "", "the folder holding `nrlmsis21.csv` and `ionosphere.csv`, relative to the scene file; unset, the `AURORA_DATA` environment variable names it, else the source tree's `data/` of the build. A table asked for and not there is refused naming the file and its terms (exit status 2)"),
    ("earth", "radius_km", "km", "radius of the spherical Earth centred at `(0, 0, -radius_km)`: altitude is the distance from its centre minus the radius everywhere (atmosphere, deposition, colour, density grid, terrain); curtain positions and paths are ground distances from the origin mapped onto it (azimuthal equidistant); the field's angles are relative to the local vertical and north; 0 is a flat ground, altitude = z"),
    ("earth", "magnetic_pole", "km", "ground coordinates `[x, y]` of the geomagnetic dipole's pole: the field at each beam's start is the dipole's (dip `tan I = 2 tan(magnetic latitude)`, horizontal part toward the pole), replacing `beams.b_inclination_deg` and `b_declination_deg`; beyond the dipole's equator (more than a quarter of the globe, 10007 km, from the pole) B points up and the electrons go down along -B; none by default"),
    ("colour", "mode", "", "`physical` (the emission lines through the observer's colour response, `observer`) or `colormap` (the `colormap` table)"),
    ("colour", "observer", "", "whose colours the lines get: `camera` (a digital camera, the Nikon D5100 measured by Darrodi et al. 2015, at daylight white balance with a ColorChecker-fitted matrix: 557.7 nm a saturated green, as photographs show it) or `eye` (the CIE 1931 observer: 557.7 nm yellow-green); the bake writes its RGB and the air's channels are weighed for it (docs/colour.md)"),
    ("colour", "lines", "", "the line model of `mode = \"physical\"`: `chemistry` (steady-state ion and excited-state chemistry driven by the local ionization rate, after NCAR GLOW's; docs/physics.md) or `simple` (yields in proportion to mole fractions, one quencher per state: the older rule of thumb)"),
    ("colour", "noise_km", "km", "amplitude of the low-frequency noise on the altitude used for colour (not intensity)"),
    ("colour", "noise_freq", "1/km", "spatial frequency of that noise along the curtain"),
    ("colour", "colormap", "km, linear Rec.709", "rows `[altitude_km, r, g, b]` (colour per unit deposited power), altitudes ascending, used when `mode = \"colormap\"`; the default is the 2014 report's look"),
    ("photons", "radius_km", "km", "kernel radius r, the Gaussian's standard deviation"),
    ("photons", "cutoff", "r", "the kernel is cut off at `cutoff` x r and renormalised"),
    ("photons", "radius_noise", "", "relative amplitude of the medium-frequency 2D noise on the radius"),
    ("photons", "radius_noise_freq", "1/km", "spatial frequency of that noise"),
    ("photons", "gather", "", "`splat` (each photon adds its kernel to the voxels it covers), `kdtree` (each voxel gathers from a kd-tree: the same field) or `report2014` (the 2014 report's kernel-weighted average of colours, not a density estimate, for comparison)"),
    ("photons", "kernel", "", "`segment` (each beam step's power spread along the step: the Gaussian convolved with the segment) or `point` (at the step's end, for comparison)"),
    ("grid", "voxel_size", "km", "voxel edge, or `\"auto\"`: one voxel projects to about one pixel at the nearest aurora (never below half the kernel radius, never above twice its smallest value); `bake.json` says what it picked"),
    ("grid", "density_a", "1/km", "artistic extinction where the aurora is: `density = a exp(-b (h - base))`; 0 (the default) is the physical, optically thin air: an empty `density` grid"),
    ("grid", "density_b", "1/km", "fall-off of that extinction with altitude"),
    ("grid", "density_base_km", "km", "base altitude of that extinction"),
    ("grid", "half_emission", "", "store `emission` (and `emission_high`) as half floats: 2^-11 relative rounding per voxel; a grid whose values pass 65504 is stored as full floats, with a warning"),
    ("grid", "half_density", "", "store `density` (and `density_high`) as half floats (as `half_emission`)"),
    ("grid", "mantissa_bits", "bits", "mantissa bits kept of every stored `density` and `emission` value: each is rounded to the nearest number with this many (at most 2^-(bits+1) relative; unbiased), so that ZIP compresses the cleared bits away; 10 keeps a half float whole, 23 a full float; the grids' metadata `aurora_mantissa_bits` says what was kept"),
    ("grid", "cycles_shell", "", "a one-voxel shell of active zeros around the aurora (and its high column), so that Cycles' biased volume mode renders its edges exactly (the field is unchanged); off by default: the aurora's edges are its faint kernel tails, and the Cycles cross-check agrees without it"),
    ("grid", "high_above_km", "km", "altitude above which the faint soft-electron column is stored at `high_voxel_factor` times the voxel size, in grids of its own (`emission_high`, `density_high`) that a renderer adds to `emission` and `density` (blended over two coarse voxels: no seam); `aurora render` and the add-on add them"),
    ("grid", "high_voxel_factor", "", "voxel size of the high column over `voxel_size`; 1 stores one grid per field at the voxel size"),
    ("grid", "compression", "", "VDB value compression; `zip-active-mask` (deflate, which every OpenVDB reader has; written with libdeflate) stores the rounded mantissas in 0.59x of `blosc-active-mask`'s bytes (OpenVDB's and Houdini's default: LZ4 with byte shuffle, faster to write, but it finds no repeats in photon noise)"),
    ("grid", "prune", "", "error budget of contribution-based pruning: the 8^3 blocks faintest in the camera's image are dropped while their share of the image's light stays within it (0 = keep all); `bake.json` `stats.prune` reports what went"),
    ("grid", "lines", "", "emission lines written as float grids of their own in the same `.vdb`, `line_NAME`, in rayleigh per km (a ray's integral is the line's brightness in R; 1 R/km = 10 photons cm^-3 s^-1): `5577`, `6300` (630.0 nm alone), `6364`, `4278`, `n2_1p`; empty by default; colour noise applies to `emission` only; every three lines cost one more gather"),
    ("grid", "velocity", "", "also store `v`, the emission pattern's velocity in km/s on the emission's voxels (a vec3 grid; half floats with `half_emission`), for motion blur in Cycles (the add-on sets the Volume's velocity grid) and `render.shutter_s`; off by default: it adds about half to a frame's bytes (52 % on the default scene)"),
    ("camera", "position", "km", "camera position"),
    ("camera", "look_at", "km", "the point the camera looks at"),
    ("camera", "up", "", "up direction"),
    ("camera", "projection", "", "`perspective`, `orthographic`, `fisheye` (equidistant, as Cycles' `FISHEYE_EQUIDISTANT`) or `equirectangular` (360 x 180 degrees, as Cycles' `EQUIRECTANGULAR`)"),
    ("camera", "fov_deg", "deg", "vertical field of view (perspective); for `fisheye` the angle across the image circle (180 = a planetarium dome master); unused by `equirectangular`"),
    ("camera", "ortho_height", "km", "height of the view (orthographic)"),
    ("render", "width", "px", "image width"),
    ("render", "height", "px", "image height (row 0 is the top)"),
    ("render", "spp", "", "samples per pixel (pixel positions and shadow rays): 1 samples pixel centres; more average the pixel square (box filter) at stratified antithetic positions"),
    ("render", "exposure", "stops", "PNG only: the view transform of 2^exposure x the linear image"),
    ("render", "png_bits", "bits", "PNG only: bits per channel, 8 or 16 (16 for delivery: dome masters, whose faint sky gradients band at 8)"),
    ("render", "view_transform", "", "PNG only: `agx` (Blender's default AgX view for an sRGB display, built from its published construction) or `standard` (the sRGB OETF, clipped: Blender's Standard); the EXR stays linear"),
    ("render", "shutter_s", "s", "motion blur of `aurora render`: each camera sample reads the fields at `p - v(p) tau`, tau uniform over the shutter centred on the frame, as Cycles does; needs the bake's `v` (`grid.velocity = true`); 0 is sharp"),
    ("volume", "density_scale", "", "extinction = `density_scale` x the `density` grid"),
    ("volume", "emission_scale", "", "emitted radiance per km = `emission_scale` x the `emission` grid"),
    ("background", "radiance", "linear Rec.709", "constant radiance seen behind the volume where no terrain is hit (it does not light the terrain)"),
    ("background", "image", "", "an equirectangular linear EXR of sky radiance added to `radiance` (relative to the scene file; mapped as Blender's Environment Texture: centre towards +x, top row the zenith); the add-on sets it as the World"),
    ("background", "stars", "", "a procedural star field (`aurora render` only): counts log10 N(<m) ~ 0.45 m, V-band flux, blackbody colours; each star is a Gaussian of one pixel's sigma that keeps its flux; none in orthographic views; Cycles gets them through `aurora sky`"),
    ("background", "limiting_magnitude", "mag", "faintest star drawn (6: the naked eye's limit)"),
    ("background", "star_brightness", "", "scale on the stars' physical irradiance"),
    ("airglow", "on", "", "draw the airglow behind the volume (`false`: a black sky, as before it existed)"),
    ("airglow", "scale", "", "scale on every layer's zenith brightness"),
    ("airglow", "green_r", "R", "zenith brightness of the OI 557.7 nm layer (97 km)"),
    ("airglow", "red_r", "R", "zenith brightness of the OI 630.0 nm layer (250 km); OI 636.4 nm comes with it at 1 / 2.997"),
    ("airglow", "sodium_r", "R", "zenith brightness of the sodium D lines (589 nm, 92 km)"),
    ("airglow", "hydroxyl_r", "R", "zenith brightness of the OH Meinel bands of the visible red (6-1, 7-2, 8-3 at 650-727 nm, 87 km), together"),
    ("sky", "extinction", "", "dim and redden the volume, the terrain's light and the stars through the air (Rayleigh by Bodhaine et al. 1999 with the observer's pressure, ozone's Chappuis band, aerosol; Kasten & Young's air mass); `false`: no air, the images of the renderer without it"),
    ("sky", "ozone_du", "DU", "ozone column (Chappuis band, Serdyuchenko et al. 2014 cross-sections); 300 is the global mean"),
    ("sky", "aerosol_optical_depth", "", "aerosol optical depth at 550 nm at sea level (0.05: clean Arctic winter air)"),
    ("sky", "angstrom", "", "Angstrom exponent: the aerosol's depth goes as (lambda / 550 nm)^-angstrom"),
    ("sky", "aerosol_scale_height_km", "km", "scale height of the aerosol's density (the column above the observer falls as exp(-altitude / it))"),
    ("terrain", "kind", "", "`none`, `plane` (z = `height`) or `heightfield`"),
    ("terrain", "height", "km", "base height of the plane or heightfield"),
    ("terrain", "albedo", "", "Lambertian albedo, linear Rec.709; the default 0.85 is fresh snow in the visible (Warren & Wiscombe 1980)"),
    ("terrain", "mountain_height", "km", "heightfield: peak height of the procedural fBm mountains above `height`"),
    ("terrain", "mountain_scale", "km", "heightfield: horizontal feature size of the mountains"),
    ("terrain", "heightmap", "", "heightfield: a 16- or 8-bit greyscale PNG instead of the procedural mountains (relative to the scene file)"),
    ("terrain", "extent", "km", "heightfield: the ground covered, `[x0, y0, x1, y1]`"),
    ("terrain", "seed", "", "heightfield: seed of the procedural mountains"),
    ("animation", "fps", "1/s", "frames per second of a sequence (USD `timeCodesPerSecond`, Blender's scene fps); dome masters are delivered at 30 or 60 (the fulldome Dome Master Show File Format; `--plan` notes another rate)"),
    ("animation", "time_s", "s", "time of the bake; frame N of `--frames` is baked at `time_s + (N - 1) / fps`"),
    ("animation", "fold_speed_kms", "km/s", "phase speed of the folds along the curtain (spirals drift about 4 km/s, surges about 2 km/s); the footprint's three vortex modes travel at 1, -0.5 and 1.6 times it"),
    ("animation", "fold_breathing", "", "relative swing of the fold-driving velocity (folds deepen and relax)"),
    ("animation", "fold_breathing_period_s", "s", "period of that swing"),
    ("animation", "bend_speed_kms", "km/s", "speed at which the bend curve travels along the curtain"),
    ("animation", "bend_change_hz", "1/s", "rate at which the bend curve changes shape"),
    ("animation", "drift_km", "km", "amplitude of the curtain's drift across its axis, `drift_km sin(2 pi t / drift_period_s)`: bounded, so it never leaves the view"),
    ("animation", "drift_period_s", "s", "period of the drift"),
    ("animation", "ray_speed_kms", "km/s", "speed of the rays (the start-height and colour noise) along the curtain (up to about 25 km/s observed)"),
    ("animation", "pulsation", "", "depth of pulsating patches (0 = off): each patch's electron flux swings between `1 - pulsation` and 1 times its value"),
    ("animation", "pulsation_patch_km", "km", "size of a pulsating patch"),
    ("animation", "pulsation_period_s", "s", "range each patch's period is drawn from (observed: a few s to 20 s, mostly 6-10 s)"),
    ("animation", "trail_samples", "", "the red trail: earlier times of the motion the O(1D) lines (630.0, 636.4 nm) sum, weighted by O(1D)'s decay at each deposit's altitude, so moving curtains leave red behind (0 = off; each sample traces the beams once more)"),
];

/// The types the default cannot tell: a key whose default is none, or
/// one that takes a number or a word.
fn stated_type(section: &str, key: &str) -> Option<&'static str> {
    Some(match (section, key) {
        ("background", "image") | ("terrain", "heightmap") | ("atmosphere", "data") => "path",
        ("grid", "voxel_size") => "number or `\"auto\"`",
        ("grid", "lines") => "list of words",
        ("curtain", "path") => "rows of 2 numbers",
        ("earth", "magnetic_pole") => "2 numbers",
        _ => return None,
    })
}

/// docs/scene.md: a header, then per section a table of key, type,
/// default, range, unit and description. Deterministic: the order is
/// [`SECTIONS`]' and [`KEYS`]', and values print as serde_json prints them.
fn scene_doc(schema: &Value) -> String {
    let schema = schema.as_object().expect("the schema is an object");
    for section in schema.keys() {
        assert!(SECTIONS.iter().any(|s| s.0 == section), "schema section `{section}` has no entry in SECTIONS (tests/cli/schema.rs)");
    }
    for (section, key, _, _) in KEYS {
        let known = schema.get(*section).and_then(|s| s.get(*key)).is_some();
        assert!(known, "KEYS (tests/cli/schema.rs) documents `{section}.{key}`, which the schema does not have");
    }
    let mut out = String::new();
    out.push_str("# Scene keys\n\n");
    out.push_str("<!-- Generated from `aurora scene --schema` by tests/cli/schema.rs; do not edit.\n");
    let _ = write!(out, "     Regenerate: {REGENERATE} -->\n\n");
    out.push_str(
        "A scene is a TOML file. Every key is optional and takes the default below; an unknown key, a \
         value out of range or an unknown word is an error naming the file, line, key, value and allowed \
         range (exit status 2). `aurora scene default` prints the default scene with every key, \
         `aurora scene FILE` prints FILE with every default filled in, and `aurora scene --schema` prints \
         the facts of these tables as JSON (the Blender add-on reads its committed copy, \
         `blender/scene_schema.json`). Lengths are kilometres, z up, x east, y north.\n\n",
    );
    out.push_str(
        "Any key can be set on the command line without editing the file: `--set KEY=VALUE` (every \
         command that takes a scene; repeatable), the key spelled as the errors spell it (`seed`, \
         `render.width`, `curtain[1].energy_flux`, `camera.up[2]`), the value in TOML (`64`, \
         `'[0, 1, 0]'`, `\"agx\"`; a bare word is text). Overrides apply in command-line order after the \
         file and before these checks, so the same ranges apply (docs/guide.md, \"Overrides\").\n\n",
    );
    out.push_str(
        "Ranges: `[a, b]` includes both ends, `(a, b)` neither, `inf` is unbounded. A type \
         `3 numbers` is a TOML array of three numbers.\n\n",
    );
    for (name, heading, about) in SECTIONS {
        let Some(keys) = schema.get(*name).and_then(Value::as_object) else { continue };
        let _ = write!(out, "## {heading}\n\n{about}\n\n");
        out.push_str("| key | type | default | range | unit | description |\n|---|---|---|---|---|---|\n");
        for key in keys.keys() {
            assert!(
                KEYS.iter().any(|k| k.0 == *name && k.1 == key),
                "scene key `{name}.{key}` has no row in KEYS (tests/cli/schema.rs): give it a unit and a description"
            );
        }
        for (_, key, unit, text) in KEYS.iter().filter(|k| k.0 == *name) {
            let entry = keys[*key].as_object().expect("a key's entry is an object");
            let row = [
                format!("`{key}`"),
                type_of(name, key, entry),
                default_of(name, entry),
                range_of(entry),
                unit.to_string(),
                text.to_string(),
            ];
            let _ = writeln!(out, "| {} |", row.map(|c| cell(&c)).join(" | "));
        }
        out.push('\n');
    }
    out.truncate(out.trim_end().len());
    out.push('\n');
    out
}

/// A table cell: pipes escaped, never empty.
fn cell(s: &str) -> String {
    if s.is_empty() {
        "-".into()
    } else {
        s.replace('|', "\\|")
    }
}

fn type_of(section: &str, key: &str, entry: &Map<String, Value>) -> String {
    if let Some(t) = stated_type(section, key) {
        return t.to_string();
    }
    let d = &entry["default"];
    match d {
        Value::Bool(_) => "bool".into(),
        Value::Number(n) if n.is_u64() || n.is_i64() => "integer".into(),
        Value::Number(_) => "number".into(),
        Value::String(_) if entry.contains_key("values") => "word".into(),
        Value::String(_) => "string".into(),
        Value::Array(items) => match items.first() {
            Some(Value::Array(row)) => format!("rows of {} numbers", row.len()),
            Some(Value::Number(n)) if n.is_u64() || n.is_i64() => format!("{} integers", items.len()),
            _ => format!("{} numbers", items.len()),
        },
        other => panic!("`{section}.{key}`: no type for a default of {other}; add it to `stated_type` (tests/cli/schema.rs)"),
    }
}

/// A value as TOML writes it: words quoted, arrays inline, none as `none`.
fn toml_value(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::String(s) => format!("\"{s}\""),
        Value::Array(items) => format!("[{}]", items.iter().map(toml_value).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

fn default_of(section: &str, entry: &Map<String, Value>) -> String {
    let mut s = format!("`{}`", toml_value(&entry["default"]));
    if let Some(t) = entry.get("default_in_table") {
        let _ = write!(s, " (`{}` in a written `[{section}]` table)", toml_value(t));
    }
    s
}

fn range_of(entry: &Map<String, Value>) -> String {
    if let Some(Value::Array(values)) = entry.get("values") {
        return values.iter().map(|v| format!("`{}`", toml_value(v))).collect::<Vec<_>>().join(", ");
    }
    if let Some(Value::String(rule)) = entry.get("rule") {
        return rule.clone();
    }
    let bound = |k: &str| entry.get(k).map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_string));
    match (bound("min"), bound("max")) {
        (Some(lo), Some(hi)) => {
            let open = if entry.get("min_inclusive") == Some(&Value::Bool(true)) { '[' } else { '(' };
            let close = if entry.get("max_inclusive") == Some(&Value::Bool(true)) { ']' } else { ')' };
            format!("{open}{lo}, {hi}{close}")
        }
        _ => String::new(),
    }
}

/// `blender/scene_keys.json`: each key's unit and description from
/// [`KEYS`], `{section: {key: {"unit", "description"}}}`, which the add-on's
/// panel shows beside the schema's defaults and ranges. Regenerated with
/// the docs (`AURORA_UPDATE_DOCS=1`).
#[test]
fn committed_key_docs_match_the_table() {
    let mut out = Map::new();
    for (section, key, unit, description) in KEYS {
        let entry = out.entry(section.to_string()).or_insert_with(|| Value::Object(Map::new()));
        let mut k = Map::new();
        k.insert("unit".into(), Value::String(unit.to_string()));
        k.insert("description".into(), Value::String(description.to_string()));
        entry.as_object_mut().expect("object").insert(key.to_string(), Value::Object(k));
    }
    let text = serde_json::to_string_pretty(&Value::Object(out)).expect("serialises") + "\n";
    update_or_check_committed("blender/scene_keys.json", &text, REGENERATE);
}
