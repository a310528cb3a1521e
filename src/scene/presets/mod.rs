//! Built-in scenes: `default` (three sheets, as in the report's final
//! image), `seed2014` (the report's final scene parameters), `oval` (a
//! 2500 km arc along a circle of magnetic latitude, overhead, for a dome)
//! and the classic auroral forms ([`forms`]: a quiet arc, a rayed band, a corona, pulsating
//! patches, red type-A and pink type-B aurora, a westward travelling surge).
//!
//! Every preset is a [`Preset`] row of [`PRESETS`]: its name (what `aurora
//! scene NAME` and any scene argument accept), a one-line description
//! (`aurora scene --list`) and the function that builds its [`Scene`].
use crate::scene::root::Scene;

pub mod classic;
pub mod forms;
pub mod sites;

pub use classic::{default_scene, oval, seed2014, OVAL_LENGTH_KM, OVAL_POLE_DISTANCE_KM};

/// A built-in scene: its name, what it shows, and how it is built.
#[derive(Clone, Copy, Debug)]
pub struct Preset {
    pub name: &'static str,
    /// One line for `aurora scene --list`: what the scene shows.
    pub description: &'static str,
    pub build: fn() -> Scene,
    /// The International Brightness Coefficient class its brightest 557.7
    /// nm column along B reaches (I-IV: 1, 10, 100, 1000 kR;
    /// `crate::pipeline::columns`); `None` for a colour map's scene and for
    /// one that shows another preset's arcs (`tromso`: the default's).
    pub ibc_class: Option<u32>,
}

/// Every preset, in the order `aurora scene --list` prints them.
pub const PRESETS: &[Preset] = &[
    Preset {
        name: "default",
        description: "three curtains seen from the ground, mountains lit by the aurora",
        build: default_scene,
        ibc_class: Some(3),
    },
    Preset {
        name: "seed2014",
        description: "the 2014 report's final scene: 500,000 beams, CSDA, its colour map",
        build: seed2014,
        ibc_class: None,
    },
    Preset {
        name: "oval",
        description: "a 2500 km arc along a circle of magnetic latitude about a dipole pole, overhead, seen as a dome master",
        build: oval,
        ibc_class: Some(3),
    },
    Preset { name: "quiet_arc", description: forms::QUIET_ARC, build: forms::quiet_arc, ibc_class: Some(2) },
    Preset { name: "rayed_band", description: forms::RAYED_BAND, build: forms::rayed_band, ibc_class: Some(3) },
    Preset { name: "corona", description: forms::CORONA, build: forms::corona, ibc_class: Some(3) },
    Preset { name: "pulsating_patches", description: forms::PULSATING_PATCHES, build: forms::pulsating_patches, ibc_class: Some(1) },
    Preset { name: "type_a_red", description: forms::TYPE_A_RED, build: forms::type_a_red, ibc_class: Some(2) },
    Preset { name: "type_b_pink", description: forms::TYPE_B_PINK, build: forms::type_b_pink, ibc_class: Some(3) },
    Preset { name: "surge", description: forms::SURGE, build: forms::surge, ibc_class: Some(3) },
    Preset { name: "tromso", description: sites::TROMSO, build: sites::tromso, ibc_class: None },
    Preset { name: "tromso_dome", description: sites::TROMSO_DOME, build: sites::tromso_dome, ibc_class: None },
    Preset { name: "tromso_kp5", description: sites::TROMSO_KP5, build: sites::tromso_kp5, ibc_class: None },
    Preset { name: "tromso_kp5_dome", description: sites::TROMSO_KP5_DOME, build: sites::tromso_kp5_dome, ibc_class: None },
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
pub use crate::scene::colour::report_colormap;

/// The unit tests' small scene: one short curtain (40 x 16 km, bent 3 km),
/// a coarse footprint (the 2014 fluid, straight ends: the unit tests'
/// noise figures were measured on it), 300 beams, a 1 km kernel on 1 km
/// voxels: a bake in about a second. Tests change what they need from it.
/// (`tests/common::small_scene` is the integration tests' two-curtain
/// variant: integration tests do not see `cfg(test)` items.)
#[cfg(test)]
pub(crate) fn small_test_scene() -> Scene {
    use crate::scene::{Curtain, VoxelSize};
    // The tables' own footprint and render keys, not the default preset's
    // art (its footprint's bends and rays, its shadow samples).
    let mut s = Scene {
        curtains: vec![Curtain { length: 40.0, width: 16.0, bend_km: 3.0, ..Curtain::default() }],
        footprint: crate::scene::FootprintParams::default(),
        render: crate::scene::RenderParams { exposure: -6.0, ..crate::scene::RenderParams::default() },
        ..Scene::default()
    };
    s.footprint.resolution = [128, 48];
    s.footprint.model = crate::scene::FootprintModel::Fluid2014;
    s.footprint.end_fade_km = 0.0;
    s.beams.count = 300;
    s.photons.radius_km = 1.0;
    // The 2014 walk and the kernel's noise its figures were measured with.
    s.photons.radius_noise = 0.3;
    s.beams.alpha_d_deg = 5.0;
    s.beams.delta_alpha_deg = 3.0;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::*;
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
