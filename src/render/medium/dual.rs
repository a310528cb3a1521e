//! The ghosted dual leaves, leaf by leaf: which dual leaves a source leaf
//! feeds, its values copied into its block, and which dual cells have a
//! non-zero corner.
//!
//! Cycles (like OpenVDB's `BoxSampler`) samples trilinearly between the
//! eight voxel centres around a point, voxel (i,j,k) at index point
//! (i,j,k), so the field is a trilinear polynomial in each dual cell
//! `[i,i+1] x [j,j+1] x [k,k+1]`. Dual leaf `D` holds the 8^3 dual cells of
//! `[8D, 8D+8]^3` and reads the 9^3 voxels `8D .. 8D+8`: its own leaf's
//! block plus the faces, edges and corner of its seven upper neighbours'
//! ("ghosted": read in place, never copied). Hence a source leaf at key `K`
//! feeds dual leaf `K - (dx,dy,dz)` iff it has a non-zero active voxel with
//! local coordinate 0 on every axis where the offset is 1, and a dual cell
//! can be skipped iff all 8 of its corners are 0. Both are computed a
//! 64-bit mask word at a time (the bit layout of `layout.rs`); each has a
//! brute-force oracle in the tests.

use super::layout::{shr, CellMask, Y0_BITS, Z0_BITS, Z7_BITS};
use super::values::Stored;
use crate::grid::leaf_source::LeafValues;
use crate::grid::{LEAF_LOG2DIM, LEAF_MASK_WORDS};
use glam::IVec3;
#[cfg(test)]
use {
    super::check::leaf_peak,
    super::layout::{block_offset, cell_bit},
    crate::grid::VoxelValue,
};

/// Every dual leaf a source leaf at `origin` feeds (bit `d` of `feeds`:
/// dual leaf `key - (dx,dy,dz)`, see [`feeds_from_nonzero`]), appended.
pub(super) fn push_dual_keys(origin: IVec3, feeds: u8, out: &mut Vec<IVec3>) {
    let key = shr(origin, LEAF_LOG2DIM);
    out.extend(
        (0..8u8).filter(|d| feeds >> d & 1 == 1).map(|d| key - IVec3::new((d >> 2 & 1) as i32, (d >> 1 & 1) as i32, (d & 1) as i32)),
    );
}

/// The feeds byte of a leaf from its 512-bit set of non-zero active voxels
/// (bit n = voxel `(x << 6) | (y << 3) | z`, word `x`): bit `d` = (dx,dy,dz)
/// is set iff some voxel in the set has local coordinate 0 on every axis
/// where the offset is 1. Word 0 holds x = 0; within a word the low byte
/// holds y = 0 and [`Z0_BITS`] z = 0.
pub(super) fn feeds_from_nonzero(nz: &CellMask) -> u8 {
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

/// Second pass over a source leaf with a non-zero voxel in its block: copies
/// its active values into block `dst` (stride `stride`, starting at channel
/// `first`; `dst` starts at 0, so inactive voxels read 0) and returns its
/// voxels whose first component (resp. some component) is not 0.
pub(super) fn fill_leaf<S: Stored>(
    values: LeafValues<'_, S>,
    channels: usize,
    mask: &[u64; LEAF_MASK_WORDS],
    dst: &mut [S],
    stride: usize,
    first: usize,
) -> (CellMask, CellMask) {
    match channels {
        1 => fill_leaf_n::<1, S>(values, mask, dst, stride, first),
        3 => fill_leaf_n::<3, S>(values, mask, dst, stride, first),
        _ => unreachable!("sources have 1 or 3 channels (checked in Medium::from_sources)"),
    }
}

/// [`fill_leaf`] for `C` channels (copies of a known length: no call).
fn fill_leaf_n<const C: usize, S: Stored>(
    values: LeafValues<'_, S>,
    mask: &[u64; LEAF_MASK_WORDS],
    dst: &mut [S],
    stride: usize,
    first: usize,
) -> (CellMask, CellMask) {
    let channels = C;
    let (mut nz_first, mut nz_any) = ([0u64; LEAF_MASK_WORDS], [0u64; LEAF_MASK_WORDS]);
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
            let v: &[S; C] = a[i * channels..(i + 1) * channels].try_into().expect("C values");
            let at = n * stride + first;
            let d: &mut [S; C] = (&mut dst[at..at + channels]).try_into().expect("C values");
            *d = *v;
            nz_first[w] |= u64::from(!v[0].is_zero()) << b;
            nz_any[w] |= u64::from(v.iter().any(|x| !x.is_zero())) << b;
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
    let mut dst = vec![0.0f32; flat.len()];
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

/// The dual cells of one dual leaf with a non-zero corner, from the
/// non-zero voxels of its eight blocks (`m[d]`, `d = dx << 2 | dy << 1 |
/// dz`), a mask word at a time: cell (x,y,z) has corners (x+a, y+b, z+c),
/// a,b,c in {0,1}, a coordinate 8 being 0 in the upper neighbour. Word `x`
/// (bits `y << 3 | z`) ORs voxel words x and x+1, then shifts by one in z
/// (bringing in the z = 0 column of the z neighbour) and by one in y (the
/// y = 0 row of the y neighbour).
fn cells_from_voxels(m: [&CellMask; 8]) -> CellMask {
    let mut out = [0u64; LEAF_MASK_WORDS];
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
pub(super) fn cell_masks(nb: &[u32; 8], nonzero: &[(CellMask, CellMask)]) -> (CellMask, CellMask) {
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
                    leaf.values[n] = if on && rng.random::<f64>() < 0.7 {
                        rng.random::<f32>()
                    } else if on {
                        0.0
                    } else {
                        5.0
                    };
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
