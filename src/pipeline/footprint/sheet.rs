//! The footprint as a rolled-up vortex sheet (`footprint.model = "sheet"`).
//!
//! An auroral arc is a sheet of space charge drifting at E x B: in the
//! plane across the field the electric potential is a stream function and
//! the charge density its vorticity, so the arc is a vortex sheet and rolls
//! up by the Kelvin-Helmholtz instability into curls (2-10 km), folds
//! (20-50 km) and surges (100+ km) (Hallinan & Davis 1970, Planet. Space
//! Sci. 18, 1735). Arcs are 5-20 km wide (Knudsen et al. 2001), with
//! filaments 0.05-0.2 km wide inside them (Borovsky 1993).
//!
//! Model (Krasny 1986, J. Comput. Phys. 65, 292, the desingularised
//! periodic vortex sheet): N markers at spacing h along a sheet of period P
//! (the curtain's length), each carrying circulation Γ = γ h (γ = 1 km/s,
//! the velocity jump across the sheet). A marker at (x, y) moves with
//!
//! ```text
//! u = -Γ/(2P) Σ sinh Y / (cosh Y - cos X + δ²)
//! v =  Γ/(2P) Σ sin X  / (cosh Y - cos X + δ²),   X = 2π Δx / P, Y = 2π Δy / P
//! ```
//!
//! with `cosh(2π d / P) = 1 + δ²`, d = `sheet_smoothing_km`. For a flat
//! sheet perturbed by a mode of wavenumber κ = 2πk/P, linearising gives
//! `dξ/dt = -(γ/2)(2π/P)(1 - e^{-κd}) / sinh(2πd/P) η` and
//! `dη/dt = -(γ/2) κ e^{-κd} ξ`, so the mode grows at
//! [`growth_rate`] `σ = (γ/2) sqrt(κ e^{-κd} (1 - e^{-κd}) (2π/P) / sinh(2πd/P))`
//! (→ γκ/2, Kelvin-Helmholtz, as d → 0; `tests/physics/footprint.rs`
//! checks it). Markers further than `WINDOW_KM` along the sheet are left
//! out of a marker's sum (a long oval would cost N²; the far sheet's pull
//! is small), otherwise the sum is exact.
//!
//! The sheet starts flat across the middle of the box, displaced by a sum
//! of modes (random phases and amplitudes, from the curtain seed) whose
//! displacement spectrum falls as κ^-3 above 2π / 200 km (flat below), so
//! curls saturate, folds grow and the longest scales stay gentle; it is
//! integrated by RK4 for a time `sheet_rollup_km / γ`. The markers are then
//! drawn into the footprint as a Gaussian line of FWHM
//! `sheet_thickness_km`, each marker's charge spread over its segment
//! (a stretched sheet dims; a fold seen edge-on stacks it, bright and
//! thin), times a brightness along the sheet: rays at gamma-like spacing
//! (mean `ray_spacing_km`, CV about 0.85) of brightness log-uniform in
//! [1, `ray_contrast`] over a floor, plus a diffuse glow (`glow`, a
//! Gaussian blur of 3 km).
//!
//! Motion (closed form in t): the modes' phases travel at `fold_speed_kms`
//! times a per-mode factor in [-0.5, 1.6] (dispersive), their amplitude
//! breathes by `fold_breathing`, and the rays travel along the sheet at
//! `ray_speed_kms`; the integration time is the same at every t.

use super::cells::Cells;
use crate::scene::{AnimationParams, FootprintParams};
use crate::util::fmath;
use crate::util::rng;
use rand::Rng;
use rayon::prelude::*;

/// Markers further than this along the sheet (km) are left out of a
/// marker's velocity sum.
pub const WINDOW_KM: f64 = 80.0;
/// Most markers along one sheet (a longer one gets a wider spacing).
pub const MAX_MARKERS: usize = 65_536;
/// Wavelength above which the initial displacement spectrum is flat, km.
const FLAT_ABOVE_KM: f64 = 200.0;
/// The velocity jump across the sheet, km/s (time is in its units).
const GAMMA: f64 = 1.0;
/// Width of the diffuse glow's blur, km.
const GLOW_KM: f64 = 3.0;
/// Brightness along the sheet between rays, of a ray of brightness 1.
const RAY_FLOOR: f64 = 0.1;

/// The desingularised periodic kernel: period, δ², circulation per marker
/// and the window of markers summed each side.
#[derive(Clone, Copy, Debug)]
pub struct Kernel {
    pub period: f64,
    pub delta2: f64,
    pub circulation: f64,
    pub window: usize,
}

