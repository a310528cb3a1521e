//! The splat: the sample-point estimator, kernel radius r(x_i) at the
//! photon (Terrell & Scott, "Variable Kernel Density Estimation", Annals of
//! Statistics 20(3), 1992, name it and the balloon estimator), the default
//! gather.
//!
//! Each photon carries its own kernel ([`KernelF32`], made once per photon
//! by [`super::gather::GatherInput`]: r at the point or the segment's midpoint, a
//! Perlin lookup) and is binned by its own reach `c r_i` ([`super::bins`]);
//! each leaf then adds its photons' kernels, in photon order, to the voxels
//! within their reach ([`LeafGather::splat`]). A point photon (or a segment
//! shorter than [`MIDPOINT_LAMBDA`] r, at its midpoint) takes the point
//! kernel's row loop of [`super::leaf`]. Any other segment takes the
//! segment kernel's closed form of [`super::kernel`],
//!
//! ```text
//! K_seg = exp(-perp^2 / 2r^2) / (2 pi r^2) * [erf(s / sqrt2 r) - erf((s - L) / sqrt2 r)] / (2 L M_seg(L / r))
//! ```
//!
//! (s along the segment, perp across it), over whole z-rows of 8 voxels,
//! or half rows of 4 where the leaf's range holds one half, without
//! branches: the capsule test `dist^2 < (c r)^2` selects the lanes, the
//! rows the capsule misses are skipped. The across factor is
//! [`exp_neg_f32`], the two erfs' difference [`erf_diff_lanes`] (a
//! rational function, vectorised whole), so the per-voxel arithmetic is that of the balloon's scalar
//! path and the gathers' tolerances hold for both.
//!
//! The leaf loop is compiled twice: as is, and for AVX2 (`#[target_feature]`),
//! taken after a runtime check of the CPU; the 8-wide rows are then one
//! instruction wide. IEEE 754 arithmetic gives the same result at any
//! vector width and Rust contracts no multiply-add, so both give the same
//! bits. Scratch space ([`SplatScratch`]) is reused from leaf to leaf, one
//! per thread.

use super::fast_math::{erf_diff_lanes, exp_neg_f32};
use super::kernel::{Kernel, KernelF32, MIDPOINT_LAMBDA};
use super::leaf::{LeafGather, LeafKernels, LeafSums, PHOTONS_PER_KM2_S_PER_KR};
use crate::grid::Leaf;
use crate::pipeline::deposit::{end, pos, Photon};
use crate::util::fmath;
use glam::IVec3;

/// How many photons ahead of the one being added [`LeafGather::splat`]
/// prefetches.
const PREFETCH_AHEAD: usize = 4;

