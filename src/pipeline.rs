//! The bake pipeline: one [`BakePlan`] built from a scene, and the stages
//! as functions of it and of plain data.
//!
//! The bake is scene -> footprints -> beams -> photons -> grids:
//! 1. one footprint per curtain ([`BakePlan::new`], seeded by scene and
//!    curtain seed, at the scene's `animation.time_s`); the plan also holds
//!    the atmosphere, the colour table, the magnetic field, the kernel
//!    radius field and the grid, camera and photon parameters;
//! 2. electron beams traced through the atmosphere, leaving photons
//!    ([`trace`]: beams `[first, first + n)` of a bake of `count` beams; a
//!    beam is the same beam whatever range it is traced in, so chunks
//!    concatenate to the whole, byte for byte); with
//!    `beams.target_noise > 0` the count comes from a pilot
//!    (`crate::pilot`, which traces and gathers through this plan);
//! 3. the emission grid by kernel density estimation over the photons
//!    ([`gather`], on the transform `voxel_size * (i, j, k)` km of
//!    [`BakePlan::voxel_size`]): candidate 8^3 leaves are those within
//!    `cutoff * r_max` of a photon, gathered in parallel, collected in leaf
//!    order and sorted; a voxel is active when its emission is nonzero;
//! 4. [`finish`]: the f32 / half-float range checks; with `grid.prune > 0`,
//!    the leaves faintest at the camera dropped within that error budget
//!    ([`crate::prune`]); the density grid on the (kept) active voxels
//!    ([`density_grid`]); with `grid.cycles_shell`, both grids dilated by one
//!    voxel of active zeros ([`crate::grid::Grid::dilate_active`]); the
//!    stats.
//!
//! `crate::bake::bake` composes them for a scene; `crate::preview` keeps
//! their outputs between edits; the bench and frame sequences reuse a plan
//! ([`BakePlan::reusing`] keeps the footprints, atmosphere and colour table
//! when the sections they depend on are unchanged: a new frame time
//! recomputes only the footprints). Nothing here imports `bake` or `pilot`.
//!
//! [`resolution_warnings`] flags bakes whose voxels under-resolve the kernel
//! or the curtains, [`extinction_warning`] air extinction clamped at
//! [`MAX_EXTINCTION_PER_KM`] (`BakeStats::warnings`; the CLI prints them on
//! stderr). Emission that overflows f32 is an error, never a file.
//!
//! `photons.radius_km` is read in one place, [`KernelRadius::of`].

use crate::atmosphere::Atmosphere;
use crate::beams::{self, BeamError, BeamStats, TraceParams, Traced};
use crate::camera::{CameraError, CameraModel};
use crate::deposit::Photon;
use crate::footprint::{self, Footprint};
use crate::grid::{Grid, Leaf, Transform};
use crate::magnetic::MagneticField;
use crate::photons::{self, radius::RadiusField};
use crate::progress::Progress;
use crate::prune::{self, PruneStats};
use crate::scene::{
    AnimationParams, AtmosphereParams, BeamParams, Camera, ColourMode, ColourParams, Curtain, FootprintParams,
    GatherMethod, GridParams, PhotonParams, Scene, VoxelSize,
};
use crate::spectrum::{luminance, ColourTable, EmissionModel};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::ops::Range;
use std::time::Instant;

/// `indicator = 1 - exp(-Y / (AURORA_FRACTION * Y_peak))`, about 1 wherever
/// the aurora is within a few percent of its peak, falling smoothly to 0 in
/// its faint fringes.
pub const AURORA_FRACTION: f64 = 0.01;

/// Largest air extinction stored, per km (the top of `density_a`'s range).
/// `density_a exp(-density_b (h - density_base_km))` grows without bound
/// below the base altitude and overflows f32 (and then f64) for steep
/// profiles; at 10^6 per km a metre of path has optical depth 10^3, so any
/// voxel is opaque and larger values change nothing but the risk of
/// infinity. Clamped voxels are reported by a warning.
pub const MAX_EXTINCTION_PER_KM: f64 = 1e6;

/// The baked volumes and what produced them.
#[derive(Clone, Debug)]
pub struct Bake {
    /// Linear Rec.709 emission, kR per km (Y = 1: 1 kR of 557.7 nm per km).
    pub emission: Grid<[f32; 3]>,
    /// Extinction per km, on the emission's active voxels.
    pub density: Grid<f32>,
    pub photons: Vec<Photon>,
    pub stats: BakeStats,
}

/// Wall time of each stage, seconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    pub footprints: f64,
    pub pilot: f64,
    pub beams: f64,
    pub gather: f64,
    pub prune: f64,
    pub density: f64,
    pub total: f64,
}

