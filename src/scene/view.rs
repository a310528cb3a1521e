//! What the reference renderer sees: `[camera]`, `[render]`, `[volume]`,
//! `[background]`, `[sky]` and `[terrain]`, each with its defaults. No
//! checks here (`super::validation`).

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

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderParams {
    pub width: usize,
    pub height: usize,
    /// Samples per pixel for the stochastic parts (pixel jitter, shadow rays).
    pub spp: usize,
    /// Exposure of the PNG preview, in stops.
    pub exposure: f64,
    /// The PNG preview's view transform (the EXR stays linear).
    pub view_transform: ViewTransform,
    /// Bits per channel of the PNG: 8, or 16 for delivery (a dome master's
    /// frames: the fulldome show file format takes 8-16 bit PNG or TIFF).
    pub png_bits: u32,
    /// Shutter time, s, of the reference renderer's motion blur: each
    /// camera sample reads the fields at `p - v(p) tau`, tau uniform over
    /// [-shutter_s / 2, shutter_s / 2], as Cycles does with a velocity grid
    /// (the bake's `v`: `grid.velocity = true`). 0: no blur.
    pub shutter_s: f64,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self { width: 640, height: 360, spp: 16, exposure: 3.0, view_transform: ViewTransform::Agx, png_bits: 8, shutter_s: 0.0 }
    }
}

/// How a linear image becomes PNG code values (`crate::render::view_transform`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ViewTransform {
    /// The sRGB OETF of the linear value, clipped (Blender's "Standard").
    Standard,
    /// AgX, Blender's default view (`crate::render::agx`).
    #[default]
    Agx,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct VolumeParams {
    /// extinction = density_scale * density grid.
    pub density_scale: f64,
    /// emitted radiance per unit length = emission_scale * emission grid.
    pub emission_scale: f64,
}

impl Default for VolumeParams {
    fn default() -> Self {
        Self { density_scale: 1.0, emission_scale: 1.0 }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Background {
    /// Constant radiance behind the volume where no terrain is hit.
    pub radiance: [f64; 3],
    /// Optional equirectangular linear EXR of sky radiance, added to
    /// `radiance` (path relative to the scene file; mapped as Blender's
    /// Environment Texture: centre towards +x, top row the zenith).
    pub image: Option<String>,
    /// A procedural star field (`crate::render::sky`), from the scene seed.
    pub stars: bool,
    /// Faintest star drawn, visual magnitude (6: the naked eye's limit).
    pub limiting_magnitude: f64,
    /// Scale on the stars' physical irradiance.
    pub star_brightness: f64,
}

impl Default for Background {
    fn default() -> Self {
        Self { radiance: [0.0, 0.0, 0.0], image: None, stars: true, limiting_magnitude: 6.0, star_brightness: 1.0 }
    }
}

/// The air between the aurora and the observer (`crate::physics::air_extinction`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SkyParams {
    /// Dim and redden what is seen through the lower atmosphere (Rayleigh,
    /// ozone, aerosol along each camera ray); false: no air.
    pub extinction: bool,
    /// Ozone column, Dobson units.
    pub ozone_du: f64,
    /// Aerosol optical depth at 550 nm, at sea level.
    pub aerosol_optical_depth: f64,
    /// Angstrom exponent of the aerosol's optical depth.
    pub angstrom: f64,
    /// Scale height of the aerosol's density, km.
    pub aerosol_scale_height_km: f64,
}

impl Default for SkyParams {
    fn default() -> Self {
        Self { extinction: true, ozone_du: 300.0, aerosol_optical_depth: 0.05, angstrom: 1.3, aerosol_scale_height_km: 1.2 }
    }
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TerrainKind {
    None,
    Plane,
    Heightfield,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Terrain {
    pub kind: TerrainKind,
    /// Base height of the plane or heightfield, km.
    pub height: f64,
    /// Lambertian albedo, linear Rec.709. The default, 0.85, is fresh
    /// snow's in the visible (Warren & Wiscombe 1980, J. Atmos. Sci. 37,
    /// 2734: 0.96-0.99 for pure snow, 5-15 % less with traces of soot).
    pub albedo: [f64; 3],
    /// Heightfield: peak height of the procedural mountains above `height`, km.
    pub mountain_height: f64,
    /// Heightfield: horizontal feature size of the mountains, km.
    pub mountain_scale: f64,
    /// Heightfield: optional 16-bit or 8-bit greyscale PNG heightmap instead of
    /// procedural mountains (path relative to the scene file).
    pub heightmap: Option<String>,
    /// Heightfield: ground extent covered by the heightmap, km: [x0, y0, x1, y1].
    pub extent: [f64; 4],
    /// Heightfield: seed of the procedural mountains.
    pub seed: u64,
}

impl Default for Terrain {
    fn default() -> Self {
        Self {
            kind: TerrainKind::None,
            height: 0.0,
            albedo: [0.85, 0.85, 0.85],
            mountain_height: 3.0,
            mountain_scale: 10.0,
            heightmap: None,
            extent: [-300.0, -300.0, 300.0, 300.0],
            seed: 7,
        }
    }
}
