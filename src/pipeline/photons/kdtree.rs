//! The kd-tree gather: the balloon estimator, kernel radius r(x) at the
//! voxel (Terrell & Scott, "Variable Kernel Density Estimation", Annals of
//! Statistics 20(3), 1992),
//!
//! ```text
//! eta(x) = sum_i Phi_i K_{r(x)}(x; photon i)
//! ```
//!
//! with `K` the point or segment kernel of [`super::kernel`]. The photons
//! that can reach a leaf are found by one range query per 8^3 leaf in a
//! kd-tree ([`PhotonMap`], kiddo's immutable tree: Bentley, "Multidimensional
//! binary search trees used for associative searching", CACM 18(9), 1975);
//! the tree holds segment midpoints, and queries widen by the longest half
//! segment, so they return a superset, in ascending index order. Each voxel
//! then sums its photons' kernels in that order ([`LeafGather::balloon`]):
//! point photons, and segments shorter than [`MIDPOINT_LAMBDA`] r at every
//! voxel of the leaf (at their midpoint), by the point kernel's row loop of
//! [`super::leaf`]; other segments by the closed form, voxel by voxel with
//! each voxel's own r, over the z range of each row that the capsule
//! meets. [`PhotonMap::estimate`] is the same sum at one point in f64.

use super::fast_math::{erf_diff, exp_neg_f32};
use super::kernel::{photon_kernel, Kernel, KernelF32, MIDPOINT_LAMBDA};
use super::leaf::{LeafGather, LeafKernels, LeafSums, PHOTONS_PER_KM2_S_PER_KR};
use crate::grid::{Leaf, LEAF_DIM, LEAF_NUM_VALUES};
use crate::pipeline::deposit::{end, pos, Photon};
use crate::util::fmath;
use glam::{DVec3, IVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Half the longest segment, km (0 for point photons).
pub fn max_half_length(photons: &[Photon]) -> f64 {
    photons.par_iter().map(|p| 0.5 * pos(p).distance(end(p))).reduce(|| 0.0, f64::max)
}

/// Photons with a kd-tree over their positions (kiddo's immutable tree:
/// built once, queried many times).
pub struct PhotonMap<'a> {
    pub photons: &'a [Photon],
    tree: ImmutableKdTree<f32, 3>,
    /// Half the longest segment: the tree holds midpoints.
    max_half: f64,
}

impl<'a> PhotonMap<'a> {
    pub fn new(photons: &'a [Photon]) -> Self {
        let pts: Vec<[f32; 3]> = photons.iter().map(|p| (0.5 * (pos(p) + end(p))).as_vec3().to_array()).collect();
        Self { photons, tree: ImmutableKdTree::new_from_slice(&pts), max_half: max_half_length(photons) }
    }

    /// Indices of the photons whose segment comes within `radius` km of `x`
    /// (a superset: midpoints within `radius` plus the longest half segment,
    /// and the f32 query radius widened by a relative 1e-5 to cover
    /// rounding), ascending.
    pub fn within(&self, x: DVec3, radius: f64) -> Vec<usize> {
        if self.photons.is_empty() {
            return Vec::new();
        }
        let q = [x.x as f32, x.y as f32, x.z as f32];
        let radius = radius + self.max_half;
        let r = (radius * (1.0 + 1e-5) + 1e-5 * x.abs().max_element()) as f32;
        let mut idx: Vec<usize> = self.tree.within_unsorted::<SquaredEuclidean>(&q, r * r).into_iter().map(|n| n.item as usize).collect();
        idx.sort_unstable();
        idx
    }

    /// eta(x) = sum_i Phi_i K_i(x) (the point or segment kernel of photon
    /// i), photons km^-3 s^-1 per colour, through the tree. Exactly zero (never NaN) with no photon in reach.
    pub fn estimate(&self, x: DVec3, kernel: &Kernel) -> [f64; 3] {
        let mut acc = [0.0; 3];
        for i in self.within(x, kernel.reach()) {
            let p = &self.photons[i];
            let w = photon_kernel(p, kernel, x);
            for (a, &c) in acc.iter_mut().zip(&p.power) {
                *a += w * c as f64;
            }
        }
        acc
    }
}

