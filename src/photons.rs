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
//! The kernel radius is perturbed by the report's medium-frequency 2D noise,
//! taken at the point's field-line foot so the variation follows B (rays).
//!
//! Gather methods (`photons.gather`):
//! - `kdtree` (default): a balloon estimator, radius r(x) at the voxel. One
//!   kiddo range query per 8^3 leaf finds the photons that can reach it; each
//!   voxel then sums its photons' kernels in photon-index order.
//! - `splat`: a sample-point estimator, radius r(x_i) at the photon. Photons
//!   are binned per leaf (in photon order), each adds its kernel to the
//!   leaf's voxels within its cutoff. No tree.
//! - `report2014`: the report's estimate, a kernel-weighted *average*
//!   `sum(w Phi) / sum(w)` (w the unnormalised Gaussian) of photons binned in a
//!   uniform grid (the leaves). Not a density: its magnitude is a photon's
//!   power, not comparable with the two others. For comparison only.
//!
//! Every per-voxel sum runs over photons in ascending index order, so the
//! grids are identical whatever the thread count.

use crate::beams::Photon;
use crate::grid::{leaf_offset, Grid, Leaf, Transform, LEAF_DIM, LEAF_NUM_VALUES};
use crate::progress::Progress;
use crate::rng;
use crate::scene::GatherMethod;
use glam::{DVec3, IVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use noise::Perlin;
use rayon::prelude::*;
use std::collections::HashMap;

/// Photons km^-2 s^-1 in one kR.
pub const PHOTONS_PER_KM2_S_PER_KR: f64 = 1e19;

/// Mass of the standard 3D Gaussian inside radius `c` (in standard
/// deviations): `erf(c / sqrt 2) - sqrt(2 / pi) c exp(-c^2 / 2)`, computed by
/// composite Simpson integration of `4 pi r^2 phi(r)` (4096 intervals: error
/// far below 1e-12 for c <= 6).
pub fn gaussian_mass_inside(c: f64) -> f64 {
    let n = 4096;
    let h = c / n as f64;
    let f = |r: f64| 4.0 * std::f64::consts::PI * r * r * (-0.5 * r * r).exp() / (2.0 * std::f64::consts::PI).powf(1.5);
    let mut s = f(0.0) + f(c);
    for k in 1..n {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// The truncated, renormalised 3D Gaussian kernel of standard deviation `r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    pub r: f64,
    pub cutoff: f64,
    /// 1 / ((2 pi)^(3/2) r^3 M(cutoff)).
    norm: f64,
    inv_2r2: f64,
    /// (cutoff r)^2.
    reach2: f64,
}

impl Kernel {
    /// `mass` is [`gaussian_mass_inside`]`(cutoff)`, passed in so a kernel
    /// per voxel costs no integration.
    #[inline]
    pub fn with_mass(r: f64, cutoff: f64, mass: f64) -> Self {
        let norm = 1.0 / ((2.0 * std::f64::consts::PI).powf(1.5) * r * r * r * mass);
        Self { r, cutoff, norm, inv_2r2: 0.5 / (r * r), reach2: (cutoff * r) * (cutoff * r) }
    }

    pub fn new(r: f64, cutoff: f64) -> Self {
        Self::with_mass(r, cutoff, gaussian_mass_inside(cutoff))
    }

    /// Support radius, km.
    pub fn reach(&self) -> f64 {
        self.cutoff * self.r
    }

    /// K(d) for squared distance `d2` (km^-3); exactly 0 beyond the cutoff.
    #[inline]
    pub fn eval_d2(&self, d2: f64) -> f64 {
        if d2 < self.reach2 {
            self.norm * (-d2 * self.inv_2r2).exp()
        } else {
            0.0
        }
    }

    /// The unnormalised weight exp(-d^2 / 2r^2) inside the cutoff (report2014).
    #[inline]
    fn weight_d2(&self, d2: f64) -> f64 {
        if d2 < self.reach2 {
            (-d2 * self.inv_2r2).exp()
        } else {
            0.0
        }
    }
}

/// Kernel radius as a function of position: `base * (1 + amp * n)`, n a 2D
/// Perlin noise in [-1, 1] of the field-line foot (x, y) at altitude `z_ref`,
/// at `freq` cycles per km. Bounded by `base * (1 + amp)`.
#[derive(Clone, Debug)]
pub struct RadiusField {
    pub base: f64,
    pub amp: f64,
    pub freq: f64,
    pub b: DVec3,
    pub z_ref: f64,
    noise: Perlin,
}

impl RadiusField {
    pub fn new(base: f64, amp: f64, freq: f64, b: DVec3, z_ref: f64, seed: &[u64]) -> Self {
        let mut parts = seed.to_vec();
        parts.push(rng::tag::RADIUS_NOISE);
        Self { base, amp, freq, b, z_ref, noise: rng::perlin(&parts) }
    }

    /// The scene's kernel radius field (`photons.radius_km`, its noise, along
    /// the scene's B field from the beams' top).
    pub fn from_scene(scene: &crate::scene::Scene) -> Self {
        let b = crate::beams::Field::new(scene.beams.b_inclination_deg, scene.beams.b_declination_deg).b;
        let p = &scene.photons;
        Self::new(p.radius_km, p.radius_noise, p.radius_noise_freq, b, scene.beams.top_km, &[scene.seed])
    }

    /// A constant radius.
    pub fn constant(r: f64) -> Self {
        Self { base: r, amp: 0.0, freq: 0.0, b: DVec3::NEG_Z, z_ref: 0.0, noise: Perlin::new(0) }
    }

    pub fn max(&self) -> f64 {
        self.base * (1.0 + self.amp)
    }

    #[inline]
    pub fn radius(&self, p: DVec3) -> f64 {
        if self.amp == 0.0 {
            return self.base;
        }
        let foot = p + self.b * ((self.z_ref - p.z) / self.b.z);
        self.base * (1.0 + self.amp * rng::noise2(&self.noise, foot.x * self.freq, foot.y * self.freq))
    }
}

#[inline]
fn pos(p: &Photon) -> DVec3 {
    DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64)
}

/// Photons with a kd-tree over their positions (kiddo's immutable tree:
/// built once, queried many times).
pub struct PhotonMap<'a> {
    pub photons: &'a [Photon],
    tree: ImmutableKdTree<f32, 3>,
}

