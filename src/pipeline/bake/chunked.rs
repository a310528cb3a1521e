//! The bake's trace and gather a chunk of beams at a time, so its memory
//! does not grow with `beams.count`.
//!
//! [`trace_and_gather`] traces beams `[a, a + C)` for `C = ` the plan's
//! `beam_chunk` ([`super::plan::BEAM_CHUNK`], a constant), gathers their
//! photons into running per-leaf sums ([`GatherSums`]: the emission, each
//! three of `grid.lines`, the velocity's numerator), drops them, and goes
//! on to the next chunk; with the red trail, every chunk of each sample in
//! sample order. The beam stats are tallied across chunks in beam order
//! ([`crate::pipeline::beams::running`]) and the photons' power summed in
//! photon order. Every sum thus has the terms, in the order, of one trace
//! and one gather of all the beams ([`super::plan::trace_and_gather`]): the
//! grids, stats and files are the same bytes for any chunk size (tested),
//! thread count, frame range or shard.
//!
//! What stays per beam or per photon: with `voxel_size = "auto"` (and a
//! camera with a pixel angle) the voxel size is a percentile of every
//! photon's distance from the camera, needed before the first gather, so a
//! first pass traces the chunks and keeps those distances (8 bytes a
//! photon, not the photon's 36, traced twice); with `grid.velocity` each
//! beam's velocity (12 bytes a beam). `photons.gather = "report2014"`'s
//! weighted average is a ratio, not a sum: it is gathered whole, as is a
//! bake of one chunk (which keeps its photons in [`super::Bake`]).

use super::plan::{self, gather_input, gathered, lined_photons, simulate_footprints, sum_power, BakePlan, Gathered};
use super::result::BakeError;
use super::stats::{NoiseEstimate, StageTimes};
use super::velocity::{beam_velocities, weighted_photons};
use super::voxel::{auto_voxel_size_of, camera_distances, grid_transform, needs_distances};
use crate::grid::Grid;
use crate::pipeline::beams::running::{finish_running, trace_range_running};
use crate::pipeline::beams::{BeamError, BeamStats, TraceParams, Traced};
use crate::pipeline::footprint::curtain_path::Lift;
use crate::pipeline::photons::GatherSums;
use crate::pipeline::red_trail::{self, TrailSample};
use crate::scene::{AnimationParams, GatherMethod};
use crate::util::progress::{NoProgress, Progress};
use std::ops::Range;
use std::time::Instant;

