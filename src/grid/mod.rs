//! Sparse voxel grid: the in-memory form of one OpenVDB grid.
//!
//! OpenVDB stores a grid as a 5-4-3 tree (root -> 32^3 internal -> 16^3 internal
//! -> 8^3 leaves). For a fog volume with no tiles, the only data are the leaves,
//! so we keep an equivalent *keyed map of leaves*: a `Vec<Leaf<T>>` plus a hash
//! index by leaf origin. The VDB writer (`crate::io::vdb::write`) regroups leaves
//! into the 5-4-3 hierarchy, sorted the way OpenVDB's `std::map` orders them.
//!
//! Conventions (OpenVDB's, and what Cycles uses; see
//! docs/guide.md, "How Cycles reads the VDB"):
//! - voxel (i, j, k) is centred at the *index point* (i, j, k): world position
//!   `voxel_size * (i, j, k) + translation`, no half-voxel offset;
//! - inactive voxels read as the background value;
//! - sampling is trilinear between the eight surrounding voxel centres, so a
//!   single active voxel influences exactly one voxel around its centre.
//!
//! The leaf and its mask operations are [`leaf`]; index-to-world is
//! [`transform`]; the high column's coarse grids are [`high_column`] and the
//! leaf-by-leaf reading interface shared with the file reader is
//! [`leaf_source`]. The grid knows nothing of the bake, the file format or
//! the renderer.

pub mod high_column;
pub mod leaf;
pub mod leaf_source;
pub mod transform;

pub use leaf::{
    dilate_mask, leaf_offset, leaf_origin, mask_bbox, offset_to_local, Leaf, VoxelValue, LEAF_DIM, LEAF_LOG2DIM, LEAF_MASK_WORDS,
    LEAF_NUM_VALUES,
};
pub use transform::Transform;

use glam::{DVec3, IVec3};
use std::collections::HashMap;

/// A multiplicative hash of leaf origins for the grids' leaf index and the
/// gather's binning (std's SipHash, built against flooding, cost more than
/// the lookups' other work): the coordinates mixed by rotation, xor and an
/// odd multiplier. Deterministic (no random state); only lookups use it,
/// never an iteration order.
#[derive(Default, Clone, Copy)]
pub struct OriginHasher(u64);

impl std::hash::Hasher for OriginHasher {
    #[inline]
    fn finish(&self) -> u64 {
        // The high bits are the well-mixed ones: fold them down for the
        // table's low-bit bucket index.
        self.0 ^ (self.0 >> 29)
    }
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    #[inline]
    fn write_i32(&mut self, i: i32) {
        self.write_u64(i as u32 as u64);
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(26) ^ i).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

/// A map keyed by leaf origin, hashed by [`OriginHasher`].
pub type OriginMap<V> = HashMap<IVec3, V, std::hash::BuildHasherDefault<OriginHasher>>;

/// A sparse grid of `T` with a name, a background value and a transform.
#[derive(Clone, Debug)]
pub struct Grid<T> {
    pub name: String,
    pub background: T,
    pub transform: Transform,
    leaves: Vec<Leaf<T>>,
    index: OriginMap<u32>,
}

impl<T: VoxelValue> PartialEq for Grid<T> {
    /// Two grids are equal when they hold the same active voxels with the same
    /// values, background, name and transform (leaf order does not matter).
    fn eq(&self, other: &Self) -> bool {
        if self.name != other.name
            || self.background != other.background
            || self.transform != other.transform
            || self.leaves.len() != other.leaves.len()
        {
            return false;
        }
        self.leaves.iter().all(|l| other.leaf(l.origin) == Some(l))
    }
}

impl Grid<[f32; 3]> {
    /// Component `k` of every voxel as a float grid named `name`, on the
    /// same transform, active where that component is nonzero (the
    /// emission's rule), in this grid's leaf order.
    pub fn component(&self, k: usize, name: impl Into<String>) -> Grid<f32> {
        let mut g = Grid::new(name, 0.0f32, self.transform);
        for l in &self.leaves {
            let mut out = Leaf::new(l.origin, 0.0f32);
            for n in 0..LEAF_NUM_VALUES {
                let v = l.values[n][k];
                if l.is_active(n) && v != 0.0 {
                    out.values[n] = v;
                    out.set_active(n, true);
                }
            }
            g.insert_leaf(out);
        }
        g
    }
}

impl<T: VoxelValue> Grid<T> {
    pub fn new(name: impl Into<String>, background: T, transform: Transform) -> Self {
        Self { name: name.into(), background, transform, leaves: Vec::new(), index: OriginMap::default() }
    }

