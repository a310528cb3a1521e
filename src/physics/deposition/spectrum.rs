//! The precipitating electrons' energy spectra at the top of the
//! atmosphere, and the quadrature nodes Fang et al. 2010 is integrated
//! over ([`Spectrum::energy_nodes`], `crate::physics::deposition::fang`).
//!
//! - **Maxwellian** of characteristic energy E0: number flux per energy
//!   `phi(E) ~ E exp(-E / E0)`, mean energy 2 E0 (the diffuse aurora and an
//!   arc's soft body).
//! - **Monoenergetic** at E: every electron the same energy (the limit of
//!   a strong acceleration over a cold source).
//! - **Accelerated** (Evans 1974, J. Geophys. Res. 79, 2853): a source
//!   Maxwellian of thermal energy `kT = E0` accelerated downward through a
//!   field-aligned potential drop `e Phi`; Liouville's theorem shifts the
//!   distribution, `phi(E) ~ E exp(-(E - e Phi) / E0)` for `E >= e Phi`,
//!   none below (the inverted-V's peaked spectrum). With
//!   `N0 = n sqrt(kT / 2 pi m)` the source's one-way flux and `x = e Phi / kT`,
//!   the flux through the ionosphere with every pitch angle admitted
//!   (mirror ratio R -> infinity) is, in closed form,
//!
//! ```text
//! number flux  N = N0 (1 + x)
//! energy flux  Q = N0 kT (x^2 + 2 x + 2)
//! ```
//!
//!   and the mean energy `kT (x^2 + 2x + 2) / (1 + x)`, `2 kT` at `x = 0`.
//! - **Knight 1973** (Planet. Space Sci. 21, 741), the current a drop
//!   drives through a finite mirror ratio R = B_ionosphere / B_source:
//!   `j = e N0 [R - (R - 1) exp(-x / (R - 1))]` ([`knight_number_flux`]),
//!   `N0 (1 + x)` while `x << R`, saturating at `R N0`.
//!
//! Fang 2010 is monoenergetic, so a spectrum deposits `int w(E) D_E(m) dE`
//! with `w(E) = E phi(E) / Q` its energy-flux density: [`Spectrum::energy_nodes`]
//! gives the nodes and weights of that integral (weights summing to 1),
//! [`Spectrum::sample_energy`] one energy drawn from `w` (the `sampled`
//! deposition's beams), both in closed forms of the Gamma distribution.

use crate::util::fmath;
use rand::Rng;

/// Quadrature over `x = (E - e Phi) / E0`: trapezoid on [0, X_MAX] (the
/// Gamma(3) mass beyond 45 is `e^-45 45^2 / 2`, about 3e-17).
pub const X_MAX: f64 = 45.0;
/// Trapezoid intervals over [0, X_MAX].
pub const N_X: usize = 450;

/// Electron mass, kg.
const M_E_KG: f64 = 9.109_383_7e-31;
/// One keV in joules.
const J_PER_KEV: f64 = 1.602_176_634e-16;
/// The elementary charge, C.
const E_CHARGE_C: f64 = 1.602_176_634e-19;

/// One electron spectrum at the top of the atmosphere (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spectrum {
    /// Characteristic energy E0, keV.
    Maxwellian { e0_kev: f64 },
    /// Every electron at `e_kev`.
    Monoenergetic { e_kev: f64 },
    /// A source Maxwellian of thermal energy `e0_kev` accelerated through
    /// a drop of `potential_kv` kV (Evans 1974).
    Accelerated { e0_kev: f64, potential_kv: f64 },
}

impl Spectrum {
    /// The number flux per unit energy, `phi(E)`, in units of the source's
    /// one-way flux N0 per keV (a Maxwellian's and the accelerated
    /// spectrum's; a monoenergetic spectrum has no density: 0).
    pub fn number_flux_density(&self, e_kev: f64) -> f64 {
        match *self {
            Spectrum::Maxwellian { e0_kev } => Spectrum::Accelerated { e0_kev, potential_kv: 0.0 }.number_flux_density(e_kev),
            Spectrum::Monoenergetic { .. } => 0.0,
            Spectrum::Accelerated { e0_kev, potential_kv } => {
                if e_kev < potential_kv {
                    0.0
                } else {
                    e_kev * fmath::exp(-(e_kev - potential_kv) / e0_kev) / (e0_kev * e0_kev)
                }
            }
        }
    }

