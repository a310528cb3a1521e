//! The studies of `aurora bench`: each sweeps one method choice on the
//! reduced scene ([`super::reduced`]) and measures, per setting, the wall time
//! of the stage the choice affects and the error against a converged
//! reference of the same quantity.
//!
//! | study | swept | timed stage | reference | metric |
//! |---|---|---|---|---|
//! | photon count | beams, r fixed; scene's and old estimators | beams + gather | kd-tree, `M` beams, same r, voxel | rel. RMS of `emission` |
//! | gather radius | r, beams fixed | gather | kd-tree, `M` beams, r / 2, voxel / 2 | rel. RMS of `emission` |
//! | gather method | kd-tree, splat, report2014, old estimators, beams | gather | kd-tree, `M` beams | rel. RMS of `emission` |
//! | voxel size | voxel, per gather method | gather | same photons and method, fine voxels | rel. RMS of `emission` |
//! | primary-ray integration | fixed step h, exact | render (pixel loop) | exact integration | mean rel. luminance error, pixels > 1 % of peak |
//! | pruning | error budget `grid.prune` | VDB write (in memory) | the unpruned bake's image | mean rel. luminance error, pixels > 1 % of peak |
//! | storage (scene camera, dome master) | half floats, pruning budget, high-column altitude, Cycles shell | file size (MB, not a time) | the unpruned full-float file's image | mean rel. luminance error, pixels > 1 % of peak |
//! | shadow rays | shadow rays per hit, pixel samples | render (pixel loop) | same estimator, many samples | mean rel. luminance error, terrain pixels > 1 % of peak |
//!
//! "Old estimators" ([`old_estimators`]: point kernels, random starts, one
//! sampled energy per beam where the build has `beams.deposition`) are the
//! earlier estimators, traced and gathered afresh at each beam count
//! and measured against the same reference (the scene's estimators), so
//! their error also holds the small bias between point and segment kernels;
//! both series share one chart, time against error.
//!
//! Noise references share their first beams (or samples) with every test
//! run: beam `i` has the random stream `(seed, curtain seed, i)` whatever the
//! count, and a pixel's shadow samples come from one stream in order. The
//! error of `n` samples against `M` is then `sigma sqrt(1/n - 1/M)`, the
//! test's own noise slightly understated (by 1 - sqrt(1 - n/M) relative: 6 %
//! at n = M / 8), never inflated by the reference's. From the photon-count
//! reference, `sigma / sqrt(M)` (the reference's own noise) is estimated as
//! `err(N) / sqrt(M / N - 1)`.
//!
//! Times: each timed call is repeated until it has used
//! [`Plan::min_timing_seconds`] (at most [`Plan::max_timing_runs`] runs) and
//! the fastest run is kept (the machine may be shared; the fastest run is the
//! least disturbed). A setting that several studies share (the scene's own
//! gather appears in four) is gathered and timed once and reused, so it has
//! one time everywhere; after all studies every gather setting is timed once
//! more ([`Bench::retime`]), minutes later, and the fastest of all its runs
//! kept, so a burst of load from other processes does not single out the
//! settings measured during it. Results are deterministic; only the times
//! vary between runs.

use super::measurement::{Cost, CostUnit, Measurement};
use super::reduced::volume_camera;
use crate::grid::Grid;
use crate::pipeline::bake::{self, BakeError};
use crate::pipeline::deposit::Photon;
use crate::pipeline::photons::gather_grid;
use crate::pipeline::plan::BakePlan;
use crate::pipeline::voxel::grid_transform;
use crate::render::{self, Image, RenderError, RenderSettings, Volume};
use crate::scene::{GatherMethod, KernelRadius, Scene, TerrainKind, VoxelSize};
use crate::util::progress::NoProgress;
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Instant;

