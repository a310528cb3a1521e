//! The scene file: every parameter of the bake and of the reference render.
//!
//! Units: **kilometres** for every length (positions, altitudes, radii, voxel
//! size), z up as in Blender, x east, y north. Extinction (`density`) is per
//! kilometre; emission is linear Rec.709 radiance per kilometre of path, scaled
//! so that Y = 1 corresponds to 1 kR of OI 557.7 nm per km (see `spectrum`).
//!
//! Parsing is separate from validation (pbrt's `GridMedium::Create` pattern):
//! serde reads the TOML (unknown keys are errors), then [`Scene::validate`]
//! checks every range once and names the file, line, key, value and the
//! allowed range. Stages downstream trust a validated scene.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    /// Master seed: every random stream is derived from it and an index.
    pub seed: u64,
    /// One entry per curtain (sheet): `[[curtain]]` tables.
    #[serde(rename = "curtain")]
    pub curtains: Vec<Curtain>,
    pub footprint: FootprintParams,
    pub beams: BeamParams,
    pub colour: ColourParams,
    pub photons: PhotonParams,
    pub grid: GridParams,
    pub camera: Camera,
    pub render: RenderParams,
    pub volume: VolumeParams,
    pub background: Background,
    pub terrain: Terrain,
    pub animation: AnimationParams,
    pub atmosphere: AtmosphereParams,
}

/// One auroral curtain: where its footprint lies and how hard it is driven.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
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
}

/// Motion in time (`crate::animation`): closed form in t, so any frame costs
/// one bake. Speeds from the time scales physicists quote (see
/// `../shared/notes/validation-and-animation.md`); every motion parameter at 0
/// gives identical frames.
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
    /// count from it (`crate::pilot`), at most `count`.
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
    /// How a beam deposits its energy (`crate::beams`): `expected` (the
    /// curtain's whole spectrum on every beam, Fang et al. 2010 integrated),
    /// `sampled` (one energy per beam, Fang 2010 monoenergetic) or `csda`
    /// (one energy per beam, straight-line continuous slowing down: the
    /// model before Fang, kept for comparison).
    pub deposition: Deposition,
    /// How beam starts are placed over the footprint (`crate::starts`).
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

/// The neutral atmosphere model (`crate::atmosphere`).
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

/// Placement of beam starts over the footprint, in proportion to its flux.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BeamStarts {
    /// Low-discrepancy: beam i takes point i of a randomly shifted R2
    /// sequence, mapped through the footprint's flux (default).
    Stratified,
    /// Independent random points (the estimator before issue 10; for comparison).
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

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ColourParams {
    pub mode: ColourMode,
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
    /// end point (the estimator before issue 10; for comparison).
    pub kernel: KernelShape,
}

/// Photon kernel shape (`crate::photons`).
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

/// Voxel size: a number of km, or "auto" (from the camera).
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

/// Largest seed: TOML integers are signed 64-bit, so a scene (and the
/// `--seed` flag, whose bake is written back as TOML) holds at most i64::MAX.
pub const MAX_SEED: u64 = i64::MAX as u64;
/// Largest `render.spp` (also the `--spp` flag's).
pub const MAX_SPP: u64 = 65_536;
/// Largest `--shadow-samples` per terrain hit per pixel sample.
pub const MAX_SHADOW_SAMPLES: u64 = 4_096;
/// Largest colour-map component (linear RGB per unit deposited power, about
/// 1 for the report's map): far beyond any look, and small enough that a
/// voxel's emission stays within single precision.
pub const MAX_COLORMAP_VALUE: f64 = 1e6;
/// Largest `--threads`.
pub const MAX_THREADS: u64 = 1_024;

/// Largest `grid.prune`: half the light may go, no more (beyond that the
/// "error budget" is no longer a small error).
pub const MAX_PRUNE: f64 = 0.5;

