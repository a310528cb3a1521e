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
//!
//! Last come the lines' volume emission rates, `*_ver_cm3_s` (photons
//! cm^-3 s^-1): each bin's photons/s over the curtain's footprint area `A`
//! times the bin's height, the footprint average. `A` is the area of the
//! footprint cells above `footprint.threshold` (the cells beams start
//! from: the box `length x width` for `footprint.uniform`), written in the
//! CSV's first line (a `#` comment). [`columns`] integrates them over
//! altitude: each curtain's column brightness per line in rayleigh, 1 R =
//! 1e6 photons cm^-2 s^-1 in the column (Hunten, Roach & Chamberlain 1956,
//! J. Atmos. Terr. Phys. 8, 345), `4 pi I = 1e-6 sum VER dz`, and in R per
//! erg cm^-2 s^-1 of the curtain's mean energy flux over `A` (its electron
//! power over `A`; the ratio does not depend on `A`). The published 557.7
//! nm yield is about 1-1.4 kR per erg cm^-2 s^-1 for E0 of a few keV (Rees
//! & Luckey 1974, J. Geophys. Res. 79, 5181; GLOW at E0 = 3 keV: 1268 R,
//! `crate::physics::air_extinction::REFERENCE_MIX`).

use crate::physics::atmosphere::Atmosphere;
use crate::physics::chemistry::CHANNEL_NAMES;
use crate::physics::deposition::fang::KEV_PER_ION_PAIR;
use crate::physics::emission::line_colour::{ColourTable, EmissionModel};
use crate::pipeline::plan::BakePlan;

use crate::pipeline::beams::{self, BeamError, BeamStats};
use crate::pipeline::deposit::StepDeposit;
use crate::scene::Scene;
use crate::util::progress::Progress;

/// The lines with a volume emission rate and a column, in the profile's
/// order (its columns 3 to 7): CSV name prefixes.
pub const LINE_NAMES: [&str; 5] = ["n2p_4278", "oi_5577", "oi_6300", "oi_6364", "n2_1p"];

/// Photons cm^-2 s^-1 of column per rayleigh.
pub const PHOTONS_PER_RAYLEIGH: f64 = 1e6;

/// Square centimetres per square kilometre.
const CM2_PER_KM2: f64 = 1e10;

/// Bin width, km.
pub const BIN_KM: f64 = 0.5;

/// CSV header (the first six columns are the interface `aurora profile`
/// promises; the rest follow: the deposited power, then the chemistry's
/// channels, [`CHANNEL_NAMES`] prefixed `oi_5577_` (g_) and `oi_6300_` (r_)).
pub const HEADER: &str = "curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300,oi_6364,n2_1p,deposited_kev_s,\
oi_5577_impact,oi_5577_n2a,oi_5577_recombination,oi_5577_n2d,\
oi_6300_impact,oi_6300_recombination,oi_6300_n2d,oi_6300_cascade,oi_6300_other,\
n2p_4278_ver_cm3_s,oi_5577_ver_cm3_s,oi_6300_ver_cm3_s,oi_6364_ver_cm3_s,n2_1p_ver_cm3_s";

/// Values per bin: the seven of [`CurtainProfile::bins`] and the channels.
pub const COLUMNS: usize = 7 + CHANNEL_NAMES.len();

/// One curtain's profile: rates per bin, bins from `z0` up every [`BIN_KM`].
#[derive(Clone, Debug, PartialEq)]
pub struct CurtainProfile {
    pub z0: f64,
    /// The footprint's area above threshold, km^2 (module doc); 0 before
    /// [`profile`] sets it.
    pub area_km2: f64,
    /// The curtain's electron power into the atmosphere, W.
    pub electron_power_w: f64,
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

    /// Bin `i`'s volume emission rate of each of [`LINE_NAMES`], photons
    /// cm^-3 s^-1: its photons/s over the area times the bin's height (0
    /// without an area).
    pub fn ver_cm3_s(&self, i: usize) -> [f64; 5] {
        let volume_cm3 = self.area_km2 * CM2_PER_KM2 * BIN_KM * 1e5;
        let b = &self.bins[i];
        std::array::from_fn(|k| if volume_cm3 > 0.0 { b[1 + k] / volume_cm3 } else { 0.0 })
    }

    /// The mean energy flux over the area, erg cm^-2 s^-1 (0 without one).
    pub fn energy_flux_erg_cm2_s(&self) -> f64 {
        if self.area_km2 > 0.0 {
            self.electron_power_w * 1e7 / (self.area_km2 * CM2_PER_KM2)
        } else {
            0.0
        }
    }
}

