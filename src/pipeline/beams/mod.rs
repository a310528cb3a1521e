//! Electron beams: precipitating electrons traced down the geomagnetic field
//! with random deflections (Baranoski, Rokne, Shirley, Trondsen & Bastos,
//! "Simulating the aurora borealis", Pacific Graphics 2000), losing energy to
//! the atmosphere, and leaving a photon at every deflection point.
//!
//! This stage starts every beam of every curtain and sums where their power
//! went ([`trace_range`]). One beam's data are [`beam`]'s, its walk and the
//! deposition models [`walk`]'s, a step's photon [`emit`]'s; the start points are `crate::pipeline::beams::starts`'s, the field
//! `crate::physics::geomagnetic_field`'s (its dip where each curtain starts, and the
//! refusal of a field the beams cannot go down, [`dip`]'s), and the photons and step deposits it returns are the
//! plain records of `crate::pipeline::deposit`. Where the beams' power went
//! is summed per curtain ([`CurtainPower`], with the share deposited) and a
//! loss above 5 % is warned about ([`loss_warnings`]).
//!
//! Photons carry physical power (see [`crate::pipeline::deposit::Photon`]), not a
//! colour-map colour.
//!
//! Normalisation: curtain c with peak energy flux `F` (mW m^-2 = erg cm^-2
//! s^-1) and footprint `f` (peak 1) receives the electron power
//! `P_c = F * int f dA` over the cells above threshold. Its `N_c` beams (its
//! `beam_weight` share of `beams.count`) each carry `P_c / N_c`. A beam's
//! energy E is drawn from the *energy-flux* distribution of a Maxwellian:
//! the number flux is `phi(E) ~ E exp(-E/E0)` (Gamma(2, E0) in E), so
//! the energy flux is `E phi(E) ~ Gamma(3, E0)`; since every beam carries
//! the same power, energies must follow the energy flux, else hard electrons
//! would be under-weighted by `E / <E>`. A share `soft_fraction` of the energy
//! flux is carried by a second, soft Maxwellian (E0 = `soft_energy_kev`, some
//! 0.1 keV): the low-energy electrons of real arc spectra that stop above
//! 200 km, where O(1D) escapes quenching and the red tops shine. Each beam is
//! soft with probability `soft_fraction` (equal-power beams: the mixture by
//! energy flux).

pub mod beam;
pub mod dip;
pub mod emit;
pub mod running;
pub mod starts;
pub mod walk;

use crate::geometry::earth::Earth;
use crate::physics::atmosphere::Atmosphere;
use crate::physics::deposition::curtain_spectrum::{self, Population};
use crate::physics::deposition::fang::{MonoDeposition, SpectrumDeposition};
use crate::physics::emission::line_colour::ColourTable;
use crate::physics::emission::line_table::LineTable;
use crate::physics::geomagnetic_field::MagneticField;
use crate::physics::site_field::SiteField;
use crate::pipeline::beams::starts::{StartMap, UnitPoints};
use crate::pipeline::deposit::Photon;
use crate::pipeline::deposit::StepDeposit;
use crate::pipeline::footprint::Footprint;
use crate::scene::{AnimationParams, BeamParams, Curtain, Deposition, KernelShape, Scene};
use crate::util::progress::Progress;
use crate::util::rng;
use beam::{BeamBuffers, BeamContext, BeamStart, DepositModel, EndReason};
use glam::DVec3;
use noise::Perlin;
use rand::Rng;
use rayon::prelude::*;
use std::ops::Range;
use walk::trace_beam_into;

/// keV per joule.
pub const KEV_PER_J: f64 = 1.0 / 1.602_176_634e-16;

/// Splits `count` beams between curtains in proportion to their weights
/// (largest remainder, so the total is exactly `count`; ties go to the
/// earlier curtain).
pub fn apportion(count: usize, weights: &[f64]) -> Vec<usize> {
    let total: f64 = weights.iter().map(|w| w.max(0.0)).sum();
    if total <= 0.0 || weights.is_empty() {
        return vec![0; weights.len()];
    }
    let exact: Vec<f64> = weights.iter().map(|w| count as f64 * w.max(0.0) / total).collect();
    let mut n: Vec<usize> = exact.iter().map(|x| x.floor() as usize).collect();
    let mut left = count - n.iter().sum::<usize>();
    let mut order: Vec<usize> = (0..weights.len()).collect();
    order.sort_by(|&a, &b| (exact[b] - n[b] as f64).total_cmp(&(exact[a] - n[a] as f64)).then(a.cmp(&b)));
    for &i in order.iter().cycle() {
        if left == 0 {
            break;
        }
        if weights[i] > 0.0 {
            n[i] += 1;
            left -= 1;
        }
    }
    n
}

