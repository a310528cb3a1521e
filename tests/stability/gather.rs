//! Where the density estimate fails: a gather radius far below the photon
//! spacing (noise) or far above the curtain's thickness (blur), on a
//! synthetic sheet of photons whose true emission profile is known.
//!
//! The sheet: `n` photons of power 1, uniform in x and z over a square of
//! side `L`, normal in y with standard deviation `s` (the curtain's
//! half-thickness). The true emission is `eta(y) = n / L^2 phi_s(y)`
//! (`phi_s` the normal density). The kd-tree estimate with a Gaussian kernel
//! of sd r (cutoff 6, where the truncated mass is 2e-7 of the total, below
//! every tolerance here) has, away from the square's edges,
//! - mean `n / L^2 phi_sqrt(s^2 + r^2)(y)` (Gaussians convolve): the blur;
//! - variance `n / L^2 phi_sqrt(s^2 + r^2 / 2)(y) / ((4 pi)^(3/2) r^3) - n / L^4 phi_sqrt(s^2 + r^2)(y)^2`
//!   (the square of a Gaussian kernel of sd r is `1 / ((4 pi)^(3/2) r^3)`
//!   times one of sd `r / sqrt 2`): the noise.
//!
//! So the expected squared relative RMS error over sample points is
//! `sum (bias^2 + var) / sum eta^2`, which falls with r while noise
//! dominates and rises once blur does. The test measures the curve, checks
//! it against this prediction, and asserts its shape: up at both ends, a
//! minimum in between, between the photon spacing and the thickness.

use aurora::pipeline::deposit::Photon;
use aurora::pipeline::photons::{kdtree::PhotonMap, kernel::Kernel};
use aurora::util::fmath;
use glam::DVec3;
use rand::Rng;

/// A standard normal deviate by Box-Muller (no extra crate needed).
fn normal(r: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - r.random::<f64>(); // (0, 1]
    let u2: f64 = r.random();
    (-2.0 * fmath::ln(u1)).sqrt() * fmath::cos(2.0 * std::f64::consts::PI * u2)
}

const N: usize = 100_000;
const L: f64 = 40.0; // km, side of the square in x and z
const S: f64 = 0.5; // km, sd of the sheet across (y)
const CUTOFF: f64 = 6.0;

fn phi(y: f64, sd: f64) -> f64 {
    fmath::exp(-0.5 * fmath::powi(y / sd, 2)) / (sd * (2.0 * std::f64::consts::PI).sqrt())
}

fn sheet() -> Vec<Photon> {
    let mut r = aurora::util::rng::rng(&[20_140, 6]);
    (0..N)
        .map(|_| {
            let x = (r.random::<f64>() - 0.5) * L;
            let z = (r.random::<f64>() - 0.5) * L;
            let y = S * normal(&mut r);
            Photon::point([x as f32, y as f32, z as f32], [1.0; 3])
        })
        .collect()
}

/// Sample points: 8 x 8 positions in x, z over the central 10 km (15 km
/// from every edge: beyond the reach 6 r of every radius tested), and 25
/// across the sheet, y in [-3 s, 3 s].
fn points() -> Vec<DVec3> {
    let mut p = Vec::new();
    for i in 0..8 {
        for k in 0..8 {
            for j in 0..25 {
                let x = -5.0 + 10.0 * (i as f64 + 0.5) / 8.0;
                let z = -5.0 + 10.0 * (k as f64 + 0.5) / 8.0;
                let y = -3.0 * S + 6.0 * S * j as f64 / 24.0;
                p.push(DVec3::new(x, y, z));
            }
        }
    }
    p
}

#[test]
fn radius_error_curve_has_noise_and_blur_ends_and_a_minimum_between() {
    let photons = sheet();
    let map = PhotonMap::new(&photons);
    let pts = points();
    let density = N as f64 / (L * L); // photons per km^2 of sheet
    let truth = |y: f64| density * phi(y, S);
    let sum_truth2: f64 = pts.iter().map(|p| fmath::powi(truth(p.y), 2)).sum();
    // Photon spacing at the sheet's middle: (photons per km^3)^(-1/3).
    let spacing = fmath::powf(density * phi(0.0, S), -1.0 / 3.0);
    let thickness = 2.0 * S;
    let radii = [0.02, 0.05, 0.1, 0.2, 0.35, 0.6, 1.0, 1.6, 2.4];
    assert!(radii[0] < 0.25 * spacing && radii[radii.len() - 1] > 2.0 * thickness);
    assert!(CUTOFF * radii[radii.len() - 1] <= 15.0, "sample points must stay clear of the edges");

    let mut measured = Vec::new();
    for &r in &radii {
        let k = Kernel::new(r, CUTOFF);
        let mut num = 0.0;
        for p in &pts {
            let e = map.estimate(*p, &k)[0];
            num += fmath::powi(e - truth(p.y), 2);
        }
        let err = (num / sum_truth2).sqrt();
        // The prediction.
        let norm_k2 = 1.0 / (fmath::powf(4.0 * std::f64::consts::PI, 1.5) * r * r * r);
        let mut pred = 0.0;
        for p in &pts {
            let mean = density * phi(p.y, (S * S + r * r).sqrt());
            let var = density * phi(p.y, (S * S + 0.5 * r * r).sqrt()) * norm_k2 - mean * mean / N as f64;
            pred += fmath::powi(mean - truth(p.y), 2) + var;
        }
        let pred = (pred / sum_truth2).sqrt();
        // Photons expected inside one kernel (within r) at the middle.
        let per_kernel = density * phi(0.0, S) * 4.0 / 3.0 * std::f64::consts::PI * fmath::powi(r, 3);
        eprintln!("r = {r:5.2} km: error {err:.4} (predicted {pred:.4}), {per_kernel:.2} photons within r");
        measured.push((r, err, pred, per_kernel));
    }
    eprintln!("photon spacing {spacing:.3} km, sheet thickness 2 s = {thickness} km");

    // Against the prediction where the estimate's error has a well-behaved
    // distribution: with at least ~3 photons per kernel the squared error
    // is an average over 1600 points whose noise is correlated only within
    // r, so its relative spread is a few percent; where blur dominates it
    // is deterministic. With fewer photons per kernel the error is a sum of
    // rare spikes (a heavy tail): only its order of magnitude is stable
    // (checked by the shape assertions below). Tolerance 15 % on the RMS.
    for &(r, err, pred, per_kernel) in &measured {
        if per_kernel >= 3.0 {
            assert!((err / pred - 1.0).abs() < 0.15, "r = {r}: measured {err} vs predicted {pred}");
        }
    }
    // The shape: a minimum strictly inside, between a quarter of the photon
    // spacing and the thickness; both ends at least twice the minimum.
    let (imin, &(rmin, emin, _, _)) = measured.iter().enumerate().min_by(|a, b| a.1 .1.total_cmp(&b.1 .1)).unwrap();
    assert!(imin > 0 && imin < measured.len() - 1, "minimum at an end: {measured:?}");
    assert!(rmin > 0.25 * spacing && rmin < thickness, "minimum at r = {rmin}: {measured:?}");
    assert!(measured[0].1 > 2.0 * emin, "noise end: {measured:?}");
    assert!(measured[measured.len() - 1].1 > 2.0 * emin, "blur end: {measured:?}");
    // Monotone on each side of the minimum (noise falls, blur grows).
    for w in measured[..=imin].windows(2) {
        assert!(w[1].1 < w[0].1, "noise side not falling: {measured:?}");
    }
    for w in measured[imin..].windows(2) {
        assert!(w[1].1 > w[0].1, "blur side not rising: {measured:?}");
    }
}
