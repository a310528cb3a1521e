//! The render's cost for `aurora bake --plan`: a baked frame rendered from
//! its VDB, as a farm's `aurora render --vdb` task would, at a reduced size
//! (`crate::farm::cost_plan`'s module docs give the model
//! `R = F + k W H spp`).
//!
//! F is the CPU to open the VDB and build the medium
//! ([`crate::app::vdb_for_render::prepare_from_vdb`]); k the CPU per pixel
//! sample of the trace at the reduced size: the scene's image scaled by one
//! factor in both directions (the same field of view, so the same mix of
//! sky, aurora and ground per pixel) to about [`CALIBRATION_SAMPLES`] pixel
//! samples at the scene's spp. CPU is the process's user + system time, so
//! the thread count does not change it. What the calibration cannot see: a
//! cost per sample that changes with the pixel's size (the trace does not
//! change its step with it today).

use crate::farm::cost_plan::{usage, RenderCost};
use crate::render::{render_prepared, RenderSettings};
use crate::scene::Scene;
use crate::util::progress::NoProgress;
use std::path::Path;

/// Pixel samples the calibration render traces (fewer when the scene's
/// image has fewer): about a second of CPU on one core.
pub const CALIBRATION_SAMPLES: usize = 400_000;

/// The reduced image for a `width` x `height` image at `spp`: scaled by one
/// factor to about `budget` pixel samples, at least 1 x 1, never larger.
pub fn calibration_size(width: usize, height: usize, spp: usize, budget: usize) -> (usize, usize) {
    let full = (width * height * spp) as f64;
    if full <= budget as f64 {
        return (width, height);
    }
    let f = (budget as f64 / full).sqrt();
    (((width as f64 * f).round() as usize).max(1), ((height as f64 * f).round() as usize).max(1))
}

/// Renders `vdb` (frame `frame` of `scene`, with `settings` from it) at the
/// calibration size and returns the render's cost at the scene's size.
pub fn calibrate(scene: &Scene, settings: &RenderSettings, vdb: &Path, frame: i64) -> Result<RenderCost, String> {
    let (width, height, spp) = (scene.render.width, scene.render.height, scene.render.spp);
    let (cw, ch) = calibration_size(width, height, spp, CALIBRATION_SAMPLES);
    let (cpu0, _) = usage();
    let (mut prepared, _, _) = crate::app::vdb_for_render::prepare_from_vdb(settings, vdb, &scene.colour).map_err(|e| e.to_string())?;
    let (cpu1, _) = usage();
    prepared.set_image(cw, ch, spp).map_err(|e| e.to_string())?;
    let image = render_prepared(&prepared, &NoProgress).map_err(|e| e.to_string())?;
    let (cpu2, _) = usage();
    drop(image);
    Ok(RenderCost {
        frame,
        width,
        height,
        spp,
        calibrated_width: cw,
        calibrated_height: ch,
        fixed_cpu_s: cpu1 - cpu0,
        cpu_per_sample_s: (cpu2 - cpu1) / (cw * ch * spp) as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_keeps_the_aspect_and_the_budget() {
        assert_eq!(calibration_size(64, 36, 4, 400_000), (64, 36));
        let (w, h) = calibration_size(4096, 4096, 2, 400_000);
        assert_eq!(w, h);
        assert!(((w * h * 2) as f64 / 400_000.0 - 1.0).abs() < 0.01, "{w}x{h}");
        let (w, h) = calibration_size(1920, 1080, 16, 400_000);
        assert!(((w as f64 / h as f64) / (16.0 / 9.0) - 1.0).abs() < 0.02, "{w}x{h}");
        assert_eq!(calibration_size(100_000, 1, 1000, 10).1, 1);
    }
}
