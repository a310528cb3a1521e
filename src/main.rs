//! `aurora`: the command line. A thin layer over the library: it parses
//! arguments, maps errors to exit codes in one place, draws progress bars and
//! composes the library's stages (bake -> files, files -> render).
//!
//! Exit status: 0 on success, 2 for bad input (scene file, arguments, an
//! unreadable VDB or one the renderer refuses, a scene the bake cannot
//! honour), 1 for anything else.

use anyhow::{Context, Result};
use aurora::progress::{NoProgress, Progress};
use aurora::scene::{Scene, SceneError};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

#[derive(Parser)]
#[command(
    name = "aurora",
    version,
    about = "Bake physically plausible aurora into OpenVDB volumes, and render them.",
    long_about = "Bake physically plausible aurora into sparse OpenVDB volumes (an `emission` vec3 grid and a \
`density` float grid) for Blender Cycles, Houdini or a USD pipeline, and render them with a reference raymarcher.\n\n\
SCENE is a TOML scene file or the name of a built-in preset (default, seed2014); `aurora scene default` prints one to edit. \
Units are kilometres, z up."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args)]
struct Common {
    /// Worker threads (default: all cores). Output is identical for any count.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_THREADS))]
    threads: Option<u64>,
    /// No progress bars or summary on stderr.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Bake a scene into DIR/aurora.vdb, DIR/aurora.usda and DIR/bake.json.
    ///
    /// With --frames, a sequence: DIR/aurora.NNNN.vdb and DIR/aurora.NNNN.json per frame
    /// (frame N at [animation] time_s + (N - 1) / fps) and one DIR/aurora.usda time-sampled over
    /// the whole range. Frames already complete are skipped, so a rerun resumes: a frame counts
    /// as complete only if its report names the same bake (the scene's keys that change the bake,
    /// not render-only ones such as [render] exposure, and the same build of aurora). A folder
    /// holding frames of another bake is refused (exit 2): bake into a new folder, or --rebake.
    Bake {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        /// Output folder (created if missing).
        #[arg(long, default_value = "aurora-out", value_name = "DIR")]
        out: PathBuf,
        /// Override the scene's seed.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(..=aurora::scene::MAX_SEED))]
        seed: Option<u64>,
        /// Frames to bake, in Open Job Description range syntax: 4, 1-100, 1,3,7-20:2.
        #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
        frames: Option<String>,
        /// Bake only a share of the frames: I/N (I from 0), auto (a Slurm job array's
        /// SLURM_ARRAY_TASK_ID, _MIN and _COUNT) or auto/N (JOB_COMPLETION_INDEX of a
        /// Kubernetes Indexed Job). Shards share one output folder.
        #[arg(long, value_name = "I/N|auto|auto/N", requires = "frames")]
        shard: Option<String>,
        /// The whole range aurora.usda lists, when --frames is one farm task's part of it
        /// (an Open Job Description task baking frame 7 of 1-100: --frames 7 --sequence 1-100).
        /// Default: --frames.
        #[arg(long, value_name = "SPEC", requires = "frames", allow_hyphen_values = true)]
        sequence: Option<String>,
        /// When DIR holds frames of another bake (another scene, seed or build), delete every one
        /// of them, in the range or not, and bake these frames; the frames of this bake are kept.
        /// Without it such a folder is refused.
        #[arg(long, requires = "frames")]
        rebake: bool,
        #[command(flatten)]
        common: Common,
    },
    /// Render a scene with the reference raymarcher to linear OpenEXR (and an optional PNG preview).
    ///
    /// Without --vdb the scene is baked first, in memory. With --vdb the file is rendered,
    /// whoever wrote it: a float `density` grid gives extinction, a vec3 `emission` grid emission
    /// (a float `emission` grid counts as grey). The scene's [camera], [render], [volume],
    /// [background] and [terrain] sections set up the picture.
    Render {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        /// Render this VDB instead of baking the scene (with --frame: the sequence folder).
        #[arg(long, value_name = "FILE.vdb")]
        vdb: Option<PathBuf>,
        /// Render frames of a sequence folder (--vdb DIR holding aurora.NNNN.vdb): one frame N,
        /// or a range (1-48) for an image sequence. The frame number goes before the extension
        /// of --out and --png (aurora.0003.exr).
        #[arg(long, value_name = "SPEC", requires = "vdb", allow_hyphen_values = true)]
        frame: Option<String>,
        /// Output image, its format from the extension: .exr (linear Rec.709 RGBA, A = volume
        /// coverage 1 - T) or .png (sRGB preview at [render] exposure). Only a new name or a
        /// regular file is ever replaced.
        #[arg(long, default_value = "aurora.exr", value_name = "IMAGE.exr|IMAGE.png")]
        out: PathBuf,
        /// Also write an sRGB PNG preview (exposure from [render] exposure).
        #[arg(long, value_name = "PREVIEW.png")]
        png: Option<PathBuf>,
        /// Override [render] spp.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_SPP))]
        spp: Option<u64>,
        /// Emissive shadow-ray samples per terrain hit per pixel sample (default 1):
        /// more makes lit terrain less noisy at less cost than more spp.
        #[arg(long, value_name = "N", default_value_t = 1,
              value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_SHADOW_SAMPLES))]
        shadow_samples: u64,
        /// Override the scene's seed.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(..=aurora::scene::MAX_SEED))]
        seed: Option<u64>,
        /// Adaptive sampling by pixel variance: spp becomes the average per pixel; half goes
        /// to every pixel, the rest to the pixels with the largest relative spread (spp >= 8;
        /// README "The reference renderer").
        #[arg(long)]
        adaptive: bool,
        #[command(flatten)]
        common: Common,
    },
    /// Measure speed against accuracy of every method choice (photon count, gather radius and
    /// method, voxel size, ray integration, shadow rays) on a reduced copy of the scene.
    ///
    /// Writes DIR/bench.csv, DIR/bench.json and a PNG and SVG chart per study (time against
    /// error, Pareto front marked), and prints a summary table. A few minutes on 2 cores;
    /// under a minute with --quick.
    Bench {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        /// Output folder (created if missing).
        #[arg(long, default_value = "aurora-bench", value_name = "DIR")]
        out: PathBuf,
        /// Fewer settings and cheaper references (a smoke test of the bench).
        #[arg(long)]
        quick: bool,
        #[command(flatten)]
        common: Common,
    },
    /// Altitude profiles per curtain from the bake's own beam deposits: CSV with columns
    /// curtain,altitude_km,ionization,n2p_4278,oi_5577,oi_6300,oi_6364,n2_1p,deposited_kev_s
    /// (0.5 km bin centres; ion pairs/s, photons/s, keV/s summed over the curtain).
    Profile {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        /// Output CSV (written atomically); standard output without it.
        #[arg(long, value_name = "FILE.csv")]
        out: Option<PathBuf>,
        /// Override the scene's seed.
        #[arg(long, value_name = "N")]
        seed: Option<u64>,
        #[command(flatten)]
        common: Common,
    },
    /// Print a built-in scene as TOML, to copy and edit; or a scene file with every default filled in.
    Scene {
        /// Preset name (default, seed2014) or a scene file.
        #[arg(default_value = "default")]
        name: String,
        /// Print every scene key's default and allowed range as JSON instead
        /// (the Blender add-on reads a copy: blender/scene_schema.json).
        #[arg(long)]
        schema: bool,
    },
    /// Render a quick preview PNG of a scene; with --watch, re-render on every save.
    ///
    /// With --watch each save of the scene file is taken once it has ended (on Linux a close after
    /// writing or a rename onto the name, by inotify; elsewhere, or with AURORA_WATCH=poll, once
    /// the file has been unchanged for 400 ms), then parsed and validated (a bad edit, or a file
    /// saved empty, prints the error and the watch goes on) and only the stages the edit touches are
    /// rerun: an exposure edit re-encodes the last image (nothing traced), a render edit
    /// re-renders from the cached grids and renderer, a camera edit re-derives the voxel size and
    /// pruning, a beams or colour edit retraces the beams but keeps the footprints. A coarse
    /// picture (1/4 size, 1 spp) is written first, then the refined one (--size, --spp), then,
    /// when [render] spp is larger, one at the scene's spp, each atomically; each update prints
    /// its stage times. The bake uses the scene's own settings. Without --watch: one update, then
    /// exit.
    Preview {
        /// Scene file or preset name (a file for --watch).
        #[arg(default_value = "default")]
        scene: String,
        /// Output PNG (replaced atomically on every update).
        #[arg(long, default_value = "preview.png", value_name = "IMAGE.png")]
        out: PathBuf,
        /// Picture size in pixels, WIDTHxHEIGHT.
        #[arg(long, default_value = "320x180", value_name = "WxH", value_parser = parse_size)]
        size: [usize; 2],
        /// Keep watching the scene file and update the picture on every save.
        #[arg(long)]
        watch: bool,
        /// Samples per pixel of the refined picture; when [render] spp is larger, a picture at
        /// the scene's spp follows it (when smaller, it caps this).
        #[arg(long, value_name = "N", default_value_t = aurora::preview::DEFAULT_SPP as u64,
              value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_SPP))]
        spp: u64,
        #[command(flatten)]
        common: Common,
    },
    /// Write each curtain's 2D footprint (the fluid simulation, bent along its noise curve) as a PNG.
    Footprint {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        /// Output folder: footprint-<N>.png per curtain.
        #[arg(long, default_value = "aurora-out", value_name = "DIR")]
        out: PathBuf,
    },
    /// Write the scene's terrain as an OBJ mesh (km, z up), exactly the triangles `aurora render` traces.
    Terrain {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        #[arg(long, default_value = "terrain.obj", value_name = "FILE.obj")]
        out: PathBuf,
    },
}

