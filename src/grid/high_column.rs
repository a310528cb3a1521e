//! The high column at a resolution of its own: how a grid is stored as a
//! fine grid below an altitude and a coarse grid above it, and how a reader
//! adds the two back.
//!
//! Soft electrons light a faint column far above the curtain (up to about
//! 400 km on the default scene), smooth on the scale of a few voxels: above
//! 240 km lie about half of the default bake's voxels and a small share of
//! its light. Stored at the bright curtain's 0.5 km they are most of the file.
//! Here they are stored at `factor` times the voxel size, in a second grid
//! named `NAME_high` on the same translation (coarse index `c` is fine index
//! `f c`), which a renderer samples and adds to `NAME`.
//!
//! **Blend.** With `s(h)` a smoothstep from 0 at `above_km` to 1 at
//! `above_km + band_km` (altitude `h` above the Earth, `crate::geometry::earth`), the
//! fine grid stores `(1 - s) E` and the coarse grid the restriction of
//! `s E`, so the two fields sum to `E` up to the coarse grid's smoothing,
//! with no seam: each part falls to zero smoothly where the other takes over.
//!
//! **Restriction and prolongation.** Trilinear interpolation is the
//! prolongation `P` from the coarse grid to the fine one: fine voxel `i`
//! takes `sum_c w(i - f c) C_c`, `w(d) = prod_axes (f - |d|) / f` over the
//! coarse voxels within `f` fine voxels. Since the coarse voxel centres are
//! fine voxel centres, trilinear interpolation of `P C` on the fine grid is
//! exactly trilinear interpolation of `C` on the coarse one (a trilinear
//! function on a sub-box of a cell is trilinear), so a reader that adds
//! `P C` to the fine grid ([`merge`]) renders what a renderer sampling both
//! grids (Cycles) renders. The emission's and the density's restriction is
//! injection, `C_c = (s E)_{f c}`: prolonged back it is the field at every
//! `f`-th voxel and trilinear between, exact on linear fields, no blur. Its
//! total is `f^3 sum_c C_c`, the midpoint rule of `sum_i (s E)_i` at the
//! coarse spacing, exact to the field's smoothness on that scale.
//! [`coarsen`] uses full weighting instead, `R = P^T / f^3` (per axis the
//! tent `(f - |d|) / f^2`, summing to one), which keeps the total exactly,
//! `sum_i (P R x)_i = sum_i x_i`, but blurs by a tent of `f` voxels' half
//! width (multigrid's standard pair: Briggs, Henson & McCormick, *A
//! Multigrid Tutorial*, 2nd ed., SIAM 2000, ch. 3). On the default scene,
//! split at 250 km, injection gives a 0.25 % picture error and full
//! weighting 0.42 % (`docs/storage.md`).
//!
//! The functions take plain grids and know nothing of the bake or the file.

use crate::geometry::earth::Earth;
use crate::grid::{leaf_offset, leaf_origin, Grid, Leaf, VoxelValue, LEAF_DIM, LEAF_NUM_VALUES};
use glam::{DVec3, IVec3};
use rayon::prelude::*;

/// Suffix of a grid's high-column part: `emission` -> `emission_high`.
pub const HIGH_SUFFIX: &str = "_high";

/// Where the high column starts and how coarse it is stored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Column {
    /// Altitude where the blend to the coarse grid starts, km.
    pub above_km: f64,
    /// Width of the blend, km.
    pub band_km: f64,
    /// Coarse voxel size over the fine one (an integer >= 2).
    pub factor: i32,
}

impl Column {
    /// The blend band of two coarse voxels (`2 factor voxel_km`): the fine
    /// part then falls to zero over four fine voxels at the default factor.
    pub fn new(above_km: f64, factor: i32, voxel_km: f64) -> Column {
        Column { above_km, band_km: 2.0 * factor as f64 * voxel_km, factor }
    }

    /// `s(h)`: 0 below `above_km`, 1 above `above_km + band_km`, the
    /// smoothstep `3 t^2 - 2 t^3` between.
    #[inline]
    pub fn blend(&self, h: f64) -> f64 {
        let t = ((h - self.above_km) / self.band_km).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }
}

