//! The bake's gather: the emission grid by kernel density estimation over
//! the traced photons, on the transform `voxel_size * (i, j, k)` km
//! ([`crate::pipeline::voxel::grid_transform`]), with the per-line grids of
//! `grid.lines` and the velocity's numerator beside it.
//!
//! [`trace_and_gather`] is the bake's one trace-and-gather. It traces the
//! plan's chunks of beams ([`crate::pipeline::plan::BakePlan::chunks`];
//! `super::trace::for_each_chunk`) and adds each chunk's photons to
//! running per-leaf sums ([`GatherSums`]: the emission, each three of
//! `grid.lines`, the velocity's numerator), then drops them; the photons'
//! power is summed in photon order. Every sum thus has the terms, in the
//! order, of one gather of all the beams' photons: the grids, stats and
//! files are the same bytes for any chunk size (tested), thread count,
//! frame range or shard. A bake of one chunk (at most `beam_chunk` beams,
//! or `photons.gather = "report2014"`, whose weighted average is a ratio,
//! not a sum) is that loop with one chunk: its photons are gathered at
//! once ([`crate::pipeline::photons::gather_prepared`]) and kept
//! ([`super::Bake::photons`]).
//!
//! What stays per beam or per photon in a bake of several chunks: with
//! `voxel_size = "auto"` (and a camera with a pixel angle) the voxel size
//! is a percentile of every photon's distance from the camera, needed
//! before the first gather, so a first pass traces the chunks and keeps
//! those distances (8 bytes a photon, not the photon's 36, traced twice);
//! with `grid.velocity` each beam's velocity (12 bytes a beam).
//!
//! Candidate 8^3 leaves are those within `cutoff * r_max` of a photon,
//! gathered in parallel, collected in leaf order and sorted; a voxel is
//! active when its emission is nonzero (`crate::pipeline::photons`).

use super::result::BakeError;
use super::stats::{NoiseEstimate, StageTimes};
use super::trace::{for_each_chunk, trace_bake};
use super::velocity::{beam_velocities, weighted_photons, Motion};
use crate::grid::{Grid, Transform};
use crate::physics::emission::line_table::grid_name;
use crate::pipeline::beams::{self, BeamStats, Traced};
use crate::pipeline::deposit::Photon;
use crate::pipeline::footprint::curtain_path::bend_warnings;
use crate::pipeline::photons::{self, GatherInput, GatherSums};
use crate::pipeline::plan::BakePlan;
use crate::pipeline::voxel::{auto_voxel_size_of, camera_distances, grid_transform, needs_distances, resolution_warnings_for};
use crate::util::progress::{NoProgress, Progress};
use rayon::prelude::*;
use std::ops::Range;
use std::time::Instant;

/// The emission grid of `photons` at voxel size `voxel_km`, with the plan's
/// radius field, cutoff and gather method.
pub fn gather(plan: &BakePlan, photons: &[Photon], voxel_km: f64, progress: &dyn Progress) -> Grid<[f32; 3]> {
    gather_from(&plan.gather_input(photons), voxel_km, progress)
}

/// [`gather`] of photons made ready by [`BakePlan::gather_input`], with the plan they
/// were made with: the same grid.
pub fn gather_from(input: &GatherInput, voxel_km: f64, progress: &dyn Progress) -> Grid<[f32; 3]> {
    photons::gather_prepared(input, grid_transform(voxel_km), progress)
}

/// The photons carrying lines `first..first + 3` (at most; of the `n` a
/// photon's `line_power` holds) as their colours: one gather of the
/// per-line grids.
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

/// `total` plus the photons' powers, summed in photon order in f64.
pub fn sum_power(photons: &[Photon], mut total: [f64; 3]) -> [f64; 3] {
    for p in photons {
        for (t, &c) in total.iter_mut().zip(&p.power) {
            *t += c as f64;
        }
    }
    total
}

