//! `[animation]`: closed-form motion in time and the red trail, with its
//! defaults.
//! [`ANIMATION_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
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

/// Every key of `[animation]`: name, unit, allowed range and description (`super::keys`).
pub const ANIMATION_KEYS: &[KeySpec] = &[
    KeySpec::new("fps", "1/s", Range::Num(Num::open_min(0.0, 1000.0)), "frames per second of a sequence (USD `timeCodesPerSecond`, Blender's scene fps); dome masters are delivered at 30 or 60 (the fulldome Dome Master Show File Format; `--plan` notes another rate)"),
    KeySpec::new("time_s", "s", Range::Num(Num::closed(0.0, 1e7)), "time of the bake; frame N of `--frames` is baked at `time_s + (N - 1) / fps`"),
    KeySpec::new("fold_speed_kms", "km/s", Range::Num(Num::closed(-100.0, 100.0)), "phase speed of the folds along the curtain (spirals drift about 4 km/s, surges about 2 km/s); the footprint's three vortex modes travel at 1, -0.5 and 1.6 times it"),
    KeySpec::new("fold_breathing", "", Range::Num(Num::open_max(0.0, 1.0)), "relative swing of the fold-driving velocity (folds deepen and relax)"),
    KeySpec::new("fold_breathing_period_s", "s", Range::Num(Num::open_min(0.0, 1e6)), "period of that swing"),
    KeySpec::new("bend_speed_kms", "km/s", Range::Num(Num::closed(-100.0, 100.0)), "speed at which the bend curve travels along the curtain"),
    KeySpec::new("bend_change_hz", "1/s", Range::Num(Num::closed(0.0, 100.0)), "rate at which the bend curve changes shape"),
    KeySpec::new("drift_km", "km", Range::Num(Num::closed(0.0, 1e3)), "amplitude of the curtain's drift across its axis, `drift_km sin(2 pi t / drift_period_s)`: bounded, so it never leaves the view"),
    KeySpec::new("drift_period_s", "s", Range::Num(Num::open_min(0.0, 1e6)), "period of the drift"),
    KeySpec::new("ray_speed_kms", "km/s", Range::Num(Num::closed(-100.0, 100.0)), "speed of the rays (the start-height and colour noise) along the curtain (up to about 25 km/s observed)"),
    KeySpec::new("pulsation", "", Range::Num(Num::closed(0.0, 1.0)), "depth of pulsating patches (0 = off): each patch's electron flux swings between `1 - pulsation` and 1 times its value"),
    KeySpec::new("pulsation_patch_km", "km", Range::Num(Num::open_min(0.0, 1e4)), "size of a pulsating patch"),
    KeySpec::new("pulsation_period_s", "s", Range::Span { min: 0.0, max: 1e4 }, "range each patch's period is drawn from (observed: a few s to 20 s, mostly 6-10 s)"),
    KeySpec::new("trail_samples", "", Range::Int { min: 0, max: MAX_TRAIL_SAMPLES as i64 }, "the red trail: earlier times of the motion the O(1D) lines (630.0, 636.4 nm) sum, weighted by O(1D)'s decay at each deposit's altitude, so moving curtains leave red behind (0 = off; each sample traces the beams once more)"),
];
