//! A plan before the farm: what baking a frame range will cost, measured on
//! a few of its frames instead of the whole range (`aurora bake --plan`).
//!
//! The model. A sequence's frames differ only in time (the closed-form
//! motion of `crate::pipeline::motion`), so their cost is smooth in the frame
//! number: the bytes of a frame follow its active voxels, its CPU time its
//! beams, gather and write, and both change slowly as curtains fold and
//! drift. The plan bakes `samples` frames spread evenly over the range
//! (first, last and evenly between, by index: [`sample_frames`]) exactly as
//! a farm task would: each at its own time, one [`crate::pipeline::plan::BakePlan`]
//! carried from one to the next (`bake::bake_reusing`, as `aurora bake
//! --frames` does), and each frame's files staged and committed by the same
//! writer the sequence uses (`crate::farm::frame_files::stage_frame`) into a scratch folder
//! that is removed afterwards. It then estimates
//!
//! ```text
//! bytes per frame   B = mean over samples of (frame VDB + frame report)
//! total bytes         = N B + U (what one task writes)
//! stage             U = aurora.usda listing every frame of the sequence,
//!                       counted exactly by its writer into a sink that
//!                       keeps nothing; every task writes it whole
//! CPU per frame     C = mean CPU of the samples after the first
//! setup per task    S = CPU of the first sample - C (the plan: footprints,
//!                       atmosphere, colour table; a task pays it once)
//! total CPU           = S + N C      (one task baking all N frames)
//! peak memory         = the process's peak resident set after the samples
//! ```
//!
//! CPU time is the process's user + system time (`getrusage`), summed over
//! its threads, so it does not depend on how many cores a task gets; wall
//! time is printed beside it for this machine. The peak resident set is what
//! one task baking frames one after the other needs (each frame's grids are
//! freed before the next; the plan is shared). The memory budget's model
//! (`crate::pipeline::memory::budget::estimate`, the upper bound a bake is
//! refused by) is printed beside it, and the expected peak of one bake on
//! the plan's threads, from a traced sample of the last sample frame's
//! beams (`crate::pipeline::memory::expected`). With one sample, C is
//! that sample's CPU (setup included) and S is 0: an upper bound.
//!
//! The task is one shard's share (`--shard I/N`): its N frames are the
//! ones it bakes, and the samples are drawn from them, but the stage it
//! writes lists the whole sequence (each shard rewrites the same stage,
//! `crate::farm::frame_files::write_sequence_usda`), so for a long range
//! the stage can outweigh the task's frames. The ownership record (about
//! 100 bytes, once per folder) is left out.
//!
//! The render. A show's cost is mostly its render, so with a render probe
//! (the command line gives one: `crate::app::render_cost`) the plan also
//! renders its first calibration frame from the VDB it wrote, as a farm's
//! `aurora render --vdb` would, at a reduced size, and scales:
//!
//! ```text
//! render CPU per frame  R = F + k W H spp
//! F = CPU to open the VDB and build the medium (paid per frame)
//! k = CPU per pixel sample, measured at the reduced size (the same
//!     picture scaled, so the same mix of sky and aurora per pixel)
//! ```
//!
//! What it does not know: how a farm packs tasks (a task's setup is paid
//! once per task; divide the range by the tasks' frame count to add it per
//! task), and file-system overheads beyond the files' bytes.

use crate::io::bake_folder::{self, OutputError};
use crate::pipeline::bake::identity::BakeIdentity;
use crate::pipeline::bake::{self, BakeError};
use crate::pipeline::memory::budget::{self, LeafCount};
use crate::pipeline::plan::BakePlan;
use crate::scene::Scene;
use crate::util::progress::{NoProgress, Progress};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The most frames a plan bakes to calibrate.
pub const MAX_SAMPLES: usize = 16;

