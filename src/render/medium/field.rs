//! A field: one or more scalar channels on one grid transform, stored as
//! blocks of values under a tree of dual leaves, and its lookup.
//!
//! The values are stored once per source leaf (a *block* of 8^3 voxels,
//! every channel interleaved, as stored in the grid: the volume scales are
//! applied at lookup, [`Field::scale`]); block 0 is all zeros. Each dual
//! leaf holds the block numbers of its own leaf and its seven upper
//! neighbours (0 where absent), so a dual cell finds its 8 corners with no
//! hash lookup: in its own block for cells with every local coordinate
//! below 7 (343 of 512), else across the neighbours' faces
//! ([`Field::corner_indices`]).
//!
//! The dual leaves hang from a tree like OpenVDB's 5-4-3 (and
//! `VolumeHDDA`'s): blocks of 16^3 dual leaves (128 voxels), super nodes of
//! 32^3 blocks (4096 voxels), found by a hash map at the root ([`Tree`];
//! geometry in `layout.rs`). Children are dense `u32` index arrays
//! ([`NONE`] = empty), so memory and build time scale with the number of
//! occupied leaves, never with the bounding box; the walk (`dda.rs`) costs
//! a few root steps per 4096 voxels of empty space.

use super::layout::{block_offset, shr, slot, CellMask, BLOCK_LOG2, BLOCK_SLOTS, CORNER_OFFSETS, NONE, SUPER_LOG2, SUPER_SLOTS};
use super::values::Values;
use crate::grid::{Transform, LEAF_DIM, LEAF_LOG2DIM, LEAF_NUM_VALUES};
use glam::{DVec3, IVec3};
use std::collections::HashMap;

/// One or more scalar fields on one grid transform, as blocks and dual leaves.
///
/// Channel `c` of voxel `(x,y,z)` of block `b` is
/// `scale[c] * values.get((b * LEAF_NUM_VALUES + block_offset(x, y, z)) * channels + c)`
/// (half floats' bits or `f32`s: `values.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub transform: Transform,
    pub channels: usize,
    /// Dual-leaf keys (index origin / 8), in ascending (x, y, z) order.
    pub keys: Vec<IVec3>,
    /// Blocks of the stored (unit) values; block 0 is all zeros.
    pub values: Values,
    /// Per dual leaf `D`: the block of source leaf `D + (dx,dy,dz)` at
    /// `dx << 2 | dy << 1 | dz` (0 where that leaf has no non-zero voxel).
    pub neighbours: Vec<[u32; 8]>,
    /// Per dual leaf: cells where channel 0 is not identically 0.
    pub mask_first: Vec<CellMask>,
    /// Per dual leaf: cells where some channel is not identically 0.
    pub mask_any: Vec<CellMask>,
    pub(crate) blocks: Vec<Box<[u32; BLOCK_SLOTS]>>,
    pub(crate) supers: Vec<Box<[u32; SUPER_SLOTS]>>,
    pub(crate) root: HashMap<IVec3, u32>,
    /// Per super node: the index-space box of its dual leaves (voxel units),
    /// so a ray is clipped to what is occupied, not to the node's 4096^3.
    pub(crate) super_bounds: Vec<(IVec3, IVec3)>,
    /// Index-space box covered by the dual leaves, in voxel units: `[lo, hi]`.
    pub lo: IVec3,
    pub hi: IVec3,
    /// Super-node coordinates spanned by the root: `[root_lo, root_hi)`.
    pub(crate) root_lo: IVec3,
    pub(crate) root_hi: IVec3,
    /// Per channel, the factor its stored (unit) values are multiplied by
    /// at lookup ([`Medium::set_scales`]).
    pub scale: [f64; 4],
    /// Blocks written (the others are all zeros and never touched).
    pub(super) live_blocks: usize,
    /// Origin (index space) of the source leaf of block `b` at `b - 1`.
    pub block_origins: Vec<IVec3>,
}

/// The tree over a field's dual leaves: the root's map of super nodes, the
/// super nodes' blocks, the blocks' dual-leaf slots, and the boxes a ray is
/// clipped to (as in [`Field`]).
pub(super) struct Tree {
    pub(super) blocks: Vec<Box<[u32; BLOCK_SLOTS]>>,
    pub(super) supers: Vec<Box<[u32; SUPER_SLOTS]>>,
    pub(super) root: HashMap<IVec3, u32>,
    pub(super) super_bounds: Vec<(IVec3, IVec3)>,
    pub(super) lo: IVec3,
    pub(super) hi: IVec3,
    pub(super) root_lo: IVec3,
    pub(super) root_hi: IVec3,
}

