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
//! which compiles them from the laboratory literature, with O2+ + N2 from
//! Rees (1989, "Physics and chemistry of the upper atmosphere") and N(2D)
//! from electron-impact dissociation of N2 after Zipf et al. (1980); the two
//! electron-impact yields on O are fits to GLOW's own transport. Every
//! balance is local and in steady state: production P (cm^-3 s^-1) over
//! loss frequency L (s^-1), X = P / L. Units: cm^-3, cm^3 s^-1, s^-1, K.
//!
//! - **Ionization**: q shared between N2, O2 and O as 1 : 1.09 : 0.63 times
//!   their densities, with the dissociative and excited-ion branches.
//! - **Ions** N2+, N+, O+, O2+, NO+ (ion-neutral rates at Tn), each closed
//!   form given ne. Above 200 km O+ lives an hour and transport sets it, so
//!   it is capped at the ambient electron density (uncapped, 630.0 nm comes
//!   out about 40 % high against GLOW). ne, the ions' sum plus the ambient
//!   density where that is larger, is a fixed point started from the
//!   E-region `sqrt(q / alpha)`, each pass taking the geometric mean of the
//!   old and new ne: it converges to 1e-6 in under 20 passes (tested).
//! - **Excited states** N2(A), N(2D), O(1S) (557.7 nm, A = 1.06 s^-1) and
//!   O(1D) (630.0 + 636.4 nm, Storey & Zeippen 2000's coefficients in
//!   [`einstein`], photon ratio 2.997, radiative lifetime 133.2 s):
//!   their production channels and quenchers, O(1D) impact excitation
//!   reduced above about 240 km where the secondaries heat the F-region
//!   electrons instead.
//! - **N2+ 427.8 nm**: 0.022 photons per N2 ionization, unquenched. **N2 1P**
//!   (647-688 nm): not in GLOW; N2(B) from direct impact and cascade,
//!   quenched by N2 and O2, plus the collisional cascade from W below about
//!   100 km ([`n2_triplet`]): [`R_1P`] photons per 427.8 nm photon high up,
//!   about 1.5 times that below 100 km (type-B aurora).
//!
//! It knows nothing of transport (beyond the O+ cap) or of time: the
//! lifetimes it returns are applied by `crate::physics::emission::lifetime`.
//! Every reaction, rate and branching ratio: docs/physics.md, "The
//! chemistry's reactions". Against GLOW driven by its own q(z) and densities
//! it reproduces GLOW's 427.8, 557.7 and 630.0 nm columns
//! (tests/physics/chemistry.rs; `tests/data/glow_chemistry.csv` from
//! `tools/reference/glow_tables.py`).

use crate::util::fmath;

pub mod ambient;
pub mod einstein;
pub mod n2_triplet;
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

pub use einstein::{A_2972, A_5577, A_6300, A_6364};
/// 427.8 nm photons per N2 ionization.
pub const Y_4278: f64 = 0.022;
/// N2 1P (Delta v = 3) photons per 427.8 nm photon high up, the simple
/// model's `line_colour::R_1P` (equal by test); [`n2_triplet`] adds the
/// quenching and the collisional cascade.
pub use n2_triplet::R_1P;
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
    let k3 = 1.4e-10 * fmath::powf(t3, 0.44);
    let k39 = 1e-11 * fmath::powf(t3, 0.23);
    let k4 = 5e-11 * fmath::powf(t3, 0.8);
    let a_n2p = 2.2e-7 * fmath::powf(te3, 0.39);
    let k25 = 5.5e-10;
    let k32 = 1e-12;
    let k1 = 1.2e-12;
    let k2 = 1.6e-11 * fmath::powf(t3, 0.52);
    let k40 = 8e-13;
    let a_o2p = 1.95e-7 * fmath::powf(te3, 0.7);
    let k30 = 4.4e-10;
    let k37 = 1.2e-10;
    let k71 = 5e-16;
    let a_nop = 3.5e-7 * fmath::powf(te3, 0.69);
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
    let n2a = n2_triplet::n2_a(q_n2, o2, o, no);
    // N(2D).
    let p_n2d = k3 * n2p * o + a_n2p * n2p * ne + 0.76 * a_nop * nop * ne + 0.5 * p_np + 0.5 * q_n2;
    let (k5, k6, k31) = (6e-12, 6.9e-13, 7e-11);
    let n2d = p_n2d / (k5 * o2 + k6 * o + k31 * no + 5.5e-10 * (te / 300.0).sqrt() * ne + 1.07e-5);
    // O(1S).
    let b1s = (0.12 + 0.02 * fmath::log10(ne / o * fmath::powf(te3, 0.7))).max(0.03);
    let g_impact = q * 0.153 * x_o / (1.0 + 1.36 * x_o);
    let g_n2a = n2a.o1s_rate;
    let g_recomb = b1s * a_o2p * o2p * ne;
    let g_n2d = 0.2 * k31 * n2d * no + 0.21 * k37 * o2p * n4s;
    let l_1s = A_5577 + A_2972 + 4e-12 * fmath::exp(-865.0 / t) * o2 + 2e-14 * o;
    let f_5577 = A_5577 / l_1s;
    // O(1D).
    let r_impact = q * 2.63 * x_o / (1.0 + 1.18 * x_o) / (1.0 + fmath::powf(amb.ne / (1.1e-4 * o), 0.62));
    let r_recomb = 1.2 * a_o2p * o2p * ne;
    let r_n2d = 0.1 * (k5 * o2 + k6 * o) * n2d;
    let p_1s = g_impact + g_n2a + g_recomb + g_n2d;
    let r_cascade = f_5577 * p_1s;
    let r_other = 0.3 * k25 * n_p * o2 + 0.4 * q_o2;
    let l_1d = A_6300
        + A_6364
        + 2.0e-11 * fmath::exp(107.8 / t) * n2
        + 2.9e-11 * fmath::exp(67.5 / t) * o2
        + 3e-12 * o
        + 8.1e-10 * (te / 300.0).sqrt() * ne;
    let f_6300 = A_6300 / l_1d;
    let f_6364 = A_6364 / l_1d;
    let p_1d = r_impact + r_recomb + r_n2d + r_cascade + r_other;
    let blue = Y_4278 * q_n2 / q;
    let first_positive = n2_triplet::n2_1p_per_n2_ion(Y_4278, n2, o2) * q_n2 / q;
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
        per_ion_pair: [f_5577 * p_1s / q, f_6300 * p_1d / q, f_6364 * p_1d / q, blue, first_positive],
        channels,
        tau_1d: 1.0 / l_1d,
        tau_1s: 1.0 / l_1s,
        ne,
        ions,
    }
}

#[cfg(test)]
mod tests;
