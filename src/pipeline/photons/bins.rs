//! Which leaves a photon reaches, and which photons each leaf gets: the
//! uniform grid of 8^3-voxel leaves that the splat and `report2014`
//! gathers bin photons in, and the leaf set of every gather.
//!
//! A photon of reach R (km: `cutoff r`, the kernel's support) can touch the
//! voxel centres within R of its segment, so the leaves it reaches are
//! those overlapping its segment's bounding box widened by R
//! (`leaf_range`: voxel indices `ceil((min - R) / h)` to `floor((max +
//! R) / h)`, h the voxel size, then their leaves' origins). The candidate
//! leaves are the union over photons ([`candidate_leaves`]), sorted by (x,
//! y, z), the grid's leaf order.
//!
//! The bins are a stable counting sort of the (leaf, photon) pairs by leaf
//! (Cormen, Leiserson, Rivest & Stein, *Introduction to Algorithms*, 8.2:
//! counts, prefix sum, scatter), with the pairs produced in photon order,
//! so each leaf's photons are ascending whatever the thread count
//! ([`bin_photons`], through a hash map from origin to leaf). On a box of
//! leaves small enough to hold densely ([`DENSE_BIN_CELLS`]), the leaves
//! and bins come in one go without hash maps ([`bin_photons_dense`]: the
//! same leaves and bins, tested).

use super::fast_math::{ceil_i, floor_i};
use crate::grid::LEAF_DIM;
use crate::pipeline::deposit::{end, pos, Photon};
use glam::{DVec3, IVec3};
use rayon::prelude::*;

/// Origins (index space) of the leaves within `reach` km of some photon's
/// segment:
/// every voxel centre a kernel of that reach can touch lies in one of them.
/// Sorted by (x, y, z), the grid's leaf order.
pub fn candidate_leaves(photons: &[Photon], voxel_size: f64, reach: f64) -> Vec<IVec3> {
    candidate_leaves_by(photons, voxel_size, |_| reach)
}

/// [`candidate_leaves`] with a reach per photon, `reach(i)` km for photon
/// i (the splat's: `cutoff r_i`, not the largest r's).
pub fn candidate_leaves_by(photons: &[Photon], voxel_size: f64, reach: impl Fn(usize) -> f64 + Sync) -> Vec<IVec3> {
    const CHUNK: usize = 1 << 16;
    // Per chunk a set of origins (each leaf once per chunk however many
    // photons reach it), then one sort of the chunks' few: deterministic.
    let mut keys: Vec<(i32, i32, i32)> = photons
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(c, chunk)| {
            let mut set = crate::grid::OriginMap::<()>::default();
            let mut last: Option<(IVec3, IVec3)> = None;
            for (j, p) in chunk.iter().enumerate() {
                let range = leaf_range(p, voxel_size, reach(c * CHUNK + j));
                if last == Some(range) {
                    continue; // neighbouring photons of a beam share leaves
                }
                last = Some(range);
                for_each_leaf(range, |o| {
                    set.insert(o, ());
                });
            }
            set.into_keys().map(|o| (o.x, o.y, o.z))
        })
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    keys.into_iter().map(|(x, y, z)| IVec3::new(x, y, z)).collect()
}

/// `ceil` per component as integers, by truncation and a correction
/// (x86-64's baseline has no rounding instruction, so `f64::ceil` is a libm
/// call; the gather takes six per photon and leaf). Exact for |x| < 2^31;
/// Leaf origins (first, last) covering the voxel centres within `reach` of
/// the photon's segment (its bounding box widened by `reach`).
#[inline]
fn leaf_range(p: &Photon, voxel_size: f64, reach: f64) -> (IVec3, IVec3) {
    let (a, b) = (pos(p), end(p));
    let lo = ceil_i((a.min(b) - DVec3::splat(reach)) / voxel_size);
    let hi = floor_i((a.max(b) + DVec3::splat(reach)) / voxel_size);
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

/// Photon indices per candidate leaf: leaf k's photons are
/// `photons[start[k]..start[k + 1]]`, ascending.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bins {
    pub start: Vec<usize>,
    pub photons: Vec<u32>,
}

impl Bins {
    /// The photons of leaf `k`.
    #[inline]
    pub fn get(&self, k: usize) -> &[u32] {
        &self.photons[self.start[k]..self.start[k + 1]]
    }
}

/// Photon indices per candidate leaf, each list ascending: the uniform
/// grid of `splat` and `report2014`.
///
/// (leaf, photon) pairs from chunks of photons in parallel, collected in
/// photon order, then a stable counting sort by leaf (count, prefix sum,
/// scatter): each leaf's list is in photon order whatever the thread count.
pub fn bin_photons(photons: &[Photon], leaves: &[IVec3], voxel_size: f64, reach: f64) -> Bins {
    bin_photons_by(photons, leaves, voxel_size, |_| reach)
}