/// Numbers describing a bake (written as bake.json).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BakeStats {
    pub units: &'static str,
    pub seed: u64,
    /// FNV-1a hash of the scene's canonical TOML, hex.
    pub scene_hash: String,
    pub voxel_size_km: f64,
    /// "scene" or "auto (photons.radius_km)".
    pub voxel_size_source: String,
    pub gather: GatherMethod,
    pub beams: usize,
    pub photons: usize,
    /// Voxels (and leaves) holding aurora: non-zero emission.
    pub active_voxels: u64,
    pub leaves: usize,
    /// Active zero voxels of the `grid.cycles_shell` (0 without it).
    pub shell_voxels: u64,
    /// Active voxels and leaves per grid in the file: the aurora's plus the shell.
    pub file_voxels: u64,
    pub file_leaves: usize,
    /// Inclusive index bounding box of the file's active voxels (shell
    /// included), [min, max].
    pub index_bbox: Option<[[i32; 3]; 2]>,
    /// World bounding box of the active voxel centres, km, [min, max].
    pub world_bbox: Option<[[f64; 3]; 2]>,
    /// Largest emission per component, and the largest luminance, kR/km.
    pub peak_emission: [f32; 3],
    pub peak_luminance: f64,
    /// Sum of the photons' power, 557.7-equivalent photons per second, RGB.
    pub total_emitted_power: [f64; 3],
    /// The same as luminance, in 557.7 nm photons per second.
    pub total_emitted_luminance: f64,
    /// Electron power into the atmosphere, W, and how much the beams
    /// deposited before stopping.
    pub electron_power_w: f64,
    pub deposited_power_w: f64,
    pub beam_stats: BeamStats,
    pub times_s: StageTimes,
    /// How `beams.target_noise` set the beam count (None when it is 0).
    pub noise: Option<NoiseEstimate>,
    /// What `grid.prune` removed (None when it is 0).
    pub prune: Option<PruneStats>,
    /// Under-resolution warnings ([`resolution_warnings`]); empty when the
    /// grid resolves the kernel and every curtain.
    pub warnings: Vec<String>,
}

impl BakeStats {
    /// Wall time of the whole bake, seconds.
    pub fn total_seconds(&self) -> f64 {
        self.times_s.total
    }
}