/// What [`super::finish::finish`] needs besides the plan and the emission grid.
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    /// The photons, when the bake kept them (one chunk; the preview).
    pub photons: Vec<Photon>,
    /// The per-line grids (named by [`grid_name`], rayleigh per km; empty
    /// without `grid.lines`).
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
    /// `photons` does not hold them all.
    pub photon_totals: Option<(usize, [f64; 3])>,
}

/// What [`super::finish::finish`] needs of `photons` (their per-line grids
/// `lines`, their beams' `beam_stats`) gathered at `voxel` (km, and where
/// that size came from): the warnings of that voxel size
/// ([`resolution_warnings_for`]), of the curtains' paths ([`bend_warnings`])
/// and of the power the beams did not deposit ([`beams::loss_warnings`]),
/// then `earlier` (the pilot's).
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
    let mut warnings = resolution_warnings_for(plan.kernel, &plan.footprints, plan.scene.footprint.threshold, voxel_km);
    warnings.extend(bend_warnings(&plan.scene.curtains));
    warnings.extend(beams::loss_warnings(&beam_stats));
    warnings.extend(earlier.iter().cloned());
    Gathered { photons, lines, beam_stats, voxel_km, voxel_source, warnings, noise, velocity: None, photon_totals: None }
}

/// One grid gathered a chunk of photons at a time: at once when the bake
/// has one chunk, else into running per-leaf sums.
enum Gatherer {
    Whole(Option<Grid<[f32; 3]>>, Transform),
    Sums(GatherSums),
}

impl Gatherer {
    fn new(whole: bool, transform: Transform) -> Self {
        if whole {
            Gatherer::Whole(None, transform)
        } else {
            Gatherer::Sums(GatherSums::new(transform))
        }
    }

    fn add(&mut self, input: &GatherInput, progress: &dyn Progress) {
        match self {
            Gatherer::Whole(grid, transform) => {
                debug_assert!(grid.is_none(), "a bake of one chunk gathers once");
                *grid = Some(photons::gather_prepared(input, *transform, progress));
            }
            Gatherer::Sums(sums) => sums.add(input, progress),
        }
    }

    fn finish(self) -> Grid<[f32; 3]> {
        match self {
            Gatherer::Whole(grid, transform) => grid.unwrap_or_else(|| Grid::new("emission", [0.0f32; 3], transform)),
            Gatherer::Sums(sums) => sums.finish("emission"),
        }
    }
}

/// The running gathers of one bake: the emission, each three of the
/// per-line grids, the velocity's numerator, and the photons' totals.
struct Running<'a> {
    plan: &'a BakePlan,
    emission: Gatherer,
    /// Lines per photon in a traced chunk's `line_power`.
    n_lines: usize,
    lines: Vec<Gatherer>,
    /// With `grid.velocity`, each beam's velocity and the numerator.
    velocity: Option<(Vec<[f32; 3]>, Gatherer)>,
    photons: usize,
    power: [f64; 3],
}

impl<'a> Running<'a> {
    fn new(plan: &'a BakePlan, count: usize, whole: bool, transform: Transform) -> Self {
        let n_lines = if plan.line_table.is_some() { plan.line_outputs.len() } else { 0 };
        let lines = (0..n_lines).step_by(3).map(|_| Gatherer::new(whole, transform)).collect();
        let velocity = plan.scene.grid.velocity.then(|| (beam_velocities(&Motion::of(plan), count), Gatherer::new(whole, transform)));
        Running { plan, emission: Gatherer::new(whole, transform), n_lines, lines, velocity, photons: 0, power: [0.0; 3] }
    }

    /// Adds the photons of beams `beams` (traced in photon order).
    fn add(&mut self, traced: &Traced, beams: Range<usize>, progress: &dyn Progress) {
        let plan = self.plan;
        self.photons += traced.photons.len();
        self.power = sum_power(&traced.photons, self.power);
        self.emission.add(&plan.gather_input(&traced.photons), progress);
        for (g, sums) in self.lines.iter_mut().enumerate() {
            let lined = lined_photons(&traced.photons, &traced.line_power, self.n_lines, 3 * g);
            sums.add(&plan.gather_input(&lined), progress);
        }
        if let Some((v, sums)) = self.velocity.as_mut() {
            sums.add(&plan.gather_input(&weighted_photons(traced, &v[beams])), progress);
        }
    }

