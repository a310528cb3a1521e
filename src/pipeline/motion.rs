//! Motion in time: what moves the aurora between frames, closed form in t.
//!
//! Physics. Folds and curls are a sheet of field-aligned current (a charge
//! sheet) drifting at E x B; the sheet behaves as a vortex sheet and rolls up
//! by the Kelvin-Helmholtz instability (Hallinan & Davis 1970; Baranoski et
//! al. 2005 simulate it with beams as superparticles). This crate keeps the
//! cheap analogue, a 2D incompressible fluid on the footprint
//! ([`crate::pipeline::footprint::Fluid`], stable fluids), whose linear growth of a
//! single mode on a vortex sheet is tested against Kelvin-Helmholtz's rate
//! sigma = k dU / 2 (`footprint::tests::kelvin_helmholtz_growth_rate`).
//!
//! Time. Frame N of a sequence is the scene at
//! `t = animation.time_s + (N - 1) / fps` ([`frame_time`]), and every moving
//! part is a smooth closed-form function of t, so a frame far into a show
//! costs one still bake (no history to replay, nothing to checkpoint):
//! - folds: the footprint fluid's initial vortex row travels and breathes,
//!   the fluid is integrated from it for the scene's `footprint.steps`
//!   ([`crate::pipeline::footprint::simulate_at`]); the bend curve travels and changes
//!   shape; the curtain drifts across its axis within `drift_km`;
//! - rays: the start-height and colour noise along the curtain (the rays'
//!   fine structure) run along it at `ray_speed_kms` ([`ray_shift_km`]);
//! - pulsating patches: cells of `pulsation_patch_km` whose electron flux
//!   swings with their own period in `pulsation_period_s` and phase
//!   ([`pulsation`]).
//!
//! Identity. Beam i keeps its index and its random stream in every frame; its
//! start is the same point of the unit square mapped through the frame's
//! footprint by a continuous map ([`crate::pipeline::beams::starts::StartMap`]), so as the
//! footprint moves the beam moves with it and its noise (deflections,
//! energy) moves with the curtain instead of being redrawn.
//!
//! The time scales behind the defaults (AnimationParams): rays up to about
//! 25 km/s along the arc, spirals drifting about 4 km/s, surges about 2 km/s,
//! pulsating aurora with periods of a few s to 20 s, most often 6-10 s.

use crate::scene::AnimationParams;
use crate::util::fmath;
use crate::util::rng;

/// Seconds from `animation.time_s` to frame `frame` (frame 1 is at time_s).
pub fn frame_time(anim: &AnimationParams, frame: i64) -> f64 {
    anim.time_s + (frame - 1) as f64 / anim.fps
}

/// The scene's animation at frame `frame`: the same parameters with
/// `time_s` moved to that frame's time.
pub fn at_frame(anim: &AnimationParams, frame: i64) -> AnimationParams {
    AnimationParams { time_s: frame_time(anim, frame), ..anim.clone() }
}

/// How far the rays' pattern has run along the curtain at `time_s`, km: the
/// along-curtain noise is read at `u - ray_shift_km`.
pub fn ray_shift_km(anim: &AnimationParams) -> f64 {
    anim.ray_speed_kms * anim.time_s
}

/// Multiplier of the electron flux at world (x, y) km at `anim.time_s`, in
/// [1 - pulsation, 1]: the plane is tiled with square patches of side
/// `pulsation_patch_km`; patch (a, b) has its own period T in
/// `pulsation_period_s` and phase phi (hashed from the seed and the patch),
/// and inside it the flux is `1 - p w(x, y) (1 - s(t)) ` with
/// `s = (1 + sin(2 pi t / T + phi)) / 2` and a window
/// `w = sin^2(pi fx) sin^2(pi fy)` (fx, fy the position in the patch), so
/// patch edges never pulse and the field is continuous in space and time.
/// 1 everywhere when `pulsation` is 0.
pub fn pulsation(anim: &AnimationParams, seed: u64, x: f64, y: f64) -> f64 {
    if anim.pulsation <= 0.0 {
        return 1.0;
    }
    let (gx, gy) = (x / anim.pulsation_patch_km, y / anim.pulsation_patch_km);
    let (a, b) = (gx.floor(), gy.floor());
    let (fx, fy) = (gx - a, gy - b);
    let (period, phase) = patch_period_phase(anim, seed, a, b);
    let s = 0.5 * (1.0 + fmath::sin(std::f64::consts::TAU * anim.time_s / period + phase));
    let w = fmath::powi(fmath::sin(std::f64::consts::PI * fx) * fmath::sin(std::f64::consts::PI * fy), 2);
    1.0 - anim.pulsation * w * (1.0 - s)
}

/// A pulsating patch's flux at one place as a wave in time:
/// `m(t) = mean + amplitude sin(theta)` with `theta = omega t + phi`, the
/// closed form of [`pulsation`] written as a sine (mean `1 - p w / 2`,
/// amplitude `p w / 2`): what a line of lifetime tau follows with
/// [`Wave::at_lifetime`] (`crate::physics::emission::lifetime`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    pub mean: f64,
    pub amplitude: f64,
    /// Angular frequency, rad/s.
    pub omega: f64,
    /// Phase at the frame's time, rad, and its sine and cosine.
    pub theta: f64,
    pub sin_theta: f64,
    pub cos_theta: f64,
}

