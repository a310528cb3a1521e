//! Constants and node geometry of the OpenVDB file format, shared by the
//! writer ([`super::write`]) and the bounds-checked parser ([`super::parse`]).
//!
//! The tree is OpenVDB's standard 5-4-3 configuration (`tree/RootNode.h`,
//! `tree/InternalNode.h`, `tree/LeafNode.h`):
//!
//! | level      | `LOG2DIM` | slots        | child covers | node covers |
//! |------------|-----------|--------------|--------------|-------------|
//! | root       | -         | sorted map   | 4096^3       | everything  |
//! | Internal32 | 5         | 32^3 = 32768 | 128^3        | 4096^3      |
//! | Internal16 | 4         | 16^3 = 4096  | 8^3 (leaf)   | 128^3       |
//! | leaf       | 3         | 8^3 = 512    | 1 voxel      | 8^3         |
//!
//! Each level has exactly one offset function (OpenVDB `coordToOffset`) and
//! its inverse; the leaf's lives in `crate::grid` ([`crate::grid::leaf_offset`]).
//! The byte layout is OpenVDB's `writeTopology` / `writeBuffers`
//! (`tree/RootNode.h`, `InternalNode.h`, `LeafNode.h`, `io/Compression.h`).

use glam::IVec3;

/// `i64` magic number `0x56444220` ("VDB " read little-endian), OpenVDB
/// `OPENVDB_MAGIC`: bytes `20 42 44 56 00 00 00 00`.
pub const MAGIC: i64 = 0x5644_4220;
/// File format version written: what OpenVDB 10.x to 12.x write.
pub const FILE_VERSION: u32 = 224;
/// Oldest file version read: per-grid compression and the per-array
/// metadata byte (`OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION`).
pub const MIN_READ_VERSION: u32 = 222;
/// Newest file version read. 225 (OpenVDB 13, `OPENVDB_FILE_VERSION_HALF_GRID`)
/// only adds new grid types; float and vec3s grids are stored as in 224.
pub const MAX_READ_VERSION: u32 = 225;
/// Library version recorded in the header. Only compared against 6.1 by
/// readers; the bytes we write were checked against libopenvdb 10.0.1.
pub const LIBRARY_MAJOR: u32 = 10;
pub const LIBRARY_MINOR: u32 = 0;
/// Header length in bytes (magic 8, version 4, library 4+4, offsets flag 1, UUID 36).
pub const HEADER_LEN: usize = 57;
/// Length of the ASCII UUID in the header.
pub const UUID_LEN: usize = 36;

/// Per-grid compression flags (OpenVDB `io::COMPRESS_*`).
pub const COMPRESS_ZIP: u32 = 0x1;
pub const COMPRESS_ACTIVE_MASK: u32 = 0x2;
pub const COMPRESS_BLOSC: u32 = 0x4;

/// Suffix of the grid type name of a grid stored as half floats.
pub const HALF_FLOAT_SUFFIX: &str = "_HalfFloat";
/// Grid metadata key that switches a grid to half-float storage.
pub const META_HALF: &str = "is_saved_as_half_float";

/// The per-array metadata byte of a compressed-values record (OpenVDB
/// `io::NO_MASK_OR_INACTIVE_VALS` .. `io::NO_MASK_AND_ALL_VALS`): how the
/// inactive values of the array are rebuilt.
pub mod meta {
    /// No inactive values, or all equal +background.
    pub const NO_MASK_OR_INACTIVE_VALS: u8 = 0;
    /// All inactive values equal -background.
    pub const NO_MASK_AND_MINUS_BG: u8 = 1;
    /// All inactive values equal one stored value.
    pub const NO_MASK_AND_ONE_INACTIVE_VAL: u8 = 2;
    /// A selection mask chooses between -background (clear) and +background (set).
    pub const MASK_AND_NO_INACTIVE_VALS: u8 = 3;
    /// A selection mask chooses between one stored value (clear) and +background (set).
    pub const MASK_AND_ONE_INACTIVE_VAL: u8 = 4;
    /// A selection mask chooses between two stored values.
    pub const MASK_AND_TWO_INACTIVE_VALS: u8 = 5;
    /// All values are stored.
    pub const NO_MASK_AND_ALL_VALS: u8 = 6;
}

