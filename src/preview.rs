//! `aurora preview`: a picture of the scene that follows its edits.
//!
//! A [`Preview`] keeps every stage's output in memory: the
//! [`BakePlan`](crate::pipeline::BakePlan) (footprints, atmosphere, colour
//! table), the photons, the gathered emission grid before pruning, and the
//! finished grids. An edit is diffed against the last good scene section by
//! section ([`stage_for_edit`]) and only the stages it touches are rerun:
//!
//! | the edit touches | rerun |
//! |---|---|
//! | `[render]` spp / exposure, `[volume]`, `[background]`, `[terrain]` | the render |
//! | `[camera]`, `[render]` width / height | the voxel size (`"auto"` follows the camera): the gather when it changed, pruning when `grid.prune > 0`, then the render |
//! | `[grid]` other than `voxel_size` | finish (checks, pruning, density, shell) |
//! | `grid.voxel_size`, `[photons]` other than `kernel` | gather and finish |
//! | `[beams]`, `[colour]`, `[atmosphere]`, `photons.kernel` | trace, gather, finish (the footprints are kept) |
//! | `seed`, `[[curtain]]`, `[footprint]`, `[animation]` | everything |
//!
//! Colour edits retrace: a photon carries its RGB power, not the altitude
//! and deposited power it was coloured from, so the data do not allow a
//! recolour without the beams; the footprints (the fluid simulation) are
//! kept ([`crate::pipeline::BakePlan::reusing`]).
//!
//! Each update renders a coarse picture first (a quarter of the size, one
//! sample per pixel; when the edit rebuilds the grids, from a quick gather on
//! voxels [`COARSE_VOXEL_FACTOR`] times larger, before the full gather) and
//! then the refined one (the preview size, the
//! scene's `render.spp`), each written atomically to the output PNG
//! (`crate::render::film::write_png`), and reports the time of every stage
//! and from the edit to each picture. The bake runs at the scene's own
//! settings (beam count, voxel size for the scene's `render` size): the
//! preview size only sets the picture's.

use crate::bake::{self, Bake, BakeError};
use crate::grid::Grid;
use crate::pipeline::{self, BakePlan, Gathered, StageTimes};
use crate::progress::NoProgress;
use crate::render::{self, RenderError, RenderSettings, Volume};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Default preview size, pixels.
pub const DEFAULT_SIZE: [usize; 2] = [320, 180];

/// The coarse picture is this many times smaller per side, one sample per
/// pixel.
pub const COARSE_FACTOR: usize = 4;

/// When an edit rebuilds the grids, the coarse picture is rendered from a
/// gather on voxels this many times larger per side: the coarse picture's
/// pixels are four times larger too, and the gather costs about 8x less.
pub const COARSE_VOXEL_FACTOR: f64 = 2.0;

/// The earliest stage an edit invalidates (later stages rerun too).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Nothing the picture depends on changed.
    Nothing,
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
    at(old.beams != new.beams || old.colour != new.colour || old.atmosphere != new.atmosphere, Stage::Trace);
    at(old.photons.kernel != new.photons.kernel, Stage::Trace);
    at(old.photons != new.photons || old.grid.voxel_size != new.grid.voxel_size, Stage::Gather);
    at(old.grid != new.grid, Stage::Finish);
    at(old.camera != new.camera || (old.render.width, old.render.height) != (new.render.width, new.render.height), Stage::Camera);
    at(old.render != new.render || old.volume != new.volume || old.background != new.background || old.terrain != new.terrain, Stage::Render);
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
    pub coarse_render: f64,
    pub render: f64,
    /// Of `render`: building the renderer's structures from the grids
    /// (`RenderStats::build_seconds`), and the pixel loop.
    pub render_build: f64,
    pub render_pixels: f64,
    /// From the start of the update to the coarse and the refined picture
    /// on disk.
    pub to_coarse: f64,
    pub to_picture: f64,
}

impl Update {
    /// One line for the terminal.
    pub fn summary(&self) -> String {
        let st = self.stage.map_or("first".to_string(), |s| format!("{s:?}").to_lowercase());
        format!(
            "edit ({st}): footprints {:.2} s, pilot {:.2} s, trace {:.2} s, gather {:.2} s, finish {:.2} s, coarse render {:.2} s, render {:.2} s (build {:.2} s, pixels {:.2} s); edit to coarse picture {:.2} s, to picture {:.2} s",
            self.footprints, self.pilot, self.trace, self.gather, self.finish, self.coarse_render, self.render, self.render_build, self.render_pixels, self.to_coarse, self.to_picture
        )
    }
}

/// The cached stages of one scene.
struct Cache {
    scene: Scene,
    plan: BakePlan,
    /// Beam count, pilot estimate and pilot warnings.
    count: (usize, Option<pipeline::NoiseEstimate>, Vec<String>),
    beam_stats: crate::beams::BeamStats,
    /// The gathered emission before finishing, and its voxel size.
    gathered: Grid<[f32; 3]>,
    voxel: (f64, String),
    bake: Bake,
}

