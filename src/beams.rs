//! Electron beams: precipitating electrons traced down the geomagnetic field
//! with random deflections (Baranoski, Rokne, Shirley, Trondsen & Bastos,
//! "Simulating the aurora borealis", Pacific Graphics 2000), losing energy to
//! the atmosphere, and leaving a photon at every deflection point.
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
//!     `G` Fang et al. 2010 integrated over the spectrum ([`crate::fang`]).
//!     Random numbers shape only the path (Rao-Blackwellisation: the path
//!     does not depend on the electron's energy in this model), so which
//!     altitudes a beam lights is no longer a coin toss.
//!   - **sampled**: one energy per beam, drawn as below, deposited by Fang
//!     2010's monoenergetic profile, `P (D_E(m1) - D_E(m0))`: the same mean.
//!   - **csda**: one energy per beam, continuous slowing down along the
//!     straight step with the range-energy relation `R(E) = 4.30e-7 +
//!     5.36e-6 E^1.67` g cm^-2 (Barrett & Hays 1976, Rees 1989): the model
//!     before Fang, which puts the energy at the end of the range. Kept for
//!     comparison, with its old stopping rules (below).
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
//!   deposit is reported ([`CurtainPower`]), so nothing is lost silently.
//! - Photons carry physical power (see [`Photon`]), not a colour-map colour.
//!
//! Normalisation: curtain c with peak energy flux `F` (mW m^-2 = erg cm^-2
//! s^-1) and footprint `f` (peak 1) receives the electron power
//! `P_c = F * int f dA` over the cells above threshold. Its `N_c` beams (its
//! `beam_weight` share of `beams.count`) each carry `P_c / N_c`. A beam's
//! energy E is drawn from the *energy-flux* distribution of a Maxwellian:
//! the number flux is `phi(E) ~ E exp(-E/E0)` (a Gamma(2, E0) density), so
//! the energy flux is `E phi(E) ~ Gamma(3, E0)`; since every beam carries
//! the same power, energies must follow the energy flux, else hard electrons
//! would be under-weighted by E / <E>. A share `soft_fraction` of the energy
//! flux is carried by a second, soft Maxwellian (E0 = `soft_energy_kev`, some
//! 0.1 keV): the low-energy electrons of real arc spectra that stop above
//! 200 km, where O(1D) escapes quenching and the red tops shine. Each beam is
//! soft with probability `soft_fraction` (equal-power beams: the mixture by
//! energy flux).

use crate::atmosphere::Atmosphere;
use crate::fang::{MonoDeposition, SpectrumDeposition};
use crate::footprint::Footprint;
use crate::progress::Progress;
use crate::rng;
use crate::scene::{AnimationParams, BeamParams, BeamStarts, Curtain, Deposition, KernelShape, Scene};
use crate::spectrum::ColourTable;
use glam::DVec3;
use noise::Perlin;
use rand::Rng;
use rayon::prelude::*;

/// keV per joule.
pub const KEV_PER_J: f64 = 1.0 / 1.602_176_634e-16;

/// A photon of the photon map: a segment from `position` to `end` (km; a
/// point photon has `end == position`) and the power emitted along it,
/// spread uniformly, as linear Rec.709 RGB in "557.7 nm photons per second"
/// (one photon per second of 557.7 nm has luminance 1; see `spectrum`). The
/// gather convolves its kernel with the segment (`crate::photons`, photon
/// beams of Jarosz et al. 2011).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    pub position: [f32; 3],
    pub end: [f32; 3],
    pub power: [f32; 3],
}

impl Photon {
    /// A point photon at `p`.
    #[inline]
    pub fn point(p: [f32; 3], power: [f32; 3]) -> Self {
        Self { position: p, end: p, power }
    }

    /// A segment photon from `a` to `b`.
    #[inline]
    pub fn segment(a: [f32; 3], b: [f32; 3], power: [f32; 3]) -> Self {
        Self { position: a, end: b, power }
    }

    /// The same power as a point photon at the segment's end (the deflection
    /// point where the point estimator of `photons.kernel = "point"` puts it).
    #[inline]
    pub fn to_point(self) -> Self {
        Self::point(self.end, self.power)
    }

    /// Whether the photon is a point (zero-length segment).
    #[inline]
    pub fn is_point(&self) -> bool {
        self.position == self.end
    }
}

/// The photon of one beam step: `power` spread along the step from `start`
/// to `end` (km). The gather's segment kernel smooths it along the step;
/// `photons.kernel = "point"` collapses it to a point at `end`.
#[inline]
pub fn deposit(start: DVec3, end: DVec3, power: [f32; 3]) -> Photon {
    Photon::segment([start.x as f32, start.y as f32, start.z as f32], [end.x as f32, end.y as f32, end.z as f32], power)
}

/// The geomagnetic frame: `b` the unit field direction (pointing down, the
/// way precipitating electrons move), `u`, `v` completing an orthonormal,
/// right-handed basis (u x v = b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    pub b: DVec3,
    pub u: DVec3,
    pub v: DVec3,
}

