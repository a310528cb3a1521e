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

/// Bytes of memory a dense bounding box may need at most before the scene is
/// refused: the machine's physical memory (MemTotal; 24 GiB if unknown). The
/// bake allocates per leaf, but a dense box beyond this means the voxel size
/// is wrong by orders of magnitude, and a renderer that densifies would fail.
pub fn max_dense_bytes() -> f64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|m| {
            m.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map(|kib| kib * 1024.0)
        .unwrap_or(24.0 * (1u64 << 30) as f64)
}

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
    /// How beam starts are placed over the footprint (`crate::starts`).
    pub starts: BeamStarts,
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
}

/// Voxel size: a number of km, or "auto" (from the camera).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum VoxelSize {
    Km(f64),
    Auto(AutoTag),
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AutoTag {
    Auto,
}

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
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Camera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    pub projection: Projection,
    /// Vertical field of view, degrees (perspective).
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
            gather: GatherMethod::Kdtree,
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
            compression: Compression::ZipActiveMask,
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
        Self { radiance: [0.0, 0.0, 0.0] }
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
        let mut v = Validator { file, text, errors: Vec::new() };
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
            v.finite(t, "center", c.center[0] + c.center[1]);
            if c.bend_km * 2.0 >= c.width {
                v.push(t, "bend_km", c.bend_km.to_string(), format!("must be less than width / 2 = {}", c.width / 2.0));
            }
        }
        if self.curtains.iter().all(|c| c.beam_weight <= 0.0) && !self.curtains.is_empty() {
            v.push(Some(("curtain", 0)), "beam_weight", "0".into(), "at least one curtain needs beam_weight > 0".into());
        }
        let f = &self.footprint;
        let t = Some(("footprint", 0));
        v.range(t, "resolution", f.resolution[0].min(f.resolution[1]) as f64, 8.0, 4096.0, true);
        v.range(t, "steps", f.steps as f64, 0.0, 10_000.0, true);
        v.range(t, "dt", f.dt, 0.0, 1e6, false);
        v.range(t, "pressure_iterations", f.pressure_iterations as f64, 0.0, 10_000.0, true);
        v.range(t, "band_fraction", f.band_fraction, 0.0, 1.0, false);
        v.range(t, "velocity_waves", f.velocity_waves, 0.0, 1e3, true);
        v.range(t, "velocity_amplitude", f.velocity_amplitude, 0.0, 1e6, true);
        v.range(t, "density_waves", f.density_waves, 0.0, 1e3, true);
        v.range(t, "bend_wavelength", f.bend_wavelength, 0.0, 1e3, false);
        v.range(t, "threshold", f.threshold, 0.0, 1.0, false);

        let b = &self.beams;
        let t = Some(("beams", 0));
        v.range(t, "count", b.count as f64, 1.0, 1e8, true);
        v.range(t, "target_noise", b.target_noise, 0.0, 1.0, true);
        v.range(t, "top_km", b.top_km, 80.0, 1000.0, true);
        v.range(t, "top_noise_km", b.top_noise_km, 0.0, 100.0, true);
        v.range(t, "top_noise_freq", b.top_noise_freq, 0.0, 1e3, true);
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
                if r.iter().any(|x| !x.is_finite()) || r[1..].iter().any(|&x| x < 0.0) {
                    v.push(t, "colormap", format!("row {i}: {r:?}"), "values must be finite, colours >= 0".into());
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
        if let VoxelSize::Km(s) = g.voxel_size {
            v.finite_pos(t, "voxel_size", s);
        }
        v.range(t, "density_a", g.density_a, 0.0, 1e6, true);
        v.range(t, "density_b", g.density_b, 0.0, 10.0, true);
        v.finite(t, "density_base_km", g.density_base_km);
        v.range(t, "prune", g.prune, 0.0, MAX_PRUNE, true);

        let cam = &self.camera;
        let t = Some(("camera", 0));
        if !(cam.fov_deg > 0.0 && cam.fov_deg < 180.0) {
            v.push(t, "fov_deg", fmt_num(cam.fov_deg), "must be in (0, 180)".into());
        }
        v.finite_pos(t, "ortho_height", cam.ortho_height);
        let dir = [cam.look_at[0] - cam.position[0], cam.look_at[1] - cam.position[1], cam.look_at[2] - cam.position[2]];
        if dir.iter().all(|d| *d == 0.0) {
            v.push(t, "look_at", format!("{:?}", cam.look_at), "must differ from camera.position".into());
        }
        let cross = [
            dir[1] * cam.up[2] - dir[2] * cam.up[1],
            dir[2] * cam.up[0] - dir[0] * cam.up[2],
            dir[0] * cam.up[1] - dir[1] * cam.up[0],
        ];
        if cross.iter().map(|c| c * c).sum::<f64>() < 1e-18 {
            v.push(t, "up", format!("{:?}", cam.up), "must not be parallel to the view direction".into());
        }
        for (k, a) in [("position", cam.position), ("look_at", cam.look_at), ("up", cam.up)] {
            if a.iter().any(|x| !x.is_finite()) {
                v.push(t, k, format!("{a:?}"), "must be finite".into());
            }
        }
        let r = &self.render;
        let t = Some(("render", 0));
        v.range(t, "width", r.width as f64, 1.0, 16384.0, true);
        v.range(t, "height", r.height as f64, 1.0, 16384.0, true);
        v.range(t, "spp", r.spp as f64, 1.0, 65536.0, true);
        v.range(t, "exposure", r.exposure, -50.0, 50.0, true);
        let vol = &self.volume;
        let t = Some(("volume", 0));
        v.range(t, "density_scale", vol.density_scale, 0.0, 1e9, true);
        v.range(t, "emission_scale", vol.emission_scale, 0.0, 1e9, true);
        let t = Some(("background", 0));
        // Bounded so that pixels (f32) stay finite.
        if self.background.radiance.iter().any(|x| !(0.0..=1e9).contains(x)) {
            v.push(t, "radiance", format!("{:?}", self.background.radiance), "components must be in [0, 1e9]".into());
        }
        let ter = &self.terrain;
        let t = Some(("terrain", 0));
        v.finite(t, "height", ter.height);
        if ter.albedo.iter().any(|x| !(0.0..=1.0).contains(x)) {
            v.push(t, "albedo", format!("{:?}", ter.albedo), "components must be in [0, 1]".into());
        }
        v.range(t, "mountain_height", ter.mountain_height, 0.0, 100.0, true);
        v.finite_pos(t, "mountain_scale", ter.mountain_scale);
        if !(ter.extent[2] > ter.extent[0] && ter.extent[3] > ter.extent[1]) {
            v.push(t, "extent", format!("{:?}", ter.extent), "must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0".into());
        }

        if v.errors.is_empty() {
            if let Some(s) = self.voxel_size_km() {
                // Refuse scenes whose dense bounding box could not be held.
                let (lo, hi) = self.world_bounds();
                let n: f64 = (0..3).map(|i| ((hi[i] - lo[i]) / s).ceil() + 1.0).product();
                let bytes = n * 16.0;
                let limit = max_dense_bytes();
                if bytes > limit {
                    v.push(Some(("grid", 0)), "voxel_size", s.to_string(), format!(
                        "the aurora's bounding box would need {:.1} GiB dense at this voxel size (this machine has {:.1} GiB): use a voxel size of at least {:.3} km",
                        bytes / (1u64 << 30) as f64, limit / (1u64 << 30) as f64,
                        s * (bytes / limit).cbrt()
                    ));
                }
            }
        }
        if v.errors.is_empty() {
            Ok(())
        } else {
            Err(SceneError::Invalid(v.errors))
        }
    }

    /// A conservative world-space box around every curtain: footprint boxes
    /// (rotated), from below the lowest altitude electrons reach (80 km) to the
    /// beams' top, widened by the drift along an inclined B and the kernel.
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        let z0 = 80.0;
        let z1 = self.beams.top_km + self.beams.top_noise_km;
        let tilt = (90.0 - self.beams.b_inclination_deg).to_radians().tan() * (z1 - z0);
        let pad = tilt + self.photons.radius_km * self.photons.cutoff * 2.0;
        let mut lo = [f64::INFINITY, f64::INFINITY, z0 - pad.min(10.0)];
        let mut hi = [f64::NEG_INFINITY, f64::NEG_INFINITY, z1 + self.photons.radius_km * self.photons.cutoff];
        for c in &self.curtains {
            let (s, co) = c.rotation_deg.to_radians().sin_cos();
            for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)] {
                let (u, w) = (a * c.length, b * c.width);
                let x = c.center[0] + u * co - w * s;
                let y = c.center[1] + u * s + w * co;
                lo[0] = lo[0].min(x - pad);
                lo[1] = lo[1].min(y - pad);
                hi[0] = hi[0].max(x + pad);
                hi[1] = hi[1].max(y + pad);
            }
        }
        (lo, hi)
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
    fn range(&mut self, t: Option<(&str, usize)>, key: &str, x: f64, lo: f64, hi: f64, lo_inclusive: bool) {
        let ok = x.is_finite() && (if lo_inclusive { x >= lo } else { x > lo }) && x <= hi;
        if !ok {
            let open = if lo_inclusive { "[" } else { "(" };
            self.push(t, key, fmt_num(x), format!("must be in {open}{}, {}]", fmt_num(lo), fmt_num(hi)));
        }
    }
    fn finite_pos(&mut self, t: Option<(&str, usize)>, key: &str, x: f64) {
        if !(x.is_finite() && x > 0.0) {
            self.push(t, key, fmt_num(x), "must be a finite number > 0".into());
        }
    }
    fn finite(&mut self, t: Option<(&str, usize)>, key: &str, x: f64) {
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

#[cfg(test)]
mod tests {
    use super::*;

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
        let m = Scene::from_toml_str("[grid]\nvoxel_size = 0.0001\n", "s.toml").unwrap_err().to_string();
        assert!(m.contains("grid.voxel_size") && m.contains("GiB"), "{m}");
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
    fn voxel_size_auto_parses() {
        let s = Scene::from_toml_str("[grid]\nvoxel_size = \"auto\"\n", "a.toml").unwrap();
        assert_eq!(s.grid.voxel_size, VoxelSize::Auto(AutoTag::Auto));
    }
}