impl Kernel {
    /// The kernel of `n` markers along a sheet of period `period` km, with
    /// smoothing length `smoothing_km`.
    pub fn new(period: f64, n: usize, smoothing_km: f64) -> Self {
        let h = period / n as f64;
        let delta2 = fmath::cosh(std::f64::consts::TAU * smoothing_km / period) - 1.0;
        let window = ((WINDOW_KM / h).ceil() as usize).min(n / 2);
        Kernel { period, delta2, circulation: GAMMA * h, window }
    }

    /// The velocities of every marker, km/s. Each marker's sum runs in
    /// index order on one thread: the same bits whatever the thread count.
    pub fn velocities(&self, x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n = x.len();
        let s = std::f64::consts::TAU / self.period;
        let trig: Vec<[f64; 4]> = x
            .iter()
            .zip(y)
            .map(|(&xi, &yi)| {
                let (sx, cx) = fmath::sin_cos(s * xi);
                let e = fmath::exp(s * yi);
                [sx, cx, e, 1.0 / e]
            })
            .collect();
        let all = 2 * self.window + 1 >= n;
        let c = self.circulation / (2.0 * self.period);
        let d2 = self.delta2;
        let w = self.window;
        let uv: Vec<(f64, f64)> = (0..n)
            .into_par_iter()
            .map(|j| {
                let [sj, cj, ej, fj] = trig[j];
                let term = |k: usize| {
                    let [sk, ck, ek, fk] = trig[k];
                    let cos = cj * ck + sj * sk;
                    let sin = sj * ck - cj * sk;
                    let a = ej * fk;
                    let b = fj * ek;
                    let d = 0.5 * (a + b) - cos + d2;
                    (0.5 * (a - b) / d, sin / d)
                };
                let (mut su, mut sv) = (0.0, 0.0);
                if all {
                    for k in 0..n {
                        let (a, b) = term(k);
                        su += a;
                        sv += b;
                    }
                } else {
                    for o in 0..=2 * w {
                        let k = (j + n + o - w) % n;
                        let (a, b) = term(k);
                        su += a;
                        sv += b;
                    }
                }
                (-c * su, c * sv)
            })
            .collect();
        uv.into_iter().unzip()
    }