/// log2 of the voxels spanned per axis by a root child (5 + 4 + 3).
pub const ROOT_CHILD_LOG2: u32 = 12;

/// One internal-node level of the 5-4-3 tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InternalLevel {
    /// log2 of the slots per axis (OpenVDB `LOG2DIM`).
    pub log2dim: u32,
    /// log2 of the voxels per axis covered by one child (OpenVDB `ChildNodeType::TOTAL`).
    pub child_log2: u32,
}

impl InternalLevel {
    /// Slots in the node (OpenVDB `NUM_VALUES`).
    pub const fn num_values(self) -> usize {
        1 << (3 * self.log2dim)
    }
    /// 64-bit words in one of its masks.
    pub const fn mask_words(self) -> usize {
        self.num_values() / 64
    }
    /// log2 of the voxels per axis covered by the node (OpenVDB `TOTAL`).
    pub const fn total(self) -> u32 {
        self.log2dim + self.child_log2
    }
}

/// Internal node right below the root: 32^3 slots of 128^3 voxels.
pub const INTERNAL32: InternalLevel = InternalLevel { log2dim: 5, child_log2: 7 };
/// Internal node right above the leaves: 16^3 slots of 8^3 voxels.
pub const INTERNAL16: InternalLevel = InternalLevel { log2dim: 4, child_log2: 3 };

/// Slot of voxel `ijk` inside the node of `level` containing it
/// (OpenVDB `InternalNode::coordToOffset`):
/// `(((x & (DIM-1)) >> c) << 2L) | (((y & (DIM-1)) >> c) << L) | ((z & (DIM-1)) >> c)`.
#[inline]
fn internal_offset(level: InternalLevel, ijk: IVec3) -> usize {
    let m = (1i32 << level.total()) - 1;
    let c = level.child_log2;
    let l = level.log2dim;
    ((((ijk.x & m) >> c) << (2 * l)) | (((ijk.y & m) >> c) << l) | ((ijk.z & m) >> c)) as usize
}

/// Origin of the child in slot `n` of the node of `level` at `origin`: the
/// inverse of [`internal_offset`].
#[inline]
fn internal_child_origin(level: InternalLevel, origin: IVec3, n: usize) -> IVec3 {
    let n = n as i32;
    let l = level.log2dim;
    let m = (1i32 << l) - 1;
    let c = level.child_log2;
    origin + IVec3::new((n >> (2 * l)) << c, ((n >> l) & m) << c, (n & m) << c)
}

/// Origin of the root child (an Internal32 node) holding voxel `ijk`:
/// `ijk & ~4095`, floor-aligned so it can be negative. The root keeps its
/// children in a `std::map<Coord>`, i.e. sorted by signed (x, y, z).
#[inline]
pub fn root_child_origin(ijk: IVec3) -> IVec3 {
    let m = !((1i32 << ROOT_CHILD_LOG2) - 1);
    IVec3::new(ijk.x & m, ijk.y & m, ijk.z & m)
}

/// Slot of voxel `ijk` in its Internal32 node.
#[inline]
pub fn internal32_offset(ijk: IVec3) -> usize {
    internal_offset(INTERNAL32, ijk)
}

/// Origin of the Internal16 child in slot `n` of the Internal32 node at `origin`.
#[inline]
pub fn internal32_child_origin(origin: IVec3, n: usize) -> IVec3 {
    internal_child_origin(INTERNAL32, origin, n)
}

/// Slot of voxel `ijk` in its Internal16 node.
#[inline]
pub fn internal16_offset(ijk: IVec3) -> usize {
    internal_offset(INTERNAL16, ijk)
}

/// Origin of the leaf in slot `n` of the Internal16 node at `origin`.
#[inline]
pub fn internal16_child_origin(origin: IVec3, n: usize) -> IVec3 {
    internal_child_origin(INTERNAL16, origin, n)
}

/// Whether bit `n` of a mask stored as little-endian `u64` words is set
/// (OpenVDB `util::NodeMask`: bit n is word `n >> 6`, bit `n & 63`).
#[inline]
pub fn mask_bit(mask: &[u64], n: usize) -> bool {
    mask[n >> 6] >> (n & 63) & 1 == 1
}