    /// A grid of `leaves` (each inserted as [`Grid::insert_leaf`] does: a
    /// later leaf at the same origin replaces an earlier one, an empty leaf
    /// is dropped), sorted by origin ([`Grid::sort_leaves`]): the one order,
    /// whatever order the leaves came in.
    pub fn from_leaves(name: impl Into<String>, background: T, transform: Transform, leaves: impl IntoIterator<Item = Leaf<T>>) -> Self {
        let mut g = Self::new(name, background, transform);
        for l in leaves {
            g.insert_leaf(l);
        }
        g.sort_leaves();
        g
    }

    pub fn leaves(&self) -> &[Leaf<T>] {
        &self.leaves
    }
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }
    pub fn is_empty(&self) -> bool {
        self.active_voxel_count() == 0
    }

    /// The leaf with this origin, if stored.
    #[inline]
    pub fn leaf(&self, origin: IVec3) -> Option<&Leaf<T>> {
        self.index.get(&origin).map(|&i| &self.leaves[i as usize])
    }

    /// Adds a whole leaf. A leaf at the same origin is replaced. A leaf with no
    /// active voxel is not stored (the grid stays sparse).
    pub fn insert_leaf(&mut self, leaf: Leaf<T>) {
        if leaf.active_count() == 0 {
            if let Some(i) = self.index.remove(&leaf.origin) {
                self.remove_slot(i as usize);
            }
            return;
        }
        match self.index.get(&leaf.origin) {
            Some(&i) => self.leaves[i as usize] = leaf,
            None => {
                self.index.insert(leaf.origin, self.leaves.len() as u32);
                self.leaves.push(leaf);
            }
        }
    }

    fn remove_slot(&mut self, i: usize) {
        self.leaves.swap_remove(i);
        if i < self.leaves.len() {
            self.index.insert(self.leaves[i].origin, i as u32);
        }
    }

    /// Removes every leaf for which `keep` returns false.
    pub fn retain_leaves(&mut self, mut keep: impl FnMut(&Leaf<T>) -> bool) {
        self.leaves.retain(|l| keep(l));
        self.index = self.leaves.iter().enumerate().map(|(i, l)| (l.origin, i as u32)).collect();
    }

    /// Removes every leaf for which `keep` returns false and returns them,
    /// in the grid's leaf order: [`Self::retain_leaves`] that gives back what
    /// it drops, so the grid can be restored ([`Self::restore_leaves`])
    /// without keeping a copy of the whole.
    pub fn split_off_leaves(&mut self, mut keep: impl FnMut(&Leaf<T>) -> bool) -> Vec<Leaf<T>> {
        // In place: kept leaves move down only past dropped ones.
        let dropped = self.leaves.extract_if(.., |l| !keep(l)).collect();
        self.index = self.leaves.iter().enumerate().map(|(i, l)| (l.origin, i as u32)).collect();
        dropped
    }

    /// Puts back leaves taken by [`Self::split_off_leaves`] (origins not in
    /// the grid); leaves end sorted by origin.
    pub fn restore_leaves(&mut self, leaves: impl IntoIterator<Item = Leaf<T>>) {
        for l in leaves {
            self.insert_leaf(l);
        }
        self.sort_leaves();
    }

    /// Sets voxel `ijk` to `value` and marks it active.
    pub fn set(&mut self, ijk: IVec3, value: T) {
        let origin = leaf_origin(ijk);
        let i = match self.index.get(&origin) {
            Some(&i) => i as usize,
            None => {
                self.index.insert(origin, self.leaves.len() as u32);
                self.leaves.push(Leaf::new(origin, self.background));
                self.leaves.len() - 1
            }
        };
        let leaf = &mut self.leaves[i];
        let n = leaf_offset(ijk);
        leaf.values[n] = value;
        leaf.set_active(n, true);
    }

