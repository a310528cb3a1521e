//! The preview's cached stages of one scene ([`Cache`]): the plan (with
//! `grid.cycles_shell` off, [`preview_plan`]), the beam count, the photons,
//! the finished grids and the leaves pruning dropped. With the finished
//! emission those leaves are the gathered grid, restored when a camera or
//! grid edit refinishes ([`Cache::refinish`]), so no copy of the gathered
//! grid is kept. An edit that gathers again ([`Cache::rebuild`], or a
//! regather) first gathers coarse grids from a subset of the photons
//! ([`coarse_grids`]) for the coarse picture.

use super::edit::Stage;
use crate::grid::Leaf;
use crate::pipeline::bake::gather::Gathered;
use crate::pipeline::bake::stats::{NoiseEstimate, StageTimes};
use crate::pipeline::bake::{self, Bake, BakeError};
use crate::pipeline::beams::BeamStats;
use crate::pipeline::photons::GatherInput;
use crate::pipeline::plan::BakePlan;
use crate::scene::Scene;
use crate::util::progress::NoProgress;
use std::time::Instant;

/// When an edit rebuilds the grids, the coarse picture is rendered from a
/// gather on voxels this many times larger per side (the coarse picture's
/// pixels are `COARSE_FACTOR` times larger too): the splat touches about
/// `COARSE_VOXEL_FACTOR^3` times fewer voxels per photon.
pub const COARSE_VOXEL_FACTOR: f64 = 4.0;

/// ... and from every this many-th photon (its power multiplied by as
/// much): the gather's cost per photon does not shrink with the voxels'
/// count.
pub const COARSE_PHOTON_STRIDE: usize = 4;

/// Seconds the cached stages took in one update (the fields of the same
/// names of the preview's `Update`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Seconds {
    pub footprints: f64,
    pub pilot: f64,
    pub trace: f64,
    pub gather: f64,
    pub finish: f64,
}

/// Renders and writes the coarse picture of a coarse bake, the coarse
/// gather having started at the given instant.
pub(super) type ShowCoarse<'a, E> = dyn FnMut(&Bake, Instant) -> Result<(), E> + 'a;

/// The cached stages of one scene.
pub(super) struct Cache {
    pub scene: Scene,
    /// The scene's plan, with `grid.cycles_shell` off ([`preview_plan`]).
    pub plan: BakePlan,
    /// Beam count, pilot estimate and pilot warnings.
    pub count: (usize, Option<NoiseEstimate>, Vec<String>),
    pub beam_stats: BeamStats,
    /// The leaves pruning dropped from the gathered emission: with
    /// `bake.emission` (no Cycles shell) they are the gathered grid, which
    /// a camera or grid edit refinishes ([`crate::grid::Grid::restore_leaves`]).
    pub dropped: Vec<Leaf<[f32; 3]>>,
    /// The gathered emission's voxel size.
    pub voxel: (f64, String),
    pub bake: Bake,
    /// The coarse picture's grids ([`coarse_grids`]) while they match
    /// `bake` (None after a finish without a coarse gather): a `[volume]`
    /// edit renders its coarse picture from them before the full medium is
    /// rebuilt.
    pub coarse: Option<Bake>,
}

/// The preview's copy of the scene's plan: without the Cycles shell, and
/// one chunk of every beam. The shell is one voxel of active zeros around
/// both grids for Cycles' sake (`crate::pipeline::bake::finish`); the
/// reference renderer samples inactive voxels as 0 too, so it changes no
/// pixel (tested: `the_refined_picture_is_the_render_of_the_bake`) and
/// only costs the dilation and a larger medium. The preview keeps every
/// photon to gather again after an edit, so it traces as the bake traces
/// a bake of one chunk, and its memory check counts every photon.
pub(super) fn preview_plan(mut plan: BakePlan) -> BakePlan {
    plan.scene.grid.cycles_shell = false;
    plan.beam_chunk = usize::MAX;
    plan
}

impl Cache {
    /// Every stage for `scene` (a first update, or an edit from the
    /// footprints or the trace): `prev`'s plan keeps what it can
    /// ([`BakePlan::reusing`]). The coarse grids are gathered and shown
    /// (`show`) before the full gather; the bake's total time runs from `t0`.
    pub(super) fn rebuild<E: From<BakeError>>(
        prev: Option<&Cache>,
        scene: &Scene,
        t0: Instant,
        s: &mut Seconds,
        show: &mut ShowCoarse<E>,
    ) -> Result<Cache, E> {
        let nothing = &NoProgress;
        let t = Instant::now();
        let plan = preview_plan(match prev {
            Some(c) => BakePlan::reusing(scene, &c.plan, nothing),
            None => BakePlan::new(scene, nothing),
        });
        s.footprints = t.elapsed().as_secs_f64();
        bake::check_memory(&plan)?;
        let mut times = StageTimes { footprints: plan.footprint_seconds, ..StageTimes::default() };
        let count = bake::beam_count(&plan, &mut times, nothing)?;
        s.pilot = times.pilot;
        let t = Instant::now();
        let traced = crate::pipeline::bake::trace::trace_bake(&plan, count.0, nothing).map_err(BakeError::from)?;
        s.trace = t.elapsed().as_secs_f64();
        let voxel = plan.voxel_size(&traced.photons);
        let t = Instant::now();
        let input = plan.gather_input(&traced.photons);
        s.gather = t.elapsed().as_secs_f64();
        let coarse = coarse_grids(&plan, &input, voxel.0, show)?;
        let t = Instant::now();
        let emission = crate::pipeline::bake::gather::gather_from(&input, voxel.0, nothing);
        drop(input);
        s.gather += t.elapsed().as_secs_f64();
        (times.beams, times.gather) = (s.trace, s.gather);
        let beam_stats = traced.stats.clone();
        let g = crate::pipeline::bake::gather::gathered(
            &plan,
            traced.photons,
            Vec::new(),
            traced.stats,
            voxel.clone(),
            &count.2,
            count.1.clone(),
        );
        let t = Instant::now();
        let (bake, dropped) = crate::pipeline::bake::finish::finish_keeping(&plan, emission, g, times, t0, nothing)?;
        s.finish = t.elapsed().as_secs_f64();
        Ok(Cache { scene: scene.clone(), plan, count, beam_stats, dropped, voxel, bake, coarse: Some(coarse) })
    }

