//! Volumetric photon mapping: from the beams' photons to an emission grid by
//! kernel density estimation.
//!
//! The volume emission rate at x is the density estimate
//!
//! ```text
//! eta(x) = sum_i Phi_i K_r(|x - x_i|)      [photons km^-3 s^-1, per colour]
//! ```
//!
//! with `K_r` the normalised 3D Gaussian of standard deviation r (the kernel
//! radius), truncated at `cutoff * r` and renormalised by the Gaussian mass
//! inside the cutoff, so it still integrates to 1: twice the photons give
//! twice the emission. (The 2014 report divided by the sum of the weights, an
//! average colour that throws the photon density away; `report2014` keeps it
//! for comparison only.) Radiance is `eta / (4 pi)` per steradian; a Rayleigh
//! is a column emission rate, `1 R = 1e6 photons cm^-2 s^-1` = 4 pi times
//! radiance, so the 4 pi cancels and `eta / 1e19` is in kR per km of path
//! (1 kR = 1e9 photons cm^-2 s^-1 = 1e19 photons km^-2 s^-1). That is the
//! unit of the `emission` grid: Y = 1 is 1 kR of 557.7 nm per km.
//!
//! A beam step deposits its power along its segment (`photons.kernel =
//! "segment"`, default: the Gaussian convolved with the segment, a short
//! photon beam after Jarosz et al. 2011) or at its end (`"point"`, kept for
//! comparison); [`kernel`] derives both kernels and their masses. The
//! kernel radius r varies with position ([`radius`]).
//!
//! Gather methods (`photons.gather`):
//! - `kdtree`: a balloon estimator, radius r(x) at the voxel: one range
//!   query per 8^3 leaf in a kd-tree of the photons ([`kdtree`]).
//! - `splat` (default): a sample-point estimator, radius r(x_i) at the
//!   photon: photons binned per leaf ([`bins`]), each adding its kernel to
//!   the leaf's voxels within its cutoff ([`splat`]). No tree.
//! - `report2014`: the report's kernel-weighted *average* of binned photons
//!   ([`report2014`]). Not a density; for comparison only.
//!
//! The kd-tree and the splat take the same field to the f64 form (tests);
//! the splat needs no tree and gathered the default scene's segments in
//! about two thirds of the kd-tree's CPU time (`examples/smoothness.rs
//! --gather`), so it is the default. Before either, straight and evenly
//! lit runs of a beam's steps become one segment each ([`merge`]).
//!
//! Its parts:
//! - [`kernel`]: the truncated Gaussian, the segment kernel, their masses
//!   and the f64 estimate (every gather's oracle);
//! - [`fast_math`]: the f32 `exp`, `erf` and integer `ceil` / `floor` of
//!   the inner loops, with their error bounds;
//! - [`radius`]: the kernel radius field;
//! - [`bins`]: the leaves a photon reaches, and each leaf's photons;
//! - [`leaf`]: one leaf's sums and the point kernel's vectorised rows,
//!   shared by the three leaf gathers;
//! - [`splat`]: the splat's leaf (segment rows, AVX2 where the CPU has it);
//! - [`kdtree`]: the kd-tree and the balloon's leaf;
//! - [`report2014`]: the report's average;
//! - [`merge`]: merging a beam's steps into runs;
//! - the drivers, the public entry points: [`gather_grid`],
//!   [`GatherInput`] and [`gather_prepared`].
//!
//! Every per-voxel sum runs over photons in ascending index order, so the
//! grids are identical whatever the thread count.

pub mod bins;
pub mod fast_math;
mod gather;
pub mod kdtree;
pub mod kernel;
pub mod leaf;
pub mod merge;
pub mod radius;
pub mod splat;
#[cfg(test)]
mod test_fixtures;
pub mod weighted_average;

pub use gather::{gather_grid, gather_prepared, GatherInput};

use crate::pipeline::deposit::Photon;
use glam::DVec3;

/// Photons km^-2 s^-1 in one kR.
pub const PHOTONS_PER_KM2_S_PER_KR: f64 = 1e19;

/// A photon's position (its segment's start), f64.
#[inline]
fn pos(p: &Photon) -> DVec3 {
    DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64)
}

/// A photon's segment end (its position for a point photon), f64.
#[inline]
fn end(p: &Photon) -> DVec3 {
    DVec3::new(p.end[0] as f64, p.end[1] as f64, p.end[2] as f64)
}