/// A beam stage failure.
#[derive(Debug, thiserror::Error)]
pub enum BeamError {
    #[error("curtain[{curtain}]: no footprint cell is above footprint.threshold = {threshold} after the fluid simulation (largest cell: {peak}), so it cannot emit beams: the band was advected out of its box or thinned below the threshold; lower footprint.threshold, footprint.velocity_amplitude or footprint.steps, or widen the curtain")]
    EmptyFootprint { curtain: usize, threshold: f64, peak: f32 },
    /// The electrons' field line at the curtain's start lies within the
    /// beams' deflection cone of the horizontal ([`dip::check_field`]).
    #[error("curtain[{curtain}]: the geomagnetic field where its beams start dips only {dip_deg:.2} degrees below the horizon (at [{:.1}, {:.1}] km), within the beams' deflection cone beams.alpha_d_deg = {alpha_d_deg} of the horizontal, so its electrons may go up or sideways instead of down into the atmosphere; the dip must exceed beams.alpha_d_deg: {fix}", at[0], at[1])]
    FieldInCone { curtain: usize, dip_deg: f64, at: [f64; 2], alpha_d_deg: f64, fix: String },
    /// A pilot of the curtain's beams deposited under
    /// [`MIN_DEPOSITED_FRACTION`] of the power they carried
    /// (`crate::pipeline::bake::pilot::check_deposition`).
    #[error("curtain[{curtain}]: a pilot of {beams} of its beams deposited only {:.1} % of the power they carried into the atmosphere ({left} left the footprint's box, {bottom} went through the atmosphere's bottom, {capped} took the most steps), under the {:.0} % a bake needs; the field where its beams start dips {dip_deg:.2} degrees below the horizon with beams.alpha_d_deg = {alpha_d_deg}: a steeper field (earth.magnetic_pole nearer the curtain, or beams.b_inclination_deg), a smaller beams.alpha_d_deg or beams.length_km, or a larger curtain keeps the beams over their footprint", 100.0 * fraction, 100.0 * MIN_DEPOSITED_FRACTION)]
    LowDeposit { curtain: usize, beams: usize, fraction: f64, left: usize, bottom: usize, capped: usize, dip_deg: f64, alpha_d_deg: f64 },
    /// The caller asked the trace to stop (`Progress::cancelled`): nothing
    /// of it is returned.
    #[error("cancelled before the beams were traced")]
    Cancelled,
}

/// A curtain whose beams deposit less than this share of the power they
/// carry into the atmosphere is refused (Fang's depositions; csda's beams
/// stop by its own rules, after `1 / beams.dt` steps or off the footprint,
/// and are only warned about).
pub const MIN_DEPOSITED_FRACTION: f64 = 0.5;

/// A bake whose curtains deposit less than this share of the power their
/// beams carry is warned about (`aurora: warning: ...`).
pub const WARN_DEPOSITED_FRACTION: f64 = 0.95;

impl BeamError {
    /// The user's input (the scene's parameters, exit status 2), except a
    /// trace the caller cancelled.
    pub fn is_input(&self) -> bool {
        !matches!(self, BeamError::Cancelled)
    }
}

/// Where one curtain's electron power went, W. `electron = deposited +
/// backscattered + above_top + undeposited` (to rounding).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CurtainPower {
    /// Energy flux times footprint area above threshold.
    pub electron_power_w: f64,
    /// Deposited along the beams (the photons' energy).
    pub deposited_power_w: f64,
    /// Backscattered according to the deposition model (Fang: 1 minus the
    /// fit's total deposition; 0 for CSDA).
    pub backscattered_power_w: f64,
    /// Deposited by the model above the beams' start altitude, outside the
    /// bake (soft electrons).
    pub above_top_power_w: f64,
    /// Still carried by beams when they stopped: CSDA beams that left the
    /// footprint or ran out of steps, Fang beams below the atmosphere's
    /// bottom or at the safety cap.
    pub undeposited_power_w: f64,
    /// The share of the power the beams carried into the atmosphere (at the
    /// frame's pulsation; without it, electron power less backscatter) that
    /// they deposited in the bake: the rest was still carried when they
    /// stopped or lay above the column's top. 1 when they carried none.
    pub deposited_fraction: f64,
}

impl CurtainPower {
    /// [`CurtainPower::deposited_fraction`] from the powers.
    pub fn fraction_deposited(&self) -> f64 {
        deposited_fraction(self.deposited_power_w, self.undeposited_power_w + self.above_top_power_w)
    }
}

/// `deposited / (deposited + lost)`, 1 when both are 0.
fn deposited_fraction(deposited: f64, lost: f64) -> f64 {
    if deposited + lost > 0.0 {
        deposited / (deposited + lost)
    } else {
        1.0
    }
}

