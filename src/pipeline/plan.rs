//! The bake's plan: one [`BakePlan`] built from a validated scene, holding
//! the scene and what it determines, and the rules the bake and its memory
//! budget must both follow, each written once here.
//!
//! What the plan holds: the scene; one footprint per curtain at the
//! scene's `animation.time_s` (simulated in parallel, seeded by the scene
//! and curtain seeds: `crate::pipeline::footprint`); the neutral atmosphere
//! (`[atmosphere]`), the colour table (`[colour]`), the per-line table
//! when a pulsation, the red trail or `grid.lines` needs one; the uniform
//! magnetic field (`beams.b_inclination_deg`, `b_declination_deg`), the
//! kernel radius and its noise field (`photons.radius_km`, read in one
//! place: [`crate::scene::KernelRadius::of`]); and the chunk of beams the
//! bake traces and gathers at a time.
//!
//! The rules written once:
//! - **chunks** ([`BakePlan::chunks`]): beams `[a, a + C)` for
//!   `C = beam_chunk` ([`BEAM_CHUNK`], a constant, so the working set does
//!   not depend on the memory limit or the thread count), or one chunk of
//!   every beam when `photons.gather = "report2014"` (its weighted
//!   average is a ratio, not a sum);
//! - **the field a beam follows** ([`BakePlan::field_at`], from
//!   [`crate::pipeline::beams::beam_field`], which the trace calls too): the
//!   IGRF-14's at its start with a `[site]` (unless its `field` is
//!   `scene`), else the dipole's on a round Earth with `[earth]
//!   magnetic_pole`, else the uniform field;
//! - **the pilots' sizes** ([`DEPOSIT_PILOT_BEAMS`], [`PILOT_HALF_BEAMS`]).
//!
//! [`BakePlan::reusing`] keeps a previous plan's footprints, atmosphere and
//! colour table where the sections they depend on are unchanged (a frame
//! sequence: only the time changes; the preview: most edits touch
//! neither). The stages that run a plan are `crate::pipeline::bake`'s
//! (trace, gather, finish); the memory budget (`crate::pipeline::memory`)
//! reads the same plan, so estimate and bake cannot drift apart. Nothing
//! here imports either.

use super::voxel::voxel_size_for;
use crate::geometry::camera::{CameraError, CameraModel};
use crate::geometry::earth::Earth;
use crate::physics::atmosphere::Atmosphere;
use crate::physics::emission::line_colour::{ColourTable, EmissionModel};
use crate::physics::emission::line_table::{line_index, LineTable};
use crate::physics::geomagnetic_field::MagneticField;
use crate::physics::site_field::SiteField;
use crate::pipeline::beams::{beam_field, site_field, TraceParams};
use crate::pipeline::deposit::Photon;
use crate::pipeline::footprint::curtain_path::Lift;
use crate::pipeline::footprint::{self, Footprint};
use crate::pipeline::photons::radius::RadiusField;
use crate::pipeline::photons::GatherInput;
use crate::scene::{
    AnimationParams, AtmosphereParams, ColourMode, ColourParams, Curtain, FootprintParams, GatherMethod, GridParams, KernelRadius,
    LineModel, PhotonParams, Scene,
};
use crate::util::progress::{NoProgress, Progress};
use glam::DVec3;
use rayon::prelude::*;
use std::ops::Range;
use std::time::Instant;

/// Beams a bake traces and gathers at a time: a constant, so the bake's
/// working set is the same whatever the memory limit or the thread count.
/// 8192 beams of the 2014 report's 250 steps are 2 M photons, 74 MB a copy.
pub const BEAM_CHUNK: usize = 8192;

/// Beams per curtain of the deposition pilot (at most `beams.count`;
/// `crate::pipeline::bake::pilot::check_deposition`): the deposited
/// fraction's sampling error is at most `sqrt(1/4 / 256)` = 3 %.
pub const DEPOSIT_PILOT_BEAMS: usize = 256;

