//! A star's light through the air, per channel: the broadband version of
//! `crate::physics::air_extinction`'s line mix.
//!
//! **Model.** A star of spectrum `S(lambda)` seen at air mass `X` reaches
//! channel `c` of the observer with
//!
//! ```text
//! T_c(X) = sum_lambda S r_c exp(-tau(lambda) X) / sum_lambda S r_c
//! ```
//!
//! over 380-780 nm by 5 nm, `r_c` the observer's response
//! (`crate::util::observer::Observer::rgb`), `tau` the zenith optical depth
//! of the air above the observer at `lambda` (Rayleigh, ozone's Chappuis
//! band, aerosol: `Air::depths` and `Air::column_above`), `X` Kasten &
//! Young's air mass (`air_extinction::air_mass`). The air dims a star's
//! blue more than its red, so near the horizon it comes out dimmer and
//! redder: at sea level with the default air (aerosol 0.05 at 550 nm) the
//! V-band depth is about 0.14 (0.15 magnitudes per air mass; 0.1-0.3 are
//! measured at observatories: Green 1992, Schaefer 1993, "Astronomy and the
//! limits of vision"), so a star 2 degrees up (X = 19) loses about 3
//! magnitudes in green and twice as many in blue. The aurora's lines,
//! whose mix weights each channel otherwise, are not a star's spectrum:
//! 427.8 nm carries the camera's blue there, well below a star's blue.

use crate::physics::air_extinction::{air_mass, Air};
use crate::util::fmath;
use crate::util::observer::Observer;

/// The wavelengths summed over, nm: 380 to 780 by 5.
const FIRST_NM: f64 = 380.0;
const STEP_NM: f64 = 5.0;
const N: usize = 81;

/// The air above an observer for starlight (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct StarAir {
    /// Zenith optical depth above the observer at each wavelength.
    tau: [f64; N],
    /// The observer's response at each wavelength.
    rgb: [[f64; 3]; N],
}

impl StarAir {
    /// The air `air` above an observer at `altitude_km` seen by `observer`.
    pub fn new(air: &Air, altitude_km: f64, observer: Observer) -> StarAir {
        let lambda = |i: usize| FIRST_NM + STEP_NM * i as f64;
        StarAir {
            tau: std::array::from_fn(|i| air.column_above(&air.depths(lambda(i)), altitude_km)),
            rgb: std::array::from_fn(|i| observer.rgb(lambda(i))),
        }
    }

    /// Each channel's transmittance at elevation `e_deg` for a source of
    /// spectrum `spectrum` (per nm, any scale), in [0, 1].
    pub fn transmittance(&self, spectrum: impl Fn(f64) -> f64, e_deg: f64) -> [f64; 3] {
        let x = air_mass(e_deg);
        let (mut num, mut den) = ([0.0f64; 3], [0.0f64; 3]);
        for i in 0..N {
            let s = spectrum(FIRST_NM + STEP_NM * i as f64);
            let t = fmath::exp(-self.tau[i] * x);
            for c in 0..3 {
                den[c] += s * self.rgb[i][c];
                num[c] += s * self.rgb[i][c] * t;
            }
        }
        std::array::from_fn(|c| if den[c] > 0.0 { (num[c] / den[c]).clamp(0.0, 1.0) } else { 0.0 })
    }

    /// The zenith optical depth above the observer at `lambda_nm` (the
    /// nearest of the summed wavelengths).
    pub fn tau_at(&self, lambda_nm: f64) -> f64 {
        self.tau[(((lambda_nm - FIRST_NM) / STEP_NM).round().clamp(0.0, (N - 1) as f64)) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn air() -> Air {
        Air { ozone_du: 300.0, aerosol_tau_550: 0.05, angstrom: 1.3, aerosol_scale_height_km: 1.2 }
    }

    /// A source seen through one narrow band is dimmed by exactly that
    /// band's depth times the air mass (the closed form), and a flat
    /// spectrum's channels lie between the depths of their ends.
    #[test]
    fn a_narrow_band_is_dimmed_by_its_own_depth() {
        let a = StarAir::new(&air(), 0.0, Observer::Camera);
        for e in [90.0, 30.0, 5.0] {
            let t = a.transmittance(|l| if (l - 550.0).abs() < 1.0 { 1.0 } else { 0.0 }, e);
            let want = fmath::exp(-a.tau_at(550.0) * air_mass(e));
            assert!((t[1] - want).abs() < 1e-12, "{e}: {t:?} vs {want}");
        }
        // The V-band depth at sea level: Rayleigh 0.097 + ozone 0.03 + aerosol 0.05.
        let k_v = 2.5 * std::f64::consts::LOG10_E * a.tau_at(550.0);
        assert!((0.1..0.3).contains(&k_v), "{k_v} mag per air mass");
    }

    fn planck(l: f64, t: f64) -> f64 {
        fmath::powi(l, -5) / (fmath::exp(1.438_777e7 / (l * t)) - 1.0)
    }

    /// A Sun-like star (5800 K) through the camera low in the sky: each
    /// channel's loss `-ln T_c` is the cumulant series of the depths across
    /// the channel (weights `S r_c`, signed: the Rec.709 matrix leaves the
    /// camera's responses small negative lobes), `<tau> X - Var(tau) X^2 / 2`
    /// and so on: it lies between the first and the second partial sums
    /// (within 0.005), to 5 degrees (X = 10); so the horizon's stars are
    /// dimmer and redder: at 2 degrees (X = 19) blue loses over twice the
    /// magnitudes red does (6.1 against 2.6). Grey extinction (every
    /// wavelength at 550 nm's depth) keeps the colour and fails.
    #[test]
    fn stars_low_in_the_sky_are_dimmer_and_redder_as_the_air_model_says() {
        let a = StarAir::new(&air(), 0.0, Observer::Camera);
        let s = |l: f64| planck(l, 5800.0);
        let moments: [(f64, f64); 3] = std::array::from_fn(|c| {
            let (mut w_sum, mut m1, mut m2) = (0.0, 0.0, 0.0);
            for i in 0..N {
                let w = s(FIRST_NM + STEP_NM * i as f64) * a.rgb[i][c];
                w_sum += w;
                m1 += w * a.tau[i];
                m2 += w * a.tau[i] * a.tau[i];
            }
            let mean = m1 / w_sum;
            (mean, m2 / w_sum - mean * mean)
        });
        let to_mag = 2.5 * std::f64::consts::LOG10_E;
        for e in [30.0, 10.0, 5.0] {
            let t = a.transmittance(s, e);
            let x = air_mass(e);
            for c in 0..3 {
                let (mean, var) = moments[c];
                let loss = -fmath::ln(t[c]);
                let (first, second) = (mean * x, mean * x - var * x * x / 2.0);
                assert!(
                    loss >= first.min(second) - 0.005 && loss <= first.max(second) + 0.005,
                    "{e} deg, channel {c}: {loss} not between {first} and {second}"
                );
            }
            assert!(t[2] < t[1] && t[1] < t[0], "{e}: {t:?}");
        }
        let t = a.transmittance(s, 2.0);
        let mag = t.map(|v| -to_mag * fmath::ln(v));
        eprintln!("a 5800 K star 2 degrees up loses {mag:?} magnitudes (R, G, B)");
        assert!(mag[2] > 2.0 * mag[0], "{mag:?}");
    }
}
