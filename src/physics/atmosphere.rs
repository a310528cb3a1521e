//! The neutral atmosphere, 50-700 km: mass density, the number densities of
//! N2, O2 and O, the column mass above an altitude, and the ambient state
//! the chemistry needs with it (`crate::physics::chemistry::ambient`).
//! `[atmosphere] model` chooses the table (terms and validations:
//! docs/data.md):
//!
//! - **`us1976`** (the default): the U.S. Standard Atmosphere 1976 (NOAA,
//!   NASA, USAF, NOAA-S/T 76-1562; public domain), every 0.5 km from 50 to
//!   700 km with its temperature, in `data/us1976.csv`, compiled in; made by
//!   `tools/reference/ussa1976_table.py` with the `ussa1976` package (the
//!   standard defines O from 86 km: below, its first slope continues).
//! - **`nrlmsis21`**: NRLMSIS 2.1 (Emmert et al. 2022, J. Geophys. Res.
//!   Space Physics 127, e2022JA030896) for an auroral-zone winter night, 67
//!   N, 20 E, 2020-01-15 00:00 UT, F10.7 = 150, Ap = 15, on the same grid
//!   (`tools/reference/msis_table.py`, `pymsis`). Research, academic and
//!   non-profit use only: read at run time from `nrlmsis21.csv` in the data
//!   folder (`crate::physics::data_files`), never compiled in.
//!
//! Between table altitudes every quantity is interpolated log-linearly (an
//! exponential within each segment, with its own scale height), and outside
//! the table the end segments are extrapolated. The column mass above `h` is
//! the exact integral of that piecewise-exponential density (per segment
//! `H_i (rho_i - rho_{i+1})`), so `-dC/dh = rho` holds everywhere.
//!
//! Units: altitude km, mass density g cm^-3, number density cm^-3, column
//! mass g cm^-2 (the unit of the electron range-energy relation in `csda`).

use crate::physics::chemistry::ambient::AmbientTable;
use crate::physics::data_files::{self, DataError};
use crate::scene::{AtmosphereModel, AtmosphereParams, Ionosphere};
use crate::util::fmath;
use std::sync::Arc;

/// Centimetres per kilometre.
pub const CM_PER_KM: f64 = 1e5;

/// The U.S. Standard Atmosphere 1976 table (module doc): a CSV with `#`
/// comment lines, a header, then altitude_km, rho_g_cm3, n2_cm3, o2_cm3,
/// o_cm3, temperature_k, ar_cm3, he_cm3, h_cm3.
const US1976_CSV: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/us1976.csv"));

/// Number densities of the three species that matter for the aurora, cm^-3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Composition {
    pub n2: f64,
    pub o2: f64,
    pub o: f64,
}

impl Composition {
    /// Total of the three, cm^-3 (Ar, He, H are below 1 % in 80-500 km).
    pub fn total(&self) -> f64 {
        self.n2 + self.o2 + self.o
    }
}

/// The tabulated atmosphere with per-segment scale heights and columns.
#[derive(Clone, Debug)]
pub struct Atmosphere {
    h: Vec<f64>,
    /// ln rho, ln n(N2), ln n(O2), ln n(O) at the nodes.
    ln: Vec<[f64; 4]>,
    /// Density scale height of segment i (between nodes i and i+1), km.
    scale: Vec<f64>,
    /// Column mass above node i, g cm^-2.
    col: Vec<f64>,
    /// rho at node i, g cm^-3: `exp(ln[i][0])`, made once (the column mass
    /// takes it at every call).
    rho_node: Vec<f64>,
    /// `1 / dh` when the nodes are evenly spaced (`h[i] = h[0] + i dh`
    /// exactly, NRLMSIS's 0.5 km), for [`Self::segment`]'s first guess; 0
    /// otherwise.
    inv_dh: f64,
    /// Tn, N(4S), NO and the ambient ionosphere for the chemistry.
    ambient: Arc<AmbientTable>,
}

