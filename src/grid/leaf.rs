//! The 8^3 leaf, OpenVDB's `tree/LeafNode.h`: 512 values in x-major
//! order (`offset = x * 64 + y * 8 + z`, as OpenVDB), an active mask of
//! eight `u64` words, the voxel value types a grid may hold
//! ([`VoxelValue`]), and the mask operations the bake and the writer share
//! (dilation by one voxel, the active bounding box).

use glam::IVec3;

/// log2 of the leaf edge length (OpenVDB `LeafNode::LOG2DIM`).
pub const LEAF_LOG2DIM: u32 = 3;

/// Leaf edge length in voxels (OpenVDB `LeafNode::DIM`).
pub const LEAF_DIM: i32 = 1 << LEAF_LOG2DIM;

/// Voxels per leaf (OpenVDB `LeafNode::NUM_VALUES`).
pub const LEAF_NUM_VALUES: usize = 1 << (3 * LEAF_LOG2DIM);

/// 64-bit words in a leaf's value mask.
pub const LEAF_MASK_WORDS: usize = LEAF_NUM_VALUES / 64;

/// Offset of a voxel inside its leaf: `((x&7)<<6)|((y&7)<<3)|(z&7)` (OpenVDB
/// `LeafNode::coordToOffset`; x is the slowest axis).
#[inline]
pub fn leaf_offset(ijk: IVec3) -> usize {
    let m = LEAF_DIM - 1;
    (((ijk.x & m) << (2 * LEAF_LOG2DIM)) | ((ijk.y & m) << LEAF_LOG2DIM) | (ijk.z & m)) as usize
}

/// The inverse of [`leaf_offset`], relative to the leaf origin.
#[inline]
pub fn offset_to_local(n: usize) -> IVec3 {
    let n = n as i32;
    let m = LEAF_DIM - 1;
    IVec3::new(n >> (2 * LEAF_LOG2DIM), (n >> LEAF_LOG2DIM) & m, n & m)
}

/// Origin of the leaf holding voxel `ijk` (floor-aligned, so it can be negative).
#[inline]
pub fn leaf_origin(ijk: IVec3) -> IVec3 {
    IVec3::new(ijk.x & !(LEAF_DIM - 1), ijk.y & !(LEAF_DIM - 1), ijk.z & !(LEAF_DIM - 1))
}

/// A voxel value type: `f32` (density) or `[f32; 3]` (emission).
pub trait VoxelValue: Copy + PartialEq + Send + Sync + std::fmt::Debug + 'static {
    /// Number of `f32` components.
    const COMPONENTS: usize;
    const ZERO: Self;
    /// OpenVDB tree type name, e.g. `Tree_float_5_4_3`.
    const TREE_TYPE: &'static str;
    fn components(&self) -> [f32; 3];
    fn from_components(c: &[f32]) -> Self;
    fn is_finite(&self) -> bool {
        // f32::is_finite by path: `c.is_finite()` on a `&f32` resolves to this
        // very trait method (receiver &f32) and recursed forever.
        self.components()[..Self::COMPONENTS].iter().all(|c| f32::is_finite(*c))
    }
    /// a + (b - a) * t, componentwise.
    fn lerp(a: Self, b: Self, t: f64) -> Self;
}

impl VoxelValue for f32 {
    const COMPONENTS: usize = 1;
    const ZERO: Self = 0.0;
    const TREE_TYPE: &'static str = "Tree_float_5_4_3";
    fn components(&self) -> [f32; 3] {
        [*self, 0.0, 0.0]
    }
    fn from_components(c: &[f32]) -> Self {
        c[0]
    }
    #[inline]
    fn lerp(a: Self, b: Self, t: f64) -> Self {
        (a as f64 + (b as f64 - a as f64) * t) as f32
    }
}

impl VoxelValue for [f32; 3] {
    const COMPONENTS: usize = 3;
    const ZERO: Self = [0.0; 3];
    const TREE_TYPE: &'static str = "Tree_vec3s_5_4_3";
    fn components(&self) -> [f32; 3] {
        *self
    }
    fn from_components(c: &[f32]) -> Self {
        [c[0], c[1], c[2]]
    }
    #[inline]
    fn lerp(a: Self, b: Self, t: f64) -> Self {
        std::array::from_fn(|i| (a[i] as f64 + (b[i] as f64 - a[i] as f64) * t) as f32)
    }
}

/// An 8^3 block of voxels with its active mask. Inactive voxels hold the
/// grid's background value.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf<T> {
    /// Index coordinates of voxel (0,0,0) of this leaf; multiples of 8.
    pub origin: IVec3,
    /// Active mask: bit `n` of the leaf is word `n >> 6`, bit `n & 63`.
    pub mask: [u64; LEAF_MASK_WORDS],
    /// Values in [`leaf_offset`] order.
    pub values: Box<[T; LEAF_NUM_VALUES]>,
}

