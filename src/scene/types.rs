//! The scene's sections: one plain-data struct or enum per TOML table or
//! choice, each with the defaults a missing table or key takes. No checks
//! here (they are in [`super::validation`]) and nothing that reads the
//! machine.

use serde::{Deserialize, Serialize};
use std::fmt;

/// One auroral curtain: where its footprint lies and how hard it is driven.
/// Serialised through [`CurtainToml`], which leaves out `center`, `length`
/// and `rotation_deg` when `path` places the curtain.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default, into = "CurtainToml")]
pub struct Curtain {
    /// Centre of the footprint on the ground plane, km.
    pub center: [f64; 2],
    /// Length of the curtain along its axis, km.
    pub length: f64,
    /// Width of the footprint box across the axis, km (room for folds and the
    /// noise curve's bends).
    pub width: f64,
    /// Direction of the curtain's axis, degrees counter-clockwise from +x.
    pub rotation_deg: f64,
    /// Peak precipitating electron energy flux, mW/m^2 (= erg cm^-2 s^-1).
    pub energy_flux: f64,
    /// Characteristic energy E0 of the Maxwellian electron spectrum, keV.
    pub char_energy_kev: f64,
    /// Share of the energy flux carried by a soft Maxwellian component (the
    /// low-energy electrons that light the red tops above 200 km), in [0, 1].
    pub soft_fraction: f64,
    /// Characteristic energy of that soft component, keV.
    pub soft_energy_kev: f64,
    /// Share of the scene's beams given to this curtain (relative weight).
    pub beam_weight: f64,
    /// Amplitude of the low-frequency noise curve that bends the band, km.
    pub bend_km: f64,
    /// Seed offset so curtains differ.
    pub seed: u64,
    /// The ground track of the curtain's lower border (at 110 km), km: a
    /// centripetal Catmull-Rom curve through these points (`crate::pipeline::footprint::curtain_path`),
    /// instead of `center`, `length` and `rotation_deg`.
    pub path: Option<Vec<[f64; 2]>>,
}

/// [`Curtain`] as written: the straight placement's keys only without a path.
#[derive(Serialize)]
pub struct CurtainToml {
    #[serde(skip_serializing_if = "Option::is_none")]
    center: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    length: Option<f64>,
    width: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    rotation_deg: Option<f64>,
    energy_flux: f64,
    char_energy_kev: f64,
    soft_fraction: f64,
    soft_energy_kev: f64,
    beam_weight: f64,
    bend_km: f64,
    seed: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    path: Option<Vec<[f64; 2]>>,
}

impl From<Curtain> for CurtainToml {
    fn from(c: Curtain) -> Self {
        let straight = c.path.is_none();
        Self {
            center: straight.then_some(c.center),
            length: straight.then_some(c.length),
            width: c.width,
            rotation_deg: straight.then_some(c.rotation_deg),
            energy_flux: c.energy_flux,
            char_energy_kev: c.char_energy_kev,
            soft_fraction: c.soft_fraction,
            soft_energy_kev: c.soft_energy_kev,
            beam_weight: c.beam_weight,
            bend_km: c.bend_km,
            seed: c.seed,
            path: c.path,
        }
    }
}

/// The 2D stable-fluids footprint simulation (Stam 1999), per curtain.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct FootprintParams {
    /// Grid cells along and across the curtain.
    pub resolution: [usize; 2],
    /// Number of simulation steps.
    pub steps: usize,
    /// Time step in cell units (semi-Lagrangian advection is stable for any).
    pub dt: f64,
    /// Gauss-Seidel / Jacobi iterations of the pressure projection.
    pub pressure_iterations: usize,
    /// Initial band thickness as a fraction of the footprint width.
    pub band_fraction: f64,
    /// Number of sine periods of the initial velocity along the band.
    pub velocity_waves: f64,
    /// Initial velocity amplitude, cells per unit time.
    pub velocity_amplitude: f64,
    /// Number of sine periods of the initial density modulation along the band.
    pub density_waves: f64,
    /// Wavelength of the noise curve that bends the band, in curtain lengths.
    pub bend_wavelength: f64,
    /// Footprint densities below this (of a peak of 1) emit no beams.
    pub threshold: f64,
    /// For validation: a footprint of density 1 over the whole box (no
    /// fluid, no band, no bend), so every beam carries the curtain's
    /// `energy_flux` and line yields that depend on the local flux can be
    /// compared with a one-dimensional model (NCAR GLOW) at a known flux.
    pub uniform: bool,
}