/// Traces `count` beams, picks the voxel size and gathers, a chunk of
/// beams at a time when there is more than one (module documentation);
/// otherwise [`super::plan::trace_and_gather`]. `times.beams` and
/// `times.gather` are filled in.
pub fn trace_and_gather(
    plan: &BakePlan,
    count: usize,
    noise: Option<NoiseEstimate>,
    warnings: Vec<String>,
    times: &mut StageTimes,
    progress: &dyn Progress,
) -> Result<(Grid<[f32; 3]>, Gathered), BakeError> {
    let chunk = plan.beam_chunk.max(1);
    if count <= chunk || plan.photons.gather == GatherMethod::Report2014 {
        return plan::trace_and_gather(plan, count, noise, warnings, times, progress);
    }
    let t_all = Instant::now();
    let camera = plan.camera_model().ok();
    let mut trace_s = 0.0;
    let voxel = match camera.as_ref().filter(|c| needs_distances(plan.grid.voxel_size, Some(c))) {
        Some(cam) => {
            let mut d = Vec::new();
            trace_s += for_each_chunk(plan, count, &mut BeamStats::default(), progress, |t, _| {
                d.extend(camera_distances(cam.position, &t.photons));
            })?;
            let (v, why) = auto_voxel_size_of(plan.kernel, Some(cam), d);
            (v, format!("auto: {why}"))
        }
        None => plan.voxel_size(&[]),
    };
    let transform = grid_transform(voxel.0);
    let mut emission = GatherSums::new(transform);
    let n_lines = if plan.line_table.is_some() { plan.line_outputs.len() } else { 0 };
    let mut lines: Vec<GatherSums> = (0..n_lines).step_by(3).map(|_| GatherSums::new(transform)).collect();
    let velocities = plan.grid.velocity.then(|| beam_velocities(&plan.motion(), count));
    let mut velocity = plan.grid.velocity.then(|| GatherSums::new(transform));
    let mut stats = BeamStats::default();
    let (mut photon_count, mut total) = (0usize, [0.0f64; 3]);
    trace_s += for_each_chunk(plan, count, &mut stats, progress, |traced, beams| {
        photon_count += traced.photons.len();
        total = sum_power(&traced.photons, total);
        emission.add(&gather_input(plan, &traced.photons), &NoProgress);
        for (g, sums) in lines.iter_mut().enumerate() {
            let lined = lined_photons(&traced.photons, &traced.line_power, n_lines, 3 * g);
            sums.add(&gather_input(plan, &lined), &NoProgress);
        }
        if let (Some(sums), Some(v)) = (velocity.as_mut(), velocities.as_ref()) {
            sums.add(&gather_input(plan, &weighted_photons(&traced, &v[beams])), &NoProgress);
        }
    })?;
    finish_running(&mut stats);
    stats.photons = photon_count;
    let line_grids = lines
        .into_iter()
        .enumerate()
        .flat_map(|(g, sums)| {
            let grid = sums.finish("emission");
            let take = (n_lines - 3 * g).min(3);
            (0..take).map(move |k| grid.component(k, crate::physics::emission::line_table::grid_name(&plan.grid.lines[3 * g + k])))
        })
        .collect();
    let emission = emission.finish("emission");
    let mut g = gathered(plan, Vec::new(), line_grids, stats, voxel, &warnings, noise);
    g.velocity = velocity.map(|v| v.finish("emission"));
    g.photon_totals = Some((photon_count, total));
    times.beams = trace_s;
    times.gather = t_all.elapsed().as_secs_f64() - trace_s;
    Ok((emission, g))
}

/// Traces the bake's `count` beams a chunk at a time, in photon order (with
/// the red trail, each sample's chunks in sample order: `trace_trail`'s
/// order) and hands each chunk's photons and beam range to `each`; the
/// beams of the plan's own time are tallied into `stats`. Returns the
/// seconds spent tracing.
fn for_each_chunk(
    plan: &BakePlan,
    count: usize,
    stats: &mut BeamStats,
    progress: &dyn Progress,
    mut each: impl FnMut(Traced, Range<usize>),
) -> Result<f64, BeamError> {
    let chunk = plan.beam_chunk.max(1);
    let samples: Vec<Option<TrailSample>> = match (plan.animation.trail_samples, &plan.line_table) {
        (n, Some(_)) if n > 0 => red_trail::samples(n).into_iter().map(Some).collect(),
        _ => vec![None],
    };
    // The bar counts beams traced, as a whole bake's does; each chunk's
    // gather runs between its beams and the next chunk's.
    progress.start("beams", (count * samples.len()) as u64);
    let mut trace_s = 0.0;
    for (k, sample) in samples.into_iter().enumerate() {
        let animation = match sample {
            Some(s) => AnimationParams { time_s: plan.animation.time_s - s.lag_s, ..plan.animation.clone() },
            None => plan.animation.clone(),
        };
        let earlier;
        let footprints = if sample.is_none_or(|s| s.is_now()) {
            &plan.footprints
        } else {
            let lift = Lift::of(&plan.beams, &plan.earth);
            earlier = simulate_footprints(plan.seed, &plan.curtains, &plan.footprint, &animation, lift, &NoProgress);
            &earlier
        };
        let params = TraceParams { animation: &animation, trail: sample, ..plan.trace_params() };
        // The stats are the plan's time's, the first sample's.
        let mut other = BeamStats::default();
        for first in (0..count).step_by(chunk) {
            let beams = first..(first + chunk).min(count);
            let running = if k == 0 { &mut *stats } else { &mut other };
            let t = Instant::now();
            let traced =
                trace_range_running(&params, footprints, &plan.atmosphere, &plan.colour_table, count, 0, beams.clone(), running, progress)?;
            trace_s += t.elapsed().as_secs_f64();
            each(traced, beams);
        }
    }
    progress.finish();
    Ok(trace_s)
}