/// Why two grids cannot be added.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MergeError {
    #[error("grid `{high}` (voxel {coarse} km) is not an integer multiple >= 2 of `{fine}`'s voxel ({voxel} km) on the same translation")]
    Transform { fine: String, high: String, voxel: f64, coarse: f64 },
    #[error("grid `{0}` has a background other than zero")]
    Background(String),
}

/// Lowest and highest altitude over the fine index box `[lo, hi]`.
fn altitude_range(g_tr: &crate::grid::Transform, earth: &Earth, lo: IVec3, hi: IVec3) -> (f64, f64) {
    let (a, b) = (g_tr.index_to_world(lo.as_dvec3()), g_tr.index_to_world(hi.as_dvec3()));
    if earth.is_flat() {
        return (a.z, b.z);
    }
    let corners = (0..8).map(|k| DVec3::new([a.x, b.x][k & 1], [a.y, b.y][(k >> 1) & 1], [a.z, b.z][k >> 2]));
    let max = corners.map(|p| earth.altitude(p)).fold(f64::MIN, f64::max);
    // |p - centre| is convex: its minimum over the box is at the point of
    // the box nearest the centre.
    (earth.altitude(earth.centre().clamp(a, b)), max)
}

/// The value at index `i` of `g`, through a one-leaf cache.
struct Reader<'a, T> {
    g: &'a Grid<T>,
    origin: IVec3,
    leaf: Option<&'a Leaf<T>>,
}

impl<'a, T: VoxelValue> Reader<'a, T> {
    fn new(g: &'a Grid<T>) -> Self {
        Reader { g, origin: IVec3::MAX, leaf: None }
    }
    /// (active, value); background zero.
    #[inline]
    fn get(&mut self, i: IVec3) -> (bool, T) {
        let o = leaf_origin(i);
        if o != self.origin {
            self.origin = o;
            self.leaf = self.g.leaf(o);
        }
        match self.leaf {
            Some(l) => {
                let n = leaf_offset(i);
                (l.is_active(n), l.values[n])
            }
            None => (false, T::ZERO),
        }
    }
}

fn scale<T: VoxelValue>(v: T, s: f64) -> T {
    let c = v.components();
    T::from_components(&[(c[0] as f64 * s) as f32, (c[1] as f64 * s) as f32, (c[2] as f64 * s) as f32])
}

/// Splits `g` (background zero) into the fine part `(1 - s) E`, named as
/// `g`, and the coarse part `R (s E)` named `g.name + "_high"` (module
/// doc). A fine voxel is kept where it was active and `s < 1`; a coarse
/// voxel is active where any fine voxel it restricts is active with
/// `s > 0`. Both grids' leaves sorted; deterministic whatever the thread
/// count.
pub fn split<T: VoxelValue>(g: &Grid<T>, col: &Column, earth: &Earth) -> (Grid<T>, Grid<T>) {
    let tr = g.transform;
    let f = col.factor;
    let top = col.above_km + col.band_km;
    let h_of = |i: IVec3| earth.altitude(tr.index_to_world(i.as_dvec3()));
    let fine_leaves: Vec<Leaf<T>> = g
        .leaves()
        .par_iter()
        .filter_map(|l| {
            let (lo, hi) = altitude_range(&tr, earth, l.origin, l.origin + IVec3::splat(LEAF_DIM - 1));
            if hi < col.above_km {
                return Some(l.clone());
            }
            if lo >= top {
                return None;
            }
            let mut out = Leaf::new(l.origin, T::ZERO);
            for n in 0..LEAF_NUM_VALUES {
                if l.is_active(n) {
                    let s = col.blend(h_of(l.origin + crate::grid::offset_to_local(n)));
                    if s < 1.0 {
                        out.values[n] = scale(l.values[n], 1.0 - s);
                        out.set_active(n, true);
                    }
                }
            }
            (out.active_count() > 0).then_some(out)
        })
        .collect();
    let fine = Grid::from_leaves(g.name.clone(), T::ZERO, tr, fine_leaves);

    let coarse =
        restrict(g, f, Restriction::Injection, &|i| col.blend(h_of(i)), Some(col.above_km), earth, format!("{}{HIGH_SUFFIX}", g.name));
    (fine, coarse)
}

