//! The look of the default picture at the default white balance, as the
//! photographs it is compared with show a night sky: the zenith's sky
//! blue-grey (a hue of 190-250 degrees where it is above 2 % of display
//! white), the aurora's core green (110-170 degrees); and `render.exposure
//! = "auto"`: the EV it metered printed and in the PNG's and the EXR's
//! metadata, with the white balance.
//!
//! The hue is the HSV hue of the PNG's 8-bit code values (the display's),
//! as a photograph's is read. Photographs of aurora at 3200-4000 K show
//! the sky blue and the green line green to cyan-green (docs/colour.md).

use crate::common::{aurora, ok, scratch};
use std::path::Path;

/// The PNG's pixels in [0, 1] and its size.
fn read_png(path: &Path) -> (Vec<[f64; 3]>, usize, usize) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.color_type, info.bit_depth), (png::ColorType::Rgb, png::BitDepth::Eight));
    let px = buf[..info.buffer_size()].chunks(3).map(|c| [c[0] as f64 / 255.0, c[1] as f64 / 255.0, c[2] as f64 / 255.0]).collect();
    (px, info.width as usize, info.height as usize)
}

fn png_text(path: &Path, key: &str) -> String {
    let reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap())).read_info().unwrap();
    let info = reader.info();
    info.uncompressed_latin1_text.iter().find(|t| t.keyword == key).map(|t| t.text.clone()).unwrap_or_else(|| panic!("no {key} chunk"))
}

