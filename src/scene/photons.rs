//! `[photons]`: the photon kernel and the gather, with the defaults.
//! [`PHOTONS_KEYS`]: each key's unit, allowed range and description.

use super::keys::{KeySpec, Num, Range};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum GatherMethod {
    /// Gaussian kernel density estimate with a kiddo kd-tree gather.
    Kdtree,
    /// Each photon splats its kernel into the voxels it covers.
    Splat,
    /// The 2014 report: photons binned in a uniform grid, kernel-weighted
    /// *average* of colours (no density estimate). For comparison only.
    Report2014,
}

/// Volumetric photon mapping: Gaussian kernel density estimation.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct PhotonParams {
    /// Kernel radius r (the Gaussian's standard deviation), km.
    pub radius_km: f64,
    /// The kernel is cut off at this many radii (and renormalised).
    pub cutoff: f64,
    /// Relative amplitude of the medium-frequency 2D noise on the radius.
    pub radius_noise: f64,
    /// Spatial frequency of that noise, cycles per km.
    pub radius_noise_freq: f64,
    pub gather: GatherMethod,
    /// Kernel shape: each step's power spread along its segment, or at its
    /// end point (for comparison).
    pub kernel: KernelShape,
}

impl Default for PhotonParams {
    fn default() -> Self {
        Self {
            radius_km: 0.35,
            cutoff: 2.5,
            radius_noise: 0.25,
            radius_noise_freq: 0.05,
            gather: GatherMethod::Splat,
            kernel: KernelShape::Segment,
        }
    }
}

/// Photon kernel shape (`crate::pipeline::photons`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum KernelShape {
    /// The Gaussian convolved with each step's segment (photon beams; default).
    Segment,
    /// The Gaussian at each step's end point.
    Point,
}

/// Every key of `[photons]`: name, unit, allowed range and description (`super::keys`).
pub const PHOTONS_KEYS: &[KeySpec] = &[
    KeySpec::new("radius_km", "km", Range::Num(Num::POSITIVE), "kernel radius r, the Gaussian's standard deviation"),
    KeySpec::new("cutoff", "r", Range::Num(Num::closed(1.0, 6.0)), "the kernel is cut off at `cutoff` x r and renormalised"),
    KeySpec::new("radius_noise", "", Range::Num(Num::closed(0.0, 0.9)), "relative amplitude of the medium-frequency 2D noise on the radius"),
    KeySpec::new("radius_noise_freq", "1/km", Range::Num(Num::closed(0.0, 1e3)), "spatial frequency of that noise"),
    KeySpec::new("gather", "", Range::Word(&["kdtree", "splat", "report2014"]), "`splat` (each photon adds its kernel to the voxels it covers), `kdtree` (each voxel gathers from a kd-tree: the same field) or `report2014` (the 2014 report's kernel-weighted average of colours, not a density estimate, for comparison)"),
    KeySpec::new("kernel", "", Range::Word(&["segment", "point"]), "`segment` (each beam step's power spread along the step: the Gaussian convolved with the segment) or `point` (at the step's end, for comparison)"),
];