    /// Number flux in units of N0, closed form (Evans 1974): `1 + x`.
    pub fn number_flux(&self) -> f64 {
        match *self {
            Spectrum::Maxwellian { .. } => 1.0,
            Spectrum::Monoenergetic { .. } => 1.0,
            Spectrum::Accelerated { e0_kev, potential_kv } => 1.0 + potential_kv / e0_kev,
        }
    }

    /// Energy flux in units of N0 keV, closed form (Evans 1974):
    /// `kT (x^2 + 2x + 2)`; a monoenergetic spectrum's is its energy.
    pub fn energy_flux(&self) -> f64 {
        match *self {
            Spectrum::Maxwellian { e0_kev } => 2.0 * e0_kev,
            Spectrum::Monoenergetic { e_kev } => e_kev,
            Spectrum::Accelerated { e0_kev, potential_kv } => {
                let x = potential_kv / e0_kev;
                e0_kev * (x * x + 2.0 * x + 2.0)
            }
        }
    }

    /// Mean energy of the electrons, keV.
    pub fn mean_energy_kev(&self) -> f64 {
        self.energy_flux() / self.number_flux()
    }

    /// Nodes `(E keV, weight)` of `int w(E) f(E) dE`, `w` the spectrum's
    /// energy-flux density, weights summing to 1 (module documentation):
    /// a Maxwellian's and the accelerated spectrum's the trapezoid over
    /// `x = (E - e Phi) / E0` in `(0, X_MAX]` of `(e Phi + x E0)^2 e^-x`
    /// (normalised so the total is exact whatever the quadrature's error;
    /// the node at x = 0 carries `(e Phi)^2 / 2`, nothing for a Maxwellian);
    /// a monoenergetic spectrum's, its one energy.
    pub fn energy_nodes(&self) -> Vec<(f64, f64)> {
        let (e0, phi) = match *self {
            Spectrum::Monoenergetic { e_kev } => return vec![(e_kev, 1.0)],
            Spectrum::Maxwellian { e0_kev } => (e0_kev, 0.0),
            Spectrum::Accelerated { e0_kev, potential_kv } => (e0_kev, potential_kv),
        };
        let dx = X_MAX / N_X as f64;
        let mut nodes: Vec<(f64, f64)> = Vec::with_capacity(N_X + 1);
        if phi > 0.0 {
            nodes.push((phi, 0.25 * fmath::powi(phi / e0, 2)));
        }
        nodes.extend((1..=N_X).map(|i| {
            let x = i as f64 * dx;
            let end = if i == N_X { 0.5 } else { 1.0 };
            // w ~ (phi + x E0)^2 e^-x, in units of E0^2; for a Maxwellian
            // x^2 e^-x / 2 (the same nodes and weights, bit for bit, as
            // before the accelerated spectrum existed).
            let w = if phi > 0.0 { 0.5 * fmath::powi(phi / e0 + x, 2) * fmath::exp(-x) } else { 0.5 * x * x * fmath::exp(-x) };
            (phi + x * e0, w * end)
        }));
        let sum: f64 = nodes.iter().map(|n| n.1).sum();
        nodes.iter_mut().for_each(|n| n.1 /= sum);
        nodes
    }

    /// One energy drawn from the energy-flux density `w(E)` (so beams of
    /// equal power carry the spectrum's energy flux): a Maxwellian's is
    /// Gamma(3, E0) (three uniforms); the accelerated spectrum's
    /// `w ~ (e Phi + x)^2 e^{-x / E0}` is the mixture of Gamma(1), Gamma(2)
    /// and Gamma(3) of E0 in the proportions `x^2 : 2x : 2` shifted by
    /// `e Phi` (one uniform for the part, three more); a monoenergetic
    /// spectrum's is its energy (no draw).
    pub fn sample_energy(&self, r: &mut impl Rng) -> f64 {
        match *self {
            Spectrum::Maxwellian { e0_kev } => gamma(3, e0_kev, r),
            Spectrum::Monoenergetic { e_kev } => e_kev,
            Spectrum::Accelerated { e0_kev, potential_kv } => {
                let x = potential_kv / e0_kev;
                let (a, b, c) = (x * x, 2.0 * x, 2.0);
                let u = r.random::<f64>() * (a + b + c);
                let k = if u < a {
                    1
                } else if u < a + b {
                    2
                } else {
                    3
                };
                let g = [r.random::<f64>(), r.random::<f64>(), r.random::<f64>()];
                potential_kv - e0_kev * g[..k].iter().map(|&v| fmath::ln(1.0 - v)).sum::<f64>()
            }
        }
    }
}

