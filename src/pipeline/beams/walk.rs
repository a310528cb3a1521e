//! One beam's walk: a precipitating electron beam traced down the
//! geomagnetic field with random deflections (Baranoski, Rokne, Shirley,
//! Trondsen & Bastos, "Simulating the aurora borealis", Pacific Graphics
//! 2000), losing energy to the atmosphere, and leaving a photon at every
//! deflection point ([`trace_beam`]). Where a curtain's beams start and what
//! each carries is the stage's (`crate::pipeline::beams`).
//!
//! Departures from the 2014 report, with reasons:
//! - Step length and deflection angle use **independent** random numbers. The
//!   report drew one number `t` for both (`s = L dt t`, `alpha = alpha_D - t
//!   delta_alpha`), which makes long steps always the least deflected: a
//!   correlation with no physical basis.
//! - Energy deposition follows the atmosphere, not a hand-set beam length,
//!   in one of three models (`beams.deposition`, [`DepositModel`]):
//!   - **expected** (default): every beam carries its curtain's whole
//!     spectrum and deposits on each step the spectrum's expected energy
//!     between the column masses of the step's ends, `P (G(m1) - G(m0))`, with
//!     `G` Fang et al. 2010 integrated over the spectrum ([`crate::physics::deposition::fang`]).
//!     Random numbers shape only the path (Rao-Blackwellisation: the path
//!     does not depend on the electron's energy in this model), so which
//!     altitudes a beam lights is no longer a coin toss.
//!   - **sampled**: one energy per beam (drawn by the stage from the
//!     energy-flux spectrum, `crate::pipeline::beams`), deposited by Fang
//!     2010's monoenergetic profile, `P (D_E(m1) - D_E(m0))`: the same mean.
//!   - **csda**: one energy per beam, continuous slowing down along the
//!     straight step with the range-energy relation `R(E) = 4.30e-7 +
//!     5.36e-6 E^1.67` g cm^-2 (Barrett & Hays 1976, Rees 1989;
//!     [`crate::physics::deposition::csda`]): the model
//!     before Fang, which puts the energy at the end of the range. Kept for
//!     comparison, with its old stopping rules (below).
//!
//!   In the Fang models `m` is the deepest vertical column reached so far (a
//!   step that climbs deposits nothing until the beam is deeper again), so
//!   deposits never go negative and sum to `P G(m_deepest)`.
//! - Where a beam stops. Fang models: when its deposition is complete (at
//!   most 1e-4 of the spectrum's total remains: that rest is deposited on
//!   the last step, so a finished beam deposits exactly `P G(inf)`), or at
//!   the atmosphere's bottom (50 km). A beam whose field-line foot leaves the
//!   footprint **keeps going**: the footprint only says where electrons enter
//!   at the top; a field line does not end where our threshold cuts the
//!   footprint's fringe, and stopping there lost 21 % of the default scene's
//!   power. (Only a foot outside the footprint's box enlarged by its own
//!   size on every side stops a Fang beam: runaway steps, never the
//!   sub-kilometre wander of ordinary deflections.) A step through the
//!   atmosphere's bottom is cut there. The `1/dt` step limit does not stop a Fang beam either (only a
//!   safety cap of [`FANG_MAX_STEPS`]). CSDA keeps the old rules: leaving the
//!   footprint, `1/dt` steps, or energy spent. Whatever a beam did not
//!   deposit is reported ([`CurtainPower`](super::CurtainPower)), so
//!   nothing is lost silently.
//!
//! On a round Earth (`crate::geometry::earth`) the walk is in the curved frame:
//! positions are ground coordinates and altitude, so `z` is the altitude the
//! atmosphere, the deposition and the colour read, and the field's angles
//! are relative to the local vertical and north; each photon is mapped to
//! the scene frame as it is made ([`deposit`]). On a flat ground the map is
//! the identity.

use crate::geometry::earth::Earth;
use crate::physics::atmosphere::Atmosphere;
use crate::physics::deposition::csda::{energy_from_range, range_g_cm2, step_column};
use crate::physics::deposition::fang::{IonizationProfile, MonoDeposition, SpectrumDeposition};
use crate::physics::emission::line_colour::ColourTable;
use crate::physics::emission::line_table::{LineTable, O1D_LINES, R_PER_KM_SCALE};
use crate::physics::geomagnetic_field::MagneticField;
use crate::pipeline::deposit::{Photon, StepDeposit};
use crate::pipeline::footprint::Footprint;
use crate::pipeline::motion::Wave;
use crate::pipeline::red_trail::TrailSample;
use crate::scene::BeamParams;
use glam::DVec3;
use rand::Rng;

/// Why a beam stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndReason {
    /// Its field-line foot left the footprint: CSDA, the density at or below
    /// threshold; Fang models, the footprint's box enlarged by its own size
    /// on every side (runaway steps only).
    LeftFootprint,
    /// The atmosphere absorbed all its energy.
    EnergySpent,
    /// It took the maximum number of steps (1 / dt for CSDA,
    /// [`FANG_MAX_STEPS`] for the Fang models).
    MaxSteps,
    /// It went below the atmosphere's table (Fang models).
    Bottom,
}

/// Safety cap on the steps of a Fang-model beam (which otherwise goes on
/// until its deposition is complete).
pub const FANG_MAX_STEPS: usize = 1_000_000;

/// A beam has finished when at most this fraction of its spectrum's total
/// deposition remains (the rest goes into its last step).
pub const COMPLETE_TOL: f64 = 1e-4;

