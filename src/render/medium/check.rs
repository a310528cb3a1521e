//! What the renderer accepts from a grid, checked as Cycles would sample
//! it: a finite voxel size, a box the renderer can place in its frame
//! ([`MAX_LEAF_INDEX`], [`MAX_BOX_KM`]), a zero background (a non-zero one fills all of
//! space, which no renderer samples the same way), active values finite
//! and >= 0 (inactive voxels read as 0 whatever they hold), and a largest value
//! that times its volume scale stays below [`MAX_SCALED_VALUE`], so no
//! finite input reaches an infinite pixel.
//!
//! The value check runs on the floats' bits: a finite value >= 0 has bits
//! below +inf's (or is -0), and such bits order as the values, so one pass
//! gives both the verdict and the leaf's largest value.

use super::values::Stored;
use crate::grid::leaf_source::{LeafSource, LeafValues};
use crate::grid::LEAF_MASK_WORDS;
use crate::render::settings::RenderError;

/// First pass over a source leaf: its largest active component, or the
/// offset of its first active voxel that is negative, infinite or NaN.
/// Inactive voxels count as 0 whatever they hold. On a leaf's active values
/// alone ([`LeafValues::Active`]) the check runs on the values' bits, in
/// SIMD lanes: a valid value's bits order as its value (for `f32`s and
/// half floats alike: [`Stored`]).
pub(super) fn leaf_peak<S: Stored>(values: LeafValues<'_, S>, channels: usize, mask: &[u64; LEAF_MASK_WORDS]) -> Result<f32, usize> {
    match values {
        LeafValues::Active(a) => {
            let (mut peak, mut bad) = (0u32, false);
            for &x in a {
                bad |= !x.is_valid();
                peak = peak.max(x.magnitude());
            }
            if bad {
                // The first active voxel with a bad component.
                let mut k = 0;
                for (w, &word) in mask.iter().enumerate() {
                    let mut bits = word;
                    while bits != 0 {
                        let n = w * 64 + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        if a[k * channels..(k + 1) * channels].iter().any(|x| !x.is_valid()) {
                            return Err(n);
                        }
                        k += 1;
                    }
                }
            }
            Ok(S::from_magnitude(peak))
        }
        LeafValues::All(a) => {
            let mut peak = 0u32;
            for (w, &word) in mask.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let n = w * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    for &x in &a[n * channels..(n + 1) * channels] {
                        if !x.is_valid() {
                            return Err(n);
                        }
                        peak = peak.max(x.magnitude());
                    }
                }
            }
            Ok(S::from_magnitude(peak))
        }
    }
}

/// The checks on a source that need no values: transform and background.
pub(super) fn check_header(src: &dyn LeafSource) -> Result<(), RenderError> {
    let err = |message: String| RenderError::Grid { grid: src.name().to_string(), message };
    let t = src.transform();
    let ts = t.voxel_size;
    if !(ts.is_finite() && ts > 0.0 && t.translation.is_finite()) {
        return Err(err(format!("transform must have a finite voxel size > 0 (got {ts})")));
    }
    check_placement(src).map_err(err)?;
    let bg = src.background();
    if bg[..src.channels()].iter().any(|&x| x != 0.0) {
        return Err(err(format!(
            "background {} is not 0: a non-zero background fills all of space, which no renderer samples the same way",
            value_text(&bg[..src.channels()])
        )));
    }
    Ok(())
}

/// The largest leaf index, in voxels on each axis, the renderer places: a
/// leaf's corner (origin + 8) and the block arithmetic stay within i32, and
/// an index converts to a position exactly.
pub const MAX_LEAF_INDEX: i64 = 1 << 30;

/// The farthest a grid's box may reach from the scene's origin, km: an
/// Earth's radius is 6371 km; a box beyond this (a voxel size of 1e100 km,
/// a foreign grid's translation) cannot be placed in the camera's frame
/// with the precision the renderer's steps need.
pub const MAX_BOX_KM: f64 = 1e6;