/// An error that is the user's input: exit status 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct InputError(String);

fn main() {
    let cli = Cli::parse();
    let code = match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            // A bake error comes from the scene's parameters (every variant
            // names the keys to change): the user's input too.
            let input = e.downcast_ref::<InputError>().is_some()
                || e.downcast_ref::<SceneError>().is_some()
                || e.downcast_ref::<aurora::bake::BakeError>().is_some()
                || e.downcast_ref::<aurora::atomic::AtomicError>().is_some_and(|a| a.is_input())
                || e.downcast_ref::<aurora::outputs::OutputError>().is_some_and(|o| o.is_input())
                || e.downcast_ref::<aurora::sequence::SequenceError>().is_some_and(|s| s.is_input())
                || e.downcast_ref::<aurora::footprint::FootprintError>()
                    .is_some_and(|f| matches!(f, aurora::footprint::FootprintError::Output(a) if a.is_input()))
                || e.downcast_ref::<aurora::render::RenderError>().is_some_and(|r| {
                    use aurora::render::RenderError::*;
                    match r {
                        Settings(_) | Grid { .. } | Source { .. } | Memory { .. } | Heightmap { .. } | Input { .. } => true,
                        Output(a) => a.is_input(),
                        _ => false,
                    }
                });
            eprintln!("aurora: error: {e:#}");
            if input {
                2
            } else {
                1
            }
        }
    };
    std::process::exit(code);
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake { scene, out, seed, frames, shard, sequence, rebake, common } => {
            let mut scene = load_scene(&scene)?;
            if let Some(s) = seed {
                scene.seed = s;
            }
            match frames {
                Some(spec) => {
                    let (mut frames, mine) = frame_selection(&spec, shard.as_deref())?;
                    if let Some(seq) = sequence {
                        let (all, _) = frame_selection(&seq, None)?;
                        if let Some(f) = frames.iter().find(|f| all.binary_search(f).is_err()) {
                            return Err(InputError(format!("--frames `{spec}`: frame {f} is not in --sequence `{seq}`")).into());
                        }
                        frames = all;
                    }
                    with_threads(common.threads, || bake_frames_cmd(&scene, &out, &frames, &mine, rebake, common.quiet))
                }
                None => with_threads(common.threads, || bake_cmd(&scene, &out, common.quiet)),
            }
        }
        Command::Render { scene: scene_arg, vdb, frame, out, png, spp, shadow_samples, seed, adaptive, common } => {
            let shadow_samples = shadow_samples as usize;
            let mut scene = load_scene(&scene_arg)?;
            if let Some(s) = seed {
                scene.seed = s;
            }
            if let Some(n) = spp {
                scene.render.spp = n as usize;
            }
            let dir = scene_dir(&scene_arg);
            // Refuse a bad output before rendering, not after.
            let format = image_format("--out", &out)?;
            if let Some(p) = &png {
                if image_format("--png", p)? != ImageFormat::Png {
                    return Err(InputError(format!("--png {}: the preview is a PNG; give a name ending in .png", p.display())).into());
                }
                aurora::atomic::check_replaceable(p)?;
            }
            aurora::atomic::check_replaceable(&out)?;
            match frame {
                Some(spec) => {
                    let (frames, _) = frame_selection(&spec, None)?;
                    let seq = vdb.expect("clap requires --vdb with --frame");
                    for &f in &frames {
                        aurora::atomic::check_replaceable(&frame_name(&out, f))?;
                    }
                    with_threads(common.threads, || {
                        for &f in &frames {
                            let (vdb_path, _) = aurora::outputs::frame_paths(&seq, f);
                            let exr = frame_name(&out, f);
                            let pngf = png.as_deref().map(|p| frame_name(p, f));
                            render_cmd(
                                &scene,
                                &dir,
                                Some(&vdb_path),
                                &exr,
                                format,
                                pngf.as_deref(),
                                shadow_samples,
                                adaptive,
                                common.quiet,
                            )?;
                        }
                        Ok(())
                    })
                }
                None => with_threads(common.threads, || {
                    render_cmd(&scene, &dir, vdb.as_deref(), &out, format, png.as_deref(), shadow_samples, adaptive, common.quiet)
                }),
            }
        }
        Command::Bench { scene: scene_arg, out, quick, common } => {
            let scene = load_scene(&scene_arg)?;
            with_threads(common.threads, || bench_cmd(&scene, &scene_arg, &out, quick, common.quiet))
        }
        Command::Profile { scene, out, seed, common } => {
            let mut scene = load_scene(&scene)?;
            if let Some(s) = seed {
                scene.seed = s;
            }
            with_threads(common.threads, || profile_cmd(&scene, out.as_deref(), common.quiet))
        }
        Command::Scene { schema: true, .. } => {
            print!("{}", aurora::scene::schema::schema_json());
            Ok(())
        }
        Command::Scene { name, .. } => {
            let s = load_scene(&name)?;
            print!("{}", scene_header(&name));
            print!("{}", s.to_toml());
            Ok(())
        }
        Command::Preview { scene: scene_arg, out, size, watch, spp, common } => {
            image_format("--out", &out).and_then(|f| match f {
                ImageFormat::Png => Ok(()),
                ImageFormat::Exr => Err(InputError(format!("--out {}: the preview writes PNG", out.display())).into()),
            })?;
            let dir = scene_dir(&scene_arg);
            with_threads(common.threads, || preview_cmd(&scene_arg, &dir, &out, size, spp as usize, watch, common.quiet))
        }
        Command::Footprint { scene, out } => {
            let scene = load_scene(&scene)?;
            aurora::atomic::prepare_folder(&out)?;
            for (i, fp) in aurora::bake::plan::footprints(&scene).iter().enumerate() {
                let path = out.join(format!("footprint-{i}.png"));
                fp.write_png(&path).with_context(|| format!("cannot write {}", path.display()))?;
                eprintln!("wrote {}", path.display());
            }
            Ok(())
        }
        Command::Terrain { scene: scene_arg, out } => {
            let scene = load_scene(&scene_arg)?;
            if out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("obj") {
                return Err(InputError(format!(
                    "--out {}: the terrain is written as a Wavefront OBJ; give a name ending in .obj",
                    out.display()
                ))
                .into());
            }
            aurora::atomic::check_replaceable(&out)?;
            if scene.terrain.kind != aurora::scene::TerrainKind::Heightfield {
                return Err(InputError(format!(
                    "terrain.kind = {:?}: only a heightfield has a mesh to write (a plane is z = terrain.height)",
                    scene.terrain.kind
                ))
                .into());
            }
            let hf = aurora::render::terrain::Heightfield::from_terrain(&scene.terrain, Some(&scene_dir(&scene_arg)))
                .map_err(|e| InputError(e.to_string()))?;
            aurora::render::terrain::write_obj(&out, &hf).with_context(|| format!("cannot write {}", out.display()))?;
            eprintln!("wrote {}", out.display());
            Ok(())
        }
    }
}

