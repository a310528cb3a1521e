//! The pixel loop's cost on a real bake: open the VDB and build the medium
//! once, then trace the scene `--repeats` times and print, per run, the
//! wall time, the process CPU time of the loop (utime + stime from
//! /proc/self/stat, 100 ticks/s: robust to other load on a shared machine,
//! unlike wall or per-row times) and the rates per CPU-second.
//!
//! `cargo run --release --example trace_bench -- SCENE --vdb FILE.vdb
//! [--spp N] [--threads N] [--repeats N] [--shadow-samples N]`
//!
//! With `--repeats 1` it is also the harness for instruction counts
//! (`valgrind --tool=callgrind --toggle-collect='*render_prepared*'`).

mod common;

use aurora::render::{render_prepared, Prepared, RenderSettings, Volume};
use aurora::scene::Scene;
use aurora::util::progress::NoProgress;
use common::cpu_seconds;
use std::path::PathBuf;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opt = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned();
    let num = |name: &str| opt(name).map(|v| v.parse::<usize>()).transpose();
    let vdb = PathBuf::from(opt("--vdb").ok_or("--vdb FILE.vdb is required")?);
    let name = args.first().filter(|a| !a.starts_with("--")).cloned().unwrap_or("default".into());
    let scene = Scene::load(&name)?;
    let mut settings = RenderSettings::from_scene(&scene);
    if let Some(n) = num("--spp")? {
        settings.render.spp = n;
    }
    if let Some(n) = num("--shadow-samples")? {
        settings.render.shadow_samples = n;
    }
    settings.base_dir = std::path::Path::new(&name).parent().map(|p| p.to_path_buf());
    let repeats = num("--repeats")?.unwrap_or(3);
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = num("--threads")? {
        pool = pool.num_threads(n);
    }
    let pool = pool.build()?;
    let file = aurora::io::vdb::read::read_vdb_for_render(&vdb)?;
    let (d, e) = aurora::app::vdb_for_render::render_grids(file)?;
    let volume = Volume { density: d.as_ref(), emission: e.as_ref() };
    let prepared = pool.install(|| Prepared::new(&settings, &volume))?;
    println!(
        "# {name} {}x{} spp {}, {} threads, load {}",
        settings.render.width,
        settings.render.height,
        settings.render.spp,
        pool.current_num_threads(),
        common::loadavg()
    );
    println!("# sigma_t majorant {:.6} per unit length", prepared.medium().sigma_t_majorant());
    println!("run,wall_s,cpu_s,primary_rays,shadow_rays,terrain_hits,primary_per_cpu_s,shadow_cpu_s,volume_work_per_primary");
    for r in 0..repeats {
        let c0 = cpu_seconds();
        let t0 = Instant::now();
        let img = pool.install(|| render_prepared(&prepared, &NoProgress))?;
        let wall = t0.elapsed().as_secs_f64();
        let cpu = (cpu_seconds() - c0).max(0.01);
        let st = &img.stats;
        // Shadow share of the thread time (as RenderStats measures it),
        // applied to the CPU time: the shadow rays' CPU seconds.
        let shadow_share = st.shadow_thread_seconds / st.thread_seconds.max(1e-12);
        println!(
            "{r},{wall:.3},{cpu:.2},{},{},{},{:.0},{:.3},{:.1}",
            st.primary_rays,
            st.shadow_rays,
            st.terrain_hits,
            st.primary_rays as f64 / cpu,
            cpu * shadow_share,
            st.volume_work as f64 / st.primary_rays.max(1) as f64
        );
    }
    Ok(())
}
