//! Built-in scenes: `default` (three sheets, as in the report's final
//! image), `seed2014` (the report's final scene parameters), `oval` (a
//! 2500 km arc along a circle of magnetic latitude, overhead, for a dome)
//! and the classic auroral forms ([`forms`]: a quiet arc, a rayed band, a corona, pulsating
//! patches, red type-A and pink type-B aurora, a westward travelling surge).
//!
//! Every preset is a [`Preset`] row of [`PRESETS`]: its name (what `aurora
//! scene NAME` and any scene argument accept), a one-line description
//! (`aurora scene --list`) and the function that builds its [`Scene`].
use super::*;

pub mod forms;

/// A built-in scene: its name, what it shows, and how it is built.
#[derive(Clone, Copy, Debug)]
pub struct Preset {
    pub name: &'static str,
    /// One line for `aurora scene --list`: what the scene shows.
    pub description: &'static str,
    pub build: fn() -> Scene,
}

/// Every preset, in the order `aurora scene --list` prints them.
pub const PRESETS: &[Preset] = &[
    Preset { name: "default", description: "three curtains seen from the ground, mountains lit by the aurora", build: default_scene },
    Preset { name: "seed2014", description: "the 2014 report's final scene: 500,000 beams, CSDA, its colour map", build: seed2014 },
    Preset {
        name: "oval",
        description: "a 2500 km arc along a circle of magnetic latitude about a dipole pole, overhead, seen as a dome master",
        build: oval,
    },
    Preset { name: "quiet_arc", description: forms::QUIET_ARC, build: forms::quiet_arc },
    Preset { name: "rayed_band", description: forms::RAYED_BAND, build: forms::rayed_band },
    Preset { name: "corona", description: forms::CORONA, build: forms::corona },
    Preset { name: "pulsating_patches", description: forms::PULSATING_PATCHES, build: forms::pulsating_patches },
    Preset { name: "type_a_red", description: forms::TYPE_A_RED, build: forms::type_a_red },
    Preset { name: "type_b_pink", description: forms::TYPE_B_PINK, build: forms::type_b_pink },
    Preset { name: "surge", description: forms::SURGE, build: forms::surge },
];

/// The presets' names, in [`PRESETS`] order.
pub fn names() -> impl Iterator<Item = &'static str> {
    PRESETS.iter().map(|p| p.name)
}

/// The preset called `name`, built.
pub fn by_name(name: &str) -> Option<Scene> {
    PRESETS.iter().find(|p| p.name == name).map(|p| (p.build)())
}

/// `aurora scene --list`: one line per preset, its name padded to the
/// longest, two spaces, its description.
pub fn list() -> String {
    let w = names().map(str::len).max().unwrap_or(0);
    PRESETS.iter().map(|p| format!("{:w$}  {}\n", p.name, p.description)).collect()
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
        terrain: Terrain { kind: TerrainKind::Heightfield, ..Terrain::default() },
        animation: AnimationParams::default(),
        atmosphere: AtmosphereParams::default(),
        earth: EarthParams::default(),
        sky: SkyParams::default(),
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

/// Ground distance from the oval's dipole pole to its arc, km: magnetic
/// latitude 90 deg - 2200 / 6371 rad = 70.2 deg, the auroral oval's night
/// side.
pub const OVAL_POLE_DISTANCE_KM: f64 = 2200.0;
/// Length of the oval's arc along its circle of magnetic latitude, km.
pub const OVAL_LENGTH_KM: f64 = 2500.0;

/// An arc of the auroral oval for a planetarium dome: the lower border
/// (the path, at 110 km) runs 2500 km along the small circle of magnetic
/// latitude 70.2 deg about a dipole pole 2200 km north
/// (`earth.magnetic_pole`), its middle overhead; seen by a 180-degree
/// fisheye looking at the zenith, north up, with stars. On the round
/// Earth its ends go down behind the horizon, some 1250 km away.
pub fn oval() -> Scene {
    let earth = crate::geometry::earth::Earth::new(crate::geometry::earth::MEAN_RADIUS_KM);
    let pole = [0.0, OVAL_POLE_DISTANCE_KM];
    // The small circle's radius in space, R sin(rho / R): its azimuths from
    // the pole span the arc's length; 33 points, 78 km apart.
    let rho = OVAL_POLE_DISTANCE_KM;
    let span_deg = (OVAL_LENGTH_KM / (earth.radius_km * (rho / earth.radius_km).sin())).to_degrees();
    let south = earth.azimuth_deg(pole, [0.0, 0.0]);
    let n = 33;
    let path: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let az = south + span_deg * (0.5 - k as f64 / (n - 1) as f64);
            let [x, y] = earth.destination(pole, az, rho);
            // Rounded to metres: the TOML stays readable.
            [(x * 1e3).round() / 1e3, (y * 1e3).round() / 1e3]
        })
        .collect();
    let mut s = Scene {
        curtains: vec![Curtain {
            path: Some(path),
            width: 40.0,
            energy_flux: 12.0,
            char_energy_kev: 4.0,
            bend_km: 8.0,
            seed: 1,
            ..Curtain::default()
        }],
        ..default_scene()
    };
    s.earth.magnetic_pole = Some(pole);
    s.beams.count = 50_000;
    s.photons.radius_km = 1.5;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s.camera = Camera {
        position: [0.0, 0.0, 0.002],
        look_at: [0.0, 0.0, 1.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Fisheye,
        fov_deg: 180.0,
        ..Camera::default()
    };
    s.render.width = 1024;
    s.render.height = 1024;
    // A bright arc (12 mW/m^2) straight overhead: 1.5 stops under the
    // default exposure keeps its core out of the view transform's shoulder.
    s.render.exposure = 1.5;
    s.background.stars = true;
    s.terrain = Terrain { kind: TerrainKind::Plane, ..Terrain::default() };
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
        let names: Vec<&str> = presets::names().collect();
        assert!(names.len() >= 9, "{names:?}");
        for name in names {
            let s = presets::by_name(name).unwrap();
            s.validate(name, None).unwrap();
            let text = s.to_toml();
            let back = Scene::from_toml_str(&text, name).unwrap();
            assert_eq!(back, s, "{name}");
        }
    }

    #[test]
    fn names_are_distinct_and_the_list_has_one_line_each() {
        let names: Vec<&str> = presets::names().collect();
        let mut sorted = names.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len(), "{names:?}");
        let list = presets::list();
        let lines: Vec<&str> = list.lines().collect();
        assert_eq!(lines.len(), names.len());
        for (line, p) in lines.iter().zip(presets::PRESETS) {
            assert_eq!(line.split_whitespace().next(), Some(p.name));
            assert!(line.ends_with(p.description) && !p.description.is_empty(), "{line}");
        }
        assert!(presets::by_name("no_such_preset").is_none());
    }
}
