//! How long the upper states of the auroral lines live, and what a lifetime
//! does to a line whose source changes in time.
//!
//! Lifetimes. An excited state X made at rate P (cm^-3 s^-1) and lost by
//! radiation (Einstein coefficients A_i) and by collisions with the
//! quenchers Q_j (rate coefficients k_j, cm^3 s^-1) has the population
//! equation
//!
//! ```text
//! dn/dt = P(t) - n / tau,    1 / tau = sum_i A_i + sum_j k_j [Q_j]
//! ```
//!
//! so tau is its effective lifetime. The rates are the ones the NCAR GLOW
//! model uses (its `gchem.f90`, compiled from Solomon & Abreu 1989, J.
//! Geophys. Res. 94, 6817, and Solomon 2017):
//! - **O(1D)** (630.0 + 636.4 nm): A = 5.63e-3 + 1.879e-3 s^-1 (Storey &
//!   Zeippen 2000, `crate::physics::chemistry::einstein`); quenched by
//!   N2 at 2.0e-11 exp(107.8 / T), O2 at 2.9e-11 exp(67.5 / T) and O at
//!   3e-12 cm^3/s. Some 1.5 s at 150 km, 10 s at 200 km, 80-110 s at 300 km.
//! - **O(1S)** (557.7 nm): A = 1.06 s^-1 at 557.7 nm plus 0.045 s^-1 at
//!   297.2 nm; quenched by O2 at 4e-12 exp(-865 / T) and by O at 2e-14
//!   cm^3/s: about 0.9 s at every auroral altitude.
//! - N2+(B) (427.8 nm) and N2(B) (the 1P bands) radiate in microseconds:
//!   lifetime 0 here.
//!
//! The quenching by ambient electrons (8.1e-10 (Te / 300)^0.5 for O(1D))
//! needs an electron density the neutral atmosphere does not give; it is
//! left out (it shortens O(1D) by some 20 % at 300 km). The neutral
//! temperature T is the one the atmosphere's density scale height implies
//! for a gas in hydrostatic equilibrium, `T = m g H / k` (mean molecular
//! mass m of N2, O2 and O, gravity g at that altitude): where T rises with
//! altitude this reads up to some 25 % low, which moves the exp(107.8 / T)
//! factor by under 5 %.
//!
//! Response to a modulated source. With `P(t) = P0 (1 + a sin(omega t))`
//! the population is the convolution of P with the decay kernel
//! `exp(-t / tau)`. For the sine, try `n = n0 + n1 sin(omega t - phi)`:
//!
//! ```text
//! n0 / tau = P0
//! n1 omega cos(omega t - phi) + n1 sin(omega t - phi) / tau = P0 a sin(omega t)
//! ```
//!
//! Writing `sin(omega t) = sin((omega t - phi) + phi)` and matching the sine
//! and cosine terms: `n1 / tau = P0 a cos(phi)` and `n1 omega = P0 a sin(phi)`,
//! so `tan(phi) = omega tau` and `n1 = P0 a tau / sqrt(1 + (omega tau)^2)`.
//! The emission `A n` (yield times source in the steady state, `A tau P0`)
//! so keeps the fraction `1 / sqrt(1 + (omega tau)^2)` of the source's
//! modulation, lagging it by `atan(omega tau)`: [`response`]. This is exact
//! once the start-up transient `exp(-t / tau)` has died away, which a
//! closed-form motion that has always been running assumes.

use crate::physics::atmosphere::{Atmosphere, Composition};
use crate::util::fmath;

/// O(1D) radiative rate, 630.0 + 636.4 nm, and O(1S)'s, 557.7 + 297.2
/// nm, 1/s (`crate::physics::chemistry::einstein`).
pub use crate::physics::chemistry::einstein::{A_1D, A_1S};

/// Boltzmann constant, J/K.
const K_B: f64 = 1.380_649e-23;
/// Atomic mass unit, kg.
const AMU: f64 = 1.660_539_07e-27;
/// Gravity at the surface, m/s^2, and the Earth's radius, km.
const G0: f64 = 9.80665;
const R_EARTH_KM: f64 = 6371.0;

/// Effective lifetimes of the upper states at one altitude, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lifetimes {
    /// O(1S), the upper state of 557.7 nm.
    pub o1s_s: f64,
    /// O(1D), the upper state of 630.0 and 636.4 nm.
    pub o1d_s: f64,
}

/// The neutral temperature implied by the density scale height `h_scale_km`
/// at `h_km` for composition `c`, K (module doc).
pub fn scale_height_temperature(c: &Composition, h_km: f64, h_scale_km: f64) -> f64 {
    let m = (28.0134 * c.n2 + 31.9988 * c.o2 + 15.9994 * c.o) / c.total() * AMU;
    let g = G0 * fmath::powi(R_EARTH_KM / (R_EARTH_KM + h_km), 2);
    m * g * h_scale_km * 1e3 / K_B
}

/// The lifetimes at `h_km` for the densities `c` (cm^-3) and temperature
/// `t_k`: the module doc's rates.
pub fn lifetimes_of(c: &Composition, t_k: f64) -> Lifetimes {
    let q_1d = 2.0e-11 * fmath::exp(107.8 / t_k) * c.n2 + 2.9e-11 * fmath::exp(67.5 / t_k) * c.o2 + 3e-12 * c.o;
    let q_1s = 4e-12 * fmath::exp(-865.0 / t_k) * c.o2 + 2e-14 * c.o;
    Lifetimes { o1s_s: 1.0 / (A_1S + q_1s), o1d_s: 1.0 / (A_1D + q_1d) }
}

