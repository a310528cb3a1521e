//! The medium's tree geometry: node levels, slot and offset functions, and
//! the bit layout of the 512-bit voxel and cell masks.
//!
//! Like OpenVDB's 5-4-3 tree (`tree/LeafNode.h`, `tree/InternalNode.h`),
//! with the renderer's names:
//!
//! | level     | log2 per axis             | children         | node covers |
//! |-----------|---------------------------|------------------|-------------|
//! | root      | -                         | hash map         | everything  |
//! | super     | [`SUPER_LOG2`] = 5        | 32^3 blocks      | 4096^3      |
//! | block     | [`BLOCK_LOG2`] = 4        | 16^3 dual leaves | 128^3       |
//! | dual leaf | `grid::LEAF_LOG2DIM` = 3  | 8^3 dual cells   | 8^3         |
//!
//! A dual leaf has the edge of a grid leaf (`crate::grid::LEAF_LOG2DIM`):
//! dual leaf `D` covers index space `[8D, 8D + 8]^3`. Every slot order is
//! OpenVDB's `coordToOffset` (x slowest, z fastest), so a leaf's 512
//! voxels, a dual leaf's 512 cells and their masks' bits share one order:
//! bit `n = x << 6 | y << 3 | z` is bit `n & 63` of word `x`.

use crate::grid::{LEAF_LOG2DIM, LEAF_MASK_WORDS};
use glam::IVec3;

/// Empty child slot.
pub const NONE: u32 = u32::MAX;
/// log2 of the block edge in dual leaves (OpenVDB InternalNode<.,4>).
pub const BLOCK_LOG2: u32 = 4;
/// log2 of the super-node edge in blocks (OpenVDB InternalNode<.,5>).
pub const SUPER_LOG2: u32 = 5;
/// log2 of a block edge in voxels (128).
pub const BLOCK_VOXELS_LOG2: u32 = LEAF_LOG2DIM + BLOCK_LOG2;
/// log2 of a super-node edge in voxels (4096).
pub const SUPER_VOXELS_LOG2: u32 = BLOCK_VOXELS_LOG2 + SUPER_LOG2;

pub(super) const BLOCK_SLOTS: usize = 1 << (3 * BLOCK_LOG2);
pub(super) const SUPER_SLOTS: usize = 1 << (3 * SUPER_LOG2);

/// Offsets (in values of one channel) of the 8 corners of a dual cell from its
/// (0,0,0) corner within one block, for a cell whose corners all lie in it,
/// in the order (x,y,z) = 000, 001, 010, 011, 100, 101, 110, 111 (corner `k`
/// is `(k >> 2, k >> 1 & 1, k & 1)`).
pub const CORNER_OFFSETS: [usize; 8] = [0, 1, 8, 9, 64, 65, 72, 73];

/// Offset of voxel (x,y,z), each in 0..8, within one block (OpenVDB's
/// `coordToOffset`).
#[inline]
pub fn block_offset(x: usize, y: usize, z: usize) -> usize {
    (x << 6) | (y << 3) | z
}

/// Bit of dual cell (x,y,z), each in 0..8, in a dual leaf's cell mask
/// (same order as OpenVDB's `coordToOffset`).
#[inline]
pub fn cell_bit(x: i32, y: i32, z: i32) -> usize {
    ((x << 6) | (y << 3) | z) as usize
}

/// Slot of a child with coordinates `c` (in child units) in a node of
/// `2^log2` children per axis.
#[inline]
pub fn slot(c: IVec3, log2: u32) -> usize {
    let m = (1 << log2) - 1;
    (((c.x & m) << (2 * log2)) | ((c.y & m) << log2) | (c.z & m)) as usize
}

#[inline]
pub(super) fn shr(c: IVec3, n: u32) -> IVec3 {
    IVec3::new(c.x >> n, c.y >> n, c.z >> n)
}

/// A 512-bit set of a dual leaf's cells (or of a leaf's voxels), in the
/// bit order above.
pub type CellMask = [u64; LEAF_MASK_WORDS];

#[inline]
pub fn mask_has(m: &CellMask, bit: usize) -> bool {
    (m[bit >> 6] >> (bit & 63)) & 1 == 1
}

/// Bits of a leaf's 64-voxel mask word with local z = 0 (`n & 7 == 0`).
pub(super) const Z0_BITS: u64 = 0x0101_0101_0101_0101;
/// Bits of a mask word with local y = 0 (`(n >> 3) & 7 == 0`).
pub(super) const Y0_BITS: u64 = 0xff;
/// Bits of a mask word with local z = 7.
pub(super) const Z7_BITS: u64 = 0x8080_8080_8080_8080;