    /// One classical Runge-Kutta step of `dt` s.
    pub fn rk4(&self, x: &mut [f64], y: &mut [f64], dt: f64) {
        let n = x.len();
        let stage = |x0: &[f64], y0: &[f64], du: &[f64], dv: &[f64], f: f64| -> (Vec<f64>, Vec<f64>) {
            ((0..n).map(|i| x0[i] + f * du[i]).collect(), (0..n).map(|i| y0[i] + f * dv[i]).collect())
        };
        let (u1, v1) = self.velocities(x, y);
        let (xa, ya) = stage(x, y, &u1, &v1, 0.5 * dt);
        let (u2, v2) = self.velocities(&xa, &ya);
        let (xb, yb) = stage(x, y, &u2, &v2, 0.5 * dt);
        let (u3, v3) = self.velocities(&xb, &yb);
        let (xc, yc) = stage(x, y, &u3, &v3, dt);
        let (u4, v4) = self.velocities(&xc, &yc);
        for i in 0..n {
            x[i] += dt / 6.0 * (u1[i] + 2.0 * u2[i] + 2.0 * u3[i] + u4[i]);
            y[i] += dt / 6.0 * (v1[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
        }
    }
}

/// Linear growth rate (1/s) of a mode of wavenumber `kappa` (rad/km) on the
/// sheet of [`Kernel`] with period `period` and smoothing `smoothing_km`,
/// velocity jump γ = 1 km/s (module documentation).
pub fn growth_rate(kappa: f64, period: f64, smoothing_km: f64) -> f64 {
    let a = std::f64::consts::TAU / period;
    let e = fmath::exp(-kappa * smoothing_km);
    0.5 * GAMMA * (kappa * e * (1.0 - e) * a / fmath::sinh(a * smoothing_km)).sqrt()
}

/// Markers along a sheet of `period` km for `params`: one per
/// `sheet_spacing_km`, at least 16 and at most [`MAX_MARKERS`].
pub fn marker_count(period: f64, params: &FootprintParams) -> usize {
    ((period / params.sheet_spacing_km).round() as usize).clamp(16, MAX_MARKERS)
}

/// The rolled-up sheet at time `t`: marker positions (x along the
/// curtain from -P/2, y across from its middle), km.
pub fn roll_up(period: f64, params: &FootprintParams, anim: &AnimationParams, seeds: [u64; 2], t: f64) -> (Vec<f64>, Vec<f64>) {
    let n = marker_count(period, params);
    let h = period / n as f64;
    let tau = std::f64::consts::TAU;
    let mut r = rng::rng(&[seeds[0], seeds[1], rng::tag::FOOTPRINT_VELOCITY, 1]);
    let breathing =
        if anim.fold_breathing > 0.0 { 1.0 + anim.fold_breathing * fmath::sin(tau * t / anim.fold_breathing_period_s) } else { 1.0 };
    // Modes up to the wavelength 2π d (shorter ones hardly grow), at most
    // a quarter of the markers.
    let k_max = ((period / (tau * params.sheet_smoothing_km)).floor() as usize).clamp(1, (n / 4).max(1));
    let dk = tau / period;
    let k0 = tau / FLAT_ABOVE_KM;
    let modes: Vec<(f64, f64, f64)> = (1..=k_max)
        .map(|k| {
            let kappa = k as f64 * dk;
            // E(κ) = ε² min(κ, κ0)^-3 per unit κ: a mode holds E Δκ.
            let amp = params.sheet_amplitude * (2.0 * dk).sqrt() * fmath::powf(kappa.max(k0), -1.5);
            let a = amp * (0.5 + r.random::<f64>());
            let phase = r.random::<f64>() * tau;
            let speed = anim.fold_speed_kms * (-0.5 + 2.1 * r.random::<f64>());
            (kappa, a * breathing, phase - kappa * speed * t)
        })
        .collect();
    let mut x: Vec<f64> = (0..n).map(|j| -0.5 * period + (j as f64 + 0.5) * h).collect();
    let mut y: Vec<f64> = x.par_iter().map(|&xj| modes.iter().map(|&(k, a, p)| a * fmath::sin(k * xj + p)).sum()).collect();
    let steps = params.sheet_steps.max(1);
    let dt = params.sheet_rollup_km / GAMMA / steps as f64;
    if params.sheet_rollup_km > 0.0 {
        let kernel = Kernel::new(period, n, params.sheet_smoothing_km);
        for _ in 0..steps {
            kernel.rk4(&mut x, &mut y, dt);
        }
    }
    (x, y)
}

/// Brightness along the sheet at each marker (its parameter α from 0 to
/// P): rays over a floor (module documentation), peak about `ray_contrast`.
pub fn ray_brightness(n: usize, period: f64, params: &FootprintParams, seeds: [u64; 2], shift_km: f64) -> Vec<f64> {
    let mut r = rng::rng(&[seeds[0], seeds[1], rng::tag::FOOTPRINT_VELOCITY, 2]);
    let mean = params.ray_spacing_km;
    let mut rays = Vec::new();
    let mut a = r.random::<f64>() * mean;
    while a < period {
        let b = fmath::powf(params.ray_contrast, r.random::<f64>());
        rays.push((a, b));
        // Gaps 0.15 mean + an exponential of 0.85 mean: CV 0.85 (rays
        // bunch and part), none closer than 0.15 mean.
        let e = -fmath::ln(1.0 - r.random::<f64>());
        a += mean * (0.15 + 0.85 * e);
    }
    let w = params.ray_width_km.max(1e-6);
    let h = period / n as f64;
    (0..n)
        .map(|j| {
            let alpha = (j as f64 + 0.5) * h - shift_km;
            let mut s = RAY_FLOOR;
            for &(ar, b) in &rays {
                let mut d = (alpha - ar).rem_euclid(period);
                if d > 0.5 * period {
                    d -= period;
                }
                if d.abs() < 4.0 * w {
                    s += b * fmath::exp(-0.5 * fmath::powi(d / w, 2));
                }
            }
            s
        })
        .collect()
}

/// The sheet drawn on an nx x ny grid of a box `length` x `width` km
/// (index `j * nx + i`, u from -length/2, v from -width/2), unnormalised:
/// each marker's charge (brightness times spacing) spread evenly over the
/// segment to the next, a Gaussian line of FWHM `thickness_km` across.
pub fn rasterise(x: &[f64], y: &[f64], brightness: &[f64], cells: Cells, thickness_km: f64) -> Vec<f64> {
    let Cells { nx, ny, length: period, width } = cells;
    let n = x.len();
    let (du, dv) = (period / nx as f64, width / ny as f64);
    let sigma = thickness_km / 2.3548;
    let (su, sv) = ((sigma * sigma + du * du / 6.0).sqrt(), (sigma * sigma + dv * dv / 6.0).sqrt());
    let (ru, rv) = ((3.0 * su / du).ceil() as i64, (3.0 * sv / dv).ceil() as i64);
    let step = 0.5 * du.min(dv);
    let h = period / n as f64;
    let mut out = vec![0.0f64; nx * ny];
    for j in 0..n {
        let k = (j + 1) % n;
        let (x1, y1) = (x[k] + if k == 0 { period } else { 0.0 }, y[k]);
        let (ex, ey) = (x1 - x[j], y1 - y[j]);
        let len = (ex * ex + ey * ey).sqrt();
        let m = ((len / step).ceil() as usize).max(1);
        let q = brightness[j] * h / m as f64;
        for s in 0..m {
            let f = (s as f64 + 0.5) / m as f64;
            let (px, py) = (x[j] + f * ex, y[j] + f * ey);
            let gi = (px + 0.5 * period) / du - 0.5;
            let gj = (py + 0.5 * width) / dv - 0.5;
            let (ci, cj) = (gi.round() as i64, gj.round() as i64);
            for jj in (cj - rv).max(0)..=(cj + rv).min(ny as i64 - 1) {
                let wv = fmath::exp(-0.5 * fmath::powi((jj as f64 - gj) * dv / sv, 2));
                for ii in ci - ru..=ci + ru {
                    let wu = fmath::exp(-0.5 * fmath::powi((ii as f64 - gi) * du / su, 2));
                    let i = ii.rem_euclid(nx as i64) as usize;
                    out[jj as usize * nx + i] += q * wu * wv;
                }
            }
        }
    }
    out
}

/// A separable Gaussian blur of `sigma_km` (periodic along u, zero beyond
/// the box across).
fn blur(data: &[f64], nx: usize, ny: usize, du: f64, dv: f64, sigma_km: f64) -> Vec<f64> {
    let taps = |d: f64| -> Vec<f64> {
        let r = (3.0 * sigma_km / d).ceil() as i64;
        (-r..=r).map(|o| fmath::exp(-0.5 * fmath::powi(o as f64 * d / sigma_km, 2))).collect()
    };
    let (tu, tv) = (taps(du), taps(dv));
    let (ru, rv) = ((tu.len() / 2) as i64, (tv.len() / 2) as i64);
    let mut a = vec![0.0; nx * ny];
    a.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
        for (i, o) in row.iter_mut().enumerate() {
            *o = tu.iter().enumerate().map(|(t, w)| w * data[j * nx + (i as i64 + t as i64 - ru).rem_euclid(nx as i64) as usize]).sum();
        }
    });
    let mut b = vec![0.0; nx * ny];
    b.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
        for (i, o) in row.iter_mut().enumerate() {
            *o = tv
                .iter()
                .enumerate()
                .filter_map(|(t, w)| {
                    let jj = j as i64 + t as i64 - rv;
                    (0..ny as i64).contains(&jj).then(|| w * a[jj as usize * nx + i])
                })
                .sum();
        }
    });
    b
}

