//! The Moon's light, and the sky it brightens: Krisciunas & Schaefer
//! (1991), PASP 103, 1033, "A model of the brightness of moonlight"
//! (doi:10.1086/132921), in the V band.
//!
//! **The Moon.** At phase angle `alpha` (degrees, 0 at full) its V magnitude
//! at mean distance is (their eq. 20)
//! `m = -12.73 + 0.026 |alpha| + 4e-9 alpha^4`, and its illuminance outside
//! the air, in foot-candles, `I* = 10^(-0.4 (m + 16.57))`, times the
//! opposition surge near full Moon: 35 % brighter at full, fading linearly
//! to nothing at 7 degrees (`1.35 - 0.05 |alpha|`: the paper mentions the
//! surge on p. 1035; the linear fade is Thorstensen's skycalc's reading).
//!
//! **The sky.** Scattered moonlight at angular distance `rho` from the Moon,
//! zenith distance `Z`, the Moon at `Z_m`, for a V extinction `k` (mag per
//! air mass), in nanoLamberts:
//!
//! ```text
//! B_moon = f(rho) I* 10^(-0.4 k X(Z_m)) (1 - 10^(-0.4 k X(Z)))
//! f(rho) = 10^5.36 (1.06 + cos^2 rho) + 10^(6.15 - rho / 40)   (rho in degrees; eq. 21)
//! X(Z)   = (1 - 0.96 sin^2 Z)^(-1/2)                           (air mass)
//! ```
//!
//! Rayleigh plus Mie scattering; the Mie term is the paper's fit for rho >=
//! 10 degrees (eq. 21), which is the domain here ([`MoonSky`] refuses
//! less). The paper finds its model within 8-23 % of its Mauna Kea data.
//!
//! **Units.** nanoLamberts to V surface brightness (mag/arcsec^2) by their
//! eq. 1 (Garstang 1986): `B = 34.08 exp(20.7233 - 0.92104 V)`. A surface of
//! `mu` mag/arcsec^2 gives each arcsec^2 a V = `mu` star's irradiance, so
//! its radiance in the volume's unit is `0.0111 x 10^(-0.4 mu) x 4.2545e10`
//! kR (0.0111 kR sr for V = 0, [`V0_IRRADIANCE_KR_SR`]; 4.2545e10 arcsec^2
//! per sr). The Moon's whole-disc irradiance is `0.0111 x 10^(-0.4 m)` kR sr
//! times the surge, and its disc's mean radiance that over the disc's solid
//! angle at mean distance, [`MOON_SOLID_ANGLE_SR`].

use super::star_colour::V0_IRRADIANCE_KR_SR;
use crate::util::fmath;

/// Square arcseconds in a steradian, (180 x 3600 / pi)^2.
pub const ARCSEC2_PER_SR: f64 = 4.254_517_029_615_221e10;
/// The Moon's mean radius and mean distance from the Earth's centre, km.
pub const MOON_RADIUS_KM: f64 = 1737.4;
pub const MOON_MEAN_DISTANCE_KM: f64 = 384_400.0;
/// The Moon's disc at mean distance, sr: `pi (R / D)^2`, 6.42e-5.
pub const MOON_SOLID_ANGLE_SR: f64 =
    std::f64::consts::PI * (MOON_RADIUS_KM / MOON_MEAN_DISTANCE_KM) * (MOON_RADIUS_KM / MOON_MEAN_DISTANCE_KM);
/// The least Moon-sky distance the scattering fit holds for, degrees.
pub const MIN_SEPARATION_DEG: f64 = 10.0;

/// Where the Moon and the sky point are, and the air's extinction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoonSky {
    /// Sun-Moon-Earth angle, degrees: 0 full, 180 new.
    pub phase_angle_deg: f64,
    /// Zenith distance of the Moon and of the sky point, degrees.
    pub moon_zenith_deg: f64,
    pub sky_zenith_deg: f64,
    /// Angle between the Moon and the sky point, degrees.
    pub separation_deg: f64,
    /// V-band extinction, magnitudes per air mass.
    pub extinction_v_mag: f64,
}