/// Counts from the beam stage.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct BeamStats {
    pub beams: usize,
    pub photons: usize,
    pub ended_left_footprint: usize,
    pub ended_energy_spent: usize,
    pub ended_max_steps: usize,
    pub ended_bottom: usize,
    /// Where the electron power of all curtains went, W: their sums, and
    /// the share deposited over all of them (written flat in bake.json).
    #[serde(flatten)]
    pub power: CurtainPower,
    /// The same per curtain, in scene order.
    pub curtains: Vec<CurtainPower>,
}

/// What tracing needs of the scene, as plain data (no `Scene`): the
/// curtains, the beam parameters, the seed, the footprint threshold, the
/// animation time (pulsation, ray drift), the colour noise and the kernel
/// shape. [`TraceParams::of`] reads them from a scene; `crate::pipeline::plan`
/// keeps owned copies.
#[derive(Clone, Copy, Debug)]
pub struct TraceParams<'a> {
    pub seed: u64,
    pub curtains: &'a [Curtain],
    pub beams: &'a BeamParams,
    /// `footprint.threshold`.
    pub threshold: f64,
    pub animation: &'a AnimationParams,
    /// `colour.noise_km` and `colour.noise_freq`.
    pub colour_noise_km: f64,
    pub colour_noise_freq: f64,
    /// `photons.kernel`.
    pub kernel: KernelShape,
    /// The lines one at a time (physical colour with pulsation or
    /// `grid.lines`; `None` otherwise): each line follows the pulsation
    /// through its lifetime, and the lines of `line_outputs` (indices in
    /// `crate::physics::emission::line_colour::LINES`) leave per-line photon powers.
    pub lines: Option<&'a LineTable>,
    pub line_outputs: &'a [usize],
    /// The red trail's sample this trace makes (`crate::pipeline::red_trail`, with
    /// `lines`); `None` keeps every line at the animation's time.
    pub trail: Option<crate::pipeline::red_trail::TrailSample>,
    /// `[earth]`: the beams walk in its curved frame, their photons mapped
    /// onto it (`crate::geometry::earth`).
    pub earth: Earth,
    /// `earth.magnetic_pole`: the dipole's field at each beam's start
    /// instead of `beams`' angles.
    pub magnetic_pole: Option<[f64; 2]>,
    /// IGRF over the site (`[site] field = "igrf"`, [`site_field`]): it
    /// wins over `magnetic_pole` and `beams`' angles.
    pub site_field: Option<&'a SiteField>,
    /// One footprint per curtain, at the trace's time: where beams start.
    pub footprints: &'a [Footprint],
    /// The neutral atmosphere the beams deposit in, and the colour table
    /// their photons take.
    pub atmosphere: &'a Atmosphere,
    pub colour: &'a ColourTable,
}

impl<'a> TraceParams<'a> {
    /// The scene's parameters, with its footprints, atmosphere and colour table.
    /// The scene's parameters, with its footprints, atmosphere, colour
    /// table and site field ([`site_field`] of the scene).
    pub fn of(
        scene: &'a Scene,
        footprints: &'a [Footprint],
        atmosphere: &'a Atmosphere,
        colour: &'a ColourTable,
        site_field: Option<&'a SiteField>,
    ) -> Self {
        TraceParams {
            seed: scene.seed,
            curtains: &scene.curtains,
            beams: &scene.beams,
            threshold: scene.footprint.threshold,
            animation: &scene.animation,
            colour_noise_km: scene.colour.noise_km,
            colour_noise_freq: scene.colour.noise_freq,
            kernel: scene.photons.kernel,
            lines: None,
            line_outputs: &[],
            trail: None,
            earth: Earth::new(scene.earth.radius_km),
            magnetic_pole: scene.earth.magnetic_pole,
            site_field,
            footprints,
            atmosphere,
            colour,
        }
    }
}

/// Traces every beam of every curtain. Beams run in parallel; each has its
/// own random stream seeded from (scene seed, curtain seed, beam index), and
/// photons are concatenated in (curtain, beam) order, so the result does not
/// depend on the thread count.
pub fn trace_all(
    scene: &Scene,
    footprints: &[Footprint],
    atmosphere: &Atmosphere,
    colour: &ColourTable,
    progress: &dyn Progress,
) -> Result<(Vec<Photon>, BeamStats), BeamError> {
    trace_all_from(scene, footprints, atmosphere, colour, 0, progress)
}

