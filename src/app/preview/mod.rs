//! `aurora preview`: a picture of the scene that follows its edits.
//!
//! A [`Preview`] keeps every stage's output in memory (the plan, the
//! photons, the finished grids: `cache`), the renderer's structures
//! ([`crate::render::Prepared`]: camera, medium, terrain, emission sampler,
//! sky) and the last linear image. An edit is diffed against the last good
//! scene section by section and only the stages it touches rerun
//! ([`stage_for_edit`]; its module has the table).
//!
//! Each update writes, atomically to the output PNG
//! (`crate::render::image_file::write_png`), up to three pictures:
//! 1. a coarse one: [`COARSE_FACTOR`] times smaller per side, one sample
//!    per pixel. When the edit gathers again it comes before the full
//!    gather, from a gather of every [`COARSE_PHOTON_STRIDE`]-th photon on
//!    voxels [`COARSE_VOXEL_FACTOR`] times larger; after any other edit it
//!    is rendered from the refined picture's structures with a smaller
//!    camera.
//! 2. the refined one: the preview size at the preview's spp
//!    ([`DEFAULT_SPP`], two antithetic pairs; `aurora preview --spp`),
//!    capped by the scene's `render.spp`. **The edit-to-picture targets
//!    (<= 1 s after a render edit, <= 3 s after a beams edit, on 2 cores) are
//!    judged on this picture.**
//! 3. when the scene's `render.spp` is larger, the picture at the scene's
//!    spp, the very image `aurora render` makes of `aurora bake` at that
//!    size and spp (tested). `--watch` skips it when the file changed again
//!    meanwhile, so a newer edit waits only for picture 2; `aurora preview`
//!    without `--watch` always does (the quick picture is its last).
//!
//! The bake runs at the scene's own settings (beam count, voxel size for
//! the scene's `render` size): the preview size only sets the picture's.
//! It skips the Cycles shell (`grid.cycles_shell`), which changes no pixel
//! of the reference renderer (tested against `aurora bake`'s grids, shell
//! included) and would cost the dilation and a larger medium. The update
//! reports every stage's time ([`Update`]; `examples/preview_bench.rs`
//! measures an edit of each kind).

mod cache;
mod edit;

pub use cache::{COARSE_PHOTON_STRIDE, COARSE_VOXEL_FACTOR};
pub use edit::{stage_for_edit, Stage};

use crate::pipeline::bake::{Bake, BakeError};
use crate::render::{self, Image, Prepared, RenderError, RenderSettings, Volume};
use crate::scene::Scene;
use crate::util::progress::NoProgress;
use cache::{Cache, Seconds};
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

/// What the last refined picture was rendered with: the renderer's
/// structures (kept while their inputs are unchanged) and the linear
/// image last written (an exposure edit re-encodes it).
struct Look {
    prepared: Prepared,
    image: Image,
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

    /// Writes `img` developed for `scene` (white balance, exposure:
    /// `crate::render::develop`) through its view to the output PNG;
    /// returns its seconds.
    fn write(&self, img: &Image, scene: &Scene) -> Result<f64, RenderError> {
        let t = Instant::now();
        let (shown, d) = render::develop::develop(img, &scene.colour, &scene.render);
        render::image_file::write_png_with(
            &self.out,
            &shown,
            d.exposure_ev,
            scene.render.view_transform,
            render::image_file::PngBits::Eight,
            &d.metadata(),
        )?;
        Ok(t.elapsed().as_secs_f64())
    }

    /// The coarse picture's size, pixels.
    fn coarse_size(&self) -> (usize, usize) {
        let [w, h] = self.size;
        ((w / COARSE_FACTOR).max(1), (h / COARSE_FACTOR).max(1))
    }

    /// Renders and writes the coarse picture of `coarse`'s grids, with the
    /// renderer's parts that do not depend on the grids (terrain, sky)
    /// taken from `prev`, which holds the coarse picture's afterwards.
    /// Returns the PNG's seconds.
    fn coarse_from(&self, scene: &Scene, coarse: &Bake, prev: &mut Option<Prepared>) -> Result<f64, RenderError> {
        let volume = Volume { density: Some(&coarse.density), emission: Some(&coarse.emission) };
        let (cw, ch) = self.coarse_size();
        let s = self.settings(scene, cw, ch, 1);
        let p = Prepared::reuse(prev.take(), true, &s, &volume)?;
        let img = render::render_prepared(&p, &NoProgress)?;
        *prev = Some(p);
        self.write(&img, scene)
    }