/// The frames of SPEC (exit 2 on bad syntax or a negative frame) and the
/// share `--shard` gives this process.
fn frame_selection(spec: &str, shard: Option<&str>) -> Result<(Vec<i64>, Vec<i64>)> {
    let frames = aurora::frames::parse_range(spec).map_err(|e| InputError(e.to_string()))?;
    if let Some(f) = frames.iter().find(|&&f| f < 0) {
        return Err(InputError(format!(
            "--frames `{spec}`: frame {f} is negative; frame files are named by frame number (aurora.0001.vdb), so frames must be >= 0"
        ))
        .into());
    }
    let (i, n) = match shard {
        None => (0, 1),
        Some(t) => {
            aurora::frames::Shard::parse(t).and_then(|s| s.resolve(|k| std::env::var(k).ok())).map_err(|e| InputError(e.to_string()))?
        }
    };
    let mine = aurora::frames::select(&frames, i, n);
    Ok((frames, mine))
}

/// `name.ext` -> `name.NNNN.ext` (the frame before the extension).
fn frame_name(path: &Path, frame: i64) -> PathBuf {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "frame".into());
    let ext = path.extension().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(aurora::frames::frame_file_name(&stem, frame, &ext))
}

/// Bakes this process's share `mine` of the sequence `frames` into `out`
/// (a folder of one bake: `aurora::sequence`; `rebake` deletes another's).
fn bake_frames_cmd(scene: &Scene, out: &Path, frames: &[i64], mine: &[i64], rebake: bool, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bars };
    let identity = aurora::bake_identity::BakeIdentity::of(scene);
    let mut seq = aurora::sequence::Sequence::open(out, identity, frames, scene.animation.fps, rebake, || {
        if !quiet {
            eprintln!("aurora: another bake is writing to {}; waiting", out.display())
        }
    })?;
    let t0 = std::time::Instant::now();
    let (mut baked, mut skipped) = (0usize, 0usize);
    let mut plan: Option<aurora::bake::plan::BakePlan> = None;
    for &f in mine {
        if seq.frame_complete(f) {
            skipped += 1;
            continue;
        }
        seq.check_still_ours()?;
        // One writer per frame: a shard that finds another baking it waits,
        // then finds it complete.
        let _lock = aurora::outputs::lock_frame(out, f, || {
            if !quiet {
                eprintln!("frame {f}: another process is baking it; waiting")
            }
        })?;
        if seq.frame_complete(f) {
            skipped += 1;
            continue;
        }
        let at = Scene { animation: aurora::animation::at_frame(&scene.animation, f), ..scene.clone() };
        // One plan, carried from frame to frame (only the time changes).
        let (bake, p) = aurora::bake::bake_reusing(&at, plan.as_ref(), progress)?;
        plan = Some(p);
        print_warnings(&bake.stats.warnings);
        let report = seq.write_frame(&at, &bake, f)?;
        baked += 1;
        if !quiet {
            eprintln!("frame {f} (t = {:.4} s): {}", at.animation.time_s, report.vdb.display());
        }
    }
    if !quiet {
        let secs = t0.elapsed().as_secs_f64();
        eprintln!(
            "{baked} frames baked, {skipped} already complete, of {} for this shard ({} in the sequence) in {secs:.2} s ({:.3} frames/s); stage {}",
            mine.len(),
            frames.len(),
            if secs > 0.0 { baked as f64 / secs } else { 0.0 },
            out.join(aurora::outputs::USDA_NAME).display()
        );
    }
    Ok(())
}

