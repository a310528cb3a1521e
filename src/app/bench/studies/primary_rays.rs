//! The primary-ray integration study of `aurora bench` (see [`super::sweeps`] for the
//! harness, the table of studies and how times are taken).

use crate::app::bench::harness::{Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::image_rel_error_masked;
use crate::pipeline::bake::{self};
use crate::render::{Integration, Volume};

impl<'a> Bench<'a> {
    /// Fixed-step ray marching against exact per-voxel integration.
    pub fn integration_study(&self, grids: &bake::Bake) -> Result<Study, SweepError> {
        let v = self.voxel();
        let mut s = self.volume_settings();
        let vol = Volume { density: Some(&grids.density), emission: Some(&grids.emission) };
        let name = "primary-ray integration";
        let metric = "mean relative luminance error, pixels > 1% of peak";
        s.integration = Integration::Exact;
        let (exact, exact_s) = self.render_timed(&s, &vol)?;
        let all = vec![true; exact.pixels.len()];
        let mut ms = vec![self.measure(
            &Series { study: name, method: "exact (per dual cell)", param_name: "step_km", stage: "render", metric },
            0.0,
            Cost::seconds(exact_s),
            0.0,
            true,
        )];
        let mut flux = Vec::new();
        for f in self.plan.step_factors.clone() {
            let h = v * f;
            s.integration = Integration::FixedStep(h);
            let (img, secs) = self.render_timed(&s, &vol)?;
            let (e, fl) = image_rel_error_masked(&img.pixels, &exact.pixels, &all, 0.01);
            flux.push(format!("h = {h} km: {fl:.5}"));
            ms.push(self.measure(
                &Series { study: name, method: "fixed step", param_name: "step_km", stage: "render", metric },
                h,
                Cost::seconds(secs),
                e,
                false,
            ));
        }
        let lit = exact.pixels.iter().filter(|p| p[1] > 0.0).count();
        Ok(Study {
            name: name.into(),
            stage: "render".into(),
            metric: metric.into(),
            reference: format!(
                "the exact integrator's image ({}x{} px, spp 1, {} pixels with emission; camera: bench volume camera, no terrain)",
                exact.width, exact.height, lit
            ),
            reference_cost: exact_s,
            unit: CostUnit::Seconds,
            expected_trend: vec![("fixed step".into(), -1)],
            notes: vec![
                format!("Voxel size {v} km; steps are multiples of it. Exact integration is the reference (error 0, drawn on the bottom edge); its own error against closed forms is below 1e-4 (tests/render/closed_forms.rs, tests/stability/integration.rs)."),
                format!("Total flux ratio fixed/exact: {}", flux.join(", ")),
            ],
            measurements: ms,
        })
    }
}