impl Field {
    /// B dipping `inclination_deg` below the horizon, its horizontal part
    /// toward azimuth `declination_deg` (degrees from +y, north, toward +x, east).
    pub fn new(inclination_deg: f64, declination_deg: f64) -> Self {
        let (si, ci) = inclination_deg.to_radians().sin_cos();
        let (sd, cd) = declination_deg.to_radians().sin_cos();
        let b = DVec3::new(ci * sd, ci * cd, -si).normalize();
        // Any unit vector orthogonal to b; pick the one from the axis least
        // aligned with b.
        let a = if b.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let u = (a - b * a.dot(b)).normalize();
        let v = b.cross(u);
        Self { b, u, v }
    }

    /// The point where the field line through `p` crosses altitude `z`
    /// (traced back up along -B for z above p).
    #[inline]
    pub fn foot(&self, p: DVec3, z: f64) -> DVec3 {
        // p + b * t has altitude z when t = (z - p.z) / b.z.
        p + self.b * ((z - p.z) / self.b.z)
    }
}

/// Range-energy relation of precipitating electrons in air (Barrett & Hays
/// 1976 / Rees 1989): the column mass, g cm^-2, that stops an electron of
/// energy `e_kev` keV.
#[inline]
pub fn range_g_cm2(e_kev: f64) -> f64 {
    4.30e-7 + 5.36e-6 * e_kev.max(0.0).powf(1.67)
}

/// Inverse of [`range_g_cm2`]: the energy whose range is `r`; 0 when `r`
/// does not exceed the relation's offset R(0).
#[inline]
pub fn energy_from_range(r: f64) -> f64 {
    let x = r - 4.30e-7;
    if x <= 0.0 {
        0.0
    } else {
        (x / 5.36e-6).powf(1.0 / 1.67)
    }
}

/// Draws an energy from Gamma(3, e0), the energy-flux distribution of a
/// Maxwellian of characteristic energy e0: the sum of three exponentials.
pub fn sample_gamma3(e0: f64, r: &mut impl Rng) -> f64 {
    // 1 - U lies in (0, 1], so the logarithm is finite.
    let p = (1.0 - r.random::<f64>()) * (1.0 - r.random::<f64>()) * (1.0 - r.random::<f64>());
    -e0 * p.ln()
}

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
    /// Electron power of the beam, keV/s.
    pub power_kev_s: f64,
    /// Colour altitude offset of this beam, km (the report's low-frequency
    /// colour noise; it shifts colour, not intensity).
    pub colour_offset_km: f64,
}

/// The result of tracing one beam.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamTrace {
    pub photons: Vec<Photon>,
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
}

/// One step's deposit: from altitude `z_start` to `z_end` km, `power_kev_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepDeposit {
    pub z_start: f64,
    pub z_end: f64,
    pub power_kev_s: f64,
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
    pub field: Field,
    pub params: &'a BeamParams,
    pub footprint: &'a Footprint,
    /// Footprint density at or below which a beam has left the curtain.
    pub threshold: f64,
    /// Keep the path (off in the bake: memory).
    pub record_path: bool,
}

/// Cumulative distribution over the footprint cells above threshold, each
/// cell weighted by its density (beams per area follow the energy flux).
#[derive(Clone, Debug)]
pub struct FootprintCdf {
    cells: Vec<u32>,
    cdf: Vec<f64>,
}

