//! The gather radius study of `aurora bench` (see [`super::sweeps`] for the
//! harness, the table of studies and how times are taken).

use crate::app::bench::harness::{gather_key, Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::grid_rel_rms;
use crate::scene::GatherMethod;

impl<'a> Bench<'a> {
    /// Gather radius at fixed photon count: noise against blur.
    pub fn radius_study(&mut self) -> Result<Study, SweepError> {
        let (r, v, n) = (self.radius(), self.voxel(), self.beams());
        let m = self.beams_times(self.plan.reference_beams);
        let (r_ref, v_ref) = (0.5 * r, 0.5 * v);
        self.say(&format!("reference: kd-tree, {m} beams, r = {r_ref} km, voxel {v_ref} km"));
        let (reference, ref_secs) = self.gather_uncached(m, r_ref, v_ref, GatherMethod::Kdtree)?;
        let name = "gather radius";
        let metric = "relative RMS of emission";
        let mut ms = Vec::new();
        let (gm, label) = self.density_gather();
        for bf in self.plan.radius_beam_factors.clone() {
            let k = self.beams_times(bf);
            let method = format!("{label}, {k} beams");
            for f in self.plan.radius_factors.clone() {
                let rr = r * f;
                let (g, secs) = self.gather(k, rr, v, gm)?;
                let e = grid_rel_rms(&g, &reference);
                ms.push(self.measure(
                    &Series { study: name, method: &method, param_name: "radius_km", stage: "gather", metric },
                    rr,
                    Cost::seconds(secs),
                    e,
                    k == n && f == 1.0,
                ));
                self.note_last(&ms, gather_key(k, rr, v, gm), 0.0);
            }
        }
        Ok(Study {
            name: name.into(),
            stage: "gather".into(),
            metric: metric.into(),
            reference: format!(
                "kd-tree gather of {m} beams with half the radius (r = {r_ref} km, radius noise as in the scene) on half the voxel size ({v_ref} km): the blur of the reference itself (r/2) is not measured"
            ),
            reference_cost: ref_secs,
            unit: CostUnit::Seconds,
            expected_trend: vec![],
            notes: vec![
                format!("Voxel size fixed at the scene's ({v} km). Small radii: noise (few photons per kernel) and, below half a voxel, aliasing; large radii: blur across the curtain."),
                format!("The reference's own noise is about sqrt((N r^3) / (M (r/2)^3)) = {:.2} of the noise at the scene's setting (N = {n}, r = {r}); it adds to every error in quadrature.", ((n as f64 * 8.0) / m as f64).sqrt()),
            ],
            measurements: ms,
        })
    }
}
