//! Reference-renderer throughput on a synthetic aurora: primary rays and
//! shadow-ray samples per second, and how they scale with image size, active
//! voxel count and (not) bounding-box volume.
//!
//! `cargo run --release --example render_bench [-- quick]` prints CSV rows.
//! Rates: per wall-second of the pixel loop; per CPU-second of the pixel loop
//! (process utime + stime from /proc/self/stat at 100 ticks/s, minus a
//! separate build's), which is robust to other load on a shared machine; and
//! per thread-second as `RenderStats` reports them (primary rays with the
//! shadow-ray time excluded, shadow samples in the shadow-ray time).
//!
//! The volume: `sheets` curtains like the default scene's (y = 0, 45, 95 km,
//! folded by a sine), 0.5 km voxels, 400 km long, 90-200 km high, 3 voxels
//! thick: 528k active voxels each, emission peaked at 110 km (green) with a
//! red tail, and the air's extinction 0.02 exp(-0.02 (h - 90)) per km on the
//! same voxels. Camera: the default scene's (ground, 260 km south, 50 deg).

use aurora::util::fmath;

mod common;

use aurora::grid::{Grid, Transform};
use aurora::render::{render, Integration, Prepared, RenderSettings, Volume};
use aurora::scene::{Scene, TerrainKind};
use aurora::util::progress::NoProgress;
use common::cpu_seconds;
use glam::{DVec3, IVec3};

const VS: f64 = 0.5;

fn curtains(sheets: usize, thickness: i32, far_voxel: bool) -> (Grid<f32>, Grid<[f32; 3]>) {
    let tr = Transform::new(VS, DVec3::ZERO);
    let mut d = Grid::new("density", 0.0f32, tr);
    let mut e = Grid::new("emission", [0.0f32; 3], tr);
    let centres = [0.0, 45.0, 95.0, 140.0];
    for (k, yc) in centres.iter().take(sheets).enumerate() {
        for x in -400..400 {
            let xk = x as f64 * VS;
            let y = yc + 12.0 * fmath::sin(2.0 * std::f64::consts::PI * xk / (90.0 + 20.0 * k as f64) + k as f64);
            let yi = (y / VS).round() as i32;
            let along = 0.6 + 0.4 * fmath::powi(fmath::sin(xk / 37.0 + k as f64), 2);
            for z in 180..400 {
                let h = z as f64 * VS;
                let green = fmath::exp(-fmath::powi((h - 110.0) / 12.0, 2));
                let red = 0.3 * fmath::exp(-fmath::powi((h - 160.0) / 30.0, 2));
                let sigma = 0.02 * fmath::exp(-0.02 * (h - 90.0));
                for dy in 0..thickness {
                    let p = IVec3::new(x, yi + dy - thickness / 2, z);
                    let w = 1.0 - ((dy - thickness / 2) as f64 / thickness as f64).abs();
                    let i = (along * w * 0.05) as f32;
                    e.set(p, [i * (0.1 * green as f32 + red as f32), i * green as f32, i * 0.2 * green as f32]);
                    d.set(p, sigma as f32);
                }
            }
        }
    }
    if far_voxel {
        d.set(IVec3::new(2_000_000, -2_000_000, 1_000_000), 1.0);
        e.set(IVec3::new(2_000_000, -2_000_000, 1_000_000), [1.0; 3]);
    }
    d.sort_leaves();
    e.sort_leaves();
    (d, e)
}

fn run(case: &str, s: &RenderSettings, d: &Grid<f32>, e: &Grid<[f32; 3]>, threads: usize) -> Vec<[f32; 4]> {
    let vol = Volume { density: Some(d), emission: Some(e) };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    // CPU time of the build alone, then of the whole render: the difference
    // is the pixel loop's.
    let c0 = cpu_seconds();
    drop(pool.install(|| Prepared::new(s, &vol)).expect("prepare"));
    let c1 = cpu_seconds();
    let img = pool.install(|| render(s, &vol, &NoProgress)).expect("render");
    let c2 = cpu_seconds();
    let loop_cpu = ((c2 - c1) - (c1 - c0)).max(0.01);
    let st = &img.stats;
    println!(
        "{case},{},{},{},{},{},{},{threads},{:.3},{:.3},{:.2},{},{},{},{:.0},{:.0},{:.0},{:.0}",
        s.render.width,
        s.render.height,
        s.render.spp,
        d.active_voxel_count(),
        st.leaves,
        st.accel_bytes / (1 << 20),
        st.build_seconds,
        st.render_seconds,
        loop_cpu,
        st.primary_rays,
        st.shadow_samples,
        st.volume_work,
        st.primary_rays as f64 / st.render_seconds,
        st.primary_rays as f64 / loop_cpu,
        st.primary_rays_per_thread_second(),
        if st.shadow_samples > 0 { st.shadow_samples_per_thread_second() } else { 0.0 },
    );
    img.pixels
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let scene = Scene::default();
    let base = |w: usize, h: usize| {
        let mut s = RenderSettings::from_scene(&scene);
        s.render.width = w;
        s.render.height = h;
        s.render.spp = 1;
        s.terrain.kind = TerrainKind::None;
        s.background.radiance = [0.0; 3];
        s
    };
    println!(
        "# machine: {} cores, load average {}",
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    println!("case,width,height,spp,active_voxels,dual_leaves,accel_MiB,threads,build_wall_s,render_wall_s,loop_cpu_s,primary_rays,shadow_samples,volume_work,primary_per_wall_s,primary_per_loop_cpu_s,primary_per_thread_s,shadow_per_thread_s");
    let (d3, e3) = curtains(3, 3, false);
    let sizes: &[(usize, usize)] = if quick { &[(320, 180), (640, 360)] } else { &[(320, 180), (640, 360), (1280, 720)] };
    // Image size, one thread.
    for &(w, h) in sizes {
        run("size", &base(w, h), &d3, &e3, 1);
    }
    // Active voxel count at 640x360, one thread: 1, 2, 3, 4 sheets, and 3 sheets twice as thick.
    for n in 1..=4 {
        let (d, e) = curtains(n, 3, false);
        run("voxels", &base(640, 360), &d, &e, 1);
    }
    let (d6, e6) = curtains(3, 6, false);
    run("voxels-thick", &base(640, 360), &d6, &e6, 1);
    // The same voxels inside a 2e6-voxel bounding box.
    let (df, ef) = curtains(3, 3, true);
    let a = run("bbox-tight", &base(640, 360), &d3, &e3, 1);
    let b = run("bbox-huge", &base(640, 360), &df, &ef, 1);
    assert_eq!(a, b, "the far voxel is out of view: identical pixels");
    // Terrain lit by the aurora: procedural heightfield, 1 shadow ray per sample.
    let mut t = base(640, 360);
    t.terrain.kind = TerrainKind::Heightfield;
    run("terrain", &t, &d3, &e3, 1);
    // Both cores.
    let (w, h) = *sizes.last().expect("sizes");
    run("threads", &base(w, h), &d3, &e3, 2);
    // Fixed-step marcher (h = half a voxel, as Cycles' default step rate) vs exact.
    let exact = run("exact", &base(640, 360), &d3, &e3, 1);
    let mut f = base(640, 360);
    f.integration = Integration::FixedStep(0.25);
    let fixed = run("fixed-0.25km", &f, &d3, &e3, 1);
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in fixed.iter().zip(&exact) {
        num += (x[1] as f64 - y[1] as f64).abs();
        den += y[1] as f64;
    }
    println!("# fixed step 0.25 km vs exact: mean |dG| / mean G = {:.3e}", num / den);
}
