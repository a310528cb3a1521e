//! The bake's expected peak memory, from a traced sample of its beams:
//! what `aurora bake --plan` prints beside the refusal's upper bound
//! (`super::budget`, which stays the bound the bake is
//! refused by), so a farm asks for what a task will use.
//!
//! **The sample.** [`SAMPLE_BEAMS`] of the bake's `count` beams (all when
//! fewer) in [`SAMPLE_RUNS`] runs of consecutive indices starting at `k
//! count / runs` (every curtain gets its share; consecutive points of the
//! R2 sequence cover a footprint evenly), traced by the bake's own tracer
//! ([`crate::pipeline::beams::trace_range`]); a beam is the same beam in
//! any range, so the estimate is deterministic. Per beam: its photons, and
//! the 8^3 leaves its kernels reach (each photon's box widened by `cutoff
//! r`, r at its midpoint, `r_max` for the other gathers, kept where the
//! leaf's voxel centres lie within that plus half the segment of its
//! midpoint). The merged runs ([`merge_segments`]) of the sample's photons.
//!
//! **The leaves** `L` of all `count` beams: a union of tubes around beam
//! paths that saturates. The leaves of the first quarter, half and all of
//! each run's beams, `s4`, `s2`, `s1`, fit `S(k) = S_inf - B k^-c`
//! ([`extrapolate_leaves`]: `rho = (s1 - s2) / (s2 - s4) = 2^-c`, clamped
//! to [`INCREMENT_RATIO`]), times the share of the sample's reached leaves
//! its own gather ([`GatherSums`]) keeps.
//!
//! **The peak**, bytes, the largest of its phases, `P` the photons (`P_c`
//! those of one chunk of `beam_chunk` beams), `M` the merged ones:
//! - program: [`RESIDENT_PROGRAM_BYTES`] plus [`THREAD_BYTES`] a thread;
//! - leaves: `L (`[`LEAF_HEAP_BYTES`]` + `[`LEAF_ENTRY_BYTES`]`)`, the
//!   `[f32; 3]` values: what dominates;
//! - a bake of one chunk (`count <= beam_chunk`, or `report2014`), at its
//!   gather: every traced photon (36 bytes, 4 more a line of
//!   `grid.lines`, held to the end), and `M` merged photons with the
//!   splat's kernel (32), leaf range (24) and a bin entry (4) per leaf it
//!   reaches; with `grid.lines`, at the last three lines' split: the
//!   emission, their `[f32; 3]` grid and every line's float grid (2 KB a
//!   leaf), the photons and their lit copy;
//! - a bake in chunks, at a chunk's gather: one set of sums per grid (the
//!   emission, each three lines, the velocity), the chunk's photons twice
//!   (the tracer's per-thread lists and their concatenation, whose pages
//!   the allocator keeps for the next chunk) and its gather input;
//! - finish: the leaves, the per-line float grids, a float leaf each of
//!   density with `grid.density_a > 0`, the velocity.
//!
//! Threads: the bake makes its leaves on the threads and keeps them where
//! they are made; the per-thread scratch and stacks are small (measured:
//! 0.1 to 1.2 MB more at 2 threads than at 1), so the peak barely grows
//! with them. Not modelled: the Cycles shell's extra leaves (a skin of the
//! grid), the red trail's earlier samples, `voxel_size = "auto"`'s
//! distances in chunks. Measured against the bake's peak resident set by
//! `benchmarks/memory/expected.sh` (docs/benchmarks.md).

use crate::grid::{leaf_origin, LEAF_DIM, LEAF_NUM_VALUES};
use crate::pipeline::beams::{self, BeamError};
use crate::pipeline::deposit::{end, pos, Photon};
use crate::pipeline::photons::kernel::KernelF32;
use crate::pipeline::photons::merge::{merge_segments, MERGE_CDF, MERGE_LEN_R, MERGE_OFF_R};
use crate::pipeline::photons::GatherSums;
use crate::pipeline::plan::BakePlan;
use crate::scene::GatherMethod;
use crate::util::fmath;
use crate::util::progress::NoProgress;
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;