/// The folder relative paths in a scene file (a heightmap) are resolved
/// against: the scene file's own folder, or "." for a preset.
fn scene_dir(scene_arg: &str) -> PathBuf {
    let p = Path::new(scene_arg);
    if p.exists() {
        p.parent().filter(|d| !d.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."))
    } else {
        PathBuf::from(".")
    }
}

fn scene_header(name: &str) -> String {
    format!(
        "# aurora scene `{name}`. Units: kilometres, z up (x east, y north).\n\
         # Bake: aurora bake FILE.toml --out DIR    Render: aurora render FILE.toml --out image.exr\n\
         # Every key is optional; unknown keys are errors. See README.md for each key's meaning.\n\n"
    )
}

fn load_scene(arg: &str) -> Result<Scene> {
    Ok(Scene::load(arg)?)
}

fn with_threads<T>(threads: Option<u64>, f: impl FnOnce() -> Result<T> + Send) -> Result<T>
where
    T: Send,
{
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        // 1..=MAX_THREADS, checked by clap.
        b = b.num_threads(n as usize);
    }
    let pool = b.build().context("cannot start the thread pool")?;
    pool.install(f)
}

fn profile_cmd(scene: &Scene, out: Option<&Path>, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bars };
    let p = aurora::profile::profile(scene, progress)?;
    let csv = aurora::profile::to_csv(&p);
    match out {
        Some(path) => {
            aurora::atomic::write_atomic(path, csv.as_bytes()).with_context(|| format!("cannot write {}", path.display()))?;
            if !quiet {
                eprintln!("wrote {}", path.display());
            }
        }
        None => print!("{csv}"),
    }
    if !quiet {
        let s = &p.beam_stats;
        eprintln!(
            "electron power {:.4e} W: deposited {:.4e}, backscattered {:.4e}, above the beams' top {:.4e}, undeposited {:.4e}",
            s.electron_power_w, s.deposited_power_w, s.backscattered_power_w, s.above_top_power_w, s.undeposited_power_w
        );
    }
    Ok(())
}

