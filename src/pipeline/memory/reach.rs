//! How far a bake's beams and deposits reach, from its plan's scene and
//! atmosphere (`crate::pipeline::plan`): the
//! highest deposit and the columns above the starts, the lowest stop, the
//! steps a beam takes and how far its walk spreads across the field, and
//! the world box around the curtains. The memory budget bounds its terms
//! from these (`super::budget`, its module documentation
//! gives the models: Wald's identity for the steps, the random walk's
//! four standard deviations for the spread).

use crate::physics::deposition::curtain_spectrum::{self, Population};
use crate::physics::deposition::fang::SpectrumDeposition;
use crate::pipeline::beams::dip::min_dip_deg;
use crate::pipeline::beams::walk::{above_start_column_top, above_start_spans, max_above_start_spans, COMPLETE_TOL, FANG_MAX_STEPS};
use crate::pipeline::footprint::curtain_path::{polyline_length, vertices, Lift};
use crate::pipeline::plan::BakePlan;
use crate::scene::{Curtain, Deposition};
use crate::util::fmath;
use std::sync::Arc;

/// The spectrum that reaches highest of a curtain's populations: the
/// body's (the filaments' are its source accelerated further, without the
/// soft part; [`stop_km`] takes the lowest stop of both).
fn body_spectrum(curtain: &Curtain) -> Arc<SpectrumDeposition> {
    curtain_spectrum::deposition(curtain, Population::Body)
}

/// The highest altitude a deposit of `curtain` can lie at, km: the beams'
/// highest start, or above it for Fang's depositions, which lay what the
/// spectrum leaves above a beam's start along the field line above it up
/// to [`crate::pipeline::beams::walk::above_start_column_top`]: for `expected`, that altitude for
/// the curtain's own spectrum (the function the trace calls, so the same
/// altitude); for `sampled`, where each
/// beam's energy is drawn, the atmosphere table's top (700 km for NRLMSIS
/// 2.1), which bounds every energy's.
pub fn deposit_top_km(plan: &BakePlan, curtain: &Curtain) -> f64 {
    let start_top = plan.scene.beams.top_km + plan.scene.beams.top_noise_km;
    let atm = &plan.atmosphere;
    match plan.scene.beams.deposition {
        Deposition::Csda => start_top,
        Deposition::Sampled => start_top.max(atm.top_km()),
        Deposition::Expected => {
            let g = body_spectrum(curtain);
            above_start_column_top(atm, &|m| g.fraction_above(m), g.total(), start_top)
        }
    }
}

/// Bound on the spans of a beam's column above its start (one photon
/// each): for `expected`, the spans the trace lays above the curtain's
/// lowest start ([`above_start_spans`], the function the trace calls; a
/// higher start's column is a part of it, plus 2 for where their
/// boundaries fall differently); for `sampled`, [`max_above_start_spans`]
/// of the whole column; none for `csda`.
pub fn column_spans(plan: &BakePlan, curtain: &Curtain) -> f64 {
    let column = column_km(plan, curtain);
    if column <= 0.0 {
        return 0.0;
    }
    match plan.scene.beams.deposition {
        Deposition::Csda => 0.0,
        Deposition::Sampled => max_above_start_spans(column) as f64,
        Deposition::Expected => {
            let atm = &plan.atmosphere;
            let g = body_spectrum(curtain);
            let lowest = plan.scene.beams.top_km - plan.scene.beams.top_noise_km;
            let n = above_start_spans(atm, &|m| g.fraction_above(m), g.total(), lowest).len();
            if n < 2 {
                0.0
            } else {
                (n - 1 + 2) as f64
            }
        }
    }
}

/// Altitude span of a curtain's columns above the starts, km: from the
/// lowest start to [`deposit_top_km`] (0 without them).
pub fn column_km(plan: &BakePlan, curtain: &Curtain) -> f64 {
    (deposit_top_km(plan, curtain) - (plan.scene.beams.top_km - plan.scene.beams.top_noise_km)).max(0.0)
}

