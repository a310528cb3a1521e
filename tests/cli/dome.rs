//! Dome delivery: `render --frame` writes frames under the names a
//! producer asks for (`--png 'show_#####.png'`: show_00001.png, the run of
//! `#` the zero-padded frame number, as the fulldome Dome Master Show File
//! Format names them) at 16 bits with `render.png_bits = 16`; a name the
//! frames cannot fill is refused before anything is rendered; `--plan` of a
//! fisheye scene notes a frame rate the format does not take.

use crate::common::small::baked_frames;
use crate::common::{file_names, ok, refused, scratch, write, Aurora};
use crate::{dome_master_toml, small_bake_toml};

const DOME: &str = concat!(
    small_bake_toml!(),
    r#"[animation]
fps = 30.0
ray_speed_kms = 20.0
"#,
    dome_master_toml!("0.5", "24")
);

/// PNG's IHDR: width, height, bit depth, colour type.
fn png_header(bytes: &[u8]) -> (u32, u32, u8, u8) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20), bytes[24], bytes[25])
}

#[test]
fn render_frames_are_named_as_the_producer_asks_and_16_bit() {
    let (dir, scene, seq) = baked_frames("dome", "names", DOME, "1-2");
    let shots = dir.join("shots");
    std::fs::create_dir(&shots).unwrap();
    let render =
        |extra: &[&str]| Aurora::new().arg("render").arg(&scene).arg("--vdb").arg(&seq).args(["--frame", "1-2", "-q"]).args(extra).output();
    let pattern = shots.join("show_#####.png");
    ok(&render(&["--set", "render.png_bits=16", "--png", pattern.to_str().unwrap()]));
    assert_eq!(file_names(&shots), vec!["show_00001.png", "show_00002.png"]);
    for f in ["show_00001.png", "show_00002.png"] {
        // 16 bits per channel, RGB (colour type 2), square.
        assert_eq!(png_header(&std::fs::read(shots.join(f)).unwrap()), (24, 24, 16, 2), "{f}");
    }
    let eight = dir.join("eight");
    std::fs::create_dir(&eight).unwrap();
    ok(&render(&["--png", eight.join("show_#####.png").to_str().unwrap()]));
    assert_eq!(png_header(&std::fs::read(eight.join("show_00001.png")).unwrap()).2, 8);
    // The EXR takes the pattern too.
    ok(&render(&["--out", shots.join("master.###.exr").to_str().unwrap()]));
    assert!(shots.join("master.001.exr").is_file() && shots.join("master.002.exr").is_file());
}

#[test]
fn a_name_the_frames_cannot_fill_is_refused_before_rendering() {
    let (dir, scene, seq) = baked_frames("dome", "refused", DOME, "9-10");
    let shots = dir.join("shots");
    std::fs::create_dir(&shots).unwrap();
    let render = |frames: Option<&str>, name: &str, extra: &[&str]| {
        let c = Aurora::new().arg("render").arg(&scene).arg("-q").arg("--png").arg(shots.join(name)).args(extra);
        match frames {
            Some(f) => c.arg("--vdb").arg(&seq).args(["--frame", f]),
            None => c.arg("--vdb").arg(seq.join("aurora.0009.vdb")),
        }
        .output()
    };
    let msg = refused(&render(Some("9-10"), "show_#.png", &[]));
    assert!(msg.contains("frame 10 has 2 digits") && msg.contains("1 #"), "{msg}");
    let msg = refused(&render(Some("9-10"), "a_##_b_##.png", &[]));
    assert!(msg.contains("more than one run of #"), "{msg}");
    let msg = refused(&render(None, "show_####.png", &[]));
    assert!(msg.contains("give --frame"), "{msg}");
    let msg = refused(&render(Some("9"), "x.png", &["--set", "render.png_bits=12"]));
    assert!(msg.contains("png_bits") && msg.contains("12") && msg.contains("8 or 16"), "{msg}");
    assert!(file_names(&shots).is_empty(), "a refused render wrote {:?}", file_names(&shots));
}

#[test]
fn plan_of_a_dome_master_notes_a_rate_the_fulldome_format_does_not_take() {
    let dir = scratch("dome", "plan");
    let at = |fps: &str| {
        let scene = write(&dir, &format!("dome{fps}.toml"), DOME.replace("fps = 30.0", &format!("fps = {fps}")));
        let o = Aurora::new().arg("bake").arg(&scene).args(["--plan", "--frames", "1-600", "--out"]).arg(dir.join("p")).output();
        ok(&o);
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let at24 = at("24.0");
    assert!(at24.contains("show length          25.0 s at 24 fps"), "{at24}");
    assert!(at24.contains("delivered at 30 or 60 fps") && at24.contains("this scene has 24"), "{at24}");
    let at30 = at("30.0");
    assert!(at30.contains("at 30 fps") && !at30.contains("delivered at"), "{at30}");
}
