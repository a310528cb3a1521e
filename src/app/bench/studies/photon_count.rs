//! The photon count and gather method study of `aurora bench` (see [`super::sweeps`] for the
//! harness, the table of studies and how times are taken).

use crate::app::bench::harness::{gather_key, Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::{grid_rel_rms, grid_rel_rms_best_scale};
use crate::scene::GatherMethod;

impl<'a> Bench<'a> {
    /// Photon count and gather method (they share the kd-tree reference).
    pub fn photon_and_gather_studies(&mut self) -> Result<Vec<Study>, SweepError> {
        let (reference, m, ref_secs) = self.noise_reference()?;
        let n = self.beams();
        let (r, v) = (self.radius(), self.voxel());
        let metric = "relative RMS of emission";

        // Photon count at fixed radius: beams + gather time.
        let name = "photon count";
        let (gm, label) = self.density_gather();
        let method = format!("{label}, r = {r} km");
        let mut ms = Vec::new();
        let mut err_n = None;
        for f in self.plan.beam_factors.clone() {
            let k = self.beams_times(f);
            let (g, gather_s) = self.gather(k, r, v, gm)?;
            let trace_s = self.photons[&k].1;
            let e = grid_rel_rms(&g, &reference);
            if k == n {
                err_n = Some(e);
            }
            ms.push(self.measure(
                &Series { study: name, method: &method, param_name: "beams", stage: "beams+gather", metric },
                k as f64,
                Cost::seconds(trace_s + gather_s),
                e,
                k == n,
            ));
            self.note_last(&ms, gather_key(k, r, v, gm), trace_s);
        }
        // The old estimators over the same beam counts, on the same chart.
        let old_label = self.old_label();
        let mut old_gathers = Vec::new();
        for f in self.plan.beam_factors.clone() {
            let k = self.beams_times(f);
            let (g, trace_s, gather_s) = self.old_estimator_grid(k)?;
            let e = grid_rel_rms(&g, &reference);
            ms.push(self.measure(
                &Series { study: name, method: &old_label, param_name: "beams", stage: "beams+gather", metric },
                k as f64,
                Cost::seconds(trace_s + gather_s),
                e,
                false,
            ));
            old_gathers.push((k, gather_s, e));
        }
        let mut notes = vec![format!(
            "Pure noise: the reference has the same kernel and voxels, so the error is the Monte Carlo noise of the density estimate, expected to fall as beams^-1/2 (sigma sqrt(1/n - 1/M) with the shared first beams)."
        ), format!("'{old_label}': the earlier estimators (photons.kernel = \"point\", beams.starts = \"random\"), against the same reference: its error also holds the point-vs-segment kernel bias, and its streams share no beams with the reference's.")];
        if let Some(e) = err_n {
            notes.push(format!(
                "Estimated noise of the reference itself ({m} beams): err(N = {n}) / sqrt(M/N - 1) = {:.3e}.",
                e / ((m as f64 / n as f64) - 1.0).max(1e-12).sqrt()
            ));
        }
        let photon = Study {
            name: name.into(),
            stage: "beams+gather".into(),
            metric: metric.into(),
            reference: format!("kd-tree gather of {m} beams, same radius (r = {r} km, radius noise as in the scene) and voxel ({v} km)"),
            reference_cost: ref_secs + self.photons[&m].1,
            unit: CostUnit::Seconds,
            expected_trend: vec![(method.clone(), 1), (old_label.clone(), 1)],
            notes,
            measurements: ms,
        };

        // Gather methods, each over beams: gather time only.
        let name = "gather method";
        let mut ms = Vec::new();
        let scene_gather = self.scene.photons.gather;
        let mut trend = Vec::new();
        for method in [GatherMethod::Kdtree, GatherMethod::Splat, GatherMethod::Report2014] {
            let label = match method {
                GatherMethod::Kdtree => "kd-tree (kiddo)",
                GatherMethod::Splat => "splat",
                GatherMethod::Report2014 => "report2014 (average)",
            };
            if method != GatherMethod::Report2014 {
                trend.push((label.to_string(), 1));
            }
            let mut scaled = Vec::new();
            for f in self.plan.gather_beam_factors.clone() {
                let k = self.beams_times(f);
                let (g, secs) = self.gather(k, r, v, method)?;
                let here = method == scene_gather && k == n;
                ms.push(self.measure(
                    &Series { study: name, method: label, param_name: "beams", stage: "gather", metric },
                    k as f64,
                    Cost::seconds(secs),
                    grid_rel_rms(&g, &reference),
                    here,
                ));
                self.note_last(&ms, gather_key(k, r, v, method), 0.0);
                if method == GatherMethod::Report2014 {
                    let (e, s) = grid_rel_rms_best_scale(&g, &reference);
                    scaled.push(self.measure(
                        &Series { study: name, method: "report2014, best-fit scale", param_name: "beams", stage: "gather", metric },
                        k as f64,
                        Cost::seconds(secs),
                        e,
                        false,
                    ));
                    self.note_last(&scaled, gather_key(k, r, v, method), 0.0);
                    self.say(&format!("  (report2014 best-fit scale factor {s:.4e})"));
                }
            }
            ms.extend(scaled);
        }
        // The old estimators' gather times (kd-tree, point photons), from
        // the photon-count study's runs at the gather study's beam counts.
        for f in self.plan.gather_beam_factors.clone() {
            let k = self.beams_times(f);
            let (gather_s, e) = match old_gathers.iter().find(|g| g.0 == k) {
                Some(&(_, s, e)) => (s, e),
                None => {
                    let (g, _, s) = self.old_estimator_grid(k)?;
                    (s, grid_rel_rms(&g, &reference))
                }
            };
            ms.push(self.measure(
                &Series { study: name, method: &old_label, param_name: "beams", stage: "gather", metric },
                k as f64,
                Cost::seconds(gather_s),
                e,
                false,
            ));
        }
        trend.push((old_label.clone(), 1));
        let gather = Study {
            name: name.into(),
            stage: "gather".into(),
            metric: metric.into(),
            reference: photon.reference.clone(),
            reference_cost: ref_secs,
            unit: CostUnit::Seconds,
            expected_trend: trend,
            notes: vec![
                "kd-tree is a balloon estimator (radius at the voxel), splat a sample-point estimator (radius at the photon): with radius noise they differ slightly, without it they are the same sum.".into(),
                "report2014 is the 2014 report's kernel-weighted average of photon colours, not a density: its values are a photon's power, so its error against the density reference is expected to be large (about 1 or more). 'report2014, best-fit scale' is the same grid scaled by the least-squares factor: the error of its shape alone.".into(),
            ],
            measurements: ms,
        };
        Ok(vec![photon, gather])
    }
}