/// Why a [`MoonSky`] was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MoonlightError {
    #[error("phase angle {0} degrees: the model takes 0 to 180")]
    PhaseAngle(f64),
    #[error("{what} zenith distance {value} degrees: the model takes 0 to 90 (above the horizon)")]
    Zenith { what: &'static str, value: f64 },
    #[error("Moon-sky separation {0} degrees: the scattering fit holds from {MIN_SEPARATION_DEG} to 180")]
    Separation(f64),
    #[error("extinction {0} mag per air mass: must be finite and not negative")]
    Extinction(f64),
}

/// The Moon's V magnitude at mean distance (eq. 20), without the opposition surge.
pub fn moon_v_magnitude(phase_angle_deg: f64) -> f64 {
    let a = phase_angle_deg.abs();
    -12.73 + 0.026 * a + 4e-9 * fmath::powi(a, 4)
}

/// The opposition surge: 1.35 at full Moon, linearly to 1 at 7 degrees.
pub fn opposition_surge(phase_angle_deg: f64) -> f64 {
    let a = phase_angle_deg.abs();
    if a < 7.0 {
        1.35 - 0.05 * a
    } else {
        1.0
    }
}

/// The Moon's illuminance outside the air, `I*`, foot-candles, surge included.
pub fn moon_illuminance_fc(phase_angle_deg: f64) -> f64 {
    fmath::powf(10f64, -0.4 * (moon_v_magnitude(phase_angle_deg) + 16.57)) * opposition_surge(phase_angle_deg)
}

/// The scattering function `f(rho)` (eq. 21), `rho` in degrees.
pub fn scattering_function(separation_deg: f64) -> f64 {
    let c = fmath::cos(separation_deg.to_radians());
    fmath::powf(10f64, 5.36) * (1.06 + c * c) + fmath::powf(10f64, 6.15 - separation_deg / 40.0)
}

/// Air mass at zenith distance `zenith_deg` (the paper's; 5 at the horizon).
pub fn air_mass(zenith_deg: f64) -> f64 {
    let s = fmath::sin(zenith_deg.to_radians());
    fmath::powf(1.0 - 0.96 * s * s, -0.5)
}

/// Checks a [`MoonSky`] against the model's domain.
pub fn check(sky: &MoonSky) -> Result<(), MoonlightError> {
    let MoonSky { phase_angle_deg: a, moon_zenith_deg: zm, sky_zenith_deg: z, separation_deg: rho, extinction_v_mag: k } = *sky;
    if !(0.0..=180.0).contains(&a) {
        return Err(MoonlightError::PhaseAngle(a));
    }
    for (what, value) in [("Moon", zm), ("sky", z)] {
        if !(0.0..=90.0).contains(&value) {
            return Err(MoonlightError::Zenith { what, value });
        }
    }
    if !(MIN_SEPARATION_DEG..=180.0).contains(&rho) {
        return Err(MoonlightError::Separation(rho));
    }
    if !(k.is_finite() && k >= 0.0) {
        return Err(MoonlightError::Extinction(k));
    }
    Ok(())
}

/// The sky's brightness from scattered moonlight, nanoLamberts.
pub fn moon_sky_brightness_nl(sky: &MoonSky) -> Result<f64, MoonlightError> {
    check(sky)?;
    let k = sky.extinction_v_mag;
    Ok(scattering_function(sky.separation_deg)
        * moon_illuminance_fc(sky.phase_angle_deg)
        * fmath::powf(10f64, -0.4 * k * air_mass(sky.moon_zenith_deg))
        * (1.0 - fmath::powf(10f64, -0.4 * k * air_mass(sky.sky_zenith_deg))))
}

/// V surface brightness (mag/arcsec^2) of `b_nl` nanoLamberts (eq. 1 inverted).
pub fn nl_to_v_surface_brightness(b_nl: f64) -> f64 {
    (20.7233 - fmath::ln(b_nl / 34.08)) / 0.92104
}

/// nanoLamberts of a V surface brightness `mu` (mag/arcsec^2) (eq. 1).
pub fn v_surface_brightness_to_nl(mu: f64) -> f64 {
    34.08 * fmath::exp(20.7233 - 0.92104 * mu)
}

