//! `aurora preview`: a picture of the scene that follows its edits.
//!
//! A [`Preview`] keeps every stage's output in memory: the
//! [`BakePlan`](crate::pipeline::bake::plan::BakePlan) (footprints, atmosphere, colour
//! table), the photons, the finished grids and the leaves pruning dropped
//! (with the finished emission they are the gathered grid, restored when a
//! camera or grid edit refinishes: no copy of the gathered grid, some
//! 340 MB on the default scene, on every rebuild), the renderer's
//! structures ([`crate::render::Prepared`]:
//! camera, medium, terrain, emission sampler, sky) and the last linear
//! image. An edit is diffed against the last good scene section by section
//! ([`stage_for_edit`]) and only the stages it touches are rerun:
//!
//! | the edit touches | rerun |
//! |---|---|
//! | `render.exposure` or `render.view_transform` only | nothing traced: the last linear image re-encoded (a tone map of the linear film, `crate::render::view_transform::display_rgb`) |
//! | `[render]` spp, `[background]`, `[terrain]` | the pixels (the medium is kept; the terrain model unless its geometry changed, the sky unless `[background]` did) |
//! | `[volume]` | the pixels (the medium holds unit values and applies the scales at lookup: `Prepared::set_volume_scales`, no rebuild) |
//! | `[camera]`, `[render]` width / height | the voxel size (`"auto"` follows the camera): the gather when it changed, pruning when `grid.prune > 0` (then the medium), then the pixels |
//! | `[grid]` other than `voxel_size` | finish (checks, pruning, density), the medium, the pixels |
//! | `grid.voxel_size`, `[photons]` other than `kernel` | gather and after |
//! | `[beams]`, `[colour]`, `[atmosphere]`, `photons.kernel` | trace and after (the footprints are kept) |
//! | `seed`, `[[curtain]]`, `[footprint]`, `[animation]` | everything |
//!
//! Colour edits retrace: a photon carries its RGB power, not the altitude
//! and deposited power it was coloured from, so the data do not allow a
//! recolour without the beams; the footprints (the fluid simulation) are
//! kept ([`crate::pipeline::bake::plan::BakePlan::reusing`]).
//!
//! Each update writes, atomically to the output PNG
//! (`crate::render::image_file::write_png`), up to three pictures:
//! 1. a coarse one: a quarter of the size, one sample per pixel. When the
//!    edit rebuilds the grids it comes before the full gather, from every
//!    [`COARSE_PHOTON_STRIDE`]-th photon of the full gather's input (the
//!    merged runs and their kernels, [`crate::pipeline::photons::GatherInput`], made
//!    once for both gathers; power multiplied by the stride) gathered on
//!    voxels [`COARSE_VOXEL_FACTOR`] times larger: only this picture is
//!    made from a photon subset. After any other edit it is rendered
//!    from the refined picture's structures with a smaller camera: a few
//!    ms.
//! 2. the refined one: the preview size at the preview's spp
//!    ([`DEFAULT_SPP`] = 4, two antithetic pairs; `aurora preview --spp`),
//!    capped by the scene's `render.spp`. **The edit-to-picture targets
//!    (<= 1 s after a render edit, <= 3 s after a beams edit, on 2 cores) are
//!    judged on this picture.**
//! 3. when the scene's `render.spp` is larger, the picture at the scene's
//!    spp, the very image `aurora render` makes of `aurora bake` at that
//!    size and spp (tested). `--watch` skips it when the file changed again
//!    meanwhile, so a newer edit waits only for picture 2.
//!
//! The bake runs at the scene's own settings (beam count, voxel size for
//! the scene's `render` size): the preview size only sets the picture's.
//! It skips the Cycles shell (`grid.cycles_shell`: active zeros around the
//! grids, for Cycles' sake; the reference renderer samples inactive voxels
//! as zeros too, so no pixel changes: tested against `aurora bake`'s grids,
//! shell included), which saves the dilation and a larger medium.
//!
//! Where an edit's time goes on the default scene at 320x180, 2 cores
//! (`cargo run --release --example preview_bench -- --threads 2`,
//! `benchmarks/preview/2026-11-29-default-320x180.txt`, numbers in
//! docs/benchmarks.md): a render edit is the pixel loop of picture 2 (230 k
//! camera rays at 4 spp) and the coarse picture; a `[volume]` edit adds
//! the medium's build; a beams edit is trace, the gather's input (merge,
//! kernels), coarse picture, gather (the largest part: the splat's
//! segment kernels, about 2.2 of the edit's 4 CPU seconds before the
//! renderer), finish, the medium's build and the pixel loop. The update
//! reports every stage's time ([`Update`]); `gather` includes the input
//! made before the coarse picture.

