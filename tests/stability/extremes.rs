//! No NaN or infinity reaches a file or an image under any parameters the
//! scene file accepts: a property-style sweep that bakes and renders a tiny
//! scene at the extremes of every accepted range (one parameter at a time,
//! then a few combinations of the worst), and checks every voxel and pixel.
//!
//! The cases are `tests/data/extremes.toml`, each a few keys set over
//! [`base`]'s scene file. Each must be accepted by validation (through
//! TOML, as a scene file would give it). Its bake and render then either succeed with finite,
//! non-negative values everywhere (grids, image, the numbers of bake.json)
//! and a VDB the writer accepts, or fail with a typed error naming the
//! problem; a handful of cases are *expected* to fail that way (listed with
//! the reason) and must not succeed silently, and values just beyond the
//! accepted ranges where a float would overflow are refused by validation.

use crate::common::small::coarse;
use aurora::io::vdb::write::{write_vdb_bytes, GridRef, VdbWriteError};
use aurora::pipeline::bake::bake;
use aurora::render::{render, Integration, RenderSettings, Volume};
use aurora::scene::{Curtain, Scene, TerrainKind};
use aurora::util::progress::NoProgress;
use serde_json::Value;

/// One 8 km curtain seen from 60 km away, 20 beams, coarse voxels, an
/// 8 x 6 image with terrain and shadow rays.
fn base() -> Scene {
    // The footprint table's own keys, not the default preset's art.
    let s = Scene {
        seed: 11,
        curtains: vec![Curtain { length: 8.0, width: 4.0, bend_km: 1.0, ..Curtain::default() }],
        footprint: aurora::scene::FootprintParams::default(),
        ..Scene::default()
    };
    let mut s = coarse(s, [32, 16], 20);
    s.footprint.steps = 4;
    s.footprint.pressure_iterations = 10;
    s.camera.position = [0.0, -60.0, 1.5];
    s.camera.look_at = [0.0, 0.0, 120.0];
    s.camera.fov_deg = 70.0;
    s.render.width = 8;
    s.render.height = 6;
    s.render.spp = 2;
    s.terrain.kind = TerrainKind::Heightfield;
    s.terrain.extent = [-40.0, -70.0, 40.0, 20.0];
    s
}

/// `base` with `patch` laid over it key by key; a `curtain` table in the
/// patch applies to the scene's one `[[curtain]]`.
fn overlay(base: &mut toml::Table, patch: toml::Table) {
    for (k, v) in patch {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Array(a)), toml::Value::Table(t)) if k == "curtain" => {
                overlay(a[0].as_table_mut().expect("a [[curtain]] table"), t)
            }
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => overlay(b, t),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// What a case must do.
#[derive(Clone, PartialEq, Debug)]
enum Expect {
    /// Bake, write and render with finite values everywhere.
    Finite,
    /// Values beyond the half-float range in half mode: baked with a
    /// warning naming `grid.half_emission`, and written as full floats
    /// (`aurora::io::bake_folder::fit_half`; the writer itself refuses half
    /// storage of such values, a safety net).
    HalfOverflow,
    /// Fail with a typed bake error (e.g. an empty footprint).
    BakeError,
    /// Refused by validation, naming this key.
    Refused(String),
}

use Expect::*;

/// The cases (`tests/data/extremes.toml`): each one's name, the keys it
/// sets over [`base`], and what it must do.
fn cases() -> Vec<(String, toml::Table, Expect)> {
    let doc: toml::Table = include_str!("../data/extremes.toml").parse().expect("tests/data/extremes.toml parses");
    let cases = doc["case"].as_array().expect("[[case]] tables");
    cases
        .iter()
        .map(|c| {
            let name = c["name"].as_str().expect("a case's name").to_string();
            let set = c["set"].as_table().cloned().unwrap_or_else(|| panic!("{name}: no `set` table"));
            let expect = match (c.get("expect").and_then(|e| e.as_str()), c.get("refused").and_then(|r| r.as_str())) {
                (Some("finite"), None) => Finite,
                (Some("half-overflow"), None) => HalfOverflow,
                (Some("bake-error"), None) => BakeError,
                (None, Some(key)) => Refused(key.to_string()),
                other => panic!("{name}: `expect` is finite, half-overflow or bake-error, or `refused` a key: {other:?}"),
            };
            (name, set, expect)
        })
        .collect()
}

/// Every number in a JSON value is finite (serde_json writes NaN and
/// infinity as null): no null outside the keys that may be absent.
fn no_null_numbers(v: &Value, path: &str, bad: &mut Vec<String>) {
    match v {
        Value::Null if !["index_bbox", "world_bbox", "stats.noise", "stats.prune"].iter().any(|k| path.ends_with(k)) => {
            bad.push(path.to_string())
        }
        Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| no_null_numbers(x, &format!("{path}[{i}]"), bad)),
        Value::Object(o) => o.iter().for_each(|(k, x)| no_null_numbers(x, &format!("{path}.{k}"), bad)),
        _ => {}
    }
}

