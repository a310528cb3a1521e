//! A scene as every command and the Python module take it: a scene file or
//! a preset, its overrides (`--set KEY=VALUE`, `crate::scene::overrides`)
//! applied in order, validated (`crate::scene::load`); then what the scene
//! names outside itself is read before any work: a table that is not
//! compiled in (`[atmosphere] data`, refused if missing or damaged) and a
//! `[site]`'s hour (refused if its `utc` is not RFC 3339; a sky in
//! daylight or twilight is warned of). Then the curtains given in magnetic
//! coordinates (`[oval]`, `magnetic_path`) are placed over the `[site]`
//! (`crate::pipeline::footprint::magnetic_placement`), unless the caller
//! wants the scene as written ([`load_as_given`], what `aurora scene`
//! prints). The warnings are returned, for the caller to show.

use crate::physics::data_files::DataError;
use crate::scene::{Override, Scene, SceneError};
use std::path::{Path, PathBuf};

/// Why a scene could not be taken; each variant names the key or file.
#[derive(Debug, thiserror::Error)]
pub enum SceneInputError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Data(#[from] DataError),
    /// The `[site]`'s hour (its message names `site.utc`).
    #[error("{0}")]
    Site(String),
    /// A curtain in magnetic coordinates that cannot be placed (its
    /// message names the key).
    #[error("{0}")]
    Placement(String),
}

impl SceneInputError {
    /// The scene, its files or its overrides are at fault (exit status 2),
    /// as the errors inside say.
    pub fn is_input(&self) -> bool {
        match self {
            SceneInputError::Scene(e) => e.is_input(),
            SceneInputError::Data(e) => e.is_input(),
            SceneInputError::Site(_) | SceneInputError::Placement(_) => true,
        }
    }
}

/// A scene and the warnings taking it gave.
#[derive(Clone, Debug)]
pub struct SceneInput {
    pub scene: Scene,
    pub warnings: Vec<String>,
}

/// The scene `arg` names (a file or a preset) with `overrides` in order
/// (module doc).
pub fn load(arg: &str, overrides: &[Override]) -> Result<SceneInput, SceneInputError> {
    let input = load_as_given(arg, overrides)?;
    let scene =
        crate::pipeline::footprint::magnetic_placement::place(&input.scene).map_err(|e| SceneInputError::Placement(e.to_string()))?;
    Ok(SceneInput { scene, warnings: input.warnings })
}

/// As [`load`], with the curtains in magnetic coordinates as written.
pub fn load_as_given(arg: &str, overrides: &[Override]) -> Result<SceneInput, SceneInputError> {
    let scene = Scene::load_with(arg, overrides)?;
    let mut warnings: Vec<String> = Scene::shadowed_preset(arg).into_iter().collect();
    warnings.extend(checked(&scene)?);
    Ok(SceneInput { scene, warnings })
}

/// The checks of what a validated scene names outside itself (module doc),
/// and their warnings.
pub fn checked(scene: &Scene) -> Result<Vec<String>, SceneInputError> {
    crate::physics::atmosphere::Atmosphere::of_params(&scene.atmosphere)?;
    let mut warnings = Vec::new();
    if let Some(site) = &scene.site {
        let hour = crate::render::site_sky::SiteHour::of(site, scene.animation.time_s).map_err(SceneInputError::Site)?;
        warnings.extend(hour.twilight_warning());
    }
    Ok(warnings)
}

/// The folder relative paths in a scene file (a heightmap) are resolved
/// against: the scene file's own folder, or "." for a preset.
pub fn scene_dir(arg: &str) -> PathBuf {
    let p = Path::new(arg);
    if p.exists() {
        p.parent().filter(|d| !d.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."))
    } else {
        PathBuf::from(".")
    }
}
