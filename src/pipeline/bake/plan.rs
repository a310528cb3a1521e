//! One [`BakePlan`] built from a scene, and the stages
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
//!    ([`super::pilot`], which traces and gathers through this plan);
//! 3. the emission grid by kernel density estimation over the photons
//!    ([`gather`], on the transform `voxel_size * (i, j, k)` km of
//!    [`BakePlan::voxel_size`]): candidate 8^3 leaves are those within
//!    `cutoff * r_max` of a photon, gathered in parallel, collected in leaf
//!    order and sorted; a voxel is active when its emission is nonzero;
//! 4. [`finish`]: the f32 / half-float range checks; with `grid.prune > 0`,
//!    the leaves faintest at the camera dropped within that error budget
//!    ([`crate::pipeline::prune`]); the density grid on the (kept) active voxels
//!    ([`super::density::density_grid`]); with `grid.cycles_shell`, both grids dilated by one
//!    voxel of active zeros ([`crate::grid::Grid::dilate_active`]); the
//!    stats.
//!
//! [`super::bake`] composes them for a scene; `crate::app::preview` keeps
//! their outputs between edits; the bench and frame sequences reuse a plan
//! ([`BakePlan::reusing`] keeps the footprints, atmosphere and colour table
//! when the sections they depend on are unchanged: a new frame time
//! recomputes only the footprints). Nothing here imports the
//! composition or the pilot.
//!
//! [`super::voxel::resolution_warnings`] flags bakes whose voxels under-resolve the kernel
//! or the curtains, [`crate::pipeline::footprint::curtain_path::bend_warnings`] paths bent tighter than half their
//! curtain's width, [`super::density::extinction_warning`] air
//! extinction clamped at [`super::density::MAX_EXTINCTION_PER_KM`] (`BakeStats::warnings`; the CLI prints them on
//! stderr). Emission that overflows f32 is an error, never a file.
//!
//! `photons.radius_km` is read in one place, [`crate::scene::KernelRadius::of`].

use super::density::{density_grid, extinction_warning};
use super::result::{empty_reason, Bake, BakeError};
use super::stats::{BakeStats, NoiseEstimate, StageTimes};
use super::voxel::{grid_transform, resolution_warnings_for, voxel_size_for};
use crate::geometry::camera::{CameraError, CameraModel};
use crate::geometry::earth::Earth;
use crate::grid::{Grid, Leaf};
use crate::physics::atmosphere::Atmosphere;
use crate::physics::emission::line_colour::{ColourTable, EmissionModel};
use crate::physics::emission::line_table::{grid_name, line_index, LineTable};
use crate::physics::geomagnetic_field::MagneticField;
use crate::pipeline::beams::{self, BeamError, BeamStats, TraceParams, Traced};
use crate::pipeline::deposit::Photon;
use crate::pipeline::footprint::curtain_path::{bend_warnings, Lift};
use crate::pipeline::footprint::{self, Footprint};
use crate::pipeline::photons::{self, radius::RadiusField};
use crate::pipeline::prune;
use crate::scene::{
    AnimationParams, AtmosphereParams, BeamParams, Camera, ColourMode, ColourParams, Curtain, EarthParams, FootprintParams, GatherMethod,
    GridParams, KernelRadius, LineModel, PhotonParams, Scene,
};
use crate::util::colour::luminance;
use crate::util::progress::{NoProgress, Progress};
use glam::DVec3;
use rayon::prelude::*;
use std::ops::Range;
use std::time::Instant;

/// One footprint per curtain (in curtain order; simulated in parallel), at
/// the scene's `animation.time_s`.
pub fn footprints(scene: &Scene) -> Vec<Footprint> {
    let lift = Lift::of(&scene.beams, &scene.earth);
    simulate_footprints(scene.seed, &scene.curtains, &scene.footprint, &scene.animation, lift, &NoProgress)
}