/// Bound on the leaves of the columns above the starts (module
/// documentation): per curtain, its rotated footprint box dilated by
/// `reach`, `(dx / leaf + 3) (dy / leaf + 3)` leaves per slab, over
/// `column_km / leaf + 2` slabs.
pub fn column_leaves(plan: &BakePlan, leaf_km: f64, reach: f64) -> f64 {
    plan.scene
        .curtains
        .iter()
        .map(|c| {
            let h = column_km(plan, c);
            if h <= 0.0 {
                return 0.0;
            }
            let slabs = h / leaf_km + 2.0;
            if let Some((length, _)) = path_curve(plan, c) {
                let rho = 0.5 * c.width + reach + std::f64::consts::SQRT_2 * leaf_km + leaf_km;
                return band_area_leaves(length, rho, leaf_km) * slabs;
            }
            let (s, co) = fmath::sin_cos(c.rotation_deg.to_radians());
            let dx = (c.length * co).abs() + (c.width * s).abs() + 2.0 * reach;
            let dy = (c.length * s).abs() + (c.width * co).abs() + 2.0 * reach;
            (dx / leaf_km + 3.0) * (dy / leaf_km + 3.0) * slabs
        })
        .sum()
}

/// A path curtain's curve lifted to the start altitude: its length and
/// vertices (None for a straight curtain).
pub fn path_curve(plan: &BakePlan, c: &Curtain) -> Option<(f64, Vec<[f64; 2]>)> {
    let p = c.path.as_ref()?;
    let v = vertices(&Lift::of_scene(&plan.scene).path(p));
    Some((polyline_length(&v), v))
}

/// Leaves of side `leaf` per slab within `rho` of a curve of `length`
/// (module documentation).
pub fn band_area_leaves(length: f64, rho: f64, leaf: f64) -> f64 {
    let r = rho + std::f64::consts::SQRT_2 * leaf;
    (2.0 * r * length + std::f64::consts::PI * r * r) / (leaf * leaf)
}

/// A conservative world box around every curtain, km: footprint boxes
/// (rotated), from 50 km (below the lowest altitude the hardest electrons
/// reach) to the beams' highest start, widened by the drift along an
/// inclined field (at the smallest dip, [`dip_deg`]) and the beams' spread
/// across it ([`spread_km`]). The columns above the starts are bounded apart
/// ([`column_leaves`]).
pub fn world_bounds(plan: &BakePlan) -> ([f64; 3], [f64; 3]) {
    let z0 = 50.0;
    let z1 = plan.scene.beams.top_km + plan.scene.beams.top_noise_km;
    let tilt = fmath::tan((90.0 - dip_deg(plan)).to_radians()) * (z1 - z0) + spread_km(plan);
    let mut lo = [f64::INFINITY, f64::INFINITY, z0];
    let mut hi = [f64::NEG_INFINITY, f64::NEG_INFINITY, z1];
    for c in &plan.scene.curtains {
        if let Some((_, v)) = path_curve(plan, c) {
            let h = 0.5 * c.width;
            for p in v {
                lo[0] = lo[0].min(p[0] - h - tilt);
                lo[1] = lo[1].min(p[1] - h - tilt);
                hi[0] = hi[0].max(p[0] + h + tilt);
                hi[1] = hi[1].max(p[1] + h + tilt);
            }
            continue;
        }
        let (s, co) = fmath::sin_cos(c.rotation_deg.to_radians());
        for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)] {
            let (u, w) = (a * c.length, b * c.width);
            let x = c.center[0] + u * co - w * s;
            let y = c.center[1] + u * s + w * co;
            lo[0] = lo[0].min(x - tilt);
            lo[1] = lo[1].min(y - tilt);
            hi[0] = hi[0].max(x + tilt);
            hi[1] = hi[1].max(y + tilt);
        }
    }
    (lo, hi)
}

/// The smallest dip of the electrons' field line where any curtain's beams
/// start, degrees ([`crate::pipeline::beams::dip::min_dip_deg`]: IGRF's
/// over a `[site]` whose beams follow it, the plan's `site_field`), at least
/// 1e-3 so the bounds stay finite for a scene the bake refuses.
pub fn dip_deg(plan: &BakePlan) -> f64 {
    min_dip_deg(&plan.scene.curtains, &plan.scene.beams, &plan.scene.earth, plan.site_field.as_ref()).max(1e-3)
}