/// A bake failure.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Beams(#[from] BeamError),
    /// The emission overflowed single precision (never written: a safety
    /// net behind the scene's validation ranges).
    #[error("the emission at voxel ({}, {}, {}) is {value}, beyond single precision: the power per photon (curtain energy_flux and area over beams.count) is too high for photons.radius_km = {radius_km}; use more beams or a larger radius", ijk[0], ijk[1], ijk[2])]
    NonFinite { ijk: [i32; 3], value: String, radius_km: f64 },
    /// The bake would need more memory than this process may use
    /// ([`crate::budget`]); refused before anything is allocated. Boxed: its
    /// six strings would otherwise set the size of every
    /// `Result<_, BakeError>`.
    #[error(transparent)]
    Memory(#[from] Box<crate::budget::TooLarge>),
    /// The bake produced no emission at all: an empty VDB is never written
    /// silently. The message says where the beams' energy went.
    #[error("the bake deposited no light: {0}")]
    Empty(String),
    /// `grid.half_emission` asks for half floats the emission exceeds.
    #[error("grid.half_emission = true, but the emission reaches {peak} at voxel ({}, {}, {}), beyond the half-float range (|x| <= 65504): set grid.half_emission = false, or lower the curtains' energy_flux or raise photons.radius_km", ijk[0], ijk[1], ijk[2])]
    HalfOverflow { ijk: [i32; 3], peak: f32 },
    /// The scene's camera is out of range (never with a validated scene).
    #[error(transparent)]
    Camera(#[from] crate::camera::CameraError),
}

/// The voxel size in km and where it came from. `"auto"` asks the camera:
/// see [`auto_voxel_size`].
pub fn voxel_size(scene: &Scene, photons: &[Photon]) -> (f64, String) {
    let camera = CameraModel::new(&scene.camera, scene.render.width, scene.render.height);
    voxel_size_for(scene.grid.voxel_size, KernelRadius::of(&scene.photons), camera.as_ref().ok(), photons)
}

/// [`voxel_size`] from plain data: `grid.voxel_size`, the kernel radius and
/// the camera (None: not valid).
pub fn voxel_size_for(size: VoxelSize, kernel: KernelRadius, camera: Option<&CameraModel>, photons: &[Photon]) -> (f64, String) {
    match size {
        VoxelSize::Km(v) => (v, "scene".into()),
        VoxelSize::Auto(_) => {
            let (v, why) = auto_voxel_size_for(kernel, camera, photons);
            (v, format!("auto: {why}"))
        }
    }
}

/// No more model than the picture needs: the voxel size at which one voxel
/// projects to about one pixel at the nearest aurora.
///
/// A pixel at the image centre subtends an angle `a` (perspective:
/// 2 tan(fov/2) / height; fisheye: fov / max(width, height); equirectangular:
/// min(360 / width, 180 / height) degrees: `CameraModel::pixel_angle`), so at
/// distance d it covers d a km; d is the 1st percentile
/// of the photons' distances from the camera (robust to a few stray photons,
/// which would otherwise shrink every voxel). Orthographic: ortho_height /
/// height. Never below half the kernel radius: the kernel already blurs the
/// field at that scale, so finer voxels add memory and no detail; never above
/// twice the smallest kernel radius, where the voxels would alias it.
/// Rounded to three significant digits (down, at that ceiling) so the size
/// reads well in bake.json.
pub fn auto_voxel_size(scene: &Scene, photons: &[Photon]) -> (f64, String) {
    let camera = CameraModel::new(&scene.camera, scene.render.width, scene.render.height);
    auto_voxel_size_for(KernelRadius::of(&scene.photons), camera.as_ref().ok(), photons)
}

/// [`auto_voxel_size`] from plain data.
pub fn auto_voxel_size_for(kernel: KernelRadius, camera: Option<&CameraModel>, photons: &[Photon]) -> (f64, String) {
    let floor = kernel.auto_voxel_floor_km();
    // A validated scene always has a camera; should it not, the kernel
    // radius is a size that neither aliases nor wastes.
    let Some(cam) = camera else {
        return (kernel.base_km, "no valid camera: kernel radius".into());
    };
    let (raw, why) = match cam.pixel_angle() {
        None => (cam.pixel_footprint(0.0), "ortho_height / height".to_string()),
        Some(_) => {
            let eye = cam.position;
            let mut d: Vec<f64> = photons.iter().map(|p| (DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64) - eye).length()).collect();
            if d.is_empty() {
                return (kernel.base_km, "no photons: kernel radius".into());
            }
            let k = d.len() / 100;
            let (_, nth, _) = d.select_nth_unstable_by(k, f64::total_cmp);
            let dist = *nth;
            (cam.pixel_footprint(dist), format!("one pixel at {dist:.1} km (1st percentile of photon distances)"))
        }
    };
    // Never above twice the smallest kernel radius either: coarser voxels
    // alias the kernel (see [`resolution_warnings`]), so the bake would
    // warn about its own choice.
    let ceiling = 2.0 * kernel.min_km;
    if raw > ceiling && ceiling >= floor {
        let p = 10f64.powi(2 - ceiling.abs().log10().floor() as i32);
        return ((ceiling * p).floor() / p, format!("{why}, lowered to twice the smallest kernel radius"));
    }
    let v = raw.max(floor);
    let why = if raw < floor { format!("{why}, raised to half the kernel radius") } else { why };
    (round_sig(v, 3), why)
}

fn round_sig(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let p = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * p).round() / p
}

/// One footprint per curtain (in curtain order; simulated in parallel), at
/// the scene's `animation.time_s`.
pub fn footprints(scene: &Scene) -> Vec<Footprint> {
    simulate_footprints(scene.seed, &scene.curtains, &scene.footprint, &scene.animation, &crate::progress::NoProgress)
}

/// One footprint per curtain at `animation.time_s`, in parallel.
pub fn simulate_footprints(
    seed: u64,
    curtains: &[Curtain],
    params: &FootprintParams,
    animation: &AnimationParams,
    progress: &dyn Progress,
) -> Vec<Footprint> {
    progress.start("footprints", curtains.len() as u64);
    let fps = curtains
        .par_iter()
        .map(|c| {
            let f = footprint::simulate_at(c, params, animation, seed, animation.time_s);
            progress.inc(1);
            f
        })
        .collect();
    progress.finish();
    fps
}

/// Mean thickness, km, of the band the beams of a footprint start from: the
/// area of the cells above `threshold` divided by the curtain's length (the
/// sum of the band's widths across the curtain, averaged along it).
pub fn band_thickness_km(fp: &Footprint, threshold: f64) -> f64 {
    let cells = fp.data.iter().filter(|&&d| d as f64 > threshold).count();
    cells as f64 * fp.cell_area_km2() / fp.length
}

