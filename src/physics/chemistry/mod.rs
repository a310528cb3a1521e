//! Auroral line emission from the chemistry: at one altitude, from the local
//! ionization rate q (ion pairs cm^-3 s^-1) and the neutral and ambient
//! ionospheric state, the steady-state densities of the ions and of the
//! excited states that emit 427.8, 557.7, 630.0 and 636.4 nm, and so the
//! photons each line emits per ion pair, which reaction made them, and the
//! upper states' effective lifetimes.
//!
//! The reactions, rates and branching ratios are those of NCAR GLOW's
//! `gchem` (Solomon, Hays & Abreu 1988, J. Geophys. Res. 93, 9867; Solomon
//! & Abreu 1989, J. Geophys. Res. 94, 6817; GLOW 0.98/4.0, Solomon 2017),
//! which compiles them from the laboratory literature; the two
//! electron-impact yields are fits to GLOW's own transport (below). Every
//! balance is local and in steady state: production P (cm^-3 s^-1) over
//! loss frequency L (s^-1), X = P / L. Units: cm^-3, cm^3 s^-1, s^-1, K.
//!
//! **Ionization.** q is shared between N2, O2 and O in proportion to
//! 1 : 1.09 : 0.63 times their densities (the ratio of their total
//! ionization cross sections at auroral energies, holds in GLOW from 100 to
//! 200 km). Of the N2 ionizations 0.16 are dissociative (N+ + N), of the O2
//! ionizations 0.19 (O+ + O); of the O ionizations 0.6 leave O+ in its 2D or
//! 2P states, which give their charge to N2 (k = 8e-10) or O2 (7e-10) unless
//! O (5e-12) or an electron (6.6e-8 (300/Te)^0.5) returns them to O+(4S).
//!
//! **Ions** (Tn for the ion-neutral rates; the night-time ion temperature
//! is within 10 % of it below 250 km, where the ions matter):
//! - N2+: made by N2 ionization and O+(2D,2P) + N2; lost to
//!   O (-> NO+ + N(2D), k3 = 1.4e-10 (300/T)^0.44; -> O+ + N2, 1e-11 (300/T)^0.23),
//!   O2 (-> O2+, k4 = 5e-11 (300/T)^0.8) and electrons
//!   (-> 2 N, 2.2e-7 (300/Te)^0.39, one N(2D) per recombination).
//! - N+: made by dissociative N2 ionization; lost to O2
//!   (5.5e-10: 0.43 NO+ + O, of which 0.3 O(1D) per reaction; 0.51 O2+ + N;
//!   0.06 O+ + NO) and O (-> O+, 1e-12).
//! - O+: made by O ionization (4S and the returned 2D/2P), dissociative O2
//!   ionization, N2+ + O and N+; lost to N2 (-> NO+, 1.2e-12), O2 (-> O2+,
//!   1.6e-11 (300/T)^0.52) and NO (-> NO+, 8e-13). Above 200 km its
//!   lifetime is an hour and transport, not the local balance, sets it: there
//!   O+ is capped at the ambient electron density (without the cap the
//!   auroral O+ feeds O2+ as if in steady state and 630.0 nm comes out about
//!   40 % high against GLOW).
//! - O2+: made by O2 ionization, O+ + O2, N2+ + O2, N+ + O2 and O+(2D,2P) +
//!   O2; lost by dissociative recombination (alpha2 = 1.95e-7 (300/Te)^0.7),
//!   to NO (-> NO+, 4.4e-10), N(4S) (-> NO+ + O, 1.2e-10) and N2 (-> NO+ +
//!   NO, 5e-16, Rees 1989, "Physics and chemistry of the upper atmosphere",
//!   table 8.x: slow, but below 85 km [N2] makes it the O2+ sink that keeps
//!   O2+ recombination, and with it 557.7 nm, off the lower border; GLOW's
//!   557.7/427.8 there is 0.03-0.11 from 80 to 84 km).
//! - NO+: made by all of the above; lost by recombination
//!   (3.5e-7 (300/Te)^0.69, 0.76 N(2D) per recombination).
//!
//! Each ion is closed form given ne; ne = N2+ + N+ + O+ + O2+ + NO+ plus
//! the ambient density where it is larger (above 200 km) is found by a fixed
//! point from the E-region estimate ne = sqrt(q / alpha): each pass
//! recomputes the ions and takes the geometric mean of the old and new ne,
//! which converges to 1e-6 in under 20 passes (tested).
//!
//! **N2(A)**: 0.60 per N2 ionization (GLOW's N2(A, B, C) excitation with the
//! cascade into A); lost to O (3.1e-11, O(1S) with branching 0.19), O2
//! (4.1e-12), NO (8.9e-11) and by radiation (0.77 s^-1).
//!
//! **N(2D)**: made by N2+ + O, N2+ + e, NO+ + e (above), dissociative N2
//! ionization (0.5 per) and electron-impact dissociation of N2 (0.5 N(2D)
//! per N2 ionization, Zipf et al. 1980); lost to O2 (6e-12, O(1D) branching
//! 0.1), O (6.9e-13, 0.1), NO (7e-11, O(1S) branching 0.2), electrons
//! (5.5e-10 (Te/300)^0.5) and radiation (1.07e-5 s^-1).
//!
//! **O(1S), 557.7 nm** (A = 1.06 s^-1 at 557.7, 0.045 at 297.2 nm):
//! - electron impact on O: 0.153 x_O / (1 + 1.36 x_O) per ion pair, x_O the
//!   O mole fraction (a fit to GLOW's transport; a mole-fraction law is 1.9
//!   times too small at x_O = 0.1, where secondaries of a few eV prefer O);
//! - N2(A) + O (above);
//! - O2+ + e, branching max(0.03, 0.12 + 0.02 log10(ne/[O] (300/Te)^0.7))
//!   (the vibrational development of O2+ with density, GLOW's fit);
//! - N(2D) + NO (0.2) and O2+ + N (0.21);
//! - quenched by O2 (4e-12 exp(-865/T)) and O (2e-14).
//!
//! **O(1D), 630.0 + 636.4 nm** (A = 0.00585 and 0.00185 s^-1: ratio 3.16,
//! radiative lifetime 130 s):
//! - electron impact on O: 2.63 x_O / (1 + 1.18 x_O) per ion pair (fit to
//!   GLOW within 2 % from 95 to 230 km: slow secondaries excite O(1D) in
//!   competition with N2 vibration), times 1 / (1 + (ne0 / (1.1e-4 [O]))^0.62)
//!   with ne0 the ambient electron density: above about 240 km the
//!   secondaries lose their energy to the thermal F-region electrons
//!   (0.88 at 240 km, 0.43 at 300, 0.14 at 400 km on this ionosphere);
//! - O2+ + e, 1.2 O(1D) per recombination;
//! - N(2D) + O2 and N(2D) + O (above); N+ + O2 (0.3 per reaction);
//! - the cascade O(1S) -> O(1D): every 557.7 nm photon leaves O in 1D;
//! - electron-impact dissociation of O2 (0.4 O(1D) per O2 ionization, the
//!   Schumann-Runge continuum share);
//! - quenched by N2 (2.0e-11 exp(107.8/T)), O2 (2.9e-11 exp(67.5/T)), O
//!   (3e-12) and electrons (8.1e-10 (Te/300)^0.5).
//!
//! **N2+ 427.8 nm**: 0.11 N2+(B) per N2 ionization, 0.20 of which radiate in
//! the (0,1) band: 0.022 photons per N2 ionization, unquenched.
//!
//! **N2 1P** (647-688 nm, Delta v = 3): GLOW does not compute it; kept as in
//! the simple model, as many photons as 427.8 nm (`spectrum::R_1P`).
//!
//! Against GLOW driven by its own q(z) and densities this reproduces its
//! 427.8, 557.7 and 630.0 nm columns (tests/physics/chemistry.rs, the fixture
//! `tests/data/glow_chemistry.csv` from `tools/reference/glow_tables.py`).