/// Beams in each half of the noise pilot (`beams.target_noise > 0`;
/// `crate::pipeline::bake::pilot`): a small share of the default scene's
/// tracing and gathering, and enough that the noise estimate itself is
/// within a few percent (the sums run over millions of voxel values).
pub const PILOT_HALF_BEAMS: usize = 500;

/// One footprint per curtain (in curtain order; simulated in parallel), at
/// the scene's `animation.time_s`.
pub fn footprints(scene: &Scene) -> Vec<Footprint> {
    let lift = Lift::of_scene(scene);
    simulate_footprints(scene.seed, &scene.curtains, &scene.footprint, &scene.animation, lift, &NoProgress)
}

/// One footprint per curtain at `animation.time_s`, in parallel; paths
/// lifted by `lift` to the start altitude ([`crate::pipeline::footprint::curtain_path::Lift`]).
pub fn simulate_footprints(
    seed: u64,
    curtains: &[Curtain],
    params: &FootprintParams,
    animation: &AnimationParams,
    lift: Lift,
    progress: &dyn Progress,
) -> Vec<Footprint> {
    progress.start("footprints", curtains.len() as u64);
    let fps = curtains
        .par_iter()
        .map(|c| {
            let f = footprint::simulate_at(c, params, animation, seed, animation.time_s, &lift);
            progress.inc(1);
            f
        })
        .collect();
    progress.finish();
    fps
}

/// The colour table the scene asks for.
pub fn colour_table(scene: &Scene, atmosphere: &Atmosphere) -> ColourTable {
    colour_table_for(&scene.colour, atmosphere)
}

/// The colour table of `[colour]` (its mode and colour map).
pub fn colour_table_for(colour: &ColourParams, atmosphere: &Atmosphere) -> ColourTable {
    match colour.mode {
        ColourMode::Physical => match colour.lines {
            LineModel::Chemistry => ColourTable::chemistry(atmosphere, colour.observer),
            LineModel::Simple => ColourTable::physical(&EmissionModel::new(atmosphere.clone()).with_observer(colour.observer)),
        },
        ColourMode::Colormap => ColourTable::colormap(&colour.colormap),
    }
}

/// The scene's neutral atmosphere (`[atmosphere] model`).
pub fn atmosphere(scene: &Scene) -> Atmosphere {
    atmosphere_for(&scene.atmosphere)
}

/// The neutral atmosphere of `[atmosphere]`.
pub fn atmosphere_for(params: &AtmosphereParams) -> Atmosphere {
    // A table from the data folder was read when the scene was checked
    // (`Atmosphere::of_params`, kept for the process): this cannot fail then.
    Atmosphere::of_params(params).unwrap_or_else(|e| panic!("{e}"))
}

/// The kernel radius field at base radius `kernel.base_km` (noise from
/// `photons.radius_noise_freq`, along the field `b` from the beams' top
/// `top_km`, seeded by the scene seed).
pub fn radius_field(kernel: KernelRadius, p: &PhotonParams, b: DVec3, top_km: f64, seed: u64) -> RadiusField {
    RadiusField::new(kernel.base_km, kernel.noise, p.radius_noise_freq, b, top_km, &[seed])
}

/// Everything the stages need, built once from a scene: the scene and what
/// it determines (footprints, atmosphere, colour table, field, kernel
/// radius field).
#[derive(Clone, Debug)]
pub struct BakePlan {
    /// The validated scene the plan was built from.
    pub scene: Scene,
    /// FNV-1a hash of the scene's canonical TOML, hex.
    pub scene_hash: String,
    /// One per curtain, at `animation.time_s`.
    pub footprints: Vec<Footprint>,
    /// Seconds the footprints took (0 when reused).
    pub footprint_seconds: f64,
    pub atmosphere: Atmosphere,
    pub colour_table: ColourTable,
    /// The uniform field (`beams.b_inclination_deg`, `b_declination_deg`).
    pub field: MagneticField,
    /// IGRF over the site, when `[site] field = "igrf"`
    /// (`crate::pipeline::beams::site_field`).
    pub site_field: Option<SiteField>,
    pub kernel: KernelRadius,
    pub radius: RadiusField,
    /// The lines one at a time ([`line_table_for`]): with a physical colour
    /// and a pulsation or `grid.lines`; `None` otherwise (the default bake
    /// builds none).
    pub line_table: Option<LineTable>,
    /// `grid.lines` as indices in `crate::physics::emission::line_colour::LINES`.
    pub line_outputs: Vec<usize>,
    /// Beams traced and gathered at a time ([`BEAM_CHUNK`]; [`BakePlan::chunks`]).
    /// The output does not depend on it; a test sets it smaller, and the
    /// preview, which keeps every photon, sets it to every beam.
    pub beam_chunk: usize,
}

