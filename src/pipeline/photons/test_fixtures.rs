//! Photon sets the gathers' tests share: uniform points in a box, loose
//! segments, and beam-like paths of contiguous steps.

use crate::pipeline::deposit::Photon;
use crate::util::fmath;
use crate::util::rng;
use glam::DVec3;
use rand::Rng;

/// `n` point photons uniform in the box [lo, hi]^3, power `[P, P/2, P/4]`.
pub fn uniform_box(n: usize, lo: f64, hi: f64, power: f32, seed: u64) -> Vec<Photon> {
    let mut r = rng::rng(&[seed]);
    (0..n)
        .map(|_| {
            let mut p = [0.0f32; 3];
            for c in &mut p {
                *c = (lo + (hi - lo) * r.random::<f64>()) as f32;
            }
            Photon::point(p, [power, 0.5 * power, 0.25 * power])
        })
        .collect()
}

/// `n` loose beam-like steps of 0 to 1.2 km along a tilted direction in a
/// 6 km box, every tenth a point, power `[1e19, 5e18, 2e18]` each.
pub fn segment_photons(n: usize, seed: u64) -> Vec<Photon> {
    let mut r = rng::rng(&[seed]);
    (0..n)
        .map(|i| {
            let a = DVec3::new(r.random::<f64>() * 6.0, r.random::<f64>() * 6.0, r.random::<f64>() * 6.0);
            let d = DVec3::new(r.random::<f64>() - 0.5, r.random::<f64>() - 0.5, -2.0).normalize();
            let len = if i % 10 == 0 { 0.0 } else { 1.2 * r.random::<f64>() };
            let b = a + d * len;
            Photon::segment(a.as_vec3().to_array(), b.as_vec3().to_array(), [1e19, 5e18, 2e18])
        })
        .collect()
}

/// One beam-like path: `n` contiguous steps of 0 to 1 km, each 2 to 5
/// degrees off a steep B, power per step proportional to its drop in
/// altitude times a smooth profile (like Fang's per-step deposits).
pub fn beam_path(n: usize, seed: u64) -> Vec<Photon> {
    let mut r = rng::rng(&[seed]);
    let b = DVec3::new(0.0, 0.22, -0.975).normalize();
    let u = b.cross(DVec3::X).normalize();
    let v = b.cross(u);
    let mut p = DVec3::new(3.0, 3.0, 40.0);
    (0..n)
        .map(|_| {
            let s = r.random::<f64>();
            let alpha = (2.0 + 3.0 * r.random::<f64>()).to_radians();
            let beta = std::f64::consts::TAU * r.random::<f64>();
            let q = p + b * s + (u * fmath::cos(beta) + v * fmath::sin(beta)) * s * fmath::tan(alpha);
            let rate = 1.0 + 0.5 * fmath::sin(0.3 * q.z);
            let w = (p.z - q.z) * rate * 1e19;
            let ph = Photon::segment(
                p.as_vec3().to_array(),
                q.as_vec3().to_array(),
                [w as f32, (0.5 * w * (1.0 + 0.01 * q.z)) as f32, (0.2 * w) as f32],
            );
            p = q;
            ph
        })
        .collect()
}