/// Where a beam starts and what it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamStart {
    pub position: DVec3,
    /// The beam's electron energy (sampled and CSDA models; unused by the
    /// expected model, which carries the whole spectrum).
    pub energy_kev: f64,
    /// Electron power of the beam, keV/s (at the frame's time: with
    /// pulsation, `base_power_kev_s` times the flux's modulation).
    pub power_kev_s: f64,
    /// The beam's power without the pulsation, keV/s.
    pub base_power_kev_s: f64,
    /// The pulsation at the beam's start as a wave in time, when each line
    /// follows it through its lifetime (`crate::physics::emission::line_table`); `None` when nothing
    /// pulses or the colour is a colour map (the colour then follows
    /// `power_kev_s`).
    pub wave: Option<Wave>,
    /// Colour altitude offset of this beam, km (the report's low-frequency
    /// colour noise; it shifts colour, not intensity).
    pub colour_offset_km: f64,
    /// Energy flux entering the atmosphere at the beam's foot, keV cm^-2
    /// s^-1: the curtain's peak flux times the footprint's density at the
    /// start (relative to its peak) times the pulsation. With the curtain's
    /// [`IonizationProfile`] it gives the local ionization rate at every
    /// deposit, which the chemistry's colours need.
    pub flux_kev_cm2_s: f64,
}

/// The result of tracing one beam.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamTrace {
    pub photons: Vec<Photon>,
    /// Per photon, the powers of `BeamContext::line_outputs` in that order,
    /// photons per second times [`R_PER_KM_SCALE`] (empty without outputs).
    pub line_power: Vec<f32>,
    /// One entry per photon, in step order: the step's altitudes and the
    /// power it deposited.
    pub deposits: Vec<StepDeposit>,
    /// Power the beam's model says is backscattered (never deposited:
    /// `P (1 - D(inf))`), keV/s; 0 for CSDA.
    pub backscatter_kev_s: f64,
    /// Power the model deposits above the top of the beam's deposit (at
    /// most [`ABOVE_START_TOL`] of its total, above [`above_start_top`]),
    /// outside the bake, keV/s; 0 for CSDA.
    pub above_top_kev_s: f64,
    /// Power the beam still carried when it stopped, keV/s.
    pub undeposited_kev_s: f64,
    pub end: EndReason,
    /// Position after the last accepted step.
    pub end_position: DVec3,
    /// Deflection points, including the start (for tests and debugging).
    pub path: Vec<DVec3>,
    /// The last photon's end: in the walk's frame and mapped to the scene
    /// (f32), for the next step, which starts there ([`emit`]).
    last_end: Option<(DVec3, [f32; 3])>,
}

impl BeamTrace {
    /// A beam at `p` that has not stepped yet (its path starting at `p` if
    /// recorded), `backscatter_kev_s` set by its model, appending to `bufs`.
    fn begin(p: DVec3, backscatter_kev_s: f64, record_path: bool, bufs: BeamBuffers) -> Self {
        let mut out = BeamTrace {
            photons: bufs.photons,
            line_power: bufs.line_power,
            deposits: bufs.deposits,
            backscatter_kev_s,
            above_top_kev_s: 0.0,
            undeposited_kev_s: 0.0,
            end: EndReason::MaxSteps,
            end_position: p,
            path: Vec::new(),
            last_end: None,
        };
        if record_path {
            out.path.push(p);
        }
        out
    }
}

/// Vectors a trace appends its photons, line powers and deposits to
/// ([`trace_beam_into`]): empty for a beam of its own, or those of the
/// beams before it, so many beams fill one allocation instead of each
/// growing its own.
#[derive(Clone, Debug, Default)]
pub struct BeamBuffers {
    pub photons: Vec<Photon>,
    pub line_power: Vec<f32>,
    pub deposits: Vec<StepDeposit>,
}

/// How a curtain's beams deposit energy (module doc).
#[derive(Clone, Copy, Debug)]
pub enum DepositModel<'a> {
    /// The curtain's whole spectrum on every beam.
    Expected(&'a SpectrumDeposition),
    /// One energy per beam, Fang 2010 monoenergetic.
    Sampled(&'a MonoDeposition),
    /// One energy per beam, continuous slowing down.
    Csda,
}

/// Everything a beam needs that is shared by the beams of one curtain.
pub struct BeamContext<'a> {
    pub atmosphere: &'a Atmosphere,
    pub model: DepositModel<'a>,
    pub colour: &'a ColourTable,
    pub field: MagneticField,
    pub params: &'a BeamParams,
    pub footprint: &'a Footprint,
    /// Footprint density at or below which a beam has left the curtain.
    pub threshold: f64,
    /// Keep the path (off in the bake: memory).
    pub record_path: bool,
    /// The lines one at a time (`crate::pipeline::beams::TraceParams::lines`) and
    /// the ones that leave per-line photon powers.
    pub lines: Option<&'a LineTable>,
    pub line_outputs: &'a [usize],
    /// The red trail's sample this trace makes (`crate::pipeline::red_trail`; with
    /// `lines`): `None` keeps every line at the bake's time.
    pub trail: Option<TrailSample>,
    /// The curtain spectrum's ionization per unit flux over altitude, when
    /// the colours need the ionization rate (the chemistry); `None` leaves
    /// q = 0 on every deposit.
    pub ionization: Option<&'a IonizationProfile>,
    /// The Earth: the walk is in its curved frame (ground coordinates and
    /// altitude, `crate::geometry::earth`), and each photon is mapped to the scene
    /// frame as it is made ([`deposit`]); the identity when flat.
    pub earth: Earth,
}