/// Gamma(k, scale) for integer k: `-scale ln(prod (1 - U_i))` (1 - U lies
/// in (0, 1], so the logarithm is finite).
fn gamma(k: usize, scale: f64, r: &mut impl Rng) -> f64 {
    let p: f64 = (0..k).map(|_| 1.0 - r.random::<f64>()).product();
    -scale * fmath::ln(p)
}

/// The source's one-way number flux `N0 = n sqrt(kT / 2 pi m)`, electrons
/// cm^-2 s^-1, for a density `n_cm3` cm^-3 and thermal energy `kt_kev`.
pub fn one_way_flux(n_cm3: f64, kt_kev: f64) -> f64 {
    n_cm3 * (kt_kev * J_PER_KEV / (std::f64::consts::TAU * M_E_KG)).sqrt() * 100.0
}

/// Knight's (1973) number flux of electrons through the ionosphere,
/// cm^-2 s^-1, from a source Maxwellian (`n_cm3`, `kt_kev`) through a drop
/// of `potential_kv` with mirror ratio `mirror_ratio` > 1 (module
/// documentation).
pub fn knight_number_flux(n_cm3: f64, kt_kev: f64, potential_kv: f64, mirror_ratio: f64) -> f64 {
    let (r, x) = (mirror_ratio, potential_kv / kt_kev);
    one_way_flux(n_cm3, kt_kev) * (r - (r - 1.0) * fmath::exp(-x / (r - 1.0)))
}

