//! One leaf (8^3 voxels) of a gather: what every leaf gather shares. The
//! three leaf gathers ([`super::splat`], the balloon of [`super::kdtree`],
//! [`super::weighted_average`]) each add their photons' kernels to a leaf's
//! per-voxel sums (`LeafSums`) and turn the sums into a grid leaf
//! (`LeafSums::finish`); [`LeafGather`] holds what they read.
//!
//! Voxel n of the leaf at `origin` is `origin + (x, y, z)` with `n = 64 x +
//! 8 y + z` (`crate::grid::leaf_offset`, OpenVDB's `LeafNode::coordToOffset`),
//! so a z-row of 8 voxels is contiguous: the inner loops run over whole
//! z-rows, or half rows of 4, at fixed length and without branches (a voxel
//! out of reach is given a weight of exactly 0, and adding 0 changes no
//! sum), which the compiler vectorises. The point kernel's row loop
//! (`LeafGather::accumulate`) reads each voxel's kernel from
//! `LeafKernels`, structure of arrays, so the balloon (r at the voxel)
//! and the splat (the photon's r, copied into the rows it reaches) share
//! it.
//!
//! Distances and offsets are taken in f64 then rounded to f32; the kernel
//! values and the sums are f32 (error bounds at `LeafSums` and at each
//! gather's tests).

use super::fast_math::{ceil_i, exp_neg_f32, floor_i};
use super::kernel::{KernelF32, SegmentMass};
use super::radius::RadiusField;
use crate::grid::{Leaf, Transform, LEAF_DIM, LEAF_NUM_VALUES};
use crate::pipeline::deposit::{pos, Photon};
use glam::{DVec3, IVec3};

/// Photons km^-2 s^-1 in one kR: [`LeafSums::finish`] scales the sums
/// (photons km^-3 s^-1) by its inverse to the emission grid's kR per km.
pub const PHOTONS_PER_KM2_S_PER_KR: f64 = 1e19;

/// One gather's fixed inputs, borrowed for the evaluation of its leaves:
/// the photons, the grid's transform, the kernel radius, cutoff and masses,
/// and for the splat each photon's own kernel.
pub struct LeafGather<'a> {
    pub photons: &'a [Photon],
    pub transform: Transform,
    pub radius: &'a RadiusField,
    pub cutoff: f64,
    /// gaussian_mass_inside(cutoff)
    pub mass: f64,
    /// Segment kernel masses for `cutoff`.
    pub seg: SegmentMass,
    /// The splat's kernel of each photon (r at the point or the segment's
    /// midpoint), computed once per photon rather than once per leaf it
    /// touches (the radius noise is a Perlin lookup); empty for the other
    /// gathers.
    pub splat_kernels: &'a [KernelF32],
}

/// Per-voxel sums of one leaf, one array per colour. f32: the sums are of
/// positive terms in a fixed order, so n terms are good to n 2^-24 relative
/// at worst (about sqrt(n) 2^-24 in practice, 1e-5 for 10^4 terms), far
/// below the estimate's Monte Carlo noise; f64 made the gather 30 % slower.
pub(super) struct LeafSums {
    pub(super) c: [[f32; LEAF_NUM_VALUES]; 3],
}

/// The point kernel's f32 constants at each voxel of one leaf, structure of
/// arrays (the row loop reads them four lanes at a time).
pub(super) struct LeafKernels {
    /// 1 / ((2 pi)^(3/2) r^3 M(c)), km^-3.
    pub(super) norm: [f32; LEAF_NUM_VALUES],
    /// 1 / (2 r^2).
    pub(super) inv_2r2: [f32; LEAF_NUM_VALUES],
    /// (c r)^2.
    pub(super) reach2: [f32; LEAF_NUM_VALUES],
}

impl LeafKernels {
    /// Zeroed, on the heap (6 kB).
    pub(super) fn new_boxed() -> Box<Self> {
        Box::new(Self { norm: [0.0; LEAF_NUM_VALUES], inv_2r2: [0.0; LEAF_NUM_VALUES], reach2: [0.0; LEAF_NUM_VALUES] })
    }

