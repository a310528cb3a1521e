//! The renderer's plain-data view of the volume: sigma_t and emission laid out
//! for fast, exact sampling along rays, built once per render.
//!
//! # Dual leaves
//! Cycles (like OpenVDB's `BoxSampler`) samples a grid trilinearly between the
//! eight voxel centres around a point; voxel (i,j,k) sits at index point
//! (i,j,k) and inactive voxels read as 0 (`../shared/notes/cycles-conventions.md`).
//! So the field is a trilinear polynomial inside each *dual cell* `[i,i+1] x
//! [j,j+1] x [k,k+1]` of index space. We group dual cells into *dual leaves* of
//! 8^3 cells: dual leaf `D` covers index space `[8D, 8D+8]^3` and needs the 9^3
//! voxel values `8D .. 8D+8`: its own 8^3 leaf plus the faces, edges and
//! corner of its three upper neighbours. A dual leaf exists iff one of its
//! 9^3 voxels is active and non-zero, so the field is exactly 0 outside the
//! stored dual leaves: a single active voxel creates the 8 dual leaves (or
//! fewer) around it, and its tent-shaped footprint reaches exactly one voxel
//! past its centre.
//!
//! # Blocks
//! The values are stored once, per source leaf (a *block* of 8^3 voxels,
//! every channel interleaved, as stored in the grid: the volume scales are
//! applied at lookup, [`Field::scale`]), and written only for leaves with a
//! non-zero active voxel; block 0 is all zeros. Each dual leaf holds the block numbers
//! of its own leaf and its seven upper neighbours (0 where absent), so a
//! dual cell finds its 8 corners with no hash lookup: in its own block for
//! cells with every local coordinate below 7 (343 of 512), else across the
//! neighbours' faces. Earlier versions copied 9^3 "ghost" values per dual
//! leaf; on the default bake (48.6 k dual leaves over 38.3 k source leaves)
//! that was 567 MB against 314 MB now, and the copy dominated the build.
//!
//! # Hierarchy (for empty-space skipping)
//! Like OpenVDB's 5-4-3 tree (and `VolumeHDDA`), the dual leaves hang from
//! `Block`s of 16^3 dual leaves (128 voxels) and those from `Super` nodes of
//! 32^3 blocks (4096 voxels), found by a hash map at the root. Children are
//! dense `u32` index arrays (`NONE` = empty). Memory and build time scale with
//! the number of occupied leaves, never with the bounding-box volume; the walk
//! (`dda.rs`) costs a few root steps per 4096 voxels of empty space.
//!
//! # Construction
//! One parallel pass over the union of the sources' leaves
//! ([`LeafSource`]: a grid in memory, or a VDB file's records decoded on
//! demand), each leaf read into a per-thread buffer, checked (finite,
//! >= 0) and its largest value taken on the floats' bits, then, if some
//! source has a non-zero voxel there, copied into its block of one array
//! allocated up front, its non-zero voxels and the dual leaves it feeds
//! taken in the same loop. Blocks are numbered by the union of the leaves,
//! so a grid read from a file and the same grid in memory give the same
//! medium, field for field.
//!
//! The structure is plain data: no references into the source grids.

use crate::grid::{Grid, Transform, VoxelValue, LEAF_DIM, LEAF_MASK_WORDS};
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use std::collections::HashMap;

use super::RenderError;

/// Values per channel of a block (one source leaf).
pub const BLOCK_VALUES: usize = crate::grid::LEAF_NUM_VALUES;

/// The share of this process's memory limit ([`crate::memory::available`])
/// the medium's values may take; the rest is the mapped file, the image,
/// the threads' stacks and heaps.
pub const MEDIUM_MEMORY_FRACTION: f64 = 0.75;
/// Empty child slot.
pub const NONE: u32 = u32::MAX;
/// log2 of the dual-leaf edge in voxels (OpenVDB LeafNode::LOG2DIM).
pub const LEAF_LOG2: u32 = 3;
/// log2 of the block edge in dual leaves (OpenVDB InternalNode<.,4>).
pub const BLOCK_LOG2: u32 = 4;
/// log2 of the super-node edge in blocks (OpenVDB InternalNode<.,5>).
pub const SUPER_LOG2: u32 = 5;
/// log2 of a block edge in voxels (128).
pub const BLOCK_VOXELS_LOG2: u32 = LEAF_LOG2 + BLOCK_LOG2;
/// log2 of a super-node edge in voxels (4096).
pub const SUPER_VOXELS_LOG2: u32 = BLOCK_VOXELS_LOG2 + SUPER_LOG2;

const BLOCK_SLOTS: usize = 1 << (3 * BLOCK_LOG2);
const SUPER_SLOTS: usize = 1 << (3 * SUPER_LOG2);

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
fn slot(c: IVec3, log2: u32) -> usize {
    let m = (1 << log2) - 1;
    (((c.x & m) << (2 * log2)) | ((c.y & m) << log2) | (c.z & m)) as usize
}

#[inline]
fn shr(c: IVec3, n: u32) -> IVec3 {
    IVec3::new(c.x >> n, c.y >> n, c.z >> n)
}

/// A 512-bit set of dual cells.
pub type CellMask = [u64; 8];

#[inline]
pub fn mask_has(m: &CellMask, bit: usize) -> bool {
    (m[bit >> 6] >> (bit & 63)) & 1 == 1
}

/// One or more scalar fields on one grid transform, as blocks and dual leaves.
///
/// Channel `c` of voxel `(x,y,z)` of block `b` is
/// `scale[c] * values[(b * BLOCK_VALUES + block_offset(x, y, z)) * channels + c]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub transform: Transform,
    pub channels: usize,
    /// Dual-leaf keys (index origin / 8), in ascending (x, y, z) order.
    pub keys: Vec<IVec3>,
    /// Blocks of scaled values; block 0 is all zeros.
    pub values: Vec<f32>,
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
    live_blocks: usize,
    /// Origin (index space) of the source leaf of block `b` at `b - 1`.
    pub block_origins: Vec<IVec3>,
}