/// One footprint per curtain at `animation.time_s`, in parallel; paths
/// lifted by `lift` to the start altitude ([`crate::pipeline::footprint::curtain_path::Lift`]).
pub fn simulate_footprints(
    seed: u64,
    curtains: &[Curtain],
    params: &FootprintParams,
    animation: &AnimationParams,
    lift: Lift,
    progress: &dyn Progress,
) -> Vec<Footprint> {
    progress.start("footprints", curtains.len() as u64);
    let fps = curtains
        .par_iter()
        .map(|c| {
            let f = footprint::simulate_at(c, params, animation, seed, animation.time_s, lift);
            progress.inc(1);
            f
        })
        .collect();
    progress.finish();
    fps
}

/// The colour table the scene asks for.
pub fn colour_table(scene: &Scene, atmosphere: &Atmosphere) -> ColourTable {
    colour_table_for(&scene.colour, atmosphere)
}

/// The colour table of `[colour]` (its mode and colour map).
pub fn colour_table_for(colour: &ColourParams, atmosphere: &Atmosphere) -> ColourTable {
    match colour.mode {
        ColourMode::Physical => match colour.lines {
            LineModel::Chemistry => ColourTable::chemistry(atmosphere, colour.observer),
            LineModel::Simple => ColourTable::physical(&EmissionModel::new(atmosphere.clone()).with_observer(colour.observer)),
        },
        ColourMode::Colormap => ColourTable::colormap(&colour.colormap),
    }
}

/// The scene's neutral atmosphere (`[atmosphere] model`).
pub fn atmosphere(scene: &Scene) -> Atmosphere {
    atmosphere_for(&scene.atmosphere)
}

/// The neutral atmosphere of `[atmosphere]`.
pub fn atmosphere_for(params: &AtmosphereParams) -> Atmosphere {
    // A table from the data folder was read when the scene was checked
    // (`Atmosphere::of_params`, kept for the process): this cannot fail then.
    Atmosphere::of_params(params).unwrap_or_else(|e| panic!("{e}"))
}

/// The kernel radius field at base radius `kernel.base_km` (noise from
/// `photons.radius_noise_freq`, along the field `b` from the beams' top
/// `top_km`, seeded by the scene seed).
pub fn radius_field(kernel: KernelRadius, p: &PhotonParams, b: DVec3, top_km: f64, seed: u64) -> RadiusField {
    RadiusField::new(kernel.base_km, kernel.noise, p.radius_noise_freq, b, top_km, &[seed])
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
    /// `[earth]`: the ground's shape and the dipole pole.
    pub earth: EarthParams,
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
    /// The lines one at a time ([`line_table_for`]): with a physical colour
    /// and a pulsation or `grid.lines`; `None` otherwise (the default bake
    /// builds none).
    pub line_table: Option<LineTable>,
    /// `grid.lines` as indices in `crate::physics::emission::line_colour::LINES`.
    pub line_outputs: Vec<usize>,
    /// Beams traced and gathered at a time ([`BEAM_CHUNK`]; `super::chunked`).
    /// The output does not depend on it; a test sets it smaller.
    pub beam_chunk: usize,
}

/// Beams a bake traces and gathers at a time (`super::chunked`): a constant,
/// so the bake's working set is the same whatever the memory limit or the
/// thread count. 8192 beams of the 2014 report's 250 steps are 2 M photons,
/// 74 MB a copy.
pub const BEAM_CHUNK: usize = 8192;

/// The per-line table a scene needs: with `colour.mode = "physical"`, when
/// something pulses (each line then follows its lifetime), the red trail is
/// on (`animation.trail_samples`) or `grid.lines` asks for per-line grids;
/// `None` otherwise.
pub fn line_table_for(colour: &ColourParams, animation: &AnimationParams, grid: &GridParams, atmosphere: &Atmosphere) -> Option<LineTable> {
    needs_line_table(colour, animation, grid)
        .then(|| LineTable::new(&EmissionModel::new(atmosphere.clone()).with_observer(colour.observer)))
}

/// Whether [`line_table_for`] builds a table.
pub fn needs_line_table(colour: &ColourParams, animation: &AnimationParams, grid: &GridParams) -> bool {
    colour.mode == ColourMode::Physical && (animation.pulsation > 0.0 || animation.trail_samples > 0 || !grid.lines.is_empty())
}

