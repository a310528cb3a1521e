//! Camera rays, defined so that the Blender add-on builds the same camera.
//!
//! Basis: `forward = normalize(look_at - position)`,
//! `right = normalize(forward x up)`, `up' = right x forward`.
//! Film coordinates `(fx, fy)` run over `[0, W] x [0, H]`, row 0 at the top;
//! a pixel (px, py) is the square `[px, px+1] x [py, py+1]`.
//!
//! * Perspective (`fov_deg` is the *vertical* field of view):
//!   `x_ndc = (2 fx / W - 1) tan(fov/2) W/H`, `y_ndc = (1 - 2 fy / H) tan(fov/2)`,
//!   ray from `position` along `normalize(forward + x_ndc right + y_ndc up')`.
//!   In Blender: `sensor_fit = 'VERTICAL'`, `angle_y = fov`, `shift = 0`.
//! * Orthographic: ray from `position + x_o right + y_o up'` along `forward`, with
//!   `y_o = (1 - 2 fy / H) ortho_height / 2`, `x_o = (2 fx / W - 1) ortho_height / 2 * W/H`.
//!   In Blender: `sensor_fit = 'VERTICAL'`, `ortho_scale = ortho_height`, and
//!   `clip_start` near 0 (we start rays on the camera plane).
//!
//! All ray math is f64.

use super::RenderError;
use crate::scene::{Camera, Projection};
use glam::DVec3;

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
    /// `ortho_height / 2` (orthographic).
    pub half_height: f64,
    pub width: usize,
    pub height: usize,
}

impl CameraModel {
    pub fn new(cam: &Camera, width: usize, height: usize) -> Result<CameraModel, RenderError> {
        let bad = |m: String| Err(RenderError::Settings(m));
        if width == 0 || height == 0 {
            return bad(format!("image size {width}x{height} must be at least 1x1"));
        }
        let position = DVec3::from_array(cam.position);
        let look_at = DVec3::from_array(cam.look_at);
        let up = DVec3::from_array(cam.up);
        if !(position.is_finite() && look_at.is_finite() && up.is_finite()) {
            return bad("camera position, look_at and up must be finite".into());
        }
        let forward = (look_at - position).normalize_or_zero();
        if forward == DVec3::ZERO {
            return bad("camera.look_at must differ from camera.position".into());
        }
        let right = forward.cross(up);
        if !(right.length_squared() > 1e-18 * up.length_squared()) {
            return bad("camera.up must not be parallel to the view direction".into());
        }
        let right = right.normalize();
        let up = right.cross(forward);
        match cam.projection {
            Projection::Perspective if !(cam.fov_deg > 0.0 && cam.fov_deg < 180.0) => {
                return bad(format!("camera.fov_deg = {} must be in (0, 180)", cam.fov_deg));
            }
            Projection::Orthographic if !(cam.ortho_height > 0.0 && cam.ortho_height.is_finite()) => {
                return bad(format!("camera.ortho_height = {} must be finite and > 0", cam.ortho_height));
            }
            _ => {}
        }
        Ok(CameraModel {
            position,
            forward,
            right,
            up,
            projection: cam.projection,
            tan_half_fov: (cam.fov_deg.to_radians() / 2.0).tan(),
            half_height: cam.ortho_height / 2.0,
            width,
            height,
        })
    }

    /// The ray through film point `(fx, fy)` (pixel (px, py) sampled at
    /// offset (jx, jy) is `(px + jx, py + jy)`).
    pub fn ray(&self, fx: f64, fy: f64) -> Ray {
        let (w, h) = (self.width as f64, self.height as f64);
        let sx = 2.0 * fx / w - 1.0;
        let sy = 1.0 - 2.0 * fy / h;
        match self.projection {
            Projection::Perspective => {
                let x_ndc = sx * self.tan_half_fov * w / h;
                let y_ndc = sy * self.tan_half_fov;
                Ray { origin: self.position, dir: (self.forward + x_ndc * self.right + y_ndc * self.up).normalize() }
            }
            Projection::Orthographic => {
                let x_o = sx * self.half_height * w / h;
                let y_o = sy * self.half_height;
                Ray { origin: self.position + x_o * self.right + y_o * self.up, dir: self.forward }
            }
        }
    }
}
