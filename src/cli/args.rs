//! The command line's arguments: the `clap` definitions of every command
//! and its flags, checked as far as clap can (ranges, `--size` syntax). Each
//! command's help is the doc of its [`Command`] variant; the texts that list
//! a registry (the presets, the profile's columns) are built from it in
//! [`super::help`].

use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "aurora",
    version,
    about = "Bake physically plausible aurora into OpenVDB volumes, and render them.",
    long_about = super::help::long_about()
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(clap::Args)]
pub struct Common {
    /// Worker threads (default: all cores). Output is identical for any count.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_THREADS))]
    pub threads: Option<u64>,
    /// No progress bars or summary on stderr.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `--set KEY=VALUE`, on every command that takes a scene, and the order
/// of every override flag ([`parse`] fills it).
#[derive(clap::Args, Default)]
pub struct SceneOverrides {
    /// Set a scene key: KEY=VALUE, VALUE in TOML (--set render.width=64, --set 'camera.up=[0, 1, 0]',
    /// --set colour.mode=colormap: a bare word is text, --set 'curtain[1].energy_flux=3').
    /// Repeatable. Applied to the scene file's TOML before it is checked, so the file's rules
    /// apply (ranges, unknown keys). Every flag that sets a key (--set, --seed, and render's
    /// --spp, --size and --exposure) applies in command-line order, the later winning. A bake
    /// records them in its bake.json (`overrides`).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
    pub set: Vec<aurora::scene::Override>,
    /// Every override of the command line, in its order.
    #[arg(skip)]
    pub ordered: Vec<aurora::scene::Override>,
}

impl SceneOverrides {
    /// The overrides in command-line order (the `--set` flags alone when
    /// the order was not taken from the command line).
    pub fn in_order(&self) -> &[aurora::scene::Override] {
        if self.ordered.is_empty() {
            &self.set
        } else {
            &self.ordered
        }
    }
}

#[derive(Subcommand)]
pub enum Command {
    /// Bake a scene into DIR/aurora.vdb, DIR/aurora.usda and DIR/bake.json.
    ///
    /// With --frames, a sequence: DIR/aurora.NNNN.vdb and DIR/aurora.NNNN.json per frame
    /// (frame N at [animation] time_s + (N - 1) / fps) and one DIR/aurora.usda time-sampled over
    /// the whole range. Frames already complete are skipped, so a rerun resumes: a frame counts
    /// as complete only if its report names the same bake (the scene's keys that change the bake,
    /// not render-only ones such as [render] exposure, and the same build of aurora). A folder
    /// holding frames of another bake is refused (exit 2): bake into a new folder, or --rebake.
    Bake(BakeArgs),
    /// Render a scene with the reference raymarcher to linear OpenEXR (and an optional PNG preview).
    ///
    /// Without --vdb the scene is baked first, in memory. With --vdb the file is rendered,
    /// whoever wrote it: a float `density` grid gives extinction, a vec3 `emission` grid emission
    /// (a float `emission` grid counts as grey). The scene's [camera], [render], [volume],
    /// [background] and [terrain] sections set up the picture.
    Render(RenderArgs),
    /// Measure speed against accuracy of every method choice (photon count, gather radius and
    /// method, voxel size, ray integration, pruning, storage, shadow rays, animation flicker) on a
    /// reduced copy of the scene.
    ///
    /// Writes DIR/bench.csv, DIR/bench.json and a PNG and SVG chart per study (time against
    /// error, Pareto front marked), and prints a summary table. A few minutes on 2 cores;
    /// under a minute with --quick.
    Bench(BenchArgs),
    /// Altitude profiles per curtain from the bake's own beam deposits, as CSV: ionization, each
    /// line's photons and the deposited power per 0.5 km bin.
    #[command(long_about = super::help::profile_long_about())]
    Profile(ProfileArgs),
    /// A keogram of a baked sequence: one float grid (a line's, in rayleigh) along the magnetic
    /// meridian through the camera, one column per frame.
    #[command(long_about = super::help::keogram_long_about())]
    Keogram(KeogramArgs),
    /// Print a built-in scene as TOML, to copy and edit; or a scene file with every default filled in.
    Scene(SceneArgs),
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
    /// its stage times. The bake uses the scene's own settings. Without --watch: the coarse and
    /// the refined picture (--size, --spp), then exit.
    Preview(PreviewArgs),
    /// Write each curtain's 2D footprint (the fluid simulation, bent along its noise curve) as a PNG.
    Footprint(FootprintArgs),
    /// Write the scene's terrain as an OBJ mesh (km, z up), exactly the triangles `aurora render` traces.
    Terrain(TerrainArgs),
    /// Write the sky `aurora render` draws behind the volume (the airglow and the stars, seen from
    /// the camera's position through the air) as an equirectangular linear OpenEXR, mapped as
    /// Blender's Environment Texture reads it: the Blender add-on makes it the world's background.
    /// [background] radiance and image are left out (the add-on adds them itself).
    Sky(SkyArgs),
}

// The arguments of `aurora bake` (its help is the doc of [`Command::Bake`]).
#[derive(clap::Args)]
pub struct BakeArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    /// Output folder (created if missing).
    #[arg(long, default_value = "aurora-out", value_name = "DIR")]
    pub out: PathBuf,
    /// Override the scene's seed.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(..=aurora::scene::MAX_SEED))]
    pub seed: Option<u64>,
    /// Frames to bake, in Open Job Description range syntax: 4, 1-100, 1,3,7-20:2.
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Bake only a share of the frames: I/N (I from 0), auto (a Slurm job array's
    /// SLURM_ARRAY_TASK_ID, _MIN and _COUNT) or auto/N (JOB_COMPLETION_INDEX of a
    /// Kubernetes Indexed Job). Shards share one output folder.
    #[arg(long, value_name = "I/N|auto|auto/N", requires = "frames")]
    pub shard: Option<String>,
    /// The whole range aurora.usda lists, when --frames is one farm task's part of it
    /// (an Open Job Description task baking frame 7 of 1-100: --frames 7 --sequence 1-100).
    /// Default: --frames.
    #[arg(long, value_name = "SPEC", requires = "frames", allow_hyphen_values = true)]
    pub sequence: Option<String>,
    /// When DIR holds frames of another bake (another scene, seed or build), delete every one
    /// of them, in the range or not, and bake these frames; the frames of this bake are kept.
    /// Without it such a folder is refused.
    #[arg(long, requires = "frames")]
    pub rebake: bool,
    /// Progress on stderr: `bars` (a terminal's bars and summaries) or `json` (for a host
    /// program such as the Blender add-on: stderr then carries only JSON objects, one per line,
    /// progress, warnings and errors; docs/guide.md, "Progress as JSON").
    #[arg(long, value_enum, default_value_t = ProgressFormat::Bars, value_name = "FORMAT")]
    pub progress: ProgressFormat,
    /// Stop the bake once PATH exists (checked every 50 ms), as Ctrl-C would: exit status 130,
    /// the folder's previous bake left whole. A host program's cancel that needs no signal
    /// (the Blender add-on's, on Windows too).
    #[arg(long, value_name = "PATH")]
    pub cancel_file: Option<PathBuf>,
    /// Do not bake the range: bake a few of its frames (--plan-samples, spread over it) in a
    /// scratch folder and print the estimated bytes per frame and in total, peak memory per
    /// task and CPU time per frame and in total, then exit 0 (nothing is written to DIR).
    /// With --progress json the plan is one JSON object on stdout.
    #[arg(long, requires = "frames")]
    pub plan: bool,
    /// Frames --plan bakes to calibrate (first, last and evenly between).
    #[arg(long, value_name = "N", default_value_t = 3, requires = "plan",
          value_parser = clap::value_parser!(u64).range(1..=aurora::farm::cost_plan::MAX_SAMPLES as u64))]
    pub plan_samples: u64,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

