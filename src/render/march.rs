//! Integration along a ray through the [`Medium`]: the one walker used by
//! primary rays (emission and transmittance) and shadow rays (transmittance).
//!
//! Primary rays: `L = int_0^d T(0,s) e(s) ds` and `T(0,d) = exp(-int_0^d sigma_t)`
//! (the emission-absorption model; no scattering).
//!
//! Two integrators:
//! * [`Integration::Exact`]: a primary ray through a medium without
//!   extinction takes the emission-only path (`emission_only.rs`, the
//!   plain line integral, exact per cell; [`primary_path`]); otherwise it
//!   walks the dual cells ([`segments`]) and
//!   integrates each piece with [`Accum`]: optical depth exactly,
//!   emission with Gauss-Legendre of bounded error. When density and emission
//!   live on different transforms, the two cell sequences are merged so that
//!   each piece lies inside one dual cell of each grid.
//! * [`Integration::FixedStep`]`(h)`: the classic ray marcher Cycles uses in
//!   its biased mode (`volume_integrate_heterogeneous`): steps of length `h`
//!   from the ray's entry into the volume's bounds, one sample per step at
//!   the same fraction `offset` of every step, and per step
//!   `T_step = exp(-sigma_t dt)`, `L += T e (1 - T_step) / sigma_t` (Cycles'
//!   `volume_emission_integrate`). Its error grows with `h` where sigma_t
//!   varies within a step. Steps whose sample falls outside every occupied
//!   dual leaf are skipped: the field is 0 there, so this changes nothing.

use super::dda::{segments, CellFilter, CellSeg, CellWalker, IndexRay, LeafWalker};
use super::emission_only::emission_integral;
use super::medium::velocity::Velocity;
use super::medium::{field::Field, Channel, Medium};
use super::segment::{Accum, Along, Piece, TAU_CUTOFF};
use super::settings::Integration;
use crate::util::fmath;
use glam::DVec3;

/// The result of integrating along one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayIntegral {
    /// Emitted radiance reaching the ray origin, `int T e ds`, linear Rec.709.
    pub l: [f64; 3],
    /// Optical depth `int sigma_t ds` (stops growing past [`TAU_CUTOFF`]).
    pub tau: f64,
    /// Pieces (exact) or steps (fixed step) evaluated: a work measure.
    pub work: u64,
}

impl RayIntegral {
    /// Transmittance `T = exp(-tau)`.
    pub fn transmittance(&self) -> f64 {
        fmath::exp(-self.tau)
    }
}

/// Radiance emitted along `origin + s dir`, `s` in `[0, t_max]`, and the
/// transmittance over that range. `dir` must have unit length (so `s` is a
/// world length); `t_max` may be infinite. `offset` in [0,1) is the sample
/// position inside each fixed step (ignored by the exact integrator).
pub fn radiance_along_ray(medium: &Medium, origin: DVec3, dir: DVec3, t_max: f64, integration: Integration, offset: f64) -> RayIntegral {
    integrate(medium, RaySpan { origin, dir, t_max }, integration, offset, true)
}

/// The part `s` in `[0, t_max]` of the ray `origin + s dir` (`dir` of unit
/// length, `t_max` possibly infinite) that a march integrates over.
#[derive(Clone, Copy, Debug)]
pub struct RaySpan {
    pub origin: DVec3,
    pub dir: DVec3,
    pub t_max: f64,
}

/// Which walk a primary ray takes with [`Integration::Exact`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimaryPath {
    /// No extinction anywhere (no density grid, an empty one, or
    /// `volume.density_scale = 0`): the emission's plain line integral
    /// (`emission_only.rs`), with the transmittance 1.
    EmissionOnly,
    /// The emission-absorption walk (optical depth and `int T e`).
    General,
}

/// The walk [`radiance_along_ray`] takes through `medium` with
/// [`Integration::Exact`]: the emission-only one exactly when the medium
/// has no extinction (the terrain does not matter: a primary ray stops at
/// it, and the terrain's light is estimated by shadow rays apart).
pub fn primary_path(medium: &Medium) -> PrimaryPath {
    if medium.sigma_t.is_none() {
        PrimaryPath::EmissionOnly
    } else {
        PrimaryPath::General
    }
}