impl<'a> PhotonMap<'a> {
    pub fn new(photons: &'a [Photon]) -> Self {
        let pts: Vec<[f32; 3]> = photons.iter().map(|p| p.position).collect();
        Self { photons, tree: ImmutableKdTree::new_from_slice(&pts) }
    }

    /// Indices of the photons within `radius` km of `x` (a superset: the
    /// f32 query radius is widened by a relative 1e-5 to cover rounding),
    /// ascending.
    pub fn within(&self, x: DVec3, radius: f64) -> Vec<usize> {
        if self.photons.is_empty() {
            return Vec::new();
        }
        let q = [x.x as f32, x.y as f32, x.z as f32];
        let r = (radius * (1.0 + 1e-5) + 1e-5 * x.abs().max_element()) as f32;
        let mut idx: Vec<usize> =
            self.tree.within_unsorted::<SquaredEuclidean>(&q, r * r).into_iter().map(|n| n.item as usize).collect();
        idx.sort_unstable();
        idx
    }

    /// eta(x) = sum_i Phi_i K(|x - x_i|), photons km^-3 s^-1 per colour,
    /// through the tree. Exactly zero (never NaN) with no photon in reach.
    pub fn estimate(&self, x: DVec3, kernel: &Kernel) -> [f64; 3] {
        let mut acc = [0.0; 3];
        for i in self.within(x, kernel.reach()) {
            let p = &self.photons[i];
            let w = kernel.eval_d2(pos(p).distance_squared(x));
            for (a, &c) in acc.iter_mut().zip(&p.power) {
                *a += w * c as f64;
            }
        }
        acc
    }
}

/// The same estimate by brute force over every photon (the oracle).
pub fn estimate_brute_force(photons: &[Photon], x: DVec3, kernel: &Kernel) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for p in photons {
        let w = kernel.eval_d2(pos(p).distance_squared(x));
        if w > 0.0 {
            for (a, &c) in acc.iter_mut().zip(&p.power) {
                *a += w * c as f64;
            }
        }
    }
    acc
}