/// Warnings for a bake at voxel size `voxel_km` whose grid under-resolves
/// what it stores:
/// - the smallest kernel radius, `r_min = radius_km (1 - radius_noise)`, is
///   below half a voxel. Voxel centres sample the Gaussian kernel; by Poisson
///   summation the sum of a Gaussian of sd r sampled every h differs from its
///   integral by up to `2 exp(-2 pi^2 r^2 / h^2)` per axis: 1.4 % at
///   r = h / 2, 22 % at r = h / 3, so below h / 2 each photon's contribution
///   depends on where it falls between voxel centres (noise at the voxel
///   scale, power no longer conserved voxel by voxel).
/// - a curtain's beams start in a band thinner than a voxel
///   ([`band_thickness_km`]): across its thickness the sheet is one voxel or
///   less, so its profile is lost (beam deflections widen the sheet a
///   little; the kernel blurs it to at least r).
pub fn resolution_warnings(scene: &Scene, footprints: &[Footprint], voxel_km: f64) -> Vec<String> {
    resolution_warnings_for(KernelRadius::of(&scene.photons), footprints, scene.footprint.threshold, voxel_km)
}

/// [`resolution_warnings`] from plain data: the kernel radius, the
/// footprints and `footprint.threshold`.
pub fn resolution_warnings_for(kernel: KernelRadius, footprints: &[Footprint], threshold: f64, voxel_km: f64) -> Vec<String> {
    let mut w = Vec::new();
    let r_min = kernel.min_km;
    if r_min < 0.5 * voxel_km {
        w.push(format!(
            "under-resolved kernel: photons.radius_km = {} (smallest radius with radius_noise = {}: {:.4} km) is below half the voxel size ({} km); the emission is aliased at the voxel scale: use grid.voxel_size <= {:.4} or a larger radius",
            kernel.base_km, kernel.noise, r_min, voxel_km, 2.0 * r_min
        ));
    }
    for (i, fp) in footprints.iter().enumerate() {
        let t = band_thickness_km(fp, threshold);
        if t < voxel_km {
            w.push(format!(
                "under-resolved curtain: curtain[{i}]'s beams start in a band {t:.3} km thick on average (footprint above threshold), thinner than a voxel ({voxel_km} km); the sheet's profile across is lost: use grid.voxel_size <= {:.3}",
                t
            ));
        }
    }
    w
}

/// The colour table the scene asks for.
pub fn colour_table(scene: &Scene, atmosphere: &Atmosphere) -> ColourTable {
    colour_table_for(&scene.colour, atmosphere)
}

/// The colour table of `[colour]` (its mode and colour map).
pub fn colour_table_for(colour: &ColourParams, atmosphere: &Atmosphere) -> ColourTable {
    match colour.mode {
        ColourMode::Physical => ColourTable::physical(&EmissionModel::new(atmosphere.clone())),
        ColourMode::Colormap => ColourTable::colormap(&colour.colormap),
    }
}

/// The density grid on the emission's active voxels:
/// `density_a exp(-density_b (h - density_base_km))` (the report's air
/// density, per km; [`extinction`], clamped at [`MAX_EXTINCTION_PER_KM`]) times an aurora indicator in [0, 1] that saturates
/// smoothly in the emission's luminance relative to [`AURORA_FRACTION`] of the
/// peak. No fog box: only where the aurora is.
pub fn density_grid(emission: &Grid<[f32; 3]>, params: &GridParams, peak_luminance: f64) -> Grid<f32> {
    let tr = emission.transform;
    let scale = AURORA_FRACTION * peak_luminance;
    let inv_scale = if scale > 0.0 { (1.0 / scale) as f32 } else { 0.0 };
    let leaves: Vec<Leaf<f32>> = emission
        .leaves()
        .par_iter()
        .map(|l| {
            // The air depends on the altitude only: once per z of the leaf.
            let air: [f64; 8] = std::array::from_fn(|z| extinction(params, tr.index_to_world((l.origin + glam::IVec3::new(0, 0, z as i32)).as_dvec3()).z));
            let mut out = Leaf::new(l.origin, 0.0f32);
            out.mask = l.mask;
            for n in 0..crate::grid::LEAF_NUM_VALUES {
                if l.is_active(n) {
                    let v = l.values[n];
                    let y = luminance([v[0] as f64, v[1] as f64, v[2] as f64]).max(0.0);
                    // 1 - exp(-y / scale) in f32: within 2e-7 of the f64
                    // value (exp_neg_f32's 1.2e-7 relative plus rounding);
                    // 0 when scale is.
                    let indicator = 1.0 - photons::fast_math::exp_neg_f32(-(y as f32) * inv_scale);
                    out.values[n] = (air[n & 7] * indicator as f64) as f32;
                }
            }
            out
        })
        .collect();
    let mut g = Grid::new("density", 0.0f32, tr);
    for l in leaves {
        g.insert_leaf(l);
    }
    g.sort_leaves();
    g
}

/// The air extinction at altitude `h` km, per km:
/// `density_a exp(-density_b (h - density_base_km))`, at most
/// [`MAX_EXTINCTION_PER_KM`] (and 0, not NaN, when `density_a` is 0).
pub fn extinction(params: &GridParams, h: f64) -> f64 {
    if params.density_a > 0.0 {
        (params.density_a * (-params.density_b * (h - params.density_base_km)).exp()).min(MAX_EXTINCTION_PER_KM)
    } else {
        0.0
    }
}

