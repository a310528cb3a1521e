//! Smoothness benchmark: how far the
//! default bake's picture is from a converged one, and what the new
//! estimators cost, measured side by side in one run.
//!
//! The scene is the default preset with the build's settings written out: 8000
//! beams (no noise target), 0.5 km kernel and voxels, no pruning, rendered
//! volume only (no terrain, black sky) at 320x180, 16 samples per pixel.
//! Each estimator ("new": the scene's defaults, whatever `beams.deposition`
//! default the build has, segment kernels, stratified starts; "old": point
//! kernels, random starts, and `beams.deposition = "sampled"` where the build
//! has that key) is baked at 8000 beams and at `factor` times as many (the
//! reference), and both are rendered. Printed: the mean relative difference
//! per pixel (luminance, pixels above 1 % of the reference's peak, as
//! `tools/cycles/compare.py`) of each 8000-beam picture against its own
//! estimator's reference, the new picture against the old reference, and the bake times
//! (the fastest of `runs` alternating bakes of each, so load from other jobs
//! hits both alike) and their ratio, in wall time and in CPU time (on a
//! shared machine the wall time moves with the other jobs' load; the CPU
//! time is the work done). Targets: 5 % and 1.5x.
//!
//! cargo run --release --example smoothness_bench -- [--factor 16] [--runs 3] [--out DIR] [--time-only] [--gather kdtree|splat]
//!
//! `--time-only` stops after the bake times (no references, no pictures).
//! `--gather` overrides the new estimators' gather (default: the scene's).
//! The old estimators always gather with the kd-tree, their own default.
//!
//! With `--out`, writes `smoothness.json`, `smoothness.txt` and the four
//! pictures (PNG) there.

use aurora::util::fmath;

mod common;

use aurora::app::bench::metrics::image_rel_error;
use aurora::pipeline::bake::{self, Bake};
use aurora::render::{self, RenderSettings, Volume};
use aurora::scene::{GatherMethod, Scene, TerrainKind, VoxelSize};
use aurora::util::progress::NoProgress;
use common::cpu_seconds;
use std::time::Instant;

/// The default scene with the build's settings written out.
fn base_scene(beams: usize) -> Scene {
    let mut s = Scene::load("default").expect("default preset");
    s.beams.count = beams;
    s.beams.target_noise = 0.0;
    s.photons.radius_km = 0.5;
    s.grid.voxel_size = VoxelSize::Km(0.5);
    s.grid.prune = 0.0;
    s.render.width = 320;
    s.render.height = 180;
    s.render.spp = 16;
    s.terrain.kind = TerrainKind::None;
    s.background.radiance = [0.0; 3];
    s
}

/// A bake, its wall time and its CPU time. On a shared machine the wall time
/// depends on the other jobs; the CPU time much less (it is the work done).
fn bake_timed(s: &Scene) -> (Bake, f64, f64) {
    let (t, c) = (Instant::now(), cpu_seconds());
    let b = bake::bake(s, &NoProgress).unwrap_or_else(|e| {
        eprintln!("bake failed: {e}");
        std::process::exit(1);
    });
    (b, t.elapsed().as_secs_f64(), cpu_seconds() - c)
}

fn render(s: &Scene, b: &Bake) -> render::Image {
    let settings = RenderSettings::from_scene(s);
    let vol = Volume { density: Some(&b.density), emission: Some(&b.emission) };
    render::render(&settings, &vol, &NoProgress).unwrap_or_else(|e| {
        eprintln!("render failed: {e}");
        std::process::exit(1);
    })
}

fn write_png(path: &std::path::Path, img: &render::Image, scale: f64) {
    // Linear luminance scaled so the reference's peak is 1, sRGB-encoded.
    let enc = |x: f64| {
        let x = (x * scale).clamp(0.0, 1.0);
        let v = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * fmath::powf(x, 1.0 / 2.4) - 0.055 };
        (v * 255.0 + 0.5) as u8
    };
    let mut data = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        data.extend([enc(p[0] as f64), enc(p[1] as f64), enc(p[2] as f64)]);
    }
    let f = std::fs::File::create(path).expect("create png");
    let mut e = png::Encoder::new(std::io::BufWriter::new(f), img.width as u32, img.height as u32);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header().and_then(|mut w| w.write_image_data(&data)).expect("write png");
}

