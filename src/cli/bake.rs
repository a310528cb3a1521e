//! `aurora bake`: one bake into a folder ([`bake_one`]), or a frame
//! sequence ([`bake_frames`]), resumed frame by frame: a frame already
//! complete for this bake is skipped, one another process is baking is
//! waited for (`aurora::sequence`, `aurora::outputs::lock_frame`).

use super::args::BakeArgs;
use super::bars::Bars;
use super::exit::InputError;
use super::frames::frame_selection;
use super::{load_scene, print_warnings, with_threads};
use anyhow::Result;
use aurora::scene::Scene;
use std::path::Path;

pub fn run(a: BakeArgs) -> Result<()> {
    let BakeArgs { scene, out, seed, frames, shard, sequence, rebake, common } = a;
    let mut scene = load_scene(&scene)?;
    if let Some(s) = seed {
        scene.seed = s;
    }
    let Some(spec) = frames else {
        return with_threads(common.threads, || bake_one(&scene, &out, common.quiet));
    };
    let (mut frames, mine) = frame_selection(&spec, shard.as_deref())?;
    if let Some(seq) = sequence {
        let (all, _) = frame_selection(&seq, None)?;
        if let Some(f) = frames.iter().find(|f| all.binary_search(f).is_err()) {
            return Err(InputError(format!("--frames `{spec}`: frame {f} is not in --sequence `{seq}`")).into());
        }
        frames = all;
    }
    with_threads(common.threads, || bake_frames(&scene, &out, &frames, &mine, rebake, common.quiet))
}

/// One bake into `out`: aurora.vdb, aurora.usda and bake.json.
fn bake_one(scene: &Scene, out: &Path, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    // The folder is checked and locked before the bake, not after it.
    let _lock =
        aurora::outputs::prepare(out, || eprintln!("aurora: another bake is writing to {}; waiting for it to finish", out.display()))?;
    let bake = aurora::bake::bake(scene, bars.progress())?;
    print_warnings(&bake.stats.warnings);
    let report = aurora::outputs::write_outputs_locked(scene, &bake, out)?;
    if !quiet {
        eprintln!("{}", report.summary());
    }
    Ok(())
}

/// Bakes this process's share `mine` of the sequence `frames` into `out`
/// (a folder of one bake: `aurora::sequence`; `rebake` deletes another's).
fn bake_frames(scene: &Scene, out: &Path, frames: &[i64], mine: &[i64], rebake: bool, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    let progress = bars.progress();
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