/// Knight's field-aligned current density, uA/m^2 ([`knight_number_flux`]
/// times the elementary charge).
pub fn knight_current_ua_m2(n_cm3: f64, kt_kev: f64, potential_kv: f64, mirror_ratio: f64) -> f64 {
    knight_number_flux(n_cm3, kt_kev, potential_kv, mirror_ratio) * 1e4 * E_CHARGE_C * 1e6
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// Simpson over [a, b] in n (even) intervals.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        let s: f64 = (1..n).map(|k| f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 }).sum();
        (f(a) + f(b) + s) * h / 3.0
    }

    #[test]
    fn the_accelerated_spectrum_carries_evans_fluxes() {
        // Evans 1974: N = N0 (1 + x), Q = N0 kT (x^2 + 2x + 2), from the
        // spectrum's own density integrated by brute force (Simpson, 2e5
        // intervals to 60 kT above the drop); within 1 %.
        for (e0, phi) in [(0.5, 0.0), (0.5, 5.0), (1.0, 8.0), (2.0, 3.0), (0.3, 12.0)] {
            let s = Spectrum::Accelerated { e0_kev: e0, potential_kv: phi };
            let hi = phi + 60.0 * e0;
            let n = simpson(|e| s.number_flux_density(e), phi, hi, 200_000);
            let q = simpson(|e| e * s.number_flux_density(e), phi, hi, 200_000);
            let x = phi / e0;
            assert!((n / (1.0 + x) - 1.0).abs() < 0.01, "N {n} against {}", 1.0 + x);
            assert!((q / (e0 * (x * x + 2.0 * x + 2.0)) - 1.0).abs() < 0.01, "Q {q}");
            assert!((n / s.number_flux() - 1.0).abs() < 0.01 && (q / s.energy_flux() - 1.0).abs() < 0.01);
        }
        // A deliberately wrong model (the Maxwellian not shifted, only cut
        // at the drop) misses the closed form by far more than 1 %.
        let (e0, phi) = (1.0, 8.0);
        let cut = |e: f64| if e < phi { 0.0 } else { e * fmath::exp(-e / e0) / (e0 * e0) };
        let n_cut = simpson(cut, phi, phi + 60.0, 200_000);
        assert!((n_cut / (1.0 + phi / e0) - 1.0).abs() > 0.5, "{n_cut}");
    }

    #[test]
    fn the_nodes_integrate_the_energy_flux_density() {
        // The mean of E^-1 under w is number flux / energy flux: a test of
        // the nodes' weights and energies against the closed forms.
        for s in [
            Spectrum::Maxwellian { e0_kev: 3.0 },
            Spectrum::Accelerated { e0_kev: 0.5, potential_kv: 6.0 },
            Spectrum::Accelerated { e0_kev: 2.0, potential_kv: 1.0 },
            Spectrum::Monoenergetic { e_kev: 8.0 },
        ] {
            let nodes = s.energy_nodes();
            assert!((nodes.iter().map(|n| n.1).sum::<f64>() - 1.0).abs() < 1e-12);
            let inv: f64 = nodes.iter().map(|&(e, w)| w / e).sum();
            let expect = s.number_flux() / s.energy_flux();
            assert!((inv / expect - 1.0).abs() < 2e-3, "{s:?}: {inv} against {expect}");
            assert!(nodes.iter().all(|&(e, _)| e >= s.mean_energy_kev() * 0.0));
        }
    }

    #[test]
    fn sampled_energies_have_the_energy_flux_weighted_mean() {
        // Under w(E) the mean energy is <E^2> / <E> over phi: for the
        // accelerated spectrum sum_k c_k (phi + (k) E0) ... computed here
        // from the nodes; 2e5 draws, within 4 standard errors.
        let mut r = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        for s in [Spectrum::Maxwellian { e0_kev: 2.0 }, Spectrum::Accelerated { e0_kev: 0.5, potential_kv: 6.0 }] {
            let nodes = s.energy_nodes();
            let m1: f64 = nodes.iter().map(|&(e, w)| w * e).sum();
            let m2: f64 = nodes.iter().map(|&(e, w)| w * e * e).sum();
            let n = 200_000;
            let mean = (0..n).map(|_| s.sample_energy(&mut r)).sum::<f64>() / n as f64;
            let se = ((m2 - m1 * m1) / n as f64).sqrt();
            assert!((mean - m1).abs() < 4.0 * se, "{s:?}: {mean} against {m1} (se {se})");
            let below = (0..1000).map(|_| s.sample_energy(&mut r)).fold(f64::INFINITY, f64::min);
            if let Spectrum::Accelerated { potential_kv, .. } = s {
                assert!(below >= potential_kv, "an electron below the drop: {below}");
            }
        }
    }

    #[test]
    fn knights_current_is_the_accessible_flux_of_the_source() {
        // Brute force: electrons of the source Maxwellian (energy W,
        // sin^2 of pitch angle s) reach the ionosphere if the first
        // adiabatic invariant lets them, R W s / (W + e Phi) <= 1; the flux
        // tube narrows by R. So N / N0 = (R / kT^2) int W e^{-W/kT}
        // min(1, (W + e Phi) / (R W)) dW (the s integral done by the
        // indicator's bound), integrated by Simpson over 60 kT in 6e5
        // intervals, against the closed form at three potentials.
        let (n, kt, r) = (1.0, 1.0, 10.0);
        let n0 = one_way_flux(n, kt);
        for phi in [0.5, 3.0, 20.0] {
            let f = |w: f64| if w <= 0.0 { 0.0 } else { w * fmath::exp(-w / kt) * ((w + phi) / (r * w)).min(1.0) };
            let brute = r / (kt * kt) * simpson(f, 0.0, 60.0 * kt, 600_000) * n0;
            let closed = knight_number_flux(n, kt, phi, r);
            assert!((brute / closed - 1.0).abs() < 1e-3, "phi {phi}: brute {brute:e}, Knight {closed:e}");
        }
        // The linear regime and saturation.
        assert!((knight_number_flux(n, kt, 0.1, 1e6) / (n0 * 1.1) - 1.0).abs() < 1e-4);
        assert!((knight_number_flux(n, kt, 1e4, 10.0) / (n0 * 10.0) - 1.0).abs() < 1e-6);
        // 1 cm^-3 at 1 keV: N0 = sqrt(1.602e-16 J / (2 pi 9.109e-31 kg))
        // = 5.29e6 m/s times 1 cm^-3, 5.29e8 cm^-2 s^-1: 0.848 uA/m^2.
        assert!((n0 / 5.29e8 - 1.0).abs() < 0.01, "{n0:e}");
        assert!((knight_current_ua_m2(n, kt, 0.0, 10.0) - 0.848).abs() < 0.01);
    }
}