fn bake_cmd(scene: &Scene, out: &Path, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bars };
    // The folder is checked and locked before the bake, not after it.
    let _lock =
        aurora::outputs::prepare(out, || eprintln!("aurora: another bake is writing to {}; waiting for it to finish", out.display()))?;
    let bake = aurora::bake::bake(scene, progress)?;
    print_warnings(&bake.stats.warnings);
    let report = aurora::outputs::write_outputs_locked(scene, &bake, out)?;
    if !quiet {
        eprintln!("{}", report.summary());
    }
    Ok(())
}

/// The image formats `aurora render` writes, chosen by the file name's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ImageFormat {
    /// Linear Rec.709 RGBA f32 OpenEXR.
    Exr,
    /// sRGB 8-bit preview at the scene's exposure.
    Png,
}

/// The format an output name asks for: `.exr` or `.png` (any case); anything
/// else is an error naming the flag, so `--out x.png` never gets EXR bytes.
fn image_format(flag: &str, path: &Path) -> Result<ImageFormat> {
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

#[allow(clippy::too_many_arguments)]
fn render_cmd(
    scene: &Scene,
    dir: &Path,
    vdb: Option<&Path>,
    out: &Path,
    format: ImageFormat,
    png: Option<&Path>,
    shadow_samples: usize,
    adaptive: bool,
    quiet: bool,
) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bars };
    let mut settings = aurora::render::RenderSettings::from_scene(scene);
    settings.base_dir = Some(dir.to_path_buf());
    settings.shadow_samples = shadow_samples;
    // A heightmap or sky image that is missing or not a regular file is
    // refused before the bake or the medium build, not after.
    settings.check_input_files()?;
    // From a VDB, the medium straight from the file's records (no grids;
    // the terrain's emission sampler is built from the medium); from grids
    // where that path does not apply (a float emission grid, active tiles)
    // and after a bake.
    let from_records = match vdb {
        Some(path) => aurora::vdb::read::read_render_medium(path, scene.volume.density_scale, scene.volume.emission_scale)
            .map_err(|e| InputError(e.to_string()))?,
        None => None,
    };
    let (prepared, open_seconds, build_seconds) = match from_records {
        Some(read) => (aurora::render::Prepared::with_medium(&settings, read.medium, None)?, read.open_seconds, read.build_seconds),
        None => {
            let open = std::time::Instant::now();
            let (density, emission) = match vdb {
                Some(path) => {
                    let file = aurora::vdb::read::read_vdb_for_render(path).map_err(|e| InputError(e.to_string()))?;
                    aurora::vdb::read::render_grids(file).map_err(|e| InputError(format!("{}: {e}", path.display())))?
                }
                None => {
                    let bake = aurora::bake::bake(scene, progress)?;
                    print_warnings(&bake.stats.warnings);
                    (Some(bake.density), Some(bake.emission))
                }
            };
            let open_seconds = open.elapsed().as_secs_f64();
            let build = std::time::Instant::now();
            let volume = aurora::render::Volume { density: density.as_ref(), emission: emission.as_ref() };
            (aurora::render::Prepared::new(&settings, &volume)?, open_seconds, build.elapsed().as_secs_f64())
        }
    };
    let image = if adaptive {
        aurora::render::render_adaptive_prepared(&prepared, build_seconds, progress)?
    } else {
        let mut img = aurora::render::render_prepared(&prepared, progress)?;
        img.stats.build_seconds = build_seconds;
        img
    };
    finish_render(scene, vdb, out, format, png, quiet, &image, open_seconds)
}