/// Origins (index space) of the leaves within `reach` km of some photon:
/// every voxel centre a kernel of that reach can touch lies in one of them.
/// Sorted by (x, y, z), the grid's leaf order.
pub fn candidate_leaves(photons: &[Photon], voxel_size: f64, reach: f64) -> Vec<IVec3> {
    let mut keys: Vec<(i32, i32, i32)> = photons
        .par_chunks(1 << 16)
        .flat_map_iter(|chunk| {
            let mut v = Vec::new();
            let mut last: Option<(IVec3, IVec3)> = None;
            for p in chunk {
                let range = leaf_range(pos(p), voxel_size, reach);
                if last == Some(range) {
                    continue; // neighbouring photons of a beam share leaves
                }
                last = Some(range);
                for_each_leaf(range, |o| v.push((o.x, o.y, o.z)));
            }
            v.sort_unstable();
            v.dedup();
            v
        })
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    keys.into_iter().map(|(x, y, z)| IVec3::new(x, y, z)).collect()
}

/// Leaf origins (first, last) covering the voxel centres within `reach` of `q`.
#[inline]
fn leaf_range(q: DVec3, voxel_size: f64, reach: f64) -> (IVec3, IVec3) {
    let lo = ((q - DVec3::splat(reach)) / voxel_size).ceil().as_ivec3();
    let hi = ((q + DVec3::splat(reach)) / voxel_size).floor().as_ivec3();
    (crate::grid::leaf_origin(lo), crate::grid::leaf_origin(hi))
}

#[inline]
fn for_each_leaf((lo, hi): (IVec3, IVec3), mut f: impl FnMut(IVec3)) {
    let mut x = lo.x;
    while x <= hi.x {
        let mut y = lo.y;
        while y <= hi.y {
            let mut z = lo.z;
            while z <= hi.z {
                f(IVec3::new(x, y, z));
                z += LEAF_DIM;
            }
            y += LEAF_DIM;
        }
        x += LEAF_DIM;
    }
}

/// Photon indices per candidate leaf, each list ascending (counting sort in
/// photon order): the uniform grid of `splat` and `report2014`.
pub fn bin_photons(photons: &[Photon], leaves: &[IVec3], voxel_size: f64, reach: f64) -> Vec<Vec<u32>> {
    let index: HashMap<IVec3, usize> = leaves.iter().enumerate().map(|(i, &o)| (o, i)).collect();
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); leaves.len()];
    for (i, p) in photons.iter().enumerate() {
        for_each_leaf(leaf_range(pos(p), voxel_size, reach), |o| {
            if let Some(&k) = index.get(&o) {
                bins[k].push(i as u32);
            }
        });
    }
    bins
}

/// exp(x) for x <= 0 in f32, deterministic and branch-free so loops
/// vectorise: `2^(x log2 e)` split into an integer power (exponent bits) and
/// 2^f for f in [-1/2, 1/2] by its degree-6 Taylor polynomial (truncation
/// ln2^7 / 7! / 2^7 = 1.2e-7 relative). Arguments below -87 return 0-ish
/// subnormal-free values (clamped at 2^-126).
#[inline(always)]
pub fn exp_neg_f32(x: f32) -> f32 {
    let y = (x * std::f32::consts::LOG2_E).max(-126.0);
    // Round to nearest by the 1.5 * 2^23 trick (exact for |y| < 2^22): the
    // integer lands in the low mantissa bits of t, so neither libm's round
    // nor a saturating float-to-int conversion is needed (both block
    // vectorisation).
    const MAGIC: f32 = 12_582_912.0;
    let t = y + MAGIC;
    let i_bits = t.to_bits() as i32 - MAGIC.to_bits() as i32;
    let f = y - (t - MAGIC);
    const C: [f32; 7] = [
        1.0,
        std::f32::consts::LN_2,
        0.240_226_5,
        0.055_504_11,
        0.009_618_129,
        0.001_333_355_8,
        0.000_154_035_3,
    ];
    let p = C[0] + f * (C[1] + f * (C[2] + f * (C[3] + f * (C[4] + f * (C[5] + f * C[6])))));
    let scale = f32::from_bits(((i_bits + 127) as u32) << 23);
    p * scale
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

/// Per-voxel kernel parameters of one leaf, structure of arrays.
struct LeafKernels {
    /// 1 / ((2 pi)^(3/2) r^3 M(c)), km^-3.
    norm: [f32; LEAF_NUM_VALUES],
    /// 1 / (2 r^2).
    inv_2r2: [f32; LEAF_NUM_VALUES],
    /// (c r)^2.
    reach2: [f32; LEAF_NUM_VALUES],
}

impl LeafKernels {
    fn set(&mut self, n: usize, k: &Kernel) {
        self.norm[n] = k.norm as f32;
        self.inv_2r2[n] = k.inv_2r2 as f32;
        self.reach2[n] = k.reach2 as f32;
    }
}

/// Per-voxel sums of one leaf, one array per colour. f32: the sums are of
/// positive terms in a fixed order, so n terms are good to n 2^-24 relative
/// at worst (about sqrt(n) 2^-24 in practice, 1e-5 for 10^4 terms), far
/// below the estimate's Monte Carlo noise; f64 made the gather 30 % slower.
struct LeafAcc {
    c: [[f32; LEAF_NUM_VALUES]; 3],
}

/// What a leaf gather needs.
pub struct GatherSetup<'a> {
    pub photons: &'a [Photon],
    pub transform: Transform,
    pub radius: &'a RadiusField,
    pub cutoff: f64,
    /// gaussian_mass_inside(cutoff)
    pub mass: f64,
}