/// Default `grid.prune`, from the pruning study of `aurora bench` and the
/// default scene (640x360): at 10^-3 the file is 11 % smaller (9 % fewer
/// voxels, 28 % fewer leaves) and the image differs from the unpruned one by
/// 0.28 % per pixel (mean, pixels above 1 % of the peak), below the 0.42 % to
/// which our renderer and Cycles agree on the same file; at 10^-2 the error
/// is 2.7 %, visible in the faint fringes.
pub const DEFAULT_PRUNE: f64 = 1e-3;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct GridParams {
    pub voxel_size: VoxelSize,
    /// Air extinction where the aurora is: density = a * exp(-b (h - base_km)),
    /// per km (the report's a exp(-b h)).
    pub density_a: f64,
    pub density_b: f64,
    pub density_base_km: f64,
    /// Store `emission` as half floats in the VDB.
    pub half_emission: bool,
    /// Also store a one-voxel shell of active zero voxels around the aurora
    /// (the 26-neighbourhood of its voxels): Cycles' biased volume mode
    /// marches only the active voxels grown across faces, so without it the
    /// low-index edges lose up to half a voxel of their trilinear ramp
    /// (`blender/vdb_pad.py`). The field is unchanged.
    pub cycles_shell: bool,
    pub compression: Compression,
    /// Error budget of contribution-based pruning (`crate::prune`): the
    /// faintest leaves, as seen from the camera, are dropped while their
    /// share of the light reaching it stays below this fraction
    /// (0 = keep every leaf with any emission).
    pub prune: f64,
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

/// Largest `render.width` and `render.height` (the one image-size limit:
/// the scene, the camera and the renderer all check this).
pub const MAX_IMAGE_SIDE: usize = 16384;

impl Camera {
    /// The largest `fov_deg` of this projection: 360 for the fisheye (the
    /// whole sphere), below 180 for a pinhole (degrees, exclusive).
    pub fn max_fov_deg(&self) -> (f64, bool) {
        match self.projection {
            Projection::Fisheye => (360.0, true),
            _ => (180.0, false),
        }
    }

    /// Every camera value outside its range, as (key, value, allowed): the
    /// one set of camera limits, applied by [`Scene::validate`] and by
    /// `crate::camera::CameraModel::new`.
    pub fn problems(&self) -> Vec<(&'static str, String, String)> {
        let mut p = Vec::new();
        let (max_fov, inclusive) = self.max_fov_deg();
        if !(self.fov_deg > 0.0 && (self.fov_deg < max_fov || (inclusive && self.fov_deg == max_fov))) {
            let close = if inclusive { "]" } else { ")" };
            p.push(("fov_deg", fmt_num(self.fov_deg), format!("must be in (0, {}{close}", fmt_num(max_fov))));
        }
        if !(self.ortho_height.is_finite() && self.ortho_height > 0.0) {
            p.push(("ortho_height", fmt_num(self.ortho_height), "must be a finite number > 0".into()));
        }
        let dir = [self.look_at[0] - self.position[0], self.look_at[1] - self.position[1], self.look_at[2] - self.position[2]];
        if dir.iter().all(|d| *d == 0.0) {
            p.push(("look_at", format!("{:?}", self.look_at), "must differ from camera.position".into()));
        }
        let cross = [
            dir[1] * self.up[2] - dir[2] * self.up[1],
            dir[2] * self.up[0] - dir[0] * self.up[2],
            dir[0] * self.up[1] - dir[1] * self.up[0],
        ];
        let up2: f64 = self.up.iter().map(|u| u * u).sum();
        let dir2: f64 = dir.iter().map(|u| u * u).sum();
        if !(cross.iter().map(|c| c * c).sum::<f64>() > 1e-18 * up2 * dir2) {
            p.push(("up", format!("{:?}", self.up), "must not be parallel to the view direction".into()));
        }
        for (k, a) in [("position", self.position), ("look_at", self.look_at), ("up", self.up)] {
            if a.iter().any(|x| !x.is_finite()) {
                p.push((k, format!("{a:?}"), "must be finite".into()));
            }
        }
        p
    }
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

// ---------------------------------------------------------------- defaults

impl Default for Scene {
    fn default() -> Self {
        presets::default_scene()
    }
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

impl Default for ColourParams {
    fn default() -> Self {
        Self {
            mode: ColourMode::Physical,
            noise_km: 8.0,
            noise_freq: 0.02,
            colormap: presets::report_colormap(),
        }
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
            half_emission: false,
            cycles_shell: true,
            // OpenVDB's and Houdini's default; read by OpenVDB 10-12,
            // Blender 5 and our reader; writes ~8x faster than ZIP, same size.
            compression: Compression::BloscActiveMask,
            prune: DEFAULT_PRUNE,
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
        Self { width: 640, height: 360, spp: 16, exposure: 3.0 }
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

pub mod presets {
    //! Built-in scenes: `default` (three sheets, as in the report's final
    //! image) and `seed2014` (the report's final scene parameters).
    use super::*;

    /// Names accepted by `aurora scene NAME` and as a scene argument.
    pub const NAMES: &[&str] = &["default", "seed2014"];

    pub fn by_name(name: &str) -> Option<Scene> {
        match name {
            "default" => Some(default_scene()),
            "seed2014" => Some(seed2014()),
            _ => None,
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

    /// Three sheets one behind the other, seen from the ground to the south.
    pub fn default_scene() -> Scene {
        let sheet = |cx: f64, cy: f64, rot: f64, flux: f64, e0: f64, seed: u64| Curtain {
            center: [cx, cy],
            rotation_deg: rot,
            energy_flux: flux,
            char_energy_kev: e0,
            seed,
            ..Curtain::default()
        };
        Scene {
            seed: 2014,
            curtains: vec![
                sheet(-20.0, 0.0, 4.0, 6.0, 4.0, 1),
                sheet(25.0, 45.0, -6.0, 4.0, 2.5, 2),
                sheet(-5.0, 95.0, 2.0, 3.0, 1.5, 3),
            ],
            footprint: FootprintParams::default(),
            beams: BeamParams::default(),
            colour: ColourParams::default(),
            photons: PhotonParams::default(),
            grid: GridParams::default(),
            camera: Camera::default(),
            render: RenderParams::default(),
            volume: VolumeParams::default(),
            background: Background::default(),
            terrain: Terrain { kind: TerrainKind::Heightfield, ..Terrain::default() },
            animation: AnimationParams::default(),
            atmosphere: AtmosphereParams::default(),
        }
    }

    /// The 2014 report's final scene: 500,000 beams, alpha_D = 25 deg,
    /// delta alpha = 12 deg, beam length 70, dt = 0.004 (at most 250
    /// deflections), photon radius 0.2, air density 0.9 exp(-0.02 h), three
    /// sheets. Report units are taken as km.
    pub fn seed2014() -> Scene {
        let mut s = default_scene();
        s.beams.count = 500_000;
        s.beams.alpha_d_deg = 25.0;
        s.beams.delta_alpha_deg = 12.0;
        s.beams.length_km = 70.0;
        s.beams.dt = 0.004;
        // With s = L dt xi (mean L dt / 2 = 0.14 km) and at most 250 steps a
        // beam travels 35 km on average: starting at 140 km it reaches the
        // green layer (100-120 km), as the report's curtains do.
        s.beams.top_km = 140.0;
        // The report's beams end after 1/dt steps wherever they are: its look
        // needs the straight-line model and its stopping rules.
        s.beams.deposition = Deposition::Csda;
        s.photons.radius_km = 0.2;
        s.grid.voxel_size = VoxelSize::Km(0.2);
        s.grid.density_a = 0.9;
        s.grid.density_b = 0.02;
        s.grid.density_base_km = 90.0;
        s.colour.mode = ColourMode::Colormap;
        s.render.width = 640;
        s.render.height = 438;
        s.render.spp = 8;
        s
    }
}

// ---------------------------------------------------------------- errors

/// A scene that could not be read or is out of range.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: cannot read: {source}")]
    Io { file: String, source: std::io::Error },
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))]
    Invalid(Vec<RangeError>),
}

/// One value outside its allowed range.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeError {
    pub file: String,
    pub line: Option<usize>,
    pub key: String,
    pub value: String,
    pub allowed: String,
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: ", self.file, l)?,
            None => write!(f, "{}: ", self.file)?,
        }
        write!(f, "{} = {} is out of range: {}", self.key, self.value, self.allowed)
    }
}