pub mod ambient;
pub mod table;

use crate::physics::atmosphere::Composition;
pub use ambient::{Ambient, AmbientTable};

/// The state of the air at one altitude that the chemistry needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Air {
    pub h_km: f64,
    pub n2: f64,
    pub o2: f64,
    pub o: f64,
    pub ambient: Ambient,
}

impl Air {
    /// `c`'s major species with the ambient table's values at `h_km`.
    pub fn new(h_km: f64, c: Composition, ambient: Ambient) -> Self {
        Air { h_km, n2: c.n2, o2: c.o2, o: c.o, ambient }
    }
}

/// The O+ cap (module doc) applies above this altitude, km.
pub const O_PLUS_CAP_KM: f64 = 200.0;

/// Which reaction made the light, photons per ion pair.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Channels {
    /// 557.7 nm: electron impact on O, N2(A) + O, O2+ + e, N(2D) + NO and
    /// O2+ + N together.
    pub g_impact: f64,
    pub g_n2a: f64,
    pub g_recomb: f64,
    pub g_n2d: f64,
    /// 630.0 nm: electron impact on O, O2+ + e, N(2D) + O2 and O, the O(1S)
    /// cascade, N+ + O2 and O2 dissociation together.
    pub r_impact: f64,
    pub r_recomb: f64,
    pub r_n2d: f64,
    pub r_cascade: f64,
    pub r_other: f64,
}