use crate::grid::Leaf;
use crate::pipeline::bake::plan::{self, BakePlan, Gathered};
use crate::pipeline::bake::stats::{NoiseEstimate, StageTimes};
use crate::pipeline::bake::voxel;
use crate::pipeline::bake::{self, Bake, BakeError};
use crate::pipeline::photons::GatherInput;
use crate::render::{self, Image, Prepared, RenderError, RenderSettings, Volume};
use crate::scene::Scene;
use crate::util::progress::NoProgress;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Default preview size, pixels.
pub const DEFAULT_SIZE: [usize; 2] = [320, 180];

/// Default samples per pixel of the first refined picture (two antithetic
/// pairs, `crate::render::pixel_position`); the scene's `render.spp`
/// follows when it is larger.
pub const DEFAULT_SPP: usize = 4;

/// The coarse picture is this many times smaller per side, one sample per
/// pixel.
pub const COARSE_FACTOR: usize = 4;

/// When an edit rebuilds the grids, the coarse picture is rendered from a
/// gather on voxels this many times larger per side (the coarse picture's
/// pixels are [`COARSE_FACTOR`] times larger too): the splat touches about
/// `COARSE_VOXEL_FACTOR^3` times fewer voxels per photon.
pub const COARSE_VOXEL_FACTOR: f64 = 4.0;

/// ... and from every this many-th photon (its power multiplied by as
/// much): the gather's cost per photon does not shrink with the voxels'
/// count (about 1.3 s of the default scene's 2.9 M photons on 4x voxels
/// and 2 loaded cores, 0.9 s on 8x).
pub const COARSE_PHOTON_STRIDE: usize = 4;

/// The earliest stage an edit invalidates (later stages rerun too).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Nothing the picture depends on changed.
    Nothing,
    /// `render.exposure` only: a tone map of the last linear image, no
    /// ray is traced.
    Exposure,
    Render,
    /// The camera or the scene's image size: the automatic voxel size and
    /// pruning may change.
    Camera,
    Finish,
    Gather,
    Trace,
    /// Footprints and everything after (the plan finds which it can keep).
    Footprints,
}

/// Which stage an edit from `old` to `new` starts at (see the module
/// documentation's table).
pub fn stage_for_edit(old: &Scene, new: &Scene) -> Stage {
    let mut s = Stage::Nothing;
    let mut at = |changed: bool, stage: Stage| {
        if changed && stage > s {
            s = stage;
        }
    };
    at(old.seed != new.seed || old.curtains != new.curtains || old.footprint != new.footprint, Stage::Footprints);
    at(old.animation != new.animation, Stage::Footprints);
    // A path is placed up the field line from its altitude: the field and
    // the start altitude move it.
    at(
        new.curtains.iter().any(|c| c.path.is_some())
            && crate::pipeline::footprint::curtain_path::Lift::of(&old.beams, &old.earth)
                != crate::pipeline::footprint::curtain_path::Lift::of(&new.beams, &new.earth),
        Stage::Footprints,
    );
    at(old.beams != new.beams || old.colour != new.colour || old.atmosphere != new.atmosphere || old.earth != new.earth, Stage::Trace);
    at(old.photons.kernel != new.photons.kernel, Stage::Trace);
    at(old.photons != new.photons || old.grid.voxel_size != new.grid.voxel_size, Stage::Gather);
    at(old.grid != new.grid, Stage::Finish);
    at(old.camera != new.camera || (old.render.width, old.render.height) != (new.render.width, new.render.height), Stage::Camera);
    let mut render = old.render.clone();
    render.exposure = new.render.exposure;
    render.view_transform = new.render.view_transform;
    at(render != new.render || old.volume != new.volume || old.background != new.background || old.terrain != new.terrain, Stage::Render);
    at(old.render.exposure != new.render.exposure || old.render.view_transform != new.render.view_transform, Stage::Exposure);
    s
}

/// A preview failure: the scene's bake or the render.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    #[error(transparent)]
    Bake(#[from] BakeError),
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl PreviewError {
    /// True when the scene or the output is at fault, as for a bake or a render (exit status 2).
    pub fn is_input(&self) -> bool {
        match self {
            PreviewError::Bake(e) => e.is_input(),
            PreviewError::Render(e) => e.is_input(),
        }
    }
}

/// What one update did and how long it took, seconds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Update {
    /// The stage the edit started at.
    pub stage: Option<Stage>,
    pub footprints: f64,
    pub pilot: f64,
    pub trace: f64,
    pub gather: f64,
    pub finish: f64,
    /// The coarse picture, everything included (its quick gather and
    /// finish after an edit that rebuilds the grids).
    pub coarse_render: f64,
    /// The refined picture at the preview's spp: `render_build` (building or
    /// refreshing the renderer's structures, `crate::render::Prepared`)
    /// plus `render_pixels` (the pixel loop).
    pub render: f64,
    pub render_build: f64,
    pub render_pixels: f64,
    /// Samples per pixel of the refined picture.
    pub spp: usize,
    /// The pixel loop of the picture at the scene's `render.spp` when it is
    /// larger than the preview's (0 and `full_spp` 0 otherwise).
    pub full_render: f64,
    pub full_spp: usize,
    /// Encoding and writing the PNGs (all pictures of the update).
    pub png: f64,
    /// From the start of the update to the coarse picture, the refined one
    /// (at the preview's spp) and the one at the scene's spp on disk (0
    /// when not written: an exposure edit writes only the refined one).
    pub to_coarse: f64,
    pub to_picture: f64,
    pub to_full: f64,
}

