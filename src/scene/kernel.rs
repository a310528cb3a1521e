//! The photon kernel's radius as the scene sets it: `photons.radius_km`,
//! its relative noise amplitude, and the smallest and largest radius they
//! give. The one place that reads `photons.radius_km`: the bake's plan
//! (`crate::pipeline::plan`, the radius field and the automatic voxel size) and
//! the memory budget (`crate::pipeline::memory::budget`) both take it from here, so they
//! cannot disagree on the kernel's reach or on the automatic voxel's floor.

use super::photons::PhotonParams;

/// The kernel radius the scene asks for (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelRadius {
    /// `photons.radius_km`.
    pub base_km: f64,
    /// `photons.radius_noise`.
    pub noise: f64,
    /// `base_km (1 - noise)`.
    pub min_km: f64,
    /// `base_km (1 + noise)`.
    pub max_km: f64,
}

impl KernelRadius {
    pub fn of(p: &PhotonParams) -> Self {
        Self::with_base(p.radius_km, p)
    }

    /// The same noise around another base radius (the bench's radius study).
    pub fn with_base(base_km: f64, p: &PhotonParams) -> Self {
        KernelRadius { base_km, noise: p.radius_noise, min_km: base_km * (1.0 - p.radius_noise), max_km: base_km * (1.0 + p.radius_noise) }
    }

    /// The smallest voxel `grid.voxel_size = "auto"` may choose, km: half
    /// the base radius (finer voxels resolve nothing the kernel has not
    /// already smoothed away).
    pub fn auto_voxel_floor_km(&self) -> f64 {
        0.5 * self.base_km
    }

    /// The largest distance at which a photon's kernel is nonzero, km:
    /// `cutoff` standard deviations of the largest radius.
    pub fn max_reach_km(&self, cutoff: f64) -> f64 {
        cutoff * self.max_km
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::*;

    #[test]
    fn the_range_brackets_the_base_radius() {
        let p = PhotonParams { radius_km: 2.0, radius_noise: 0.25, cutoff: 3.0, ..PhotonParams::default() };
        let k = KernelRadius::of(&p);
        assert_eq!((k.base_km, k.min_km, k.max_km), (2.0, 1.5, 2.5));
        assert_eq!(k.auto_voxel_floor_km(), 1.0);
        assert_eq!(k.max_reach_km(p.cutoff), 7.5);
        assert_eq!(KernelRadius::with_base(4.0, &p).max_km, 5.0);
    }
}
