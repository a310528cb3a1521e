//! What the emission chemistry needs besides N2, O2 and O: the neutral
//! temperature Tn, ground-state atomic nitrogen N(4S), nitric oxide NO and
//! the ambient night-time ionosphere (electron and ion temperatures Te, Ti
//! and electron density ne). Two sources, chosen by `[atmosphere]`
//! (`crate::physics::atmosphere` assembles them; docs/data.md has the
//! terms, docs/physics.md the derivations):
//!
//! - **Closed forms** (`ionosphere = "closed-form"`, the default, compiled
//!   in): Te = Ti = Tn (the night-time assumption below the F peak);
//!   ne a night-time F layer and E layer, each a Chapman alpha layer
//!   (Chapman 1931; Rishbeth & Garriott 1969, "Introduction to Ionospheric
//!   Physics"), [`NE_LAYERS`]; NO held at its peak below [`NO_PEAK_KM`] and
//!   falling with a [`NO_SCALE_KM`] scale height above (the peak at 106-110
//!   km and the auroral-zone magnitude SNOE measured, Barth et al. 2003, J.
//!   Geophys. Res. 108(A1), 1027). With the U.S. Standard Atmosphere, N(4S)
//!   is in diffusive equilibrium with O above its peak, anchored at the
//!   night-time density AE-C measured at 400 km (Mauersberger et al. 1976,
//!   J. Geophys. Res. 81), and cut off below [`N4S_PEAK_KM`] where
//!   N + NO and N + O2 destroy it ([`closed_form_n4s`]).
//! - **The validated tables** (`model = "nrlmsis21"` gives Tn and N(4S),
//!   `ionosphere = "glow"` gives Te, Ti, ne and NO): NRLMSIS 2.1 (Emmert et
//!   al. 2022) and NCAR GLOW 4.0.4 (Solomon 2017; IRI above 200 km, NO from
//!   NOEM, Marsh et al. 2004), at 67 N, 20 E, 2020-01-15 00:00 UT,
//!   F10.7 = 150, Ap = 15, read from the data folder
//!   (`crate::physics::data_files`). The chemistry was checked against GLOW
//!   with these (tests/python/test_glow.py); NOEM's NO is 2.7-4.4 times
//!   NRLMSIS 2.1's from 120 to 400 km, and N(2D) + NO makes 557.7 nm, so
//!   GLOW's NO is the one taken with it.
//!
//! Interpolation: temperatures linearly, densities log-linearly in altitude;
//! held at the first and last row outside the tables.

use crate::util::fmath;

/// NO's peak altitude, km: the middle of SNOE's 106-110 km (Barth et al. 2003).
pub const NO_PEAK_KM: f64 = 108.0;
/// NO at its peak, cm^-3: a round auroral-zone value of SNOE's 110 km
/// densities (Barth et al. 2003), 1e8 to a few 1e8 at 60-70 geomagnetic.
pub const NO_PEAK_CM3: f64 = 2e8;
/// NO's scale height above its peak, km: within a factor of 2 of NOEM's fall
/// from 110 to 250 km at 67 N (docs/data.md), between the neutral gas's
/// scale heights at 120 and 200 km.
pub const NO_SCALE_KM: f64 = 20.0;
/// N(4S) at 400 km, cm^-3: AE-C's afternoon maximum there, 1.5e6
/// (Mauersberger et al. 1975, Geophys. Res. Lett. 2, 337), over the 5.2
/// afternoon-to-night ratio it measured at 68 N, 17 h against 02 h local
/// time (Mauersberger et al. 1976).
pub const N4S_400_CM3: f64 = 3e5;
/// Below this altitude, km, N(4S) is cut off by a Gaussian of
/// [`N4S_CUT_KM`] (its chemical loss, above which diffusion holds).
pub const N4S_PEAK_KM: f64 = 200.0;
pub const N4S_CUT_KM: f64 = 35.0;
/// The night-time Chapman layers of ne: (peak cm^-3, peak km, scale height
/// km). F layer: NmF2 = 1.5e5 cm^-3 (foF2 = 3.5 MHz) at 350 km, H = 50 km,
/// a winter night in the auroral zone at moderate solar activity (GLOW's IRI
/// at the NRLMSIS table's place and time has 1.7e5 at 361 km). E layer: 3e3
/// cm^-3 at 110 km, H = 10 km, the residual night E layer.
pub const NE_LAYERS: [(f64, f64, f64); 2] = [(1.5e5, 350.0, 50.0), (3e3, 110.0, 10.0)];