    /// Voxel `n` takes kernel `k`.
    #[inline]
    pub(super) fn set(&mut self, n: usize, k: &KernelF32) {
        self.norm[n] = k.norm;
        self.inv_2r2[n] = k.inv_2r2;
        self.reach2[n] = k.reach2;
    }
}

/// Kernel weights of 4 consecutive voxels of a z-row at squared distances
/// `dxy + dz2[z]`: `norm exp(-d^2 inv_2r2)` inside `reach2`, else 0.
#[inline(always)]
fn kernel_lanes(dxy: f32, dz2: &[f32; 4], reach2: &[f32], norm: &[f32], inv_2r2: &[f32]) -> [f32; 4] {
    let (reach2, norm, inv_2r2): (&[f32; 4], &[f32; 4], &[f32; 4]) =
        (reach2.try_into().unwrap(), norm.try_into().unwrap(), inv_2r2.try_into().unwrap());
    let mut w = [0.0f32; 4];
    for z in 0..4 {
        let dd = dxy + dz2[z];
        let e = norm[z] * exp_neg_f32(-dd * inv_2r2[z]);
        w[z] = if dd < reach2[z] { e } else { 0.0 };
    }
    w
}

impl LeafGather<'_> {
    /// The world position of voxel `ijk`'s centre.
    pub(super) fn centre(&self, ijk: IVec3) -> DVec3 {
        self.transform.index_to_world(ijk.as_dvec3())
    }

    /// Index range (inclusive, leaf-local, clamped to 0..8) of the voxels
    /// whose centres can lie within `reach` of `q`.
    #[inline]
    pub(super) fn local_range(&self, origin: IVec3, q: DVec3, reach: f64) -> Option<(IVec3, IVec3)> {
        let qi = self.transform.world_to_index(q);
        let r = reach / self.transform.voxel_size;
        let lo = ceil_i(qi - DVec3::splat(r)) - origin;
        let hi = floor_i(qi + DVec3::splat(r)) - origin;
        let lo = lo.max(IVec3::ZERO);
        let hi = hi.min(IVec3::splat(LEAF_DIM - 1));
        (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z).then_some((lo, hi))
    }

    /// Adds photon `p`'s kernel, with the per-voxel parameters `k`, to the
    /// voxels of the leaf at `origin` within `reach` of it:
    /// `acc[n] += Phi * norm[n] exp(-d^2 / 2 r_n^2)` where `d^2 < (c r_n)^2`.
    /// Distances are taken in f64 then rounded to f32; the kernel value is f32
    /// (relative error below 1e-6 for |exponent| <= c^2 / 2 <= 18).
    #[inline]
    pub(super) fn accumulate(&self, origin: IVec3, p: &Photon, reach: f64, k: &LeafKernels, acc: &mut LeafSums) {
        let q = pos(p);
        let Some((lo, hi)) = self.local_range(origin, q, reach) else { return };
        let vs = self.transform.voxel_size;
        let t = self.transform.translation;
        let d2 = |axis: usize, l: i32| -> f32 {
            let c = (origin[axis] + l) as f64 * vs + t[axis];
            let d = c - q[axis];
            (d * d) as f32
        };
        // Whole z-rows of 8 voxels at a time, voxels out of range given an
        // infinite distance (weight exactly 0, and adding 0 changes no sum):
        // fixed-length, branch-free loops the compiler vectorises.
        let mut dz2 = [f32::INFINITY; LEAF_DIM as usize];
        for z in lo.z..=hi.z {
            dz2[z as usize] = d2(2, z);
        }
        let phi = p.power;
        let reach2 = (reach * reach) as f32;
        // Nearest z of each half row (lanes 0-3, 4-7): a half whose nearest
        // voxel is out of reach is skipped whole.
        let near = [dz2[..4].iter().cloned().fold(f32::INFINITY, f32::min), dz2[4..].iter().cloned().fold(f32::INFINITY, f32::min)];
        for x in lo.x..=hi.x {
            let dx2 = d2(0, x);
            for y in lo.y..=hi.y {
                let dxy = dx2 + d2(1, y);
                let row = ((x << 6) | (y << 3)) as usize;
                for (half, &nz) in near.iter().enumerate() {
                    if dxy + nz >= reach2 {
                        continue; // this half row misses the reach sphere
                    }
                    let (b, o) = (row + 4 * half, 4 * half);
                    let dz: &[f32; 4] = dz2[o..o + 4].try_into().unwrap();
                    let w = kernel_lanes(dxy, dz, &k.reach2[b..b + 4], &k.norm[b..b + 4], &k.inv_2r2[b..b + 4]);
                    for (col, &ph) in acc.c.iter_mut().zip(&phi) {
                        for (a, &wz) in col[b..b + 4].iter_mut().zip(&w) {
                            *a += wz * ph;
                        }
                    }
                }
            }
        }
    }

    /// Index range (inclusive, leaf-local, clamped to 0..8) of the voxels
    /// whose centres can lie within `reach` of the box [lo, hi].
    #[inline]
    pub(super) fn local_box(&self, origin: IVec3, lo: DVec3, hi: DVec3, reach: f64) -> Option<(IVec3, IVec3)> {
        let (li, hi_) = (self.transform.world_to_index(lo), self.transform.world_to_index(hi));
        let r = reach / self.transform.voxel_size;
        let lo = (ceil_i(li - DVec3::splat(r)) - origin).max(IVec3::ZERO);
        let hi = (floor_i(hi_ + DVec3::splat(r)) - origin).min(IVec3::splat(LEAF_DIM - 1));
        (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z).then_some((lo, hi))
    }
}