impl Default for Atmosphere {
    fn default() -> Self {
        Self::us1976()
    }
}

impl Atmosphere {
    /// The tables `[atmosphere]` names: the neutral model's, and the ambient
    /// state from the ionosphere it names. A table that is not compiled in
    /// is read from the data folder (`crate::physics::data_files`).
    pub fn of_params(params: &AtmosphereParams) -> Result<Self, DataError> {
        if (params.model, params.ionosphere) == (AtmosphereModel::Us1976, Ionosphere::ClosedForm) {
            // The default: built once for the process (every stage asks).
            return Ok(Self::us1976());
        }
        let rows = match params.model {
            AtmosphereModel::Us1976 => us1976_rows().to_vec(),
            AtmosphereModel::Nrlmsis21 => {
                let (path, text) = data_files::read(&data_files::NRLMSIS21, params)?;
                data_files::file_rows(&path, &text, 7, Some(1))?
            }
        };
        let ions = match params.ionosphere {
            Ionosphere::ClosedForm => None,
            Ionosphere::Glow => {
                let (path, text) = data_files::read(&data_files::IONOSPHERE, params)?;
                Some(data_files::file_rows(&path, &text, 5, None)?.iter().map(|r| [r[0], r[1], r[2], r[3], r[4]]).collect::<Vec<_>>())
            }
        };
        Ok(Self::from_tables(params.model, &rows, ions))
    }

    /// The compiled-in U.S. Standard Atmosphere 1976 with the closed-form
    /// ionosphere: the default, which reads no file.
    pub fn us1976() -> Self {
        static TABLE: std::sync::OnceLock<Atmosphere> = std::sync::OnceLock::new();
        TABLE.get_or_init(|| Self::from_tables(AtmosphereModel::Us1976, us1976_rows(), None)).clone()
    }

    /// NRLMSIS 2.1 with GLOW's ionosphere, the pair the chemistry and the
    /// deposition were validated on, from the source tree's `data/`
    /// (`data_files::BUILD_DATA_DIR`) whatever `AURORA_DATA` says: for the
    /// tests and tools that check against them. Panics where the files are
    /// not there (a binary away from its source tree).
    pub fn nrlmsis21() -> Self {
        static TABLE: std::sync::OnceLock<Atmosphere> = std::sync::OnceLock::new();
        TABLE
            .get_or_init(|| {
                let params = AtmosphereParams {
                    model: AtmosphereModel::Nrlmsis21,
                    ionosphere: Ionosphere::Glow,
                    data: Some(data_files::BUILD_DATA_DIR.into()),
                    base_dir: None,
                };
                Self::of_params(&params).unwrap_or_else(|e| panic!("{e}"))
            })
            .clone()
    }

    /// The ambient state the chemistry needs with this atmosphere.
    pub fn ambient(&self) -> &AmbientTable {
        &self.ambient
    }

    /// From a neutral table's rows (altitude, rho, N2, O2, O, T, then
    /// NRLMSIS's N(4S)) and the ionosphere's rows (altitude, Te, Ti, ne, NO;
    /// `None`: the closed forms on the neutral table's altitudes).
    fn from_tables(model: AtmosphereModel, rows: &[Vec<f64>], ions: Option<Vec<[f64; 5]>>) -> Self {
        let h: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let tn: Vec<f64> = rows.iter().map(|r| r[5]).collect();
        let n4s: Vec<f64> = match model {
            AtmosphereModel::Nrlmsis21 => rows.iter().map(|r| r[6]).collect(),
            AtmosphereModel::Us1976 => {
                let top = rows.iter().find(|r| r[0] >= 400.0).unwrap_or(&rows[rows.len() - 1]);
                rows.iter().map(|r| crate::physics::chemistry::ambient::closed_form_n4s(r[0], r[4], r[5], top[4], top[5])).collect()
            }
        };
        let neutral: Vec<[f64; 3]> = (0..h.len()).map(|i| [h[i], tn[i], n4s[i]]).collect();
        let ions = ions.unwrap_or_else(|| AmbientTable::closed_form_ions(&h, &tn));
        let five: Vec<[f64; 5]> = rows.iter().map(|r| [r[0], r[1], r[2], r[3], r[4]]).collect();
        Self::from_rows(&five, AmbientTable::new(&neutral, &ions))
    }

