//! The bake's trace: electron beams through the atmosphere, leaving
//! photons, a chunk of beams at a time ([`for_each_chunk`]).
//!
//! Beam `i` of a curtain is traced on random stream `stream_offset + i`
//! ([`crate::pipeline::beams::trace_range`]), so a beam is the same beam
//! whatever range it is traced in, and chunks concatenate to the whole,
//! byte for byte. The plan's chunks ([`BakePlan::chunks`]) are traced in
//! beam order; with the red trail on (`animation.trail_samples > 0` and a
//! physical colour, `crate::pipeline::red_trail`) every chunk of each
//! sample in sample order: the beams at the plan's time with every line
//! (the O(1D) lines weighted by the first sample), then for each of `n`
//! earlier times `t - s_k` the footprints of that time and the same beams
//! again carrying only the O(1D) lines with that sample's weight. The beam
//! stats are the plan's time's, tallied across chunks in beam order
//! ([`crate::pipeline::beams::running`]): the same f64 terms in the same
//! order as one trace of every beam.
//!
//! [`trace_bake`] is that trace kept whole (the preview, which keeps its
//! photons); [`trace`] one range of beams (the pilots).

use crate::pipeline::beams::running::{finish_running, trace_range_running};
use crate::pipeline::beams::{self, BeamError, BeamStats, TraceParams, Traced};
use crate::pipeline::footprint::curtain_path::Lift;
use crate::pipeline::plan::{simulate_footprints, BakePlan};
use crate::pipeline::red_trail::{self, TrailSample};
use crate::scene::AnimationParams;
use crate::util::progress::{NoProgress, Progress};
use std::ops::Range;
use std::time::Instant;

/// Traces beams `beams` of a bake of `count` beams, beam `i` of a curtain
/// on random stream `stream_offset + i`, with the stats of that range
/// ([`crate::pipeline::beams::trace_range`]).
pub fn trace(plan: &BakePlan, count: usize, stream_offset: u64, beams: Range<usize>, progress: &dyn Progress) -> Result<Traced, BeamError> {
    beams::trace_range(&plan.trace_params(), count, stream_offset, beams, false, progress)
}

/// The red trail's samples the bake traces: every sample with the trail
/// on (a physical colour, so a line table, and `animation.trail_samples >
/// 0`), else the plan's time alone (`None`).
fn samples(plan: &BakePlan) -> Vec<Option<TrailSample>> {
    match (plan.scene.animation.trail_samples, &plan.line_table) {
        (n, Some(_)) if n > 0 => red_trail::samples(n).into_iter().map(Some).collect(),
        _ => vec![None],
    }
}

/// Traces the bake's `count` beams a chunk of the plan's at a time, in
/// photon order (module documentation), and hands each chunk's photons
/// and beam range to `each`; the beams of the plan's own time are tallied
/// into `stats`, which holds their totals at the end. Returns the seconds
/// spent tracing (not in `each`).
pub fn for_each_chunk(
    plan: &BakePlan,
    count: usize,
    stats: &mut BeamStats,
    progress: &dyn Progress,
    mut each: impl FnMut(Traced, Range<usize>),
) -> Result<f64, BeamError> {
    let samples = samples(plan);
    let chunks = plan.chunks(count);
    // The bar counts beams traced; each chunk's gather runs between its
    // beams and the next chunk's.
    progress.start("beams", (count * samples.len()) as u64);
    let mut trace_s = 0.0;
    let scene = &plan.scene;
    for (k, sample) in samples.into_iter().enumerate() {
        let animation = match sample {
            Some(s) => AnimationParams { time_s: scene.animation.time_s - s.lag_s, ..scene.animation.clone() },
            None => scene.animation.clone(),
        };
        let earlier;
        let footprints = if sample.is_none_or(|s| s.is_now()) {
            &plan.footprints
        } else {
            let lift = Lift::of_scene(scene);
            earlier = simulate_footprints(scene.seed, &scene.curtains, &scene.footprint, &animation, lift, &NoProgress);
            &earlier
        };
        let params = TraceParams { animation: &animation, trail: sample, footprints, ..plan.trace_params() };
        // The stats are the plan's time's, the first sample's.
        let mut other = BeamStats::default();
        for beams in &chunks {
            if progress.cancelled() {
                return Err(BeamError::Cancelled);
            }
            let running = if k == 0 { &mut *stats } else { &mut other };
            let t = Instant::now();
            let traced = trace_range_running(&params, count, 0, beams.clone(), running, progress)?;
            trace_s += t.elapsed().as_secs_f64();
            each(traced, beams.clone());
        }
    }
    finish_running(stats);
    progress.finish();
    Ok(trace_s)
}

/// The bake's photons kept whole: [`for_each_chunk`]'s chunks concatenated
/// in photon order, with the stats of the plan's time and the count of
/// every photon (every sample's).
pub fn trace_bake(plan: &BakePlan, count: usize, progress: &dyn Progress) -> Result<Traced, BeamError> {
    let mut stats = BeamStats::default();
    let mut out = Traced::default();
    for_each_chunk(plan, count, &mut stats, progress, |t, _| append(&mut out, t))?;
    stats.photons = out.photons.len();
    out.stats = stats;
    Ok(out)
}

/// `t`'s photons, line powers and per-beam photon counts after `out`'s.
pub fn append(out: &mut Traced, t: Traced) {
    if out.photons.is_empty() && out.line_power.is_empty() && out.beam_photons.is_empty() {
        let stats = std::mem::take(&mut out.stats);
        *out = Traced { stats, ..t };
        return;
    }
    out.photons.extend(t.photons);
    out.line_power.extend(t.line_power);
    out.beam_photons.extend(t.beam_photons);
}
