//! `[atmosphere]`: the neutral atmosphere and the ambient ionosphere the
//! electrons fall through, with the defaults.
//! [`ATMOSPHERE_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Range};
use serde::{Deserialize, Serialize};

/// The neutral atmosphere model (`crate::physics::atmosphere`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AtmosphereModel {
    /// U.S. Standard Atmosphere 1976, 50-700 km: public domain, compiled in.
    Us1976,
    /// NRLMSIS 2.1, 67 N, 20 E, 2020-01-15 00:00 UT, F10.7 = 150, Ap = 15:
    /// research, academic and non-profit use only, read from `nrlmsis21.csv`
    /// in the data folder (docs/data.md).
    Nrlmsis21,
}

/// The ambient night-time ionosphere and NO the chemistry needs
/// (`crate::physics::chemistry::ambient`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Ionosphere {
    /// Closed forms: Te = Ti = Tn, a Chapman night-time F layer, a
    /// published NO peak; compiled in.
    ClosedForm,
    /// NCAR GLOW 4.0.4's (IRI above 200 km, NOEM's NO): no sale, read from
    /// `ionosphere.csv` in the data folder (docs/data.md).
    Glow,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AtmosphereParams {
    /// `us1976` (default) or `nrlmsis21`.
    pub model: AtmosphereModel,
    /// `closed-form` (default) or `glow`.
    pub ionosphere: Ionosphere,
    /// The folder holding the tables that are not compiled in
    /// (`nrlmsis21.csv`, `ionosphere.csv`), relative to the scene file's
    /// folder; unset, the `AURORA_DATA` environment variable names it, else
    /// the source tree's `data/` of the build.
    pub data: Option<String>,
    /// The folder `data` is relative to: the scene file's, set when the
    /// scene is read from a file (not part of the scene's TOML).
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
}

impl Default for AtmosphereParams {
    fn default() -> Self {
        Self { model: AtmosphereModel::Us1976, ionosphere: Ionosphere::ClosedForm, data: None, base_dir: None }
    }
}

/// Every key of `[atmosphere]`: name, unit, allowed range and description (`super::keys`).
pub const ATMOSPHERE_KEYS: &[KeySpec] = &[
    KeySpec::new("model", "", Range::Word(&["us1976", "nrlmsis21"]), "the neutral atmosphere: `us1976` (U.S. Standard Atmosphere 1976, 50-700 km, public domain, compiled in: `data/us1976.csv` from `tools/reference/ussa1976_table.py`) or `nrlmsis21` (NRLMSIS 2.1 at 67 N 20 E, 2020-01-15 00 UT, F10.7 150, Ap 15, made by `tools/reference/msis_table.py`; research, academic and non-profit use only, so read from `nrlmsis21.csv` in the data folder, never compiled in; docs/data.md)"),
    KeySpec::new("ionosphere", "", Range::Word(&["closed-form", "glow"]), "the ambient night ionosphere and NO the chemistry needs: `closed-form` (Te = Ti = Tn, Chapman F and E layers, SNOE's NO peak; compiled in; `src/physics/chemistry/ambient.rs`) or `glow` (NCAR GLOW 4.0.4's IRI ionosphere and NOEM NO at the NRLMSIS table's place and time, the data the chemistry was validated on; GLOW's licence forbids sale, so read from `ionosphere.csv` in the data folder; docs/data.md)"),
    KeySpec::new("data", "", Range::Any, "the folder holding `nrlmsis21.csv` and `ionosphere.csv`, relative to the scene file; unset, the `AURORA_DATA` environment variable names it, else the source tree's `data/` of the build. A table asked for and not there is refused naming the file and its terms (exit status 2)"),
];