// ---------------------------------------------------------------- loading

impl Scene {
    /// Parses TOML text (unknown keys are errors), then validates it.
    /// `file` names the source in messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        check_shapes(text, file)?;
        let scene: Scene = toml::from_str(text)
            .map_err(|e| SceneError::Parse { file: file.to_string(), message: e.to_string() })?;
        scene.validate(file, Some(text))?;
        Ok(scene)
    }

    /// Reads a scene file, or a preset by name (`default`, `seed2014`).
    pub fn load(path_or_preset: &str) -> Result<Scene, SceneError> {
        if let Some(s) = presets::by_name(path_or_preset) {
            if !Path::new(path_or_preset).exists() {
                return Ok(s);
            }
        }
        let text = std::fs::read_to_string(path_or_preset)
            .map_err(|source| SceneError::Io { file: path_or_preset.to_string(), source })?;
        Self::from_toml_str(&text, path_or_preset)
    }

    /// The scene as TOML, as `aurora scene default` prints it.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene always serialises")
    }

    /// 64-bit FNV-1a hash of the canonical TOML: identifies a bake's inputs.
    pub fn hash(&self) -> u64 {
        fnv1a(self.to_toml().as_bytes())
    }

    /// The voxel size in km, once resolved (`auto` is resolved by the bake).
    pub fn voxel_size_km(&self) -> Option<f64> {
        match self.grid.voxel_size {
            VoxelSize::Km(v) => Some(v),
            VoxelSize::Auto(_) => None,
        }
    }

    /// Checks every range; `text` (the TOML source) is used to find lines.
    pub fn validate(&self, file: &str, text: Option<&str>) -> Result<(), SceneError> {
        self.validate_with(file, text).map(|_| ())
    }

    /// [`validate`](Self::validate), also returning every check made (the
    /// ranges [`schema`] prints).
    fn validate_with(&self, file: &str, text: Option<&str>) -> Result<Vec<(String, schema::Allowed)>, SceneError> {
        let mut v = Validator { file, text, errors: Vec::new(), checks: Vec::new() };
        if self.curtains.is_empty() {
            v.push(None, "curtain", "[]".into(), "at least one [[curtain]] table is required".into());
        }
        for (i, c) in self.curtains.iter().enumerate() {
            let t = Some(("curtain", i));
            // At most 10^4 km: beyond that the flat ground is meaningless and
            // a single beam's photon power (f32) can overflow.
            v.range(t, "length", c.length, 0.0, 1e4, false);
            v.range(t, "width", c.width, 0.0, 1e4, false);
            v.range(t, "energy_flux", c.energy_flux, 0.0, 1e4, false);
            v.range(t, "char_energy_kev", c.char_energy_kev, 0.05, 100.0, true);
            v.range(t, "soft_fraction", c.soft_fraction, 0.0, 1.0, true);
            v.range(t, "soft_energy_kev", c.soft_energy_kev, 0.01, 100.0, true);
            v.range(t, "beam_weight", c.beam_weight, 0.0, 1e9, false);
            v.range(t, "bend_km", c.bend_km, 0.0, 1e4, true);
            v.finite(t, "rotation_deg", c.rotation_deg);
            // Within 10^4 km of the origin, like the curtain's size: the flat
            // ground means nothing beyond, and photon positions are f32 (at
            // 10^20 km their spacing would exceed the aurora).
            if c.center.iter().any(|x| !(x.is_finite() && x.abs() <= 1e4)) {
                v.push(t, "center", format!("{:?}", c.center), "each coordinate must be in [-1e4, 1e4] km".into());
            }
            v.allow(t, "center", schema::Allowed::Rule("each coordinate in [-1e4, 1e4] km".into()));
            v.allow(t, "bend_km", schema::Allowed::Rule("in [0, 1e4], less than width / 2".into()));
            if c.bend_km * 2.0 >= c.width {
                v.push(t, "bend_km", c.bend_km.to_string(), format!("must be less than width / 2 = {}", c.width / 2.0));
            }
        }
        if self.curtains.is_empty() {
            // Record the per-curtain ranges from a default curtain.
            let one = Scene { curtains: vec![Curtain::default()], ..self.clone() };
            if let Ok(c) = one.validate_with(file, None) {
                for (k, a) in c.into_iter().filter(|(k, _)| k.starts_with("curtain.")) {
                    v.checks.push((k, a));
                }
            }
        }
        if self.curtains.iter().all(|c| c.beam_weight <= 0.0) && !self.curtains.is_empty() {
            v.push(Some(("curtain", 0)), "beam_weight", "0".into(), "at least one curtain needs beam_weight > 0".into());
        }
        let f = &self.footprint;
        let t = Some(("footprint", 0));
        v.allow(t, "resolution", schema::Allowed::Rule("each side in [8, 4096]".into()));
        // Each side: a 10^8 x 8 footprint would pass a check of the smaller one.
        if f.resolution.iter().any(|&n| !(8..=4096).contains(&n)) {
            v.push(t, "resolution", format!("{:?}", f.resolution), "each side must be in [8, 4096]".into());
        }
        v.range(t, "steps", f.steps as f64, 0.0, 10_000.0, true);
        v.range(t, "dt", f.dt, 0.0, 1e6, false);
        v.range(t, "pressure_iterations", f.pressure_iterations as f64, 0.0, 10_000.0, true);
        v.range(t, "band_fraction", f.band_fraction, 0.0, 1.0, false);
        v.range(t, "velocity_waves", f.velocity_waves, 0.0, 1e3, true);
        v.range(t, "velocity_amplitude", f.velocity_amplitude, 0.0, 1e6, true);
        v.range(t, "density_waves", f.density_waves, 0.0, 1e3, true);
        v.range(t, "bend_wavelength", f.bend_wavelength, 0.0, 1e3, false);
        v.range(t, "threshold", f.threshold, 0.0, 1.0, false);

        let a = &self.animation;
        let t = Some(("animation", 0));
        v.range(t, "fps", a.fps, 0.0, 1000.0, false);
        v.range(t, "time_s", a.time_s, 0.0, 1e7, true);
        v.range(t, "fold_speed_kms", a.fold_speed_kms, -100.0, 100.0, true);
        v.allow(t, "fold_breathing", schema::Allowed::Range { min: 0.0, max: 1.0, min_inclusive: true, max_inclusive: false });
        v.allow(t, "pulsation_period_s", schema::Allowed::Rule("[min, max] with 0 < min <= max <= 10000".into()));
        if !(0.0..1.0).contains(&a.fold_breathing) {
            v.push(t, "fold_breathing", fmt_num(a.fold_breathing), "must be in [0, 1)".into());
        }
        v.range(t, "fold_breathing_period_s", a.fold_breathing_period_s, 0.0, 1e6, false);
        v.range(t, "bend_speed_kms", a.bend_speed_kms, -100.0, 100.0, true);
        v.range(t, "bend_change_hz", a.bend_change_hz, 0.0, 100.0, true);
        v.range(t, "drift_km", a.drift_km, 0.0, 1e3, true);
        v.range(t, "drift_period_s", a.drift_period_s, 0.0, 1e6, false);
        v.range(t, "ray_speed_kms", a.ray_speed_kms, -100.0, 100.0, true);
        v.range(t, "pulsation", a.pulsation, 0.0, 1.0, true);
        v.range(t, "pulsation_patch_km", a.pulsation_patch_km, 0.0, 1e4, false);
        let [p0, p1] = a.pulsation_period_s;
        if !(p0.is_finite() && p1.is_finite() && p0 > 0.0 && p1 >= p0 && p1 <= 1e4) {
            v.push(t, "pulsation_period_s", format!("[{}, {}]", fmt_num(p0), fmt_num(p1)), "must be [min, max] with 0 < min <= max <= 10000".into());
        }

        let b = &self.beams;
        let t = Some(("beams", 0));
        v.range(t, "count", b.count as f64, 1.0, 1e8, true);
        v.range(t, "target_noise", b.target_noise, 0.0, 1.0, true);
        v.range(t, "top_km", b.top_km, 80.0, 1000.0, true);
        v.range(t, "top_noise_km", b.top_noise_km, 0.0, 100.0, true);
        v.range(t, "top_noise_freq", b.top_noise_freq, 0.0, 1e3, true);
        v.allow(t, "alpha_d_deg", schema::Allowed::Range { min: 0.0, max: 90.0, min_inclusive: true, max_inclusive: false });
        v.allow(t, "delta_alpha_deg", schema::Allowed::Rule("in [0, beams.alpha_d_deg]".into()));
        if !(b.alpha_d_deg >= 0.0 && b.alpha_d_deg < 90.0) {
            v.push(t, "alpha_d_deg", b.alpha_d_deg.to_string(), "must be in [0, 90) degrees: at 90 a beam no longer moves along B".into());
        }
        if !(b.delta_alpha_deg >= 0.0 && b.delta_alpha_deg <= b.alpha_d_deg) {
            v.push(t, "delta_alpha_deg", b.delta_alpha_deg.to_string(), format!("must be in [0, alpha_d_deg = {}]", b.alpha_d_deg));
        }
        v.finite_pos(t, "length_km", b.length_km);
        v.range(t, "dt", b.dt, 1e-6, 1.0, true);
        v.range(t, "b_inclination_deg", b.b_inclination_deg, 10.0, 90.0, true);
        v.finite(t, "b_declination_deg", b.b_declination_deg);

        let c = &self.colour;
        let t = Some(("colour", 0));
        v.range(t, "noise_km", c.noise_km, 0.0, 200.0, true);
        v.range(t, "noise_freq", c.noise_freq, 0.0, 1e3, true);
        v.allow(t, "colormap", schema::Allowed::Rule("rows of [altitude_km, r, g, b], at least 2, altitudes ascending, colours >= 0 (mode = \"colormap\")".into()));
        if c.mode == ColourMode::Colormap {
            if c.colormap.len() < 2 {
                v.push(t, "colormap", format!("{} rows", c.colormap.len()), "needs at least 2 rows of [altitude_km, r, g, b]".into());
            }
            for (i, w) in c.colormap.windows(2).enumerate() {
                if !(w[1][0] > w[0][0]) {
                    v.push(t, "colormap", format!("row {}: {}", i + 1, w[1][0]), "altitudes must be strictly ascending".into());
                }
            }
            for (i, r) in c.colormap.iter().enumerate() {
                if r.iter().any(|x| !x.is_finite()) || r[1..].iter().any(|&x| !(0.0..=MAX_COLORMAP_VALUE).contains(&x)) {
                    v.push(t, "colormap", format!("row {i}: {r:?}"), format!("values must be finite, colours in [0, {MAX_COLORMAP_VALUE:e}]"));
                }
            }
        }

        let p = &self.photons;
        let t = Some(("photons", 0));
        v.finite_pos(t, "radius_km", p.radius_km);
        v.range(t, "cutoff", p.cutoff, 1.0, 6.0, true);
        v.range(t, "radius_noise", p.radius_noise, 0.0, 0.9, true);
        v.range(t, "radius_noise_freq", p.radius_noise_freq, 0.0, 1e3, true);

        let g = &self.grid;
        let t = Some(("grid", 0));
        v.allow(t, "voxel_size", schema::Allowed::Rule("a number of km > 0, or \"auto\"".into()));
        if let VoxelSize::Km(s) = g.voxel_size {
            v.finite_pos(t, "voxel_size", s);
        }
        v.range(t, "density_a", g.density_a, 0.0, 1e6, true);
        v.range(t, "density_b", g.density_b, 0.0, 10.0, true);
        v.finite(t, "density_base_km", g.density_base_km);
        v.range(t, "prune", g.prune, 0.0, MAX_PRUNE, true);

        let t = Some(("camera", 0));
        v.allow(t, "fov_deg", schema::Allowed::Rule("in (0, 180); in (0, 360] for projection = \"fisheye\"".into()));
        v.allow(t, "ortho_height", schema::Allowed::Range { min: 0.0, max: f64::INFINITY, min_inclusive: false, max_inclusive: false });
        v.allow(t, "look_at", schema::Allowed::Rule("finite, differs from camera.position".into()));
        v.allow(t, "up", schema::Allowed::Rule("finite, not parallel to look_at - position".into()));
        v.allow(t, "position", schema::Allowed::Rule("finite".into()));
        for (key, value, allowed) in self.camera.problems() {
            v.push(t, key, value, allowed);
        }
        let r = &self.render;
        let t = Some(("render", 0));
        v.range(t, "width", r.width as f64, 1.0, MAX_IMAGE_SIDE as f64, true);
        v.range(t, "height", r.height as f64, 1.0, MAX_IMAGE_SIDE as f64, true);
        v.range(t, "spp", r.spp as f64, 1.0, MAX_SPP as f64, true);
        v.range(t, "exposure", r.exposure, -50.0, 50.0, true);
        let vol = &self.volume;
        let t = Some(("volume", 0));
        v.range(t, "density_scale", vol.density_scale, 0.0, 1e9, true);
        v.range(t, "emission_scale", vol.emission_scale, 0.0, 1e9, true);
        let t = Some(("background", 0));
        // Bounded so that pixels (f32) stay finite.
        v.allow(t, "radiance", schema::Allowed::Range { min: 0.0, max: 1e9, min_inclusive: true, max_inclusive: true });
        if self.background.radiance.iter().any(|x| !(0.0..=1e9).contains(x)) {
            v.push(t, "radiance", format!("{:?}", self.background.radiance), "components must be in [0, 1e9]".into());
        }
        // Beyond m = 8 the 0.45 slope of the star counts no longer holds
        // (and the count passes 38,000).
        v.range(t, "limiting_magnitude", self.background.limiting_magnitude, -1.5, 8.0, true);
        v.range(t, "star_brightness", self.background.star_brightness, 0.0, 1e6, true);
        let ter = &self.terrain;
        let t = Some(("terrain", 0));
        v.finite(t, "height", ter.height);
        v.allow(t, "albedo", schema::Allowed::Range { min: 0.0, max: 1.0, min_inclusive: true, max_inclusive: true });
        v.allow(t, "extent", schema::Allowed::Rule("[x0, y0, x1, y1] with x1 > x0 and y1 > y0".into()));
        if ter.albedo.iter().any(|x| !(0.0..=1.0).contains(x)) {
            v.push(t, "albedo", format!("{:?}", ter.albedo), "components must be in [0, 1]".into());
        }
        v.range(t, "mountain_height", ter.mountain_height, 0.0, 100.0, true);
        v.finite_pos(t, "mountain_scale", ter.mountain_scale);
        if !(ter.extent[2] > ter.extent[0] && ter.extent[3] > ter.extent[1]) {
            v.push(t, "extent", format!("{:?}", ter.extent), "must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0".into());
        }

        if v.errors.is_empty() {
            Ok(v.checks)
        } else {
            Err(SceneError::Invalid(v.errors))
        }
    }
}