/// [`bin_photons`] with a reach per photon (see [`candidate_leaves_by`]).
pub fn bin_photons_by(photons: &[Photon], leaves: &[IVec3], voxel_size: f64, reach: impl Fn(usize) -> f64 + Sync) -> Bins {
    let index: crate::grid::OriginMap<u32> = leaves.iter().enumerate().map(|(i, &o)| (o, i as u32)).collect();
    const CHUNK: usize = 1 << 14;
    let pairs: Vec<(u32, u32)> = photons
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(c, chunk)| {
            let mut v = Vec::with_capacity(chunk.len() * 2);
            for (j, p) in chunk.iter().enumerate() {
                let i = (c * CHUNK + j) as u32;
                for_each_leaf(leaf_range(p, voxel_size, reach(i as usize)), |o| {
                    if let Some(&k) = index.get(&o) {
                        v.push((k, i));
                    }
                });
            }
            v
        })
        .collect();
    let mut start = vec![0usize; leaves.len() + 1];
    for &(k, _) in &pairs {
        start[k as usize + 1] += 1;
    }
    for k in 0..leaves.len() {
        start[k + 1] += start[k];
    }
    let mut next = start.clone();
    let mut out = vec![0u32; pairs.len()];
    for &(k, i) in &pairs {
        out[next[k as usize]] = i;
        next[k as usize] += 1;
    }
    Bins { start, photons: out }
}

/// Largest leaf box (in leaves) that [`bin_photons_dense`] takes: 4 M
/// cells, 32 MB of counts and slots. Beyond it the hashed path.
pub const DENSE_BIN_CELLS: u64 = 1 << 22;

/// [`candidate_leaves_by`] and [`bin_photons_by`] at once, on a dense box
/// of leaves rather than hash maps: the same leaves (sorted by (x, y, z),
/// the box's linear order) and the same bins (each leaf's photons
/// ascending). Each photon's leaf range once; per cell a count (atomic
/// adds: the counts do not depend on the order), the leaves where it is
/// not zero, a prefix sum, then the photon indices scattered in photon
/// order. None when the box holds more than [`DENSE_BIN_CELLS`] leaves.
pub fn bin_photons_dense(photons: &[Photon], voxel_size: f64, reach: impl Fn(usize) -> f64 + Sync) -> Option<(Vec<IVec3>, Bins)> {
    use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
    let ranges: Vec<(IVec3, IVec3)> = photons.par_iter().enumerate().map(|(i, p)| leaf_range(p, voxel_size, reach(i))).collect();
    let (lo, hi) = ranges
        .par_iter()
        .filter(|(a, b)| a.cmple(*b).all())
        .map(|&r| r)
        .reduce(|| (IVec3::MAX, IVec3::MIN), |(a, b), (c, d)| (a.min(c), b.max(d)));
    if lo.x > hi.x {
        return Some((Vec::new(), Bins { start: vec![0], photons: Vec::new() }));
    }
    let dims = ((hi.as_i64vec3() - lo.as_i64vec3()) / LEAF_DIM as i64 + 1).as_u64vec3();
    if dims.x.saturating_mul(dims.y).saturating_mul(dims.z) > DENSE_BIN_CELLS {
        return None;
    }
    let (ny, nz) = (dims.y as usize, dims.z as usize);
    let cells = dims.x as usize * ny * nz;
    let cell = |o: IVec3| {
        let d = (o - lo) / LEAF_DIM;
        (d.x as usize * ny + d.y as usize) * nz + d.z as usize
    };
    let counts: Vec<AtomicU32> = (0..cells).map(|_| AtomicU32::new(0)).collect();
    ranges.par_iter().for_each(|&r| {
        for_each_leaf(r, |o| {
            counts[cell(o)].fetch_add(1, Relaxed);
        })
    });
    let (mut leaves, mut start, mut slot) = (Vec::new(), vec![0usize], vec![u32::MAX; cells]);
    for (c, n) in counts.iter().enumerate() {
        let n = n.load(Relaxed) as usize;
        if n > 0 {
            let (x, y, z) = (c / (ny * nz), (c / nz) % ny, c % nz);
            slot[c] = leaves.len() as u32;
            leaves.push(lo + IVec3::new(x as i32, y as i32, z as i32) * LEAF_DIM);
            start.push(start[start.len() - 1] + n);
        }
    }
    let mut next = start.clone();
    let mut out = vec![0u32; start[start.len() - 1]];
    for (i, &r) in ranges.iter().enumerate() {
        for_each_leaf(r, |o| {
            let k = slot[cell(o)] as usize;
            out[next[k]] = i as u32;
            next[k] += 1;
        });
    }
    Some((leaves, Bins { start, photons: out }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::rng;
    use rand::Rng;

    /// The dense binning gives the hashed path's leaves and bins: random
    /// segments and points with a reach per photon, including negative
    /// coordinates and leaves shared by many photons.
    #[test]
    fn dense_bins_equal_hashed_bins() {
        let mut r = rng::rng(&[91]);
        let photons: Vec<Photon> = (0..3000)
            .map(|i| {
                let a: [f32; 3] = std::array::from_fn(|_| r.random_range(-20.0f32..15.0));
                if i % 3 == 0 {
                    Photon::point(a, [1.0; 3])
                } else {
                    let b = std::array::from_fn(|k| a[k] + r.random_range(-2.0f32..2.0));
                    Photon::segment(a, b, [1.0; 3])
                }
            })
            .collect();
        let reach: Vec<f64> = (0..photons.len()).map(|_| r.random_range(0.2..2.5)).collect();
        for vs in [0.25, 0.5, 1.3] {
            let leaves = candidate_leaves_by(&photons, vs, |i| reach[i]);
            let bins = bin_photons_by(&photons, &leaves, vs, |i| reach[i]);
            let (dl, db) = bin_photons_dense(&photons, vs, |i| reach[i]).unwrap();
            assert_eq!(dl, leaves, "voxel {vs}");
            assert_eq!(db, bins, "voxel {vs}");
        }
        let (l, b) = bin_photons_dense(&[], 0.5, |_| 1.0).unwrap();
        assert!(l.is_empty() && b.photons.is_empty() && b.start == [0]);
    }
}