/// Beams the sample traces at most.
pub const SAMPLE_BEAMS: usize = 1024;
/// Runs of consecutive beams the sample is cut into.
pub const SAMPLE_RUNS: usize = 32;
/// A process that bakes a few beams (code, tables, footprints, thread
/// pool): measured 47 MB resident for the default scene with 20 beams.
pub const RESIDENT_PROGRAM_BYTES: f64 = 47.0e6;
/// A leaf's `[f32; 3]` values on the heap, with the allocator's header.
pub const LEAF_HEAP_BYTES: f64 = (12 * LEAF_NUM_VALUES + 16) as f64;
/// A leaf's float values on the heap, with the allocator's header.
pub const FLOAT_LEAF_HEAP_BYTES: f64 = (4 * LEAF_NUM_VALUES + 16) as f64;
/// A leaf's entry: the grid's `Leaf` (origin, mask, pointer, 88 bytes),
/// its index and the list the gather collects, or the sums' hash slot.
pub const LEAF_ENTRY_BYTES: f64 = 200.0;
/// Each worker thread: its stack's touched pages, the splat's scratch, its
/// arena's slack (measured: 0.1 to 1.2 MB more at 2 threads than at 1).
pub const THREAD_BYTES: f64 = 1.0e6;

/// One term of the expected peak.
#[derive(Clone, Debug, PartialEq)]
pub struct ExpectedTerm {
    pub what: &'static str,
    pub bytes: f64,
}

/// The expected peak of a bake and what it is made of (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ExpectedPeak {
    /// The peak resident set, bytes: the largest phase's terms summed.
    pub bytes: f64,
    /// The terms of the largest phase.
    pub terms: Vec<ExpectedTerm>,
    /// The phase that peaks: "gather", "lines" or "finish".
    pub phase: &'static str,
    pub threads: usize,
    /// Beams traced for the estimate.
    pub sample_beams: usize,
    /// The leaves the bake's gather is expected to make.
    pub leaves: f64,
    /// The photons the bake is expected to trace.
    pub photons: f64,
    /// Whether the bake runs in chunks of beams.
    pub chunked: bool,
}

/// The sample's beam ranges: `min(count, SAMPLE_BEAMS)` beams in up to
/// [`SAMPLE_RUNS`] runs starting at `k count / runs`.
pub fn sample_ranges(count: usize) -> Vec<Range<usize>> {
    let n = count.min(SAMPLE_BEAMS);
    if n == count {
        return std::iter::once(0..count).filter(|r| !r.is_empty()).collect();
    }
    let runs = SAMPLE_RUNS.min(n).max(1);
    (0..runs)
        .map(|k| {
            let start = k * count / runs;
            let len = n / runs + usize::from(k < n % runs);
            start..(start + len).min(count)
        })
        .collect()
}

/// The leaves reached by a photon of reach `reach` km on voxels of `h`
/// km, added to `out`: those of its segment's box widened by `reach` whose
/// voxel centres' box lies within `reach` plus half the segment of its
/// midpoint.
fn photon_leaves(p: &Photon, h: f64, reach: f64, out: &mut Vec<IVec3>) {
    let (a, b) = (pos(p), end(p));
    let mid = 0.5 * (a + b);
    let r = reach + 0.5 * a.distance(b);
    let lo = leaf_origin(((a.min(b) - DVec3::splat(reach)) / h).ceil().as_ivec3());
    let hi = leaf_origin(((a.max(b) + DVec3::splat(reach)) / h).floor().as_ivec3());
    let step = LEAF_DIM as usize;
    for x in (lo.x..=hi.x).step_by(step) {
        for y in (lo.y..=hi.y).step_by(step) {
            for z in (lo.z..=hi.z).step_by(step) {
                let o = IVec3::new(x, y, z);
                let box_lo = o.as_dvec3() * h;
                let box_hi = (o + IVec3::splat(LEAF_DIM - 1)).as_dvec3() * h;
                if mid.clamp(box_lo, box_hi).distance_squared(mid) <= r * r {
                    out.push(o);
                }
            }
        }
    }
}

