//! The chemistry tabulated for a bake: photons per keV deposited of every
//! line, each line's channels and the upper states' lifetimes, over altitude
//! and the logarithm of the ionization rate q, built once per atmosphere.
//!
//! Grid: altitude 50-700 km every [`DH_KM`] = 0.5 km (1301 rows), log10 q
//! from [`LOG_Q`].0 = -2 to .1 = 7 every [`D_LOG_Q`] = 0.25 (37 columns; q
//! in ion pairs cm^-3 s^-1: 1e-2 is a faint glow's top side, 1e7 three
//! times the peak of a 20 erg cm^-2 s^-1 10 keV arc). Outside, q and h are
//! clamped to the grid. Lookup is bilinear in (h, log10 q). Interpolation
//! error (tested against the solver at off-grid points): the yields vary on
//! the scale of the neutral scale height (6 km and more) in h and by a few
//! per cent per decade in q (the note's GLOW runs: 427.8 within 2 %, 557.7
//! and 630.0 within 5-15 % over Q = 1-20), so linear interpolation errs by
//! (0.5 km)^2 / 8 / H^2 ~ 1e-3 in h and well under 1 % in q.
//!
//! Cost: 48,137 solves (each 24 fixed-point passes of a few dozen flops)
//! in parallel, tens of milliseconds on two cores; memory 48,137 nodes of
//! 5 f64 + 11 f32 = 84 bytes, 4.0 MB (plus the colour table's 3 f64 per
//! node in `spectrum`, 1.2 MB).

use super::{solve, Air, Emission};
use crate::physics::atmosphere::Atmosphere;
use crate::util::fmath;

/// Altitude range and step, km.
pub const H_KM: (f64, f64) = (50.0, 700.0);
pub const DH_KM: f64 = 0.5;
/// log10 q range and step.
pub const LOG_Q: (f64, f64) = (-2.0, 7.0);
pub const D_LOG_Q: f64 = 0.25;
/// keV per ion pair (the 35 eV of `fang::KEV_PER_ION_PAIR`, equal by test).
pub const KEV_PER_ION_PAIR: f64 = 0.035;

/// One node: photons per keV deposited per line (`spectrum::LINES` order),
/// the channels per keV ([`super::CHANNEL_NAMES`]), the O(1D) and O(1S)
/// lifetimes, s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    pub per_kev: [f64; 5],
    pub channels: [f32; 9],
    pub tau: [f32; 2],
}

impl Node {
    fn of(e: &Emission) -> Node {
        Node {
            per_kev: e.per_ion_pair.map(|x| x / KEV_PER_ION_PAIR),
            channels: e.channels.as_array().map(|x| (x / KEV_PER_ION_PAIR) as f32),
            tau: [e.tau_1d as f32, e.tau_1s as f32],
        }
    }
}

/// The tabulated chemistry of one atmosphere.
#[derive(Clone, Debug)]
pub struct ChemistryTable {
    nh: usize,
    nq: usize,
    /// Row-major: `nodes[ih * nq + iq]`.
    nodes: Vec<Node>,
}

/// Where a lookup falls: the four corner indices' weights.
#[derive(Clone, Copy, Debug)]
pub struct Cell {
    pub i: [usize; 4],
    pub w: [f64; 4],
}

impl ChemistryTable {
    /// Solves the chemistry at every node for `atmosphere`'s N2, O2 and O
    /// and its ambient state (`Atmosphere::ambient`).
    pub fn build(atmosphere: &Atmosphere) -> Self {
        use rayon::prelude::*;
        let nh = ((H_KM.1 - H_KM.0) / DH_KM).round() as usize + 1;
        let nq = ((LOG_Q.1 - LOG_Q.0) / D_LOG_Q).round() as usize + 1;
        let amb = atmosphere.ambient();
        let nodes = (0..nh)
            .into_par_iter()
            .flat_map_iter(|ih| {
                let h = H_KM.0 + ih as f64 * DH_KM;
                let air = Air::new(h, atmosphere.composition(h), amb.at(h));
                (0..nq).map(move |iq| Node::of(&solve(fmath::powf(10f64, LOG_Q.0 + iq as f64 * D_LOG_Q), &air)))
            })
            .collect();
        ChemistryTable { nh, nq, nodes }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The nodes, row-major in altitude then log q.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The bilinear cell of (`h_km`, `q`), clamped to the grid.
    #[inline]
    pub fn cell(&self, h_km: f64, q: f64) -> Cell {
        self.cell_log(h_km, Self::log_q(q))
    }

    /// The table's log q of `q` (its lowest for q <= 0), for [`Self::cell_log`].
    #[inline]
    pub fn log_q(q: f64) -> f64 {
        if q > 0.0 {
            fmath::log10(q)
        } else {
            LOG_Q.0
        }
    }

    /// [`Self::cell`] at `lq = Self::log_q(q)`: several cells at one
    /// ionization rate take its logarithm once.
    #[inline]
    pub fn cell_log(&self, h_km: f64, lq: f64) -> Cell {
        let u = ((h_km - H_KM.0) / DH_KM).clamp(0.0, (self.nh - 1) as f64);
        let v = ((lq - LOG_Q.0) / D_LOG_Q).clamp(0.0, (self.nq - 1) as f64);
        let (ih, iq) = ((u as usize).min(self.nh - 2), (v as usize).min(self.nq - 2));
        let (fu, fv) = (u - ih as f64, v - iq as f64);
        let base = ih * self.nq + iq;
        Cell {
            i: [base, base + 1, base + self.nq, base + self.nq + 1],
            w: [(1.0 - fu) * (1.0 - fv), (1.0 - fu) * fv, fu * (1.0 - fv), fu * fv],
        }
    }

    /// The interpolated node at (`h_km`, `q`).
    pub fn at(&self, h_km: f64, q: f64) -> Node {
        let c = self.cell(h_km, q);
        let mut out = Node::default();
        for (&i, &w) in c.i.iter().zip(&c.w) {
            let n = &self.nodes[i];
            for k in 0..5 {
                out.per_kev[k] += w * n.per_kev[k];
            }
            for k in 0..9 {
                out.channels[k] += (w as f32) * n.channels[k];
            }
            for k in 0..2 {
                out.tau[k] += (w as f32) * n.tau[k];
            }
        }
        out
    }
}
