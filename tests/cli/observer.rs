//! `[colour] observer` seen in pictures, and the camera's place against the
//! terrain: the camera records the green line green where the CIE 1931 eye
//! puts it at a yellow-green; a camera inside the ground is refused by
//! `render` and `preview` naming both heights, and only warned of by
//! `bake`, which never reads the terrain.

use crate::common::{ok, refused, scratch, Aurora};

/// The 8-bit sRGB pixels of a PNG.
fn png_pixels(path: &std::path::Path) -> Vec<[u8; 3]> {
    let file = std::fs::File::open(path).expect("png");
    let mut dec = png::Decoder::new(std::io::BufReader::new(file));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().expect("png parses");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("png decodes");
    let ch = info.color_type.samples();
    buf[..info.buffer_size()].chunks(ch).map(|p| [p[0], p[1], p[2]]).collect()
}

/// HSV hue (degrees) and saturation of an encoded pixel.
fn hue_saturation(p: [u8; 3]) -> (f64, f64) {
    aurora::util::colour::hsv_hue_saturation(p.map(|c| c as f64 / 255.0))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median hue and saturation of the curtain in quiet_arc's AgX picture
/// (the pixels above 20 % of the brightest's value) for `observer`.
fn curtain_hue(observer: &str) -> (f64, f64, usize) {
    let dir = scratch("observer", observer);
    let png = dir.join("arc.png");
    // No stars (white points), no airglow (the sky's own lines) and no air
    // density in the volume: the curtain alone.
    let sets = ["background.stars=false", "airglow.on=false", "grid.density_a=0", "beams.count=4000"];
    let mut cmd = Aurora::new().args(["render", "quiet_arc", "--size", "240x135", "--spp", "2", "--threads", "2", "-q", "--png"]).arg(&png);
    for s in sets.iter().map(|s| s.to_string()).chain([format!("colour.observer={observer}")]) {
        cmd = cmd.args(["--set", &s]);
    }
    ok(&cmd.output());
    let px = png_pixels(&png);
    let value = |p: &[u8; 3]| *p.iter().max().unwrap() as f64;
    let peak = px.iter().map(value).fold(0.0, f64::max);
    let lit: Vec<[u8; 3]> = px.iter().copied().filter(|p| value(p) > 0.2 * peak).collect();
    let hs: Vec<(f64, f64)> = lit.iter().map(|p| hue_saturation(*p)).collect();
    (median(hs.iter().map(|h| h.0).collect()), median(hs.iter().map(|h| h.1).collect()), lit.len())
}

#[test]
fn the_camera_records_the_green_line_green_and_the_eye_yellow_green() {
    // Photographs of 557.7 nm-dominated arcs are green, hue 120-140 degrees
    // (docs/colour.md). The medians are over hundreds of pixels of a smooth
    // arc: the sampling noise moves them by a degree or two, far inside the
    // 110-170 window; the eye's gamut-mapped yellow-green sits near 75-85.
    let (hue, sat, n) = curtain_hue("camera");
    assert!(n > 200, "{n} curtain pixels");
    assert!((110.0..=170.0).contains(&hue) && sat >= 0.5, "camera: median hue {hue:.1}, saturation {sat:.2} over {n} pixels");
    let (hue, sat, n) = curtain_hue("eye");
    assert!(n > 200 && !(110.0..=170.0).contains(&hue), "eye: median hue {hue:.1}, saturation {sat:.2} over {n} pixels");
}

#[test]
fn a_camera_inside_the_terrain_is_refused_by_render_and_preview_and_bake_warns() {
    let dir = scratch("observer", "inside");
    // The default scene's mountains rise to 1.58 km over (-10, 40) km.
    let inside = "camera.position=[-10, 40, 0.5]";
    let want = |e: &str| {
        assert!(
            e.contains("camera.position = [-10, 40, 0.5]")
                && e.contains("height above the ground is -1.0828 km")
                && e.contains("0.5000 km")
                && e.contains("below the terrain's 1.5828 km"),
            "{e}"
        );
    };
    let png = dir.join("r.png");
    let e = refused(&Aurora::new().args(["render", "--set", inside, "--png"]).arg(&png).output());
    want(&e);
    assert!(!png.exists(), "nothing written");
    let e = refused(&Aurora::new().args(["preview", "--set", inside, "--out"]).arg(dir.join("p.png")).output());
    want(&e);
    assert!(!dir.join("p.png").exists());
    // Bake: a warning, and the bake goes on (a small one).
    let out = dir.join("bake");
    let o = Aurora::new()
        .args(["bake", "--set", inside, "--set", "beams.count=300", "--set", "grid.voxel_size=2.0", "-q", "--threads", "2", "--out"])
        .arg(&out)
        .output();
    let e = ok(&o);
    assert!(e.contains("aurora: warning: camera.position") && e.contains("below the terrain's 1.5828 km"), "{e}");
    assert!(out.join("aurora.vdb").is_file());
    // Above the ground: no refusal, no warning (render checked at 1 spp).
    let above = "camera.position=[-10, 40, 1.7]";
    let o = Aurora::new()
        .args(["bake", "--set", above, "--set", "beams.count=300", "--set", "grid.voxel_size=2.0", "-q", "--threads", "2", "--out"])
        .arg(dir.join("bake2"))
        .output();
    assert!(!ok(&o).contains("below the terrain"));
}
