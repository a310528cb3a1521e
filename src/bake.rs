//! The bake: scene -> footprints -> beams -> photons -> grids.
//!
//! [`bake`] composes the stages, each a function of plain data:
//! 1. one footprint per curtain ([`footprints`], seeded by scene and curtain seed);
//! 2. electron beams traced through the atmosphere, leaving photons
//!    ([`crate::beams::trace_all`]); with `beams.target_noise > 0` their
//!    number comes from a pilot ([`crate::pilot`]);
//! 3. the emission grid by kernel density estimation over the photons
//!    ([`crate::photons::gather_grid`]): candidate 8^3 leaves are those within
//!    `cutoff * r_max` of a photon, gathered in parallel, collected in leaf
//!    order and sorted; a voxel is active when its emission is nonzero;
//! 4. with `grid.prune > 0`, the leaves faintest at the camera dropped within
//!    that error budget ([`crate::prune`]);
//! 5. the density grid on the (kept) active voxels ([`density_grid`]);
//! 6. with `grid.cycles_shell`, both grids dilated by one voxel of active
//!    zeros ([`crate::grid::Grid::dilate_active`]).
//!
//! [`resolution_warnings`] flags bakes whose voxels under-resolve the kernel
//! or the curtains, [`extinction_warning`] air extinction clamped at
//! [`MAX_EXTINCTION_PER_KM`] (`BakeStats::warnings`; the CLI prints them on
//! stderr). Emission that overflows f32 is an error, never a file.
//!
//! Grid transform: `voxel_size` from the scene (for `voxel_size = "auto"` the
//! camera's choice, [`auto_voxel_size`]: one pixel at the nearest aurora,
//! within [half the kernel radius, twice the smallest kernel radius]),
//! translation 0, so voxel (i, j, k) is centred at
//! `voxel_size * (i, j, k)` km.