fn hue(c: [f64; 3]) -> f64 {
    aurora::util::colour::hsv_hue_saturation(c).0
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The default scene at 320 x 180 (its exposure and view): the aurora's
/// core, the 3 % brightest pixels of the upper two thirds (the arcs; the
/// ground and its lit snow below), has a median hue in 110-170 degrees.
/// Looking straight up from the default camera (20 degrees wide, stars
/// off), the zenith's sky, above 2 % of white, has a hue in 190-250.
/// Measured: 163 and 195 at 3200 K; at daylight white balance (5500 K)
/// the sky is brown-yellow, hue 46, and the test fails; so is a sky of
/// the airglow's lines alone (no broadband light: hue 74).
#[test]
fn the_default_sky_is_blue_and_its_aurora_green_at_the_default_white_balance() {
    let d = scratch("sky_colour", "default");
    let pic = d.join("default.png");
    ok(&aurora(&["render", "--png", pic.to_str().unwrap(), "--size", "320x180", "--spp", "4", "--quiet"]));
    let (px, w, h) = read_png(&pic);
    let luma = |c: &[f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let top: Vec<[f64; 3]> = px[..w * (2 * h / 3)].to_vec();
    let mut l: Vec<f64> = top.iter().map(luma).collect();
    l.sort_by(f64::total_cmp);
    let cut = l[(0.97 * l.len() as f64) as usize];
    let core = median(top.iter().filter(|c| luma(c) >= cut).map(|c| hue(*c)).collect());
    assert!((110.0..170.0).contains(&core), "aurora core hue {core}");

    let up = d.join("zenith.png");
    ok(&aurora(&[
        "render",
        "--png",
        up.to_str().unwrap(),
        "--size",
        "32x32",
        "--spp",
        "1",
        "--quiet",
        "--set",
        "camera.look_at=[0.0, -90.0, 100.0]",
        "--set",
        "camera.up=[0.0, 1.0, 0.0]",
        "--set",
        "camera.fov_deg=20.0",
        "--set",
        "background.stars=false",
    ]));
    let (px, w, h) = read_png(&up);
    let centre: Vec<[f64; 3]> =
        (h / 2 - 2..h / 2 + 2).flat_map(|y| (w / 2 - 2..w / 2 + 2).map(move |x| (x, y))).map(|(x, y)| px[y * w + x]).collect();
    let mean = [0, 1, 2].map(|k| centre.iter().map(|c| c[k]).sum::<f64>() / centre.len() as f64);
    assert!(mean.iter().cloned().fold(0.0, f64::max) > 0.02, "the zenith is black: {mean:?}");
    let h = hue(mean);
    assert!((190.0..250.0).contains(&h), "zenith sky {mean:?}: hue {h}");
}

/// `render.exposure = "auto"`: the EV metered is printed, and the PNG and
/// the EXR record it and the white balance; the PNG is the one a fixed
/// exposure at that EV gives (to the printed precision: the pixels of the
/// two differ by at most 1 code value).
#[test]
fn auto_exposure_prints_and_records_the_ev_it_metered() {
    let d = scratch("sky_colour", "auto");
    let (exr, pic) = (d.join("a.exr"), d.join("a.png"));
    let base = ["--size", "96x54", "--spp", "1", "--set", "beams.count=4000"];
    let mut args = vec!["render", "--out", exr.to_str().unwrap(), "--png", pic.to_str().unwrap(), "--set", "render.exposure=\"auto\""];
    args.extend(base);
    let err = ok(&aurora(&args));
    let line = err.lines().find(|l| l.starts_with("exposure: auto, metered ")).unwrap_or_else(|| panic!("{err}"));
    let ev: f64 = line["exposure: auto, metered ".len()..].split_whitespace().next().unwrap().parse().unwrap();
    assert!(ev.is_finite() && ev.abs() < 20.0, "{ev}");
    let text = png_text(&pic, "aurora_exposure_ev");
    let recorded: f64 = text.split_whitespace().next().unwrap().parse().unwrap();
    assert!((recorded - ev).abs() < 0.006 && text.contains("metered"), "{text} vs {ev}");
    assert!(png_text(&pic, "aurora_white_balance").starts_with("3200 K"));
    let attrs = aurora::render::image_file::read_exr_text_attributes(&exr).unwrap();
    assert!(attrs.iter().any(|(k, v)| k == "aurora_exposure_ev" && v.contains("metered")), "{attrs:?}");
    // The same picture at the metered EV given as a number.
    let fixed = d.join("fixed.png");
    let ev_text: String = text.split_whitespace().next().unwrap().to_string();
    let set = format!("render.exposure={ev_text}");
    let mut args = vec!["render", "--png", fixed.to_str().unwrap(), "--set", set.as_str(), "--quiet"];
    args.extend(base);
    ok(&aurora(&args));
    let ((a, _, _), (b, _, _)) = (read_png(&pic), read_png(&fixed));
    let worst = a.iter().zip(&b).flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs())).fold(0.0, f64::max);
    assert!(worst <= 1.5 / 255.0, "{worst}");
}

/// The add-on's copy of the camera observer (`blender/camera_observer.json`:
/// the table's matrix and its Rec.709 per nm, from which `blender/display.py`
/// computes the same white balance) is the binary's, number for number;
/// `AURORA_UPDATE_DOCS=1` rewrites it.
#[test]
fn the_add_ons_camera_table_is_the_binarys() {
    use aurora::util::observer::{camera_matrix, Observer, CAMERA_RANGE_NM};
    let (a, b) = (CAMERA_RANGE_NM.0 as u32, CAMERA_RANGE_NM.1 as u32);
    let rgb: Vec<[f64; 3]> = (a..=b).map(|l| Observer::Camera.rgb(l as f64)).collect();
    let doc = serde_json::json!({
        "about": "The camera observer of aurora (src/util/observer.rs, data/observer_camera.csv): its 3x3 matrix (rows) and its linear Rec.709 per nm; blender/display.py computes the white balance from it. Written by tests/render/sky_colour.rs.",
        "first_nm": a,
        "matrix": camera_matrix(),
        "rgb": rgb,
        "white_balance_3200": aurora::util::white_balance::camera_white_balance(3200.0),
    });
    let text = serde_json::to_string_pretty(&doc).unwrap() + "\n";
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("blender/camera_observer.json");
    if std::env::var_os("AURORA_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(committed == text, "{} is stale: AURORA_UPDATE_DOCS=1 cargo test --release --test render sky_colour::", path.display());
}
