//! A grid's leaves as a reader sees them, whatever holds them: the
//! renderer's medium (`crate::render::medium`) is built from this view, so
//! a grid in memory ([`GridSource`]) and a VDB file's grid decoded leaf by
//! leaf (`crate::io::vdb::read`) give the same medium.
//!
//! Model: a sparse grid of OpenVDB 8^3 leaves (`crate::grid`), listed as
//! each leaf's origin and active mask (known up front: a file's topology
//! precedes its values) and its values, produced per leaf on demand, in
//! any order and from several threads. The values come in one of the two
//! layouts an OpenVDB leaf record may hold (`io::writeCompressedValues`):
//! all 512 slots, or the active slots only (mask compression).
//!
//! This is the bottom layer: it knows grids, and nothing of the renderer or
//! the file format.

use crate::grid::{Grid, Transform, VoxelValue, LEAF_MASK_WORDS};
use glam::IVec3;

/// Why a leaf's values could not be produced (a file's decode error).
pub type LeafError = Box<dyn std::error::Error + Send + Sync>;

/// Per-thread buffers a [`LeafSource`] may decode a leaf into.
#[derive(Default)]
pub struct Scratch {
    pub values: Vec<f32>,
    /// Half floats' bits ([`LeafSource::values_half`]).
    pub halves: Vec<u16>,
    pub bytes: Vec<u8>,
    /// A [`GreySource`]'s three channels.
    pub wide: Vec<f32>,
    pub wide_halves: Vec<u16>,
}

/// One grid's leaves as the medium's builder reads them: origins and
/// active masks up front (a file's topology lists them before any value),
/// the values leaf by leaf, possibly decoded on demand and in parallel. A
/// grid in memory is one ([`GridSource`]); so is a VDB file's grid
/// (`crate::io::vdb::read`), which lets a render build its medium straight from
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
    /// Whether every value [`values`](Self::values) gives is a half float's
    /// (an `f32` that a half holds exactly): a file's grid stored in half
    /// mode. A store of half floats then holds the source without loss.
    fn half(&self) -> bool {
        false
    }
    /// The values of leaf `i` as half floats' bits, for a source whose
    /// [`half`](Self::half) is true (the bits as stored: no conversion);
    /// an error for any other.
    fn values_half<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s, u16>, LeafError> {
        let _ = (i, scratch);
        Err(format!("grid `{}` does not store half floats", self.name()).into())
    }
}

/// A leaf's values as a [`LeafSource`] gives them: `f32`s, or half floats'
/// bits (`u16`, [`LeafSource::values_half`]).
#[derive(Clone, Copy, Debug)]
pub enum LeafValues<'s, T = f32> {
    /// All 512 slots in index order (`512 * channels` values; inactive
    /// slots may hold anything).
    All(&'s [T]),
    /// The active slots only, in index order (`popcount(mask) * channels`
    /// values): what an active-mask VDB record stores.
    Active(&'s [T]),
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

/// A one-channel source seen as a grey three-channel one named `emission`:
/// each value in all three channels, the same leaves and masks (what
/// `crate::render::grids::grey` makes of a float grid in memory, leaf for
/// leaf), so a line's grid read from a file builds the medium the grey grid
/// would.
pub struct GreySource<'a>(pub &'a dyn LeafSource);

/// `v`'s values, each repeated three times, into `out`.
fn widen<T: Copy>(v: LeafValues<'_, T>, out: &mut Vec<T>) -> bool {
    let (a, all) = match v {
        LeafValues::All(a) => (a, true),
        LeafValues::Active(a) => (a, false),
    };
    out.clear();
    out.extend(a.iter().flat_map(|&x| [x, x, x]));
    all
}

impl LeafSource for GreySource<'_> {
    fn name(&self) -> &str {
        "emission"
    }
    fn transform(&self) -> Transform {
        self.0.transform()
    }
    fn channels(&self) -> usize {
        3
    }
    fn background(&self) -> [f32; 3] {
        [self.0.background()[0]; 3]
    }
    fn leaf_count(&self) -> usize {
        self.0.leaf_count()
    }
    fn origin(&self, i: usize) -> IVec3 {
        self.0.origin(i)
    }
    fn mask(&self, i: usize) -> &[u64; LEAF_MASK_WORDS] {
        self.0.mask(i)
    }
    fn values<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s>, LeafError> {
        let mut wide = std::mem::take(&mut scratch.wide);
        let all = widen(self.0.values(i, scratch)?, &mut wide);
        scratch.wide = wide;
        Ok(if all { LeafValues::All(&scratch.wide) } else { LeafValues::Active(&scratch.wide) })
    }
    fn half(&self) -> bool {
        self.0.half()
    }
    fn values_half<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s, u16>, LeafError> {
        let mut wide = std::mem::take(&mut scratch.wide_halves);
        let all = widen(self.0.values_half(i, scratch)?, &mut wide);
        scratch.wide_halves = wide;
        Ok(if all { LeafValues::All(&scratch.wide_halves) } else { LeafValues::Active(&scratch.wide_halves) })
    }
}
