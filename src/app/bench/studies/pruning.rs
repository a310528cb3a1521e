//! The pruning study of `aurora bench` (see [`super::sweeps`] for the
//! harness, the table of studies and how times are taken).

use crate::app::bench::harness::{timed, Bench, Series, Study, SweepError};
use crate::app::bench::measurement::{Cost, CostUnit};
use crate::app::bench::metrics::image_rel_error_masked;
use crate::grid::Grid;
use crate::io::vdb::write::GridRef;
use crate::pipeline::bake::{self};
use crate::render::{Integration, RenderError, Volume};
use crate::util::progress::NoProgress;

impl<'a> Bench<'a> {
    /// Contribution-based pruning ([`crate::pipeline::prune`]): the reduced scene
    /// baked unpruned, then pruned at each budget (and given the Cycles
    /// shell, as the bake does), seen through the bench volume camera
    /// (which also weights the leaves), against the unpruned image. What
    /// pruning saves is storage, so the time is the VDB write (encoding both
    /// grids with the scene's compression, in memory: it scales with the
    /// file's size), fastest of the timing runs; sizes and voxels go in the
    /// notes. Render time barely changes: the dropped leaves are faint and
    /// few rays cross them.
    pub fn prune_study(&self) -> Result<Study, SweepError> {
        // The reference: the reduced scene baked without pruning (and
        // without the Cycles shell, added below to every variant as the bake
        // adds it after pruning).
        let mut unpruned = self.scene.clone();
        unpruned.grid.prune = 0.0;
        unpruned.grid.cycles_shell = false;
        let base = bake::bake(&unpruned, &NoProgress)?;
        let peak = base.stats.peak_luminance;
        let finish = |e: &Grid<[f32; 3]>| -> (Grid<[f32; 3]>, Grid<f32>) {
            let mut e = e.clone();
            let mut d =
                bake::density::density_grid(&e, &self.scene.grid, peak, &crate::geometry::earth::Earth::new(self.scene.earth.radius_km));
            if self.scene.grid.cycles_shell {
                e.dilate_active();
                d.dilate_active();
            }
            (e, d)
        };
        let (full_e, full_d) = finish(&base.emission);
        let mut s = self.volume_settings();
        s.integration = Integration::Exact;
        let camera = crate::geometry::camera::CameraModel::new(&s.camera, s.render.width, s.render.height).map_err(RenderError::from)?;
        let opts = crate::io::bake_folder::write_options(&self.scene);
        let (min, max_runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        // (bytes, fastest write time)
        let write = |e: &Grid<[f32; 3]>, d: &Grid<f32>| -> (usize, f64) {
            let (len, secs) = timed(min, max_runs, || {
                crate::io::vdb::write::write_vdb_bytes(&[GridRef::Float(d), GridRef::Vec3(e)], &opts).map(|b| b.len())
            });
            (len.unwrap_or(0), secs)
        };
        let name = "pruning";
        let metric = "mean relative luminance error, pixels > 1% of peak";
        let vol = Volume { density: Some(&full_d), emission: Some(&full_e) };
        let (full, _) = self.render_timed(&s, &vol)?;
        let all = vec![true; full.pixels.len()];
        let (full_bytes, full_s) = write(&full_e, &full_d);
        let scene_budget = self.scene.grid.prune;
        let mut ms = vec![self.measure(
            &Series { study: name, method: "unpruned", param_name: "budget", stage: "vdb write", metric },
            0.0,
            Cost::seconds(full_s),
            0.0,
            scene_budget == 0.0,
        )];
        let mut notes = vec![format!(
            "Unpruned: {} aurora voxels, {} leaves, {full_bytes} bytes (VDB, scene compression, Cycles shell: {}). Removed light is estimated without extinction; per budget: leaves and voxels removed, estimated share removed, image flux ratio, file size:",
            base.emission.active_voxel_count(),
            base.emission.leaf_count(),
            self.scene.grid.cycles_shell
        )];
        let mut budgets = self.plan.prune_budgets.clone();
        if scene_budget > 0.0 && !budgets.contains(&scene_budget) {
            budgets.push(scene_budget);
            budgets.sort_by(f64::total_cmp);
        }
        for &b in &budgets {
            let mut e = base.emission.clone();
            let st = crate::pipeline::prune::prune(&mut e, &camera, b);
            let (e, d) = finish(&e);
            let vol = Volume { density: Some(&d), emission: Some(&e) };
            let (img, _) = self.render_timed(&s, &vol)?;
            let (err, flux) = image_rel_error_masked(&img.pixels, &full.pixels, &all, 0.01);
            let (nb, secs) = write(&e, &d);
            notes.push(format!(
                "budget {b}: {} of {} leaves, {} of {} voxels, estimate {:.3e}, flux {flux:.5}, {nb} bytes ({:.3} of unpruned)",
                st.leaves_removed,
                st.leaves_before,
                st.voxels_removed,
                st.voxels_before,
                st.removed_fraction,
                nb as f64 / full_bytes.max(1) as f64
            ));
            ms.push(self.measure(
                &Series { study: name, method: "contribution pruning", param_name: "budget", stage: "vdb write", metric },
                b,
                Cost::seconds(secs),
                err,
                b == scene_budget,
            ));
        }
        notes.push(format!("The scene's grid.prune = {scene_budget}."));
        Ok(Study {
            name: name.into(),
            stage: "vdb write".into(),
            metric: metric.into(),
            reference: format!(
                "the unpruned bake's image ({}x{} px, spp 1, exact integration; bench volume camera, no terrain)",
                full.width, full.height
            ),
            reference_cost: full_s,
            unit: CostUnit::Seconds,
            expected_trend: vec![("contribution pruning".into(), -1)],
            notes,
            measurements: ms,
        })
    }
}
