//! `[camera]`: the camera of the reference render and of the Blender scene,
//! with its defaults and its one set of limits ([`Camera::problems`]).
//! [`CAMERA_KEYS`]: each key's unit, allowed range and description.

use super::keys::fmt_num;
use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    Perspective,
    Orthographic,
    /// Equidistant fisheye (Cycles' `FISHEYE_EQUIDISTANT`): `fov_deg` is the
    /// angle across the image circle, up to 360; 180 is a dome master.
    Fisheye,
    /// 360 x 180 degree latitude-longitude panorama (Cycles'
    /// `EQUIRECTANGULAR`); `fov_deg` is not used.
    Equirectangular,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Camera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    pub projection: Projection,
    /// Vertical field of view, degrees (perspective); the angle across the
    /// image circle (fisheye, up to 360).
    pub fov_deg: f64,
    /// Height of the view in scene units (orthographic).
    pub ortho_height: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            position: [0.0, -90.0, 1.0],
            look_at: [0.0, 20.0, 70.0],
            up: [0.0, 0.0, 1.0],
            projection: Projection::Perspective,
            fov_deg: 75.0,
            ortho_height: 10.0,
        }
    }
}

impl Camera {
    /// The largest `fov_deg` of this projection: 360 for the fisheye (the
    /// whole sphere), below 180 for a pinhole (degrees, exclusive).
    pub fn max_fov_deg(&self) -> (f64, bool) {
        match self.projection {
            Projection::Fisheye => (360.0, true),
            _ => (180.0, false),
        }
    }

    /// Every camera value outside its range, as (key, value, allowed): the
    /// one set of camera limits, applied by [`Scene::validate`](super::root::Scene::validate) and by
    /// `crate::geometry::camera::CameraModel::new`.
    pub fn problems(&self) -> Vec<(&'static str, String, String)> {
        let mut p = Vec::new();
        let (max_fov, inclusive) = self.max_fov_deg();
        if !(self.fov_deg > 0.0 && (self.fov_deg < max_fov || (inclusive && self.fov_deg == max_fov))) {
            let close = if inclusive { "]" } else { ")" };
            p.push(("fov_deg", fmt_num(self.fov_deg), format!("must be in (0, {}{close}", fmt_num(max_fov))));
        }
        if let Some((value, allowed)) =
            CAMERA_KEYS.iter().find(|k| k.name == "ortho_height").and_then(|k| k.number_problem(self.ortho_height))
        {
            p.push(("ortho_height", value, allowed));
        }
        let dir = [self.look_at[0] - self.position[0], self.look_at[1] - self.position[1], self.look_at[2] - self.position[2]];
        if dir.iter().all(|d| *d == 0.0) {
            p.push(("look_at", format!("{:?}", self.look_at), "must differ from camera.position".into()));
        }
        let cross = [
            dir[1] * self.up[2] - dir[2] * self.up[1],
            dir[2] * self.up[0] - dir[0] * self.up[2],
            dir[0] * self.up[1] - dir[1] * self.up[0],
        ];
        let up2: f64 = self.up.iter().map(|u| u * u).sum();
        let dir2: f64 = dir.iter().map(|u| u * u).sum();
        if !(cross.iter().map(|c| c * c).sum::<f64>() > 1e-18 * up2 * dir2) {
            // `up` is the picture's top: across a view along z (straight up
            // or down) north, [0, 1, 0], is; across any other view, z is.
            let vertical = dir[2].abs() >= dir[0].abs().max(dir[1].abs());
            let (along, suggest) = if vertical {
                (
                    if dir[2] > 0.0 { "the camera looks straight up" } else { "the camera looks straight down" },
                    "[0, 1, 0] (north at the top of the picture)",
                )
            } else {
                ("`up` lies along the view", "[0, 0, 1] (the sky at the top of the picture)")
            };
            p.push((
                "up",
                format!("{:?}", self.up),
                format!("must not be parallel to the view direction (look_at - position): {along}; set camera.up = {suggest}"),
            ));
        }
        for (k, a) in [("position", self.position), ("look_at", self.look_at), ("up", self.up)] {
            if a.iter().any(|x| !x.is_finite()) {
                p.push((k, format!("{a:?}"), "must be finite".into()));
            }
        }
        p
    }
}

/// Every key of `[camera]`: name, unit, allowed range and description (`super::keys`).
pub const CAMERA_KEYS: &[KeySpec] = &[
    KeySpec::new("position", "km", Range::Rule("finite"), "camera position"),
    KeySpec::new("look_at", "km", Range::Rule("finite, differs from camera.position"), "the point the camera looks at"),
    KeySpec::new("up", "", Range::Rule("finite, not parallel to look_at - position"), "up direction"),
    KeySpec::new("projection", "", Range::Word(&["perspective", "orthographic", "fisheye", "equirectangular"]), "`perspective`, `orthographic`, `fisheye` (equidistant, as Cycles' `FISHEYE_EQUIDISTANT`) or `equirectangular` (360 x 180 degrees, as Cycles' `EQUIRECTANGULAR`)"),
    KeySpec::new("fov_deg", "deg", Range::Rule("in (0, 180); in (0, 360] for projection = \"fisheye\""), "vertical field of view (perspective); for `fisheye` the angle across the image circle (180 = a planetarium dome master); unused by `equirectangular`"),
    KeySpec::new("ortho_height", "km", Range::Num(Num::POSITIVE), "height of the view (orthographic)"),
];