/// What each study sweeps. Factors multiply the reduced scene's own values
/// (`N` = its beam count, `r` its kernel radius, `v` its voxel size).
#[derive(Clone, Debug, serde::Serialize)]
pub struct StudyPlan {
    pub quick: bool,
    /// Length the curtain is cut to, km ([`super::reduced::reduce`]).
    pub curtain_km: f64,
    /// Photon-count study: beams, times N.
    pub beam_factors: Vec<f64>,
    /// Beams of the gather references, times N.
    pub reference_beams: f64,
    /// Radius study: radii, times r; one curve per beam factor (times N).
    pub radius_factors: Vec<f64>,
    pub radius_beam_factors: Vec<f64>,
    /// Gather-method study: beams, times N.
    pub gather_beam_factors: Vec<f64>,
    /// Voxel study: voxel sizes, times v, and the reference's, times v.
    pub voxel_factors: Vec<f64>,
    pub reference_voxel: f64,
    /// Integration study: fixed steps, times v; image size.
    pub step_factors: Vec<f64>,
    pub volume_image: [usize; 2],
    /// Pruning study: error budgets (`grid.prune`), the unpruned bake as the
    /// reference.
    pub prune_budgets: Vec<f64>,
    /// Storage study ([`super::storage`]): altitudes of the high column, km,
    /// the mantissa bits kept, and the dome master's image size.
    pub storage_high_km: Vec<f64>,
    pub storage_mantissa_bits: Vec<u32>,
    pub dome_image: [usize; 2],
    /// Storage study: render the pictures at the scene's spp and
    /// integration instead of point-sampled ([`super::storage`]).
    pub storage_as_rendered: bool,
    /// Shadow study: samples per pixel or per hit; reference count; image size.
    pub shadow_counts: Vec<usize>,
    pub shadow_reference: usize,
    pub ground_image: [usize; 2],
    /// Repeat a timed call until it has used this long, at most
    /// `max_timing_runs` times, and keep the fastest run.
    pub min_timing_seconds: f64,
    pub max_timing_runs: usize,
    /// Time every gather setting once more after all studies (keeping the
    /// fastest of all its runs): a later, independent sample of the
    /// machine's load.
    pub retime: bool,
}

impl StudyPlan {
    /// The full bench: a few minutes on 2 cores.
    pub fn full() -> StudyPlan {
        StudyPlan {
            quick: false,
            curtain_km: 40.0,
            beam_factors: vec![0.125, 0.25, 0.5, 1.0, 2.0, 4.0],
            reference_beams: 32.0,
            radius_factors: vec![0.5, 0.7, 1.0, 1.4, 2.0, 2.8],
            radius_beam_factors: vec![1.0, 4.0],
            gather_beam_factors: vec![0.25, 0.5, 1.0, 2.0],
            voxel_factors: vec![2.0, 1.4, 1.0, 0.7, 0.5],
            reference_voxel: 0.4,
            step_factors: vec![4.0, 2.0, 1.0, 0.5, 0.25],
            volume_image: [128, 128],
            prune_budgets: vec![1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1],
            storage_high_km: vec![200.0, 220.0, 240.0, 260.0, 280.0],
            storage_mantissa_bits: vec![10, 7, 6, 5, 4, 3],
            dome_image: [256, 256],
            storage_as_rendered: false,
            shadow_counts: vec![1, 2, 4, 8, 16, 32, 64],
            shadow_reference: 512,
            ground_image: [64, 40],
            min_timing_seconds: 1.0,
            max_timing_runs: 5,
            retime: true,
        }
    }

    /// `--quick`: under a minute on 2 cores (a shorter curtain, fewer points,
    /// cheaper references).
    pub fn quick() -> StudyPlan {
        StudyPlan {
            quick: true,
            curtain_km: 20.0,
            beam_factors: vec![0.25, 0.5, 1.0, 2.0],
            reference_beams: 8.0,
            radius_factors: vec![0.5, 1.0, 2.0, 2.8],
            radius_beam_factors: vec![1.0],
            gather_beam_factors: vec![0.5, 1.0, 2.0],
            voxel_factors: vec![2.0, 1.4, 1.0],
            reference_voxel: 0.5,
            step_factors: vec![4.0, 2.0, 1.0, 0.5],
            volume_image: [64, 64],
            prune_budgets: vec![1e-3, 1e-2, 0.1],
            storage_high_km: vec![200.0, 240.0],
            storage_mantissa_bits: vec![10, 5, 3],
            dome_image: [64, 64],
            storage_as_rendered: false,
            shadow_counts: vec![1, 4, 16],
            shadow_reference: 256,
            ground_image: [32, 20],
            min_timing_seconds: 0.0,
            max_timing_runs: 1,
            retime: true,
        }
    }
}

/// One study: its measurements and how they were made.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Study {
    pub name: String,
    /// The stage whose wall time is measured.
    pub stage: String,
    pub metric: String,
    /// What the errors are measured against.
    pub reference: String,
    /// The reference's cost: wall time of its timed stage, or its file's size.
    pub reference_cost: f64,
    /// The unit of the reference's and the measurements' costs.
    pub unit: CostUnit,
    /// The parameter whose increase is expected to lower the error, per
    /// method (`+1`: error falls as the parameter grows, `-1`: it rises).
    pub expected_trend: Vec<(String, i32)>,
    pub notes: Vec<String>,
    #[serde(skip)]
    pub measurements: Vec<Measurement>,
}

