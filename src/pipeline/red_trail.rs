//! The red trail: O(1D) (630.0 and 636.4 nm) remembers where the aurora was.
//!
//! Model. An upper state of lifetime tau (s) made at rate P(t) obeys
//! `dn/dt = P(t) - n / tau` (`crate::physics::emission::lifetime`); for a
//! source that has always run, `n(t) / tau = int_0^inf P(t - s) exp(-s / tau)
//! / tau ds`: the line's emission at t is its steady-state emission averaged
//! over the past with the density `exp(-s / tau) / tau` (mean lag tau). A
//! curtain moving at v leaves its red about `v tau` behind; the green (O(1S),
//! 0.9 s) and the prompt lines stay with the electrons (GLOW's lifetimes;
//! Solomon & Abreu 1989, J. Geophys. Res. 94, 6817, for the rates).
//!
//! Discretisation. The motion is closed form in t (`crate::pipeline::motion`),
//! so the deposits of an earlier time are one more trace of the beams. Lags
//! `0 = s_0 < ... < s_N` ([`samples`]: `s_k = L (k / N)^2`, `L = tau_max
//! sqrt(N + 1)`, `tau_max = 1 / A` = 129 s the unquenched O(1D) lifetime)
//! cut the past at the midpoints `a_0 = 0`, `a_k = (s_{k-1} + s_k) / 2`,
//! `a_{N+1} = inf`, and the deposits of `t - s_k` stand for `[a_k, a_{k+1})`:
//!
//! ```text
//! E(t) ~ sum_k w_k(tau) S(t - s_k),   w_k = exp(-a_k / tau) - exp(-a_{k+1} / tau)
//! ```
//!
//! The weights telescope to exactly 1 (a still scene keeps its red), and the
//! sum converges to the convolution as N grows.
//!
//! A pulsating patch (`crate::pipeline::motion::Wave`) is a sine at a fixed
//! place, so its part of each interval has a closed form: with `theta_k` its
//! phase at `t - s_k`, `x = omega tau`, `E_a = exp(-a / tau)`,
//!
//! ```text
//! integral_a^b (mean + amp sin(theta_k - omega (s - s_k))) exp(-s / tau) / tau ds
//!   = mean (E_a - E_b) + amp [E_a (sin phi_a - x cos phi_a) - E_b (sin phi_b - x cos phi_b)] / (1 + x^2)
//! phi_a = theta_k + omega (s_k - a),  phi_b = theta_k + omega (s_k - b)
//! ```
//!
//! ([`TrailSample::weight`]): over `[0, inf)` the sinusoid response of
//! `crate::physics::emission::lifetime::response`. The trace at t gives every
//! line (O(1D) with `w_0`), each earlier time only the O(1D) lines with
//! `w_k`; frames stay independent and byte-identical however a sequence is
//! split. Convergence, cost and measurements: docs/physics.md, "The red trail".

use crate::physics::emission::lifetime::A_1D;
use crate::pipeline::motion::Wave;
use crate::util::fmath;

/// The longest O(1D) lifetime, unquenched (`1 / A`), s: about 129 s.
pub const TAU_MAX_S: f64 = 1.0 / A_1D;

/// One sample of the trail: the deposits of time `t - lag_s` stand for the
/// interval of lags `[from_s, to_s)` (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrailSample {
    /// 0 for the bake's own time, then 1..=N.
    pub index: usize,
    pub lag_s: f64,
    pub from_s: f64,
    /// `f64::INFINITY` for the last sample.
    pub to_s: f64,
}

/// The last lag of `n` earlier samples, s: `tau_max sqrt(n + 1)`.
pub fn span_s(n: u32) -> f64 {
    TAU_MAX_S * ((n + 1) as f64).sqrt()
}

/// The bake's own time and `n` earlier ones: lags `L (k / n)^2`, intervals
/// cut at the midpoints (module doc). `n = 0`: one sample holding all lags.
pub fn samples(n: u32) -> Vec<TrailSample> {
    let span = span_s(n);
    let lag = |k: u32| if n == 0 { 0.0 } else { span * fmath::powi(k as f64 / n as f64, 2) };
    (0..=n)
        .map(|k| TrailSample {
            index: k as usize,
            lag_s: lag(k),
            from_s: if k == 0 { 0.0 } else { 0.5 * (lag(k - 1) + lag(k)) },
            to_s: if k == n { f64::INFINITY } else { 0.5 * (lag(k) + lag(k + 1)) },
        })
        .collect()
}

impl TrailSample {
    /// Whether this sample is the bake's own time (the lines without the
    /// trail are kept there only).
    pub fn is_now(&self) -> bool {
        self.index == 0
    }