/// The sheet footprint at time `t` on an nx x ny grid over a box of
/// `length` x `width` km (before the bend), peak 1: the sheet with its
/// rays and glow.
pub fn density(cells: Cells, params: &FootprintParams, anim: &AnimationParams, seeds: [u64; 2], t: f64) -> Vec<f64> {
    let (x, y) = roll_up(cells.length, params, anim, seeds, t);
    drawn(&x, &y, cells, params, anim, seeds, t)
}

/// The sheet of markers `(x, y)` drawn with its rays and glow, peak 1.
fn drawn(x: &[f64], y: &[f64], cells: Cells, params: &FootprintParams, anim: &AnimationParams, seeds: [u64; 2], t: f64) -> Vec<f64> {
    let Cells { nx, ny, length, width } = cells;
    let b = ray_brightness(x.len(), length, params, seeds, anim.ray_speed_kms * t);
    let sharp = rasterise(x, y, &b, cells, params.sheet_thickness_km);
    let peak = |d: &[f64]| d.iter().cloned().fold(0.0f64, f64::max);
    let ps = peak(&sharp);
    if ps <= 0.0 {
        return sharp;
    }
    let mut out = sharp;
    if params.glow > 0.0 {
        let g = blur(&out, nx, ny, length / nx as f64, width / ny as f64, GLOW_KM);
        let pg = peak(&g).max(1e-300);
        for (o, gi) in out.iter_mut().zip(&g) {
            *o = *o / ps + params.glow * gi / pg;
        }
    }
    normalised(out)
}

