//! Which stages an edit reruns: the earliest [`Stage`] it invalidates, from
//! a diff of the old and the new scene section by section
//! ([`stage_for_edit`]); that stage and every later one rerun.
//!
//! | the edit touches | rerun |
//! |---|---|
//! | `render.exposure` or `render.view_transform` only | nothing traced: the last linear image re-encoded (a tone map of the linear film, `crate::render::view_transform::display_rgb`) |
//! | `[render]` spp, `[background]`, `[terrain]` | the pixels (the medium is kept; the terrain model unless its geometry changed, the sky unless `[background]` did) |
//! | `[volume]` | the pixels (the medium holds unit values and applies the scales at lookup: `Prepared::set_volume_scales`, no rebuild) |
//! | `[camera]`, `[render]` width / height | the voxel size (`"auto"` follows the camera): the gather when it changed, pruning when `grid.prune > 0` (then the medium), then the pixels |
//! | `[grid]` other than `voxel_size` | finish (checks, pruning, density), the medium, the pixels |
//! | `grid.voxel_size`, `[photons]` other than `kernel` | gather and after |
//! | `[beams]`, `[colour]`, `[atmosphere]`, `photons.kernel` | trace and after (the footprints are kept) |
//! | `seed`, `[[curtain]]`, `[footprint]`, `[animation]` | everything |
//!
//! Colour edits retrace: a photon carries its RGB power, not the altitude
//! and deposited power it was coloured from, so a recolour needs the beams;
//! the footprints (the fluid simulation) are kept
//! ([`crate::pipeline::plan::BakePlan::reusing`]).

use crate::pipeline::footprint::curtain_path::Lift;
use crate::scene::{ColourParams, Scene};

/// The earliest stage an edit invalidates (later stages rerun too).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Nothing the picture depends on changed.
    Nothing,
    /// `render.exposure` only: a tone map of the last linear image, no
    /// ray is traced.
    Exposure,
    Render,
    /// The camera or the scene's image size: the automatic voxel size and
    /// pruning may change.
    Camera,
    Finish,
    Gather,
    Trace,
    /// Footprints and everything after (the plan finds which it can keep).
    Footprints,
}

/// Which stage an edit from `old` to `new` starts at (the module
/// documentation's table).
pub fn stage_for_edit(old: &Scene, new: &Scene) -> Stage {
    let mut s = Stage::Nothing;
    let mut at = |changed: bool, stage: Stage| {
        if changed && stage > s {
            s = stage;
        }
    };
    at(old.seed != new.seed || old.curtains != new.curtains || old.footprint != new.footprint, Stage::Footprints);
    at(old.animation != new.animation, Stage::Footprints);
    // A path is placed up the field line from its altitude: the field and
    // the start altitude move it.
    at(new.curtains.iter().any(|c| c.path.is_some()) && Lift::of_scene(old) != Lift::of_scene(new), Stage::Footprints);
    // The white balance is the PNG's, as the exposure (`crate::render::develop`).
    let colour = ColourParams { white_balance_k: new.colour.white_balance_k, ..old.colour.clone() };
    at(old.beams != new.beams || colour != new.colour || old.atmosphere != new.atmosphere || old.earth != new.earth, Stage::Trace);
    at(old.photons.kernel != new.photons.kernel, Stage::Trace);
    at(old.photons != new.photons || old.grid.voxel_size != new.grid.voxel_size, Stage::Gather);
    at(old.grid != new.grid, Stage::Finish);
    at(old.camera != new.camera || (old.render.width, old.render.height) != (new.render.width, new.render.height), Stage::Camera);
    let mut render = old.render.clone();
    render.exposure = new.render.exposure;
    render.auto_exposure = new.render.auto_exposure;
    render.view_transform = new.render.view_transform;
    at(
        render != new.render
            || old.volume != new.volume
            || old.background != new.background
            || old.airglow != new.airglow
            || old.terrain != new.terrain,
        Stage::Render,
    );
    at(
        old.render.exposure != new.render.exposure
            || old.render.auto_exposure != new.render.auto_exposure
            || old.render.view_transform != new.render.view_transform
            || old.colour.white_balance_k != new.colour.white_balance_k,
        Stage::Exposure,
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_map_to_the_stages_they_touch() {
        let a = Scene::default();
        let edit = |f: &dyn Fn(&mut Scene)| {
            let mut b = a.clone();
            f(&mut b);
            stage_for_edit(&a, &b)
        };
        assert_eq!(edit(&|_| {}), Stage::Nothing);
        assert_eq!(edit(&|s| s.render.exposure += 1.0), Stage::Exposure);
        assert_eq!(
            edit(&|s| {
                s.render.exposure += 1.0;
                s.render.spp += 1
            }),
            Stage::Render
        );
        assert_eq!(edit(&|s| s.render.spp += 1), Stage::Render);
        assert_eq!(edit(&|s| s.volume.emission_scale *= 2.0), Stage::Render);
        assert_eq!(edit(&|s| s.render.width += 2), Stage::Camera);
        assert_eq!(edit(&|s| s.camera.fov_deg += 1.0), Stage::Camera);
        assert_eq!(edit(&|s| s.grid.density_a = 0.02), Stage::Finish);
        assert_eq!(edit(&|s| s.grid.voxel_size = crate::scene::VoxelSize::Km(0.7)), Stage::Gather);
        assert_eq!(edit(&|s| s.photons.radius_km *= 1.1), Stage::Gather);
        assert_eq!(edit(&|s| s.photons.kernel = crate::scene::KernelShape::Point), Stage::Trace);
        assert_eq!(edit(&|s| s.beams.count += 1), Stage::Trace);
        assert_eq!(edit(&|s| s.colour.noise_km += 1.0), Stage::Trace);
        assert_eq!(edit(&|s| s.curtains[0].energy_flux *= 2.0), Stage::Footprints);
        assert_eq!(edit(&|s| s.seed += 1), Stage::Footprints);
        // The earliest stage wins.
        assert_eq!(
            edit(&|s| {
                s.render.exposure += 1.0;
                s.beams.count += 1
            }),
            Stage::Trace
        );
    }
}