impl Update {
    /// One line for the terminal.
    pub fn summary(&self) -> String {
        let st = self.stage.map_or("first".to_string(), |s| format!("{s:?}").to_lowercase());
        let full =
            if self.full_spp > 0 { format!(", full render {:.2} s ({} spp)", self.full_render, self.full_spp) } else { String::new() };
        let to_full = if self.full_spp > 0 { format!(", to full picture {:.2} s", self.to_full) } else { String::new() };
        format!(
            "edit ({st}): footprints {:.2} s, pilot {:.2} s, trace {:.2} s, gather {:.2} s, finish {:.2} s, coarse render {:.2} s, render {:.2} s (build {:.2} s, pixels {:.2} s, {} spp){full}, png {:.2} s; edit to coarse picture {:.2} s, to picture {:.2} s{to_full}",
            self.footprints, self.pilot, self.trace, self.gather, self.finish, self.coarse_render, self.render, self.render_build, self.render_pixels, self.spp, self.png, self.to_coarse, self.to_picture
        )
    }
}

/// The cached stages of one scene.
struct Cache {
    scene: Scene,
    /// The scene's plan, with `grid.cycles_shell` off ([`preview_plan`]).
    plan: BakePlan,
    /// Beam count, pilot estimate and pilot warnings.
    count: (usize, Option<NoiseEstimate>, Vec<String>),
    beam_stats: crate::pipeline::beams::BeamStats,
    /// The leaves pruning dropped from the gathered emission: with
    /// `bake.emission` (no Cycles shell) they are the gathered grid, which
    /// a camera or grid edit refinishes ([`crate::grid::Grid::restore_leaves`]). Kept
    /// instead of a copy of the gathered grid (some 340 MB on the default
    /// scene, whose copy cost every beams edit 0.1-0.2 s).
    dropped: Vec<Leaf<[f32; 3]>>,
    /// The gathered emission's voxel size.
    voxel: (f64, String),
    bake: Bake,
    /// The coarse picture's grids ([`Preview::coarse_picture`]) while they
    /// match `bake` (None after a finish without a coarse gather): a
    /// `[volume]` edit renders its coarse picture from them before the
    /// full medium is rebuilt.
    coarse: Option<Bake>,
}

/// What the last refined picture was rendered with: the renderer's
/// structures (kept while their inputs are unchanged) and the linear
/// image last written (an exposure edit re-encodes it).
struct Look {
    prepared: Prepared,
    image: Image,
}

/// The preview's copy of the scene's plan: without the Cycles shell. The
/// shell is one voxel of active zeros around both grids for Cycles' sake
/// (`crate::pipeline::bake::plan::finish`); the reference renderer samples inactive
/// voxels as 0 too, so it changes no pixel (tested:
/// `the_refined_picture_is_the_render_of_the_bake`) and only costs the
/// dilation and a larger medium.
fn preview_plan(mut plan: BakePlan) -> BakePlan {
    plan.grid.cycles_shell = false;
    plan
}

/// The preview's state: the last good scene's stage outputs.
pub struct Preview {
    pub out: PathBuf,
    pub size: [usize; 2],
    /// Samples per pixel of the refined picture ([`DEFAULT_SPP`]); the
    /// scene's `render.spp` follows when larger, and caps it when smaller.
    pub spp: usize,
    /// Folder against which a relative `terrain.heightmap` is resolved.
    pub base_dir: Option<PathBuf>,
    cache: Option<Cache>,
    look: Option<Look>,
}

impl Preview {
    pub fn new(out: &Path, size: [usize; 2], base_dir: Option<PathBuf>) -> Preview {
        Preview { out: out.to_path_buf(), size, spp: DEFAULT_SPP, base_dir, cache: None, look: None }
    }

    /// The last finished bake (None before the first update). The preview
    /// bakes without `grid.cycles_shell` (module doc).
    pub fn bake(&self) -> Option<&Bake> {
        self.cache.as_ref().map(|c| &c.bake)
    }

    /// The linear image of the last picture written at the preview size
    /// (the scene's spp when it was rendered, else the preview's).
    pub fn image(&self) -> Option<&Image> {
        self.look.as_ref().map(|l| &l.image)
    }