/// Why a leaf's values could not be produced (a file's decode error).
pub type LeafError = Box<dyn std::error::Error + Send + Sync>;

/// Per-thread buffers a [`LeafSource`] may decode a leaf into.
#[derive(Default)]
pub struct Scratch {
    pub values: Vec<f32>,
    pub bytes: Vec<u8>,
}

/// One grid's leaves as the medium's builder reads them: origins and
/// active masks up front (a file's topology lists them before any value),
/// the values leaf by leaf, possibly decoded on demand and in parallel. A
/// grid in memory is one ([`GridSource`]); so is a VDB file's grid
/// (`crate::vdb::read`), which lets a render build its medium straight from
/// the file's records, with no intermediate [`Grid`].
pub trait LeafSource: Sync {
    /// The grid's name (for messages).
    fn name(&self) -> &str;
    fn transform(&self) -> Transform;
    /// Components per voxel: 1 (float) or 3 (vec3).
    fn channels(&self) -> usize;
    /// The background's components (the first [`channels`](Self::channels)).
    fn background(&self) -> [f32; 3];
    fn leaf_count(&self) -> usize;
    /// Origin of leaf `i` (distinct for distinct `i`).
    fn origin(&self, i: usize) -> IVec3;
    /// Active mask of leaf `i`.
    fn mask(&self, i: usize) -> &[u64; LEAF_MASK_WORDS];
    /// The values of leaf `i`, components interleaved, borrowed from the
    /// source or decoded into `scratch`.
    fn values<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s>, LeafError>;
}

/// A leaf's values as a [`LeafSource`] gives them.
#[derive(Clone, Copy, Debug)]
pub enum LeafValues<'s> {
    /// All 512 slots in index order (`512 * channels` floats; inactive
    /// slots may hold anything).
    All(&'s [f32]),
    /// The active slots only, in index order (`popcount(mask) * channels`
    /// floats): what an active-mask VDB record stores.
    Active(&'s [f32]),
}

/// A grid in memory as a [`LeafSource`].
pub struct GridSource<'a, T>(pub &'a Grid<T>);

macro_rules! grid_source {
    ($t:ty, $flat:expr) => {
        impl LeafSource for GridSource<'_, $t> {
            fn name(&self) -> &str {
                &self.0.name
            }
            fn transform(&self) -> Transform {
                self.0.transform
            }
            fn channels(&self) -> usize {
                <$t as VoxelValue>::COMPONENTS
            }
            fn background(&self) -> [f32; 3] {
                self.0.background.components()
            }
            fn leaf_count(&self) -> usize {
                self.0.leaves().len()
            }
            fn origin(&self, i: usize) -> IVec3 {
                self.0.leaves()[i].origin
            }
            fn mask(&self, i: usize) -> &[u64; LEAF_MASK_WORDS] {
                &self.0.leaves()[i].mask
            }
            fn values<'s>(&'s self, i: usize, _: &'s mut Scratch) -> Result<LeafValues<'s>, LeafError> {
                let flat: fn(&[$t]) -> &[f32] = $flat;
                Ok(LeafValues::All(flat(&self.0.leaves()[i].values[..])))
            }
        }
    };
}
grid_source!(f32, |v| v);
grid_source!([f32; 3], |v| v.as_flattened());

/// Every dual leaf a source leaf at `origin` feeds (bit `d` of `feeds`:
/// dual leaf `key - (dx,dy,dz)`, see [`feeds_from_nonzero`]), appended.
fn push_dual_keys(origin: IVec3, feeds: u8, out: &mut Vec<IVec3>) {
    let key = shr(origin, LEAF_LOG2);
    out.extend((0..8u8).filter(|d| feeds >> d & 1 == 1).map(|d| {
        key - IVec3::new((d >> 2 & 1) as i32, (d >> 1 & 1) as i32, (d & 1) as i32)
    }));
}

/// Bits of a leaf's 64-voxel mask word with local z = 0 (`n & 7 == 0`).
const Z0_BITS: u64 = 0x0101_0101_0101_0101;
/// Bits of a mask word with local y = 0 (`(n >> 3) & 7 == 0`).
const Y0_BITS: u64 = 0xff;

/// The feeds byte of a leaf from its 512-bit set of non-zero active voxels
/// (bit n = voxel `(x << 6) | (y << 3) | z`, word `x`): bit `d` = (dx,dy,dz)
/// is set iff some voxel in the set has local coordinate 0 on every axis
/// where the offset is 1. Word 0 holds x = 0; within a word the low byte
/// holds y = 0 and [`Z0_BITS`] z = 0.
fn feeds_from_nonzero(nz: &[u64; 8]) -> u8 {
    let all = nz.iter().fold(0u64, |a, w| a | w);
    let mut feeds = 0u8;
    for d in 0..8u8 {
        let x = if d >> 2 & 1 == 1 { nz[0] } else { all };
        let y = if d >> 1 & 1 == 1 { Y0_BITS } else { u64::MAX };
        let z = if d & 1 == 1 { Z0_BITS } else { u64::MAX };
        if x & y & z != 0 {
            feeds |= 1 << d;
        }
    }
    feeds
}

/// Whether a stored component is acceptable: finite and >= 0 (-0 included),
/// on its bits: below +inf's bits, or -0's.
#[inline]
fn valid_bits(b: u32) -> bool {
    b < 0x7f80_0000 || b == 0x8000_0000
}