/// A warning when the air extinction reaches [`MAX_EXTINCTION_PER_KM`] at
/// the lowest altitude `h_min` km of the grid (it decreases with altitude).
pub fn extinction_warning(params: &GridParams, h_min: f64) -> Option<String> {
    let raw = params.density_a * (-params.density_b * (h_min - params.density_base_km)).exp();
    (params.density_a > 0.0 && raw >= MAX_EXTINCTION_PER_KM).then(|| {
        format!(
            "air extinction clamped: grid.density_a exp(-density_b (h - density_base_km)) reaches {raw:.3e} per km at {h_min:.1} km, above the maximum {MAX_EXTINCTION_PER_KM:e} (opaque); density is clamped there"
        )
    })
}

/// Why a bake came out empty, in the user's terms: how its beams ended and
/// which keys to look at.
pub fn empty_reason(stats: &BeamStats, beams: &crate::scene::BeamParams) -> String {
    let mut why = format!(
        "{} beams made {} photons ({} left their footprint, {} spent their energy, {} took the most steps, 1 / beams.dt = {})",
        stats.beams,
        stats.photons,
        stats.ended_left_footprint,
        stats.ended_energy_spent,
        stats.ended_max_steps,
        (1.0 / beams.dt).round()
    );
    if stats.photons == 0 {
        why += &format!(
            "; no beam deposited energy before stopping: check beams.length_km = {} (a first step longer than the atmosphere leaves nothing) and beams.top_km = {}",
            beams.length_km, beams.top_km
        );
    } else {
        why += "; their emission is zero everywhere (curtain energy_flux, or an all-zero colour map)";
    }
    why
}

/// The scene's neutral atmosphere (`[atmosphere] model`).
pub fn atmosphere(scene: &Scene) -> Atmosphere {
    atmosphere_for(&scene.atmosphere)
}

/// The neutral atmosphere of `[atmosphere]`.
pub fn atmosphere_for(params: &AtmosphereParams) -> Atmosphere {
    Atmosphere::of_model(params.model)
}

/// What the pilot measured and chose (`crate::pilot`; kept here so the
/// stats do not depend on the pilot's module).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseEstimate {
    /// `beams.target_noise`.
    pub target: f64,
    /// Beams per pilot half, `m`.
    pub pilot_beams: usize,
    /// Relative RMS noise of an `m`-beam grid, measured.
    pub pilot_noise: f64,
    /// Relative RMS noise of an `m / 4`-beam grid, measured.
    pub quarter_noise: f64,
    /// The fitted law `noise(N)^2 = law_a / N + law_b / N^(3/2)`.
    pub law_a: f64,
    pub law_b: f64,
    /// The N of the fitted law at the target (`m (pilot_noise / target)^2`
    /// when law_b = 0).
    pub beams_needed: f64,
    /// The count used: `beams_needed` rounded up, at most `beams.count`.
    pub beams: usize,
    /// The noise expected at `beams` by the fitted law.
    pub expected_noise: f64,
    /// `beams.count` capped the count.
    pub capped: bool,
    pub seconds: f64,
}

/// The kernel radius the scene asks for; it lives beside the scene
/// (`crate::scene::kernel`) so that the memory budget reads it too.
pub use crate::scene::KernelRadius;

/// The kernel radius field at base radius `kernel.base_km` (noise from
/// `photons.radius_noise_freq`, along the field `b` from the beams' top
/// `top_km`, seeded by the scene seed).
pub fn radius_field(kernel: KernelRadius, p: &PhotonParams, b: DVec3, top_km: f64, seed: u64) -> RadiusField {
    RadiusField::new(kernel.base_km, kernel.noise, p.radius_noise_freq, b, top_km, &[seed])
}

/// The grid transform of voxel size `voxel_km`: translation 0, so voxel
/// (i, j, k) is centred at `voxel_km * (i, j, k)` km.
pub fn grid_transform(voxel_km: f64) -> Transform {
    Transform::new(voxel_km, DVec3::ZERO)
}

