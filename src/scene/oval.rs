//! `[oval]`: the auroral oval's activity, which places the scene's arcs
//! where the oval is over the site at its hour (needs `[site]`).
//! [`OVAL_KEYS`]: each key's unit, allowed range and description.
//!
//! With `[oval]` every curtain given by `center`, `length` and
//! `rotation_deg` is laid along the oval instead: curtain `i` of `n`
//! follows the line `(i + 1/2) / n` of the way from the oval's
//! equatorward edge to its poleward edge (Starkov 1994, in corrected
//! geomagnetic latitude at each magnetic local time:
//! `crate::physics::auroral_oval`), `length` km long, its middle at the
//! magnetic local time `mlt_h` (omitted: the site's own, so the arcs cross
//! the site's magnetic meridian); its `center` and `rotation_deg` are not
//! used. A curtain with a `path` or a `magnetic_path` keeps it. The
//! placement happens when a command loads the scene
//! (`crate::pipeline::footprint::magnetic_placement`): `aurora scene`
//! prints the keys as written, and the bake's scene hash is the placed
//! scene's.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

/// The oval's activity (module documentation).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OvalParams {
    /// The planetary Kp index, 0-9 (AL from it by Starkov's regression).
    pub kp: f64,
    /// The AL index, nT (negative); when given it replaces `kp`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub al_nt: Option<f64>,
    /// The magnetic local time of the arcs' middle, hours; none: the site's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mlt_h: Option<f64>,
}

impl Default for OvalParams {
    fn default() -> Self {
        OvalParams { kp: 3.0, al_nt: None, mlt_h: None }
    }
}

/// Every key of `[oval]`: name, unit, allowed range and description (`super::keys`).
pub const OVAL_KEYS: &[KeySpec] = &[
    KeySpec::new(
        "kp",
        "",
        Range::Num(Num::closed(0.0, 9.0)),
        "the planetary Kp index: the oval's boundaries by Starkov (1994) from AL = -(18 - 12.3 Kp + 27.2 Kp^2 - 2 Kp^3) nT (as Sigernes et al. 2011); the scene's straight curtains are laid between them",
    ),
    KeySpec::new("al_nt", "nT", Range::Num(Num::closed(-2000.0, -1.0)), "the AL index (negative); given, it replaces `kp` in Starkov's boundaries"),
    KeySpec::new(
        "mlt_h",
        "h",
        Range::Num(Num::closed(0.0, 24.0)),
        "the magnetic local time (AACGM-v2) of the arcs' middle; omitted: the site's at the scene's hour, so the arcs cross the site's magnetic meridian",
    ),
];
