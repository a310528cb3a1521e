//! [`TABLES`]: every table of the scene with its keys ([`super::keys`]),
//! in the order a scene file gives them, and what each table is. The one
//! list validation, the schema, the plain-word messages and docs/scene.md
//! walk.

use super::keys::KeySpec;

/// One table of the scene: its name (`""` for the top level, `curtain`
/// for each `[[curtain]]`), its keys and what it is.
#[derive(Clone, Copy, Debug)]
pub struct Table {
    pub name: &'static str,
    pub keys: &'static [KeySpec],
    /// What the table is, for docs/scene.md.
    pub about: &'static str,
}

impl Table {
    /// The table's heading in docs/scene.md: "Top level", "`[[curtain]]`", "`[beams]`".
    pub fn heading(&self) -> String {
        match self.name {
            "" => "Top level".into(),
            "curtain" => "`[[curtain]]`".into(),
            name => format!("`[{name}]`"),
        }
    }
}

/// Every table, in the order a scene file gives them (and docs/scene.md).
pub const TABLES: &[Table] = &[
    Table {
        name: "",
        keys: super::root::ROOT_KEYS,
        about: "Keys outside any table.",
    },
    Table {
        name: "curtain",
        keys: super::curtain::CURTAIN_KEYS,
        about: "One table per auroral curtain: where its footprint lies and how hard it is driven. A scene without any `[[curtain]]` has the default scene's three; the defaults below are those of one table that omits a key.",
    },
    Table {
        name: "footprint",
        keys: super::footprint::FOOTPRINT_KEYS,
        about: "The 2D stable-fluids simulation (Stam 1999) that makes each curtain's footprint, bent along a low-frequency noise curve.",
    },
    Table {
        name: "beams",
        keys: super::beams::BEAMS_KEYS,
        about: "Electron beams traced down the geomagnetic field with random deflections (Baranoski et al. 2000), depositing energy by Fang et al. (2010).",
    },
    Table {
        name: "atmosphere",
        keys: super::atmosphere::ATMOSPHERE_KEYS,
        about: "The neutral atmosphere the electrons deposit their energy in, and the ambient night ionosphere the chemistry needs. The default is compiled in and free to sell with; `nrlmsis21` and `glow` are the data the physics was validated on, whose terms forbid commercial use or sale, read from a data folder ([data.md](data.md)).",
    },
    Table {
        name: "earth",
        keys: super::earth::EARTH_KEYS,
        about: "The ground's shape: a sphere (curtain positions and paths are ground distances from the origin, azimuthal equidistant) or a flat plane.",
    },
    Table {
        name: "site",
        keys: super::site::SITE_KEYS,
        about: "Where on the Earth and when: the real stars of the Hipparcos-2 catalogue, the Moon with its phase and its light, and the Sun's elevation over the site at the hour. Optional: without it the scene has no place or hour, a statistical star field and no Moon. With it the scene's frame is the site's (x east, y north, z along the WGS 84 ellipsoid's normal).",
    },
    Table {
        name: "oval",
        keys: super::oval::OVAL_KEYS,
        about: "Where the auroral oval is: with a `[site]`, the oval's equatorward and poleward edges by Starkov (1994) in corrected geomagnetic (AACGM-v2) latitude at the activity (`kp` or `al_nt`), and the scene's straight curtains laid between them along the oval, their middle at the site's magnetic local time. AACGM-v2 is defined by IGRF-14, so with `site.field = \"scene\"` the arcs are placed where they are with IGRF (the same ground tracks at 110 km) and only the beams rising from them follow the scene's own field. Optional: without it the curtains stay where their keys put them.",
    },
    Table {
        name: "colour",
        keys: super::colour::COLOUR_KEYS,
        about: "How deposited energy becomes colour.",
    },
    Table {
        name: "photons",
        keys: super::photons::PHOTONS_KEYS,
        about: "Volumetric photon mapping: a Gaussian-kernel density estimate of the emission.",
    },
    Table {
        name: "grid",
        keys: super::grid::GRID_KEYS,
        about: "The sparse grids written to the VDB.",
    },
    Table {
        name: "camera",
        keys: super::camera::CAMERA_KEYS,
        about: "The camera of `aurora render` and of the Blender scene; pruning and the automatic voxel size follow it.",
    },
    Table {
        name: "render",
        keys: super::render::RENDER_KEYS,
        about: "The reference renderer's image.",
    },
    Table {
        name: "volume",
        keys: super::volume::VOLUME_KEYS,
        about: "The volume material, as `aurora render` and the add-on's Cycles material apply it.",
    },
    Table {
        name: "background",
        keys: super::background::BACKGROUND_KEYS,
        about: "What is seen behind the volume.",
    },
    Table {
        name: "sky",
        keys: super::sky::SKY_KEYS,
        about: "The air between the aurora and the observer: Rayleigh scattering, ozone and aerosol dim and redden what is seen through the lower atmosphere (docs/physics.md, \"The air between the aurora and the eye\").",
    },
    Table {
        name: "airglow",
        keys: super::airglow::AIRGLOW_KEYS,
        about: "The night sky's own light, drawn by `aurora render` behind the volume (camera rays only, dimmed by the air, hidden by the terrain) and by Cycles through `aurora sky`'s map: Gaussian layers in spherical shells (docs/physics.md, \"Airglow\"). Render-only: the bake never reads it.",
    },
    Table {
        name: "terrain",
        keys: super::terrain::TERRAIN_KEYS,
        about: "The ground, lit by the aurora only (emissive shadow rays).",
    },
    Table {
        name: "animation",
        keys: super::animation::ANIMATION_KEYS,
        about: "Motion in time, closed form in t, so any frame costs one bake; every motion key at 0 gives identical frames.",
    },
];