use crate::atmosphere::Atmosphere;
use crate::beams::{self, BeamError, BeamStats, Photon};
use crate::pilot::{self, NoiseEstimate};
use crate::footprint::{self, Footprint};
use crate::grid::{Grid, Leaf, Transform};
use crate::photons::{self, RadiusField};
use crate::progress::Progress;
use crate::camera::CameraModel;
use crate::prune::{self, PruneStats};
use crate::scene::{ColourMode, GatherMethod, GridParams, Scene, VoxelSize};
use crate::spectrum::{luminance, ColourTable, EmissionModel};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// The density indicator saturates at this fraction of the peak luminance:
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
    /// `grid.half_emission` asks for half floats the emission exceeds.
    /// The bake would need more memory than this process may use
    /// ([`crate::budget`]); refused before anything is allocated.
    #[error(transparent)]
    Memory(#[from] crate::budget::TooLarge),
    /// The bake produced no emission at all: an empty VDB is never written
    /// silently. The message says where the beams' energy went.
    #[error("the bake deposited no light: {0}")]
    Empty(String),
    #[error("grid.half_emission = true, but the emission reaches {peak} at voxel ({}, {}, {}), beyond the half-float range (|x| <= 65504): set grid.half_emission = false, or lower the curtains' energy_flux or raise photons.radius_km", ijk[0], ijk[1], ijk[2])]
    HalfOverflow { ijk: [i32; 3], peak: f32 },
    /// The scene's camera is out of range (never with a validated scene).
    #[error(transparent)]
    Camera(#[from] crate::camera::CameraError),
}

/// The voxel size in km and where it came from. `"auto"` asks the camera:
/// see [`auto_voxel_size`].
pub fn voxel_size(scene: &Scene, photons: &[Photon]) -> (f64, String) {
    match scene.grid.voxel_size {
        VoxelSize::Km(v) => (v, "scene".into()),
        VoxelSize::Auto(_) => {
            let (v, why) = auto_voxel_size(scene, photons);
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
    let floor = 0.5 * scene.photons.radius_km;
    // A validated scene always has a camera; should it not, the kernel
    // radius is a size that neither aliases nor wastes.
    let Ok(cam) = CameraModel::new(&scene.camera, scene.render.width, scene.render.height) else {
        return (scene.photons.radius_km, "no valid camera: kernel radius".into());
    };
    let (raw, why) = match cam.pixel_angle() {
        None => (cam.pixel_footprint(0.0), "ortho_height / height".to_string()),
        Some(_) => {
            let eye = cam.position;
            let mut d: Vec<f64> = photons.iter().map(|p| (DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64) - eye).length()).collect();
            if d.is_empty() {
                return (scene.photons.radius_km, "no photons: kernel radius".into());
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
    let ceiling = 2.0 * scene.photons.radius_km * (1.0 - scene.photons.radius_noise);
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
    scene.curtains.par_iter().map(|c| footprint::simulate_at(c, &scene.footprint, &scene.animation, scene.seed, scene.animation.time_s)).collect()
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
    let mut w = Vec::new();
    let p = &scene.photons;
    let r_min = p.radius_km * (1.0 - p.radius_noise);
    if r_min < 0.5 * voxel_km {
        w.push(format!(
            "under-resolved kernel: photons.radius_km = {} (smallest radius with radius_noise = {}: {:.4} km) is below half the voxel size ({} km); the emission is aliased at the voxel scale: use grid.voxel_size <= {:.4} or a larger radius",
            p.radius_km, p.radius_noise, r_min, voxel_km, 2.0 * r_min
        ));
    }
    for (i, fp) in footprints.iter().enumerate() {
        let t = band_thickness_km(fp, scene.footprint.threshold);
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
    match scene.colour.mode {
        ColourMode::Physical => ColourTable::physical(&EmissionModel::new(atmosphere.clone())),
        ColourMode::Colormap => ColourTable::colormap(&scene.colour.colormap),
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
    let leaves: Vec<Leaf<f32>> = emission
        .leaves()
        .par_iter()
        .map(|l| {
            let mut out = Leaf::new(l.origin, 0.0f32);
            out.mask = l.mask;
            for n in 0..crate::grid::LEAF_NUM_VALUES {
                if l.is_active(n) {
                    let ijk = l.origin + crate::grid::offset_to_local(n);
                    let h = tr.index_to_world(ijk.as_dvec3()).z;
                    let v = l.values[n];
                    let y = luminance([v[0] as f64, v[1] as f64, v[2] as f64]).max(0.0);
                    let indicator = if scale > 0.0 { 1.0 - (-y / scale).exp() } else { 0.0 };
                    let air = extinction(params, h);
                    out.values[n] = (air * indicator) as f32;
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
    match scene.atmosphere.model {
        crate::scene::AtmosphereModel::Nrlmsis21 => Atmosphere::nrlmsis21(),
        crate::scene::AtmosphereModel::Us1976 => Atmosphere::us1976(),
    }
}

/// Runs every stage of the bake for a validated scene.
pub fn bake(scene: &Scene, progress: &dyn Progress) -> Result<Bake, BakeError> {
    let t_all = Instant::now();
    let mut times = StageTimes::default();
    crate::budget::check(&crate::budget::estimate(scene), &crate::memory::available())?;

    let t = Instant::now();
    progress.start("footprints", scene.curtains.len() as u64);
    let fps: Vec<Footprint> = scene
        .curtains
        .par_iter()
        .map(|c| {
            let f = footprint::simulate_at(c, &scene.footprint, &scene.animation, scene.seed, scene.animation.time_s);
            progress.inc(1);
            f
        })
        .collect();
    progress.finish();
    times.footprints = t.elapsed().as_secs_f64();

    let atmosphere = atmosphere(scene);
    let colour = colour_table(scene, &atmosphere);
    let mut noise_warning = None;
    let noise = if scene.beams.target_noise > 0.0 {
        let t = Instant::now();
        progress.start("pilot (beams.target_noise)", 1);
        let est = pilot::beams_for_noise(scene, &fps, &atmosphere, &colour, scene.beams.target_noise)?;
        progress.inc(1);
        progress.finish();
        times.pilot = t.elapsed().as_secs_f64();
        if est.capped {
            noise_warning = Some(format!(
                "beams.target_noise = {} needs {:.0} beams (pilot: {:.3} relative RMS noise at {} beams); capped at beams.count = {}, expected noise {:.3}: raise beams.count to reach the target",
                est.target, est.beams_needed, est.pilot_noise, est.pilot_beams, est.beams, est.expected_noise
            ));
        }
        Some(est)
    } else {
        None
    };
    let counted;
    let traced_scene = match &noise {
        Some(est) => {
            counted = Scene { beams: crate::scene::BeamParams { count: est.beams, ..scene.beams.clone() }, ..scene.clone() };
            &counted
        }
        None => scene,
    };

    let t = Instant::now();
    let (photons, beam_stats) = beams::trace_all(traced_scene, &fps, &atmosphere, &colour, progress)?;
    times.beams = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let (vs, vs_source) = voxel_size(scene, &photons);
    let mut warnings = resolution_warnings(scene, &fps, vs);
    warnings.extend(noise_warning);
    let transform = Transform::new(vs, DVec3::ZERO);
    let radius = RadiusField::from_scene(scene);
    let emission =
        photons::gather_grid(&photons, transform, &radius, scene.photons.cutoff, scene.photons.gather, progress);
    times.gather = t.elapsed().as_secs_f64();
    if emission.leaf_count() == 0 {
        return Err(BakeError::Empty(empty_reason(&beam_stats, &scene.beams)));
    }

    let t = Instant::now();
    let mut peak = [0.0f32; 3];
    let mut peak_y = 0.0f64;
    for (ijk, v) in emission.iter_active() {
        if v.iter().any(|x| !x.is_finite()) {
            return Err(BakeError::NonFinite {
                ijk: ijk.to_array(),
                value: format!("{v:?}"),
                radius_km: scene.photons.radius_km,
            });
        }
        if scene.grid.half_emission && v.iter().any(|x| x.abs() > half::f16::MAX.to_f32()) {
            let peak = v.iter().fold(0.0f32, |m, x| m.max(x.abs()));
            return Err(BakeError::HalfOverflow { ijk: ijk.to_array(), peak });
        }
        for k in 0..3 {
            peak[k] = peak[k].max(v[k]);
        }
        peak_y = peak_y.max(luminance([v[0] as f64, v[1] as f64, v[2] as f64]));
    }
    if let Some((lo, _)) = emission.index_bbox() {
        warnings.extend(extinction_warning(&scene.grid, transform.index_to_world(lo.as_dvec3()).z));
    }
    let scan_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut emission = emission;
    let prune_stats = if scene.grid.prune > 0.0 {
        let camera = CameraModel::new(&scene.camera, scene.render.width, scene.render.height)?;
        Some(prune::prune(&mut emission, &camera, scene.grid.prune))
    } else {
        None
    };
    times.prune = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.start("density", emission.leaf_count() as u64);
    let mut density = density_grid(&emission, &scene.grid, peak_y);
    progress.inc(emission.leaf_count() as u64);
    progress.finish();
    let (aurora_voxels, aurora_leaves) = (emission.active_voxel_count(), emission.leaf_count());
    let shell_voxels = if scene.grid.cycles_shell {
        let n = emission.dilate_active();
        let m = density.dilate_active();
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
        seed: scene.seed,
        scene_hash: format!("{:016x}", scene.hash()),
        voxel_size_km: vs,
        voxel_size_source: vs_source,
        gather: scene.photons.gather,
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
    Ok(Bake { emission, density, photons, stats })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;
    use crate::scene::{Curtain, VoxelSize};

    /// A small, fast scene: one short curtain, few beams, coarse voxels.
    fn small_scene() -> Scene {
        let mut s = Scene {
            curtains: vec![Curtain { length: 40.0, width: 16.0, bend_km: 3.0, ..Curtain::default() }],
            ..Scene::default()
        };
        s.footprint.resolution = [128, 48];
        s.beams.count = 300;
        s.photons.radius_km = 1.0;
        s.grid.voxel_size = VoxelSize::Km(1.0);
        s
    }

    #[test]
    fn bake_is_deterministic_across_thread_counts() {
        let s = small_scene();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| bake(&s, &NoProgress).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.photons, b.photons);
        assert_eq!(a.emission, b.emission);
        assert_eq!(a.density, b.density);
        assert!(a.stats.photons > 10_000, "{}", a.stats.photons);
    }

    #[test]
    fn emission_integrates_to_the_photon_power() {
        // With a constant radius the kernel integrates to 1, so
        // sum(emission) voxel^3 = sum(Phi) / 1e19. The voxel sum of a Gaussian
        // of sd = 1 voxel matches its integral to ~1e-8 (Poisson summation);
        // the truncation sphere cuts voxels, an error of order
        // K(c r) * (surface * voxel) ~ 1e-3 per photon, averaging out: 0.5 %.
        let mut s = small_scene();
        s.photons.radius_noise = 0.0;
        let b = bake(&s, &NoProgress).unwrap();
        let v3 = b.stats.voxel_size_km.powi(3);
        let mut sum = [0.0f64; 3];
        for (_, v) in b.emission.iter_active() {
            for (t, &c) in sum.iter_mut().zip(&v) {
                *t += c as f64 * v3;
            }
        }
        for (k, (&got, &power)) in sum.iter().zip(&b.stats.total_emitted_power).enumerate() {
            let want = power / 1e19;
            assert!((got / want - 1.0).abs() < 5e-3, "component {k}: {got} vs {want}");
        }
    }

    #[test]
    fn density_lives_on_the_emission_voxels_and_stats_are_consistent() {
        let b = bake(&small_scene(), &NoProgress).unwrap();
        assert_eq!(b.density.active_voxel_count(), b.emission.active_voxel_count());
        for (ijk, d) in b.density.iter_active() {
            assert!(b.emission.is_active(ijk));
            assert!(d.is_finite() && d >= 0.0);
        }
        assert!(b.emission.first_non_finite().is_none());
        // The aurora's voxels (non-zero emission) plus the Cycles shell (zeros).
        let nonzero = b.emission.iter_active().filter(|(_, v)| *v != [0.0; 3]).count() as u64;
        assert_eq!(b.stats.active_voxels, nonzero);
        assert_eq!(b.stats.active_voxels + b.stats.shell_voxels, b.emission.active_voxel_count());
        assert_eq!(b.stats.file_voxels, b.emission.active_voxel_count());
        assert_eq!(b.stats.file_leaves, b.emission.leaf_count());
        // The shell is exactly the 26-neighbourhood of the non-zero voxels.
        for (ijk, v) in b.emission.iter_active() {
            let near = (-1..=1).any(|dx| {
                (-1..=1).any(|dy| {
                    (-1..=1).any(|dz| b.emission.get(ijk + glam::IVec3::new(dx, dy, dz)) != [0.0; 3])
                })
            });
            assert!(near, "active voxel {ijk} = {v:?} is not next to the aurora");
        }
        assert_eq!(b.stats.photons, b.photons.len());
        // Energy bookkeeping: deposited <= electron power.
        assert!(b.stats.deposited_power_w <= b.stats.electron_power_w * (1.0 + 1e-9));
        let json = serde_json::to_string(&b.stats).unwrap();
        assert!(json.contains("\"units\":\"km\""));
        // Voxel centres on the lattice voxel_size * ijk.
        let (lo, _) = b.emission.index_bbox().unwrap();
        assert_eq!(b.emission.transform.index_to_world(lo.as_dvec3()), lo.as_dvec3() * b.stats.voxel_size_km);
    }

    #[test]
    fn gather_methods_and_colour_map_mode_bake() {
        // splat (sample-point radius) and kdtree (balloon radius) estimate the
        // same density: with radius noise their totals agree to the noise's
        // effect on normalisation (a few percent), and both conserve power.
        let mut s = small_scene();
        let a = bake(&s, &NoProgress).unwrap();
        s.photons.gather = GatherMethod::Splat;
        let b = bake(&s, &NoProgress).unwrap();
        let total = |g: &Grid<[f32; 3]>| g.iter_active().map(|(_, v)| v[1] as f64).sum::<f64>();
        let (ta, tb) = (total(&a.emission), total(&b.emission));
        assert!((ta / tb - 1.0).abs() < 0.05, "{ta} vs {tb}");
        // report2014 averages colours: its values are photon powers / 1e19,
        // bounded by the largest photon's.
        s.photons.gather = GatherMethod::Report2014;
        let c = bake(&s, &NoProgress).unwrap();
        let max_photon = c.photons.iter().map(|p| p.power[1]).fold(0.0f32, f32::max) as f64 / 1e19;
        assert!(c.emission.iter_active().all(|(_, v)| (v[1] as f64) <= max_photon * (1.0 + 1e-5)));
        // Artist colour map: a constant blue map gives blue everywhere.
        s.photons.gather = GatherMethod::Kdtree;
        s.colour.mode = ColourMode::Colormap;
        s.colour.colormap = vec![[80.0, 0.0, 0.0, 1.0], [400.0, 0.0, 0.0, 1.0]];
        s.grid.cycles_shell = false;
        let d = bake(&s, &NoProgress).unwrap();
        assert!(d.emission.iter_active().all(|(_, v)| v[0] == 0.0 && v[1] == 0.0 && v[2] > 0.0));
    }

    #[test]
    fn a_resolved_bake_has_no_warnings() {
        // small_scene: r_min = 1.0 * 0.7 = 0.7 km >= half of the 1 km voxel,
        // and the band (band_fraction 0.08 of 16 km, spread by the fluid) is
        // wider than a voxel.
        let b = bake(&small_scene(), &NoProgress).unwrap();
        assert!(b.stats.warnings.is_empty(), "{:?}", b.stats.warnings);
    }

    #[test]
    fn steep_air_density_is_clamped_and_warned_never_infinite() {
        // exp(-10 (h - 10^6)) overflows f64 for any altitude of the grid.
        let mut s = small_scene();
        s.grid.density_b = 10.0;
        s.grid.density_base_km = 1e6;
        let b = bake(&s, &NoProgress).unwrap();
        assert!(b.density.first_non_finite().is_none());
        let max = b.density.iter_active().map(|(_, d)| d).fold(0.0f32, f32::max);
        assert_eq!(max, MAX_EXTINCTION_PER_KM as f32, "the peak voxel's indicator is 1 - e^-100 = 1 in f64");
        assert!(b.stats.warnings.iter().any(|w| w.starts_with("air extinction clamped")), "{:?}", b.stats.warnings);
        // density_a = 0 gives 0, not 0 * inf = NaN.
        s.grid.density_a = 0.0;
        let b = bake(&s, &NoProgress).unwrap();
        assert!(b.density.iter_active().all(|(_, d)| d == 0.0));
        assert!(b.stats.warnings.is_empty(), "{:?}", b.stats.warnings);
        // The default profile is far below the clamp: no warning, the formula.
        let p = GridParams::default();
        assert_eq!(extinction(&p, 100.0), p.density_a * (-p.density_b * (100.0 - p.density_base_km)).exp());
        assert!(extinction_warning(&p, 60.0).is_none());
    }

    #[test]
    fn power_accounting_closes_and_deposits_match_electron_power_less_backscatter() {
        // Expected deposition: every beam finishes (no undeposited power),
        // each curtain's electron power splits exactly into deposited +
        // backscattered (Fang's 1 - G(inf)) + above the beams' top, and the
        // deposit matches electron power less those within 1 % (it is exact
        // up to rounding: telescoping sums).
        let s = small_scene();
        let b = bake(&s, &NoProgress).unwrap();
        let st = &b.stats.beam_stats;
        assert_eq!(st.curtains.len(), 1);
        assert_eq!((st.ended_left_footprint, st.ended_max_steps, st.ended_bottom), (0, 0, 0));
        for c in &st.curtains {
            let sum = c.deposited_power_w + c.backscattered_power_w + c.above_top_power_w + c.undeposited_power_w;
            assert!((sum / c.electron_power_w - 1.0).abs() < 1e-9, "{c:?}");
            assert_eq!(c.undeposited_power_w, 0.0);
            let g = crate::fang::SpectrumDeposition::curtain(s.curtains[0].char_energy_kev, s.curtains[0].soft_fraction, s.curtains[0].soft_energy_kev);
            assert!((c.backscattered_power_w / c.electron_power_w - (1.0 - g.total())).abs() < 1e-9, "{c:?}");
            let expect = c.electron_power_w - c.backscattered_power_w - c.above_top_power_w;
            assert!((c.deposited_power_w / expect - 1.0).abs() < 0.01, "{c:?}");
            // Soft electrons above 260 km: a few percent at most.
            assert!(c.above_top_power_w < 0.05 * c.electron_power_w, "{c:?}");
        }
        assert!((b.stats.deposited_power_w - st.deposited_power_w).abs() < 1e-9 * st.deposited_power_w);
        // The photons carry the deposited energy: total luminance > 0 and the
        // stats agree with the per-curtain sums.
        assert!((st.electron_power_w - st.curtains[0].electron_power_w).abs() < 1e-9 * st.electron_power_w);
        // CSDA keeps its old stopping rules, and reports what they leave.
        let mut c = small_scene();
        c.beams.deposition = crate::scene::Deposition::Csda;
        let st = bake(&c, &NoProgress).unwrap().stats.beam_stats;
        let cp = &st.curtains[0];
        assert!(st.ended_left_footprint > 0 && cp.undeposited_power_w > 0.0, "{st:?}");
        let sum = cp.deposited_power_w + cp.undeposited_power_w;
        assert!((sum / cp.electron_power_w - 1.0).abs() < 1e-9, "{cp:?}");
    }

    #[test]
    fn hard_spectrum_shows_the_pink_n2_first_positive_lower_border() {
        // 30 keV Maxwellian, no soft part, no colour noise: below 84 km the
        // grid is red and violet over green (N2 1P and N2+ 1N stay with N2,
        // 557.7 nm fades with O), while the green layer is green.
        let mut s = small_scene();
        s.curtains[0].char_energy_kev = 30.0;
        s.curtains[0].soft_fraction = 0.0;
        s.colour.noise_km = 0.0;
        s.beams.count = 600;
        let b = bake(&s, &NoProgress).unwrap();
        let band = |lo: f64, hi: f64| {
            let mut c = [0.0f64; 3];
            for (ijk, v) in b.emission.iter_active() {
                let z = ijk.z as f64 * b.stats.voxel_size_km;
                if (lo..hi).contains(&z) {
                    for k in 0..3 {
                        c[k] += v[k] as f64;
                    }
                }
            }
            c
        };
        let green = band(100.0, 120.0);
        assert!(green[1] > green[0] && green[1] > green[2], "100-120 km {green:?}");
        let border = band(76.0, 84.0);
        assert!(border[0] > border[1] && border[2] > border[1], "76-84 km {border:?}");
        assert!(border.iter().sum::<f64>() > 1e-3 * green.iter().sum::<f64>(), "a 30 keV spectrum lights 76-84 km: {border:?}");
    }

    #[test]
    fn aurora_is_green_in_the_middle_and_red_on_top() {
        // Luminance-weighted colour of the emission by altitude band.
        let mut s = small_scene();
        s.beams.count = 1500;
        let b = bake(&s, &NoProgress).unwrap();
        let band = |lo: f64, hi: f64| {
            let mut c = [0.0f64; 3];
            for (ijk, v) in b.emission.iter_active() {
                let z = ijk.z as f64 * b.stats.voxel_size_km;
                if (lo..hi).contains(&z) {
                    for k in 0..3 {
                        c[k] += v[k] as f64;
                    }
                }
            }
            c
        };
        let mid = band(105.0, 130.0);
        assert!(mid[1] > mid[0] && mid[1] > mid[2], "105-130 km {mid:?}");
        let top = band(230.0, 300.0);
        assert!(top[0] > top[1] && top[0] > top[2], "230-300 km {top:?}");
    }
}

#[cfg(test)]
mod auto_voxel_tests {
    use super::*;
    use crate::scene::{AutoTag, Projection};

    fn photon_at(p: [f32; 3]) -> Photon {
        Photon::point(p, [1.0; 3])
    }

    /// A pixel at distance d covers d * 2 tan(fov/2) / height.
    #[test]
    fn auto_voxel_projects_to_one_pixel_at_the_nearest_aurora() {
        let mut s = Scene::default();
        s.grid.voxel_size = VoxelSize::Auto(AutoTag::Auto);
        s.camera.position = [0.0, 0.0, 0.0];
        s.camera.fov_deg = 90.0;
        s.render.height = 100;
        s.photons.radius_km = 2.0;
        s.photons.radius_noise = 0.0;
        // 1000 photons at 150, 151, ... km: the 1st percentile (index 10) is 160 km.
        let photons: Vec<Photon> = (0..1000).map(|i| photon_at([0.0, 0.0, 150.0 + i as f32])).collect();
        let (v, why) = voxel_size(&s, &photons);
        assert!((v - 160.0 * 2.0 / 100.0).abs() < 1e-9, "{v} {why}");
        assert!(why.starts_with("auto"));
        // One stray photon near the camera moves the percentile by one photon
        // (159 km instead of 160), not to 1 km.
        let mut with_stray = photons.clone();
        with_stray.push(photon_at([0.0, 0.0, 1.0]));
        assert!((voxel_size(&s, &with_stray).0 - 1.59 * 2.0).abs() < 1e-9);
        // Never below half the kernel radius.
        s.photons.radius_km = 10.0;
        assert_eq!(voxel_size(&s, &photons).0, 5.0);
        // Never above twice the smallest radius (1.0 x (1 - 0.3) x 2 = 1.4 km).
        s.photons.radius_km = 1.0;
        s.photons.radius_noise = 0.3;
        let (v, why) = voxel_size(&s, &photons);
        assert!((v - 1.4).abs() < 1e-12 && why.contains("lowered"), "{v} {why}");
        assert!(resolution_warnings(&s, &[], v).is_empty(), "the bake does not warn about its own choice");
        // Orthographic: ortho_height / height.
        s.photons.radius_km = 0.1;
        s.photons.radius_noise = 0.0;
        s.camera.projection = Projection::Orthographic;
        s.camera.ortho_height = 20.0;
        assert!((voxel_size(&s, &photons).0 - 0.2).abs() < 1e-12);
    }
}