    /// The render settings of a picture of `scene` at `w` x `h`, `spp`.
    fn settings(&self, scene: &Scene, w: usize, h: usize, spp: usize) -> RenderSettings {
        let mut s = RenderSettings::from_scene(scene);
        s.base_dir = self.base_dir.clone();
        s.render.width = w;
        s.render.height = h;
        s.render.spp = spp;
        s
    }

    /// Writes `img` at `exposure` through `view` to the output PNG; returns its seconds.
    fn write(&self, img: &Image, exposure: f64, view: crate::scene::ViewTransform) -> Result<f64, RenderError> {
        let t = Instant::now();
        render::image_file::write_png(&self.out, img, exposure, view)?;
        Ok(t.elapsed().as_secs_f64())
    }

    /// The coarse picture of an edit that rebuilds the grids: every
    /// [`COARSE_PHOTON_STRIDE`]-th photon, its power multiplied by the
    /// stride (the same expected emission), gathered on voxels
    /// [`COARSE_VOXEL_FACTOR`] times larger, finished, rendered at the
    /// coarse size with one sample and written. Only this picture comes
    /// from a photon subset; the refined ones use every photon. The
    /// renderer's parts that do not depend on the grids (terrain, sky) are
    /// taken from `prev`, which holds the coarse picture's afterwards.
    /// Returns its seconds and the PNG's.
    fn coarse_picture(
        &self,
        scene: &Scene,
        plan: &BakePlan,
        input: &GatherInput,
        voxel_km: f64,
        prev: &mut Option<Prepared>,
    ) -> Result<(f64, f64, Bake), PreviewError> {
        let t = Instant::now();
        let nothing = &NoProgress;
        let v = COARSE_VOXEL_FACTOR * voxel_km;
        let emission = plan::gather_from(plan, &input.every(COARSE_PHOTON_STRIDE), v, nothing);
        // Only the grids are used: no photons for the power sums, no warnings.
        let g = Gathered {
            lines: Vec::new(),
            photons: Vec::new(),
            beam_stats: Default::default(),
            voxel_km: v,
            voxel_source: "coarse preview".into(),
            warnings: Vec::new(),
            noise: None,
        };
        let b = plan::finish(plan, emission, g, StageTimes::default(), t, nothing)?;
        let png = self.coarse_from(scene, &b, prev)?;
        Ok((t.elapsed().as_secs_f64(), png, b))
    }

    /// Renders and writes the coarse picture of `coarse`'s grids, with the
    /// renderer's parts that do not depend on the grids (terrain, sky)
    /// taken from `prev`, which holds the coarse picture's afterwards.
    /// Returns the PNG's seconds.
    fn coarse_from(&self, scene: &Scene, coarse: &Bake, prev: &mut Option<Prepared>) -> Result<f64, RenderError> {
        let volume = Volume { density: Some(&coarse.density), emission: Some(&coarse.emission) };
        let [w, h] = self.size;
        let s = self.settings(scene, (w / COARSE_FACTOR).max(1), (h / COARSE_FACTOR).max(1), 1);
        let p = Prepared::reuse(prev.take(), true, &s, &volume)?;
        let img = render::render_prepared(&p, &NoProgress)?;
        *prev = Some(p);
        self.write(&img, scene.render.exposure, scene.render.view_transform)
    }

