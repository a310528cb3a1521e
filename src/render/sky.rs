//! The sky behind the volume: an equirectangular radiance map
//! (`[background] image`) and the stars (`[background] stars`: the
//! statistical field of `stars.rs`, or over a `[site]` the catalogue's,
//! `site_sky.rs`) with the Moon (`moon.rs`). Like `background.radiance`, the sky is seen by camera rays only
//! (through the volume's transmittance) and lights nothing.
//!
//! **Sky image.** A linear equirectangular EXR, mapped as Blender's
//! Environment Texture maps it by default (Cycles
//! `direction_to_equirectangular`): a world direction `(x, y, z)` reads
//! `u = 1/2 - atan2(y, x) / (2 pi)` (left to right) and
//! `v = 1/2 + asin(z) / pi` (bottom to top), so the image centre faces +x
//! and its top row the zenith; bilinear between pixel centres, periodic in
//! u, clamped in v (Cycles' Linear interpolation with Repeat extension).
//!
//! **Drawing stars.** A star is drawn as the reference lens draws it
//! (`star_psf.rs`: a core of 2.5 arcminutes and a faint halo, sized in
//! angle and integrated over the render's pixels) and keeps its flux: star
//! `s` seen at film point `f` gives pixel `q` of its footprint the radiance
//! `E T w_q / Omega_q`, `w_q` the PSF's share of pixel `q` normalised over
//! the footprint, `Omega_q` the solid angle of pixel `q` (from the camera,
//! at its centre), `T` the volume's transmittance towards the star times
//! the air's per channel for the star's own spectrum
//! (`crate::physics::night_sky::star_extinction`, with `[sky] extinction`;
//! 0 behind terrain or below the ground). So `sum_q L_q Omega_q = E T` at
//! any resolution and projection; the part of a footprint off the image
//! (or outside a fisheye's circle) is lost, and an equirectangular image
//! wraps around in azimuth. An orthographic camera sees no stars (its
//! pixels have no solid angle). Same seed, same stars; the pixel sums are
//! done star by star in a fixed order after the pixel loop, so the image
//! does not depend on the thread count.

use super::image::Image;
use super::moon::MoonSky;
use super::settings::{RenderError, RenderSettings};
use super::site_sky::{site_moon, site_stars, SiteHour};
use super::star_psf::StarPsf;
pub use super::stars::{blackbody_rgb, planck, spectrum_rgb, star_field, Star, BRIGHTEST_MAG, MAG0_KR_SR, STAR_COUNTS};
use crate::geometry::camera::CameraModel;
use crate::scene::Background;
use crate::util::fmath;
use crate::util::observer::Observer;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;

/// An equirectangular radiance map (row 0 at the top).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl EnvMap {
    /// From an image; refuses negative or non-finite radiance.
    pub fn from_image(img: &Image, path: &Path) -> Result<EnvMap, RenderError> {
        if img.width == 0 || img.height == 0 {
            return Err(RenderError::Settings(format!("background.image {}: empty image", path.display())));
        }
        let pixels: Vec<[f32; 3]> = img.pixels.iter().map(|p| [p[0], p[1], p[2]]).collect();
        if let Some(i) = pixels.iter().position(|p| p.iter().any(|c| !(c.is_finite() && *c >= 0.0))) {
            return Err(RenderError::Settings(format!(
                "background.image {}: pixel ({}, {}) = {:?} must be finite and >= 0",
                path.display(),
                i % img.width,
                i / img.width,
                pixels[i]
            )));
        }
        Ok(EnvMap { width: img.width, height: img.height, pixels })
    }

    /// `(u, v)` of a world direction, v from the bottom (module documentation).
    pub fn uv(dir: DVec3) -> (f64, f64) {
        let d = dir.normalize();
        (0.5 - fmath::atan2(d.y, d.x) / (2.0 * PI), 0.5 + fmath::asin(d.z.clamp(-1.0, 1.0)) / PI)
    }

    /// Radiance seen along `dir`: bilinear between pixel centres.
    pub fn radiance(&self, dir: DVec3) -> [f64; 3] {
        let (u, v) = Self::uv(dir);
        let (w, h) = (self.width as f64, self.height as f64);
        // Continuous pixel coordinates, column 0 / row 0 (top) centres at 0.
        let x = u * w - 0.5;
        let y = (1.0 - v) * h - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let col = |i: f64| (i.rem_euclid(w)) as usize;
        let row = |j: f64| j.clamp(0.0, h - 1.0) as usize;
        let p = |i: f64, j: f64| self.pixels[row(j) * self.width + col(i)];
        let (a, b, c, d) = (p(x0, y0), p(x0 + 1.0, y0), p(x0, y0 + 1.0), p(x0 + 1.0, y0 + 1.0));
        [0, 1, 2].map(|k| (1.0 - fy) * ((1.0 - fx) * a[k] as f64 + fx * b[k] as f64) + fy * ((1.0 - fx) * c[k] as f64 + fx * d[k] as f64))
    }
}

