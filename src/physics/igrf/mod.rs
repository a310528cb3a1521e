//! The International Geomagnetic Reference Field, 14th generation (IGRF-14,
//! IAGA Division V Working Group V-MOD 2024, doi 10.5281/zenodo.14012302;
//! the model and its conventions: Alken et al. 2021, "International
//! Geomagnetic Reference Field: the thirteenth generation", Earth Planets
//! Space 73, 49), the field of the Earth's core at a geocentric point and a
//! date.
//!
//! The field is minus the gradient of the potential
//!
//! ```text
//! V(r, theta, phi) = a sum_{n=1}^{13} (a / r)^{n+1}
//!                    sum_{m=0}^{n} (g_n^m cos(m phi) + h_n^m sin(m phi)) P_n^m(cos theta)
//! ```
//!
//! with `a = 6371.2 km`, `r` the geocentric radius, `theta` the geocentric
//! colatitude, `phi` the east longitude and `P_n^m` the Schmidt
//! semi-normalised associated Legendre functions. Its components:
//!
//! ```text
//! B_r     =  sum (n + 1) (a/r)^{n+2} (g cos m phi + h sin m phi) P_n^m
//! B_theta = -sum (a/r)^{n+2} (g cos m phi + h sin m phi) dP_n^m / dtheta
//! B_phi   = -sum (a/r)^{n+2} m (-g sin m phi + h cos m phi) P_n^m / sin theta
//! ```
//!
//! The `P_n^m` come from the Gauss-normalised recursion and the Schmidt
//! factors `S_n^m` (Wertz 1978, "Spacecraft Attitude Determination and
//! Control", appendix H): `P^{n,n} = sin theta P^{n-1,n-1}`,
//! `P^{n,m} = cos theta P^{n-1,m} - K^{n,m} P^{n-2,m}`,
//! `K^{n,m} = ((n-1)^2 - m^2) / ((2n-1)(2n-3))`; `S^{n,0} = S^{n-1,0} (2n-1)/n`,
//! `S^{n,m} = S^{n,m-1} sqrt((n-m+1)(delta_{m1}+1) / (n+m))`.
//!
//! **Time.** The coefficients are given at the epochs 1900.0, 1905.0, ...,
//! 2025.0 (1 January 00:00 UTC); between two epochs each coefficient is
//! linear in time, and after 2025.0 the secular variation of the 2025 model
//! carries it on linearly (the table's 2030.0 column is the 2025 model
//! advanced five years by it, as IGRF's `.shc` files write predictive
//! models). IGRF-14 is defined from 1900.0 to 2030.0; other dates are
//! refused ([`IgrfError::Date`]). The table is `data/igrf14.csv`, made by
//! `tools/reference/igrf_table.py` (source, version and terms: docs/data.md).

use crate::geometry::astronomy::time::{days_from_civil, Utc};
use crate::util::fmath;
use glam::DVec3;
use std::sync::OnceLock;

/// The IGRF reference radius, km.
pub const REFERENCE_RADIUS_KM: f64 = 6371.2;
/// The highest degree of IGRF-14.
pub const MAX_DEGREE: usize = 13;

const TABLE_CSV: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/igrf14.csv"));
const N: usize = MAX_DEGREE + 1;

/// An IGRF date out of the model's span.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IgrfError {
    #[error("IGRF-14 is defined from 1900-01-01 to 2030-01-01; {0} is outside")]
    Date(String),
}

/// The table: the epochs (UTC seconds since J2000) and, per epoch, the
/// coefficients `g[n][m]`, `h[n][m]`, nT.
struct Table {
    epochs_s: Vec<f64>,
    g: Vec<[[f64; N]; N]>,
    h: Vec<[[f64; N]; N]>,
}

/// UTC seconds since J2000 of 1 January 00:00 of `year`.
fn year_start_s(year: i64) -> f64 {
    // J2000.0 is 1970-01-01 + 10957.5 days.
    (days_from_civil(year, 1, 1) as f64 - 10_957.5) * 86_400.0
}

fn table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(|| {
        let mut rows = TABLE_CSV.lines().filter(|l| !l.starts_with('#'));
        let header = rows.next().expect("data/igrf14.csv has a header");
        let epochs_s: Vec<f64> = header.split(',').skip(2).map(|y| year_start_s(y.parse::<f64>().expect("an epoch") as i64)).collect();
        let k = epochs_s.len();
        let (mut g, mut h) = (vec![[[0.0; N]; N]; k], vec![[[0.0; N]; N]; k]);
        for row in rows {
            let f: Vec<&str> = row.split(',').collect();
            let n: usize = f[0].parse().expect("a degree");
            let m: i64 = f[1].parse().expect("an order");
            for (e, v) in f[2..].iter().enumerate() {
                let v: f64 = v.parse().expect("a coefficient");
                if m < 0 {
                    h[e][n][(-m) as usize] = v;
                } else {
                    g[e][n][m as usize] = v;
                }
            }
        }
        Table { epochs_s, g, h }
    })
}

/// The model at one date: Gauss coefficients to degree [`Igrf::max_degree`].
#[derive(Clone, Debug, PartialEq)]
pub struct Igrf {
    g: [[f64; N]; N],
    h: [[f64; N]; N],
    max_degree: usize,
}