/// [`trace_all`] with beam `i` of a curtain drawing the random stream of
/// index `first_beam + i`: beams from disjoint index ranges are independent
/// samples of the same scene (the pilot of `crate::pipeline::bake::pilot` uses two).
pub fn trace_all_from(
    scene: &Scene,
    footprints: &[Footprint],
    atmosphere: &Atmosphere,
    colour: &ColourTable,
    first_beam: u64,
    progress: &dyn Progress,
) -> Result<(Vec<Photon>, BeamStats), BeamError> {
    let n = scene.beams.count;
    let site = site_field(scene);
    let t = trace_range(&TraceParams::of(scene, footprints, atmosphere, colour, site.as_ref()), n, first_beam, 0..n, false, progress)?;
    Ok((t.photons, t.stats))
}

/// The beams' deposits, per curtain in scene order, exactly as [`trace_all`]
/// makes them (same beams, same random streams): what `aurora profile` bins.
pub fn trace_deposits(
    scene: &Scene,
    footprints: &[Footprint],
    atmosphere: &Atmosphere,
    colour: &ColourTable,
    progress: &dyn Progress,
) -> Result<(Vec<Vec<StepDeposit>>, BeamStats), BeamError> {
    let n = scene.beams.count;
    let site = site_field(scene);
    let t = trace_range(&TraceParams::of(scene, footprints, atmosphere, colour, site.as_ref()), n, 0, 0..n, true, progress)?;
    Ok((t.deposits, t.stats))
}

/// What [`trace_range`] returns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Traced {
    pub photons: Vec<Photon>,
    pub stats: BeamStats,
    /// Per curtain (empty vectors unless recorded).
    pub deposits: Vec<Vec<StepDeposit>>,
    /// Per photon, the powers of `TraceParams::line_outputs` in that order
    /// (`line_outputs.len()` values a photon; empty without outputs).
    pub line_power: Vec<f32>,
    /// Photons of each traced beam, in beam order: beam k's photons follow
    /// the first k's (`crate::pipeline::bake::velocity` gives each its beam's velocity).
    pub beam_photons: Vec<u32>,
}

/// How a beam ended and where its power went, kept until the curtain's
/// beams are tallied.
struct BeamOut {
    end: EndReason,
    /// Photons the beam left.
    photons: u32,
    /// keV/s: deposited, backscattered, above the top, undeposited.
    power: [f64; 4],
}

/// Consecutive beams of a curtain traced on one thread: their photons,
/// line powers and deposits (if recorded) one beam after the other, and
/// each beam's [`BeamOut`] in order.
#[derive(Default)]
struct ChunkOut {
    bufs: BeamBuffers,
    beams: Vec<BeamOut>,
}

/// Beams per [`ChunkOut`]: fixed, so which beams share a chunk does not
/// depend on the thread count (the output never does: chunks are
/// concatenated in order); small enough to balance the threads, large
/// enough that a chunk's vectors grow a few times rather than each beam's.
const CHUNK_BEAMS: usize = 64;

/// Traces beams `range` of a bake of `count` beams. The bake's beams are
/// numbered curtain by curtain (curtain 0's share of `count` by
/// [`apportion`], then curtain 1's, ...); local beam `i` of curtain `c`
/// draws the random stream `stream_offset + i` (and, stratified, the R2
/// point of that index) and carries `1 / n_c` of its curtain's power. So a
/// beam is the same whatever range it is traced in: tracing `[0, K)` and
/// `[K, N)` and concatenating gives the photons of `[0, N)` byte for byte.
/// A range's `electron_power_w` is its beams' share of the curtains' power
/// (all of it for `0..count`).
pub fn trace_range(
    params: &TraceParams,
    count: usize,
    stream_offset: u64,
    range: Range<usize>,
    record_deposits: bool,
    progress: &dyn Progress,
) -> Result<Traced, BeamError> {
    let tracer = Tracer::new(params, stream_offset, record_deposits, progress);
    let mut stats = BeamStats::default();
    let mut all_deposits = vec![Vec::new(); params.curtains.len()];
    stats.curtains = vec![CurtainPower::default(); params.curtains.len()];
    let range = range.start.min(count)..range.end.min(count);
    progress.start("beams", range.len() as u64);
    let mut traced = Vec::new();
    for (ci, n, local) in curtain_ranges(params, count, &range) {
        let Some(fp) = params.footprints.get(ci) else { continue };
        let (power_w, chunks) = tracer.curtain(ci, &params.curtains[ci], fp, n, local.clone())?;
        // The range's share of the curtain's power (all of it for a whole bake).
        stats.curtains[ci].electron_power_w = if local.len() == n { power_w } else { power_w * local.len() as f64 / n as f64 };
        stats.beams += local.len();
        traced.push((ci, chunks));
    }
    // Every curtain's photons into one allocation of the final size.
    let chunks = || traced.iter().flat_map(|(_, c)| c);
    let mut photons = Vec::with_capacity(chunks().map(|c| c.bufs.photons.len()).sum());
    let mut line_power = Vec::with_capacity(chunks().map(|c| c.bufs.line_power.len()).sum());
    let mut beam_photons = Vec::with_capacity(chunks().map(|c| c.beams.len()).sum());
    for (ci, chunks) in traced {
        beam_photons.extend(chunks.iter().flat_map(|c| c.beams.iter().map(|b| b.photons)));
        tally(&mut stats, ci, chunks, &mut photons, &mut line_power, &mut all_deposits[ci]);
    }
    sum_curtains(&mut stats);
    stats.photons = photons.len();
    progress.finish();
    Ok(Traced { photons, stats, deposits: all_deposits, line_power, beam_photons })
}