/// `grid.lines` as indices in `crate::physics::emission::line_colour::LINES` (the scene has
/// checked the names).
pub fn line_outputs(grid: &GridParams) -> Vec<usize> {
    grid.lines.iter().filter_map(|k| line_index(k)).collect()
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

    /// Whether this plan's footprints are `scene`'s: the same seed,
    /// curtains, `[footprint]`, `[animation]` and Earth.
    pub fn has_footprints_of(&self, scene: &Scene) -> bool {
        self.seed == scene.seed
            && self.curtains == scene.curtains
            && self.footprint == scene.footprint
            && self.animation == scene.animation
            && self.earth == scene.earth
    }

    fn build(scene: &Scene, prev: Option<&BakePlan>, progress: &dyn Progress) -> BakePlan {
        let t = Instant::now();
        let same_fp = prev.filter(|p| p.has_footprints_of(scene));
        let (footprints, footprint_seconds) = match same_fp {
            Some(p) => (p.footprints.clone(), 0.0),
            None => {
                let f = simulate_footprints(
                    scene.seed,
                    &scene.curtains,
                    &scene.footprint,
                    &scene.animation,
                    Lift::of(&scene.beams, &scene.earth),
                    progress,
                );
                (f, t.elapsed().as_secs_f64())
            }
        };
        let same_colour = prev.filter(|p| {
            p.atmosphere_params == scene.atmosphere
                && p.colour.mode == scene.colour.mode
                && p.colour.lines == scene.colour.lines
                && p.colour.colormap == scene.colour.colormap
        });
        let (atmosphere, colour_table) = match same_colour {
            Some(p) => (p.atmosphere.clone(), p.colour_table.clone()),
            None => {
                let a = atmosphere_for(&scene.atmosphere);
                let c = colour_table_for(&scene.colour, &a);
                (a, c)
            }
        };
        // Same atmosphere and colour mode: the same table, if any was built.
        let line_table = match same_colour.and_then(|p| p.line_table.as_ref()) {
            Some(t) if needs_line_table(&scene.colour, &scene.animation, &scene.grid) => Some(t.clone()),
            _ => line_table_for(&scene.colour, &scene.animation, &scene.grid, &atmosphere),
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
            earth: scene.earth.clone(),
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
            line_table,
            line_outputs: line_outputs(&scene.grid),
            beam_chunk: BEAM_CHUNK,
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
            lines: self.line_table.as_ref(),
            line_outputs: if self.line_table.is_some() { &self.line_outputs } else { &[] },
            trail: None,
            earth: Earth::new(self.earth.radius_km),
            magnetic_pole: self.earth.magnetic_pole,
        }
    }

    /// What the velocity grid reads of the plan (`super::velocity`).
    pub fn motion(&self) -> super::velocity::Motion<'_> {
        super::velocity::Motion {
            seed: self.seed,
            curtains: &self.curtains,
            footprint: &self.footprint,
            animation: &self.animation,
            beams: &self.beams,
            earth: &self.earth,
            now: &self.footprints,
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
/// ([`crate::pipeline::beams::trace_range`]): the same beam whatever the chunking.
pub fn trace(plan: &BakePlan, count: usize, stream_offset: u64, beams: Range<usize>, progress: &dyn Progress) -> Result<Traced, BeamError> {
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

/// The bake's photons: `count` beams ([`trace`]), or with the red trail on
/// (`animation.trail_samples > 0` and a physical colour) [`trace_trail`].
pub fn trace_bake(plan: &BakePlan, count: usize, progress: &dyn Progress) -> Result<Traced, BeamError> {
    match (plan.animation.trail_samples, &plan.line_table) {
        (n, Some(_)) if n > 0 => trace_trail(plan, count, n, progress),
        _ => trace(plan, count, 0, 0..count, progress),
    }
}

/// The red trail's trace (`crate::pipeline::red_trail`): the beams at the plan's time with
/// every line (the O(1D) lines weighted by the first sample), then for each
/// of `n` earlier times `t - s_k` the footprints of that time and the same
/// beams again carrying only the O(1D) lines with that sample's weight;
/// the photons (and per-line powers) concatenated in sample order. The
/// stats are the plan's time's.
pub fn trace_trail(plan: &BakePlan, count: usize, n: u32, progress: &dyn Progress) -> Result<Traced, BeamError> {
    let lift = Lift::of(&plan.beams, &plan.earth);
    let mut out: Option<Traced> = None;
    for sample in crate::pipeline::red_trail::samples(n) {
        let animation = AnimationParams { time_s: plan.animation.time_s - sample.lag_s, ..plan.animation.clone() };
        let earlier;
        let footprints = if sample.is_now() {
            &plan.footprints
        } else {
            earlier = simulate_footprints(plan.seed, &plan.curtains, &plan.footprint, &animation, lift, &NoProgress);
            &earlier
        };
        let params = TraceParams { animation: &animation, trail: Some(sample), ..plan.trace_params() };
        let t = beams::trace_range(&params, footprints, &plan.atmosphere, &plan.colour_table, count, 0, 0..count, false, progress)?;
        match out.as_mut() {
            None => out = Some(t),
            Some(o) => {
                o.photons.extend(t.photons);
                o.line_power.extend(t.line_power);
                o.beam_photons.extend(t.beam_photons);
            }
        }
    }
    let mut out = out.expect("a trail has its own time's sample");
    out.stats.photons = out.photons.len();
    Ok(out)
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

/// [`gather`] of photons made ready by [`gather_input`], with the plan they
/// were made with: the same grid.
pub fn gather_from(input: &photons::GatherInput, voxel_km: f64, progress: &dyn Progress) -> Grid<[f32; 3]> {
    photons::gather_prepared(input, grid_transform(voxel_km), progress)
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

/// The per-line grids of `grid.lines` (named [`grid_name`], in rayleigh
/// per km: `crate::physics::emission::line_table`): the photons' segments carrying each line's
/// power (`line_power`, `outputs.len()` values a photon) gathered by
/// [`gather`] with the plan's kernel on the same transform, three lines a
/// gather. Empty without outputs.
pub fn line_grids(plan: &BakePlan, photons: &[Photon], line_power: &[f32], voxel_km: f64, progress: &dyn Progress) -> Vec<Grid<f32>> {
    let n = plan.line_outputs.len();
    if n == 0 || plan.line_table.is_none() {
        return Vec::new();
    }
    debug_assert_eq!(line_power.len(), n * photons.len());
    let mut grids = Vec::with_capacity(n);
    for first in (0..n).step_by(3) {
        let take = (n - first).min(3);
        let lined = lined_photons(photons, line_power, n, first);
        let g = gather(plan, &lined, voxel_km, progress);
        for k in 0..take {
            grids.push(g.component(k, grid_name(&plan.grid.lines[first + k])));
        }
    }
    grids
}

/// The photons carrying lines `first..first + 3` (at most; of the `n` a
/// photon's `line_power` holds) as their colours: one gather of
/// [`line_grids`].
pub fn lined_photons(photons: &[Photon], line_power: &[f32], n: usize, first: usize) -> Vec<Photon> {
    let take = (n - first).min(3);
    photons
        .par_iter()
        .enumerate()
        .map(|(j, p)| {
            let row = &line_power[j * n + first..j * n + first + take];
            let mut power = [0.0f32; 3];
            power[..take].copy_from_slice(row);
            Photon { power, ..*p }
        })
        .collect()
}

/// What [`finish`] needs besides the plan and the emission grid.
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    pub photons: Vec<Photon>,
    /// The per-line grids ([`line_grids`]; empty without `grid.lines`).
    pub lines: Vec<Grid<f32>>,
    pub beam_stats: BeamStats,
    pub voxel_km: f64,
    pub voxel_source: String,
    /// Warnings so far (resolution, pilot).
    pub warnings: Vec<String>,
    pub noise: Option<NoiseEstimate>,
    /// With `grid.velocity`, the luminance-weighted velocity gathered like
    /// the emission ([`super::velocity::weighted_photons`]).
    pub velocity: Option<Grid<[f32; 3]>>,
    /// The photons' count and summed power (f64, in photon order) when
    /// `photons` does not hold them (a bake traced in chunks keeps none).
    pub photon_totals: Option<(usize, [f64; 3])>,
}

/// What [`finish`] needs of `photons` (their per-line grids `lines`, their
/// beams' `beam_stats`) gathered at `voxel` (km, and where that size came
/// from): the warnings of that voxel size ([`resolution_warnings_for`]), of
/// the curtains' paths ([`bend_warnings`]) and of the power the beams did
/// not deposit ([`beams::loss_warnings`]), then `earlier` (the pilot's).
pub fn gathered(
    plan: &BakePlan,
    photons: Vec<Photon>,
    lines: Vec<Grid<f32>>,
    beam_stats: BeamStats,
    voxel: (f64, String),
    earlier: &[String],
    noise: Option<NoiseEstimate>,
) -> Gathered {
    let (voxel_km, voxel_source) = voxel;
    let mut warnings = resolution_warnings_for(plan.kernel, &plan.footprints, plan.footprint.threshold, voxel_km);
    warnings.extend(bend_warnings(&plan.curtains));
    warnings.extend(beams::loss_warnings(&beam_stats));
    warnings.extend(earlier.iter().cloned());
    Gathered { photons, lines, beam_stats, voxel_km, voxel_source, warnings, noise, velocity: None, photon_totals: None }
}

/// Traces `count` beams, picks the voxel size and gathers: stages 2 and 3.
/// `times.beams` and `times.gather` are filled in.
pub fn trace_and_gather(
    plan: &BakePlan,
    count: usize,
    noise: Option<NoiseEstimate>,
    warnings: Vec<String>,
    times: &mut StageTimes,
    progress: &dyn Progress,
) -> Result<(Grid<[f32; 3]>, Gathered), BakeError> {
    let t = Instant::now();
    let traced = trace_bake(plan, count, progress)?;
    times.beams = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let voxel = plan.voxel_size(&traced.photons);
    let emission = gather(plan, &traced.photons, voxel.0, progress);
    let lines = line_grids(plan, &traced.photons, &traced.line_power, voxel.0, progress);
    let velocity = plan.grid.velocity.then(|| {
        let v = super::velocity::beam_velocities(&plan.motion(), count);
        gather(plan, &super::velocity::weighted_photons(&traced, &v), voxel.0, progress)
    });
    let mut g = gathered(plan, traced.photons, lines, traced.stats, voxel, &warnings, noise);
    g.velocity = velocity;
    times.gather = t.elapsed().as_secs_f64();
    Ok((emission, g))
}

/// The emission's checks and peaks, the first step of [`finish`]: every
/// active value finite (else [`BakeError::NonFinite`] at the first bad voxel
/// in leaf order), and the largest component and luminance. Per leaf in parallel; the first error in
/// leaf order wins and maxima do not depend on the order, so the outcome is
/// the same whatever the thread count.
pub fn scan_emission(emission: &Grid<[f32; 3]>, radius_km: f64) -> Result<([f32; 3], f64), BakeError> {
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

/// Where `grid.half_emission` or `grid.half_density` asks for half floats
/// a grid's values exceed (|x| > 65504, the largest half): that grid is
/// written as full floats ([`crate::io::bake_folder::fit_half`]) and the bake says so.
fn half_warnings(grid: &crate::scene::GridParams, peak: [f32; 3], density: &Grid<f32>) -> Vec<String> {
    let max = half::f16::MAX.to_f32();
    let mut w = Vec::new();
    let e = peak.iter().fold(0.0f32, |m, x| m.max(*x));
    if grid.half_emission && e > max {
        w.push(format!("the emission reaches {e} (beyond the half-float range, |x| <= 65504): `emission` is stored as full floats although grid.half_emission = true"));
    }
    if grid.half_density {
        let d = density.iter_active().fold(0.0f32, |m, (_, x)| m.max(x.abs()));
        if d > max {
            w.push(format!("the density reaches {d} (beyond the half-float range, |x| <= 65504): `density` is stored as full floats although grid.half_density = true"));
        }
    }
    w
}

/// `total` plus the photons' powers, summed in photon order in f64.
pub fn sum_power(photons: &[Photon], mut total: [f64; 3]) -> [f64; 3] {
    for p in photons {
        for (t, &c) in total.iter_mut().zip(&p.power) {
            *t += c as f64;
        }
    }
    total
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

/// The leaves pruning dropped, in leaf order ([`finish_keeping`]).
pub type DroppedLeaves = Vec<Leaf<[f32; 3]>>;

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
) -> Result<(Bake, DroppedLeaves), BakeError> {
    let Gathered { photons, mut lines, beam_stats, voxel_km: vs, voxel_source: vs_source, mut warnings, noise, velocity, photon_totals } =
        g;
    if emission.leaf_count() == 0 {
        return Err(BakeError::Empty(empty_reason(&beam_stats, &plan.beams)));
    }
    let transform = emission.transform;

    let t = Instant::now();
    let (peak, peak_y) = scan_emission(&emission, plan.kernel.base_km)?;
    if let Some((lo, hi)) = emission.index_bbox() {
        // The lowest altitude in the grid's box: at the box's point nearest
        // the Earth's centre (the lowest z when flat).
        let (lo, hi) = (transform.index_to_world(lo.as_dvec3()), transform.index_to_world(hi.as_dvec3()));
        let earth = Earth::new(plan.earth.radius_km);
        let h_min = if earth.is_flat() { lo.z } else { earth.altitude(earth.centre().clamp(lo, hi)) };
        warnings.extend(extinction_warning(&plan.grid, h_min));
    }
    let scan_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut emission = emission;
    let (prune_stats, dropped) = if plan.grid.prune > 0.0 {
        let camera = plan.camera_model()?;
        let (st, dropped) = prune::prune_keeping(&mut emission, &camera, plan.grid.prune);
        // The per-line grids keep the leaves the emission kept (crate::pipeline::prune).
        for g in &mut lines {
            prune::prune_like(g, &emission);
        }
        (Some(st), dropped)
    } else {
        (None, Vec::new())
    };
    times.prune = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.start("density", emission.leaf_count() as u64);
    let mut density = density_grid(&emission, &plan.grid, peak_y, &Earth::new(plan.earth.radius_km));
    progress.inc(emission.leaf_count() as u64);
    progress.finish();
    warnings.extend(half_warnings(&plan.grid, peak, &density));
    let (aurora_voxels, aurora_leaves) = (emission.active_voxel_count(), emission.leaf_count());
    // On the kept voxels, before the shell (whose zeros are at rest).
    let mut velocity = velocity.map(|num| super::velocity::velocity_grid(&emission, &num));
    let shell_voxels = if plan.grid.cycles_shell {
        // Both grids live on the same voxels: the density takes the
        // emission's dilation rather than computing it again.
        let n = emission.dilate_active();
        let m = density.activate_like(&emission);
        debug_assert_eq!(n, m, "both grids live on the same voxels");
        if let Some(v) = velocity.as_mut() {
            v.activate_like(&emission);
        }
        n
    } else {
        0
    };
    times.density = scan_s + t.elapsed().as_secs_f64();
    times.total = t_all.elapsed().as_secs_f64();

    let (photon_count, total) = photon_totals.unwrap_or_else(|| (photons.len(), sum_power(&photons, [0.0; 3])));
    let bbox = emission.index_bbox();
    let stats = BakeStats {
        units: "km",
        seed: plan.seed,
        scene_hash: plan.scene_hash.clone(),
        voxel_size_km: vs,
        voxel_size_source: vs_source,
        gather: plan.photons.gather,
        beams: beam_stats.beams,
        photons: photon_count,
        active_voxels: aurora_voxels,
        leaves: aurora_leaves,
        shell_voxels,
        file_voxels: emission.active_voxel_count(),
        file_leaves: emission.leaf_count(),
        index_bbox: bbox.map(|(a, b)| [a.to_array(), b.to_array()]),
        world_bbox: bbox
            .map(|(a, b)| [transform.index_to_world(a.as_dvec3()).to_array(), transform.index_to_world(b.as_dvec3()).to_array()]),
        peak_emission: peak,
        peak_luminance: peak_y,
        total_emitted_power: total,
        total_emitted_luminance: luminance(total),
        electron_power_w: beam_stats.electron_power_w,
        deposited_power_w: beam_stats.deposited_power_w,
        deposited_fraction: beam_stats.deposited_fraction,
        beam_stats,
        times_s: times,
        noise,
        prune: prune_stats,
        warnings,
    };
    Ok((Bake { emission, density, lines, velocity, photons, stats }, dropped))
}