/// [`radiance_along_ray`] with [`Integration::Exact`] through the general
/// walk whatever the medium holds: the reference the emission-only path is
/// checked against.
pub fn radiance_general(medium: &Medium, origin: DVec3, dir: DVec3, t_max: f64) -> RayIntegral {
    walk(medium, RaySpan { origin, dir, t_max }, Integration::Exact, 0.0, true)
}

/// Optical depth along `origin + s dir`, `s` in `[0, t_max]` (shadow rays).
pub fn optical_depth_along_ray(
    medium: &Medium,
    origin: DVec3,
    dir: DVec3,
    t_max: f64,
    integration: Integration,
    offset: f64,
) -> RayIntegral {
    integrate(medium, RaySpan { origin, dir, t_max }, integration, offset, false)
}

fn integrate(medium: &Medium, seg: RaySpan, integration: Integration, offset: f64, with_emission: bool) -> RayIntegral {
    let RaySpan { origin, dir, t_max } = seg;
    debug_assert!((dir.length() - 1.0).abs() < 1e-9, "direction must be unit length");
    if with_emission && integration == Integration::Exact && primary_path(medium) == PrimaryPath::EmissionOnly {
        let Some(c) = medium.emission else { return RayIntegral::default() };
        let (l, work) = emission_integral(&medium.fields[c.field], c.channel, origin, dir, t_max);
        return RayIntegral { l, tau: 0.0, work };
    }
    walk(medium, seg, integration, offset, with_emission)
}

/// The emission-absorption walk of `integration` (optical depth and, with
/// `with_emission`, `int T e`), whatever the medium holds.
fn walk(medium: &Medium, seg: RaySpan, integration: Integration, offset: f64, with_emission: bool) -> RayIntegral {
    let mut acc = Accum::default();
    let mut work = 0;
    if seg.t_max > 0.0 {
        match integration {
            Integration::Exact => work = walk_exact(medium, seg, with_emission, &mut acc),
            Integration::FixedStep(h) => work = walk_fixed(medium, seg, h, offset, with_emission, &mut acc),
        }
    }
    RayIntegral { l: acc.l, tau: acc.tau, work: work.max(acc.parts) }
}

#[inline]
fn corners(field: &Field, at: &[usize; 8], channel: usize) -> [f64; 8] {
    let scale = field.scale[channel];
    std::array::from_fn(|k| field.values.get(at[k] + channel) as f64 * scale)
}

#[inline]
fn local(ray: &IndexRay, t: f64, seg: &CellSeg) -> [f64; 3] {
    (ray.at(t) - seg.corner.as_dvec3()).to_array()
}

/// Adds the cubics of the channels `sigma` / `e` held by `field` over `[t0, t1]`
/// of cell `seg` to `piece`.
#[inline]
fn fill_piece(piece: &mut Piece, field: &Field, ray: &IndexRay, seg: &CellSeg, sigma: Option<usize>, e: Option<usize>) {
    let line = Along::new(local(ray, piece.t0, seg), local(ray, piece.t1, seg));
    if field.channels == 4 && sigma == Some(0) && e == Some(1) {
        // sigma_t and emission in one field (the usual case): each corner's
        // four channels in one load, the four cubics lane by lane (the same
        // operations per channel as `Along::cubic`, so the same values).
        // The field holds unit values; the volume scales apply here, to
        // each corner as in `corners`.
        let k = field.scale;
        let mut v = [[0.0f64; 4]; 8];
        for (vk, &i) in v.iter_mut().zip(&seg.at) {
            let c = |j: usize| field.values.get(i + j) as f64;
            *vk = [c(0) * k[0], c(1) * k[1], c(2) * k[2], c(3) * k[3]];
        }
        let [s, r, g, b] = line.cubic4(v);
        piece.sigma_t = s;
        piece.e = [r, g, b];
        return;
    }
    if let Some(ch) = sigma {
        piece.sigma_t = line.cubic(corners(field, &seg.at, ch));
    }
    if let Some(ch) = e {
        for k in 0..3 {
            piece.e[k] = line.cubic(corners(field, &seg.at, ch + k));
        }
    }
}

fn channel_in(c: Option<Channel>, field: usize) -> Option<usize> {
    c.filter(|c| c.field == field).map(|c| c.channel)
}

