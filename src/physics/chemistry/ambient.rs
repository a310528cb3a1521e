//! What the emission chemistry needs besides N2, O2 and O: the neutral
//! temperature, ground-state atomic nitrogen N(4S) and nitric oxide NO, and
//! the ambient night-time ionosphere (electron and ion temperatures, electron
//! density), all at the place and time of `data/nrlmsis21.csv` (67 N, 20 E,
//! 2020-01-15 00:00 UT, F10.7 = F10.7a = 150, Ap = 15).
//!
//! - **Tn, N(4S)**: NRLMSIS 2.1 (Emmert et al. 2022, J. Geophys. Res.
//!   Space Physics 127, e2022JA030896), columns 6-7 of `data/nrlmsis21.csv`,
//!   made by `tools/reference/msis_table.py`.
//! - **Te, Ti, ambient ne, NO**: NCAR GLOW 4.0.4 (Solomon 2017,
//!   `glowpython`) called without precipitation at the same place and time:
//!   the IRI ionosphere above 200 km and GLOW's own night-time chemistry
//!   below, and GLOW's NO (the empirical NOEM model of Marsh et al. 2004, J.
//!   Geophys. Res. 109, A07301, driven by the date, Kp and F10.7),
//!   `data/ionosphere.csv`, made by `tools/reference/glow_tables.py`. At night the
//!   F-region peak is 1.7e5 cm^-3 at 361 km; below 200 km the ambient
//!   density is a few 1e3 cm^-3, negligible beside auroral ionization.
//!
//! **Why GLOW's NO, not NRLMSIS 2.1's.** NO makes 557.7 nm through N(2D) +
//! NO -> O(1S) (branching 0.2), so above 120 km, where most of the green of
//! soft aurora is made, the green per ion pair follows it. NOEM's
//! auroral-zone NO is 2.7-4.4 times NRLMSIS 2.1's from 120 to 400 km (2.4e7
//! against 8.8e6 cm^-3 at 150 km, 4.5e6 against 1.1e6 at 200 km) and 1.05-1.8
//! times at 90-110 km. With NRLMSIS 2.1's NO the whole pipeline (`aurora
//! profile` against GLOW, tests/python/test_glow.py) gave 557.7 / 427.8 at
//! 0.77-0.81 of GLOW's for E0 <= 1 keV and 0.86-0.88 at 2-3 keV; with GLOW's
//! NO, 0.91-0.93 from 0.5 to 10 keV. (GLOW's 10 % more O and 5 % less N2
//! above 110 km than NRLMSIS 2.1 make most of the rest.) Both NO models are
//! empirical and no NO measurement was made here; GLOW is the oracle the
//! colours are checked against and already supplies the ambient ionosphere,
//! so its NO is taken with it. NRLMSIS 2.1's NO stays in
//! `data/nrlmsis21.csv` (column 8), unused by the chemistry.
//!
//! The U.S. Standard Atmosphere 1976 defines none of these: with it the same
//! profiles are used (the standard's N2, O2 and O, these minor species and
//! this ionosphere), a documented equivalent rather than a second source.
//!
//! Interpolation: temperatures linearly, densities log-linearly in altitude;
//! held at the first and last row outside the tables (50-700 km and
//! 73-962 km; GLOW's NO is constant below 94 km, so holding it below 73 km
//! continues it).

/// The NRLMSIS table: columns 6-7 (T, N(4S)) are read here.
const NRLMSIS21_CSV: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/nrlmsis21.csv"));
/// The GLOW ambient ionosphere: altitude, Te, Ti, ne, NO.
const IONOSPHERE_CSV: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/ionosphere.csv"));

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

/// Rows of numbers of a committed CSV (comment lines start with `#`, the
/// header with a letter). The files are ours and fixed at compile time: a
/// malformed row is a build defect, caught by the tests.
fn rows(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with(|c: char| c.is_ascii_alphabetic()) && !l.trim().is_empty())
        .map(|l| l.split(',').map(|x| x.trim().parse::<f64>().expect("ambient table: a number")).collect())
        .collect()
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

/// The ambient profiles (module doc), parsed once.
#[derive(Clone, Debug)]
pub struct AmbientTable {
    /// T, ln N(4S).
    neutral: Profile,
    /// Te, Ti, ln ne, ln NO.
    ions: Profile,
}

impl AmbientTable {
    /// The committed tables (module doc).
    pub fn get() -> &'static AmbientTable {
        static TABLE: std::sync::OnceLock<AmbientTable> = std::sync::OnceLock::new();
        TABLE.get_or_init(|| {
            let m = rows(NRLMSIS21_CSV);
            let neutral = Profile { h: m.iter().map(|r| r[0]).collect(), v: m.iter().map(|r| vec![r[5], r[6].ln()]).collect() };
            let i = rows(IONOSPHERE_CSV);
            let ions =
                Profile { h: i.iter().map(|r| r[0]).collect(), v: i.iter().map(|r| vec![r[1], r[2], r[3].ln(), r[4].ln()]).collect() };
            AmbientTable { neutral, ions }
        })
    }

    /// The ambient quantities at `h_km`.
    pub fn at(&self, h_km: f64) -> Ambient {
        let n = self.neutral.at(h_km);
        let i = self.ions.at(h_km);
        Ambient { tn: n[0], n4s: n[1].exp(), no: i[3].exp(), te: i[0], ti: i[1], ne: i[2].exp() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_hold_the_documented_profiles() {
        let t = AmbientTable::get();
        // GLOW's NO (NOEM) near its 100-110 km maximum: 2.2e8 / 3.1e8 at
        // 100 / 110 km in the table; 2.3e7 at 150 km and 4.5e6 at 200 km,
        // 2-4 times NRLMSIS 2.1's there (module doc).
        let a = t.at(105.0);
        assert!((1e8..4e8).contains(&a.no), "{a:?}");
        assert!((1.8e7..2.8e7).contains(&t.at(150.7).no) && (3.6e6..5.5e6).contains(&t.at(199.7).no), "{:?}", t.at(150.7));
        // Night-time F-region: ambient ne peaks near 1.7e5 cm^-3 around 360
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
