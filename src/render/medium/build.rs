//! Building a [`Field`] from one or two [`LeafSource`]s in one parallel
//! pass, with its value array checked against the process's memory limit
//! before it is allocated.
//!
//! The pass runs over the union of the sources' leaves: each leaf is read
//! (a file's record decoded on demand) into a per-thread buffer, checked
//! (finite, >= 0; `check.rs`) with its largest value taken on the floats'
//! bits, then, if some source has a non-zero voxel there, copied into its
//! block of one array allocated up front, its non-zero voxels and the dual
//! leaves it feeds taken in the same loop (`dual.rs`). Blocks are numbered
//! by the union of the leaves in key order, so a grid read from a file and
//! the same grid in memory give the same field, and the result never
//! depends on the thread count. The tree over the dual leaves follows
//! ([`Tree`]).

use super::check::{bad_voxel, leaf_peak};
use super::dual::{cell_masks, feeds_from_nonzero, fill_leaf, push_dual_keys};
use super::field::{Field, Tree};
use super::layout::{CellMask, NONE};
use super::values::{Stored, Values};
use crate::grid::leaf_source::{LeafSource, LeafValues, Scratch};
use crate::grid::{LEAF_DIM, LEAF_MASK_WORDS, LEAF_NUM_VALUES};
use crate::render::settings::RenderError;
use glam::IVec3;
use rayon::prelude::*;

/// The share of this process's memory limit ([`crate::util::memory::available`])
/// the medium's values may take; the rest is the file's bytes, the image,
/// the threads' stacks and heaps.
pub const MEDIUM_MEMORY_FRACTION: f64 = 0.75;

/// What [`Field::from_sources`] found in one source.
pub(super) struct SourceReport {
    /// Largest active component (0 for none).
    pub(super) peak: f32,
    /// The first failure in block order: a bad voxel or a read error.
    pub(super) fail: Option<RenderError>,
}

/// What the pass found in one block.
struct BlockScan {
    /// Dual leaves the block feeds (0: no non-zero active voxel, the block
    /// is not stored).
    feeds: u8,
    /// Its non-zero voxels: channel 0, any channel ([`fill_leaf`]).
    masks: (CellMask, CellMask),
    /// Per source: the largest active component, the first failure.
    peaks: [f32; 2],
    fails: [Option<Box<RenderError>>; 2],
}

/// Reads, checks and (if some source has a non-zero active voxel here)
/// stores the leaves of one block: `leaves[k]` is source `k`'s leaf at the
/// block's origin ([`NONE`] if it has none). A block with no non-zero voxel
/// is never written, so its pages are never touched.
fn scan_block<S: Stored>(
    sources: &[&dyn LeafSource],
    leaves: &[u32; 2],
    dst: &mut [S],
    channels: usize,
    scratch: &mut [Scratch; 2],
) -> BlockScan {
    let mut scan = BlockScan { feeds: 0, masks: ([0; LEAF_MASK_WORDS], [0; LEAF_MASK_WORDS]), peaks: [0.0; 2], fails: [None, None] };
    let mut got: [Option<LeafValues<'_, S>>; 2] = [None, None];
    for ((k, src), scr) in sources.iter().enumerate().zip(scratch.iter_mut()) {
        let li = leaves[k];
        if li == NONE {
            continue;
        }
        let li = li as usize;
        match S::leaf_values(*src, li, scr) {
            Err(source) => scan.fails[k] = Some(Box::new(RenderError::Source { grid: src.name().to_string(), source })),
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
        let (mut first, mut nz) = (0, [0u64; LEAF_MASK_WORDS]);
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
    pub(super) fn from_sources(
        sources: &[&dyn LeafSource],
        reserved: f64,
        limit: &crate::util::memory::MemoryLimit,
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
        let per_block = LEAF_NUM_VALUES * channels;
        // Half floats are kept as such when every source stores them.
        let half = sources.iter().all(|s| s.half());
        let needed = reserved + ((origins.len() + 1) * per_block * Values::value_bytes(half)) as f64;
        if needed > MEDIUM_MEMORY_FRACTION * limit.bytes {
            return Err(RenderError::Memory {
                leaves: origins.len(),
                needed: crate::util::memory::gib(needed),
                available: limit.to_string(),
            });
        }
        // Zeroed by the allocator (fresh pages): blocks not written cost
        // no memory.
        let mut values = Values::zeros((origins.len() + 1) * per_block, half);
        fn scan_all<S: Stored>(sources: &[&dyn LeafSource], leaf_of: &[[u32; 2]], blocks: &mut [S], channels: usize) -> Vec<BlockScan> {
            blocks
                .par_chunks_mut(LEAF_NUM_VALUES * channels)
                .zip(leaf_of.par_iter())
                .map_init(<[Scratch; 2]>::default, |scratch, (dst, leaves)| scan_block(sources, leaves, dst, channels, scratch))
                .collect()
        }
        let mut scans = match &mut values {
            Values::F32(v) => scan_all(sources, &leaf_of, &mut v[per_block..], channels),
            Values::Half(v) => scan_all(sources, &leaf_of, &mut v[per_block..], channels),
        };
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
        nonzero.push(([0; LEAF_MASK_WORDS], [0; LEAF_MASK_WORDS]));
        nonzero.extend(scans.iter().map(|s| s.masks));
        drop(scans);
        let (mask_first, mask_any): (Vec<CellMask>, Vec<CellMask>) = neighbours.par_iter().map(|nb| cell_masks(nb, &nonzero)).unzip();

        // The tree: blocks of 16^3 dual leaves, super nodes of 32^3 blocks.
        let Tree { blocks, supers, root, super_bounds, lo, hi, root_lo, root_hi } = Tree::new(&keys);
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
}
