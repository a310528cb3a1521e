//! `aurora render`'s inputs and outputs, checked before anything is baked,
//! read or traced, so that bad input exits 2 having written nothing (the
//! README's promise) and a render is never lost to a folder it cannot
//! write:
//!
//! - every VDB the render reads: `--vdb FILE`, or with `--frame A-B` each
//!   frame's `aurora.NNNN.vdb` in the sequence folder, is a regular file
//!   whose header the reader accepts (magic number, file version, grid
//!   offsets: `aurora::farm::frame_files::vdb_header`); the rest of each
//!   file is read when its frame is rendered;
//! - every output (`--out`, `--png`, and with `--frame` each frame's name)
//!   is a new name or a regular file (`aurora::util::atomic_write`), and its
//!   folder exists, is a folder and takes a new file (a probe is created
//!   and removed: a read-only folder, or one on a full or read-only file
//!   system, is found here rather than after the render);
//! - every VDB can be shown through the scene's observer ([`observer_inputs`]):
//!   baked for it, or holding the line grids to re-colour it;
//! - the image's pixels fit in the memory this process may use
//!   ([`image_within_memory`]; the same rule, [`pixels_within_memory`],
//!   for `preview`'s, `sky`'s and `keogram`'s pictures): a picture too
//!   large for the limit is refused naming its size and the limit, never
//!   ended by a failed allocation;
//! - the camera is above the terrain ([`camera_above_terrain`]): a camera
//!   inside the ground would give a black picture, so `render` and
//!   `preview` refuse it naming both heights; `bake` never reads the
//!   terrain and only warns ([`camera_below_terrain`]).

use super::exit::InputError;
use super::frames::{frame_name, frame_pattern, frame_selection};
use anyhow::Result;
use aurora::farm::frame_files::{vdb_header, VdbHeaderError};
use aurora::render::terrain::TerrainModel;
use aurora::scene::Scene;
use aurora::util::atomic_write::AtomicError;
use std::path::{Path, PathBuf};

/// Checks the render's inputs and outputs (module docs): `vdb` is `--vdb`
/// (the sequence folder with `frame`, `--frame`'s range), `outputs` the
/// image names given (`--out`, `--png`).
pub fn inputs_and_outputs(vdb: Option<&Path>, frame: Option<&str>, outputs: &[Option<&Path>]) -> Result<()> {
    let outputs: Vec<&Path> = outputs.iter().flatten().copied().collect();
    let frames = match (vdb, frame) {
        (Some(_), Some(spec)) => Some(frame_selection(spec, None)?.0),
        _ => None,
    };
    for out in &outputs {
        frame_pattern("output", out, frames.as_deref())?;
        output_folder(out)?;
        if frames.is_none() {
            aurora::util::atomic_write::check_replaceable(out)?;
        }
    }
    match (vdb, frame) {
        (Some(seq), Some(spec)) => {
            let frames = frames.unwrap_or_default();
            for &f in &frames {
                let (path, _) = aurora::farm::frame_files::frame_paths(seq, f);
                vdb_input(&path, &format!("--frame {spec}: frame {f}"))?;
                for out in &outputs {
                    aurora::util::atomic_write::check_replaceable(&frame_name(out, f))?;
                }
            }
        }
        (Some(path), None) => vdb_input(path, "--vdb")?,
        (None, _) => {}
    }
    Ok(())
}

/// Every VDB the render reads (`vdb`, with `frame` each frame's) can be
/// shown through `colour.observer`: baked for it, or holding every line's
/// grid to re-colour it (`aurora::app::vdb_for_render::emission_source_of`,
/// from each file's listing); else refused naming the missing grids. Run
/// after [`inputs_and_outputs`], which has checked the files exist.
pub fn observer_inputs(vdb: Option<&Path>, frame: Option<&str>, colour: &aurora::scene::ColourParams) -> Result<()> {
    let paths: Vec<PathBuf> = match (vdb, frame) {
        (Some(seq), Some(spec)) => {
            frame_selection(spec, None)?.0.iter().map(|&f| aurora::farm::frame_files::frame_paths(seq, f).0).collect()
        }
        (Some(path), None) => vec![path.to_path_buf()],
        (None, _) => Vec::new(),
    };
    for path in &paths {
        aurora::app::vdb_for_render::emission_source_of(path, colour).map_err(|e| super::exit::by_message(e.to_string(), e.is_input()))?;
    }
    Ok(())
}

/// `path` is a VDB file the reader accepts, by its header; `what` names it
/// in the message.
fn vdb_input(path: &Path, what: &str) -> Result<()> {
    match vdb_header(path) {
        Ok(_) => Ok(()),
        Err(VdbHeaderError::NotVdb(why)) => Err(InputError(format!("{what}: {}: {why}", path.display())).into()),
        Err(VdbHeaderError::Unreadable(e)) if e.kind() == std::io::ErrorKind::NotFound => {
            Err(InputError(format!("{what}: {} does not exist", path.display())).into())
        }
        Err(VdbHeaderError::Unreadable(e)) => Err(InputError(format!("{what}: cannot read {}: {e}", path.display())).into()),
    }
}