/// Refuses arrays of the wrong length before serde sees them (serde fills a
/// fixed-size array from the first N values of a longer TOML array and drops
/// the rest silently: `center = [-20, 0, 999]` would bake at (-20, 0)).
///
/// The expected shapes come from the scene's own defaults, so every key added
/// later is covered: an array of numbers there is a fixed-size array (its
/// length is the one required); an array of arrays (the colour map) has rows
/// of the default row's length; an array of tables (`[[curtain]]`) is checked
/// table by table against a default curtain.
pub fn check_shapes(text: &str, file: &str) -> Result<(), SceneError> {
    let user: toml::Table = match text.parse() {
        Ok(t) => t,
        // Syntax errors are reported by the parser proper, with its message.
        Err(_) => return Ok(()),
    };
    let mut reference = Scene::default();
    reference.curtains = vec![Curtain::default()];
    let reference = toml::Table::try_from(&reference).expect("a scene serialises to a table");
    let mut v = Validator { file, text: Some(text), errors: Vec::new(), checks: Vec::new() };
    shapes_table(&user, &reference, None, &mut v);
    if v.errors.is_empty() {
        Ok(())
    } else {
        Err(SceneError::Invalid(v.errors))
    }
}

fn shapes_table(user: &toml::Table, reference: &toml::Table, table: Option<(&str, usize)>, v: &mut Validator<'_>) {
    use toml::Value;
    for (key, uv) in user {
        let Some(rv) = reference.get(key) else { continue };
        match (uv, rv) {
            (Value::Table(ut), Value::Table(rt)) if table.is_none() => shapes_table(ut, rt, Some((key.as_str(), 0)), v),
            (Value::Array(ua), Value::Array(ra)) => match ra.first() {
                Some(Value::Table(rt)) if table.is_none() => {
                    for (i, u) in ua.iter().enumerate() {
                        if let Value::Table(ut) = u {
                            shapes_table(ut, rt, Some((key.as_str(), i)), v);
                        }
                    }
                }
                Some(Value::Array(row)) => {
                    for (i, u) in ua.iter().enumerate() {
                        if let Value::Array(ur) = u {
                            if ur.len() != row.len() {
                                v.push(table, key, format!("row {i}: {u}"), format!("every row must have {} values", row.len()));
                            }
                        }
                    }
                }
                Some(_) if ua.len() != ra.len() => {
                    v.push(table, key, uv.to_string(), format!("must have exactly {} values, not {}", ra.len(), ua.len()));
                }
                _ => {}
            },
            _ => {}
        }
    }
}

