//! `aurora bench`: speed against accuracy for every method choice.
//!
//! [`run`] reduces the scene ([`reduced`]), runs every study ([`studies`],
//! on the [`harness`]):
//! photon count, gather radius, gather method, voxel size, primary-ray
//! integration, pruning, storage (bytes against picture error,
//! `studies::storage`), shadow rays and animation flicker, each measuring wall time of the affected
//! stage against error relative to a converged reference, and returns a
//! [`report::BenchRun`]; [`report::write`] leaves `bench.csv`, `bench.json`
//! and a chart per study (PNG and SVG, [`chart`]) in the output folder.
//! Speed targets live here and in the committed runs under
//! `benchmarks/bench/`, never in unit tests.

pub mod chart;
pub mod harness;
pub mod measurement;
pub mod metrics;
pub mod reduced;
pub mod report;
pub mod studies;
pub mod vdb_write_timing;

use crate::pipeline::bake::BakeError;
use crate::pipeline::plan::BakePlan;
use crate::scene::{Scene, VoxelSize};
use crate::util::progress::NoProgress;
use harness::{Bench, StudyPlan, SweepError};
use report::{BenchRun, Machine};
use std::time::{Instant, SystemTime};

/// The storage studies alone on the full `scene` (not reduced): its
/// camera at its own image size and a 1024 x 1024 dome master, each picture
/// rendered at the scene's spp and integration, fewer settings per lever
/// ([`storage`]), with the throughput of the full scene as in [`run`].
pub fn run_storage(scene: &Scene, scene_name: &str, log: &(dyn Fn(&str) + Sync)) -> Result<BenchRun, SweepError> {
    let started = Started::now();
    let mut plan = StudyPlan::full();
    plan.dome_image = [1024, 1024];
    plan.storage_as_rendered = true;
    plan.prune_budgets = vec![1e-3];
    plan.storage_high_km = vec![240.0, 260.0];
    plan.storage_mantissa_bits = vec![10, 6, 5, 4];
    plan.min_timing_seconds = 0.0;
    plan.max_timing_runs = 1;
    plan.retime = false;
    let b = Bench::new(scene.clone(), plan.clone(), log);
    let studies = vec![
        b.storage_study(studies::storage::View::Scene, [scene.render.width, scene.render.height])?,
        b.storage_study(studies::storage::View::Dome, plan.dome_image)?,
    ];
    let reduction = vec!["none: the storage studies run on the full scene".into()];
    started.finish(scene, scene_name, plan, (scene.to_toml(), reduction), studies, log)
}

/// A run's clock, date and machine as it starts; [`Started::finish`] adds
/// the full scene's throughput and the load at the end.
struct Started {
    start: Instant,
    /// [`report::utc_date`] of the start.
    date: (String, String),
    machine: Machine,
}

impl Started {
    fn now() -> Started {
        Started { start: Instant::now(), date: report::utc_date(SystemTime::now()), machine: Machine::probe() }
    }

    /// The run's record: `studies` measured on the scene `reduced` (its TOML
    /// and the changes from `scene`), then the throughput of `scene` itself.
    fn finish(
        mut self,
        scene: &Scene,
        scene_name: &str,
        plan: StudyPlan,
        reduced: (String, Vec<String>),
        studies: Vec<harness::Study>,
        log: &(dyn Fn(&str) + Sync),
    ) -> Result<BenchRun, SweepError> {
        let throughput = throughput(scene, log)?;
        self.machine.loadavg_end = report::loadavg();
        Ok(BenchRun {
            machine: self.machine,
            date: self.date,
            wall_seconds: self.start.elapsed().as_secs_f64(),
            plan,
            scene_name: scene_name.to_string(),
            reduced_toml: reduced.0,
            reduction: reduced.1,
            studies,
            throughput,
        })
    }
}

/// The full scene's frames 1 and 18000 of a ten-minute range at its fps,
/// baked and written ([`crate::farm::cost_plan::plan`]).
fn throughput(scene: &Scene, log: &(dyn Fn(&str) + Sync)) -> Result<crate::farm::cost_plan::CostPlan, SweepError> {
    log("throughput: the full scene's frames 1 and 18000 of a ten-minute range at its fps");
    let show: Vec<i64> = (1..=(600.0 * scene.animation.fps).round().max(2.0) as i64).collect();
    crate::farm::cost_plan::plan(scene, &show, 2, &NoProgress).map_err(|e| SweepError::Plan(Box::new(e)))
}

/// Runs every study on `scene` (validated), full or `quick`. `scene_name`
/// names it in the outputs; `log` receives a line per measurement.
pub fn run(scene: &Scene, scene_name: &str, quick: bool, log: &(dyn Fn(&str) + Sync)) -> Result<BenchRun, SweepError> {
    let started = Started::now();
    let plan = if quick { StudyPlan::quick() } else { StudyPlan::full() };
    let auto_voxel = match scene.grid.voxel_size {
        VoxelSize::Km(_) => None,
        VoxelSize::Auto(_) => {
            // "auto" depends on the full scene's photons: trace them once.
            let plan = BakePlan::new(scene, &NoProgress);
            let n = plan.scene.beams.count;
            let photons = crate::pipeline::bake::trace::trace(&plan, n, 0, 0..n, &NoProgress).map_err(BakeError::from)?.photons;
            Some(plan.voxel_size(&photons))
        }
    };
    let red = reduced::reduce(scene, plan.curtain_km, auto_voxel);
    for c in &red.changes {
        log(&format!("reduced scene: {c}"));
    }
    let mut b = Bench::new(red.scene.clone(), plan.clone(), log);
    let mut studies = b.photon_and_gather_studies()?;
    studies.insert(1, b.radius_study()?);
    studies.push(b.voxel_study()?);
    let grids = b.bake_grids()?;
    studies.push(b.integration_study(&grids)?);
    studies.push(b.prune_study()?);
    studies.push(b.storage_study(studies::storage::View::Scene, plan.volume_image)?);
    studies.push(b.storage_study(studies::storage::View::Dome, plan.dome_image)?);
    studies.push(b.shadow_study(&grids)?);
    studies.push(studies::flicker::animation_study(&red.scene, &plan, log)?);
    if plan.retime {
        b.retime(&mut studies)?;
    }
    started.finish(scene, scene_name, plan, (red.scene.to_toml(), red.changes), studies, log)
}