impl GatherSetup<'_> {
    fn centre(&self, ijk: IVec3) -> DVec3 {
        self.transform.index_to_world(ijk.as_dvec3())
    }

    /// Index range (inclusive, leaf-local, clamped to 0..8) of the voxels
    /// whose centres can lie within `reach` of `q`.
    #[inline]
    fn local_range(&self, origin: IVec3, q: DVec3, reach: f64) -> Option<(IVec3, IVec3)> {
        let qi = self.transform.world_to_index(q);
        let r = reach / self.transform.voxel_size;
        let lo = (qi - DVec3::splat(r)).ceil().as_ivec3() - origin;
        let hi = (qi + DVec3::splat(r)).floor().as_ivec3() - origin;
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
    fn accumulate(&self, origin: IVec3, p: &Photon, reach: f64, k: &LeafKernels, acc: &mut LeafAcc) {
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

    /// Turns per-voxel sums into a leaf: value = sum * scale as f32, active
    /// where nonzero. None if nothing is active.
    fn finish(origin: IVec3, acc: &LeafAcc, scale: f64) -> Option<Leaf<[f32; 3]>> {
        let mut leaf = Leaf::new(origin, [0.0f32; 3]);
        for n in 0..LEAF_NUM_VALUES {
            let v = [(acc.c[0][n] as f64 * scale) as f32, (acc.c[1][n] as f64 * scale) as f32, (acc.c[2][n] as f64 * scale) as f32];
            if v.iter().any(|&c| c != 0.0) {
                leaf.values[n] = v;
                leaf.set_active(n, true);
            }
        }
        (leaf.active_count() > 0).then_some(leaf)
    }

    fn new_acc() -> Box<LeafAcc> {
        Box::new(LeafAcc { c: [[0.0f32; LEAF_NUM_VALUES]; 3] })
    }

    fn new_kernels() -> Box<LeafKernels> {
        Box::new(LeafKernels { norm: [0.0; LEAF_NUM_VALUES], inv_2r2: [0.0; LEAF_NUM_VALUES], reach2: [0.0; LEAF_NUM_VALUES] })
    }

    /// Balloon estimate for the voxels of one leaf from the given photons
    /// (ascending indices; a superset of those in reach). Kernel radius at
    /// each voxel: r(x_v).
    pub fn leaf_balloon(&self, origin: IVec3, candidates: impl Iterator<Item = usize>) -> Option<Leaf<[f32; 3]>> {
        let mut k = Self::new_kernels();
        for n in 0..LEAF_NUM_VALUES {
            let c = self.centre(origin + crate::grid::offset_to_local(n));
            k.set(n, &Kernel::with_mass(self.radius.radius(c), self.cutoff, self.mass));
        }
        let reach = self.cutoff * self.radius.max();
        let mut acc = Self::new_acc();
        for i in candidates {
            self.accumulate(origin, &self.photons[i], reach, &k, &mut acc);
        }
        Self::finish(origin, &acc, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }

    /// Sample-point estimate (splat): kernel radius r(x_i) at each photon.
    pub fn leaf_splat(&self, origin: IVec3, photons: &[u32]) -> Option<Leaf<[f32; 3]>> {
        let mut acc = Self::new_acc();
        let mut k = Self::new_kernels();
        for &i in photons {
            let p = &self.photons[i as usize];
            let q = pos(p);
            let kernel = Kernel::with_mass(self.radius.radius(q), self.cutoff, self.mass);
            let Some((lo, hi)) = self.local_range(origin, q, kernel.reach()) else { continue };
            // The photon's kernel in the rows it can touch (whole z-rows:
            // accumulate reads them 4 lanes at a time).
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    let row = ((x << 6) | (y << 3)) as usize;
                    for n in row..row + 8 {
                        k.set(n, &kernel);
                    }
                }
            }
            self.accumulate(origin, p, kernel.reach(), &k, &mut acc);
        }
        Self::finish(origin, &acc, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }

    /// The 2014 report's weighted average colour, sum(w Phi) / sum(w), with
    /// w = exp(-d^2 / 2 r^2) inside the cutoff (r at the voxel).
    pub fn leaf_report2014(&self, origin: IVec3, photons: &[u32]) -> Option<Leaf<[f32; 3]>> {
        let mut acc = Self::new_acc();
        let mut wsum = vec![0.0f64; LEAF_NUM_VALUES];
        let reach = self.cutoff * self.radius.max();
        let kernels: Vec<Kernel> = (0..LEAF_NUM_VALUES)
            .map(|n| Kernel::with_mass(self.radius.radius(self.centre(origin + crate::grid::offset_to_local(n))), self.cutoff, self.mass))
            .collect();
        for &i in photons {
            let p = &self.photons[i as usize];
            let q = pos(p);
            let Some((lo, hi)) = self.local_range(origin, q, reach) else { continue };
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    for z in lo.z..=hi.z {
                        let ijk = origin + IVec3::new(x, y, z);
                        let n = leaf_offset(ijk);
                        let w = kernels[n].weight_d2(self.centre(ijk).distance_squared(q));
                        if w > 0.0 {
                            wsum[n] += w;
                            for k in 0..3 {
                                acc.c[k][n] += (w * p.power[k] as f64) as f32;
                            }
                        }
                    }
                }
            }
        }
        for (n, &w) in wsum.iter().enumerate() {
            if w > 0.0 {
                for k in 0..3 {
                    acc.c[k][n] = (acc.c[k][n] as f64 / w) as f32;
                }
            }
        }
        Self::finish(origin, &acc, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }
}