    /// The weight of this sample's deposit in a line of lifetime `tau_s`:
    /// `exp(-a / tau) - exp(-b / tau)`, or with the source pulsating as
    /// `wave` (its phase at this sample's time) the closed form of the
    /// module doc. A prompt line (tau = 0) follows the source at once: all
    /// of it at lag 0, the flux's modulation at that time.
    pub fn weight(&self, tau_s: f64, wave: Option<&Wave>) -> f64 {
        if tau_s <= 0.0 {
            return if self.is_now() { wave.map_or(1.0, |w| w.at_lifetime(0.0)) } else { 0.0 };
        }
        let e_a = fmath::exp(-self.from_s / tau_s);
        let e_b = if self.to_s.is_finite() { fmath::exp(-self.to_s / tau_s) } else { 0.0 };
        let Some(w) = wave else { return e_a - e_b };
        let x = w.omega * tau_s;
        let part = |e: f64, s: f64| {
            if e == 0.0 {
                return 0.0;
            }
            let (sin, cos) = fmath::sin_cos(w.theta + w.omega * (self.lag_s - s));
            e * (sin - x * cos)
        };
        w.mean * (e_a - e_b) + w.amplitude * (part(e_a, self.from_s) - part(e_b, self.to_s)) / (1.0 + x * x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wave_at(theta: f64, omega: f64) -> Wave {
        let (sin_theta, cos_theta) = fmath::sin_cos(theta);
        Wave { mean: 0.7, amplitude: 0.3, omega, theta, sin_theta, cos_theta }
    }

    #[test]
    fn samples_tile_the_past_and_reach_the_span() {
        for n in [1u32, 2, 8, 16] {
            let s = samples(n);
            assert_eq!(s.len(), n as usize + 1);
            assert_eq!((s[0].lag_s, s[0].from_s), (0.0, 0.0));
            for k in 1..s.len() {
                assert_eq!(s[k].from_s, s[k - 1].to_s, "{n}: the intervals touch");
                assert!(s[k].lag_s > s[k - 1].lag_s && (s[k].from_s..=s[k].to_s).contains(&s[k].lag_s));
            }
            assert!((s[n as usize].lag_s - span_s(n)).abs() < 1e-9 && s[n as usize].to_s.is_infinite());
        }
        // N = 8 reaches three unquenched lifetimes.
        assert!((span_s(8) / TAU_MAX_S - 3.0).abs() < 1e-12);
    }

    #[test]
    fn weights_sum_to_one_for_every_lifetime() {
        // Telescoping: exp(0) - exp(-inf), to the rounding of N + 1 terms.
        for n in [1u32, 3, 8, 16] {
            for tau in [0.0, 0.9, 1.5, 10.0, 40.0, 129.0, 1e4] {
                let sum: f64 = samples(n).iter().map(|s| s.weight(tau, None)).sum();
                assert!((sum - 1.0).abs() < 1e-14, "{n} {tau}: {sum}");
            }
        }
    }

    #[test]
    fn a_still_pulsating_patch_keeps_the_sinusoid_response() {
        // The patch does not move: sample k sees the phase theta - omega s_k,
        // and the intervals' closed forms add up to the response over
        // [0, inf) (`Wave::at_lifetime`, `crate::physics::emission::lifetime::response`).
        for (theta, period) in [(0.3, 6.0), (2.9, 10.0), (-1.0, 20.0)] {
            let omega = std::f64::consts::TAU / period;
            for tau in [0.9, 1.5, 30.0, 100.0] {
                for n in [1u32, 8] {
                    let sum: f64 = samples(n).iter().map(|s| s.weight(tau, Some(&wave_at(theta - omega * s.lag_s, omega)))).sum();
                    let want = wave_at(theta, omega).at_lifetime(tau);
                    assert!((sum - want).abs() < 1e-12, "{theta} {period} {tau} {n}: {sum} vs {want}");
                }
            }
        }
    }

    #[test]
    fn the_sum_converges_to_the_convolution() {
        // S(t) = cos(nu t): the convolution with exp(-s/tau)/tau is
        // (cos(nu t) + x sin(nu t)) / (1 + x^2), x = nu tau. The error of the
        // sum falls as the samples grow (the widest interval ~2 L / N), and
        // at N = 16 is a few per cent of the swing for a drift period of
        // 300 s (the default `drift_period_s`) at every lifetime.
        let nu = std::f64::consts::TAU / 300.0;
        let t = 17.0;
        for tau in [1.5, 10.0, 40.0, 100.0] {
            let x = nu * tau;
            let exact = (fmath::cos(nu * t) + x * fmath::sin(nu * t)) / (1.0 + x * x);
            let err = |n: u32| (samples(n).iter().map(|s| s.weight(tau, None) * fmath::cos(nu * (t - s.lag_s))).sum::<f64>() - exact).abs();
            let (e2, e8, e16) = (err(2), err(8), err(16));
            assert!(e16 < e2, "{tau}: {e2} {e8} {e16}");
            assert!(e16 < 0.06, "{tau}: {e16}");
            assert!(e8 < 0.12, "{tau}: {e8}");
        }
    }

    #[test]
    fn the_mean_lag_is_the_lifetime() {
        // The kernel's mean lag is tau; the samples' mean lag sum w_k s_k
        // approaches it as N grows (module doc). At N = 8 a 1.5 s lifetime
        // sees only the first sample (6 s, weight 1 - exp(-2) of it at 0):
        // 0.54 of tau; from 10 s up, where most of the red lives, within
        // 10 %. At N = 16 (first sample 2 s) within 20 % everywhere.
        let mean = |n: u32, tau: f64| samples(n).iter().map(|s| s.weight(tau, None) * s.lag_s).sum::<f64>() / tau;
        for tau in [1.5, 5.0, 10.0, 40.0, 100.0] {
            let (r8, r16) = (mean(8, tau), mean(16, tau));
            assert!((r8 - 1.0).abs() < 0.5 && (r16 - 1.0).abs() < 0.2, "{tau}: {r8} {r16}");
            assert!((r16 - 1.0).abs() <= (r8 - 1.0).abs(), "{tau}: {r8} {r16}");
            if tau >= 10.0 {
                assert!((r8 - 1.0).abs() < 0.1, "{tau}: {r8}");
            }
        }
    }
}