/// The most earlier times `animation.trail_samples` may ask for.
pub const MAX_TRAIL_SAMPLES: u32 = 16;

/// Motion in time (`crate::pipeline::motion`): closed form in t, so any frame costs
/// one bake. Speeds from the time scales observers report; every motion
/// parameter at 0 gives identical frames.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AnimationParams {
    /// Frames per second of a sequence (`aurora bake --frames`).
    pub fps: f64,
    /// Time of the bake, s; frame N of a sequence is baked at
    /// `time_s + (N - 1) / fps`.
    pub time_s: f64,
    /// Phase speed of the folds (the footprint's vortex row) along the
    /// curtain, km/s (spirals drift about 4 km/s, surges about 2 km/s).
    pub fold_speed_kms: f64,
    /// Relative swing of the fold-driving velocity (folds deepen and relax), in [0, 1).
    pub fold_breathing: f64,
    /// Period of that swing, s.
    pub fold_breathing_period_s: f64,
    /// Speed at which the bend curve travels along the curtain, km/s.
    pub bend_speed_kms: f64,
    /// Rate at which the bend curve changes shape, 1/s (its noise moves one
    /// lattice cell in 1 / rate seconds).
    pub bend_change_hz: f64,
    /// Amplitude of the curtain's drift across its axis, km (bounded: a
    /// sine of period `drift_period_s`, so curtains never leave the view).
    pub drift_km: f64,
    pub drift_period_s: f64,
    /// Speed of the rays (the start-height and colour noise) along the
    /// curtain, km/s (up to about 25 km/s).
    pub ray_speed_kms: f64,
    /// Depth of pulsating patches, in [0, 1] (0 = off): each patch's
    /// electron flux swings between (1 - pulsation) and 1 times its value.
    pub pulsation: f64,
    /// Size of a pulsating patch, km.
    pub pulsation_patch_km: f64,
    /// Range of patch periods, s (most often 6-10 s; a few s to 20 s).
    pub pulsation_period_s: [f64; 2],
    /// The red trail (`crate::pipeline::red_trail`): how many earlier times of the
    /// motion the O(1D) lines (630.0, 636.4 nm) of a bake at `time_s` sum,
    /// each weighted by the decay of O(1D) at the deposit's altitude;
    /// 0 (the default) is off: every line at `time_s`. At most
    /// [`MAX_TRAIL_SAMPLES`]; each costs one more trace of the beams (the
    /// red only).
    pub trail_samples: u32,
}

/// Electron beams traced down the geomagnetic field (Baranoski et al. 2000).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct BeamParams {
    /// Total number of beams over all curtains; with `target_noise > 0`, the
    /// most the noise target may use.
    pub count: usize,
    /// Relative RMS noise of the emission grid to aim for (0 = off: use
    /// `count`). A pilot bake measures the scene's noise and sets the beam
    /// count from it (`crate::pipeline::bake::pilot`), at most `count`.
    pub target_noise: f64,
    /// Altitude where beams start, km.
    pub top_km: f64,
    /// Amplitude of the high-frequency 1D Perlin noise on the start height, km.
    pub top_noise_km: f64,
    /// Spatial frequency of that noise along the curtain, cycles per km.
    pub top_noise_freq: f64,
    /// Upper bound of the deflection angle alpha_D, degrees, in [0, 90).
    pub alpha_d_deg: f64,
    /// Width of the deflection angle range: alpha in [alpha_D - delta, alpha_D].
    pub delta_alpha_deg: f64,
    /// Beam length L, km: steps are s = L * dt * u along B.
    pub length_km: f64,
    /// Step parameter dt; at most 1/dt deflections per beam.
    pub dt: f64,
    /// Magnetic inclination (dip) angle, degrees below the horizon (90 = vertical).
    pub b_inclination_deg: f64,
    /// Magnetic declination: azimuth of B's horizontal part, degrees from +y towards +x.
    pub b_declination_deg: f64,
    /// How a beam deposits its energy (`crate::pipeline::beams`): `expected` (the
    /// curtain's whole spectrum on every beam, Fang et al. 2010 integrated),
    /// `sampled` (one energy per beam, Fang 2010 monoenergetic) or `csda`
    /// (one energy per beam, straight-line continuous slowing down: the
    /// model before Fang, kept for comparison).
    pub deposition: Deposition,
    /// How beam starts are placed over the footprint (`crate::pipeline::beams::starts`).
    pub starts: BeamStarts,
}

