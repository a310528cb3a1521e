//! A star as a lens draws it: the point spread function of a stated
//! reference lens and sensor, sized in angle, integrated over the render's
//! own pixels ([`StarPsf`]).
//!
//! **Reference.** A 14-24 mm f/2.8 wide-angle zoom at 14 mm, wide open, on
//! a full-frame (36 x 24 mm) sensor: the aurora photographer's lens. Its
//! image of a star is
//!
//! * a *core*: diffraction, the Airy disc of FWHM `1.029 lambda N` = 1.58 um
//!   at 550 nm and f/2.8 (Born & Wolf, Principles of Optics, 7th ed., 8.5.2),
//!   with the lens's residual aberration and focus blur, taken as 10 um FWHM
//!   in the focal plane (about 1.7 pixels of a 24 MP full-frame sensor, 5.98
//!   um: a star a sharp point of a couple of pixels at the frame's centre), added in
//!   quadrature, 10.1 um: a Gaussian of FWHM [`CORE_FWHM_ARCSEC`] = 149
//!   arcseconds (10.1 um / 14 mm), 2.5 arcminutes;
//! * a faint *halo*, light the lens's glass, coatings and the sensor's
//!   cover glass scatter around the core (veiling glare: ISO 9358 measures a few
//!   per cent for camera lenses): [`HALO_FRACTION`] = 4 % of the flux in a
//!   Gaussian of FWHM [`HALO_FWHM_ARCMIN`] = 20 arcminutes. Its surface
//!   brightness is 0.04 / 0.96 x (2.5 / 20)^2 = 6.5e-4 of the core's peak:
//!   only a star some 8 magnitudes above the faintest the picture shows
//!   (Sirius, Vega in a frame exposed for fifth-magnitude stars) shows it, so bright
//!   stars look bigger through the halo alone, as in photographs.
//!
//! The sensor's own pixels are not part of it: the render's pixels are.
//!
//! **At the render's pixels.** At a star's film point the render's pixel
//! spans `p = sqrt(Omega)` radians (`Omega` the pixel's solid angle, from
//! the camera), so each component is a Gaussian of `sigma / p` pixels; a
//! Gaussian of [`MIN_SIGMA_PX`] = 0.35 pixel is added in quadrature (the
//! smoothing a resampled photograph has at its own pixel scale; it keeps a
//! star that moves by part of a pixel from flickering). Each pixel's weight
//! is the PSF integrated over its square (a product of `erf` differences in
//! x and y), normalised over the footprint, which reaches
//! [`FOOTPRINT_SIGMAS`] halo sigmas and at most [`MAX_RADIUS_PX`]. So a
//! star stays a point when the core is below a pixel (at 640 px across a
//! 100-degree view a pixel is 9.4 arcminutes) and has the core's angular
//! size above it (at 3840 px, 1.6 arcminutes), and `sky.rs` keeps its flux
//! `sum L Omega = E T` at any resolution.

use crate::util::fmath;

/// FWHM of the core, arcseconds (module doc).
pub const CORE_FWHM_ARCSEC: f64 = 149.0;
/// FWHM of the halo, arcminutes.
pub const HALO_FWHM_ARCMIN: f64 = 20.0;
/// The halo's share of the flux.
pub const HALO_FRACTION: f64 = 0.04;
/// The render's own smoothing, pixels (a Gaussian sigma).
pub const MIN_SIGMA_PX: f64 = 0.35;
/// The footprint's half-width in halo sigmas.
pub const FOOTPRINT_SIGMAS: f64 = 3.5;
/// The footprint's largest half-width, pixels.
pub const MAX_RADIUS_PX: i64 = 96;

/// Gaussian sigma of a FWHM.
const FWHM_TO_SIGMA: f64 = 0.42466090014400953; // 1 / (2 sqrt(2 ln 2))

/// The reference lens's PSF (module doc), in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StarPsf {
    pub core_sigma_rad: f64,
    pub halo_sigma_rad: f64,
    pub halo_fraction: f64,
}

