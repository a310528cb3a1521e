//! The night sky's broadband light: what is left between the airglow's
//! lines, about half of a dark sky's visible light (Leinert et al. 1998,
//! A&AS 127, 1; Benn & Ellison 1998, La Palma Technical Note 115).
//!
//! **Model.** Three continua, each a spectral photon radiance in rayleigh
//! per nm (1 R/nm = 10^6 / (4 pi) photons cm^-2 s^-1 sr^-1 nm^-1):
//!
//! | component | where | spectrum | typical dark sky (key default) |
//! |---|---|---|---|
//! | zodiacal light | outside the atmosphere | sunlight: a 5772 K Planck spectrum | 90 x 10^-8 W m^-2 sr^-1 um^-1 at 500 nm |
//! | integrated starlight | outside the atmosphere | a G-K star's: a 5000 K Planck spectrum | 50 x 10^-8 W m^-2 sr^-1 um^-1 at 500 nm |
//! | airglow continuum | a layer at 90 km (sigma 6 km) | [`CONTINUUM_SHAPE`], rising from 400 nm to a broad maximum near 600 nm | 1.0 R/nm at 550 nm (zenith) |
//!
//! The zodiacal light's brightness is Leinert et al.'s Table 17 at 500 nm
//! (its unit, 10^-8 W m^-2 sr^-1 um^-1): 77 at the ecliptic pole, 259 in the
//! ecliptic 90 degrees from the Sun; the default, 90, is the sky at
//! ecliptic latitudes of 45-90 degrees away from the Sun, where a winter
//! night at an auroral site looks. Its colour is the Sun's (Leinert et al.,
//! sect. 8: solar from 0.2 to 2 um, slightly reddened; the reddening is
//! left out). The integrated starlight of the stars fainter than the
//! renderer draws (about V 6.5) at middle and high galactic latitude is
//! about half the zodiacal light (Leinert et al., sect. 6; Benn & Ellison
//! 1998: V 23.3 mag arcsec^-2 of zodiacal light, V 23.4-24 of starlight at
//! high latitudes); its colour is that of G and K giants, close to a 5000 K
//! Planck spectrum. The airglow continuum (NO + O -> NO2 + hv, the "air
//! afterglow") begins at 400 nm and is broad across the visible with its
//! maximum in the yellow-green to orange (Khomich, Semenov & Shefov 2008,
//! "Airglow as an Indicator of Upper Atmospheric Structure and Dynamics",
//! sect. 2; Noll et al. 2012, A&A 543, A92, the Cerro Paranal sky model's
//! residual continuum): not blue. Its level, about 0.1 R per angstrom in
//! the green, puts it between the zodiacal light and the starlight in the V
//! band. These are typical values, not a night's: every one is a key
//! (`[airglow]`).
//!
//! **Geometry.** Light from outside the atmosphere has no slant factor: its
//! radiance is the same from every direction up to the air's extinction
//! (`crate::render::airglow`). The continuum is a layer and brightens
//! toward the horizon by its slant factor, as the line layers do
//! (`crate::physics::airglow::slant_factor`).

use crate::util::fmath;

/// Planck constant times the speed of light, J nm.
const HC_J_NM: f64 = 1.986_445_857e-16;
/// The second radiation constant, nm K.
const HC_K_NM: f64 = 1.438_777e7;
/// Photons cm^-2 s^-1 sr^-1 of one rayleigh of column, 10^6 / (4 pi).
pub const PHOTONS_PER_R_SR: f64 = 1e6 / (4.0 * std::f64::consts::PI);

/// The Sun's effective temperature, K (the zodiacal light's spectrum).
pub const SUN_K: f64 = 5772.0;
/// The integrated starlight's colour temperature, K.
pub const STARLIGHT_K: f64 = 5000.0;
/// Reference wavelength of the zodiacal light and starlight keys, nm.
pub const REFERENCE_NM: f64 = 500.0;
/// Reference wavelength of the continuum key, nm.
pub const CONTINUUM_REFERENCE_NM: f64 = 550.0;
/// The continuum's relative photon spectrum, (nm, value), linear between
/// rows, 0 below the first and flat after the last (module doc).
pub const CONTINUUM_SHAPE: [(f64, f64); 9] =
    [(395.0, 0.0), (420.0, 0.25), (450.0, 0.45), (500.0, 0.7), (550.0, 1.0), (600.0, 1.15), (650.0, 1.1), (700.0, 1.0), (780.0, 0.9)];

