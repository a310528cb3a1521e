//! `aurora keogram`: a drifting arc tracked along the magnetic meridian
//! frame by frame, the files it writes, and bad input refused with exit
//! status 2 before anything is written; a frame that changes size while
//! it is read exits 1, an I/O failure.

use crate::common::{aurora, file_names, ok, refused, repo_root, scratch, write};
use crate::green_line_grid_toml;
use aurora::util::fmath;
use std::path::{Path, PathBuf};

/// An arc 80 km long and 4 km wide along x (magnetic east-west: the
/// declination is 0, so the meridian is the y-z plane), uniform, of 3 keV
/// electrons on a vertical field over flat ground, drifting north by
/// `30 sin(2 pi t / 80 s)` km; frames 10 s apart; its 557.7 nm on a grid of
/// its own; a camera on the ground 60 km south of the arc's rest position.
const SCENE: &str = concat!(
    r#"seed = 3
[[curtain]]
center = [0.0, 0.0]
length = 80.0
width = 4.0
bend_km = 0.0
energy_flux = 5.0
char_energy_kev = 3.0
soft_fraction = 0.0
[footprint]
resolution = [32, 8]
uniform = true
[beams]
count = 4000
b_inclination_deg = 90.0
b_declination_deg = 0.0
"#,
    green_line_grid_toml!(),
    r#"[animation]
fps = 0.1
drift_km = 30.0
drift_period_s = 80.0
[camera]
position = [0.0, -60.0, 0.1]
look_at = [0.0, 0.0, 100.0]
[render]
width = 64
height = 36
[terrain]
kind = "none"
"#
);

/// The scene and its frames 1-3 baked into `dir/seq` (once per test that
/// needs them: each test has its own folder).
fn baked(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = scratch("keogram", name);
    let scene = write(&dir, "s.toml", SCENE);
    let seq = dir.join("seq");
    ok(&aurora(&["bake", scene.to_str().unwrap(), "--frames", "1-3", "--out", seq.to_str().unwrap(), "--quiet"]));
    (dir, scene, seq)
}

fn keogram(scene: &Path, seq: &Path, frame: &str, grid: &str, out: &Path) -> std::process::Output {
    let args = [scene.to_str().unwrap(), "--vdb", seq.to_str().unwrap(), "--frame", frame, "--grid", grid, "--out", out.to_str().unwrap()];
    aurora(&[&["keogram"][..], &args, &["--quiet"]].concat())
}

