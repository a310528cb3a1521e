//! The identity of a bake: what its output is a function of. A frame of a
//! sequence folder counts as complete for a rerun only when its report
//! (`aurora.NNNN.json`, key `bake_identity`) names the identity of the bake
//! asked for (`crate::farm::sequence_folder`); a single bake's `bake.json` records it too.
//!
//! It has two parts, each a 64-bit FNV-1a hash in hex:
//!
//! - **`scene`**: the validated scene (after `--seed`), serialised
//!   canonically (serde's JSON of the [`Scene`] struct: keys sorted, numbers
//!   in their shortest round-trip form, so comments, key order and `1` vs
//!   `1.0` in the TOML do not matter) with the keys the bake never reads
//!   removed ([`RENDER_ONLY`]; every other key is in, so a key added later
//!   counts until someone shows the bake does not read it). The camera and
//!   `render.width` / `render.height` stay in: pruning weighs leaves by
//!   their light in the camera's image and `grid.voxel_size = "auto"`
//!   follows the camera's pixel size. `[animation]` stays in: frame N is
//!   baked at `time_s + (N - 1) / fps`.
//! - **`build`**: [`BUILD`], a hash of the crate's source, data and
//!   manifests made by `build.rs` (the version, 0.1.0 on every commit,
//!   cannot tell builds apart).
//!
//! **Files.** The compiled-in atmosphere (`data/us1976.csv`, `include_str!`)
//! is covered by `build`; the tables a scene reads from the data folder
//! (`nrlmsis21.csv`, `ionosphere.csv`: `crate::physics::data_files`) add
//! their bytes' hash to `scene`; the heightmap and the sky image are read
//! by the renderer only (their keys are render-only below). A file the bake
//! comes to read must add its bytes' hash here.
//!
//! The identity is kept in the JSON report only, never in the VDB (whose
//! bytes are pinned): a frame kept across a render-only edit still carries
//! the old scene's `aurora_scene_hash` metadata, the hash of every key.

use crate::scene::{fnv1a, Scene};
use serde::{Deserialize, Serialize};

/// The scene keys no stage of the bake reads, each with the reason; they
/// are left out of the identity's `scene` hash. `render.width` and
/// `render.height` are not here (pruning and the automatic voxel size read
/// them), nor is any key of `[camera]`.
pub const RENDER_ONLY: &[(&str, &str)] = &[
    ("render.spp", "samples per pixel of the reference renderer; the bake traces no pixel"),
    ("render.shadow_samples", "the reference renderer's shadow rays per terrain hit; the bake lights no terrain"),
    ("render.exposure", "the PNG preview's exposure, a tone map of the rendered image"),
    ("render.shutter_s", "the reference renderer's motion blur, read from the velocity grid at lookup"),
    ("render.view_transform", "the PNG preview's view transform, a tone map of the rendered image"),
    ("colour.white_balance_k", "the camera's white balance, applied to the rendered image before the PNG's exposure"),
    ("render.png_bits", "the PNG's bits per channel, an encoding of the rendered image"),
    ("volume", "density_scale and emission_scale are applied by the renderer at lookup; the files hold the unscaled grids"),
    ("background", "radiance, image and stars are seen by camera rays only; the bake never reads the image"),
    ("airglow", "the night sky's own light is drawn by the renderer behind the volume; the bake never reads it"),
    ("sky", "the air between the volume and the camera is applied by the renderer; the files hold the emission above it"),
    ("terrain", "the ground is traced by the renderer only; the bake neither reads the heightmap nor shades or occludes with it"),
];

/// The build part of the identity: `build.rs`'s hash of the source.
pub const BUILD: &str = env!("AURORA_BUILD_HASH");

/// See the module docs.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BakeIdentity {
    /// Hash of the scene's bake keys.
    pub scene: String,
    /// Hash of the build's source ([`BUILD`]).
    pub build: String,
}

impl BakeIdentity {
    /// The identity of baking `scene` (validated) with this build.
    pub fn of(scene: &Scene) -> BakeIdentity {
        // The tables read from the data folder count with their bytes.
        let keys = bake_keys_json(scene) + &crate::physics::data_files::identity(&scene.atmosphere);
        BakeIdentity { scene: format!("{:016x}", fnv1a(keys.as_bytes())), build: BUILD.to_string() }
    }