/// The per-line table a scene needs: with `colour.mode = "physical"`, when
/// something pulses (each line then follows its lifetime), the red trail is
/// on (`animation.trail_samples`) or `grid.lines` asks for per-line grids;
/// `None` otherwise.
pub fn line_table_for(colour: &ColourParams, animation: &AnimationParams, grid: &GridParams, atmosphere: &Atmosphere) -> Option<LineTable> {
    needs_line_table(colour, animation, grid)
        .then(|| LineTable::new(&EmissionModel::new(atmosphere.clone()).with_observer(colour.observer)))
}

/// Whether [`line_table_for`] builds a table.
pub fn needs_line_table(colour: &ColourParams, animation: &AnimationParams, grid: &GridParams) -> bool {
    colour.mode == ColourMode::Physical && (animation.pulsation > 0.0 || animation.trail_samples > 0 || !grid.lines.is_empty())
}

/// `grid.lines` as indices in `crate::physics::emission::line_colour::LINES` (the scene has
/// checked the names).
pub fn line_outputs(grid: &GridParams) -> Vec<usize> {
    grid.lines.iter().filter_map(|k| line_index(k)).collect()
}

impl BakePlan {
    /// The plan of a validated scene (simulates the footprints).
    pub fn new(scene: &Scene, progress: &dyn Progress) -> BakePlan {
        Self::build(scene, None, progress)
    }

    /// The plan of `scene`, reusing `prev`'s footprints when the seed,
    /// curtains, `[footprint]`, `[animation]` and `[earth]` are unchanged,
    /// and its atmosphere and colour table when `[atmosphere]` and the
    /// colour mode, lines and map are unchanged.
    pub fn reusing(scene: &Scene, prev: &BakePlan, progress: &dyn Progress) -> BakePlan {
        Self::build(scene, Some(prev), progress)
    }

    /// Whether this plan's footprints are `scene`'s: the same seed,
    /// curtains, `[footprint]`, `[animation]` and Earth.
    pub fn has_footprints_of(&self, scene: &Scene) -> bool {
        let s = &self.scene;
        s.seed == scene.seed
            && s.curtains == scene.curtains
            && s.footprint == scene.footprint
            && s.animation == scene.animation
            && s.earth == scene.earth
    }

    fn build(scene: &Scene, prev: Option<&BakePlan>, progress: &dyn Progress) -> BakePlan {
        let t = Instant::now();
        let same_fp = prev.filter(|p| p.has_footprints_of(scene));
        let (footprints, footprint_seconds) = match same_fp {
            Some(p) => (p.footprints.clone(), 0.0),
            None => {
                let f =
                    simulate_footprints(scene.seed, &scene.curtains, &scene.footprint, &scene.animation, Lift::of_scene(scene), progress);
                (f, t.elapsed().as_secs_f64())
            }
        };
        let same_colour = prev.filter(|p| {
            let c = &p.scene.colour;
            p.scene.atmosphere == scene.atmosphere
                && c.mode == scene.colour.mode
                && c.lines == scene.colour.lines
                && c.colormap == scene.colour.colormap
        });
        let (atmosphere, colour_table) = match same_colour {
            Some(p) => (p.atmosphere.clone(), p.colour_table.clone()),
            None => {
                let a = atmosphere_for(&scene.atmosphere);
                let c = colour_table_for(&scene.colour, &a);
                (a, c)
            }
        };
        // Same atmosphere and colour mode: the same table, if any was built.
        let line_table = match same_colour.and_then(|p| p.line_table.as_ref()) {
            Some(t) if needs_line_table(&scene.colour, &scene.animation, &scene.grid) => Some(t.clone()),
            _ => line_table_for(&scene.colour, &scene.animation, &scene.grid, &atmosphere),
        };
        let field = MagneticField::new(scene.beams.b_inclination_deg, scene.beams.b_declination_deg);
        let kernel = KernelRadius::of(&scene.photons);
        let radius = radius_field(kernel, &scene.photons, field.b, scene.beams.top_km, scene.seed);
        BakePlan {
            scene: scene.clone(),
            scene_hash: format!("{:016x}", scene.hash()),
            footprints,
            footprint_seconds,
            atmosphere,
            colour_table,
            field,
            site_field: site_field(scene),
            kernel,
            radius,
            line_table,
            line_outputs: line_outputs(&scene.grid),
            beam_chunk: BEAM_CHUNK,
        }
    }

