//! The default's aurora stands above its sky as in photographs: in the
//! default's own camera, with the sky it renders (the airglow's lines and
//! the air; stars off, and no terrain, which is not sky), the aurora's
//! 99th-percentile pixel is at least 20x the median sky pixel above the
//! horizon. The aurora is the render less the same render with
//! `volume.emission_scale = 0`, in linear luminance (docs/testing.md,
//! "Aurora over the sky"). Photographs of active displays show 20-200
//! (docs/physics.md, "Arcs: a body and filaments").

use aurora::geometry::camera::CameraModel;
use aurora::pipeline::bake::bake;
use aurora::render::{render, RenderSettings, Volume};
use aurora::scene::{Scene, TerrainKind};
use aurora::util::progress::NoProgress;

/// The luminance of every pixel of `s`'s render of `b` whose ray looks
/// above the horizon, in pixel order.
fn above_horizon(s: &Scene, b: &aurora::pipeline::bake::Bake) -> Vec<f64> {
    let img =
        render(&RenderSettings::from_scene(s), &Volume { density: Some(&b.density), emission: Some(&b.emission) }, &NoProgress).unwrap();
    let cam = CameraModel::new(&s.camera, s.render.width, s.render.height).unwrap();
    let mut out = Vec::new();
    for y in 0..img.height {
        for x in 0..img.width {
            let Some(ray) = cam.ray_at(x as f64 + 0.5, y as f64 + 0.5) else { continue };
            if ray.dir.z > 0.0 {
                let p = img.pixel(x, y);
                out.push(aurora::util::colour::luminance([p[0] as f64, p[1] as f64, p[2] as f64]));
            }
        }
    }
    out
}

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

#[test]
fn the_default_aurora_stands_twenty_times_above_its_sky() {
    let mut s = Scene::load("default").unwrap();
    s.background.stars = false;
    s.terrain.kind = TerrainKind::None;
    // A quarter of the default's pixels and samples: percentiles of
    // thousands of pixels, not single ones.
    s.render.width /= 4;
    s.render.height /= 4;
    s.render.spp = 4;
    let b = bake(&s, &NoProgress).unwrap();
    let all = above_horizon(&s, &b);
    let mut dark = s.clone();
    dark.volume.emission_scale = 0.0;
    let sky = above_horizon(&dark, &b);
    let aurora: Vec<f64> = all.iter().zip(&sky).map(|(a, s)| a - s).collect();
    let (p99, median) = (percentile(&aurora, 0.99), percentile(&sky, 0.5));
    eprintln!("aurora 99th percentile {p99:.4e}, sky median {median:.4e}: {:.1}x over {} pixels", p99 / median, sky.len());
    assert!(p99 >= 20.0 * median, "{:.1}x", p99 / median);
}
