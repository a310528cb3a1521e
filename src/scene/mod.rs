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
//! The tables, each struct beside its defaults: [`curtain`] (`[[curtain]]`,
//! `[footprint]`, `[animation]`), [`beams`] (`[beams]`, `[atmosphere]`,
//! `[earth]`), [`colour`], [`grid`] (`[photons]`, `[grid]`) and [`view`]
//! (`[camera]`, `[render]`, `[volume]`, `[background]`, `[sky]`,
//! `[terrain]`), [`airglow`] (`[airglow]`); [`root`] (the [`Scene`] that holds them), reading
//! (`load`), [`overrides`] (`--set KEY=VALUE` applied to the document
//! before validation), [`validation`] (the range checks, their limits and
//! the error types), [`wording`] (the parser's messages in plain words,
//! did-you-mean), [`schema`] (the `--schema` JSON drawn from those checks),
//! [`presets`] (the built-in scenes) and [`kernel`] (the photon kernel's
//! radius range). Callers outside use the re-exports here
//! (`crate::scene::Camera`); files inside import from the file that
//! defines an item.

pub mod airglow;
pub mod beams;
pub mod colour;
pub mod curtain;
pub mod grid;
pub mod kernel;
mod load;
pub mod overrides;
pub mod presets;
pub mod root;
pub mod schema;
pub mod validation;
pub mod view;
pub mod wording;

pub use airglow::AirglowParams;
pub use beams::*;
pub use colour::*;
pub use curtain::*;
pub use grid::*;
pub use kernel::KernelRadius;
pub use overrides::Override;
pub use root::{fnv1a, Scene, OFF_WHEN_ZERO};
pub use validation::{
    check_shapes, find_key_line, RangeError, SceneError, MAX_COLORMAP_VALUE, MAX_IMAGE_SIDE, MAX_PRUNE, MAX_SEED, MAX_SHADOW_SAMPLES,
    MAX_SPP, MAX_THREADS,
};
pub use view::*;
