//! Edit-to-picture times of `aurora preview` (src/preview.rs) on a scene
//! (default: the default preset) at 320x180: the first picture, then a
//! render edit (`render.exposure`) and a beams edit (`beams.top_noise_km`),
//! each timed from the edit to the refined picture on disk, with the time
//! of every stage. The bake runs at the scene's own settings.
//!
//! `cargo run --release --example preview_bench [SCENE] [--threads N]`
//! Targets (issue 14 part 4): <= 1 s for a render edit, <= 3 s for a beams
//! edit, on 2 cores.

use aurora::preview::{Preview, Update, DEFAULT_SIZE};
use aurora::scene::Scene;

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg").map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" ")).unwrap_or_default()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let threads = args.iter().position(|a| a == "--threads").and_then(|i| args.get(i + 1)).map(|t| t.parse::<usize>()).transpose()?;
    let name = args.iter().find(|a| !a.starts_with("--") && Some(*a) != threads.map(|t| t.to_string()).as_ref()).cloned().unwrap_or("default".into());
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
    println!("# aurora preview benchmark: scene {name}, {}x{}, {} threads, spp {}, beams {}, voxel {:?}", DEFAULT_SIZE[0], DEFAULT_SIZE[1], pool.current_num_threads(), scene.render.spp, scene.beams.count, scene.grid.voxel_size);
    println!("# load average before: {}", loadavg());
    let row = |what: &str, u: &Update| println!("{what:<12} edit to picture {:6.2} s (coarse {:5.2} s) | {}", u.to_picture, u.to_coarse, u.summary());
    let u = pool.install(|| p.update(&scene, &|_| {}))?;
    row("first", &u);
    scene.render.exposure += 0.5;
    let u = pool.install(|| p.update(&scene, &|_| {}))?;
    row("render edit", &u);
    scene.beams.top_noise_km += 1.0;
    let u = pool.install(|| p.update(&scene, &|_| {}))?;
    row("beams edit", &u);
    println!("# load average after: {}", loadavg());
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
