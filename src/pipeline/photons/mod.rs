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
//! radius, [`radius`]), truncated at `cutoff * r` and renormalised by its
//! mass inside, so it still integrates to 1: twice the photons give twice
//! the emission. A beam step deposits its power along its segment
//! (`photons.kernel = "segment"`, default: the Gaussian convolved with the
//! segment, a photon beam after Jarosz et al., ACM TOG 30(1), 2011) or at
//! its end (`"point"`); [`kernel`] derives both and their masses. A Rayleigh
//! is a column emission rate, `1 R = 1e6 photons cm^-2 s^-1`, so `eta / 1e19`
//! is in kR per km of path ([`leaf::PHOTONS_PER_KM2_S_PER_KR`]): the unit of
//! the `emission` grid, Y = 1 being 1 kR of 557.7 nm per km.
//!
//! Gather methods (`photons.gather`), each over the merged runs of a beam's
//! straight, evenly lit steps ([`merge`]):
//! - `splat` (default): a sample-point estimator, r at the photon: photons
//!   binned per leaf ([`bins`]), each adding its kernel to the leaf's voxels
//!   within its cutoff ([`splat`]; AVX2 where the CPU has it). No tree.
//! - `kdtree`: a balloon estimator, r at the voxel: one range query per 8^3
//!   leaf in a kd-tree of the photons ([`kdtree`]).
//! - `report2014`: the 2014 report's kernel-weighted *average* of binned
//!   photons ([`weighted_average`]); not a density, for comparison only.
//!
//! [`leaf`] holds one leaf's sums and the point kernel's vectorised rows,
//! shared by the three; [`fast_math`] the f32 `exp`, `erf`, `ceil` and
//! `floor` of the inner loops with their error bounds; the drivers
//! ([`gather_grid`], [`GatherInput`], [`gather_prepared`]) are `gather`'s.
//! The kd-tree and the splat agree with the f64 estimate of [`kernel`]
//! (tests). Every per-voxel sum runs over photons in ascending index order,
//! so the grids are identical whatever the thread count. [`sums`] gathers
//! the photons a chunk at a time, carrying each leaf's sums from chunk to
//! chunk: the same terms in the same order, so the same grid as one gather
//! of all the photons, bit for bit.

pub mod bins;
pub mod fast_math;
mod gather;
pub mod kdtree;
pub mod kernel;
pub mod leaf;
pub mod merge;
pub mod radius;
pub mod splat;
pub mod sums;
#[cfg(test)]
mod test_fixtures;
pub mod weighted_average;

pub use gather::{gather_grid, gather_prepared, GatherInput};
pub use sums::GatherSums;