    /// The identity a report names (its `bake_identity`), if any.
    pub fn from_report(report: &serde_json::Value) -> Option<BakeIdentity> {
        serde_json::from_value(report.get("bake_identity")?.clone()).ok()
    }

    /// As it goes into a report.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("two strings serialise")
    }

    /// What differs between a report's identity `other` and this one, in
    /// words for an error message.
    pub fn difference(&self, other: &BakeIdentity) -> &'static str {
        match (self.scene == other.scene, self.build == other.build) {
            (false, false) => "another scene (keys that change the bake differ) and another build of aurora",
            (false, true) => "another scene: keys that change the bake differ (a render-only key such as render.exposure does not count)",
            (true, false) => "another build of aurora (its source differs)",
            (true, true) => "the same bake",
        }
    }
}

/// The canonical JSON of `scene` without the [`RENDER_ONLY`] keys.
pub fn bake_keys_json(scene: &Scene) -> String {
    let mut v = serde_json::to_value(scene).expect("a scene always serialises");
    for (key, _) in RENDER_ONLY {
        remove_key(&mut v, key);
    }
    for key in crate::scene::OFF_WHEN_ZERO {
        if lookup(&v, key).is_some_and(|x| x.as_u64() == Some(0) || x.as_f64() == Some(0.0) || x.as_bool() == Some(false)) {
            remove_key(&mut v, key);
        }
    }
    serde_json::to_string(&v).expect("JSON serialises")
}

/// The value at the dotted `key` of `v`.
fn lookup<'a>(v: &'a serde_json::Value, key: &str) -> Option<&'a serde_json::Value> {
    key.split('.').try_fold(v, |v, k| v.get(k))
}