    /// The coarse picture is on disk: its time since `t0`, and
    /// `on_picture` told (too early to stop: the refined picture follows).
    fn coarse_written(&self, u: &mut Update, t0: Instant, on_picture: &dyn Fn(&str, f64) -> bool) {
        let (cw, ch) = self.coarse_size();
        u.to_coarse = t0.elapsed().as_secs_f64();
        let _ = on_picture(&format!("coarse picture ({cw}x{ch}, 1 spp)"), u.to_coarse);
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
        if stage == Stage::Exposure {
            if let Some(look) = &self.look {
                // A tone map of the last linear image: nothing is traced.
                u.png = self.write(&look.image, scene)?;
                u.spp = look.prepared.settings().render.spp;
                u.to_picture = t0.elapsed().as_secs_f64();
                if let Some(c) = self.cache.as_mut() {
                    c.scene = scene.clone();
                }
                return Ok(u);
            }
        }
        // The renderer's parts of the last picture (the coarse picture's
        // once it is rendered from a coarse gather).
        let mut parts = self.look.take().map(|l| l.prepared);
        let mut secs = Seconds::default();
        let cached = self.cache.take();
        // An edit that gathers again shows the coarse grids before the
        // full gather.
        let mut show = |coarse: &Bake, t: Instant| -> Result<(), PreviewError> {
            u.png = self.coarse_from(scene, coarse, &mut parts)?;
            u.coarse_render = t.elapsed().as_secs_f64();
            self.coarse_written(&mut u, t0, on_picture);
            Ok(())
        };
        // Stages up to the grids; the cache is replaced only on success.
        let (next, grids_changed) = match cached {
            Some(mut c) if stage <= Stage::Gather => match c.refinish(scene, stage, t0, &mut secs, &mut show) {
                Ok(changed) => {
                    c.scene = scene.clone();
                    (c, changed)
                }
                Err(e) => {
                    self.cache = Some(c);
                    return Err(e);
                }
            },
            prev => match Cache::rebuild(prev.as_ref(), scene, t0, &mut secs, &mut show) {
                Ok(c) => (c, true),
                Err(e) => {
                    self.cache = prev;
                    return Err(e);
                }
            },
        };
        (u.footprints, u.pilot, u.trace, u.gather, u.finish) = (secs.footprints, secs.pilot, secs.trace, secs.gather, secs.finish);
        self.cache = Some(next);
        self.look = Some(self.pictures(scene, parts, grids_changed, &mut u, t0, on_picture)?);
        Ok(u)
    }

    /// The pictures of the cached grids: the coarse one unless it is on
    /// disk already (from the coarse grids when the grids are new, else
    /// from the refined picture's structures at the coarse size), the
    /// refined one, and the one at the scene's spp when larger (unless
    /// `on_picture` says stop). `parts` are the renderer's structures of
    /// the last picture.
    fn pictures(
        &self,
        scene: &Scene,
        mut parts: Option<Prepared>,
        grids_changed: bool,
        u: &mut Update,
        t0: Instant,
        on_picture: &dyn Fn(&str, f64) -> bool,
    ) -> Result<Look, PreviewError> {
        let nothing = &NoProgress;
        let cache = self.cache.as_ref().expect("the cache is set before the pictures");
        let volume = Volume { density: Some(&cache.bake.density), emission: Some(&cache.bake.emission) };
        let [w, h] = self.size;
        let spp = self.spp.clamp(1, scene.render.spp.max(1));
        let settings = self.settings(scene, w, h, spp);
        // New grids: the coarse picture first, from the coarse grids. A
        // `[volume]` edit keeps the medium (the scales apply at lookup).
        let rebuild = grids_changed || parts.is_none();
        if let (true, 0.0, Some(coarse)) = (rebuild, u.to_coarse, &cache.coarse) {
            let t = Instant::now();
            u.png += self.coarse_from(scene, coarse, &mut parts)?;
            u.coarse_render = t.elapsed().as_secs_f64();
            self.coarse_written(u, t0, on_picture);
        }
        let t = Instant::now();
        let mut prepared = Prepared::reuse(parts, grids_changed || u.to_coarse > 0.0, &settings, &volume)?;
        u.render_build = t.elapsed().as_secs_f64();
        if u.to_coarse == 0.0 {
            // From the refined picture's structures at the coarse size.
            let t = Instant::now();
            let (cw, ch) = self.coarse_size();
            prepared.set_image(cw, ch, 1)?;
            let img = render::render_prepared(&prepared, nothing);
            prepared.set_image(w, h, spp)?;
            u.png += self.write(&img?, scene)?;
            u.coarse_render = t.elapsed().as_secs_f64();
            self.coarse_written(u, t0, on_picture);
        }
        let t = Instant::now();
        let img = render::render_prepared(&prepared, nothing)?;
        u.render_pixels = t.elapsed().as_secs_f64();
        u.render = u.render_build + u.render_pixels;
        u.spp = spp;
        u.png += self.write(&img, scene)?;
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
            u.png += self.write(&img, scene)?;
            u.to_full = t0.elapsed().as_secs_f64();
            look.image = img;
        }
        Ok(look)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::bake;