/// How fine voxels become a coarse one (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Restriction {
    /// `C_c = x_{f c}`: the fine value at the coarse voxel's centre.
    /// Prolonged back, it is the fine field at every `f`-th voxel and the
    /// trilinear interpolation between: no blur of what the coarse grid
    /// can hold, the choice for the emission's high column.
    Injection,
    /// Full weighting `R = P^T / f^3`: keeps the total exactly, a tent blur
    /// once prolonged; the choice for a field whose integral matters more
    /// than its detail (the density's optical depth).
    FullWeighting,
}

/// `g` at `f` times its voxel size (full weighting, [`Restriction`]),
/// named as `g`: a coarse copy for a smooth field.
pub fn coarsen<T: VoxelValue>(g: &Grid<T>, f: i32) -> Grid<T> {
    restrict(g, f, Restriction::FullWeighting, &|_| 1.0, None, &Earth::new(0.0), g.name.clone())
}

/// Appends the origins of the leaves from origin `lo` to origin `hi`
/// (both leaf origins, inclusive), x outermost and z innermost.
fn push_leaf_origins(lo: IVec3, hi: IVec3, out: &mut Vec<IVec3>) {
    for x in (lo.x..=hi.x).step_by(LEAF_DIM as usize) {
        for y in (lo.y..=hi.y).step_by(LEAF_DIM as usize) {
            out.extend((lo.z..=hi.z).step_by(LEAF_DIM as usize).map(|z| IVec3::new(x, y, z)));
        }
    }
}

/// The coarse grid of `weight * g` at `f` times the voxel size; only fine
/// leaves reaching above `above_km` (all when None) are read.
fn restrict<T: VoxelValue>(
    g: &Grid<T>,
    f: i32,
    rule: Restriction,
    weight: &(dyn Fn(IVec3) -> f64 + Sync),
    above_km: Option<f64>,
    earth: &Earth,
    name: String,
) -> Grid<T> {
    let tr = g.transform;
    let w: Vec<f64> = (-(f - 1)..f)
        .map(|d| match rule {
            Restriction::Injection => (d == 0) as i32 as f64,
            Restriction::FullWeighting => (f - d.abs()) as f64 / (f * f) as f64,
        })
        .collect();
    let ctr = crate::grid::Transform::new(tr.voxel_size * f as f64, tr.translation);
    // The coarse leaves any fine voxel above `above_km` restricts to:
    // coarse c takes fine i with |i - f c| < f on every axis.
    let mut origins: Vec<IVec3> = g
        .leaves()
        .iter()
        .filter(|l| above_km.is_none_or(|h| altitude_range(&tr, earth, l.origin, l.origin + IVec3::splat(LEAF_DIM - 1)).1 > h))
        .flat_map(|l| {
            let a = l.origin - IVec3::splat(f - 1);
            let lo = leaf_origin(IVec3::new(ceil_div(a.x, f), ceil_div(a.y, f), ceil_div(a.z, f)));
            let hi = leaf_origin((l.origin + IVec3::splat(LEAF_DIM - 1 + f - 1)).div_euclid(IVec3::splat(f)));
            let mut v = Vec::new();
            push_leaf_origins(lo, hi, &mut v);
            v
        })
        .collect();
    origins.sort_unstable_by_key(|o| (o.x, o.y, o.z));
    origins.dedup();
    let coarse_leaves: Vec<Leaf<T>> = origins
        .par_iter()
        .filter_map(|&co| {
            if rule == Restriction::Injection {
                return inject_leaf(g, co, f, weight);
            }
            // The fine block this coarse leaf restricts, dense: s E and
            // whether the voxel counts (active with s > 0).
            let base = co * f - IVec3::splat(f - 1);
            let n = (LEAF_DIM - 1) * f + 2 * (f - 1) + 1;
            let idx = |x: i32, y: i32, z: i32| ((x * n + y) * n + z) as usize;
            let mut block = vec![[0.0f64; 3]; (n * n * n) as usize];
            let mut live = vec![false; (n * n * n) as usize];
            let mut rd = Reader::new(g);
            let mut any = false;
            for x in 0..n {
                for y in 0..n {
                    for z in 0..n {
                        let i = base + IVec3::new(x, y, z);
                        let (on, v) = rd.get(i);
                        if on {
                            let s = weight(i);
                            if s > 0.0 {
                                let c = v.components();
                                block[idx(x, y, z)] = [c[0] as f64 * s, c[1] as f64 * s, c[2] as f64 * s];
                                live[idx(x, y, z)] = true;
                                any = true;
                            }
                        }
                    }
                }
            }
            if !any {
                return None;
            }
            let mut out = Leaf::new(co, T::ZERO);
            for cx in 0..LEAF_DIM {
                for cy in 0..LEAF_DIM {
                    for cz in 0..LEAF_DIM {
                        let mut sum = [0.0f64; 3];
                        let mut on = false;
                        let (x0, y0, z0) = (cx * f, cy * f, cz * f);
                        for (a, wa) in w.iter().enumerate() {
                            for (b, wb) in w.iter().enumerate() {
                                for (c, wc) in w.iter().enumerate() {
                                    let k = idx(x0 + a as i32, y0 + b as i32, z0 + c as i32);
                                    if live[k] && wa * wb * wc != 0.0 {
                                        on = true;
                                        let ww = wa * wb * wc;
                                        for (s, v) in sum.iter_mut().zip(block[k]) {
                                            *s += ww * v;
                                        }
                                    }
                                }
                            }
                        }
                        if on {
                            let nn = leaf_offset(IVec3::new(cx, cy, cz));
                            out.values[nn] = T::from_components(&[sum[0] as f32, sum[1] as f32, sum[2] as f32]);
                            out.set_active(nn, true);
                        }
                    }
                }
            }
            Some(out)
        })
        .collect();
    Grid::from_leaves(name, T::ZERO, ctr, coarse_leaves)
}

