//! The scene file: every parameter of the bake and of the reference render.
//!
//! Units: **kilometres** for every length (positions, altitudes, radii, voxel
//! size), z up as in Blender, x east, y north. Extinction (`density`) is per
//! kilometre; emission is linear Rec.709 radiance per kilometre of path, scaled
//! so that Y = 1 corresponds to 1 kR of OI 557.7 nm per km (see `spectrum`).
//!
//! Parsing is separate from validation (pbrt's `GridMedium::Create` pattern):
//! serde reads the TOML (unknown keys are errors), then [`Scene::validate`]
//! checks every range once and names the file, line, key, value and the
//! allowed range. Stages downstream trust a validated scene.
//!
//! The rooms: [`types`] (the section structs and enums with their
//! defaults), [`presets`] (the built-in scenes), [`validation`] (the range
//! checks, their limits and the error types), [`schema`] (the
//! `--schema` JSON drawn from those checks) and [`kernel`] (the photon
//! kernel's radius range, read by the bake and the memory budget alike).
//! Everything is re-exported here, so `crate::scene::Camera`,
//! `crate::scene::MAX_SPP` and the like are the paths callers use.

pub mod kernel;
pub mod presets;
pub mod schema;
pub mod types;
pub mod validation;

pub use kernel::KernelRadius;
pub use types::*;
pub use validation::{
    check_shapes, find_key_line, RangeError, SceneError, MAX_COLORMAP_VALUE, MAX_IMAGE_SIDE, MAX_PRUNE, MAX_SEED, MAX_SHADOW_SAMPLES,
    MAX_SPP, MAX_THREADS,
};

use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    /// Master seed: every random stream is derived from it and an index.
    pub seed: u64,
    /// One entry per curtain (sheet): `[[curtain]]` tables.
    #[serde(rename = "curtain")]
    pub curtains: Vec<Curtain>,
    pub footprint: FootprintParams,
    pub beams: BeamParams,
    pub colour: ColourParams,
    pub photons: PhotonParams,
    pub grid: GridParams,
    pub camera: Camera,
    pub render: RenderParams,
    pub volume: VolumeParams,
    pub background: Background,
    pub sky: SkyParams,
    pub terrain: Terrain,
    pub animation: AnimationParams,
    pub atmosphere: AtmosphereParams,
    pub earth: EarthParams,
}

impl Default for Scene {
    fn default() -> Self {
        presets::default_scene()
    }
}

// ---------------------------------------------------------------- loading

/// Keys added with a default of 0 that means "off", left out of
/// [`Scene::hash`] and of the bake identity (`crate::pipeline::bake::identity`) while
/// 0: a scene that does not set them keeps the hash it had before they
/// existed, and its bake is the same.
pub const OFF_WHEN_ZERO: &[&str] = &["animation.trail_samples"];

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
        Self::from_toml_str(&text, path_or_preset)
    }

    /// The scene as TOML, as `aurora scene default` prints it.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene always serialises")
    }

    /// 64-bit FNV-1a hash of the canonical TOML: identifies a bake's inputs.
    /// Keys added later whose default means "off" ([`OFF_WHEN_ZERO`]) are
    /// left out while off, so a scene that does not use them keeps the hash
    /// (and the files) it had before they existed.
    pub fn hash(&self) -> u64 {
        let mut text = self.to_toml();
        for key in OFF_WHEN_ZERO {
            let (table, name) = key.split_once('.').expect("a dotted key");
            let line = format!("{name} = 0\n");
            if let Some(start) = text.find(&format!("[{table}]\n")) {
                let end = text[start + 1..].find("\n[").map_or(text.len(), |e| start + 1 + e);
                if let Some(i) = text[start..end].find(&line).map(|i| start + i) {
                    if text[..i].ends_with('\n') {
                        text.replace_range(i..i + line.len(), "");
                    }
                }
            }
        }
        fnv1a(text.as_bytes())
    }

    /// The voxel size in km, once resolved (`auto` is resolved by the bake).
    pub fn voxel_size_km(&self) -> Option<f64> {
        match self.grid.voxel_size {
            VoxelSize::Km(v) => Some(v),
            VoxelSize::Auto(_) => None,
        }
    }

    /// Checks every range; `text` (the TOML source) is used to find lines.
    pub fn validate(&self, file: &str, text: Option<&str>) -> Result<(), SceneError> {
        self.validate_with(file, text).map(|_| ())
    }
}

/// FNV-1a, 64 bit: a stable hash with no dependency (scene identity only).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn render_only_scene_takes_defaults_elsewhere() {
        let text = "[camera]\nposition = [0, -5, 0]\nlook_at = [0, 0, 0]\nprojection = \"orthographic\"\northo_height = 4.0\n[render]\nwidth = 8\nheight = 4\nspp = 1\n";
        let s = Scene::from_toml_str(text, "r.toml").unwrap();
        assert_eq!(s.camera.projection, Projection::Orthographic);
        assert_eq!(s.render.width, 8);
        assert_eq!(s.curtains.len(), 3);
    }

    #[test]
    fn keys_off_at_zero_leave_the_hash_alone() {
        // The hash of a scene with `animation.trail_samples = 0` is the hash
        // of its TOML without that line: what it was before the key existed,
        // so a bake that leaves the key off keeps its files.
        let s = Scene::default();
        assert!(s.to_toml().contains("\ntrail_samples = 0\n"));
        assert_eq!(s.hash(), fnv1a(s.to_toml().replacen("\ntrail_samples = 0\n", "\n", 1).as_bytes()));
        let mut t = s.clone();
        t.animation.trail_samples = 4;
        assert_ne!(t.hash(), s.hash());
        // Read back, the TOML without the line is the same scene.
        let back = Scene::from_toml_str(&s.to_toml().replace("\ntrail_samples = 0\n", "\n"), "t.toml").unwrap();
        assert_eq!(back, s);
    }
}