/// The photon of one beam step: `power` spread along the step from `start`
/// to `end` (km, the curved frame of `earth`, mapped to the scene frame:
/// a step of at most a few km is a chord of the mapped curve, off it by
/// its sagitta, under a metre on the scale of R). The gather's segment
/// kernel smooths it along the step; `photons.kernel = "point"` collapses
/// it to a point at `end`.
#[inline]
pub fn deposit(earth: &Earth, start: DVec3, end: DVec3, power: [f32; 3]) -> Photon {
    Photon::segment(scene_f32(earth, start), scene_f32(earth, end), power)
}

/// A walk-frame point mapped to the scene frame, in f32 (a photon's end).
#[inline]
fn scene_f32(earth: &Earth, q: DVec3) -> [f32; 3] {
    let p = earth.to_scene(q);
    [p.x as f32, p.y as f32, p.z as f32]
}

/// [`deposit`] for the next photon of `out`: a step starting where the
/// last one ended (the same bits) takes that end's mapping rather than
/// mapping it again (on a round Earth a square root and a sine and cosine).
#[inline]
fn deposit_next(earth: &Earth, out: &mut BeamTrace, start: DVec3, end: DVec3, power: [f32; 3]) -> Photon {
    let same = |a: DVec3, b: DVec3| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits);
    let s = match out.last_end {
        Some((q, s)) if same(q, start) => s,
        _ => scene_f32(earth, start),
    };
    let e = scene_f32(earth, end);
    out.last_end = Some((end, e));
    Photon::segment(s, e, power)
}

/// Traces one beam (Baranoski et al. 2000, eq. for p_new) from `start`.
///
/// Each step: `p_new = p + s B + t (u cos beta + v sin beta)` with
/// `s = L dt xi`, `tan alpha = t / s`, alpha uniform in
/// [alpha_D - delta_alpha, alpha_D], beta uniform in [0, 2 pi), xi uniform in
/// [0, 1), all independent. The energy the step deposits ([`DepositModel`])
/// becomes one photon ([`deposit`]), coloured by the emission lines at the
/// step's end altitude.
pub fn trace_beam(ctx: &BeamContext, start: &BeamStart, r: &mut impl Rng) -> BeamTrace {
    trace_beam_into(ctx, start, r, BeamBuffers::default())
}

/// [`trace_beam`] appending to `bufs`: the trace's `photons`, `line_power`
/// and `deposits` are `bufs`' followed by this beam's (the same values as
/// [`trace_beam`]'s).
pub fn trace_beam_into(ctx: &BeamContext, start: &BeamStart, r: &mut impl Rng, bufs: BeamBuffers) -> BeamTrace {
    match ctx.model {
        DepositModel::Csda => trace_csda(ctx, start, r, bufs),
        DepositModel::Expected(g) => {
            let total = g.total();
            trace_fang(ctx, start, r, total, |m| g.fraction_above(m), bufs)
        }
        DepositModel::Sampled(d) => {
            let e = start.energy_kev;
            trace_fang(ctx, start, r, d.total(e), |m| d.fraction_above(e, m), bufs)
        }
    }
}

/// One random step from `p` (the Baranoski et al. update).
#[inline]
fn step(ctx: &BeamContext, p: DVec3, r: &mut impl Rng) -> (DVec3, f64) {
    let p_ = ctx.params;
    let s = p_.length_km * p_.dt * r.random::<f64>();
    let alpha = p_.alpha_d_deg.to_radians() - p_.delta_alpha_deg.to_radians() * r.random::<f64>();
    let beta = std::f64::consts::TAU * r.random::<f64>();
    let t = s * alpha.tan();
    let (sb, cb) = beta.sin_cos();
    let f = ctx.field;
    (p + f.b * s + (f.u * cb + f.v * sb) * t, s / alpha.cos())
}

/// Pushes the photon and deposit record of one step: `kev_s` deposited at
/// the frame's time, `base_kev_s` the same without the pulsation. The
/// step's colour is that of its end altitude at the local ionization rate
/// `q = flux * q_per_flux(end)` (ion pairs cm^-3 s^-1), which the deposit
/// record keeps for `aurora profile`. Under a pulsation each line's photons
/// are its yield times the unmodulated deposit times the modulation a line
/// of its lifetime shows (`crate::physics::emission::line_table`); otherwise the colour table's
/// colour times the deposit. Per-line powers take each line's yield at the
/// step's midpoint (the altitude a step spread along its length averages to
/// second order, as `aurora profile` bins it), with no colour noise. In a
/// sample of the red trail (`ctx.trail`) each line's photons are the
/// unmodulated deposit times [`trail_factor`].
#[inline]
#[allow(clippy::too_many_arguments)]
fn emit(ctx: &BeamContext, start: &BeamStart, out: &mut BeamTrace, from: DVec3, to: DVec3, kev_s: f64, base_kev_s: f64) {
    let q_at = |z: f64| match ctx.ionization {
        Some(p) => start.flux_kev_cm2_s * p.per_flux(z),
        None => 0.0,
    };
    let q = q_at(to.z);
    let h_colour = to.z + start.colour_offset_km;
    let rgb = match (ctx.trail, start.wave, ctx.lines) {
        (Some(tr), wave, Some(t)) => {
            let factor = |i: usize, tau: f64| trail_factor(&tr, wave.as_ref(), i, tau);
            t.rgb_trail(|z| t.at_q(ctx.colour, z, q), to.z, h_colour, factor).map(|c| c * base_kev_s)
        }
        (None, Some(w), Some(t)) => {
            t.rgb_in_motion(|z| t.at_q(ctx.colour, z, q), to.z, h_colour, |tau| w.at_lifetime(tau)).map(|c| c * base_kev_s)
        }
        _ => ctx.colour.rgb_with_colour_altitude(to.z, h_colour, q).map(|c| c * kev_s),
    };
    let photon = deposit_next(&ctx.earth, out, from, to, [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32]);
    out.photons.push(photon);
    out.deposits.push(StepDeposit { z_start: from.z, z_end: to.z, power_kev_s: kev_s, q });
    if let (Some(t), false) = (ctx.lines, ctx.line_outputs.is_empty()) {
        let zm = 0.5 * (from.z + to.z);
        let l = t.at_q(ctx.colour, zm, q_at(zm));
        for &i in ctx.line_outputs {
            let n = match (ctx.trail, start.wave) {
                (Some(tr), wave) => base_kev_s * trail_factor(&tr, wave.as_ref(), i, l.tau_s[i]),
                (None, Some(w)) => base_kev_s * w.at_lifetime(l.tau_s[i]),
                (None, None) => kev_s,
            };
            out.line_power.push((l.yields[i] * n * R_PER_KM_SCALE) as f32);
        }
    }
}

