//! `[animation]`: closed-form motion in time and the red trail, with its
//! defaults.

use serde::{Deserialize, Serialize};

/// The most earlier times `animation.trail_samples` may ask for.
pub const MAX_TRAIL_SAMPLES: u32 = 16;

/// Motion in time (`crate::pipeline::motion`): closed form in t, so any frame costs
/// one bake. Speeds from the time scales observers report; every motion
/// parameter at 0 gives identical frames.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AnimationParams {
    /// Frames per second of a sequence (`aurora bake --frames`).
    pub fps: f64,
    /// Time of the bake, s; frame N of a sequence is baked at
    /// `time_s + (N - 1) / fps`.
    pub time_s: f64,
    /// Phase speed of the folds (the footprint's vortex row) along the
    /// curtain, km/s (spirals drift about 4 km/s, surges about 2 km/s).
    pub fold_speed_kms: f64,
    /// Relative swing of the fold-driving velocity (folds deepen and relax), in [0, 1).
    pub fold_breathing: f64,
    /// Period of that swing, s.
    pub fold_breathing_period_s: f64,
    /// Speed at which the bend curve travels along the curtain, km/s.
    pub bend_speed_kms: f64,
    /// Rate at which the bend curve changes shape, 1/s (its noise moves one
    /// lattice cell in 1 / rate seconds).
    pub bend_change_hz: f64,
    /// Amplitude of the curtain's drift across its axis, km (bounded: a
    /// sine of period `drift_period_s`, so curtains never leave the view).
    pub drift_km: f64,
    pub drift_period_s: f64,
    /// Speed of the rays (the start-height and colour noise) along the
    /// curtain, km/s (up to about 25 km/s).
    pub ray_speed_kms: f64,
    /// Depth of pulsating patches, in [0, 1] (0 = off): each patch's
    /// electron flux swings between (1 - pulsation) and 1 times its value.
    pub pulsation: f64,
    /// Size of a pulsating patch, km.
    pub pulsation_patch_km: f64,
    /// Range of patch periods, s (most often 6-10 s; a few s to 20 s).
    pub pulsation_period_s: [f64; 2],
    /// The red trail (`crate::pipeline::red_trail`): how many earlier times of the
    /// motion the O(1D) lines (630.0, 636.4 nm) of a bake at `time_s` sum,
    /// each weighted by the decay of O(1D) at the deposit's altitude;
    /// 0 (the default) is off: every line at `time_s`. At most
    /// [`MAX_TRAIL_SAMPLES`]; each costs one more trace of the beams (the
    /// red only).
    pub trail_samples: u32,
}

impl Default for AnimationParams {
    fn default() -> Self {
        Self {
            fps: 24.0,
            time_s: 0.0,
            fold_speed_kms: 3.0,
            fold_breathing: 0.3,
            fold_breathing_period_s: 40.0,
            bend_speed_kms: 1.0,
            bend_change_hz: 1.0 / 60.0,
            drift_km: 8.0,
            drift_period_s: 300.0,
            ray_speed_kms: 10.0,
            pulsation: 0.0,
            pulsation_patch_km: 25.0,
            pulsation_period_s: [6.0, 10.0],
            trail_samples: 0,
        }
    }
}
