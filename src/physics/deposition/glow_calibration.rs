//! The low-energy shape of the deposition: Fang et al. (2010)'s
//! monoenergetic profile, its deposit smeared towards higher altitudes below
//! a few keV so that its Maxwellians reach as high as NCAR GLOW's two-stream
//! transport puts them; calibrated against GLOW, not derived from a
//! transport calculation of our own.
//!
//! **Why.** GLOW (Solomon, Hays & Abreu 1988, J. Geophys. Res. 93, 9867;
//! two-stream transport after Banks & Nagy 1970; glowpython 4.0.4) puts
//! electrons below a few keV higher than Fang's fits (Fang et al. 2008,
//! 2010): 15 km at 0.3-0.5 keV to 2-3 km at 5-10 keV, on the Maxwellians'
//! upper side, where 630.0 nm is made. The peak (427.8 and 557.7 nm) stays
//! Fang 2008's to 1.5 km: only the upper side moves, by a one-sided kernel.
//!
//! **The correction.** In Fang's variable `y = (2 / E) (m / 6e-6)^0.7` (m the
//! column mass, g cm^-2; E in keV), the cumulative deposit `D_E(l)`, `l = ln
//! y` ([`crate::physics::deposition::fang::MonoDeposition`]), becomes
//!
//! ```text
//! D'_E(l) = int_0^inf D_E(l + u) exp(-u / a) / a du
//! a(E) = A0 phi(E),  phi(E) = 1 / (1 + (E / E_f)^p),  A0 = 0.2, E_f = 1.3 keV, p = 2
//! ```
//!
//! every deposit of energy E moved to a higher altitude by an exponentially
//! distributed `u` of mean `a`. The kernel is a probability density in l, so
//! `D'_E(inf) = D_E(inf)`: the energy deposited in total (Fang's
//! backscatter, the energy accounting) is unchanged; the correction moves
//! energy, it never makes or loses any. Fang's profiles are kept above
//! ~5 keV, and so are the Maxwellians of E0 >= 3 keV.
//!
//! **Evaluation.** On Fang's table grid (`D` at nodes of l every h), `D` is
//! piecewise linear and the smoothing is exact on it by a backward recursion
//! from the grid's top, where D has saturated (`D' = D` there):
//!
//! ```text
//! D'_i = r D'_(i+1) + D_i (beta - gamma) + D_(i+1) gamma
//! r = e^(-h/a),  beta = 1 - r,  gamma = (a/h) beta - r
//! ```
//!
//! (the integral of the cell's linear piece against the kernel). Measured
//! offsets, the calibration and its limits: docs/physics.md, "The low-energy
//! correction in detail" and "Against GLOW 4.0.4".

use crate::util::fmath;

/// Mean of the smear in ln y at low energies (`a` at E -> 0).
pub const SKEW_0: f64 = 0.2;
/// Energy where the smear is half its low-energy size, keV.
pub const E_FADE_KEV: f64 = 1.3;
/// Steepness of the fade in E.
pub const FADE_POWER: f64 = 2.0;

/// The smear's mean `a` (ln y) at energy `e_kev`.
pub fn smear(e_kev: f64) -> f64 {
    SKEW_0 / (1.0 + fmath::powf(e_kev / E_FADE_KEV, FADE_POWER))
}

/// Applies the correction to one row of the cumulative deposit `d` of
/// electrons of `e_kev`, tabulated at ln y nodes every `h` (increasing; the
/// last node saturated): `D'` at the same nodes (module doc).
pub fn correct_row(d: &[f64], h: f64, e_kev: f64) -> Vec<f64> {
    smear_row(d, h, smear(e_kev))
}

/// `D'` for a smear of mean `a` (ln y): exact for `d` linear between nodes.
pub fn smear_row(d: &[f64], h: f64, a: f64) -> Vec<f64> {
    let n = d.len();
    if n == 0 || !(a > 1e-12) {
        return d.to_vec();
    }
    let r = fmath::exp(-h / a);
    let beta = 1.0 - r;
    let gamma = (a / h) * beta - r;
    let mut g = vec![0.0; n];
    g[n - 1] = d[n - 1];
    for i in (0..n - 1).rev() {
        g[i] = r * g[i + 1] + d[i] * (beta - gamma) + d[i + 1] * gamma;
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smear_is_exact_on_piecewise_linear_data() {
        // D = c l: D'(l) = c (l + a) exactly (the kernel's mean is a), away
        // from the top, whose influence decays as e^(-(l_top - l) / a):
        // e^-100 at the nodes checked.
        let h = 0.02;
        let d: Vec<f64> = (0..2000).map(|i| 0.3 * i as f64 * h).collect();
        let g = smear_row(&d, h, 0.2);
        for (i, v) in g.iter().enumerate().take(1000) {
            assert!((v - 0.3 * (i as f64 * h + 0.2)).abs() < 1e-12, "{i}: {v}");
        }
    }

    #[test]
    fn the_total_is_kept_and_the_deposit_moves_up() {
        // A cumulative that saturates inside the grid (the logistic): the
        // total (last node) is unchanged bit for bit, D' >= D everywhere
        // (energy laid at smaller y, that is higher), and the deposit's mean
        // position in l (int l dD / D(inf)) moves by the kernel's mean a,
        // to the quadrature's accuracy (a cell's midpoint rule: h^2 / 12).
        let h = 0.02;
        let d: Vec<f64> = (0..1500).map(|i| 1.0 / (1.0 + fmath::exp(15.0 - i as f64 * h))).collect();
        for a in [0.05, 0.15, 0.4] {
            let c = smear_row(&d, h, a);
            assert_eq!(c[c.len() - 1], d[d.len() - 1]);
            for i in 0..d.len() {
                assert!(c[i] >= d[i] - 1e-15, "{a} node {i}: {} < {}", c[i], d[i]);
            }
            let mean = |v: &[f64]| (1..v.len()).map(|i| (-15.0 + (i as f64 - 0.5) * h) * (v[i] - v[i - 1])).sum::<f64>() / v[v.len() - 1];
            let moved = mean(&d) - mean(&c);
            assert!((moved - a).abs() < 1e-3, "{a}: moved {moved}");
        }
    }

    #[test]
    fn the_smear_fades_above_a_few_kev() {
        assert!(smear(0.1) > 0.99 * SKEW_0);
        assert!((smear(E_FADE_KEV) - 0.5 * SKEW_0).abs() < 1e-12);
        // phi(E) = 1 / (1 + (E / E_f)^p): below 7 % of A0 from 5 keV on
        // (6.3 % at 5 keV), below 2 % from 10 keV (1.7 %): the fade is kept.
        for e in [5.0, 10.0, 30.0, 100.0] {
            assert!(smear(e) < 0.07 * SKEW_0, "{e} keV: {}", smear(e));
        }
        for e in [10.0, 30.0, 100.0] {
            assert!(smear(e) < 0.02 * SKEW_0, "{e} keV: {}", smear(e));
        }
    }
}
