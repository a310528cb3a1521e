//! The low-energy shape of the deposition: Fang et al. (2010)'s
//! monoenergetic profile, its deposit smeared towards higher altitudes below
//! a few keV so that its Maxwellians reach as high as NCAR GLOW's two-stream
//! transport puts them; calibrated against GLOW, not derived from a
//! transport calculation of our own.
//!
//! **Why.** Fang's fits reproduce their own multi-stream transport runs
//! (Fang et al. 2008, 2010; errors "significantly less than 5 km" in the
//! peak's altitude). GLOW (Solomon, Hays & Abreu 1988, J. Geophys. Res. 93,
//! 9867; two-stream transport after Banks & Nagy 1970; glowpython 4.0.4)
//! puts electrons below a few keV higher: on the default atmosphere its
//! monoenergetic profiles peak 15 km above Fang 2010's at 0.3-0.5 keV, 11
//! km at 1 keV, 6 km at 2 keV, 4 km at 3 keV and 2-3 km at 5-10 keV
//! (`tools/reference/deposition_glow.py --mono`), and its Maxwellians of E0 <= 1 keV
//! reach 7-17 km higher on their upper side (E0 = 0.5 keV: half maximum at
//! 210 km against 192; 1 keV: 154 against 144) while their lower side and
//! peak stay within 2.5 km at 1 keV. The 630.0 nm line, made mostly above
//! 150 km, follows that upper side: on Fang's profile 630.0 / 427.8 came out
//! at 0.72-0.77 of GLOW's at E0 <= 1 keV. The peak, where 427.8 and 557.7 nm
//! are made, is Fang 2008's to 1.5 km (tests/python/test_profile.py) and
//! stays so: only the upper side is moved, by a one-sided kernel.
//!
//! **The correction.** In Fang's own variable `y = (2 / E) (m / 6e-6)^0.7`
//! (a power of the column mass m), the cumulative deposit `D_E(l)`, `l = ln
//! y` (the fraction deposited above the column of y,
//! [`crate::physics::deposition::fang::MonoDeposition`]), becomes
//!
//! ```text
//! D'_E(l) = int_0^inf D_E(l + u) exp(-u / a) / a du
//! a(E) = A0 phi(E),  phi(E) = 1 / (1 + (E / E_f)^p)
//! ```
//!
//! that is every deposit of energy E is moved to a smaller y (a higher
//! altitude) by an exponentially distributed `u` of mean `a`: the lower
//! edge stays where it is and the upper side stretches. In altitude a step
//! `dl` is `dz = H dl / 0.7` (hydrostatic: `dm / m = -dz / H`), so at
//! 150-200 km (H of 20-30 km) `l = 0.1` is 3-4 km. The kernel is a
//! probability density in l, so `D'_E(inf) = D_E(inf)`: the energy deposited
//! in total, hence Fang's backscatter and the energy accounting, are
//! unchanged; the correction moves energy, it never makes or loses any.
//! `phi` is smooth in E and falls from 1 to 0 over a few E_f, so Fang's
//! profiles are kept above ~5 keV (phi = 0.063 at 5 keV, 0.017 at 10) and so are the
//! Maxwellians of E0 >= 3 keV, whose energy lies mostly there.
//!
//! **Evaluation.** On Fang's table grid (`D` at nodes of l every h), `D` is
//! piecewise linear, and the smoothing is exact on it by a backward
//! recursion from the grid's top, where D has saturated (`D' = D` there):
//!
//! ```text
//! D'_i = r D'_(i+1) + D_i (beta - gamma) + D_(i+1) gamma
//! r = e^(-h/a),  beta = 1 - r,  gamma = (a/h) beta - r
//! ```
//!
//! (the integral of the cell's linear piece against the kernel).
//!
//! **Calibration.** A0, E_f and p were chosen on the line columns against
//! GLOW (tests/python/test_glow.py's cases, E0 = 0.5-3 keV) subject to the
//! Maxwellian peaks staying within 1.5 km of Fang et al. (2008)'s at 0.5 and
//! 1 keV and their L1 against Fang 2008 below 0.15 (the checks of
//! tests/python/test_profile.py); `tools/reference/deposition_glow.py --corr
//! 0,A0,E_f,p` prints the profiles' agreement with GLOW and Fang 2008
//! (docs/physics.md, "The deposition at low energies"). A hand search over
//! A0 0.06-0.26, E_f 1-3 keV and p 1.5-3 chose A0 = 0.2, E_f = 1.3 keV, p =
//! 2: the 557.7 nm shape at E0 = 0.5 keV comes to L1 0.192 (1 erg cm^-2
//! s^-1) and 0.197 (20) against GLOW's target of 0.2, with the 0.5 keV
//! ionization peak 1.5 km above Fang 2008's, on a plateau flat to 0.1 % over
//! 2 km; Fang 2008 L1 0.083 at 0.5 keV, 0.042 at 1 keV; no set found meets
//! that shape with the peak within 1 km (docs/physics.md, "Against GLOW
//! 4.0.4").

/// Mean of the smear in ln y at low energies (`a` at E -> 0).
pub const SKEW_0: f64 = 0.2;
/// Energy where the smear is half its low-energy size, keV.
pub const E_FADE_KEV: f64 = 1.3;
/// Steepness of the fade in E.
pub const FADE_POWER: f64 = 2.0;

/// The smear's mean `a` (ln y) at energy `e_kev`.
pub fn smear(e_kev: f64) -> f64 {
    SKEW_0 / (1.0 + (e_kev / E_FADE_KEV).powf(FADE_POWER))
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
    let r = (-h / a).exp();
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
        let d: Vec<f64> = (0..1500).map(|i| 1.0 / (1.0 + (15.0 - i as f64 * h).exp())).collect();
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
