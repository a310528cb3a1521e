//! `[atmosphere]`: the neutral atmosphere and the ambient ionosphere the
//! electrons fall through, with the defaults.

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