/// FNV-1a, 64 bit: a stable hash with no dependency (scene identity only).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

struct Validator<'a> {
    file: &'a str,
    text: Option<&'a str>,
    errors: Vec<RangeError>,
    /// Every check made, as (key, allowed range), for [`schema`].
    checks: Vec<(String, schema::Allowed)>,
}

impl Validator<'_> {
    fn push(&mut self, table: Option<(&str, usize)>, key: &str, value: String, allowed: String) {
        let line = self.text.and_then(|t| find_key_line(t, table, key));
        let key = match table {
            Some(("curtain", i)) => format!("curtain[{i}].{key}"),
            Some((t, _)) => format!("{t}.{key}"),
            None => key.to_string(),
        };
        self.errors.push(RangeError { file: self.file.to_string(), line, key, value, allowed });
    }
    fn key(t: Option<(&str, usize)>, key: &str) -> String {
        match t {
            Some((t, _)) => format!("{t}.{key}"),
            None => key.to_string(),
        }
    }
    /// Records an allowed range or rule for the schema (no check).
    fn allow(&mut self, t: Option<(&str, usize)>, key: &str, a: schema::Allowed) {
        let k = Self::key(t, key);
        if !self.checks.iter().any(|(c, _)| *c == k) {
            self.checks.push((k, a));
        }
    }
    fn range(&mut self, t: Option<(&str, usize)>, key: &str, x: f64, lo: f64, hi: f64, lo_inclusive: bool) {
        self.allow(t, key, schema::Allowed::Range { min: lo, max: hi, min_inclusive: lo_inclusive, max_inclusive: true });
        let ok = x.is_finite() && (if lo_inclusive { x >= lo } else { x > lo }) && x <= hi;
        if !ok {
            let open = if lo_inclusive { "[" } else { "(" };
            self.push(t, key, fmt_num(x), format!("must be in {open}{}, {}]", fmt_num(lo), fmt_num(hi)));
        }
    }
    fn finite_pos(&mut self, t: Option<(&str, usize)>, key: &str, x: f64) {
        self.allow(t, key, schema::Allowed::Range { min: 0.0, max: f64::INFINITY, min_inclusive: false, max_inclusive: false });
        if !(x.is_finite() && x > 0.0) {
            self.push(t, key, fmt_num(x), "must be a finite number > 0".into());
        }
    }
    fn finite(&mut self, t: Option<(&str, usize)>, key: &str, x: f64) {
        self.allow(t, key, schema::Allowed::Rule("finite".into()));
        if !x.is_finite() {
            self.push(t, key, fmt_num(x), "must be finite".into());
        }
    }
}