/// The range of the ratio of successive increments [`extrapolate_leaves`]
/// takes. Above the top the sample has not begun to saturate and the
/// leaves are taken to grow as at it; below the bottom the sample's runs
/// saturate faster than the whole bake's sparse fringe does (leaves
/// reached by few beams of many): fitted on the four scenes of
/// `benchmarks/memory/expected.sh` (leaves within 10 % of the bake's).
pub const INCREMENT_RATIO: (f64, f64) = (0.85, 0.9);

/// Leaves of `big` beams from those of `n / 4`, `n / 2` and `n` (`s4`,
/// `s2`, `s1`): a union of tubes around beam paths that saturates as
/// `S(k) = S_inf - B k^-c`; with the increments `d1 = s2 - s4`, `d2 = s1 -
/// s2` and `rho = d2 / d1 = 2^-c`, `S(big) = s1 + d2 rho / (1 - rho) (1 -
/// (n / big)^c)`.
pub fn extrapolate_leaves(s4: f64, s2: f64, s1: f64, n: f64, big: f64) -> f64 {
    let (d1, d2) = (s2 - s4, s1 - s2);
    if big <= n || d2 <= 0.0 || d1 <= 0.0 {
        return s1;
    }
    let rho = (d2 / d1).clamp(INCREMENT_RATIO.0, INCREMENT_RATIO.1);
    let c = -fmath::log2(rho);
    s1 + d2 * rho / (1.0 - rho) * (1.0 - fmath::powf(n / big, c))
}

/// What the sample measured, per beam and in all.
struct Sample {
    beams: usize,
    photons: usize,
    merged: usize,
    /// (leaf, photon) pairs of the merged photons: the splat's bins.
    pairs: usize,
    /// Leaves reached, and by one and by two beams.
    seen: usize,
    /// Leaves reached by the first quarter, the first half of each run's
    /// beams.
    seen_quarter: f64,
    seen_half: f64,
    /// Leaves the sample's own gather made.
    gathered: usize,
}

fn trace_sample(plan: &BakePlan, count: usize) -> Result<Sample, BeamError> {
    let params = plan.trace_params();
    let mut photons = Vec::new();
    let mut per_beam = Vec::new();
    // Each beam's place in its run.
    let mut place = Vec::new();
    let ranges = sample_ranges(count);
    let run_len = ranges.iter().map(|r| r.len()).max().unwrap_or(0);
    for r in ranges {
        let t = beams::trace_range(&params, count, 0, r, false, &NoProgress)?;
        photons.extend(t.photons);
        place.extend((0..t.beam_photons.len()).map(|k| k as u32));
        per_beam.extend(t.beam_photons);
    }
    let (h, _) = plan.voxel_size(&photons);
    let cutoff = plan.scene.photons.cutoff;
    let splat = plan.scene.photons.gather == GatherMethod::Splat;
    let r_max = plan.radius.max();
    let reach = |p: &Photon| cutoff * if splat { plan.radius.radius(0.5 * (pos(p) + end(p))) } else { r_max };
    // Each beam's leaves, once per beam.
    let mut bounds = Vec::with_capacity(per_beam.len() + 1);
    bounds.push(0usize);
    for &n in &per_beam {
        bounds.push(bounds.last().copied().unwrap_or(0) + n as usize);
    }
    let leaf_sets: Vec<Vec<IVec3>> = bounds
        .par_windows(2)
        .map(|w| {
            let mut v = Vec::new();
            for p in photons.get(w[0]..w[1]).unwrap_or(&[]) {
                photon_leaves(p, h, reach(p), &mut v);
            }
            v.sort_unstable_by_key(|o| (o.x, o.y, o.z));
            v.dedup();
            v
        })
        .collect();
    // Each leaf's earliest place in a run among the beams reaching it.
    let mut first: HashMap<IVec3, u32> = HashMap::new();
    for (set, &k) in leaf_sets.iter().zip(&place) {
        for o in set {
            let e = first.entry(*o).or_insert(k);
            *e = (*e).min(k);
        }
    }
    let within = |q: usize| first.values().filter(|&&k| (k as usize) < q).count() as f64;
    let merged = merge_segments(&photons, |x| plan.radius.radius(x), MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF);
    let mut scratch = Vec::new();
    let mut pairs = 0usize;
    for p in &merged {
        scratch.clear();
        photon_leaves(p, h, reach(p), &mut scratch);
        pairs += scratch.len();
    }
    let gathered = if photons.is_empty() || plan.scene.photons.gather == GatherMethod::Report2014 {
        first.len()
    } else {
        let mut sums = GatherSums::new(crate::pipeline::voxel::grid_transform(h));
        sums.add(&plan.gather_input(&photons), &NoProgress);
        sums.leaf_count()
    };
    Ok(Sample {
        beams: per_beam.len(),
        photons: photons.len(),
        merged: merged.len(),
        pairs,
        seen: first.len(),
        seen_quarter: within(run_len.div_ceil(4)),
        seen_half: within(run_len.div_ceil(2)),
        gathered,
    })
}

