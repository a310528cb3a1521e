//! The tree's topology, as OpenVDB writes it (`tree/RootNode.h`,
//! `tree/InternalNode.h`, `tree/LeafNode.h`, `writeTopology`): the root's
//! background and tiles, then depth first each 32^3 and 16^3 internal node's
//! child and value masks with its tile values, then each 8^3 leaf's value
//! mask. The leaves' values follow separately (`writeBuffers`).

use super::codec::{self, Encoder, Storage};
use super::layout::{self, INTERNAL16, INTERNAL32};
use super::mantissa;
use crate::grid::{Grid, Leaf, VoxelValue};
use glam::IVec3;

/// A grid's leaves regrouped into the 5-4-3 tree, in file order.
pub(super) struct Tree<'g, T> {
    pub(super) roots: Vec<RootChild>,
    /// Leaves in depth-first file order.
    pub(super) leaves: Vec<&'g Leaf<T>>,
}

/// A root child: an Internal32 node and its Internal16 children.
pub(super) struct RootChild {
    pub(super) origin: IVec3,
    pub(super) child_mask: Vec<u64>,
    pub(super) nodes: Vec<Node16>,
}

/// An Internal16 node: its child mask and the range of its leaves in `Tree::leaves`.
pub(super) struct Node16 {
    pub(super) child_mask: Vec<u64>,
    pub(super) leaves: std::ops::Range<usize>,
}

/// Regroups leaves: sort by (root origin x, y, z, Internal32 slot, Internal16
/// slot), which is exactly the depth-first order of OpenVDB's tree.
pub(super) fn build_tree<T: VoxelValue>(grid: &Grid<T>) -> Tree<'_, T> {
    // (root origin x, y, z, Internal32 slot, Internal16 slot)
    type Key = (i32, i32, i32, u32, u32);
    let mut keyed: Vec<(Key, &Leaf<T>)> = grid
        .leaves()
        .iter()
        .map(|l| {
            let r = layout::root_child_origin(l.origin);
            ((r.x, r.y, r.z, layout::internal32_offset(l.origin) as u32, layout::internal16_offset(l.origin) as u32), l)
        })
        .collect();
    keyed.sort_unstable_by_key(|(k, _)| *k);
    let mut roots: Vec<RootChild> = Vec::new();
    for (i, ((rx, ry, rz, s32, s16), _)) in keyed.iter().enumerate() {
        let origin = IVec3::new(*rx, *ry, *rz);
        if roots.last().is_none_or(|r| r.origin != origin) {
            roots.push(RootChild { origin, child_mask: vec![0; INTERNAL32.mask_words()], nodes: Vec::new() });
        }
        let root = roots.last_mut().expect("just pushed");
        let new16 = !layout::mask_bit(&root.child_mask, *s32 as usize);
        if new16 {
            layout::set_mask_bit(&mut root.child_mask, *s32 as usize);
            root.nodes.push(Node16 { child_mask: vec![0; INTERNAL16.mask_words()], leaves: i..i });
        }
        let node = root.nodes.last_mut().expect("just pushed");
        layout::set_mask_bit(&mut node.child_mask, *s16 as usize);
        node.leaves.end = i + 1;
    }
    Tree { roots, leaves: keyed.into_iter().map(|(_, l)| l).collect() }
}

/// Root node topology (OpenVDB `RootNode::writeTopology`): background (rounded
/// to half in half mode, stored full), tile count 0, child count, then each
/// child's origin and Internal32 topology in ascending (x, y, z) order.
/// An internal node's topology (OpenVDB `InternalNode::writeTopology`) is
/// its node record ([`write_internal_node`]), then each child's topology in
/// slot order: an Internal32's Internal16 nodes, an Internal16's leaves.
pub(super) fn write_root_topology<T: VoxelValue>(out: &mut Vec<u8>, tree: &Tree<T>, bg: T, flags: u32, st: Storage) {
    out.extend_from_slice(&1i32.to_le_bytes()); // buffer count
    codec::push_full(out, if st.half { codec::round_half_value(bg) } else { bg });
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&(tree.roots.len() as u32).to_le_bytes());
    // Internal nodes hold the background and zeros: stored exactly.
    let mut enc = Encoder::new(flags, Storage { mantissa_bits: mantissa::FLOAT_MANTISSA_BITS, ..st });
    let mut cache = InternalCache::default();
    for root in &tree.roots {
        for c in root.origin.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        write_internal_node(out, INTERNAL32, &root.child_mask, bg, &mut enc, &mut cache.level32);
        for node in &root.nodes {
            write_internal_node(out, INTERNAL16, &node.child_mask, bg, &mut enc, &mut cache.level16);
            for leaf in &tree.leaves[node.leaves.clone()] {
                write_leaf_topology(out, leaf);
            }
        }
    }
}

/// Records of internal nodes whose value arrays are all zero bits (child
/// slots hold 0, tiles the background +0): identical for every node of a
/// level, so encoded once.
#[derive(Default)]
pub(super) struct InternalCache {
    pub(super) level32: Option<Vec<u8>>,
    pub(super) level16: Option<Vec<u8>>,
}

/// An internal node's record: its child mask, its value mask (empty), and
/// its value record, whose slot n holds the tile value (here the
/// background, inactive) or 0 for child slots.
pub(super) fn write_internal_node<T: VoxelValue>(
    out: &mut Vec<u8>,
    level: layout::InternalLevel,
    child_mask: &[u64],
    bg: T,
    enc: &mut Encoder,
    cached: &mut Option<Vec<u8>>,
) {
    let value_mask = vec![0u64; level.mask_words()];
    write_mask(out, child_mask);
    write_mask(out, &value_mask);
    let zero_bits = bg.components().iter().all(|x| x.to_bits() == 0);
    if zero_bits {
        if let Some(c) = cached {
            out.extend_from_slice(c);
            return;
        }
    }
    let values: Vec<T> = (0..level.num_values()).map(|n| if layout::mask_bit(child_mask, n) { T::ZERO } else { bg }).collect();
    let start = out.len();
    enc.write_values(out, &values, &value_mask, Some(child_mask), bg);
    if zero_bits {
        *cached = Some(out[start..].to_vec());
    }
}

/// Leaf topology (OpenVDB `LeafNode::writeTopology`): the value mask only.
pub(super) fn write_leaf_topology<T: VoxelValue>(out: &mut Vec<u8>, leaf: &Leaf<T>) {
    write_mask(out, &leaf.mask);
}

pub(super) fn write_mask(out: &mut Vec<u8>, mask: &[u64]) {
    for w in mask {
        out.extend_from_slice(&w.to_le_bytes());
    }
}