/// Radiance (kR) of a V surface brightness `mu` (mag/arcsec^2).
pub fn v_surface_brightness_to_kr(mu: f64) -> f64 {
    V0_IRRADIANCE_KR_SR * fmath::powf(10f64, -0.4 * mu) * ARCSEC2_PER_SR
}

/// The sky's radiance from scattered moonlight, kR.
pub fn moon_sky_radiance_kr(sky: &MoonSky) -> Result<f64, MoonlightError> {
    Ok(v_surface_brightness_to_kr(nl_to_v_surface_brightness(moon_sky_brightness_nl(sky)?)))
}

/// The Moon's whole-disc V irradiance outside the air, kR sr, surge included.
pub fn moon_irradiance_kr_sr(phase_angle_deg: f64) -> f64 {
    V0_IRRADIANCE_KR_SR * fmath::powf(10f64, -0.4 * moon_v_magnitude(phase_angle_deg)) * opposition_surge(phase_angle_deg)
}

/// The mean radiance of the Moon's disc outside the air, kR.
pub fn moon_disc_radiance_kr(phase_angle_deg: f64) -> f64 {
    moon_irradiance_kr_sr(phase_angle_deg) / MOON_SOLID_ANGLE_SR
}

#[cfg(test)]
mod tests {
    use super::*;

    /// specsim's documented example of this model (specsim.atmosphere.krisciunas_schaefer,
    /// https://specsim.readthedocs.io/en/latest/api/specsim.atmosphere.krisciunas_schaefer.html):
    /// sky at Z 20, Moon at Z 70, 50 degrees apart, phase 0.25 (alpha 45), k 0.15:
    /// 19.855 mag/arcsec^2.
    const SPECSIM: MoonSky =
        MoonSky { phase_angle_deg: 45.0, moon_zenith_deg: 70.0, sky_zenith_deg: 20.0, separation_deg: 50.0, extinction_v_mag: 0.15 };

    #[test]
    fn the_sky_matches_another_implementation_of_the_paper() {
        // 19.8548 here; specsim prints three decimals, so 0.005 mag (0.5 %)
        // is its rounding with room for float differences, and any slip in
        // a coefficient of eqs. 1, 3, 20 or 21 moves it by more.
        let mu = nl_to_v_surface_brightness(moon_sky_brightness_nl(&SPECSIM).unwrap());
        assert!((mu - 19.855).abs() < 0.005, "{mu}");
    }

    #[test]
    fn a_wrong_model_fails_the_same_test() {
        // The Moon's beam left unextinguished (no 10^(-0.4 k X(Z_m))): 19.471
        // mag/arcsec^2, 0.38 mag too bright, far outside the 0.005 allowed.
        let wrong = scattering_function(50.0) * moon_illuminance_fc(45.0) * (1.0 - fmath::powf(10f64, -0.4 * 0.15 * air_mass(20.0)));
        let mu = nl_to_v_surface_brightness(wrong);
        assert!((mu - 19.471).abs() < 0.001, "{mu}");
        assert!((mu - 19.855).abs() > 0.005);
    }

    #[test]
    fn the_phase_law_follows_allens_table() {
        // The Moon's magnitude against phase in Allen's Astrophysical
        // Quantities, relative to full Moon, as quoted by M. Waterman
        // (http://satobs.org/seesat/Mar-2000/0265.html), for alpha = 10, 20,
        // ... 120 degrees. Eq. 20 follows it to 0.035 mag at most (alpha 90);
        // 0.05 allowed, the table's rounding and a fit's spread.
        let allen = [0.23, 0.51, 0.79, 1.06, 1.35, 1.62, 1.91, 2.24, 2.63, 3.04, 3.48, 3.93];
        for (i, m) in allen.iter().enumerate() {
            let a = 10.0 * (i + 1) as f64;
            let d = moon_v_magnitude(a) - moon_v_magnitude(0.0);
            assert!((d - m).abs() < 0.05, "alpha {a}: {d} against {m}");
        }
        assert_eq!(moon_v_magnitude(0.0), -12.73);
    }

