//! Gather and finish times of a bake at the scene's own settings (default:
//! the default preset): traces once, then runs the gather and each part of
//! the finish (scan, prune, density, Cycles shell) `--reps` times, printing
//! wall and CPU seconds of each and the load average. The preview's beams
//! edit pays trace + gather + finish.
//!
//! `cargo run --release --example gather_bench -- [SCENE] [--threads N] [--reps K] [--beams B]`
//!
//! `--beams B` traces B beams instead of the scene's count: with
//! `valgrind --tool=callgrind --toggle-collect='*gather_grid*'` it gives the
//! gather's instruction count, which the machine's load does not change.

mod common;

use aurora::pipeline::plan::BakePlan;
use aurora::scene::Scene;
use aurora::util::progress::NoProgress;
use common::{cpu_seconds as cpu, loadavg};
use std::time::Instant;

fn timed<R>(what: &str, f: impl FnOnce() -> R) -> R {
    let (t, c) = (Instant::now(), cpu());
    let r = f();
    println!("  {what:<8} wall {:6.3} s  cpu {:6.2} s", t.elapsed().as_secs_f64(), cpu() - c);
    r
}

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opt = |k: &str| args.iter().position(|a| a == k).and_then(|i| args.get(i + 1)).cloned();
    let threads = opt("--threads").map(|t| t.parse::<usize>()).transpose()?;
    let reps = opt("--reps").map(|t| t.parse::<usize>()).transpose()?.unwrap_or(2);
    let beams = opt("--beams").map(|t| t.parse::<usize>()).transpose()?;
    let values: Vec<String> = [opt("--threads"), opt("--reps"), opt("--beams")].into_iter().flatten().collect();
    let name = args.iter().find(|a| !a.starts_with("--") && !values.contains(a)).cloned().unwrap_or("default".into());
    let mut scene = Scene::load(&name)?;
    if let Some(n) = beams {
        // A smaller bake for instruction counts (valgrind --tool=callgrind).
        (scene.beams.count, scene.beams.target_noise) = (n, 0.0);
    }
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        pool = pool.num_threads(n);
    }
    let pool = pool.build()?;
    pool.install(|| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        println!("# gather bench: scene {name}, {} threads, load average {}", rayon::current_num_threads(), loadavg());
        let plan = BakePlan::new(&scene, &NoProgress);
        let mut times = aurora::pipeline::bake::stats::StageTimes::default();
        let count = aurora::pipeline::bake::beam_count(&plan, &mut times, &NoProgress)?;
        let traced = timed("trace", || aurora::pipeline::bake::trace::trace(&plan, count.0, 0, 0..count.0, &NoProgress))?;
        let voxel = plan.voxel_size(&traced.photons);
        println!("# {} beams, {} photons, voxel {} km", count.0, traced.photons.len(), voxel.0);
        {
            // The gather's set-up steps alone (the gather repeats them).
            use aurora::pipeline::photons::{bins, merge};
            let r = &plan.radius;
            let merged = timed("merge", || {
                merge::merge_segments(&traced.photons, |p| r.radius(p), merge::MERGE_LEN_R, merge::MERGE_OFF_R, merge::MERGE_CDF)
            });
            let reach = plan.scene.photons.cutoff * r.max();
            let leaves = timed("leaves", || bins::candidate_leaves(&merged, voxel.0, reach));
            let bins = timed("bins", || bins::bin_photons(&merged, &leaves, voxel.0, reach));
            println!("# {} merged photons, {} candidate leaves, {} (leaf, photon) pairs", merged.len(), leaves.len(), bins.photons.len());
        }
        for rep in 0..reps {
            println!("rep {rep} (load {})", loadavg());
            let (t0, c0) = (Instant::now(), cpu());
            let mut emission = timed("gather", || aurora::pipeline::bake::gather::gather(&plan, &traced.photons, voxel.0, &NoProgress));
            let t1 = Instant::now();
            let (_, peak_y) = timed("scan", || aurora::pipeline::bake::finish::scan_emission(&emission, plan.kernel.base_km))?;
            if plan.scene.grid.prune > 0.0 {
                let camera = plan.camera_model()?;
                timed("prune", || aurora::pipeline::prune::prune(&mut emission, &camera, plan.scene.grid.prune));
            }
            let mut density = timed("density", || {
                aurora::pipeline::bake::density::density_grid(
                    &emission,
                    &plan.scene.grid,
                    peak_y,
                    &aurora::geometry::earth::Earth::new(plan.scene.earth.radius_km),
                )
            });
            let (n, _) = timed("shell", || {
                let n = emission.dilate_active();
                (n, density.activate_like(&emission))
            });
            println!(
                "  gather+finish wall {:.3} s (finish {:.3} s), cpu {:.2} s; {} leaves, {} voxels + {n} shell",
                t0.elapsed().as_secs_f64(),
                t1.elapsed().as_secs_f64(),
                cpu() - c0,
                density.leaf_count(),
                density.active_voxel_count() - n
            );
        }
        println!("# load average after: {}", loadavg());
        Ok(())
    })
}