/// Names of [`Channels`] in order (the profile's column names).
pub const CHANNEL_NAMES: [&str; 9] = ["g_impact", "g_n2a", "g_recomb", "g_n2d", "r_impact", "r_recomb", "r_n2d", "r_cascade", "r_other"];

impl Channels {
    pub fn as_array(&self) -> [f64; 9] {
        [self.g_impact, self.g_n2a, self.g_recomb, self.g_n2d, self.r_impact, self.r_recomb, self.r_n2d, self.r_cascade, self.r_other]
    }
}

/// The solution at one altitude.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Emission {
    /// Photons per ion pair: 557.7, 630.0, 636.4, 427.8 nm, N2 1P (the
    /// order of `spectrum::LINES`).
    pub per_ion_pair: [f64; 5],
    /// Each line's production by channel, photons per ion pair.
    pub channels: Channels,
    /// Effective lifetime of O(1D) with quenching, s.
    pub tau_1d: f64,
    /// Effective lifetime of O(1S), s.
    pub tau_1s: f64,
    /// Electron density, cm^-3.
    pub ne: f64,
    /// Densities of N2+, N+, O+, O2+, NO+, cm^-3.
    pub ions: [f64; 5],
}

/// Einstein coefficients, s^-1.
pub const A_5577: f64 = 1.06;
pub const A_2972: f64 = 0.045;
pub const A_6300: f64 = 0.00585;
pub const A_6364: f64 = 0.00185;
/// 427.8 nm photons per N2 ionization.
pub const Y_4278: f64 = 0.022;
/// N2 1P (Delta v = 3) photons per 427.8 nm photon: `spectrum::R_1P`, the
/// simple model's round reading of auroral spectra (equal by test).
pub const R_1P: f64 = 1.0;
/// Fixed-point passes on ne.
pub const NE_PASSES: usize = 24;