/// `aurora bake --progress`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, clap::ValueEnum)]
pub enum ProgressFormat {
    Bars,
    Json,
}

impl Cli {
    /// Whether errors go to stderr as JSON (`aurora bake --progress json`).
    pub fn json_errors(&self) -> bool {
        matches!(&self.command, Command::Bake(a) if a.progress == ProgressFormat::Json)
    }
}

// The arguments of `aurora render` (its help is the doc of [`Command::Render`]).
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    /// Render this VDB instead of baking the scene (with --frame: the sequence folder). A
    /// colour.observer other than the one it was baked for re-colours it from its line grids
    /// (baked with every line in grid.lines; refused without them: docs/colour.md).
    #[arg(long, value_name = "FILE.vdb")]
    pub vdb: Option<PathBuf>,
    /// Render frames of a sequence folder (--vdb DIR holding aurora.NNNN.vdb): one frame N,
    /// or a range (1-48) for an image sequence. The frame number goes before the extension
    /// of --out and --png (aurora.0003.exr), or in place of a run of # in their names,
    /// zero-padded to its length (--png 'show_#####.png': show_00001.png, as a fulldome
    /// show's frames are named; 16-bit with --set render.png_bits=16).
    #[arg(long, value_name = "SPEC", requires = "vdb", allow_hyphen_values = true)]
    pub frame: Option<String>,
    /// Output image, its format from the extension: .exr (linear Rec.709 RGBA, A = volume
    /// coverage 1 - T) or .png (sRGB preview at [render] exposure). Only a new name or a
    /// regular file is ever replaced. Default: aurora.exr, or none when --png is given alone.
    #[arg(long, value_name = "IMAGE.exr|IMAGE.png")]
    pub out: Option<PathBuf>,
    /// Also write an sRGB PNG preview (exposure from [render] exposure); alone (without
    /// --out), the PNG is the only image written.
    #[arg(long, value_name = "PREVIEW.png")]
    pub png: Option<PathBuf>,
    /// Override [render] spp.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_SPP))]
    pub spp: Option<u64>,
    /// Override [render] width and height: WIDTHxHEIGHT in pixels.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<[usize; 2]>,
    /// Override [render] exposure, in stops (EV).
    #[arg(long, value_name = "EV", allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// Override [render] shadow_samples: emissive shadow rays per terrain hit per pixel
    /// sample; more makes lit terrain less noisy at less cost than more spp.
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_SHADOW_SAMPLES))]
    pub shadow_samples: Option<u64>,
    /// Override the scene's seed.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(..=aurora::scene::MAX_SEED))]
    pub seed: Option<u64>,
    /// Adaptive sampling by pixel variance: spp becomes the average per pixel; half goes
    /// to every pixel, the rest to the pixels with the largest relative spread (spp >= 8;
    /// docs/physics.md#the-reference-renderer).
    #[arg(long)]
    pub adaptive: bool,
    /// Render the float grid NAME alone as a one-channel image: a per-line grid of
    /// grid.lines (line_5577, line_6300, ...: an all-sky imager's narrow-band filter image,
    /// in rayleigh) or any float emission grid, through the file's density. EXR: one
    /// channel Y, the grid integrated along each ray; PNG: greyscale, linear, 255 = --grid-max
    /// (default: the image's largest value; the scale is printed and stored in the PNG).
    /// Background and stars are left out. Without --vdb the scene is baked with its grid.lines.
    #[arg(long, value_name = "NAME")]
    pub grid: Option<String>,
    /// With --grid: the value PNG 255 stands for (e.g. rayleigh).
    #[arg(long, value_name = "VALUE", requires = "grid")]
    pub grid_max: Option<f64>,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

