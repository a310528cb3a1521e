//! Where fixed-step ray marching fails: steps much larger than a voxel in an
//! optically thick medium. The error is predicted exactly, in closed form,
//! and exact integration stays on the closed form.
//!
//! (`tests/render/integrator.rs`, `fixed_step_error_grows_with_step_size_while_exact_stays_exact`,
//! shows the growth against a numerical oracle on a random blob; this test
//! predicts the fixed-step result itself.)
//!
//! Set-up: an exponential atmosphere along x, `sigma_i = a q^i` with
//! `q = exp(-b v)` on voxels i = 0..n-1 (v the voxel size), and emission
//! proportional to it, `e = c sigma`. A ray along +x through a row of voxel
//! centres sees the trilinear field, which is the piecewise-linear
//! interpolant of the voxel values (0 outside the box), so:
//! - exact: `tau = v sum_i sigma_i = v a (1 - q^n) / (1 - q)` (the ramps at
//!   both ends are the trapezoid rule's half weights, the zeros beyond them
//!   give the other halves), and since e = c sigma,
//!   `L = int c sigma T ds = c (1 - exp(-tau))` for any sigma;
//! - fixed step h = m v: the step grid starts where the ray enters the
//!   field's box, index `lo` (a multiple of 8, here -8); step k spans
//!   `[lo + k m, min(lo + (k+1) m, hi)]` and is sampled at the fraction
//!   `offset` of its length, `tau_h = sum_k dt_k sigma(x_k)`. For m dividing
//!   8 and offset 0 the samples are the voxel centres `0, m, 2m, ...`: a
//!   left-point sum, in closed form a geometric series of ratio q^m.
//!   Cycles' per-step emission `T e (1 - exp(-sigma dt)) / sigma` telescopes
//!   for e = c sigma to `L_h = c (1 - exp(-tau_h))`: bounded by c whatever h.
//!
//! At m = 1 the two agree exactly; for m = 2, 4, 8 the left-point sum of a
//! decreasing convex function overestimates tau, by more as m grows, so T
//! is too small by the factor `exp(-(tau_h - tau))`. Steps of 16 and 32
//! voxels (4 and 8 km, a quarter and half of the medium) are checked against
//! the step sum: bounded and finite, however wrong.

#![allow(clippy::needless_range_loop)] // colour channels index several arrays

use aurora::grid::{Grid, Transform};
use aurora::render::{radiance_along_ray, Integration, Medium};
use aurora::util::fmath;
use glam::{DVec3, IVec3};

const A: f64 = 2.5; // per km at x = 0
const B: f64 = 0.1; // per km
const V: f64 = 0.25; // voxel, km
const N: i32 = 64; // voxels along x: 16 km, tau about 20
const C: [f64; 3] = [0.5, 0.3, 0.1];

fn sigma_node(i: i32) -> f64 {
    if (0..N).contains(&i) {
        A * fmath::exp(-B * V * i as f64)
    } else {
        0.0
    }
}

fn grids() -> (Grid<f32>, Grid<[f32; 3]>) {
    let tr = Transform::new(V, DVec3::ZERO);
    let mut d = Grid::new("density", 0.0f32, tr);
    let mut e = Grid::new("emission", [0.0f32; 3], tr);
    for i in 0..N {
        for j in -2..=2 {
            for k in -2..=2 {
                let s = sigma_node(i) as f32;
                d.set(IVec3::new(i, j, k), s);
                // e = c sigma in f32: the same rounding as sigma up to one
                // more ulp (relative 2^-24).
                e.set(IVec3::new(i, j, k), [C[0] as f32 * s, C[1] as f32 * s, C[2] as f32 * s]);
            }
        }
    }
    (d, e)
}

/// Closed form of the exact optical depth: v a (1 - q^n) / (1 - q).
fn tau_exact() -> f64 {
    let q = fmath::exp(-B * V);
    V * A * (1.0 - fmath::powi(q, N)) / (1.0 - q)
}

/// sigma along the ray at index x: the piecewise-linear interpolant of the
/// voxel values (what trilinear interpolation is on a row of centres).
fn sigma_lin(x: f64) -> f64 {
    let i = x.floor() as i32;
    let f = x - i as f64;
    (1.0 - f) * sigma_node(i) + f * sigma_node(i + 1)
}

/// The fixed-step optical depth for h = m v as the walker's step sum: step k
/// spans [lo + k m, min(lo + (k + 1) m, hi)], sampled at `offset` of it.
fn tau_fixed_steps(m: i32, offset: f64, lo: i32, hi: i32) -> f64 {
    let mut tau = 0.0;
    let mut a = lo;
    while a < hi {
        let b = (a + m).min(hi);
        tau += (b - a) as f64 * V * sigma_lin(a as f64 + offset * (b - a) as f64);
        a += m;
    }
    tau
}