fn fmt_num(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}

/// 1-based line of `key = ...` inside `[table]` (or the `index`-th
/// `[[table]]`), or at the top level when `table` is None. A plain text scan:
/// enough to point a user at the line, not a TOML parser.
pub fn find_key_line(text: &str, table: Option<(&str, usize)>, key: &str) -> Option<usize> {
    let mut current: Option<(String, usize)> = None;
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    for (ln, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if let Some(rest) = line.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let c = counts.entry(name.clone()).or_insert(0);
            current = Some((name, *c));
            *c += 1;
            continue;
        }
        if let Some(rest) = line.strip_prefix('[') {
            let name = rest.split(']').next().unwrap_or("").trim().to_string();
            current = Some((name, 0));
            continue;
        }
        let here = match (&current, table) {
            (None, None) => true,
            (Some((n, i)), Some((t, j))) => n == t && *i == j,
            _ => false,
        };
        if here {
            if let Some((k, _)) = line.split_once('=') {
                if k.trim().trim_matches('"') == key {
                    return Some(ln + 1);
                }
            }
        }
    }
    None
}

pub mod schema {
    //! `aurora scene --schema`: every scene key, its default and its allowed
    //! range, as JSON. One source: defaults are `Scene::default()` (what a
    //! missing table or key gives) serialised, and ranges are the checks
    //! [`Scene::validate`] makes, recorded as it validates the default
    //! scene (`Validator::allow`): a range changed there changes here.
    use super::*;
    use serde_json::{json, Map, Value};

    /// What a key accepts.
    #[derive(Clone, Debug, PartialEq)]
    pub enum Allowed {
        Range { min: f64, max: f64, min_inclusive: bool, max_inclusive: bool },
        Rule(String),
    }

    fn num(x: f64) -> Value {
        if x.is_finite() {
            json!(x)
        } else {
            json!(if x > 0.0 { "inf" } else { "-inf" })
        }
    }