/// Planck's spectral radiance up to a constant (energy per nm).
fn planck(lambda_nm: f64, t_k: f64) -> f64 {
    fmath::powi(lambda_nm, -5) / (fmath::exp(HC_K_NM / (lambda_nm * t_k)) - 1.0)
}

/// R/nm of a spectral radiance `b` in 10^-8 W m^-2 sr^-1 um^-1 at
/// `lambda_nm`: `b 1e-8 W m^-2 um^-1 = b 1e-15 W cm^-2 nm^-1`, over the
/// photon energy `hc / lambda`, over [`PHOTONS_PER_R_SR`].
pub fn energy_to_r_per_nm(b: f64, lambda_nm: f64) -> f64 {
    b * 1e-15 * lambda_nm / HC_J_NM / PHOTONS_PER_R_SR
}

/// A Planck spectrum of `t_k` scaled to `b500` (10^-8 W m^-2 sr^-1 um^-1)
/// at [`REFERENCE_NM`], in R/nm at `lambda_nm`.
fn planck_r_per_nm(b500: f64, t_k: f64, lambda_nm: f64) -> f64 {
    energy_to_r_per_nm(b500 * planck(lambda_nm, t_k) / planck(REFERENCE_NM, t_k), lambda_nm)
}

/// The zodiacal light, R/nm at `lambda_nm`, for `b500` at 500 nm.
pub fn zodiacal_r_per_nm(b500: f64, lambda_nm: f64) -> f64 {
    planck_r_per_nm(b500, SUN_K, lambda_nm)
}

/// The integrated starlight, R/nm at `lambda_nm`, for `b500` at 500 nm.
pub fn starlight_r_per_nm(b500: f64, lambda_nm: f64) -> f64 {
    planck_r_per_nm(b500, STARLIGHT_K, lambda_nm)
}

/// The airglow continuum's zenith column, R/nm at `lambda_nm`, for `r550`
/// R/nm at 550 nm ([`CONTINUUM_SHAPE`]).
pub fn continuum_r_per_nm(r550: f64, lambda_nm: f64) -> f64 {
    let s = &CONTINUUM_SHAPE;
    if lambda_nm <= s[0].0 {
        return 0.0;
    }
    let shape = match s.windows(2).find(|w| lambda_nm <= w[1].0) {
        Some(w) => w[0].1 + (w[1].1 - w[0].1) * (lambda_nm - w[0].0) / (w[1].0 - w[0].0),
        None => s[s.len() - 1].1,
    };
    r550 * shape
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 10^-8 W m^-2 sr^-1 um^-1 at 500 nm is 0.0317 R/nm: a photon of 500 nm
    /// carries 3.973e-19 J, so 1e-15 W cm^-2 nm^-1 is 2517 photons, over
    /// 79577 per rayleigh.
    #[test]
    fn the_units_convert_as_by_hand() {
        assert!((energy_to_r_per_nm(1.0, 500.0) / 0.031_63 - 1.0).abs() < 1e-3, "{}", energy_to_r_per_nm(1.0, 500.0));
        assert!((zodiacal_r_per_nm(90.0, 500.0) / (90.0 * 0.031_63) - 1.0).abs() < 1e-3);
        // The continuum: its key at 550 nm, nothing below 395 nm, flat past 780.
        assert_eq!(continuum_r_per_nm(2.0, 550.0), 2.0);
        assert_eq!(continuum_r_per_nm(2.0, 390.0), 0.0);
        assert!((continuum_r_per_nm(2.0, 800.0) - 1.8).abs() < 1e-12);
        // Starlight is redder than sunlight: less at 400 nm, relative to 500.
        assert!(
            starlight_r_per_nm(1.0, 400.0) / starlight_r_per_nm(1.0, 500.0) < zodiacal_r_per_nm(1.0, 400.0) / zodiacal_r_per_nm(1.0, 500.0)
        );
    }
}
