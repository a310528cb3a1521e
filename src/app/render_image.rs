//! One image of a scene, as `aurora render` makes it and the Python module
//! returns it: the renderer's settings from the scene ([`settings_for`]),
//! the volume prepared from one of three sources ([`prepare`]), traced
//! (with adaptive sampling if asked). The sources: a VDB's records read
//! straight into the renderer's medium, a VDB read into grids where that
//! path does not apply (a float emission grid, active tiles, the motion
//! blur's velocity grid), or a bake in memory.
//!
//! With a grid name one float grid alone is the emission, grey
//! ([`prepare_grid`]): a `line_*` grid of `grid.lines` in rayleigh per km,
//! integrated along each ray, is the line's column brightness in rayleigh,
//! `4 pi I / 1e6` with I the radiance in photons cm^-2 s^-1 sr^-1 (Hunten,
//! Roach & Chamberlain 1956, J. Atmos. Terr. Phys. 8, 345): an all-sky
//! imager's narrow-band filter image ([`grey_metadata`] words its units).
//! The sky, the stars and the airglow are left out of such an image, and
//! the air's extinction is the line's own.

use crate::io::vdb::read::read_vdb_for_render;
use crate::pipeline::bake::BakeError;
use crate::render::image::Image;
use crate::render::image_file::GreyMetadata;
use crate::render::{Prepared, RenderError, RenderSettings, Volume};
use crate::scene::Scene;
use crate::util::progress::Progress;
use std::path::{Path, PathBuf};

/// What one image is made from.
#[derive(Clone, Debug)]
pub struct ImageRequest<'a> {
    pub scene: &'a Scene,
    /// The folder the scene's relative paths are resolved against.
    pub dir: PathBuf,
    /// The VDB to render; none: bake the scene in memory.
    pub vdb: Option<&'a Path>,
    /// The sequence's frame (its time for the motion and a `[site]`'s sky).
    pub frame: Option<i64>,
    /// One float grid alone as a grey emission (module doc).
    pub grid: Option<&'a str>,
    pub adaptive: bool,
}

/// An image and how it was made.
pub struct Rendered {
    pub image: Image,
    /// Seconds spent opening the source (reading the VDB, or baking).
    pub open_seconds: f64,
    /// The bake's warnings, when the scene was baked.
    pub warnings: Vec<String>,
}