/// First pass over a source leaf: its largest active component, or the
/// offset of its first active voxel that is negative, infinite or NaN.
/// Inactive voxels count as 0 whatever they hold. On a leaf's active values
/// alone ([`LeafValues::Active`]) the check runs on the floats' bits, in
/// SIMD lanes: a valid value's bits order as its value.
fn leaf_peak(values: LeafValues<'_>, channels: usize, mask: &[u64; LEAF_MASK_WORDS]) -> Result<f32, usize> {
    match values {
        LeafValues::Active(a) => {
            let (mut peak, mut bad) = (0u32, 0u32);
            for &x in a {
                let b = x.to_bits();
                bad |= u32::from(!valid_bits(b));
                peak = peak.max(b & 0x7fff_ffff);
            }
            if bad != 0 {
                // The first active voxel with a bad component.
                let mut k = 0;
                for (w, &word) in mask.iter().enumerate() {
                    let mut bits = word;
                    while bits != 0 {
                        let n = w * 64 + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        if a[k * channels..(k + 1) * channels].iter().any(|x| !valid_bits(x.to_bits())) {
                            return Err(n);
                        }
                        k += 1;
                    }
                }
            }
            Ok(f32::from_bits(peak))
        }
        LeafValues::All(a) => {
            let mut peak = 0u32;
            for (w, &word) in mask.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let n = w * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    for &x in &a[n * channels..(n + 1) * channels] {
                        let b = x.to_bits();
                        if !valid_bits(b) {
                            return Err(n);
                        }
                        peak = peak.max(b & 0x7fff_ffff);
                    }
                }
            }
            Ok(f32::from_bits(peak))
        }
    }
}

/// Second pass over a source leaf with a non-zero voxel in its block: copies
/// its active values into block `dst` (stride `stride`, starting at channel
/// `first`; `dst` starts at 0, so inactive voxels read 0) and returns its
/// voxels whose first component (resp. some component) is not 0.
fn fill_leaf(
    values: LeafValues<'_>,
    channels: usize,
    mask: &[u64; LEAF_MASK_WORDS],
    dst: &mut [f32],
    stride: usize,
    first: usize,
) -> (CellMask, CellMask) {
    match channels {
        1 => fill_leaf_n::<1>(values, mask, dst, stride, first),
        3 => fill_leaf_n::<3>(values, mask, dst, stride, first),
        _ => unreachable!("sources have 1 or 3 channels (checked in Medium::from_sources)"),
    }
}

/// [`fill_leaf`] for `C` channels (copies of a known length: no call).
fn fill_leaf_n<const C: usize>(
    values: LeafValues<'_>,
    mask: &[u64; LEAF_MASK_WORDS],
    dst: &mut [f32],
    stride: usize,
    first: usize,
) -> (CellMask, CellMask) {
    let channels = C;
    let (mut nz_first, mut nz_any) = ([0u64; 8], [0u64; 8]);
    let (a, active) = match values {
        LeafValues::All(a) => (a, false),
        LeafValues::Active(a) => (a, true),
    };
    let mut k = 0;
    for (w, &word) in mask.iter().enumerate() {
        let mut bits = word;
        while bits != 0 {
            let b = bits.trailing_zeros();
            bits &= bits - 1;
            let n = w * 64 + b as usize;
            let i = if active { k } else { n };
            k += 1;
            let v: &[f32; C] = a[i * channels..(i + 1) * channels].try_into().expect("C floats");
            let at = n * stride + first;
            let d: &mut [f32; C] = (&mut dst[at..at + channels]).try_into().expect("C floats");
            *d = *v;
            nz_first[w] |= u64::from(v[0] != 0.0) << b;
            nz_any[w] |= u64::from(v.iter().any(|&x| x != 0.0)) << b;
        }
    }
    (nz_first, nz_any)
}

/// The largest active component and the feeds byte of a grid leaf (the
/// tests' entry to the two passes).
#[cfg(test)]
fn scan_leaf<T: VoxelValue>(leaf: &crate::grid::Leaf<T>) -> Result<(f32, u8), usize> {
    let flat: Vec<f32> = leaf.values.iter().flat_map(|v| v.components().into_iter().take(T::COMPONENTS)).collect();
    let peak = leaf_peak(LeafValues::All(&flat), T::COMPONENTS, &leaf.mask)?;
    let mut dst = vec![0.0; flat.len()];
    let (first, nz) = fill_leaf(LeafValues::All(&flat), T::COMPONENTS, &leaf.mask, &mut dst, T::COMPONENTS, 0);
    assert_eq!((first, nz), voxel_masks(&dst, T::COMPONENTS), "the masks of the copied block");
    Ok((peak, feeds_from_nonzero(&nz)))
}

/// The feeds byte by brute force (every active voxel, every offset): the
/// oracle of [`feeds_from_nonzero`].
#[cfg(test)]
fn leaf_feeds<T: VoxelValue>(leaf: &crate::grid::Leaf<T>) -> u8 {
    let mut feeds = 0u8;
    for n in 0..crate::grid::LEAF_NUM_VALUES {
        if !leaf.is_active(n) || leaf.values[n] == T::ZERO {
            continue;
        }
        let (x0, y0, z0) = (n >> 6 == 0, (n >> 3) & 7 == 0, n & 7 == 0);
        for d in 0..8u8 {
            if (d >> 2 & 1 == 0 || x0) && (d >> 1 & 1 == 0 || y0) && (d & 1 == 0 || z0) {
                feeds |= 1 << d;
            }
        }
    }
    feeds
}

/// Rejects grids the renderer cannot sample the way Cycles does.
pub fn validate_grid<T: VoxelValue>(g: &Grid<T>) -> Result<(), RenderError>
where
    for<'a> GridSource<'a, T>: LeafSource,
{
    let src = GridSource(g);
    check_header(&src)?;
    let mut scratch = Scratch::default();
    for i in 0..src.leaf_count() {
        let v = src.values(i, &mut scratch).map_err(|e| RenderError::Grid { grid: g.name.clone(), message: e.to_string() })?;
        if let Err(n) = leaf_peak(v, src.channels(), src.mask(i)) {
            return Err(bad_voxel(&src, i, n, v));
        }
    }
    Ok(())
}