/// The field a beam starting at the curved frame's point `at` (ground
/// coordinates and altitude, km) follows, held along the beam (over a
/// beam's path, some 50 km across the field at I = 78 deg from 260 to 100
/// km, its direction turns by about 50 / R rad = 0.5 degrees):
/// - with a site whose `field` is `igrf` (`site`, [`site_field`]), IGRF-14
///   at the point and the hour (`crate::physics::site_field`);
/// - else with a dipole pole (`[earth] magnetic_pole`, which needs a round
///   Earth) the dipole's field there;
/// - otherwise the uniform field `uniform`.
///
/// The trace and the memory budget (through
/// `crate::pipeline::plan::BakePlan::field_at`) both ask here.
pub fn beam_field(earth: &Earth, pole: Option<[f64; 2]>, site: Option<&SiteField>, uniform: MagneticField, at: DVec3) -> MagneticField {
    match (site, pole) {
        (Some(site), _) => site.field([at.x, at.y], at.z),
        (None, Some(pole)) => MagneticField::dipole(earth, pole, [at.x, at.y]),
        (None, None) => uniform,
    }
}

/// IGRF-14 over the scene's site at its hour (`utc + animation.time_s`),
/// when the scene has a `[site]` whose `field` is `igrf`; `None` for the
/// scene's own field. The scene is a validated one (its `utc` parses and
/// lies in IGRF-14's years).
pub fn site_field(scene: &Scene) -> Option<SiteField> {
    SiteField::of_scene(scene)
}

/// Where the beams of a bake of `count` beams start, per curtain: the
/// points [`trace_range`] draws on stream 0 (beam `i` of a curtain on
/// stream `i`), km, in the frame of the footprint (curved, before the
/// Earth's map). A curtain whose footprint has no cell above the threshold
/// has none (the trace refuses it).
pub fn start_positions(params: &TraceParams, count: usize) -> Vec<Vec<DVec3>> {
    let weights: Vec<f64> = params.curtains.iter().map(|c| c.beam_weight).collect();
    let counts = apportion(count, &weights);
    params
        .curtains
        .iter()
        .zip(params.footprints)
        .zip(counts)
        .map(|((curtain, fp), n)| {
            let map = StartMap::new(fp, params.threshold);
            if map.is_empty() {
                return Vec::new();
            }
            let starts = CurtainStarts::new(params, curtain, fp, map, 0.0);
            (0..n as u64)
                .into_par_iter()
                .map(|i| {
                    let mut r = beam_rng(params, curtain, i);
                    starts.start(i, &mut r).position
                })
                .collect()
        })
        .collect()
}

/// The random stream of a curtain's beam `index`: its start, energy and walk.
fn beam_rng(params: &TraceParams, curtain: &Curtain, index: u64) -> impl Rng {
    rng::rng(&[params.seed, curtain.seed, rng::tag::BEAM, index])
}

/// The curtains with beams in `range` (bake indices, within `count`): each
/// one's index, its share of the `count` beams and its beams of the range
/// as local indices.
pub(super) fn curtain_ranges(params: &TraceParams, count: usize, range: &Range<usize>) -> Vec<(usize, usize, Range<usize>)> {
    let weights: Vec<f64> = params.curtains.iter().map(|c| c.beam_weight).collect();
    let mut first = 0usize;
    let mut out = Vec::new();
    for (ci, n) in apportion(count, &weights).into_iter().enumerate() {
        let local = local_beams(range, first, n);
        first += n;
        if !local.is_empty() {
            out.push((ci, n, local));
        }
    }
    out
}

/// The beams of `range` (bake indices) that belong to the curtain whose `n`
/// beams are `[curtain_first, curtain_first + n)` of the bake, as local
/// indices (empty if none).
fn local_beams(range: &Range<usize>, curtain_first: usize, n: usize) -> Range<usize> {
    let lo = range.start.saturating_sub(curtain_first).min(n);
    let hi = range.end.saturating_sub(curtain_first).min(n);
    lo..hi.max(lo)
}