/// The air's V-band extinction coefficient at the camera, magnitudes per
/// air mass: `2.5 log10(e)` times the zenith depth at 550 nm above it (0
/// without air).
pub fn v_extinction_coefficient(s: &RenderSettings) -> f64 {
    let Some(air) = crate::physics::air_extinction::Air::from_sky(&s.sky) else { return 0.0 };
    let earth = crate::geometry::earth::Earth::new(s.earth_radius_km);
    let z = earth.altitude(DVec3::from_array(s.camera.position));
    2.5 * std::f64::consts::LOG10_E * air.column_above(&air.depths(550.0), z)
}

/// Everything the renderer needs of the sky.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sky {
    pub image: Option<EnvMap>,
    pub stars: Vec<Star>,
    /// The Moon, with a site when any of it is up (`moon.rs`).
    pub moon: Option<MoonSky>,
}

impl Sky {
    /// The sky of `s`: without a site, [`Sky::new`]; with one, its image,
    /// the catalogue's stars at the site and hour and the Moon
    /// (`site_sky.rs`).
    pub fn of_settings(s: &RenderSettings) -> Result<Sky, RenderError> {
        let Some(p) = &s.site else { return Sky::new(&s.background, s.seed, s.base_dir.as_deref(), s.observer) };
        let hour = SiteHour::of(p, s.time_s).map_err(RenderError::Settings)?;
        let bg = &s.background;
        let mut sky = Sky::new(&Background { stars: false, ..bg.clone() }, s.seed, s.base_dir.as_deref(), s.observer)?;
        if bg.stars {
            sky.stars = site_stars(&hour, bg.limiting_magnitude, bg.star_brightness, s.observer, s.seed);
        }
        sky.moon = site_moon(&hour, v_extinction_coefficient(s), s.observer);
        Ok(sky)
    }

    /// Loads `background.image` (relative to `base_dir`) and draws the
    /// stars of `seed`, coloured for `observer`.
    pub fn new(bg: &Background, seed: u64, base_dir: Option<&Path>, observer: Observer) -> Result<Sky, RenderError> {
        let image = match &bg.image {
            None => None,
            Some(p) => {
                let path = super::settings::input_path(base_dir, p);
                let file = crate::util::input_file::open(&path).map_err(|source| RenderError::Input { key: "background.image", source })?;
                let img = super::image_file::read_exr_file(file, &path)?;
                Some(EnvMap::from_image(&img, &path)?)
            }
        };
        let stars = if bg.stars { star_field(seed, bg.limiting_magnitude, bg.star_brightness, observer) } else { Vec::new() };
        Ok(Sky { image, stars, moon: None })
    }

    /// The sky's radiance along `dir`: the image's and the moonlit sky's
    /// (stars and the Moon's disc are added apart).
    pub fn radiance(&self, dir: DVec3) -> [f64; 3] {
        let i = self.image.as_ref().map_or([0.0; 3], |m| m.radiance(dir));
        match &self.moon {
            Some(m) => {
                let l = m.sky_radiance(dir);
                [i[0] + l[0], i[1] + l[1], i[2] + l[2]]
            }
            None => i,
        }
    }