/// The checks on a source that need no values: transform and background.
fn check_header(src: &dyn LeafSource) -> Result<(), RenderError> {
    let err = |message: String| RenderError::Grid { grid: src.name().to_string(), message };
    let t = src.transform();
    let ts = t.voxel_size;
    if !(ts.is_finite() && ts > 0.0 && t.translation.is_finite()) {
        return Err(err(format!("transform must have a finite voxel size > 0 (got {ts})")));
    }
    let bg = src.background();
    if bg[..src.channels()].iter().any(|&x| x != 0.0) {
        return Err(err(format!(
            "background {} is not 0: a non-zero background fills all of space, which no renderer samples the same way",
            value_text(&bg[..src.channels()])
        )));
    }
    Ok(())
}

/// A voxel value as `{:?}` prints the grid's value type (`1.5` or `[1.0, 2.0, 3.0]`).
fn value_text(c: &[f32]) -> String {
    if c.len() == 1 {
        format!("{:?}", c[0])
    } else {
        format!("{c:?}")
    }
}

/// The error for voxel `n` of leaf `i` of `src` (values `v`).
fn bad_voxel(src: &dyn LeafSource, i: usize, n: usize, v: LeafValues<'_>) -> RenderError {
    let ch = src.channels();
    let ijk = src.origin(i) + crate::grid::offset_to_local(n);
    let at = match v {
        LeafValues::All(a) => &a[n * ch..(n + 1) * ch],
        LeafValues::Active(a) => {
            // The voxel's rank among the active ones.
            let mask = src.mask(i);
            let k: usize = (0..n >> 6).map(|w| mask[w].count_ones() as usize).sum::<usize>()
                + (mask[n >> 6] & ((1u64 << (n & 63)) - 1)).count_ones() as usize;
            &a[k * ch..(k + 1) * ch]
        }
    };
    RenderError::Grid {
        grid: src.name().to_string(),
        message: format!("voxel {ijk} holds {}: values must be finite and >= 0", value_text(at)),
    }
}

/// Largest scaled voxel value the renderer accepts. The film is f32 and a
/// radiance of 10^30 per km integrated over 10^8 km of path still fits, so
/// no finite input below this bound can reach an infinite pixel.
pub const MAX_SCALED_VALUE: f64 = 1e30;

/// Rejects a grid whose largest value times `scale` exceeds
/// [`MAX_SCALED_VALUE`] (a foreign VDB near f32's limit with a large scale).
fn check_scaled_peak(grid: &str, peak: f32, key: &str, scale: f64) -> Result<(), RenderError> {
    if scale == 0.0 {
        return Ok(());
    }
    let peak = peak as f64;
    if peak * scale > MAX_SCALED_VALUE {
        return Err(RenderError::Grid {
            grid: grid.to_string(),
            message: format!(
                "largest value {peak:e} times volume.{key} = {scale:e} is {:e}, above {MAX_SCALED_VALUE:e}: the image would overflow; lower volume.{key}",
                peak * scale
            ),
        });
    }
    Ok(())
}

/// What [`Field::from_sources`] found in one source.
struct SourceReport {
    /// Largest active component (0 for none).
    peak: f32,
    /// The first failure in block order: a bad voxel or a read error.
    fail: Option<RenderError>,
}

/// What the pass found in one block.
struct BlockScan {
    /// Dual leaves the block feeds (0: no non-zero active voxel, the block
    /// is not stored).
    feeds: u8,
    /// Its non-zero voxels: channel 0, any channel ([`voxel_masks`]).
    masks: (CellMask, CellMask),
    /// Per source: the largest active component, the first failure.
    peaks: [f32; 2],
    fails: [Option<Box<RenderError>>; 2],
}