impl Tree {
    /// The tree whose dual leaf `i` has key `keys[i]` (keys distinct).
    pub(super) fn new(keys: &[IVec3]) -> Tree {
        let mut blocks: Vec<Box<[u32; BLOCK_SLOTS]>> = Vec::new();
        let mut supers: Vec<Box<[u32; SUPER_SLOTS]>> = Vec::new();
        let mut root: HashMap<IVec3, u32> = HashMap::new();
        let mut super_bounds: Vec<(IVec3, IVec3)> = Vec::new();
        let (mut lo, mut hi) = (IVec3::MAX, IVec3::MIN);
        for (i, &k) in keys.iter().enumerate() {
            lo = lo.min(k);
            hi = hi.max(k);
            let b = shr(k, BLOCK_LOG2);
            let s = shr(b, SUPER_LOG2);
            let si = *root.entry(s).or_insert_with(|| {
                supers.push(Box::new([NONE; SUPER_SLOTS]));
                super_bounds.push((IVec3::MAX, IVec3::MIN));
                (supers.len() - 1) as u32
            });
            let sb = &mut super_bounds[si as usize];
            *sb = (sb.0.min(k * LEAF_DIM), sb.1.max((k + IVec3::ONE) * LEAF_DIM));
            let sup = &mut supers[si as usize];
            let bs = slot(b, SUPER_LOG2);
            if sup[bs] == NONE {
                blocks.push(Box::new([NONE; BLOCK_SLOTS]));
                sup[bs] = (blocks.len() - 1) as u32;
            }
            blocks[sup[bs] as usize][slot(k, BLOCK_LOG2)] = i as u32;
        }
        let (lo, hi, root_lo, root_hi) = if keys.is_empty() {
            (IVec3::ZERO, IVec3::ZERO, IVec3::ZERO, IVec3::ZERO)
        } else {
            (lo * LEAF_DIM, (hi + IVec3::ONE) * LEAF_DIM, shr(lo, BLOCK_LOG2 + SUPER_LOG2), shr(hi, BLOCK_LOG2 + SUPER_LOG2) + IVec3::ONE)
        };
        Tree { blocks, supers, root, super_bounds, lo, hi, root_lo, root_hi }
    }
}

impl Field {
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    pub fn leaf_count(&self) -> usize {
        self.keys.len()
    }

    /// Blocks holding a non-zero voxel (the others are all zeros).
    pub fn live_blocks(&self) -> usize {
        self.live_blocks
    }

    /// Bytes held by the structure (for reports).
    pub fn memory_bytes(&self) -> usize {
        (self.live_blocks + 1) * LEAF_NUM_VALUES * self.channels * Values::value_bytes(self.values.is_half())
            + self.keys.len() * (12 + 32 + 128)
            + self.blocks.len() * BLOCK_SLOTS * 4
            + self.supers.len() * SUPER_SLOTS * 4
            + self.root.len() * (24 + 24)
    }

    /// Index of the dual leaf with key `k`, if stored.
    #[inline]
    pub fn find_leaf(&self, k: IVec3) -> Option<u32> {
        let b = shr(k, BLOCK_LOG2);
        let s = shr(b, SUPER_LOG2);
        let si = *self.root.get(&s)?;
        let bi = self.supers[si as usize][slot(b, SUPER_LOG2)];
        if bi == NONE {
            return None;
        }
        let li = self.blocks[bi as usize][slot(k, BLOCK_LOG2)];
        (li != NONE).then_some(li)
    }

    /// Start (in `values`, channel 0) of each of the 8 corners of dual cell
    /// `(x,y,z)` (each in 0..8) of dual leaf `leaf`, in [`CORNER_OFFSETS`]'
    /// order.
    #[inline(always)]
    pub fn corner_indices(&self, leaf: u32, x: usize, y: usize, z: usize) -> [usize; 8] {
        let nb = &self.neighbours[leaf as usize];
        let c = self.channels;
        if x < 7 && y < 7 && z < 7 {
            let base = nb[0] as usize * LEAF_NUM_VALUES + block_offset(x, y, z);
            return CORNER_OFFSETS.map(|o| (base + o) * c);
        }
        std::array::from_fn(|k| {
            let (cx, cy, cz) = (x + (k >> 2), y + (k >> 1 & 1), z + (k & 1));
            let d = (cx >> 3) << 2 | (cy >> 3) << 1 | cz >> 3;
            (nb[d] as usize * LEAF_NUM_VALUES + block_offset(cx & 7, cy & 7, cz & 7)) * c
        })
    }

    /// Trilinear value of every channel at index-space point `u` (voxel
    /// centres at integers; 0 outside the stored dual leaves). Written
    /// independently of `Grid::sample_index` but equal to it.
    pub fn sample_index(&self, u: DVec3, out: &mut [f64]) {
        out[..self.channels].fill(0.0);
        let base = u.floor();
        if !base.is_finite() || base.abs().max_element() > (i32::MAX / 2) as f64 {
            return;
        }
        let c = base.as_ivec3();
        let Some(leaf) = self.find_leaf(shr(c, LEAF_LOG2DIM)) else { return };
        let l = c - shr(c, LEAF_LOG2DIM) * LEAF_DIM;
        let f = u - base;
        let at = self.corner_indices(leaf, l.x as usize, l.y as usize, l.z as usize);
        let w = [
            (1.0 - f.x) * (1.0 - f.y) * (1.0 - f.z),
            (1.0 - f.x) * (1.0 - f.y) * f.z,
            (1.0 - f.x) * f.y * (1.0 - f.z),
            (1.0 - f.x) * f.y * f.z,
            f.x * (1.0 - f.y) * (1.0 - f.z),
            f.x * (1.0 - f.y) * f.z,
            f.x * f.y * (1.0 - f.z),
            f.x * f.y * f.z,
        ];
        for (k, &i) in at.iter().enumerate() {
            for ch in 0..self.channels {
                out[ch] += w[k] * self.values.get(i + ch) as f64;
            }
        }
        for ch in 0..self.channels {
            out[ch] *= self.scale[ch];
        }
    }

    /// World-space box of the stored dual leaves (the support of the field).
    pub fn world_bounds(&self) -> (DVec3, DVec3) {
        (self.transform.index_to_world(self.lo.as_dvec3()), self.transform.index_to_world(self.hi.as_dvec3()))
    }
}