/// The preview's state: the last good scene's stage outputs.
pub struct Preview {
    pub out: PathBuf,
    pub size: [usize; 2],
    /// Folder against which a relative `terrain.heightmap` is resolved.
    pub base_dir: Option<PathBuf>,
    cache: Option<Cache>,
}

impl Preview {
    pub fn new(out: &Path, size: [usize; 2], base_dir: Option<PathBuf>) -> Preview {
        Preview { out: out.to_path_buf(), size, base_dir, cache: None }
    }

    /// The last finished bake (None before the first update).
    pub fn bake(&self) -> Option<&Bake> {
        self.cache.as_ref().map(|c| &c.bake)
    }

    /// The coarse picture of an edit that rebuilds the grids: the photons
    /// gathered on voxels [`COARSE_VOXEL_FACTOR`] times larger (that many
    /// cubed fewer voxels per photon), finished, rendered at the coarse size
    /// with one sample and written. Returns its seconds.
    fn coarse_picture(&self, scene: &Scene, plan: &BakePlan, photons: &[crate::beams::Photon], voxel_km: f64) -> Result<f64, PreviewError> {
        let t = Instant::now();
        let nothing = &NoProgress;
        let v = COARSE_VOXEL_FACTOR * voxel_km;
        let emission = pipeline::gather(plan, photons, v, nothing);
        // Only the grids are used: no photons for the power sums, no warnings.
        let g = Gathered {
            photons: Vec::new(),
            beam_stats: Default::default(),
            voxel_km: v,
            voxel_source: "coarse preview".into(),
            warnings: Vec::new(),
            noise: None,
        };
        let b = pipeline::finish(plan, emission, g, StageTimes::default(), t, nothing)?;
        let volume = Volume { density: Some(&b.density), emission: Some(&b.emission) };
        let mut s = RenderSettings::from_scene(scene);
        s.base_dir = self.base_dir.clone();
        s.render.width = (self.size[0] / COARSE_FACTOR).max(1);
        s.render.height = (self.size[1] / COARSE_FACTOR).max(1);
        s.render.spp = 1;
        let img = render::render(&s, &volume, nothing)?;
        render::film::write_png(&self.out, &img, scene.render.exposure)?;
        Ok(t.elapsed().as_secs_f64())
    }