/// Reads, checks and (if some source has a non-zero active voxel here)
/// stores the leaves of one block: `leaves[k]` is source `k`'s leaf at the
/// block's origin ([`NONE`] if it has none). A block with no non-zero voxel
/// is never written, so its pages are never touched.
fn scan_block(
    sources: &[&dyn LeafSource],
    leaves: &[u32; 2],
    dst: &mut [f32],
    channels: usize,
    scratch: &mut [Scratch; 2],
) -> BlockScan {
    let mut scan = BlockScan { feeds: 0, masks: ([0; 8], [0; 8]), peaks: [0.0; 2], fails: [None, None] };
    let mut got: [Option<LeafValues<'_>>; 2] = [None, None];
    for ((k, src), scr) in sources.iter().enumerate().zip(scratch.iter_mut()) {
        let li = leaves[k];
        if li == NONE {
            continue;
        }
        let li = li as usize;
        match src.values(li, scr) {
            Err(source) => {
                scan.fails[k] = Some(Box::new(RenderError::Source { grid: src.name().to_string(), source }))
            }
            Ok(v) => match leaf_peak(v, src.channels(), src.mask(li)) {
                Err(n) => scan.fails[k] = Some(Box::new(bad_voxel(*src, li, n, v))),
                Ok(peak) => {
                    scan.peaks[k] = peak;
                    got[k] = Some(v);
                }
            },
        }
    }
    // Stored iff some source has a non-zero active voxel here (values are
    // >= 0, so iff some peak is above 0).
    if scan.peaks.iter().any(|&p| p > 0.0) {
        let (mut first, mut nz) = (0, [0u64; 8]);
        for (k, src) in sources.iter().enumerate() {
            if let Some(v) = got[k] {
                let (f, a) = fill_leaf(v, src.channels(), src.mask(leaves[k] as usize), dst, channels, first);
                if first == 0 {
                    scan.masks.0 = f;
                }
                for (x, y) in nz.iter_mut().zip(a) {
                    *x |= y;
                }
            }
            first += src.channels();
        }
        scan.masks.1 = nz;
        scan.feeds = feeds_from_nonzero(&nz);
    }
    scan
}

impl Field {
    /// Builds a field whose channels are the concatenation of `sources`'
    /// channels (one or two sources, all on the same transform), at unit
    /// scale (`scale` all 1), in one parallel pass over the union of their
    /// leaves: each leaf is read (a file's record decoded) straight into a
    /// per-thread buffer, checked (finite, >= 0), and its active values
    /// copied into its block of one preallocated array; its largest value
    /// and the dual leaves it feeds come from the same pass. Blocks are
    /// numbered by the union of the sources' leaves (in key order), so a
    /// leaf with no non-zero active voxel (the Cycles shell) keeps an
    /// all-zero block that nothing references and nothing writes: its
    /// memory is reserved, never touched. The result depends only on the
    /// sources' leaves and values, never on the thread count.
    ///
    /// The value array (one block of all channels per leaf of the union,
    /// unwritten blocks included: they count against an address-space
    /// limit) is checked before it is allocated: with `reserved` bytes
    /// already held by other fields, at most [`MEDIUM_MEMORY_FRACTION`] of
    /// `limit`, else [`RenderError::Memory`] (a file's leaf table is its
    /// word, and a failed allocation would abort the process).
    fn from_sources(
        sources: &[&dyn LeafSource],
        reserved: f64,
        limit: &crate::memory::MemoryLimit,
    ) -> Result<(Field, Vec<SourceReport>), RenderError> {
        assert!(!sources.is_empty() && sources.len() <= 2);
        let transform = sources[0].transform();
        debug_assert!(sources.iter().all(|s| s.transform() == transform));
        let channels: usize = sources.iter().map(|s| s.channels()).sum();

        // Blocks: the union of the sources' leaves, in key order.
        let mut all: Vec<(IVec3, u32, u32)> = Vec::new();
        for (k, s) in sources.iter().enumerate() {
            all.extend((0..s.leaf_count()).map(|i| (s.origin(i), k as u32, i as u32)));
        }
        all.par_sort_unstable_by_key(|&(o, k, _)| (o.x, o.y, o.z, k));
        let mut origins: Vec<IVec3> = Vec::with_capacity(all.len());
        let mut leaf_of: Vec<[u32; 2]> = Vec::with_capacity(all.len());
        for &(o, k, i) in &all {
            if origins.last() != Some(&o) {
                origins.push(o);
                leaf_of.push([NONE; 2]);
            }
            if let Some(l) = leaf_of.last_mut() {
                l[k as usize] = i;
            }
        }
        drop(all);
        let per_block = BLOCK_VALUES * channels;
        let needed = reserved + ((origins.len() + 1) * per_block * std::mem::size_of::<f32>()) as f64;
        if needed > MEDIUM_MEMORY_FRACTION * limit.bytes {
            return Err(RenderError::Memory {
                leaves: origins.len(),
                needed: crate::memory::gib(needed),
                available: limit.to_string(),
            });
        }
        // Zeroed by the allocator (fresh pages): blocks not written cost
        // no memory.
        let mut values = vec![0.0f32; (origins.len() + 1) * per_block];
        let mut scans: Vec<BlockScan> = values[per_block..]
            .par_chunks_mut(per_block)
            .zip(leaf_of.par_iter())
            .map_init(<[Scratch; 2]>::default, |scratch, (dst, leaves)| {
                scan_block(sources, leaves, dst, channels, scratch)
            })
            .collect();
        drop(leaf_of);
        let mut reports: Vec<SourceReport> = sources.iter().map(|_| SourceReport { peak: 0.0, fail: None }).collect();
        for s in scans.iter_mut() {
            for (k, r) in reports.iter_mut().enumerate() {
                r.peak = r.peak.max(s.peaks[k]);
                if r.fail.is_none() {
                    r.fail = s.fails[k].take().map(|b| *b);
                }
            }
        }
        let live_blocks = scans.iter().filter(|s| s.feeds != 0).count();
        let block_of = |origin: IVec3| -> u32 {
            match origins.binary_search_by_key(&(origin.x, origin.y, origin.z), |k| (k.x, k.y, k.z)) {
                Ok(i) if scans[i].feeds != 0 => i as u32 + 1,
                _ => 0,
            }
        };

        let mut keys = Vec::new();
        for (s, &o) in scans.iter().zip(&origins) {
            push_dual_keys(o, s.feeds, &mut keys);
        }
        keys.par_sort_unstable_by_key(|k| (k.x, k.y, k.z));
        keys.dedup();
        let neighbours: Vec<[u32; 8]> = keys
            .par_iter()
            .map(|&k| {
                std::array::from_fn(|d| {
                    let d = d as i32;
                    block_of((k + IVec3::new(d >> 2 & 1, d >> 1 & 1, d & 1)) * LEAF_DIM)
                })
            })
            .collect();
        // Per block, its non-zero voxels (block 0 and unwritten blocks: none).
        let mut nonzero: Vec<(CellMask, CellMask)> = Vec::with_capacity(scans.len() + 1);
        nonzero.push(([0; 8], [0; 8]));
        nonzero.extend(scans.iter().map(|s| s.masks));
        drop(scans);
        let (mask_first, mask_any): (Vec<CellMask>, Vec<CellMask>) =
            neighbours.par_iter().map(|nb| cell_masks(nb, &nonzero)).unzip();


        // Hierarchy: blocks of 16^3 dual leaves, super nodes of 32^3 blocks.
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
            (
                lo * LEAF_DIM,
                (hi + IVec3::ONE) * LEAF_DIM,
                shr(lo, BLOCK_LOG2 + SUPER_LOG2),
                shr(hi, BLOCK_LOG2 + SUPER_LOG2) + IVec3::ONE,
            )
        };
        let field = Field {
            transform,
            channels,
            keys,
            values,
            neighbours,
            mask_first,
            mask_any,
            blocks,
            supers,
            root,
            super_bounds,
            lo,
            hi,
            root_lo,
            root_hi,
            scale: [1.0; 4],
            live_blocks,
            block_origins: origins,
        };
        Ok((field, reports))
    }

    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    pub fn leaf_count(&self) -> usize {
        self.keys.len()
    }

    /// Bytes held by the structure (for reports).
    pub fn memory_bytes(&self) -> usize {
        (self.live_blocks + 1) * BLOCK_VALUES * self.channels * 4
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
    #[inline]
    pub fn corner_indices(&self, leaf: u32, x: usize, y: usize, z: usize) -> [usize; 8] {
        let nb = &self.neighbours[leaf as usize];
        let c = self.channels;
        if x < 7 && y < 7 && z < 7 {
            let base = nb[0] as usize * BLOCK_VALUES + block_offset(x, y, z);
            return CORNER_OFFSETS.map(|o| (base + o) * c);
        }
        std::array::from_fn(|k| {
            let (cx, cy, cz) = (x + (k >> 2), y + (k >> 1 & 1), z + (k & 1));
            let d = (cx >> 3) << 2 | (cy >> 3) << 1 | cz >> 3;
            (nb[d] as usize * BLOCK_VALUES + block_offset(cx & 7, cy & 7, cz & 7)) * c
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
        let Some(leaf) = self.find_leaf(shr(c, LEAF_LOG2)) else { return };
        let l = c - shr(c, LEAF_LOG2) * LEAF_DIM;
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
            let v = &self.values[i..][..self.channels];
            for ch in 0..self.channels {
                out[ch] += w[k] * v[ch] as f64;
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

/// Voxels of one block where channel 0 (resp. some channel) is not 0: the
/// oracle of the masks [`fill_leaf`] returns.
#[cfg(test)]
fn voxel_masks(v: &[f32], channels: usize) -> (CellMask, CellMask) {
    let mut first = [0u64; 8];
    let mut any = [0u64; 8];
    for (n, c) in v.chunks_exact(channels).enumerate() {
        first[n >> 6] |= u64::from(c[0] != 0.0) << (n & 63);
        any[n >> 6] |= u64::from(c.iter().any(|x| *x != 0.0)) << (n & 63);
    }
    (first, any)
}

/// Bits of a mask word with local z = 7.
const Z7_BITS: u64 = 0x8080_8080_8080_8080;

/// The dual cells of one dual leaf with a non-zero corner, from the
/// non-zero voxels of its eight blocks (`m[d]`, `d = dx << 2 | dy << 1 |
/// dz`), a mask word at a time: cell (x,y,z) has corners (x+a, y+b, z+c),
/// a,b,c in {0,1}, a coordinate 8 being 0 in the upper neighbour. Word `x`
/// (bits `y << 3 | z`) ORs voxel words x and x+1, then shifts by one in z
/// (bringing in the z = 0 column of the z neighbour) and by one in y (the
/// y = 0 row of the y neighbour).
fn cells_from_voxels(m: [&CellMask; 8]) -> CellMask {
    let mut out = [0u64; 8];
    for (x, o) in out.iter_mut().enumerate() {
        let q = |d: usize| m[d][x] | if x < 7 { m[d][x + 1] } else { m[4 | d][0] };
        let zs = |a: u64, b: u64| a | ((a >> 1) & !Z7_BITS) | ((b & Z0_BITS) << 7);
        let (r0, r1) = (zs(q(0), q(1)), zs(q(2), q(3)));
        *o = r0 | (r0 >> 8) | ((r1 & Y0_BITS) << 56);
    }
    out
}

/// Masks of the dual cells of one dual leaf (its blocks `nb`) in which
/// channel 0 (resp. any channel) has a non-zero corner, from the blocks'
/// non-zero voxels (channel 0, any channel).
fn cell_masks(nb: &[u32; 8], nonzero: &[(CellMask, CellMask)]) -> (CellMask, CellMask) {
    let first = cells_from_voxels(std::array::from_fn(|d| &nonzero[nb[d] as usize].0));
    let any = cells_from_voxels(std::array::from_fn(|d| &nonzero[nb[d] as usize].1));
    (first, any)
}

/// [`cell_masks`] by brute force over the 9^3 lattice (the tests' oracle).
#[cfg(test)]
fn cell_masks_brute(nb: &[u32; 8], nonzero: &[(CellMask, CellMask)]) -> (CellMask, CellMask) {
    // Per point of the 9^3 lattice: bit 0 = channel 0 non-zero, bit 1 = any.
    const G: usize = 9;
    let mut nz = [0u8; G * G * G];
    for gx in 0..G {
        for gy in 0..G {
            for gz in 0..G {
                let d = (gx >> 3) << 2 | (gy >> 3) << 1 | gz >> 3;
                let (f, a) = &nonzero[nb[d] as usize];
                let bit = block_offset(gx & 7, gy & 7, gz & 7);
                let has = |m: &CellMask| (m[bit >> 6] >> (bit & 63)) as u8 & 1;
                nz[(gx * G + gy) * G + gz] = has(f) | has(a) << 1;
            }
        }
    }
    const CORNERS: [usize; 8] = [0, 1, G, G + 1, G * G, G * G + 1, G * G + G, G * G + G + 1];
    let mut first = [0u64; 8];
    let mut any = [0u64; 8];
    for x in 0..8 {
        for y in 0..8 {
            for z in 0..8 {
                let at = (x * G + y) * G + z;
                let m = CORNERS.iter().fold(0u8, |m, off| m | nz[at + off]);
                let bit = cell_bit(x as i32, y as i32, z as i32);
                first[bit >> 6] |= u64::from(m & 1) << (bit & 63);
                any[bit >> 6] |= u64::from(m >> 1 & 1) << (bit & 63);
            }
        }
    }
    (first, any)
}

/// Where a quantity lives: which field, which channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Channel {
    pub field: usize,
    pub channel: usize,
}

/// The volume as the renderer sees it: sigma_t = density_scale * density and
/// emission e = emission_scale * emission, each on its grid's own transform.
/// When both grids share a transform they share one [`Field`] (channel 0 =
/// density, channels 1..4 = emission), so a ray walks one tree. The fields
/// hold the grids' values as stored (unit scale) and the scales are applied
/// at lookup ([`Field::scale`]), so [`Medium::set_scales`] changes them
/// without a rebuild.
#[derive(Debug, Clone, PartialEq)]
pub struct Medium {
    pub fields: Vec<Field>,
    /// sigma_t, if the volume has any extinction.
    pub sigma_t: Option<Channel>,
    /// First of the three emission channels, if the volume emits.
    pub emission: Option<Channel>,
    /// Density, then emission: where its values are stored, its largest
    /// value and its grid's name; `None` for a missing grid or one with no
    /// non-zero active voxel. Kept whatever the scale, so that a scale
    /// leaving or reaching 0 needs no rebuild either.
    stored: [Option<Stored>; 2],
    pub density_scale: f64,
    pub emission_scale: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct Stored {
    channel: Channel,
    peak: f32,
    grid: String,
}

/// The scene keys of the two scales, density then emission.
const SCALE_KEYS: [&str; 2] = ["density_scale", "emission_scale"];

fn check_scales(scales: [f64; 2]) -> Result<(), RenderError> {
    for (what, s) in SCALE_KEYS.iter().zip(scales) {
        if !(s.is_finite() && s >= 0.0) {
            return Err(RenderError::Settings(format!("volume.{what} = {s} must be finite and >= 0")));
        }
    }
    Ok(())
}

impl Medium {
    /// Builds the medium. A missing grid, a zero scale or a grid with no
    /// non-zero voxel means "no extinction" / "no emission".
    pub fn new(
        density: Option<&Grid<f32>>,
        emission: Option<&Grid<[f32; 3]>>,
        density_scale: f64,
        emission_scale: f64,
    ) -> Result<Medium, RenderError> {
        let d = density.map(GridSource);
        let e = emission.map(GridSource);
        Medium::from_sources(
            d.as_ref().map(|s| s as &dyn LeafSource),
            e.as_ref().map(|s| s as &dyn LeafSource),
            density_scale,
            emission_scale,
        )
    }

    /// [`Medium::new`] from any [`LeafSource`]s (a density source of 1
    /// channel, an emission source of 3): the same medium, field for field,
    /// from a grid in memory or from a file's leaves decoded on the fly.
    /// Errors (in this order): a scale out of range, a bad transform or
    /// background, then per source (density first) its first bad voxel or
    /// unreadable leaf in key order and a scaled peak above
    /// [`MAX_SCALED_VALUE`].
    pub fn from_sources(
        density: Option<&dyn LeafSource>,
        emission: Option<&dyn LeafSource>,
        density_scale: f64,
        emission_scale: f64,
    ) -> Result<Medium, RenderError> {
        let scales = [density_scale, emission_scale];
        check_scales(scales)?;
        let srcs = [density, emission];
        for (s, want) in srcs.iter().zip([1, 3]) {
            if let Some(s) = s {
                if s.channels() != want {
                    return Err(RenderError::Grid {
                        grid: s.name().to_string(),
                        message: format!("has {} components a voxel, expected {want}", s.channels()),
                    });
                }
                check_header(*s)?;
            }
        }
        // Each field's value storage is checked against the process's
        // memory limit before it is allocated ([`Field::from_sources`]).
        let limit = crate::memory::available();
        let mut reserved = 0.0;
        // Sources sharing a transform share a field.
        let groups: Vec<Vec<usize>> = match srcs {
            [Some(d), Some(e)] if d.transform() == e.transform() => vec![vec![0, 1]],
            _ => (0..2).filter(|&k| srcs[k].is_some()).map(|k| vec![k]).collect(),
        };
        let mut medium = Medium {
            fields: Vec::new(),
            sigma_t: None,
            emission: None,
            stored: [None, None],
            density_scale,
            emission_scale,
        };
        for group in groups {
            let list: Vec<&dyn LeafSource> = group.iter().filter_map(|&k| srcs[k]).collect();
            let (mut field, reports) = Field::from_sources(&list, reserved, &limit)?;
            let mut peaks = [0.0f32; 2];
            for (r, &k) in reports.into_iter().zip(&group) {
                if let Some(e) = r.fail {
                    return Err(e);
                }
                let name = srcs[k].map_or("", |s| s.name());
                check_scaled_peak(name, r.peak, SCALE_KEYS[k], scales[k])?;
                peaks[k] = r.peak;
            }
            // A source feeds the field iff it has a non-zero active voxel:
            // its peak (values are >= 0) is above 0. Rebuilt without a
            // source that has none (rare: an all-zero grid).
            let live: Vec<usize> = group.iter().copied().filter(|&k| peaks[k] > 0.0).collect();
            if live.is_empty() {
                continue;
            }
            if live.len() < group.len() {
                let list: Vec<&dyn LeafSource> = live.iter().filter_map(|&k| srcs[k]).collect();
                drop(field); // never two copies at once
                field = Field::from_sources(&list, reserved, &limit)?.0;
            }
            let fi = medium.fields.len();
            let mut ch = 0;
            for &k in &live {
                let src = srcs[k].expect("live sources exist");
                medium.stored[k] =
                    Some(Stored { channel: Channel { field: fi, channel: ch }, peak: peaks[k], grid: src.name().into() });
                ch += src.channels();
            }
            reserved += (field.values.len() * std::mem::size_of::<f32>()) as f64;
            medium.fields.push(field);
        }
        medium.set_scales(density_scale, emission_scale)?;
        Ok(medium)
    }

    /// The emission channel's field and first channel whatever the scale
    /// (`None` without a non-zero emission voxel).
    pub fn stored_emission(&self) -> Option<Channel> {
        self.stored[1].as_ref().map(|s| s.channel)
    }

    /// Sets `volume.density_scale` and `volume.emission_scale` without
    /// rebuilding anything (the fields hold unit values; the scales are
    /// applied at lookup): the medium then equals `Medium::new` with these
    /// scales, field for field. On error (a scale out of range, or a grid's
    /// largest value times its scale above [`MAX_SCALED_VALUE`]) the medium
    /// is unchanged.
    pub fn set_scales(&mut self, density_scale: f64, emission_scale: f64) -> Result<(), RenderError> {
        let scales = [density_scale, emission_scale];
        check_scales(scales)?;
        for (k, st) in self.stored.iter().enumerate() {
            if let Some(st) = st {
                check_scaled_peak(&st.grid, st.peak, SCALE_KEYS[k], scales[k])?;
            }
        }
        for f in &mut self.fields {
            f.scale = [1.0; 4];
        }
        for (k, (st, n)) in self.stored.iter().zip([1, 3]).enumerate() {
            if let Some(st) = st {
                let c = st.channel;
                self.fields[c.field].scale[c.channel..c.channel + n].fill(scales[k]);
            }
        }
        let on = |k: usize| self.stored[k].as_ref().filter(|_| scales[k] > 0.0).map(|s| s.channel);
        self.sigma_t = on(0);
        self.emission = on(1);
        self.density_scale = density_scale;
        self.emission_scale = emission_scale;
        Ok(())
    }

    /// The largest sigma_t anywhere in the medium (0 without extinction):
    /// the density grid's largest stored value times `volume.density_scale`,
    /// a majorant of the trilinear field (a convex combination of stored
    /// values, 0 outside them) for the shadow rays' ratio tracking. O(1):
    /// the build keeps each source's peak, and a scale edit changes only
    /// the factor, so nothing is cached that could go stale.
    pub fn sigma_t_majorant(&self) -> f64 {
        match (self.sigma_t, &self.stored[0]) {
            (Some(c), Some(st)) => st.peak as f64 * self.fields[c.field].scale[c.channel],
            _ => 0.0,
        }
    }

    /// sigma_t at a world point (per unit length).
    pub fn sigma_t_at(&self, p: DVec3) -> f64 {
        let Some(c) = self.sigma_t else { return 0.0 };
        let f = &self.fields[c.field];
        let mut v = [0.0; 4];
        f.sample_index(f.transform.world_to_index(p), &mut v);
        v[c.channel]
    }

    /// Emitted radiance per unit length at a world point.
    pub fn emission_at(&self, p: DVec3) -> [f64; 3] {
        let Some(c) = self.emission else { return [0.0; 3] };
        let f = &self.fields[c.field];
        let mut v = [0.0; 4];
        f.sample_index(f.transform.world_to_index(p), &mut v);
        [v[c.channel], v[c.channel + 1], v[c.channel + 2]]
    }

    /// Total dual leaves stored.
    pub fn leaf_count(&self) -> usize {
        self.fields.iter().map(Field::leaf_count).sum()
    }

    pub fn memory_bytes(&self) -> usize {
        self.fields.iter().map(Field::memory_bytes).sum()
    }

    /// World-space box enclosing every field's support, if any.
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        self.fields
            .iter()
            .filter(|f| !f.is_empty())
            .map(Field::world_bounds)
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Leaf, LEAF_NUM_VALUES};
    use rand::{Rng, SeedableRng};

    /// The word-wise feeds byte equals the brute-force one on random
    /// leaves of every density, with inactive voxels holding garbage that
    /// must be ignored, and single voxels at every corner, edge and face.
    #[test]
    fn feeds_match_brute_force() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(5);
        let check = |leaf: &Leaf<f32>| {
            let (peak, feeds) = scan_leaf(leaf).unwrap();
            assert_eq!(feeds, leaf_feeds(leaf));
            let want = (0..LEAF_NUM_VALUES).filter(|&n| leaf.is_active(n)).map(|n| leaf.values[n]).fold(0.0, f32::max);
            assert_eq!(peak, want);
        };
        for n in 0..LEAF_NUM_VALUES {
            let mut leaf = Leaf::new(IVec3::ZERO, 0.0f32);
            leaf.values[n] = 1.0;
            leaf.set_active(n, true);
            check(&leaf);
        }
        for &p in &[0.002, 0.01, 0.05, 0.3] {
            for _ in 0..200 {
                let mut leaf = Leaf::new(IVec3::ZERO, 0.0f32);
                for n in 0..LEAF_NUM_VALUES {
                    let on = rng.random::<f64>() < p;
                    leaf.set_active(n, on);
                    leaf.values[n] = if on && rng.random::<f64>() < 0.7 { rng.random::<f32>() } else if on { 0.0 } else { 5.0 };
                }
                check(&leaf);
            }
        }
        let mut leaf = Leaf::new(IVec3::ZERO, 0.0f32);
        leaf.set_active(77, true);
        leaf.values[77] = -1.0;
        leaf.values[3] = f32::NAN;
        assert_eq!(scan_leaf(&leaf), Err(77));
    }

    /// The word-wise dual-cell masks equal the brute-force ones on random
    /// blocks of every density, each block shared or absent (block 0).
    #[test]
    fn cell_masks_match_brute_force() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(9);
        for &p in &[0.001, 0.01, 0.1, 0.5, 0.95] {
            let mut nonzero: Vec<(CellMask, CellMask)> = vec![([0; 8], [0; 8])];
            for _ in 0..12 {
                let mut a = [0u64; 8];
                let mut f = [0u64; 8];
                for n in 0..512 {
                    if rng.random::<f64>() < p {
                        a[n >> 6] |= 1 << (n & 63);
                        if rng.random::<f64>() < 0.5 {
                            f[n >> 6] |= 1 << (n & 63);
                        }
                    }
                }
                nonzero.push((f, a));
            }
            for _ in 0..200 {
                let nb: [u32; 8] = std::array::from_fn(|_| rng.random_range(0..nonzero.len() as u32));
                assert_eq!(cell_masks(&nb, &nonzero), cell_masks_brute(&nb, &nonzero), "density {p}, blocks {nb:?}");
            }
        }
        // One voxel at each corner of the lattice lights exactly its cells.
        let mut one = [0u64; 8];
        one[0] = 1;
        let nonzero = vec![([0; 8], [0; 8]), (one, one)];
        for d in 0..8 {
            let mut nb = [0u32; 8];
            nb[d] = 1;
            assert_eq!(cell_masks(&nb, &nonzero), cell_masks_brute(&nb, &nonzero), "corner {d}");
        }
    }
}
