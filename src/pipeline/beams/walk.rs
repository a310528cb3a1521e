//! One beam's walk down the geomagnetic field (Baranoski, Rokne, Shirley,
//! Trondsen & Bastos, "Simulating the aurora borealis", Pacific Graphics
//! 2000): each step `p_new = p + s B + t (u cos beta + v sin beta)`, its
//! length, its deflection from B and the deflection's azimuth independent
//! random numbers ([`trace_beam`]); each step's deposit becomes a photon
//! ([`super::emit`]).
//!
//! The deposit follows the atmosphere, in one of three models
//! (`beams.deposition`, [`DepositModel`]):
//! - **expected** (default): every beam carries its curtain's whole
//!   spectrum and deposits `P (G(m1) - G(m0))` between the column masses of
//!   the step's ends, `G` Fang et al. 2010 integrated over the spectrum
//!   (`crate::physics::deposition::fang`); random numbers shape only the path.
//! - **sampled**: one energy per beam, Fang 2010's monoenergetic profile,
//!   `P (D_E(m1) - D_E(m0))`: the same mean.
//! - **csda**: one energy per beam, continuous slowing down along the
//!   straight step by the range-energy relation of Barrett & Hays 1976
//!   (`crate::physics::deposition::csda`), for comparison.
//!
//! In the Fang models `m` is the deepest column reached so far, so deposits
//! are never negative and sum to `P G(m_deepest)`. A Fang beam stops when at
//! most [`COMPLETE_TOL`] of its total remains (deposited on that last step),
//! at the atmosphere's bottom (a step through it is cut there), or when its
//! field-line foot leaves the footprint's box enlarged by its own size on
//! every side (runaway steps only: the footprint says where electrons enter
//! at the top, not where a field line ends). What the spectrum deposits
//! above the start is laid along the field line above it, in spans that
//! follow the deposition's shape up to where at most [`ABOVE_START_TOL`]
//! of it lies higher ([`above_start_spans`]). A CSDA beam stops when its foot leaves the
//! footprint, after `1/dt` steps, or when its energy is spent. What a beam
//! did not deposit is reported ([`super::CurtainPower`]).
//!
//! On a round Earth (`crate::geometry::earth`) the walk is in the curved
//! frame: positions are ground coordinates and altitude, so `z` is the
//! altitude the atmosphere, the deposition and the colour read, and the
//! field's angles are relative to the local vertical and north.

use super::beam::{BeamBuffers, BeamContext, BeamStart, BeamTrace, DepositModel, EndReason};
use super::emit::emit;
use crate::physics::atmosphere::Atmosphere;
use crate::physics::deposition::csda::{energy_from_range, range_g_cm2, step_column};
use crate::util::fmath;
use glam::DVec3;
use rand::Rng;

/// Safety cap on the steps of a Fang-model beam (which otherwise goes on
/// until its deposition is complete).
pub const FANG_MAX_STEPS: usize = 1_000_000;

/// A beam has finished when at most this fraction of its spectrum's total
/// deposition remains (the rest goes into its last step).
pub const COMPLETE_TOL: f64 = 1e-4;