    /// An edit from `stage`, at most [`Stage::Gather`], with the photons
    /// kept: the plan's plain data follow the edit (footprints, atmosphere
    /// and colour table kept); a gather edit, or a camera edit that changes
    /// the (automatic) voxel size, gathers again (the coarse grids first,
    /// shown by `show`); a grid edit, or a camera edit with pruning,
    /// finishes the gathered grid again. Returns whether the grids changed;
    /// on an error the cache is as it was. `scene` is the caller's to set.
    pub(super) fn refinish<E: From<BakeError>>(
        &mut self,
        scene: &Scene,
        stage: Stage,
        t0: Instant,
        s: &mut Seconds,
        show: &mut ShowCoarse<E>,
    ) -> Result<bool, E> {
        let nothing = &NoProgress;
        let plan = preview_plan(BakePlan::reusing(scene, &self.plan, nothing));
        let mut regather = stage == Stage::Gather;
        if stage == Stage::Camera {
            // "auto" voxel size follows the camera.
            let v = plan.voxel_size(&self.bake.photons);
            regather = v.0 != self.voxel.0;
            if !regather && plan.scene.grid.prune <= 0.0 {
                (self.plan, self.voxel) = (plan, v);
                return Ok(false);
            }
        }
        if stage <= Stage::Render {
            self.plan = plan;
            return Ok(false);
        }
        let (gathered, voxel, coarse) = if regather {
            let voxel = plan.voxel_size(&self.bake.photons);
            let t = Instant::now();
            let input = plan.gather_input(&self.bake.photons);
            s.gather = t.elapsed().as_secs_f64();
            let coarse = coarse_grids(&plan, &input, voxel.0, show)?;
            let t = Instant::now();
            let gathered = crate::pipeline::bake::gather::gather_from(&input, voxel.0, nothing);
            s.gather += t.elapsed().as_secs_f64();
            (gathered, voxel, Some(coarse))
        } else {
            // The gathered grid again: the finished emission and the
            // leaves pruning dropped. (The coarse grids were finished
            // otherwise.)
            let mut gathered = self.bake.emission.clone();
            gathered.restore_leaves(self.dropped.iter().cloned());
            (gathered, self.voxel.clone(), None)
        };
        let t = Instant::now();
        let g = crate::pipeline::bake::gather::gathered(
            &plan,
            self.bake.photons.clone(),
            Vec::new(),
            self.beam_stats.clone(),
            voxel.clone(),
            &self.count.2,
            self.count.1.clone(),
        );
        (self.bake, self.dropped) = crate::pipeline::bake::finish::finish_keeping(&plan, gathered, g, StageTimes::default(), t0, nothing)?;
        s.finish = t.elapsed().as_secs_f64();
        (self.plan, self.voxel, self.coarse) = (plan, voxel, coarse);
        Ok(true)
    }
}

/// The coarse grids of an edit that gathers again: every
/// [`COARSE_PHOTON_STRIDE`]-th photon of `input`, its power multiplied by
/// the stride (the same expected emission), gathered on voxels
/// [`COARSE_VOXEL_FACTOR`] times larger than `voxel_km` and finished, then
/// shown (`show`). Only the coarse picture comes from a photon subset; the
/// refined ones use every photon.
fn coarse_grids<E: From<BakeError>>(plan: &BakePlan, input: &GatherInput, voxel_km: f64, show: &mut ShowCoarse<E>) -> Result<Bake, E> {
    let t = Instant::now();
    let nothing = &NoProgress;
    let v = COARSE_VOXEL_FACTOR * voxel_km;
    let emission = crate::pipeline::bake::gather::gather_from(&input.every(COARSE_PHOTON_STRIDE), v, nothing);
    // Only the grids are used: no photons for the power sums, no warnings.
    let g = Gathered { voxel_km: v, voxel_source: "coarse preview".into(), ..Gathered::default() };
    let b = crate::pipeline::bake::finish::finish(plan, emission, g, StageTimes::default(), t, nothing)?;
    show(&b, t)?;
    Ok(b)
}