    /// Brings the pictures up to date with `scene` (validated), rerunning
    /// only the stages the edit touches, and writes the coarse and refined
    /// PNGs (and the one at the scene's spp when larger than the
    /// preview's). On an error the previous state is kept. `on_picture`
    /// is called with a description and the seconds since the update began
    /// once each picture but the last is written; it returns whether to go
    /// on, which only the picture at the preview's spp heeds: false skips
    /// the one at the scene's spp (the watcher returns false when the file
    /// changed again, so a newer edit does not wait for it).
    pub fn update(&mut self, scene: &Scene, on_picture: &dyn Fn(&str, f64) -> bool) -> Result<Update, PreviewError> {
        let t0 = Instant::now();
        let mut u = Update::default();
        let stage = match &self.cache {
            None => Stage::Footprints,
            Some(c) => {
                let s = stage_for_edit(&c.scene, scene);
                u.stage = Some(s);
                s
            }
        };
        if stage == Stage::Nothing {
            // Same scene (a save without changes): the picture is current.
            return Ok(u);
        }
        let [w, h] = self.size;
        let (cw, ch) = ((w / COARSE_FACTOR).max(1), (h / COARSE_FACTOR).max(1));
        let coarse_what = format!("coarse picture ({cw}x{ch}, 1 spp)");
        if stage == Stage::Exposure {
            if let Some(look) = &self.look {
                // A tone map of the last linear image: nothing is traced.
                u.png = self.write(&look.image, scene.render.exposure, scene.render.view_transform)?;
                u.spp = look.prepared.settings().render.spp;
                u.to_picture = t0.elapsed().as_secs_f64();
                if let Some(c) = self.cache.as_mut() {
                    c.scene = scene.clone();
                }
                return Ok(u);
            }
        }
        let mut times = StageTimes::default();
        let nothing = &NoProgress;
        // The renderer's parts of the last picture (the coarse picture's
        // once it is rendered from a coarse gather).
        let mut parts = self.look.take().map(|l| l.prepared);
        // When the grids are rebuilt, the coarse picture comes from a
        // coarse gather before the full one (Preview::coarse_picture).
        let coarse_done = |u: &mut Update| {
            u.to_coarse = t0.elapsed().as_secs_f64();
            // Too early to stop: the refined picture follows the cache.
            let _ = on_picture(&coarse_what, u.to_coarse);
        };
        // Stages up to the grids; the cache is replaced only on success.
        let mut grids_changed = true;
        let next = match self.cache.take() {
            Some(mut c) if stage <= Stage::Gather => {
                let r = (|| -> Result<bool, PreviewError> {
                    // The plan's plain data follow the edit; footprints,
                    // atmosphere and colour table are kept.
                    let plan = preview_plan(BakePlan::reusing(scene, &c.plan, nothing));
                    let mut regather = stage == Stage::Gather;
                    if stage == Stage::Camera {
                        // "auto" voxel size follows the camera.
                        let v = plan.voxel_size(&c.bake.photons);
                        regather = v.0 != c.voxel.0;
                        if !regather && plan.grid.prune <= 0.0 {
                            c.plan = plan;
                            c.voxel = v;
                            return Ok(false);
                        }
                    }
                    if stage <= Stage::Render {
                        c.plan = plan;
                        return Ok(false);
                    }
                    let (gathered, voxel, coarse) = if regather {
                        let voxel = plan.voxel_size(&c.bake.photons);
                        let t = Instant::now();
                        let input = plan::gather_input(&plan, &c.bake.photons);
                        u.gather = t.elapsed().as_secs_f64();
                        let coarse;
                        (u.coarse_render, u.png, coarse) = self.coarse_picture(scene, &plan, &input, voxel.0, &mut parts)?;
                        coarse_done(&mut u);
                        let t = Instant::now();
                        let gathered = plan::gather_from(&plan, &input, voxel.0, nothing);
                        u.gather += t.elapsed().as_secs_f64();
                        (gathered, voxel, Some(coarse))
                    } else {
                        // The gathered grid again: the finished emission
                        // and the leaves pruning dropped. (The coarse grids
                        // were finished otherwise.)
                        let mut gathered = c.bake.emission.clone();
                        gathered.restore_leaves(c.dropped.iter().cloned());
                        (gathered, c.voxel.clone(), None)
                    };
                    let t = Instant::now();
                    let mut warnings = voxel::resolution_warnings_for(plan.kernel, &plan.footprints, plan.footprint.threshold, voxel.0);
                    warnings.extend(c.count.2.iter().cloned());
                    let g = Gathered {
                        lines: Vec::new(),
                        photons: c.bake.photons.clone(),
                        beam_stats: c.beam_stats.clone(),
                        voxel_km: voxel.0,
                        voxel_source: voxel.1.clone(),
                        warnings,
                        noise: c.count.1.clone(),
                    };
                    (c.bake, c.dropped) = plan::finish_keeping(&plan, gathered, g, times.clone(), t0, nothing)?;
                    u.finish = t.elapsed().as_secs_f64();
                    (c.plan, c.voxel, c.coarse) = (plan, voxel, coarse);
                    Ok(true)
                })();
                match r {
                    Ok(changed) => {
                        grids_changed = changed;
                        c.scene = scene.clone();
                        c
                    }
                    Err(e) => {
                        self.cache = Some(c);
                        return Err(e);
                    }
                }
            }
            prev => {
                let r = (|| -> Result<Cache, PreviewError> {
                    crate::pipeline::memory_budget::check(
                        &crate::pipeline::memory_budget::estimate(scene),
                        &crate::util::memory::available(),
                    )
                    .map_err(BakeError::from)?;
                    let t = Instant::now();
                    let plan = preview_plan(match &prev {
                        Some(c) => BakePlan::reusing(scene, &c.plan, nothing),
                        None => BakePlan::new(scene, nothing),
                    });
                    u.footprints = t.elapsed().as_secs_f64();
                    times.footprints = plan.footprint_seconds;
                    let count = bake::beam_count(&plan, &mut times, nothing)?;
                    u.pilot = times.pilot;
                    let t = Instant::now();
                    let traced = plan::trace_bake(&plan, count.0, nothing).map_err(BakeError::from)?;
                    u.trace = t.elapsed().as_secs_f64();
                    let voxel = plan.voxel_size(&traced.photons);
                    let t = Instant::now();
                    let input = plan::gather_input(&plan, &traced.photons);
                    u.gather = t.elapsed().as_secs_f64();
                    let (secs, png, coarse) = self.coarse_picture(scene, &plan, &input, voxel.0, &mut parts)?;
                    (u.coarse_render, u.png) = (secs, png);
                    coarse_done(&mut u);
                    let t = Instant::now();
                    let mut warnings = voxel::resolution_warnings_for(plan.kernel, &plan.footprints, plan.footprint.threshold, voxel.0);
                    warnings.extend(count.2.iter().cloned());
                    let emission = plan::gather_from(&plan, &input, voxel.0, nothing);
                    drop(input);
                    u.gather += t.elapsed().as_secs_f64();
                    (times.beams, times.gather) = (u.trace, u.gather);
                    let g = Gathered {
                        lines: Vec::new(),
                        photons: traced.photons,
                        beam_stats: traced.stats,
                        voxel_km: voxel.0,
                        voxel_source: voxel.1,
                        warnings,
                        noise: count.1.clone(),
                    };
                    let t = Instant::now();
                    let (voxel, beam_stats) = ((g.voxel_km, g.voxel_source.clone()), g.beam_stats.clone());
                    let (bake, dropped) = plan::finish_keeping(&plan, emission, g, times.clone(), t0, nothing)?;
                    u.finish = t.elapsed().as_secs_f64();
                    Ok(Cache { scene: scene.clone(), plan, count, beam_stats, dropped, voxel, bake, coarse: Some(coarse) })
                })();
                match r {
                    Ok(c) => c,
                    Err(e) => {
                        self.cache = prev;
                        return Err(e);
                    }
                }
            }
        };
        self.cache = Some(next);
        let cache = self.cache.as_ref().expect("just set");
        let (exposure, view) = (scene.render.exposure, scene.render.view_transform);
        let volume = Volume { density: Some(&cache.bake.density), emission: Some(&cache.bake.emission) };
        let spp = self.spp.clamp(1, scene.render.spp.max(1));
        let settings = self.settings(scene, w, h, spp);
        // New grids: the coarse picture first, from the coarse grids. A
        // `[volume]` edit keeps the medium (the scales apply at lookup).
        let rebuild = grids_changed || parts.is_none();
        if let (true, 0.0, Some(coarse)) = (rebuild, u.to_coarse, &cache.coarse) {
            let t = Instant::now();
            u.png += self.coarse_from(scene, coarse, &mut parts)?;
            u.coarse_render = t.elapsed().as_secs_f64();
            coarse_done(&mut u);
        }
        let t = Instant::now();
        let mut prepared = Prepared::reuse(parts, grids_changed || u.to_coarse > 0.0, &settings, &volume)?;
        u.render_build = t.elapsed().as_secs_f64();
        if u.to_coarse == 0.0 {
            // From the refined picture's structures at the coarse size.
            let t = Instant::now();
            prepared.set_image(cw, ch, 1)?;
            let img = render::render_prepared(&prepared, nothing);
            prepared.set_image(w, h, spp)?;
            u.png += self.write(&img?, exposure, view)?;
            u.coarse_render = t.elapsed().as_secs_f64();
            coarse_done(&mut u);
        }
        let t = Instant::now();
        let img = render::render_prepared(&prepared, nothing)?;
        u.render_pixels = t.elapsed().as_secs_f64();
        u.render = u.render_build + u.render_pixels;
        u.spp = spp;
        u.png += self.write(&img, exposure, view)?;
        u.to_picture = t0.elapsed().as_secs_f64();
        let mut look = Look { prepared, image: img };
        if scene.render.spp > spp && on_picture(&format!("picture ({w}x{h}, {spp} spp)"), u.to_picture) {
            // The scene's spp: the same samples and more (a pixel's first
            // `spp` samples do not depend on the total), as `aurora render`
            // draws them.
            let t = Instant::now();
            look.prepared.set_image(w, h, scene.render.spp)?;
            let img = render::render_prepared(&look.prepared, nothing)?;
            u.full_render = t.elapsed().as_secs_f64();
            u.full_spp = scene.render.spp;
            u.png += self.write(&img, exposure, view)?;
            u.to_full = t0.elapsed().as_secs_f64();
            look.image = img;
        }
        self.look = Some(look);
        Ok(u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_map_to_the_stages_they_touch() {
        let a = Scene::default();
        let edit = |f: &dyn Fn(&mut Scene)| {
            let mut b = a.clone();
            f(&mut b);
            stage_for_edit(&a, &b)
        };
        assert_eq!(edit(&|_| {}), Stage::Nothing);
        assert_eq!(edit(&|s| s.render.exposure += 1.0), Stage::Exposure);
        assert_eq!(
            edit(&|s| {
                s.render.exposure += 1.0;
                s.render.spp += 1
            }),
            Stage::Render
        );
        assert_eq!(edit(&|s| s.render.spp += 1), Stage::Render);
        assert_eq!(edit(&|s| s.volume.emission_scale *= 2.0), Stage::Render);
        assert_eq!(edit(&|s| s.render.width += 2), Stage::Camera);
        assert_eq!(edit(&|s| s.camera.fov_deg += 1.0), Stage::Camera);
        assert_eq!(edit(&|s| s.grid.density_a *= 2.0), Stage::Finish);
        assert_eq!(edit(&|s| s.grid.voxel_size = crate::scene::VoxelSize::Km(0.7)), Stage::Gather);
        assert_eq!(edit(&|s| s.photons.radius_km *= 1.1), Stage::Gather);
        assert_eq!(edit(&|s| s.photons.kernel = crate::scene::KernelShape::Point), Stage::Trace);
        assert_eq!(edit(&|s| s.beams.count += 1), Stage::Trace);
        assert_eq!(edit(&|s| s.colour.noise_km += 1.0), Stage::Trace);
        assert_eq!(edit(&|s| s.curtains[0].energy_flux *= 2.0), Stage::Footprints);
        assert_eq!(edit(&|s| s.seed += 1), Stage::Footprints);
        // The earliest stage wins.
        assert_eq!(
            edit(&|s| {
                s.render.exposure += 1.0;
                s.beams.count += 1
            }),
            Stage::Trace
        );
    }

    /// A scene that bakes in about a second, 4 samples per pixel, with the
    /// Cycles shell (the preview drops it: the pictures must not change).
    fn small_scene() -> Scene {
        let mut s = crate::scene::presets::small_test_scene();
        s.render.spp = 4;
        s.grid.cycles_shell = true;
        s
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("aurora-preview-test-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join("p.png")
    }

    const SIZE: [usize; 2] = [48, 27];

    /// `aurora render` of `aurora bake` at the preview size and `spp`: the
    /// bake with its Cycles shell, rendered from scratch.
    fn reference(scene: &Scene, spp: usize) -> Image {
        let b = bake::bake(scene, &NoProgress).unwrap();
        assert!(b.stats.shell_voxels > 0, "the reference keeps the shell");
        let mut s = RenderSettings::from_scene(scene);
        (s.render.width, s.render.height, s.render.spp) = (SIZE[0], SIZE[1], spp);
        render::render(&s, &Volume { density: Some(&b.density), emission: Some(&b.emission) }, &NoProgress).unwrap()
    }

    /// The progressive pictures: first at the preview's spp, then at the
    /// scene's, each the very image `aurora render` makes of `aurora bake`
    /// at that spp (so dropping the Cycles shell changes no pixel, and the
    /// cached renderer is the fresh one); a preview spp above the scene's
    /// is capped by it (one picture).
    #[test]
    fn the_refined_picture_is_the_render_of_the_bake() {
        let scene = small_scene();
        let out = scratch("progressive");
        let seen = std::sync::Mutex::new(Vec::new());
        let mut p = Preview::new(&out, SIZE, None);
        p.spp = 2;
        let u = p
            .update(&scene, &|what, _| {
                seen.lock().unwrap().push(what.to_string());
                true
            })
            .unwrap();
        assert_eq!((u.spp, u.full_spp), (2, 4));
        assert!(u.to_coarse > 0.0 && u.to_picture >= u.to_coarse && u.to_full >= u.to_picture, "{u:?}");
        assert_eq!(*seen.lock().unwrap(), ["coarse picture (12x6, 1 spp)", "picture (48x27, 2 spp)"]);
        assert_eq!(p.bake().unwrap().stats.shell_voxels, 0, "the preview bakes without the shell");
        let full = reference(&scene, 4);
        assert_eq!(p.image().unwrap().pixels, full.pixels);
        let mut q = Preview::new(&out, SIZE, None);
        q.spp = 8;
        let u = q.update(&scene, &|_, _| true).unwrap();
        assert_eq!((u.spp, u.full_spp, u.to_full), (4, 0, 0.0));
        assert_eq!(q.image().unwrap().pixels, full.pixels);
        let mut r = Preview::new(&out, SIZE, None);
        r.spp = 2;
        let mut two = scene.clone();
        two.render.spp = 2;
        r.update(&two, &|_, _| true).unwrap();
        assert_eq!(r.image().unwrap().pixels, reference(&two, 2).pixels);
        let _ = std::fs::remove_dir_all(out.parent().unwrap());
    }

    /// A false from `on_picture` after the preview-spp picture skips the
    /// one at the scene's spp; the next exposure edit re-encodes the
    /// preview-spp image.
    #[test]
    fn a_newer_edit_skips_the_full_picture() {
        let mut scene = small_scene();
        let out = scratch("skip");
        let mut p = Preview::new(&out, SIZE, None);
        p.spp = 2;
        let u = p.update(&scene, &|what, _| what.starts_with("coarse")).unwrap();
        assert_eq!((u.spp, u.full_spp, u.full_render, u.to_full), (2, 0, 0.0, 0.0));
        assert_eq!(p.image().unwrap().stats.primary_rays, (SIZE[0] * SIZE[1] * 2) as u64);
        scene.render.exposure += 1.0;
        let u = p.update(&scene, &|_, _| true).unwrap();
        assert_eq!((u.stage, u.spp), (Some(Stage::Exposure), 2));
        let _ = std::fs::remove_dir_all(out.parent().unwrap());
    }

    /// An exposure edit traces nothing: the PNG is the last linear image
    /// re-encoded at the new exposure, every stage time is 0.
    #[test]
    fn an_exposure_edit_only_reencodes() {
        let mut scene = small_scene();
        let out = scratch("exposure");
        let mut p = Preview::new(&out, SIZE, None);
        p.update(&scene, &|_, _| true).unwrap();
        let before = std::fs::read(&out).unwrap();
        let image = p.image().unwrap().clone();
        scene.render.exposure += 1.5;
        let u = p.update(&scene, &|_, _| panic!("an exposure edit writes one picture")).unwrap();
        assert_eq!(u.to_full, 0.0);
        assert_eq!(u.stage, Some(Stage::Exposure));
        let traced = [u.footprints, u.trace, u.gather, u.finish, u.coarse_render, u.render, u.render_build, u.render_pixels, u.full_render];
        assert_eq!(traced, [0.0; 9], "{u:?}");
        assert!(u.to_picture > 0.0 && u.png > 0.0);
        assert_eq!(p.image().unwrap(), &image, "the linear image is kept");
        let after = std::fs::read(&out).unwrap();
        assert_ne!(after, before, "the picture follows the exposure");
        let want = out.with_file_name("want.png");
        render::image_file::write_png(&want, &image, scene.render.exposure, scene.render.view_transform).unwrap();
        assert_eq!(after, std::fs::read(&want).unwrap());
        // The next render edit is diffed against the new exposure.
        scene.render.exposure += 0.5;
        scene.volume.emission_scale *= 2.0;
        let u = p.update(&scene, &|_, _| true).unwrap();
        assert_eq!(u.stage, Some(Stage::Render));
        let _ = std::fs::remove_dir_all(out.parent().unwrap());
    }

    /// Every edit through the cached stages and renderer gives the picture
    /// a fresh preview of the edited scene gives: render edits that keep
    /// the medium (albedo, background, spp, stars, terrain geometry, the
    /// terrain's presence: the sampler), rescale it (volume scales) or
    /// only the camera (fov, with and without pruning), a grid edit and a
    /// beams edit.
    #[test]
    fn cached_updates_equal_fresh_ones() {
        let mut scene = small_scene();
        let out = scratch("cached");
        let mut p = Preview::new(&out, SIZE, None);
        p.spp = 2;
        p.update(&scene, &|_, _| true).unwrap();
        type Edit<'a> = (&'a str, Stage, &'a dyn Fn(&mut Scene));
        let edits: [Edit; 12] = [
            ("albedo", Stage::Render, &|s| s.terrain.albedo = [0.5, 0.4, 0.3]),
            ("background", Stage::Render, &|s| s.background.radiance = [1e-3, 2e-3, 3e-3]),
            ("spp", Stage::Render, &|s| s.render.spp = 6),
            ("stars", Stage::Render, &|s| s.background.stars = true),
            ("mountains", Stage::Render, &|s| s.terrain.mountain_height += 1.0),
            ("no terrain", Stage::Render, &|s| s.terrain.kind = crate::scene::TerrainKind::None),
            // A medium built without terrain has no emission sampler: the
            // terrain's return needs one.
            ("scales", Stage::Render, &|s| {
                s.volume.emission_scale *= 3.0;
                s.volume.density_scale *= 2.0
            }),
            ("plane", Stage::Render, &|s| s.terrain.kind = crate::scene::TerrainKind::Plane),
            ("fov, pruned", Stage::Camera, &|s| s.camera.fov_deg += 5.0),
            ("unpruned", Stage::Finish, &|s| s.grid.prune = 0.0),
            ("fov, unpruned", Stage::Camera, &|s| s.camera.fov_deg -= 3.0),
            ("beams", Stage::Trace, &|s| s.beams.top_noise_km += 1.0),
        ];
        for (what, stage, edit) in edits {
            edit(&mut scene);
            let u = p.update(&scene, &|_, _| true).unwrap();
            assert_eq!(u.stage, Some(stage), "{what}");
            assert!(u.to_coarse > 0.0 && u.to_coarse <= u.to_picture, "{what}: coarse first {u:?}");
            let mut fresh = Preview::new(&out, SIZE, None);
            fresh.spp = 2;
            fresh.update(&scene, &|_, _| true).unwrap();
            assert!(p.image().unwrap().pixels == fresh.image().unwrap().pixels, "{what}: the cached picture differs from a fresh one");
        }
        let _ = std::fs::remove_dir_all(out.parent().unwrap());
    }
}