    #[test]
    fn illuminance_and_irradiance_agree() {
        // I* of a V = 0 source is 10^(-0.4 x 16.57) fc = 2.54e-6 lux
        // (1 fc = 10.764 lux), the standard illuminance of a zero-magnitude star.
        let lux0 = fmath::powf(10f64, -0.4 * 16.57) * 10.7639;
        assert!((lux0 / 2.54e-6 - 1.0).abs() < 0.01, "{lux0}");
        // The full Moon: 0.42 lux with the surge; and the same ratio in kR sr.
        for a in [0.0, 3.0, 45.0, 90.0, 150.0] {
            let ratio = moon_irradiance_kr_sr(a) / moon_illuminance_fc(a);
            assert!((ratio / (V0_IRRADIANCE_KR_SR / fmath::powf(10f64, -0.4 * 16.57)) - 1.0).abs() < 1e-12);
        }
        assert!((moon_illuminance_fc(0.0) * 10.7639 - 0.423).abs() < 0.005);
        assert_eq!(opposition_surge(7.0), 1.0);
        assert!((opposition_surge(6.999) - 1.0).abs() < 1e-4);
    }

    #[test]
    fn the_disc_radiance_is_its_surface_brightness() {
        // The full Moon's disc: m + 2.5 log10(Omega in arcsec^2) = 3.36 mag/arcsec^2
        // without the surge; its radiance the same through v_surface_brightness_to_kr.
        let omega_arcsec2 = MOON_SOLID_ANGLE_SR * ARCSEC2_PER_SR;
        assert!((omega_arcsec2 / 2.7306e6 - 1.0).abs() < 1e-3);
        let a = 30.0;
        let mu = moon_v_magnitude(a) + 2.5 * fmath::log10(omega_arcsec2);
        assert!((moon_disc_radiance_kr(a) / v_surface_brightness_to_kr(mu) - 1.0).abs() < 1e-12);
        assert!((moon_v_magnitude(0.0) + 2.5 * fmath::log10(omega_arcsec2) - 3.36).abs() < 0.01);
        assert!((ARCSEC2_PER_SR - fmath::powi(180.0 * 3600.0 / std::f64::consts::PI, 2)).abs() < 1.0);
    }

    #[test]
    fn unit_conversions_invert() {
        // Eq. 1's constants put 34.08 nL at 22.50 mag/arcsec^2.
        assert!((nl_to_v_surface_brightness(34.08) - 22.5).abs() < 1e-3);
        for mu in [15.0, 19.855, 21.9] {
            assert!((nl_to_v_surface_brightness(v_surface_brightness_to_nl(mu)) - mu).abs() < 1e-12);
        }
        // 21.9 mag/arcsec^2, a dark sky, is 0.73 kR of V-band radiance.
        assert!((v_surface_brightness_to_kr(21.9) - 0.0111 * fmath::powf(10f64, -0.4 * 21.9) * 4.2545e10).abs() < 1e-4);
    }

    #[test]
    fn the_domain_is_checked() {
        let ok = SPECSIM;
        assert!(moon_sky_radiance_kr(&ok).unwrap() > 0.0);
        assert_eq!(check(&MoonSky { phase_angle_deg: 190.0, ..ok }), Err(MoonlightError::PhaseAngle(190.0)));
        assert_eq!(check(&MoonSky { moon_zenith_deg: 95.0, ..ok }), Err(MoonlightError::Zenith { what: "Moon", value: 95.0 }));
        assert_eq!(check(&MoonSky { sky_zenith_deg: -1.0, ..ok }), Err(MoonlightError::Zenith { what: "sky", value: -1.0 }));
        assert_eq!(check(&MoonSky { separation_deg: 5.0, ..ok }), Err(MoonlightError::Separation(5.0)));
        assert!(matches!(check(&MoonSky { extinction_v_mag: f64::NAN, ..ok }), Err(MoonlightError::Extinction(_))));
        // Brighter nearer the Moon, and none without air.
        let near = moon_sky_brightness_nl(&MoonSky { separation_deg: 20.0, ..ok }).unwrap();
        assert!(near > moon_sky_brightness_nl(&ok).unwrap());
        assert_eq!(moon_sky_brightness_nl(&MoonSky { extinction_v_mag: 0.0, ..ok }).unwrap(), 0.0);
    }
}
