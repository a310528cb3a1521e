//! Throwaway debugging aid (not the renderer): bakes a scene, prints the
//! stats and an altitude profile, and writes orthographic projections of the
//! emission (sum along an axis) as PNGs to the folder given (default /tmp/aur).
//!
//! cargo run --release --example bake_debug -- [scene.toml|default|seed2014] [out_dir]
use aurora::grid::Grid;
use std::path::Path;

fn project(g: &Grid<[f32; 3]>, axis: usize, out: &Path, gain: f64) {
    let (lo, hi) = g.index_bbox().unwrap();
    let (a, b) = match axis { 0 => (1, 2), 1 => (0, 2), _ => (0, 1) };
    let w = (hi[a] - lo[a] + 1) as usize;
    let h = (hi[b] - lo[b] + 1) as usize;
    let mut img = vec![[0.0f64; 3]; w * h];
    let vs = g.transform.voxel_size;
    for (ijk, v) in g.iter_active() {
        let x = (ijk[a] - lo[a]) as usize;
        let y = (hi[b] - ijk[b]) as usize;
        for k in 0..3 { img[y * w + x][k] += v[k] as f64 * vs; }
    }
    let mut lum: Vec<f64> = img.iter().map(|c| aurora::spectrum::luminance(*c)).filter(|&y| y > 0.0).collect();
    lum.sort_by(|a, b| a.total_cmp(b));
    let p = lum[(lum.len() as f64 * 0.995) as usize];
    let srgb = |x: f64| { let x = x.clamp(0.0, 1.0); if x <= 0.0031308 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 } };
    let bytes: Vec<u8> = img.iter().flat_map(|c| c.map(|x| (srgb(x * gain / p) * 255.0).round() as u8)).collect();
    let f = std::fs::File::create(out).unwrap();
    let mut e = png::Encoder::new(std::io::BufWriter::new(f), w as u32, h as u32);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header().unwrap().write_image_data(&bytes).unwrap();
    println!("{}: {w}x{h}, 99.5% luminance {p:.4} kR", out.display());
}

/// Emission integrated along camera rays (nearest voxel, 0.25 voxel steps):
/// a rough look through the scene camera, not the renderer.
fn camera_view(scene: &aurora::scene::Scene, g: &Grid<[f32; 3]>, out: &Path, gain: f64) {
    use glam::DVec3;
    let (w, h) = (480usize, 270usize);
    let c = &scene.camera;
    let pos = DVec3::from(c.position);
    let fwd = (DVec3::from(c.look_at) - pos).normalize();
    let right = fwd.cross(DVec3::from(c.up)).normalize();
    let up = right.cross(fwd);
    let tan = (c.fov_deg.to_radians() * 0.5).tan();
    let vs = g.transform.voxel_size;
    let (lo, hi) = g.index_bbox().unwrap();
    let (wlo, whi) = (lo.as_dvec3() * vs - 1.0, hi.as_dvec3() * vs + 1.0);
    use rayon::prelude::*;
    let img: Vec<[f64; 3]> = (0..w * h).into_par_iter().map(|k| {
        let (i, j) = (k % w, k / w);
        let x = (2.0 * (i as f64 + 0.5) / w as f64 - 1.0) * tan * w as f64 / h as f64;
        let y = (1.0 - 2.0 * (j as f64 + 0.5) / h as f64) * tan;
        let d = (fwd + right * x + up * y).normalize();
        // Slab intersection with the grid's bounds.
        let (mut t0, mut t1) = (0.0f64, 1e9f64);
        for a in 0..3 {
            let inv = 1.0 / d[a];
            let (ta, tb) = ((wlo[a] - pos[a]) * inv, (whi[a] - pos[a]) * inv);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        let mut acc = [0.0f64; 3];
        let step = 0.25 * vs;
        let mut t = t0;
        while t < t1 {
            let p = (pos + d * t) / vs;
            let v = g.get(p.round().as_ivec3());
            for q in 0..3 { acc[q] += v[q] as f64 * step; }
            t += step;
        }
        acc
    }).collect();
    let mut lum: Vec<f64> = img.iter().map(|c| aurora::spectrum::luminance(*c)).filter(|&y| y > 0.0).collect();
    lum.sort_by(|a, b| a.total_cmp(b));
    let p = lum[(lum.len() as f64 * 0.995) as usize];
    let srgb = |x: f64| { let x = x.clamp(0.0, 1.0); if x <= 0.0031308 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 } };
    let bytes: Vec<u8> = img.iter().flat_map(|c| c.map(|x| (srgb(x * gain / p) * 255.0).round() as u8)).collect();
    let f = std::fs::File::create(out).unwrap();
    let mut e = png::Encoder::new(std::io::BufWriter::new(f), w as u32, h as u32);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header().unwrap().write_image_data(&bytes).unwrap();
    println!("{}: {w}x{h}, 99.5% {p:.3} kR, max {:.3} kR", out.display(), lum[lum.len() - 1]);
}

fn main() {
    let arg = std::env::args().nth(1).unwrap_or("default".into());
    let dir = std::env::args().nth(2).unwrap_or("/tmp/aur".into());
    let gain: f64 = std::env::var("GAIN").ok().and_then(|g| g.parse().ok()).unwrap_or(1.0);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = aurora::scene::Scene::load(&arg).unwrap();
    let b = aurora::bake::bake(&scene, &aurora::progress::NoProgress).unwrap();
    println!("{}", serde_json::to_string_pretty(&b.stats).unwrap());
    // Altitude profile: emission summed per 10 km band.
    let vs = b.stats.voxel_size_km;
    let mut bands = vec![[0.0f64; 3]; 40];
    for (ijk, v) in b.emission.iter_active() {
        let z = ijk.z as f64 * vs;
        let i = ((z / 10.0) as usize).min(39);
        for k in 0..3 { bands[i][k] += v[k] as f64 * vs * vs * vs; }
    }
    for (i, c) in bands.iter().enumerate() {
        let y = aurora::spectrum::luminance(*c);
        if y > 0.0 { println!("{:4}-{:<4} km  Y {:10.3e}  rgb/Y {:.2} {:.2} {:.2}", i * 10, i * 10 + 10, y, c[0] / y, c[1] / y, c[2] / y); }
    }
    camera_view(&scene, &b.emission, &Path::new(&dir).join("camera.png"), gain);
    for (axis, name) in [(1, "front"), (2, "top"), (0, "side")] {
        project(&b.emission, axis, &Path::new(&dir).join(format!("{name}.png")), gain);
    }
}
