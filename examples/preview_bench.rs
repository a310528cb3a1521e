//! Edit-to-picture times of `aurora preview` (src/app/preview/) on a scene
//! (default: the default preset) at 320x180: the first picture, then
//! - an exposure edit (`render.exposure`): a tone map of the last linear
//!   image, nothing traced;
//! - two render edits that retrace every pixel: `terrain.albedo` (the
//!   renderer's medium is kept) and `volume.emission_scale` (the medium
//!   is kept too: the volume scales apply at lookup);
//! - a beams edit (`beams.top_noise_km`): trace, gather, finish, render;
//!
//! each timed from the edit to the refined picture on disk at the
//! preview's spp (`--spp`, default 4), and, when the scene's `render.spp`
//! is larger, to the picture at the scene's spp, with the time of every
//! stage. The bake runs at the scene's own settings (beam count, voxel
//! size).
//!
//! `cargo run --release --example preview_bench [SCENE] [--threads N] [--spp N]`
//! Targets, on the refined picture at the preview's spp:
//! <= 1 s for a render edit, <= 3 s for a beams edit, on 2 cores.

mod common;

use aurora::app::preview::{Preview, Update, DEFAULT_SIZE, DEFAULT_SPP};
use aurora::scene::Scene;
use common::{cpu_seconds, loadavg};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opt = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).map(|t| t.parse::<usize>()).transpose();
    let threads = opt("--threads")?;
    let spp = opt("--spp")?.unwrap_or(DEFAULT_SPP);
    let values: Vec<usize> = args.iter().enumerate().filter(|(_, a)| a.starts_with("--")).map(|(i, _)| i + 1).collect();
    let name = args
        .iter()
        .enumerate()
        .find(|(i, a)| !a.starts_with("--") && !values.contains(i))
        .map(|(_, a)| a.clone())
        .unwrap_or("default".into());
    let mut scene = Scene::load(&name)?;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        pool = pool.num_threads(n);
    }
    let pool = pool.build()?;
    let dir = std::env::temp_dir().join(format!("aurora-preview-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let out = dir.join("preview.png");
    let mut p = Preview::new(&out, DEFAULT_SIZE, None);
    p.spp = spp;
    println!(
        "# aurora preview benchmark: scene {name}, {}x{}, {} threads, preview spp {spp}, scene spp {}, beams {}, voxel {:?}",
        DEFAULT_SIZE[0],
        DEFAULT_SIZE[1],
        pool.current_num_threads(),
        scene.render.spp,
        scene.beams.count,
        scene.grid.voxel_size
    );
    println!("# 'picture': edit to the refined picture at the preview spp on disk (the targets: <= 1 s render edit, <= 3 s beams edit); 'full': to the picture at the scene spp");
    println!("# load average before: {}", loadavg());
    println!("# cpu: CPU seconds (all threads) from the edit to the refined picture: on a loaded machine wall times stretch, CPU times much less; cpu / threads is a floor for a quiet machine's wall time");
    let row = |what: &str, u: &Update, cpu: f64| {
        println!(
            "{what:<22} picture {:6.2} s | cpu {:6.2} s | full {:6.2} s | coarse {:5.2} s | {}",
            u.to_picture,
            cpu,
            u.to_full,
            u.to_coarse,
            u.summary()
        )
    };
    let mut step = |what: &str, scene: &Scene| -> Result<(), Box<dyn std::error::Error>> {
        let c0 = cpu_seconds();
        let at_picture = std::sync::Mutex::new(None);
        let u = pool.install(|| {
            p.update(scene, &|what, _| {
                if what.starts_with("picture") {
                    *at_picture.lock().unwrap() = Some(cpu_seconds());
                }
                true
            })
        })?;
        let c1 = at_picture.lock().unwrap().unwrap_or_else(cpu_seconds);
        row(what, &u, c1 - c0);
        Ok(())
    };
    step("first", &scene)?;
    scene.render.exposure += 0.5;
    step("exposure edit", &scene)?;
    scene.terrain.albedo = scene.terrain.albedo.map(|a| (a * 1.2).min(1.0));
    step("render edit (albedo)", &scene)?;
    scene.volume.emission_scale *= 1.5;
    step("render edit (emission)", &scene)?;
    scene.beams.top_noise_km += 1.0;
    step("beams edit", &scene)?;
    println!("# load average after: {}", loadavg());
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