impl LeafGather<'_> {
    /// Balloon estimate for the voxels of the leaf at `origin` from the
    /// given photons (ascending indices; a superset of those in reach).
    /// Kernel radius at each voxel: r(x_v).
    pub fn balloon(&self, origin: IVec3, candidates: impl Iterator<Item = usize>) -> Option<Leaf<[f32; 3]>> {
        let mut acc = LeafSums::new_boxed();
        self.balloon_into(origin, candidates, &mut acc);
        acc.finish(origin, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }

    /// [`Self::balloon`]'s sums without the leaf, added to what `acc`
    /// already holds in candidate order (a chunked gather carries a leaf's
    /// sums from one chunk of photons to the next).
    pub(super) fn balloon_into(&self, origin: IVec3, candidates: impl Iterator<Item = usize>, acc: &mut LeafSums) {
        let mut k = LeafKernels::new_boxed();
        let mut each = vec![KernelF32::default(); LEAF_NUM_VALUES];
        // The smallest r over the leaf, km.
        let mut r_min = f64::INFINITY;
        for (n, e) in each.iter_mut().enumerate() {
            let c = self.centre(origin + crate::grid::offset_to_local(n));
            let kernel = Kernel::with_mass(self.radius.radius(c), self.cutoff, self.mass);
            *e = KernelF32::new(&kernel);
            k.set(n, e);
            r_min = r_min.min(kernel.r);
        }
        let reach = self.cutoff * self.radius.max();
        for i in candidates {
            let p = &self.photons[i];
            let (a, b) = (pos(p), end(p));
            if p.is_point() {
                self.accumulate(origin, p, reach, &k, acc);
            } else if a.distance(b) < MIDPOINT_LAMBDA * r_min {
                // Shorter than MIDPOINT_LAMBDA r at every voxel: the
                // (vectorised) point path at the midpoint.
                let mid = Photon::point((0.5 * (a + b)).as_vec3().to_array(), p.power);
                self.accumulate(origin, &mid, reach, &k, acc);
            } else {
                // The scalar loop, voxel by voxel (a branch-free 8-wide
                // version is slower: it evaluates the voxels of each z-row
                // that the scalar loop's z range skips).
                self.accumulate_segment(origin, p, reach, &each, acc);
            }
        }
    }

    /// Adds segment photon `p`'s kernel to the voxels of the leaf at
    /// `origin` within `reach` of its segment, with the constants `each[n]`
    /// of voxel n: the closed form of [`super::kernel`], or the point
    /// kernel at the midpoint below [`MIDPOINT_LAMBDA`]. Offsets from the
    /// segment's start are taken in f64 then rounded to f32.
    #[inline]
    fn accumulate_segment(&self, origin: IVec3, p: &Photon, reach: f64, each: &[KernelF32], acc: &mut LeafSums) {
        let (a, b) = (pos(p), end(p));
        let Some((lo, hi)) = self.local_box(origin, a.min(b), a.max(b), reach) else { return };
        let len = a.distance(b);
        let dir = ((b - a) / len).as_vec3();
        let l = len as f32;
        let vs = self.transform.voxel_size;
        let t = self.transform.translation;
        let off = |axis: usize, i: i32| -> f32 { ((origin[axis] + i) as f64 * vs + t[axis] - a[axis]) as f32 };
        let mut wz = [0.0f32; LEAF_DIM as usize];
        for z in lo.z..=hi.z {
            wz[z as usize] = off(2, z);
        }
        let wz0 = off(2, 0);
        let phi = p.power;
        let inv_2l = 0.5 / l;
        // Rows along z: a voxel within `reach` of the segment lies within it
        // in (x, y) of the segment's (x, y) projection, at a distance e, and
        // within sqrt(reach^2 - e^2) in z of the segment's z range. Rows and
        // voxels outside are skipped (their kernel is 0 there anyway).
        let (px, py) = (l * dir.x, l * dir.y);
        let pxy2 = px * px + py * py;
        let reach2 = (reach * reach) as f32;
        let vs32 = vs as f32;
        let (za, zb) = (0.0f32.min(l * dir.z), 0.0f32.max(l * dir.z));
        for x in lo.x..=hi.x {
            let wx = off(0, x);
            for y in lo.y..=hi.y {
                let wy = off(1, y);
                let t = if pxy2 > 0.0 { ((wx * px + wy * py) / pxy2).clamp(0.0, 1.0) } else { 0.0 };
                let e2 = fmath::powi(wx - t * px, 2) + fmath::powi(wy - t * py, 2);
                if e2 >= reach2 {
                    continue;
                }
                let h = (reach2 - e2).sqrt() * (1.0 + 1e-5) + 1e-5;
                // Voxel z offsets from a are wz[0] + k vs, k = 0..8.
                // Rounding toward zero then widening by one voxel: a
                // superset without libm's ceil and floor.
                let z0 = (((za - h - wz0) / vs32).max(-1.0) as i32).max(lo.z);
                let z1 = (((zb + h - wz0) / vs32).min(9.0) as i32 + 1).min(hi.z);
                let sxy = wx * dir.x + wy * dir.y;
                let w2xy = wx * wx + wy * wy;
                for z in z0..=z1 {
                    let n = ((x << 6) | (y << 3) | z) as usize;
                    let q = each[n];
                    let wzz = wz[z as usize];
                    let s = sxy + wzz * dir.z;
                    let w2 = w2xy + wzz * wzz;
                    let lam = l * q.inv_r;
                    let v = if (lam as f64) < MIDPOINT_LAMBDA {
                        // |w - d L/2|^2.
                        let dm2 = (w2 - s * l + 0.25 * l * l).max(0.0);
                        if dm2 >= q.reach2 {
                            continue;
                        }
                        q.norm * exp_neg_f32(-dm2 * q.inv_2r2)
                    } else {
                        let perp2 = (w2 - s * s).max(0.0);
                        let dist2 = if s < 0.0 {
                            w2
                        } else if s > l {
                            (w2 - 2.0 * s * l + l * l).max(0.0)
                        } else {
                            perp2
                        };
                        if dist2 >= q.reach2 {
                            continue;
                        }
                        q.inv_2pi_r2
                            * inv_2l
                            * self.seg.inv_mass_f32(lam)
                            * exp_neg_f32(-perp2 * q.inv_2r2)
                            * erf_diff(s * q.inv_sqrt2r, (s - l) * q.inv_sqrt2r)
                    };
                    for (col, &ph) in acc.c.iter_mut().zip(&phi) {
                        col[n] += v * ph;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use crate::pipeline::photons::gather::gather_grid;
    use crate::pipeline::photons::kernel::{estimate_brute_force, gaussian_mass_inside};
    use crate::pipeline::photons::radius::RadiusField;
    use crate::pipeline::photons::test_fixtures::uniform_box;
    use crate::scene::GatherMethod;
    use crate::util::progress::NoProgress;
    use crate::util::rng;
    use rand::Rng;

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
        let v = fmath::powi(side, 3);
        let mean = n as f64 * 2.0 / v;
        let mc = gaussian_mass_inside(c);
        let int_k2 = gaussian_mass_inside(c * 2f64.sqrt()) / (mc * mc * fmath::powf(4.0 * std::f64::consts::PI, 1.5) * fmath::powi(r, 3));
        let var = n as f64 * 4.0 / v * int_k2 - n as f64 * 4.0 / (v * v);
        let sigma = var.sqrt();
        let mut r_ = rng::rng(&[8]);
        for _ in 0..20 {
            // Points at least c r from every face.
            let x = DVec3::new(4.0 + 12.0 * r_.random::<f64>(), 4.0 + 12.0 * r_.random::<f64>(), 4.0 + 12.0 * r_.random::<f64>());
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
            .map(|_| {
                Photon::point(
                    [(r.random::<f64>() * 30.0) as f32, (r.random::<f64>() * 1.5) as f32, (100.0 + r.random::<f64>() * 30.0) as f32],
                    [r.random::<f32>(), r.random::<f32>(), r.random::<f32>()],
                )
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
}