/// Beam energy deposition model; see [`BeamParams::deposition`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Deposition {
    Expected,
    Sampled,
    Csda,
}

/// The neutral atmosphere model (`crate::physics::atmosphere`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AtmosphereModel {
    /// NRLMSIS 2.1, 67 N, 20 E, 2020-01-15 00:00 UT, F10.7 = 150, Ap = 15.
    Nrlmsis21,
    /// Approximate U.S. Standard Atmosphere 1976, 80-500 km.
    Us1976,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AtmosphereParams {
    /// `nrlmsis21` (default) or `us1976`.
    pub model: AtmosphereModel,
}

impl Default for AtmosphereParams {
    fn default() -> Self {
        Self { model: AtmosphereModel::Nrlmsis21 }
    }
}

/// The Earth under the scene (`crate::geometry::earth`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EarthParams {
    /// Radius of the spherical Earth, km (6371, the mean radius); 0 is a
    /// flat ground where altitude is z.
    pub radius_km: f64,
    /// Ground coordinates `[x, y]` km of the geomagnetic (dipole) pole:
    /// when given the field at each beam's start follows the dipole
    /// (`crate::physics::geomagnetic_field`) and `beams.b_inclination_deg` and
    /// `b_declination_deg` are unused; none by default.
    pub magnetic_pole: Option<[f64; 2]>,
}

impl Default for EarthParams {
    fn default() -> Self {
        Self { radius_km: crate::geometry::earth::MEAN_RADIUS_KM, magnetic_pole: None }
    }
}

/// Placement of beam starts over the footprint, in proportion to its flux.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BeamStarts {
    /// Low-discrepancy: beam i takes point i of a randomly shifted R2
    /// sequence, mapped through the footprint's flux (default).
    Stratified,
    /// Independent random points (for comparison).
    Random,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ColourMode {
    /// Emission lines OI 557.7, OI 630.0, N2+ 427.8 through CIE 1931.
    Physical,
    /// Artist colour map: altitude -> RGB table.
    Colormap,
}

/// The line model of `mode = "physical"`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LineModel {
    /// The ion and excited-state chemistry (`crate::physics::chemistry`), driven by
    /// the local ionization rate at each deposit (default).
    Chemistry,
    /// The altitude-only parameterisation (`spectrum::EmissionModel`).
    Simple,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ColourParams {
    pub mode: ColourMode,
    /// Line model of the physical colours: "chemistry" or "simple".
    pub lines: LineModel,
    /// Amplitude of the low-frequency 1D noise on the altitude used for colour, km.
    pub noise_km: f64,
    /// Spatial frequency of that noise, cycles per km (along the curtain).
    pub noise_freq: f64,
    /// Artist colour map: rows of [altitude_km, r, g, b] (linear Rec.709, per
    /// unit deposited power), ascending altitude. Used when mode = "colormap".
    pub colormap: Vec<[f64; 4]>,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum GatherMethod {
    /// Gaussian kernel density estimate with a kiddo kd-tree gather.
    Kdtree,
    /// Each photon splats its kernel into the voxels it covers.
    Splat,
    /// The 2014 report: photons binned in a uniform grid, kernel-weighted
    /// *average* of colours (no density estimate). For comparison only.
    Report2014,
}

/// Volumetric photon mapping: Gaussian kernel density estimation.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct PhotonParams {
    /// Kernel radius r (the Gaussian's standard deviation), km.
    pub radius_km: f64,
    /// The kernel is cut off at this many radii (and renormalised).
    pub cutoff: f64,
    /// Relative amplitude of the medium-frequency 2D noise on the radius.
    pub radius_noise: f64,
    /// Spatial frequency of that noise, cycles per km.
    pub radius_noise_freq: f64,
    pub gather: GatherMethod,
    /// Kernel shape: each step's power spread along its segment, or at its
    /// end point (for comparison).
    pub kernel: KernelShape,
}

/// Photon kernel shape (`crate::pipeline::photons`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum KernelShape {
    /// The Gaussian convolved with each step's segment (photon beams; default).
    Segment,
    /// The Gaussian at each step's end point.
    Point,
}

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
/// (`crate::pipeline::bake::voxel::auto_voxel_size`).
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

/// Largest `grid.mantissa_bits`: a full float's mantissa
/// (`vdb::mantissa::FLOAT_MANTISSA_BITS`, which a test there checks).
pub const MAX_MANTISSA_BITS: u32 = 23;