/// Closed form of the left-point sum for m dividing 8 and offset 0 (samples
/// at x = 0, m, 2m, ..., n - m; none is cut, since n is a multiple of m and
/// hi >= n): h a (1 - q^n) / (1 - q^m).
fn tau_fixed_closed(m: i32) -> f64 {
    let q = fmath::exp(-B * V);
    m as f64 * V * A * (1.0 - fmath::powi(q, N)) / (1.0 - fmath::powi(q, m))
}

#[test]
fn fixed_step_error_follows_its_closed_form_and_exact_stays_exact() {
    let (d, e) = grids();
    let medium = Medium::new(Some(&d), Some(&e), 1.0, 1.0).unwrap();
    assert_eq!(medium.fields.len(), 1, "shared transform: one field");
    let (lo, hi) = (medium.fields[0].lo.x, medium.fields[0].hi.x);
    // The ray: along +x through the voxel centres of row (j, k) = (0, 0).
    let o = DVec3::new(-5.0, 0.0, 0.0);
    let dir = DVec3::X;

    let tau = tau_exact();
    assert!(tau > 15.0 && tau < 30.0, "optically thick but below the walker's cutoff: {tau}");
    let ex = radiance_along_ray(&medium, o, dir, f64::INFINITY, Integration::Exact, 0.5);
    // Voxel values are f32: each sigma_i is off by at most 2^-24 relative,
    // so tau by at most 2^-24 tau (6e-8 relative); the exact integrator's
    // own error is far below that. Ask for 1e-6.
    assert!((ex.tau / tau - 1.0).abs() < 1e-6, "exact tau {} vs closed form {tau}", ex.tau);
    // The renderer's stated bound: within 1e-4 of the closed form (T and L). An
    // optical-depth error of 2^-24 tau is a relative T error of 1.2e-6.
    let t = fmath::exp(-tau);
    assert!((ex.transmittance() / t - 1.0).abs() < 1e-4, "T {} vs {t}", ex.transmittance());
    for c in 0..3 {
        let l = C[c] * (1.0 - t);
        assert!((ex.l[c] / l - 1.0).abs() < 1e-4, "L[{c}] {} vs {l}", ex.l[c]);
    }

    assert_eq!((lo, N % 8), (-8, 0), "the set-up the closed forms assume");
    let mut last_dtau = -1.0;
    for m in [1, 2, 4, 8, 16, 32] {
        let h = m as f64 * V;
        let fx = radiance_along_ray(&medium, o, dir, f64::INFINITY, Integration::FixedStep(h), 0.0);
        let predicted = tau_fixed_steps(m, 0.0, lo, hi);
        if 8 % m == 0 {
            // Two forms of the same sum, in f64: 1e-12.
            assert!((predicted / tau_fixed_closed(m) - 1.0).abs() < 1e-12, "m = {m}");
        }
        // The same f32 voxel values, summed in a different order: 1e-6.
        assert!((fx.tau / predicted - 1.0).abs() < 1e-6, "h = {h}: tau {} vs predicted {predicted}", fx.tau);
        // Bounded: T in (0, 1], L = c (1 - T_h) in [0, c], finite for any h.
        assert!(fx.transmittance() > 0.0 && fx.transmittance() <= 1.0);
        for c in 0..3 {
            let l = C[c] * (1.0 - fmath::exp(-predicted));
            assert!(fx.l[c].is_finite() && fx.l[c] >= 0.0 && fx.l[c] <= C[c] * (1.0 + 1e-6), "h = {h}: L {:?}", fx.l);
            assert!((fx.l[c] / l - 1.0).abs() < 1e-6, "h = {h}: L[{c}] {} vs predicted {l}", fx.l[c]);
        }
        let dtau = predicted - tau;
        let t_err = fx.transmittance() / t - 1.0;
        eprintln!("h = {h:5.2} km ({m:2} voxels): tau {:.4} (exact {tau:.4}), T relative error {t_err:+.3e}", fx.tau);
        // The error grows as predicted: 0 at one voxel, then strictly more
        // with every doubling of the step (left-point sums).
        if m == 1 {
            assert!(dtau.abs() < 1e-9 * tau, "h = v is exact here: {dtau}");
        } else if 8 % m == 0 {
            assert!(dtau > last_dtau, "m = {m}: {dtau} after {last_dtau}");
            last_dtau = dtau;
        }
        if m >= 8 {
            // Far past the voxel in a medium of optical depth 20, T is wrong
            // by more than a factor of e (|d tau| > 1), yet finite.
            assert!(dtau.abs() > 1.0, "m = {m}: {dtau}");
        }
    }
    // Other sample positions inside the step (as jittered pixels use): the
    // step sum still predicts the walker.
    for (m, offset) in [(16, 0.5), (32, 0.25), (4, 0.7)] {
        let fx = radiance_along_ray(&medium, o, dir, f64::INFINITY, Integration::FixedStep(m as f64 * V), offset);
        let predicted = tau_fixed_steps(m, offset, lo, hi);
        assert!((fx.tau / predicted - 1.0).abs() < 1e-6, "m = {m}, offset {offset}: {} vs {predicted}", fx.tau);
    }
}
