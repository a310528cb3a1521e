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
//! | shadow rays | shadow rays per hit, pixel samples | render (pixel loop) | same estimator, many samples | mean rel. luminance error, terrain pixels > 1 % of peak |
//!
//! "Old estimators" ([`old_estimators`]: point kernels, random starts, one
//! sampled energy per beam where the build has `beams.deposition`) are the
//! estimators before issue 10, traced and gathered afresh at each beam count
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

use super::chart::Measurement;
use super::metrics::{grid_rel_rms, grid_rel_rms_best_scale, image_rel_error_masked};
use super::reduced::{ground_camera, ground_terrain, volume_camera};
use crate::bake::{self, BakeError};
use crate::beams::Photon;
use crate::grid::Grid;
use crate::pipeline::{self, BakePlan, KernelRadius};
use crate::progress::NoProgress;
use crate::vdb::write::GridRef;
use crate::render::{self, Image, Integration, Prepared, RenderError, RenderSettings, Volume};
use crate::scene::{GatherMethod, Scene, TerrainKind, VoxelSize};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Instant;

/// What each study sweeps. Factors multiply the reduced scene's own values
/// (`N` = its beam count, `r` its kernel radius, `v` its voxel size).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Plan {
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

impl Plan {
    /// The full bench: a few minutes on 2 cores.
    pub fn full() -> Plan {
        Plan {
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
    pub fn quick() -> Plan {
        Plan {
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
    /// Wall time of the reference's timed stage, seconds.
    pub reference_seconds: f64,
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
    pub plan: Plan,
    /// The reduced scene's bake plan (footprints, atmosphere, colour
    /// table, field, radius field).
    bake: BakePlan,
    photons: BTreeMap<usize, (Vec<Photon>, f64)>,
    /// Test gathers by (beams, radius bits, voxel bits, method).
    gathers: HashMap<GatherKey, Timed<Arc<Grid<[f32; 3]>>>>,
    /// Measurements timed by a cached gather: (study, method, param bits),
    /// the gather's key and the seconds added to it (the beam trace).
    gather_timed: Vec<((String, String, u64), GatherKey, f64)>,
    log: &'a (dyn Fn(&str) + Sync),
}

type GatherKey = (usize, u64, u64, u8);

fn gather_key(n: usize, r: f64, v: f64, method: GatherMethod) -> GatherKey {
    (n, r.to_bits(), v.to_bits(), method as u8)
}

/// The scene with the estimators before issue 10: point kernels, random
/// beam starts and, where this build has the key, `beams.deposition =
/// "sampled"` (one drawn energy per beam), applied as a TOML overlay so the
/// bench needs no change when that key arrives. The flag says whether it
/// was applied.
pub fn old_estimators(scene: &Scene) -> (Scene, bool) {
    let mut s = scene.clone();
    s.photons.kernel = crate::scene::KernelShape::Point;
    s.beams.starts = crate::scene::BeamStarts::Random;
    let overlay = || -> Option<Scene> {
        let mut doc: toml::Table = toml::from_str(&s.to_toml()).ok()?;
        let beams = doc.get_mut("beams")?.as_table_mut()?;
        beams.insert("deposition".into(), toml::Value::String("sampled".into()));
        Scene::from_toml_str(&toml::to_string(&doc).ok()?, "old estimators").ok()
    };
    match overlay() {
        Some(t) => (t, true),
        None => (s, false),
    }
}

/// A result and the wall time it took, seconds.
type Timed<T> = (T, f64);

impl<'a> Bench<'a> {
    /// `scene` is the reduced scene.
    pub fn new(scene: Scene, plan: Plan, log: &'a (dyn Fn(&str) + Sync)) -> Bench<'a> {
        let bake = BakePlan::new(&scene, &NoProgress);
        Bench {
            scene,
            plan,
            bake,
            photons: BTreeMap::new(),
            gathers: HashMap::new(),
            gather_timed: Vec::new(),
            log,
        }
    }

    /// N, the reduced scene's beam count.
    pub fn beams(&self) -> usize {
        self.scene.beams.count
    }

    fn beams_times(&self, factor: f64) -> usize {
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
    fn trace(&mut self, n: usize) -> Result<(), SweepError> {
        if self.photons.contains_key(&n) {
            return Ok(());
        }
        let (min, runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (res, secs) = timed(min, runs, || pipeline::trace(&self.bake, n, 0, 0..n, &NoProgress));
        let ph = res.map_err(BakeError::from)?.photons;
        self.photons.insert(n, (ph, secs));
        Ok(())
    }

    fn photons_of(&mut self, n: usize) -> Result<(&[Photon], f64), SweepError> {
        self.trace(n)?;
        let (p, s) = &self.photons[&n];
        Ok((p.as_slice(), *s))
    }

    /// Records that the time of the last measurement of `ms` is the gather
    /// `key`'s plus `extra` seconds.
    fn note_last(&mut self, ms: &[Measurement], key: GatherKey, extra: f64) {
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
                        m.seconds = best;
                    }
                }
            }
        }
        Ok(())
    }

    /// [`Bench::gather_uncached`], kept for the other studies that use the
    /// same setting (test settings only: references are used once).
    fn gather(
        &mut self,
        n: usize,
        r: f64,
        v: f64,
        method: GatherMethod,
    ) -> Result<Timed<Arc<Grid<[f32; 3]>>>, SweepError> {
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
    fn gather_uncached(
        &mut self,
        n: usize,
        r: f64,
        v: f64,
        method: GatherMethod,
    ) -> Result<(Grid<[f32; 3]>, f64), SweepError> {
        let b = &self.bake;
        let radius = pipeline::radius_field(KernelRadius::with_base(r, &b.photons), &b.photons, b.field.b, b.beams.top_km, b.seed);
        let cutoff = b.photons.cutoff;
        let (min, runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (photons, _) = self.photons_of(n)?;
        Ok(timed(min, runs, || pipeline::gather_with(photons, v, &radius, cutoff, method, &NoProgress)))
    }

    fn say(&self, s: &str) {
        (self.log)(s)
    }

    /// The old estimators ([`old_estimators`]) at `n` beams, kd-tree gather
    /// at the scene's radius and voxel: the grid, the trace time and the
    /// gather time (each the fastest of the plan's runs; not cached).
    fn old_estimator_grid(&self, n: usize) -> Result<(Grid<[f32; 3]>, f64, f64), SweepError> {
        let (s, _) = old_estimators(&self.scene);
        // Same curtains and footprint: the plan reuses the footprints.
        let old = BakePlan::reusing(&s, &self.bake, &NoProgress);
        let (min, runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        let (res, trace_s) = timed(min, runs, || pipeline::trace(&old, n, 0, 0..n, &NoProgress));
        let photons = res.map_err(BakeError::from)?.photons;
        let (v, cutoff) = (self.voxel(), self.bake.photons.cutoff);
        let (g, gather_s) = timed(min, runs, || {
            pipeline::gather_with(&photons, v, &self.bake.radius, cutoff, GatherMethod::Kdtree, &NoProgress)
        });
        Ok((g, trace_s, gather_s))
    }

    /// Label of the old estimators' series.
    fn old_label(&self) -> String {
        let (_, sampled) = old_estimators(&self.scene);
        format!("old: point kernel, random starts{}, kd-tree", if sampled { ", sampled deposition" } else { "" })
    }

    /// The kd-tree reference of the photon-count and gather-method studies:
    /// `M` beams, the scene's radius and voxel.
    fn noise_reference(&mut self) -> Result<(Grid<[f32; 3]>, usize, f64), SweepError> {
        let m = self.beams_times(self.plan.reference_beams);
        self.say(&format!("reference: kd-tree, {m} beams, r = {} km, voxel {} km", self.radius(), self.voxel()));
        let (g, secs) = self.gather_uncached(m, self.radius(), self.voxel(), GatherMethod::Kdtree)?;
        Ok((g, m, secs))
    }

    #[allow(clippy::too_many_arguments)]
    fn measure(
        &self,
        study: &str,
        method: &str,
        param_name: &str,
        param: f64,
        stage: &str,
        seconds: f64,
        error: f64,
        metric: &str,
        scene_setting: bool,
    ) -> Measurement {
        self.say(&format!(
            "{study}: {method}, {param_name} = {param}: {seconds:.3} s ({stage}), error {error:.4e}{}",
            if scene_setting { " [scene setting]" } else { "" }
        ));
        Measurement {
            study: study.into(),
            method: method.into(),
            param_name: param_name.into(),
            param,
            stage: stage.into(),
            seconds,
            error,
            metric: metric.into(),
            scene_setting,
        }
    }

    /// Photon count and gather method (they share the kd-tree reference).
    pub fn photon_and_gather_studies(&mut self) -> Result<Vec<Study>, SweepError> {
        let (reference, m, ref_secs) = self.noise_reference()?;
        let n = self.beams();
        let (r, v) = (self.radius(), self.voxel());
        let metric = "relative RMS of emission";

        // Photon count at fixed radius: beams + gather time.
        let name = "photon count";
        let method = format!("kd-tree, r = {r} km");
        let mut ms = Vec::new();
        let mut err_n = None;
        for f in self.plan.beam_factors.clone() {
            let k = self.beams_times(f);
            let (g, gather_s) = self.gather(k, r, v, GatherMethod::Kdtree)?;
            let trace_s = self.photons[&k].1;
            let e = grid_rel_rms(&g, &reference);
            if k == n {
                err_n = Some(e);
            }
            ms.push(self.measure(
                name,
                &method,
                "beams",
                k as f64,
                "beams+gather",
                trace_s + gather_s,
                e,
                metric,
                k == n,
            ));
            self.note_last(&ms, gather_key(k, r, v, GatherMethod::Kdtree), trace_s);
        }
        // The old estimators over the same beam counts, on the same chart.
        let old_label = self.old_label();
        let mut old_gathers = Vec::new();
        for f in self.plan.beam_factors.clone() {
            let k = self.beams_times(f);
            let (g, trace_s, gather_s) = self.old_estimator_grid(k)?;
            let e = grid_rel_rms(&g, &reference);
            ms.push(self.measure(name, &old_label, "beams", k as f64, "beams+gather", trace_s + gather_s, e, metric, false));
            old_gathers.push((k, gather_s, e));
        }
        let mut notes = vec![format!(
            "Pure noise: the reference has the same kernel and voxels, so the error is the Monte Carlo noise of the density estimate, expected to fall as beams^-1/2 (sigma sqrt(1/n - 1/M) with the shared first beams)."
        ), format!("'{old_label}': the estimators before issue 10 (photons.kernel = \"point\", beams.starts = \"random\"), against the same reference: its error also holds the point-vs-segment kernel bias, and its streams share no beams with the reference's.")];
        if let Some(e) = err_n {
            notes.push(format!(
                "Estimated noise of the reference itself ({m} beams): err(N = {n}) / sqrt(M/N - 1) = {:.3e}.",
                e / ((m as f64 / n as f64) - 1.0).max(1e-12).sqrt()
            ));
        }
        let photon = Study {
            name: name.into(),
            stage: "beams+gather".into(),
            metric: metric.into(),
            reference: format!("kd-tree gather of {m} beams, same radius (r = {r} km, radius noise as in the scene) and voxel ({v} km)"),
            reference_seconds: ref_secs + self.photons[&m].1,
            expected_trend: vec![(method.clone(), 1), (old_label.clone(), 1)],
            notes,
            measurements: ms,
        };

        // Gather methods, each over beams: gather time only.
        let name = "gather method";
        let mut ms = Vec::new();
        let scene_gather = self.scene.photons.gather;
        let mut trend = Vec::new();
        for method in [GatherMethod::Kdtree, GatherMethod::Splat, GatherMethod::Report2014] {
            let label = match method {
                GatherMethod::Kdtree => "kd-tree (kiddo)",
                GatherMethod::Splat => "splat",
                GatherMethod::Report2014 => "report2014 (average)",
            };
            if method != GatherMethod::Report2014 {
                trend.push((label.to_string(), 1));
            }
            let mut scaled = Vec::new();
            for f in self.plan.gather_beam_factors.clone() {
                let k = self.beams_times(f);
                let (g, secs) = self.gather(k, r, v, method)?;
                let here = method == scene_gather && k == n;
                ms.push(self.measure(
                    name,
                    label,
                    "beams",
                    k as f64,
                    "gather",
                    secs,
                    grid_rel_rms(&g, &reference),
                    metric,
                    here,
                ));
                self.note_last(&ms, gather_key(k, r, v, method), 0.0);
                if method == GatherMethod::Report2014 {
                    let (e, s) = grid_rel_rms_best_scale(&g, &reference);
                    scaled.push(self.measure(
                        name,
                        "report2014, best-fit scale",
                        "beams",
                        k as f64,
                        "gather",
                        secs,
                        e,
                        metric,
                        false,
                    ));
                    self.note_last(&scaled, gather_key(k, r, v, method), 0.0);
                    self.say(&format!("  (report2014 best-fit scale factor {s:.4e})"));
                }
            }
            ms.extend(scaled);
        }
        // The old estimators' gather times (kd-tree, point photons), from
        // the photon-count study's runs at the gather study's beam counts.
        for f in self.plan.gather_beam_factors.clone() {
            let k = self.beams_times(f);
            let (gather_s, e) = match old_gathers.iter().find(|g| g.0 == k) {
                Some(&(_, s, e)) => (s, e),
                None => {
                    let (g, _, s) = self.old_estimator_grid(k)?;
                    (s, grid_rel_rms(&g, &reference))
                }
            };
            ms.push(self.measure(name, &old_label, "beams", k as f64, "gather", gather_s, e, metric, false));
        }
        trend.push((old_label.clone(), 1));
        let gather = Study {
            name: name.into(),
            stage: "gather".into(),
            metric: metric.into(),
            reference: photon.reference.clone(),
            reference_seconds: ref_secs,
            expected_trend: trend,
            notes: vec![
                "kd-tree is a balloon estimator (radius at the voxel), splat a sample-point estimator (radius at the photon): with radius noise they differ slightly, without it they are the same sum.".into(),
                "report2014 is the 2014 report's kernel-weighted average of photon colours, not a density: its values are a photon's power, so its error against the density reference is expected to be large (about 1 or more). 'report2014, best-fit scale' is the same grid scaled by the least-squares factor: the error of its shape alone.".into(),
            ],
            measurements: ms,
        };
        Ok(vec![photon, gather])
    }

    /// Gather radius at fixed photon count: noise against blur.
    pub fn radius_study(&mut self) -> Result<Study, SweepError> {
        let (r, v, n) = (self.radius(), self.voxel(), self.beams());
        let m = self.beams_times(self.plan.reference_beams);
        let (r_ref, v_ref) = (0.5 * r, 0.5 * v);
        self.say(&format!("reference: kd-tree, {m} beams, r = {r_ref} km, voxel {v_ref} km"));
        let (reference, ref_secs) = self.gather_uncached(m, r_ref, v_ref, GatherMethod::Kdtree)?;
        let name = "gather radius";
        let metric = "relative RMS of emission";
        let mut ms = Vec::new();
        for bf in self.plan.radius_beam_factors.clone() {
            let k = self.beams_times(bf);
            let method = format!("kd-tree, {k} beams");
            for f in self.plan.radius_factors.clone() {
                let rr = r * f;
                let (g, secs) = self.gather(k, rr, v, GatherMethod::Kdtree)?;
                let e = grid_rel_rms(&g, &reference);
                ms.push(self.measure(name, &method, "radius_km", rr, "gather", secs, e, metric, k == n && f == 1.0));
                self.note_last(&ms, gather_key(k, rr, v, GatherMethod::Kdtree), 0.0);
            }
        }
        Ok(Study {
            name: name.into(),
            stage: "gather".into(),
            metric: metric.into(),
            reference: format!(
                "kd-tree gather of {m} beams with half the radius (r = {r_ref} km, radius noise as in the scene) on half the voxel size ({v_ref} km): the blur of the reference itself (r/2) is not measured"
            ),
            reference_seconds: ref_secs,
            expected_trend: vec![],
            notes: vec![
                format!("Voxel size fixed at the scene's ({v} km). Small radii: noise (few photons per kernel) and, below half a voxel, aliasing; large radii: blur across the curtain."),
                format!("The reference's own noise is about sqrt((N r^3) / (M (r/2)^3)) = {:.2} of the noise at the scene's setting (N = {n}, r = {r}); it adds to every error in quadrature.", ((n as f64 * 8.0) / m as f64).sqrt()),
            ],
            measurements: ms,
        })
    }

    /// Voxel size at fixed photons and radius, per gather method.
    pub fn voxel_study(&mut self) -> Result<Study, SweepError> {
        let (r, v, n) = (self.radius(), self.voxel(), self.beams());
        let v_ref = v * self.plan.reference_voxel;
        let name = "voxel size";
        let metric = "relative RMS of emission";
        let mut ms = Vec::new();
        let mut ref_secs = 0.0;
        let mut trend = Vec::new();
        for (method, label) in [(GatherMethod::Kdtree, "kd-tree (kiddo)"), (GatherMethod::Splat, "splat")] {
            self.say(&format!("reference: {label}, {n} beams, r = {r} km, voxel {v_ref} km"));
            let (reference, secs) = self.gather_uncached(n, r, v_ref, method)?;
            ref_secs += secs;
            trend.push((label.to_string(), -1));
            for f in self.plan.voxel_factors.clone() {
                let vv = v * f;
                let (g, secs) = self.gather(n, r, vv, method)?;
                let e = grid_rel_rms(&g, &reference);
                let here = f == 1.0 && method == self.scene.photons.gather;
                ms.push(self.measure(name, label, "voxel_km", vv, "gather", secs, e, metric, here));
                self.note_last(&ms, gather_key(n, r, vv, method), 0.0);
            }
        }
        Ok(Study {
            name: name.into(),
            stage: "gather".into(),
            metric: metric.into(),
            reference: format!("the same photons ({n} beams) and method on voxels of {v_ref} km; kernel r = {r} km"),
            reference_seconds: ref_secs,
            expected_trend: trend,
            notes: vec!["Pure discretisation: the photons and kernel are those of the reference, so the error is that of storing the estimate at voxel centres and reading it back trilinearly (as Cycles does), against a finer grid.".into()],
            measurements: ms,
        })
    }

    /// The reduced scene's grids at its own settings (the CLI's bake).
    pub fn bake_grids(&self) -> Result<bake::Bake, SweepError> {
        Ok(bake::bake(&self.scene, &NoProgress)?)
    }

    fn render_timed(&self, s: &RenderSettings, vol: &Volume<'_>) -> Result<(Image, f64), SweepError> {
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
    fn volume_settings(&self) -> RenderSettings {
        let mut s = RenderSettings::from_scene(&self.scene);
        s.camera = volume_camera(&self.scene);
        s.render.width = self.plan.volume_image[0];
        s.render.height = self.plan.volume_image[1];
        s.render.spp = 1;
        s.terrain.kind = TerrainKind::None;
        s.background.radiance = [0.0; 3];
        s
    }

    /// Fixed-step ray marching against exact per-voxel integration.
    pub fn integration_study(&self, grids: &bake::Bake) -> Result<Study, SweepError> {
        let v = self.voxel();
        let mut s = self.volume_settings();
        let vol = Volume { density: Some(&grids.density), emission: Some(&grids.emission) };
        let name = "primary-ray integration";
        let metric = "mean relative luminance error, pixels > 1% of peak";
        s.integration = Integration::Exact;
        let (exact, exact_s) = self.render_timed(&s, &vol)?;
        let all = vec![true; exact.pixels.len()];
        let mut ms =
            vec![self.measure(name, "exact (per dual cell)", "step_km", 0.0, "render", exact_s, 0.0, metric, true)];
        let mut flux = Vec::new();
        for f in self.plan.step_factors.clone() {
            let h = v * f;
            s.integration = Integration::FixedStep(h);
            let (img, secs) = self.render_timed(&s, &vol)?;
            let (e, fl) = image_rel_error_masked(&img.pixels, &exact.pixels, &all, 0.01);
            flux.push(format!("h = {h} km: {fl:.5}"));
            ms.push(self.measure(name, "fixed step", "step_km", h, "render", secs, e, metric, false));
        }
        let lit = exact.pixels.iter().filter(|p| p[1] > 0.0).count();
        Ok(Study {
            name: name.into(),
            stage: "render".into(),
            metric: metric.into(),
            reference: format!(
                "the exact integrator's image ({}x{} px, spp 1, {} pixels with emission; camera: bench volume camera, no terrain)",
                exact.width, exact.height, lit
            ),
            reference_seconds: exact_s,
            expected_trend: vec![("fixed step".into(), -1)],
            notes: vec![
                format!("Voxel size {v} km; steps are multiples of it. Exact integration is the reference (error 0, drawn on the bottom edge); its own error against closed forms is below 1e-4 (tests/render_closed_forms.rs, tests/stability_integration.rs)."),
                format!("Total flux ratio fixed/exact: {}", flux.join(", ")),
            ],
            measurements: ms,
        })
    }

    /// Contribution-based pruning ([`crate::prune`]): the reduced scene
    /// baked unpruned, then pruned at each budget (and given the Cycles
    /// shell, as the bake does), seen through the bench volume camera
    /// (which also weights the leaves), against the unpruned image. What
    /// pruning saves is storage, so the time is the VDB write (encoding both
    /// grids with the scene's compression, in memory: it scales with the
    /// file's size), fastest of the timing runs; sizes and voxels go in the
    /// notes. Render time barely changes: the dropped leaves are faint and
    /// few rays cross them.
    pub fn prune_study(&self) -> Result<Study, SweepError> {
        // The reference: the reduced scene baked without pruning (and
        // without the Cycles shell, added below to every variant as the bake
        // adds it after pruning).
        let mut unpruned = self.scene.clone();
        unpruned.grid.prune = 0.0;
        unpruned.grid.cycles_shell = false;
        let base = bake::bake(&unpruned, &NoProgress)?;
        let peak = base.stats.peak_luminance;
        let finish = |e: &Grid<[f32; 3]>| -> (Grid<[f32; 3]>, Grid<f32>) {
            let mut e = e.clone();
            let mut d = bake::density_grid(&e, &self.scene.grid, peak);
            if self.scene.grid.cycles_shell {
                e.dilate_active();
                d.dilate_active();
            }
            (e, d)
        };
        let (full_e, full_d) = finish(&base.emission);
        let mut s = self.volume_settings();
        s.integration = Integration::Exact;
        let camera = crate::camera::CameraModel::new(&s.camera, s.render.width, s.render.height).map_err(RenderError::from)?;
        let opts = crate::outputs::write_options(&self.scene);
        let (min, max_runs) = (self.plan.min_timing_seconds, self.plan.max_timing_runs);
        // (bytes, fastest write time)
        let write = |e: &Grid<[f32; 3]>, d: &Grid<f32>| -> (usize, f64) {
            let (len, secs) = timed(min, max_runs, || {
                crate::vdb::write::write_vdb_bytes(&[GridRef::Float(d), GridRef::Vec3(e)], &opts).map(|b| b.len())
            });
            (len.unwrap_or(0), secs)
        };
        let name = "pruning";
        let metric = "mean relative luminance error, pixels > 1% of peak";
        let vol = Volume { density: Some(&full_d), emission: Some(&full_e) };
        let (full, _) = self.render_timed(&s, &vol)?;
        let all = vec![true; full.pixels.len()];
        let (full_bytes, full_s) = write(&full_e, &full_d);
        let scene_budget = self.scene.grid.prune;
        let mut ms =
            vec![self.measure(name, "unpruned", "budget", 0.0, "vdb write", full_s, 0.0, metric, scene_budget == 0.0)];
        let mut notes = vec![format!(
            "Unpruned: {} aurora voxels, {} leaves, {full_bytes} bytes (VDB, scene compression, Cycles shell: {}). Removed light is estimated without extinction; per budget: leaves and voxels removed, estimated share removed, image flux ratio, file size:",
            base.emission.active_voxel_count(),
            base.emission.leaf_count(),
            self.scene.grid.cycles_shell
        )];
        let mut budgets = self.plan.prune_budgets.clone();
        if scene_budget > 0.0 && !budgets.contains(&scene_budget) {
            budgets.push(scene_budget);
            budgets.sort_by(f64::total_cmp);
        }
        for &b in &budgets {
            let mut e = base.emission.clone();
            let st = crate::prune::prune(&mut e, &camera, b);
            let (e, d) = finish(&e);
            let vol = Volume { density: Some(&d), emission: Some(&e) };
            let (img, _) = self.render_timed(&s, &vol)?;
            let (err, flux) = image_rel_error_masked(&img.pixels, &full.pixels, &all, 0.01);
            let (nb, secs) = write(&e, &d);
            notes.push(format!(
                "budget {b}: {} of {} leaves, {} of {} voxels, estimate {:.3e}, flux {flux:.5}, {nb} bytes ({:.3} of unpruned)",
                st.leaves_removed,
                st.leaves_before,
                st.voxels_removed,
                st.voxels_before,
                st.removed_fraction,
                nb as f64 / full_bytes.max(1) as f64
            ));
            ms.push(self.measure(name, "contribution pruning", "budget", b, "vdb write", secs, err, metric, b == scene_budget));
        }
        notes.push(format!("The scene's grid.prune = {scene_budget}."));
        Ok(Study {
            name: name.into(),
            stage: "vdb write".into(),
            metric: metric.into(),
            reference: format!(
                "the unpruned bake's image ({}x{} px, spp 1, exact integration; bench volume camera, no terrain)",
                full.width, full.height
            ),
            reference_seconds: full_s,
            expected_trend: vec![("contribution pruning".into(), -1)],
            notes,
            measurements: ms,
        })
    }

    /// Shadow rays per terrain hit, and pixel samples, against converged
    /// terrain lighting.
    pub fn shadow_study(&self, grids: &bake::Bake) -> Result<Study, SweepError> {
        let mut s = RenderSettings::from_scene(&self.scene);
        s.terrain = ground_terrain(&self.scene);
        s.camera = ground_camera(&self.scene, &s.terrain);
        s.render.width = self.plan.ground_image[0];
        s.render.height = self.plan.ground_image[1];
        s.integration = Integration::Exact;
        let vol = Volume { density: Some(&grids.density), emission: Some(&grids.emission) };
        // Terrain pixels: where the pixel-centre ray hits the ground.
        let prepared = Prepared::new(&s, &vol)?;
        let (w, h) = (s.render.width, s.render.height);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| {
                let ray = prepared.camera.ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                prepared.terrain.intersect(ray.origin, ray.dir, 0.0, f64::INFINITY).is_some()
            })
            .collect();
        drop(prepared);
        let terrain_px = mask.iter().filter(|&&m| m).count();
        let name = "shadow rays";
        let metric = "mean relative luminance error, terrain pixels > 1% of peak";
        let big = self.plan.shadow_reference;
        let scene_spp = self.scene.render.spp;
        let mut counts = self.plan.shadow_counts.clone();
        if !self.plan.quick && !counts.contains(&scene_spp) && scene_spp < big {
            counts.push(scene_spp);
            counts.sort_unstable();
        }
        let mut ms = Vec::new();
        let mut ref_secs = 0.0;
        let methods = [("shadow rays per hit (spp 1)", true), ("pixel samples (1 shadow ray each)", false)];
        for (label, per_hit) in methods {
            let set = |s: &mut RenderSettings, k: usize| {
                if per_hit {
                    s.render.spp = 1;
                    s.shadow_samples = k;
                } else {
                    s.render.spp = k;
                    s.shadow_samples = 1;
                }
            };
            set(&mut s, big);
            self.say(&format!("reference: {label}, {big} samples per pixel"));
            let (reference, secs) = self.render_timed(&s, &vol)?;
            ref_secs += secs;
            for &k in &counts {
                set(&mut s, k);
                let (img, secs) = self.render_timed(&s, &vol)?;
                let (e, _) = image_rel_error_masked(&img.pixels, &reference.pixels, &mask, 0.01);
                // The CLI renders with the scene's spp and one shadow ray per hit.
                let here = !per_hit && k == scene_spp;
                ms.push(self.measure(name, label, "samples", k as f64, "render", secs, e, metric, here));
            }
        }
        Ok(Study {
            name: name.into(),
            stage: "render".into(),
            metric: metric.into(),
            reference: format!(
                "the same estimator with {big} samples per pixel ({w}x{h} px, {terrain_px} terrain pixels; bench ground camera, terrain {:?})",
                s.terrain.kind
            ),
            reference_seconds: ref_secs,
            expected_trend: methods.iter().map(|(l, _)| (l.to_string(), 1)).collect(),
            notes: vec![
                "Each curve has its own reference (its estimator with many samples): 'shadow rays per hit' converges to the pixel-centre value, 'pixel samples' to the pixel's box-filtered value. Both errors are Monte Carlo noise, falling as samples^-1/2.".into(),
                format!("The CLI's `aurora render` uses spp = {scene_spp} from the scene and 1 shadow ray per terrain hit (marked as the scene setting)."),
            ],
            measurements: ms,
        })
    }
}
