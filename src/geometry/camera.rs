//! The camera: projection, ray generation and the size of a pixel in the
//! world, defined so that the Blender add-on builds the same camera. The one
//! owner of camera maths: the renderer, pruning (`crate::pipeline::prune`) and the
//! automatic voxel size (`crate::pipeline::voxel::auto_voxel_size`) all ask it. The
//! limits it checks are the scene's ([`crate::scene::Camera::problems`],
//! [`crate::scene::MAX_IMAGE_SIDE`]), so a scene that validates always has a
//! camera.
//!
//! Basis: `forward = normalize(look_at - position)`,
//! `right = normalize(forward x up)`, `up' = right x forward`.
//! Film coordinates `(fx, fy)` run over `[0, W] x [0, H]`, row 0 at the top;
//! a pixel (px, py) is the square `[px, px+1] x [py, py+1]`. Write
//! `sx = 2 fx / W - 1` and `sy = 1 - 2 fy / H` (both in [-1, 1], y up).
//!
//! * Perspective (`fov_deg` is the *vertical* field of view):
//!   ray from `position` along `normalize(forward + sx tan(fov/2) W/H right + sy tan(fov/2) up')`.
//!   In Blender: `sensor_fit = 'VERTICAL'`, `angle_y = fov`, `shift = 0`.
//! * Orthographic: ray from `position + sx h W/H right + sy h up'` along
//!   `forward`, `h = ortho_height / 2`. In Blender: `sensor_fit = 'VERTICAL'`,
//!   `ortho_scale = ortho_height`, `clip_start` near 0 (rays start on the
//!   camera plane).
//! * Fisheye, equidistant (Cycles' `FISHEYE_EQUIDISTANT`,
//!   `kernel/camera/projection.h`, `fisheye_equidistant_to_direction`):
//!   `r = sqrt(sx^2 + sy^2)`, no ray for `r > 1` (outside the image circle:
//!   the pixel is empty, RGBA 0, as in Cycles), else the angle from the
//!   optical axis is `theta = r fov/2` and the ray runs along
//!   `cos theta forward + sin theta (sx/r right + sy/r up')`. `fov_deg` is the
//!   angle across the image circle, up to 360 (180: a planetarium dome
//!   master). Cycles' equidistant fisheye ignores the sensor: `(sx, sy)` span
//!   the whole frame whatever its aspect, so a square image holds a circle
//!   touching its edges and any other aspect an ellipse filling the frame
//!   (Blender's viewplane for panoramic cameras is `[0, 1]^2`,
//!   `blender_camera_viewplane` in `intern/cycles/blender/camera.cpp`).
//! * Equirectangular (Cycles' `EQUIRECTANGULAR` with its default range,
//!   longitude -180..180, latitude -90..90): longitude `lambda = pi sx`
//!   (positive to the right), latitude `beta = pi/2 sy`, ray along
//!   `cos beta (cos lambda forward + sin lambda right) + sin beta up'`: the
//!   image centre looks along `forward`, the top row at `up'`. Cycles' camera
//!   space for panoramas looks along +x (`blender_camera_matrix` turns it
//!   onto Blender's -z), and with `phi = -lambda`, `theta = pi/2 - beta` its
//!   `equirectangular_range_to_direction` is this formula.
//!
//! Pixel solid angle, relative to the image centre's (`Omega_p / Omega_0`,
//! [`CameraModel::relative_pixel_solid_angle`]): `cos^3 theta` for the
//! pinhole (the film plane at focal distance f: `dOmega = cos theta dA /
//! (f / cos theta)^2`); for the equidistant fisheye `dA = r dr dphi` maps to
//! `dOmega = sin theta dtheta dphi` with `theta = k r`, so
//! `Omega_p / Omega_0 = sin theta / theta`; for the equirectangular map
//! `dOmega = cos beta dlambda dbeta` on a uniform grid of (lambda, beta), so
//! `cos beta`.
//!
//! All ray math is f64.

use crate::scene::{Camera, Projection, MAX_IMAGE_SIDE};
use crate::util::fmath;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};

/// A ray `origin + t dir` with unit `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub dir: DVec3,
}