    /// Lowest and highest tabulated altitude, km (outside, the end segments
    /// are extrapolated).
    pub fn bottom_km(&self) -> f64 {
        self.h[0]
    }
    pub fn top_km(&self) -> f64 {
        self.h[self.h.len() - 1]
    }

    /// A table of rows [altitude km, rho g cm^-3, n(N2), n(O2), n(O) cm^-3],
    /// ascending altitude, every value positive.
    fn from_rows(rows: &[[f64; 5]], ambient: AmbientTable) -> Self {
        let n = rows.len();
        let h: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let ln: Vec<[f64; 4]> = rows.iter().map(|r| [fmath::ln(r[1]), fmath::ln(r[2]), fmath::ln(r[3]), fmath::ln(r[4])]).collect();
        let scale: Vec<f64> = (0..n - 1).map(|i| (h[i + 1] - h[i]) / (ln[i][0] - ln[i + 1][0])).collect();
        let mut col = vec![0.0; n];
        // Above the last node the last segment's exponential continues to
        // infinity: integral = rho * H.
        col[n - 1] = rows[n - 1][1] * scale[n - 2] * CM_PER_KM;
        for i in (0..n - 1).rev() {
            // Exact integral of rho_i exp(-(h - h_i)/H_i) over the segment.
            col[i] = col[i + 1] + scale[i] * (rows[i][1] - rows[i + 1][1]) * CM_PER_KM;
        }
        let rho_node = ln.iter().map(|l| fmath::exp(l[0])).collect();
        let dh = (h[n - 1] - h[0]) / (n - 1) as f64;
        let even = dh > 0.0 && h.iter().enumerate().all(|(i, &x)| x == h[0] + i as f64 * dh);
        let inv_dh = if even { 1.0 / dh } else { 0.0 };
        Self { h, ln, scale, col, rho_node, inv_dh, ambient: Arc::new(ambient) }
    }

    /// Index of the segment holding `h` (end segments extrapolate).
    #[inline]
    fn segment(&self, h: f64) -> usize {
        let n = self.h.len();
        if self.inv_dh == 0.0 {
            let i = self.h.partition_point(|&x| x <= h);
            return i.saturating_sub(1).min(n - 2);
        }
        // Evenly spaced nodes: the node below h by its offset (a float to
        // integer cast saturates, NaN gives 0), then corrected to the last
        // node at or below h (0 if none), as the search finds it.
        let mut i = (((h - self.h[0]) * self.inv_dh) as usize).min(n - 1);
        while i + 1 < n && self.h[i + 1] <= h {
            i += 1;
        }
        while i > 0 && self.h[i] > h {
            i -= 1;
        }
        i.min(n - 2)
    }

    /// Log-linear interpolation of column `k` of `ln`.
    #[inline]
    fn interp(&self, h: f64, k: usize) -> f64 {
        self.interp_in(self.segment(h), h, k)
    }

    /// [`Self::interp`] in segment `i` (`self.segment(h)`).
    #[inline]
    fn interp_in(&self, i: usize, h: f64, k: usize) -> f64 {
        let t = (h - self.h[i]) / (self.h[i + 1] - self.h[i]);
        fmath::exp(self.ln[i][k] + t * (self.ln[i + 1][k] - self.ln[i][k]))
    }

    /// Mass density at altitude `h` km, g cm^-3.
    #[inline]
    pub fn rho(&self, h: f64) -> f64 {
        self.interp(h, 0)
    }

    /// N2, O2 and O number densities at `h` km, cm^-3.
    pub fn composition(&self, h: f64) -> Composition {
        Composition { n2: self.interp(h, 1), o2: self.interp(h, 2), o: self.interp(h, 3) }
    }