/// Writes a render's image (and PNG) and prints its statistics.
#[allow(clippy::too_many_arguments)]
fn finish_render(
    scene: &Scene,
    vdb: Option<&Path>,
    out: &Path,
    format: ImageFormat,
    png: Option<&Path>,
    quiet: bool,
    image: &aurora::render::Image,
    open_seconds: f64,
) -> Result<()> {
    match format {
        ImageFormat::Exr => aurora::render::film::write_exr(out, image),
        ImageFormat::Png => aurora::render::film::write_png(out, image, scene.render.exposure),
    }
    .with_context(|| format!("cannot write {}", out.display()))?;
    if let Some(p) = png {
        aurora::render::film::write_png(p, image, scene.render.exposure).with_context(|| format!("cannot write {}", p.display()))?;
    }
    if !quiet {
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

/// Bake warnings (under-resolved kernel or curtains) on stderr, even with --quiet.
fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("aurora: warning: {w}");
    }
}

/// `--size WxH`: two positive integers up to the scene's image limit.
fn parse_size(text: &str) -> std::result::Result<[usize; 2], String> {
    let max = aurora::scene::MAX_IMAGE_SIDE;
    let bad = || format!("`{text}`: expected WIDTHxHEIGHT, each 1..={max} (e.g. 320x180)");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (usize, usize) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if w == 0 || h == 0 || w > max || h > max {
        return Err(bad());
    }
    Ok([w, h])
}