/// Why a plan could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    #[error(transparent)]
    Bake(#[from] BakeError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("the plan's scratch folder `{path}`: {message}")]
    Scratch { path: PathBuf, message: String },
    #[error("--plan needs at least one frame")]
    NoFrames,
    /// The render probe failed on a frame the plan baked.
    #[error("the plan's render of frame {frame}: {message}")]
    Render { frame: i64, message: String },
    /// The task's shard holds no frame of the range.
    #[error("--shard {index}/{count}: this shard has no frame to plan: the range has {frames} frames, fewer than the {count} shards (shard I takes the frames at positions I, I+N, ...; shards {frames} to {} get none)", count - 1)]
    EmptyShard { index: u64, count: u64, frames: usize },
}

impl PlanError {
    /// The user's input is at fault (a scene the bake cannot honour).
    pub fn is_input(&self) -> bool {
        match self {
            PlanError::Bake(e) => e.is_input(),
            PlanError::Output(e) => e.is_input(),
            PlanError::Scratch { .. } | PlanError::Render { .. } => false,
            PlanError::NoFrames | PlanError::EmptyShard { .. } => true,
        }
    }
}

/// The render's cost, calibrated on one frame (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderCost {
    /// The frame it was calibrated on.
    pub frame: i64,
    /// The image the plan is for: the scene's size and samples per pixel.
    pub width: usize,
    pub height: usize,
    pub spp: usize,
    /// The reduced image it was measured on.
    pub calibrated_width: usize,
    pub calibrated_height: usize,
    /// CPU seconds to open the VDB and build the medium: F.
    pub fixed_cpu_s: f64,
    /// CPU seconds per pixel sample: k.
    pub cpu_per_sample_s: f64,
}

impl RenderCost {
    /// CPU seconds to render one frame at the plan's size: F + k W H spp.
    pub fn cpu_per_frame_s(&self) -> f64 {
        self.fixed_cpu_s + self.cpu_per_sample_s * (self.width * self.height * self.spp) as f64
    }
}

/// What renders a baked frame to measure the render's cost: given the
/// scene at the frame's time and the frame's VDB.
pub type RenderProbe<'a> = &'a dyn Fn(&Scene, &Path, i64) -> Result<RenderCost, String>;

/// One calibration frame, measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    pub frame: i64,
    pub time_s: f64,
    /// The frame's VDB, bytes.
    pub vdb_bytes: u64,
    /// The frame's report (aurora.NNNN.json), bytes.
    pub report_bytes: u64,
    /// User + system CPU seconds of its bake and write.
    pub cpu_s: f64,
    pub wall_s: f64,
}

/// The estimate for a frame range (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct CostPlan {
    /// The frames the task bakes.
    pub frames: usize,
    /// The frames of the whole sequence (its stage lists them all).
    pub sequence_frames: usize,
    /// The task's shard, (index, count), when it is one.
    pub shard: Option<(u64, u64)>,
    pub first: i64,
    pub last: i64,
    pub samples: Vec<Sample>,
    pub bytes_per_frame: f64,
    /// The sequence stage, aurora.usda, as the task writes it (every frame
    /// of the sequence listed).
    pub stage_bytes: u64,
    pub total_bytes: f64,
    pub cpu_per_frame_s: f64,
    pub setup_cpu_s: f64,
    pub total_cpu_s: f64,
    pub wall_per_frame_s: f64,
    /// Peak resident set of this process after the samples, bytes.
    pub peak_rss_bytes: f64,
    /// The memory budget's model of one bake, bytes.
    pub budget_bytes: f64,
    /// The expected peak of one bake on `threads` threads, bytes, from a
    /// traced sample of the last calibration frame's beams
    /// (`crate::pipeline::memory::expected`); the budget's is the upper
    /// bound the bake is refused by.
    pub expected_peak_bytes: Option<f64>,
    /// Worker threads the samples ran on (wall time depends on it; CPU time does not).
    pub threads: usize,
    /// The sequence's frame rate (`animation.fps`).
    pub fps: f64,
    /// The camera is a fisheye: the frames are dome masters.
    pub dome: bool,
    /// The render's cost, when the plan was given a render probe.
    pub render: Option<RenderCost>,
}