/// Traces one beam (Baranoski et al. 2000, eq. for p_new) from `start`.
///
/// Each step: `p_new = p + s B + t (u cos beta + v sin beta)` with
/// `s = L dt xi`, `tan alpha = t / s`, alpha uniform in
/// [alpha_D - delta_alpha, alpha_D], beta uniform in [0, 2 pi), xi uniform in
/// [0, 1), all independent. The energy the step deposits ([`DepositModel`])
/// becomes one photon ([`super::emit::deposit`]), coloured by the emission
/// lines at the step's end altitude.
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
    let t = s * fmath::tan(alpha);
    let (sb, cb) = fmath::sin_cos(beta);
    let f = ctx.field;
    (p + f.b * s + (f.u * cb + f.v * sb) * t, s / fmath::cos(alpha))
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
    done = deposit_above_start(ctx, start, &mut out, &frac, total, done);
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
/// high up), `done` the fraction above the start's column, laid along the
/// field line above the start following the deposition's own shape (Fang
/// 2010 over the spectrum): the spans of [`above_start_spans`] up to the
/// altitude where at most [`ABOVE_START_TOL`] of the total lies higher
/// ([`above_start_column_top`]; that last share is reported, not laid:
/// `above_top_kev_s`).
/// Each span holds the difference of the fraction above its ends, spread
/// evenly along it. Returns the fraction the walk below starts from, `done`
/// (where no column lies above the start, the share above it, under
/// [`ABOVE_START_TOL`], is reported as above the top, not laid in the
/// first step).
fn deposit_above_start(
    ctx: &BeamContext,
    start: &BeamStart,
    out: &mut BeamTrace,
    frac: &impl Fn(f64) -> f64,
    total: f64,
    done: f64,
) -> f64 {
    let pw = start.power_kev_s;
    let p = start.position;
    out.above_top_kev_s = 0.0;
    let spans = above_start_spans(ctx.atmosphere, frac, total, p.z);
    if spans.len() < 2 || done <= 0.0 {
        // No column: at most ABOVE_START_TOL of the total lies above the
        // start, reported, not laid in the first step (a lid at the start).
        out.above_top_kev_s = pw * done.max(0.0);
        return done.max(0.0);
    }
    let along = |z: f64| column_point(ctx, p, z);
    // Top down: what lies above the top (at most ABOVE_START_TOL of the
    // total, high in the thin air) is not laid anywhere, so the top span
    // holds only its own share: the deposit ends with the topside's own
    // shape instead of a lid of everything above it in one span.
    let top = spans[spans.len() - 1];
    let mut f_hi = frac(ctx.atmosphere.column_mass(top)).min(done);
    out.above_top_kev_s = pw * f_hi;
    for k in (0..spans.len() - 1).rev() {
        let (z_lo, z_hi) = (spans[k], spans[k + 1]);
        let f_lo = if k == 0 { done } else { frac(ctx.atmosphere.column_mass(z_lo)).min(done) };
        if f_lo > f_hi {
            emit(ctx, start, out, along(z_hi), along(z_lo), pw * (f_lo - f_hi), start.base_power_kev_s * (f_lo - f_hi));
        }
        f_hi = f_hi.max(f_lo);
    }
    done
}

/// The point at altitude `z` of the field line through `p`, in the walk's
/// frame. On a round Earth (`crate::geometry::earth`) a ground distance at
/// altitude h spans `(R + h) / R` times as much: a line of the field's
/// constant inclination covers `cot(I) R ln((R + z) / (R + z0))` of ground
/// between altitudes z0 and z (the straight line of the flat frame, the
/// limit R -> inf, is 0.6 degree off at 600 km where the column of a soft
/// spectrum reaches).
fn column_point(ctx: &BeamContext, p: DVec3, z: f64) -> DVec3 {
    let b = ctx.field.b;
    let dz = z - p.z;
    let r = ctx.earth.radius_km;
    let ground = if r > 0.0 { r * fmath::ln((r + z) / (r + p.z)) } else { dz };
    DVec3::new(p.x + b.x * ground / b.z, p.y + b.y * ground / b.z, z)
}

/// The top of the column above a beam starting at `z_start` km:
/// [`above_start_top`] within the atmosphere's table, or `z_start` where
/// that lies below the start (no column).
pub fn above_start_column_top(atm: &Atmosphere, frac: &impl Fn(f64) -> f64, total: f64, z_start: f64) -> f64 {
    above_start_top(atm, frac, total).min(atm.top_km()).max(z_start)
}