/// One curtain's columns: the lines' brightness seen along the vertical
/// through the footprint average.
#[derive(Clone, Debug, PartialEq)]
pub struct CurtainColumn {
    pub area_km2: f64,
    pub energy_flux_erg_cm2_s: f64,
    /// Rayleigh, per [`LINE_NAMES`].
    pub rayleigh: [f64; 5],
    /// Rayleigh per erg cm^-2 s^-1 of energy flux, per [`LINE_NAMES`].
    pub rayleigh_per_erg: [f64; 5],
}

/// The curtain's column brightness per line: the volume emission rates
/// integrated over altitude (module doc).
pub fn column(c: &CurtainProfile) -> CurtainColumn {
    let dz_cm = BIN_KM * 1e5;
    let mut rayleigh = [0.0; 5];
    for i in 0..c.bins.len() {
        let v = c.ver_cm3_s(i);
        for k in 0..5 {
            rayleigh[k] += v[k] * dz_cm / PHOTONS_PER_RAYLEIGH;
        }
    }
    let flux = c.energy_flux_erg_cm2_s();
    let rayleigh_per_erg = rayleigh.map(|r| if flux > 0.0 { r / flux } else { 0.0 });
    CurtainColumn { area_km2: c.area_km2, energy_flux_erg_cm2_s: flux, rayleigh, rayleigh_per_erg }
}

/// Every curtain's [`column`], in scene order.
pub fn columns(p: &Profile) -> Vec<CurtainColumn> {
    p.curtains.iter().map(column).collect()
}

/// The area of a footprint's cells above `threshold`, km^2.
pub fn footprint_area_km2(f: &crate::pipeline::footprint::Footprint, threshold: f64) -> f64 {
    f.data.iter().filter(|&&d| d as f64 > threshold).count() as f64 * f.cell_area_km2()
}

/// The first line of both CSVs: how the area and the units are taken.
fn area_comment(p: &Profile) -> String {
    let areas: Vec<String> = p.curtains.iter().map(|c| format!("{:.6e}", c.area_km2)).collect();
    format!(
        "# footprint area per curtain, km^2: {} (the footprint cells above footprint.threshold, each its length x width \
over the cell counts); *_ver_cm3_s: photons cm^-3 s^-1, the bin's photons/s over that area times {BIN_KM} km\n",
        areas.join(" ")
    )
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
    CurtainProfile { z0, area_km2: 0.0, electron_power_w: 0.0, bins }
}

/// Traces the scene's beams exactly as the bake does and bins their
/// deposits per curtain, from the atmosphere's bottom to the highest deposit.
pub fn profile(scene: &Scene, progress: &dyn Progress) -> Result<Profile, BeamError> {
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
    let threshold = scene.footprint.threshold;
    let curtains = deposits
        .iter()
        .enumerate()
        .map(|(c, d)| CurtainProfile {
            area_km2: footprint_area_km2(&plan.footprints[c], threshold),
            electron_power_w: beam_stats.curtains.get(c).map_or(0.0, |p| p.electron_power_w),
            ..bin_deposits(d, &model, &plan.colour_table, z0, z1)
        })
        .collect();
    Ok(Profile { curtains, beam_stats })
}

/// The profile's rows, one per curtain and bin, in [`HEADER`]'s columns:
/// the curtain's index, the bin's centre altitude, the bin's values and its
/// volume emission rates.
pub fn rows(p: &Profile) -> Vec<Vec<f64>> {
    let mut out = Vec::with_capacity(p.curtains.iter().map(|c| c.bins.len()).sum());
    for (ci, c) in p.curtains.iter().enumerate() {
        for (i, b) in c.bins.iter().enumerate() {
            let mut row = Vec::with_capacity(2 + COLUMNS + 5);
            row.extend([ci as f64, c.centre(i)]);
            row.extend(b.iter().chain(c.ver_cm3_s(i).iter()));
            out.push(row);
        }
    }
    out
}

/// The unit of a column of [`HEADER`] (module doc): ion pairs/s, photons/s
/// and keV/s over the whole curtain, photons cm^-3 s^-1 for the volume
/// emission rates.
pub fn unit(column: &str) -> &'static str {
    match column {
        "curtain" => "index",
        "altitude_km" => "km",
        "ionization" => "ion pairs s^-1",
        "deposited_kev_s" => "keV s^-1",
        c if c.ends_with("_ver_cm3_s") => "photons cm^-3 s^-1",
        _ => "photons s^-1",
    }
}