    /// Allowed values of the enum-valued keys: every key whose default is a
    /// string is given a value no enum has, and the parser's own message
    /// ("expected one of `a`, `b`") lists the variants. No list to keep in
    /// step by hand: a variant added to an enum appears here (a test checks
    /// each value parses).
    pub fn enum_values() -> Vec<(String, Value)> {
        let defaults = serde_json::to_value(Scene::default()).expect("a scene serialises");
        let mut out = Vec::new();
        let Value::Object(top) = defaults else { return out };
        for (table, fields) in top {
            let fields = if table == "curtain" { serde_json::to_value(Curtain::default()).expect("serialises") } else { fields };
            let Value::Object(fields) = fields else { continue };
            for (key, d) in fields {
                if !d.is_string() {
                    continue;
                }
                let header = if table == "curtain" { "[[curtain]]".to_string() } else { format!("[{table}]") };
                let text = format!("{header}\n{key} = \"not a variant\"\n");
                let Err(SceneError::Parse { message, .. }) = Scene::from_toml_str(&text, "enum") else { continue };
                let Some(list) = message.split("expected one of ").nth(1).or_else(|| message.split("expected ").nth(1)) else { continue };
                let values: Vec<Value> = list
                    .split('`')
                    .enumerate()
                    .filter(|(i, _)| i % 2 == 1)
                    .map(|(_, v)| json!(v))
                    .collect();
                if !values.is_empty() {
                    out.push((format!("{table}.{key}"), Value::Array(values)));
                }
            }
        }
        out
    }

    /// The schema: `{table: {key: {"default": .., "min"/"max"/.. or "rule"
    /// or "values"}}}`; `curtain` describes one `[[curtain]]` entry
    /// (defaults of `Curtain::default()`), top-level keys sit under `""`.
    /// Where a key inside a table that is present defaults differently from
    /// a missing table (`terrain.kind`), `default_in_table` says so.
    pub fn schema() -> Value {
        let scene = Scene::default();
        let checks = scene.validate_with("default", None).expect("the default scene validates");
        let defaults = serde_json::to_value(&scene).expect("a scene serialises");
        let in_table: Value = json!({
            "footprint": FootprintParams::default(), "beams": BeamParams::default(), "colour": ColourParams::default(),
            "photons": PhotonParams::default(), "grid": GridParams::default(), "camera": Camera::default(),
            "render": RenderParams::default(), "volume": VolumeParams::default(), "background": Background::default(),
            "terrain": Terrain::default(), "atmosphere": AtmosphereParams::default(), "animation": AnimationParams::default(),
        });
        let enums = enum_values();
        let mut out = Map::new();
        let Value::Object(top) = defaults else { unreachable!() };
        for (table, value) in top {
            let (name, fields) = match (table.as_str(), value) {
                ("curtain", _) => ("curtain".to_string(), serde_json::to_value(Curtain::default()).expect("serialises")),
                (_, v @ Value::Object(_)) => (table.clone(), v),
                (_, v) => {
                    let mut m = Map::new();
                    m.insert(table.clone(), v);
                    (String::new(), Value::Object(m))
                }
            };
            let Value::Object(fields) = fields else { continue };
            let entry = out.entry(name.clone()).or_insert_with(|| Value::Object(Map::new()));
            for (key, default) in fields {
                let full = if name.is_empty() { key.clone() } else { format!("{name}.{key}") };
                let mut k = Map::new();
                k.insert("default".into(), default.clone());
                if let Some(d) = in_table.get(&name).and_then(|t| t.get(&key)) {
                    if *d != default {
                        k.insert("default_in_table".into(), d.clone());
                    }
                }
                match checks.iter().find(|(c, _)| *c == full).map(|(_, a)| a) {
                    Some(Allowed::Range { min, max, min_inclusive, max_inclusive }) => {
                        k.insert("min".into(), num(*min));
                        k.insert("max".into(), num(*max));
                        k.insert("min_inclusive".into(), json!(min_inclusive));
                        k.insert("max_inclusive".into(), json!(max_inclusive));
                    }
                    Some(Allowed::Rule(r)) => {
                        k.insert("rule".into(), json!(r));
                    }
                    None => {}
                }
                if let Some((_, v)) = enums.iter().find(|(e, _)| *e == full) {
                    k.insert("values".into(), v.clone());
                }
                entry.as_object_mut().expect("object").insert(key, Value::Object(k));
            }
        }
        Value::Object(out)
    }