/// What line i of lifetime `tau` keeps of a deposit in the red trail's
/// sample `tr` (`crate::pipeline::red_trail`): the O(1D) lines the sample's weight, the
/// others their value at the bake's time (under a pulsation, what a line of
/// their lifetime shows) in sample 0 and nothing in the earlier ones.
#[inline]
fn trail_factor(tr: &TrailSample, wave: Option<&Wave>, i: usize, tau: f64) -> f64 {
    if O1D_LINES[i] {
        tr.weight(tau, wave)
    } else if tr.is_now() {
        wave.map_or(1.0, |w| w.at_lifetime(tau))
    } else {
        0.0
    }
}

/// The Fang models: `frac(m)` is the fraction of the beam's power deposited
/// above column mass m, `total` its limit. Deposits `P (frac(m1) - frac(m0))`
/// per step with m the deepest column so far; stops when complete (the
/// remaining <= COMPLETE_TOL of the total goes into that last step) or below
/// the atmosphere's table.
fn trace_fang(
    ctx: &BeamContext,
    start: &BeamStart,
    r: &mut impl Rng,
    total: f64,
    frac: impl Fn(f64) -> f64,
    bufs: BeamBuffers,
) -> BeamTrace {
    let pw = start.power_kev_s;
    let mut p = start.position;
    let mut done = frac(ctx.atmosphere.column_mass(p.z));
    let mut out = BeamTrace::begin(p, pw * (1.0 - total), ctx.record_path, bufs);
    deposit_above_start(ctx, start, &mut out, &frac, total, done);
    let bottom = ctx.atmosphere.bottom_km();
    let z0 = start.position.z;
    let (half_l, half_w) = (0.5 * ctx.footprint.length, 0.5 * ctx.footprint.width);
    let local = ctx.footprint.local_map();
    for _ in 0..FANG_MAX_STEPS {
        if total - done <= COMPLETE_TOL * total {
            out.end = EndReason::EnergySpent;
            break;
        }
        let (mut p_new, _) = step(ctx, p, r);
        // The foot may leave the footprint's density (the beam goes on), but
        // not the simulated domain enlarged by its own size on every side:
        // only runaway steps (deflections near 90 degrees, huge lengths)
        // get that far; what they carry is reported as undeposited.
        let foot = ctx.field.foot(p_new, z0);
        let (u, v) = local.to_local(foot.x, foot.y);
        if !(u.abs() <= 2.0 * half_l && v.abs() <= 2.0 * half_w) {
            out.end = EndReason::LeftFootprint;
            break;
        }
        // A step through the atmosphere's bottom ends there: below it the
        // model has no air; the rest is reported as undeposited.
        let through_bottom = p_new.z < bottom;
        if through_bottom {
            p_new = p + (p_new - p) * ((p.z - bottom) / (p.z - p_new.z)).clamp(0.0, 1.0);
        }
        if ctx.record_path {
            out.path.push(p_new);
        }
        let f_new = frac(ctx.atmosphere.column_mass(p_new.z)).max(done);
        let complete = total - f_new <= COMPLETE_TOL * total;
        let f_new = if complete { total } else { f_new };
        if f_new > done {
            emit(ctx, start, &mut out, p, p_new, pw * (f_new - done), start.base_power_kev_s * (f_new - done));
        }
        done = f_new;
        p = p_new;
        if complete {
            out.end = EndReason::EnergySpent;
            break;
        }
        if through_bottom {
            out.end = EndReason::Bottom;
            break;
        }
    }
    out.undeposited_kev_s = pw * (total - done).max(0.0);
    out.end_position = p;
    out
}