impl<T: VoxelValue> Leaf<T> {
    /// Switches on, with the value `bg`, every voxel set in `mask` and off
    /// here, a mask word at a time; returns how many.
    pub(crate) fn switch_on(&mut self, mask: &[u64; LEAF_MASK_WORDS], bg: T) -> u64 {
        let mut added = 0u64;
        for (w, (&want, have)) in mask.iter().zip(self.mask.iter_mut()).enumerate() {
            let mut new = want & !*have;
            *have |= new;
            while new != 0 {
                let b = new.trailing_zeros() as usize;
                self.values[w * 64 + b] = bg;
                added += 1;
                new &= new - 1;
            }
        }
        added
    }

    pub fn new(origin: IVec3, background: T) -> Self {
        debug_assert_eq!(origin, leaf_origin(origin));
        Self { origin, mask: [0; LEAF_MASK_WORDS], values: Box::new([background; LEAF_NUM_VALUES]) }
    }
    #[inline]
    pub fn is_active(&self, n: usize) -> bool {
        self.mask[n >> 6] >> (n & 63) & 1 == 1
    }
    #[inline]
    pub fn set_active(&mut self, n: usize, on: bool) {
        if on {
            self.mask[n >> 6] |= 1 << (n & 63);
        } else {
            self.mask[n >> 6] &= !(1 << (n & 63));
        }
    }
    pub fn active_count(&self) -> u64 {
        self.mask.iter().map(|w| w.count_ones() as u64).sum()
    }
    /// Active voxels as (global index, value), in offset order.
    pub fn iter_active(&self) -> impl Iterator<Item = (IVec3, T)> + '_ {
        (0..LEAF_NUM_VALUES).filter(|&n| self.is_active(n)).map(|n| (self.origin + offset_to_local(n), self.values[n]))
    }
}

/// Bits of a mask word (an x slice: bit `y << 3 | z`) with z = 0.
const Z0: u64 = 0x0101_0101_0101_0101;

/// Bits with z = 7.
const Z7: u64 = Z0 << 7;

/// Bits with y = 0.
const Y0: u64 = 0xFF;

/// The 26-neighbourhood dilation of one leaf's active mask, split over the
/// leaf and its neighbours: entry `((dx + 1) * 3 + dy + 1) * 3 + dz + 1` is
/// the mask it gives the leaf at offset (dx, dy, dz) leaves. The 3^3 cube is
/// the product of three segments, so the dilation is one per axis in turn,
/// on whole mask words (word x holds the (y, z) slice, bit `y << 3 | z`):
/// shifts by 1 move along z (the bits crossing a z-row's end go to the z
/// neighbour), by 8 along y, and neighbouring words along x.
pub fn dilate_mask(m: &[u64; LEAF_MASK_WORDS]) -> [[u64; LEAF_MASK_WORDS]; 27] {
    // z: [dz + 1][x].
    let mut a = [[0u64; LEAF_MASK_WORDS]; 3];
    for x in 0..LEAF_MASK_WORDS {
        let v = m[x];
        a[0][x] = (v & Z0) << 7;
        a[1][x] = v | ((v << 1) & !Z0) | ((v >> 1) & !Z7);
        a[2][x] = (v & Z7) >> 7;
    }
    // y: [dy + 1][dz + 1][x].
    let mut b = [[[0u64; LEAF_MASK_WORDS]; 3]; 3];
    for dz in 0..3 {
        for x in 0..LEAF_MASK_WORDS {
            let v = a[dz][x];
            b[0][dz][x] = (v & Y0) << 56;
            b[1][dz][x] = v | (v << 8) | (v >> 8);
            b[2][dz][x] = v >> 56;
        }
    }
    // x: [dx + 1][dy + 1][dz + 1][x].
    let mut out = [[0u64; LEAF_MASK_WORDS]; 27];
    let last = LEAF_MASK_WORDS - 1;
    for (dy, row) in b.iter().enumerate() {
        for (dz, v) in row.iter().enumerate() {
            let (lo, mid, hi) = (dy * 3 + dz, 9 + dy * 3 + dz, 18 + dy * 3 + dz);
            for x in 0..LEAF_MASK_WORDS {
                let prev = if x > 0 { v[x - 1] } else { 0 };
                let next = if x < last { v[x + 1] } else { 0 };
                out[mid][x] = prev | v[x] | next;
            }
            out[lo][last] = v[0];
            out[hi][0] = v[last];
        }
    }
    out
}

/// Inclusive local bounding box (0..8 per axis) of a leaf's active mask,
/// None when it is empty.
pub fn mask_bbox(m: &[u64; LEAF_MASK_WORDS]) -> Option<(IVec3, IVec3)> {
    let x0 = m.iter().position(|&w| w != 0)?;
    let x1 = m.iter().rposition(|&w| w != 0)?;
    let plane = m.iter().fold(0u64, |a, &w| a | w);
    // y: the nonzero bytes of the (y, z) plane; z: the bits of their OR.
    let ys = (0..8).filter(|&y| (plane >> (8 * y)) & 0xFF != 0);
    let (y0, y1) = (ys.clone().min()?, ys.max()?);
    let zbits = (0..8).fold(0u64, |a, y| a | ((plane >> (8 * y)) & 0xFF));
    let (z0, z1) = (zbits.trailing_zeros() as i32, 63 - zbits.leading_zeros() as i32);
    Some((IVec3::new(x0 as i32, y0, z0), IVec3::new(x1 as i32, y1, z1)))
}
