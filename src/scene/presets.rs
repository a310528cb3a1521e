//! Built-in scenes: `default` (three sheets, as in the report's final
//! image) and `seed2014` (the report's final scene parameters).
use super::*;

/// Names accepted by `aurora scene NAME` and as a scene argument.
pub const NAMES: &[&str] = &["default", "seed2014"];

pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "default" => Some(default_scene()),
        "seed2014" => Some(seed2014()),
        _ => None,
    }
}

/// The report's colour map (defined beside [`ColourParams`], whose default it is).
pub use super::types::report_colormap;

/// Three sheets one behind the other, seen from the ground to the south.
pub fn default_scene() -> Scene {
    let sheet = |cx: f64, cy: f64, rot: f64, flux: f64, e0: f64, seed: u64| Curtain {
        center: [cx, cy],
        rotation_deg: rot,
        energy_flux: flux,
        char_energy_kev: e0,
        seed,
        ..Curtain::default()
    };
    Scene {
        seed: 2014,
        curtains: vec![sheet(-20.0, 0.0, 4.0, 6.0, 4.0, 1), sheet(25.0, 45.0, -6.0, 4.0, 2.5, 2), sheet(-5.0, 95.0, 2.0, 3.0, 1.5, 3)],
        footprint: FootprintParams::default(),
        beams: BeamParams::default(),
        colour: ColourParams::default(),
        photons: PhotonParams::default(),
        grid: GridParams::default(),
        camera: Camera::default(),
        render: RenderParams::default(),
        volume: VolumeParams::default(),
        background: Background::default(),
        sky: SkyParams::default(),
        terrain: Terrain { kind: TerrainKind::Heightfield, ..Terrain::default() },
        animation: AnimationParams::default(),
        atmosphere: AtmosphereParams::default(),
    }
}

/// The 2014 report's final scene: 500,000 beams, alpha_D = 25 deg,
/// delta alpha = 12 deg, beam length 70, dt = 0.004 (at most 250
/// deflections), photon radius 0.2, air density 0.9 exp(-0.02 h), three
/// sheets. Report units are taken as km.
pub fn seed2014() -> Scene {
    let mut s = default_scene();
    s.beams.count = 500_000;
    s.beams.alpha_d_deg = 25.0;
    s.beams.delta_alpha_deg = 12.0;
    s.beams.length_km = 70.0;
    s.beams.dt = 0.004;
    // With s = L dt xi (mean L dt / 2 = 0.14 km) and at most 250 steps a
    // beam travels 35 km on average: starting at 140 km it reaches the
    // green layer (100-120 km), as the report's curtains do.
    s.beams.top_km = 140.0;
    // The report's beams end after 1/dt steps wherever they are: its look
    // needs the straight-line model and its stopping rules.
    s.beams.deposition = Deposition::Csda;
    s.photons.radius_km = 0.2;
    s.grid.voxel_size = VoxelSize::Km(0.2);
    s.grid.density_a = 0.9;
    s.grid.density_b = 0.02;
    s.grid.density_base_km = 90.0;
    s.colour.mode = ColourMode::Colormap;
    s.render.width = 640;
    s.render.height = 438;
    s.render.spp = 8;
    s
}

/// The unit tests' small scene: one short curtain (40 x 16 km, bent 3 km),
/// a coarse footprint, 300 beams, a 1 km kernel on 1 km voxels: a bake in
/// about a second. Tests change what they need from it.
/// (`tests/common::small_scene` is the integration tests' two-curtain
/// variant: integration tests do not see `cfg(test)` items.)
#[cfg(test)]
pub(crate) fn small_test_scene() -> Scene {
    let mut s = Scene { curtains: vec![Curtain { length: 40.0, width: 16.0, bend_km: 3.0, ..Curtain::default() }], ..Scene::default() };
    s.footprint.resolution = [128, 48];
    s.beams.count = 300;
    s.photons.radius_km = 1.0;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s
}

#[cfg(test)]
mod tests {
    use super::super::Scene;
    use super::*;
    #[test]
    fn presets_validate_and_round_trip_through_toml() {
        for name in presets::NAMES {
            let s = presets::by_name(name).unwrap();
            s.validate(name, None).unwrap();
            let text = s.to_toml();
            let back = Scene::from_toml_str(&text, name).unwrap();
            assert_eq!(back, s, "{name}");
        }
    }
}