fn normalised(mut d: Vec<f64>) -> Vec<f64> {
    let p = d.iter().cloned().fold(0.0f64, f64::max);
    if p > 0.0 {
        d.iter_mut().for_each(|v| *v /= p);
    }
    d
}

/// An arc with filaments at time `t`: its body (the sheet of FWHM
/// `sheet_thickness_km`, no rays: a smooth glow that folds and curls with
/// the sheet) and its filaments, both of peak 1. The filaments are
/// `filament_count` copies of the sheet's centre line moved along its
/// normal to offsets spread evenly within +-0.3 of the body's FWHM (a
/// seeded jitter of 0.1 of it), each of FWHM `filament_width_km` with rays
/// of its own along it (Maggs & Davis 1968: thin sheets inside an arc, rays
/// along them).
pub fn arc_layers(cells: Cells, params: &FootprintParams, anim: &AnimationParams, seeds: [u64; 2], t: f64) -> (Vec<f64>, Vec<f64>) {
    let (x, y) = roll_up(cells.length, params, anim, seeds, t);
    let n = x.len();
    let even = vec![1.0; n];
    let body = normalised(rasterise(&x, &y, &even, cells, params.sheet_thickness_km));
    let period = cells.length;
    // Unit normals by central differences (periodic along the sheet).
    let normals: Vec<(f64, f64)> = (0..n)
        .map(|j| {
            let (a, b) = ((j + n - 1) % n, (j + 1) % n);
            let dx = x[b] - x[a] + if b < a { period } else { 0.0 };
            let dy = y[b] - y[a];
            let l = fmath::hypot(dx, dy).max(1e-12);
            (-dy / l, dx / l)
        })
        .collect();
    let k = params.filament_count.max(1);
    let mut r = rng::rng(&[seeds[0], seeds[1], rng::tag::FOOTPRINT_FILAMENTS]);
    let mut fil = vec![0.0; cells.nx * cells.ny];
    for f in 0..k {
        let spread = if k > 1 { f as f64 / (k - 1) as f64 - 0.5 } else { 0.0 };
        let offset = params.sheet_thickness_km * (0.6 * spread + 0.1 * (r.random::<f64>() - 0.5));
        let xs: Vec<f64> = (0..n).map(|j| x[j] + offset * normals[j].0).collect();
        let ys: Vec<f64> = (0..n).map(|j| y[j] + offset * normals[j].1).collect();
        let rays = ray_brightness(n, period, params, [seeds[0], seeds[1] ^ (0x9E37_79B9 * (f as u64 + 1))], anim.ray_speed_kms * t);
        for (o, v) in fil.iter_mut().zip(rasterise(&xs, &ys, &rays, cells, params.filament_width_km)) {
            *o += v;
        }
    }
    (body, normalised(fil))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_sheet_stays_flat_and_the_sum_is_symmetric() {
        // Flat sheet: every velocity vanishes (each pair's pull cancels
        // its mirror); the windowed sum agrees with the full one there.
        let n = 64;
        let x: Vec<f64> = (0..n).map(|j| -50.0 + (j as f64 + 0.5) * 100.0 / n as f64).collect();
        let y = vec![0.0; n];
        let (u, v) = Kernel::new(100.0, n, 1.0).velocities(&x, &y);
        assert!(u.iter().chain(&v).all(|a| a.abs() < 1e-12), "{u:?} {v:?}");
        // A marker lifted above a sheet of positive circulation moves in -x,
        // slower than the far field's γ/2 (the blob smooths the jump).
        let mut y2 = y.clone();
        y2[10] = 0.5;
        let (u2, _) = Kernel::new(100.0, n, 1.0).velocities(&x, &y2);
        assert!(u2[10] < 0.0 && u2[10] > -0.5 * GAMMA - 1e-9, "{}", u2[10]);
    }

    #[test]
    fn roll_up_is_deterministic_and_seeded() {
        let p = FootprintParams { sheet_rollup_km: 5.0, sheet_steps: 5, ..FootprintParams::default() };
        let a = roll_up(40.0, &p, &AnimationParams::default(), [1, 2], 0.0);
        assert_eq!(a, roll_up(40.0, &p, &AnimationParams::default(), [1, 2], 0.0));
        assert_ne!(a, roll_up(40.0, &p, &AnimationParams::default(), [1, 3], 0.0));
    }
}