/// Frame rates the fulldome show file format takes (IMERSA / fulldome.org
/// Dome Master Show File Format: 30 or 60 frames per second).
pub const FULLDOME_FPS: [f64; 2] = [30.0, 60.0];

/// Up to `n` frames of `frames` spread evenly by index, first and last
/// included, in order and distinct.
pub fn sample_frames(frames: &[i64], n: usize) -> Vec<i64> {
    let n = n.clamp(1, MAX_SAMPLES).min(frames.len());
    if n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![frames[0]];
    }
    let last = frames.len() - 1;
    let mut out: Vec<i64> = (0..n).map(|i| frames[(i * last + (n - 1) / 2) / (n - 1)]).collect();
    out.dedup();
    out
}

/// This process's user + system CPU seconds and peak resident set (bytes).
#[cfg(unix)]
pub fn usage() -> (f64, f64) {
    // SAFETY: getrusage writes one plain struct we own.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    let ok = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } == 0;
    if !ok {
        return (0.0, 0.0);
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    // ru_maxrss is in KiB on Linux.
    (secs(u.ru_utime) + secs(u.ru_stime), u.ru_maxrss as f64 * 1024.0)
}

/// This process's user + kernel CPU seconds and peak working set (bytes):
/// Windows' `GetProcessTimes` and `K32GetProcessMemoryInfo` (kernel32).
#[cfg(windows)]
pub fn usage() -> (f64, f64) {
    /// PROCESS_MEMORY_COUNTERS.
    #[repr(C)]
    #[derive(Default)]
    struct Counters {
        cb: u32,
        page_faults: u32,
        peak_working_set: usize,
        rest: [usize; 7],
    }
    #[link(name = "kernel32")]
    extern "system" {
        fn GetCurrentProcess() -> isize;
        fn GetProcessTimes(process: isize, creation: *mut u64, exit: *mut u64, kernel: *mut u64, user: *mut u64) -> i32;
        fn K32GetProcessMemoryInfo(process: isize, counters: *mut Counters, cb: u32) -> i32;
    }
    let (mut creation, mut exit, mut kernel, mut user) = (0u64, 0u64, 0u64, 0u64);
    let mut c = Counters { cb: std::mem::size_of::<Counters>() as u32, ..Default::default() };
    // SAFETY: the pseudo-handle of this process, and plain out-structs we own
    // (a FILETIME is two u32s, which a u64 holds at a stricter alignment).
    let (times, memory) = unsafe {
        let me = GetCurrentProcess();
        (GetProcessTimes(me, &mut creation, &mut exit, &mut kernel, &mut user) != 0, K32GetProcessMemoryInfo(me, &mut c, c.cb) != 0)
    };
    // FILETIME durations are in 100 ns.
    let cpu = if times { (kernel + user) as f64 * 1e-7 } else { 0.0 };
    (cpu, if memory { c.peak_working_set as f64 } else { 0.0 })
}

/// Removes the scratch folder however the plan ends.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A new, empty folder of ours under the system's temporary directory.
fn scratch_folder() -> Result<Scratch, PlanError> {
    let base = std::env::temp_dir();
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0);
    let path = base.join(format!("aurora-plan-{}-{nanos}", std::process::id()));
    std::fs::create_dir(&path).map_err(|e| PlanError::Scratch { path: path.clone(), message: e.to_string() })?;
    Ok(Scratch(path))
}

/// What one farm task bakes: its frames (`frames`, ascending), the sequence
/// they belong to (`sequence`, whose stage the task writes) and its shard
/// (index, count) when it is one.
#[derive(Clone, Copy, Debug)]
pub struct Task<'a> {
    pub sequence: &'a [i64],
    pub frames: &'a [i64],
    pub shard: Option<(u64, u64)>,
}

