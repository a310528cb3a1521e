//! The scene file: every parameter of the bake and of the reference render.
//!
//! Units: **kilometres** for every length (positions, altitudes, radii, voxel
//! size), z up as in Blender, x east, y north. Extinction (`density`) is per
//! kilometre; emission is linear Rec.709 radiance per kilometre of path, scaled
//! so that Y = 1 corresponds to 1 kR of OI 557.7 nm per km (`crate::physics::emission::line_colour`).
//!
//! Parsing is separate from validation (pbrt's `GridMedium::Create` pattern):
//! serde reads the TOML (unknown keys are errors), then [`Scene::validate`]
//! checks every range once and names the file, line, key, value and the
//! allowed range. Stages downstream trust a validated scene.
//!
//! One file per table, named for it, each struct beside its defaults:
//! [`curtain`] (`[[curtain]]`), [`footprint`], [`animation`], [`beams`],
//! [`atmosphere`], [`earth`], [`colour`], [`photons`], [`grid`],
//! [`camera`], [`render`], [`volume`], [`background`], [`sky`],
//! [`airglow`] and [`terrain`]; [`root`] (the [`Scene`] that holds them),
//! [`keys`] (what a key is: name, unit, range, description) and [`tables`]
//! (every table with its keys, the one list the checks, the schema and the
//! docs walk), reading (`load`), [`overrides`] (`--set KEY=VALUE` applied
//! to the document before validation), [`validation`] (the range checks
//! from the tables, the rules between keys and the error types), [`wording`] (the parser's messages in
//! plain words, did-you-mean), [`schema`] (the `--schema` JSON drawn from
//! the tables), [`presets`] (the built-in scenes) and [`kernel`] (the
//! photon kernel's radius range). Callers outside use the re-exports here
//! (`crate::scene::Camera`); files inside import from the file that
//! defines an item.

pub mod airglow;
pub mod animation;
pub mod atmosphere;
pub mod background;
pub mod beams;
pub mod camera;
pub mod colour;
pub mod curtain;
pub mod earth;
pub mod footprint;
pub mod grid;
pub mod kernel;
pub mod keys;
mod load;
pub mod oval;
pub mod overrides;
pub mod photons;
pub mod presets;
pub mod render;
pub mod root;
pub mod schema;
pub mod site;
pub mod sky;
pub mod tables;
pub mod terrain;
pub mod validation;
pub mod volume;
pub mod wording;

pub use airglow::AirglowParams;
pub use animation::*;
pub use atmosphere::*;
pub use background::*;
pub use beams::*;
pub use camera::*;
pub use colour::*;
pub use curtain::*;
pub use earth::*;
pub use footprint::*;
pub use grid::*;
pub use kernel::KernelRadius;
pub use oval::OvalParams;
pub use overrides::Override;
pub use photons::*;
pub use render::*;
pub use root::{fnv1a, Scene, OFF_WHEN_ZERO};
pub use site::{SiteField, SiteParams};
pub use sky::*;
pub use terrain::*;
pub use validation::{check_shapes, find_key_line, RangeError, SceneError, MAX_COLORMAP_VALUE, MAX_SEED, MAX_THREADS};
pub use volume::*;