/// The brightest row of each frame's column is the arc's elevation from
/// the camera at the 557.7 nm emission peak, within one 0.5 degree row.
/// The peak altitude is the profile's: the 0.5 km bin of the largest
/// volume emission rate of the same beams (about 110 km for 3 keV). Along
/// a ray at elevation e the 4 km arc is crossed over `4 / cos e` km, so a
/// row reads the emission rate at the altitude where it crosses the arc;
/// one row (0.5 degrees) is about 2 km of altitude or 1.8 km of arc
/// position here, the voxel's order. Then the files: EXR (frames x rows,
/// values in rayleigh as its header says), PNG and CSV (rows, times).
#[test]
fn keogram_tracks_a_drifting_arc_along_the_meridian() {
    let (dir, scene, seq) = baked("drift");
    let profile = dir.join("p.csv");
    ok(&aurora(&["profile", scene.to_str().unwrap(), "--out", profile.to_str().unwrap(), "--quiet"]));
    let text = std::fs::read_to_string(&profile).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (z, ver) = (1, header.iter().position(|c| *c == "oi_5577_ver_cm3_s").unwrap());
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    let peak_km = rows.iter().max_by(|a, b| a[ver].total_cmp(&b[ver])).unwrap()[z];
    assert!((100.0..125.0).contains(&peak_km), "557.7 nm peak at {peak_km} km");

    let out = dir.join("k.exr");
    ok(&keogram(&scene, &seq, "1-3", "line_5577", &out));
    let (w, h, px) = aurora::render::image_file::read_exr_grey(&out).unwrap();
    assert_eq!((w, h), (3, 361));
    let attrs = aurora::render::image_file::read_exr_text_attributes(&out).unwrap();
    assert!(attrs.iter().any(|(k, v)| k == "aurora_units" && v.starts_with("R (rayleigh)")), "{attrs:?}");
    for (col, frame) in [1i64, 2, 3].into_iter().enumerate() {
        let t = (frame - 1) as f64 / 0.1;
        let arc_y = 30.0 * fmath::sin(std::f64::consts::TAU * t / 80.0);
        let want = fmath::atan2(peak_km - 0.1, arc_y + 60.0).to_degrees();
        let brightest = (0..h).max_by(|&a, &b| px[a * w + col].total_cmp(&px[b * w + col])).unwrap();
        // Rows 0..=180 look north at elevation row / 2.
        let got = brightest as f64 * 0.5;
        assert!(brightest <= 180 && (got - want).abs() <= 0.5, "frame {frame}: brightest row at {got} degrees, arc at {want:.2}");
        assert!(px[brightest * w + col] > 1000.0, "frame {frame}: {} R", px[brightest * w + col]);
    }
    let csv = std::fs::read_to_string(dir.join("k.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(lines.next().unwrap(), "scan_deg,elevation_deg,azimuth_deg,0,10,20");
    assert_eq!(lines.count(), 361);
    assert!(dir.join("k.png").is_file());
    assert_eq!(file_names(&dir), ["k.csv", "k.exr", "k.png", "p.columns.csv", "p.csv", "s.toml", "seq"]);
}

/// A bad frame spec, a frame not baked, a grid the files do not hold and
/// an output that is not an EXR are each refused with exit status 2, a
/// message naming what is wrong, and no file written.
#[test]
fn keogram_refuses_bad_frames_grids_and_outputs() {
    let dir = scratch("keogram", "refused");
    let scene = write(&dir, "s.toml", SCENE.replace("count = 4000", "count = 200"));
    let seq = dir.join("seq");
    ok(&aurora(&["bake", scene.to_str().unwrap(), "--frames", "1", "--out", seq.to_str().unwrap(), "--quiet"]));
    let out = dir.join("k.exr");
    let err = refused(&keogram(&scene, &seq, "3-x", "line_5577", &out));
    assert!(err.contains("3-x"), "{err}");
    let err = refused(&keogram(&scene, &seq, "1-2", "line_5577", &out));
    assert!(err.contains("frame 2") && err.contains("aurora.0002.vdb") && err.contains("missing"), "{err}");
    let err = refused(&keogram(&scene, &seq, "1", "line_6300", &out));
    assert!(err.contains("line_6300") && err.contains("line_5577"), "{err}");
    let err = refused(&keogram(&scene, &seq, "1", "line_5577", &dir.join("k.png")));
    assert!(err.contains("k.png") && err.contains(".exr"), "{err}");
    let err = refused(&keogram(&scene, &dir.join("nowhere"), "1", "line_5577", &out));
    assert!(err.contains("nowhere"), "{err}");
    assert_eq!(file_names(&dir), ["s.toml", "seq"]);
}

/// A frame that is not the length it had when opened by the end of its
/// read (as a file another process truncates or extends meanwhile: here,
/// deterministically, `/proc/self/status`, which says it is 0 bytes long
/// and holds more) is an I/O failure, exit status 1 naming the file and
/// both lengths, not bad input; nothing is written.
#[test]
fn a_frame_that_changes_size_while_it_is_read_is_an_io_failure() {
    let dir = scratch("keogram", "changed");
    let scene = write(&dir, "s.toml", SCENE);
    let seq = dir.join("seq");
    std::fs::create_dir_all(&seq).unwrap();
    let frame = seq.join("aurora.0001.vdb");
    std::os::unix::fs::symlink("/proc/self/status", &frame).unwrap();
    let out = dir.join("k.exr");
    let o = keogram(&scene, &seq, "1", "line_5577", &out);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let want = format!("{}`: the file changed size while it was read (0 bytes when opened, 1 read)", frame.display());
    assert!(e.contains(&want), "{e}");
    assert_eq!(file_names(&dir), ["s.toml", "seq"], "nothing written");
}

/// The README's keogram lines as written (its sequence bake with the line's
/// grid, then the keogram), on this small scene without `grid.lines` and
/// over frames 1-2 instead of 1-48; and a keogram of a plain sequence bake
/// is refused with the exact `--set` to add to the bake.
#[test]
fn the_readmes_keogram_example_bakes_the_grid_it_needs() {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).unwrap();
    let commands = readme.split("\n## The commands\n").nth(1).unwrap();
    let line = |start: &str| -> String {
        let l = commands.lines().find(|l| l.starts_with(start)).unwrap_or_else(|| panic!("README.md has no `{start}` line"));
        l.split(" #").next().unwrap().trim().replace("1-48", "1-2")
    };
    let (bake, keo) = (line("aurora bake my.toml --frames"), line("aurora keogram my.toml"));
    assert!(bake.contains("--out shot/") && keo.contains("--vdb shot/"), "{bake}\n{keo}");
    let dir = scratch("keogram", "readme");
    let plain = SCENE.replace("lines = [\"5577\"]\n", "").replace("count = 4000", "count = 300");
    assert!(!plain.contains("lines ="));
    write(&dir, "my.toml", &plain);
    let sh = |line: &str| {
        let bin = std::path::Path::new(crate::common::child::AURORA_BIN).parent().unwrap().to_path_buf();
        let path = std::env::join_paths(std::iter::once(bin).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())));
        std::process::Command::new("sh").arg("-c").arg(format!("{line} -q")).current_dir(&dir).env("PATH", path.unwrap()).output().unwrap()
    };
    // A plain sequence bake: the keogram names the --set that gives it its grid.
    ok(&aurora(&["bake", dir.join("my.toml").to_str().unwrap(), "--frames", "1-2", "--out", dir.join("plain").to_str().unwrap(), "-q"]));
    let err = refused(&sh(&keo.replace("shot/", "plain/")));
    assert!(err.contains("--set 'grid.lines=[\"5577\"]'") && err.contains("--rebake"), "{err}");
    ok(&sh(&bake));
    ok(&sh(&keo));
    let (w, h, _) = aurora::render::image_file::read_exr_grey(dir.join("k.exr")).unwrap();
    assert_eq!((w, h), (2, 361));
}
