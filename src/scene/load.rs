//! Reading a scene: TOML text or a file, or a built-in preset by name.
//! Parsing is separate from validation (pbrt's `GridMedium::Create`
//! pattern): serde reads the TOML (unknown keys are errors), then
//! [`Scene::validate`] checks every range once.

use super::presets;
use super::root::Scene;
use super::validation::{check_shapes, SceneError};
use std::path::Path;

impl Scene {
    /// Parses TOML text (unknown keys are errors), then validates it.
    /// `file` names the source in messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        check_shapes(text, file)?;
        let scene: Scene = toml::from_str(text).map_err(|e| SceneError::Parse { file: file.to_string(), message: e.to_string() })?;
        scene.validate(file, Some(text))?;
        Ok(scene)
    }

    /// Reads a scene file, or a preset by name ([`presets::PRESETS`]); a
    /// name that is neither is [`SceneError::Unknown`], naming the presets.
    pub fn load(path_or_preset: &str) -> Result<Scene, SceneError> {
        if let Some(s) = presets::by_name(path_or_preset) {
            if !Path::new(path_or_preset).exists() {
                return Ok(s);
            }
        }
        // Only a regular file is read (a FIFO or a device is refused, never
        // waited on: `crate::util::input_file`).
        let path = Path::new(path_or_preset);
        if !path.exists() && path.symlink_metadata().is_err() {
            return Err(SceneError::Unknown { name: path_or_preset.to_string(), presets: presets::names().collect() });
        }
        let text = crate::util::input_file::read_to_string(path)
            .map_err(|e| SceneError::Io { file: path_or_preset.to_string(), error: e.into() })?;
        let mut scene = Self::from_toml_str(&text, path_or_preset)?;
        // `[atmosphere] data` is relative to the scene file's folder.
        scene.atmosphere.base_dir = Some(path.parent().map(Path::to_path_buf).unwrap_or_default());
        Ok(scene)
    }
}