/// One preview, or (--watch) a preview per save of the scene file until
/// killed. A bad edit is reported as `aurora bake` words it and the watch
/// goes on with the last good scene.
fn preview_cmd(scene_arg: &str, dir: &Path, out: &Path, size: [usize; 2], spp: usize, watch: bool, quiet: bool) -> Result<()> {
    use aurora::preview::Preview;
    let mut preview = Preview::new(out, size, Some(dir.to_path_buf()));
    preview.spp = spp;
    let report = |u: &aurora::preview::Update| {
        if !quiet {
            eprintln!("wrote {}: {}", out.display(), u.summary());
        }
    };
    // --watch: the watcher, and the hash of the scene text being previewed
    // (a picture at the scene's spp is skipped once another save has ended).
    let watcher = std::cell::RefCell::new(None::<aurora::watch::Watcher>);
    let previewing = std::cell::Cell::new(None::<u64>);
    let on_picture = |what: &str, secs: f64| {
        if !quiet {
            eprintln!("{what} in {secs:.2} s");
        }
        let mut w = watcher.borrow_mut();
        previewing.get().zip(w.as_mut()).is_none_or(|(h, w)| !w.changed_since(h))
    };
    if !watch {
        let scene = load_scene(scene_arg)?;
        let u = preview.update(&scene, &on_picture)?;
        if let Some(b) = preview.bake() {
            print_warnings(&b.stats.warnings);
        }
        report(&u);
        return Ok(());
    }
    let path = Path::new(scene_arg);
    if !path.is_file() {
        return Err(InputError(format!(
            "{scene_arg}: --watch needs a scene file (write a preset to one: aurora scene default > scene.toml)"
        ))
        .into());
    }
    let w = aurora::watch::Watcher::new(path).map_err(|e| InputError(e.to_string()))?;
    if !quiet {
        eprintln!("watching {} ({}; Ctrl-C to stop)", path.display(), w.describe());
    }
    *watcher.borrow_mut() = Some(w);
    loop {
        // Only saves that ended and changed the text (src/watch.rs); a bad
        // one is worded as `aurora bake` words it and the last good scene stays.
        let save = watcher.borrow_mut().as_mut().expect("set above").next_save();
        let save = match save {
            Ok(s) => s,
            Err(e) => {
                eprintln!("aurora: error: {e}");
                continue;
            }
        };
        previewing.set(Some(save.hash));
        if !quiet {
            eprintln!("scene {}: text hash {:016x}, {} bytes", path.display(), save.hash, save.text.len());
        }
        if save.is_blank() {
            eprintln!(
                "aurora: error: {scene_arg}: the saved scene file is empty (only whitespace and comments); keeping the last good scene"
            );
            continue;
        }
        match Scene::from_toml_str(&save.text, scene_arg) {
            Err(e) => eprintln!("aurora: error: {:#}", anyhow::Error::from(e)),
            Ok(scene) => match preview.update(&scene, &on_picture) {
                Ok(u) => {
                    if let Some(b) = preview.bake() {
                        print_warnings(&b.stats.warnings);
                    }
                    report(&u)
                }
                Err(e) => eprintln!("aurora: error: {:#}", anyhow::Error::from(e)),
            },
        }
    }
}

