//! `aurora render`: the outputs checked before anything is traced, then one
//! image or one per frame of a sequence folder, each made by
//! `aurora::app::render_image` (the volume from a VDB or a bake in memory;
//! with `--grid NAME` one float grid alone as the emission, grey, written
//! with one channel: `aurora::render::image_file::write_exr_grey`).

use super::args::RenderArgs;
use super::bars::Bars;
use super::exit::InputError;
use super::frames::{frame_name, frame_selection};
use super::{load_scene, print_warnings, scene_dir, with_threads};
use anyhow::{Context, Result};
use aurora::render::image_file::PngBits;
use aurora::scene::Scene;
use std::path::{Path, PathBuf};

/// The image formats `aurora render` writes, chosen by the file name's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// Linear Rec.709 RGBA f32 OpenEXR.
    Exr,
    /// sRGB 8-bit preview at the scene's exposure.
    Png,
}

/// The format an output name asks for: `.exr` or `.png` (any case); anything
/// else is an error naming the flag, so `--out x.png` never gets EXR bytes.
pub fn image_format(flag: &str, path: &Path) -> Result<ImageFormat> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("exr") => Ok(ImageFormat::Exr),
        Some("png") => Ok(ImageFormat::Png),
        _ => Err(InputError(format!(
            "{flag} {}: unknown image format; the name must end in .exr (linear OpenEXR) or .png (sRGB preview)",
            path.display()
        ))
        .into()),
    }
}

/// What every image of one `aurora render` shares.
struct Job {
    scene: Scene,
    /// The folder the scene's relative paths are resolved against.
    dir: PathBuf,
    format: ImageFormat,
    adaptive: bool,
    quiet: bool,
    /// `--grid NAME` and `--grid-max`.
    grid: Option<String>,
    grid_max: Option<f64>,
}

/// One image's files: the volume to render (none: bake the scene), the
/// image and the optional PNG preview.
#[derive(Clone, Copy)]
struct Files<'a> {
    vdb: Option<&'a Path>,
    out: &'a Path,
    png: Option<&'a Path>,
    /// The sequence's frame (its time for the sky of a `[site]`), or none.
    frame: Option<i64>,
}

pub fn run(a: RenderArgs) -> Result<()> {
    // --seed, --spp, --size and --exposure are overrides, applied in command-line order.
    let RenderArgs { scene: scene_arg, vdb, frame, out, png, adaptive, grid, grid_max, common, overrides, .. } = a;
    if let Some(m) = grid_max {
        if !(m.is_finite() && m > 0.0) {
            return Err(InputError(format!("--grid-max {m}: must be a finite number > 0")).into());
        }
    }
    if let (Some(dir), None) = (&vdb, &frame) {
        if dir.is_dir() {
            return Err(InputError(sequence_folder_without_frame(dir)).into());
        }
    }
    let scene = load_scene(&scene_arg, &overrides)?;
    let min = aurora::render::adaptive::ADAPTIVE_MIN_SPP;
    if adaptive && scene.render.spp < min {
        return Err(InputError(format!(
            "--adaptive with render.spp = {}: adaptive sampling needs at least {min} samples a pixel (half go to every pixel, \
             the rest where the spread is largest); give --spp {min} or more, or leave --adaptive out",
            scene.render.spp
        ))
        .into());
    }
    let dir = scene_dir(&scene_arg);
    // Refuse a bad output before rendering, not after.
    if let Some(p) = &png {
        if image_format("--png", p)? != ImageFormat::Png {
            return Err(InputError(format!("--png {}: the preview is a PNG; give a name ending in .png", p.display())).into());
        }
    }
    // --png alone: the PNG is the one image.
    let (out, png) = match (out, png) {
        (None, Some(p)) => (p, None),
        (out, png) => (out.unwrap_or_else(|| PathBuf::from("aurora.exr")), png),
    };
    let format = image_format("--out", &out)?;
    super::render_checks::inputs_and_outputs(vdb.as_deref(), frame.as_deref(), &[Some(&out), png.as_deref()])?;
    super::render_checks::camera_above_terrain(&scene, &dir)?;
    super::render_checks::image_within_memory(&scene, adaptive)?;
    if grid.is_none() {
        super::render_checks::observer_inputs(vdb.as_deref(), frame.as_deref(), &scene.colour)?;
    }
    let job = Job { scene, dir, format, adaptive, quiet: common.quiet, grid, grid_max };
    match frame {
        Some(spec) => {
            let (frames, _) = frame_selection(&spec, None)?;
            let seq = vdb.expect("clap requires --vdb with --frame");
            with_threads(common.threads, || render_frames(&job, &seq, &frames, &out, png.as_deref()))
        }
        None => {
            with_threads(common.threads, || render_one(&job, &Files { vdb: vdb.as_deref(), out: &out, png: png.as_deref(), frame: None }))
        }
    }
}

/// The refusal of `--vdb DIR` without `--frame`: DIR is a sequence folder
/// (or a folder of none), with the frames found there.
fn sequence_folder_without_frame(dir: &Path) -> String {
    let stem = format!("{}.", aurora::io::bake_folder::FRAME_STEM);
    let mut frames: Vec<i64> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter_map(|e| {
                    let name = e.file_name().into_string().ok()?;
                    let digits = name.strip_prefix(&stem)?.strip_suffix(".vdb")?;
                    digits.bytes().all(|b| b.is_ascii_digit()).then(|| digits.parse().ok())?
                })
                .collect()
        })
        .unwrap_or_default();
    frames.sort_unstable();
    let d = dir.display();
    match (frames.first(), frames.last()) {
        (Some(first), Some(last)) => format!(
            "--vdb {d}: is a sequence folder ({} frames, {}); pass --frame N to render one frame (--frame {first}) or a range \
             (--frame {first}-{last}), or give --vdb a .vdb file",
            frames.len(),
            frame_ranges(&frames)
        ),
        _ => format!(
            "--vdb {d}: is a directory, not a regular file, and holds no frames ({stem}NNNN.vdb); give --vdb a .vdb file, or with \
             --frame N a sequence folder"
        ),
    }
}