    /// Adds every star's footprint (module doc): `E T w_q / Omega_q` to
    /// each pixel `q` around it, `T` per channel from `transmittance(star)`
    /// (None when terrain hides the star).
    pub fn add_stars(&self, img: &mut [[f32; 4]], camera: &CameraModel, transmittance: impl Fn(&Star) -> Option<[f64; 3]>) {
        if camera.pixel_solid_angle(DVec3::Z).is_none() {
            return;
        }
        let (w, height) = (camera.width as i64, camera.height as i64);
        let wraps = camera.projection == crate::scene::Projection::Equirectangular;
        let psf = StarPsf::default();
        let mut weights = Vec::new();
        for s in &self.stars {
            let Some((fx, fy)) = camera.project(camera.position + s.dir) else { continue };
            let Some(t) = transmittance(s) else { continue };
            let Some(omega) = camera.pixel_solid_angle(s.dir) else { continue };
            let fp = psf.footprint(omega.sqrt());
            let k = fp.radius;
            let (cx, cy) = (fx.floor() as i64, fy.floor() as i64);
            let side = (2 * k + 1) as usize;
            let (sx, sy) = (fp.shares(cx - k, side, fx), fp.shares(cy - k, side, fy));
            let h = fp.halo_fraction;
            weights.clear();
            weights.extend(sy.iter().flat_map(|b| sx.iter().map(move |a| (1.0 - h) * a[0] * b[0] + h * a[1] * b[1])));
            let sum: f64 = weights.iter().sum();
            for y in (cy - k..=cy + k).filter(|y| (0..height).contains(y)) {
                for x in cx - k..=cx + k {
                    let xi = if wraps { x.rem_euclid(w) } else { x };
                    if !(0..w).contains(&xi) {
                        continue;
                    }
                    let wq = weights[(y - cy + k) as usize * side + (x - cx + k) as usize];
                    if wq <= 0.0 {
                        continue;
                    }
                    let Some(ray) = camera.ray_at(xi as f64 + 0.5, y as f64 + 0.5) else { continue };
                    let Some(omega) = camera.pixel_solid_angle(ray.dir) else { continue };
                    let f = wq / sum / omega;
                    let p = &mut img[y as usize * camera.width + xi as usize];
                    for c in 0..3 {
                        p[c] += (s.irradiance[c] * t[c] * f) as f32;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Projection};

    /// A star's flux, summed over the image (radiance times each pixel's
    /// solid angle), is E T whatever the resolution and projection, within
    /// 1e-4 (f32 pixels), and the flux-weighted centre is within 0.05 pixel
    /// of the projected point.
    #[test]
    fn a_star_keeps_its_flux_at_any_resolution() {
        let sky = Sky {
            image: None,
            stars: vec![Star {
                dir: DVec3::new(0.3, 0.4, 1.0).normalize(),
                magnitude: 0.0,
                irradiance: [1.0, 2.0, 3.0],
                temperature_k: 5800.0,
            }],
            moon: None,
        };
        for (p, w, h) in [
            (Projection::Fisheye, 64, 64),
            (Projection::Fisheye, 512, 512),
            (Projection::Fisheye, 2048, 2048),
            (Projection::Equirectangular, 128, 64),
            (Projection::Equirectangular, 4096, 2048),
            (Projection::Perspective, 300, 200),
            (Projection::Perspective, 3840, 2160),
        ] {
            let m = CameraModel::new(&camera(p, [0.0, 0.0, 1.0], if p == Projection::Fisheye { 180.0 } else { 90.0 }), w, h).unwrap();
            let mut img = vec![[0.0f32; 4]; w * h];
            sky.add_stars(&mut img, &m, |_| Some([0.5; 3]));
            let omega = |i: usize| m.pixel_solid_angle(m.ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5).dir).unwrap();
            let (mut flux, mut cx, mut cy) = (0.0, 0.0, 0.0);
            for i in (0..w * h).filter(|&i| img[i][2] > 0.0) {
                let f = img[i][2] as f64 * omega(i);
                flux += f;
                cx += f * ((i % w) as f64 + 0.5);
                cy += f * ((i / w) as f64 + 0.5);
            }
            assert!((flux / 1.5 - 1.0).abs() < 1e-4, "{p:?} {w}x{h}: {flux}");
            let (fx, fy) = m.project(m.position + sky.stars[0].dir).unwrap();
            assert!(
                (cx / flux - fx).abs() < 0.05 && (cy / flux - fy).abs() < 0.05,
                "{p:?} {w}x{h}: ({}, {}) vs ({fx}, {fy})",
                cx / flux,
                cy / flux
            );
        }
    }

    fn camera(p: Projection, look_at: [f64; 3], fov_deg: f64) -> Camera {
        Camera { position: [0.0; 3], look_at, up: [0.0, 1.0, 0.0], projection: p, fov_deg, ortho_height: 1.0 }
    }

    /// The image of a star seen at the centre of a 5-degree view, across
    /// the row through it: its FWHM (linear between pixel centres) at 1,
    /// 0.5 and 0.25 arcminutes a pixel is the reference lens's core, 149
    /// arcseconds, widened by the render's own pixel (a box, variance
    /// p^2 / 12) and smoothing (0.35 p) in quadrature, within 5 % (the
    /// faint halo and the sampling of the profile); at the finest within 3 %
    /// of the core itself: the size in angle does not follow the pixel. A
    /// star a fixed number of pixels wide (the Gaussian of one pixel drawn
    /// before) is 4 times narrower in angle at the finest and fails.
    #[test]
    fn a_star_is_as_wide_in_angle_at_any_resolution_above_the_pixel_scale() {
        let star = |dir: DVec3| Sky {
            image: None,
            stars: vec![Star { dir, magnitude: 0.0, irradiance: [1.0; 3], temperature_k: 5800.0 }],
            moon: None,
        };
        let mut widths = Vec::new();
        for n in [301usize, 601, 1201] {
            let m = CameraModel::new(&camera(Projection::Perspective, [0.0, 0.0, 1.0], 5.0), n, n).unwrap();
            let mut img = vec![[0.0f32; 4]; n * n];
            star(DVec3::Z).add_stars(&mut img, &m, |_| Some([1.0; 3]));
            let row: Vec<f64> = (0..n).map(|x| img[(n / 2) * n + x][1] as f64).collect();
            let (peak_x, peak) = row.iter().enumerate().fold((0, 0.0), |a, (i, &v)| if v > a.1 { (i, v) } else { a });
            let half = peak / 2.0;
            let cross = |step: i64| {
                let mut i = peak_x as i64;
                while row[(i + step) as usize] > half {
                    i += step;
                }
                let (a, b) = (row[i as usize], row[(i + step) as usize]);
                i as f64 + step as f64 * (a - half) / (a - b)
            };
            let fwhm_px = cross(1) - cross(-1);
            let pixel_arcsec = m.pixel_solid_angle(DVec3::Z).unwrap().sqrt().to_degrees() * 3600.0;
            let fwhm = fwhm_px * pixel_arcsec;
            let core = super::super::star_psf::CORE_FWHM_ARCSEC;
            let sigma = core / 2.354_820_045;
            let p = pixel_arcsec;
            let want = 2.354_820_045 * (sigma * sigma + fmath::powi(0.35 * p, 2) + p * p / 12.0).sqrt();
            eprintln!("{n} px: {fwhm} arcsec ({fwhm_px} px), want {want}");
            assert!((fwhm / want - 1.0).abs() < 0.05, "{n} px: {fwhm} arcsec ({fwhm_px} px), want {want}");
            widths.push(fwhm);
        }
        let core = super::super::star_psf::CORE_FWHM_ARCSEC;
        assert!((widths[2] / core - 1.0).abs() < 0.03, "{widths:?}");
        let (w, h) = (640, 360);
        let m = CameraModel::new(&camera(Projection::Perspective, [0.0, 0.0, 1.0], 100.0 * 360.0 / 640.0), w, h).unwrap();
        for (dx, dy) in [(0.0, 0.0), (0.013, 0.007), (0.021, -0.017)] {
            let dir = DVec3::new(dx, dy, 1.0).normalize();
            let mut img = vec![[0.0f32; 4]; w * h];
            star(dir).add_stars(&mut img, &m, |_| Some([1.0; 3]));
            let (fx, fy) = m.project(m.position + dir).unwrap();
            let omega = |x: usize, y: usize| m.pixel_solid_angle(m.ray(x as f64 + 0.5, y as f64 + 0.5).dir).unwrap();
            let (cx, cy) = (fx.floor() as usize, fy.floor() as usize);
            let near: f64 = (cy - 1..=cy + 1)
                .flat_map(|y| (cx - 1..=cx + 1).map(move |x| (x, y)))
                .map(|(x, y)| img[y * w + x][1] as f64 * omega(x, y))
                .sum();
            assert!(near > 0.9, "({fx}, {fy}): {near} of the flux in 3 x 3 pixels");
        }
    }

    #[test]
    fn env_map_faces_plus_x_at_its_centre_and_the_zenith_at_its_top() {
        let (w, h) = (8, 4);
        let mut pixels = vec![[0.0f32; 3]; w * h];
        pixels[w + w / 2] = [1.0, 0.0, 0.0]; // row 1, column 4: just above the horizon, centre
        pixels[0] = [0.0, 5.0, 0.0]; // top row, column 0
        let m = EnvMap { width: w, height: h, pixels };
        // Centre of pixel (4, 1): u = 4.5 / 8, v = 1 - 1.5 / 4.
        let (u, v) = (4.5 / 8.0, 1.0 - 1.5 / 4.0);
        let az = (0.5 - u) * 2.0 * PI;
        let el = (v - 0.5) * PI;
        let d = DVec3::new(fmath::cos(el) * fmath::cos(az), fmath::cos(el) * fmath::sin(az), fmath::sin(el));
        assert!((m.radiance(d)[0] - 1.0).abs() < 1e-9);
        assert_eq!(EnvMap::uv(DVec3::X), (0.5, 0.5));
        let (_, vz) = EnvMap::uv(DVec3::Z);
        assert_eq!(vz, 1.0);
        // Periodic in u: column 0 and column 7 blend across the seam.
        let (u0, v0) = (0.0, 1.0 - 0.5 / 4.0);
        let az = (0.5 - u0) * 2.0 * PI;
        let el = (v0 - 0.5) * PI;
        let d = DVec3::new(fmath::cos(el) * fmath::cos(az), fmath::cos(el) * fmath::sin(az), fmath::sin(el));
        assert!((m.radiance(d)[1] - 2.5).abs() < 1e-6, "{:?}", m.radiance(d));
    }
}