impl FootprintCdf {
    pub fn new(f: &Footprint, threshold: f64) -> Self {
        let mut cells = Vec::new();
        let mut cdf = Vec::new();
        let mut acc = 0.0;
        for (k, &d) in f.data.iter().enumerate() {
            if d as f64 > threshold {
                acc += d as f64;
                cells.push(k as u32);
                cdf.push(acc);
            }
        }
        Self { cells, cdf }
    }

    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// A point (u, v) in the curtain frame: a cell drawn from the CDF, then a
    /// uniform point inside it (no rejection).
    pub fn sample(&self, f: &Footprint, r: &mut impl Rng) -> (f64, f64) {
        let total = *self.cdf.last().unwrap_or(&0.0);
        let x = r.random::<f64>() * total;
        let i = self.cdf.partition_point(|&c| c <= x).min(self.cells.len() - 1);
        let k = self.cells[i] as usize;
        let (ci, cj) = (k % f.nx, k / f.nx);
        let (du, dv) = f.cell_size();
        let u = -0.5 * f.length + (ci as f64 + r.random::<f64>()) * du;
        let v = -0.5 * f.width + (cj as f64 + r.random::<f64>()) * dv;
        (u, v)
    }
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
    match ctx.model {
        DepositModel::Csda => trace_csda(ctx, start, r),
        DepositModel::Expected(g) => {
            let total = g.total();
            trace_fang(ctx, start, r, total, |m| g.fraction_above(m))
        }
        DepositModel::Sampled(d) => {
            let e = start.energy_kev;
            trace_fang(ctx, start, r, d.total(e), |m| d.fraction_above(e, m))
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

/// Pushes the photon and deposit record of one step.
#[inline]
fn emit(ctx: &BeamContext, start: &BeamStart, out: &mut BeamTrace, from: DVec3, to: DVec3, kev_s: f64) {
    let rgb = ctx.colour.rgb_with_colour_altitude(to.z, to.z + start.colour_offset_km);
    out.photons.push(deposit(from, to, [(rgb[0] * kev_s) as f32, (rgb[1] * kev_s) as f32, (rgb[2] * kev_s) as f32]));
    out.deposits.push(StepDeposit { z_start: from.z, z_end: to.z, power_kev_s: kev_s });
}

/// The Fang models: `frac(m)` is the fraction of the beam's power deposited
/// above column mass m, `total` its limit. Deposits `P (frac(m1) - frac(m0))`
/// per step with m the deepest column so far; stops when complete (the
/// remaining <= COMPLETE_TOL of the total goes into that last step) or below
/// the atmosphere's table.
fn trace_fang(ctx: &BeamContext, start: &BeamStart, r: &mut impl Rng, total: f64, frac: impl Fn(f64) -> f64) -> BeamTrace {
    let pw = start.power_kev_s;
    let mut p = start.position;
    let mut done = frac(ctx.atmosphere.column_mass(p.z));
    let mut out = BeamTrace {
        photons: Vec::new(),
        deposits: Vec::new(),
        backscatter_kev_s: pw * (1.0 - total),
        above_top_kev_s: 0.0,
        undeposited_kev_s: 0.0,
        end: EndReason::MaxSteps,
        end_position: p,
        path: Vec::new(),
    };
    if ctx.record_path {
        out.path.push(p);
    }
    // What the spectrum deposits above the start altitude (soft electrons,
    // high up): along the field line above the start, in spans of
    // ABOVE_START_SPAN_KM altitude, up to where at most ABOVE_START_TOL of
    // the total lies higher (or the atmosphere's top); that rest is reported.
    let z_up = above_start_top(ctx.atmosphere, &frac, total);
    out.above_top_kev_s = pw * frac(ctx.atmosphere.column_mass(z_up)).min(done);
    if z_up > p.z && done > 0.0 {
        let n = ((z_up - p.z) / ABOVE_START_SPAN_KM).ceil().max(1.0) as usize;
        let along = |z: f64| p + ctx.field.b * ((z - p.z) / ctx.field.b.z);
        let mut f_hi = out.above_top_kev_s / pw;
        for k in (0..n).rev() {
            let (z_lo, z_hi) = (p.z + (z_up - p.z) * k as f64 / n as f64, p.z + (z_up - p.z) * (k + 1) as f64 / n as f64);
            let f_lo = if k == 0 { done } else { frac(ctx.atmosphere.column_mass(z_lo)).min(done) };
            if f_lo > f_hi {
                emit(ctx, start, &mut out, along(z_hi), along(z_lo), pw * (f_lo - f_hi));
            }
            f_hi = f_hi.max(f_lo);
        }
    } else {
        out.above_top_kev_s = pw * done;
    }
    let bottom = ctx.atmosphere.bottom_km();
    let z0 = start.position.z;
    let (half_l, half_w) = (0.5 * ctx.footprint.length, 0.5 * ctx.footprint.width);
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
        let (u, v) = ctx.footprint.to_local(foot.x, foot.y);
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
            emit(ctx, start, &mut out, p, p_new, pw * (f_new - done));
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

/// A Fang beam deposits what its spectrum leaves above its start along the
/// field line above it, up to the altitude where at most this share of the
/// spectrum's total deposition lies higher ([`above_start_top`]).
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

/// Continuous slowing down along straight steps (the model before Fang):
/// the step's column mass shrinks the residual range; the energy lost is
/// the deposit. Stops after 1/dt steps, when the energy is spent, or when
/// the field-line foot leaves the footprint.
fn trace_csda(ctx: &BeamContext, start: &BeamStart, r: &mut impl Rng) -> BeamTrace {
    let max_steps = (1.0 / ctx.params.dt).round().max(1.0) as usize;
    let z0 = start.position.z;
    let f = ctx.field;
    let mut p = start.position;
    let mut e = start.energy_kev;
    let mut r_res = range_g_cm2(e);
    let power_per_kev = if start.energy_kev > 0.0 { start.power_kev_s / start.energy_kev } else { 0.0 };
    let mut col_p = ctx.atmosphere.column_mass(p.z);
    let mut out = BeamTrace {
        photons: Vec::new(),
        deposits: Vec::new(),
        backscatter_kev_s: 0.0,
        above_top_kev_s: 0.0,
        undeposited_kev_s: 0.0,
        end: EndReason::MaxSteps,
        end_position: p,
        path: Vec::new(),
    };
    if ctx.record_path {
        out.path.push(p);
    }
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
        // Column mass along the straight step (plane-parallel atmosphere):
        // (length / |dz|) |C(z1) - C(z0)|, or rho * length when level.
        let col_new = ctx.atmosphere.column_mass(p_new.z);
        let dz = (p_new.z - p.z).abs();
        let column = if dz > 1e-6 * len && dz > 1e-9 {
            (len / dz) * (col_new - col_p).abs()
        } else {
            ctx.atmosphere.slant_column(p.z, p_new.z, len)
        };
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
            emit(ctx, start, &mut out, from, p, de * power_per_kev);
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
    /// Electron power into the atmosphere over all curtains, W.
    pub electron_power_w: f64,
    /// Of which deposited along the beams, W (the rest: see [`CurtainPower`]).
    pub deposited_power_w: f64,
    pub backscattered_power_w: f64,
    pub above_top_power_w: f64,
    pub undeposited_power_w: f64,
    /// The same per curtain, in scene order.
    pub curtains: Vec<CurtainPower>,
}

/// What tracing needs of the scene, as plain data (no `Scene`): the
/// curtains, the beam parameters, the seed, the footprint threshold, the
/// animation time (pulsation, ray drift), the colour noise and the kernel
/// shape. [`TraceParams::of`] reads them from a scene; `crate::pipeline`
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
}

impl<'a> TraceParams<'a> {
    pub fn of(scene: &'a Scene) -> Self {
        TraceParams {
            seed: scene.seed,
            curtains: &scene.curtains,
            beams: &scene.beams,
            threshold: scene.footprint.threshold,
            animation: &scene.animation,
            colour_noise_km: scene.colour.noise_km,
            colour_noise_freq: scene.colour.noise_freq,
            kernel: scene.photons.kernel,
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
/// samples of the same scene (the pilot of `crate::pilot` uses two).
pub fn trace_all_from(
    scene: &Scene,
    footprints: &[Footprint],
    atmosphere: &Atmosphere,
    colour: &ColourTable,
    first_beam: u64,
    progress: &dyn Progress,
) -> Result<(Vec<Photon>, BeamStats), BeamError> {
    let n = scene.beams.count;
    let t = trace_range(&TraceParams::of(scene), footprints, atmosphere, colour, n, first_beam, 0..n, false, progress)?;
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
    let t = trace_range(&TraceParams::of(scene), footprints, atmosphere, colour, n, 0, 0..n, true, progress)?;
    Ok((t.deposits, t.stats))
}

/// What [`trace_range`] returns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Traced {
    pub photons: Vec<Photon>,
    pub stats: BeamStats,
    /// Per curtain (empty vectors unless recorded).
    pub deposits: Vec<Vec<StepDeposit>>,
}

/// One beam's result, kept until the curtain's beams are concatenated.
struct BeamOut {
    photons: Vec<Photon>,
    deposits: Vec<StepDeposit>,
    end: EndReason,
    /// keV/s: deposited, backscattered, above the top, undeposited.
    power: [f64; 4],
}

/// Traces beams `range` of a bake of `count` beams. The bake's beams are
/// numbered curtain by curtain (curtain 0's share of `count` by
/// [`apportion`], then curtain 1's, ...); local beam `i` of curtain `c`
/// draws the random stream `stream_offset + i` (and, stratified, the R2
/// point of that index) and carries `1 / n_c` of its curtain's power. So a
/// beam is the same whatever range it is traced in: tracing `[0, K)` and
/// `[K, N)` and concatenating gives the photons of `[0, N)` byte for byte.
/// A range's `electron_power_w` is its beams' share of the curtains' power
/// (all of it for `0..count`).
#[allow(clippy::too_many_arguments)]
pub fn trace_range(
    params: &TraceParams,
    footprints: &[Footprint],
    atmosphere: &Atmosphere,
    colour: &ColourTable,
    count: usize,
    stream_offset: u64,
    range: std::ops::Range<usize>,
    record_deposits: bool,
    progress: &dyn Progress,
) -> Result<Traced, BeamError> {
    let first_beam = stream_offset;
    let weights: Vec<f64> = params.curtains.iter().map(|c| c.beam_weight).collect();
    let counts = apportion(count, &weights);
    let field = Field::new(params.beams.b_inclination_deg, params.beams.b_declination_deg);
    let threshold = params.threshold;
    let mut stats = BeamStats::default();
    let mut photons = Vec::new();
    let mut all_deposits = vec![Vec::new(); params.curtains.len()];
    stats.curtains = vec![CurtainPower::default(); params.curtains.len()];
    let range = range.start.min(count)..range.end.min(count);
    progress.start("beams", range.len() as u64);
    let mut curtain_first = 0usize;
    for (ci, (curtain, fp)) in params.curtains.iter().zip(footprints).enumerate() {
        let n = counts[ci];
        // This curtain's beams are [curtain_first, curtain_first + n) of the
        // bake; those in `range`, as local indices:
        let lo = range.start.saturating_sub(curtain_first).min(n);
        let hi = range.end.saturating_sub(curtain_first).min(n);
        curtain_first += n;
        let local = lo..hi.max(lo);
        if local.is_empty() {
            continue;
        }
        // Beam i maps the same point of the unit square through every
        // frame's footprint (crate::animation: identity across frames).
        let starts = crate::footprint::StartMap::new(fp, threshold);
        let anim = params.animation;
        let ray_shift = crate::animation::ray_shift_km(anim);
        let shift0 = crate::starts::shift(&[params.seed, curtain.seed, rng::tag::BEAM_STARTS]);
        // Each block of 2^40 beam indices (the pilot's independent halves
        // live in blocks 1-3) has its own Cranley-Patterson shift, so the
        // blocks are independent randomisations of the sequence; block 0
        // (every bake) keeps the plain shift.
        let shift = |index: u64| match index >> 40 {
            0 => shift0,
            k => crate::starts::shift(&[params.seed, curtain.seed, rng::tag::BEAM_STARTS, k]),
        };
        if starts.is_empty() {
            let peak = fp.data.iter().cloned().fold(0.0f32, f32::max);
            return Err(BeamError::EmptyFootprint { curtain: ci, threshold, peak });
        };
        // P_c = F [mW/m^2] * 1e-3 [W/mW] * A [km^2] * 1e6 [m^2/km^2].
        let power_w = curtain.energy_flux * 1e-3 * fp.integral_above(threshold) * 1e6;
        let power_kev_s = power_w * KEV_PER_J / n as f64;
        let top_noise: Perlin = rng::perlin(&[params.seed, curtain.seed, rng::tag::BEAM_TOP_NOISE]);
        let colour_noise: Perlin = rng::perlin(&[params.seed, curtain.seed, rng::tag::COLOUR_NOISE]);
        let spectrum;
        let model = match params.beams.deposition {
            Deposition::Expected => {
                spectrum = SpectrumDeposition::curtain(curtain.char_energy_kev, curtain.soft_fraction, curtain.soft_energy_kev);
                DepositModel::Expected(&spectrum)
            }
            Deposition::Sampled => DepositModel::Sampled(MonoDeposition::get()),
            Deposition::Csda => DepositModel::Csda,
        };
        let ctx = BeamContext {
            atmosphere,
            model,
            colour,
            field,
            params: params.beams,
            footprint: fp,
            threshold,
            record_path: false,
        };
        let traces: Vec<BeamOut> = local.clone()
            .into_par_iter()
            .map(|i| {
                let mut r = rng::rng(&[params.seed, curtain.seed, rng::tag::BEAM, first_beam + i as u64]);
                // The unit-square point of beam i: the shifted R2 sequence
                // (stratified, fixed by the index whatever the count) or two
                // random numbers; either is mapped through the footprint's
                // continuous start map, so the beam moves with its curtain
                // from frame to frame. Both numbers are drawn in either mode,
                // so the rest of the beam's stream (energy, path) is the same.
                let (xi1, xi2) = (r.random::<f64>(), r.random::<f64>());
                let (xi1, xi2) = match params.beams.starts {
                    BeamStarts::Random => (xi1, xi2),
                    BeamStarts::Stratified => {
                        let [a, b] = crate::starts::r2(first_beam + i as u64, shift(first_beam + i as u64));
                        (a, b)
                    }
                };
                let (u, v) = starts.map(xi1, xi2);
                let (x, y) = fp.to_world(u, v);
                // High-frequency noise on the start height along the curtain
                // (the rays), running along it in time.
                let ur = u - ray_shift;
                let z = params.beams.top_km
                    + params.beams.top_noise_km * rng::noise1(&top_noise, ur * params.beams.top_noise_freq);
                let colour_offset_km = params.colour_noise_km * rng::noise1(&colour_noise, ur * params.colour_noise_freq);
                let power_kev_s = power_kev_s * crate::animation::pulsation(anim, params.seed, x, y);
                // Drawn in every model, so a beam's path is the same in all.
                let e0 = if r.random::<f64>() < curtain.soft_fraction { curtain.soft_energy_kev } else { curtain.char_energy_kev };
                let start = BeamStart {
                    position: DVec3::new(x, y, z),
                    energy_kev: sample_gamma3(e0, &mut r),
                    power_kev_s,
                    colour_offset_km,
                };
                let t = trace_beam(&ctx, &start, &mut r);
                progress.inc(1);
                let deposited: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
                let mut photons = t.photons;
                if params.kernel == KernelShape::Point {
                    // The point estimator: each step's power at its end.
                    photons.iter_mut().for_each(|p| *p = p.to_point());
                }
                BeamOut {
                    power: [deposited, t.backscatter_kev_s, t.above_top_kev_s, t.undeposited_kev_s],
                    photons,
                    deposits: if record_deposits { t.deposits } else { Vec::new() },
                    end: t.end,
                }
            })
            .collect();
        let cp = &mut stats.curtains[ci];
        // The range's share of the curtain's power (all of it for a whole bake).
        cp.electron_power_w = if local.len() == n { power_w } else { power_w * local.len() as f64 / n as f64 };
        for b in traces {
            match b.end {
                EndReason::LeftFootprint => stats.ended_left_footprint += 1,
                EndReason::EnergySpent => stats.ended_energy_spent += 1,
                EndReason::MaxSteps => stats.ended_max_steps += 1,
                EndReason::Bottom => stats.ended_bottom += 1,
            }
            cp.deposited_power_w += b.power[0] / KEV_PER_J;
            cp.backscattered_power_w += b.power[1] / KEV_PER_J;
            cp.above_top_power_w += b.power[2] / KEV_PER_J;
            cp.undeposited_power_w += b.power[3] / KEV_PER_J;
            photons.extend_from_slice(&b.photons);
            all_deposits[ci].extend_from_slice(&b.deposits);
        }
        stats.beams += local.len();
    }
    for cp in &stats.curtains {
        stats.electron_power_w += cp.electron_power_w;
        stats.deposited_power_w += cp.deposited_power_w;
        stats.backscattered_power_w += cp.backscattered_power_w;
        stats.above_top_power_w += cp.above_top_power_w;
        stats.undeposited_power_w += cp.undeposited_power_w;
    }
    stats.photons = photons.len();
    progress.finish();
    Ok(Traced { photons, stats, deposits: all_deposits })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Curtain, FootprintParams};
    use crate::spectrum::EmissionModel;

    /// A footprint that is 1 everywhere in a huge box: beams never leave it.
    fn flat_footprint(size: f64) -> Footprint {
        Footprint { nx: 4, ny: 4, data: vec![1.0; 16], center: [0.0, 0.0], rotation_rad: 0.0, length: size, width: size }
    }

    fn params() -> BeamParams {
        BeamParams { length_km: 400.0, dt: 0.0025, ..BeamParams::default() }
    }

    fn start(e: f64) -> BeamStart {
        BeamStart { position: DVec3::new(0.0, 0.0, 260.0), energy_kev: e, power_kev_s: 1.0, colour_offset_km: 0.0 }
    }

    #[test]
    fn field_frame_is_orthonormal_and_points_down() {
        for (inc, dec) in [(78.0, 0.0), (90.0, 0.0), (45.0, 30.0), (10.0, -120.0)] {
            let f = Field::new(inc, dec);
            assert!((f.b.length() - 1.0).abs() < 1e-12 && (f.u.length() - 1.0).abs() < 1e-12);
            assert!(f.b.dot(f.u).abs() < 1e-12 && f.b.dot(f.v).abs() < 1e-12 && f.u.dot(f.v).abs() < 1e-12);
            assert!(f.b.z < 0.0);
            // Dip angle below the horizon.
            assert!(((-f.b.z).asin().to_degrees() - inc).abs() < 1e-9);
        }
        // Declination 0: the horizontal part points north (+y).
        let f = Field::new(78.0, 0.0);
        assert!(f.b.y > 0.0 && f.b.x.abs() < 1e-12);
        let p = DVec3::new(1.0, 2.0, 150.0);
        let foot = f.foot(p, 260.0);
        assert!((foot.z - 260.0).abs() < 1e-9 && (foot - p).normalize().dot(-f.b) > 1.0 - 1e-12);
    }

    #[test]
    fn range_energy_inverse_round_trips() {
        for e in [0.05, 0.3, 1.0, 3.7, 10.0, 55.0] {
            let back = energy_from_range(range_g_cm2(e));
            assert!((back / e - 1.0).abs() < 1e-12, "{e} -> {back}");
        }
        assert_eq!(energy_from_range(4.0e-7), 0.0);
    }

    #[test]
    fn deflection_angle_to_b_lies_in_the_sampled_range() {
        let atm = Atmosphere::us1976();
        let colour = ColourTable::physical(&EmissionModel::default());
        let fp = flat_footprint(1e5);
        let p = BeamParams { alpha_d_deg: 25.0, delta_alpha_deg: 12.0, b_inclination_deg: 70.0, b_declination_deg: 20.0, ..params() };
        let ctx = BeamContext { atmosphere: &atm, model: DepositModel::Csda, colour: &colour, field: Field::new(70.0, 20.0), params: &p, footprint: &fp, threshold: 0.03, record_path: true };
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
        let ctx = BeamContext { atmosphere: &atm, model: DepositModel::Csda, colour: &colour, field: Field::new(78.0, 0.0), params: &p, footprint: &fp, threshold: 0.03, record_path: false };
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
        let ctx = BeamContext { atmosphere: &atm, model: DepositModel::Csda, colour: &colour, field: Field::new(78.0, 0.0), params: &p, footprint: &fp, threshold: 0.03, record_path: false };
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

    #[test]
    fn start_points_land_only_above_threshold() {
        let c = Curtain::default();
        let fpp = FootprintParams { resolution: [128, 48], steps: 6, pressure_iterations: 30, ..FootprintParams::default() };
        let fp = crate::footprint::simulate(&c, &fpp, 9);
        let thr = 0.2;
        let cdf = FootprintCdf::new(&fp, thr);
        let mut r = rng::rng(&[4]);
        let mut hits = vec![0usize; fp.data.len()];
        for _ in 0..20_000 {
            let (u, v) = cdf.sample(&fp, &mut r);
            let (x, y) = fp.to_world(u, v);
            assert!(fp.cell_value_world(x, y) > thr);
            let (du, dv) = fp.cell_size();
            let k = ((v + 0.5 * fp.width) / dv) as usize * fp.nx + ((u + 0.5 * fp.length) / du) as usize;
            hits[k] += 1;
        }
        // Cells are drawn in proportion to density: compare the hit share of
        // the densest half of the eligible mass with its expected share, to
        // 5 sigma of a binomial with N = 20000.
        let mut eligible: Vec<(f64, usize)> = fp.data.iter().enumerate().filter(|(_, &d)| d as f64 > thr).map(|(k, &d)| (d as f64, k)).collect();
        eligible.sort_by(|a, b| b.0.total_cmp(&a.0));
        let total: f64 = eligible.iter().map(|e| e.0).sum();
        let top: Vec<_> = eligible.iter().take(eligible.len() / 4).collect();
        let p: f64 = top.iter().map(|e| e.0).sum::<f64>() / total;
        let got = top.iter().map(|e| hits[e.1]).sum::<usize>() as f64 / 20_000.0;
        let sigma = (p * (1.0 - p) / 20_000.0).sqrt();
        assert!((got - p).abs() < 5.0 * sigma, "{got} vs {p} +- {sigma}");
    }

    fn fang_ctx<'a>(atm: &'a Atmosphere, colour: &'a ColourTable, fp: &'a Footprint, p: &'a BeamParams, model: DepositModel<'a>) -> BeamContext<'a> {
        BeamContext { atmosphere: atm, model, colour, field: Field::new(p.b_inclination_deg, p.b_declination_deg), params: p, footprint: fp, threshold: 0.03, record_path: false }
    }

    #[test]
    fn expected_beam_deposits_the_spectrum_total_below_its_start_and_accounts_for_the_rest() {
        let atm = Atmosphere::nrlmsis21();
        let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
        let fp = flat_footprint(1e5);
        let p = params();
        for (e0, soft) in [(1.0, 0.0), (3.0, 0.1), (30.0, 0.0)] {
            let g = SpectrumDeposition::curtain(e0, soft, 0.2);
            let ctx = fang_ctx(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
            let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(e0) }, &mut rng::rng(&[7]));
            assert_eq!(t.end, EndReason::EnergySpent, "{e0} keV");
            let dep: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
            // Above the start it deposits up to z_up, where at most
            // ABOVE_START_TOL of the total lies higher: that rest is
            // reported. A finished beam deposits exactly G(inf) - G(m(z_up)):
            // sums of telescoping differences, rounding only.
            let z_up = above_start_top(&atm, &|m| g.fraction_above(m), g.total());
            let above = g.fraction_above(atm.column_mass(z_up.max(260.0)));
            assert!(z_up <= atm.top_km() && above <= ABOVE_START_TOL * g.total(), "{e0}: {z_up} km, {above}");
            assert!((dep - (g.total() - above)).abs() < 1e-12, "{e0}: {dep} vs {}", g.total() - above);
            assert!((t.above_top_kev_s - above).abs() < 1e-15 && t.undeposited_kev_s == 0.0);
            // What lies above the start is on the field line above it.
            let up: f64 = t.deposits.iter().filter(|d| d.z_end >= 260.0 - 1e-9).map(|d| d.power_kev_s).sum();
            let want = g.fraction_above(atm.column_mass(260.0)) - above;
            assert!((up - want).abs() < 1e-12, "{e0}: above the start {up} vs {want}");
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
        let fp = Footprint { nx: 1, ny: 9, data, center: [0.0, 0.0], rotation_rad: 0.0, length: 1e4, width: 18.0 };
        let p = BeamParams { alpha_d_deg: 20.0, delta_alpha_deg: 10.0, ..params() };
        let g = SpectrumDeposition::curtain(30.0, 0.0, 0.2);
        let ctx = fang_ctx(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
        let mut r = rng::rng(&[6]);
        let mut outside = 0;
        for _ in 0..20 {
            let t = trace_beam(&ctx, &start(30.0), &mut r);
            assert_eq!(t.end, EndReason::EnergySpent);
            assert_eq!(t.undeposited_kev_s, 0.0);
            outside += t.photons.iter().filter(|ph| {
                let q = DVec3::new(ph.position[0] as f64, ph.position[1] as f64, ph.position[2] as f64);
                let foot = ctx.field.foot(q, 260.0);
                fp.cell_value_world(foot.x, foot.y) <= 0.03
            }).count();
        }
        assert!(outside > 100, "only {outside} photons beyond the strip: the test does not test");
    }

    #[test]
    fn runaway_fang_steps_end_at_the_bottom_or_the_enlarged_box() {
        let atm = Atmosphere::nrlmsis21();
        let colour = ColourTable::physical(&EmissionModel::new(atm.clone()));
        let fp = Footprint { nx: 1, ny: 1, data: vec![1.0], center: [0.0, 0.0], rotation_rad: 0.0, length: 10.0, width: 4.0 };
        let g = SpectrumDeposition::curtain(3.0, 0.0, 0.2);
        // Straight down in steps of up to 2.5e6 km: the first step is cut at
        // the atmosphere's bottom (where a 3 keV spectrum is complete).
        let p = BeamParams { length_km: 1e9, alpha_d_deg: 0.0, delta_alpha_deg: 0.0, b_inclination_deg: 90.0, ..params() };
        let ctx = fang_ctx(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
        let t = trace_beam(&ctx, &BeamStart { power_kev_s: 1.0, ..start(3.0) }, &mut rng::rng(&[9]));
        assert!(matches!(t.end, EndReason::Bottom | EndReason::EnergySpent), "{:?}", t.end);
        assert!(t.photons.iter().all(|ph| ph.position[2] >= 50.0 - 1e-4), "{:?}", t.photons);
        let dep: f64 = t.deposits.iter().map(|d| d.power_kev_s).sum();
        assert!((dep + t.backscatter_kev_s + t.above_top_kev_s + t.undeposited_kev_s - 1.0).abs() < 1e-12);
        // Near-horizontal steps of 1e11 km: stopped at the box enlarged by
        // its size (|u| <= 10, |v| <= 4 at the start altitude), never placing
        // a photon whose foot is further out.
        let p = BeamParams { length_km: 1e9, alpha_d_deg: 89.999, delta_alpha_deg: 0.0, b_inclination_deg: 10.0, ..params() };
        let ctx = fang_ctx(&atm, &colour, &fp, &p, DepositModel::Expected(&g));
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

    /// A small scene: one short curtain, few beams.
    fn small_scene(count: usize) -> Scene {
        let mut s = crate::scene::presets::small_test_scene();
        s.beams.count = count;
        s
    }

    #[test]
    fn stratified_beam_i_is_the_same_whatever_the_count_and_threads() {
        // Beam i's start, energy and path depend on (seed, curtain, i) only:
        // its photons are the same in a bake of N and of 2N beams (their
        // power scales by N / 2N: each beam carries P / N), and the whole
        // photon list is the same for 1 and 3 threads.
        let s1 = small_scene(300);
        let s2 = small_scene(600);
        let fps = crate::bake::footprints(&s1);
        let atm = Atmosphere::us1976();
        let colour = crate::bake::colour_table(&s1, &atm);
        let run = |s: &Scene, threads: usize| {
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
                trace_all(s, &fps, &atm, &colour, &crate::progress::NoProgress).unwrap().0
            })
        };
        let (a, b) = (run(&s1, 1), run(&s2, 3));
        assert_eq!(a, run(&s1, 3));
        // The first 300 beams of the 600 come first in the list.
        assert!(b.len() > a.len());
        for (p, q) in a.iter().zip(&b) {
            assert_eq!((p.position, p.end), (q.position, q.end));
            for k in 0..3 {
                // P/N halves exactly in binary, up to the f32 rounding of
                // the product.
                assert!((p.power[k] - 2.0 * q.power[k]).abs() <= 2e-7 * p.power[k].abs(), "{p:?} {q:?}");
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
        let (ce, cs) = (fang_ctx(&atm, &colour, &fp, &p, DepositModel::Expected(&g)), fang_ctx(&atm, &colour, &fp, &p, DepositModel::Sampled(MonoDeposition::get())));
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
    fn steps_are_segments_and_the_point_kernel_collapses_them() {
        let mut s = small_scene(50);
        let fps = crate::bake::footprints(&s);
        let atm = Atmosphere::us1976();
        let colour = crate::bake::colour_table(&s, &atm);
        let (seg, _) = trace_all(&s, &fps, &atm, &colour, &crate::progress::NoProgress).unwrap();
        assert!(seg.iter().filter(|p| !p.is_point()).count() > seg.len() / 2);
        // Consecutive steps of a beam chain: one ends where the next starts
        // (except across beams, and after a step that deposited nothing).
        let chained = seg.windows(2).filter(|w| w[0].end == w[1].position).count();
        assert!(chained as f64 > 0.9 * seg.len() as f64, "{chained} of {}", seg.len());
        s.photons.kernel = KernelShape::Point;
        let (pts, _) = trace_all(&s, &fps, &atm, &colour, &crate::progress::NoProgress).unwrap();
        assert_eq!(pts.len(), seg.len());
        for (p, q) in pts.iter().zip(&seg) {
            assert!(p.is_point() && p.position == q.end && p.power == q.power);
        }
    }

    #[test]
    fn gamma3_has_the_right_mean_and_variance() {
        // Gamma(3, E0): mean 3 E0, variance 3 E0^2. Sample mean of N = 1e5 has
        // sigma = sqrt(3) E0 / sqrt(N); allow 5 sigma.
        let mut r = rng::rng(&[5]);
        let n = 100_000;
        let xs: Vec<f64> = (0..n).map(|_| sample_gamma3(2.0, &mut r)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        assert!((mean - 6.0).abs() < 5.0 * 3f64.sqrt() * 2.0 / (n as f64).sqrt(), "{mean}");
        // Sample variance: relative sigma sqrt((kurtosis - 1) / N) with
        // kurtosis 3 + 6/3 = 5 for Gamma(3): 0.0063; 5 sigma = 3.2 %.
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((var / 12.0 - 1.0).abs() < 0.032, "{var}");
    }

    #[test]
    fn apportion_is_exact_and_proportional() {
        assert_eq!(apportion(10, &[1.0, 1.0, 1.0]), vec![4, 3, 3]);
        assert_eq!(apportion(7, &[0.0, 2.0, 1.0]).iter().sum::<usize>(), 7);
        assert_eq!(apportion(7, &[0.0, 2.0, 1.0])[0], 0);
        assert_eq!(apportion(100, &[3.0, 1.0]), vec![75, 25]);
    }

    #[test]
    fn beams_leave_when_their_foot_leaves_the_footprint() {
        let atm = Atmosphere::us1976();
        let colour = ColourTable::physical(&EmissionModel::default());
        // A 2 km wide strip: a random walk of 10-20 degree steps leaves it.
        let fp = Footprint { nx: 1, ny: 1, data: vec![1.0], center: [0.0, 0.0], rotation_rad: 0.0, length: 1e4, width: 2.0 };
        let p = BeamParams { alpha_d_deg: 20.0, delta_alpha_deg: 10.0, ..params() };
        let ctx = BeamContext { atmosphere: &atm, model: DepositModel::Csda, colour: &colour, field: Field::new(78.0, 0.0), params: &p, footprint: &fp, threshold: 0.03, record_path: false };
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