/// What the spectrum deposits above the start altitude (soft electrons,
/// high up), `done` the fraction above the start's column: along the field
/// line above the start, in spans of [`ABOVE_START_SPAN_KM`] altitude, up
/// to `z_up`, the higher of [`above_start_top`] (where at most
/// [`ABOVE_START_TOL`] of the total lies higher) and one span above the
/// start (capped at the atmosphere's top). What lies above `z_up` is laid
/// in the top span: the tail above 250 km, which lights the red tops, keeps
/// its whole column (the cut-off share used to be dropped: 40 % of a 3 keV
/// Maxwellian's ionization above 250 km, all of a 10 keV one's), at the
/// price of its top 0.2 % sitting a few scale heights low, where the grid
/// already reaches. `above_top_kev_s` is zero, except for a beam starting
/// at the atmosphere's top, with no field line above it in the table.
fn deposit_above_start(ctx: &BeamContext, start: &BeamStart, out: &mut BeamTrace, frac: &impl Fn(f64) -> f64, total: f64, done: f64) {
    let pw = start.power_kev_s;
    let p = start.position;
    let z_up = above_start_column_top(ctx.atmosphere, frac, total, p.z);
    out.above_top_kev_s = 0.0;
    if z_up > p.z && done > 0.0 {
        let n = ((z_up - p.z) / ABOVE_START_SPAN_KM).ceil().max(1.0) as usize;
        let along = |z: f64| p + ctx.field.b * ((z - p.z) / ctx.field.b.z);
        // The top span starts from nothing deposited above it: it takes
        // everything above its bottom.
        let mut f_hi = 0.0;
        for k in (0..n).rev() {
            let (z_lo, z_hi) = (p.z + (z_up - p.z) * k as f64 / n as f64, p.z + (z_up - p.z) * (k + 1) as f64 / n as f64);
            let f_lo = if k == 0 { done } else { frac(ctx.atmosphere.column_mass(z_lo)).min(done) };
            if f_lo > f_hi {
                emit(ctx, start, out, along(z_hi), along(z_lo), pw * (f_lo - f_hi), start.base_power_kev_s * (f_lo - f_hi));
            }
            f_hi = f_hi.max(f_lo);
        }
    } else {
        out.above_top_kev_s = pw * done;
    }
}

/// The top of the column above a beam starting at `z_start` km:
/// [`above_start_top`], and at least one [`ABOVE_START_SPAN_KM`] above the
/// start (a hard spectrum's share above the start, under
/// [`ABOVE_START_TOL`], gets one span), within the atmosphere's table.
pub fn above_start_column_top(atm: &Atmosphere, frac: &impl Fn(f64) -> f64, total: f64, z_start: f64) -> f64 {
    above_start_top(atm, frac, total).max((z_start + ABOVE_START_SPAN_KM).min(atm.top_km()))
}

/// A Fang beam lays what its spectrum leaves above its start along the
/// field line above it, spread up to the altitude where at most this share
/// of the spectrum's total deposition lies higher ([`above_start_top`]);
/// that share goes into the top span.
pub const ABOVE_START_TOL: f64 = 2e-3;

/// Altitude span of each segment of that deposit, km: the deposition
/// above 250 km falls by e in some 40 km, so a 10 km span's power is
/// spread evenly along it to within about 12 % at its ends.
pub const ABOVE_START_SPAN_KM: f64 = 10.0;

