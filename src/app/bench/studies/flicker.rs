//! The animation study: flicker against beam count, and the cost of a frame.
//!
//! Flicker. Between two consecutive frames (t0 and t0 + 1 / fps) the grid
//! changes because the aurora moves, and because the Monte Carlo noise
//! changes. The motion's own change is measured on a converged pair (the
//! reference beam count): M = relRMS(ref(t1), ref(t0)). At a test beam count
//! the change is C = relRMS(grid(t1), grid(t0)); the study's error is
//! C / M (1: the frames differ only as much as the motion makes them; the
//! excess C / M - 1 is the flicker). Two methods: "beam identity" (beam i keeps its index
//! and random stream in both frames: its noise moves with the curtain,
//! [`crate::pipeline::motion`]) and "redrawn each frame" (frame t1 draws fresh
//! streams: the noise boils). Time: the bake of one frame.
//!
//! Cost. A frame at t0 and a lone frame far into a show (t = 600 s) against
//! the still (t = 0): motion is closed form in t, so they cost the same;
//! the ratios go into the study's notes, with frames per second.

use crate::app::bench::harness::{timed, Study, StudyPlan, SweepError};
use crate::app::bench::measurement::{CostUnit, Measurement};
use crate::app::bench::metrics::grid_rel_rms;
use crate::pipeline::bake;
use crate::scene::Scene;
use crate::util::progress::NoProgress;

/// Seconds into the show of the study's first frame.
pub const T0: f64 = 10.0;
/// A lone frame far into a show, s (a 10-minute planetarium show's last frame).
pub const T_LATE: f64 = 600.0;

fn at(scene: &Scene, t: f64, beams: usize, seed: u64) -> Scene {
    let mut s = scene.clone();
    s.animation.time_s = t;
    s.beams.count = beams;
    s.seed = seed;
    s
}

/// Runs the study on the reduced `scene` (its own animation parameters).
pub fn animation_study(scene: &Scene, plan: &StudyPlan, log: &(dyn Fn(&str) + Sync)) -> Result<Study, SweepError> {
    let n = scene.beams.count;
    let dt = 1.0 / scene.animation.fps;
    let t1 = T0 + dt;
    let seed = scene.seed;
    let bake_at = |t: f64, beams: usize, seed: u64| -> Result<(bake::Bake, f64), SweepError> {
        let s = at(scene, t, beams, seed);
        let (b, secs) = timed(plan.min_timing_seconds, plan.max_timing_runs, || bake::bake(&s, &NoProgress));
        Ok((b?, secs))
    };
    let n_ref = ((n as f64) * plan.reference_beams).round() as usize;
    let (r0, ref_s) = bake_at(T0, n_ref, seed)?;
    let (r1, _) = bake_at(t1, n_ref, seed)?;
    let motion = grid_rel_rms(&r1.emission, &r0.emission);
    log(&format!("animation: motion's own change between frames at {n_ref} beams: {motion:.4} relative RMS"));
    let mut ms = Vec::new();
    for &f in &plan.beam_factors {
        let beams = ((n as f64) * f).round().max(1.0) as usize;
        let (g0, s0) = bake_at(T0, beams, seed)?;
        let (g1, s1) = bake_at(t1, beams, seed)?;
        let (h1, s2) = bake_at(t1, beams, seed ^ 0x9E37_79B9)?;
        for (method, g, secs) in [("beam identity", &g1, 0.5 * (s0 + s1)), ("redrawn each frame", &h1, 0.5 * (s0 + s2))] {
            let change = grid_rel_rms(&g.emission, &g0.emission);
            let ratio = if motion > 0.0 { change / motion } else { f64::NAN };
            log(&format!("animation: {method}, {beams} beams: change {change:.4}, {ratio:.3} x the motion's own, {secs:.3} s a frame"));
            ms.push(Measurement {
                study: "animation flicker".into(),
                method: method.into(),
                param_name: "beams".into(),
                param: beams as f64,
                stage: "bake (one frame)".into(),
                cost: secs,
                unit: CostUnit::Seconds,
                error: ratio,
                metric: "frame-to-frame change / motion's own change".into(),
                scene_setting: beams == n && method == "beam identity",
            });
        }
    }
    // Cost of a frame: the still, a frame in the show, a lone late frame.
    let (_, still_s) = bake_at(0.0, n, seed)?;
    let (_, frame_s) = bake_at(T0, n, seed)?;
    let (_, late_s) = bake_at(T_LATE, n, seed)?;
    let notes = vec![
        format!("motion's own frame-to-frame change (relative RMS of the emission grid, {n_ref} beams, t = {T0} s and {T0} s + 1/{} s): {motion:.4}", scene.animation.fps),
        format!(
            "one frame at {n} beams: still (t = 0) {still_s:.3} s, frame at t = {T0} s {frame_s:.3} s ({:.2}x), lone frame at t = {T_LATE} s {late_s:.3} s ({:.2}x); {:.2} frames per second (bake only, no VDB write)",
            frame_s / still_s,
            late_s / still_s,
            1.0 / frame_s
        ),
    ];
    for l in &notes {
        log(&format!("animation: {l}"));
    }
    Ok(Study {
        name: "animation flicker".into(),
        stage: "bake (one frame)".into(),
        metric: "frame-to-frame change / motion's own change".into(),
        reference: format!("{n_ref} beams, same streams, frames at t = {T0} s and +1/fps"),
        reference_cost: ref_s,
        unit: CostUnit::Seconds,
        expected_trend: vec![("beam identity".into(), 1), ("redrawn each frame".into(), 1)],
        notes,
        measurements: ms,
    })
}