/// Builds the emission grid (kR per km, linear Rec.709) from the photons
/// with the chosen gather method. Leaves are gathered in parallel, collected
/// in leaf order and sorted, so the grid does not depend on the thread count.
pub fn gather_grid(
    photons: &[Photon],
    transform: Transform,
    radius: &RadiusField,
    cutoff: f64,
    method: GatherMethod,
    progress: &dyn Progress,
) -> Grid<[f32; 3]> {
    let mut grid = Grid::new("emission", [0.0f32; 3], transform);
    let setup = GatherSetup { photons, transform, radius, cutoff, mass: gaussian_mass_inside(cutoff) };
    let reach = cutoff * radius.max();
    let leaves = candidate_leaves(photons, transform.voxel_size, reach);
    progress.start("gather", leaves.len() as u64);
    let out: Vec<Option<Leaf<[f32; 3]>>> = match method {
        GatherMethod::Kdtree => {
            let map = PhotonMap::new(photons);
            // Voxel centres of a leaf lie within 3.5 voxels (per axis) of its
            // middle: a sphere of radius 3.5 sqrt(3) voxels plus the reach.
            let half_diag = 3.5 * 3f64.sqrt() * transform.voxel_size;
            leaves
                .par_iter()
                .map(|&o| {
                    let mid = transform.index_to_world(o.as_dvec3() + DVec3::splat(3.5));
                    let cand = map.within(mid, half_diag + reach);
                    progress.inc(1);
                    setup.leaf_balloon(o, cand.into_iter())
                })
                .collect()
        }
        GatherMethod::Splat | GatherMethod::Report2014 => {
            let bins = bin_photons(photons, &leaves, transform.voxel_size, reach);
            leaves
                .par_iter()
                .zip(bins.par_iter())
                .map(|(&o, b)| {
                    progress.inc(1);
                    if method == GatherMethod::Splat {
                        setup.leaf_splat(o, b)
                    } else {
                        setup.leaf_report2014(o, b)
                    }
                })
                .collect()
        }
    };
    for leaf in out.into_iter().flatten() {
        grid.insert_leaf(leaf);
    }
    grid.sort_leaves();
    progress.finish();
    grid
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;
    use rand::Rng;

    fn uniform_box(n: usize, lo: f64, hi: f64, power: f32, seed: u64) -> Vec<Photon> {
        let mut r = rng::rng(&[seed]);
        (0..n)
            .map(|_| {
                let mut p = [0.0f32; 3];
                for c in &mut p {
                    *c = (lo + (hi - lo) * r.random::<f64>()) as f32;
                }
                Photon { position: p, power: [power, 0.5 * power, 0.25 * power] }
            })
            .collect()
    }

    #[test]
    fn fast_exp_matches_std_exp() {
        // Relative error budget: polynomial 1.2e-7 + f32 rounding of the
        // product chain (~6 operations x 2^-24 = 3.6e-7) + the argument's
        // own rounding, |x| 2^-24 <= 1.1e-6 at x = -18 (c = 6).
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = -18.0f32 * i as f32 / 200_000.0;
            let got = exp_neg_f32(x) as f64;
            let want = (x as f64).exp();
            worst = worst.max((got / want - 1.0).abs());
        }
        assert!(worst < 1.5e-6, "worst relative error {worst}");
        assert_eq!(exp_neg_f32(0.0), 1.0);
        assert!(exp_neg_f32(-200.0) >= 0.0 && exp_neg_f32(-200.0) < 1e-37);
    }

    #[test]
    fn truncated_kernel_integrates_to_one() {
        // Closed form of the truncated mass for c = 3: erf(3/sqrt2) - sqrt(2/pi) 3 e^-4.5.
        let m = gaussian_mass_inside(3.0);
        assert!((m - (0.997_300_203_936_740 - (2.0 / std::f64::consts::PI).sqrt() * 3.0 * (-4.5f64).exp())).abs() < 1e-12, "{m}");
        for (r, c) in [(0.5, 3.0), (1.3, 1.5), (0.2, 6.0)] {
            let k = Kernel::new(r, c);
            // Midpoint rule on a grid of h = r / 8 over the cube [-c r, c r]^3.
            // The smooth part is integrated to ~1e-6; the cutoff is a jump of
            // height K(c r) on the sphere, and each cell it cuts is wrong by at
            // most its mass there: |error| <= 4 pi (c r)^2 (h / 2) K(c r).
            // (Without the renormalisation the error would be 1 - M(c):
            // 0.029 for c = 3, 0.52 for c = 1.5, far above these bounds.)
            let h = r / 8.0;
            let m = (c * r / h).ceil() as i32;
            let mut s = 0.0;
            for i in -m..=m {
                for j in -m..=m {
                    for l in -m..=m {
                        let d2 = (i * i + j * j + l * l) as f64 * h * h;
                        s += k.eval_d2(d2);
                    }
                }
            }
            s *= h * h * h;
            let jump = k.eval_d2((c * r) * (c * r) * (1.0 - 1e-12));
            let bound = 4.0 * std::f64::consts::PI * (c * r).powi(2) * 0.5 * h * jump + 1e-6;
            assert!(bound < 0.5 * (1.0 - gaussian_mass_inside(c)) || c > 5.0, "test too weak for c = {c}");
            assert!((s - 1.0).abs() < bound, "r {r} c {c}: {s} (bound {bound})");
        }
    }

    #[test]
    fn uniform_photons_give_a_constant_estimate() {
        // N photons of power P uniform in a box of volume V: E[eta] = N P / V
        // inside (the kernel integrates to 1 and is fully inside), and
        // Var[eta] = N (E[(P K)^2] - E[P K]^2) = (N P^2 / V) int K^2 - (N P^2 / V^2),
        // with int K^2 = 1 / (M(c)^2 (4 pi)^(3/2) r^3) * M(c sqrt 2) (the
        // square of a Gaussian of sd r is one of sd r / sqrt 2). Test at 5 sigma.
        let (n, side, r, c) = (200_000usize, 20.0f64, 1.0, 3.0);
        let photons = uniform_box(n, 0.0, side, 2.0, 7);
        let k = Kernel::new(r, c);
        let map = PhotonMap::new(&photons);
        let v = side.powi(3);
        let mean = n as f64 * 2.0 / v;
        let mc = gaussian_mass_inside(c);
        let int_k2 = gaussian_mass_inside(c * 2f64.sqrt()) / (mc * mc * (4.0 * std::f64::consts::PI).powf(1.5) * r.powi(3));
        let var = n as f64 * 4.0 / v * int_k2 - n as f64 * 4.0 / (v * v);
        let sigma = var.sqrt();
        let mut r_ = rng::rng(&[8]);
        for _ in 0..20 {
            // Points at least c r from every face.
            let x = DVec3::new(
                4.0 + 12.0 * r_.random::<f64>(),
                4.0 + 12.0 * r_.random::<f64>(),
                4.0 + 12.0 * r_.random::<f64>(),
            );
            let e = map.estimate(x, &k);
            assert!((e[0] - mean).abs() < 5.0 * sigma, "{} vs {mean} +- {sigma}", e[0]);
            assert!((e[1] - 0.5 * e[0]).abs() < 1e-12 * e[0]);
        }
    }

    #[test]
    fn doubling_the_photons_doubles_the_estimate() {
        let photons = uniform_box(5_000, 0.0, 10.0, 1.0, 9);
        let doubled: Vec<Photon> = photons.iter().chain(photons.iter()).cloned().collect();
        let k = Kernel::new(0.8, 3.0);
        let (a, b) = (PhotonMap::new(&photons), PhotonMap::new(&doubled));
        for x in [DVec3::splat(5.0), DVec3::new(2.0, 7.0, 4.0)] {
            let (ea, eb) = (a.estimate(x, &k), b.estimate(x, &k));
            // Same terms, each twice: equal to 2x up to summation rounding.
            assert!((eb[0] - 2.0 * ea[0]).abs() < 1e-12 * eb[0], "{ea:?} {eb:?}");
        }
    }

    #[test]
    fn kdtree_gather_matches_brute_force() {
        // Clustered photons (a thin sheet, like a curtain) and random queries.
        let mut r = rng::rng(&[10]);
        let photons: Vec<Photon> = (0..20_000)
            .map(|_| Photon {
                position: [(r.random::<f64>() * 30.0) as f32, (r.random::<f64>() * 1.5) as f32, (100.0 + r.random::<f64>() * 30.0) as f32],
                power: [r.random::<f32>(), r.random::<f32>(), r.random::<f32>()],
            })
            .collect();
        let map = PhotonMap::new(&photons);
        for i in 0..200 {
            let k = Kernel::new(0.3 + 0.01 * (i % 50) as f64, 3.0);
            let x = DVec3::new(r.random::<f64>() * 30.0, r.random::<f64>() * 3.0 - 0.75, 100.0 + r.random::<f64>() * 30.0);
            let (a, b) = (map.estimate(x, &k), estimate_brute_force(&photons, x, &k));
            // Same photons in the same (index) order: identical sums.
            assert_eq!(a, b, "query {i} at {x}");
        }
    }

    #[test]
    fn empty_neighbourhood_gives_zero_not_nan() {
        let photons = uniform_box(100, 0.0, 1.0, 1.0, 11);
        let k = Kernel::new(0.1, 3.0);
        assert_eq!(PhotonMap::new(&photons).estimate(DVec3::splat(50.0), &k), [0.0; 3]);
        assert_eq!(PhotonMap::new(&[]).estimate(DVec3::ZERO, &k), [0.0; 3]);
        let empty = gather_grid(&[], Transform::new(0.5, DVec3::ZERO), &RadiusField::constant(0.5), 3.0, GatherMethod::Kdtree, &NoProgress);
        assert_eq!(empty.leaf_count(), 0);
    }

    fn voxel_brute(photons: &[Photon], g: &Grid<[f32; 3]>, rf: &RadiusField, cutoff: f64, ijk: IVec3) -> [f64; 3] {
        let x = g.transform.index_to_world(ijk.as_dvec3());
        let e = estimate_brute_force(photons, x, &Kernel::new(rf.radius(x), cutoff));
        e.map(|v| v / PHOTONS_PER_KM2_S_PER_KR)
    }

    fn terms_in_reach(photons: &[Photon], g: &Grid<[f32; 3]>, rf: &RadiusField, cutoff: f64, ijk: IVec3) -> usize {
        let x = g.transform.index_to_world(ijk.as_dvec3());
        let k = Kernel::new(rf.radius(x), cutoff);
        photons.iter().filter(|p| k.eval_d2(pos(p).distance_squared(x)) > 0.0).count()
    }

    #[test]
    fn grid_gather_matches_per_voxel_brute_force_and_is_complete() {
        let photons = {
            let mut v = uniform_box(3_000, 0.0, 6.0, 1e19, 12);
            v.truncate(3_000);
            v
        };
        let rf = RadiusField::new(0.4, 0.3, 0.2, DVec3::new(0.0, 0.2, -1.0).normalize(), 10.0, &[1]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        let g = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Kdtree, &NoProgress);
        assert!(g.active_voxel_count() > 1000);
        // Every active voxel equals the brute-force balloon estimate (f32
        // rounding of the stored value: relative 2^-24, plus summation order
        // which is the same).
        for (ijk, v) in g.iter_active().step_by(7) {
            let b = voxel_brute(&photons, &g, &rf, 3.0, ijk);
            let n = terms_in_reach(&photons, &g, &rf, 3.0, ijk) as f64;
            for k in 0..3 {
                // The grid evaluates each kernel in f32 (exponent |x| <= 4.5
                // rounded to 2^-24 relative, fast exp 1.2e-7, norm 2^-24: each
                // term within 1e-6 relative) and sums the n positive terms in
                // f32 (at most n 2^-24 relative), then rounds to f32.
                let tol = 1e-6 + (n + 1.0) * 2f64.powi(-24);
                assert!((v[k] as f64 - b[k]).abs() <= tol * b[k].abs(), "{ijk}: {v:?} vs {b:?} ({n} terms)");
            }
        }
        // And no voxel outside the grid's leaves has any photon in reach:
        // probe a shell of voxels around the photon box.
        for i in -6..20 {
            for j in [-6, 19] {
                let ijk = IVec3::new(i, j, i.rem_euclid(13));
                if !g.is_active(ijk) {
                    assert_eq!(voxel_brute(&photons, &g, &rf, 3.0, ijk), [0.0; 3], "{ijk}");
                }
            }
        }
    }

    #[test]
    fn splat_and_kdtree_agree_for_a_constant_radius() {
        // With r(x) constant the balloon and sample-point estimators are the
        // same sum; only the f64 terms' order could differ, and it does not.
        let photons = uniform_box(4_000, 0.0, 5.0, 3e19, 13);
        let rf = RadiusField::constant(0.35);
        let tr = Transform::new(0.25, DVec3::ZERO);
        let a = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Kdtree, &NoProgress);
        let b = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Splat, &NoProgress);
        assert_eq!(a, b);
        // report2014 averages: inside the box its value is about one photon's
        // power (3e19 / 1e19 = 3 in red), whatever the photon count.
        let c = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Report2014, &NoProgress);
        let v = c.get(IVec3::splat(10));
        assert!((v[0] - 3.0).abs() < 1e-3, "{v:?}");
    }

    #[test]
    fn gather_is_independent_of_thread_count() {
        let photons = uniform_box(5_000, 0.0, 8.0, 1e19, 14);
        let rf = RadiusField::new(0.5, 0.3, 0.1, DVec3::NEG_Z, 0.0, &[3]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
                gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Kdtree, &NoProgress)
            })
        };
        let (a, b) = (run(1), run(3));
        assert_eq!(a, b);
        let la: Vec<_> = a.leaves().iter().map(|l| l.origin).collect();
        let lb: Vec<_> = b.leaves().iter().map(|l| l.origin).collect();
        assert_eq!(la, lb);
    }
}