/// Why a bench failed.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("bench bake: {0}")]
    Bake(#[from] BakeError),
    #[error("bench render: {0}")]
    Render(#[from] RenderError),
    #[error("bench throughput: {0}")]
    Plan(Box<crate::farm::cost_plan::PlanError>),
    /// Writing or reading back a file of the storage study (never the
    /// scene's fault: the bake it writes has been validated).
    #[error("bench storage: {0}")]
    Storage(String),
}

impl SweepError {
    /// True when the scene is at fault, as for a bake or a render (exit status 2).
    pub fn is_input(&self) -> bool {
        match self {
            SweepError::Bake(e) => e.is_input(),
            SweepError::Render(e) => e.is_input(),
            SweepError::Plan(e) => e.is_input(),
            SweepError::Storage(_) => false,
        }
    }
}

/// Runs `f` until it has used `min_seconds` (at most `max_runs` times) and
/// returns its first result with the fastest run's wall time.
pub fn timed<T>(min_seconds: f64, max_runs: usize, mut f: impl FnMut() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    let mut best = t.elapsed().as_secs_f64();
    let mut spent = best;
    let mut runs = 1;
    while spent < min_seconds && runs < max_runs {
        let t = Instant::now();
        drop(f());
        let s = t.elapsed().as_secs_f64();
        best = best.min(s);
        spent += s;
        runs += 1;
    }
    (out, best)
}

/// Everything the studies share: the reduced scene's footprints, tables,
/// field and a cache of traced photons per beam count.
pub struct Bench<'a> {
    pub scene: Scene,
    pub plan: StudyPlan,
    /// The reduced scene's bake plan (footprints, atmosphere, colour
    /// table, field, radius field).
    pub(super) bake: BakePlan,
    pub(super) photons: BTreeMap<usize, (Vec<Photon>, f64)>,
    /// Test gathers by (beams, radius bits, voxel bits, method).
    pub(super) gathers: HashMap<GatherKey, Timed<Arc<Grid<[f32; 3]>>>>,
    /// Measurements timed by a cached gather: (study, method, param bits),
    /// the gather's key and the seconds added to it (the beam trace).
    pub(super) gather_timed: Vec<((String, String, u64), GatherKey, f64)>,
    pub(super) log: &'a (dyn Fn(&str) + Sync),
}

pub(super) type GatherKey = (usize, u64, u64, u8);

pub(super) fn gather_key(n: usize, r: f64, v: f64, method: GatherMethod) -> GatherKey {
    (n, r.to_bits(), v.to_bits(), method as u8)
}

/// The scene with the earlier estimators: point kernels, random beam
/// starts, `beams.deposition = "sampled"` (one drawn energy per beam) and
/// the kd-tree gather.
pub fn old_estimators(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.photons.kernel = crate::scene::KernelShape::Point;
    s.photons.gather = GatherMethod::Kdtree;
    s.beams.starts = crate::scene::BeamStarts::Random;
    s.beams.deposition = crate::scene::Deposition::Sampled;
    s
}

/// A result and the wall time it took, seconds.
pub(super) type Timed<T> = (T, f64);

/// The curve a [`Measurement`] belongs to: its study (e.g. "photon
/// count"), its method (the curve's label), the swept parameter's name,
/// the stage whose cost is measured and the error's metric.
#[derive(Clone, Copy, Debug)]
pub(super) struct Series<'a> {
    pub(super) study: &'a str,
    pub(super) method: &'a str,
    pub(super) param_name: &'a str,
    pub(super) stage: &'a str,
    pub(super) metric: &'a str,
}