/// The key `name` of table `table` (`""` for the top level).
pub fn spec(table: &str, name: &str) -> Option<&'static KeySpec> {
    TABLES.iter().find(|t| t.name == table)?.keys.iter().find(|k| k.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::keys::{Num, Range};
    use crate::scene::*;
    use serde_json::{json, Map};

    #[test]
    fn every_field_has_one_key_and_every_key_a_field() {
        let defaults = serde_json::to_value(Scene::default()).unwrap();
        for t in TABLES {
            let fields = match t.name {
                "" => defaults.as_object().unwrap().iter().filter(|(_, v)| !v.is_object()).map(|(k, _)| k.clone()).collect::<Vec<_>>(),
                "curtain" => {
                    let mut f: Vec<String> =
                        serde_json::to_value(Curtain::default()).unwrap().as_object().unwrap().keys().cloned().collect();
                    f.push("path".into());
                    f.push("magnetic_path".into());
                    f.retain(|k| k != "curtain");
                    f
                }
                // No site by default: the preset's, with the key it omits.
                "site" => {
                    let mut f: Vec<String> =
                        serde_json::to_value(presets::sites::tromso_site()).unwrap().as_object().unwrap().keys().cloned().collect();
                    f.push("pressure_hpa".into());
                    f
                }
                // No oval by default: its defaults, with the keys they omit.
                "oval" => {
                    let mut f: Vec<String> =
                        serde_json::to_value(OvalParams::default()).unwrap().as_object().unwrap().keys().cloned().collect();
                    f.extend(["al_nt".into(), "mlt_h".into()]);
                    f
                }
                name => defaults[name].as_object().unwrap().keys().cloned().collect(),
            };
            let fields: Vec<String> = fields.into_iter().filter(|k| k != "curtain").collect();
            for f in &fields {
                assert_eq!(t.keys.iter().filter(|k| k.name == f).count(), 1, "{}.{f}: no key or two", t.name);
            }
            for k in t.keys {
                assert!(fields.iter().any(|f| f == k.name), "{}.{}: no such field", t.name, k.name);
            }
        }
    }

    #[test]
    fn words_are_the_parsers() {
        // Each Word range lists exactly the words the parser takes, in its order.
        let parsed = schema::enum_values();
        for t in TABLES {
            for k in t.keys {
                if let Range::Word(words) = k.range {
                    let key = format!("{}.{}", t.name, k.name);
                    let p = parsed.iter().find(|(e, _)| *e == key).unwrap_or_else(|| panic!("{key}: the parser lists no words"));
                    assert_eq!(p.1, json!(words), "{key}");
                }
            }
        }
        assert!(grid::GRID_KEYS
            .iter()
            .any(|k| matches!(k.range, Range::Rule(r) if validation::LINE_KEYS.iter().all(|l| r.contains(&format!("\"{l}\""))))));
    }

    #[test]
    fn ranges_say_what_they_allow() {
        let k = spec("beams", "alpha_d_deg").unwrap();
        assert_eq!(
            k.number_problem(95.0).unwrap(),
            ("95".into(), "must be in [0, 90) degrees: at 90 a beam no longer moves along B".into())
        );
        assert!(k.number_problem(45.0).is_none());
        let v = toml::Value::Array(vec![toml::Value::Float(2e4), toml::Value::Float(0.0)]);
        assert_eq!(spec("curtain", "center").unwrap().problem(&v).unwrap().1, "each coordinate must be in [-1e4, 1e4] km");
        assert_eq!(
            spec("earth", "radius_km").unwrap().number_problem(10.0).unwrap().1,
            "must be 0 (a flat ground) or in [1000, 100000] km"
        );
        let voxel = spec("grid", "voxel_size").unwrap();
        assert!(voxel.problem(&toml::Value::String("auto".into())).is_none());
        assert_eq!(voxel.number_problem(0.0).unwrap().1, "must be a finite number > 0");
        let mut k = Map::new();
        voxel.range.schema_into(voxel.unit, &mut k);
        assert_eq!(k["rule"], "a number of km > 0, or \"auto\"");
        // A key that takes a number or a word needs no code of its own.
        let exposure = KeySpec::new("exposure", "stops", Range::NumOrWord(Num::closed(-50.0, 50.0), &["auto"]), "");
        assert!(exposure.problem(&toml::Value::String("auto".into())).is_none());
        assert_eq!(exposure.number_problem(99.0).unwrap().1, "must be in [-50, 50]");
        assert_eq!(exposure.problem(&toml::Value::String("dim".into())).unwrap().1, "must be a number of stops in [-50, 50], or \"auto\"");
    }
}