fn walk_exact(medium: &Medium, seg: RaySpan, with_emission: bool, acc: &mut Accum) -> u64 {
    let RaySpan { origin, dir, t_max } = seg;
    let sigma = medium.sigma_t;
    let emission = if with_emission { medium.emission } else { None };
    let mut n = 0u64;
    match (sigma, emission) {
        (None, None) => {}
        (Some(a), Some(b)) if a.field != b.field => {
            // Density and emission on different transforms: merge the two
            // ordered cell sequences into pieces lying in one cell of each.
            let (fa, fb) = (&medium.fields[a.field], &medium.fields[b.field]);
            let (ra, rb) = (IndexRay::new(fa, origin, dir), IndexRay::new(fb, origin, dir));
            let mut ia = segments(fa, origin, dir, 0.0, t_max, CellFilter::First);
            let mut ib = segments(fb, origin, dir, 0.0, t_max, CellFilter::Any);
            let (mut sa, mut sb) = (ia.next(), ib.next());
            loop {
                let (lo, hi, use_a, use_b) = match (&sa, &sb) {
                    (None, None) => break,
                    (Some(x), None) => (x.t0, x.t1, true, false),
                    (None, Some(y)) => (y.t0, y.t1, false, true),
                    (Some(x), Some(y)) => {
                        if x.t0 < y.t0 {
                            (x.t0, x.t1.min(y.t0), true, false)
                        } else if y.t0 < x.t0 {
                            (y.t0, y.t1.min(x.t0), false, true)
                        } else {
                            (x.t0, x.t1.min(y.t1), true, true)
                        }
                    }
                };
                let mut piece = Piece { t0: lo, t1: hi, ..Piece::default() };
                if use_a {
                    let x = sa.as_mut().expect("use_a implies a segment");
                    fill_piece(&mut piece, fa, &ra, x, Some(a.channel), None);
                    x.t0 = hi;
                    if x.t1 <= hi {
                        sa = ia.next();
                    }
                }
                if use_b {
                    let y = sb.as_mut().expect("use_b implies a segment");
                    fill_piece(&mut piece, fb, &rb, y, None, Some(b.channel));
                    y.t0 = hi;
                    if y.t1 <= hi {
                        sb = ib.next();
                    }
                }
                acc.add(&piece, true);
                n += 1;
                if acc.tau > TAU_CUTOFF {
                    break;
                }
            }
        }
        (s, e) => {
            // One field holds every channel this ray needs.
            let fi = s.or(e).map(|c| c.field).expect("some channel");
            let field = &medium.fields[fi];
            let (cs, ce) = (channel_in(s, fi), channel_in(e, fi));
            // Shadow rays need cells where sigma_t (channel 0) is non-zero.
            let filter = if ce.is_none() && cs == Some(0) { CellFilter::First } else { CellFilter::Any };
            // The leaves, then each leaf's cells: `segments` written out as
            // two loops (the flattened iterator cost a tenth of the trace).
            let leaves = LeafWalker::new(field, origin, dir, 0.0, t_max);
            let ray = leaves.ray;
            'leaves: for span in leaves {
                for seg in CellWalker::new(field, ray, span, filter) {
                    let mut piece = Piece { t0: seg.t0, t1: seg.t1, ..Piece::default() };
                    fill_piece(&mut piece, field, &ray, &seg, cs, ce);
                    acc.add(&piece, ce.is_some());
                    n += 1;
                    if acc.tau > TAU_CUTOFF {
                        break 'leaves;
                    }
                }
            }
        }
    }
    n
}

/// [`radiance_along_ray`] at shutter time `tau` s with the lookups
/// advected along `velocity` as Cycles does: fixed steps of `h` (one sample
/// each, at the fraction `offset` of the step, as [`Integration::FixedStep`])
/// from the ray's entry into the volume's bounds grown by the farthest a
/// lookup can move (`max_speed |tau|`); the sample at `p` reads sigma_t and
/// the emission at `p - v(p) tau`. At tau = 0 the fixed-step march.
pub fn radiance_advected(medium: &Medium, velocity: &Velocity, seg: RaySpan, h: f64, offset: f64, tau: f64) -> RayIntegral {
    let RaySpan { origin, dir, t_max } = seg;
    let mut acc = Accum::default();
    let Some((lo, hi)) = medium.world_bounds() else { return RayIntegral::default() };
    let grow = DVec3::splat(velocity.max_speed() * tau.abs() + h);
    let Some((t0, t1)) = clip_box(origin, dir, lo - grow, hi + grow, t_max) else { return RayIntegral::default() };
    let mut n = 0u64;
    let mut a = t0;
    while a < t1 {
        let b = (a + h).min(t1);
        let dt = b - a;
        let p = origin + dir * (a + offset * dt);
        let q = p - velocity.at(p) * tau;
        let sigma = medium.sigma_t_at(q);
        let e = medium.emission_at(q);
        emit_step(&mut acc, sigma, e, dt);
        acc.tau += sigma * dt;
        n += 1;
        if acc.tau > TAU_CUTOFF {
            break;
        }
        a = b;
    }
    RayIntegral { l: acc.l, tau: acc.tau, work: n }
}