/// Largest `grid.high_voxel_factor`.
pub const MAX_HIGH_VOXEL_FACTOR: u32 = 4;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct GridParams {
    pub voxel_size: VoxelSize,
    /// Air extinction where the aurora is: density = a * exp(-b (h - base_km)),
    /// per km (the report's a exp(-b h)).
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
    /// ...), in rayleigh per km: names of [`LINE_KEYS`].
    pub lines: Vec<String>,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    Perspective,
    Orthographic,
    /// Equidistant fisheye (Cycles' `FISHEYE_EQUIDISTANT`): `fov_deg` is the
    /// angle across the image circle, up to 360; 180 is a dome master.
    Fisheye,
    /// 360 x 180 degree latitude-longitude panorama (Cycles'
    /// `EQUIRECTANGULAR`); `fov_deg` is not used.
    Equirectangular,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Camera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    pub projection: Projection,
    /// Vertical field of view, degrees (perspective); the angle across the
    /// image circle (fisheye, up to 360).
    pub fov_deg: f64,
    /// Height of the view in scene units (orthographic).
    pub ortho_height: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderParams {
    pub width: usize,
    pub height: usize,
    /// Samples per pixel for the stochastic parts (pixel jitter, shadow rays).
    pub spp: usize,
    /// Exposure of the PNG preview, in stops.
    pub exposure: f64,
    /// The PNG preview's view transform (the EXR stays linear).
    pub view_transform: ViewTransform,
}

/// How a linear image becomes PNG code values (`crate::render::image_file`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ViewTransform {
    /// The sRGB OETF of the linear value, clipped (Blender's "Standard").
    Standard,
    /// AgX, Blender's default view (`crate::render::agx`).
    #[default]
    Agx,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct VolumeParams {
    /// extinction = density_scale * density grid.
    pub density_scale: f64,
    /// emitted radiance per unit length = emission_scale * emission grid.
    pub emission_scale: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Background {
    /// Constant radiance behind the volume where no terrain is hit.
    pub radiance: [f64; 3],
    /// Optional equirectangular linear EXR of sky radiance, added to
    /// `radiance` (path relative to the scene file; mapped as Blender's
    /// Environment Texture: centre towards +x, top row the zenith).
    pub image: Option<String>,
    /// A procedural star field (`crate::render::sky`), from the scene seed.
    pub stars: bool,
    /// Faintest star drawn, visual magnitude (6: the naked eye's limit).
    pub limiting_magnitude: f64,
    /// Scale on the stars' physical irradiance.
    pub star_brightness: f64,
}

/// The air between the aurora and the observer (`crate::physics::air_extinction`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SkyParams {
    /// Dim and redden what is seen through the lower atmosphere (Rayleigh,
    /// ozone, aerosol along each camera ray); false: no air.
    pub extinction: bool,
    /// Ozone column, Dobson units.
    pub ozone_du: f64,
    /// Aerosol optical depth at 550 nm, at sea level.
    pub aerosol_optical_depth: f64,
    /// Angstrom exponent of the aerosol's optical depth.
    pub angstrom: f64,
    /// Scale height of the aerosol's density, km.
    pub aerosol_scale_height_km: f64,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TerrainKind {
    None,
    Plane,
    Heightfield,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Terrain {
    pub kind: TerrainKind,
    /// Base height of the plane or heightfield, km.
    pub height: f64,
    /// Lambertian albedo, linear Rec.709.
    pub albedo: [f64; 3],
    /// Heightfield: peak height of the procedural mountains above `height`, km.
    pub mountain_height: f64,
    /// Heightfield: horizontal feature size of the mountains, km.
    pub mountain_scale: f64,
    /// Heightfield: optional 16-bit or 8-bit greyscale PNG heightmap instead of
    /// procedural mountains (path relative to the scene file).
    pub heightmap: Option<String>,
    /// Heightfield: ground extent covered by the heightmap, km: [x0, y0, x1, y1].
    pub extent: [f64; 4],
    /// Heightfield: seed of the procedural mountains.
    pub seed: u64,
}

impl Default for Curtain {
    fn default() -> Self {
        Self {
            center: [0.0, 0.0],
            length: 160.0,
            width: 40.0,
            rotation_deg: 0.0,
            energy_flux: 5.0,
            char_energy_kev: 3.0,
            soft_fraction: 0.1,
            soft_energy_kev: 0.2,
            beam_weight: 1.0,
            bend_km: 12.0,
            seed: 0,
            path: None,
        }
    }
}

impl Default for FootprintParams {
    fn default() -> Self {
        Self {
            resolution: [512, 128],
            steps: 12,
            dt: 1.0,
            pressure_iterations: 40,
            band_fraction: 0.08,
            velocity_waves: 6.0,
            velocity_amplitude: 2.5,
            density_waves: 9.0,
            bend_wavelength: 0.6,
            threshold: 0.03,
            uniform: false,
        }
    }
}

impl Default for AnimationParams {
    fn default() -> Self {
        Self {
            fps: 24.0,
            time_s: 0.0,
            fold_speed_kms: 3.0,
            fold_breathing: 0.3,
            fold_breathing_period_s: 40.0,
            bend_speed_kms: 1.0,
            bend_change_hz: 1.0 / 60.0,
            drift_km: 8.0,
            drift_period_s: 300.0,
            ray_speed_kms: 10.0,
            pulsation: 0.0,
            pulsation_patch_km: 25.0,
            pulsation_period_s: [6.0, 10.0],
            trail_samples: 0,
        }
    }
}

impl Default for BeamParams {
    fn default() -> Self {
        Self {
            count: 8_000,
            target_noise: 0.0,
            top_km: 260.0,
            top_noise_km: 6.0,
            top_noise_freq: 0.5,
            alpha_d_deg: 5.0,
            delta_alpha_deg: 3.0,
            length_km: 400.0,
            dt: 0.0025,
            b_inclination_deg: 78.0,
            b_declination_deg: 0.0,
            deposition: Deposition::Expected,
            starts: BeamStarts::Stratified,
        }
    }
}

/// The report's hand-tuned look as an artist colour map: green low,
/// fading through yellow to red and violet high up (altitude in km).
pub fn report_colormap() -> Vec<[f64; 4]> {
    vec![
        [95.0, 0.05, 0.6, 0.25],
        [110.0, 0.1, 1.0, 0.35],
        [150.0, 0.25, 0.9, 0.3],
        [190.0, 0.7, 0.4, 0.2],
        [240.0, 0.9, 0.15, 0.25],
        [300.0, 0.5, 0.05, 0.4],
    ]
}

impl Default for ColourParams {
    fn default() -> Self {
        Self { mode: ColourMode::Physical, lines: LineModel::Chemistry, noise_km: 8.0, noise_freq: 0.02, colormap: report_colormap() }
    }
}

impl Default for PhotonParams {
    fn default() -> Self {
        Self {
            radius_km: 0.5,
            cutoff: 2.5,
            radius_noise: 0.3,
            radius_noise_freq: 0.05,
            gather: GatherMethod::Splat,
            kernel: KernelShape::Segment,
        }
    }
}

impl Default for GridParams {
    fn default() -> Self {
        Self {
            voxel_size: VoxelSize::Km(0.5),
            density_a: 0.02,
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
        }
    }
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            position: [0.0, -90.0, 1.0],
            look_at: [0.0, 20.0, 70.0],
            up: [0.0, 0.0, 1.0],
            projection: Projection::Perspective,
            fov_deg: 75.0,
            ortho_height: 10.0,
        }
    }
}

impl Default for RenderParams {
    fn default() -> Self {
        Self { width: 640, height: 360, spp: 16, exposure: 3.0, view_transform: ViewTransform::Agx }
    }
}

impl Default for VolumeParams {
    fn default() -> Self {
        Self { density_scale: 1.0, emission_scale: 1.0 }
    }
}

impl Default for Background {
    fn default() -> Self {
        Self { radiance: [0.0, 0.0, 0.0], image: None, stars: false, limiting_magnitude: 6.0, star_brightness: 1.0 }
    }
}

impl Default for SkyParams {
    fn default() -> Self {
        Self { extinction: true, ozone_du: 300.0, aerosol_optical_depth: 0.05, angstrom: 1.3, aerosol_scale_height_km: 1.2 }
    }
}

impl Default for Terrain {
    fn default() -> Self {
        Self {
            kind: TerrainKind::None,
            height: 0.0,
            albedo: [0.3, 0.3, 0.3],
            mountain_height: 3.0,
            mountain_scale: 10.0,
            heightmap: None,
            extent: [-300.0, -300.0, 300.0, 300.0],
            seed: 7,
        }
    }
}
