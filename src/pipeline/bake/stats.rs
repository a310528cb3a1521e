//! What a bake reports (bake.json): the stage times, the counts, powers and
//! bounds of the grids, the pilot's estimate and the warnings.

use crate::pipeline::beams::BeamStats;
use crate::pipeline::prune::PruneStats;
use crate::scene::GatherMethod;
use serde::Serialize;

/// Wall time of each stage, seconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    pub footprints: f64,
    pub pilot: f64,
    pub beams: f64,
    pub gather: f64,
    pub prune: f64,
    pub density: f64,
    pub total: f64,
}

/// Numbers describing a bake (written as bake.json).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BakeStats {
    pub units: &'static str,
    pub seed: u64,
    /// FNV-1a hash of the scene's canonical TOML, hex.
    pub scene_hash: String,
    pub voxel_size_km: f64,
    /// "scene" or "auto (photons.radius_km)".
    pub voxel_size_source: String,
    pub gather: GatherMethod,
    pub beams: usize,
    pub photons: usize,
    /// Voxels (and leaves) holding aurora: non-zero emission.
    pub active_voxels: u64,
    pub leaves: usize,
    /// Active zero voxels of the `grid.cycles_shell` (0 without it).
    pub shell_voxels: u64,
    /// Active voxels and leaves per grid in the file: the aurora's plus the shell.
    pub file_voxels: u64,
    pub file_leaves: usize,
    /// Inclusive index bounding box of the file's active voxels (shell
    /// included), [min, max].
    pub index_bbox: Option<[[i32; 3]; 2]>,
    /// World bounding box of the active voxel centres, km, [min, max].
    pub world_bbox: Option<[[f64; 3]; 2]>,
    /// Largest emission per component, and the largest luminance, kR/km.
    pub peak_emission: [f32; 3],
    pub peak_luminance: f64,
    /// Sum of the photons' power, 557.7-equivalent photons per second, RGB.
    pub total_emitted_power: [f64; 3],
    /// The same as luminance, in 557.7 nm photons per second.
    pub total_emitted_luminance: f64,
    /// Electron power into the atmosphere, W, and how much the beams
    /// deposited before stopping.
    pub electron_power_w: f64,
    pub deposited_power_w: f64,
    /// The deposit over the power the beams carried into the atmosphere
    /// (electron power less backscatter when nothing pulses); under 0.95 the bake warns
    /// ([`crate::pipeline::beams::loss_warnings`]; per curtain in `beam_stats`).
    pub deposited_fraction: f64,
    pub beam_stats: BeamStats,
    pub times_s: StageTimes,
    /// How `beams.target_noise` set the beam count (None when it is 0).
    pub noise: Option<NoiseEstimate>,
    /// What `grid.prune` removed (None when it is 0).
    pub prune: Option<PruneStats>,
    /// Under-resolution warnings ([`crate::pipeline::voxel::resolution_warnings`]); empty when the
    /// grid resolves the kernel and every curtain.
    pub warnings: Vec<String>,
}

impl BakeStats {
    /// Wall time of the whole bake, seconds.
    pub fn total_seconds(&self) -> f64 {
        self.times_s.total
    }
}

/// What the pilot measured and chose ([`super::pilot`]; kept here so the
/// stats do not depend on the pilot's module).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseEstimate {
    /// `beams.target_noise`.
    pub target: f64,
    /// Beams per pilot half, `m`.
    pub pilot_beams: usize,
    /// Relative RMS noise of an `m`-beam grid, measured.
    pub pilot_noise: f64,
    /// Relative RMS noise of an `m / 4`-beam grid, measured.
    pub quarter_noise: f64,
    /// The fitted law `noise(N)^2 = law_a / N + law_b / N^(3/2)`.
    pub law_a: f64,
    pub law_b: f64,
    /// The N of the fitted law at the target (`m (pilot_noise / target)^2`
    /// when law_b = 0).
    pub beams_needed: f64,
    /// The count used: `beams_needed` rounded up, at most `beams.count`.
    pub beams: usize,
    /// The noise expected at `beams` by the fitted law.
    pub expected_noise: f64,
    /// `beams.count` capped the count.
    pub capped: bool,
    pub seconds: f64,
}