impl<'a> Bench<'a> {
    /// `scene` is the reduced scene.
    pub fn new(scene: Scene, plan: StudyPlan, log: &'a (dyn Fn(&str) + Sync)) -> Bench<'a> {
        let bake = BakePlan::new(&scene, &NoProgress);
        Bench { scene, plan, bake, photons: BTreeMap::new(), gathers: HashMap::new(), gather_timed: Vec::new(), log }
    }

    /// N, the reduced scene's beam count.
    pub fn beams(&self) -> usize {
        self.scene.beams.count
    }

    pub(super) fn beams_times(&self, factor: f64) -> usize {
        ((self.beams() as f64 * factor).round() as usize).max(1)
    }

    /// r, the scene's kernel radius, km.
    pub fn radius(&self) -> f64 {
        self.bake.kernel.base_km
    }

    /// v, the scene's voxel size, km.
    pub fn voxel(&self) -> f64 {
        match self.scene.grid.voxel_size {
            VoxelSize::Km(v) => v,
            // reduce() resolves "auto"; kept as a fallback: the kernel radius.
            VoxelSize::Auto(_) => self.bake.kernel.base_km,
        }
    }

    /// The photons of `n` beams and the fastest trace time (cached).
    pub(super) fn trace(&mut self, n: usize) -> Result<(), SweepError> {
        if self.photons.contains_key(&n) {
            return Ok(());
        }
        let (min, runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (res, secs) = timed(min, runs, || crate::pipeline::bake::trace::trace(&self.bake, n, 0, 0..n, &NoProgress));
        let ph = res.map_err(BakeError::from)?.photons;
        self.photons.insert(n, (ph, secs));
        Ok(())
    }

    pub(super) fn photons_of(&mut self, n: usize) -> Result<(&[Photon], f64), SweepError> {
        self.trace(n)?;
        let (p, s) = &self.photons[&n];
        Ok((p.as_slice(), *s))
    }

    /// Records that the time of the last measurement of `ms` is the gather
    /// `key`'s plus `extra` seconds.
    pub(super) fn note_last(&mut self, ms: &[Measurement], key: GatherKey, extra: f64) {
        if let Some(m) = ms.last() {
            self.gather_timed.push(((m.study.clone(), m.method.clone(), m.param.to_bits()), key, extra));
        }
    }

    /// Times every cached gather setting once more and sets each
    /// measurement's time from the fastest of all its runs.
    pub fn retime(&mut self, studies: &mut [Study]) -> Result<(), SweepError> {
        let mut keys: Vec<GatherKey> = self.gather_timed.iter().map(|(_, k, _)| *k).collect();
        keys.sort_unstable();
        keys.dedup();
        self.say(&format!("retiming {} gather settings", keys.len()));
        for key in keys {
            let (n, r, v, m) = (key.0, f64::from_bits(key.1), f64::from_bits(key.2), key.3);
            let method = [GatherMethod::Kdtree, GatherMethod::Splat, GatherMethod::Report2014][m as usize];
            let (_, secs) = self.gather_uncached(n, r, v, method)?;
            if let Some(entry) = self.gathers.get_mut(&key) {
                entry.1 = entry.1.min(secs);
            }
        }
        for (id, key, extra) in &self.gather_timed {
            let best = self.gathers[key].1 + extra;
            for st in studies.iter_mut() {
                for m in st.measurements.iter_mut() {
                    if (&m.study, &m.method, m.param.to_bits()) == (&id.0, &id.1, id.2) {
                        m.cost = best;
                    }
                }
            }
        }
        Ok(())
    }

    /// The scene's density gather and its label, for the studies that vary
    /// something else (photon count, radius): kd-tree or splat compute the
    /// same field; report2014 is not a density estimate, so the kd-tree
    /// stands in for it.
    pub(super) fn density_gather(&self) -> (GatherMethod, &'static str) {
        match self.scene.photons.gather {
            GatherMethod::Splat => (GatherMethod::Splat, "splat"),
            _ => (GatherMethod::Kdtree, "kd-tree"),
        }
    }

    /// [`Bench::gather_uncached`], kept for the other studies that use the
    /// same setting (test settings only: references are used once).
    pub(super) fn gather(&mut self, n: usize, r: f64, v: f64, method: GatherMethod) -> Result<Timed<Arc<Grid<[f32; 3]>>>, SweepError> {
        let key = gather_key(n, r, v, method);
        if let Some((g, s)) = self.gathers.get(&key) {
            return Ok((g.clone(), *s));
        }
        let (g, s) = self.gather_uncached(n, r, v, method)?;
        let g = Arc::new(g);
        self.gathers.insert(key, (g.clone(), s));
        Ok((g, s))
    }

    /// The emission grid of `n` beams gathered with base radius `r`, voxel
    /// `v` and `method` (radius noise as in the scene), and the gather time.
    pub(super) fn gather_uncached(&mut self, n: usize, r: f64, v: f64, method: GatherMethod) -> Result<(Grid<[f32; 3]>, f64), SweepError> {
        let b = &self.bake;
        let p = &b.scene.photons;
        let radius = crate::pipeline::plan::radius_field(KernelRadius::with_base(r, p), p, b.field.b, b.scene.beams.top_km, b.scene.seed);
        let cutoff = p.cutoff;
        let (min, runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (photons, _) = self.photons_of(n)?;
        Ok(timed(min, runs, || gather_grid(photons, grid_transform(v), &radius, cutoff, method, &NoProgress)))
    }

    pub(super) fn say(&self, s: &str) {
        (self.log)(s)
    }

    /// The old estimators ([`old_estimators`]) at `n` beams, kd-tree gather
    /// at the scene's radius and voxel: the grid, the trace time and the
    /// gather time (each the fastest of the plan's runs; not cached).
    pub(super) fn old_estimator_grid(&self, n: usize) -> Result<(Grid<[f32; 3]>, f64, f64), SweepError> {
        let s = old_estimators(&self.scene);
        // Same curtains and footprint: the plan reuses the footprints.
        let old = BakePlan::reusing(&s, &self.bake, &NoProgress);
        let (min, runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (res, trace_s) = timed(min, runs, || crate::pipeline::bake::trace::trace(&old, n, 0, 0..n, &NoProgress));
        let photons = res.map_err(BakeError::from)?.photons;
        let (v, cutoff) = (self.voxel(), self.bake.scene.photons.cutoff);
        let (g, gather_s) =
            timed(min, runs, || gather_grid(&photons, grid_transform(v), &self.bake.radius, cutoff, GatherMethod::Kdtree, &NoProgress));
        Ok((g, trace_s, gather_s))
    }

    /// Label of the old estimators' series.
    pub(super) fn old_label(&self) -> String {
        "old: point kernel, random starts, sampled deposition, kd-tree".to_string()
    }

    /// The kd-tree reference of the photon-count and gather-method studies:
    /// `M` beams, the scene's radius and voxel.
    pub(super) fn noise_reference(&mut self) -> Result<(Grid<[f32; 3]>, usize, f64), SweepError> {
        let m = self.beams_times(self.plan.reference_beams);
        self.say(&format!("reference: kd-tree, {m} beams, r = {} km, voxel {} km", self.radius(), self.voxel()));
        let (g, secs) = self.gather_uncached(m, self.radius(), self.voxel(), GatherMethod::Kdtree)?;
        Ok((g, m, secs))
    }

    /// One point of `series`: the setting `param` costs `cost` with the
    /// error `error` (`scene_setting`: the scene's own setting), said and
    /// returned as a [`Measurement`].
    pub(super) fn measure(&self, series: &Series<'_>, param: f64, cost: Cost, error: f64, scene_setting: bool) -> Measurement {
        let Series { study, method, param_name, stage, metric } = *series;
        let Cost(value, unit) = cost;
        self.say(&format!(
            "{study}: {method}, {param_name} = {param}: {value:.3} {} ({stage}), error {error:.4e}{}",
            unit.symbol(),
            if scene_setting { " [scene setting]" } else { "" }
        ));
        Measurement {
            study: study.into(),
            method: method.into(),
            param_name: param_name.into(),
            param,
            stage: stage.into(),
            cost: value,
            unit,
            error,
            metric: metric.into(),
            scene_setting,
        }
    }

    /// The reduced scene's grids at its own settings (the CLI's bake).
    pub fn bake_grids(&self) -> Result<bake::Bake, SweepError> {
        Ok(bake::bake(&self.scene, &NoProgress)?)
    }

    pub(super) fn render_timed(&self, s: &RenderSettings, vol: &Volume<'_>) -> Result<(Image, f64), SweepError> {
        let (min, max_runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (img, _) = timed(0.0, 1, || render::render(s, vol, &NoProgress));
        let img = img?;
        // The pixel loop only (the acceleration structure is built once per
        // render whatever the integrator): the fastest of the runs.
        let mut best = img.stats.render_seconds;
        let mut spent = best;
        let mut runs = 1;
        while spent < min && runs < max_runs {
            let again = render::render(s, vol, &NoProgress)?;
            best = best.min(again.stats.render_seconds);
            spent += again.stats.render_seconds;
            runs += 1;
        }
        Ok((img, best))
    }

    /// The volume studies' render settings: the bench volume camera, its
    /// image size, one sample at each pixel centre, no terrain, black sky.
    pub(super) fn volume_settings(&self) -> RenderSettings {
        let mut s = RenderSettings::from_scene(&self.scene);
        s.camera = volume_camera(&self.scene);
        s.render.width = self.plan.volume_image[0];
        s.render.height = self.plan.volume_image[1];
        s.render.spp = 1;
        s.terrain.kind = TerrainKind::None;
        s.background.radiance = [0.0; 3];
        s.background.stars = false;
        s.airglow.on = false;
        s
    }
}