impl Ray {
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// A camera value or image size outside its range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key} = {value} is out of range: {allowed}")]
pub struct CameraError {
    pub key: String,
    pub value: String,
    pub allowed: String,
}

impl CameraError {
    /// Always the user's input: a camera key out of range (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// A validated camera for an image of `width x height` pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraModel {
    pub position: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    pub projection: Projection,
    /// `tan(fov/2)` (perspective).
    pub tan_half_fov: f64,
    /// `fov/2` in radians (fisheye).
    pub half_fov: f64,
    /// `ortho_height / 2` (orthographic).
    pub half_height: f64,
    pub width: usize,
    pub height: usize,
}

impl CameraModel {
    /// Checks the camera against the scene's limits (the same ones
    /// `Scene::validate` applies) and builds its basis.
    pub fn new(cam: &Camera, width: usize, height: usize) -> Result<CameraModel, CameraError> {
        for (key, n) in [("render.width", width), ("render.height", height)] {
            if n == 0 || n > MAX_IMAGE_SIDE {
                return Err(CameraError { key: key.into(), value: n.to_string(), allowed: format!("must be in [1, {MAX_IMAGE_SIDE}]") });
            }
        }
        if let Some((key, value, allowed)) = cam.problems().into_iter().next() {
            return Err(CameraError { key: format!("camera.{key}"), value, allowed });
        }
        let position = DVec3::from_array(cam.position);
        let forward = (DVec3::from_array(cam.look_at) - position).normalize();
        let right = forward.cross(DVec3::from_array(cam.up)).normalize();
        let up = right.cross(forward);
        Ok(CameraModel {
            position,
            forward,
            right,
            up,
            projection: cam.projection,
            tan_half_fov: fmath::tan(cam.fov_deg.to_radians() / 2.0),
            half_fov: cam.fov_deg.to_radians() / 2.0,
            half_height: cam.ortho_height / 2.0,
            width,
            height,
        })
    }

    /// Width / height.
    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }

    /// The ray through film point `(fx, fy)` (pixel (px, py) sampled at
    /// offset (jx, jy) is `(px + jx, py + jy)`), or None outside a fisheye's
    /// image circle.
    pub fn ray_at(&self, fx: f64, fy: f64) -> Option<Ray> {
        let (w, h) = (self.width as f64, self.height as f64);
        let sx = 2.0 * fx / w - 1.0;
        let sy = 1.0 - 2.0 * fy / h;
        let dir = match self.projection {
            Projection::Perspective => {
                let x_ndc = sx * self.tan_half_fov * w / h;
                let y_ndc = sy * self.tan_half_fov;
                (self.forward + x_ndc * self.right + y_ndc * self.up).normalize()
            }
            Projection::Orthographic => {
                let x_o = sx * self.half_height * w / h;
                let y_o = sy * self.half_height;
                return Some(Ray { origin: self.position + x_o * self.right + y_o * self.up, dir: self.forward });
            }
            Projection::Fisheye => {
                let r = (sx * sx + sy * sy).sqrt();
                if r > 1.0 {
                    return None;
                }
                let (s, c) = fmath::sin_cos(r * self.half_fov);
                if r > 0.0 {
                    (c * self.forward + (s / r) * (sx * self.right + sy * self.up)).normalize()
                } else {
                    self.forward
                }
            }
            Projection::Equirectangular => {
                let (sl, cl) = fmath::sin_cos(PI * sx);
                let (sb, cb) = fmath::sin_cos(FRAC_PI_2 * sy);
                (cb * (cl * self.forward + sl * self.right) + sb * self.up).normalize()
            }
        };
        Some(Ray { origin: self.position, dir })
    }

    /// [`ray_at`](Self::ray_at) for film points that always have a ray; for
    /// a fisheye outside its image circle, the ray at the circle's edge in
    /// the same direction on the film.
    pub fn ray(&self, fx: f64, fy: f64) -> Ray {
        self.ray_at(fx, fy).unwrap_or_else(|| {
            let (w, h) = (self.width as f64, self.height as f64);
            let (sx, sy) = (2.0 * fx / w - 1.0, 1.0 - 2.0 * fy / h);
            let r = (sx * sx + sy * sy).sqrt();
            let (s, c) = fmath::sin_cos(self.half_fov);
            Ray { origin: self.position, dir: (c * self.forward + (s / r) * (sx * self.right + sy * self.up)).normalize() }
        })
    }