/// The altitude where a Fang beam of `curtain` has deposited all but
/// [`COMPLETE_TOL`] of its total and stops, km: for `expected` the
/// curtain's spectrum's (by bisection on the atmosphere's table, 50
/// halvings); for `sampled`, where each beam's energy is drawn, the
/// table's bottom, which bounds every energy's.
pub fn stop_km(plan: &BakePlan, curtain: &Curtain) -> f64 {
    let atm = &plan.atmosphere;
    if plan.scene.beams.deposition != Deposition::Expected {
        return atm.bottom_km();
    }
    let mut pops = vec![Population::Body];
    if curtain_spectrum::has_filaments(curtain) {
        pops.push(Population::Filaments);
    }
    pops.into_iter().map(|pop| spectrum_stop_km(plan, &curtain_spectrum::deposition(curtain, pop))).fold(f64::INFINITY, f64::min)
}

/// Where a beam of spectrum `g` has deposited all but [`COMPLETE_TOL`].
fn spectrum_stop_km(plan: &BakePlan, g: &SpectrumDeposition) -> f64 {
    let atm = &plan.atmosphere;
    let done = |z: f64| g.fraction_above(atm.column_mass(z)) >= (1.0 - COMPLETE_TOL) * g.total();
    let (mut lo, mut hi) = (atm.bottom_km(), plan.scene.beams.top_km + plan.scene.beams.top_noise_km);
    if !done(lo) {
        return lo;
    }
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if done(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// A beam's steps: their expected number and its variance, for the worst
/// curtain (module documentation). csda: `ceil(1 / dt)`, no variance. Fang's
/// depositions: Wald's bound `(H + L dt (sin I + tan alpha_D cos I)) / mu`
/// with `mu = L dt sin(I) / 2` the mean descent of a step, and the renewal
/// variance `H sigma^2 / mu^3`, `sigma^2 <= (L dt)^2 (sin^2 I / 12 +
/// tan^2 alpha_D cos^2 I / 6)` the variance of a step's descent; at most
/// [`FANG_MAX_STEPS`].
pub fn steps_per_beam(plan: &BakePlan) -> (f64, f64) {
    let b = &plan.scene.beams;
    if b.deposition == Deposition::Csda {
        return ((1.0 / b.dt).ceil(), 0.0);
    }
    let dip = dip_deg(plan);
    let cap = FANG_MAX_STEPS as f64;
    if dip <= b.alpha_d_deg {
        return (cap, 0.0);
    }
    let top = b.top_km + b.top_noise_km;
    let h = plan.scene.curtains.iter().map(|c| (top - stop_km(plan, c)).max(0.0)).fold(0.0, f64::max);
    let (si, ci) = fmath::sin_cos(dip.to_radians());
    let ta = fmath::tan(b.alpha_d_deg.to_radians());
    let a = b.length_km * b.dt;
    let mu = 0.5 * a * si;
    let mean = ((h + a * (si + ta * ci)) / mu).min(cap);
    let sigma2 = a * a * (si * si / 12.0 + ta * ta * ci * ci / 6.0);
    (mean, h * sigma2 / fmath::powi(mu, 3))
}

/// The step photons of `beams` beams: `beams` times the expected steps plus
/// four standard deviations of their sum ([`steps_per_beam`]).
pub fn photons_of_steps(plan: &BakePlan, beams: f64) -> f64 {
    let (mean, var) = steps_per_beam(plan);
    beams * mean + 4.0 * (beams * var).sqrt()
}

/// How far a beam wanders across the field line, km: its deflections are a
/// random walk of [`steps_per_beam`] steps, each at most `L dt tan
/// alpha_D` across with mean square `(L dt tan alpha_D)^2 / 3`; four
/// standard deviations of its sum, and at most `sin(alpha_D)` of its
/// longest path, `h / sin(I - alpha_D)`.
pub fn spread_km(plan: &BakePlan) -> f64 {
    let b = &plan.scene.beams;
    let (n, _) = steps_per_beam(plan);
    let walk = 4.0 * (n / 3.0).sqrt() * b.length_km * b.dt * fmath::tan(b.alpha_d_deg.to_radians());
    // However long the steps, a path that descends at least sin(I - alpha_D)
    // per km from the highest start to 50 km goes at most tan(alpha_D) per
    // km along the line across it.
    let descent = (dip_deg(plan) - b.alpha_d_deg).to_radians();
    if descent > 0.0 {
        let h = (b.top_km + b.top_noise_km - 50.0).max(0.0);
        walk.min(h / fmath::sin(descent) * fmath::sin(b.alpha_d_deg.to_radians()))
    } else {
        walk
    }
}