/// Why an image could not be made; each variant names the key, grid or file.
#[derive(Debug, thiserror::Error)]
pub enum RenderImageError {
    /// The motion blur needs the velocity grid, which the source lacks.
    #[error(
        "render.shutter_s = {shutter_s} blurs along the velocity grid `v`, which {what} does not hold: bake it with grid.velocity = true (or set render.shutter_s = 0)"
    )]
    NoVelocity { shutter_s: f64, what: String },
    /// The grid asked for is not in the source.
    #[error("--grid {name}: {what} has no float grid of that name (float emission grids: {there})")]
    NoGrid { name: String, what: String, there: String },
    /// The VDB could not be read or shown (its own message, and its class).
    #[error("{message}")]
    Vdb { message: String, input: bool },
    #[error(transparent)]
    Bake(#[from] BakeError),
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl RenderImageError {
    /// The source, the grid name or the scene is the user's (exit status
    /// 2); a failure of the renderer or the bake as they say.
    pub fn is_input(&self) -> bool {
        match self {
            RenderImageError::NoVelocity { .. } | RenderImageError::NoGrid { .. } => true,
            RenderImageError::Vdb { input, .. } => *input,
            RenderImageError::Bake(e) => e.is_input(),
            RenderImageError::Render(e) => e.is_input(),
        }
    }
}

/// The renderer's settings for `req`: the scene's, its folder, the frame's
/// time, and for a grid image no sky, stars or airglow (module doc). The
/// heightmap and sky image the scene names are checked to be regular files.
pub fn settings_for(req: &ImageRequest<'_>) -> Result<RenderSettings, RenderError> {
    let mut settings = RenderSettings::from_scene(req.scene);
    settings.base_dir = Some(req.dir.clone());
    if let Some(f) = req.frame {
        settings.time_s = crate::pipeline::motion::frame_time(&req.scene.animation, f);
    }
    if req.grid.is_some() {
        settings.background.radiance = [0.0; 3];
        settings.background.image = None;
        settings.background.stars = false;
        settings.airglow.on = false;
    }
    settings.check_input_files()?;
    Ok(settings)
}

/// The image of `req` (module doc).
pub fn render(req: &ImageRequest<'_>, progress: &dyn Progress) -> Result<Rendered, RenderImageError> {
    let settings = settings_for(req)?;
    let (prepared, open_seconds, build_seconds, warnings) = match req.grid {
        Some(name) => prepare_grid(req.scene, &settings, req.vdb, name, progress)?,
        None => prepare(req.scene, &settings, req.vdb, progress)?,
    };
    let image = if req.adaptive {
        crate::render::adaptive::render_adaptive_prepared(&prepared, build_seconds, progress)?
    } else {
        let mut img = crate::render::render_prepared(&prepared, progress)?;
        img.stats.build_seconds = build_seconds;
        img
    };
    Ok(Rendered { image, open_seconds, warnings })
}

/// The renderer prepared, the seconds spent opening and building, the bake's warnings.
type PreparedSource = (Prepared, f64, f64, Vec<String>);

fn vdb_error(message: String, input: bool) -> RenderImageError {
    RenderImageError::Vdb { message, input }
}

/// The renderer prepared from the image's source (module doc).
pub fn prepare(
    scene: &Scene,
    settings: &RenderSettings,
    vdb: Option<&Path>,
    progress: &dyn Progress,
) -> Result<PreparedSource, RenderImageError> {
    // The motion blur reads the velocity grid `v` beside the medium: from grids.
    let blur = scene.render.shutter_s > 0.0;
    if let (Some(path), false) = (vdb, blur) {
        let (p, open, build) = crate::app::vdb_for_render::prepare_from_vdb(settings, path, &scene.colour)
            .map_err(|e| vdb_error(e.to_string(), e.is_input()))?;
        return Ok((p, open, build, Vec::new()));
    }
    let no_velocity = |source: String| RenderImageError::NoVelocity { shutter_s: scene.render.shutter_s, what: source };
    let mut velocity = None;
    let mut warnings = Vec::new();
    let open = std::time::Instant::now();
    let (density, emission) = match vdb {
        Some(path) => {
            let file = read_vdb_for_render(path).map_err(|e| vdb_error(e.to_string(), e.is_input()))?;
            if blur {
                let v = file.vec3_grids.iter().find(|g| g.name == crate::pipeline::bake::velocity::GRID_NAME).cloned();
                velocity = Some(v.ok_or_else(|| no_velocity(path.display().to_string()))?);
            }
            crate::app::vdb_for_render::render_grids_as(file, &scene.colour)
                .map_err(|e| vdb_error(format!("{}: {e}", path.display()), true))?
        }
        None => {
            if blur && !scene.grid.velocity {
                return Err(no_velocity("the bake".to_string()));
            }
            let bake = crate::pipeline::bake::bake(scene, progress)?;
            warnings = bake.stats.warnings.clone();
            velocity = bake.velocity;
            (Some(bake.density), Some(bake.emission))
        }
    };
    let open_seconds = open.elapsed().as_secs_f64();
    let build = std::time::Instant::now();
    let volume = Volume { density: density.as_ref(), emission: emission.as_ref() };
    let mut prepared = Prepared::new(settings, &volume)?;
    if let Some(v) = velocity {
        prepared = prepared.with_velocity(v)?;
    }
    Ok((prepared, open_seconds, build.elapsed().as_secs_f64(), warnings))
}

/// The renderer prepared for one float grid `name` as a grey emission,
/// with the `density` grid, from the VDB or from a bake of the scene (its
/// `grid.lines`); a missing grid names the float grids there are.
pub fn prepare_grid(
    scene: &Scene,
    settings: &RenderSettings,
    vdb: Option<&Path>,
    name: &str,
    progress: &dyn Progress,
) -> Result<PreparedSource, RenderImageError> {
    let open = std::time::Instant::now();
    let mut warnings = Vec::new();
    let (density, floats, source) = match vdb {
        Some(path) => {
            let file = read_vdb_for_render(path).map_err(|e| vdb_error(e.to_string(), e.is_input()))?;
            let density = file.float("density").cloned();
            (density, file.float_grids, path.display().to_string())
        }
        None => {
            let bake = crate::pipeline::bake::bake(scene, progress)?;
            warnings = bake.stats.warnings.clone();
            (Some(bake.density), bake.lines, "the bake (grid.lines)".to_string())
        }
    };
    let Some(g) = floats.iter().find(|g| g.name == name) else {
        let there: Vec<&str> = floats.iter().map(|g| g.name.as_str()).filter(|n| *n != "density").collect();
        let there = if there.is_empty() { "none".to_string() } else { there.join(", ") };
        return Err(RenderImageError::NoGrid { name: name.to_string(), what: source, there });
    };
    let emission = crate::render::grids::grey(g);
    // A line's own grid sees the air at that line's optical depth.
    let mut settings = settings.clone();
    settings.line = name.strip_prefix("line_").and_then(crate::physics::emission::line_table::line_index);
    let open_seconds = open.elapsed().as_secs_f64();
    let build = std::time::Instant::now();
    let volume = Volume { density: density.as_ref(), emission: Some(&emission) };
    Ok((Prepared::new(&settings, &volume)?, open_seconds, build.elapsed().as_secs_f64(), warnings))
}

/// What a grid image holds (module doc): a `line_*` grid (rayleigh per km)
/// integrated along the ray is the line's column brightness in rayleigh;
/// any other grid its units times km. The air's extinction is in it when
/// `[sky] extinction` is on.
pub fn grey_metadata(scene: &Scene, name: &str) -> GreyMetadata {
    let mut units = if name.starts_with("line_") {
        format!(
            "R (rayleigh): the {name} grid (R/km) integrated along each ray, the line's column brightness 4 pi I / 1e6, \
I in photons cm^-2 s^-1 sr^-1"
        )
    } else {
        format!("the {name} grid's units times km: the grid integrated along each ray")
    };
    if scene.volume.emission_scale != 1.0 {
        units.push_str(&format!(", times volume.emission_scale = {}", scene.volume.emission_scale));
    }
    let air = if scene.sky.extinction {
        "applied: sky.extinction = true, the line's own optical depth along each ray (the brightness seen below the air)"
    } else {
        "not applied: sky.extinction = false (the brightness above the air)"
    };
    GreyMetadata { units, air: air.to_string() }
}