fn main() {
    let mut factor = 16usize;
    let mut runs = 3usize;
    let mut out: Option<std::path::PathBuf> = None;
    let mut time_only = false;
    let mut gather: Option<GatherMethod> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut val = |name: &str| {
            args.next().unwrap_or_else(|| {
                eprintln!("{name} needs a value");
                std::process::exit(2)
            })
        };
        match a.as_str() {
            "--factor" => factor = val("--factor").parse().unwrap_or(0),
            "--runs" => runs = val("--runs").parse().unwrap_or(0),
            "--out" => out = Some(val("--out").into()),
            "--time-only" => time_only = true,
            "--gather" => {
                gather = Some(match val("--gather").as_str() {
                    "kdtree" => GatherMethod::Kdtree,
                    "splat" => GatherMethod::Splat,
                    g => {
                        eprintln!("--gather {g}: allowed kdtree, splat");
                        std::process::exit(2)
                    }
                })
            }
            _ => {
                eprintln!("usage: smoothness [--factor N (>= 2)] [--runs N (>= 1)] [--out DIR] [--time-only] [--gather kdtree|splat]");
                std::process::exit(2);
            }
        }
    }
    if factor < 2 || runs < 1 {
        eprintln!("--factor must be at least 2 and --runs at least 1");
        std::process::exit(2);
    }
    let beams = 8000;
    let mut new = base_scene(beams);
    if let Some(g) = gather {
        new.photons.gather = g;
    }
    let old = aurora::app::bench::harness::old_estimators(&new);
    let scaled = |s: &Scene| Scene { beams: aurora::scene::BeamParams { count: beams * factor, ..s.beams.clone() }, ..s.clone() };
    let threads = rayon::current_num_threads();
    let load0 = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let t0 = Instant::now();
    // The commit when the run starts (the tree may move while it runs).
    let commit = std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());

    // Bake times: alternate old and new, keep the fastest of each.
    let (mut t_new, mut t_old) = (f64::INFINITY, f64::INFINITY);
    let (mut c_new, mut c_old) = (f64::INFINITY, f64::INFINITY);
    let (mut b_new, mut b_old) = (None, None);
    for _ in 0..runs {
        let (b, t, c) = bake_timed(&old);
        (t_old, c_old) = (t_old.min(t), c_old.min(c));
        b_old = Some(b);
        let (b, t, c) = bake_timed(&new);
        (t_new, c_new) = (t_new.min(t), c_new.min(c));
        b_new = Some(b);
    }
    let (b_new, b_old) = (b_new.unwrap(), b_old.unwrap());
    if time_only {
        let g = |b: &Bake| (b.stats.times_s.beams, b.stats.times_s.gather);
        println!("bake time at {beams} beams, fastest of {runs}: wall new {t_new:.2} s (beams, gather of the last: {:?}), old {t_old:.2} s ({:?}), ratio {:.2}; CPU new {c_new:.2} s, old {c_old:.2} s, ratio {:.2}", g(&b_new), g(&b_old), t_new / t_old, c_new / c_old);
        return;
    }
    let (r_new, t_ref_new, _) = bake_timed(&scaled(&new));
    let (r_old, t_ref_old, _) = bake_timed(&scaled(&old));
    let (i_new, i_old) = (render(&new, &b_new), render(&old, &b_old));
    let (i_ref_new, i_ref_old) = (render(&new, &r_new), render(&old, &r_old));
    let floor = 0.01;
    let (e_new, f_new) = image_rel_error(&i_new.pixels, &i_ref_new.pixels, floor);
    let (e_old, f_old) = image_rel_error(&i_old.pixels, &i_ref_old.pixels, floor);
    let (e_cross, f_cross) = image_rel_error(&i_new.pixels, &i_ref_old.pixels, floor);
    let (e_refs, f_refs) = image_rel_error(&i_ref_new.pixels, &i_ref_old.pixels, floor);
    let ratio = t_new / t_old;
    let cpu_ratio = c_new / c_old;
    let load1 = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let dep = |s: &Scene| {
        let v: toml::Table = toml::from_str(&s.to_toml()).unwrap_or_default();
        v.get("beams")
            .and_then(|b| b.get("deposition"))
            .map(|d| d.to_string())
            .unwrap_or_else(|| "(no key: one sampled energy per beam)".into())
    };
    let lines = vec![
        format!("smoothness benchmark: default scene, {beams} beams vs {}x, 0.5 km kernel and voxels, no pruning, volume only, 320x180, 16 spp", factor),
        format!("threads {threads}; load average before: {}; after: {}", load0.trim(), load1.trim()),
        format!(
            "new estimators: kernel {:?}, gather {:?}, starts {:?}, deposition {}",
            new.photons.kernel,
            new.photons.gather,
            new.beams.starts,
            dep(&new)
        ),
        format!(
            "old estimators: kernel {:?}, gather {:?}, starts {:?}, deposition {}",
            old.photons.kernel,
            old.photons.gather,
            old.beams.starts,
            dep(&old),
        ),
        format!("mean relative difference per pixel vs {factor}x beams (same estimator): new {:.1} % (flux ratio {f_new:.4}), old {:.1} % (flux ratio {f_old:.4}); target <= 5 %", 100.0 * e_new, 100.0 * e_old),
        format!("new {beams}-beam picture vs old {factor}x reference: {:.1} % (flux {f_cross:.4}); new vs old {factor}x references: {:.1} % (flux {f_refs:.4})", 100.0 * e_cross, 100.0 * e_refs),
        format!("bake time at {beams} beams, fastest of {runs}: wall new {t_new:.2} s, old {t_old:.2} s, ratio {ratio:.2}; CPU new {c_new:.2} s, old {c_old:.2} s, ratio {cpu_ratio:.2}; target <= 1.5"),
        format!(
            "new: {} photons, gather {:.2} s, beams {:.2} s; old: {} photons, gather {:.2} s, beams {:.2} s",
            b_new.stats.photons, b_new.stats.times_s.gather, b_new.stats.times_s.beams, b_old.stats.photons, b_old.stats.times_s.gather, b_old.stats.times_s.beams
        ),
        format!("references ({} beams): new {t_ref_new:.1} s, old {t_ref_old:.1} s; total wall {:.0} s", beams * factor, t0.elapsed().as_secs_f64()),
    ];
    for l in &lines {
        println!("{l}");
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(&dir).expect("create --out");
        std::fs::write(dir.join("smoothness.txt"), lines.join("\n") + "\n").expect("write txt");
        let json = serde_json::json!({
            "beams": beams, "factor": factor, "runs": runs, "threads": threads,
            "loadavg_start": load0.trim(), "loadavg_end": load1.trim(),
            "new": {"kernel": format!("{:?}", new.photons.kernel), "gather": format!("{:?}", new.photons.gather), "starts": format!("{:?}", new.beams.starts), "deposition": dep(&new),
                    "mean_rel_vs_ref": e_new, "flux_vs_ref": f_new, "bake_s": t_new, "ref_bake_s": t_ref_new, "photons": b_new.stats.photons},
            "old": {"kernel": format!("{:?}", old.photons.kernel), "gather": format!("{:?}", old.photons.gather), "starts": format!("{:?}", old.beams.starts), "deposition": dep(&old),
                    "mean_rel_vs_ref": e_old, "flux_vs_ref": f_old, "bake_s": t_old, "ref_bake_s": t_ref_old, "photons": b_old.stats.photons},
            "new_vs_old_ref": e_cross, "refs_new_vs_old": e_refs,
            "bake_time_ratio": ratio, "bake_cpu_ratio": cpu_ratio, "bake_cpu_s": {"new": c_new, "old": c_old},
            "git_commit": commit,
        });
        std::fs::write(dir.join("smoothness.json"), serde_json::to_string_pretty(&json).unwrap() + "\n").expect("write json");
        let lum = |p: &[f32; 4]| aurora::util::colour::luminance([p[0] as f64, p[1] as f64, p[2] as f64]);
        let peak = i_ref_new.pixels.iter().map(lum).fold(0.0, f64::max).max(1e-30);
        for (name, img) in [("new", &i_new), ("old", &i_old), ("new_ref", &i_ref_new), ("old_ref", &i_ref_old)] {
            write_png(&dir.join(format!("{name}.png")), img, 1.0 / peak);
        }
    }
}