/// Sets bit `n` of a mask.
#[inline]
pub fn set_mask_bit(mask: &mut [u64], n: usize) {
    mask[n >> 6] |= 1 << (n & 63);
}

/// Number of set bits of a mask.
#[inline]
pub fn mask_count(mask: &[u64]) -> usize {
    mask.iter().map(|w| w.count_ones() as usize).sum()
}

/// Indices of the set bits of a mask, ascending.
pub fn mask_ones(mask: &[u64]) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(w, &word)| {
        let mut bits = word;
        std::iter::from_fn(move || {
            if bits == 0 {
                return None;
            }
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            Some(w * 64 + b)
        })
    })
}

/// OpenVDB's `io::compressionToString`, written as `file_compression` metadata.
pub fn compression_name(flags: u32) -> String {
    if flags == 0 {
        return "none".into();
    }
    let mut parts = Vec::new();
    if flags & COMPRESS_ZIP != 0 {
        parts.push("zip");
    }
    if flags & COMPRESS_BLOSC != 0 {
        parts.push("blosc");
    }
    if flags & COMPRESS_ACTIVE_MASK != 0 {
        parts.push("active values");
    }
    parts.join(" + ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{leaf_offset, leaf_origin, offset_to_local};

    /// Every slot of each level maps to a child origin whose offset is that slot,
    /// and every voxel of a child maps to the child's slot.
    #[test]
    fn internal_offsets_round_trip() {
        let origins = [IVec3::ZERO, IVec3::new(-4096, 4096, -8192), IVec3::new(8192, -4096, 0)];
        for &o in &origins {
            for n in 0..INTERNAL32.num_values() {
                let c = internal32_child_origin(o, n);
                assert_eq!(internal32_offset(c), n);
                assert_eq!(internal32_offset(c + IVec3::splat(127)), n);
                assert_eq!(root_child_origin(c), o);
            }
            let o16 = internal32_child_origin(o, 12345);
            for n in 0..INTERNAL16.num_values() {
                let c = internal16_child_origin(o16, n);
                assert_eq!(internal16_offset(c), n);
                assert_eq!(internal16_offset(c + IVec3::splat(7)), n);
                assert_eq!(internal32_offset(c), 12345);
                assert_eq!(leaf_origin(c), c);
            }
        }
    }

    /// Hand-derived slots: x is the slowest axis at every level.
    #[test]
    fn offsets_match_openvdb_formula() {
        assert_eq!(internal32_offset(IVec3::new(128, 0, 0)), 1 << 10);
        assert_eq!(internal32_offset(IVec3::new(0, 128, 0)), 1 << 5);
        assert_eq!(internal32_offset(IVec3::new(0, 0, 128)), 1);
        assert_eq!(internal16_offset(IVec3::new(8, 0, 0)), 1 << 8);
        assert_eq!(internal16_offset(IVec3::new(0, 8, 0)), 1 << 4);
        assert_eq!(internal16_offset(IVec3::new(0, 0, 8)), 1);
        // -1 lies in the last slot of the node below the origin.
        assert_eq!(root_child_origin(IVec3::new(-1, 0, 4095)), IVec3::new(-4096, 0, 0));
        assert_eq!(internal32_offset(IVec3::new(-1, 0, 0)), 31 << 10);
        assert_eq!(internal16_offset(IVec3::new(0, -1, 0)), 15 << 4);
        for n in [0, 1, 63, 64, 511] {
            assert_eq!(leaf_offset(offset_to_local(n)), n);
        }
    }

    #[test]
    fn masks_and_names() {
        let mut m = [0u64; 8];
        for n in [0, 5, 63, 64, 200, 511] {
            set_mask_bit(&mut m, n);
        }
        assert_eq!(mask_ones(&m).collect::<Vec<_>>(), vec![0, 5, 63, 64, 200, 511]);
        assert_eq!(mask_count(&m), 6);
        assert!(mask_bit(&m, 200) && !mask_bit(&m, 201));
        assert_eq!(compression_name(0), "none");
        assert_eq!(compression_name(3), "zip + active values");
        assert_eq!(compression_name(6), "blosc + active values");
        assert_eq!(compression_name(2), "active values");
    }
}
