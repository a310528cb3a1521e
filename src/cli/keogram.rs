//! `aurora keogram`: a baked sequence's brightness along the magnetic
//! meridian, one column per frame (`aurora::app::keogram`), written as a
//! one-channel EXR, a scaled greyscale PNG beside it (`K.png`) and a CSV
//! (`K.csv`), each atomically; every output and frame is checked before
//! any is traced.

use super::args::KeogramArgs;
use super::bars::Bars;
use super::exit::InputError;
use super::frames::frame_selection;
use super::render::{grey_metadata, image_format, ImageFormat};
use super::{load_scene, with_threads};
use anyhow::{Context, Result};
use aurora::util::atomic_write::{check_replaceable, write_atomic};

pub fn run(a: KeogramArgs) -> Result<()> {
    let KeogramArgs { scene: scene_arg, vdb, frame, grid, out, common, overrides } = a;
    let scene = load_scene(&scene_arg, &overrides)?;
    if image_format("--out", &out)? != ImageFormat::Exr {
        return Err(InputError(format!("--out {}: the keogram is an OpenEXR; give a name ending in .exr", out.display())).into());
    }
    if !vdb.is_dir() {
        return Err(InputError(format!(
            "--vdb {}: is not a folder; give the sequence folder of a bake with --frames (aurora bake SCENE --frames SPEC --out DIR)",
            vdb.display()
        ))
        .into());
    }
    let (frames, _) = frame_selection(&frame, None)?;
    super::render_checks::keogram_within_memory(&frame, frames.len(), aurora::app::keogram::meridian(&scene).len())?;
    let (png, csv) = (out.with_extension("png"), out.with_extension("csv"));
    for p in [&out, &png, &csv] {
        check_replaceable(p)?;
    }
    aurora::app::keogram::frame_files(&vdb, &frames)?;
    let bars = Bars::new(common.quiet);
    let k = with_threads(common.threads, || Ok(aurora::app::keogram::keogram(&scene, &vdb, &frames, &grid, bars.progress())?))?;
    let meta = grey_metadata(&scene, &grid);
    let image = k.image();
    let largest = k.values.iter().fold(0.0f64, |m, &v| m.max(v as f64));
    let scale = if largest > 0.0 { largest } else { 1.0 };
    write_atomic(&csv, k.to_csv(&meta.units).as_bytes()).with_context(|| format!("cannot write {}", csv.display()))?;
    aurora::render::image_file::write_png_grey(&png, &image, scale, Some(&meta))
        .with_context(|| format!("cannot write {}", png.display()))?;
    aurora::render::image_file::write_exr_grey(&out, &image, Some(&meta)).with_context(|| format!("cannot write {}", out.display()))?;
    if !common.quiet {
        eprintln!(
            "wrote {}, {} and {}: {} frames x {} rows, largest {largest:.6e} (PNG 255)",
            out.display(),
            png.display(),
            csv.display(),
            k.frames.len(),
            k.rows.len()
        );
    }
    Ok(())
}