// The arguments of `aurora bench` (its help is the doc of [`Command::Bench`]).
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    /// Output folder (created if missing).
    #[arg(long, default_value = "aurora-bench", value_name = "DIR")]
    pub out: PathBuf,
    /// Fewer settings and cheaper references (a smoke test of the bench).
    #[arg(long)]
    pub quick: bool,
    /// Only the storage studies (bytes per frame against picture error), on the full scene,
    /// not reduced: its own camera and image size, and a 1024 x 1024 dome master.
    #[arg(long, conflicts_with = "quick")]
    pub storage: bool,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

// The arguments of `aurora sky` (its help is the doc of [`Command::Sky`]).
#[derive(clap::Args)]
pub struct SkyArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    /// Output image (.exr; only a new name or a regular file is ever replaced).
    #[arg(long, value_name = "SKY.exr", default_value = "sky.exr")]
    pub out: PathBuf,
    /// Width of the map, pixels (even); its height is half of it.
    #[arg(long, value_name = "N", default_value_t = 2048)]
    pub width: usize,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

// The arguments of `aurora profile` (its help is the doc of [`Command::Profile`]).
#[derive(clap::Args)]
pub struct ProfileArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    /// Output CSV (written atomically); standard output without it.
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
    /// Override the scene's seed.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(..=aurora::scene::MAX_SEED))]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

