//! The presets: `aurora scene --list` names them, every one prints as a
//! scene file that reads back to the same scene, and every one bakes and
//! renders at reduced size (fewer beams, a coarse footprint, 1 km voxels,
//! a small image) to a picture with light in it and, where the physics says
//! so, its colour:
//! - `type_a_red`: soft electrons stop above 200 km, where O(1D) radiates
//!   630 nm before it is quenched, so the upper half of its picture has more
//!   red than green light;
//! - `type_b_pink`: hard electrons reach 85-95 km, where O(1S) is quenched
//!   and N2 1P (red) and N2+ 1N (violet) are left, so its lower border is
//!   redder (R / G higher) than the default scene's (E0 1.5-4 keV, lower
//!   border near 105 km);
//! - `pulsating_patches`: its patches blink, so two frames 3 s apart
//!   differ pixel by pixel far more than the same scene's with the
//!   pulsation off (which moves only by its slow folds and drift);
//! - no preset's path bends tighter than half its width (no `tight bend`
//!   warning).

use crate::common::small::coarse;
use crate::common::{aurora, ok, refused};
use aurora::pipeline::bake::{bake, Bake};
use aurora::render::{render, Image, RenderSettings, Volume};
use aurora::scene::{presets, Scene, TerrainKind};
use aurora::util::progress::NoProgress;

/// The preset at test size: 1,500 beams, a 128 x 32 footprint, a 1 km
/// kernel on 1 km voxels, 96 x 54 pixels (64 x 64 for a square picture) at
/// 1 sample.
fn reduced(name: &str) -> Scene {
    // As a command loads it: `[oval]`'s arcs placed.
    let placed = aurora::pipeline::footprint::magnetic_placement::place(&presets::by_name(name).unwrap()).unwrap();
    let mut s = coarse(placed, [128, 32], 1500);
    s.beams.target_noise = 0.0;
    s.photons.radius_noise = 0.0;
    let (w, h) = if s.render.width == s.render.height { (64, 64) } else { (96, 54) };
    s.render.width = w;
    s.render.height = h;
    s.render.spp = 1;
    s
}

/// Bakes `s` and renders it; with `aurora_only`, without terrain, stars, airglow and Moon,
/// so that every pixel's light is the aurora's.
fn bake_and_render(s: &Scene, aurora_only: bool) -> (Image, Vec<String>) {
    let b = bake(s, &NoProgress).unwrap_or_else(|e| panic!("bake: {e}"));
    (render_of(s, &b, aurora_only), b.stats.warnings)
}

fn render_of(s: &Scene, b: &Bake, aurora_only: bool) -> Image {
    let mut s = s.clone();
    if aurora_only {
        s.terrain.kind = TerrainKind::None;
        s.background.stars = false;
        s.airglow.on = false;
    }
    let mut settings = RenderSettings::from_scene(&s);
    if aurora_only {
        // No Moon and no moonlit sky over a `[site]` (the bake keeps its field).
        settings.site = None;
    }
    render(&settings, &Volume { density: Some(&b.density), emission: Some(&b.emission) }, &NoProgress)
        .unwrap_or_else(|e| panic!("render: {e}"))
}

fn luminance(p: &[f32; 4]) -> f64 {
    aurora::util::colour::luminance([p[0] as f64, p[1] as f64, p[2] as f64])
}