    /// Value of voxel `ijk`: its stored value if active, else the background.
    #[inline]
    pub fn get(&self, ijk: IVec3) -> T {
        match self.leaf(leaf_origin(ijk)) {
            Some(l) => {
                let n = leaf_offset(ijk);
                if l.is_active(n) {
                    l.values[n]
                } else {
                    self.background
                }
            }
            None => self.background,
        }
    }

    pub fn is_active(&self, ijk: IVec3) -> bool {
        self.leaf(leaf_origin(ijk)).is_some_and(|l| l.is_active(leaf_offset(ijk)))
    }

    pub fn active_voxel_count(&self) -> u64 {
        self.leaves.iter().map(Leaf::active_count).sum()
    }

    /// Inclusive index-space bounding box of the active voxels
    /// (OpenVDB's `file_bbox_min/max`), or `None` when nothing is active.
    pub fn index_bbox(&self) -> Option<(IVec3, IVec3)> {
        self.leaves
            .iter()
            .filter_map(|l| mask_bbox(&l.mask).map(|(lo, hi)| (l.origin + lo, l.origin + hi)))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// Active voxels as (index, value), leaf by leaf.
    pub fn iter_active(&self) -> impl Iterator<Item = (IVec3, T)> + '_ {
        self.leaves.iter().flat_map(Leaf::iter_active)
    }

    /// Trilinear interpolation at a continuous *index-space* point, voxel
    /// centres at integer coordinates.
    pub fn sample_index(&self, u: DVec3) -> T {
        let base = u.floor();
        let f = u - base;
        let i0 = base.as_ivec3();
        let v = |dx: i32, dy: i32, dz: i32| self.get(i0 + IVec3::new(dx, dy, dz));
        let x00 = T::lerp(v(0, 0, 0), v(1, 0, 0), f.x);
        let x10 = T::lerp(v(0, 1, 0), v(1, 1, 0), f.x);
        let x01 = T::lerp(v(0, 0, 1), v(1, 0, 1), f.x);
        let x11 = T::lerp(v(0, 1, 1), v(1, 1, 1), f.x);
        let y0 = T::lerp(x00, x10, f.y);
        let y1 = T::lerp(x01, x11, f.y);
        T::lerp(y0, y1, f.z)
    }

    /// Trilinear interpolation at a world position.
    pub fn sample_world(&self, p: DVec3) -> T {
        self.sample_index(self.transform.world_to_index(p))
    }

    /// The first active voxel whose value is NaN or infinite, if any.
    pub fn first_non_finite(&self) -> Option<(IVec3, T)> {
        self.iter_active().find(|(_, v)| !v.is_finite())
    }

    /// Switches on, with the background value, every inactive voxel in the
    /// 26-neighbourhood (faces, edges, corners) of an active voxel: OpenVDB's
    /// `tools::dilateActiveValues(tree, 1, NN_FACE_EDGE_VERTEX)`. Values of
    /// active voxels are unchanged. Returns the number of voxels switched on;
    /// leaves end sorted by origin.
    pub fn dilate_active(&mut self) -> u64 {
        use rayon::prelude::*;
        let bg = self.background;
        // Per leaf, in parallel: the dilated mask split into masks for the
        // leaf and its 26 neighbours ([`dilate_mask`]).
        let per_leaf: Vec<Vec<(IVec3, [u64; LEAF_MASK_WORDS])>> = self
            .leaves
            .par_iter()
            .map(|l| {
                let masks = dilate_mask(&l.mask);
                let mut out = Vec::new();
                for (slot, mask) in masks.iter().enumerate() {
                    if mask.iter().any(|&w| w != 0) {
                        let s = slot as i32;
                        let d = IVec3::new(s / 9 - 1, (s / 3) % 3 - 1, s % 3 - 1);
                        out.push((l.origin + d * LEAF_DIM, *mask));
                    }
                }
                out
            })
            .collect();
        // Apply in leaf order (deterministic whatever the thread count).
        let mut added = 0u64;
        for (origin, mask) in per_leaf.into_iter().flatten() {
            let i = match self.index.get(&origin) {
                Some(&i) => i as usize,
                None => {
                    self.index.insert(origin, self.leaves.len() as u32);
                    self.leaves.push(Leaf::new(origin, bg));
                    self.leaves.len() - 1
                }
            };
            added += self.leaves[i].switch_on(&mask, bg);
        }
        self.sort_leaves();
        added
    }