fn file_len(path: &Path) -> Result<u64, PlanError> {
    std::fs::metadata(path).map(|m| m.len()).map_err(|e| PlanError::Scratch { path: path.to_path_buf(), message: e.to_string() })
}

/// Bakes `samples` frames of `frames` (module docs) and estimates the
/// range, baked by one task. Nothing is written outside a scratch folder,
/// which is removed.
pub fn plan(scene: &Scene, frames: &[i64], samples: usize, progress: &dyn Progress) -> Result<CostPlan, PlanError> {
    plan_task(scene, Task { sequence: frames, frames, shard: None }, samples, None, progress)
}

/// [`plan`] for one task of a sequence: its frames sampled and estimated,
/// and the stage counted for the whole sequence it writes (module docs).
/// A shard without frames is refused naming the shard.
pub fn plan_task(
    scene: &Scene,
    task: Task<'_>,
    samples: usize,
    render: Option<RenderProbe<'_>>,
    progress: &dyn Progress,
) -> Result<CostPlan, PlanError> {
    let frames = task.frames;
    let (&first, &last) = match (frames.first(), frames.last()) {
        (Some(a), Some(b)) => (a, b),
        _ => {
            return Err(match task.shard {
                Some((index, count)) => PlanError::EmptyShard { index, count, frames: task.sequence.len() },
                None => PlanError::NoFrames,
            })
        }
    };
    let fields = bake_folder::stage_fields(scene);
    let stage_bytes = crate::farm::frame_files::sequence_usda_bytes(task.sequence, scene.animation.fps, &fields)
        .map_err(|e| OutputError::Write { path: PathBuf::from(bake_folder::USDA_NAME), message: e.to_string() })?;
    let scratch = scratch_folder()?;
    let identity = BakeIdentity::of(scene);
    let mut carried: Option<BakePlan> = None;
    let mut beams = 0;
    let mut measured = Vec::new();
    let mut first_frame: Option<(Scene, PathBuf, i64)> = None;
    for frame in sample_frames(frames, samples) {
        let at = Scene { animation: crate::pipeline::motion::at_frame(&scene.animation, frame), ..scene.clone() };
        let (cpu0, _) = usage();
        let t0 = Instant::now();
        let (b, p) = bake::bake_reusing(&at, carried.as_ref(), progress)?;
        carried = Some(p);
        beams = b.stats.beams;
        let staged = crate::farm::frame_files::stage_frame(&at, &b, &scratch.0, frame, &identity)?;
        let report = staged.commit()?;
        let wall_s = t0.elapsed().as_secs_f64();
        let (cpu1, _) = usage();
        measured.push(Sample {
            frame,
            time_s: at.animation.time_s,
            vdb_bytes: file_len(&report.vdb)?,
            report_bytes: file_len(&report.json_path)?,
            cpu_s: cpu1 - cpu0,
            wall_s,
        });
        drop(b);
        if first_frame.is_none() {
            first_frame = Some((at, report.vdb.clone(), frame));
        }
    }
    // The bake's peak, taken before the render probe (a farm renders in
    // tasks of its own).
    let (_, peak_rss_bytes) = usage();
    let mut plan = estimate(scene, frames.len(), first, last, measured, stage_bytes, peak_rss_bytes);
    if let Some(p) = &carried {
        let expected = crate::pipeline::memory::expected::expected_peak(p, beams, plan.threads).map_err(BakeError::from)?;
        plan.expected_peak_bytes = Some(expected.bytes);
    }
    if let (Some(probe), Some((at, vdb, frame))) = (render, first_frame) {
        plan.render = Some(probe(&at, &vdb, frame).map_err(|message| PlanError::Render { frame, message })?);
    }
    plan.sequence_frames = task.sequence.len();
    plan.shard = task.shard;
    Ok(plan)
}