/// The electron power a curtain receives, W: its peak energy flux times its
/// footprint's integral above `threshold` (module doc).
fn curtain_power_w(curtain: &Curtain, fp: &Footprint, threshold: f64) -> f64 {
    // P_c = F [mW/m^2] * 1e-3 [W/mW] * A [km^2] * 1e6 [m^2/km^2].
    curtain.energy_flux * fp.flux_scale * 1e-3 * fp.integral_above(threshold) * 1e6
}

/// Adds curtain `ci`'s beams to the stage's counts and power (W), and
/// appends their photons and deposits in beam order.
fn tally(
    stats: &mut BeamStats,
    ci: usize,
    chunks: Vec<ChunkOut>,
    photons: &mut Vec<Photon>,
    line_power: &mut Vec<f32>,
    deposits: &mut Vec<StepDeposit>,
) {
    for c in chunks {
        photons.extend_from_slice(&c.bufs.photons);
        line_power.extend_from_slice(&c.bufs.line_power);
        deposits.extend_from_slice(&c.bufs.deposits);
        tally_beams(stats, ci, &c.beams);
    }
}

/// Adds beams' ends and power (W) to curtain `ci`'s counts, in order.
fn tally_beams(stats: &mut BeamStats, ci: usize, beams: &[BeamOut]) {
    for b in beams {
        match b.end {
            EndReason::LeftFootprint => stats.ended_left_footprint += 1,
            EndReason::EnergySpent => stats.ended_energy_spent += 1,
            EndReason::MaxSteps => stats.ended_max_steps += 1,
            EndReason::Bottom => stats.ended_bottom += 1,
        }
        let cp = &mut stats.curtains[ci];
        cp.deposited_power_w += b.power[0] / KEV_PER_J;
        cp.backscattered_power_w += b.power[1] / KEV_PER_J;
        cp.above_top_power_w += b.power[2] / KEV_PER_J;
        cp.undeposited_power_w += b.power[3] / KEV_PER_J;
    }
}

/// The stage's totals: the sums over its curtains, in scene order, and
/// the deposited fractions.
fn sum_curtains(stats: &mut BeamStats) {
    for cp in &mut stats.curtains {
        cp.deposited_fraction = cp.fraction_deposited();
        let all = &mut stats.power;
        all.electron_power_w += cp.electron_power_w;
        all.deposited_power_w += cp.deposited_power_w;
        all.backscattered_power_w += cp.backscattered_power_w;
        all.above_top_power_w += cp.above_top_power_w;
        all.undeposited_power_w += cp.undeposited_power_w;
    }
    stats.power.deposited_fraction = stats.power.fraction_deposited();
}

/// A warning for each curtain (and the bake) that deposited less than
/// [`WARN_DEPOSITED_FRACTION`] of the power its beams carried: where
/// the rest went, and the keys that keep the beams over their footprint.
pub fn loss_warnings(stats: &BeamStats) -> Vec<String> {
    stats
        .curtains
        .iter()
        .enumerate()
        .filter(|(_, c)| c.deposited_fraction < WARN_DEPOSITED_FRACTION)
        .map(|(i, c)| {
            format!(
                "curtain[{i}]: its beams deposited {:.1} % of the power they carried into the atmosphere ({:.3e} of {:.3e} W; {:.3e} W still carried when they stopped, {:.3e} W above the column's top), more than {:.0} % lost: bake.json beam_stats.deposited_fraction; a steeper field, a smaller beams.alpha_d_deg or beams.length_km, or a larger curtain keeps the beams over their footprint",
                100.0 * c.deposited_fraction,
                c.deposited_power_w,
                c.deposited_power_w + c.undeposited_power_w + c.above_top_power_w,
                c.undeposited_power_w,
                c.above_top_power_w,
                100.0 * (1.0 - WARN_DEPOSITED_FRACTION)
            )
        })
        .collect()
}

/// What the curtains of one [`trace_range`] share.
struct Tracer<'a> {
    params: &'a TraceParams<'a>,
    atmosphere: &'a Atmosphere,
    colour: &'a ColourTable,
    field: MagneticField,
    stream_offset: u64,
    record_deposits: bool,
    progress: &'a dyn Progress,
}

impl<'a> Tracer<'a> {
    /// A tracer of `params`' beams on streams from `stream_offset`, in the
    /// uniform field of `beams`' angles (a beam's own: [`beam_field`]).
    pub(super) fn new(params: &'a TraceParams<'a>, stream_offset: u64, record_deposits: bool, progress: &'a dyn Progress) -> Self {
        let field = MagneticField::new(params.beams.b_inclination_deg, params.beams.b_declination_deg);
        let (atmosphere, colour) = (params.atmosphere, params.colour);
        Tracer { params, atmosphere, colour, field, stream_offset, record_deposits, progress }
    }