impl Wave {
    /// The modulation a line of upper-state lifetime `tau_s` shows at the
    /// frame's time: `mean + amplitude g sin(theta - lag)` with `(g, lag)`
    /// the first-order response ([`crate::physics::emission::lifetime::response`]). At tau = 0
    /// it is the flux itself. With x = omega tau, `cos(lag) = g` and
    /// `sin(lag) = x g`, so `g sin(theta - lag) = (sin theta - x cos theta)
    /// / (1 + x^2)`: no trigonometry per call.
    #[inline]
    pub fn at_lifetime(&self, tau_s: f64) -> f64 {
        let x = self.omega * tau_s;
        self.mean + self.amplitude * (self.sin_theta - x * self.cos_theta) / (1.0 + x * x)
    }
}

/// [`pulsation`] at world (x, y) km as a [`Wave`]; `None` when `pulsation`
/// is 0 (nothing moves).
pub fn pulsation_wave(anim: &AnimationParams, seed: u64, x: f64, y: f64) -> Option<Wave> {
    if anim.pulsation <= 0.0 {
        return None;
    }
    let (gx, gy) = (x / anim.pulsation_patch_km, y / anim.pulsation_patch_km);
    let (a, b) = (gx.floor(), gy.floor());
    let (fx, fy) = (gx - a, gy - b);
    let (period, phase) = patch_period_phase(anim, seed, a, b);
    let w = fmath::powi(fmath::sin(std::f64::consts::PI * fx) * fmath::sin(std::f64::consts::PI * fy), 2);
    let omega = std::f64::consts::TAU / period;
    let half = 0.5 * anim.pulsation * w;
    let theta = omega * anim.time_s + phase;
    let (sin_theta, cos_theta) = fmath::sin_cos(theta);
    Some(Wave { mean: 1.0 - half, amplitude: half, omega, theta, sin_theta, cos_theta })
}

/// Patch (a, b)'s period in `pulsation_period_s` and phase, hashed from the
/// seed and the patch.
fn patch_period_phase(anim: &AnimationParams, seed: u64, a: f64, b: f64) -> (f64, f64) {
    let h = rng::stream_seed(&[seed, rng::tag::PULSATION, a as i64 as u64, b as i64 as u64]);
    let unit = |bits: u64| (bits >> 11) as f64 / (1u64 << 53) as f64;
    let [t0, t1] = anim.pulsation_period_s;
    (t0 + (t1 - t0) * unit(h), std::f64::consts::TAU * unit(rng::splitmix64(h)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_spaced_by_one_over_fps() {
        let a = AnimationParams { fps: 30.0, time_s: 2.0, ..AnimationParams::default() };
        assert_eq!(frame_time(&a, 1), 2.0);
        assert!((frame_time(&a, 31) - 3.0).abs() < 1e-12);
        assert_eq!(at_frame(&a, 4).time_s, frame_time(&a, 4));
    }

    #[test]
    fn pulsation_is_bounded_periodic_and_off_at_zero() {
        let mut a = AnimationParams { pulsation: 0.8, pulsation_period_s: [7.0, 7.0], ..AnimationParams::default() };
        let (mut lo, mut hi) = (f64::MAX, f64::MIN);
        for k in 0..4000 {
            a.time_s = k as f64 * 0.01;
            let m = pulsation(&a, 3, 12.3, -40.1);
            lo = lo.min(m);
            hi = hi.max(m);
            // Period 7 s exactly: the value repeats (to rounding of sin).
            let b = AnimationParams { time_s: a.time_s + 7.0, ..a.clone() };
            assert!((pulsation(&b, 3, 12.3, -40.1) - m).abs() < 1e-9);
        }
        assert!(lo >= 1.0 - 0.8 - 1e-12 && hi <= 1.0);
        // The window at (12.3, -40.1) in 25 km patches is w > 0.1, so the
        // swing over a full period exceeds 0.8 * 0.1.
        assert!(hi - lo > 0.08, "{lo} {hi}");
        // Patch edges do not pulse.
        assert!((pulsation(&a, 3, 25.0, 10.0) - 1.0).abs() < 1e-12);
        a.pulsation = 0.0;
        assert_eq!(pulsation(&a, 3, 12.3, -40.1), 1.0);
    }

    #[test]
    fn the_wave_is_the_pulsation_and_follows_lifetimes() {
        let mut a = AnimationParams { pulsation: 0.7, pulsation_period_s: [6.0, 9.0], ..AnimationParams::default() };
        for k in 0..300 {
            a.time_s = 0.37 * k as f64;
            let (x, y) = (3.0 + 0.5 * k as f64, -7.0);
            let w = pulsation_wave(&a, 5, x, y).unwrap();
            // Lifetime 0: the flux itself (sin written two ways: rounding).
            assert!((w.at_lifetime(0.0) - pulsation(&a, 5, x, y)).abs() < 1e-12);
            // A long lifetime keeps the mean: 1e5 s at a 9 s period keeps
            // 1.4e-4 of the swing.
            assert!((w.at_lifetime(1e5) - w.mean).abs() <= 1.5e-4 * w.amplitude + 1e-15);
            // The closed form without trigonometry is the response law.
            for tau in [0.9, 30.0] {
                let (g, lag) = crate::physics::emission::lifetime::response(w.omega, tau);
                assert!((w.at_lifetime(tau) - (w.mean + w.amplitude * g * fmath::sin(w.theta - lag))).abs() < 1e-12);
            }
            let period = std::f64::consts::TAU / w.omega;
            assert!((6.0..=9.0).contains(&period));
        }
        a.pulsation = 0.0;
        assert!(pulsation_wave(&a, 5, 1.0, 1.0).is_none());
    }
}
