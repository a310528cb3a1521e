//! The scene file's root table, [`Scene`]: one field per TOML table, its
//! canonical TOML and the hash that identifies a bake's inputs.
//! [`ROOT_KEYS`]: each key's unit, allowed range and description.

use super::airglow::AirglowParams;
use super::animation::AnimationParams;
use super::atmosphere::AtmosphereParams;
use super::background::Background;
use super::beams::BeamParams;
use super::camera::Camera;
use super::colour::ColourParams;
use super::curtain::Curtain;
use super::earth::EarthParams;
use super::footprint::FootprintParams;
use super::grid::{GridParams, VoxelSize};
use super::keys::{KeySpec, Range};
use super::oval::OvalParams;
use super::photons::PhotonParams;
use super::render::RenderParams;
use super::site::SiteParams;
use super::sky::SkyParams;
use super::terrain::Terrain;
use super::volume::VolumeParams;
use serde::{Deserialize, Serialize};

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
    pub airglow: AirglowParams,
    pub terrain: Terrain,
    pub animation: AnimationParams,
    pub atmosphere: AtmosphereParams,
    pub earth: EarthParams,
    /// Where and when the scene is (`[site]`, `super::site`): none is the
    /// local frame with no place or hour (and writes no table).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub site: Option<SiteParams>,
    /// The oval's activity (`[oval]`, `super::oval`): none leaves the
    /// curtains where their keys put them (and writes no table).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub oval: Option<OvalParams>,
    /// The overrides applied to the file, in order, as `KEY=VALUE`
    /// (`crate::scene::overrides`; recorded in bake.json). Not part of the
    /// TOML: the values above already hold them, so the hash and the bake
    /// identity follow the effective scene.
    #[serde(skip)]
    pub overrides: Vec<String>,
}

/// Keys added with a default of 0 (or false) that means "off", left out of
/// [`Scene::hash`] and of the bake identity (`crate::pipeline::bake::identity`) while
/// off: a scene that does not set them keeps the hash it had before they
/// existed, and its bake is the same.
pub const OFF_WHEN_ZERO: &[&str] = &["animation.trail_samples", "grid.velocity", "render.shutter_s"];

impl Scene {
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
            for off in ["0", "0.0", "false"] {
                let line = format!("{name} = {off}\n");
                if let Some(start) = text.find(&format!("[{table}]\n")) {
                    let end = text[start + 1..].find("\n[").map_or(text.len(), |e| start + 1 + e);
                    if let Some(i) = text[start..end].find(&line).map(|i| start + i) {
                        if text[..i].ends_with('\n') {
                            text.replace_range(i..i + line.len(), "");
                        }
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

/// Every key of the top level: name, unit, allowed range and description (`super::keys`).
pub const ROOT_KEYS: &[KeySpec] =
    &[KeySpec::new("seed", "", Range::Any, "master seed: every random stream is derived from it and an index")];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Projection;
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
        // The same for `grid.velocity = false` and `render.shutter_s = 0.0`.
        let s = Scene::default();
        let lines = ["\ntrail_samples = 0\n", "\nvelocity = false\n", "\nshutter_s = 0.0\n"];
        let mut before = s.to_toml();
        for l in lines {
            assert!(before.contains(l), "{l}");
            before = before.replacen(l, "\n", 1);
        }
        assert_eq!(s.hash(), fnv1a(before.as_bytes()));
        let mut t = s.clone();
        t.animation.trail_samples = 4;
        assert_ne!(t.hash(), s.hash());
        let mut t = s.clone();
        t.grid.velocity = true;
        assert_ne!(t.hash(), s.hash());
        let mut t = s.clone();
        t.render.shutter_s = 0.5;
        assert_ne!(t.hash(), s.hash());
        // Read back, the TOML without the line is the same scene.
        let back = Scene::from_toml_str(&s.to_toml().replace("\ntrail_samples = 0\n", "\n"), "t.toml").unwrap();
        assert_eq!(back, s);
    }
}