/// Removes the dotted `key` from `v`; true if it was there.
fn remove_key(v: &mut serde_json::Value, key: &str) -> bool {
    match key.split_once('.') {
        Some((head, rest)) => v.get_mut(head).is_some_and(|t| remove_key(t, rest)),
        None => v.as_object_mut().is_some_and(|m| m.remove(key).is_some()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

    /// Every leaf of `v` (numbers, strings, booleans, nulls), by path.
    fn leaves(v: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    path.push(k.clone());
                    leaves(x, path, out);
                    path.pop();
                }
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    path.push(i.to_string());
                    leaves(x, path, out);
                    path.pop();
                }
            }
            _ => out.push(path.clone()),
        }
    }

    fn at<'a>(v: &'a mut Value, path: &[String]) -> &'a mut Value {
        path.iter().fold(v, |v, k| match v {
            Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
            other => &mut other[k.as_str()],
        })
    }

    /// Every value a string leaf of the scene may take (enum names), and a
    /// path for an absent one.
    const STRINGS: &[&str] = &[
        "fluid2014",
        "accelerated",
        "maxwellian",
        "sampled",
        "csda",
        "random",
        "colormap",
        "physical",
        "simple",
        "kdtree",
        "report2014",
        "point",
        "none",
        "zip",
        "auto",
        "orthographic",
        "fisheye",
        "plane",
        "heightfield",
        "us1976",
        "standard",
        "nrlmsis21",
        "glow",
        "x.png",
        "eye",
    ];

    /// The scenes that differ from `base` in the leaf at `path` alone.
    fn perturbed(base: &Value, path: &[String]) -> Vec<Scene> {
        let old = {
            let mut b = base.clone();
            at(&mut b, path).clone()
        };
        let candidates: Vec<Value> = match &old {
            Value::Bool(b) => vec![Value::Bool(!b)],
            Value::Number(n) if n.is_u64() => vec![Value::from(n.as_u64().unwrap() + 1)],
            Value::Number(n) => vec![Value::from(n.as_f64().unwrap() * 1.5 + 0.25)],
            Value::String(_) | Value::Null => STRINGS.iter().map(|s| Value::from(*s)).collect(),
            _ => unreachable!(),
        };
        let base_scene: Scene = serde_json::from_value(base.clone()).unwrap();
        candidates
            .into_iter()
            .filter_map(|c| {
                let mut v = base.clone();
                *at(&mut v, path) = c;
                serde_json::from_value::<Scene>(v).ok().filter(|s| *s != base_scene)
            })
            .collect()
    }

    /// A scene with every optional part present (two curtains, a heightmap,
    /// a sky image, the trail, a magnetic pole), so every key has a leaf.
    fn full_scene() -> Scene {
        let mut s = Scene::default();
        s.curtains.push(s.curtains[0].clone());
        s.terrain.heightmap = Some("h.png".into());
        s.background.image = Some("sky.exr".into());
        s.animation.trail_samples = 4;
        s.earth.magnetic_pole = Some([0.0, 2200.0]);
        s
    }

    /// Changing any one leaf of the scene changes the identity exactly when
    /// the leaf is not under a [`RENDER_ONLY`] key; and the identity is
    /// exactly what `aurora preview` keeps its bake for: an edit that
    /// leaves the identity alone starts at the render (or later), any other
    /// edit before it (`preview::stage_for_edit`, an independent account of
    /// which stage reads which key).
    #[test]
    fn every_key_but_the_render_only_ones_changes_the_identity() {
        use crate::app::preview::{stage_for_edit, Stage};
        let base_scene = full_scene();
        let base = serde_json::to_value(&base_scene).unwrap();
        let id = BakeIdentity::of(&base_scene);
        let mut all = Vec::new();
        leaves(&base, &mut Vec::new(), &mut all);
        let (mut kept, mut changed) = (0, 0);
        for path in &all {
            let dotted = path.join(".");
            let render_only = RENDER_ONLY.iter().any(|(k, _)| dotted == *k || dotted.starts_with(&format!("{k}.")));
            let scenes = perturbed(&base, path);
            assert!(!scenes.is_empty(), "{dotted}: no other value tried");
            for s in scenes {
                let same = BakeIdentity::of(&s) == id;
                assert_eq!(
                    same,
                    render_only,
                    "{dotted}: identity {} but the key is {}",
                    if same { "kept" } else { "changed" },
                    if render_only { "render-only" } else { "a bake key" }
                );
                let stage = stage_for_edit(&base_scene, &s);
                assert_eq!(stage <= Stage::Render, same, "{dotted}: preview stage {stage:?}");
                if same {
                    kept += 1
                } else {
                    changed += 1
                }
            }
        }
        // The default scene has over a hundred leaves; a dozen are render-only.
        assert!(changed > 100 && kept >= 10, "{changed} changed, {kept} kept");
    }

    #[test]
    fn every_render_only_key_names_a_key_of_the_scene() {
        let mut v = serde_json::to_value(full_scene()).unwrap();
        for (k, why) in RENDER_ONLY {
            assert!(remove_key(&mut v, k), "{k} is not a scene key");
            assert!(!why.is_empty());
        }
        let text = serde_json::to_string(&v).unwrap();
        assert!(text.contains("\"width\":640") && text.contains("\"camera\""), "{text}");
    }

    #[test]
    fn the_toml_spelling_does_not_matter_and_reports_round_trip() {
        let a = Scene::from_toml_str("seed = 3\n[grid]\nvoxel_size = 1\n", "a").unwrap();
        let b = Scene::from_toml_str("# a comment\n[grid]\nvoxel_size = 1.0\n\n[render]\nexposure = 5.0\n\nseed = 3\n", "b");
        // `seed` after a table belongs to the table: refused, as it should be.
        assert!(b.is_err());
        let b = Scene::from_toml_str("seed = 3 # the seed\n[render]\nexposure = 5.0\n[grid]\nvoxel_size = 1.0\n", "b").unwrap();
        assert_eq!(BakeIdentity::of(&a), BakeIdentity::of(&b));
        let id = BakeIdentity::of(&a);
        assert_eq!(id.build, BUILD);
        assert_eq!(id.scene.len(), 16);
        let report = serde_json::json!({ "bake_identity": id.to_json() });
        assert_eq!(BakeIdentity::from_report(&report), Some(id.clone()));
        assert_eq!(BakeIdentity::from_report(&serde_json::json!({})), None);
        let mut c = a.clone();
        c.seed = 4;
        assert_ne!(BakeIdentity::of(&c), id);
    }
}
