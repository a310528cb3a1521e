//! `aurora preview --watch` driven as a user would: an exposure edit (a
//! tone map, nothing traced), a render edit, a syntax error, a fix. The
//! picture follows good edits, a bad one prints the error `aurora bake`
//! prints and the watch goes on.

use crate::common::small::preview_scene;
use crate::common::{ok, refused, scratch, Aurora};
use std::time::Duration;

fn pictures(text: &str) -> usize {
    text.lines().filter(|l| l.starts_with("wrote ")).count()
}

#[test]
fn watch_follows_good_edits_and_survives_a_bad_one() {
    let dir = scratch("preview", "watch");
    let scene_path = dir.join("scene.toml");
    let png = dir.join("p.png");
    let mut scene = preview_scene();
    std::fs::write(&scene_path, scene.to_toml()).unwrap();
    let w = Aurora::new()
        .args(["preview", scene_path.to_str().unwrap(), "--watch", "--size", "64x36", "--spp", "1", "--threads", "2", "--out"])
        .arg(&png)
        .watch();
    // The first update: coarse, the preview-spp picture (--spp 1), then the
    // scene's spp (2).
    let text = w.wait_for("the first picture", Duration::from_secs(300), |t| pictures(t) >= 1);
    let lines: Vec<&str> = text.lines().collect();
    let at = |p: &str| lines.iter().position(|l| l.starts_with(p)).unwrap_or_else(|| panic!("no '{p}' in\n{text}"));
    assert!(
        at("coarse picture (16x9, 1 spp) in ") < at("picture (64x36, 1 spp) in ") && at("picture (64x36, 1 spp) in ") < at("wrote "),
        "{text}"
    );
    let last = text.lines().rfind(|l| l.starts_with("wrote ")).unwrap();
    assert!(last.contains("edit (first)") && last.contains("1 spp), full render") && last.contains("(2 spp)"), "{last}");
    let first = std::fs::read(&png).unwrap();

    // 1. An exposure edit: brighter, a tone map of the last image, nothing traced.
    scene.render.exposure += 2.0;
    std::fs::write(&scene_path, scene.to_toml()).unwrap();
    let text = w.wait_for("the exposure edit's picture", Duration::from_secs(120), |t| pictures(t) >= 2);
    let last = text.lines().rfind(|l| l.starts_with("wrote ")).unwrap();
    for zero in
        ["trace 0.00 s", "gather 0.00 s", "finish 0.00 s", "coarse render 0.00 s", "render 0.00 s (build 0.00 s, pixels 0.00 s, 2 spp)"]
    {
        assert!(last.contains("edit (exposure)") && last.contains(zero), "{zero}: {last}");
    }
    let exposed = std::fs::read(&png).unwrap();
    assert_ne!(first, exposed, "the exposure edit must change the picture");

    // 1b. A render edit that retraces: brighter emission, from the cached grids.
    scene.volume.emission_scale *= 2.0;
    std::fs::write(&scene_path, scene.to_toml()).unwrap();
    let text = w.wait_for("the render edit's picture", Duration::from_secs(120), |t| pictures(t) >= 3);
    let last = text.lines().rfind(|l| l.starts_with("wrote ")).unwrap();
    assert!(
        last.contains("edit (render)") && last.contains("trace 0.00 s") && last.contains("gather 0.00 s") && last.contains("full render"),
        "{last}"
    );
    let second = std::fs::read(&png).unwrap();
    assert_ne!(exposed, second, "the render edit must change the picture");

    // 2. A syntax error: the error as `aurora bake` words it; the process lives on.
    let bad = format!("{}\n[render\n", scene.to_toml());
    std::fs::write(&scene_path, &bad).unwrap();
    let text = w.wait_for("the syntax error", Duration::from_secs(60), |t| t.contains("aurora: error:"));
    let got = text.lines().find(|l| l.starts_with("aurora: error:")).unwrap().to_string();
    let want = refused(&Aurora::new().args(["bake", scene_path.to_str().unwrap(), "--out"]).arg(dir.join("bake")).output());
    assert!(want.lines().any(|l| l == got), "preview: {got}\nbake: {want}");
    // The error is printed once the save is done with: no picture follows it.
    assert!(w.running(), "the watcher exited on a bad edit");
    assert_eq!(std::fs::read(&png).unwrap(), second, "a bad edit must not touch the picture");
    assert_eq!(pictures(&text), 3);

    // 3. The fix (and another exposure): a new picture, diffed against the
    // last good scene (an exposure edit again).
    scene.render.exposure -= 1.0;
    std::fs::write(&scene_path, scene.to_toml()).unwrap();
    let text = w.wait_for("the fix's picture", Duration::from_secs(120), |t| pictures(t) >= 4);
    let last = text.lines().rfind(|l| l.starts_with("wrote ")).unwrap();
    assert!(last.contains("edit (exposure)"), "{last}");
    let third = std::fs::read(&png).unwrap();
    assert_ne!(third, second);
    assert!(w.running(), "the watcher must still run");
    // PNG signature: a whole file, never a torn one.
    assert_eq!(&third[..8], b"\x89PNG\r\n\x1a\n");
    w.stop();
}

#[test]
fn without_watch_one_picture_then_exit() {
    let dir = scratch("preview", "once");
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, preview_scene().to_toml()).unwrap();
    let png = dir.join("once.png");
    ok(&Aurora::new().args(["preview", scene_path.to_str().unwrap(), "--size", "32x18", "--out"]).arg(&png).output());
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // A size out of range is refused with exit status 2.
    refused(&Aurora::new().args(["preview", "--size", "0x10"]).output());
    refused(&Aurora::new().args(["preview", "--spp", "0"]).output());
}

/// Without --watch the quick picture is the last: the preview's size at
/// its spp (4), the very PNG `aurora render --spp 4` makes, not the one at
/// the scene's 64 spp; and --set applies to the preview's scene.
#[test]
fn without_watch_the_quick_picture_is_the_last() {
    let dir = scratch("preview", "quick");
    let mut scene = preview_scene();
    (scene.render.width, scene.render.height, scene.render.spp) = (48, 27, 64);
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, scene.to_toml()).unwrap();
    let (quick, full) = (dir.join("quick.png"), dir.join("full.png"));
    let e = ok(&Aurora::new()
        .args(["preview", scene_path.to_str().unwrap(), "--size", "48x27", "--threads", "2", "--set", "render.exposure=1", "--out"])
        .arg(&quick)
        .output());
    let last = e.lines().rfind(|l| l.starts_with("wrote ")).unwrap();
    assert!(last.contains("(build") && last.contains("4 spp)") && !last.contains("full render"), "{e}");
    let render = |spp: &str, png: &std::path::Path| {
        ok(&Aurora::new()
            .args(["render", scene_path.to_str().unwrap(), "--threads", "2", "--exposure", "1", "--spp", spp, "--png"])
            .arg(png)
            .output())
    };
    render("4", &full);
    assert_eq!(std::fs::read(&quick).unwrap(), std::fs::read(&full).unwrap(), "the preview is the render at 4 spp");
    render("64", &full);
    assert_ne!(std::fs::read(&quick).unwrap(), std::fs::read(&full).unwrap(), "not the render at the scene's spp");
}