    /// Density scale height at `h`, km (constant within a table segment).
    pub fn scale_height(&self, h: f64) -> f64 {
        self.scale[self.segment(h)]
    }

    /// Vertical column mass above altitude `h`, g cm^-2: the exact integral of
    /// the piecewise-exponential `rho` from `h` to infinity.
    #[inline]
    pub fn column_mass(&self, h: f64) -> f64 {
        let i = self.segment(h);
        let rho = self.interp_in(i, h, 0);
        let h_i = self.scale[i];
        if h >= self.h[self.h.len() - 1] {
            return rho * h_i * CM_PER_KM;
        }
        // col(h) = col_{i+1} + H_i (rho(h) - rho_{i+1}); below the table the
        // first segment's exponential continues (the same formula).
        self.col[i + 1] + h_i * (rho - self.rho_node[i + 1]) * CM_PER_KM
    }

    /// Column mass along a straight path of length `len_km` from altitude
    /// `h0` to `h1` (plane-parallel atmosphere), g cm^-2:
    /// `int rho ds = (len / |h1 - h0|) |C(h1) - C(h0)|`; a (nearly) horizontal
    /// path uses `rho(mid) len` instead, where the difference would cancel.
    #[inline]
    pub fn slant_column(&self, h0: f64, h1: f64, len_km: f64) -> f64 {
        let dh = (h1 - h0).abs();
        if dh < 1e-6 * len_km.max(1e-300) || dh < 1e-9 {
            return self.rho(0.5 * (h0 + h1)) * len_km * CM_PER_KM;
        }
        (len_km / dh) * (self.column_mass(h0) - self.column_mass(h1)).abs()
    }
}

