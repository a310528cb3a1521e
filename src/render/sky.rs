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
//! **Drawing stars.** Stars are drawn a few pixels wide and keep their flux: star `s` seen at
//! film point `f` gives pixel `q` (of the 7 x 7 around it) the radiance
//! `E T w_q / Omega_q`, `w_q = exp(-|c_q - f|^2 / (2 sigma^2)) / sum`, a
//! Gaussian of [`STAR_SIGMA_PX`] = 1 pixel at the pixel centres `c_q`
//! normalised over the 49 pixels, `Omega_q` the solid angle of pixel `q`
//! (from the camera, at its centre), `T` the volume's transmittance towards
//! the star times the air's per channel with `[sky] extinction` (0 behind
//! terrain or below the ground). So `sum_q L_q Omega_q = E T` at any resolution and
//! projection; the part of a footprint off the image (or outside a
//! fisheye's circle) is lost, and an equirectangular image wraps around in
//! azimuth. An orthographic camera sees no stars (its pixels have no solid
//! angle). Same seed, same stars; the pixel sums are done star by star in
//! a fixed order after the pixel loop, so the image does not depend on the
//! thread count.

use super::image::Image;
use super::moon::MoonSky;
use super::settings::{RenderError, RenderSettings};
use super::site_sky::{site_moon, site_stars, SiteHour};
pub use super::stars::{blackbody_rgb, planck, spectrum_rgb, star_field, Star, BRIGHTEST_MAG, COUNT_SLOPE, MAG0_KR_SR, STARS_TO_MAG_6};
use crate::geometry::camera::CameraModel;
use crate::scene::Background;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;

/// Standard deviation of a star's footprint, pixels.
pub const STAR_SIGMA_PX: f64 = 1.0;
/// Half-width of the footprint, pixels (3 sigma).
const STAR_RADIUS_PX: i64 = 3;
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
        (0.5 - d.y.atan2(d.x) / (2.0 * PI), 0.5 + d.z.clamp(-1.0, 1.0).asin() / PI)
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
        let Some(p) = &s.site else { return Sky::new(&s.background, s.seed, s.base_dir.as_deref()) };
        let hour = SiteHour::of(p, s.time_s).map_err(RenderError::Settings)?;
        let bg = &s.background;
        let mut sky = Sky::new(&Background { stars: false, ..bg.clone() }, s.seed, s.base_dir.as_deref())?;
        if bg.stars {
            sky.stars = site_stars(&hour, bg.limiting_magnitude, bg.star_brightness, s.observer, s.seed);
        }
        sky.moon = site_moon(&hour, v_extinction_coefficient(s), s.observer);
        Ok(sky)
    }

    /// Loads `background.image` (relative to `base_dir`) and draws the
    /// stars of `seed`.
    pub fn new(bg: &Background, seed: u64, base_dir: Option<&Path>) -> Result<Sky, RenderError> {
        let image = match &bg.image {
            None => None,
            Some(p) => {
                let path = super::settings::input_path(base_dir, p);
                let file = crate::util::input_file::open(&path).map_err(|source| RenderError::Input { key: "background.image", source })?;
                let img = super::image_file::read_exr_file(file, &path)?;
                Some(EnvMap::from_image(&img, &path)?)
            }
        };
        let stars = if bg.stars { star_field(seed, bg.limiting_magnitude, bg.star_brightness) } else { Vec::new() };
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
    /// each pixel `q` around it, `T` per channel from `transmittance(dir)`
    /// (None when terrain hides the star).
    pub fn add_stars(&self, img: &mut [[f32; 4]], camera: &CameraModel, transmittance: impl Fn(DVec3) -> Option<[f64; 3]>) {
        if camera.pixel_solid_angle(DVec3::Z).is_none() {
            return;
        }
        let (w, h) = (camera.width as i64, camera.height as i64);
        let wraps = camera.projection == crate::scene::Projection::Equirectangular;
        let k = STAR_RADIUS_PX;
        for s in &self.stars {
            let Some((fx, fy)) = camera.project(camera.position + s.dir) else { continue };
            let Some(t) = transmittance(s.dir) else { continue };
            let (cx, cy) = (fx.floor() as i64, fy.floor() as i64);
            let weight = |x: i64, y: i64| {
                let (dx, dy) = (x as f64 + 0.5 - fx, y as f64 + 0.5 - fy);
                (-(dx * dx + dy * dy) / (2.0 * STAR_SIGMA_PX * STAR_SIGMA_PX)).exp()
            };
            let mut sum = 0.0;
            for y in cy - k..=cy + k {
                for x in cx - k..=cx + k {
                    sum += weight(x, y);
                }
            }
            for y in (cy - k..=cy + k).filter(|y| (0..h).contains(y)) {
                for x in cx - k..=cx + k {
                    let xi = if wraps { x.rem_euclid(w) } else { x };
                    if !(0..w).contains(&xi) {
                        continue;
                    }
                    let Some(ray) = camera.ray_at(xi as f64 + 0.5, y as f64 + 0.5) else { continue };
                    let Some(omega) = camera.pixel_solid_angle(ray.dir) else { continue };
                    let f = weight(x, y) / sum / omega;
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
    /// 1e-4 (f32 pixels); it is spread over the pixels around it, centred on
    /// its projection: at least 9 pixels hold 1 % of its peak, and the
    /// flux-weighted centre is within 0.05 pixel of the projected point.
    #[test]
    fn a_star_keeps_its_flux_over_a_few_pixels() {
        let sky = Sky {
            image: None,
            stars: vec![Star { dir: DVec3::new(0.3, 0.4, 1.0).normalize(), magnitude: 0.0, irradiance: [1.0, 2.0, 3.0] }],
            moon: None,
        };
        for (p, w, h) in [
            (Projection::Fisheye, 64, 64),
            (Projection::Fisheye, 512, 512),
            (Projection::Equirectangular, 128, 64),
            (Projection::Perspective, 300, 200),
        ] {
            let cam = Camera {
                position: [0.0; 3],
                look_at: [0.0, 0.0, 1.0],
                up: [0.0, 1.0, 0.0],
                projection: p,
                fov_deg: if p == Projection::Fisheye { 180.0 } else { 90.0 },
                ortho_height: 1.0,
            };
            let m = CameraModel::new(&cam, w, h).unwrap();
            let mut img = vec![[0.0f32; 4]; w * h];
            sky.add_stars(&mut img, &m, |_| Some([0.5; 3]));
            let omega = |i: usize| m.pixel_solid_angle(m.ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5).dir).unwrap();
            let peak = img.iter().map(|q| q[2]).fold(0.0f32, f32::max);
            let lit = (0..w * h).filter(|&i| img[i][2] > 0.01 * peak).count();
            assert!(lit >= 9, "{p:?} {w}x{h}: {lit} pixels");
            let (mut flux, mut cx, mut cy) = (0.0, 0.0, 0.0);
            for i in 0..w * h {
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
        let d = DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        assert!((m.radiance(d)[0] - 1.0).abs() < 1e-9);
        assert_eq!(EnvMap::uv(DVec3::X), (0.5, 0.5));
        let (_, vz) = EnvMap::uv(DVec3::Z);
        assert_eq!(vz, 1.0);
        // Periodic in u: column 0 and column 7 blend across the seam.
        let (u0, v0) = (0.0, 1.0 - 0.5 / 4.0);
        let az = (0.5 - u0) * 2.0 * PI;
        let el = (v0 - 0.5) * PI;
        let d = DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        assert!((m.radiance(d)[1] - 2.5).abs() < 1e-6, "{:?}", m.radiance(d));
    }
}
