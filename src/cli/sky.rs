//! `aurora sky`: the airglow and the stars the scene's camera sees, as an
//! equirectangular linear EXR for Blender's world
//! (`aurora::render::sky_map`). The output is checked before any work, as
//! `aurora render` checks its own.

use super::args::SkyArgs;
use super::bars::Bars;
use super::exit::InputError;
use super::render::{image_format, ImageFormat};
use super::{load_scene, scene_dir, with_threads};
use anyhow::Result;

pub fn run(a: SkyArgs) -> Result<()> {
    let SkyArgs { scene: scene_arg, out, width, overrides, common } = a;
    let max = aurora::render::sky_map::MAX_SKY_WIDTH;
    if !(8..=max).contains(&width) || !width.is_multiple_of(2) {
        return Err(InputError(format!("--width {width}: must be an even number in [8, {max}]")).into());
    }
    if image_format("--out", &out)? != ImageFormat::Exr {
        return Err(InputError(format!("--out {}: the sky map is a linear OpenEXR; give a name ending in .exr", out.display())).into());
    }
    super::render_checks::sky_within_memory(width)?;
    let scene = load_scene(&scene_arg, &overrides)?;
    super::render_checks::inputs_and_outputs(None, None, &[Some(&out)])?;
    let mut settings = aurora::render::RenderSettings::from_scene(&scene);
    settings.base_dir = Some(scene_dir(&scene_arg));
    with_threads(common.threads, || {
        let bars = Bars::new(common.quiet);
        let image = aurora::render::sky_map::sky_map(&settings, width, bars.progress())?;
        aurora::render::image_file::write_exr(&out, &image)?;
        if !common.quiet {
            eprintln!("wrote {} ({}x{})", out.display(), image.width, image.height);
        }
        Ok(())
    })
}