/// The module docs' estimate from measured samples.
pub fn estimate(scene: &Scene, n: usize, first: i64, last: i64, samples: Vec<Sample>, stage_bytes: u64, peak_rss_bytes: f64) -> CostPlan {
    let mean = |v: &mut dyn Iterator<Item = f64>| {
        let (s, k) = v.fold((0.0, 0usize), |(s, k), x| (s + x, k + 1));
        if k == 0 {
            0.0
        } else {
            s / k as f64
        }
    };
    let bytes_per_frame = mean(&mut samples.iter().map(|s| (s.vdb_bytes + s.report_bytes) as f64));
    let (cpu_per_frame_s, setup_cpu_s, wall_per_frame_s) = if samples.len() >= 2 {
        let c = mean(&mut samples[1..].iter().map(|s| s.cpu_s));
        let w = mean(&mut samples[1..].iter().map(|s| s.wall_s));
        (c, (samples[0].cpu_s - c).max(0.0), w)
    } else {
        (samples.first().map_or(0.0, |s| s.cpu_s), 0.0, samples.first().map_or(0.0, |s| s.wall_s))
    };
    CostPlan {
        frames: n,
        sequence_frames: n,
        shard: None,
        first,
        last,
        bytes_per_frame,
        stage_bytes,
        total_bytes: bytes_per_frame * n as f64 + stage_bytes as f64,
        cpu_per_frame_s,
        setup_cpu_s,
        total_cpu_s: setup_cpu_s + cpu_per_frame_s * n as f64,
        wall_per_frame_s,
        peak_rss_bytes,
        budget_bytes: budget::estimate(&BakePlan::new(scene, &NoProgress), LeafCount::Bands).total(),
        expected_peak_bytes: None,
        threads: rayon::current_num_threads(),
        samples,
        fps: scene.animation.fps,
        dome: scene.camera.projection == crate::scene::Projection::Fisheye,
        render: None,
    }
}

/// Bytes for a person: B, KB, MB, GB, TB (powers of 1000, as disks are sold).
pub fn human_bytes(b: f64) -> String {
    let units = ["B", "KB", "MB", "GB", "TB", "PB"];
    let mut x = b;
    let mut i = 0;
    while x >= 1000.0 && i + 1 < units.len() {
        x /= 1000.0;
        i += 1;
    }
    if i == 0 {
        format!("{x:.0} {}", units[i])
    } else {
        format!("{x:.1} {}", units[i])
    }
}

