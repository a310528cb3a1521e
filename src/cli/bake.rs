//! `aurora bake`: one bake into a folder ([`bake_one`]), or a frame
//! sequence ([`bake_frames`], `aurora::app::bake_sequence`: resumed frame
//! by frame).
//!
//! What it says on stderr goes through one [`Report`]: bars, summaries and
//! warning lines for a terminal, or with `--progress json` only JSON objects
//! (`aurora::util::progress::JsonProgress`: stage lines, one `frame` line per
//! frame of a sequence, warnings; the error line is `exit::code`'s).

use super::args::{BakeArgs, ProgressFormat};
use super::bars::Bars;
use super::exit::InputError;
use super::frames::{frame_selection, selection};
use super::{load_scene, print_warnings, with_threads};
use anyhow::Result;
use aurora::scene::Scene;
use aurora::util::progress::{JsonProgress, Progress};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Where the bake's progress and messages go.
enum Report {
    Text { bars: Bars, quiet: bool },
    Json { progress: Arc<JsonProgress<std::io::Stderr>>, _ticker: Ticker },
}

/// A thread that lets the JSON progress report a stage whose work comes
/// seconds apart every second (`JsonProgress::tick`), every
/// `JsonProgress::HEARTBEAT`; stopped and joined when dropped, so no line
/// follows the run's last (the error line is written after).
struct Ticker {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Ticker {
    fn new(progress: Arc<JsonProgress<std::io::Stderr>>) -> Ticker {
        let stop = Arc::new(AtomicBool::new(false));
        let stopped = stop.clone();
        let thread = std::thread::spawn(move || loop {
            std::thread::park_timeout(JsonProgress::<std::io::Stderr>::HEARTBEAT);
            if stopped.load(Ordering::Relaxed) {
                break;
            }
            progress.tick();
        });
        Ticker { stop, thread: Some(thread) }
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

impl Report {
    fn new(format: ProgressFormat, quiet: bool) -> Self {
        match format {
            ProgressFormat::Bars => Report::Text { bars: Bars::new(quiet), quiet },
            ProgressFormat::Json => {
                let progress = Arc::new(JsonProgress::new(std::io::stderr()));
                Report::Json { _ticker: Ticker::new(progress.clone()), progress }
            }
        }
    }

    fn progress(&self) -> &dyn Progress {
        match self {
            Report::Text { bars, .. } => bars.progress(),
            Report::Json { progress, .. } => progress.as_ref(),
        }
    }

    /// The JSON progress, if that is the format.
    fn json(&self) -> Option<Arc<JsonProgress<std::io::Stderr>>> {
        match self {
            Report::Text { .. } => None,
            Report::Json { progress, .. } => Some(progress.clone()),
        }
    }

    /// Warnings: shown even with --quiet.
    fn warnings(&self, warnings: &[String]) {
        match self {
            Report::Text { .. } => print_warnings(warnings),
            Report::Json { progress, .. } => warnings.iter().for_each(|w| progress.warning(w)),
        }
    }

    /// A line for a person at a terminal (not with --quiet, not as JSON).
    fn say(&self, line: impl FnOnce() -> String) {
        if let Report::Text { quiet: false, .. } = self {
            eprintln!("{}", line());
        }
    }

    /// `done` of `total` frames of a sequence are complete.
    fn frames(&self, done: usize, total: usize) {
        if let Report::Json { progress, .. } = self {
            progress.step("frame", done as u64, total as u64);
        }
    }
}

pub fn run(a: BakeArgs) -> Result<()> {
    // --seed is one of the overrides, applied in command-line order.
    let BakeArgs {
        scene: scene_arg,
        out,
        seed: _,
        frames,
        shard,
        sequence,
        rebake,
        progress,
        cancel_file,
        plan,
        plan_samples,
        common,
        overrides,
    } = a;
    let report = Report::new(progress, common.quiet);
    if let Some(path) = cancel_file {
        super::cancel::watch(path, report.json());
    }
    let dir = super::scene_dir(&scene_arg);
    let scene = load_scene(&scene_arg, &overrides)?;
    // The bake never reads the terrain: a camera inside it is only warned of
    // (`render` and `preview` refuse it).
    report.warnings(&super::render_checks::camera_below_terrain(&scene, &dir).into_iter().collect::<Vec<_>>());
    let Some(spec) = frames else {
        return with_threads(common.threads, || bake_one(&scene, &out, &report));
    };
    let super::frames::Selection { mut frames, mine, shard } = selection(&spec, shard.as_deref())?;
    if let Some(seq) = sequence {
        let (all, _) = frame_selection(&seq, None)?;
        if let Some(f) = frames.iter().find(|f| all.binary_search(f).is_err()) {
            return Err(InputError(format!("--frames `{spec}`: frame {f} is not in --sequence `{seq}`")).into());
        }
        frames = all;
    }
    if plan {
        // This process's share: what one farm task of the range costs.
        let task = aurora::farm::cost_plan::Task { sequence: &frames, frames: &mine, shard };
        // The render's settings, as `aurora render` makes them; its input
        // files (a heightmap, a sky image) are checked before any bake.
        let mut settings = aurora::render::RenderSettings::from_scene(&scene);
        settings.base_dir = Some(dir.clone());
        settings.check_input_files()?;
        return with_threads(common.threads, || plan_frames(&scene, task, &settings, plan_samples as usize, progress, &report));
    }
    with_threads(common.threads, || bake_frames(&scene, &out, &frames, &mine, rebake, &report))
}

/// `--plan`: the estimate for `task` on stdout (`aurora::farm::cost_plan`).
fn plan_frames(
    scene: &Scene,
    task: aurora::farm::cost_plan::Task<'_>,
    settings: &aurora::render::RenderSettings,
    samples: usize,
    format: ProgressFormat,
    say: &Report,
) -> Result<()> {
    // The render of the first calibration frame, at the frame's time.
    let probe = |at: &Scene, vdb: &Path, frame: i64| {
        let mut s = aurora::render::RenderSettings::from_scene(at);
        s.base_dir = settings.base_dir.clone();
        aurora::app::render_cost::calibrate(at, &s, vdb, frame)
    };
    let plan = aurora::farm::cost_plan::plan_task(scene, task, samples, Some(&probe), say.progress())?;
    match format {
        ProgressFormat::Json => println!("{}", plan.json()),
        ProgressFormat::Bars => println!("{}", plan.text()),
    }
    Ok(())
}

/// One bake into `out`: aurora.vdb, aurora.usda and bake.json.
fn bake_one(scene: &Scene, out: &Path, say: &Report) -> Result<()> {
    // The folder is checked and locked before the bake, not after it.
    let _lock = aurora::io::bake_folder::prepare(out, || {
        say.say(|| format!("aurora: another bake is writing to {}; waiting for it to finish", out.display()))
    })?;
    let bake = aurora::pipeline::bake::bake(scene, say.progress())?;
    say.warnings(&bake.stats.warnings);
    let report = aurora::io::bake_folder::write_outputs_locked(scene, &bake, out)?;
    say.say(|| report.summary());
    Ok(())
}

impl aurora::app::bake_sequence::SequenceReport for Report {
    fn progress(&self) -> &dyn Progress {
        Report::progress(self)
    }
    fn say(&self, line: &dyn Fn() -> String) {
        Report::say(self, line)
    }
    fn warnings(&self, warnings: &[String]) {
        Report::warnings(self, warnings)
    }
    fn frames(&self, done: usize, total: usize) {
        Report::frames(self, done, total)
    }
}

/// Bakes this process's share `mine` of the sequence `frames` into `out`
/// (`aurora::app::bake_sequence`), and says how it went.
fn bake_frames(scene: &Scene, out: &Path, frames: &[i64], mine: &[i64], rebake: bool, say: &Report) -> Result<()> {
    let t0 = std::time::Instant::now();
    let n = aurora::app::bake_sequence::bake_frames(scene, out, frames, mine, rebake, say)?;
    say.say(|| {
        let secs = t0.elapsed().as_secs_f64();
        format!(
            "{} frames baked, {} already complete, of {} for this shard ({} in the sequence) in {secs:.2} s ({:.3} frames/s); stage {}",
            n.baked,
            n.skipped,
            mine.len(),
            frames.len(),
            if secs > 0.0 { n.baked as f64 / secs } else { 0.0 },
            out.join(aurora::io::bake_folder::USDA_NAME).display()
        )
    });
    Ok(())
}