impl LeafSums {
    /// Zeroed, on the heap (6 kB).
    pub(super) fn new_boxed() -> Box<Self> {
        Box::new(Self { c: [[0.0f32; LEAF_NUM_VALUES]; 3] })
    }

    /// Turns per-voxel sums into a leaf: value = sum * scale as f32, active
    /// where nonzero, and clears the sums for the next leaf. None if nothing
    /// is active. The leaf's values are written once (no zeroed buffer
    /// first).
    pub(super) fn finish(&mut self, origin: IVec3, scale: f64) -> Option<Leaf<[f32; 3]>> {
        // Structure of arrays first (loops that vectorise), then the mask,
        // then the leaf's interleaved values.
        let mut v = [[0.0f32; LEAF_NUM_VALUES]; 3];
        for (vk, ck) in v.iter_mut().zip(&self.c) {
            for (x, &c) in vk.iter_mut().zip(ck) {
                *x = (c as f64 * scale) as f32;
            }
        }
        self.c = [[0.0; LEAF_NUM_VALUES]; 3];
        // Active where some component is nonzero (`!= 0.0`: any bit but
        // the sign set), bit by bit from the top of each word.
        let mut mask = [0u64; crate::grid::LEAF_MASK_WORDS];
        for (w, m) in mask.iter_mut().enumerate() {
            let mut bits = 0u64;
            for n in (w * 64..w * 64 + 64).rev() {
                let on = ((v[0][n].to_bits() | v[1][n].to_bits() | v[2][n].to_bits()) << 1) != 0;
                bits = (bits << 1) | on as u64;
            }
            *m = bits;
        }
        if mask.iter().all(|&w| w == 0) {
            return None;
        }
        // Each value written once: the sums where active, the background
        // (zero) elsewhere, with no zeroed leaf first.
        let values =
            Box::new(std::array::from_fn(|n| if mask[n >> 6] >> (n & 63) & 1 == 1 { [v[0][n], v[1][n], v[2][n]] } else { [0.0f32; 3] }));
        Some(Leaf { origin, mask, values })
    }
}