/// Refuses a grid the renderer cannot place in its frame (a leaf index
/// beyond [`MAX_LEAF_INDEX`], or a box reaching beyond [`MAX_BOX_KM`]):
/// refused naming it, not drawn as nothing.
fn check_placement(src: &dyn LeafSource) -> Result<(), String> {
    let n = src.leaf_count();
    if n == 0 {
        return Ok(());
    }
    let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
    for i in 0..n {
        let o = src.origin(i);
        for (a, v) in [o.x, o.y, o.z].into_iter().enumerate() {
            lo[a] = lo[a].min(v as i64);
            hi[a] = hi[a].max(v as i64 + crate::grid::LEAF_DIM as i64);
        }
    }
    if let Some(a) = (0..3).find(|&a| lo[a] < -MAX_LEAF_INDEX || hi[a] > MAX_LEAF_INDEX) {
        return Err(format!(
            "its leaves reach index {} on axis {}, beyond the +-{MAX_LEAF_INDEX} voxels the renderer places (index box {lo:?} to {hi:?})",
            if lo[a] < -MAX_LEAF_INDEX { lo[a] } else { hi[a] },
            ["x", "y", "z"][a]
        ));
    }
    let t = src.transform();
    let reach = (0..3)
        .map(|a| {
            let c = t.translation[a];
            (c + lo[a] as f64 * t.voxel_size).abs().max((c + hi[a] as f64 * t.voxel_size).abs())
        })
        .fold(0.0f64, f64::max);
    if !(reach <= MAX_BOX_KM) {
        return Err(format!(
            "its box (voxel size {} km, index box {lo:?} to {hi:?}) reaches {reach:e} km from the origin, beyond the {MAX_BOX_KM:e} km the renderer places",
            t.voxel_size
        ));
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
pub(super) fn bad_voxel<S: Stored>(src: &dyn LeafSource, i: usize, n: usize, v: LeafValues<'_, S>) -> RenderError {
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
        message: format!(
            "voxel {ijk} holds {}: values must be finite and >= 0",
            value_text(&at.iter().map(|x| x.to_f32()).collect::<Vec<_>>())
        ),
    }
}

/// Largest scaled voxel value the renderer accepts. The film is f32 and a
/// radiance of 10^30 per km integrated over 10^8 km of path still fits, so
/// no finite input below this bound can reach an infinite pixel.
pub const MAX_SCALED_VALUE: f64 = 1e30;

/// Rejects a grid whose largest value times `scale` exceeds
/// [`MAX_SCALED_VALUE`] (a foreign VDB near f32's limit with a large scale).
pub(super) fn check_scaled_peak(grid: &str, peak: f32, key: &str, scale: f64) -> Result<(), RenderError> {
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

#[cfg(test)]
mod tests {
    use crate::grid::{Grid, Transform};
    use crate::render::Medium;
    use glam::{DVec3, IVec3};

    /// A grid whose leaves sit at index +-2^31, or whose box reaches beyond
    /// the renderer's frame (a voxel of 1e100 km), is refused naming it; a
    /// grid near the limits is placed.
    #[test]
    fn a_grid_the_renderer_cannot_place_is_refused() {
        let grid = |p: IVec3, vs: f64, t: DVec3| {
            let mut g = Grid::new("density", 0.0f32, Transform::new(vs, t));
            g.set(p, 1.0);
            g
        };
        let far = -(1i64 << 31) as f64 * 0.5;
        for (p, vs, t, want) in [
            (IVec3::new(i32::MAX - 3, 0, 0), 0.5, DVec3::new(far, 0.0, 0.0), "reach index 2147483648 on axis x, beyond the +-1073741824"),
            (IVec3::new(0, i32::MIN + 3, 0), 0.5, DVec3::new(0.0, -far, 0.0), "reach index -2147483648 on axis y"),
            (IVec3::new(1, 1, 1), 1e100, DVec3::ZERO, "reaches 8e100 km from the origin, beyond the 1e6 km"),
            (IVec3::new(1, 1, 1), 1e300, DVec3::ZERO, "beyond the 1e6 km"),
        ] {
            let e = Medium::new(Some(&grid(p, vs, t)), None, 1.0, 1.0).err().unwrap().to_string();
            assert!(e.starts_with("grid 'density': its ") && e.contains(want), "{e}");
        }
        assert!(Medium::new(Some(&grid(IVec3::new((1 << 30) - 8, 0, 0), 1e-4, DVec3::ZERO)), None, 1.0, 1.0).is_ok());
    }
}