/// Seconds for a person: s, min, h.
pub fn human_seconds(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

impl CostPlan {
    /// What a task pays once, before its frames (the first sample's CPU time
    /// above the later ones': the plan, atmosphere and colour table that the
    /// later frames reuse), in words; a first frame that cost no more than
    /// the others (a difference lost in the timing noise) says so rather
    /// than print a zero.
    pub fn setup_words(&self) -> String {
        if self.setup_cpu_s >= 0.05 {
            format!("+ {} once per task for the plan", human_seconds(self.setup_cpu_s))
        } else {
            "the first frame took no more CPU than the others: no cost once per task measured".into()
        }
    }

    /// The plan as a table for a terminal.
    pub fn text(&self) -> String {
        let shard = match self.shard {
            Some((i, n)) => format!(" of shard {i}/{n} (the sequence has {} frames)", self.sequence_frames),
            None => String::new(),
        };
        let mut t = format!(
            "plan for frames {}-{} ({} frames){shard}, from {} calibration frames baked on {} threads:\n",
            self.first,
            self.last,
            self.frames,
            self.samples.len(),
            self.threads
        );
        t += "  frame   time_s   vdb_bytes  report_bytes   cpu_s  wall_s\n";
        for s in &self.samples {
            t += &format!(
                "  {:>5} {:>8.3} {:>11} {:>13} {:>7.2} {:>7.2}\n",
                s.frame, s.time_s, s.vdb_bytes, s.report_bytes, s.cpu_s, s.wall_s
            );
        }
        t += &format!("bytes per frame      {} ({:.0} B)\n", human_bytes(self.bytes_per_frame), self.bytes_per_frame);
        t += &format!(
            "bytes in total       {} ({} frames' VDBs and reports, and the stage aurora.usda, {}, listing the sequence's {} frames)\n",
            human_bytes(self.total_bytes),
            self.frames,
            human_bytes(self.stage_bytes as f64),
            self.sequence_frames
        );
        t += &format!(
            "peak memory per task {} measured ({} by the memory budget's model)\n",
            crate::util::memory::gib(self.peak_rss_bytes),
            crate::util::memory::gib(self.budget_bytes)
        );
        if let Some(e) = self.expected_peak_bytes {
            t += &format!(
                "memory per bake      bound {} (the refusal's), expected peak {} at {} threads\n",
                crate::util::memory::gib(self.budget_bytes),
                crate::util::memory::gib(e),
                self.threads
            );
        }
        t += &format!("CPU per frame        {} ({})\n", human_seconds(self.cpu_per_frame_s), self.setup_words());
        t += &format!("CPU in total         {} ({:.0} CPU-hours)\n", human_seconds(self.total_cpu_s), self.total_cpu_s / 3600.0);
        t += &format!(
            "wall per frame       {} on {} threads here ({:.0} frames per hour per task)",
            human_seconds(self.wall_per_frame_s),
            self.threads,
            if self.wall_per_frame_s > 0.0 { 3600.0 / self.wall_per_frame_s } else { 0.0 }
        );
        if let Some(r) = &self.render {
            let total = r.cpu_per_frame_s() * self.frames as f64;
            t += &format!(
                "\nrender CPU per frame {} at {}x{}, {} spp ({} to open the VDB and build, {:.3} us a pixel sample; measured on frame {} at {}x{})",
                human_seconds(r.cpu_per_frame_s()),
                r.width,
                r.height,
                r.spp,
                human_seconds(r.fixed_cpu_s),
                r.cpu_per_sample_s * 1e6,
                r.frame,
                r.calibrated_width,
                r.calibrated_height
            );
            t += &format!("\nrender CPU in total  {} ({:.1} CPU-hours)", human_seconds(total), total / 3600.0);
            t += &format!("\nbake and render      {:.1} CPU-hours", (total + self.total_cpu_s) / 3600.0);
        }
        t += &format!("\nshow length          {} at {} fps", human_seconds(self.sequence_frames as f64 / self.fps), self.fps);
        if let Some(note) = self.delivery_note() {
            t += &format!("\n{note}");
        }
        t
    }

    /// For dome masters at a rate the fulldome show file format does not
    /// take, what to set.
    pub fn delivery_note(&self) -> Option<String> {
        (self.dome && !FULLDOME_FPS.contains(&self.fps)).then(|| {
            format!(
                "note: dome masters are delivered at 30 or 60 fps (the fulldome Dome Master Show File Format); this scene has {} (set animation.fps)",
                self.fps
            )
        })
    }

    /// The plan as one JSON object.
    pub fn json(&self) -> serde_json::Value {
        json!({
            "frames": self.frames,
            "sequence_frames": self.sequence_frames,
            "shard": self.shard.map(|(i, n)| json!([i, n])),
            "first": self.first,
            "last": self.last,
            "samples": self.samples.iter().map(|s| json!({
                "frame": s.frame, "time_s": s.time_s, "vdb_bytes": s.vdb_bytes,
                "report_bytes": s.report_bytes, "cpu_s": s.cpu_s, "wall_s": s.wall_s,
            })).collect::<Vec<_>>(),
            "bytes_per_frame": self.bytes_per_frame,
            "stage_bytes": self.stage_bytes,
            "total_bytes": self.total_bytes,
            "cpu_per_frame_s": self.cpu_per_frame_s,
            "setup_cpu_s": self.setup_cpu_s,
            "total_cpu_s": self.total_cpu_s,
            "wall_per_frame_s": self.wall_per_frame_s,
            "peak_rss_bytes": self.peak_rss_bytes,
            "budget_bytes": self.budget_bytes,
            "expected_peak_bytes": self.expected_peak_bytes,
            "threads": self.threads,
            "fps": self.fps,
            "render": self.render.as_ref().map(|r| json!({
                "frame": r.frame, "width": r.width, "height": r.height, "spp": r.spp,
                "calibrated_width": r.calibrated_width, "calibrated_height": r.calibrated_height,
                "fixed_cpu_s": r.fixed_cpu_s, "cpu_per_sample_s": r.cpu_per_sample_s,
                "cpu_per_frame_s": r.cpu_per_frame_s(), "total_cpu_s": r.cpu_per_frame_s() * self.frames as f64,
            })),
            "show_seconds": self.sequence_frames as f64 / self.fps,
            "delivery_note": self.delivery_note(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_spread_evenly_first_and_last_included() {
        let f: Vec<i64> = (1..=100).collect();
        assert_eq!(sample_frames(&f, 3), vec![1, 51, 100]);
        assert_eq!(sample_frames(&f, 2), vec![1, 100]);
        assert_eq!(sample_frames(&f, 1), vec![1]);
        assert_eq!(sample_frames(&[4, 9], 5), vec![4, 9]);
        assert_eq!(sample_frames(&[7], 3), vec![7]);
        assert!(sample_frames(&[], 3).is_empty());
        let s = sample_frames(&f, 1000);
        assert_eq!(s.len(), MAX_SAMPLES);
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        assert_eq!((s[0], *s.last().unwrap()), (1, 100));
    }

    fn sample(frame: i64, bytes: u64, cpu: f64) -> Sample {
        Sample { frame, time_s: 0.0, vdb_bytes: bytes, report_bytes: 0, cpu_s: cpu, wall_s: cpu / 2.0 }
    }

    /// The estimate's arithmetic (module docs): setup is what the first
    /// sample paid beyond the others' mean.
    #[test]
    fn estimate_is_the_module_docs_model() {
        let s = Scene::default();
        let p = estimate(&s, 100, 1, 100, vec![sample(1, 100, 5.0), sample(50, 200, 2.0), sample(100, 300, 4.0)], 1000, 1e9);
        assert_eq!(p.bytes_per_frame, 200.0);
        assert_eq!(p.total_bytes, 200.0 * 100.0 + 1000.0);
        assert_eq!(p.cpu_per_frame_s, 3.0);
        assert_eq!(p.setup_cpu_s, 2.0);
        assert_eq!(p.total_cpu_s, 2.0 + 300.0);
        assert_eq!(p.wall_per_frame_s, 1.5);
        let one = estimate(&s, 10, 1, 10, vec![sample(1, 100, 5.0)], 0, 1e9);
        assert_eq!((one.cpu_per_frame_s, one.setup_cpu_s, one.total_cpu_s), (5.0, 0.0, 50.0));
        assert_eq!(p.setup_words(), "+ 2.0 s once per task for the plan");
        assert!(one.setup_words().starts_with("the first frame took no more CPU"), "{}", one.setup_words());
        assert!(one.text().contains(&one.setup_words()));
    }

    #[test]
    fn human_units() {
        assert_eq!(human_bytes(999.0), "999 B");
        assert_eq!(human_bytes(187.5e6), "187.5 MB");
        assert_eq!(human_bytes(3.4e12), "3.4 TB");
        assert_eq!(human_seconds(9.2), "9.2 s");
        assert_eq!(human_seconds(600.0), "10.0 min");
        assert_eq!(human_seconds(22.0 * 3600.0), "22.0 h");
    }
}