/// Everything the stages need, built once from a scene: its sections as
/// plain data and what they determine (footprints, atmosphere, colour
/// table, field, kernel radius field).
#[derive(Clone, Debug)]
pub struct BakePlan {
    pub seed: u64,
    /// FNV-1a hash of the scene's canonical TOML, hex.
    pub scene_hash: String,
    pub curtains: Vec<Curtain>,
    pub footprint: FootprintParams,
    pub animation: AnimationParams,
    pub beams: BeamParams,
    pub colour: ColourParams,
    pub atmosphere_params: AtmosphereParams,
    pub photons: PhotonParams,
    pub grid: GridParams,
    /// The camera and image size (pruning, the automatic voxel size).
    pub camera: Camera,
    pub width: usize,
    pub height: usize,
    /// One per curtain, at `animation.time_s`.
    pub footprints: Vec<Footprint>,
    /// Seconds the footprints took (0 when reused).
    pub footprint_seconds: f64,
    pub atmosphere: Atmosphere,
    pub colour_table: ColourTable,
    pub field: MagneticField,
    pub kernel: KernelRadius,
    pub radius: RadiusField,
}

impl BakePlan {
    /// The plan of a validated scene (simulates the footprints).
    pub fn new(scene: &Scene, progress: &dyn Progress) -> BakePlan {
        Self::build(scene, None, progress)
    }

    /// The plan of `scene`, reusing `prev`'s footprints when the seed,
    /// curtains, `[footprint]` and `[animation]` are unchanged, and its
    /// atmosphere and colour table when `[atmosphere]` and the colour mode
    /// and map are unchanged (a frame sequence: only the time changes; the
    /// preview: most edits touch neither).
    pub fn reusing(scene: &Scene, prev: &BakePlan, progress: &dyn Progress) -> BakePlan {
        Self::build(scene, Some(prev), progress)
    }

    fn build(scene: &Scene, prev: Option<&BakePlan>, progress: &dyn Progress) -> BakePlan {
        let t = Instant::now();
        let same_fp = prev.filter(|p| {
            p.seed == scene.seed && p.curtains == scene.curtains && p.footprint == scene.footprint && p.animation == scene.animation
        });
        let (footprints, footprint_seconds) = match same_fp {
            Some(p) => (p.footprints.clone(), 0.0),
            None => {
                let f = simulate_footprints(scene.seed, &scene.curtains, &scene.footprint, &scene.animation, progress);
                (f, t.elapsed().as_secs_f64())
            }
        };
        let same_colour = prev.filter(|p| {
            p.atmosphere_params == scene.atmosphere && p.colour.mode == scene.colour.mode && p.colour.colormap == scene.colour.colormap
        });
        let (atmosphere, colour_table) = match same_colour {
            Some(p) => (p.atmosphere.clone(), p.colour_table.clone()),
            None => {
                let a = atmosphere_for(&scene.atmosphere);
                let c = colour_table_for(&scene.colour, &a);
                (a, c)
            }
        };
        let field = MagneticField::new(scene.beams.b_inclination_deg, scene.beams.b_declination_deg);
        let kernel = KernelRadius::of(&scene.photons);
        let radius = radius_field(kernel, &scene.photons, field.b, scene.beams.top_km, scene.seed);
        BakePlan {
            seed: scene.seed,
            scene_hash: format!("{:016x}", scene.hash()),
            curtains: scene.curtains.clone(),
            footprint: scene.footprint.clone(),
            animation: scene.animation.clone(),
            beams: scene.beams.clone(),
            colour: scene.colour.clone(),
            atmosphere_params: scene.atmosphere.clone(),
            photons: scene.photons.clone(),
            grid: scene.grid.clone(),
            camera: scene.camera.clone(),
            width: scene.render.width,
            height: scene.render.height,
            footprints,
            footprint_seconds,
            atmosphere,
            colour_table,
            field,
            kernel,
            radius,
        }
    }

    /// The tracing parameters, borrowed from the plan.
    pub fn trace_params(&self) -> TraceParams<'_> {
        TraceParams {
            seed: self.seed,
            curtains: &self.curtains,
            beams: &self.beams,
            threshold: self.footprint.threshold,
            animation: &self.animation,
            colour_noise_km: self.colour.noise_km,
            colour_noise_freq: self.colour.noise_freq,
            kernel: self.photons.kernel,
        }
    }

    /// The scene's camera model.
    pub fn camera_model(&self) -> Result<CameraModel, CameraError> {
        CameraModel::new(&self.camera, self.width, self.height)
    }

    /// The voxel size in km and where it came from ([`voxel_size_for`]).
    pub fn voxel_size(&self, photons: &[Photon]) -> (f64, String) {
        let cam = self.camera_model();
        voxel_size_for(self.grid.voxel_size, self.kernel, cam.as_ref().ok(), photons)
    }
}

/// Traces beams `[first, first + n)` of a bake of `count` beams, beam `i` of
/// a curtain on random stream `stream_offset + i`
/// ([`crate::beams::trace_range`]): the same beam whatever the chunking.
pub fn trace(
    plan: &BakePlan,
    count: usize,
    stream_offset: u64,
    beams: Range<usize>,
    progress: &dyn Progress,
) -> Result<Traced, BeamError> {
    beams::trace_range(
        &plan.trace_params(),
        &plan.footprints,
        &plan.atmosphere,
        &plan.colour_table,
        count,
        stream_offset,
        beams,
        false,
        progress,
    )
}