/// The part `[t0, t1]` of `origin + s dir`, s in `[0, t_max]`, inside the box
/// `[lo, hi]` (slabs), if any.
fn clip_box(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3, t_max: f64) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, t_max);
    for k in 0..3 {
        let (o, d) = (origin[k], dir[k]);
        if d == 0.0 {
            if o < lo[k] || o > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o) / d, (hi[k] - o) / d);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 < t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
}

fn walk_fixed(medium: &Medium, seg: RaySpan, h: f64, offset: f64, with_emission: bool, acc: &mut Accum) -> u64 {
    let RaySpan { origin, dir, t_max } = seg;
    let mut fields: Vec<usize> = Vec::with_capacity(2);
    for c in [medium.sigma_t, if with_emission { medium.emission } else { None }].into_iter().flatten() {
        if !fields.contains(&c.field) {
            fields.push(c.field);
        }
    }
    // Occupied spans of every field involved, and the ray's entry into the
    // volume's bounds (the start of the step grid).
    let mut spans: Vec<(f64, f64)> = Vec::new();
    let mut t_enter = f64::INFINITY;
    let mut t_exit: f64 = 0.0;
    for &fi in &fields {
        let f = &medium.fields[fi];
        let ray = IndexRay::new(f, origin, dir);
        if let Some((a, b)) = ray.clip(f.lo, f.hi, 0.0, t_max) {
            t_enter = t_enter.min(a);
            t_exit = t_exit.max(b);
        }
        spans.extend(LeafWalker::new(f, origin, dir, 0.0, t_max).map(|s| (s.t0, s.t1)));
    }
    if spans.is_empty() {
        return 0;
    }
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut merged: Vec<(f64, f64)> = Vec::with_capacity(spans.len());
    for s in spans {
        match merged.last_mut() {
            Some(m) if s.0 <= m.1 => m.1 = m.1.max(s.1),
            _ => merged.push(s),
        }
    }
    let step = |k: u64| -> (f64, f64) {
        let lo = t_enter + k as f64 * h;
        let hi = (t_enter + (k + 1) as f64 * h).min(t_exit);
        (lo, hi)
    };
    let mut n = 0u64;
    let mut k = 0u64;
    'spans: for (s0, s1) in merged {
        // First step whose sample may lie in [s0, s1).
        let k0 = (((s0 - t_enter) / h).floor() as i64 - 1).max(0) as u64;
        k = k.max(k0);
        loop {
            let (lo, hi) = step(k);
            if lo >= t_exit {
                break 'spans;
            }
            let ts = lo + offset * (hi - lo);
            if ts >= s1 {
                break;
            }
            k += 1;
            if ts < s0 {
                continue;
            }
            let p = origin + dir * ts;
            let dt = hi - lo;
            let sigma = medium.sigma_t_at(p);
            if with_emission {
                emit_step(acc, sigma, medium.emission_at(p), dt);
            }
            acc.tau += sigma * dt;
            n += 1;
            if acc.tau > TAU_CUTOFF {
                break 'spans;
            }
        }
    }
    n
}

/// The light a step of length `dt` through constant `sigma` and emission
/// `e` adds behind the depth so far (Cycles' volume_emission_integrate:
/// T E (1 - exp(-sigma dt)) / sigma, -> T E dt as sigma -> 0); the caller
/// then adds sigma dt to the depth. One place for the fixed-step and the
/// advected march.
fn emit_step(acc: &mut Accum, sigma: f64, e: [f64; 3], dt: f64) {
    let t = fmath::exp(-acc.tau);
    let w = if sigma > 0.0 { (1.0 - fmath::exp(-sigma * dt)) / sigma } else { dt };
    for c in 0..3 {
        acc.l[c] += t * e[c] * w;
    }
}
