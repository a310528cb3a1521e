//! The Moon as the camera sees it (`[site]`): its disc with its phase,
//! the sky it lights and the ground it lights. Where it is and how much of
//! it is lit come from `crate::geometry::astronomy::moon` (Meeus 1998,
//! ch. 47-48); its light from `crate::physics::night_sky::moonlight`
//! (Krisciunas & Schaefer 1991, V band).
//!
//! **The disc.** A sphere lit from the Sun at phase angle `alpha`, seen at
//! angular radius `r`: a point of the disc at `(x, y)` (in units of `r`, x
//! toward the bright limb) is lit where its outward normal `(x, y, sqrt(1 -
//! x^2 - y^2))` faces the Sun, `x sin(alpha) + z cos(alpha) > 0`, the
//! terminator's ellipse. The lit part is drawn at one radiance (the full
//! Moon's limb is hardly darker than its centre: Lommel-Seeliger, not
//! Lambert), scaled so that the disc's whole irradiance is the Moon's V-band
//! irradiance at that phase, `E = E_0 10^(-0.4 m(alpha))` in kR sr (K&S eq.
//! 20 and the stars' `E_0`, `sky.rs`; at the mean distance, so times
//! `(384400 km / d)^2` at the Moon's distance `d`). It is drawn after the pixel loop,
//! as the stars are: each pixel within the disc's reach gets `E T c /
//! Omega_q` times the share of its area that is lit, found on a
//! [`SUBSAMPLES`]^2 grid of points in the pixel, `T` the volume's and the
//! air's transmittance towards the Moon; so the drawn flux is `E T` within
//! the subsampling's error at any resolution.
//!
//! **The moonlit sky.** Each camera ray above the horizon that meets nothing
//! adds K&S's scattered moonlight `B(rho, Z, Z_m)` (their eq. 15: Rayleigh
//! and Mie scattering functions of the angle `rho` from the Moon, the air
//! masses of the ray's zenith distance `Z` and the Moon's `Z_m`; within 10
//! degrees of the Moon, where their fit ends, its value at 10), with the V
//! extinction coefficient `k` of `[sky]`'s air at the camera, `k = 2.5
//! log10(e) tau_550` (the zenith depth at 550 nm above the camera; no air:
//! `k = 0` and no scattered light), converted from nanoLamberts to V
//! mag/arcsec^2 (their eq. 1) and to the volume's radiance unit.
//!
//! **Colours.** The disc and the ground it lights have the colour of
//! moonlight: a blackbody at the temperature of the Moon's B-V = 0.92
//! (Allen's Astrophysical Quantities, 4th ed., 12.7; Ballesteros 2012's
//! temperature, about 4500 K), through the observer; the scattered sky
//! that colour weighted by Rayleigh's `lambda^-4`, bluer. Each has
//! luminance 1 and is scaled by the V-band value.

use super::stars::spectrum_rgb;
use crate::geometry::camera::CameraModel;
use crate::util::fmath;
use glam::DVec3;

/// Subsamples per pixel side on the disc's edge.
pub const SUBSAMPLES: usize = 6;
/// The Moon's colour index (Allen's Astrophysical Quantities).
pub const MOON_B_MINUS_V: f64 = 0.92;

/// The Moon over a site at an hour, as the renderer uses it.
#[derive(Clone, Debug, PartialEq)]
pub struct MoonSky {
    /// Apparent (refracted) direction, scene frame.
    pub dir: DVec3,
    /// Unit vector across the disc toward its lit limb.
    pub bright_limb: DVec3,
    /// Angular radius, radians.
    pub radius_rad: f64,
    /// Phase angle (0 at full), degrees.
    pub phase_angle_deg: f64,
    /// Illuminated fraction of the disc.
    pub illuminated_fraction: f64,
    /// The disc's V-band irradiance above the air, kR sr, times the
    /// colour (luminance 1).
    pub irradiance: [f64; 3],
    /// The scattered sky's colour, luminance 1.
    pub sky_colour: [f64; 3],
    /// V extinction coefficient of the air at the camera, mag per air mass.
    pub k_v: f64,
}