/// Runs one case; Err describes what went wrong.
fn check(name: &str, scene: &Scene, expect: &Expect) -> Result<(), String> {
    let baked = match bake(scene, &NoProgress) {
        Ok(b) => b,
        Err(e) if *expect == BakeError => {
            let m = e.to_string();
            return if m.is_empty() { Err("empty error message".into()) } else { Ok(()) };
        }
        // A bake whose grids come out empty (a kernel too small for any voxel
        // centre, an energy flux whose emission underflows f32, beams that
        // leave before depositing) is an error naming how its beams ended
        // (empty results are loud), never an empty file.
        Err(e @ aurora::pipeline::bake::BakeError::Empty(_)) => {
            let m = e.to_string();
            return if m.contains("beams made") { Ok(()) } else { Err(format!("unclear message: {m}")) };
        }
        Err(e) => return Err(format!("bake failed: {e}")),
    };
    if *expect == BakeError {
        return Err("expected a bake error, the bake succeeded".into());
    }
    if let Some((ijk, v)) = baked.emission.first_non_finite() {
        return Err(format!("emission {ijk}: {v:?}"));
    }
    if let Some((ijk, v)) = baked.density.first_non_finite() {
        return Err(format!("density {ijk}: {v}"));
    }
    if let Some((ijk, v)) = baked.emission.iter_active().find(|(_, v)| v.iter().any(|x| *x < 0.0)) {
        return Err(format!("negative emission {ijk}: {v:?}"));
    }
    if let Some((ijk, v)) = baked.density.iter_active().find(|(_, v)| *v < 0.0) {
        return Err(format!("negative density {ijk}: {v}"));
    }
    let mut bad = Vec::new();
    no_null_numbers(&serde_json::to_value(&baked.stats).map_err(|e| e.to_string())?, "stats", &mut bad);
    if !bad.is_empty() {
        return Err(format!("non-finite numbers in bake stats: {bad:?}"));
    }
    let half_warned = baked.stats.warnings.iter().any(|w| w.contains("grid.half_emission") && w.contains("full floats"));
    if (*expect == HalfOverflow) != half_warned {
        return Err(format!("half-range warning {half_warned}, expected {}: {:?}", *expect == HalfOverflow, baked.stats.warnings));
    }
    // The file the bake would write (in memory): half floats where they fit.
    let grids = [GridRef::Float(&baked.density), GridRef::Vec3(&baked.emission)];
    let (opts, full) = aurora::io::bake_folder::fit_half(aurora::io::bake_folder::write_options(scene), &grids);
    if *expect == HalfOverflow && !full.contains(&"emission".to_string()) {
        return Err(format!("the emission beyond half range is not stored as full floats: {full:?}"));
    }
    match write_vdb_bytes(&grids, &opts) {
        Ok(_) => {}
        Err(e @ VdbWriteError::HalfOverflow { .. }) => return Err(format!("the writer refused half storage fit_half let through: {e}")),
        Err(e) => return Err(format!("vdb write: {e}")),
    }
    let mut settings = RenderSettings::from_scene(scene);
    settings.render.shadow_samples = 2;
    for integration in [Integration::Exact, Integration::FixedStep(0.7)] {
        settings.integration = integration;
        let vol = Volume { density: Some(&baked.density), emission: Some(&baked.emission) };
        let img = render(&settings, &vol, &NoProgress).map_err(|e| format!("render {integration:?}: {e}"))?;
        for (i, p) in img.pixels.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite() || *x < 0.0) || p[3] > 1.0 {
                return Err(format!("{integration:?}: pixel {i} = {p:?}"));
            }
        }
    }
    let _ = name;
    Ok(())
}

#[test]
fn every_accepted_extreme_bakes_and_renders_finite() {
    let mut failures = Vec::new();
    let base: toml::Table = base().to_toml().parse().expect("the base scene's TOML");
    for (name, set, expect) in cases() {
        let name = name.as_str();
        // Accepted as a scene file would give it: the base scene's file
        // with the case's keys set.
        let mut t = base.clone();
        overlay(&mut t, set);
        let text = toml::to_string(&t).expect("the scene prints");
        let parsed = match (Scene::from_toml_str(&text, name), &expect) {
            (Ok(_), Refused(key)) => {
                failures.push(format!("{name}: {key} accepted by validation"));
                continue;
            }
            (Err(e), Refused(key)) => {
                let m = e.to_string();
                if !m.contains(&format!("{key} = ")) || !m.contains("out of range") {
                    failures.push(format!("{name}: the refusal does not name {key}: {m}"));
                }
                continue;
            }
            (Ok(p), _) => p,
            (Err(e), _) => {
                failures.push(format!("{name}: not accepted by validation: {e}"));
                continue;
            }
        };
        let t = std::time::Instant::now();
        if let Err(e) = check(name, &parsed, &expect) {
            failures.push(format!("{name}: {e}"));
        }
        eprintln!("{name}: {:.2} s", t.elapsed().as_secs_f64());
    }
    assert!(failures.is_empty(), "{} case(s) failed:\n{}", failures.len(), failures.join("\n"));
}