    /// The schema as `aurora scene --schema` prints it (sorted keys, two
    /// spaces, trailing newline).
    pub fn schema_json() -> String {
        serde_json::to_string_pretty(&schema()).expect("serialises") + "\n"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schema_has_every_key_with_default_and_range() {
        let s = schema::schema();
        assert_eq!(s["camera"]["fov_deg"]["default"], 75.0);
        assert!(s["camera"]["fov_deg"]["rule"].as_str().unwrap().contains("360"));
        assert_eq!(s["render"]["width"]["max"], MAX_IMAGE_SIDE as f64);
        assert_eq!(s["grid"]["prune"]["max"], MAX_PRUNE);
        assert_eq!(s["curtain"]["char_energy_kev"]["min"], 0.05);
        assert_eq!(s["terrain"]["kind"]["default"], "heightfield");
        assert_eq!(s["terrain"]["kind"]["default_in_table"], "none");
        assert_eq!(s[""]["seed"]["default"], 2014);
        // Every numeric key has a range or a rule, and every enum value parses.
        for (table, keys) in s.as_object().unwrap() {
            for (key, k) in keys.as_object().unwrap() {
                let d = &k["default"];
                if d.is_number() && key != "seed" && key != "count" || d.is_array() {
                    assert!(k.get("min").is_some() || k.get("rule").is_some() || table == "" , "{table}.{key} has no range");
                }
            }
        }
        for (key, values) in schema::enum_values() {
            let (t, k) = key.split_once('.').unwrap();
            for v in values.as_array().unwrap() {
                let text = format!("[{t}]\n{k} = {v}\n");
                assert!(Scene::from_toml_str(&text, "e.toml").is_ok() || t == "colour" || t == "terrain", "{text}");
            }
        }
    }

    #[test]
    fn presets_validate_and_round_trip_through_toml() {
        for name in presets::NAMES {
            let s = presets::by_name(name).unwrap();
            s.validate(name, None).unwrap();
            let text = s.to_toml();
            let back = Scene::from_toml_str(&text, name).unwrap();
            assert_eq!(back, s, "{name}");
        }
    }

    #[test]
    fn unknown_key_is_an_error_naming_key_and_line() {
        let e = Scene::from_toml_str("seed = 1\n[beams]\ncount = 5\nbogus = 3\n", "x.toml").unwrap_err();
        let m = e.to_string();
        assert!(m.contains("x.toml") && m.contains("bogus") && m.contains("line 4"), "{m}");
    }

    #[test]
    fn out_of_range_names_file_line_key_value_and_range() {
        let text = "[beams]\ncount = 100\nalpha_d_deg = 95.0\n";
        let m = Scene::from_toml_str(text, "s.toml").unwrap_err().to_string();
        assert!(m.contains("s.toml:3: beams.alpha_d_deg = 95"), "{m}");
        assert!(m.contains("[0, 90)"), "{m}");
        let m = Scene::from_toml_str("[photons]\nradius_km = -1\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("s.toml:2: photons.radius_km = -1"), "{m}");
        let m = Scene::from_toml_str("[beams]\ncount = 0\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("beams.count = 0") && m.contains("[1, "), "{m}");
        // Validity does not depend on the machine: a tiny voxel is valid here and
        // refused by the bake's memory budget (crate::budget).
        assert!(Scene::from_toml_str("[grid]\nvoxel_size = 0.0001\n", "s.toml").is_ok());
        let m = Scene::from_toml_str("[footprint]\nresolution = [100000000, 8]\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("s.toml:2: footprint.resolution") && m.contains("[8, 4096]"), "{m}");
    }

    #[test]
    fn render_only_scene_takes_defaults_elsewhere() {
        let text = "[camera]\nposition = [0, -5, 0]\nlook_at = [0, 0, 0]\nprojection = \"orthographic\"\northo_height = 4.0\n[render]\nwidth = 8\nheight = 4\nspp = 1\n";
        let s = Scene::from_toml_str(text, "r.toml").unwrap();
        assert_eq!(s.camera.projection, Projection::Orthographic);
        assert_eq!(s.render.width, 8);
        assert_eq!(s.curtains.len(), 3);
    }

    #[test]
    fn prune_budget_outside_its_range_is_refused() {
        let m = Scene::from_toml_str("[grid]\nprune = 0.7\n", "p.toml").unwrap_err().to_string();
        assert!(m.contains("p.toml:2: grid.prune = 0.7") && m.contains("[0, 0.5]"), "{m}");
        assert!(Scene::from_toml_str("[grid]\nprune = 0.01\n", "p.toml").is_ok());
    }

    #[test]
    fn arrays_of_the_wrong_length_are_refused_naming_key_and_line() {
        let cases = [
            ("[[curtain]]\ncenter = [-20.0, 0.0, 999.0]\n", "curtain[0].center", 2),
            ("[camera]\nposition = [0.0, -90.0, 1.0, 5.0]\n", "camera.position", 2),
            ("[camera]\nup = [0.0, 1.0]\n", "camera.up", 2),
            ("[footprint]\nresolution = [64, 32, 8]\n", "footprint.resolution", 2),
            ("[colour]\nmode = \"colormap\"\ncolormap = [[90.0, 0.1, 0.2, 0.3, 9.0], [100.0, 0.1, 0.2, 0.3]]\n", "colour.colormap", 3),
            ("[terrain]\nextent = [0.0, 0.0, 1.0]\n", "terrain.extent", 2),
        ];
        for (text, key, line) in cases {
            let e = Scene::from_toml_str(text, "s.toml").unwrap_err().to_string();
            assert!(e.contains(key) && e.contains(&format!("s.toml:{line}:")), "{text}: {e}");
        }
        // Right lengths still parse.
        Scene::from_toml_str("[[curtain]]\ncenter = [-20.0, 0.0]\n[camera]\nposition = [0.0, -90.0, 1.0]\n", "s.toml").unwrap();
    }

    #[test]
    fn atmosphere_and_deposition_models_parse_and_unknown_names_are_refused() {
        let s = Scene::from_toml_str("[atmosphere]\nmodel = \"us1976\"\n[beams]\ndeposition = \"sampled\"\n", "m.toml").unwrap();
        assert_eq!(s.atmosphere.model, AtmosphereModel::Us1976);
        assert_eq!(s.beams.deposition, Deposition::Sampled);
        let d = Scene::default();
        assert_eq!((d.atmosphere.model, d.beams.deposition), (AtmosphereModel::Nrlmsis21, Deposition::Expected));
        let m = Scene::from_toml_str("[atmosphere]\nmodel = \"msis00\"\n", "m.toml").unwrap_err().to_string();
        assert!(m.contains("m.toml") && m.contains("msis00") && m.contains("nrlmsis21") && m.contains("us1976"), "{m}");
        let m = Scene::from_toml_str("[beams]\ndeposition = \"mean\"\n", "m.toml").unwrap_err().to_string();
        assert!(m.contains("mean") && m.contains("expected") && m.contains("sampled") && m.contains("csda"), "{m}");
    }

    #[test]
    fn voxel_size_auto_parses() {
        let s = Scene::from_toml_str("[grid]\nvoxel_size = \"auto\"\n", "a.toml").unwrap();
        assert_eq!(s.grid.voxel_size, VoxelSize::Auto(AutoTag::Auto));
        let s = Scene::from_toml_str("[grid]\nvoxel_size = 1\n", "a.toml").unwrap();
        assert_eq!(s.grid.voxel_size, VoxelSize::Km(1.0));
        let e = Scene::from_toml_str("[grid]\nvoxel_size = \"AUTO\"\n", "a.toml").unwrap_err().to_string();
        assert!(e.contains("voxel_size") && e.contains("\"auto\"") && !e.contains("untagged"), "{e}");
    }
}