/// The expected peak of a bake of `count` beams of `plan` on `threads`
/// worker threads (module docs). Traces [`SAMPLE_BEAMS`] beams at most;
/// fails as the bake's tracing would.
pub fn expected_peak(plan: &BakePlan, count: usize, threads: usize) -> Result<ExpectedPeak, BeamError> {
    let s = trace_sample(plan, count)?;
    let threads = threads.max(1);
    let n = s.beams.max(1) as f64;
    let scale = count as f64 / n;
    let photons = s.photons as f64 * scale;
    let merged = s.merged as f64 * scale;
    let pairs = s.pairs as f64 * scale;
    let keep = if s.seen > 0 { s.gathered as f64 / s.seen as f64 } else { 0.0 };
    let reached = extrapolate_leaves(s.seen_quarter, s.seen_half, s.seen as f64, n, count as f64);
    let leaves = reached * keep;

    let photon = std::mem::size_of::<Photon>() as f64;
    let n_lines = if plan.line_table.is_some() { plan.line_outputs.len() } else { 0 };
    let groups = n_lines.div_ceil(3);
    let splat = plan.scene.photons.gather == GatherMethod::Splat;
    let chunked = plan.is_chunked(count);
    // Photons held: all of them, or one chunk's.
    let held = if chunked { photons * plan.beam_chunk as f64 / count.max(1) as f64 } else { photons };
    let held_merged = merged * held / photons.max(1.0);
    let held_pairs = pairs * held / photons.max(1.0);
    let traced = held * (photon + 4.0 * n_lines as f64);
    // A gather's input beside the photons: merged copies, kernels, leaf
    // ranges and bins.
    let kernel = if splat { std::mem::size_of::<KernelF32>() as f64 } else { 0.0 };
    let input = held_merged * (photon + kernel + 24.0) + 4.0 * held_pairs;
    let rgb = leaves * (LEAF_HEAP_BYTES + LEAF_ENTRY_BYTES);
    let float = leaves * (FLOAT_LEAF_HEAP_BYTES + LEAF_ENTRY_BYTES);
    let program = RESIDENT_PROGRAM_BYTES + THREAD_BYTES * threads as f64;
    let velocity = plan.scene.grid.velocity;
    let density = if plan.scene.grid.density_a > 0.0 { float } else { 0.0 };

    let mut phases: Vec<(&'static str, Vec<ExpectedTerm>)> = Vec::new();
    let term = |what, bytes| ExpectedTerm { what, bytes };
    if chunked {
        // Sums for the emission, each three lines and the velocity, held
        // for the whole trace; a chunk's photons, their line-lit and
        // weighted copies and a gather's input.
        let sets = 1.0 + groups as f64 + if velocity { 1.0 } else { 0.0 };
        let copies = if groups > 0 { held * photon } else { 0.0 } + if velocity { held * photon } else { 0.0 };
        // The tracer's per-thread lists and their concatenation: a chunk's
        // photons twice (module docs).
        let traced = 2.0 * traced;
        phases.push((
            "gather",
            vec![term("program", program), term("leaves (sums)", sets * rgb), term("photons (a chunk)", traced + copies + input)],
        ));
        // The sums turned into leaves one at a time, the per-line sums
        // split into float grids, the density.
        let lines_split = if groups > 0 { n_lines as f64 * float } else { 0.0 };
        phases.push((
            "finish",
            vec![term("program", program), term("leaves", sets * rgb), term("per-line grids", lines_split), term("density", density)],
        ));
    } else {
        let vel = if velocity { rgb + held * photon } else { 0.0 };
        phases.push((
            "gather",
            vec![
                term("program", program),
                term("leaves", rgb),
                term("photons (traced)", traced),
                term("photons (merged, kernels, bins)", input),
            ],
        ));
        if groups > 0 {
            // The last group's split: the emission, the earlier lines'
            // float grids, this group's grid and its floats, the photons
            // and the lit copy.
            phases.push((
                "lines",
                vec![
                    term("program", program),
                    term("leaves", rgb),
                    term("per-line grids", rgb + n_lines as f64 * float),
                    term("photons (traced, lit copy)", traced + held * photon),
                ],
            ));
        }
        phases.push((
            "finish",
            vec![
                term("program", program),
                term("leaves", rgb),
                term("per-line grids", n_lines as f64 * float),
                term("photons (traced)", traced),
                term("density", density),
                term("velocity", vel),
            ],
        ));
    }
    let total = |t: &[ExpectedTerm]| t.iter().map(|t| t.bytes).sum::<f64>();
    let (phase, terms) = phases.into_iter().max_by(|a, b| total(&a.1).total_cmp(&total(&b.1))).unwrap_or(("gather", Vec::new()));
    let terms: Vec<ExpectedTerm> = terms.into_iter().filter(|t| t.bytes > 0.0).collect();
    Ok(ExpectedPeak { bytes: total(&terms), terms, phase, threads, sample_beams: s.beams, leaves, photons, chunked })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::bake::bake_plan;
    use crate::pipeline::memory::budget::{estimate, LeafCount};
    use crate::util::progress::NoProgress;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
    }

    /// The small scene's 300 beams are fewer than [`SAMPLE_BEAMS`]: the
    /// sample is the bake, and its leaves are the bake's, exactly. The
    /// expected peak then lies between what the bake returns and the
    /// refusal's bound.
    #[test]
    fn expected_peak_lies_between_the_bakes_grids_and_the_bound() {
        let scene = crate::scene::presets::small_test_scene();
        let plan = BakePlan::new(&scene, &NoProgress);
        let count = scene.beams.count;
        let e = expected_peak(&plan, count, 2).unwrap();
        let b = bake_plan(&plan, std::time::Instant::now(), &NoProgress).unwrap();
        assert_eq!(e.sample_beams, count);
        assert!(!e.chunked);
        // The gathered leaves, before pruning dropped any: the sample's own
        // gather is the bake's (the same photons, voxel and kernels), so
        // the count is exact.
        let gathered = b.stats.prune.as_ref().map_or(b.emission.leaf_count(), |p| p.leaves_before);
        assert_eq!(e.leaves, gathered as f64);
        assert_eq!(e.photons, b.stats.photons as f64);
        // At least the values of the grids the bake returns (the emission's
        // [f32; 3], the density's f32, the photons it keeps) and the
        // program; those are the model's terms less the bookkeeping and the
        // gather's input, so a strict lower bound with no tolerance.
        let grids = 12.0 * LEAF_NUM_VALUES as f64 * b.emission.leaf_count() as f64
            + 4.0 * LEAF_NUM_VALUES as f64 * b.density.leaf_count() as f64
            + std::mem::size_of::<Photon>() as f64 * b.photons.len() as f64;
        assert!(e.bytes >= grids + RESIDENT_PROGRAM_BYTES, "expected {} B, the bake's grids and photons {grids} B", e.bytes);
        // The refusal's bound is an upper bound of the same peak.
        let bound = estimate(&plan, LeafCount::Bands).total();
        assert!(e.bytes <= bound, "expected {} B above the bound {bound} B", e.bytes);
    }

    /// The same plan gives the same estimate, on any thread count the
    /// estimate runs on (the sample is fixed beams, the sums exact).
    #[test]
    fn expected_peak_is_deterministic() {
        let mut scene = crate::scene::presets::small_test_scene();
        scene.beams.count = 3000; // more than the sample: extrapolated
        let plan = BakePlan::new(&scene, &NoProgress);
        let a = pool(1).install(|| expected_peak(&plan, 3000, 2).unwrap());
        let b = pool(2).install(|| expected_peak(&plan, 3000, 2).unwrap());
        assert_eq!(a, b);
        assert_eq!(a.sample_beams, SAMPLE_BEAMS);
        assert!(a.leaves > 0.0 && a.photons > 0.0);
    }

    /// Threads add [`THREAD_BYTES`] each and nothing else (module docs:
    /// the leaves stay where they are made), in one chunk or in chunks.
    #[test]
    fn expected_peak_grows_with_threads_as_modelled() {
        let scene = crate::scene::presets::small_test_scene();
        let mut plan = BakePlan::new(&scene, &NoProgress);
        for chunk in [plan.beam_chunk, 64] {
            plan.beam_chunk = chunk;
            let one = expected_peak(&plan, 300, 1).unwrap();
            let two = expected_peak(&plan, 300, 2).unwrap();
            let eight = expected_peak(&plan, 300, 8).unwrap();
            assert_eq!(one.chunked, chunk == 64);
            // f64 sums of the same terms but one: equal to rounding.
            assert!((two.bytes - one.bytes - THREAD_BYTES).abs() < 1e-6 * one.bytes, "{one:?} {two:?}");
            assert!((eight.bytes - one.bytes - 7.0 * THREAD_BYTES).abs() < 1e-6 * one.bytes, "{one:?} {eight:?}");
        }
        // In chunks, a chunk's photons are held instead of all of them.
        plan.beam_chunk = 64;
        let chunked = expected_peak(&plan, 300, 1).unwrap();
        plan.beam_chunk = crate::pipeline::plan::BEAM_CHUNK;
        let whole = expected_peak(&plan, 300, 1).unwrap();
        assert!(chunked.bytes < whole.bytes, "{chunked:?} {whole:?}");
    }

    #[test]
    fn leaves_follow_a_saturating_power_law() {
        // S(k) = 1000 - 800 k^-0.2: rho = 2^-0.2 = 0.87, inside the clamp,
        // so the fit is exact (to f64 rounding).
        let s = |k: f64| 1000.0 - 800.0 * fmath::powf(k, -0.2);
        let got = extrapolate_leaves(s(256.0), s(512.0), s(1024.0), 1024.0, 50_000.0);
        assert!((got - s(50_000.0)).abs() < 1e-9 * got, "{got} vs {}", s(50_000.0));
        // Nothing beyond the sample, or no growth: the sample's leaves.
        assert_eq!(extrapolate_leaves(10.0, 20.0, 30.0, 1024.0, 1024.0), 30.0);
        assert_eq!(extrapolate_leaves(30.0, 30.0, 30.0, 1024.0, 4096.0), 30.0);
        // A sample far from saturating grows at the clamp's ratio, finitely.
        let lin = extrapolate_leaves(100.0, 200.0, 300.0, 1024.0, 1e9);
        assert!(lin.is_finite() && lin > 300.0 && lin <= 300.0 + 100.0 * 0.9 / 0.1, "{lin}");
    }

    #[test]
    fn sample_ranges_are_disjoint_runs_spread_over_the_beams() {
        let all = sample_ranges(300);
        assert_eq!((all.len(), all[0].clone()), (1, 0..300));
        assert!(sample_ranges(0).is_empty());
        for count in [1025, 8000, 500_000] {
            let r = sample_ranges(count);
            assert_eq!(r.len(), SAMPLE_RUNS);
            assert_eq!(r.iter().map(|r| r.len()).sum::<usize>(), SAMPLE_BEAMS);
            assert!(r.windows(2).all(|w| w[0].end <= w[1].start), "{r:?}");
            assert!(r.last().unwrap().end <= count && r.last().unwrap().start >= count / 2);
        }
    }
}