    /// The emission grid, the per-line grids named by their lines, and the
    /// velocity's numerator.
    fn finish(self) -> Sums {
        let (plan, n) = (self.plan, self.n_lines);
        let lines = self
            .lines
            .into_iter()
            .enumerate()
            .flat_map(|(g, sums)| {
                let grid = sums.finish();
                (0..(n - 3 * g).min(3)).map(move |k| grid.component(k, grid_name(&plan.scene.grid.lines[3 * g + k])))
            })
            .collect();
        Sums { emission: self.emission.finish(), lines, velocity: self.velocity.map(|(_, sums)| sums.finish()) }
    }
}

/// The grids a bake's gather makes ([`Running::finish`]).
struct Sums {
    emission: Grid<[f32; 3]>,
    lines: Vec<Grid<f32>>,
    velocity: Option<Grid<[f32; 3]>>,
}

/// The voxel size of a bake of several chunks: the scene's, or for
/// `voxel_size = "auto"` with a camera the percentile of every photon's
/// distance, from a first pass over the chunks (module documentation).
/// Adds the seconds it traced to `trace_s`.
fn chunked_voxel_size(plan: &BakePlan, count: usize, trace_s: &mut f64, progress: &dyn Progress) -> Result<(f64, String), BakeError> {
    let camera = plan.camera_model().ok();
    match camera.as_ref().filter(|c| needs_distances(plan.scene.grid.voxel_size, Some(c))) {
        Some(cam) => {
            let mut d = Vec::new();
            *trace_s += for_each_chunk(plan, count, &mut BeamStats::default(), progress, |t, _| {
                d.extend(camera_distances(cam.position, &t.photons));
            })?;
            let (v, why) = auto_voxel_size_of(plan.kernel, Some(cam), d);
            Ok((v, format!("auto: {why}")))
        }
        None => Ok(plan.voxel_size(&[])),
    }
}

/// Stages 2 and 3: traces `count` beams, picks the voxel size and gathers
/// (module documentation). `times.beams` and `times.gather` are filled in.
pub fn trace_and_gather(
    plan: &BakePlan,
    count: usize,
    noise: Option<NoiseEstimate>,
    warnings: Vec<String>,
    times: &mut StageTimes,
    progress: &dyn Progress,
) -> Result<(Grid<[f32; 3]>, Gathered), BakeError> {
    let t_all = Instant::now();
    let whole = !plan.is_chunked(count);
    let mut trace_s = 0.0;
    // One chunk: traced once, its photons kept and their distances read
    // for the voxel size. Several: each chunk's photons dropped once added.
    let kept = if whole {
        let t = Instant::now();
        let traced = trace_bake(plan, count, progress)?;
        trace_s += t.elapsed().as_secs_f64();
        Some(traced)
    } else {
        None
    };
    let voxel = match &kept {
        Some(t) => plan.voxel_size(&t.photons),
        None => chunked_voxel_size(plan, count, &mut trace_s, progress)?,
    };
    let mut running = Running::new(plan, count, whole, grid_transform(voxel.0));
    let (photons, stats) = match kept {
        Some(traced) => {
            running.add(&traced, 0..count, progress);
            (traced.photons, traced.stats)
        }
        None => {
            let mut stats = BeamStats::default();
            trace_s += for_each_chunk(plan, count, &mut stats, progress, |t, beams| running.add(&t, beams, &NoProgress))?;
            stats.photons = running.photons;
            (Vec::new(), stats)
        }
    };
    let totals = (running.photons, running.power);
    let sums = running.finish();
    let mut g = gathered(plan, photons, sums.lines, stats, voxel, &warnings, noise);
    g.velocity = sums.velocity;
    g.photon_totals = Some(totals);
    times.beams = trace_s;
    times.gather = t_all.elapsed().as_secs_f64() - trace_s;
    Ok((sums.emission, g))
}
