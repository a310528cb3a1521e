//! The reference renderer, one test binary: pixels against closed forms
//! (`closed_forms`), the emission-only path against the general walk
//! (`emission_only`), the volume walker and integrators against an
//! independent brute-force oracle (`integrator`), film, camera and file
//! conventions (`film`), the lit terrain and its mesh (`terrain`), the
//! camera against Blender's (`blender`), the air between the aurora
//! and the eye (`extinction`), narrow-band images in rayleigh at the
//! zenith (`zenith`), and the airglow and the stars behind the volume
//! (`airglow`), and the sky over a site: the catalogue's stars where
//! skyfield puts them, the Moon lighting the ground (`site_sky`), and the
//! default picture's colours at its white balance and auto exposure
//! (`sky_colour`).

#[path = "../common/mod.rs"]
mod common;

mod airglow;
mod blender;
mod closed_forms;
mod contrast;
mod emission_only;
mod extinction;
mod film;
mod integrator;
mod motion_blur;
mod site_sky;
mod sky_colour;
mod terrain;
mod zenith;