    /// Switches on, with the background value, every voxel active in
    /// `other` and inactive here, where this grid's active voxels are a
    /// subset of `other`'s: after `other.dilate_active()`, a grid on the
    /// same voxels as `other` was before gets the same dilation without
    /// computing it again (the density grid follows the emission's). Both
    /// grids' leaves sorted by origin (as [`Self::sort_leaves`] leaves
    /// them); one merge walk, leaves end sorted. Returns the number of
    /// voxels switched on.
    pub fn activate_like<U: VoxelValue>(&mut self, other: &Grid<U>) -> u64 {
        let bg = self.background;
        let mut own = std::mem::take(&mut self.leaves).into_iter().peekable();
        let mut leaves = Vec::with_capacity(other.leaves.len());
        let mut added = 0u64;
        for ol in &other.leaves {
            let mut leaf = match own.peek() {
                Some(l) if l.origin == ol.origin => own.next().expect("peeked"),
                _ => Leaf::new(ol.origin, bg),
            };
            added += leaf.switch_on(&ol.mask, bg);
            leaves.push(leaf);
        }
        assert!(own.next().is_none(), "activate_like: this grid's leaves must be a subset of the other's, both sorted");
        self.leaves = leaves;
        self.index = self.leaves.iter().enumerate().map(|(i, l)| (l.origin, i as u32)).collect();
        added
    }