    /// The film point `(fx, fy)` where world point `p` is seen, or None
    /// when it is not in the image (behind a pinhole, outside the fisheye's
    /// field of view or the frame). The inverse of [`ray_at`](Self::ray_at).
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let (w, h) = (self.width as f64, self.height as f64);
        let d = p - self.position;
        let (x, y, z) = (d.dot(self.right), d.dot(self.up), d.dot(self.forward));
        let (sx, sy) = match self.projection {
            Projection::Perspective => {
                if !(z > 0.0) {
                    return None;
                }
                (x / z / (self.tan_half_fov * w / h), y / z / self.tan_half_fov)
            }
            Projection::Orthographic => (x / (self.half_height * w / h), y / self.half_height),
            Projection::Fisheye => {
                let q = (x * x + y * y).sqrt();
                let theta = fmath::atan2(q, z);
                let r = theta / self.half_fov;
                if r > 1.0 {
                    return None;
                }
                if q > 0.0 {
                    (r * x / q, r * y / q)
                } else {
                    (0.0, 0.0)
                }
            }
            Projection::Equirectangular => {
                let lambda = fmath::atan2(x, z);
                let beta = fmath::atan2(y, (x * x + z * z).sqrt());
                (lambda / PI, beta / FRAC_PI_2)
            }
        };
        let (fx, fy) = ((sx + 1.0) * 0.5 * w, (1.0 - sy) * 0.5 * h);
        ((0.0..=w).contains(&fx) && (0.0..=h).contains(&fy)).then_some((fx, fy))
    }

    /// The solid angle of the pixel that sees direction `dir` (unit), over
    /// the solid angle of the pixel at the image centre (see the module
    /// documentation), with directions outside the image taken at the
    /// image's edge where pixels are smallest: the frame's corner
    /// (perspective), the outermost pixel centre inside the image circle
    /// (fisheye), the pole row's centre (equirectangular). 1 for the
    /// orthographic camera (every pixel covers the same area).
    pub fn relative_pixel_solid_angle(&self, dir: DVec3) -> f64 {
        let cos = dir.dot(self.forward);
        match self.projection {
            Projection::Orthographic => 1.0,
            Projection::Perspective => {
                // cos theta at the frame's corner.
                let t = self.tan_half_fov;
                let a = self.aspect();
                let cos_corner = 1.0 / (1.0 + t * t * (1.0 + a * a)).sqrt();
                let c = cos.max(cos_corner);
                c * c * c
            }
            Projection::Fisheye => {
                let theta_max = self.half_fov * (1.0 - 1.0 / self.width.min(self.height) as f64);
                let theta = fmath::acos(cos.clamp(-1.0, 1.0)).min(theta_max);
                if theta > 0.0 {
                    fmath::sin(theta) / theta
                } else {
                    1.0
                }
            }
            Projection::Equirectangular => {
                let sin_beta = dir.dot(self.up).clamp(-1.0, 1.0);
                let cos_beta = (1.0 - sin_beta * sin_beta).sqrt();
                cos_beta.max(fmath::sin(FRAC_PI_2 / self.height as f64))
            }
        }
    }

    /// The solid angle, sr, of the pixel that sees direction `dir` (unit):
    /// the centre pixel's (perspective `(2 tan(fov/2) / H)^2`; fisheye
    /// `fov^2 / (W H)`, from `dtheta = fov/2 dr` and `dr = 2 / W` across a
    /// pixel; equirectangular `(2 pi / W) (pi / H)`) times
    /// [`relative_pixel_solid_angle`](Self::relative_pixel_solid_angle).
    /// None for the orthographic camera (its pixels are areas, not angles).
    pub fn pixel_solid_angle(&self, dir: DVec3) -> Option<f64> {
        let (w, h) = (self.width as f64, self.height as f64);
        let omega0 = match self.projection {
            Projection::Orthographic => return None,
            Projection::Perspective => fmath::powi(2.0 * self.tan_half_fov / h, 2),
            Projection::Fisheye => fmath::powi(2.0 * self.half_fov, 2) / (w * h),
            Projection::Equirectangular => (2.0 * PI / w) * (PI / h),
        };
        Some(omega0 * self.relative_pixel_solid_angle(dir))
    }

    /// How many pixels a unit area facing the camera at `p` covers, up to a
    /// constant factor (the same for every `p`): `1 / (d^2 Omega_p /
    /// Omega_0)` with `d` the distance (at least `sqrt(d2_min)`, so a point
    /// at the eye does not weigh infinitely), and 1 for the orthographic
    /// camera, whose pixels all cover the same area at any distance.
    pub fn pixel_weight(&self, p: DVec3, d2_min: f64) -> f64 {
        if self.projection == Projection::Orthographic {
            return 1.0;
        }
        let v = p - self.position;
        let d2 = v.length_squared().max(d2_min);
        if self.projection == Projection::Perspective {
            // Written out so the pruned bytes stay those of the first
            // implementation (same operations in the same order).
            let t = self.tan_half_fov;
            let a = self.aspect();
            let cos_corner = 1.0 / (1.0 + t * t * (1.0 + a * a)).sqrt();
            let cos = (v.dot(self.forward) / d2.sqrt()).max(cos_corner);
            return 1.0 / (d2 * cos * cos * cos);
        }
        1.0 / (d2 * self.relative_pixel_solid_angle(v / d2.sqrt()))
    }

    /// The finest angle, radians, one pixel spans at the image centre
    /// (perspective: `2 tan(fov/2) / H`, the pixel's height over the focal
    /// distance; fisheye: `fov / max(W, H)`; equirectangular:
    /// `min(2 pi / W, pi / H)`); None for the orthographic camera.
    pub fn pixel_angle(&self) -> Option<f64> {
        let (w, h) = (self.width as f64, self.height as f64);
        match self.projection {
            Projection::Orthographic => None,
            Projection::Perspective => Some(2.0 * self.tan_half_fov / h),
            Projection::Fisheye => Some(2.0 * self.half_fov / w.max(h)),
            Projection::Equirectangular => Some((2.0 * PI / w).min(PI / h)),
        }
    }

    /// The size, km, of a pixel's footprint at `distance` km from the camera
    /// (at the image centre): `distance * pixel_angle`, or `ortho_height / H`
    /// for the orthographic camera whatever the distance.
    pub fn pixel_footprint(&self, distance: f64) -> f64 {
        match self.pixel_angle() {
            Some(a) => distance * a,
            None => 2.0 * self.half_height / self.height as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(projection: Projection, fov_deg: f64) -> Camera {
        Camera { position: [1.0, 2.0, 3.0], look_at: [4.0, 9.0, 5.0], up: [0.0, 0.0, 1.0], projection, fov_deg, ortho_height: 3.0 }
    }

    /// `project` inverts `ray_at` for every projection, at random film
    /// points (inside the image circle for the fisheye).
    #[test]
    fn project_inverts_ray() {
        let mut rng = crate::util::rng::rng(&[5]);
        use rand::Rng;
        for (p, fov) in [
            (Projection::Perspective, 70.0),
            (Projection::Orthographic, 70.0),
            (Projection::Fisheye, 180.0),
            (Projection::Fisheye, 300.0),
            (Projection::Equirectangular, 70.0),
        ] {
            for (w, h) in [(64, 64), (80, 40)] {
                let m = CameraModel::new(&cam(p, fov), w, h).unwrap();
                for _ in 0..200 {
                    let (fx, fy) = (rng.random::<f64>() * w as f64, rng.random::<f64>() * h as f64);
                    let Some(r) = m.ray_at(fx, fy) else { continue };
                    assert!((r.dir.length() - 1.0).abs() < 1e-12);
                    let (gx, gy) = m.project(r.at(7.5)).unwrap();
                    assert!((gx - fx).abs() < 1e-9 && (gy - fy).abs() < 1e-9, "{p:?} {fx},{fy} -> {gx},{gy}");
                }
            }
        }
    }

    #[test]
    fn fisheye_angles_and_circle() {
        // 180 degrees: the centre looks along forward, the circle's edge at
        // 90 degrees from it, the frame's corners are outside the circle.
        let m = CameraModel::new(&cam(Projection::Fisheye, 180.0), 100, 100).unwrap();
        assert!((m.ray(50.0, 50.0).dir - m.forward).length() < 1e-12);
        let top = m.ray_at(50.0, 0.0).unwrap().dir;
        assert!((top - m.up).length() < 1e-12, "{top}");
        let right = m.ray_at(100.0, 50.0).unwrap().dir;
        assert!((right - m.right).length() < 1e-12);
        assert!(m.ray_at(1.0, 1.0).is_none());
        // Equidistant: half way to the edge is 45 degrees off axis.
        let d = m.ray_at(75.0, 50.0).unwrap().dir;
        assert!((d.dot(m.forward) - fmath::cos(std::f64::consts::FRAC_PI_4)).abs() < 1e-12);
        // 360 degrees: the circle's edge looks backwards.
        let m = CameraModel::new(&cam(Projection::Fisheye, 360.0), 64, 64).unwrap();
        assert!((m.ray_at(64.0, 32.0).unwrap().dir + m.forward).length() < 1e-9);
    }

    #[test]
    fn equirectangular_covers_the_sphere() {
        let m = CameraModel::new(&cam(Projection::Equirectangular, 75.0), 200, 100).unwrap();
        assert!((m.ray(100.0, 50.0).dir - m.forward).length() < 1e-12);
        assert!((m.ray(100.0, 0.0).dir - m.up).length() < 1e-12);
        assert!((m.ray(150.0, 50.0).dir - m.right).length() < 1e-12);
        assert!((m.ray(0.0, 50.0).dir + m.forward).length() < 1e-12);
    }

    /// The pixel solid angle of the module documentation against a brute
    /// force one: the solid angle of the spherical quadrilateral spanned by
    /// a small film square's corner rays (two triangles, Van Oosterom and
    /// Strackee's formula), relative to the centre pixel's.
    #[test]
    fn relative_pixel_solid_angle_matches_the_corner_rays() {
        fn tri(a: DVec3, b: DVec3, c: DVec3) -> f64 {
            let num = a.dot(b.cross(c)).abs();
            let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
            2.0 * fmath::atan2(num, den)
        }
        let omega = |m: &CameraModel, fx: f64, fy: f64| {
            let e = 1e-3;
            let d = |x: f64, y: f64| m.ray_at(x, y).unwrap().dir;
            let (a, b, c, q) = (d(fx - e, fy - e), d(fx + e, fy - e), d(fx + e, fy + e), d(fx - e, fy + e));
            tri(a, b, c) + tri(a, c, q)
        };
        for (p, fov, w, h) in [
            (Projection::Perspective, 90.0, 64, 48),
            (Projection::Fisheye, 180.0, 64, 64),
            (Projection::Fisheye, 270.0, 80, 40),
            (Projection::Equirectangular, 75.0, 128, 64),
        ] {
            let m = CameraModel::new(&cam(p, fov), w, h).unwrap();
            let o0 = omega(&m, w as f64 / 2.0 + 1e-7, h as f64 / 2.0 + 1e-7);
            for (fx, fy) in [(10.3, 20.1), (40.0, 8.7), (30.0, 30.0), (20.0, 13.0)] {
                let Some(r) = m.ray_at(fx, fy) else { continue };
                let want = omega(&m, fx, fy) / o0;
                let got = m.relative_pixel_solid_angle(r.dir);
                // Finite differences of 1e-3 px: relative error ~1e-6.
                assert!((got / want - 1.0).abs() < 1e-4, "{p:?} at {fx},{fy}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn limits_are_the_scenes() {
        assert!(CameraModel::new(&cam(Projection::Perspective, 75.0), MAX_IMAGE_SIDE + 1, 10).is_err());
        assert!(CameraModel::new(&cam(Projection::Perspective, 180.0), 10, 10).is_err());
        assert!(CameraModel::new(&cam(Projection::Fisheye, 360.0), 10, 10).is_ok());
        assert!(CameraModel::new(&cam(Projection::Fisheye, 361.0), 10, 10).is_err());
        let e = CameraModel::new(&Camera { up: [6.0, 14.0, 4.0], ..cam(Projection::Perspective, 75.0) }, 10, 10).unwrap_err();
        assert_eq!(e.key, "camera.up");
    }

    #[test]
    fn pixel_footprint() {
        let m = CameraModel::new(&cam(Projection::Perspective, 90.0), 100, 50).unwrap();
        assert!((m.pixel_footprint(10.0) - 10.0 * 2.0 / 50.0).abs() < 1e-12);
        let m = CameraModel::new(&cam(Projection::Orthographic, 90.0), 100, 50).unwrap();
        assert!((m.pixel_footprint(1e6) - 3.0 / 50.0).abs() < 1e-15);
        let m = CameraModel::new(&cam(Projection::Fisheye, 180.0), 100, 100).unwrap();
        assert!((m.pixel_footprint(10.0) - 10.0 * PI / 100.0).abs() < 1e-12);
    }
}
