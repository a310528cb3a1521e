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
    for (axis, name) in [(1, "front"), (2, "top"), (0, "side")] {
        project(&b.emission, axis, &Path::new(&dir).join(format!("{name}.png")), gain);
    }
}
