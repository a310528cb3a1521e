//! The small scenes the tests bake: the command-line tests' scene file
//! (`tests/data/small_bake.toml`, [`small_bake_toml!`]), the scene parts
//! several tests share ([`green_line_grid_toml!`], [`dome_master_toml!`]),
//! and the bake
//! command they run (and a sequence baked with it), and the library tests' scenes ([`small_scene`],
//! [`preview_scene`], and [`coarse`], which shrinks any scene to a bake of
//! seconds).

use super::child::Aurora;
use aurora::scene::{Curtain, Scene, VoxelSize};
use std::path::{Path, PathBuf};

/// The bake keys every small scene of the command-line tests shares
/// (`tests/data/small_bake.toml`), as TOML; a test appends its own tables
/// with `concat!`.
#[macro_export]
macro_rules! small_bake_toml {
    () => {
        include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/small_bake.toml"))
    };
}

/// A flat Earth, the 557.7 nm line on a grid of its own, no air density in
/// the volume and a 1 km kernel on 1 km voxels, as TOML: the scenes whose
/// green line is measured in rayleigh.
#[macro_export]
macro_rules! green_line_grid_toml {
    () => {
        "[earth]\nradius_km = 0.0\n[grid]\nvoxel_size = 1.0\ndensity_a = 0.0\nlines = [\"5577\"]\n[photons]\nradius_km = 1.0\n"
    };
}

/// A dome master as TOML: a 180-degree fisheye `$height` km above the
/// origin looking straight up, a square picture `$size` pixels wide at one
/// sample a pixel, no terrain.
#[macro_export]
macro_rules! dome_master_toml {
    ($height:literal, $size:literal) => {
        concat!(
            "[camera]\nposition = [0.0, 0.0, ",
            $height,
            "]\nlook_at = [0.0, 0.0, 100.0]\nup = [0.0, 1.0, 0.0]\nprojection = \"fisheye\"\nfov_deg = 180.0\n",
            "[render]\nwidth = ",
            $size,
            "\nheight = ",
            $size,
            "\nspp = 1\n[terrain]\nkind = \"none\"\n"
        )
    };
}

/// `aurora bake SCENE --out OUT`; the caller adds its flags and runs it.
pub fn bake_command(scene: &Path, out: &Path) -> Aurora {
    Aurora::new().arg("bake").arg(scene).arg("--out").arg(out)
}

/// A fresh folder `<group>/<name>` holding the scene `toml` (`scene.toml`)
/// and its frames `frames` baked quietly into `seq`: (folder, scene, seq).
pub fn baked_frames(group: &str, name: &str, toml: &str, frames: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = super::scratch(group, name);
    let scene = super::write(&dir, "scene.toml", toml);
    let seq = dir.join("seq");
    super::ok(&bake_command(&scene, &seq).args(["--frames", frames, "-q"]).output());
    (dir, scene, seq)
}

/// `s` shrunk to bake in seconds: a `resolution` footprint, `beams`
/// beams, a 1 km kernel on 1 km voxels.
pub fn coarse(mut s: Scene, resolution: [usize; 2], beams: usize) -> Scene {
    s.footprint.resolution = resolution;
    s.beams.count = beams;
    s.photons.radius_km = 1.0;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s
}

/// Two short curtains with unequal beam weights (so the apportioned counts
/// differ), few beams, coarse voxels: a bake in about a second.
pub fn small_scene() -> Scene {
    let s = Scene {
        curtains: vec![
            Curtain { length: 40.0, width: 16.0, bend_km: 3.0, ..Curtain::default() },
            Curtain { center: [30.0, 20.0], length: 30.0, width: 14.0, beam_weight: 0.5, seed: 7, ..Curtain::default() },
        ],
        ..Scene::default()
    };
    coarse(s, [128, 48], 301)
}

/// The scene `aurora preview` tests watch: [`small_scene`]'s first
/// curtain, 300 beams, 2 samples per pixel.
pub fn preview_scene() -> Scene {
    let mut s = small_scene();
    s.curtains.truncate(1);
    s.beams.count = 300;
    s.render.spp = 2;
    s
}
