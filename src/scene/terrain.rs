//! `[terrain]`: the ground the aurora lights, with the defaults.
//! [`TERRAIN_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

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

/// Every key of `[terrain]`: name, unit, allowed range and description (`super::keys`).
pub const TERRAIN_KEYS: &[KeySpec] = &[
    KeySpec::new("kind", "", Range::Word(&["none", "plane", "heightfield"]), "`none`, `plane` (z = `height`) or `heightfield`"),
    KeySpec::new("height", "km", Range::Num(Num::FINITE), "base height of the plane or heightfield"),
    KeySpec::new(
        "albedo",
        "",
        Range::Each { min: 0.0, max: 1.0, what: "components", suffix: "" },
        "Lambertian albedo, linear Rec.709; the default 0.85 is fresh snow in the visible (Warren & Wiscombe 1980)",
    ),
    KeySpec::new(
        "mountain_height",
        "km",
        Range::Num(Num::closed(0.0, 100.0)),
        "heightfield: peak height of the procedural fBm mountains above `height`",
    ),
    KeySpec::new("mountain_scale", "km", Range::Num(Num::POSITIVE), "heightfield: horizontal feature size of the mountains"),
    KeySpec::new(
        "heightmap",
        "",
        Range::Any,
        "heightfield: a 16- or 8-bit greyscale PNG instead of the procedural mountains (relative to the scene file)",
    ),
    KeySpec::new(
        "extent",
        "km",
        Range::Rule("[x0, y0, x1, y1] with x1 > x0 and y1 > y0"),
        "heightfield: the ground covered, `[x0, y0, x1, y1]`",
    ),
    KeySpec::new("seed", "", Range::Any, "heightfield: seed of the procedural mountains"),
];
