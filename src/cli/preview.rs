//! `aurora preview`: one quick picture of a scene (the coarse and the
//! refined picture, at the preview's size and spp, never the scene's spp),
//! or (--watch) a picture per save of the scene file until killed. A bad
//! edit is reported as `aurora bake` words it and the watch goes on with
//! the last good scene. The `--set` overrides apply to every save.

use super::args::{PreviewArgs, SceneOverrides};
use super::exit::InputError;
use super::render::{image_format, ImageFormat};
use super::{load_scene, print_warnings, scene_dir, with_threads};
use anyhow::Result;
use aurora::app::preview::{Preview, Update};
use aurora::scene::Scene;
use aurora::util::file_watch::Watcher;
use std::cell::{Cell, RefCell};
use std::path::Path;

pub fn run(a: PreviewArgs) -> Result<()> {
    let PreviewArgs { scene: scene_arg, out, size, watch, spp, common, overrides } = a;
    image_format("--out", &out).and_then(|f| match f {
        ImageFormat::Png => Ok(()),
        ImageFormat::Exr => Err(InputError(format!("--out {}: the preview writes PNG", out.display())).into()),
    })?;
    super::render_checks::preview_within_memory(size)?;
    let dir = scene_dir(&scene_arg);
    with_threads(common.threads, || {
        let mut preview = Preview::new(&out, size, Some(dir.to_path_buf()));
        preview.spp = spp as usize;
        let session = Session {
            out: &out,
            quiet: common.quiet,
            overrides: &overrides,
            once: !watch,
            watcher: RefCell::new(None),
            previewing: Cell::new(None),
        };
        if watch {
            session.watch(&mut preview, &scene_arg)
        } else {
            session.once(&mut preview, &scene_arg)
        }
    })
}

/// What the updates of one `aurora preview` share: where the picture goes,
/// and with --watch the watcher and the hash of the scene text being
/// previewed (a picture at the scene's spp is skipped once another save has
/// ended).
struct Session<'a> {
    out: &'a Path,
    quiet: bool,
    overrides: &'a SceneOverrides,
    /// Without --watch: the quick picture is the last (no picture at the scene's spp).
    once: bool,
    watcher: RefCell<Option<Watcher>>,
    previewing: Cell<Option<u64>>,
}

impl Session<'_> {
    /// Called after each picture of an update: prints its time, and answers
    /// whether the update goes on (no newer save has ended meanwhile).
    fn on_picture(&self, what: &str, secs: f64) -> bool {
        if !self.quiet {
            eprintln!("{what} in {secs:.2} s");
        }
        if self.once {
            return false;
        }
        let mut w = self.watcher.borrow_mut();
        self.previewing.get().zip(w.as_mut()).is_none_or(|(h, w)| !w.changed_since(h))
    }

    /// One update of the picture from `scene`, its warnings and summary printed.
    fn update(&self, preview: &mut Preview, scene: &Scene) -> Result<(), aurora::app::preview::PreviewError> {
        let u = preview.update(scene, &|what, secs| self.on_picture(what, secs))?;
        if let Some(b) = preview.bake() {
            print_warnings(&b.stats.warnings);
        }
        self.report(&u);
        Ok(())
    }

    fn report(&self, u: &Update) {
        if !self.quiet {
            eprintln!("wrote {}: {}", self.out.display(), u.summary());
        }
    }

    /// Without --watch: one update (the coarse and the refined picture), then exit.
    fn once(&self, preview: &mut Preview, scene_arg: &str) -> Result<()> {
        let scene = load_scene(scene_arg, self.overrides)?;
        super::render_checks::camera_above_terrain(&scene, &scene_dir(scene_arg))?;
        Ok(self.update(preview, &scene)?)
    }

    /// The --watch loop: an update per save that ended and changed the text
    /// (`aurora::util::file_watch`); never returns but on a watch that cannot start.
    fn watch(&self, preview: &mut Preview, scene_arg: &str) -> Result<()> {
        let path = Path::new(scene_arg);
        if !path.is_file() {
            return Err(InputError(format!(
                "{scene_arg}: --watch needs a scene file (write a preset to one: aurora scene default > scene.toml)"
            ))
            .into());
        }
        let w = Watcher::new(path).map_err(|e| InputError(e.to_string()))?;
        if !self.quiet {
            eprintln!("watching {} ({}; Ctrl-C to stop)", path.display(), w.describe());
        }
        *self.watcher.borrow_mut() = Some(w);
        loop {
            // A bad save is worded as `aurora bake` words it and the last
            // good scene stays.
            let save = self.watcher.borrow_mut().as_mut().expect("set above").next_save();
            let save = match save {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("aurora: error: {e}");
                    continue;
                }
            };
            self.previewing.set(Some(save.hash));
            if !self.quiet {
                eprintln!("scene {}: text hash {:016x}, {} bytes", path.display(), save.hash, save.text.len());
            }
            if save.is_blank() {
                eprintln!(
                    "aurora: error: {scene_arg}: the saved scene file is empty (only whitespace and comments); keeping the last good scene"
                );
                continue;
            }
            let result = Scene::from_toml_str_with(&save.text, scene_arg, self.overrides.in_order())
                .map_err(anyhow::Error::from)
                .and_then(|mut scene| {
                    // As `Scene::load` and `load_scene`: the data folder is
                    // relative to the scene file, its tables read now.
                    scene.atmosphere.base_dir = Some(path.parent().map(Path::to_path_buf).unwrap_or_default());
                    aurora::physics::atmosphere::Atmosphere::of_params(&scene.atmosphere)?;
                    super::render_checks::camera_above_terrain(&scene, &scene_dir(scene_arg))?;
                    Ok(aurora::pipeline::footprint::magnetic_placement::place(&scene).map_err(|e| InputError(e.to_string()))?)
                })
                .and_then(|scene| self.update(preview, &scene).map_err(anyhow::Error::from));
            if let Err(e) = result {
                eprintln!("aurora: error: {e:#}");
            }
        }
    }
}