/// The emission grid of `photons` at voxel size `voxel_km`, with the plan's
/// radius field, cutoff and gather method.
pub fn gather(plan: &BakePlan, photons: &[Photon], voxel_km: f64, progress: &dyn Progress) -> Grid<[f32; 3]> {
    gather_with(photons, voxel_km, &plan.radius, plan.photons.cutoff, plan.photons.gather, progress)
}

/// The photons made ready for [`gather_from`] with the plan's radius field,
/// cutoff and gather method (merged runs, splat kernels): once for several
/// gathers of the same photons.
pub fn gather_input(plan: &BakePlan, photons: &[Photon]) -> photons::GatherInput {
    photons::GatherInput::new(photons, &plan.radius, plan.photons.cutoff, plan.photons.gather)
}

/// [`gather`] of photons made ready by [`gather_input`] with the same plan:
/// the same grid.
pub fn gather_from(plan: &BakePlan, input: &photons::GatherInput, voxel_km: f64, progress: &dyn Progress) -> Grid<[f32; 3]> {
    photons::gather_prepared(input, grid_transform(voxel_km), &plan.radius, plan.photons.cutoff, plan.photons.gather, progress)
}

/// The transform + radius field + gather set-up, written once: the emission
/// grid of `photons` on [`grid_transform`]`(voxel_km)`.
pub fn gather_with(
    photons: &[Photon],
    voxel_km: f64,
    radius: &RadiusField,
    cutoff: f64,
    method: GatherMethod,
    progress: &dyn Progress,
) -> Grid<[f32; 3]> {
    photons::gather_grid(photons, grid_transform(voxel_km), radius, cutoff, method, progress)
}

/// What [`finish`] needs besides the plan and the emission grid.
#[derive(Clone, Debug)]
pub struct Gathered {
    pub photons: Vec<Photon>,
    pub beam_stats: BeamStats,
    pub voxel_km: f64,
    pub voxel_source: String,
    /// Warnings so far (resolution, pilot).
    pub warnings: Vec<String>,
    pub noise: Option<NoiseEstimate>,
}

/// Traces `count` beams, picks the voxel size and gathers: stages 2 and 3.
/// `times.beams` and `times.gather` are filled in.
pub fn trace_and_gather(
    plan: &BakePlan,
    count: usize,
    noise: Option<NoiseEstimate>,
    mut warnings: Vec<String>,
    times: &mut StageTimes,
    progress: &dyn Progress,
) -> Result<(Grid<[f32; 3]>, Gathered), BakeError> {
    let t = Instant::now();
    let traced = trace(plan, count, 0, 0..count, progress)?;
    times.beams = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (voxel_km, voxel_source) = plan.voxel_size(&traced.photons);
    let mut w = resolution_warnings_for(plan.kernel, &plan.footprints, plan.footprint.threshold, voxel_km);
    w.append(&mut warnings);
    let emission = gather(plan, &traced.photons, voxel_km, progress);
    times.gather = t.elapsed().as_secs_f64();
    Ok((emission, Gathered { photons: traced.photons, beam_stats: traced.stats, voxel_km, voxel_source, warnings: w, noise }))
}

/// The emission's checks and peaks, the first step of [`finish`]: every
/// active value finite (else [`BakeError::NonFinite`] at the first bad voxel
/// in leaf order), within the half-float range when `half_emission`, and the
/// largest component and luminance. Per leaf in parallel; the first error in
/// leaf order wins and maxima do not depend on the order, so the outcome is
/// the same whatever the thread count.
pub fn scan_emission(emission: &Grid<[f32; 3]>, half_emission: bool, radius_km: f64) -> Result<([f32; 3], f64), BakeError> {
    let half_max = half::f16::MAX.to_f32();
    let per_leaf: Vec<Result<([f32; 3], f64), BakeError>> = emission
        .leaves()
        .par_iter()
        .map(|l| {
            let mut peak = [0.0f32; 3];
            let mut peak_y = 0.0f64;
            for (ijk, v) in l.iter_active() {
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(BakeError::NonFinite { ijk: ijk.to_array(), value: format!("{v:?}"), radius_km });
                }
                if half_emission && v.iter().any(|x| x.abs() > half_max) {
                    let peak = v.iter().fold(0.0f32, |m, x| m.max(x.abs()));
                    return Err(BakeError::HalfOverflow { ijk: ijk.to_array(), peak });
                }
                for k in 0..3 {
                    peak[k] = peak[k].max(v[k]);
                }
                peak_y = peak_y.max(luminance([v[0] as f64, v[1] as f64, v[2] as f64]));
            }
            Ok((peak, peak_y))
        })
        .collect();
    let mut peak = [0.0f32; 3];
    let mut peak_y = 0.0f64;
    for r in per_leaf {
        let (p, y) = r?;
        for k in 0..3 {
            peak[k] = peak[k].max(p[k]);
        }
        peak_y = peak_y.max(y);
    }
    Ok((peak, peak_y))
}