/// Solves the local steady state for ionization rate `q` (ion pairs cm^-3
/// s^-1, > 0) in `air` (module doc).
pub fn solve(q: f64, air: &Air) -> Emission {
    let Air { h_km, n2, o2, o, ambient: amb } = *air;
    let q = q.max(1e-30);
    let t = amb.tn;
    let te = amb.te.max(t);
    let (n4s, no) = (amb.n4s, amb.no);
    let t3 = 300.0 / t;
    let te3 = 300.0 / te;
    // Ionization shares.
    let w = [n2, 1.09 * o2, 0.63 * o];
    let ws = w[0] + w[1] + w[2];
    let (q_n2, q_o2, q_o) = (q * w[0] / ws, q * w[1] / ws, q * w[2] / ws);
    let x_o = o / (n2 + o2 + o);
    // Rates.
    let k3 = 1.4e-10 * t3.powf(0.44);
    let k39 = 1e-11 * t3.powf(0.23);
    let k4 = 5e-11 * t3.powf(0.8);
    let a_n2p = 2.2e-7 * te3.powf(0.39);
    let k25 = 5.5e-10;
    let k32 = 1e-12;
    let k1 = 1.2e-12;
    let k2 = 1.6e-11 * t3.powf(0.52);
    let k40 = 8e-13;
    let a_o2p = 1.95e-7 * te3.powf(0.7);
    let k30 = 4.4e-10;
    let k37 = 1.2e-10;
    let k71 = 5e-16;
    let a_nop = 3.5e-7 * te3.powf(0.69);
    let (kx_n2, kx_o2, kx_o, kx_e) = (8e-10, 7e-10, 5e-12, 6.6e-8 * te3.sqrt());
    // N+ does not depend on ne.
    let p_np = 0.16 * q_n2;
    let l_np = k25 * o2 + k32 * o;
    let n_p = p_np / l_np;
    let cap = if h_km > O_PLUS_CAP_KM { amb.ne } else { f64::INFINITY };
    let ions_at = |ne: f64| {
        // Excited O+ from O ionization: its share to N2+, O2+ and O+(4S).
        let lx = kx_n2 * n2 + kx_o2 * o2 + kx_o * o + kx_e * ne;
        let ox = 0.6 * q_o;
        let (x_to_n2p, x_to_o2p, x_to_op) = (ox * kx_n2 * n2 / lx, ox * kx_o2 * o2 / lx, ox * (kx_o * o + kx_e * ne) / lx);
        let n2p = (0.84 * q_n2 + x_to_n2p) / (k3 * o + k39 * o + k4 * o2 + a_n2p * ne);
        let p_op = 0.4 * q_o + x_to_op + 0.19 * q_o2 + k39 * n2p * o + k32 * n_p * o + 0.06 * k25 * n_p * o2;
        let op = (p_op / (k1 * n2 + k2 * o2 + k40 * no)).min(cap);
        let p_o2p = 0.81 * q_o2 + k2 * op * o2 + k4 * n2p * o2 + 0.51 * k25 * n_p * o2 + x_to_o2p;
        let o2p = p_o2p / (a_o2p * ne + k30 * no + k37 * n4s + k71 * n2);
        let p_nop = k1 * op * n2 + k40 * op * no + k3 * n2p * o + 0.43 * k25 * n_p * o2 + (k30 * no + k37 * n4s + k71 * n2) * o2p;
        let nop = p_nop / (a_nop * ne);
        [n2p, n_p, op, o2p, nop]
    };
    let mut ne = (q / a_o2p).sqrt().max(amb.ne);
    let mut ions = ions_at(ne);
    for _ in 0..NE_PASSES {
        let sum: f64 = ions.iter().sum();
        let next = sum.max(if h_km > O_PLUS_CAP_KM { amb.ne } else { 0.0 });
        ne = (ne * next).sqrt();
        ions = ions_at(ne);
    }
    let [n2p, n_p, _op, o2p, nop] = ions;
    // N2(A).
    let k_a_o = 3.1e-11;
    let n2a = 0.60 * q_n2 / (k_a_o * o + 4.1e-12 * o2 + 8.9e-11 * no + 0.77);
    // N(2D).
    let p_n2d = k3 * n2p * o + a_n2p * n2p * ne + 0.76 * a_nop * nop * ne + 0.5 * p_np + 0.5 * q_n2;
    let (k5, k6, k31) = (6e-12, 6.9e-13, 7e-11);
    let n2d = p_n2d / (k5 * o2 + k6 * o + k31 * no + 5.5e-10 * (te / 300.0).sqrt() * ne + 1.07e-5);
    // O(1S).
    let b1s = (0.12 + 0.02 * (ne / o * te3.powf(0.7)).log10()).max(0.03);
    let g_impact = q * 0.153 * x_o / (1.0 + 1.36 * x_o);
    let g_n2a = 0.19 * k_a_o * n2a * o;
    let g_recomb = b1s * a_o2p * o2p * ne;
    let g_n2d = 0.2 * k31 * n2d * no + 0.21 * k37 * o2p * n4s;
    let l_1s = A_5577 + A_2972 + 4e-12 * (-865.0 / t).exp() * o2 + 2e-14 * o;
    let f_5577 = A_5577 / l_1s;
    // O(1D).
    let r_impact = q * 2.63 * x_o / (1.0 + 1.18 * x_o) / (1.0 + (amb.ne / (1.1e-4 * o)).powf(0.62));
    let r_recomb = 1.2 * a_o2p * o2p * ne;
    let r_n2d = 0.1 * (k5 * o2 + k6 * o) * n2d;
    let p_1s = g_impact + g_n2a + g_recomb + g_n2d;
    let r_cascade = f_5577 * p_1s;
    let r_other = 0.3 * k25 * n_p * o2 + 0.4 * q_o2;
    let l_1d = A_6300
        + A_6364
        + 2.0e-11 * (107.8 / t).exp() * n2
        + 2.9e-11 * (67.5 / t).exp() * o2
        + 3e-12 * o
        + 8.1e-10 * (te / 300.0).sqrt() * ne;
    let f_6300 = A_6300 / l_1d;
    let f_6364 = A_6364 / l_1d;
    let p_1d = r_impact + r_recomb + r_n2d + r_cascade + r_other;
    let blue = Y_4278 * q_n2 / q;
    let channels = Channels {
        g_impact: f_5577 * g_impact / q,
        g_n2a: f_5577 * g_n2a / q,
        g_recomb: f_5577 * g_recomb / q,
        g_n2d: f_5577 * g_n2d / q,
        r_impact: f_6300 * r_impact / q,
        r_recomb: f_6300 * r_recomb / q,
        r_n2d: f_6300 * r_n2d / q,
        r_cascade: f_6300 * r_cascade / q,
        r_other: f_6300 * r_other / q,
    };
    Emission {
        per_ion_pair: [f_5577 * p_1s / q, f_6300 * p_1d / q, f_6364 * p_1d / q, blue, R_1P * blue],
        channels,
        tau_1d: 1.0 / l_1d,
        tau_1s: 1.0 / l_1s,
        ne,
        ions,
    }
}

#[cfg(test)]
mod tests;