impl Igrf {
    /// IGRF-14 at instant `t` (module doc: linear between epochs, the
    /// secular variation after 2025.0).
    pub fn at(t: Utc) -> Result<Igrf, IgrfError> {
        let tab = table();
        let s = t.seconds_since_j2000;
        let (first, last) = (tab.epochs_s[0], *tab.epochs_s.last().expect("epochs"));
        if !(first..=last).contains(&s) {
            return Err(IgrfError::Date(t.to_rfc3339()));
        }
        let i = tab.epochs_s.partition_point(|&e| e <= s).clamp(1, tab.epochs_s.len() - 1) - 1;
        let w = (s - tab.epochs_s[i]) / (tab.epochs_s[i + 1] - tab.epochs_s[i]);
        let mut model = Igrf { g: [[0.0; N]; N], h: [[0.0; N]; N], max_degree: MAX_DEGREE };
        for n in 1..N {
            for m in 0..=n {
                model.g[n][m] = tab.g[i][n][m] + w * (tab.g[i + 1][n][m] - tab.g[i][n][m]);
                model.h[n][m] = tab.h[i][n][m] + w * (tab.h[i + 1][n][m] - tab.h[i][n][m]);
            }
        }
        Ok(model)
    }

    /// The same model cut at degree `n` (1: the centred, tilted dipole).
    pub fn truncated(mut self, n: usize) -> Igrf {
        self.max_degree = n.clamp(1, MAX_DEGREE);
        self
    }

    /// The highest degree summed.
    pub fn max_degree(&self) -> usize {
        self.max_degree
    }

    /// The unit vector, ITRS, from the Earth's centre to the north
    /// geomagnetic pole: the axis of the degree-1 (centred, tilted dipole)
    /// term, `-(g_1^1, h_1^1, g_1^0) / |...|`.
    pub fn dipole_north(&self) -> DVec3 {
        -DVec3::new(self.g[1][1], self.h[1][1], self.g[1][0]).normalize()
    }

    /// The field at geocentric radius `r_km`, colatitude `theta` and east
    /// longitude `phi` (radians): `(B_r, B_theta, B_phi)`, nT (`B_theta`
    /// points south, `B_phi` east). At the poles `B_phi` is taken a
    /// nanoradian away.
    pub fn field_spherical(&self, r_km: f64, theta: f64, phi: f64) -> [f64; 3] {
        let (st, ct) = fmath::sin_cos(theta);
        let st_safe = if st.abs() < 1e-9 { 1e-9_f64.copysign(if st == 0.0 { 1.0 } else { st }) } else { st };
        let nmax = self.max_degree;
        // Gauss-normalised P and dP/dtheta, then Schmidt factors (module doc).
        let (mut p, mut dp) = ([[0.0; N]; N], [[0.0; N]; N]);
        p[0][0] = 1.0;
        for n in 1..=nmax {
            for m in 0..=n {
                if m == n {
                    p[n][n] = st * p[n - 1][n - 1];
                    dp[n][n] = st * dp[n - 1][n - 1] + ct * p[n - 1][n - 1];
                } else {
                    let k = if n > 1 { (((n - 1) * (n - 1)) as f64 - (m * m) as f64) / (((2 * n - 1) * (2 * n - 3)) as f64) } else { 0.0 };
                    let (p2, dp2) = if n >= 2 { (p[n - 2][m], dp[n - 2][m]) } else { (0.0, 0.0) };
                    p[n][m] = ct * p[n - 1][m] - k * p2;
                    dp[n][m] = ct * dp[n - 1][m] - st * p[n - 1][m] - k * dp2;
                }
            }
        }
        let mut s = [[0.0; N]; N];
        s[0][0] = 1.0;
        for n in 1..=nmax {
            s[n][0] = s[n - 1][0] * (2 * n - 1) as f64 / n as f64;
            for m in 1..=n {
                let delta = if m == 1 { 2.0 } else { 1.0 };
                s[n][m] = s[n][m - 1] * (((n - m + 1) as f64 * delta) / (n + m) as f64).sqrt();
            }
        }
        let ratio = REFERENCE_RADIUS_KM / r_km;
        let (mut br, mut bt, mut bp) = (0.0, 0.0, 0.0);
        let mut rn = ratio * ratio; // (a/r)^(n+2) at n = 0
        for n in 1..=nmax {
            rn *= ratio;
            for m in 0..=n {
                let (sm, cm) = fmath::sin_cos(m as f64 * phi);
                let (g, h) = (self.g[n][m], self.h[n][m]);
                let (pn, dpn) = (s[n][m] * p[n][m], s[n][m] * dp[n][m]);
                br += (n + 1) as f64 * rn * (g * cm + h * sm) * pn;
                bt -= rn * (g * cm + h * sm) * dpn;
                bp -= rn * m as f64 * (-g * sm + h * cm) * pn / st_safe;
            }
        }
        [br, bt, bp]
    }

    /// The field at the Earth-fixed (ITRS) point `p`, km, as an ITRS
    /// vector, nT.
    pub fn field_itrs(&self, p: DVec3) -> DVec3 {
        let r = p.length();
        let theta = fmath::acos((p.z / r).clamp(-1.0, 1.0));
        let phi = fmath::atan2(p.y, p.x);
        let [br, bt, bp] = self.field_spherical(r, theta, phi);
        let (st, ct) = fmath::sin_cos(theta);
        let (sp, cp) = fmath::sin_cos(phi);
        let r_hat = DVec3::new(st * cp, st * sp, ct);
        let t_hat = DVec3::new(ct * cp, ct * sp, -st);
        let p_hat = DVec3::new(-sp, cp, 0.0);
        br * r_hat + bt * t_hat + bp * p_hat
    }
}

#[cfg(test)]
mod tests;
