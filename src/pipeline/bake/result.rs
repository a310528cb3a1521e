//! What a bake returns: the grids and photons with their stats ([`Bake`]),
//! or why it failed ([`BakeError`], and [`empty_reason`] for a bake that
//! deposited no light).

use super::stats::BakeStats;
use crate::grid::Grid;
use crate::pipeline::beams::{BeamError, BeamStats};
use crate::pipeline::deposit::Photon;
use crate::pipeline::memory::refusal::TooLarge;

/// The baked volumes and what produced them.
#[derive(Clone, Debug)]
pub struct Bake {
    /// Linear Rec.709 emission, kR per km (Y = 1: 1 kR of 557.7 nm per km).
    pub emission: Grid<[f32; 3]>,
    /// Extinction per km, on the emission's active voxels.
    pub density: Grid<f32>,
    /// The per-line grids of `grid.lines`, rayleigh per km
    /// (`crate::physics::emission::line_table`), unpruned; empty by default.
    pub lines: Vec<Grid<f32>>,
    /// With `grid.velocity`, the emission pattern's velocity `v`, km/s, on
    /// the emission's active voxels (`super::velocity`).
    pub velocity: Option<Grid<[f32; 3]>>,
    pub photons: Vec<Photon>,
    pub stats: BakeStats,
}

/// A bake failure.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Beams(#[from] BeamError),
    /// The emission overflowed single precision (never written: a safety
    /// net behind the scene's validation ranges).
    #[error("the emission at voxel ({}, {}, {}) is {value}, beyond single precision: the power per photon (curtain energy_flux and area over beams.count) is too high for photons.radius_km = {radius_km}; use more beams or a larger radius", ijk[0], ijk[1], ijk[2])]
    NonFinite { ijk: [i32; 3], value: String, radius_km: f64 },
    /// The bake would need more memory than this process may use
    /// (`crate::pipeline::memory`): refused after the plan is built and
    /// before any beam is traced. Boxed: its strings and suggestions would
    /// otherwise set the size of every `Result<_, BakeError>`.
    #[error(transparent)]
    Memory(#[from] Box<TooLarge>),
    /// The bake produced no emission at all: an empty VDB is never written
    /// silently. The message says where the beams' energy went.
    #[error("the bake deposited no light: {0}")]
    Empty(String),
    /// The scene's camera is out of range (never with a validated scene).
    #[error(transparent)]
    Camera(#[from] crate::geometry::camera::CameraError),
}

impl BakeError {
    /// The user's input: every variant comes from the scene's parameters and names the keys to change (exit status 2), except a
    /// bake the caller cancelled.
    pub fn is_input(&self) -> bool {
        match self {
            BakeError::Beams(e) => e.is_input(),
            _ => true,
        }
    }
}

/// Why a bake came out empty, in the user's terms: how its beams ended and
/// which keys to look at.
pub fn empty_reason(stats: &BeamStats, beams: &crate::scene::BeamParams) -> String {
    let mut why = format!(
        "{} beams made {} photons ({} left their footprint, {} spent their energy, {} took the most steps, 1 / beams.dt = {})",
        stats.beams,
        stats.photons,
        stats.ended_left_footprint,
        stats.ended_energy_spent,
        stats.ended_max_steps,
        (1.0 / beams.dt).round()
    );
    if stats.photons == 0 {
        why += &format!(
            "; no beam deposited energy before stopping: check beams.length_km = {} (a first step longer than the atmosphere leaves nothing) and beams.top_km = {}",
            beams.length_km, beams.top_km
        );
    } else {
        why += "; their emission is zero everywhere (curtain energy_flux, or an all-zero colour map)";
    }
    why
}