    /// Curtain `ci`'s local beams `local` (of its `n`), in parallel, in index
    /// order (chunks of [`CHUNK_BEAMS`]), and the curtain's whole electron
    /// power, W.
    fn curtain(
        &self,
        ci: usize,
        curtain: &Curtain,
        fp: &Footprint,
        n: usize,
        local: Range<usize>,
    ) -> Result<(f64, Vec<ChunkOut>), BeamError> {
        let p = self.params;
        // Beam i maps the same point of the unit square through every
        // frame's footprint (crate::pipeline::motion: identity across frames).
        let map = StartMap::new(fp, p.threshold);
        if map.is_empty() {
            let peak = fp.data.iter().cloned().fold(0.0f32, f32::max);
            return Err(BeamError::EmptyFootprint { curtain: ci, threshold: p.threshold, peak });
        };
        let power_w = curtain_power_w(curtain, fp, p.threshold);
        let starts = CurtainStarts::new(p, curtain, fp, map, power_w * KEV_PER_J / n as f64);
        // Each population's spectrum (`crate::physics::deposition::curtain_spectrum`):
        // the body's, and the filaments' where the footprint has them.
        let spectrum = |pop: Population| curtain_spectrum::deposition(curtain, pop);
        // The chemistry's colours need the local ionization rate: the
        // population spectrum's ionization per unit flux (whatever the
        // deposition model: q is the mean over the spectrum's electrons).
        let ionization = |pop: Population| self.colour.needs_q().then(|| spectrum(pop).ionization_profile(self.atmosphere));
        let has_filaments = fp.filament_share.is_some();
        let (ion_body, ion_fil) = (ionization(Population::Body), if has_filaments { ionization(Population::Filaments) } else { None });
        let (expected_body, expected_fil) = match p.beams.deposition {
            Deposition::Expected => (Some(spectrum(Population::Body)), has_filaments.then(|| spectrum(Population::Filaments))),
            _ => (None, None),
        };
        fn model<'m>(d: Deposition, expected: &'m Option<std::sync::Arc<SpectrumDeposition>>) -> DepositModel<'m> {
            match d {
                Deposition::Expected => DepositModel::Expected(expected.as_deref().expect("an expected spectrum")),
                Deposition::Sampled => DepositModel::Sampled(MonoDeposition::get()),
                Deposition::Csda => DepositModel::Csda,
            }
        }
        let ctx = BeamContext {
            atmosphere: self.atmosphere,
            model: model(p.beams.deposition, &expected_body),
            colour: self.colour,
            field: self.field,
            params: p.beams,
            footprint: fp,
            threshold: p.threshold,
            record_path: false,
            lines: p.lines,
            line_outputs: p.line_outputs,
            trail: p.lines.and(p.trail),
            ionization: ion_body.as_ref(),
            earth: p.earth,
        };
        let ctx_fil = if has_filaments {
            let m = if p.beams.deposition == Deposition::Expected { model(p.beams.deposition, &expected_fil) } else { ctx.model };
            BeamContext { model: m, ionization: ion_fil.as_ref(), ..ctx }
        } else {
            BeamContext { ..ctx }
        };
        let ctxs = [ctx, ctx_fil];
        let chunks: Vec<Range<usize>> = local.clone().step_by(CHUNK_BEAMS).map(|a| a..(a + CHUNK_BEAMS).min(local.end)).collect();
        let traces = chunks
            .into_par_iter()
            .map(|c| {
                let mut out = ChunkOut { beams: Vec::with_capacity(c.len()), ..ChunkOut::default() };
                if self.progress.cancelled() {
                    return out;
                }
                for i in c {
                    self.beam(&ctxs, &starts, self.stream_offset + i as u64, &mut out);
                }
                out
            })
            .collect();
        if self.progress.cancelled() {
            return Err(BeamError::Cancelled);
        }
        Ok((power_w, traces))
    }

    /// The beam of stream `index`: its start and its walk, on its own random
    /// stream, appended to `out` (its deposits only while it is summed,
    /// unless they are recorded).
    fn beam(&self, ctxs: &[BeamContext; 2], starts: &CurtainStarts, index: u64, out: &mut ChunkOut) {
        let mut r = beam_rng(self.params, starts.curtain, index);
        let start = starts.start(index, &mut r);
        let ctx = &ctxs[start.population as usize];
        let bufs = std::mem::take(&mut out.bufs);
        let (first_photon, first_deposit) = (bufs.photons.len(), bufs.deposits.len());
        let field = beam_field(&self.params.earth, self.params.magnetic_pole, self.params.site_field, ctx.field, start.position);
        let t = trace_beam_into(&BeamContext { field, ..*ctx }, &start, &mut r, bufs);
        self.progress.inc(1);
        let mut bufs = BeamBuffers { photons: t.photons, line_power: t.line_power, deposits: t.deposits };
        let deposited: f64 = bufs.deposits[first_deposit..].iter().map(|d| d.power_kev_s).sum();
        if !self.record_deposits {
            bufs.deposits.clear();
        }
        if self.params.kernel == KernelShape::Point {
            // The point estimator: each step's power at its end.
            bufs.photons[first_photon..].iter_mut().for_each(|p| *p = p.to_point());
        }
        let photons = (bufs.photons.len() - first_photon) as u32;
        out.bufs = bufs;
        out.beams.push(BeamOut { power: [deposited, t.backscatter_kev_s, t.above_top_kev_s, t.undeposited_kev_s], end: t.end, photons });
    }
}

