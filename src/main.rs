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
#[command(name = "aurora", version, about = "Bake physically plausible aurora into OpenVDB volumes, and render them.",
    long_about = "Bake physically plausible aurora into sparse OpenVDB volumes (an `emission` vec3 grid and a \
`density` float grid) for Blender Cycles, Houdini or a USD pipeline, and render them with a reference raymarcher.\n\n\
SCENE is a TOML scene file or the name of a built-in preset (default, seed2014); `aurora scene default` prints one to edit. \
Units are kilometres, z up.")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args)]
struct Common {
    /// Worker threads (default: all cores). Output is identical for any count.
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// No progress bars or summary on stderr.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Bake a scene into DIR/aurora.vdb, DIR/aurora.usda and DIR/bake.json.
    Bake {
        /// Scene file or preset name.
        #[arg(default_value = "default")]
        scene: String,
        /// Output folder (created if missing).
        #[arg(long, default_value = "aurora-out", value_name = "DIR")]
        out: PathBuf,
        /// Override the scene's seed.
        #[arg(long, value_name = "N")]
        seed: Option<u64>,
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
        /// Render this VDB instead of baking the scene.
        #[arg(long, value_name = "FILE.vdb")]
        vdb: Option<PathBuf>,
        /// Output image (linear Rec.709 RGBA, A = volume coverage 1 - T).
        #[arg(long, default_value = "aurora.exr", value_name = "IMAGE.exr")]
        out: PathBuf,
        /// Also write an sRGB PNG preview (exposure from [render] exposure).
        #[arg(long, value_name = "PREVIEW.png")]
        png: Option<PathBuf>,
        /// Override [render] spp.
        #[arg(long, value_name = "N")]
        spp: Option<usize>,
        /// Emissive shadow-ray samples per terrain hit per pixel sample (default 1):
        /// more makes lit terrain less noisy at less cost than more spp.
        #[arg(long, value_name = "N", default_value_t = 1)]
        shadow_samples: usize,
        /// Override the scene's seed.
        #[arg(long, value_name = "N")]
        seed: Option<u64>,
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
    /// Print a built-in scene as TOML, to copy and edit; or a scene file with every default filled in.
    Scene {
        /// Preset name (default, seed2014) or a scene file.
        #[arg(default_value = "default")]
        name: String,
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
                || e.downcast_ref::<aurora::render::RenderError>().is_some_and(|r| {
                    use aurora::render::RenderError::*;
                    matches!(r, Settings(_) | Grid { .. } | Heightmap { .. })
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
        Command::Bake { scene, out, seed, common } => {
            let mut scene = load_scene(&scene)?;
            if let Some(s) = seed {
                scene.seed = s;
            }
            with_threads(common.threads, || bake_cmd(&scene, &out, common.quiet))
        }
        Command::Render { scene: scene_arg, vdb, out, png, spp, shadow_samples, seed, common } => {
            if shadow_samples == 0 {
                return Err(InputError("--shadow-samples must be at least 1".into()).into());
            }
            let mut scene = load_scene(&scene_arg)?;
            if let Some(s) = seed {
                scene.seed = s;
            }
            if let Some(n) = spp {
                if n == 0 {
                    return Err(InputError("--spp must be at least 1".into()).into());
                }
                scene.render.spp = n;
            }
            let dir = scene_dir(&scene_arg);
            with_threads(common.threads, || render_cmd(&scene, &dir, vdb.as_deref(), &out, png.as_deref(), shadow_samples, common.quiet))
        }
        Command::Bench { scene: scene_arg, out, quick, common } => {
            let scene = load_scene(&scene_arg)?;
            with_threads(common.threads, || bench_cmd(&scene, &scene_arg, &out, quick, common.quiet))
        }
        Command::Scene { name } => {
            let s = load_scene(&name)?;
            print!("{}", scene_header(&name));
            print!("{}", s.to_toml());
            Ok(())
        }
        Command::Footprint { scene, out } => {
            let scene = load_scene(&scene)?;
            std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
            for (i, fp) in aurora::bake::footprints(&scene).iter().enumerate() {
                let path = out.join(format!("footprint-{i}.png"));
                fp.write_png(&path).with_context(|| format!("cannot write {}", path.display()))?;
                eprintln!("wrote {}", path.display());
            }
            Ok(())
        }
        Command::Terrain { scene: scene_arg, out } => {
            let scene = load_scene(&scene_arg)?;
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

fn with_threads<T>(threads: Option<usize>, f: impl FnOnce() -> Result<T> + Send) -> Result<T>
where
    T: Send,
{
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err(InputError("--threads must be at least 1".into()).into());
        }
        b = b.num_threads(n);
    }
    let pool = b.build().context("cannot start the thread pool")?;
    pool.install(f)
}

fn bake_cmd(scene: &Scene, out: &Path, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bars };
    let bake = aurora::bake::bake(scene, progress)?;
    print_warnings(&bake.stats.warnings);
    let report = aurora::outputs::write_outputs(scene, &bake, out)?;
    if !quiet {
        eprintln!("{}", report.summary());
    }
    Ok(())
}

fn render_cmd(
    scene: &Scene,
    dir: &Path,
    vdb: Option<&Path>,
    out: &Path,
    png: Option<&Path>,
    shadow_samples: usize,
    quiet: bool,
) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bars };
    let mut settings = aurora::render::RenderSettings::from_scene(scene);
    settings.base_dir = Some(dir.to_path_buf());
    settings.shadow_samples = shadow_samples;
    let (density, emission);
    let open = std::time::Instant::now();
    match vdb {
        Some(path) => {
            let file = aurora::vdb::read::read_vdb(path).map_err(|e| InputError(e.to_string()))?;
            let (d, e) = aurora::vdb::read::render_grids(file)
                .map_err(|e| InputError(format!("{}: {e}", path.display())))?;
            density = d;
            emission = e;
        }
        None => {
            let bake = aurora::bake::bake(scene, progress)?;
            print_warnings(&bake.stats.warnings);
            density = Some(bake.density);
            emission = Some(bake.emission);
        }
    }
    let open_seconds = open.elapsed().as_secs_f64();
    let volume = aurora::render::Volume { density: density.as_ref(), emission: emission.as_ref() };
    let image = aurora::render::render(&settings, &volume, progress)?;
    aurora::render::film::write_exr(out, &image).with_context(|| format!("cannot write {}", out.display()))?;
    if let Some(p) = png {
        aurora::render::film::write_png(p, &image, scene.render.exposure)
            .with_context(|| format!("cannot write {}", p.display()))?;
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