/// The closed-form NO at `h_km`, cm^-3 (module doc).
pub fn closed_form_no(h_km: f64) -> f64 {
    NO_PEAK_CM3 * fmath::exp(-(h_km - NO_PEAK_KM).max(0.0) / NO_SCALE_KM)
}

/// The closed-form night-time ne at `h_km`, cm^-3: the sum of the Chapman
/// alpha layers `Nm exp((1 - y - e^-y) / 2)`, `y = (h - hm) / H`.
pub fn closed_form_ne(h_km: f64) -> f64 {
    NE_LAYERS
        .iter()
        .map(|&(nm, hm, sh)| {
            let y = (h_km - hm) / sh;
            nm * fmath::exp(0.5 * (1.0 - y - fmath::exp(-y)))
        })
        .sum()
}

/// The closed-form N(4S) at `h_km`, cm^-3, from the atmosphere's O and Tn
/// there and at 400 km (`o_400`, `t_400`): diffusive equilibrium with O,
/// `n_N / n_N(400) = (T_400 / T)^(1 - 14/16) (n_O / n_O(400))^(14/16)`
/// (each species with its own scale height kT / mg at the common T), times
/// `exp(-((200 - h) / 35)^2)` below 200 km.
pub fn closed_form_n4s(h_km: f64, o: f64, tn: f64, o_400: f64, t_400: f64) -> f64 {
    const M: f64 = 14.0 / 16.0;
    let diffusive = N4S_400_CM3 * fmath::powf(t_400 / tn, 1.0 - M) * fmath::powf(o / o_400, M);
    let below = (N4S_PEAK_KM - h_km).max(0.0) / N4S_CUT_KM;
    diffusive * fmath::exp(-below * below)
}

/// The ambient quantities at one altitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ambient {
    /// Neutral temperature, K.
    pub tn: f64,
    /// N(4S), cm^-3.
    pub n4s: f64,
    /// NO, cm^-3.
    pub no: f64,
    /// Electron temperature, K.
    pub te: f64,
    /// Ion temperature, K.
    pub ti: f64,
    /// Ambient (non-auroral) electron density, cm^-3.
    pub ne: f64,
}

/// One tabulated profile: altitudes and, per column, values (log or linear).
#[derive(Clone, Debug)]
struct Profile {
    h: Vec<f64>,
    /// Per row, the columns (densities stored as ln).
    v: Vec<Vec<f64>>,
}

impl Profile {
    fn at(&self, h: f64) -> Vec<f64> {
        let n = self.h.len();
        if h <= self.h[0] {
            return self.v[0].clone();
        }
        if h >= self.h[n - 1] {
            return self.v[n - 1].clone();
        }
        let i = self.h.partition_point(|&x| x <= h).saturating_sub(1).min(n - 2);
        let t = (h - self.h[i]) / (self.h[i + 1] - self.h[i]);
        self.v[i].iter().zip(&self.v[i + 1]).map(|(a, b)| a + t * (b - a)).collect()
    }
}

/// The ambient profiles (module doc).
#[derive(Clone, Debug)]
pub struct AmbientTable {
    /// T, ln N(4S).
    neutral: Profile,
    /// Te, Ti, ln ne, ln NO.
    ions: Profile,
}

impl AmbientTable {
    /// From rows `[h km, Tn K, N(4S) cm^-3]` and `[h km, Te K, Ti K, ne
    /// cm^-3, NO cm^-3]`, each ascending in altitude with positive values.
    pub fn new(neutral: &[[f64; 3]], ions: &[[f64; 5]]) -> Self {
        let neutral =
            Profile { h: neutral.iter().map(|r| r[0]).collect(), v: neutral.iter().map(|r| vec![r[1], fmath::ln(r[2])]).collect() };
        let ions = Profile {
            h: ions.iter().map(|r| r[0]).collect(),
            v: ions.iter().map(|r| vec![r[1], r[2], fmath::ln(r[3]), fmath::ln(r[4])]).collect(),
        };
        AmbientTable { neutral, ions }
    }