    /// The round or flat Earth of `[earth]`.
    pub fn earth(&self) -> Earth {
        Earth::new(self.scene.earth.radius_km)
    }

    /// The field a beam starting at ground point `at`, at the beams' top
    /// (`beams.top_km`), follows ([`crate::pipeline::beams::beam_field`]).
    pub fn field_at(&self, at: [f64; 2]) -> MagneticField {
        let p = DVec3::new(at[0], at[1], self.scene.beams.top_km);
        beam_field(&self.earth(), self.scene.earth.magnetic_pole, self.site_field.as_ref(), self.field, p)
    }

    /// The tracing parameters, borrowed from the plan.
    pub fn trace_params(&self) -> TraceParams<'_> {
        let s = &self.scene;
        TraceParams {
            seed: s.seed,
            curtains: &s.curtains,
            beams: &s.beams,
            threshold: s.footprint.threshold,
            animation: &s.animation,
            colour_noise_km: s.colour.noise_km,
            colour_noise_freq: s.colour.noise_freq,
            kernel: s.photons.kernel,
            lines: self.line_table.as_ref(),
            line_outputs: if self.line_table.is_some() { &self.line_outputs } else { &[] },
            trail: None,
            earth: self.earth(),
            magnetic_pole: s.earth.magnetic_pole,
            site_field: self.site_field.as_ref(),
            footprints: &self.footprints,
            atmosphere: &self.atmosphere,
            colour: &self.colour_table,
        }
    }

    /// The chunks of beams `0..count` the bake traces and gathers one at a
    /// time (module documentation): one of every beam for `report2014`, else
    /// at most `beam_chunk` beams each. No chunk is empty; no beams, no chunk.
    pub fn chunks(&self, count: usize) -> Vec<Range<usize>> {
        let chunk = if self.scene.photons.gather == GatherMethod::Report2014 { count.max(1) } else { self.beam_chunk.max(1) };
        (0..count).step_by(chunk).map(|a| a..(a + chunk).min(count)).collect()
    }

    /// Whether a bake of `count` beams holds one chunk at a time, not every
    /// beam's photons ([`BakePlan::chunks`]).
    pub fn is_chunked(&self, count: usize) -> bool {
        self.chunks(count).len() > 1
    }

    /// The scene's camera model.
    pub fn camera_model(&self) -> Result<CameraModel, CameraError> {
        CameraModel::new(&self.scene.camera, self.scene.render.width, self.scene.render.height)
    }

    /// `photons` made ready for a gather with the plan's radius field,
    /// cutoff and gather method (merged runs, splat kernels): the bake's
    /// gathers, the preview's and the expected peak's sample all take them
    /// from here.
    pub fn gather_input(&self, photons: &[Photon]) -> GatherInput {
        let p = &self.scene.photons;
        GatherInput::new(photons, &self.radius, p.cutoff, p.gather)
    }

    /// The voxel size in km and where it came from ([`voxel_size_for`]).
    pub fn voxel_size(&self, photons: &[Photon]) -> (f64, String) {
        let cam = self.camera_model();
        voxel_size_for(self.scene.grid.voxel_size, self.kernel, cam.as_ref().ok(), photons)
    }
}