/// Sorted frame numbers as ranges: "1-48", "1-10, 12, 20-24".
fn frame_ranges(frames: &[i64]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < frames.len() {
        let mut j = i;
        while j + 1 < frames.len() && frames[j + 1] == frames[j] + 1 {
            j += 1;
        }
        parts.push(if j > i { format!("{}-{}", frames[i], frames[j]) } else { frames[i].to_string() });
        i = j + 1;
    }
    parts.join(", ")
}

/// Renders each frame of the sequence folder `seq` to `out` and `png` with
/// the frame number before the extension.
fn render_frames(job: &Job, seq: &Path, frames: &[i64], out: &Path, png: Option<&Path>) -> Result<()> {
    for &f in frames {
        let (vdb_path, _) = aurora::farm::frame_files::frame_paths(seq, f);
        let exr = frame_name(out, f);
        let pngf = png.map(|p| frame_name(p, f));
        render_one(job, &Files { vdb: Some(&vdb_path), out: &exr, png: pngf.as_deref(), frame: Some(f) })?;
    }
    Ok(())
}

/// Renders one image (`aurora::app::render_image`) and writes it.
fn render_one(job: &Job, files: &Files<'_>) -> Result<()> {
    let bars = Bars::with_log_lines(job.quiet);
    let req = aurora::app::render_image::ImageRequest {
        scene: &job.scene,
        dir: job.dir.clone(),
        vdb: files.vdb,
        frame: files.frame,
        grid: job.grid.as_deref(),
        adaptive: job.adaptive,
    };
    let rendered = aurora::app::render_image::render(&req, bars.progress())?;
    print_warnings(&rendered.warnings);
    finish(job, files, &rendered.image, rendered.open_seconds)
}

/// What a `--grid NAME` image holds (`aurora::app::render_image::grey_metadata`).
pub fn grey_metadata(scene: &Scene, name: &str) -> aurora::render::image_file::GreyMetadata {
    aurora::app::render_image::grey_metadata(scene, name)
}

/// Writes a one-channel `--grid` image (EXR `Y`, or greyscale PNG at
/// `--grid-max` or the image's largest value), its scale printed, its
/// units and air in the file ([`grey_metadata`]).
fn write_grey(job: &Job, path: &Path, png_only: bool, image: &aurora::render::Image) -> Result<()> {
    let meta = grey_metadata(&job.scene, job.grid.as_deref().unwrap_or_default());
    let grey_png = |p: &Path| -> Result<()> {
        let largest = image.pixels.iter().map(|p| p[0] as f64).fold(0.0, f64::max);
        let scale = job.grid_max.unwrap_or(if largest > 0.0 { largest } else { 1.0 });
        aurora::render::image_file::write_png_grey(p, image, scale, Some(&meta))
            .with_context(|| format!("cannot write {}", p.display()))?;
        if !job.quiet {
            let unit = if meta.units.starts_with("R ") { " R" } else { "" };
            eprintln!("{}: greyscale, linear, 255 = {scale:.6e}{unit} (the grid integrated along the ray)", p.display());
        }
        Ok(())
    };
    if png_only {
        return grey_png(path);
    }
    aurora::render::image_file::write_exr_grey(path, image, Some(&meta)).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes a render's image (and PNG) and prints its statistics.
fn finish(job: &Job, files: &Files<'_>, image: &aurora::render::Image, open_seconds: f64) -> Result<()> {
    let Files { vdb, out, png, .. } = *files;
    let view = job.scene.render.view_transform;
    let bits = if job.scene.render.png_bits == 16 { PngBits::Sixteen } else { PngBits::Eight };
    // The PNG shows the white-balanced image at the scene's or the metered EV.
    let (shown, developed) = aurora::render::develop::develop(image, &job.scene.colour, &job.scene.render);
    let (exposure, meta) = (developed.exposure_ev, developed.metadata());
    if developed.metered && !job.quiet && job.grid.is_none() {
        eprintln!("exposure: auto, metered {exposure:+.2} EV (centre-weighted highlight meter)");
    }
    if job.grid.is_some() {
        write_grey(job, out, job.format == ImageFormat::Png, image)?;
        if let Some(p) = png {
            write_grey(job, p, true, image)?;
        }
    } else {
        match job.format {
            ImageFormat::Exr => aurora::render::image_file::write_exr_with(out, image, &meta),
            ImageFormat::Png => aurora::render::image_file::write_png_with(out, &shown, exposure, view, bits, &meta),
        }
        .with_context(|| format!("cannot write {}", out.display()))?;
        if let Some(p) = png {
            aurora::render::image_file::write_png_with(p, &shown, exposure, view, bits, &meta)
                .with_context(|| format!("cannot write {}", p.display()))?;
        }
    }
    if !job.quiet {
        eprintln!("wrote {}{}", out.display(), png.map(|p| format!(" and {}", p.display())).unwrap_or_default());
        let st = &image.stats;
        eprintln!(
            "{} primary rays in {:.2} s ({:.0}/s), {} shadow samples, {} threads",
            st.primary_rays,
            st.render_seconds,
            st.primary_rays_per_second(),
            st.shadow_samples,
            st.threads
        );
        eprintln!(
            "times: {} {:.2} s, build {:.2} s, trace {:.2} s",
            if vdb.is_some() { "open VDB" } else { "bake" },
            open_seconds,
            st.build_seconds,
            st.render_seconds
        );
    }
    Ok(())
}
