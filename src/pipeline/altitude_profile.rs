//! Altitude profiles, as an aurora physicist would check us: per curtain,
//! the ionization rate and the photon rate of each line in 0.5 km altitude
//! bins, summed from the deposits the beams actually made (the bake's own
//! beams, random streams and deposition model: [`crate::pipeline::beams::trace_deposits`]),
//! not the parameterisation evaluated afresh.
//!
//! A step's deposit `P` between altitudes `z_start` and `z_end` is spread
//! uniformly in altitude over the bins it crosses (the way a segment kernel
//! spreads it along the step); a level step falls in one bin. Ion pairs per
//! second are `P / 35 eV` ([`crate::physics::deposition::fang::KEV_PER_ION_PAIR`]); photons per
//! second of each line are `P` times the line's yield per keV at the centre
//! of the part of the step inside the bin: with the chemistry (the default,
//! `colour.lines = "chemistry"`) the bake's own table,
//! [`crate::physics::emission::line_colour::ColourTable::line_yields`], at the ionization rate the
//! deposit was coloured with (its record's `q`); with the simple model
//! [`crate::physics::emission::line_colour::EmissionModel::yields`]. Units: per second over the
//! whole curtain (not per volume): the curtain's area times the
//! height-resolved rate.
//!
//! After the promised columns come the chemistry's source terms: photons/s
//! of 557.7 nm made by electron impact on O, N2(A) + O, O2+ recombination
//! and N(2D) + NO with O2+ + N, and of 630.0 nm by electron impact, O2+
//! recombination, N(2D), the O(1S) cascade and the rest (N+ + O2, O2
//! dissociation) ([`crate::physics::chemistry::Channels`]); each line's channels sum
//! to its column. Zero with the simple model.

use crate::physics::atmosphere::Atmosphere;
use crate::physics::chemistry::CHANNEL_NAMES;
use crate::physics::deposition::fang::KEV_PER_ION_PAIR;
use crate::physics::emission::line_colour::{ColourTable, EmissionModel};
use crate::pipeline::bake::plan::BakePlan;
use crate::pipeline::bake::BakeError;
use crate::pipeline::beams::{self, BeamStats};
use crate::pipeline::deposit::StepDeposit;
use crate::scene::Scene;
use crate::util::progress::Progress;

/// Bin width, km.
pub const BIN_KM: f64 = 0.5;

/// CSV header (the first six columns are the interface `aurora profile`
/// promises; the rest follow: the deposited power, then the chemistry's
/// channels, [`CHANNEL_NAMES`] prefixed `oi_5577_` (g_) and `oi_6300_` (r_)).
pub const HEADER: &str = "curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300,oi_6364,n2_1p,deposited_kev_s,\
oi_5577_impact,oi_5577_n2a,oi_5577_recombination,oi_5577_n2d,\
oi_6300_impact,oi_6300_recombination,oi_6300_n2d,oi_6300_cascade,oi_6300_other";

/// Values per bin: the seven of [`CurtainProfile::bins`] and the channels.
pub const COLUMNS: usize = 7 + CHANNEL_NAMES.len();

/// One curtain's profile: rates per bin, bins from `z0` up every [`BIN_KM`].
#[derive(Clone, Debug, PartialEq)]
pub struct CurtainProfile {
    pub z0: f64,
    /// Per bin: ion pairs/s, then photons/s of n2p_4278, oi_5577, oi_6300,
    /// oi_6364, n2_1p, then deposited keV/s, then the chemistry's channels
    /// (photons/s, module doc).
    pub bins: Vec<[f64; COLUMNS]>,
}

impl CurtainProfile {
    /// Centre altitude of bin `i`, km.
    pub fn centre(&self, i: usize) -> f64 {
        self.z0 + (i as f64 + 0.5) * BIN_KM
    }
}

/// Profiles of every curtain, and the beam stage's power accounting.
#[derive(Clone, Debug)]
pub struct Profile {
    pub curtains: Vec<CurtainProfile>,
    pub beam_stats: BeamStats,
}

/// Bins `deposits` from `z0` to `z1` km (bins outside are dropped by the
/// caller's choice of range, which covers the atmosphere and the beams).
/// `table` gives the chemistry's yields (at each deposit's `q`) when it has
/// them, `model` the simple model's otherwise.
pub fn bin_deposits(deposits: &[StepDeposit], model: &EmissionModel, table: &ColourTable, z0: f64, z1: f64) -> CurtainProfile {
    let n = ((z1 - z0) / BIN_KM).ceil().max(1.0) as usize;
    let mut bins = vec![[0.0; COLUMNS]; n];
    let mut add = |z: f64, p: f64, q: f64| {
        let i = ((z - z0) / BIN_KM).floor();
        if i < 0.0 || i >= n as f64 || p == 0.0 {
            return;
        }
        let b = &mut bins[i as usize];
        let y = match table.line_node(z, q) {
            Some(node) => {
                for (k, c) in node.channels.iter().enumerate() {
                    b[7 + k] += p * *c as f64;
                }
                table.line_yields(z, q).unwrap_or_default()
            }
            None => model.yields(z),
        };
        b[0] += p / KEV_PER_ION_PAIR;
        b[1] += p * y.n2p_4278;
        b[2] += p * y.oi_5577;
        b[3] += p * y.oi_6300;
        b[4] += p * y.oi_6364;
        b[5] += p * y.n2_1p;
        b[6] += p;
    };
    for d in deposits {
        let (lo, hi) = if d.z_start < d.z_end { (d.z_start, d.z_end) } else { (d.z_end, d.z_start) };
        if hi - lo < 1e-9 {
            add(lo, d.power_kev_s, d.q);
            continue;
        }
        // Split at bin edges; each piece gets its share of the altitude span.
        let mut a = lo;
        while a < hi {
            let edge = z0 + (((a - z0) / BIN_KM).floor() + 1.0) * BIN_KM;
            let b = edge.min(hi);
            add(0.5 * (a + b), d.power_kev_s * (b - a) / (hi - lo), d.q);
            a = b;
        }
    }
    CurtainProfile { z0, bins }
}

