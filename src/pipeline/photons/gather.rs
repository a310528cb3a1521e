//! The gather drivers, the public entry points of [`super`]: from photons
//! to the emission grid, `eta(x) / 1e19` in kR per km (the module
//! documentation of [`super`]), with the method of `photons.gather`.
//!
//! [`GatherInput::new`] makes the photons ready (merged runs,
//! [`super::merge`]; the splat's kernel per photon), once for several
//! gathers of the same photons (the preview's coarse and refined
//! pictures); [`gather_prepared`] finds the candidate leaves and bins
//! ([`super::bins`]: the splat by each photon's own reach, the others by
//! the largest r's) and evaluates the leaves in parallel
//! ([`super::kdtree`], [`super::splat`], [`super::weighted_average`]); the
//! leaves are collected in leaf order and sorted, so the grid does not
//! depend on the thread count. [`gather_grid`] is both in one call.

use super::bins::{bin_photons, bin_photons_by, bin_photons_dense, candidate_leaves, candidate_leaves_by};
use super::kdtree::PhotonMap;
use super::kernel::{gaussian_mass_inside, Kernel, KernelF32, SegmentMass};
use super::leaf::LeafGather;
use super::merge::{merge_segments, MERGE_CDF, MERGE_LEN_R, MERGE_OFF_R};
use super::radius::RadiusField;
use super::splat::SplatScratch;
use crate::grid::{Grid, Leaf, Transform};
use crate::pipeline::deposit::{end, pos, Photon};
use crate::scene::GatherMethod;
use crate::util::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;

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
    gather_prepared(&GatherInput::new(photons, radius, cutoff, method), transform, progress)
}

/// The photons as the gathers take them, made once for several gathers of
/// the same photons (the preview's coarse picture and the refined one):
/// straight, evenly lit runs of beam steps merged into one segment each
/// ([`merge_segments`], all but `report2014`) and, for the splat, each
/// photon's kernel (r at the point or the segment's midpoint: a Perlin
/// lookup per photon), with the radius field, cutoff and method they were
/// made for.
#[derive(Clone, Debug)]
pub struct GatherInput {
    pub photons: Vec<Photon>,
    pub(super) splat_kernels: Vec<KernelF32>,
    /// The segment kernel's masses for the cutoff (a table of numerical
    /// integrals).
    pub(super) seg: SegmentMass,
    pub(super) radius: RadiusField,
    pub(super) cutoff: f64,
    pub(super) method: GatherMethod,
}

impl GatherInput {
    pub fn new(photons: &[Photon], radius: &RadiusField, cutoff: f64, method: GatherMethod) -> Self {
        let photons = if method == GatherMethod::Report2014 {
            photons.to_vec()
        } else {
            merge_segments(photons, |p| radius.radius(p), MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF)
        };
        let mass = gaussian_mass_inside(cutoff);
        let splat_kernels = if method == GatherMethod::Splat {
            photons
                .par_iter()
                .map(|p| {
                    KernelF32::new(&Kernel::with_mass(
                        radius.radius(if p.is_point() { pos(p) } else { 0.5 * (pos(p) + end(p)) }),
                        cutoff,
                        mass,
                    ))
                })
                .collect()
        } else {
            Vec::new()
        };
        Self { photons, splat_kernels, seg: SegmentMass::new(cutoff), radius: radius.clone(), cutoff, method }
    }

    /// Every `k`-th photon (from the first), its power multiplied by `k`:
    /// the same expected emission from `1/k` of the photons (the preview's
    /// coarse picture). Kernels are kept.
    pub fn every(&self, k: usize) -> Self {
        let k = k.max(1);
        let photons = self.photons.iter().step_by(k).map(|p| Photon { power: p.power.map(|c| c * k as f32), ..*p }).collect();
        let splat_kernels = self.splat_kernels.iter().step_by(k).copied().collect();
        Self { photons, splat_kernels, seg: self.seg.clone(), radius: self.radius.clone(), ..*self }
    }
}