/// Stage 4: checks the emission, prunes it, builds the density grid and the
/// Cycles shell, and the stats. `times.prune`, `times.density` are filled
/// in; `times.total` is the time since `t_all`.
pub fn finish(
    plan: &BakePlan,
    emission: Grid<[f32; 3]>,
    g: Gathered,
    times: StageTimes,
    t_all: Instant,
    progress: &dyn Progress,
) -> Result<Bake, BakeError> {
    finish_keeping(plan, emission, g, times, t_all, progress).map(|(b, _)| b)
}

/// [`finish`], also returning the leaves pruning dropped (leaf order; none
/// when `grid.prune` is 0). Without the Cycles shell the bake's emission
/// and these leaves are the gathered grid, so a caller that refinishes
/// (the preview, after a camera or grid edit) keeps them instead of a copy
/// of the gathered grid ([`Grid::restore_leaves`]).
pub fn finish_keeping(
    plan: &BakePlan,
    emission: Grid<[f32; 3]>,
    g: Gathered,
    mut times: StageTimes,
    t_all: Instant,
    progress: &dyn Progress,
) -> Result<(Bake, Vec<Leaf<[f32; 3]>>), BakeError> {
    let Gathered { photons, beam_stats, voxel_km: vs, voxel_source: vs_source, mut warnings, noise } = g;
    if emission.leaf_count() == 0 {
        return Err(BakeError::Empty(empty_reason(&beam_stats, &plan.beams)));
    }
    let transform = emission.transform;

    let t = Instant::now();
    let (peak, peak_y) = scan_emission(&emission, plan.grid.half_emission, plan.kernel.base_km)?;
    if let Some((lo, _)) = emission.index_bbox() {
        warnings.extend(extinction_warning(&plan.grid, transform.index_to_world(lo.as_dvec3()).z));
    }
    let scan_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut emission = emission;
    let (prune_stats, dropped) = if plan.grid.prune > 0.0 {
        let camera = plan.camera_model()?;
        let (st, dropped) = prune::prune_keeping(&mut emission, &camera, plan.grid.prune);
        (Some(st), dropped)
    } else {
        (None, Vec::new())
    };
    times.prune = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.start("density", emission.leaf_count() as u64);
    let mut density = density_grid(&emission, &plan.grid, peak_y);
    progress.inc(emission.leaf_count() as u64);
    progress.finish();
    let (aurora_voxels, aurora_leaves) = (emission.active_voxel_count(), emission.leaf_count());
    let shell_voxels = if plan.grid.cycles_shell {
        // Both grids live on the same voxels: the density takes the
        // emission's dilation rather than computing it again.
        let n = emission.dilate_active();
        let m = density.activate_like(&emission);
        debug_assert_eq!(n, m, "both grids live on the same voxels");
        n
    } else {
        0
    };
    times.density = scan_s + t.elapsed().as_secs_f64();
    times.total = t_all.elapsed().as_secs_f64();

    let mut total = [0.0f64; 3];
    for p in &photons {
        for (t, &c) in total.iter_mut().zip(&p.power) {
            *t += c as f64;
        }
    }
    let bbox = emission.index_bbox();
    let stats = BakeStats {
        units: "km",
        seed: plan.seed,
        scene_hash: plan.scene_hash.clone(),
        voxel_size_km: vs,
        voxel_size_source: vs_source,
        gather: plan.photons.gather,
        beams: beam_stats.beams,
        photons: photons.len(),
        active_voxels: aurora_voxels,
        leaves: aurora_leaves,
        shell_voxels,
        file_voxels: emission.active_voxel_count(),
        file_leaves: emission.leaf_count(),
        index_bbox: bbox.map(|(a, b)| [a.to_array(), b.to_array()]),
        world_bbox: bbox.map(|(a, b)| {
            [transform.index_to_world(a.as_dvec3()).to_array(), transform.index_to_world(b.as_dvec3()).to_array()]
        }),
        peak_emission: peak,
        peak_luminance: peak_y,
        total_emitted_power: total,
        total_emitted_luminance: luminance(total),
        electron_power_w: beam_stats.electron_power_w,
        deposited_power_w: beam_stats.deposited_power_w,
        beam_stats,
        times_s: times,
        noise,
        prune: prune_stats,
        warnings,
    };
    Ok((Bake { emission, density, photons, stats }, dropped))
}