/// The profile as CSV (a `#` line naming the footprint areas, [`HEADER`],
/// then one row per curtain and bin: [`rows`]).
pub fn to_csv(p: &Profile) -> String {
    let rows = rows(p);
    let mut s = String::with_capacity(64 * rows.len() + 128);
    s.push_str(&area_comment(p));
    s.push_str(HEADER);
    s.push('\n');
    for row in &rows {
        s.push_str(&format!("{},{:.2}", row[0] as usize, row[1]));
        for x in &row[2..] {
            s.push_str(&format!(",{x:.6e}"));
        }
        s.push('\n');
    }
    s
}

/// Header of [`columns_to_csv`].
pub const COLUMNS_HEADER: &str = "curtain,footprint_area_km2,energy_flux_erg_cm2_s,\
n2p_4278_r,oi_5577_r,oi_6300_r,oi_6364_r,n2_1p_r,\
n2p_4278_r_per_erg,oi_5577_r_per_erg,oi_6300_r_per_erg,oi_6364_r_per_erg,n2_1p_r_per_erg";

/// Each curtain's [`column`] as CSV (`aurora profile`'s `FILE.columns.csv`):
/// the area comment, [`COLUMNS_HEADER`], one row per curtain.
pub fn columns_to_csv(p: &Profile) -> String {
    let mut s = area_comment(p);
    s.push_str(
        "# *_r: column brightness in rayleigh (1 R = 1e6 photons cm^-2 s^-1 in the column); *_r_per_erg: \
per erg cm^-2 s^-1 of energy_flux_erg_cm2_s, the curtain's electron power over its footprint area\n",
    );
    s.push_str(COLUMNS_HEADER);
    s.push('\n');
    for (ci, c) in columns(p).iter().enumerate() {
        s.push_str(&format!("{ci},{:.6e},{:.6e}", c.area_km2, c.energy_flux_erg_cm2_s));
        for x in c.rayleigh.iter().chain(c.rayleigh_per_erg.iter()) {
            s.push_str(&format!(",{x:.6e}"));
        }
        s.push('\n');
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
                CurtainProfile { z0: 50.0, area_km2: 2.0, electron_power_w: 1.0, bins: vec![[1.0; COLUMNS]; 3] },
                CurtainProfile { z0: 50.0, area_km2: 2.0, electron_power_w: 1.0, bins: vec![[0.0; COLUMNS]; 3] },
            ],
            beam_stats: BeamStats::default(),
        };
        let csv = to_csv(&p);
        let lines: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
        assert!(csv.starts_with("# footprint area per curtain, km^2: 2.000000e0 2.000000e0 "), "{csv}");
        assert!(lines[0].starts_with("curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300"));
        assert_eq!(lines.len(), 7);
        assert!(lines[1].starts_with("0,50.25,") && lines[4].starts_with("1,50.25,"));
        assert_eq!(lines[1].split(',').count(), HEADER.split(',').count());
        assert_eq!(COLUMNS + 5, HEADER.split(',').count() - 2);
    }

    #[test]
    fn volume_emission_rates_integrate_to_the_column_in_rayleigh() {
        // 2 km^2 and 1e16 photons/s of 557.7 nm in each of 3 bins: per bin
        // 1e16 / (2e10 cm^2 * 5e4 cm) = 1e1 photons cm^-3 s^-1; the column
        // 3 * 1e1 * 5e4 / 1e6 = 1.5 R; 1 W over 2 km^2 is 5e-4 erg cm^-2 s^-1.
        let mut bins = vec![[0.0; COLUMNS]; 3];
        for b in &mut bins {
            b[2] = 1e16;
        }
        let c = CurtainProfile { z0: 50.0, area_km2: 2.0, electron_power_w: 1.0, bins };
        assert!((c.ver_cm3_s(1)[1] - 10.0).abs() < 1e-12);
        let col = column(&c);
        assert!((col.rayleigh[1] - 1.5).abs() < 1e-12, "{col:?}");
        assert!((col.energy_flux_erg_cm2_s - 5e-4).abs() < 1e-16);
        assert!((col.rayleigh_per_erg[1] - 3000.0).abs() < 1e-9);
        assert_eq!(col.rayleigh[0], 0.0);
    }
}
