//! The 2014 report's estimate, kept for comparison (`photons.gather =
//! "report2014"`): per voxel, the kernel-weighted *average* colour of the
//! photons binned in a uniform grid (the leaves, [`super::bins`]),
//!
//! ```text
//! value(x) = sum_i w_i Phi_i / sum_i w_i,   w_i = exp(-|x - x_i|^2 / 2 r(x)^2) inside c r(x)
//! ```
//!
//! (r at the voxel, w the unnormalised Gaussian, points at each photon's
//! position). Not a density: dividing by the sum of the weights throws the
//! photon density away, so its magnitude is a photon's power, not
//! comparable with the two other gathers' (a uniform box of photons of
//! power P reads P / 1e19 inside, whatever their number: tested).

use super::kernel::Kernel;
use super::leaf::{LeafGather, LeafSums, PHOTONS_PER_KM2_S_PER_KR};
use crate::grid::{leaf_offset, Leaf, LEAF_NUM_VALUES};
use crate::pipeline::deposit::pos;
use glam::IVec3;

impl LeafGather<'_> {
    /// The 2014 report's weighted average colour, sum(w Phi) / sum(w), with
    /// w = exp(-d^2 / 2 r^2) inside the cutoff (r at the voxel), for the
    /// voxels of the leaf at `origin` from its bin `photons`.
    pub fn report2014(&self, origin: IVec3, photons: &[u32]) -> Option<Leaf<[f32; 3]>> {
        let mut acc = LeafSums::new_boxed();
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
        acc.finish(origin, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }
}