fn bench_cmd(scene: &Scene, scene_arg: &str, out: &Path, quick: bool, quiet: bool) -> Result<()> {
    let log = |line: &str| {
        if !quiet {
            eprintln!("bench: {line}");
        }
    };
    let run = aurora::bench::run(scene, scene_arg, quick, &log)?;
    let written = aurora::bench::report::write(&run, out)?;
    print!("{}", aurora::bench::report::summary(&run));
    if !quiet {
        eprintln!("wrote {} files to {}", written.len(), out.display());
    }
    Ok(())
}

/// indicatif progress bars on stderr, one per stage.
struct Bars {
    bar: Mutex<Option<ProgressBar>>,
    hidden: bool,
}

impl Bars {
    fn new(hidden: bool) -> Self {
        Self { bar: Mutex::new(None), hidden }
    }
}

impl Progress for Bars {
    fn start(&self, stage: &str, total: u64) {
        if self.hidden {
            return;
        }
        let pb = if total > 0 {
            ProgressBar::new(total).with_style(
                ProgressStyle::with_template("{prefix:>12} [{bar:30}] {percent:>3}% {elapsed_precise} eta {eta}")
                    .expect("valid template")
                    .progress_chars("=> "),
            )
        } else {
            ProgressBar::new_spinner()
        };
        pb.set_prefix(stage.to_string());
        if let Some(old) = self.bar.lock().expect("progress lock").replace(pb) {
            old.finish_and_clear();
        }
    }
    fn inc(&self, n: u64) {
        if let Some(b) = self.bar.lock().expect("progress lock").as_ref() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().expect("progress lock").take() {
            b.finish_and_clear();
        }
    }
}
