//! No NaN or infinity reaches a file or an image under any parameters the
//! scene file accepts: a property-style sweep that bakes and renders a tiny
//! scene at the extremes of every accepted range (one parameter at a time,
//! then a few combinations of the worst), and checks every voxel and pixel.
//!
//! Each case must be accepted by validation (through TOML, as a scene file
//! would give it). Its bake and render then either succeed with finite,
//! non-negative values everywhere (grids, image, the numbers of bake.json)
//! and a VDB the writer accepts, or fail with a typed error naming the
//! problem; a handful of cases are *expected* to fail that way (listed with
//! the reason) and must not succeed silently, and values just beyond the
//! accepted ranges where a float would overflow are refused by validation.

use aurora::io::vdb::write::{write_vdb_bytes, GridRef, VdbWriteError};
use aurora::pipeline::bake::bake;
use aurora::render::{render, Integration, RenderSettings, Volume};
use aurora::scene::{ColourMode, Curtain, GatherMethod, Projection, Scene, TerrainKind, VoxelSize};
use aurora::util::progress::NoProgress;
use serde_json::Value;

/// One 8 km curtain seen from 60 km away, 20 beams, coarse voxels, an
/// 8 x 6 image with terrain and shadow rays.
fn base() -> Scene {
    let mut s =
        Scene { seed: 11, curtains: vec![Curtain { length: 8.0, width: 4.0, bend_km: 1.0, ..Curtain::default() }], ..Scene::default() };
    s.footprint.resolution = [32, 16];
    s.footprint.steps = 4;
    s.footprint.pressure_iterations = 10;
    s.beams.count = 20;
    s.photons.radius_km = 1.0;
    s.grid.voxel_size = VoxelSize::Km(1.0);
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

/// The (only) curtain of the base scene.
fn c(s: &mut Scene) -> &mut Curtain {
    &mut s.curtains[0]
}

/// What a case must do.
#[derive(Clone, Copy, PartialEq, Debug)]
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
    Refused(&'static str),
}

type Case = (&'static str, Box<dyn Fn(&mut Scene)>, Expect);

fn cases() -> Vec<Case> {
    use Expect::*;
    let v: Vec<Case> = vec![
        // curtain
        (
            "curtain.length tiny",
            Box::new(|s| {
                c(s).length = 1e-3;
                c(s).width = 1e-3;
                c(s).bend_km = 0.0;
            }),
            Finite,
        ),
        (
            "curtain.length large",
            Box::new(|s| {
                c(s).length = 2000.0;
                c(s).width = 400.0;
                s.grid.voxel_size = VoxelSize::Km(5.0);
                s.photons.radius_km = 5.0;
            }),
            Finite,
        ),
        (
            "curtain largest accepted, all power in one beam",
            Box::new(|s| {
                c(s).length = 1e4;
                c(s).width = 1e4;
                c(s).energy_flux = 1e4;
                s.beams.count = 1;
                s.grid.voxel_size = VoxelSize::Km(20.0);
                s.photons.radius_km = 20.0;
            }),
            // One beam carrying a 10^4 km curtain's power: beyond the half
            // range, so the (default) half-float emission falls back.
            HalfOverflow,
        ),
        // Photon power (f32) would overflow for one beam over such an area.
        (
            "curtain astronomically large",
            Box::new(|s| {
                c(s).length = 1e15;
                c(s).width = 1e14;
                s.grid.voxel_size = VoxelSize::Km(1e13);
            }),
            Refused("curtain[0].length"),
        ),
        ("curtain.energy_flux tiny", Box::new(|s| c(s).energy_flux = 1e-300), Finite),
        ("curtain.energy_flux max", Box::new(|s| c(s).energy_flux = 1e4), Finite),
        ("curtain.char_energy_kev min", Box::new(|s| c(s).char_energy_kev = 0.05), Finite),
        ("curtain.char_energy_kev max", Box::new(|s| c(s).char_energy_kev = 100.0), Finite),
        (
            "curtain.soft_fraction 1, soft_energy min",
            Box::new(|s| {
                c(s).soft_fraction = 1.0;
                c(s).soft_energy_kev = 0.01;
            }),
            Finite,
        ),
        ("curtain.soft_fraction 0", Box::new(|s| c(s).soft_fraction = 0.0), Finite),
        ("curtain.beam_weight tiny", Box::new(|s| c(s).beam_weight = 1e-300), Finite),
        (
            "curtain.rotation and centre far",
            Box::new(|s| {
                c(s).rotation_deg = 1e9;
                c(s).center = [1e4, -1e4];
            }),
            Finite,
        ),
        ("curtain.bend_km 0", Box::new(|s| c(s).bend_km = 0.0), Finite),
        // footprint
        ("footprint.resolution min", Box::new(|s| s.footprint.resolution = [8, 8]), Finite),
        (
            "footprint.steps 0, no pressure iterations",
            Box::new(|s| {
                s.footprint.steps = 0;
                s.footprint.pressure_iterations = 0;
            }),
            Finite,
        ),
        // Far past the CFL limit (dt = 1e6 cells per unit velocity, or a
        // velocity of 1e6 cells per unit time): the semi-Lagrangian step
        // stays bounded (src/pipeline/footprint/fluid.rs tests) but carries the band out of
        // the footprint, so no cell is left above threshold: a clear error.
        ("footprint.dt max", Box::new(|s| s.footprint.dt = 1e6), BakeError),
        ("footprint.velocity_amplitude max", Box::new(|s| s.footprint.velocity_amplitude = 1e6), BakeError),
        ("footprint.dt large but stable", Box::new(|s| s.footprint.dt = 50.0), Finite),
        (
            "footprint.waves max",
            Box::new(|s| {
                s.footprint.velocity_waves = 1e3;
                s.footprint.density_waves = 1e3;
            }),
            Finite,
        ),
        ("footprint.band_fraction 1", Box::new(|s| s.footprint.band_fraction = 1.0), Finite),
        ("footprint.band_fraction tiny", Box::new(|s| s.footprint.band_fraction = 1e-9), Finite),
        ("footprint.bend_wavelength tiny", Box::new(|s| s.footprint.bend_wavelength = 1e-9), Finite),
        ("footprint.threshold tiny", Box::new(|s| s.footprint.threshold = 1e-300), Finite),
        // Nothing exceeds the peak of 1: no cell above threshold.
        ("footprint.threshold 1", Box::new(|s| s.footprint.threshold = 1.0), BakeError),
        // beams
        ("beams.count 1", Box::new(|s| s.beams.count = 1), Finite),
        ("beams.top_km min", Box::new(|s| s.beams.top_km = 80.0), Finite),
        ("beams.top_km max", Box::new(|s| s.beams.top_km = 1000.0), Finite),
        (
            "beams.top_noise max",
            Box::new(|s| {
                s.beams.top_noise_km = 100.0;
                s.beams.top_noise_freq = 1e3;
            }),
            Finite,
        ),
        (
            "beams.alpha_d_deg just below 90",
            Box::new(|s| {
                s.beams.alpha_d_deg = 89.999;
                s.beams.delta_alpha_deg = 89.999;
            }),
            Finite,
        ),
        (
            "beams.alpha_d_deg 0",
            Box::new(|s| {
                s.beams.alpha_d_deg = 0.0;
                s.beams.delta_alpha_deg = 0.0;
            }),
            Finite,
        ),
        ("beams.length_km tiny", Box::new(|s| s.beams.length_km = 1e-9), Finite),
        ("beams.length_km huge", Box::new(|s| s.beams.length_km = 1e9), Finite),
        (
            "beams.dt min (1e6 steps)",
            Box::new(|s| {
                s.beams.dt = 1e-6;
                s.beams.count = 2;
            }),
            Finite,
        ),
        ("beams.dt 1 (one step)", Box::new(|s| s.beams.dt = 1.0), Finite),
        (
            "beams.b_inclination_deg min",
            Box::new(|s| {
                s.beams.b_inclination_deg = 10.0;
                s.grid.voxel_size = VoxelSize::Km(8.0);
                s.photons.radius_km = 8.0;
            }),
            Finite,
        ),
        ("beams.b_inclination_deg 90", Box::new(|s| s.beams.b_inclination_deg = 90.0), Finite),
        ("beams.b_declination_deg huge", Box::new(|s| s.beams.b_declination_deg = -1e9), Finite),
        // colour
        (
            "colour.noise max",
            Box::new(|s| {
                s.colour.noise_km = 200.0;
                s.colour.noise_freq = 1e3;
            }),
            Finite,
        ),
        (
            "colour.colormap extreme",
            Box::new(|s| {
                s.colour.mode = ColourMode::Colormap;
                s.colour.colormap = vec![[-1e6, 0.0, 0.0, 0.0], [1e6, 1e6, 0.0, 1e-300]];
            }),
            Finite,
        ),
        // photons
        (
            "photons.radius_km small",
            Box::new(|s| {
                s.photons.radius_km = 1e-3;
                s.photons.radius_noise = 0.0;
            }),
            Finite,
        ),
        (
            "photons.radius_km 1e-12, max power",
            Box::new(|s| {
                s.photons.radius_km = 1e-12;
                s.photons.radius_noise = 0.0;
                c(s).energy_flux = 1e4;
                s.beams.count = 1;
            }),
            Finite,
        ),
        (
            "photons.radius_km 1e-300",
            Box::new(|s| {
                s.photons.radius_km = 1e-300;
                s.photons.radius_noise = 0.0;
            }),
            Finite,
        ),
        (
            "photons.radius_km large",
            Box::new(|s| {
                s.photons.radius_km = 40.0;
                s.grid.voxel_size = VoxelSize::Km(10.0);
            }),
            Finite,
        ),
        ("photons.cutoff min", Box::new(|s| s.photons.cutoff = 1.0), Finite),
        ("photons.cutoff max", Box::new(|s| s.photons.cutoff = 6.0), Finite),
        (
            "photons.radius_noise max",
            Box::new(|s| {
                s.photons.radius_noise = 0.9;
                s.photons.radius_noise_freq = 1e3;
            }),
            Finite,
        ),
        (
            "photons.gather splat, small radius",
            Box::new(|s| {
                s.photons.gather = GatherMethod::Splat;
                s.photons.radius_km = 1e-3;
            }),
            Finite,
        ),
        (
            "photons.gather report2014, small radius",
            Box::new(|s| {
                s.photons.gather = GatherMethod::Report2014;
                s.photons.radius_km = 1e-3;
            }),
            Finite,
        ),
        ("grid.voxel_size auto", Box::new(|s| s.grid.voxel_size = VoxelSize::Auto(aurora::scene::AutoTag::Auto)), Finite),
        ("grid.voxel_size huge", Box::new(|s| s.grid.voxel_size = VoxelSize::Km(1e4)), Finite),
        // grid: air density
        (
            "grid.density zero",
            Box::new(|s| {
                s.grid.density_a = 0.0;
                s.grid.density_b = 0.0;
            }),
            Finite,
        ),
        ("grid.density_a max", Box::new(|s| s.grid.density_a = 1e6), Finite),
        (
            "grid.density_b max, base high",
            Box::new(|s| {
                s.grid.density_b = 10.0;
                s.grid.density_base_km = 1e6;
            }),
            Finite,
        ),
        (
            "grid.density_b max, base low",
            Box::new(|s| {
                s.grid.density_b = 10.0;
                s.grid.density_base_km = -1e6;
            }),
            Finite,
        ),
        ("grid.half_emission, ordinary values", Box::new(|s| s.grid.half_emission = true), Finite),
        // camera and image
        ("camera.fov tiny", Box::new(|s| s.camera.fov_deg = 1e-9), Finite),
        ("camera.fov just below 180", Box::new(|s| s.camera.fov_deg = 179.999), Finite),
        ("camera.fov 180", Box::new(|s| s.camera.fov_deg = 180.0), Refused("camera.fov_deg")),
        (
            "camera far away",
            Box::new(|s| {
                s.camera.position = [0.0, -1e9, 1.5];
            }),
            Finite,
        ),
        (
            "camera orthographic tiny",
            Box::new(|s| {
                s.camera.projection = Projection::Orthographic;
                s.camera.ortho_height = 1e-9;
            }),
            Finite,
        ),
        (
            "camera orthographic huge",
            Box::new(|s| {
                s.camera.projection = Projection::Orthographic;
                s.camera.ortho_height = 1e9;
            }),
            Finite,
        ),
        (
            "render 1x1, spp 1",
            Box::new(|s| {
                s.render.width = 1;
                s.render.height = 1;
                s.render.spp = 1;
            }),
            Finite,
        ),
        ("render.exposure extremes", Box::new(|s| s.render.exposure = -50.0), Finite),
        // volume, background, terrain
        (
            "volume.scales 0",
            Box::new(|s| {
                s.volume.density_scale = 0.0;
                s.volume.emission_scale = 0.0;
            }),
            Finite,
        ),
        (
            "volume.scales max",
            Box::new(|s| {
                s.volume.density_scale = 1e9;
                s.volume.emission_scale = 1e9;
            }),
            Finite,
        ),
        (
            "volume.emission_scale max, thin",
            Box::new(|s| {
                s.volume.density_scale = 0.0;
                s.volume.emission_scale = 1e9;
            }),
            Finite,
        ),
        ("background.radiance max", Box::new(|s| s.background.radiance = [1e9, 0.0, 1e-300]), Finite),
        ("background.radiance beyond f32", Box::new(|s| s.background.radiance = [1e300, 0.0, 0.0]), Refused("background.radiance")),
        (
            "terrain plane high above",
            Box::new(|s| {
                s.terrain.kind = TerrainKind::Plane;
                s.terrain.height = 1e6;
            }),
            Finite,
        ),
        (
            "terrain heightfield extremes",
            Box::new(|s| {
                s.terrain.mountain_height = 100.0;
                s.terrain.mountain_scale = 1e-9;
                s.terrain.albedo = [1.0, 0.0, 1.0];
            }),
            Finite,
        ),
        ("terrain none", Box::new(|s| s.terrain.kind = TerrainKind::None), Finite),
        // combinations of the worst
        (
            "worst emission: max flux, one beam, small radius, max scales",
            Box::new(|s| {
                c(s).energy_flux = 1e4;
                s.beams.count = 1;
                s.photons.radius_km = 1e-3;
                s.photons.radius_noise = 0.0;
                s.volume.emission_scale = 1e9;
                s.volume.density_scale = 1e9;
                s.grid.density_a = 1e6;
            }),
            Finite,
        ),
        (
            "worst emission in half storage",
            Box::new(|s| {
                c(s).energy_flux = 1e4;
                s.beams.count = 40;
                s.photons.radius_km = 0.01;
                s.photons.radius_noise = 0.0;
                s.grid.voxel_size = VoxelSize::Km(0.2);
                s.grid.half_emission = true;
                // Point kernels: the segment kernel spreads a step's power
                // along it and stays in half range here.
                s.photons.kernel = aurora::scene::KernelShape::Point;
                s.seed = 3; // the CLI test's scene (stability_cli.rs): known to overflow
            }),
            HalfOverflow,
        ),
        (
            "steep beams at the horizon",
            Box::new(|s| {
                s.beams.alpha_d_deg = 89.999;
                s.beams.delta_alpha_deg = 0.0;
                s.beams.b_inclination_deg = 10.0;
                s.beams.length_km = 1e9;
                s.grid.voxel_size = VoxelSize::Km(8.0);
                s.photons.radius_km = 8.0;
            }),
            Finite,
        ),
    ];
    v
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
fn check(name: &str, scene: &Scene, expect: Expect) -> Result<(), String> {
    let baked = match bake(scene, &NoProgress) {
        Ok(b) => b,
        Err(e) if expect == Expect::BakeError => {
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
    if expect == Expect::BakeError {
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
    if (expect == Expect::HalfOverflow) != half_warned {
        return Err(format!("half-range warning {half_warned}, expected {}: {:?}", expect == Expect::HalfOverflow, baked.stats.warnings));
    }
    // The file the bake would write (in memory): half floats where they fit.
    let grids = [GridRef::Float(&baked.density), GridRef::Vec3(&baked.emission)];
    let (opts, full) = aurora::io::bake_folder::fit_half(aurora::io::bake_folder::write_options(scene), &grids);
    if expect == Expect::HalfOverflow && !full.contains(&"emission".to_string()) {
        return Err(format!("the emission beyond half range is not stored as full floats: {full:?}"));
    }
    match write_vdb_bytes(&grids, &opts) {
        Ok(_) => {}
        Err(e @ VdbWriteError::HalfOverflow { .. }) => return Err(format!("the writer refused half storage fit_half let through: {e}")),
        Err(e) => return Err(format!("vdb write: {e}")),
    }
    let mut settings = RenderSettings::from_scene(scene);
    settings.shadow_samples = 2;
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
    for (name, modify, expect) in cases() {
        let mut s = base();
        modify(&mut s);
        // Accepted as a scene file would give it.
        let text = s.to_toml();
        let parsed = match (Scene::from_toml_str(&text, name), expect) {
            (Ok(_), Expect::Refused(key)) => {
                failures.push(format!("{name}: {key} accepted by validation"));
                continue;
            }
            (Err(e), Expect::Refused(key)) => {
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
        if let Err(e) = check(name, &parsed, expect) {
            failures.push(format!("{name}: {e}"));
        }
        eprintln!("{name}: {:.2} s", t.elapsed().as_secs_f64());
    }
    assert!(failures.is_empty(), "{} case(s) failed:\n{}", failures.len(), failures.join("\n"));
}