/// Sums of R, G and B over rows `rows` of `img`.
fn rgb_of_rows(img: &Image, rows: std::ops::Range<usize>) -> [f64; 3] {
    let mut s = [0.0; 3];
    for y in rows {
        for x in 0..img.width {
            let p = img.pixel(x, y);
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
    }
    s
}

/// R / G of the lower border: climbing from the bottom row, the rows from
/// where the cumulative green first passes 2 % of the image's to where it
/// passes 15 % (the lowest light of the curtain, seen from below or the
/// side).
fn lower_border_red_over_green(img: &Image) -> f64 {
    let green: Vec<f64> = (0..img.height).map(|y| rgb_of_rows(img, y..y + 1)[1]).collect();
    let total: f64 = green.iter().sum();
    let (mut acc, mut lo, mut hi) = (0.0, None, None);
    for y in (0..img.height).rev() {
        acc += green[y];
        if lo.is_none() && acc >= 0.02 * total {
            lo = Some(y);
        }
        if acc >= 0.15 * total {
            hi = Some(y);
            break;
        }
    }
    let (lo, hi) = (lo.unwrap(), hi.unwrap());
    let s = rgb_of_rows(img, hi..lo + 1);
    s[0] / s[1]
}

#[test]
fn scene_list_names_every_preset_and_each_prints_as_its_scene() {
    let out = aurora(&["scene", "--list"]);
    ok(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    let listed: Vec<&str> = text.lines().map(|l| l.split_whitespace().next().unwrap()).collect();
    assert_eq!(listed, presets::names().collect::<Vec<_>>());
    for form in ["quiet_arc", "rayed_band", "corona", "pulsating_patches", "type_a_red", "type_b_pink", "surge"] {
        assert!(listed.contains(&form), "{form} not in {listed:?}");
    }
    for line in text.lines() {
        let name = line.split_whitespace().next().unwrap();
        assert!(line.len() > name.len() + 10, "{name} has no description: {line:?}");
        let toml = aurora(&["scene", name]);
        assert!(toml.status.success(), "aurora scene {name}");
        let back = Scene::from_toml_str(&String::from_utf8(toml.stdout).unwrap(), name).unwrap();
        assert_eq!(back, presets::by_name(name).unwrap(), "{name}");
    }
    // An unknown name is an input error naming the presets.
    let err = refused(&aurora(&["scene", "no_such_preset"]));
    assert!(err.contains("no_such_preset") && presets::names().all(|n| err.contains(n)), "{err}");
}

#[test]
fn every_preset_bakes_and_renders_with_light_in_its_picture() {
    for name in presets::names() {
        let s = reduced(name);
        let b = bake(&s, &NoProgress).unwrap_or_else(|e| panic!("{name}: bake: {e}"));
        assert!(!b.stats.warnings.iter().any(|w| w.starts_with("tight bend")), "{name}: {:?}", b.stats.warnings);
        let full = render_of(&s, &b, false);
        assert!(full.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
        // The light check on the aurora alone: a star lights one pixel
        // brighter than any aurora.
        let img = render_of(&s, &b, true);
        let lum: Vec<f64> = img.pixels.iter().map(luminance).collect();
        let max = lum.iter().cloned().fold(0.0, f64::max);
        let lit = lum.iter().filter(|&&y| y > 0.01 * max).count() as f64 / lum.len() as f64;
        println!("{name}: peak luminance {max:.4}, {:.1} % of pixels above 1 % of it", 100.0 * lit);
        // A display fills a good part of its picture: at least 2 % of the
        // pixels within a factor 100 of the brightest (a speck of light
        // would light a few of the 5,184).
        assert!(max > 1e-3 && lit > 0.02, "{name}: peak {max}, lit fraction {lit}");
    }
}

#[test]
fn type_a_is_red_above_and_type_b_pinker_below_than_the_default() {
    let (a, _) = bake_and_render(&reduced("type_a_red"), true);
    let up = rgb_of_rows(&a, 0..a.height / 2);
    println!("type_a_red, upper half: R {:.3} G {:.3} B {:.3}", up[0], up[1], up[2]);
    assert!(up[0] > up[1], "type_a_red's upper half: R {} <= G {}", up[0], up[1]);

    let (b, _) = bake_and_render(&reduced("type_b_pink"), true);
    let (d, _) = bake_and_render(&reduced("default"), true);
    let (rb, rd) = (lower_border_red_over_green(&b), lower_border_red_over_green(&d));
    println!("lower border R/G: type_b_pink {rb:.3}, default {rd:.3}");
    // Redder by a margin far above the reduced bake's noise (1,500 beams
    // over a 96-pixel-wide picture: a few per cent).
    assert!(rb > 1.2 * rd, "type_b_pink {rb} against default {rd}");
}

#[test]
fn pulsating_patches_blink_between_two_frames() {
    let change = |pulsation: f64| {
        let mut s = reduced("pulsating_patches");
        // A 3 km kernel: the diffuse aurora smooth across the 5 km between
        // the test's beams, so that what changes is the patches.
        s.photons.radius_km = 3.0;
        s.animation.pulsation = pulsation;
        // Luminance summed over blocks of 8 x 9 pixels (a patch, 40 km at
        // 100 km up, spans about 20 pixels of the 100-degree view).
        let frame = |t: f64| {
            let mut s = s.clone();
            s.animation.time_s = t;
            let img = bake_and_render(&s, true).0;
            let mut blocks = vec![0.0; (img.width / 8) * (img.height / 9)];
            for y in 0..img.height / 9 * 9 {
                for x in 0..img.width / 8 * 8 {
                    blocks[(y / 9) * (img.width / 8) + x / 8] += luminance(&img.pixel(x, y));
                }
            }
            blocks
        };
        let (a, b) = (frame(0.0), frame(3.0));
        let mean = a.iter().sum::<f64>() / a.len() as f64;
        // Mean absolute change per block, relative to the mean block.
        a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum::<f64>() / a.len() as f64 / mean
    };
    let (on, off) = (change(presets::by_name("pulsating_patches").unwrap().animation.pulsation), change(0.0));
    println!("block change over 3 s: pulsating {on:.3}, pulsation off {off:.3}");
    // Closed form (animation::pulsation): a patch's flux is
    // 1 - p w (1 - s(t)), the window w averaging 1/4 over the patch and
    // s = (1 + sin(2 pi t / T + phi)) / 2; over 3 s with T in 4-12 s and
    // phi uniform, E|s(3) - s(0)| is about 0.6, so a block on one patch
    // changes by about 0.9 x 0.25 x 0.6 / 0.89 = 0.15 of its light; blocks
    // across patch edges (where w = 0) change less. Without the pulsation
    // only the folds and the drift move (the test's 1,500 beams shift with
    // the footprint): measured 0.036, against 0.096 with it.
    assert!(on > 0.06 && on > 2.0 * off, "pulsating {on}, off {off}");
}