/// The folder `out` is written into exists, is a folder, and takes a new
/// file (a probe file is created there and removed).
fn output_folder(out: &Path) -> Result<(), AtomicError> {
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let refuse = |message: String| AtomicError::Folder { path: dir.clone(), message: format!("{message} (for {})", out.display()) };
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(refuse("exists and is not a folder".into())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(refuse("does not exist".into())),
        Err(e) => return Err(refuse(e.to_string())),
    }
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.subsec_nanos()).unwrap_or(0);
    let probe = dir.join(format!(".aurora-write-probe{}-{nanos}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(f) => {
            drop(f);
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(refuse(format!("not writable: {e}"))),
    }
}

/// The one rule for the pixels a command allocates (`render`, `preview`,
/// `sky`, `keogram`): refuses (exit status 2) a `width` x `height` picture
/// whose pixels (`aurora::render::image::image_memory_bytes`, `adaptive` or
/// not) would need more than the memory this process may use
/// (`aurora::util::memory::available`), before any is allocated, naming
/// `what` (the keys and values that ask for it), the limit, and the allowed
/// range `fits` words from the most pixels that fit.
pub fn pixels_within_memory(what: &str, width: usize, height: usize, adaptive: bool, fits: impl FnOnce(f64) -> String) -> Result<()> {
    let needed = aurora::render::image::image_memory_bytes(width, height, adaptive) as f64;
    let limit = aurora::util::memory::available();
    if needed <= limit.bytes {
        return Ok(());
    }
    let most = limit.bytes / aurora::render::image::image_memory_bytes(1, 1, adaptive) as f64;
    Err(InputError(format!(
        "{what}: the picture's {} pixels would need about {} to render, but this process may use {limit}; {}",
        width as u128 * height as u128,
        aurora::util::memory::gib(needed),
        fits(most)
    ))
    .into())
}

/// The square side of at most `pixels` pixels.
fn square_side(pixels: f64) -> u64 {
    pixels.sqrt().floor() as u64
}

/// `render`'s picture, `render.width` x `render.height`
/// ([`pixels_within_memory`]), and the largest square picture that fits.
pub fn image_within_memory(scene: &Scene, adaptive: bool) -> Result<()> {
    let (w, h) = (scene.render.width, scene.render.height);
    pixels_within_memory(&format!("render.width = {w}, render.height = {h}"), w, h, adaptive, |most| {
        let side = square_side(most);
        format!("render a smaller picture (at most about {side} x {side}, --size or --set render.width=... render.height=...)")
    })
}

/// `preview --size WxH` ([`pixels_within_memory`]).
pub fn preview_within_memory([w, h]: [usize; 2]) -> Result<()> {
    pixels_within_memory(&format!("--size {w}x{h}"), w, h, false, |most| {
        let side = square_side(most);
        format!("give a smaller --size (at most about {} pixels, {side}x{side} say)", most.floor() as u64)
    })
}

/// `sky --width W`, a W x W/2 map ([`pixels_within_memory`]): the allowed
/// widths are the even ones from 8 to the widest that fits.
pub fn sky_within_memory(width: usize) -> Result<()> {
    pixels_within_memory(&format!("--width {width} (a {width} x {} map)", width / 2), width, width / 2, false, |most| {
        let widest = (square_side(2.0 * most) as usize).min(aurora::render::sky_map::MAX_SKY_WIDTH) & !1;
        format!("give a smaller --width (an even number in [8, {widest}])")
    })
}

/// `keogram --frame SPEC`: `frames` columns of `rows` rows
/// ([`pixels_within_memory`]), and the most frames that fit.
pub fn keogram_within_memory(spec: &str, frames: usize, rows: usize) -> Result<()> {
    pixels_within_memory(&format!("--frame {spec}: {frames} frames x {rows} rows"), frames, rows, false, |most| {
        format!("select fewer frames (at most about {} in one keogram)", (most / rows.max(1) as f64).floor() as u64)
    })
}

/// The refusal's words when the scene's camera is below its terrain (the
/// terrain built as the renderer builds it, relative paths against `dir`);
/// None when it is above, or there is no ground under it. A terrain that
/// cannot be built is left to the renderer's own error.
pub fn camera_below_terrain(scene: &Scene, dir: &Path) -> Option<String> {
    let terrain = TerrainModel::on_earth(&scene.terrain, Some(dir), scene.earth.radius_km).ok()?;
    let p = scene.camera.position;
    let c = terrain.clearance(glam::DVec3::from_array(p)).filter(|c| c.is_below())?;
    let kind = toml::Value::try_from(scene.terrain.kind).map(|v| v.to_string()).unwrap_or_default();
    let what = if scene.earth.radius_km > 0.0 { "altitude (above the sphere)" } else { "z" };
    Some(format!(
        "camera.position = [{}, {}, {}]: the camera's height above the ground is {:.4} km, {:.4} km under the surface \
         (its {what} {:.4} km, below the terrain's {:.4} km there; terrain.kind = {kind}): the picture would be the \
         inside of the ground. Raise the camera above {:.4} km, move it, or set terrain.kind = \"none\"",
        p[0],
        p[1],
        p[2],
        c.point_km - c.ground_km,
        c.ground_km - c.point_km,
        c.point_km,
        c.ground_km,
        c.ground_km
    ))
}

/// Refuses (exit status 2) a camera below the terrain ([`camera_below_terrain`]).
pub fn camera_above_terrain(scene: &Scene, dir: &Path) -> Result<()> {
    match camera_below_terrain(scene, dir) {
        Some(m) => Err(InputError(m).into()),
        None => Ok(()),
    }
}