/// Rows of the compiled-in U.S. Standard Atmosphere table, parsed once. The
/// file is ours and fixed at compile time: a malformed row is a build
/// defect, caught by the tests.
fn us1976_rows() -> &'static [Vec<f64>] {
    static ROWS: std::sync::OnceLock<Vec<Vec<f64>>> = std::sync::OnceLock::new();
    ROWS.get_or_init(|| data_files::rows(US1976_CSV, 6).unwrap_or_else(|(l, m)| panic!("data/us1976.csv:{l}: {m}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sweep() -> impl Iterator<Item = f64> {
        (0..=6500).map(|i| 50.0 + i as f64 * 0.1)
    }

    #[test]
    fn segments_are_the_searched_ones() {
        let a = Atmosphere::nrlmsis21();
        assert!(a.inv_dh > 0.0, "NRLMSIS's nodes are evenly spaced");
        let searched = |h: f64| a.h.partition_point(|&x| x <= h).saturating_sub(1).min(a.h.len() - 2);
        let nodes = a.h.iter().flat_map(|&x| [x, x.next_down(), x.next_up()]);
        let sweep = (0..=80_000).map(|i| 30.0 + i as f64 * 0.01);
        let odd = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1e300, 1e300, 0.0, -0.0];
        for h in nodes.chain(sweep).chain(odd) {
            assert_eq!(a.segment(h), searched(h), "{h}");
        }
    }

    #[test]
    fn column_mass_is_its_formula_bit_for_bit() {
        // The node densities made once give the bits of exp at each call.
        for a in [Atmosphere::us1976(), Atmosphere::nrlmsis21()] {
            for h in (0..=7000).map(|i| 40.0 + i as f64 * 0.1) {
                let i = a.segment(h);
                let want = if h >= a.top_km() {
                    a.rho(h) * a.scale[i] * CM_PER_KM
                } else {
                    a.col[i + 1] + a.scale[i] * (a.rho(h) - fmath::exp(a.ln[i + 1][0])) * CM_PER_KM
                };
                assert_eq!(a.column_mass(h).to_bits(), want.to_bits(), "{h}");
            }
        }
    }

    #[test]
    fn densities_and_column_decrease_monotonically() {
        let a = Atmosphere::us1976();
        let mut prev: Option<(f64, Composition, f64)> = None;
        for h in sweep() {
            let (r, c, col) = (a.rho(h), a.composition(h), a.column_mass(h));
            assert!(r > 0.0 && col > 0.0 && c.n2 > 0.0 && c.o > 0.0);
            if let Some((r0, c0, col0)) = prev {
                assert!(r < r0 && c.n2 < c0.n2 && c.o2 < c0.o2 && col < col0, "not decreasing at {h} km");
            }
            prev = Some((r, c, col));
        }
    }

    #[test]
    fn interpolation_reproduces_the_table_nodes() {
        let a = Atmosphere::us1976();
        for r in us1976_rows() {
            let c = a.composition(r[0]);
            // exp(ln x) round trip: a few ulps of relative error.
            for (got, want) in [(a.rho(r[0]), r[1]), (c.n2, r[2]), (c.o2, r[3]), (c.o, r[4])] {
                assert!((got / want - 1.0).abs() < 1e-12, "{} km: {got} vs {want}", r[0]);
            }
        }
    }

    #[test]
    fn column_at_100_km_is_rho_times_a_6_to_7_km_scale_height() {
        let a = Atmosphere::us1976();
        let h_eff = a.column_mass(100.0) / (a.rho(100.0) * CM_PER_KM);
        assert!((6.0..7.0).contains(&h_eff), "effective scale height {h_eff} km");
    }

    #[test]
    fn column_matches_a_fine_integration_of_the_standard() {
        // Oracle: trapezoid integration of the `ussa1976` package's density on
        // a 50 m grid to 1000 km (the model itself, not this table). The table
        // has 5-25 km nodes where the scale height changes by up to 40 % per
        // segment (110-130 km, where temperature climbs fast); log-linear
        // interpolation measured 1.1 % off at 110 km, < 0.3 % elsewhere: allow 2 %.
        let a = Atmosphere::us1976();
        for (h, want) in [(100.0, 3.4023e-4), (110.0, 7.5828e-5), (150.0, 5.0198e-6), (200.0, 9.6884e-7), (300.0, 1.0560e-7)] {
            let got = a.column_mass(h);
            assert!((got / want - 1.0).abs() < 0.02, "{h} km: {got:e} vs {want:e}");
        }
    }

    #[test]
    fn column_derivative_is_minus_rho() {
        let a = Atmosphere::us1976();
        for h in [82.0, 97.3, 113.0, 161.7, 250.0, 333.0, 480.0] {
            let d = 1e-4;
            let deriv = -(a.column_mass(h + d) - a.column_mass(h - d)) / (2.0 * d * CM_PER_KM);
            // Central difference of an exponential: relative error (d/H)^2/6 < 1e-9,
            // plus cancellation of ~1e-16 C / (rho d) ~ 1e-7.
            assert!((deriv / a.rho(h) - 1.0).abs() < 1e-6, "{h}: {deriv:e} vs {:e}", a.rho(h));
        }
        // Continuity of the column across nodes.
        let rows = us1976_rows();
        for r in &rows[1..rows.len() - 1] {
            let (lo, hi) = (a.column_mass(r[0] - 1e-9), a.column_mass(r[0] + 1e-9));
            assert!((lo / hi - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn slant_column_scales_with_path_length() {
        let a = Atmosphere::us1976();
        let vertical = a.slant_column(120.0, 110.0, 10.0);
        let expect = a.column_mass(110.0) - a.column_mass(120.0);
        assert!((vertical / expect - 1.0).abs() < 1e-12);
        // 60 degrees from the vertical: path twice as long, same heights.
        let slant = a.slant_column(120.0, 110.0, 20.0);
        assert!((slant / (2.0 * expect) - 1.0).abs() < 1e-12);
        // Horizontal: rho * length.
        let flat = a.slant_column(110.0, 110.0, 3.0);
        assert!((flat / (a.rho(110.0) * 3.0 * CM_PER_KM) - 1.0).abs() < 1e-12);
        // Nearly horizontal agrees with horizontal to first order in dh / H.
        let near = a.slant_column(110.0, 110.0 + 1e-5, 3.0);
        assert!((near / flat - 1.0).abs() < 1e-5);
    }

    #[test]
    fn nrlmsis_table_spans_50_to_700_km_and_decreases() {
        let a = Atmosphere::nrlmsis21();
        assert_eq!((a.bottom_km(), a.top_km()), (50.0, 700.0));
        assert_eq!(a.h.len(), 1301);
        let mut prev = f64::INFINITY;
        for i in 0..=6500 {
            let h = 50.0 + i as f64 * 0.1;
            let (r, col) = (a.rho(h), a.column_mass(h));
            assert!(r > 0.0 && col < prev, "{h} km");
            prev = col;
        }
    }

    #[test]
    fn nrlmsis_column_is_hydrostatic_rho_times_kt_over_mg() {
        // Hydrostatic equilibrium: column mass = p / g = rho k T / (m g),
        // with m the mean molecular mass. Oracle from the table's own
        // temperature column; m = rho / (n_N2 + n_O2 + n_O) ignores Ar and He
        // (about 1 % of the number density from 50 to 120 km, up to a few %
        // near 300 km) and g is the point value at h, not the column's mean
        // (g falls 3 % per 100 km): allow 4 %.
        let a = Atmosphere::nrlmsis21();
        let text = std::fs::read_to_string(format!("{}/nrlmsis21.csv", data_files::BUILD_DATA_DIR)).unwrap();
        let rows = data_files::rows(&text, 6).unwrap();
        const K_B: f64 = 1.380649e-16; // erg/K
        for h in [60.0, 80.0, 100.0, 110.0, 130.0, 200.0, 300.0] {
            let r = rows.iter().find(|r| r[0] == h).unwrap();
            let m = r[1] / (r[2] + r[3] + r[4]);
            let g = 980.665 * fmath::powi(6371.0 / (6371.0 + h), 2);
            let want = r[1] * K_B * r[5] / (m * g);
            let got = a.column_mass(h);
            assert!((got / want - 1.0).abs() < 0.04, "{h} km: {got:e} vs {want:e}");
        }
    }

    #[test]
    fn n2_half_quenching_density_for_630_lies_near_260_km() {
        // k [N2] = 1 / tau with k = 3e-11 cm^3/s, tau = 110 s: [N2] = 3.03e8.
        let a = Atmosphere::us1976();
        let h = (0..4200).map(|i| 80.0 + i as f64 * 0.1).find(|&h| a.composition(h).n2 < 1.0 / (110.0 * 3e-11)).unwrap();
        assert!((250.0..275.0).contains(&h), "{h}");
    }

    // ---- Oracles added for the mutation report
    // (docs/mutants/REPORT.md).

    #[test]
    fn scale_height_is_minus_the_inverse_log_slope_of_density() {
        // H = -1 / (d ln rho / dh): inside a segment ln rho is linear, so a
        // central difference is exact to rounding (~1e-16 / (d/H) = 1e-10).
        // Points off both tables' nodes (0.5 km grid, US 1976 nodes).
        for a in [Atmosphere::us1976(), Atmosphere::nrlmsis21()] {
            for h in [52.3, 82.2, 97.3, 113.1, 161.7, 250.2, 333.3, 480.1, 690.7] {
                let d = 1e-4;
                let slope = (fmath::ln(a.rho(h + d)) - fmath::ln(a.rho(h - d))) / (2.0 * d);
                let hs = a.scale_height(h);
                assert!((hs * -slope - 1.0).abs() < 1e-8, "{h} km: H {hs} vs {}", -1.0 / slope);
                assert!((4.0..120.0).contains(&hs), "{h} km: {hs}");
            }
        }
    }

    #[test]
    fn column_continues_as_one_exponential_above_the_table_and_below_it() {
        // Above the top node the last segment's exponential goes on: the
        // column is rho H there, and -dC/dh = rho holds past both ends.
        for a in [Atmosphere::us1976(), Atmosphere::nrlmsis21()] {
            let top = a.top_km();
            for h in [top, top + 50.0] {
                let want = a.rho(h) * a.scale_height(h) * CM_PER_KM;
                assert!((a.column_mass(h) / want - 1.0).abs() < 1e-12, "{h} km");
            }
            let (lo, hi) = (a.column_mass(top - 1e-9), a.column_mass(top + 1e-9));
            assert!((lo / hi - 1.0).abs() < 1e-9);
            for h in [a.bottom_km() - 10.0, top + 20.0] {
                let d = 1e-4;
                let deriv = -(a.column_mass(h + d) - a.column_mass(h - d)) / (2.0 * d * CM_PER_KM);
                assert!((deriv / a.rho(h) - 1.0).abs() < 1e-6, "{h}: {deriv:e} vs {:e}", a.rho(h));
            }
        }
        let a = Atmosphere::us1976();
        assert_eq!((a.bottom_km(), a.top_km()), (50.0, 700.0));
    }

    #[test]
    fn slant_column_is_symmetric_and_continuous_at_the_horizontal_switch() {
        // The column along a path does not depend on its direction, and the
        // switch to rho(mid) len for near-horizontal paths joins the general
        // formula to first order in dh / H (dh = 1e-6 len here: 1e-7 of H).
        let a = Atmosphere::nrlmsis21();
        assert_eq!(a.slant_column(110.0, 130.0, 40.0), a.slant_column(130.0, 110.0, 40.0));
        let len = 3.0;
        let below = a.slant_column(110.0, 110.0 + 0.99e-6 * len, len);
        let above = a.slant_column(110.0, 110.0 + 1.01e-6 * len, len);
        assert!((below / above - 1.0).abs() < 1e-6, "{below:e} {above:e}");
        // A short path of dh 1e-10 km (below the absolute switch, 1e-9 km):
        // rho len, not the cancelling difference.
        let tiny = a.slant_column(110.0, 110.0 + 1e-10, 2e-10);
        assert!((tiny / (a.rho(110.0) * 2e-10 * CM_PER_KM) - 1.0).abs() < 1e-9, "{tiny:e}");
    }

    #[test]
    fn a_grazing_path_keeps_full_precision() {
        // dh = 1e-8 km over 100 km: the difference of columns would cancel
        // to ulp(C) / (rho dh) ~ 1e-7 relative; rho(mid) len is exact to
        // (dh / H)^2 ~ 1e-18 (the density is exponential across dh).
        let a = Atmosphere::nrlmsis21();
        let got = a.slant_column(110.0, 110.0 + 1e-8, 100.0);
        let want = a.rho(110.0 + 5e-9) * 100.0 * CM_PER_KM;
        assert!((got / want - 1.0).abs() < 1e-12, "{got:e} vs {want:e}");
    }

    #[test]
    fn a_steep_one_metre_path_is_not_treated_as_horizontal() {
        // The switch to rho(mid) len is for nearly horizontal paths,
        // dh < 1e-6 len. A 1 m path rising 0.99 m inside one table segment
        // (100.0-100.5 km, H = 5.9 km) must carry the exact column of the
        // exponential, rho(h0) H (1 - exp(-dh/H)) len / dh. rho(mid) len
        // misses the curvature by (dh / 2H)^2 / 6 = 1.2e-9 relative; the
        // general formula's cancellation costs about eps H / dh (a few 1e-12),
        // so 1e-10 separates the two by an order of magnitude each way.
        let a = Atmosphere::nrlmsis21();
        let (h0, len) = (100.1, 1e-3);
        let h1 = h0 + 0.99e-3;
        let dh = h1 - h0;
        let hs = a.scale_height(h0);
        assert_eq!(hs, a.scale_height(h1), "one segment");
        let want = a.rho(h0) * hs * -fmath::exp_m1(-dh / hs) * (len / dh) * CM_PER_KM;
        let got = a.slant_column(h0, h1, len);
        assert!((got / want - 1.0).abs() < 1e-10, "{got:e} vs {want:e}: {:e}", got / want - 1.0);
        // Downward the same.
        assert!((a.slant_column(h1, h0, len) / want - 1.0).abs() < 1e-10);
    }

    #[test]
    fn us1976_matches_the_standards_printed_temperature_and_density() {
        // U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562), Table I: T (K)
        // and rho (kg m^-3) at 100, 150, 200, 300 and 500 km. T is the
        // standard's defining profile: the table carries it to 6 digits.
        // rho: the `ussa1976` package's atomic oxygen runs 7 % above the
        // printed tables (4.607e11 cm^-3 at 100 km), so the density is high
        // by 7 % times O's mass fraction f_O: 0.15 % at 100 km (f_O 2 %),
        // 6.7 % at 500 km (f_O 95 %). Checked to 0.5 % of that.
        let a = Atmosphere::us1976();
        let table = [
            (100.0, 195.08, 5.604e-7),
            (150.0, 634.39, 2.076e-9),
            (200.0, 854.56, 2.541e-10),
            (300.0, 976.01, 1.916e-11),
            (500.0, 999.24, 5.215e-13),
        ];
        for (h, t, rho) in table {
            let r = us1976_rows().iter().find(|r| r[0] == h).unwrap();
            assert!((r[5] - t).abs() < 0.01, "{h} km: T {} vs {t}", r[5]);
            let c = a.composition(h);
            let f_o = 16.0 * c.o / (28.0 * c.n2 + 32.0 * c.o2 + 16.0 * c.o);
            let excess = a.rho(h) / (rho * 1e-3) - 1.0;
            assert!((excess - 0.07 * f_o).abs() < 0.005, "{h} km: rho {:e} vs {rho:e}: {excess} with f_O {f_o}", a.rho(h));
        }
    }

    #[test]
    fn the_default_reads_no_file_and_the_validated_pair_holds_its_profiles() {
        // The default is compiled in: the closed-form ambient state.
        let d = Atmosphere::of_params(&AtmosphereParams { data: Some("no such folder".into()), ..Default::default() }).unwrap();
        assert_eq!(d.ambient().at(150.0), Atmosphere::us1976().ambient().at(150.0));
        let a = d.ambient().at(300.0);
        assert!(a.te == a.tn && a.ti == a.tn && (970.0..985.0).contains(&a.tn), "{a:?}");
        // NRLMSIS 2.1 with GLOW's ionosphere: GLOW's NO (NOEM) near its
        // 100-110 km maximum, 2.2e8 / 3.1e8 at 100 / 110 km; 2.3e7 at 150 km
        // and 4.5e6 at 200 km, 2-4 times NRLMSIS 2.1's there.
        let t = Atmosphere::nrlmsis21();
        let t = t.ambient();
        let a = t.at(105.0);
        assert!((1e8..4e8).contains(&a.no), "{a:?}");
        assert!((1.8e7..2.8e7).contains(&t.at(150.7).no) && (3.6e6..5.5e6).contains(&t.at(199.7).no), "{:?}", t.at(150.7));
        // Night-time F region: ambient ne peaks near 1.7e5 cm^-3 around 360
        // km; a few 1e3 cm^-3 in the E region.
        let peak = (200..600).map(|h| (t.at(h as f64).ne, h)).fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        assert!((1.4e5..2.0e5).contains(&peak.0) && (330..400).contains(&peak.1), "{peak:?}");
        assert!(t.at(120.0).ne < 1e4);
        // Thermosphere: Tn about 1000 K at 300 km (Ap 15, F10.7 150); Te >= Tn.
        let a = t.at(300.0);
        assert!((900.0..1100.0).contains(&a.tn) && a.te >= a.tn - 1.0, "{a:?}");
        // Held outside the tables.
        assert_eq!(t.at(10.0), t.at(40.0));
        assert_eq!(t.at(2000.0), t.at(1500.0));
    }
}