    /// Sorts leaves by origin (x, then y, then z) so iteration order is
    /// independent of insertion order.
    pub fn sort_leaves(&mut self) {
        use rayon::prelude::*;
        // Origins are unique: an unstable sort gives the one order.
        self.leaves.par_sort_unstable_by_key(|l| (l.origin.x, l.origin.y, l.origin.z));
        self.index = self.leaves.iter().enumerate().map(|(i, l)| (l.origin, i as u32)).collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_and_bbox_match_brute_force_on_random_masks() {
        // Oracle for the word-wise dilation (dilate_mask) and the mask
        // bounding box: random voxels of varied densities in a few
        // neighbouring leaves (every face, edge and corner crossing occurs),
        // against the union of their 3x3x3 cubes and the min/max over them.
        use rand::Rng;
        let mut rng = crate::util::rng::rng(&[41]);
        for case in 0..40 {
            let mut g = Grid::new("d", 0.0f32, Transform::new(1.0, DVec3::ZERO));
            let p_on = [0.002, 0.02, 0.2, 0.9][case % 4];
            let mut seeds = Vec::new();
            for x in -8..16 {
                for y in -8..8 {
                    for z in 0..16 {
                        if rng.random::<f64>() < p_on {
                            seeds.push(IVec3::new(x, y, z));
                            g.set(IVec3::new(x, y, z), 1.0);
                        }
                    }
                }
            }
            let bb = seeds.iter().fold(None, |b: Option<(IVec3, IVec3)>, &p| Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p)))));
            assert_eq!(g.index_bbox(), bb, "case {case}");
            let mut want = std::collections::BTreeSet::new();
            for p in &seeds {
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            want.insert((p.x + dx, p.y + dy, p.z + dz));
                        }
                    }
                }
            }
            let mut h: Grid<[f32; 3]> = Grid::new("h", [2.0; 3], Transform::new(1.0, DVec3::ZERO));
            for p in &seeds {
                h.set(*p, [1.0; 3]);
            }
            h.sort_leaves();
            let added = g.dilate_active();
            let got: std::collections::BTreeSet<_> = g.iter_active().map(|(q, _)| (q.x, q.y, q.z)).collect();
            assert_eq!(got, want, "case {case}");
            assert_eq!(added as usize, want.len() - seeds.len());
            // The same dilation copied onto a grid on the same voxels.
            let mut h2 = h.clone();
            assert_eq!(h.activate_like(&g), added);
            assert_eq!(h2.dilate_active(), added);
            assert_eq!(h, h2, "case {case}");
            let (lh, lh2): (Vec<_>, Vec<_>) =
                (h.leaves().iter().map(|l| l.origin).collect(), h2.leaves().iter().map(|l| l.origin).collect());
            assert_eq!(lh, lh2);
        }
    }

    #[test]
    fn dilation_matches_brute_force_26_neighbourhood() {
        // Oracle: a set of voxels straddling leaf boundaries (negative
        // coordinates too); the dilated active set is exactly the union of
        // their 3x3x3 cubes, new voxels hold the background, old keep values.
        let mut g = Grid::new("d", -1.0f32, Transform::new(1.0, DVec3::ZERO));
        let seeds = [IVec3::new(0, 0, 0), IVec3::new(7, 7, 7), IVec3::new(-1, 8, 15), IVec3::new(20, -9, 3), IVec3::new(21, -9, 3)];
        for (i, &p) in seeds.iter().enumerate() {
            g.set(p, i as f32 + 1.0);
        }
        let mut want = std::collections::BTreeSet::new();
        for &p in &seeds {
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        want.insert((p.x + dx, p.y + dy, p.z + dz));
                    }
                }
            }
        }
        let added = g.dilate_active();
        let got: std::collections::BTreeSet<_> = g.iter_active().map(|(q, _)| (q.x, q.y, q.z)).collect();
        assert_eq!(got, want);
        assert_eq!(added as usize, want.len() - seeds.len());
        for (q, v) in g.iter_active() {
            match seeds.iter().position(|&p| p == q) {
                Some(i) => assert_eq!(v, i as f32 + 1.0),
                None => assert_eq!(v, -1.0, "new voxel {q} holds the background"),
            }
        }
        // Leaves sorted by origin.
        let origins: Vec<_> = g.leaves().iter().map(|l| (l.origin.x, l.origin.y, l.origin.z)).collect();
        let mut sorted = origins.clone();
        sorted.sort();
        assert_eq!(origins, sorted);
    }

    #[test]
    fn leaf_offset_round_trips_and_matches_openvdb_order() {
        for n in 0..LEAF_NUM_VALUES {
            assert_eq!(leaf_offset(offset_to_local(n)), n);
        }
        // x is the slowest axis: (1,0,0) -> 64, (0,1,0) -> 8, (0,0,1) -> 1.
        assert_eq!(leaf_offset(IVec3::new(1, 0, 0)), 64);
        assert_eq!(leaf_offset(IVec3::new(0, 1, 0)), 8);
        assert_eq!(leaf_offset(IVec3::new(0, 0, 1)), 1);
        // Negative coordinates wrap into their floor-aligned leaf.
        assert_eq!(leaf_origin(IVec3::new(-1, -8, -9)), IVec3::new(-8, -8, -16));
        assert_eq!(leaf_offset(IVec3::new(-1, 0, 0)), 7 << 6);
    }

    #[test]
    fn set_get_and_background() {
        let mut g = Grid::new("density", 0.0f32, Transform::new(1.0, DVec3::ZERO));
        g.set(IVec3::new(-3, 5, 17), 2.5);
        assert_eq!(g.get(IVec3::new(-3, 5, 17)), 2.5);
        assert_eq!(g.get(IVec3::new(-3, 5, 16)), 0.0);
        assert!(!g.is_active(IVec3::new(-3, 5, 16)));
        assert_eq!(g.active_voxel_count(), 1);
        assert_eq!(g.leaf_count(), 1);
        assert_eq!(g.index_bbox(), Some((IVec3::new(-3, 5, 17), IVec3::new(-3, 5, 17))));
    }

    #[test]
    fn single_voxel_trilinear_footprint_is_one_voxel_wide() {
        let s = 0.5;
        let t = DVec3::new(10.0, -2.0, 3.0);
        let mut g = Grid::new("density", 0.0f32, Transform::new(s, t));
        g.set(IVec3::new(4, 4, 4), 1.0);
        let c = t + DVec3::splat(4.0 * s);
        assert_eq!(g.sample_world(c), 1.0);
        // Half a voxel away along x: the tent function gives 1/2.
        assert!((g.sample_world(c + DVec3::new(0.5 * s, 0.0, 0.0)) - 0.5).abs() < 1e-6);
        // A full voxel away (or more) it is exactly zero.
        assert_eq!(g.sample_world(c + DVec3::new(s, 0.0, 0.0)), 0.0);
        assert_eq!(g.sample_world(c - DVec3::new(0.0, 1.01 * s, 0.0)), 0.0);
        // Separable: product of tents.
        let v = g.sample_world(c + DVec3::new(0.25 * s, -0.5 * s, 0.75 * s));
        assert!((v - 0.75 * 0.5 * 0.25).abs() < 1e-6);
    }

    #[test]
    fn trilinear_reproduces_linear_fields_exactly() {
        let mut g = Grid::new("e", [0.0f32; 3], Transform::new(1.0, DVec3::ZERO));
        let f = |p: IVec3| [p.x as f32 * 0.5 + 1.0, p.y as f32 - 2.0 * p.z as f32, 3.0];
        for x in -4..12 {
            for y in -4..12 {
                for z in -4..12 {
                    g.set(IVec3::new(x, y, z), f(IVec3::new(x, y, z)));
                }
            }
        }
        let u = DVec3::new(2.3, -1.7, 5.9);
        let v = g.sample_index(u);
        let expect = [u.x * 0.5 + 1.0, u.y - 2.0 * u.z, 3.0];
        for c in 0..3 {
            assert!((v[c] as f64 - expect[c]).abs() < 1e-5, "{v:?} vs {expect:?}");
        }
    }

    #[test]
    fn is_finite_checks_components_without_recursing() {
        assert!(VoxelValue::is_finite(&1.0f32) && !VoxelValue::is_finite(&f32::NAN));
        assert!(!VoxelValue::is_finite(&[0.0f32, f32::INFINITY, 0.0]));
        let mut g = Grid::new("e", [0.0f32; 3], Transform::new(1.0, DVec3::ZERO));
        g.set(IVec3::ZERO, [1.0, 2.0, 3.0]);
        assert!(g.first_non_finite().is_none());
    }

    #[test]
    fn empty_leaves_are_not_stored_and_equality_ignores_order() {
        let tr = Transform::new(1.0, DVec3::ZERO);
        let mut a = Grid::new("d", 0.0f32, tr);
        a.insert_leaf(Leaf::new(IVec3::ZERO, 0.0));
        assert_eq!(a.leaf_count(), 0);
        let mut b = a.clone();
        a.set(IVec3::new(1, 2, 3), 1.0);
        a.set(IVec3::new(100, 2, 3), 2.0);
        b.set(IVec3::new(100, 2, 3), 2.0);
        b.set(IVec3::new(1, 2, 3), 1.0);
        assert_eq!(a, b);
        b.set(IVec3::new(1, 2, 3), 1.5);
        assert_ne!(a, b);
        let whole = a.clone();
        let dropped = a.split_off_leaves(|l| l.origin.x > 50);
        assert_eq!((a.leaf_count(), dropped.len()), (1, 1));
        assert_eq!(a.get(IVec3::new(1, 2, 3)), 0.0);
        let mut restored = a.clone();
        restored.restore_leaves(dropped);
        assert_eq!(restored, whole);
        assert_eq!(restored.leaves().iter().map(|l| l.origin.x).collect::<Vec<_>>(), [0, 96], "sorted");
        a.retain_leaves(|l| l.origin.x > 50);
        assert_eq!(a.active_voxel_count(), 1);
        assert_eq!(a.get(IVec3::new(100, 2, 3)), 2.0);
    }
}
