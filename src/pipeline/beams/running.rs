//! Tracing a bake's beams a range at a time with the stats of one trace of
//! them all: [`trace_range_running`] traces beams `range` as
//! [`super::trace_range`] does and adds their ends and powers to running
//! tallies, curtain by curtain in beam order; once the ranges have covered
//! `0..count` in order, [`finish_running`] totals them. The sums are then
//! the same f64 terms in the same order as one trace's, so the stats are
//! its own, bit for bit (a range's own stats, summed, would round
//! differently).

use super::{curtain_ranges, sum_curtains, tally, BeamError, BeamStats, CurtainPower, TraceParams, Traced, Tracer};
use crate::util::progress::Progress;
use std::ops::Range;

/// Beams `range` of a bake of `count` beams, as [`super::trace_range`]
/// traces them (no deposits recorded), their tallies added to `running`;
/// the returned [`Traced`] has default stats.
pub fn trace_range_running(
    params: &TraceParams,
    count: usize,
    stream_offset: u64,
    range: Range<usize>,
    running: &mut BeamStats,
    progress: &dyn Progress,
) -> Result<Traced, BeamError> {
    let tracer = Tracer::new(params, stream_offset, false, progress);
    if running.curtains.len() != params.curtains.len() {
        running.curtains = vec![CurtainPower::default(); params.curtains.len()];
    }
    let range = range.start.min(count)..range.end.min(count);
    let mut photons = Vec::new();
    let mut line_power = Vec::new();
    let mut beam_photons = Vec::new();
    let mut deposits = Vec::new();
    for (ci, n, local) in curtain_ranges(params, count, &range) {
        let Some(fp) = params.footprints.get(ci) else { continue };
        let (power_w, chunks) = tracer.curtain(ci, &params.curtains[ci], fp, n, local.clone())?;
        // The curtain's whole power, as a trace of all its beams records it.
        running.curtains[ci].electron_power_w = power_w;
        running.beams += local.len();
        beam_photons.extend(chunks.iter().flat_map(|c| c.beams.iter().map(|b| b.photons)));
        tally(running, ci, chunks, &mut photons, &mut line_power, &mut deposits);
    }
    running.photons += photons.len();
    Ok(Traced { photons, stats: BeamStats::default(), deposits: Vec::new(), line_power, beam_photons })
}

/// The totals of tallies [`trace_range_running`] has filled over `0..count`.
pub fn finish_running(running: &mut BeamStats) {
    sum_curtains(running);
}
