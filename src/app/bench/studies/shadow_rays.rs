//! The shadow rays study of `aurora bench` (see [`super::sweeps`] for the
//! harness, the table of studies and how times are taken).

use crate::app::bench::harness::{Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::image_rel_error_masked;
use crate::app::bench::reduced::{ground_camera, ground_terrain};
use crate::pipeline::bake::{self};
use crate::render::{Integration, Prepared, RenderSettings, Volume};

impl<'a> Bench<'a> {
    /// Shadow rays per terrain hit, and pixel samples, against converged
    /// terrain lighting.
    pub fn shadow_study(&self, grids: &bake::Bake) -> Result<Study, SweepError> {
        let mut s = RenderSettings::from_scene(&self.scene);
        s.terrain = ground_terrain(&self.scene);
        s.camera = ground_camera(&self.scene, &s.terrain);
        s.render.width = self.plan.ground_image[0];
        s.render.height = self.plan.ground_image[1];
        s.integration = Integration::Exact;
        let vol = Volume { density: Some(&grids.density), emission: Some(&grids.emission) };
        // Terrain pixels: where the pixel-centre ray hits the ground.
        let prepared = Prepared::new(&s, &vol)?;
        let (w, h) = (s.render.width, s.render.height);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| {
                let ray = prepared.camera().ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                prepared.terrain().intersect(ray.origin, ray.dir, 0.0, f64::INFINITY).is_some()
            })
            .collect();
        drop(prepared);
        let terrain_px = mask.iter().filter(|&&m| m).count();
        let name = "shadow rays";
        let metric = "mean relative luminance error, terrain pixels > 1% of peak";
        let big = self.plan.shadow_reference;
        let scene_spp = self.scene.render.spp;
        let mut counts = self.plan.shadow_counts.clone();
        if !self.plan.quick && !counts.contains(&scene_spp) && scene_spp < big {
            counts.push(scene_spp);
            counts.sort_unstable();
        }
        let mut ms = Vec::new();
        let mut ref_secs = 0.0;
        let methods = [("shadow rays per hit (spp 1)", true), ("pixel samples (1 shadow ray each)", false)];
        for (label, per_hit) in methods {
            let set = |s: &mut RenderSettings, k: usize| {
                if per_hit {
                    s.render.spp = 1;
                    s.render.shadow_samples = k;
                } else {
                    s.render.spp = k;
                    s.render.shadow_samples = 1;
                }
            };
            set(&mut s, big);
            self.say(&format!("reference: {label}, {big} samples per pixel"));
            let (reference, secs) = self.render_timed(&s, &vol)?;
            ref_secs += secs;
            for &k in &counts {
                set(&mut s, k);
                let (img, secs) = self.render_timed(&s, &vol)?;
                let (e, _) = image_rel_error_masked(&img.pixels, &reference.pixels, &mask, 0.01);
                // The CLI renders with the scene's spp and one shadow ray per hit.
                let here = !per_hit && k == scene_spp;
                ms.push(self.measure(
                    &Series { study: name, method: label, param_name: "samples", stage: "render", metric },
                    k as f64,
                    Cost::seconds(secs),
                    e,
                    here,
                ));
            }
        }
        Ok(Study {
            name: name.into(),
            stage: "render".into(),
            metric: metric.into(),
            reference: format!(
                "the same estimator with {big} samples per pixel ({w}x{h} px, {terrain_px} terrain pixels; bench ground camera, terrain {:?})",
                s.terrain.kind
            ),
            reference_cost: ref_secs,
            unit: CostUnit::Seconds,
            expected_trend: methods.iter().map(|(l, _)| (l.to_string(), 1)).collect(),
            notes: vec![
                "Each curve has its own reference (its estimator with many samples): 'shadow rays per hit' converges to the pixel-centre value, 'pixel samples' to the pixel's box-filtered value. Both errors are Monte Carlo noise, falling as samples^-1/2.".into(),
                format!("The CLI's `aurora render` uses spp = {scene_spp} from the scene and 1 shadow ray per terrain hit (marked as the scene setting)."),
            ],
            measurements: ms,
        })
    }
}