/// The altitude above which at most [`ABOVE_START_TOL`] of `total` is
/// deposited by `frac` (the fraction deposited above a column mass), by
/// bisection on the atmosphere's table (40 halvings of its range: far below
/// a metre); the table's top if even that holds more.
pub fn above_start_top(atm: &Atmosphere, frac: &impl Fn(f64) -> f64, total: f64) -> f64 {
    let (mut lo, mut hi) = (atm.bottom_km(), atm.top_km());
    let above = |z: f64| frac(atm.column_mass(z));
    if above(hi) > ABOVE_START_TOL * total {
        return hi;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if above(mid) > ABOVE_START_TOL * total {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Continuous slowing down along straight steps (the model before Fang,
/// [`crate::physics::deposition::csda`]): the step's column mass shrinks the residual range; the
/// energy lost is the deposit. Stops after 1/dt steps, when the energy is
/// spent, or when the field-line foot leaves the footprint.
fn trace_csda(ctx: &BeamContext, start: &BeamStart, r: &mut impl Rng, bufs: BeamBuffers) -> BeamTrace {
    let max_steps = (1.0 / ctx.params.dt).round().max(1.0) as usize;
    let z0 = start.position.z;
    let f = ctx.field;
    let mut p = start.position;
    let mut e = start.energy_kev;
    let mut r_res = range_g_cm2(e);
    let power_per_kev = if start.energy_kev > 0.0 { start.power_kev_s / start.energy_kev } else { 0.0 };
    let base_per_kev = if start.energy_kev > 0.0 { start.base_power_kev_s / start.energy_kev } else { 0.0 };
    let mut col_p = ctx.atmosphere.column_mass(p.z);
    let mut out = BeamTrace::begin(p, 0.0, ctx.record_path, bufs);
    if e <= 0.0 {
        out.end = EndReason::EnergySpent;
        return out;
    }
    for _ in 0..max_steps {
        let (p_new, len) = step(ctx, p, r);
        // Still above the footprint? Its field line must come from a cell
        // above threshold at the start altitude.
        let foot = f.foot(p_new, z0);
        if ctx.footprint.cell_value_world(foot.x, foot.y) <= ctx.threshold {
            out.end = EndReason::LeftFootprint;
            break;
        }
        // Column mass along the straight step (plane-parallel atmosphere).
        let col_new = ctx.atmosphere.column_mass(p_new.z);
        let column = step_column(ctx.atmosphere, p.z, p_new.z, len, col_p, col_new);
        r_res -= column;
        let e_after = energy_from_range(r_res);
        let de = e - e_after;
        let from = p;
        p = p_new;
        col_p = col_new;
        if ctx.record_path {
            out.path.push(p);
        }
        if de > 0.0 {
            emit(ctx, start, &mut out, from, p, de * power_per_kev, de * base_per_kev);
        }
        e = e_after;
        if e <= 0.0 {
            out.end = EndReason::EnergySpent;
            break;
        }
    }
    out.undeposited_kev_s = e.max(0.0) * power_per_kev;
    out.end_position = p;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::emission::line_colour::EmissionModel;
    use crate::pipeline::beams::sample_gamma3;
    use crate::util::rng;

    #[test]
    fn chained_deposits_are_the_mapped_ends() {
        // Steps that start where the last one ended reuse its mapping; a
        // step that does not (a new start) maps its own; on a round Earth
        // and a flat one, every photon is `deposit`'s.
        for earth in [Earth::new(crate::geometry::earth::MEAN_RADIUS_KM), Earth::new(0.0)] {
            let mut out = BeamTrace::begin(DVec3::ZERO, 0.0, false, BeamBuffers::default());
            let pts = [DVec3::new(10.0, -3.0, 200.0), DVec3::new(10.2, -3.1, 198.5), DVec3::new(10.3, -3.0, 197.0)];
            let steps = [(pts[0], pts[1]), (pts[1], pts[2]), (pts[0], pts[2]), (pts[2], DVec3::new(-0.0, 0.0, 120.0))];
            for (a, b) in steps {
                let got = deposit_next(&earth, &mut out, a, b, [1.0, 2.0, 3.0]);
                assert_eq!(got, deposit(&earth, a, b, [1.0, 2.0, 3.0]), "{a} {b}");
            }
        }
    }

    /// A footprint that is 1 everywhere in a huge box: beams never leave it.
    fn flat_footprint(size: f64) -> Footprint {
        Footprint { nx: 4, ny: 4, data: vec![1.0; 16], center: [0.0, 0.0], rotation_rad: 0.0, length: size, width: size, path: None }
    }

    fn params() -> BeamParams {
        BeamParams { length_km: 400.0, dt: 0.0025, ..BeamParams::default() }
    }

    fn start(e: f64) -> BeamStart {
        BeamStart {
            position: DVec3::new(0.0, 0.0, 260.0),
            energy_kev: e,
            power_kev_s: 1.0,
            base_power_kev_s: 1.0,
            wave: None,
            colour_offset_km: 0.0,
            flux_kev_cm2_s: 0.0,
        }
    }

    #[test]
    fn deflection_angle_to_b_lies_in_the_sampled_range() {
        let atm = Atmosphere::us1976();
        let colour = ColourTable::physical(&EmissionModel::default());
        let fp = flat_footprint(1e5);
        let p = BeamParams { alpha_d_deg: 25.0, delta_alpha_deg: 12.0, b_inclination_deg: 70.0, b_declination_deg: 20.0, ..params() };
        let ctx = BeamContext {
            atmosphere: &atm,
            model: DepositModel::Csda,
            colour: &colour,
            field: MagneticField::new(70.0, 20.0),
            params: &p,
            footprint: &fp,
            threshold: 0.03,
            record_path: true,
            lines: None,
            trail: None,
            line_outputs: &[],
            ionization: None,
            earth: Earth::FLAT,
        };
        let (lo, hi) = ((25.0f64 - 12.0).to_radians(), 25.0f64.to_radians());
        let mut r = rng::rng(&[1]);
        let mut n = 0;
        for k in 0..20 {
            let t = trace_beam(&ctx, &start(2.0 + k as f64), &mut r);
            for w in t.path.windows(2) {
                let d = w[1] - w[0];
                let len = d.length();
                if len < 1e-6 {
                    continue; // a step with xi ~ 0 has no direction to measure
                }
                let angle = (d.dot(ctx.field.b) / len).clamp(-1.0, 1.0).acos();
                // acos near small angles loses precision ~ sqrt(eps / len);
                // 1e-6 rad covers it for steps above 1 um.
                assert!(angle >= lo - 1e-6 && angle <= hi + 1e-6, "angle {} deg", angle.to_degrees());
                n += 1;
            }
        }
        assert!(n > 1000, "{n} steps checked");
    }

    #[test]
    fn monoenergetic_beam_deposits_exactly_its_energy() {
        let atm = Atmosphere::us1976();
        let colour = ColourTable::physical(&EmissionModel::default());
        let fp = flat_footprint(1e5);
        let p = params();
        let ctx = context(&atm, &colour, &fp, &p, DepositModel::Csda);
        let mut r = rng::rng(&[2]);
        for e0 in [0.5, 3.0, 10.0, 30.0] {
            let t = trace_beam(&ctx, &start(e0), &mut r);
            assert_eq!(t.end, EndReason::EnergySpent, "{e0} keV");
            // power_kev_s = 1: the deposits are the fractions E_lost / E0.
            let sum: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
            // The deposits telescope: sum = (E0 - 0) / E0, up to one rounding
            // per step (a few hundred steps x 1 ulp).
            assert!((sum - 1.0).abs() < 1e-12 * t.deposits.len() as f64, "{e0}: {sum}");
            assert_eq!(t.photons.len(), t.deposits.len());
            assert_eq!(t.undeposited_kev_s, 0.0);
        }
    }

    #[test]
    fn harder_electrons_penetrate_deeper() {
        let atm = Atmosphere::us1976();
        let colour = ColourTable::physical(&EmissionModel::default());
        let fp = flat_footprint(1e5);
        let p = params();
        let ctx = context(&atm, &colour, &fp, &p, DepositModel::Csda);
        let mut r = rng::rng(&[3]);
        let mut mean_end = |e0: f64| {
            let n = 50;
            (0..n).map(|_| trace_beam(&ctx, &start(e0), &mut r).end_position.z).sum::<f64>() / n as f64
        };
        let (z1, z3, z10) = (mean_end(1.0), mean_end(3.0), mean_end(10.0));
        // Range-energy with USSA 1976 columns: 10 keV (2.5e-4 g/cm^2) stops
        // near 102 km, 1 keV (5.8e-6 g/cm^2) near 148 km; slant paths and
        // deflections add a few percent of column (a fraction of a km).
        assert!((97.0..106.0).contains(&z10), "10 keV ends at {z10}");
        assert!((140.0..160.0).contains(&z1), "1 keV ends at {z1}");
        assert!(z10 < z3 && z3 < z1);
    }

    /// A beam context for the tests: `p`'s field, no per-line output, no
    /// ionization profile (q = 0 at every deposit).
    fn context<'a>(
        atm: &'a Atmosphere,
        colour: &'a ColourTable,
        fp: &'a Footprint,
        p: &'a BeamParams,
        model: DepositModel<'a>,
    ) -> BeamContext<'a> {
        BeamContext {
            atmosphere: atm,
            model,
            colour,
            field: MagneticField::new(p.b_inclination_deg, p.b_declination_deg),
            params: p,
            footprint: fp,
            threshold: 0.03,
            record_path: false,
            lines: None,
            trail: None,
            line_outputs: &[],
            ionization: None,
            earth: Earth::FLAT,
        }
    }

    #[test]
    fn expected_beam_deposits_the_spectrum_total_below_its_start_and_accounts_for_the_rest() {
        let atm = Atmosphere::nrlmsis21();
        let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
        let fp = flat_footprint(1e5);
        let p = params();
        for (e0, soft) in [(1.0, 0.0), (3.0, 0.1), (30.0, 0.0)] {
            let g = SpectrumDeposition::curtain(e0, soft, 0.2);
            let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
            let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(e0) }, &mut rng::rng(&[7]));
            assert_eq!(t.end, EndReason::EnergySpent, "{e0} keV");
            let dep: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
            // Above the start it lays its share up to z_up (where at most
            // ABOVE_START_TOL of the total lies higher, at least one span
            // above the start), the rest above z_up in the top span: a
            // finished beam deposits exactly G(inf) (sums of telescoping
            // differences, rounding only) and reports nothing above.
            let z_up = above_start_column_top(&atm, &|m| g.fraction_above(m), g.total(), 260.0);
            let above = g.fraction_above(atm.column_mass(z_up));
            assert!(z_up <= atm.top_km() && z_up >= 270.0 && above <= ABOVE_START_TOL * g.total().max(1.0), "{e0}: {z_up} km, {above}");
            assert!((dep - g.total()).abs() < 1e-12, "{e0}: {dep} vs {}", g.total());
            assert!(t.above_top_kev_s == 0.0 && t.undeposited_kev_s == 0.0);
            // What lies above the start is on the field line above it, and
            // the top span holds what lies above its bottom.
            let up: f64 = t.deposits.iter().filter(|d| d.z_end >= 260.0 - 1e-9).map(|d| d.power_kev_s).sum();
            let want = g.fraction_above(atm.column_mass(260.0));
            assert!((up - want).abs() < 1e-12, "{e0}: above the start {up} vs {want}");
            let top = t.deposits.iter().map(|d| d.z_start.max(d.z_end)).fold(0.0, f64::max);
            assert!((top - z_up).abs() < 1e-6, "{e0}: highest deposit {top} km, column top {z_up} km");
            assert!((dep + t.backscatter_kev_s + t.above_top_kev_s - 1.0).abs() < 1e-12);
            assert!(t.deposits.iter().all(|d| d.power_kev_s > 0.0));
        }
    }

    #[test]
    fn fang_beams_keep_going_when_their_foot_leaves_the_footprint() {
        let atm = Atmosphere::nrlmsis21();
        let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
        // A 2 km strip of density (the kind that stops CSDA beams, test
        // below) in the middle of an 18 km box.
        let mut data = vec![0.0; 9];
        data[4] = 1.0;
        let fp = Footprint { nx: 1, ny: 9, data, center: [0.0, 0.0], rotation_rad: 0.0, length: 1e4, width: 18.0, path: None };
        let p = BeamParams { alpha_d_deg: 20.0, delta_alpha_deg: 10.0, ..params() };
        let g = SpectrumDeposition::curtain(30.0, 0.0, 0.2);
        let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
        let mut r = rng::rng(&[6]);
        let mut outside = 0;
        for _ in 0..20 {
            let t = trace_beam(&ctx, &start(30.0), &mut r);
            assert_eq!(t.end, EndReason::EnergySpent);
            assert_eq!(t.undeposited_kev_s, 0.0);
            outside += t
                .photons
                .iter()
                .filter(|ph| {
                    let q = DVec3::new(ph.position[0] as f64, ph.position[1] as f64, ph.position[2] as f64);
                    let foot = ctx.field.foot(q, 260.0);
                    fp.cell_value_world(foot.x, foot.y) <= 0.03
                })
                .count();
        }
        assert!(outside > 100, "only {outside} photons beyond the strip: the test does not test");
    }

    #[test]
    fn runaway_fang_steps_end_at_the_bottom_or_the_enlarged_box() {
        let atm = Atmosphere::nrlmsis21();
        let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
        let fp = Footprint { nx: 1, ny: 1, data: vec![1.0], center: [0.0, 0.0], rotation_rad: 0.0, length: 10.0, width: 4.0, path: None };
        let g = SpectrumDeposition::curtain(3.0, 0.0, 0.2);
        // Straight down in steps of up to 2.5e6 km: the first step is cut at
        // the atmosphere's bottom (where a 3 keV spectrum is complete).
        let p = BeamParams { length_km: 1e9, alpha_d_deg: 0.0, delta_alpha_deg: 0.0, b_inclination_deg: 90.0, ..params() };
        let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
        let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(3.0) }, &mut rng::rng(&[9]));
        assert!(matches!(t.end, EndReason::Bottom | EndReason::EnergySpent), "{:?}", t.end);
        assert!(t.photons.iter().all(|ph| ph.position[2] >= 50.0 - 1e-4), "{:?}", t.photons);
        let dep: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
        assert!((dep + t.backscatter_kev_s + t.above_top_kev_s + t.undeposited_kev_s - 1.0).abs() < 1e-12);
        // Near-horizontal steps of 1e11 km: stopped at the box enlarged by
        // its size (|u| <= 10, |v| <= 4 at the start altitude), never placing
        // a photon whose foot is further out.
        let p = BeamParams { length_km: 1e9, alpha_d_deg: 89.999, delta_alpha_deg: 0.0, b_inclination_deg: 10.0, ..params() };
        let ctx = context(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
        let mut r = rng::rng(&[10]);
        for _ in 0..20 {
            let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(3.0) }, &mut r);
            assert_ne!(t.end, EndReason::MaxSteps);
            for ph in &t.photons {
                let q = DVec3::new(ph.position[0] as f64, ph.position[1] as f64, ph.position[2] as f64);
                let foot = ctx.field.foot(q, 260.0);
                assert!(foot.x.abs() <= 10.0 + 1e-3 && foot.y.abs() <= 4.0 + 1e-3, "{foot}");
            }
        }
    }

    #[test]
    fn sampled_deposition_converges_to_the_expected_one_step_by_step() {
        // Same random stream => same path in both models (the energy is
        // drawn before the path and the path does not depend on it), so per
        // altitude bin the sampled deposits' mean over beams must converge
        // to the expected model's (Rao-Blackwellisation: E[D_E] = G). Test
        // each 2 km bin at 5 standard errors of the sampled mean (sample
        // variance over N = 4000 beams; 80 bins, so a false alarm at
        // 5 sigma has probability ~ 80 x 6e-7).
        let atm = Atmosphere::nrlmsis21();
        let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
        let fp = flat_footprint(1e5);
        let p = params();
        let (e0, soft, e_soft) = (3.0, 0.2, 0.3);
        let g = SpectrumDeposition::curtain(e0, soft, e_soft);
        let (ce, cs) = (
            context(&atm, &colour, &fp, &p, DepositModel::Expected(&g)),
            context(&atm, &colour, &fp, &p, DepositModel::Sampled(MonoDeposition::get())),
        );
        let n = 4000;
        let nb = 80;
        let bin = |z: f64| (((z - 80.0) / 2.0).floor() as isize).clamp(0, nb as isize - 1) as usize;
        let (mut sum_e, mut sum_s, mut sum_s2) = (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
        for i in 0..n {
            let mut r = rng::rng(&[8, i as u64]);
            let e0_i = if r.random::<f64>() < soft { e_soft } else { e0 };
            let st = BeamStart { energy_kev: sample_gamma3(e0_i, &mut r), ..start(0.0) };
            let mut r2 = r.clone();
            let (te, ts) = (trace_beam(&ce, &st, &mut r), trace_beam(&cs, &st, &mut r2));
            let mut per = vec![0.0; nb];
            for d in &ts.deposits {
                per[bin(d.z_end)] += d.power_kev_s;
            }
            for d in &te.deposits {
                sum_e[bin(d.z_end)] += d.power_kev_s;
            }
            // Above the start: both models account for it, not deposit it.
            sum_e[nb - 1] += te.above_top_kev_s;
            per[nb - 1] += ts.above_top_kev_s;
            for b in 0..nb {
                sum_s[b] += per[b];
                sum_s2[b] += per[b] * per[b];
            }
        }
        let nf = n as f64;
        let mut checked = 0;
        for b in 0..nb {
            let (me, ms) = (sum_e[b] / nf, sum_s[b] / nf);
            let se = ((sum_s2[b] / nf - ms * ms).max(0.0) / nf).sqrt();
            assert!((me - ms).abs() <= 5.0 * se + 1e-9, "bin {} km: expected {me:.5} sampled {ms:.5} +- {se:.5}", 80 + 2 * b);
            if me > 1e-3 {
                checked += 1;
            }
        }
        assert!(checked > 15, "{checked} bins with deposits");
    }

    #[test]
    fn beams_leave_when_their_foot_leaves_the_footprint() {
        let atm = Atmosphere::us1976();
        let colour = ColourTable::physical(&EmissionModel::default());
        // A 2 km wide strip: a random walk of 10-20 degree steps leaves it.
        let fp = Footprint { nx: 1, ny: 1, data: vec![1.0], center: [0.0, 0.0], rotation_rad: 0.0, length: 1e4, width: 2.0, path: None };
        let p = BeamParams { alpha_d_deg: 20.0, delta_alpha_deg: 10.0, ..params() };
        let ctx = context(&atm, &colour, &fp, &p, DepositModel::Csda);
        let mut r = rng::rng(&[6]);
        let mut left = 0;
        for _ in 0..50 {
            let t = trace_beam(&ctx, &start(30.0), &mut r);
            if t.end == EndReason::LeftFootprint {
                left += 1;
                let foot = ctx.field.foot(t.end_position, 260.0);
                assert!(fp.cell_value_world(foot.x, foot.y) > 0.03, "the last accepted point is inside");
            }
            for ph in &t.photons {
                let q = DVec3::new(ph.position[0] as f64, ph.position[1] as f64, ph.position[2] as f64);
                let foot = ctx.field.foot(q, 260.0);
                // f32 positions: allow 1e-4 km of rounding at the strip edge.
                assert!(foot.y.abs() < 1.0 + 1e-4, "photon outside the strip: {foot}");
            }
        }
        assert!(left > 10, "only {left} of 50 left a 2 km strip");
    }
}