impl Default for StarPsf {
    fn default() -> Self {
        StarPsf {
            core_sigma_rad: (CORE_FWHM_ARCSEC / 3600.0).to_radians() * FWHM_TO_SIGMA,
            halo_sigma_rad: (HALO_FWHM_ARCMIN / 60.0).to_radians() * FWHM_TO_SIGMA,
            halo_fraction: HALO_FRACTION,
        }
    }
}

/// A star's footprint at the render's pixel scale: the two components'
/// sigmas in pixels and the footprint's half-width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    pub core_px: f64,
    pub halo_px: f64,
    pub halo_fraction: f64,
    pub radius: i64,
}

impl StarPsf {
    /// The footprint where a pixel spans `pixel_rad` radians.
    pub fn footprint(&self, pixel_rad: f64) -> Footprint {
        let px = |s: f64| (fmath::powi(s / pixel_rad, 2) + MIN_SIGMA_PX * MIN_SIGMA_PX).sqrt();
        let (core_px, halo_px) = (px(self.core_sigma_rad), px(self.halo_sigma_rad));
        let radius = ((FOOTPRINT_SIGMAS * halo_px.max(core_px)).ceil() as i64).clamp(1, MAX_RADIUS_PX);
        Footprint { core_px, halo_px, halo_fraction: self.halo_fraction, radius }
    }
}

/// The share of a Gaussian of `sigma` centred at `c` between `a` and `b`.
fn box_share(a: f64, b: f64, c: f64, sigma: f64) -> f64 {
    let s = std::f64::consts::SQRT_2 * sigma;
    0.5 * (libm::erf((b - c) / s) - libm::erf((a - c) / s))
}

impl Footprint {
    /// The core's and the halo's shares of the `n` pixels from `first` along
    /// one axis for a star at `c` on that axis: `weight(x, y)` is
    /// `(1 - h) core_x core_y + h halo_x halo_y`.
    pub fn shares(&self, first: i64, n: usize, c: f64) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let a = (first + i as i64) as f64;
                [box_share(a, a + 1.0, c, self.core_px), box_share(a, a + 1.0, c, self.halo_px)]
            })
            .collect()
    }

    /// Unnormalised weight of pixel `(x, y)` (its square `[x, x+1] x [y, y+1]`)
    /// for a star at film point `(fx, fy)`.
    pub fn weight(&self, x: i64, y: i64, fx: f64, fy: f64) -> f64 {
        let (x, y) = (x as f64, y as f64);
        let part = |s: f64| box_share(x, x + 1.0, fx, s) * box_share(y, y + 1.0, fy, s);
        (1.0 - self.halo_fraction) * part(self.core_px) + self.halo_fraction * part(self.halo_px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The core's FWHM is the diffraction and aberration blur in quadrature
    /// over the focal length, to the arcsecond.
    #[test]
    fn the_core_is_the_reference_lens_blur_over_its_focal_length() {
        let airy_um = 1.029 * 0.55 * 2.8;
        let fwhm_um = (airy_um * airy_um + 10.0f64 * 10.0).sqrt();
        let arcsec = (fwhm_um * 1e-3 / 14.0).to_degrees() * 3600.0;
        assert!((arcsec - CORE_FWHM_ARCSEC).abs() < 1.0, "{arcsec}");
    }

    /// Weights over a wide enough window sum to 1 (the two Gaussians are
    /// normalised), and a star at a pixel's centre with a core far below a
    /// pixel puts most of its light in that pixel.
    #[test]
    fn a_sub_pixel_core_stays_in_one_pixel() {
        let f = StarPsf::default().footprint((10.0f64 / 60.0).to_radians());
        let r = f.radius + 5;
        let total: f64 = (-r..=r).flat_map(|y| (-r..=r).map(move |x| (x, y))).map(|(x, y)| f.weight(x, y, 0.5, 0.5)).sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        assert!(f.weight(0, 0, 0.5, 0.5) > 0.65, "{}", f.weight(0, 0, 0.5, 0.5));
    }
}