    /// Brings the pictures up to date with `scene` (validated), rerunning
    /// only the stages the edit touches, and writes the coarse and refined
    /// PNGs. On an error the previous state is kept. `on_coarse` is called
    /// once the coarse picture is written.
    pub fn update(&mut self, scene: &Scene, on_coarse: &dyn Fn(f64)) -> Result<Update, PreviewError> {
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
        let mut times = StageTimes::default();
        let nothing = &NoProgress;
        // When the grids are rebuilt, the coarse picture comes from a
        // coarse gather before the full one (Preview::coarse_picture).
        let coarse_done = |u: &mut Update| {
            u.to_coarse = t0.elapsed().as_secs_f64();
            on_coarse(u.to_coarse);
        };
        // Stages up to the grids; the cache is replaced only on success.
        let next = match self.cache.take() {
            Some(mut c) if stage <= Stage::Gather => {
                let r = (|| -> Result<(), PreviewError> {
                    // The plan's plain data follow the edit; footprints,
                    // atmosphere and colour table are kept.
                    let plan = BakePlan::reusing(scene, &c.plan, nothing);
                    let mut regather = stage == Stage::Gather;
                    if stage == Stage::Camera {
                        // "auto" voxel size follows the camera.
                        let v = plan.voxel_size(&c.bake.photons);
                        regather = v.0 != c.voxel.0;
                        if !regather && plan.grid.prune <= 0.0 {
                            c.plan = plan;
                            c.voxel = v;
                            return Ok(());
                        }
                    }
                    if stage == Stage::Render {
                        c.plan = plan;
                        return Ok(());
                    }
                    if regather {
                        c.voxel = plan.voxel_size(&c.bake.photons);
                        u.coarse_render = self.coarse_picture(scene, &plan, &c.bake.photons, c.voxel.0)?;
                        coarse_done(&mut u);
                        let t = Instant::now();
                        c.gathered = pipeline::gather(&plan, &c.bake.photons, c.voxel.0, nothing);
                        u.gather = t.elapsed().as_secs_f64();
                    }
                    let t = Instant::now();
                    let mut warnings = pipeline::resolution_warnings_for(plan.kernel, &plan.footprints, plan.footprint.threshold, c.voxel.0);
                    warnings.extend(c.count.2.iter().cloned());
                    let g = Gathered {
                        photons: c.bake.photons.clone(),
                        beam_stats: c.beam_stats.clone(),
                        voxel_km: c.voxel.0,
                        voxel_source: c.voxel.1.clone(),
                        warnings,
                        noise: c.count.1.clone(),
                    };
                    c.bake = pipeline::finish(&plan, c.gathered.clone(), g, times.clone(), t0, nothing)?;
                    u.finish = t.elapsed().as_secs_f64();
                    c.plan = plan;
                    Ok(())
                })();
                match r {
                    Ok(()) => {
                        c.scene = scene.clone();
                        c
                    }
                    Err(e) => {
                        self.cache = Some(c);
                        return Err(e.into());
                    }
                }
            }
            prev => {
                let r = (|| -> Result<Cache, PreviewError> {
                    crate::budget::check(&crate::budget::estimate(scene), &crate::memory::available()).map_err(BakeError::from)?;
                    let t = Instant::now();
                    let plan = match &prev {
                        Some(c) => BakePlan::reusing(scene, &c.plan, nothing),
                        None => BakePlan::new(scene, nothing),
                    };
                    u.footprints = t.elapsed().as_secs_f64();
                    times.footprints = plan.footprint_seconds;
                    let count = bake::beam_count(&plan, &mut times, nothing)?;
                    u.pilot = times.pilot;
                    let t = Instant::now();
                    let traced = pipeline::trace(&plan, count.0, 0, 0..count.0, nothing).map_err(BakeError::from)?;
                    u.trace = t.elapsed().as_secs_f64();
                    let voxel = plan.voxel_size(&traced.photons);
                    u.coarse_render = self.coarse_picture(scene, &plan, &traced.photons, voxel.0)?;
                    coarse_done(&mut u);
                    let t = Instant::now();
                    let mut warnings = pipeline::resolution_warnings_for(plan.kernel, &plan.footprints, plan.footprint.threshold, voxel.0);
                    warnings.extend(count.2.iter().cloned());
                    let emission = pipeline::gather(&plan, &traced.photons, voxel.0, nothing);
                    u.gather = t.elapsed().as_secs_f64();
                    (times.beams, times.gather) = (u.trace, u.gather);
                    let g = Gathered {
                        photons: traced.photons,
                        beam_stats: traced.stats,
                        voxel_km: voxel.0,
                        voxel_source: voxel.1,
                        warnings,
                        noise: count.1.clone(),
                    };
                    let t = Instant::now();
                    let (gathered, voxel, beam_stats) = (emission.clone(), (g.voxel_km, g.voxel_source.clone()), g.beam_stats.clone());
                    let bake = pipeline::finish(&plan, emission, g, times.clone(), t0, nothing)?;
                    u.finish = t.elapsed().as_secs_f64();
                    Ok(Cache { scene: scene.clone(), plan, count, beam_stats, gathered, voxel, bake })
                })();
                match r {
                    Ok(c) => c,
                    Err(e) => {
                        self.cache = prev;
                        return Err(e.into());
                    }
                }
            }
        };
        let cache = self.cache.insert(next);
        let exposure = scene.render.exposure;
        let volume = Volume { density: Some(&cache.bake.density), emission: Some(&cache.bake.emission) };
        let [w, h] = self.size;
        let settings = |w: usize, h: usize, spp: usize| {
            let mut s = RenderSettings::from_scene(scene);
            s.base_dir = self.base_dir.clone();
            s.render.width = w;
            s.render.height = h;
            s.render.spp = spp;
            s
        };
        if u.to_coarse == 0.0 {
            let t = Instant::now();
            let coarse = settings((w / COARSE_FACTOR).max(1), (h / COARSE_FACTOR).max(1), 1);
            let img = render::render(&coarse, &volume, nothing)?;
            render::film::write_png(&self.out, &img, exposure)?;
            u.coarse_render = t.elapsed().as_secs_f64();
            coarse_done(&mut u);
        }
        let t = Instant::now();
        let img = render::render(&settings(w, h, scene.render.spp), &volume, nothing)?;
        render::film::write_png(&self.out, &img, exposure)?;
        u.render = t.elapsed().as_secs_f64();
        (u.render_build, u.render_pixels) = (img.stats.build_seconds, img.stats.render_seconds);
        u.to_picture = t0.elapsed().as_secs_f64();
        Ok(u)
    }
}

/// The identity of a file's contents for the watcher: modification time,
/// size and an FNV-1a hash of the bytes (a save within the clock's
/// resolution, or of the same size, is still seen).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileStamp {
    pub modified: Option<std::time::SystemTime>,
    pub len: u64,
    pub hash: u64,
}

impl FileStamp {
    /// The stamp and the text of `path` (None while it cannot be read, e.g.
    /// in the middle of an editor's save).
    pub fn read(path: &Path) -> Option<(FileStamp, String)> {
        let meta = std::fs::metadata(path).ok()?;
        let bytes = std::fs::read(path).ok()?;
        let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
        let text = String::from_utf8_lossy(&bytes).into_owned();
        Some((FileStamp { modified: meta.modified().ok(), len: meta.len(), hash }, text))
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
        assert_eq!(edit(&|s| s.render.exposure += 1.0), Stage::Render);
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
        assert_eq!(edit(&|s| { s.render.exposure += 1.0; s.beams.count += 1 }), Stage::Trace);
    }
}
