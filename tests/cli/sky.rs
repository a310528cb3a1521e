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
    // Top row: the airglow overhead (about 0.3 in green with the air);
    // bottom row: under the ground, nothing.
    let top = img.pixels[..64].iter().map(|p| p[1]).sum::<f32>() / 64.0;
    assert!((0.1..1.0).contains(&top), "{top}");
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
