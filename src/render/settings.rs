//! What a render is asked for: the grids ([`Volume`]), the scene's picture
//! settings ([`RenderSettings`], with the integration method and the shadow
//! rays per terrain hit), and why a render can fail ([`RenderError`]).

use crate::grid::Grid;
use crate::scene::{AirglowParams, Background, Camera, RenderParams, Scene, SkyParams, Terrain, VolumeParams};
use std::path::{Path, PathBuf};

/// The grids to render. A VDB without a density grid has no extinction; one
/// without emission emits nothing (a float emission grid is converted to grey
/// by the loader).
#[derive(Clone, Copy, Debug, Default)]
pub struct Volume<'a> {
    pub density: Option<&'a Grid<f32>>,
    pub emission: Option<&'a Grid<[f32; 3]>>,
}

/// How rays integrate the volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integration {
    /// Exact optical depth per dual cell, Gauss-Legendre emission with a
    /// bounded error (`segment.rs`).
    Exact,
    /// Fixed steps of this length (scene units), one sample per step, as
    /// Cycles' biased ray marching (`march.rs`), on primary and shadow rays
    /// alike. For comparisons and benchmarks; its error grows with the step.
    FixedStep(f64),
}

/// Everything `render` needs besides the grids.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub camera: Camera,
    pub render: RenderParams,
    pub volume: VolumeParams,
    pub background: Background,
    pub terrain: Terrain,
    /// `earth.radius_km`: the terrain lies on the sphere of this radius
    /// about `(0, 0, -radius)` (`terrain`); 0 is the flat ground.
    pub earth_radius_km: f64,
    /// The air between the volume and the camera (`crate::physics::air_extinction`).
    pub sky: SkyParams,
    /// The airglow behind the volume (`super::airglow`).
    pub airglow: AirglowParams,
    /// The line (index in `crate::physics::emission::line_colour::LINES`) a one-line grid holds
    /// (`aurora render --grid line_*`): the air takes that line's optical
    /// depth in every channel; None: the per-channel depths of the lines' mix.
    pub line: Option<usize>,
    /// Whose colours the emission holds (`[colour] observer`): the air
    /// weighs its channels for that observer.
    pub observer: crate::util::observer::Observer,
    /// Seed of every random stream (with the pixel index).
    pub seed: u64,
    pub integration: Integration,
    /// Folder against which a relative `terrain.heightmap` is resolved (the
    /// scene file's folder); None = the working directory.
    pub base_dir: Option<PathBuf>,
    /// Where and when (`[site]`): the real stars, the Moon (`site_sky.rs`);
    /// none: the statistical star field.
    pub site: Option<crate::scene::SiteParams>,
    /// The scene's time, seconds after `site.utc` (`animation.time_s`).
    pub time_s: f64,
}

impl RenderSettings {
    /// The scene's camera, render, volume, background, sky, airglow and terrain, its seed,
    /// exact integration.
    pub fn from_scene(scene: &Scene) -> RenderSettings {
        RenderSettings {
            camera: scene.camera.clone(),
            render: scene.render.clone(),
            volume: scene.volume.clone(),
            background: scene.background.clone(),
            terrain: scene.terrain.clone(),
            earth_radius_km: scene.earth.radius_km,
            sky: scene.sky.clone(),
            airglow: scene.airglow.clone(),
            line: None,
            observer: scene.colour.observer,
            seed: scene.seed,
            integration: Integration::Exact,
            base_dir: None,
            site: scene.site.clone(),
            time_s: scene.animation.time_s,
        }
    }
    /// The files the render reads, each with its scene key: a
    /// heightfield's `terrain.heightmap` and `background.image`, resolved
    /// against `base_dir`.
    pub fn input_files(&self) -> Vec<(&'static str, PathBuf)> {
        let base = self.base_dir.as_deref();
        let heightmap = self.terrain.heightmap.as_deref().filter(|_| self.terrain.kind == crate::scene::TerrainKind::Heightfield);
        let mut files: Vec<(&'static str, PathBuf)> = heightmap.map(|p| ("terrain.heightmap", input_path(base, p))).into_iter().collect();
        files.extend(self.background.image.as_deref().map(|p| ("background.image", input_path(base, p))));
        files
    }

    /// Checks, without opening them, that [`Self::input_files`] are regular
    /// files (`crate::util::input_file::check`): a missing heightmap or a FIFO
    /// given as the sky is refused before a bake or a medium build, not
    /// after. They are opened, and checked again, when read.
    pub fn check_input_files(&self) -> Result<(), RenderError> {
        for (key, path) in self.input_files() {
            crate::util::input_file::check(&path).map_err(|source| RenderError::Input { key, source })?;
        }
        Ok(())
    }
}

/// A scene's file path (`terrain.heightmap`, `background.image`): relative
/// ones against `base_dir` (the scene file's folder) when given.
pub(crate) fn input_path(base_dir: Option<&Path>, p: &str) -> PathBuf {
    match base_dir {
        Some(d) if Path::new(p).is_relative() => d.join(p),
        _ => PathBuf::from(p),
    }
}

/// Why a render (or an image file) failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A setting is out of range.
    #[error("render settings: {0}")]
    Settings(String),
    /// A grid the renderer cannot sample like Cycles (non-zero background,
    /// negative or non-finite values, bad transform).
    #[error("grid '{grid}': {message}")]
    Grid { grid: String, message: String },
    /// A grid's leaf could not be read (a file's record would not decode).
    #[error("grid '{grid}': {source}")]
    Source { grid: String, source: crate::grid::leaf_source::LeafError },
    /// The grids' leaves would need more memory for the medium than this
    /// process may use ([`crate::util::memory::available`]); refused before the
    /// values are allocated or read.
    #[error("the volume's {leaves} leaves would need about {needed} for the renderer's medium, but this process may use {available}")]
    Memory { leaves: usize, needed: String, available: String },
    /// The terrain heightmap could not be read.
    #[error("heightmap {}: {message}", path.display())]
    Heightmap { path: PathBuf, message: String },
    /// An input file the scene names (`key`) is not a regular file, or
    /// cannot be opened (`crate::util::input_file`).
    #[error("{key} {source}")]
    Input { key: &'static str, source: crate::util::input_file::InputFileError },
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: EXR: {message}", path.display())]
    Exr { path: PathBuf, message: String },
    /// An image file whose declared size does not fit in the file or in
    /// the memory this process may use: refused before its pixels are
    /// allocated (`crate::render::image_file::check_exr_size`).
    #[error("{}: {message}", path.display())]
    ImageSize { path: PathBuf, message: String },
    #[error("{}: PNG: {message}", path.display())]
    Png { path: PathBuf, message: String },
    /// The output is not ours to replace, or could not be staged or renamed.
    #[error(transparent)]
    Output(Box<crate::util::atomic_write::AtomicError>),
}

impl RenderError {
    /// True when the scene, the volume or a file it names, or the choice of output is at fault (exit status 2); false for a failure writing the image.
    pub fn is_input(&self) -> bool {
        use RenderError::*;
        match self {
            Settings(_) | Grid { .. } | Source { .. } | Memory { .. } | ImageSize { .. } | Heightmap { .. } | Input { .. } => true,
            Output(a) => a.is_input(),
            Io { .. } | Exr { .. } | Png { .. } => false,
        }
    }
}

impl From<crate::geometry::camera::CameraError> for RenderError {
    fn from(e: crate::geometry::camera::CameraError) -> Self {
        RenderError::Settings(e.to_string())
    }
}
