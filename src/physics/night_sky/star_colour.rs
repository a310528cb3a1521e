//! A star's temperature from its colour, and its irradiance from its
//! magnitude.
//!
//! **Temperature.** Ballesteros (2012), EPL 97, 34008, "New insights into
//! black bodies": the temperature of the black body whose Johnson B-V is
//! the star's, in closed form,
//!
//! ```text
//! T = 4600 K (1 / (0.92 (B-V) + 1.7) + 1 / (0.92 (B-V) + 0.62))
//! ```
//!
//! which gives the Sun (B-V = 0.65) 5778 K. The formula has a pole at
//! B-V = -0.67, so B-V is first clamped to the range of the compiled-in
//! catalogue, [`B_V_MIN`] to [`B_V_MAX`] (21,700 K to 1,500 K): colours past
//! about 2 are of reddened or carbon stars, whose temperature B-V does not
//! tell, and come out cool.
//!
//! **Irradiance.** A V = 0 star gives [`V0_IRRADIANCE_KR_SR`] = 0.0111 kR sr
//! in the volume's radiance unit (the V band's photon flux of Bessell 1979
//! over the filter's 880 A at 550 nm; the derivation is in the renderer's
//! star field, `src/render/sky.rs`), and a star of magnitude V
//! `0.0111 x 10^(-0.4 V)` kR sr.

use crate::util::fmath;

/// The bluest and reddest B-V of the compiled-in catalogue.
pub const B_V_MIN: f64 = -0.40;
pub const B_V_MAX: f64 = 5.46;

/// Irradiance of a V = 0 star, kR sr (the renderer's `MAG0_KR_SR`).
pub const V0_IRRADIANCE_KR_SR: f64 = 0.0111;

/// Effective temperature (K) of a star of colour `b_minus_v` (Ballesteros
/// 2012), B-V clamped to the catalogue's range.
pub fn temperature_k(b_minus_v: f64) -> f64 {
    let x = 0.92 * b_minus_v.clamp(B_V_MIN, B_V_MAX);
    4600.0 * (1.0 / (x + 1.7) + 1.0 / (x + 0.62))
}

/// Irradiance (kR sr) of a star of V magnitude `v_mag`.
pub fn v_irradiance_kr_sr(v_mag: f64) -> f64 {
    V0_IRRADIANCE_KR_SR * fmath::powf(10f64, -0.4 * v_mag)
}

/// The V magnitude of an irradiance `kr_sr` (kR sr); the inverse of [`v_irradiance_kr_sr`].
pub fn v_magnitude(kr_sr: f64) -> f64 {
    -2.5 * fmath::log10(kr_sr / V0_IRRADIANCE_KR_SR)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::night_sky::catalogue::catalogue;

    #[test]
    fn the_sun_comes_out_at_its_published_temperature() {
        // Ballesteros (2012): B-V 0.65 is ~5800 K; the Sun's nominal
        // effective temperature is 5772 K (IAU 2015 B3). 2 % allowed.
        let t = temperature_k(0.65);
        assert!((t / 5800.0 - 1.0).abs() < 0.02, "{t}");
        assert!((t / 5772.0 - 1.0).abs() < 0.02, "{t}");
        // The formula itself, to rounding: 4600 (1/2.298 + 1/1.218).
        assert!((t - 5778.4).abs() < 0.1, "{t}");
    }

    #[test]
    fn arcturus_and_vega_within_the_black_body_spread() {
        // Arcturus: B-V 1.23, T 4286 K (Ramirez & Allende Prieto 2011, ApJ
        // 743, 135): the formula gives 4251 K, 0.8 % low; 2 % allowed.
        assert!((temperature_k(1.23) / 4286.0 - 1.0).abs() < 0.02);
        // Vega: B-V 0.00, T about 9600 K: the formula gives 10,125 K, 5.5 %
        // high (an A star's Balmer jump reddens its B-V from a black body's);
        // 6 % allowed.
        assert!((temperature_k(0.0) / 9600.0 - 1.0).abs() < 0.06);
    }

    #[test]
    fn colours_outside_the_catalogue_are_clamped_and_hotter_is_bluer() {
        assert_eq!(temperature_k(-2.0), temperature_k(B_V_MIN));
        assert_eq!(temperature_k(9.0), temperature_k(B_V_MAX));
        assert!((temperature_k(B_V_MIN) - 21_700.0).abs() < 100.0);
        assert!((temperature_k(B_V_MAX) - 1_500.0).abs() < 10.0);
        let mut last = f64::INFINITY;
        for i in 0..=100 {
            let t = temperature_k(B_V_MIN + (B_V_MAX - B_V_MIN) * f64::from(i) / 100.0);
            assert!(t < last && t.is_finite());
            last = t;
        }
        // The clamp is the catalogue's range.
        let (lo, hi) =
            catalogue().iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| (lo.min(s.b_minus_v), hi.max(s.b_minus_v)));
        assert_eq!((lo, hi), (B_V_MIN, B_V_MAX));
    }

    #[test]
    fn irradiance_is_the_renderers_and_inverts() {
        assert_eq!(V0_IRRADIANCE_KR_SR, crate::render::sky::MAG0_KR_SR);
        assert!((v_irradiance_kr_sr(5.0) / V0_IRRADIANCE_KR_SR - 0.01).abs() < 1e-12);
        for v in [-1.46, 0.0, 3.3, 8.5] {
            assert!((v_magnitude(v_irradiance_kr_sr(v)) - v).abs() < 1e-12);
        }
    }
}