// The arguments of `aurora keogram` (its help is the doc of [`Command::Keogram`]).
#[derive(clap::Args)]
pub struct KeogramArgs {
    /// Scene file or preset name (the sequence's: its camera, [sky] and [animation]).
    pub scene: String,
    /// The sequence folder of `aurora bake --frames` (aurora.NNNN.vdb).
    #[arg(long, value_name = "DIR")]
    pub vdb: PathBuf,
    /// Frames, in Open Job Description range syntax: 1-100, 1,3,7-20:2.
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
    pub frame: String,
    /// The float grid traced: line_5577, line_6300, ... (grid.lines) or any float emission grid.
    #[arg(long, value_name = "NAME", default_value = "line_5577")]
    pub grid: String,
    /// Output OpenEXR; the PNG and CSV take its name with .png and .csv.
    #[arg(long, value_name = "K.exr")]
    pub out: PathBuf,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

// The arguments of `aurora scene` (its help is the doc of [`Command::Scene`]).
#[derive(clap::Args)]
pub struct SceneArgs {
    /// Preset name (`aurora scene --list` names them) or a scene file.
    #[arg(default_value = "default")]
    pub name: String,
    /// List the presets instead, one a line: the name, then what it shows.
    #[arg(long, conflicts_with = "schema")]
    pub list: bool,
    /// Print every scene key's default and allowed range as JSON instead
    /// (the Blender add-on reads a copy: blender/scene_schema.json).
    #[arg(long)]
    pub schema: bool,
    #[command(flatten)]
    pub overrides: SceneOverrides,
}

// The arguments of `aurora preview` (its help is the doc of [`Command::Preview`]).
#[derive(clap::Args)]
pub struct PreviewArgs {
    /// Scene file or preset name (a file for --watch).
    #[arg(default_value = "default")]
    pub scene: String,
    /// Output PNG (replaced atomically on every update).
    #[arg(long, default_value = "preview.png", value_name = "IMAGE.png")]
    pub out: PathBuf,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "320x180", value_name = "WxH", value_parser = parse_size)]
    pub size: [usize; 2],
    /// Keep watching the scene file and update the picture on every save.
    #[arg(long)]
    pub watch: bool,
    /// Samples per pixel of the refined picture; when [render] spp is larger, a picture at
    /// the scene's spp follows it (when smaller, it caps this).
    #[arg(long, value_name = "N", default_value_t = aurora::app::preview::DEFAULT_SPP as u64,
          value_parser = clap::value_parser!(u64).range(1..=aurora::scene::MAX_SPP))]
    pub spp: u64,
    #[command(flatten)]
    pub overrides: SceneOverrides,
    #[command(flatten)]
    pub common: Common,
}

// The arguments of `aurora footprint` (its help is the doc of [`Command::Footprint`]).
#[derive(clap::Args)]
pub struct FootprintArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    /// Output folder: footprint-<N>.png per curtain.
    #[arg(long, default_value = "aurora-out", value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub overrides: SceneOverrides,
}