/// [`gather_grid`] of photons made ready by [`GatherInput::new`], with the
/// radius field, cutoff and method they were made for.
pub fn gather_prepared(input: &GatherInput, transform: Transform, progress: &dyn Progress) -> Grid<[f32; 3]> {
    let (radius, cutoff, method) = (&input.radius, input.cutoff, input.method);
    let mut grid = Grid::new("emission", [0.0f32; 3], transform);
    let photons = &input.photons[..];
    let mass = gaussian_mass_inside(cutoff);
    let splat_kernels = &input.splat_kernels[..];
    let leaf = LeafGather { photons, transform, radius, cutoff, mass, seg: input.seg.clone(), splat_kernels };
    let reach = cutoff * radius.max();
    // The splat bins each photon by its own reach (cutoff r_i, r at the
    // point or the segment's midpoint, as LeafGather::splat evaluates it); the
    // balloon's kernel takes r at the voxel, so the largest r's reach.
    let (leaves, dense_bins) = if method == GatherMethod::Splat {
        match bin_photons_dense(photons, transform.voxel_size, |i| leaf.splat_kernels[i].reach) {
            Some((leaves, bins)) => (leaves, Some(bins)),
            None => (candidate_leaves_by(photons, transform.voxel_size, |i| leaf.splat_kernels[i].reach), None),
        }
    } else {
        (candidate_leaves(photons, transform.voxel_size, reach), None)
    };
    progress.start("gather", leaves.len() as u64);
    let out: Vec<Option<Leaf<[f32; 3]>>> = match method {
        GatherMethod::Kdtree => {
            let map = PhotonMap::new(photons);
            // Voxel centres of a leaf lie within 3.5 voxels (per axis) of its
            // middle: a sphere of radius 3.5 sqrt(3) voxels plus the reach.
            // (PhotonMap::within adds the longest half segment.)
            let half_diag = 3.5 * 3f64.sqrt() * transform.voxel_size;
            leaves
                .par_iter()
                .map(|&o| {
                    let mid = transform.index_to_world(o.as_dvec3() + DVec3::splat(3.5));
                    let cand = map.within(mid, half_diag + reach);
                    progress.inc(1);
                    leaf.balloon(o, cand.into_iter())
                })
                .collect()
        }
        GatherMethod::Splat | GatherMethod::Report2014 => {
            let bins = if let Some(b) = dense_bins {
                b
            } else if method == GatherMethod::Splat {
                bin_photons_by(photons, &leaves, transform.voxel_size, |i| leaf.splat_kernels[i].reach)
            } else {
                bin_photons(photons, &leaves, transform.voxel_size, reach)
            };
            leaves
                .par_iter()
                .enumerate()
                .map_init(SplatScratch::new, |scratch, (k, &o)| {
                    let b = bins.get(k);
                    progress.inc(1);
                    if method == GatherMethod::Splat {
                        leaf.splat(o, b, scratch)
                    } else {
                        leaf.report2014(o, b)
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
    use crate::pipeline::photons::kernel::estimate_brute_force;
    use crate::pipeline::photons::leaf::PHOTONS_PER_KM2_S_PER_KR;
    use crate::pipeline::photons::test_fixtures::{beam_path, segment_photons, uniform_box};
    use crate::util::fmath;
    use crate::util::progress::NoProgress;
    use glam::IVec3;

    #[test]
    fn segment_gathers_match_the_f64_oracle_and_each_other() {
        let photons = segment_photons(1500, 22);
        let rf = RadiusField::new(0.4, 0.3, 0.2, DVec3::new(0.0, 0.2, -1.0).normalize(), 10.0, &[1]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        let g = gather_grid(&photons, tr, &rf, 2.5, GatherMethod::Kdtree, &NoProgress);
        assert!(g.active_voxel_count() > 1000);
        let vmax = g.iter_active().map(|(_, v)| v[0]).fold(0.0f32, f32::max) as f64;
        // Per voxel: each term's f32 kernel is within 1e-5 relative of the
        // f64 closed form where the erf difference is large (the
        // difference 6e-7 absolute, exp 1e-6, the mass table 1e-6), within 1e-4 of the point
        // kernel's peak for lambda below MIDPOINT_LAMBDA (module
        // documentation); so 1e-4 of the voxel plus an absolute 1e-6 of the
        // grid's largest value for the erf's absolute error at the caps.
        let mut checked = 0;
        for (ijk, v) in g.iter_active().step_by(5) {
            let b = voxel_brute(&photons, &g, &rf, 2.5, ijk);
            for k in 0..3 {
                let tol = 1e-4 * b[k].abs() + 1e-6 * vmax;
                assert!((v[k] as f64 - b[k]).abs() <= tol, "{ijk}: {v:?} vs {b:?}");
            }
            checked += 1;
        }
        assert!(checked > 200);
        // Completeness: voxels outside the grid's leaves see no photon.
        for i in -6..20 {
            for j in [-6, 19] {
                let ijk = IVec3::new(i, j, i.rem_euclid(13));
                if !g.is_active(ijk) {
                    assert_eq!(voxel_brute(&photons, &g, &rf, 2.5, ijk), [0.0; 3], "{ijk}");
                }
            }
        }
        // Constant radius: balloon and splat are the same sum in the same
        // order, through different f32 code (row lanes, the midpoint via the
        // point path, against the scalar path): each within the oracle's
        // tolerance of the other.
        let rc = RadiusField::constant(0.35);
        let a = gather_grid(&photons, tr, &rc, 2.5, GatherMethod::Kdtree, &NoProgress);
        let s = gather_grid(&photons, tr, &rc, 2.5, GatherMethod::Splat, &NoProgress);
        assert_eq!(a.active_voxel_count(), s.active_voxel_count());
        let amax = a.iter_active().map(|(_, v)| v[0]).fold(0.0f32, f32::max);
        for (ijk, v) in a.iter_active() {
            let w = s.get(ijk);
            for k in 0..3 {
                assert!((v[k] - w[k]).abs() <= 2e-4 * w[k].abs() + 2e-6 * amax, "{ijk}: {v:?} vs {w:?}");
            }
        }
    }

    #[test]
    fn segment_grid_holds_the_photons_power() {
        // Sum of the grid times the voxel volume = total power / 1e19 (kR per
        // km), photons well inside: the midpoint rule on voxels of r / 4 has
        // the capsule-surface error of `segment_kernel_integrates_to_one`,
        // under 2 % per photon at h = r / 4, and it averages over photons.
        let photons = segment_photons(300, 23);
        let rf = RadiusField::constant(0.4);
        let vs = 0.1;
        let g = gather_grid(&photons, Transform::new(vs, DVec3::ZERO), &rf, 2.5, GatherMethod::Splat, &NoProgress);
        let sum: f64 = g.iter_active().map(|(_, v)| v[0] as f64).sum::<f64>() * vs * vs * vs;
        let want = photons.len() as f64;
        assert!((sum / want - 1.0).abs() < 0.01, "{sum} vs {want}");
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
                let tol = 1e-6 + (n + 1.0) * fmath::powi(2f64, -24);
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
        // Points, loose segments and beam paths (merged runs), with more
        // photons than one binning chunk (2^14).
        let mut photons = uniform_box(5_000, 0.0, 8.0, 1e19, 14);
        photons.extend(segment_photons(2_000, 15));
        for k in 0..200 {
            photons.extend(beam_path(60, 100 + k));
        }
        assert!(photons.len() > 1 << 14);
        let rf = RadiusField::new(0.5, 0.3, 0.1, DVec3::NEG_Z, 0.0, &[3]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        for method in [GatherMethod::Kdtree, GatherMethod::Splat] {
            let run = |threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| gather_grid(&photons, tr, &rf, 3.0, method, &NoProgress))
            };
            let (a, b) = (run(1), run(3));
            assert_eq!(a, b, "{method:?}");
            let la: Vec<_> = a.leaves().iter().map(|l| l.origin).collect();
            let lb: Vec<_> = b.leaves().iter().map(|l| l.origin).collect();
            assert_eq!(la, lb);
        }
    }
}
