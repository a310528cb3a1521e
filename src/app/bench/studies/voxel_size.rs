//! The voxel size study of `aurora bench` (see [`super::sweeps`] for the
//! harness, the table of studies and how times are taken).

use crate::app::bench::harness::{gather_key, Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::grid_rel_rms;
use crate::scene::GatherMethod;

impl<'a> Bench<'a> {
    /// Voxel size at fixed photons and radius, per gather method.
    pub fn voxel_study(&mut self) -> Result<Study, SweepError> {
        let (r, v, n) = (self.radius(), self.voxel(), self.beams());
        let v_ref = v * self.plan.reference_voxel;
        let name = "voxel size";
        let metric = "relative RMS of emission";
        let mut ms = Vec::new();
        let mut ref_secs = 0.0;
        let mut trend = Vec::new();
        for (method, label) in [(GatherMethod::Kdtree, "kd-tree (kiddo)"), (GatherMethod::Splat, "splat")] {
            self.say(&format!("reference: {label}, {n} beams, r = {r} km, voxel {v_ref} km"));
            let (reference, secs) = self.gather_uncached(n, r, v_ref, method)?;
            ref_secs += secs;
            trend.push((label.to_string(), -1));
            for f in self.plan.voxel_factors.clone() {
                let vv = v * f;
                let (g, secs) = self.gather(n, r, vv, method)?;
                let e = grid_rel_rms(&g, &reference);
                let here = f == 1.0 && method == self.scene.photons.gather;
                ms.push(self.measure(
                    &Series { study: name, method: label, param_name: "voxel_km", stage: "gather", metric },
                    vv,
                    Cost::seconds(secs),
                    e,
                    here,
                ));
                self.note_last(&ms, gather_key(n, r, vv, method), 0.0);
            }
        }
        Ok(Study {
            name: name.into(),
            stage: "gather".into(),
            metric: metric.into(),
            reference: format!("the same photons ({n} beams) and method on voxels of {v_ref} km; kernel r = {r} km"),
            reference_cost: ref_secs,
            unit: CostUnit::Seconds,
            expected_trend: trend,
            notes: vec!["Pure discretisation: the photons and kernel are those of the reference, so the error is that of storing the estimate at voxel centres and reading it back trilinearly (as Cycles does), against a finer grid.".into()],
            measurements: ms,
        })
    }
}
