//! `[grid]`: the stored grids (voxel size, pruning, compression, the high
//! column), with the defaults and limits.
//! [`GRID_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};
use std::fmt;

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Compression {
    None,
    Zip,
    ActiveMask,
    ZipActiveMask,
    /// Blosc (LZ4, byte shuffle), as OpenVDB and Houdini write by default.
    Blosc,
    BloscActiveMask,
}

/// Voxel size: a number of km, or "auto": one voxel about one pixel of the
/// scene's camera at the nearest aurora, resolved by the bake
/// (`crate::pipeline::voxel::auto_voxel_size`).
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum VoxelSize {
    Km(f64),
    Auto(AutoTag),
}

/// A number (integer or float) of km, or exactly the string "auto"; anything
/// else is an error that lists both (serde's untagged enums only say "did not
/// match any variant").
impl<'de> Deserialize<'de> for VoxelSize {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = VoxelSize;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a voxel size in km (a number > 0) or \"auto\"")
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> Result<VoxelSize, E> {
                Ok(VoxelSize::Km(x))
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> Result<VoxelSize, E> {
                Ok(VoxelSize::Km(x as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, x: u64) -> Result<VoxelSize, E> {
                Ok(VoxelSize::Km(x as f64))
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<VoxelSize, E> {
                if s == "auto" {
                    Ok(VoxelSize::Auto(AutoTag::Auto))
                } else {
                    Err(E::custom(format!("unknown value \"{s}\": expected a voxel size in km (a number > 0) or \"auto\" (lower case)")))
                }
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AutoTag {
    Auto,
}

/// Default `grid.prune`, from the pruning study of `aurora bench` and the
/// default scene (640x360): at 10^-3 the file is 11 % smaller (9 % fewer
/// voxels, 28 % fewer leaves) and the image differs from the unpruned one by
/// 0.28 % per pixel (mean, pixels above 1 % of the peak), below the 0.42 % to
/// which our renderer and Cycles agree on the same file; at 10^-2 the error
/// is 2.7 %, visible in the faint fringes.
pub const DEFAULT_PRUNE: f64 = 1e-3;

/// Default `grid.high_above_km` (used with `grid.high_voxel_factor > 1`),
/// from the storage study on the default scene (`docs/storage.md`): above
/// it lies about half of the bake's voxels and a small share of its light.
/// At 240 km, with half floats and the default pruning, the default frame
/// is 61.0 MB and its picture (640x360, 16 spp) within 0.43 % of the
/// full-precision unpruned file's; the dome master from the scene camera's
/// position 0.63 %.
pub const DEFAULT_HIGH_ABOVE_KM: f64 = 240.0;

/// Default `grid.mantissa_bits`: the mantissa bits kept of every stored
/// `density` and `emission` value (`crate::io::vdb::mantissa`), relative step
/// 2^-5, at most 1.6 % per voxel. From the storage study on the default
/// scene (`docs/storage.md`): with ZIP the frame is 59.0 MB (0.31x of the
/// 187.5 MB that the 9a7556f build wrote), and its picture (640x360, 16 spp)
/// within 0.25 % of the full-precision unpruned file's, the dome master
/// within 0.37 %; 4 bits give 51 MB, 0.29 % and 0.41 %.
pub const DEFAULT_MANTISSA_BITS: u32 = 5;

/// Largest `grid.prune`: half the light may go, no more (beyond that the
/// "error budget" is no longer a small error).
pub const MAX_PRUNE: f64 = 0.5;

/// Largest `grid.mantissa_bits`: a full float's mantissa
/// (`vdb::mantissa::FLOAT_MANTISSA_BITS`, which a test there checks).
pub const MAX_MANTISSA_BITS: u32 = 23;

/// What `grid.lines` takes: the names of [`super::validation::LINE_KEYS`].
pub const LINES_RULE: &str =
    "a list of distinct line names from \"5577\", \"6300\", \"6364\", \"4278\", \"n2_1p\"; needs colour.mode = \"physical\"";

/// Largest `grid.high_voxel_factor`.
pub const MAX_HIGH_VOXEL_FACTOR: u32 = 4;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct GridParams {
    pub voxel_size: VoxelSize,
    /// Artistic air extinction where the aurora is: density =
    /// a * exp(-b (h - base_km)), per km (the report's "air density"
    /// a exp(-b h)). 0, the default, is the physical air: in the visible the
    /// thermosphere is optically thin (Rayleigh scattering at 557.7 nm,
    /// about 4.3e-27 cm^2 a molecule (Bodhaine et al. 1999), on the
    /// 1.2e13 cm^-3 of 100 km, is 5e-9 per km; the column above 90 km has
    /// an optical depth near 2e-7), so the volume holds no extinction and
    /// the `density` grid is written empty. The air below the aurora is
    /// `[sky] extinction`'s.
    pub density_a: f64,
    pub density_b: f64,
    pub density_base_km: f64,
    /// Store `emission` (and `emission_high`) as half floats in the VDB:
    /// 11 significant bits, a relative rounding error of at most 2^-11 per
    /// voxel, 10^-5 of the picture on the default scene (`docs/storage.md`).
    /// A grid whose values pass the half range (65504) is stored as full
    /// floats instead, with a warning (`crate::io::bake_folder::fit_half`).
    pub half_emission: bool,
    /// Store `density` (and `density_high`) as half floats in the VDB (as
    /// `half_emission`).
    pub half_density: bool,
    /// Mantissa bits kept of every stored `density` and `emission` value
    /// (and of their high column): each is rounded to the nearest number
    /// with this many bits, at most 2^-(bits+1) relative
    /// (`crate::io::vdb::mantissa`); 10 keeps a half float whole, 23 a full
    /// float. The cleared bits cost ZIP almost nothing.
    pub mantissa_bits: u32,
    /// Also store a one-voxel shell of active zero voxels around the aurora
    /// (the 26-neighbourhood of its voxels): Cycles' biased volume mode
    /// marches only the active voxels grown across faces, so without it the
    /// low-index edges lose up to half a voxel of their trilinear ramp
    /// (`blender/vdb_pad.py`). The field is unchanged. Off by default: the
    /// aurora's own edges are its faint kernel tails, and the Cycles
    /// cross-check agrees without it (`docs/storage.md`).
    pub cycles_shell: bool,
    /// Altitude, km, above which the grids are stored at
    /// `high_voxel_factor` times the voxel size, in grids of their own
    /// (`emission_high`, `density_high`) that a renderer adds to `emission`
    /// and `density` (`crate::grid::high_column`): the faint soft-electron column.
    pub high_above_km: f64,
    /// Voxel size of the high column over `voxel_size` (1 = no high
    /// column: one grid each at the voxel size).
    pub high_voxel_factor: u32,
    pub compression: Compression,
    /// Error budget of contribution-based pruning (`crate::pipeline::prune`): the
    /// faintest leaves, as seen from the camera, are dropped while their
    /// share of the light reaching it stays below this fraction
    /// (0 = keep every leaf with any emission).
    pub prune: f64,
    /// Emission lines written as float grids of their own (`line_5577`,
    /// ...), in rayleigh per km: names of [`LINE_KEYS`](super::validation::LINE_KEYS).
    pub lines: Vec<String>,
    /// Also store the emission pattern's velocity, a vec3 grid `v` in km/s
    /// on the emission's active voxels, for motion blur (Cycles'
    /// `velocity_grid`, `render.shutter_s`): `crate::pipeline::bake::velocity`.
    /// Off by default: it adds about half to a frame's bytes (52 % on the default scene).
    pub velocity: bool,
}

impl Default for GridParams {
    fn default() -> Self {
        Self {
            voxel_size: VoxelSize::Km(0.5),
            density_a: 0.0,
            density_b: 0.02,
            density_base_km: 90.0,
            half_emission: true,
            half_density: true,
            mantissa_bits: DEFAULT_MANTISSA_BITS,
            cycles_shell: false,
            high_above_km: DEFAULT_HIGH_ABOVE_KM,
            // One grid per field by default: with the high column apart,
            // Cycles lights terrain with up to 9 % less of the column's red
            // light than `aurora render` (docs/storage.md).
            high_voxel_factor: 1,
            // Deflate, which every OpenVDB reader has (Blender's Blosc has
            // LZ4 alone): with rounded mantissas 0.59x the size of Blosc's
            // LZ4, which finds no repeats in the remaining bits.
            compression: Compression::ZipActiveMask,
            prune: DEFAULT_PRUNE,
            lines: Vec::new(),
            velocity: false,
        }
    }
}

/// Every key of `[grid]`: name, unit, allowed range and description (`super::keys`).
pub const GRID_KEYS: &[KeySpec] = &[
    KeySpec::new("voxel_size", "km", Range::NumOrWord(Num::POSITIVE, &["auto"]), "voxel edge, or `\"auto\"`: one voxel projects to about one pixel at the nearest aurora (never below half the kernel radius, never above twice its smallest value); `bake.json` says what it picked"),
    KeySpec::new("density_a", "1/km", Range::Num(Num::closed(0.0, 1e6)), "artistic extinction where the aurora is: `density = a exp(-b (h - base))`; 0 (the default) is the physical, optically thin air: an empty `density` grid"),
    KeySpec::new("density_b", "1/km", Range::Num(Num::closed(0.0, 10.0)), "fall-off of that extinction with altitude"),
    KeySpec::new("density_base_km", "km", Range::Num(Num::FINITE), "base altitude of that extinction"),
    KeySpec::new("half_emission", "", Range::Any, "store `emission` (and `emission_high`) as half floats: 2^-11 relative rounding per voxel; a grid whose values pass 65504 is stored as full floats, with a warning"),
    KeySpec::new("half_density", "", Range::Any, "store `density` (and `density_high`) as half floats (as `half_emission`)"),
    KeySpec::new("mantissa_bits", "bits", Range::Int { min: 1, max: MAX_MANTISSA_BITS as i64 }, "mantissa bits kept of every stored `density` and `emission` value: each is rounded to the nearest number with this many (at most 2^-(bits+1) relative; unbiased), so that ZIP compresses the cleared bits away; 10 keeps a half float whole, 23 a full float; the grids' metadata `aurora_mantissa_bits` says what was kept"),
    KeySpec::new("cycles_shell", "", Range::Any, "a one-voxel shell of active zeros around the aurora (and its high column), so that Cycles' biased volume mode renders its edges exactly (the field is unchanged); off by default: the aurora's edges are its faint kernel tails, and the Cycles cross-check agrees without it"),
    KeySpec::new("high_above_km", "km", Range::Num(Num::closed(0.0, 1e4)), "altitude above which the faint soft-electron column is stored at `high_voxel_factor` times the voxel size, in grids of its own (`emission_high`, `density_high`) that a renderer adds to `emission` and `density` (blended over two coarse voxels: no seam); `aurora render` and the add-on add them"),
    KeySpec::new("high_voxel_factor", "", Range::Int { min: 1, max: MAX_HIGH_VOXEL_FACTOR as i64 }, "voxel size of the high column over `voxel_size`; 1 stores one grid per field at the voxel size"),
    KeySpec::new("compression", "", Range::Word(&["none", "zip", "active-mask", "zip-active-mask", "blosc", "blosc-active-mask"]), "VDB value compression; `zip-active-mask` (deflate, which every OpenVDB reader has; written with libdeflate) stores the rounded mantissas in 0.59x of `blosc-active-mask`'s bytes (OpenVDB's and Houdini's default: LZ4 with byte shuffle, faster to write, but it finds no repeats in photon noise)"),
    KeySpec::new("prune", "", Range::Num(Num::closed(0.0, MAX_PRUNE)), "error budget of contribution-based pruning: the 8^3 blocks faintest in the camera's image are dropped while their share of the image's light stays within it (0 = keep all); `bake.json` `stats.prune` reports what went"),
    KeySpec::new("lines", "", Range::Rule(LINES_RULE), "emission lines written as float grids of their own in the same `.vdb`, `line_NAME`, in rayleigh per km (a ray's integral is the line's brightness in R; 1 R/km = 10 photons cm^-3 s^-1): `5577`, `6300` (630.0 nm alone), `6364`, `4278`, `n2_1p`; empty by default; colour noise applies to `emission` only; every three lines cost one more gather"),
    KeySpec::new("velocity", "", Range::Any, "also store `v`, the emission pattern's velocity in km/s on the emission's voxels (a vec3 grid; half floats with `half_emission`), for motion blur in Cycles (the add-on sets the Volume's velocity grid) and `render.shutter_s`; off by default: it adds about half to a frame's bytes (52 % on the default scene)"),
];