    /// The closed-form ionosphere's rows at altitudes `h` with neutral
    /// temperatures `tn` (Te = Ti = Tn).
    pub fn closed_form_ions(h: &[f64], tn: &[f64]) -> Vec<[f64; 5]> {
        h.iter().zip(tn).map(|(&h, &t)| [h, t, t, closed_form_ne(h), closed_form_no(h)]).collect()
    }

    /// The ambient quantities at `h_km`.
    pub fn at(&self, h_km: f64) -> Ambient {
        let n = self.neutral.at(h_km);
        let i = self.ions.at(h_km);
        Ambient { tn: n[0], n4s: fmath::exp(n[1]), no: fmath::exp(i[3]), te: i[0], ti: i[1], ne: fmath::exp(i[2]) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chapman_layers_peak_where_and_as_high_as_stated() {
        // y = 0 at hm: Nm exactly (the other layer adds its tail).
        let f = closed_form_ne(350.0);
        assert!((f / 1.5e5 - 1.0).abs() < 1e-6, "{f}");
        let peak = (2000..6000).map(|i| i as f64 * 0.1).max_by(|a, b| closed_form_ne(*a).total_cmp(&closed_form_ne(*b))).unwrap();
        assert!((peak - 350.0).abs() < 0.15, "{peak}");
        // One scale height below the F peak: exp((1 + 1 - e) / 2) = 0.698.
        assert!((closed_form_ne(300.0) / 1.5e5 - fmath::exp(0.5 * (2.0 - fmath::exp(1f64)))).abs() < 1e-3);
        // The night E layer: 3e3 at 110 km, a few 1e2 to 1e3 from 90 to 200 km.
        assert!((closed_form_ne(110.0) / 3e3 - 1.0).abs() < 1e-6);
        assert!((100.0..3e3).contains(&closed_form_ne(90.0)) && (100.0..3e3).contains(&closed_form_ne(180.0)));
    }

    #[test]
    fn no_holds_its_peak_below_and_falls_a_scale_height_each_20_km_above() {
        assert_eq!(closed_form_no(80.0), NO_PEAK_CM3);
        assert_eq!(closed_form_no(NO_PEAK_KM), NO_PEAK_CM3);
        assert!((closed_form_no(NO_PEAK_KM + 20.0) / NO_PEAK_CM3 - fmath::exp(-1f64)).abs() < 1e-12);
    }

    #[test]
    fn n4s_is_anchored_at_400_km_and_follows_o_with_mass_ratio_14_16() {
        assert!((closed_form_n4s(400.0, 1e8, 1000.0, 1e8, 1000.0) / N4S_400_CM3 - 1.0).abs() < 1e-12);
        // O ten times denser at the same T: N 10^(7/8) times.
        let r = closed_form_n4s(300.0, 1e9, 1000.0, 1e8, 1000.0) / N4S_400_CM3;
        assert!((r / fmath::powf(10f64, 0.875) - 1.0).abs() < 1e-12, "{r}");
        // One cut width below 200 km: e^-1 of the diffusive value.
        let r = closed_form_n4s(165.0, 1e8, 1000.0, 1e8, 1000.0) / N4S_400_CM3;
        assert!((r - fmath::exp(-1f64)).abs() < 1e-12, "{r}");
    }

    #[test]
    fn the_table_interpolates_and_holds_outside() {
        let t = AmbientTable::new(
            &[[100.0, 200.0, 1e6], [200.0, 1000.0, 1e8]],
            &[[100.0, 200.0, 200.0, 1e3, 1e8], [200.0, 1000.0, 900.0, 1e5, 1e6]],
        );
        let a = t.at(150.0);
        assert!(
            (a.tn - 600.0).abs() < 1e-9
                && (a.n4s / 1e7 - 1.0).abs() < 1e-12
                && (a.ne / 1e4 - 1.0).abs() < 1e-12
                && (a.no / 1e7 - 1.0).abs() < 1e-12
        );
        assert!((a.ti - 550.0).abs() < 1e-9);
        assert_eq!(t.at(10.0), t.at(100.0));
        assert_eq!(t.at(2000.0), t.at(200.0));
    }
}