/// The span boundaries, km, ascending from `z_start` to
/// [`above_start_column_top`] (empty without a column): each span ends
/// where the fraction deposited above, F, and the deposit per km, q =
/// -dF/dz, have changed by at most the factor `exp(`[`ABOVE_START_DLN`]`)`
/// from its bottom (the local e-folding lengths `F / q` and
/// `q / |dq/dz|` times the step, by differences over
/// [`ABOVE_START_DZ_KM`] either side), from [`ABOVE_START_MIN_SPAN_KM`] to
/// [`ABOVE_START_SPAN_KM`] long: a span's deposit spread evenly is within
/// about `exp(+-DLN / 2)` of the profile at its ends. At most
/// [`max_above_start_spans`] spans.
pub fn above_start_spans(atm: &Atmosphere, frac: &impl Fn(f64) -> f64, total: f64, z_start: f64) -> Vec<f64> {
    let top = above_start_column_top(atm, frac, total, z_start);
    if top <= z_start {
        return Vec::new();
    }
    let f = |z: f64| frac(atm.column_mass(z));
    let mut z = z_start;
    let mut out = vec![z];
    let max = max_above_start_spans(top - z_start);
    while z < top && out.len() < max {
        let d = ABOVE_START_DZ_KM;
        let (lo, mid, hi) = (f(z - d), f(z), f(z + d));
        let (q1, q2) = ((lo - mid) / d, (mid - hi) / d);
        let q = 0.5 * (q1 + q2);
        // Where the fraction above falls by e, and where the deposit per
        // km changes by e (near a soft spectrum's peak the first is long).
        let l_f = if q > 0.0 { mid / q } else { f64::INFINITY };
        let l_q = if q1 > 0.0 && q2 > 0.0 && q1 != q2 { d / fmath::ln(q1 / q2).abs() } else { f64::INFINITY };
        let step = (ABOVE_START_DLN * l_f.min(l_q)).clamp(ABOVE_START_MIN_SPAN_KM, ABOVE_START_SPAN_KM);
        z = (z + step).min(top);
        out.push(z);
    }
    if z < top {
        *out.last_mut().expect("a start") = top;
    }
    out
}

/// Bound on the spans of a column `column_km` high ([`above_start_spans`]
/// cuts the list there, its last span reaching the top): twice the spans
/// that lower the fraction above by `exp(DLN)` each from the whole deposit
/// to [`ABOVE_START_TOL`] of it (the deposit's own e-folding may set the
/// step instead) plus one per [`ABOVE_START_SPAN_KM`] of column. Used by
/// the memory budget.
pub fn max_above_start_spans(column_km: f64) -> usize {
    2 * (fmath::ln(1.0 / ABOVE_START_TOL) / ABOVE_START_DLN).ceil() as usize
        + (column_km.max(0.0) / ABOVE_START_SPAN_KM).ceil() as usize
        + 2
}

/// A Fang beam lays what its spectrum leaves above its start along the
/// field line above it, up to the altitude where at most this share of the
/// spectrum's total deposition lies higher ([`above_start_top`]); that
/// share is not laid (reported as above the top). 1e-4: the column ends
/// with the topside's own shape where it holds no visible light (at 2e-3 the
/// cut lay where 630.0 nm was still 15-20 % of its peak, and laying the
/// rest in the top span made a red lid).
pub const ABOVE_START_TOL: f64 = 1e-4;

/// Most a span of that deposit lowers the fraction deposited above it, in
/// ln: 0.15, so a span's deposit spread evenly is within about 8 % of the
/// profile at its ends.
pub const ABOVE_START_DLN: f64 = 0.15;

/// Longest and shortest spans of that deposit, km: 10 km where the
/// fraction above barely changes (just above the peak of a soft spectrum),
/// 0.25 km at least (a slope so steep belongs to the first span over a
/// hard spectrum's last trace).
pub const ABOVE_START_SPAN_KM: f64 = 10.0;
pub const ABOVE_START_MIN_SPAN_KM: f64 = 0.25;

/// The altitude step of the differences in [`above_start_spans`], km:
/// the spectrum's table is linear between nodes 0.02 apart in ln m, 0.8
/// km at a 40 km scale height, so differences over 1 km either side see
/// its slope, not its nodes.
pub const ABOVE_START_DZ_KM: f64 = 1.0;

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

/// Continuous slowing down along straight steps
/// ([`crate::physics::deposition::csda`]): the step's column mass shrinks the residual range; the
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
mod tests;