/// Traces the scene's beams exactly as the bake does and bins their
/// deposits per curtain, from the atmosphere's bottom to the highest deposit.
pub fn profile(scene: &Scene, progress: &dyn Progress) -> Result<Profile, BakeError> {
    // The bake's own plan: its footprints, atmosphere and colour table.
    let plan = BakePlan::new(scene, progress);
    let atmosphere: &Atmosphere = &plan.atmosphere;
    let (deposits, beam_stats) = beams::trace_deposits(scene, &plan.footprints, atmosphere, &plan.colour_table, progress)?;
    let model = EmissionModel::new(atmosphere.clone());
    let z0 = atmosphere.bottom_km().floor();
    // Up to the highest deposit: the spectrum's share above a beam's start
    // goes along the field line above it (`beams`), higher than `top_km`.
    let highest = deposits.iter().flatten().map(|d| d.z_start.max(d.z_end)).fold(f64::NEG_INFINITY, f64::max);
    let z1 = ((scene.beams.top_km + scene.beams.top_noise_km).max(highest) + 1.0).ceil();
    let curtains = deposits.iter().map(|d| bin_deposits(d, &model, &plan.colour_table, z0, z1)).collect();
    Ok(Profile { curtains, beam_stats })
}

/// The profile as CSV ([`HEADER`], then one row per curtain and bin).
pub fn to_csv(p: &Profile) -> String {
    let mut s = String::with_capacity(64 * p.curtains.iter().map(|c| c.bins.len()).sum::<usize>() + 128);
    s.push_str(HEADER);
    s.push('\n');
    for (ci, c) in p.curtains.iter().enumerate() {
        for (i, b) in c.bins.iter().enumerate() {
            s.push_str(&format!("{ci},{:.2}", c.centre(i)));
            for x in b {
                s.push_str(&format!(",{x:.6e}"));
            }
            s.push('\n');
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binning_conserves_power_and_splits_by_altitude_overlap() {
        let m = EmissionModel::default();
        let t = ColourTable::physical(&m);
        let d = [
            StepDeposit { z_start: 101.3, z_end: 100.2, power_kev_s: 11.0, q: 0.0 },
            StepDeposit { z_start: 120.0, z_end: 120.0, power_kev_s: 2.0, q: 0.0 },
            StepDeposit { z_start: 99.0, z_end: 99.9, power_kev_s: 1.0, q: 0.0 }, // climbing step
        ];
        let p = bin_deposits(&d, &m, &t, 50.0, 200.0);
        let total: f64 = p.bins.iter().map(|b| b[6]).sum();
        assert!((total - 14.0).abs() < 1e-12);
        // 100.2-101.3 spans bins [100, 100.5), [100.5, 101), [101, 101.5):
        // 0.3, 0.5, 0.3 of 1.1 km.
        let at = |z: f64| p.bins[((z - 50.0) / BIN_KM) as usize][6];
        assert!((at(100.2) - 11.0 * 0.3 / 1.1).abs() < 1e-9);
        assert!((at(100.7) - 11.0 * 0.5 / 1.1).abs() < 1e-9);
        assert!((at(101.2) - 11.0 * 0.3 / 1.1).abs() < 1e-9);
        assert_eq!(at(120.1), 2.0);
        // Ionization is power / 35 eV.
        let ion: f64 = p.bins.iter().map(|b| b[0]).sum();
        assert!((ion - 14.0 / 0.035).abs() < 1e-9);
        assert!((p.centre(0) - 50.25).abs() < 1e-12);
        // Lines: the yield at each piece's centre.
        let i = ((120.0 - 50.0) / BIN_KM) as usize;
        assert!((p.bins[i][2] - 2.0 * m.yields(120.0).oi_5577).abs() < 1e-12);
    }

    #[test]
    fn csv_has_the_promised_header_and_one_row_per_curtain_and_bin() {
        let p = Profile {
            curtains: vec![
                CurtainProfile { z0: 50.0, bins: vec![[1.0; COLUMNS]; 3] },
                CurtainProfile { z0: 50.0, bins: vec![[0.0; COLUMNS]; 3] },
            ],
            beam_stats: BeamStats::default(),
        };
        let csv = to_csv(&p);
        let lines: Vec<&str> = csv.lines().collect();
        assert!(lines[0].starts_with("curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300"));
        assert_eq!(lines.len(), 7);
        assert!(lines[1].starts_with("0,50.25,") && lines[4].starts_with("1,50.25,"));
        assert_eq!(lines[1].split(',').count(), HEADER.split(',').count());
    }
}