/// The coarse leaf at `co` by injection: coarse voxel `c` is `weight * g`
/// at fine voxel `f c`, active where that fine voxel is active with a
/// positive weight (what the general restriction gives with the injection
/// weights, reading 8^3 fine voxels instead of the whole block).
fn inject_leaf<T: VoxelValue>(g: &Grid<T>, co: IVec3, f: i32, weight: &(dyn Fn(IVec3) -> f64 + Sync)) -> Option<Leaf<T>> {
    let mut rd = Reader::new(g);
    let mut out = Leaf::new(co, T::ZERO);
    let mut any = false;
    for cx in 0..LEAF_DIM {
        for cy in 0..LEAF_DIM {
            for cz in 0..LEAF_DIM {
                let i = (co + IVec3::new(cx, cy, cz)) * f;
                let (on, v) = rd.get(i);
                if !on {
                    continue;
                }
                let s = weight(i);
                if s > 0.0 {
                    let nn = leaf_offset(IVec3::new(cx, cy, cz));
                    out.values[nn] = scale(v, s);
                    out.set_active(nn, true);
                    any = true;
                }
            }
        }
    }
    any.then_some(out)
}

fn ceil_div(a: i32, b: i32) -> i32 {
    -((-a).div_euclid(b))
}

/// The fine grid plus the prolongation of the coarse one (module doc): what
/// a renderer sampling both grids and adding them sees, on the fine grid.
/// A voxel is active where it was in `fine` or where a coarse voxel of
/// non-zero weight is active. Named as `fine`; leaves sorted.
pub fn merge<T: VoxelValue>(fine: &Grid<T>, high: &Grid<T>) -> Result<Grid<T>, MergeError> {
    let (tf, tc) = (fine.transform, high.transform);
    let ratio = tc.voxel_size / tf.voxel_size;
    let f = ratio.round() as i32;
    if f < 2
        || (ratio - f as f64).abs() > 1e-9 * ratio
        || (tc.translation - tf.translation).abs().max_element() > 1e-9 * tf.voxel_size.max(1.0)
    {
        return Err(MergeError::Transform {
            fine: fine.name.clone(),
            high: high.name.clone(),
            voxel: tf.voxel_size,
            coarse: tc.voxel_size,
        });
    }
    for g in [fine.name.as_str(), high.name.as_str()] {
        let bg = if g == fine.name { fine.background } else { high.background };
        if bg != T::ZERO {
            return Err(MergeError::Background(g.to_string()));
        }
    }
    // Fine leaves the coarse grid reaches: coarse c feeds fine i with
    // |i - f c| < f.
    let mut origins: Vec<IVec3> = fine.leaves().iter().map(|l| l.origin).collect();
    for l in high.leaves() {
        let lo = leaf_origin(l.origin * f - IVec3::splat(f - 1));
        let hi = leaf_origin((l.origin + IVec3::splat(LEAF_DIM - 1)) * f + IVec3::splat(f - 1));
        push_leaf_origins(lo, hi, &mut origins);
    }
    origins.sort_unstable_by_key(|o| (o.x, o.y, o.z));
    origins.dedup();
    let leaves: Vec<Leaf<T>> = origins
        .par_iter()
        .filter_map(|&o| {
            let mut out = fine.leaf(o).cloned().unwrap_or_else(|| Leaf::new(o, T::ZERO));
            let mut rd = Reader::new(high);
            for n in 0..LEAF_NUM_VALUES {
                let i = o + crate::grid::offset_to_local(n);
                let c0 = i.div_euclid(IVec3::splat(f));
                let r = i - c0 * f; // 0..f per axis
                let mut sum = [0.0f64; 3];
                let mut on = false;
                for k in 0..8 {
                    let d = IVec3::new((k >> 2) & 1, (k >> 1) & 1, k & 1);
                    let wk = (0..3).fold(1.0f64, |acc, a| {
                        let t = r[a] as f64 / f as f64;
                        acc * if d[a] == 1 { t } else { 1.0 - t }
                    });
                    if wk == 0.0 {
                        continue;
                    }
                    let (act, v) = rd.get(c0 + d);
                    if act {
                        on = true;
                        for (s, x) in sum.iter_mut().zip(v.components()) {
                            *s += wk * x as f64;
                        }
                    }
                }
                if on {
                    let c = out.values[n].components();
                    out.values[n] =
                        T::from_components(&[(c[0] as f64 + sum[0]) as f32, (c[1] as f64 + sum[1]) as f32, (c[2] as f64 + sum[2]) as f32]);
                    out.set_active(n, true);
                }
            }
            (out.active_count() > 0).then_some(out)
        })
        .collect();
    Ok(Grid::from_leaves(fine.name.clone(), T::ZERO, tf, leaves))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use crate::util::fmath;

    /// A box of active voxels holding `field(world position)`.
    fn boxed(f: impl Fn(DVec3) -> f32, lo: IVec3, hi: IVec3, tr: Transform) -> Grid<f32> {
        let mut g = Grid::new("density", 0.0f32, tr);
        for x in lo.x..=hi.x {
            for y in lo.y..=hi.y {
                for z in lo.z..=hi.z {
                    let i = IVec3::new(x, y, z);
                    g.set(i, f(tr.index_to_world(i.as_dvec3())));
                }
            }
        }
        g
    }

    fn sum(g: &Grid<f32>) -> f64 {
        g.iter_active().map(|(_, v)| v as f64).sum()
    }

    /// A Gaussian bump of `sigma` km (a smooth field that is zero, to f32,
    /// at the box's faces) centred at `c`.
    fn bump(c: DVec3, sigma: f64) -> impl Fn(DVec3) -> f32 {
        move |p: DVec3| fmath::exp(-(p - c).length_squared() / (2.0 * sigma * sigma)) as f32
    }

    #[test]
    fn split_then_merge_keeps_the_total_and_the_field_below_the_band() {
        let tr = Transform::new(0.5, DVec3::new(0.25, -0.5, 0.0));
        let col = Column::new(20.0, 2, 0.5);
        // A bump across the band (20 to 22 km), zero at the box's faces.
        let g = boxed(bump(DVec3::new(2.0, 1.0, 21.0), 2.5), IVec3::new(-26, -28, 10), IVec3::new(34, 32, 72), tr);
        let (fine, high) = split(&g, &col, &Earth::new(0.0));
        assert_eq!(high.name, "density_high");
        assert_eq!(high.transform.voxel_size, 1.0);
        assert!(fine.iter_active().all(|(i, _)| tr.index_to_world(i.as_dvec3()).z < col.above_km + col.band_km));
        let m = merge(&fine, &high).unwrap();
        // Prolongation spreads a coarse voxel over weights summing to f^3,
        // so the merged total is f^3 times the sum of s E at the coarse
        // centres: the midpoint rule at 1 km, whose error on a field smooth
        // on a few km is tiny (measured 1e-9 here, 3e-5 on the sphere below);
        // 1e-4 leaves room for f32 sums, not for a lost or doubled voxel
        // (1e-3 of this bump).
        let ratio = sum(&m) / sum(&g);
        assert!((ratio - 1.0).abs() < 1e-4, "{} vs {}", sum(&m), sum(&g));
        // Below the band nothing changes.
        for (i, v) in g.iter_active() {
            if tr.index_to_world(i.as_dvec3()).z < col.above_km - 1.0 {
                assert_eq!(m.get(i), v);
            }
        }
    }

    #[test]
    fn a_linear_field_above_the_band_is_reproduced_exactly_inside_the_box() {
        let tr = Transform::new(0.5, DVec3::ZERO);
        let col = Column::new(10.0, 2, 0.5);
        let field = |p: DVec3| (3.0 + 0.25 * p.x - 0.125 * p.y + 0.0625 * p.z) as f32;
        let (lo, hi) = (IVec3::new(-8, -8, 40), IVec3::new(8, 8, 72));
        let g = boxed(field, lo, hi, tr);
        let (fine, high) = split(&g, &col, &Earth::new(0.0));
        assert_eq!(fine.active_voxel_count(), 0, "all of the box is above the band");
        let m = merge(&fine, &high).unwrap();
        // Injection and trilinear prolongation are exact on linear
        // functions where the tents lie inside the box (two coarse voxels
        // in from its faces).
        let mut checked = 0;
        for (i, v) in g.iter_active() {
            if (i - lo).min_element() >= 4 && (hi - i).min_element() >= 4 {
                assert!((m.get(i) - v).abs() < 2e-6 * v.abs(), "{i}: {} vs {v}", m.get(i));
                checked += 1;
            }
        }
        assert!(checked > 1000);
    }

    #[test]
    fn merge_refuses_grids_that_do_not_nest() {
        let a = Grid::new("emission", 0.0f32, Transform::new(0.5, DVec3::ZERO));
        for tr in [Transform::new(0.75, DVec3::ZERO), Transform::new(1.0, DVec3::new(0.1, 0.0, 0.0)), Transform::new(0.5, DVec3::ZERO)] {
            let b = Grid::new("emission_high", 0.0f32, tr);
            assert!(matches!(merge(&a, &b), Err(MergeError::Transform { .. })), "{tr:?}");
        }
    }

    #[test]
    fn split_is_the_same_on_a_sphere_far_below_its_top_and_on_a_round_earth_reads_altitude() {
        let tr = Transform::new(0.5, DVec3::ZERO);
        let col = Column::new(100.0, 2, 0.5);
        let g = boxed(bump(DVec3::new(0.0, 0.0, 101.0), 2.5), IVec3::new(-30, -30, 170), IVec3::new(30, 30, 235), tr);
        let earth = Earth::new(6371.0);
        let (fine, high) = split(&g, &col, &earth);
        for (i, _) in fine.iter_active() {
            assert!(earth.altitude(tr.index_to_world(i.as_dvec3())) < col.above_km + col.band_km);
        }
        let m = merge(&fine, &high).unwrap();
        // As on flat ground.
        assert!((sum(&m) / sum(&g) - 1.0).abs() < 1e-4, "{} vs {}", sum(&m), sum(&g));
    }

    #[test]
    fn the_high_column_is_the_blended_field_at_every_second_voxel() {
        // Brute force: coarse voxel c holds s(f c) E(f c), active exactly
        // where fine voxel f c is active with s > 0.
        let tr = Transform::new(0.5, DVec3::new(0.25, 0.0, -0.5));
        let col = Column::new(20.0, 2, 0.5);
        let g = boxed(bump(DVec3::new(1.0, 2.0, 22.0), 3.0), IVec3::new(-21, -17, 30), IVec3::new(23, 26, 70), tr);
        let (_, high) = split(&g, &col, &Earth::new(0.0));
        let mut want = 0;
        for (i, v) in g.iter_active() {
            if i.x.rem_euclid(2) == 0 && i.y.rem_euclid(2) == 0 && i.z.rem_euclid(2) == 0 {
                let s = col.blend(tr.index_to_world(i.as_dvec3()).z);
                if s > 0.0 {
                    want += 1;
                    assert_eq!(high.get(i / 2), (v as f64 * s) as f32, "{i}");
                }
            }
        }
        assert_eq!(high.active_voxel_count(), want);
        assert!(want > 1000);
    }
}