impl MoonSky {
    /// Builds it from where the Moon is (`dir` refracted, `bright_limb`,
    /// `radius_rad`, `phase_angle_deg`, `fraction`, its topocentric
    /// `distance_km`), the air's `k_v` and the observer: the ephemeris's
    /// quantities each by name, as the struct's fields are.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        dir: DVec3,
        bright_limb: DVec3,
        radius_rad: f64,
        phase_angle_deg: f64,
        fraction: f64,
        distance_km: f64,
        k_v: f64,
        observer: crate::util::observer::Observer,
    ) -> MoonSky {
        use crate::physics::night_sky::{moonlight, star_colour};
        let t = star_colour::temperature_k(MOON_B_MINUS_V);
        let colour = spectrum_rgb(observer, |l| super::stars::planck(l, t));
        let sky_colour = spectrum_rgb(observer, |l| super::stars::planck(l, t) * fmath::powi(550.0 / l, 4));
        // K&S's irradiance is at the mean distance: the inverse square law.
        let e = moonlight::moon_irradiance_kr_sr(phase_angle_deg) * fmath::powi(moonlight::MOON_MEAN_DISTANCE_KM / distance_km, 2);
        MoonSky {
            dir: dir.normalize(),
            bright_limb: bright_limb.normalize(),
            radius_rad,
            phase_angle_deg,
            illuminated_fraction: fraction,
            irradiance: colour.map(|c| c * e),
            sky_colour,
            k_v,
        }
    }

    /// The scattered moonlight along `dir` (module doc), 0 below the
    /// horizon or with the Moon below it.
    pub fn sky_radiance(&self, dir: DVec3) -> [f64; 3] {
        let d = dir.normalize();
        if d.z <= 0.0 || self.dir.z <= 0.0 || self.k_v <= 0.0 {
            return [0.0; 3];
        }
        use crate::physics::night_sky::moonlight::{moon_sky_radiance_kr, MoonSky as Geometry, MIN_SEPARATION_DEG};
        let rho = fmath::acos(d.dot(self.dir).clamp(-1.0, 1.0)).to_degrees();
        let sky = Geometry {
            phase_angle_deg: self.phase_angle_deg.clamp(0.0, 180.0),
            moon_zenith_deg: fmath::acos(self.dir.z.clamp(0.0, 1.0)).to_degrees(),
            sky_zenith_deg: fmath::acos(d.z.clamp(0.0, 1.0)).to_degrees(),
            // The fit holds from 10 degrees out; nearer, its value there.
            separation_deg: rho.max(MIN_SEPARATION_DEG),
            extinction_v_mag: self.k_v,
        };
        let l = moon_sky_radiance_kr(&sky).unwrap_or(0.0);
        self.sky_colour.map(|c| c * l)
    }

    /// Irradiance the Moon delivers on a surface of normal `n` above the
    /// air (times `max(0, n . dir)`), kR sr per channel.
    pub fn irradiance_on(&self, n: DVec3) -> [f64; 3] {
        let c = n.dot(self.dir).max(0.0);
        self.irradiance.map(|e| e * c)
    }

    /// Whether the point of the sky `d` (unit) is on the Moon's lit part.
    fn lit(&self, d: DVec3) -> bool {
        let s = fmath::sin(self.radius_rad);
        let along = d.dot(self.dir);
        if along <= 0.0 {
            return false;
        }
        let across = d - self.dir * along;
        let x = across.dot(self.bright_limb) / (s * along);
        let w = self.dir.cross(self.bright_limb);
        let y = across.dot(w) / (s * along);
        let r2 = x * x + y * y;
        if r2 > 1.0 {
            return false;
        }
        let a = self.phase_angle_deg.to_radians();
        x * fmath::sin(a) + (1.0 - r2).sqrt() * fmath::cos(a) > 0.0
    }

    /// The lit part's share of the disc's solid angle (for the radiance of
    /// the lit part): on a fine grid over the disc.
    fn lit_share(&self) -> f64 {
        let n = 200;
        let (mut lit, mut all) = (0usize, 0usize);
        let a = self.phase_angle_deg.to_radians();
        for j in 0..n {
            for i in 0..n {
                let x = -1.0 + (2 * i + 1) as f64 / n as f64;
                let y = -1.0 + (2 * j + 1) as f64 / n as f64;
                let r2 = x * x + y * y;
                if r2 > 1.0 {
                    continue;
                }
                all += 1;
                if x * fmath::sin(a) + (1.0 - r2).sqrt() * fmath::cos(a) > 0.0 {
                    lit += 1;
                }
            }
        }
        lit as f64 / all as f64
    }

    /// Draws the disc (module doc): `T` per channel from `transmittance`
    /// towards the Moon (None: hidden).
    pub fn draw(&self, img: &mut [[f32; 4]], camera: &CameraModel, transmittance: impl Fn(DVec3) -> Option<[f64; 3]>) {
        if camera.pixel_solid_angle(DVec3::Z).is_none() {
            return;
        }
        let Some(t) = transmittance(self.dir) else { return };
        let Some((fx, fy)) = camera.project(camera.position + self.dir) else { return };
        let disc_sr = 2.0 * std::f64::consts::PI * (1.0 - fmath::cos(self.radius_rad));
        let share = self.lit_share();
        if share <= 0.0 {
            return;
        }
        // Radiance of the lit part: E over the lit solid angle.
        let radiance = self.irradiance.map(|e| e / (disc_sr * share));
        // The disc's reach in pixels: the distance to a point on its rim.
        let rim = (self.dir * fmath::cos(self.radius_rad) + self.bright_limb * fmath::sin(self.radius_rad)).normalize();
        let reach = match camera.project(camera.position + rim) {
            Some((rx, ry)) => (fmath::hypot(rx - fx, ry - fy)).ceil() as i64 + 2,
            None => return,
        };
        let (w, h) = (camera.width as i64, camera.height as i64);
        let (cx, cy) = (fx.floor() as i64, fy.floor() as i64);
        let n = SUBSAMPLES;
        for y in (cy - reach..=cy + reach).filter(|y| (0..h).contains(y)) {
            for x in (cx - reach..=cx + reach).filter(|x| (0..w).contains(x)) {
                let mut lit = 0usize;
                for j in 0..n {
                    for i in 0..n {
                        let (px, py) = (x as f64 + (i as f64 + 0.5) / n as f64, y as f64 + (j as f64 + 0.5) / n as f64);
                        if let Some(ray) = camera.ray_at(px, py) {
                            if self.lit(ray.dir) {
                                lit += 1;
                            }
                        }
                    }
                }
                if lit == 0 {
                    continue;
                }
                let f = lit as f64 / (n * n) as f64;
                let p = &mut img[y as usize * camera.width + x as usize];
                for c in 0..3 {
                    p[c] += (radiance[c] * t[c] * f) as f32;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Projection};
    use crate::util::observer::Observer;

    fn moon(phase: f64, dir: DVec3) -> MoonSky {
        let limb = dir.cross(DVec3::Z).normalize();
        MoonSky::new(
            dir,
            limb,
            0.259f64.to_radians(),
            phase,
            (1.0 + fmath::cos(phase.to_radians())) / 2.0,
            384_400.0,
            0.15,
            Observer::Camera,
        )
    }

    /// The drawn disc keeps the Moon's irradiance (the sum of radiance
    /// times pixel solid angle is `E T`) within 2 % at a few resolutions and
    /// phases, and its lit share is the illuminated fraction `(1 + cos
    /// alpha) / 2` within 0.01 (the terminator's closed form).
    #[test]
    fn the_disc_keeps_its_flux_and_its_phase() {
        let dir = DVec3::new(0.2, 0.9, 0.4).normalize();
        for phase in [0.0, 60.0, 90.0, 130.0] {
            let m = moon(phase, dir);
            let k = m.lit_share();
            assert!((k - (1.0 + fmath::cos(phase.to_radians())) / 2.0).abs() < 0.01, "{phase}: {k}");
            for (w, fov) in [(400, 3.0), (1200, 10.0)] {
                let cam = Camera {
                    position: [0.0; 3],
                    look_at: dir.to_array(),
                    up: [0.0, 0.0, 1.0],
                    projection: Projection::Perspective,
                    fov_deg: fov,
                    ortho_height: 1.0,
                };
                let cm = CameraModel::new(&cam, w, w).unwrap();
                let mut img = vec![[0.0f32; 4]; w * w];
                m.draw(&mut img, &cm, |_| Some([1.0; 3]));
                let mut flux = 0.0;
                for (i, p) in img.iter().enumerate() {
                    let r = cm.ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                    flux += p[1] as f64 * cm.pixel_solid_angle(r.dir).unwrap();
                }
                assert!((flux / m.irradiance[1] - 1.0).abs() < 0.02, "phase {phase} w {w}: {flux} vs {}", m.irradiance[1]);
            }
        }
    }

    /// The lit limb faces the Sun's side: at quarter phase the half of the
    /// disc toward `bright_limb` is lit and the other half dark.
    #[test]
    fn the_lit_limb_faces_the_sun() {
        let dir = DVec3::new(0.0, 1.0, 1.0).normalize();
        let m = moon(90.0, dir);
        let off = m.radius_rad * 0.5;
        assert!(m.lit((dir + m.bright_limb * off).normalize()));
        assert!(!m.lit((dir - m.bright_limb * off).normalize()));
    }
}