    /// A scene that bakes in about a second, 4 samples per pixel, with the
    /// Cycles shell (the preview drops it: the pictures must not change).
    fn small_scene() -> Scene {
        let mut s = crate::scene::presets::small_test_scene();
        s.render.spp = 4;
        s.grid.cycles_shell = true;
        s
    }

    /// A test's scratch folder, removed when the test ends, passed or not.
    struct Scratch(PathBuf);

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// The scratch folder of test `name` and the output PNG's path in it.
    fn scratch(name: &str) -> (Scratch, PathBuf) {
        let d = std::env::temp_dir().join(format!("aurora-preview-test-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let out = d.join("p.png");
        (Scratch(d), out)
    }

    const SIZE: [usize; 2] = [48, 27];

    /// A preview of `SIZE` writing to `out`, its refined picture at `spp`.
    fn preview(out: &Path, spp: usize) -> Preview {
        let mut p = Preview::new(out, SIZE, None);
        p.spp = spp;
        p
    }

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
        let (_dir, out) = scratch("progressive");
        let seen = std::sync::Mutex::new(Vec::new());
        let mut p = preview(&out, 2);
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
        let mut q = preview(&out, 8);
        let u = q.update(&scene, &|_, _| true).unwrap();
        assert_eq!((u.spp, u.full_spp, u.to_full), (4, 0, 0.0));
        assert_eq!(q.image().unwrap().pixels, full.pixels);
        let mut r = preview(&out, 2);
        let mut two = scene.clone();
        two.render.spp = 2;
        r.update(&two, &|_, _| true).unwrap();
        assert_eq!(r.image().unwrap().pixels, reference(&two, 2).pixels);
    }

    /// A false from `on_picture` after the preview-spp picture skips the
    /// one at the scene's spp; the next exposure edit re-encodes the
    /// preview-spp image.
    #[test]
    fn a_newer_edit_skips_the_full_picture() {
        let mut scene = small_scene();
        let (_dir, out) = scratch("skip");
        let mut p = preview(&out, 2);
        let u = p.update(&scene, &|what, _| what.starts_with("coarse")).unwrap();
        assert_eq!((u.spp, u.full_spp, u.full_render, u.to_full), (2, 0, 0.0, 0.0));
        assert_eq!(p.image().unwrap().stats.primary_rays, (SIZE[0] * SIZE[1] * 2) as u64);
        scene.render.exposure += 1.0;
        let u = p.update(&scene, &|_, _| true).unwrap();
        assert_eq!((u.stage, u.spp), (Some(Stage::Exposure), 2));
    }

    /// An exposure edit traces nothing: the PNG is the last linear image
    /// re-encoded at the new exposure, every stage time is 0.
    #[test]
    fn an_exposure_edit_only_reencodes() {
        let mut scene = small_scene();
        let (_dir, out) = scratch("exposure");
        let mut p = preview(&out, DEFAULT_SPP);
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
        let (shown, d) = render::develop::develop(&image, &scene.colour, &scene.render);
        render::image_file::write_png_with(
            &want,
            &shown,
            d.exposure_ev,
            scene.render.view_transform,
            render::image_file::PngBits::Eight,
            &d.metadata(),
        )
        .unwrap();
        assert_eq!(after, std::fs::read(&want).unwrap());
        // The next render edit is diffed against the new exposure.
        scene.render.exposure += 0.5;
        scene.volume.emission_scale *= 2.0;
        let u = p.update(&scene, &|_, _| true).unwrap();
        assert_eq!(u.stage, Some(Stage::Render));
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
        let (_dir, out) = scratch("cached");
        let mut p = preview(&out, 2);
        p.update(&scene, &|_, _| true).unwrap();
        type Edit<'a> = (&'a str, Stage, &'a dyn Fn(&mut Scene));
        let edits: [Edit; 12] = [
            ("albedo", Stage::Render, &|s| s.terrain.albedo = [0.5, 0.4, 0.3]),
            ("background", Stage::Render, &|s| s.background.radiance = [1e-3, 2e-3, 3e-3]),
            ("spp", Stage::Render, &|s| s.render.spp = 6),
            ("stars", Stage::Render, &|s| s.background.stars = !s.background.stars),
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
            let mut fresh = preview(&out, 2);
            fresh.update(&scene, &|_, _| true).unwrap();
            assert!(p.image().unwrap().pixels == fresh.image().unwrap().pixels, "{what}: the cached picture differs from a fresh one");
        }
    }
}