/// Where one curtain's beams start and what each carries: the start map and
/// unit-square points (`crate::pipeline::beams::starts`), the noise on the start height (the
/// rays) and on the colour altitude, and the power per beam, keV/s.
struct CurtainStarts<'a> {
    params: &'a TraceParams<'a>,
    curtain: &'a Curtain,
    footprint: &'a Footprint,
    map: StartMap,
    points: UnitPoints,
    ray_shift_km: f64,
    top_noise: Perlin,
    colour_noise: Perlin,
    power_kev_s: f64,
    /// The curtain's peak energy flux, keV cm^-2 s^-1, over the footprint's
    /// peak density: times the density at a start, the flux there.
    flux_per_density: f64,
}

impl<'a> CurtainStarts<'a> {
    fn new(params: &'a TraceParams<'a>, curtain: &'a Curtain, footprint: &'a Footprint, map: StartMap, power_kev_s: f64) -> Self {
        let (seed, cs) = (params.seed, curtain.seed);
        CurtainStarts {
            params,
            curtain,
            footprint,
            map,
            points: UnitPoints::new(params.beams.starts, [seed, cs, rng::tag::BEAM_STARTS]),
            ray_shift_km: crate::pipeline::motion::ray_shift_km(params.animation),
            top_noise: rng::perlin(&[seed, cs, rng::tag::BEAM_TOP_NOISE]),
            colour_noise: rng::perlin(&[seed, cs, rng::tag::COLOUR_NOISE]),
            power_kev_s,
            flux_per_density: {
                let peak = footprint.data.iter().cloned().fold(0.0f32, f32::max) as f64;
                if peak > 0.0 {
                    curtain.energy_flux * footprint.flux_scale * crate::physics::deposition::fang::KEV_PER_ERG / peak
                } else {
                    0.0
                }
            },
        }
    }

    /// The start of the beam of stream `index`, drawn from `r`: its point of
    /// the unit square (the shifted R2 sequence, fixed by the index whatever
    /// the count, or two random numbers) mapped through the footprint's
    /// continuous start map, so the beam moves with its curtain from frame
    /// to frame; then its energy.
    fn start(&self, index: u64, r: &mut impl Rng) -> BeamStart {
        let (p, b) = (self.params, self.params.beams);
        let (xi1, xi2) = self.points.point(index, r);
        let (u, v) = self.map.map(xi1, xi2);
        let (x, y) = self.footprint.to_world(u, v);
        // High-frequency noise on the start height along the curtain
        // (the rays), running along it in time.
        let ur = u - self.ray_shift_km;
        let z = b.top_km + b.top_noise_km * rng::noise1(&self.top_noise, ur * b.top_noise_freq);
        let colour_offset_km = p.colour_noise_km * rng::noise1(&self.colour_noise, ur * p.colour_noise_freq);
        // The deposit follows the flux at once; with the lines at hand each
        // line follows it through its upper state's lifetime (`wave`).
        let pulsation = crate::pipeline::motion::pulsation(p.animation, p.seed, x, y);
        let power_kev_s = self.power_kev_s * pulsation;
        let flux_kev_cm2_s = self.flux_per_density * self.footprint.cell_value_world(x, y) * pulsation;
        let wave = p.lines.and_then(|_| crate::pipeline::motion::pulsation_wave(p.animation, p.seed, x, y));
        // Drawn in every model, so a beam's path is the same in all.
        // Which population the beam carries: in proportion to each one's
        // flux in its cell (one more draw, only where there are filaments).
        let population = match &self.footprint.filament_share {
            Some(share) => {
                let (ci, cj) = self.footprint.cell_index(u, v);
                if r.random::<f64>() < share[cj * self.footprint.nx + ci] as f64 {
                    Population::Filaments
                } else {
                    Population::Body
                }
            }
            None => Population::Body,
        };
        BeamStart {
            position: DVec3::new(x, y, z),
            energy_kev: curtain_spectrum::sample_energy(self.curtain, population, r),
            population,
            power_kev_s,
            base_power_kev_s: self.power_kev_s,
            wave,
            colour_offset_km,
            flux_kev_cm2_s,
        }
    }
}

#[cfg(test)]
mod tests;