/// The lifetimes at `h_km` in the atmosphere `atm`.
pub fn lifetimes(atm: &Atmosphere, h_km: f64) -> Lifetimes {
    let c = atm.composition(h_km);
    lifetimes_of(&c, scale_height_temperature(&c, h_km, atm.scale_height(h_km)))
}

/// The response of a line of lifetime `tau_s` to a source modulated at
/// angular frequency `omega` (rad/s): the kept fraction of the modulation
/// `1 / sqrt(1 + (omega tau)^2)` and the phase lag `atan(omega tau)`, rad
/// (module doc).
#[inline]
pub fn response(omega: f64, tau_s: f64) -> (f64, f64) {
    let x = omega * tau_s;
    (1.0 / (1.0 + x * x).sqrt(), fmath::atan(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn response_is_the_solution_of_the_decay_equation() {
        // Integrate dn/dt = P(t) - n/tau with P = 1 + a sin(omega t) over
        // 40 lifetimes (the transient is gone: e^-40) by RK4 with 1e-3 tau
        // steps, and fit the last period: amplitude and lag to 1e-6.
        for (tau, period) in [(0.9, 8.0), (30.0, 8.0), (5.0, 31.4)] {
            let omega = std::f64::consts::TAU / period;
            let a = 0.6;
            let p = |t: f64| 1.0 + a * fmath::sin(omega * t);
            let f = |t: f64, n: f64| p(t) - n / tau;
            let dt = 1e-3 * tau.min(period);
            let t_end = 40.0 * tau + 3.0 * period;
            let (mut t, mut n) = (0.0, tau);
            let (mut s, mut c, mut k) = (0.0, 0.0, 0);
            while t < t_end {
                let k1 = f(t, n);
                let k2 = f(t + 0.5 * dt, n + 0.5 * dt * k1);
                let k3 = f(t + 0.5 * dt, n + 0.5 * dt * k2);
                let k4 = f(t + dt, n + dt * k3);
                n += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                t += dt;
                if t > t_end - period {
                    // Fourier coefficients of n / (tau a) over one period.
                    s += (n / tau - 1.0) / a * fmath::sin(omega * t);
                    c += (n / tau - 1.0) / a * fmath::cos(omega * t);
                    k += 1;
                }
            }
            let (s, c) = (2.0 * s / k as f64, 2.0 * c / k as f64);
            let (gain, lag) = response(omega, tau);
            // n1 sin(wt - phi) = n1 cos(phi) sin(wt) - n1 sin(phi) cos(wt).
            assert!((fmath::hypot(s, c) - gain).abs() < 2e-3, "{tau} {period}: {} vs {gain}", fmath::hypot(s, c));
            assert!((fmath::atan2(-c, s) - lag).abs() < 2e-3, "{tau} {period}: {} vs {lag}", fmath::atan2(-c, s));
        }
    }

    #[test]
    fn lifetimes_match_the_glow_figures_of_the_note() {
        // GLOW at E0 = 3 keV (with electron quenching): O(1D) 1.5 s at
        // 150 km, 10 s at 200 km, 40 s at 250 km, 80 s at 300 km; O(1S)
        // 0.85-0.90 s. Without the electrons (module doc) and on our
        // atmosphere, within a factor 1.6 of the O(1D) figures (the
        // temperature and densities differ from GLOW's MSIS call), and
        // O(1S) within 10 %.
        let atm = Atmosphere::nrlmsis21();
        for (h, want) in [(150.0, 1.5), (200.0, 10.0), (250.0, 40.0), (300.0, 80.0)] {
            let l = lifetimes(&atm, h);
            assert!(l.o1d_s / want < 1.6 && want / l.o1d_s < 1.6, "{h} km: O(1D) {} s vs {want}", l.o1d_s);
            assert!((l.o1s_s / 0.88 - 1.0).abs() < 0.1, "{h} km: O(1S) {} s", l.o1s_s);
        }
        // Unquenched limits: 1 / A.
        let empty = Composition { n2: 0.0, o2: 0.0, o: 1e-30 };
        let l = lifetimes_of(&empty, 1000.0);
        assert!((l.o1d_s * A_1D - 1.0).abs() < 1e-12 && (l.o1s_s * A_1S - 1.0).abs() < 1e-12);
    }

    #[test]
    fn scale_height_temperature_is_the_ideal_gas_law() {
        // Pure N2 at the surface with H = 8.721 km: T = m g H / k = 288.15 K
        // (k T / m g for N2 at 15 C is 8.7211 km).
        let c = Composition { n2: 1.0, o2: 0.0, o: 0.0 };
        let t = scale_height_temperature(&c, 0.0, 8.7211);
        assert!((t - 288.15).abs() < 0.05, "{t}");
        // At 300 km gravity is (6371 / 6671)^2 = 0.912 of the surface's.
        let t300 = scale_height_temperature(&c, 300.0, 8.7211);
        assert!((t300 / t - fmath::powi(6371.0f64 / 6671.0, 2)).abs() < 1e-12);
    }
}
