//! `aurora sky`: the airglow and stars map for Blender's world. It writes
//! an equirectangular EXR of the asked width (height half of it), its top
//! row the zenith's airglow, its bottom row the solid Earth (black, the
//! stars off); bad input
//! (an odd or out-of-range width, a name that is not .exr, an out-of-range
//! `[airglow]` key) exits 2 naming it, and writes nothing.

use crate::common::child::{aurora, ok, refused};
use crate::common::scratch;

#[test]
fn sky_writes_the_map_and_refuses_bad_input() {
    let d = scratch("sky", "map");
    let out = d.join("sky.exr");
    let o = out.to_str().unwrap();
    ok(&aurora(&["sky", "default", "--out", o, "--width", "64", "--set", "background.stars=false", "--quiet"]));
    let img = aurora::render::image_file::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (64, 32));
    // Top row: the sky overhead (about 1.06 in green with the air: the
    // airglow's lines, the broadband light and the air's scattering of
    // them, docs/physics.md); bottom row: under the ground, nothing.
    let top = img.pixels[..64].iter().map(|p| p[1]).sum::<f32>() / 64.0;
    assert!((0.5..2.0).contains(&top), "{top}");
    assert!(img.pixels[31 * 64..].iter().all(|p| p[..3] == [0.0; 3]));

    for (args, names) in [
        (vec!["--width", "63"], "--width 63"),
        (vec!["--width", "4"], "--width 4"),
        (vec!["--set", "airglow.green_r=-1"], "airglow.green_r"),
    ] {
        let bad = d.join("bad.exr");
        let mut a = vec!["sky", "default", "--out", bad.to_str().unwrap(), "--quiet"];
        a.extend(args);
        let e = refused(&aurora(&a));
        assert!(e.contains(names), "{e}");
        assert!(!bad.exists());
    }
    let e = refused(&aurora(&["sky", "default", "--out", d.join("sky.png").to_str().unwrap()]));
    assert!(e.contains(".exr"), "{e}");
    let e = refused(&aurora(&["sky", "default", "--out", o, "--set", "airglow.scale=1000", "--quiet"]));
    assert!(e.contains("airglow.scale") && e.contains("1000") && e.contains("[0, 100]"), "{e}");
}

/// `[site]` through the command line: the `tromso` preset's sky map holds
/// the Moon (the map's brightest pixel, where the site's Moon stands: 2026-12-18
/// 18:00 UTC, azimuth 184.7, elevation 29.1 by skyfield) and the real
/// stars; a Sun above -12 degrees is warned of, naming its elevation; a
/// `[site]` without its hour, or with one that is no RFC 3339 time, is
/// refused naming the key, exit 2, nothing written.
#[test]
fn a_site_gives_the_moon_where_it_stands_and_bad_hours_are_refused() {
    let d = scratch("sky", "site");
    let out = d.join("sky.exr");
    let o = out.to_str().unwrap();
    let r = aurora(&["sky", "tromso", "--out", o, "--width", "720", "--quiet"]);
    ok(&r);
    assert!(!String::from_utf8_lossy(&r.stderr).contains("the Sun is"), "a night scene warned of the Sun");
    let img = aurora::render::image_file::read_exr(&out).unwrap();
    let (w, h) = (img.width, img.height);
    let (i, _) = img.pixels.iter().enumerate().max_by(|a, b| a.1[1].total_cmp(&b.1[1])).unwrap();
    // The map's layout (`aurora::render::sky`): u = 1/2 - atan2(y, x) / 2 pi,
    // v = 1/2 + el / pi, so azimuth (from north through east) = 90 - (1/2 - u) 360.
    let (u, v) = (((i % w) as f64 + 0.5) / w as f64, 1.0 - ((i / w) as f64 + 0.5) / h as f64);
    let az = (90.0 - (0.5 - u) * 360.0).rem_euclid(360.0);
    let el = (v - 0.5) * 180.0;
    // 0.5 degree pixels; the Moon is refracted by about 0.03 degrees.
    assert!((az - 184.7).abs() < 0.6 && (el - 29.1).abs() < 0.6, "the brightest pixel at azimuth {az}, elevation {el}");

    let r = aurora(&[
        "sky",
        "tromso",
        "--out",
        d.join("noon.exr").to_str().unwrap(),
        "--width",
        "64",
        "--quiet",
        "--set",
        "site.utc=\"2026-06-21T11:00:00Z\"",
    ]);
    ok(&r);
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(e.contains("warning: the Sun is") && e.contains("degrees above the horizon"), "{e}");

    for (set, names) in [
        ("site.utc=\"yesterday\"", "site.utc"),
        ("site.utc=\"2026-02-30T00:00:00Z\"", "site.utc"),
        ("site.latitude_deg=91", "site.latitude_deg"),
    ] {
        let bad = d.join("bad.exr");
        let e = refused(&aurora(&["sky", "tromso", "--out", bad.to_str().unwrap(), "--quiet", "--set", set]));
        assert!(e.contains(names), "{set}: {e}");
        assert!(!bad.exists());
    }
    // A [site] table without its hour.
    let scene = d.join("no_hour.toml");
    std::fs::write(&scene, "[site]\nlatitude_deg = 69.65\nlongitude_deg = 18.96\n").unwrap();
    let bad = d.join("bad.exr");
    let e = refused(&aurora(&["sky", scene.to_str().unwrap(), "--out", bad.to_str().unwrap(), "--quiet"]));
    assert!(e.contains("utc"), "{e}");
    assert!(!bad.exists());
}