/// A hint that the bytes at `p` will be read soon (no effect on results; a
/// no-op off x86-64). Any address may be given: a prefetch never faults.
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `_mm_prefetch` only hints the cache; it reads nothing the
    // program sees and never faults, whatever the address (SSE, which it
    // needs, is part of x86-64's baseline).
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p as *const i8)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Scratch space of the splat, one per thread: the per-voxel sums (zero
/// between leaves) and the point kernel's per-voxel constants.
pub struct SplatScratch {
    acc: Box<LeafSums>,
    k: Box<LeafKernels>,
}

impl SplatScratch {
    pub fn new() -> Self {
        Self { acc: LeafSums::new_boxed(), k: LeafKernels::new_boxed() }
    }
}

impl SplatScratch {
    /// The per-voxel kernel constants alone (a chunked gather brings its
    /// own sums).
    pub(super) fn kernels(&mut self) -> &mut LeafKernels {
        &mut self.k
    }
}

impl Default for SplatScratch {
    fn default() -> Self {
        Self::new()
    }
}

/// The segment kernel's geometry at N consecutive voxels of a z-row (4 or
/// 8), offsets from the segment's start `w = (wx, wy, wz)` given as `s_xy
/// = wx dx + wy dy` and `w2_xy = wx^2 + wy^2` for the row and `wz dz`,
/// `wz^2` per lane: `s` (along the segment), `perp^2` (across it), and 1
/// where the voxel lies inside the capsule (distance to the segment below
/// `c r`), else 0. Branch-free so it vectorises.
#[inline(always)]
fn segment_lanes<const N: usize>(
    sxy: f32,
    w2xy: f32,
    sz: &[f32; N],
    w2z: &[f32; N],
    l: f32,
    q: &KernelF32,
) -> ([f32; N], [f32; N], [f32; N]) {
    let (mut s4, mut p4, mut inside) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for j in 0..N {
        let s = sxy + sz[j];
        let w2 = w2xy + w2z[j];
        let perp2 = (w2 - s * s).max(0.0);
        let end2 = (w2 - 2.0 * s * l + l * l).max(0.0);
        let dist2 = if s < 0.0 {
            w2
        } else if s > l {
            end2
        } else {
            perp2
        };
        inside[j] = if dist2 < q.reach2 { 1.0 } else { 0.0 };
        (s4[j], p4[j]) = (s, perp2);
    }
    (s4, p4, inside)
}

/// The segment kernel's closed form at N lanes of a z-row from
/// [`segment_lanes`]' `s`, `perp2` and `inside`, times the photon's power
/// `phi`, added to the sums from voxel `n` on: `c inside exp(-perp2 / 2r^2)
/// (erf(s / sqrt2 r) - erf((s - L) / sqrt2 r))`, `c` the constant factor,
/// the erfs' difference by [`erf_diff_lanes`].
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn add_segment_lanes<const N: usize>(
    acc: &mut LeafSums,
    n: usize,
    s4: &[f32; N],
    perp2: &[f32; N],
    inside: &[f32; N],
    q: &KernelF32,
    c: f32,
    l: f32,
    phi: &[f32; 3],
) {
    let (mut ex, mut u0, mut u1) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for j in 0..N {
        ex[j] = exp_neg_f32(-perp2[j] * q.inv_2r2);
        u0[j] = s4[j] * q.inv_sqrt2r;
        u1[j] = (s4[j] - l) * q.inv_sqrt2r;
    }
    let de = erf_diff_lanes(&u0, &u1);
    let mut v = [0.0f32; N];
    for j in 0..N {
        v[j] = c * inside[j] * ex[j] * de[j];
    }
    for (col, &ph) in acc.c.iter_mut().zip(phi) {
        for (a, &vj) in col[n..n + N].iter_mut().zip(&v) {
            *a += vj * ph;
        }
    }
}

impl LeafGather<'_> {
    /// Sample-point estimate (splat) for the voxels of the leaf at
    /// `origin` from its bin `photons` (ascending indices): kernel radius
    /// r(x_i) at each photon. `scratch` is reused from leaf to leaf (one
    /// per thread): the sums are cleared after each leaf, and the per-voxel
    /// kernel rows are written before they are read.
    pub fn splat(&self, origin: IVec3, photons: &[u32], scratch: &mut SplatScratch) -> Option<Leaf<[f32; 3]>> {
        let SplatScratch { acc, k } = scratch;
        self.splat_into(origin, photons, k, acc);
        acc.finish(origin, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }

    /// [`Self::splat`]'s sums without the leaf: the kernels of the bin
    /// `photons` (ascending indices) added to `acc` in that order, on
    /// whatever `acc` already holds (a chunked gather carries a leaf's sums
    /// from one chunk of photons to the next, so the sums are the same
    /// terms in the same order as one gather of all the photons). `k` is
    /// scratch.
    pub(super) fn splat_into(&self, origin: IVec3, photons: &[u32], k: &mut LeafKernels, acc: &mut LeafSums) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above), the one
            // requirement of `splat_avx2`.
            return unsafe { self.splat_avx2(origin, photons, k, acc) };
        }
        self.splat_body(origin, photons, k, acc)
    }

    /// [`Self::splat_into`] compiled for AVX2: the 8-wide z-rows of the segment
    /// path in one pass. IEEE arithmetic is the same at any vector width
    /// and Rust fuses no multiply-add, so the values are the same bits as
    /// without AVX2.
    ///
    /// # Safety
    ///
    /// The CPU must support AVX2 (`is_x86_feature_detected!("avx2")`):
    /// the body is compiled with AVX2 instructions, which fault elsewhere.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn splat_avx2(&self, origin: IVec3, photons: &[u32], k: &mut LeafKernels, acc: &mut LeafSums) {
        self.splat_body(origin, photons, k, acc)
    }

    /// The leaf loop of [`Self::splat_into`], inlined into both of its builds.
    #[inline(always)]
    fn splat_body(&self, origin: IVec3, photons: &[u32], k: &mut LeafKernels, acc: &mut LeafSums) {
        for (j, &i) in photons.iter().enumerate() {
            // The bin's photons are scattered over the photon array: ask
            // for the one a few ahead (and its kernel) to be in cache by
            // the time it is read.
            if let Some(&ahead) = photons.get(j + PREFETCH_AHEAD) {
                prefetch(self.photons.as_ptr().wrapping_add(ahead as usize));
                prefetch(self.splat_kernels.as_ptr().wrapping_add(ahead as usize));
            }
            let p = &self.photons[i as usize];
            if !p.is_point() {
                self.splat_segment(origin, p, &self.splat_kernels[i as usize], k, acc);
                continue;
            }
            let q = pos(p);
            let kernel = Kernel::with_mass(self.radius.radius(q), self.cutoff, self.mass);
            let Some((lo, hi)) = self.local_range(origin, q, kernel.reach()) else { continue };
            let kf = KernelF32::new(&kernel);
            // The photon's kernel in the rows it can touch (whole z-rows:
            // accumulate reads them 4 lanes at a time).
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    let row = ((x << 6) | (y << 3)) as usize;
                    for n in row..row + 8 {
                        k.set(n, &kf);
                    }
                }
            }
            self.accumulate(origin, p, kernel.reach(), k, acc);
        }
    }

    /// The splat's segment path: photon `p`'s segment kernel, with its one
    /// set of constants `sk`, added to the voxels of the leaf at `origin`
    /// within its reach. A segment shorter than [`MIDPOINT_LAMBDA`] r goes
    /// to the point path at its midpoint. Otherwise the closed form of the
    /// module documentation, evaluated over whole half z-rows (4 voxels)
    /// without branches: the capsule test `dist2 < (c r)^2` selects the
    /// lanes (the same test, in the same f32 arithmetic, as the balloon's
    /// `accumulate_segment`, so the same voxels get a term), the
    /// rows the capsule misses and the half rows outside the segment's box
    /// widened by the reach are skipped whole. Offsets from the segment's
    /// start are taken in f64 then rounded to f32.
    #[inline(always)]
    fn splat_segment(&self, origin: IVec3, p: &Photon, sk: &KernelF32, k: &mut LeafKernels, acc: &mut LeafSums) {
        let (a, b) = (pos(p), end(p));
        let q = *sk;
        let reach = sk.reach;
        let len = a.distance(b);
        let l = len as f32;
        let lam = l * q.inv_r;
        if (lam as f64) < MIDPOINT_LAMBDA {
            let mid = 0.5 * (a + b);
            let Some((lo, hi)) = self.local_range(origin, mid, reach) else { return };
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    let row = ((x << 6) | (y << 3)) as usize;
                    for n in row..row + 8 {
                        k.set(n, &q);
                    }
                }
            }
            let mid = Photon::point(mid.as_vec3().to_array(), p.power);
            return self.accumulate(origin, &mid, reach, k, acc);
        }
        let Some((lo, hi)) = self.local_box(origin, a.min(b), a.max(b), reach) else { return };
        let dir = ((b - a) / len).as_vec3();
        let vs = self.transform.voxel_size;
        let t = self.transform.translation;
        let off = |axis: usize, i: i32| -> f32 { ((origin[axis] + i) as f64 * vs + t[axis] - a[axis]) as f32 };
        let (mut sz, mut w2z) = ([0.0f32; 8], [0.0f32; 8]);
        for z in 0..8 {
            let w = off(2, z as i32);
            (sz[z], w2z[z]) = (w * dir.z, w * w);
        }
        let phi = p.power;
        // The closed form's constant factor: 1 / (2 pi r^2) / (2 L M_seg).
        let c = q.inv_2pi_r2 * (0.5 / l) * self.seg.inv_mass_f32(lam);
        let (px, py) = (l * dir.x, l * dir.y);
        let pxy2 = px * px + py * py;
        let reach2 = (reach * reach) as f32;
        let inv_pxy2 = if pxy2 > 0.0 { 1.0 / pxy2 } else { 0.0 };
        let wys: [f32; 8] = std::array::from_fn(|y| off(1, y as i32));
        // Half rows (lanes 0-3, 4-7) meeting the z range lo.z..=hi.z.
        let halves = (if lo.z < 4 { 0 } else { 4 }..if hi.z >= 4 { 8 } else { 4 }).step_by(4);
        let whole_rows = lo.z < 4 && hi.z >= 4;
        for x in lo.x..=hi.x {
            let wx = off(0, x);
            for y in lo.y..=hi.y {
                let wy = wys[y as usize];
                // The row's distance e in (x, y) from the segment's
                // projection: rows with e >= reach miss the capsule. (A z
                // range per row, as in accumulate_segment, costs a square
                // root per row and saved less than it cost: the half rows
                // are those of the leaf's z range `lo.z..=hi.z`.)
                let tt = ((wx * px + wy * py) * inv_pxy2).clamp(0.0, 1.0);
                let e2 = fmath::powi(wx - tt * px, 2) + fmath::powi(wy - tt * py, 2);
                if e2 >= reach2 {
                    continue;
                }
                let sxy = wx * dir.x + wy * dir.y;
                let w2xy = wx * wx + wy * wy;
                let row = ((x << 6) | (y << 3)) as usize;
                if whole_rows {
                    // Both halves at once (one 8-wide pass with AVX2,
                    // `LeafGather::splat`); a half the capsule misses
                    // adds exact zeros (inside 0, every other factor finite
                    // and the erf difference >= 0: erf_diff is floored at 0), which leaves the
                    // non-negative sums as they are: the same values as
                    // half rows.
                    let (s8, perp2, inside) = segment_lanes(sxy, w2xy, &sz, &w2z, l, &q);
                    if inside != [0.0; 8] {
                        add_segment_lanes(acc, row, &s8, &perp2, &inside, &q, c, l, &phi);
                    }
                    continue;
                }
                for o in halves.clone() {
                    let (sz4, w2z4) = (sz[o..o + 4].try_into().unwrap(), w2z[o..o + 4].try_into().unwrap());
                    let (s4, perp2, inside) = segment_lanes::<4>(sxy, w2xy, sz4, w2z4, l, &q);
                    if inside == [0.0; 4] {
                        continue; // the half row misses the capsule
                    }
                    add_segment_lanes(acc, row + o, &s4, &perp2, &inside, &q, c, l, &phi);
                }
            }
        }
    }
}
