//! A gather a chunk of photons at a time, with memory that does not grow
//! with the photons: [`GatherSums`] holds each touched leaf's per-voxel
//! sums (photons km^-3 s^-1, before the scale to kR per km of
//! [`super::leaf::LeafSums::finish`]); [`GatherSums::add`] adds a chunk's
//! photons to them; [`GatherSums::finish`] scales them into a grid.
//!
//! Why the grid is the one gather of all the photons would make, bit for
//! bit: a leaf's sum runs over its photons in ascending index order (the
//! splat's bins, the kd-tree's candidates), the terms are each photon's
//! alone, and the f32 sum is carried from one chunk to the next without
//! rounding or scaling in between. Chunks in photon order, cut between
//! beams (where no merged run continues, [`super::merge`]), so add the
//! same terms in the same order. A candidate leaf that gets no term keeps
//! no sums, as the one gather keeps no leaf. `report2014`'s weighted
//! average is a ratio, not a sum: it is gathered whole
//! ([`super::gather_prepared`]).

use super::bins::{bin_photons_by, bin_photons_dense, candidate_leaves, candidate_leaves_by, Bins};
use super::gather::GatherInput;
use super::kdtree::PhotonMap;
use super::kernel::gaussian_mass_inside;
use super::leaf::{LeafGather, LeafSums, PHOTONS_PER_KM2_S_PER_KR};
use super::splat::SplatScratch;
use crate::grid::{Grid, Transform, LEAF_NUM_VALUES};
use crate::scene::GatherMethod;
use crate::util::progress::Progress;
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use std::collections::HashMap;

/// Bytes a leaf's sums take: three f32 per voxel.
pub const LEAF_SUM_BYTES: usize = 3 * 4 * LEAF_NUM_VALUES;

/// Per-voxel sums of the leaves a chunked gather has touched, on one
/// transform.
pub struct GatherSums {
    pub transform: Transform,
    leaves: HashMap<IVec3, Box<LeafSums>>,
}

impl GatherSums {
    pub fn new(transform: Transform) -> Self {
        Self { transform, leaves: HashMap::new() }
    }

    /// Leaves holding a nonzero sum.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    /// Adds the photons of `input` (the next chunk, in photon order) to the
    /// sums. Panics for `report2014` (module documentation).
    pub fn add(&mut self, input: &GatherInput, progress: &dyn Progress) {
        assert!(input.method != GatherMethod::Report2014, "report2014 is gathered whole");
        let transform = self.transform;
        let photons = &input.photons[..];
        let (radius, cutoff) = (&input.radius, input.cutoff);
        let leaf = LeafGather {
            photons,
            transform,
            radius,
            cutoff,
            mass: gaussian_mass_inside(cutoff),
            seg: input.seg.clone(),
            splat_kernels: &input.splat_kernels[..],
        };
        let reach = cutoff * radius.max();
        // The candidate leaves and bins of `gather_prepared`.
        let (leaves, bins): (Vec<IVec3>, Option<Bins>) = if input.method == GatherMethod::Splat {
            let by = |i: usize| leaf.splat_kernels[i].reach;
            match bin_photons_dense(photons, transform.voxel_size, by) {
                Some((l, b)) => (l, Some(b)),
                None => {
                    let l = candidate_leaves_by(photons, transform.voxel_size, by);
                    let b = bin_photons_by(photons, &l, transform.voxel_size, by);
                    (l, Some(b))
                }
            }
        } else {
            (candidate_leaves(photons, transform.voxel_size, reach), None)
        };
        progress.start("gather", leaves.len() as u64);
        // Each leaf's sums so far move into its task and back.
        let held: Vec<(IVec3, Option<Box<LeafSums>>)> = leaves.iter().map(|o| (*o, self.leaves.remove(o))).collect();
        let out: Vec<(IVec3, Box<LeafSums>)> = match &bins {
            Some(bins) => held
                .into_par_iter()
                .enumerate()
                .map_init(SplatScratch::new, |scratch, (k, (o, acc))| {
                    let mut acc = acc.unwrap_or_else(LeafSums::new_boxed);
                    leaf.splat_into(o, bins.get(k), scratch.kernels(), &mut acc);
                    progress.inc(1);
                    (o, acc)
                })
                .collect(),
            None => {
                let map = PhotonMap::new(photons);
                let half_diag = 3.5 * 3f64.sqrt() * transform.voxel_size;
                held.into_par_iter()
                    .map(|(o, acc)| {
                        let mut acc = acc.unwrap_or_else(LeafSums::new_boxed);
                        let mid = transform.index_to_world(o.as_dvec3() + DVec3::splat(3.5));
                        leaf.balloon_into(o, map.within(mid, half_diag + reach).into_iter(), &mut acc);
                        progress.inc(1);
                        (o, acc)
                    })
                    .collect()
            }
        };
        for (o, acc) in out {
            if acc.c.iter().any(|col| col.iter().any(|&x| x != 0.0)) {
                self.leaves.insert(o, acc);
            }
        }
        progress.finish();
    }

    /// The grid named `name` of the sums: each leaf scaled to kR per km and
    /// active where nonzero, as [`super::gather_prepared`] makes it; the
    /// sums are freed leaf by leaf as the grid's leaves are made.
    pub fn finish(self, name: &str) -> Grid<[f32; 3]> {
        let mut grid = Grid::new(name, [0.0f32; 3], self.transform);
        for (o, mut acc) in self.leaves {
            if let Some(l) = acc.finish(o, 1.0 / PHOTONS_PER_KM2_S_PER_KR) {
                grid.insert_leaf(l);
            }
        }
        grid.sort_leaves();
        grid
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::photons::radius::RadiusField;
    use crate::pipeline::photons::test_fixtures::{beam_path, uniform_box};
    use crate::pipeline::photons::{gather_grid, GatherInput};
    use crate::util::progress::NoProgress;

    #[test]
    fn chunked_sums_are_the_whole_gather_bit_for_bit() {
        // Beam paths (merged runs, cut between beams) and loose points; the
        // chunks cut where one beam ends and the next starts.
        let mut photons = Vec::new();
        let mut cuts = vec![0];
        for k in 0..40 {
            photons.extend(beam_path(50, 300 + k));
            cuts.push(photons.len());
        }
        photons.extend(uniform_box(500, 0.0, 6.0, 1e19, 31));
        cuts.push(photons.len());
        let rf = RadiusField::new(0.5, 0.3, 0.1, DVec3::NEG_Z, 0.0, &[3]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        for method in [GatherMethod::Splat, GatherMethod::Kdtree] {
            let whole = gather_grid(&photons, tr, &rf, 3.0, method, &NoProgress);
            let mut sums = GatherSums::new(tr);
            // Chunks of 7 beams, then the points.
            let bounds: Vec<usize> = cuts.iter().step_by(7).copied().chain([photons.len()]).collect();
            for w in bounds.windows(2).filter(|w| w[0] < w[1]) {
                sums.add(&GatherInput::new(&photons[w[0]..w[1]], &rf, 3.0, method), &NoProgress);
            }
            let chunked = sums.finish("emission");
            assert!(whole.leaf_count() > 10, "{method:?}");
            assert_eq!(chunked, whole, "{method:?}");
        }
    }
}