// The arguments of `aurora terrain` (its help is the doc of [`Command::Terrain`]).
#[derive(clap::Args)]
pub struct TerrainArgs {
    /// Scene file or preset name.
    #[arg(default_value = "default")]
    pub scene: String,
    #[arg(long, default_value = "terrain.obj", value_name = "FILE.obj")]
    pub out: PathBuf,
    #[command(flatten)]
    pub overrides: SceneOverrides,
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

/// `--set KEY=VALUE` (`aurora::scene::Override::parse`).
fn parse_set(text: &str) -> std::result::Result<aurora::scene::Override, String> {
    aurora::scene::Override::parse(text, "--set").map_err(|e| e.to_string())
}

/// The command line, with every override flag of the command in the order
/// given ([`SceneOverrides::ordered`]): `--seed N` is `seed=N`, render's
/// `--spp N`, `--shadow-samples N`, `--size WxH` and `--exposure EV` set
/// `render.spp`, `render.shadow_samples`, `render.width` and
/// `render.height`, `render.exposure`.
pub fn parse() -> Cli {
    use clap::{CommandFactory, FromArgMatches};
    let matches = Cli::command().get_matches();
    let mut cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let Some((name, m)) = matches.subcommand() else { return cli };
    let mut found: Vec<(usize, aurora::scene::Override)> = Vec::new();
    let positions = |id: &str| m.indices_of(id).map(|i| i.collect::<Vec<_>>()).unwrap_or_default();
    if let Ok(Some(sets)) = m.try_get_many::<aurora::scene::Override>("set") {
        found.extend(positions("set").into_iter().zip(sets.cloned()));
    }
    let typed = matches!(name, "bake" | "render" | "profile");
    let mut add = |id: &str, key: &str, value: toml::Value, shown: String| {
        if let Some(&at) = positions(id).last() {
            found.push((at, aurora::scene::Override::new(key, value, &format!("--{id} {shown}"))));
        }
    };
    if typed {
        if let Ok(Some(&seed)) = m.try_get_one::<u64>("seed") {
            add("seed", "seed", toml::Value::Integer(seed as i64), seed.to_string());
        }
    }
    if name == "render" {
        if let Ok(Some(&spp)) = m.try_get_one::<u64>("spp") {
            add("spp", "render.spp", toml::Value::Integer(spp as i64), spp.to_string());
        }
        if let Ok(Some(&k)) = m.try_get_one::<u64>("shadow_samples") {
            add("shadow_samples", "render.shadow_samples", toml::Value::Integer(k as i64), k.to_string());
        }
        if let Ok(Some(&ev)) = m.try_get_one::<f64>("exposure") {
            add("exposure", "render.exposure", toml::Value::Float(ev), ev.to_string());
        }
        if let Ok(Some(&[w, h])) = m.try_get_one::<[usize; 2]>("size") {
            add("size", "render.width", toml::Value::Integer(w as i64), format!("{w}x{h}"));
            add("size", "render.height", toml::Value::Integer(h as i64), format!("{w}x{h}"));
        }
    }
    found.sort_by_key(|(at, _)| *at);
    let ordered = found.into_iter().map(|(_, o)| o).collect();
    cli.command.overrides_mut().ordered = ordered;
    cli
}

impl Command {
    /// The command's scene overrides (every command that takes a scene).
    fn overrides_mut(&mut self) -> &mut SceneOverrides {
        match self {
            Command::Bake(a) => &mut a.overrides,
            Command::Render(a) => &mut a.overrides,
            Command::Bench(a) => &mut a.overrides,
            Command::Profile(a) => &mut a.overrides,
            Command::Keogram(a) => &mut a.overrides,
            Command::Scene(a) => &mut a.overrides,
            Command::Preview(a) => &mut a.overrides,
            Command::Footprint(a) => &mut a.overrides,
            Command::Terrain(a) => &mut a.overrides,
            Command::Sky(a) => &mut a.overrides,
        }
    }
}
